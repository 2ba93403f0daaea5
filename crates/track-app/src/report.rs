//! One self-contained HTML page per run: a title, the command line, a table of metrics with notes
//! on how to read them, a strip of overlay frames inlined as base64 PNG with the legend of their
//! colours, and the SVG plots inlined. It needs no other file and no network, so it can
//! be mailed or attached as it is.

use std::fmt::Write as _;
use std::path::Path;

use base64::Engine as _;
use image::RgbImage;

use crate::Result;
use crate::output::write_atomic;
use crate::plots::Figure;
use crate::record::Summary;
use crate::render::{LEGEND, encode_png, thumbnail};

/// Width of the frames in the strip, pixels (larger frames are scaled down).
pub const STRIP_WIDTH: u32 = 200;

/// What goes into a report.
#[derive(Debug, Clone, Default)]
pub struct ReportInput {
    /// Page title.
    pub title: String,
    /// A sentence under the title (for example the command that produced it).
    pub subtitle: String,
    /// Rows of the metrics table: name, value.
    pub metrics: Vec<(String, String)>,
    /// Plots, inlined as SVG.
    pub figures: Vec<Figure>,
    /// Overlay frames with their captions, inlined as PNG (scaled to [`STRIP_WIDTH`]); the
    /// legend of their colours ([`LEGEND`]) follows them.
    pub strip: Vec<(String, RgbImage)>,
    /// Paragraphs under the metrics table: how to read them ([`standard_notes`], [`ess_note`]).
    pub notes: Vec<String>,
}

/// Escapes text for HTML element content and attribute values.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for ch in text.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// `count` frame indices spread evenly over `frames` frames, first and last included (all of them
/// when there are fewer frames than `count`).
pub fn strip_indices(frames: usize, count: usize) -> Vec<usize> {
    if frames == 0 || count == 0 {
        return Vec::new();
    }
    if count >= frames {
        return (0..frames).collect();
    }
    if count == 1 {
        return vec![0];
    }
    let mut v: Vec<usize> = (0..count)
        .map(|i| (i * (frames - 1) + (count - 1) / 2) / (count - 1))
        .collect();
    v.dedup();
    v
}

/// How the frames without a tracker status are described after the status counts: empty when
/// every frame has one, else the count and why (the initialisation frame has no estimate).
pub fn unstated_text(unstated: usize) -> String {
    match unstated {
        0 => String::new(),
        1 => " (frame 1, the initialisation, has no status)".to_owned(),
        n => format!(" ({n} frames without a status, the initialisation among them)"),
    }
}

