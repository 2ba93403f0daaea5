//! SVG plots over time of what the tracker estimated (as in W Fig. 11, 14, 16): the clutter class
//! β̂ with its class probabilities, the clutter density λ̂, the occlusion γ̂, the tracker status α̂
//! with its probabilities, the effective sample size, and the IoU with the ground truth.
//!
//! What a figure shows follows the tracker ([`PlotOptions::of_tracker`]): the lock chain of the
//! appearance trackers (`head`) reports P(lost), not an occlusion, so it has no γ̂ figure, and its
//! status has no partial state, so P(partial) is not drawn. Where the truth is known ([`TruthAt`]: boxes of an OTB folder, or
//! every hidden value of the demo's synthetic scene), it is drawn beside the estimates.
//!
//! Each figure is rendered to a `String` with plotters' SVG backend, so that the report can inline
//! it, and written atomically by [`write_figures`]. A figure whose quantity the tracker does not
//! estimate (no β for Odobez's trackers, say) is left out rather than drawn empty.

use std::path::{Path, PathBuf};

use plotters::prelude::*;
use vision_core::{BoundingBox, TrackStatus};

use crate::output::write_atomic;
use crate::record::FrameRecord;
use crate::render::{CLUTTER, LOCKED, LOST, PARTIAL};
use crate::{AppError, Result};

/// Size of every figure, pixels.
pub const FIGURE_SIZE: (u32, u32) = (720, 360);

/// One rendered figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// File stem: `beta`, `lambda`, `gamma`, `alpha` or `ess`.
    pub name: &'static str,
    /// Human-readable title.
    pub title: String,
    /// The SVG document.
    pub svg: String,
}

/// The colour of ground-truth curves.
const TRUTH: RGBColor = RGBColor(0, 150, 130);

/// What is known of the truth at one frame, to draw beside the estimates.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TruthAt {
    /// The target's box (IoU figure).
    pub bbox: Option<BoundingBox>,
    /// The clutter class β (0-based).
    pub beta: Option<usize>,
    /// The clutter density, edges per pixel.
    pub lambda: Option<f64>,
    /// The occluded fraction of the target (1 − visible fraction).
    pub gamma: Option<f64>,
    /// The tracker status.
    pub alpha: Option<TrackStatus>,
}

/// What the figures draw besides the records.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotOptions {
    /// Whether γ̂ is an occlusion estimate to plot (not for the lock chain, whose γ̂ is P(lost),
    /// already drawn as the status probability).
    pub occlusion: bool,
    /// The statuses the tracker has, in [`TrackStatus::ALL`] order: their probabilities are
    /// drawn, the others not.
    pub statuses: [bool; 3],
    /// The truth, indexed by frame (0-based); frames past its end have none.
    pub truth: Vec<TruthAt>,
}

impl Default for PlotOptions {
    fn default() -> Self {
        Self {
            occlusion: true,
            statuses: [true; 3],
            truth: Vec::new(),
        }
    }
}

impl PlotOptions {
    /// The options for the tracker `config` builds, without truth: a tracker whose status has
    /// no partial state (the lock chain) has no occlusion figure.
    pub fn of_tracker(config: &trackers::TrackerConfig) -> Self {
        let partial = config.has_partial_state();
        Self {
            occlusion: partial,
            statuses: [true, partial, true],
            truth: Vec::new(),
        }
    }

    /// These options with the truth `truth` (indexed by frame).
    pub fn with_truth(mut self, truth: Vec<TruthAt>) -> Self {
        self.truth = truth;
        self
    }

    /// The truth at frame `frame`, if any.
    fn truth_at(&self, frame: usize) -> Option<&TruthAt> {
        self.truth.get(frame)
    }

    /// A series of one true value over the records' frames; `None` when no frame has it.
    fn truth_series(
        &self,
        records: &[FrameRecord],
        label: &str,
        get: impl Fn(&TruthAt) -> Option<f64>,
    ) -> Option<Series> {
        let points: Vec<(f64, f64)> = records
            .iter()
            .filter_map(|r| {
                self.truth_at(r.frame)
                    .and_then(&get)
                    .filter(|v| v.is_finite())
                    .map(|v| (fx(r), v))
            })
            .collect();
        (!points.is_empty()).then(|| Series {
            label: label.to_owned(),
            colour: TRUTH,
            points,
        })
    }
}

/// One line of a chart.
struct Series {
    label: String,
    colour: RGBColor,
    points: Vec<(f64, f64)>,
}

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

