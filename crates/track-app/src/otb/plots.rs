//! OTB's success and precision plots as SVG: one curve per tracker, its success AUC or its
//! precision at 20 px in the legend, the legend ordered best first, as the OTB toolkit draws them.

use plotters::prelude::*;

use super::{Protocol, SequenceScore};
use crate::metrics::{PRECISION_CURVE_MAX_PX, success_thresholds};
use crate::{AppError, Result};

/// Size of each chart, pixels.
pub const CHART_SIZE: (u32, u32) = (560, 420);

/// Line colours, one per tracker in turn (OTB's palette is as long as its tracker list; this one
/// repeats after ten).
const PALETTE: [RGBColor; 10] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Which plot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Success rate against the overlap threshold; legend: success AUC.
    Success,
    /// Precision against the centre-error threshold (0–50 px); legend: precision at 20 px.
    Precision,
}

impl Kind {
    /// `success` or `precision`.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Success => "success",
            Kind::Precision => "precision",
        }
    }
}

/// One rendered chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Chart {
    /// File name, e.g. `success.svg` or `precision_Boy.svg`.
    pub file: String,
    /// Title.
    pub title: String,
    /// The SVG document.
    pub svg: String,
}

/// One curve: its legend, the figure the legend gives, its points and colour.
struct Curve {
    label: String,
    score: f64,
    points: Vec<(f64, f64)>,
    colour: RGBColor,
}

fn plot_err(e: impl std::fmt::Display) -> AppError {
    AppError::computation("plotting", e)
}

/// The chart of `kind` with one curve per row of `rows` (one row per tracker: a sequence's or
/// the set's mean), titled after `protocol` and `over` (`None`: the whole set).
///
/// # Errors
/// [`AppError::Computation`] when a curve holds a value that is not finite, or plotters fails.
pub fn chart(
    kind: Kind,
    protocol: Protocol,
    over: Option<&str>,
    rows: &[&SequenceScore],
) -> Result<Chart> {
    let title = match (kind, over) {
        (Kind::Success, None) => format!("Success plots of {}", protocol.title()),
        (Kind::Precision, None) => format!("Precision plots of {}", protocol.title()),
        (Kind::Success, Some(s)) => format!("Success plot of {} on {s}", protocol.title()),
        (Kind::Precision, Some(s)) => format!("Precision plot of {} on {s}", protocol.title()),
    };
    let file = match over {
        None => format!("{}.svg", kind.name()),
        // A clip of a stress suite is named `<transform>/<clip>`: one file name all the same.
        Some(s) => format!("{}_{}.svg", kind.name(), s.replace('/', "_")),
    };
    // Curves with their legend figure, best first (OTB's order).
    let mut curves: Vec<Curve> = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        let m = &r.metrics;
        let (score, points): (f64, Vec<(f64, f64)>) = match kind {
            Kind::Success => (
                m.success_auc,
                success_thresholds()
                    .iter()
                    .zip(&m.success_curve)
                    .map(|(&t, &v)| (t, v))
                    .collect(),
            ),
            Kind::Precision => (
                m.precision_20,
                m.precision_curve
                    .iter()
                    .enumerate()
                    .map(|(t, &v)| (t as f64, v))
                    .collect(),
            ),
        };
        if !score.is_finite() || points.iter().any(|p| !p.1.is_finite()) {
            return Err(AppError::computation(
                "plotting",
                format!("{title}: the curve of {} is not finite", r.tracker),
            ));
        }
        curves.push(Curve {
            label: format!("{} [{score:.3}]", r.tracker),
            score,
            points,
            colour: PALETTE[i % PALETTE.len()],
        });
    }
    curves.sort_by(|a, b| b.score.total_cmp(&a.score));
    let (x_desc, y_desc, x_max) = match kind {
        Kind::Success => ("Overlap threshold", "Success rate", 1.0),
        Kind::Precision => (
            "Location error threshold (px)",
            "Precision",
            PRECISION_CURVE_MAX_PX as f64,
        ),
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, CHART_SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let mut c = ChartBuilder::on(&root)
            .caption(&title, ("sans-serif", 18))
            .margin(10)
            .margin_right(20)
            .x_label_area_size(36)
            .y_label_area_size(48)
            .build_cartesian_2d(0.0..x_max, 0.0..1.0)
            .map_err(plot_err)?;
        let x_fmt = |v: &f64| match kind {
            Kind::Success => format!("{v:.1}"),
            Kind::Precision => format!("{v:.0}"),
        };
        c.configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&|v: &f64| format!("{v:.1}"))
            .light_line_style(WHITE)
            .draw()
            .map_err(plot_err)?;
        for curve in &curves {
            let colour = curve.colour;
            c.draw_series(LineSeries::new(
                curve.points.iter().copied(),
                colour.stroke_width(2),
            ))
            .map_err(plot_err)?
            .label(curve.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
            });
        }
        c.configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(match kind {
                Kind::Success => SeriesLabelPosition::LowerLeft,
                Kind::Precision => SeriesLabelPosition::LowerRight,
            })
            .draw()
            .map_err(plot_err)?;
        root.present().map_err(plot_err)?;
    }
    Ok(Chart { file, title, svg })
}