/// The metrics-table rows of a run summary: sequence, tracker, particles, seed, frames, size,
/// speed, the status counts, the GIF, and the scores when there is ground truth.
pub fn summary_rows(s: &Summary) -> Vec<(String, String)> {
    let mut rows = vec![
        ("sequence".to_string(), s.sequence.clone()),
        ("tracker".to_string(), s.tracker.clone()),
        ("particles".to_string(), s.particles.to_string()),
        ("seed".to_string(), s.seed.to_string()),
        ("frames".to_string(), s.frames.to_string()),
        (
            "frame size".to_string(),
            format!("{}×{}", s.width, s.height),
        ),
        (
            "tracking rate, frames/s (the tracker alone: no decoding, no drawing)".to_string(),
            format!("{:.1}", s.fps),
        ),
        (
            "tracking time per frame, ms".to_string(),
            format!("{:.2}", s.mean_millis),
        ),
    ];
    if let Some(w) = s.wall_seconds {
        rows.push((
            "wall-clock rate, frames/s (reading, decoding, tracking and drawing)".to_string(),
            format!("{:.1}", s.frames as f64 / w.max(1e-9)),
        ));
    }
    if let Some(i) = &s.interrupted {
        rows.push((
            "interrupted".into(),
            format!("{} after {} frames read", i.reason, i.frames_read),
        ));
    }
    if let Some([l, p, o]) = s.status_counts {
        let unstated = s.frames.saturating_sub(l + p + o);
        rows.push((
            "frames locked / partial / lost".into(),
            format!("{l} / {p} / {o}{}", unstated_text(unstated)),
        ));
    }
    if let Some(g) = &s.gif {
        rows.push((
            "animated GIF (track.gif)".into(),
            if g.frames >= g.tracked {
                format!(
                    "all {} frames, {:.2} s each",
                    g.frames,
                    f64::from(g.delay_ms) / 1e3
                )
            } else {
                format!(
                    "{} of {} frames (one every {}), {:.2} s each",
                    g.frames,
                    g.tracked,
                    g.stride,
                    f64::from(g.delay_ms) / 1e3
                )
            },
        ));
    }
    if let Some(m) = &s.metrics {
        rows.push(("labelled frames".into(), m.labelled_frames.to_string()));
        rows.push((
            "precision at 20 px".into(),
            format!("{:.3}", m.precision_20),
        ));
        rows.push(("success AUC".into(), format!("{:.3}", m.success_auc)));
        rows.push(("mean IoU".into(), format!("{:.3}", m.mean_iou)));
        rows.push((
            "mean centre error (px)".into(),
            format!("{:.1}", m.mean_centre_error),
        ));
        let failed = m
            .failed_at_frame
            .map_or_else(|| "never".to_string(), |f| format!("frame {}", f + 1));
        rows.push((
            "trial failed (IoU < 0.2 for 5 labelled frames)".into(),
            failed,
        ));
    }
    rows
}

/// Notes every report carries: what the rates measure, and the GIF's frames when it leaves some
/// out.
pub fn standard_notes(s: &Summary) -> Vec<String> {
    let mut notes = vec![
        "The tracking rate counts the tracker's own time per frame only; the wall-clock rate \
         counts everything from start to the end of tracking: reading and decoding the frames \
         (and the pre-scan that checks them first), tracking, and drawing and writing overlays."
            .to_owned(),
    ];
    if let Some(n) = s.gif.and_then(|g| g.notice()) {
        notes.push(format!("The animated GIF: {n}."));
    }
    notes
}

/// What the effective sample size (ESS) plot shows, for a tracker whose likelihood is tempered
/// or not.
pub fn ess_note(tempered: bool) -> String {
    if tempered {
        "ESS: the effective sample size 1/Σw² of the weights after weighting. The tracker \
         tempers its likelihood (raises it to the largest power ≤ 1 that keeps the ESS at its \
         floor), so the ESS stays at or above that floor by design."
            .to_owned()
    } else {
        "ESS: the effective sample size 1/Σw² of the normalised weights just after weighting, \
         before resampling (N at frame 1, where nothing is weighted). The trackers do not \
         temper their weights: the likelihood (the evidence of every measurement line, or the \
         colour and template of the appearance terms) is sharp next to the spread of the \
         predicted particles, so a few particles \
         carry most of the weight, and an ESS of a few percent of the particles is the usual \
         state of these filters, not a fault (docs/RESULTS.md, \"ESS of the contour \
         trackers\"). The filter resamples every frame, so the particles are renewed around the \
         heavy ones. What marks a failing run is not a low ESS alone but one that stays near 1 \
         while the estimate drifts off the target."
            .to_owned()
    }
}

pub(crate) const STYLE: &str = "body{font-family:system-ui,sans-serif;max-width:1500px;margin:2em auto;\
padding:0 1em;color:#222}table{border-collapse:collapse}td,th{border:1px solid #ccc;\
padding:4px 10px;text-align:left}td.v{text-align:right;font-variant-numeric:tabular-nums}\
.strip{display:flex;flex-wrap:wrap;gap:8px}figure{margin:0}figcaption{font-size:.85em;\
color:#555}.plot svg{max-width:100%;height:auto}p.note{max-width:60em;color:#444}";