fn plot_err(e: impl std::fmt::Display) -> AppError {
    AppError::computation("plotting", e)
}

/// Checks a value before it is plotted, naming the frame and quantity when it is not finite.
fn finite(v: f64, frame: usize, what: &str) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(AppError::computation(
            "plotting",
            format!("frame {}: {what} is {v}", frame + 1),
        ))
    }
}

/// Draws one panel: a titled line chart with the given y range and optional y-tick names.
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    y_label: &str,
    x_max: f64,
    y_range: (f64, f64),
    y_names: Option<&[&str]>,
    series: &[Series],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(8)
        .margin_right(24)
        .x_label_area_size(32)
        .y_label_area_size(56)
        .build_cartesian_2d(1.0..x_max.max(2.0), y_range.0..y_range.1)
        .map_err(plot_err)?;
    let names: Vec<String> = y_names
        .map(|n| n.iter().map(|s| (*s).to_string()).collect())
        .unwrap_or_default();
    // Enough decimals to tell the ticks apart: none for a span of 100, two for a span of 0.2.
    let span = (y_range.1 - y_range.0).abs().max(1e-9);
    let decimals = ((-span.log10()).ceil() + 1.0).clamp(0.0, 4.0) as usize;
    let fmt = |v: &f64| {
        if names.is_empty() {
            format!("{v:.decimals$}")
        } else {
            let i = v.round();
            if (v - i).abs() < 1e-6 && i >= 0.0 {
                names.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        }
    };
    let mut mesh = chart.configure_mesh();
    let frame_fmt = |v: &f64| format!("{v:.0}");
    mesh.x_desc("frame")
        .y_desc(y_label)
        .x_label_formatter(&frame_fmt)
        .y_label_formatter(&fmt)
        .light_line_style(WHITE);
    if !names.is_empty() {
        mesh.y_labels(names.len());
    }
    mesh.draw().map_err(plot_err)?;
    for s in series {
        let colour = s.colour;
        chart
            .draw_series(LineSeries::new(
                s.points.iter().copied(),
                colour.stroke_width(2),
            ))
            .map_err(plot_err)?
            .label(s.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
            });
    }
    if series.len() > 1 || !series.iter().all(|s| s.label.is_empty()) {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(plot_err)?;
    }
    Ok(())
}

/// One panel of a figure: title, y label, y range, optional y-tick names, lines.
type Panel<'a> = (
    &'a str,
    &'a str,
    (f64, f64),
    Option<&'a [&'a str]>,
    Vec<Series>,
);

/// Renders one or two stacked panels into an SVG string.
fn render(panels: &[Panel<'_>], x_max: f64) -> Result<String> {
    let mut svg = String::new();
    {
        let size = (FIGURE_SIZE.0, FIGURE_SIZE.1 * panels.len() as u32);
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let areas = root.split_evenly((panels.len(), 1));
        for (area, (title, y_label, y_range, names, series)) in areas.iter().zip(panels) {
            panel(area, title, y_label, x_max, *y_range, *names, series)?;
        }
        root.present().map_err(plot_err)?;
    }
    Ok(svg)
}

/// The x coordinate of a record: its 1-based frame number.
fn fx(r: &FrameRecord) -> f64 {
    (r.frame + 1) as f64
}

fn x_max(records: &[FrameRecord]) -> f64 {
    records.iter().map(fx).fold(1.0, f64::max)
}

/// A y range covering `values` with a 5 % margin (and a unit range when they are all equal).
fn y_range(values: impl Iterator<Item = f64>, floor: Option<f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        0.5 * hi.abs().max(1.0)
    };
    let lo = floor.map_or(lo - pad, |f| (lo - pad).max(f));
    (lo, hi + pad)
}

/// β̂ over time (top) and the posterior probability of each clutter class (bottom); `None` when
/// no record has β.
///
/// # Errors
/// [`AppError::Computation`] for a non-finite probability (naming the frame) or a plotting failure.
pub fn plot_beta(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
) -> Result<Option<Figure>> {
    beta_figure(records, smoothed, &PlotOptions::default())
}