/// Every chart of one protocol: success and precision over the whole set (each tracker's mean
/// over sequences), then success and precision on each sequence.
///
/// # Errors
/// As [`chart`].
pub fn protocol_charts(
    protocol: Protocol,
    rows: &[SequenceScore],
    means: &[SequenceScore],
) -> Result<Vec<Chart>> {
    let mean_refs: Vec<&SequenceScore> = means.iter().collect();
    let mut charts = vec![
        chart(Kind::Success, protocol, None, &mean_refs)?,
        chart(Kind::Precision, protocol, None, &mean_refs)?,
    ];
    for seq in super::sequence_names(rows) {
        let mine: Vec<&SequenceScore> = rows.iter().filter(|r| r.sequence == seq).collect();
        charts.push(chart(Kind::Success, protocol, Some(&seq), &mine)?);
        charts.push(chart(Kind::Precision, protocol, Some(&seq), &mine)?);
    }
    Ok(charts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::score_run;
    use vision_core::BoundingBox;

    fn row(tracker: &str, shift: f64) -> SequenceScore {
        let gt = BoundingBox::new(10.0, 10.0, 20.0, 20.0);
        let truth = vec![Some(gt); 6];
        let pred: Vec<_> = (0..6)
            .map(|i| Some(BoundingBox::new(10.0 + shift * i as f64, 10.0, 20.0, 20.0)))
            .collect();
        SequenceScore {
            sequence: "seq".into(),
            tracker: tracker.into(),
            runs: 1,
            metrics: score_run(&pred, &truth, 0, None).unwrap().unwrap(),
        }
    }

    #[test]
    fn legends_carry_the_scores_best_first() {
        let rows = [row("good", 0.0), row("bad", 8.0)];
        let refs: Vec<&SequenceScore> = rows.iter().collect();
        let s = chart(Kind::Success, Protocol::Tre, None, &refs).unwrap();
        assert_eq!(s.file, "success.svg");
        assert!(s.svg.contains("Success plots of TRE"));
        let good = format!("good [{:.3}]", rows[0].metrics.success_auc);
        let bad = format!("bad [{:.3}]", rows[1].metrics.success_auc);
        let (g, b) = (s.svg.find(&good).unwrap(), s.svg.find(&bad).unwrap());
        assert!(g < b, "the better tracker is listed first");
        let p = chart(Kind::Precision, Protocol::Sre, Some("seq"), &refs).unwrap();
        assert_eq!(p.file, "precision_seq.svg");
        assert!(
            p.svg
                .contains(&format!("bad [{:.3}]", rows[1].metrics.precision_20))
        );
        assert!(p.svg.contains("Location error threshold"));
    }

    #[test]
    fn a_curve_that_is_not_finite_is_an_error() {
        let mut r = row("x", 0.0);
        r.metrics.success_curve[3] = f64::NAN;
        let e = chart(Kind::Success, Protocol::Ope, None, &[&r]).unwrap_err();
        assert!(e.to_string().contains("not finite"), "{e}");
    }
}