/// Renders the page.
///
/// # Errors
/// [`crate::AppError::Computation`] when a strip frame cannot be encoded.
pub fn render_html(input: &ReportInput) -> Result<String> {
    let mut h = String::new();
    let title = escape(&input.title);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{title}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<h1>{title}</h1>\n"
    );
    if !input.subtitle.is_empty() {
        let _ = writeln!(h, "<p>{}</p>", escape(&input.subtitle));
    }
    if !input.metrics.is_empty() {
        h.push_str("<h2>Metrics</h2>\n<table>\n");
        for (k, v) in &input.metrics {
            let _ = writeln!(
                h,
                "<tr><th>{}</th><td class=\"v\">{}</td></tr>",
                escape(k),
                escape(v)
            );
        }
        h.push_str("</table>\n");
    }
    for note in &input.notes {
        let _ = writeln!(h, "<p class=\"note\">{}</p>", escape(note));
    }
    if !input.strip.is_empty() {
        h.push_str("<h2>Frames</h2>\n<div class=\"strip\">\n");
        let b64 = base64::engine::general_purpose::STANDARD;
        for (caption, img) in &input.strip {
            let png = encode_png(&thumbnail(img, STRIP_WIDTH))?;
            let cap = escape(caption);
            let _ = writeln!(
                h,
                "<figure><img alt=\"{cap}\" src=\"data:image/png;base64,{}\"><figcaption>{cap}</figcaption></figure>",
                b64.encode(png)
            );
        }
        h.push_str("</div>\n<h3>Legend</h3>\n<ul class=\"legend\">\n");
        for line in LEGEND {
            let _ = writeln!(h, "<li>{}</li>", escape(line));
        }
        h.push_str("</ul>\n");
    }
    if !input.figures.is_empty() {
        h.push_str("<h2>Plots</h2>\n");
        for f in &input.figures {
            // plotters' SVG has no XML declaration, so it can be inlined as it is.
            let _ = writeln!(
                h,
                "<h3>{}</h3>\n<div class=\"plot\">{}</div>",
                escape(&f.title),
                f.svg
            );
        }
    }
    h.push_str("</body>\n</html>\n");
    Ok(h)
}