fn beta_figure(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
    options: &PlotOptions,
) -> Result<Option<Figure>> {
    let k = records
        .iter()
        .map(|r| r.beta_probs.len())
        .max()
        .unwrap_or(0);
    let k = k.max(
        records
            .iter()
            .filter_map(|r| r.beta_hat)
            .map(|b| b + 1)
            .max()
            .unwrap_or(0),
    );
    if k == 0 {
        return Ok(None);
    }
    let beta_hat = |rs: &[FrameRecord]| -> Vec<(f64, f64)> {
        rs.iter()
            .filter_map(|r| r.beta_hat.map(|b| (fx(r), b as f64)))
            .collect()
    };
    let mut hat = hat_series(beta_hat(records), smoothed.map(beta_hat));
    hat.extend(options.truth_series(records, "true class", |t| t.beta.map(|b| b as f64)));
    let mut probs = Vec::with_capacity(k);
    for c in 0..k {
        let mut points = Vec::new();
        for r in records {
            if let Some(&p) = r.beta_probs.get(c) {
                points.push((fx(r), finite(p, r.frame, "a clutter-class probability")?));
            }
        }
        probs.push(Series {
            label: format!("P(β = {c})"),
            colour: rgb(CLUTTER[c % CLUTTER.len()]),
            points,
        });
        if let Some(smoothed) = smoothed {
            probs.push(probability_series(
                smoothed,
                |r| r.beta_probs.get(c).copied(),
                format!("P(β = {c}) smoothed"),
                rgb(CLUTTER[c % CLUTTER.len()]),
                "a clutter-class probability",
            )?);
        }
    }
    let names: Vec<String> = (0..k).map(|c| format!("β={c}")).collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let svg = render(
        &[
            (
                "estimated clutter class β̂",
                "β̂",
                (-0.5, k as f64 - 0.5),
                Some(&names),
                hat,
            ),
            (
                "clutter-class probabilities",
                "probability",
                (0.0, 1.0),
                None,
                probs,
            ),
        ],
        x_max(records),
    )?;
    Ok(Some(Figure {
        name: "beta",
        title: "Clutter class β̂".into(),
        svg,
    }))
}

/// A single-series figure of an optional per-frame value; `None` when no record has it.
#[allow(clippy::too_many_arguments)]
fn scalar_figure(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
    name: &'static str,
    title: &str,
    y_label: &str,
    get: impl Fn(&FrameRecord) -> Option<f64>,
    fixed_range: Option<(f64, f64)>,
    colour: RGBColor,
    truth: Option<Series>,
) -> Result<Option<Figure>> {
    let mut points = Vec::new();
    for r in records {
        if let Some(v) = get(r) {
            points.push((fx(r), finite(v, r.frame, y_label)?));
        }
    }
    if points.is_empty() {
        return Ok(None);
    }
    let mut series = vec![Series {
        label: if smoothed.is_some() || truth.is_some() {
            "filtered".into()
        } else {
            String::new()
        },
        colour,
        points,
    }];
    if let Some(smoothed) = smoothed {
        let mut points = Vec::new();
        for r in smoothed {
            if let Some(v) = get(r) {
                points.push((fx(r), finite(v, r.frame, y_label)?));
            }
        }
        series.push(Series {
            label: "smoothed".into(),
            colour: SMOOTHED,
            points,
        });
    }
    series.extend(truth);
    let range = fixed_range.unwrap_or_else(|| {
        y_range(
            series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
            Some(0.0),
        )
    });
    let svg = render(&[(title, y_label, range, None, series)], x_max(records))?;
    Ok(Some(Figure {
        name,
        title: title.to_string(),
        svg,
    }))
}

/// λ̂ (clutter density, edges per pixel) over time; `None` when no record has it.
///
/// # Errors
/// As [`plot_beta`].
pub fn plot_lambda(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
) -> Result<Option<Figure>> {
    lambda_figure(records, smoothed, &PlotOptions::default())
}

fn lambda_figure(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
    options: &PlotOptions,
) -> Result<Option<Figure>> {
    scalar_figure(
        records,
        smoothed,
        "lambda",
        "clutter density λ̂ (edges per pixel)",
        "λ̂",
        |r| r.lambda_hat,
        None,
        RGBColor(60, 90, 200),
        options.truth_series(records, "true edge density", |t| t.lambda),
    )
}

/// γ̂ (occlusion, W Eq. 14) over time, on [0, 1]; `None` when no record has it.
///
/// # Errors
/// As [`plot_beta`].
pub fn plot_gamma(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
) -> Result<Option<Figure>> {
    gamma_figure(records, smoothed, &PlotOptions::default())
}

fn gamma_figure(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
    options: &PlotOptions,
) -> Result<Option<Figure>> {
    if !options.occlusion {
        return Ok(None);
    }
    scalar_figure(
        records,
        smoothed,
        "gamma",
        "occlusion γ̂",
        "γ̂",
        |r| r.gamma_hat,
        Some((0.0, 1.0)),
        RGBColor(160, 60, 160),
        options.truth_series(records, "true occluded fraction", |t| t.gamma),
    )
}

/// The effective sample size over time; `None` for no records.
///
/// # Errors
/// As [`plot_beta`].
pub fn plot_ess(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
) -> Result<Option<Figure>> {
    scalar_figure(
        records,
        smoothed,
        "ess",
        "effective sample size",
        "ESS",
        |r| Some(r.ess),
        None,
        RGBColor(30, 30, 30),
        None,
    )
}

/// The IoU of the estimated box with the ground-truth box over time, on the frames that have
/// one; `None` when none has. The smoothed records' IoU is drawn beside, when given.
///
/// # Errors
/// As [`plot_beta`].
pub fn plot_iou(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
    options: &PlotOptions,
) -> Result<Option<Figure>> {
    let iou = |r: &FrameRecord| -> Option<f64> {
        options
            .truth_at(r.frame)
            .and_then(|t| t.bbox)
            .filter(|b| b.is_finite() && b.w > 0.0 && b.h > 0.0)
            .map(|b| r.bbox.iou(&b))
    };
    scalar_figure(
        records,
        smoothed,
        "iou",
        "overlap with the ground truth (IoU)",
        "IoU",
        iou,
        Some((0.0, 1.0)),
        RGBColor(0, 120, 60),
        None,
    )
}

/// α̂ over time (top: locked, partial, lost) and the probability of each status (bottom); `None`
/// when no record has α.
///
/// # Errors
/// As [`plot_beta`].
pub fn plot_alpha(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
) -> Result<Option<Figure>> {
    alpha_figure(records, smoothed, &PlotOptions::default())
}

fn alpha_figure(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
    options: &PlotOptions,
) -> Result<Option<Figure>> {
    let has = records
        .iter()
        .any(|r| r.alpha_hat.is_some() || !r.alpha_probs.is_empty());
    if !has {
        return Ok(None);
    }
    let alpha_hat = |rs: &[FrameRecord]| -> Vec<(f64, f64)> {
        rs.iter()
            .filter_map(|r| r.alpha_hat.map(|a| (fx(r), a.index() as f64)))
            .collect()
    };
    let mut hat = hat_series(alpha_hat(records), smoothed.map(alpha_hat));
    hat.extend(options.truth_series(records, "true status", |t| {
        t.alpha.map(|a| a.index() as f64)
    }));
    let mut probs = Vec::new();
    for (status, colour) in TrackStatus::ALL.iter().zip([LOCKED, PARTIAL, LOST]) {
        if !options.statuses[status.index()] {
            continue;
        }
        let mut points = Vec::new();
        for r in records {
            if let Some(&p) = r.alpha_probs.get(status.index()) {
                points.push((fx(r), finite(p, r.frame, "a status probability")?));
            }
        }
        probs.push(Series {
            label: format!("P({})", status.name()),
            colour: rgb(colour),
            points,
        });
        if let Some(smoothed) = smoothed {
            probs.push(probability_series(
                smoothed,
                |r| r.alpha_probs.get(status.index()).copied(),
                format!("P({}) smoothed", status.name()),
                rgb(colour),
                "a status probability",
            )?);
        }
    }
    let names = TrackStatus::ALL.map(TrackStatus::name);
    let svg = render(
        &[
            ("tracker status α̂", "α̂", (-0.5, 2.5), Some(&names), hat),
            (
                "status probabilities",
                "probability",
                (0.0, 1.0),
                None,
                probs,
            ),
        ],
        x_max(records),
    )?;
    Ok(Some(Figure {
        name: "alpha",
        title: "Tracker status α̂".into(),
        svg,
    }))
}

/// Every figure the records have data for, in the order β̂, λ̂, γ̂, α̂, ESS; with `smoothed`
/// records (`track run --smooth`), each figure draws the smoothed curves beside the filtered ones.
///
/// # Errors
/// As [`plot_beta`].
pub fn all_figures(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
) -> Result<Vec<Figure>> {
    all_figures_with(records, smoothed, &PlotOptions::default())
}