/// Renders the page and writes it atomically.
///
/// # Errors
/// As [`render_html`], and [`crate::AppError::Write`].
pub fn write_report(path: &Path, input: &ReportInput) -> Result<()> {
    write_atomic(path, render_html(input)?.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::evaluate;
    use crate::plots::all_figures;
    use crate::record::FrameRecord;
    use vision_core::{BoundingBox, Ellipse};

    #[test]
    fn strip_indices_are_even_and_include_both_ends() {
        assert_eq!(strip_indices(101, 5), vec![0, 25, 50, 75, 100]);
        assert_eq!(strip_indices(3, 8), vec![0, 1, 2]);
        assert_eq!(strip_indices(10, 1), vec![0]);
        assert!(strip_indices(0, 4).is_empty());
        let v = strip_indices(502, 6);
        assert_eq!((v[0], v[5], v.len()), (0, 501, 6));
    }

    #[test]
    fn escaping() {
        assert_eq!(escape("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&#39;");
    }

    #[test]
    fn page_is_self_contained_with_plots_metrics_and_frames() {
        let records: Vec<FrameRecord> = (0..10)
            .map(|i| FrameRecord::new(i, Ellipse::new(20.0, 20.0, 5.0, 5.0, 0.0), 50.0, 1.0))
            .collect();
        let gt = BoundingBox::new(15.0, 15.0, 10.0, 10.0);
        let boxes: Vec<BoundingBox> = records.iter().map(|r| r.bbox).collect();
        let summary = Summary {
            sequence: "<synthetic>".into(),
            tracker: "full".into(),
            frames: 10,
            fps: 100.0,
            metrics: Some(evaluate(&boxes, &[Some(gt); 10], Some(0.1)).unwrap()),
            ..Default::default()
        };
        let input = ReportInput {
            title: "track demo".into(),
            subtitle: "cargo run -p track-app -- demo".into(),
            metrics: summary_rows(&summary),
            figures: all_figures(&records, None).unwrap(),
            strip: vec![
                ("frame 1".into(), RgbImage::new(400, 300)),
                ("frame 10".into(), RgbImage::new(40, 30)),
            ],
            notes: Vec::new(),
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("report.html");
        write_report(&path, &input).unwrap();
        let html = std::fs::read_to_string(&path).unwrap();
        assert!(html.starts_with("<!DOCTYPE html>"));
        assert!(html.contains("&lt;synthetic&gt;"));
        assert!(html.contains("<th>precision at 20 px</th><td class=\"v\">1.000</td>"));
        assert!(html.contains("<th>success AUC</th><td class=\"v\">0.952</td>"));
        assert_eq!(html.matches("data:image/png;base64,").count(), 2);
        assert_eq!(html.matches("<svg").count(), 1);
        // Nothing is fetched from elsewhere.
        assert!(!html.contains("src=\"http") && !html.contains("href="));
        // The inlined image decodes, scaled to the strip width.
        let start = html.find("base64,").unwrap() + 7;
        let end = start + html[start..].find('"').unwrap();
        let png = base64::engine::general_purpose::STANDARD
            .decode(&html[start..end])
            .unwrap();
        let img = image::load_from_memory(&png).unwrap();
        assert_eq!((img.width(), img.height()), (STRIP_WIDTH, 150));
    }

    #[test]
    fn rates_say_what_they_count_and_status_counts_add_up() {
        let summary = Summary {
            frames: 100,
            seconds: 2.0,
            fps: 50.0,
            mean_millis: 20.0,
            wall_seconds: Some(4.0),
            status_counts: Some([90, 4, 5]),
            ..Default::default()
        };
        let rows = summary_rows(&summary);
        let get = |k: &str| -> String {
            rows.iter()
                .find(|(name, _)| name.starts_with(k))
                .map(|(_, v)| v.clone())
                .unwrap_or_else(|| panic!("no row {k}: {rows:?}"))
        };
        let tracking = rows
            .iter()
            .find(|(k, _)| k.starts_with("tracking rate"))
            .unwrap();
        assert!(
            tracking.0.contains("no decoding, no drawing"),
            "{}",
            tracking.0
        );
        assert_eq!(tracking.1, "50.0");
        assert_eq!(get("wall-clock rate"), "25.0");
        assert_eq!(
            get("frames locked / partial / lost"),
            "90 / 4 / 5 (frame 1, the initialisation, has no status)"
        );
        let every = Summary {
            status_counts: Some([90, 5, 5]),
            ..summary
        };
        let rows = summary_rows(&every);
        assert!(rows.contains(&("frames locked / partial / lost".into(), "90 / 5 / 5".into())));
    }

    #[test]
    fn notes_and_the_legend_are_on_the_page() {
        let summary = Summary {
            frames: 573,
            gif: Some(crate::record::GifSummary {
                frames: 144,
                tracked: 573,
                stride: 4,
                delay_ms: 250,
            }),
            ..Default::default()
        };
        let mut notes = standard_notes(&summary);
        notes.push(ess_note(false));
        let input = ReportInput {
            title: "t".into(),
            metrics: summary_rows(&summary),
            strip: vec![("frame 1".into(), RgbImage::new(8, 8))],
            notes,
            ..Default::default()
        };
        let html = render_html(&input).unwrap();
        assert!(html.contains("<th>animated GIF (track.gif)</th><td class=\"v\">144 of 573 frames (one every 4), 0.25 s each</td>"));
        assert!(html.contains("track.gif holds 144 of the 573 frames tracked"));
        assert!(html.contains("ESS: the effective sample size"));
        assert!(html.contains("<h3>Legend</h3>"));
        for line in LEGEND {
            assert!(html.contains(&escape(line)), "{line}");
        }
        assert!(ess_note(true).contains("tempers"));
    }
}