/// [`all_figures`] for a tracker and a truth ([`PlotOptions`]): the figures the tracker's
/// quantities call for, the truth drawn beside the estimates, and the IoU over time (after
/// α̂) when there are ground-truth boxes.
///
/// # Errors
/// As [`plot_beta`].
pub fn all_figures_with(
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
    options: &PlotOptions,
) -> Result<Vec<Figure>> {
    let mut out = Vec::new();
    for f in [
        beta_figure,
        lambda_figure,
        gamma_figure,
        alpha_figure,
        plot_iou,
    ] {
        out.extend(f(records, smoothed, options)?);
    }
    out.extend(plot_ess(records, smoothed)?);
    Ok(out)
}

/// The colour of smoothed curves.
const SMOOTHED: RGBColor = RGBColor(230, 120, 20);

/// The estimated class over time: one black line, or "filtered" and "smoothed" lines.
fn hat_series(filtered: Vec<(f64, f64)>, smoothed: Option<Vec<(f64, f64)>>) -> Vec<Series> {
    let mut out = vec![Series {
        label: if smoothed.is_some() {
            "filtered".into()
        } else {
            String::new()
        },
        colour: RGBColor(30, 30, 30),
        points: filtered,
    }];
    if let Some(points) = smoothed {
        out.push(Series {
            label: "smoothed".into(),
            colour: SMOOTHED,
            points,
        });
    }
    out
}

/// A probability per frame of the smoothed records, drawn in a lighter shade of `colour`.
fn probability_series(
    records: &[FrameRecord],
    get: impl Fn(&FrameRecord) -> Option<f64>,
    label: String,
    colour: RGBColor,
    what: &str,
) -> Result<Series> {
    let mut points = Vec::new();
    for r in records {
        if let Some(p) = get(r) {
            points.push((fx(r), finite(p, r.frame, what)?));
        }
    }
    let RGBColor(r, g, b) = colour;
    let light = |c: u8| c + (255 - c) / 2;
    Ok(Series {
        label,
        colour: RGBColor(light(r), light(g), light(b)),
        points,
    })
}

/// Writes each figure as `DIR/NAME.svg` atomically; returns the paths written.
///
/// # Errors
/// [`AppError::Write`].
pub fn write_figures(dir: &Path, figures: &[Figure]) -> Result<Vec<PathBuf>> {
    figures
        .iter()
        .map(|f| {
            let path = dir.join(format!("{}.svg", f.name));
            write_atomic(&path, f.svg.as_bytes()).map(|()| path)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use vision_core::Ellipse;

    fn records(full: bool) -> Vec<FrameRecord> {
        (0..40)
            .map(|i| {
                let mut r = FrameRecord::new(
                    i,
                    Ellipse::new(50.0, 50.0, 10.0, 8.0, 0.0),
                    100.0 + i as f64,
                    2.0,
                );
                if full {
                    let b = (i / 15) % 3;
                    r.beta_hat = Some(b);
                    r.beta_probs = (0..3).map(|c| if c == b { 0.8 } else { 0.1 }).collect();
                    r.lambda_hat = Some([0.01, 0.0824, 0.2144][b]);
                    r.gamma_hat = Some(i as f64 / 40.0);
                    r.alpha_hat = Some(TrackStatus::ALL[b]);
                    r.alpha_probs = vec![0.6, 0.3, 0.1];
                }
                r
            })
            .collect()
    }

    #[test]
    fn every_figure_for_a_switching_tracker() {
        let figs = all_figures(&records(true), None).unwrap();
        let names: Vec<&str> = figs.iter().map(|f| f.name).collect();
        assert_eq!(names, ["beta", "lambda", "gamma", "alpha", "ess"]);
        for f in &figs {
            assert!(
                f.svg.starts_with("<svg") && f.svg.trim_end().ends_with("</svg>"),
                "{}",
                f.name
            );
            assert!(f.svg.contains("<polyline"), "{} has no line", f.name);
            assert!(f.svg.contains("frame"), "{} has no axis label", f.name);
        }
        let beta = &figs[0].svg;
        assert!(beta.contains("P(β = 2)") && beta.contains("β=1"));
        assert!(figs[3].svg.contains("partial"));
    }

    #[test]
    fn smoothed_curves_are_drawn_beside_the_filtered_ones() {
        let filtered = records(true);
        let smoothed = records(true);
        let figs = all_figures(&filtered, Some(&smoothed)).unwrap();
        assert_eq!(figs.len(), 5);
        for f in &figs {
            assert!(f.svg.contains("smoothed"), "{}", f.name);
            assert!(f.svg.contains("filtered"), "{}", f.name);
        }
        let plain = all_figures(&filtered, None).unwrap();
        assert!(plain.iter().all(|f| !f.svg.contains("smoothed")));
    }

    #[test]
    fn absent_quantities_have_no_figure() {
        let figs = all_figures(&records(false), None).unwrap();
        assert_eq!(figs.len(), 1);
        assert_eq!(figs[0].name, "ess");
        assert!(all_figures(&[], None).unwrap().is_empty());
    }

    #[test]
    fn nan_is_reported_with_its_frame() {
        let mut rs = records(true);
        rs[7].lambda_hat = Some(f64::NAN);
        let msg = plot_lambda(&rs, None).unwrap_err().to_string();
        assert!(msg.contains("frame 8"), "{msg}");
    }

    #[test]
    fn the_lock_chains_p_lost_is_no_occlusion_and_it_has_no_partial_state() {
        let head = PlotOptions::of_tracker(&trackers::Preset::Head.config(50, 1));
        let mut rs = records(false);
        for r in &mut rs {
            // What the lock chain records: γ̂ = P(lost) and P(partial) = 0.
            r.gamma_hat = Some(0.1);
            r.alpha_hat = Some(TrackStatus::Locked);
            r.alpha_probs = vec![0.9, 0.0, 0.1];
        }
        let figs = all_figures_with(&rs, None, &head).unwrap();
        let names: Vec<&str> = figs.iter().map(|f| f.name).collect();
        assert_eq!(names, ["alpha", "ess"]);
        assert!(!figs[0].svg.contains("P(partial)"), "P(partial) drawn");
        assert!(figs[0].svg.contains("P(locked)") && figs[0].svg.contains("P(lost)"));
        // The contour trackers keep both.
        let full = PlotOptions::of_tracker(&trackers::Preset::Full.config(50, 1));
        let figs = all_figures_with(&rs, None, &full).unwrap();
        assert!(figs.iter().any(|f| f.name == "gamma"));
        assert!(figs.iter().any(|f| f.svg.contains("P(partial)")));
    }

    #[test]
    fn iou_over_time_and_truth_curves_are_drawn_where_the_truth_is_known() {
        let rs = records(true);
        // The box of every record is (40, 42, 20, 16); the truth is that box on even frames,
        // nothing on odd ones, and the hidden values of a scene on every frame.
        let truth: Vec<TruthAt> = (0..40)
            .map(|i| TruthAt {
                bbox: (i % 2 == 0).then(|| BoundingBox::new(40.0, 42.0, 20.0, 16.0)),
                beta: Some(1),
                lambda: Some(0.05),
                gamma: Some(0.0),
                alpha: Some(TrackStatus::Locked),
            })
            .collect();
        let options = PlotOptions::default().with_truth(truth);
        let figs = all_figures_with(&rs, None, &options).unwrap();
        let names: Vec<&str> = figs.iter().map(|f| f.name).collect();
        assert_eq!(names, ["beta", "lambda", "gamma", "alpha", "iou", "ess"]);
        let iou = &figs[4].svg;
        assert!(iou.contains("IoU"));
        // 20 labelled frames: one polyline of 20 points at IoU 1 (the top of the y range).
        let counts: Vec<usize> = iou
            .split("<polyline")
            .skip(1)
            .filter_map(|l| l.split("points=\"").nth(1)?.split('"').next())
            .map(|p| p.split_whitespace().count())
            .collect();
        assert!(counts.contains(&20), "{counts:?}");
        for (f, label) in [
            (0, "true class"),
            (1, "true edge density"),
            (2, "true occluded fraction"),
            (3, "true status"),
        ] {
            assert!(
                figs[f].svg.contains(label),
                "{} lacks {label}",
                figs[f].name
            );
        }
        // Without truth: no IoU figure, no truth curve.
        let plain = all_figures(&rs, None).unwrap();
        assert!(
            plain
                .iter()
                .all(|f| f.name != "iou" && !f.svg.contains("true "))
        );
    }

    #[test]
    fn figures_are_written_atomically() {
        let dir = tempfile::tempdir().unwrap();
        let figs = all_figures(&records(true), None).unwrap();
        let paths = write_figures(dir.path(), &figs).unwrap();
        assert_eq!(paths.len(), 5);
        assert_eq!(std::fs::read_to_string(&paths[4]).unwrap(), figs[4].svg);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 5);
    }
}
