//! Per-frame tracking records and the files written from them: `track.csv`, `boxes.txt` and
//! `summary.json`. Every file is written atomically, and a NaN or infinity is never written: it is
//! reported as an error naming the frame and the column.

use std::fmt::Write as _;
use std::path::Path;

use serde::{Deserialize, Serialize};
use vision_core::{BoundingBox, Ellipse, TrackStatus};

use crate::metrics::SequenceMetrics;
use crate::output::write_atomic;
use crate::{AppError, Result};

/// What the tracker believed at one frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    /// 0-based frame index (files show it 1-based, as image and ground-truth numbering do).
    pub frame: usize,
    /// The estimated contour as an ellipse.
    pub ellipse: Ellipse,
    /// Its axis-aligned bounding box (the tracker's box, docs/MODELS.md).
    pub bbox: BoundingBox,
    /// Effective sample size of the weights before resampling.
    pub ess: f64,
    /// Estimated clutter class β̂ (0-based index into `beta_probs`), for switching trackers.
    pub beta_hat: Option<usize>,
    /// Posterior probability of each clutter class (empty when there is no β).
    pub beta_probs: Vec<f64>,
    /// Estimated clutter density λ̂ per pixel.
    pub lambda_hat: Option<f64>,
    /// Estimated occlusion γ̂ = E\[γ\] (W Eq. 14).
    pub gamma_hat: Option<f64>,
    /// Estimated tracker status α̂.
    pub alpha_hat: Option<TrackStatus>,
    /// Posterior probability of locked, partial, lost (empty when there is no α).
    pub alpha_probs: Vec<f64>,
    /// Time spent on this frame, milliseconds.
    pub millis: f64,
}

impl FrameRecord {
    /// A record with the contour, ESS and time only; the switching estimates are absent. The box
    /// is the ellipse's bounding box.
    pub fn new(frame: usize, ellipse: Ellipse, ess: f64, millis: f64) -> Self {
        Self {
            frame,
            ellipse,
            bbox: ellipse.bounding_box(),
            ess,
            beta_hat: None,
            beta_probs: Vec::new(),
            lambda_hat: None,
            gamma_hat: None,
            alpha_hat: None,
            alpha_probs: Vec::new(),
            millis,
        }
    }
}

/// Formats `v` for a file, or fails naming the frame and column when it is NaN or infinite.
fn num(out: &mut String, v: f64, frame: usize, column: &str) -> Result<()> {
    if !v.is_finite() {
        return Err(AppError::computation(
            "track.csv",
            format!(
                "frame {}: {column} is {v}; refusing to write a non-finite value",
                frame + 1
            ),
        ));
    }
    // `{}` prints the shortest text that reads back as the same f64.
    let _ = write!(out, "{v}");
    Ok(())
}

/// The optional columns of `track.csv`: the β class probabilities and the α status
/// probabilities. They are a property of the tracker ([`CsvColumns::of_tracker`]), not of the
/// frames tracked, so that a one-frame run writes the same columns as a long one.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CsvColumns {
    /// Number of clutter classes K: columns `beta_p0…beta_p{K−1}` (0: none).
    pub beta_classes: usize,
    /// Whether the columns `alpha_p_locked,alpha_p_partial,alpha_p_lost` are written.
    pub status: bool,
}

impl CsvColumns {
    /// The columns of the tracker `config` builds: β probabilities for the contour trackers with
    /// switching clutter (one per class of its clutter model), α probabilities for the trackers
    /// that report them (the status HMM, the appearance terms' lock chain).
    pub fn of_tracker(config: &trackers::TrackerConfig) -> Self {
        Self {
            beta_classes: match &config.clutter {
                trackers::ClutterMode::Switching(c) => c.lambda_mean.len(),
                trackers::ClutterMode::Fixed { .. } => 0,
            },
            status: config.reports_status_probabilities(),
        }
    }

    /// The columns the records themselves need: every record has either no β probabilities or
    /// the same number, and α columns when any record has α probabilities.
    ///
    /// # Errors
    /// [`AppError::Computation`] naming the frame whose number of β probabilities differs.
    pub fn of_records(records: &[FrameRecord]) -> Result<Self> {
        Ok(Self {
            beta_classes: beta_width(records, 0)?,
            status: records.iter().any(|r| !r.alpha_probs.is_empty()),
        })
    }
}

/// The number of β classes across `records`, starting from `width` (0: not fixed yet): every
/// record has either none or the same number.
fn beta_width(records: &[FrameRecord], mut width: usize) -> Result<usize> {
    for r in records {
        let k = r.beta_probs.len();
        if k > 0 && width > 0 && k != width {
            return Err(AppError::computation(
                "track.csv",
                format!(
                    "frame {}: {k} clutter-class probabilities, expected {width}",
                    r.frame + 1
                ),
            ));
        }
        width = width.max(k);
    }
    Ok(width)
}

/// Renders `track.csv` with the columns the records need ([`CsvColumns::of_records`]); a
/// command that knows its tracker uses [`csv_string_with`] so that the columns do not depend on
/// the frames.
///
/// # Errors
/// As [`csv_string_with`].
pub fn csv_string(records: &[FrameRecord]) -> Result<String> {
    csv_string_with(records, CsvColumns::of_records(records)?)
}

/// Renders `track.csv`: a header row and one row per record; absent values are empty cells.
///
/// Columns: `frame` (1-based), `cx,cy,a,b,angle` (ellipse, angle in radians), `x,y,w,h` (box),
/// `ess`, `beta_hat` (0-based class), `beta_p0…beta_p{K−1}` (when `columns.beta_classes` is
/// K > 0), `lambda_hat`, `gamma_hat`, `alpha_hat` (`locked`/`partial`/`lost`),
/// `alpha_p_locked,alpha_p_partial,alpha_p_lost` (when `columns.status`), `millis`. A record
/// with probabilities the columns do not cover widens them rather than losing its values.
///
/// # Errors
/// [`AppError::Computation`] naming the frame and column for a NaN or infinite value, a record
/// whose number of β probabilities differs from the others, or α probabilities that are not 3.
pub fn csv_string_with(records: &[FrameRecord], columns: CsvColumns) -> Result<String> {
    let k = beta_width(records, columns.beta_classes)?;
    let has_alpha = columns.status || records.iter().any(|r| !r.alpha_probs.is_empty());
    let mut out = String::from("frame,cx,cy,a,b,angle,x,y,w,h,ess,beta_hat");
    for i in 0..k {
        let _ = write!(out, ",beta_p{i}");
    }
    out.push_str(",lambda_hat,gamma_hat,alpha_hat");
    if has_alpha {
        out.push_str(",alpha_p_locked,alpha_p_partial,alpha_p_lost");
    }
    out.push_str(",millis\n");
    for r in records {
        let f = r.frame;
        let _ = write!(out, "{}", f + 1);
        let e = &r.ellipse;
        let b = &r.bbox;
        for (v, col) in [
            (e.cx, "cx"),
            (e.cy, "cy"),
            (e.a, "a"),
            (e.b, "b"),
            (e.angle, "angle"),
            (b.x, "x"),
            (b.y, "y"),
            (b.w, "w"),
            (b.h, "h"),
            (r.ess, "ess"),
        ] {
            out.push(',');
            num(&mut out, v, f, col)?;
        }
        out.push(',');
        if let Some(beta) = r.beta_hat {
            let _ = write!(out, "{beta}");
        }
        for i in 0..k {
            out.push(',');
            if let Some(&p) = r.beta_probs.get(i) {
                num(&mut out, p, f, &format!("beta_p{i}"))?;
            }
        }
        for (v, col) in [(r.lambda_hat, "lambda_hat"), (r.gamma_hat, "gamma_hat")] {
            out.push(',');
            if let Some(v) = v {
                num(&mut out, v, f, col)?;
            }
        }
        out.push(',');
        if let Some(a) = r.alpha_hat {
            out.push_str(a.name());
        }
        if has_alpha {
            match r.alpha_probs.len() {
                0 => out.push_str(",,,"),
                3 => {
                    for (p, s) in r.alpha_probs.iter().zip(TrackStatus::ALL) {
                        out.push(',');
                        num(&mut out, *p, f, &format!("alpha_p_{}", s.name()))?;
                    }
                }
                n => {
                    return Err(AppError::computation(
                        "track.csv",
                        format!("frame {}: {n} status probabilities, expected 3", f + 1),
                    ));
                }
            }
        }
        out.push(',');
        num(&mut out, r.millis, f, "millis")?;
        out.push('\n');
    }
    Ok(out)
}

/// Writes `track.csv` (see [`csv_string`]) atomically.
///
/// # Errors
/// As [`csv_string`], and [`AppError::Write`].
pub fn write_csv(path: &Path, records: &[FrameRecord]) -> Result<()> {
    write_atomic(path, csv_string(records)?.as_bytes())
}

/// Writes `track.csv` with the given columns (see [`csv_string_with`]) atomically.
///
/// # Errors
/// As [`csv_string_with`], and [`AppError::Write`].
pub fn write_csv_with(path: &Path, records: &[FrameRecord], columns: CsvColumns) -> Result<()> {
    write_atomic(path, csv_string_with(records, columns)?.as_bytes())
}

/// Renders `boxes.txt`: `x,y,w,h` of each record's box, one line per frame, two decimals (the
/// format OTB-style evaluation toolkits read).
///
/// # Errors
/// [`AppError::Computation`] for a non-finite box, naming the frame.
pub fn boxes_string(records: &[FrameRecord]) -> Result<String> {
    let mut out = String::with_capacity(records.len() * 32);
    for r in records {
        let b = &r.bbox;
        if !b.is_finite() {
            return Err(AppError::computation(
                "boxes.txt",
                format!("frame {}: the box is not finite", r.frame + 1),
            ));
        }
        let _ = writeln!(out, "{:.2},{:.2},{:.2},{:.2}", b.x, b.y, b.w, b.h);
    }
    Ok(out)
}

/// Writes `boxes.txt` (see [`boxes_string`]) atomically.
///
/// # Errors
/// As [`boxes_string`], and [`AppError::Write`].
pub fn write_boxes(path: &Path, records: &[FrameRecord]) -> Result<()> {
    write_atomic(path, boxes_string(records)?.as_bytes())
}

/// Writes a run's two tables into `dir`, each atomically: `csv_name` with the given columns (see
/// [`csv_string_with`]) and `boxes_name` (see [`boxes_string`]), whose first `untracked` lines
/// are `0,0,0,0`, the OTB convention for "no box", for the frames before the tracker started.
///
/// # Errors
/// As [`csv_string_with`] and [`boxes_string`], and [`AppError::Write`].
pub fn write_track_tables(
    dir: &Path,
    [csv_name, boxes_name]: [&str; 2],
    records: &[FrameRecord],
    columns: CsvColumns,
    untracked: usize,
) -> Result<()> {
    write_csv_with(&dir.join(csv_name), records, columns)?;
    let boxes = "0,0,0,0\n".repeat(untracked) + &boxes_string(records)?;
    write_atomic(&dir.join(boxes_name), boxes.as_bytes())
}

/// What `summary.json` holds: the run's settings, its size and speed, and its scores when the
/// sequence had ground truth.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Version of the `track` tool.
    pub tool_version: String,
    /// Sequence name.
    pub sequence: String,
    /// Tracker preset.
    pub tracker: String,
    /// Number of particles.
    pub particles: usize,
    /// Random seed.
    pub seed: u64,
    /// Frames tracked.
    pub frames: usize,
    /// Frame width, pixels.
    pub width: usize,
    /// Frame height, pixels.
    pub height: usize,
    /// Frames per second of the input, when it states it (a Y4M header, a video file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_rate: Option<f64>,
    /// The box that initialised the tracker.
    pub initial_box: Option<BoundingBox>,
    /// Total tracking time, seconds.
    pub seconds: f64,
    /// Frames per second of the tracker alone (`frames / seconds`: no reading, decoding or
    /// drawing; see `wall_seconds` for the whole run).
    pub fps: f64,
    /// Mean tracking time per frame, milliseconds.
    pub mean_millis: f64,
    /// Number of frames in each tracker status (locked, partial, lost), when the tracker has α.
    pub status_counts: Option<[usize; 3]>,
    /// Scores against the ground truth, when there is one.
    pub metrics: Option<SequenceMetrics>,
    /// The files written, relative to the output folder.
    pub outputs: Vec<String>,
    /// Wall-clock time of the run from its start to the end of tracking, seconds: reading and
    /// decoding the frames, tracking and drawing (`seconds` is the tracking alone).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wall_seconds: Option<f64>,
    /// What the animated GIF holds, when one was written.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gif: Option<GifSummary>,
    /// Set when the run stopped before the end of its input (a signal, or an error in a stream):
    /// the outputs then hold the frames tracked until then, and only those.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interrupted: Option<Interruption>,
}

/// What an animated GIF holds: which overlays, and how fast it plays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct GifSummary {
    /// Overlays in the GIF.
    pub frames: usize,
    /// Frames tracked (overlays drawn).
    pub tracked: usize,
    /// One overlay in the GIF every `stride` frames tracked.
    pub stride: usize,
    /// Display time of each GIF frame, milliseconds.
    pub delay_ms: u32,
}

impl GifSummary {
    /// The notice to print when the GIF leaves frames out, `None` when it holds every frame.
    pub fn notice(&self) -> Option<String> {
        if self.frames >= self.tracked {
            return None;
        }
        let last = (self.frames.saturating_sub(1)) * self.stride + 1;
        let span = if last + self.stride <= self.tracked {
            format!(", up to frame {last} of the run")
        } else {
            String::new()
        };
        Some(format!(
            "track.gif holds {} of the {} frames tracked (one every {}{span}), {:.2} s each;              --gif-stride and --gif-frames choose (--gif-stride 1 --gif-frames {} keeps all)",
            self.frames,
            self.tracked,
            self.stride,
            f64::from(self.delay_ms) / 1e3,
            self.tracked
        ))
    }
}

/// Why and where a run stopped early (see [`Summary::interrupted`]).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Interruption {
    /// What stopped it: a signal's name (`SIGINT`, `SIGTERM`) or the error's message.
    pub reason: String,
    /// Frames read from the input before it stopped (tracked frames are in
    /// [`Summary::frames`]).
    pub frames_read: usize,
}

impl Summary {
    /// Checks that no number in the summary is NaN or infinite (JSON has no NaN; serde_json would
    /// silently write `null`).
    ///
    /// # Errors
    /// [`AppError::Computation`] naming the field.
    pub fn validate(&self) -> Result<()> {
        let mut fields = vec![
            ("seconds", self.seconds),
            ("wall_seconds", self.wall_seconds.unwrap_or(0.0)),
            ("fps", self.fps),
            ("mean_millis", self.mean_millis),
        ];
        if let Some(r) = self.frame_rate {
            fields.push(("frame_rate", r));
        }
        if let Some(b) = &self.initial_box {
            fields.extend([("initial_box.x", b.x), ("initial_box.y", b.y)]);
            fields.extend([("initial_box.w", b.w), ("initial_box.h", b.h)]);
        }
        if let Some(m) = &self.metrics {
            fields.extend([
                ("metrics.precision_20", m.precision_20),
                ("metrics.success_auc", m.success_auc),
                ("metrics.mean_iou", m.mean_iou),
                ("metrics.mean_centre_error", m.mean_centre_error),
                ("metrics.fps", m.fps.unwrap_or(0.0)),
            ]);
            fields.extend(
                m.success_curve
                    .iter()
                    .map(|&v| ("metrics.success_curve", v)),
            );
        }
        match fields.iter().find(|(_, v)| !v.is_finite()) {
            Some((name, v)) => Err(AppError::computation(
                "summary.json",
                format!("{name} is {v}; refusing to write a non-finite value"),
            )),
            None => Ok(()),
        }
    }
}

/// Writes `summary.json` (pretty-printed) atomically.
///
/// # Errors
/// [`Summary::validate`], serialisation failure, and [`AppError::Write`].
pub fn write_summary(path: &Path, summary: &Summary) -> Result<()> {
    summary.validate()?;
    let text = serde_json::to_string_pretty(summary)
        .map_err(|e| AppError::computation("summary.json", e))?;
    write_atomic(path, format!("{text}\n").as_bytes())
}

/// How many frames were estimated locked, partially occluded and lost (`None` when the tracker
/// has no status process).
pub fn status_counts(records: &[FrameRecord]) -> Option<[usize; 3]> {
    let mut counts = [0; 3];
    let mut any = false;
    for r in records {
        if let Some(s) = r.alpha_hat {
            counts[s.index()] += 1;
            any = true;
        }
    }
    any.then_some(counts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gif_that_leaves_frames_out_says_so() {
        let g = GifSummary {
            frames: 144,
            tracked: 573,
            stride: 4,
            delay_ms: 250,
        };
        let n = g.notice().unwrap();
        assert!(
            n.contains("144 of the 573 frames tracked (one every 4)"),
            "{n}"
        );
        assert!(
            n.contains("0.25 s each") && n.contains("--gif-stride"),
            "{n}"
        );
        // A stride fixed by the user that fills the GIF before the end: where it stops.
        let cut = GifSummary {
            frames: 10,
            tracked: 573,
            stride: 2,
            delay_ms: 166,
        };
        assert!(cut.notice().unwrap().contains("up to frame 19 of the run"));
        let all = GifSummary {
            frames: 50,
            tracked: 50,
            stride: 1,
            delay_ms: 83,
        };
        assert_eq!(all.notice(), None);
    }

    fn plain(frame: usize) -> FrameRecord {
        FrameRecord::new(frame, Ellipse::new(10.0, 20.0, 4.0, 2.0, 0.0), 150.5, 1.25)
    }

    #[test]
    fn status_counts_need_a_status_process() {
        assert_eq!(status_counts(&[plain(0), plain(1)]), None);
        let statuses = [
            TrackStatus::Locked,
            TrackStatus::Lost,
            TrackStatus::Lost,
            TrackStatus::PartiallyOccluded,
        ];
        let records: Vec<FrameRecord> = statuses
            .iter()
            .enumerate()
            .map(|(k, &s)| {
                let mut r = plain(k);
                r.alpha_hat = Some(s);
                r
            })
            .collect();
        // Locked / partial / lost.
        assert_eq!(status_counts(&records), Some([1, 1, 2]));
    }

    #[test]
    fn csv_without_switching_columns() {
        let csv = csv_string(&[plain(0), plain(1)]).unwrap();
        let expected = "frame,cx,cy,a,b,angle,x,y,w,h,ess,beta_hat,lambda_hat,gamma_hat,alpha_hat,millis\n\
                        1,10,20,4,2,0,6,18,8,4,150.5,,,,,1.25\n\
                        2,10,20,4,2,0,6,18,8,4,150.5,,,,,1.25\n";
        assert_eq!(csv, expected);
    }

    #[test]
    fn csv_with_switching_columns_and_absent_values() {
        let mut full = plain(0);
        full.beta_hat = Some(2);
        full.beta_probs = vec![0.1, 0.2, 0.7];
        full.lambda_hat = Some(0.0824);
        full.gamma_hat = Some(0.05);
        full.alpha_hat = Some(TrackStatus::PartiallyOccluded);
        full.alpha_probs = vec![0.25, 0.5, 0.25];
        let csv = csv_string(&[full, plain(1)]).unwrap();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(
            lines[0],
            "frame,cx,cy,a,b,angle,x,y,w,h,ess,beta_hat,beta_p0,beta_p1,beta_p2,lambda_hat,gamma_hat,\
             alpha_hat,alpha_p_locked,alpha_p_partial,alpha_p_lost,millis"
        );
        assert_eq!(
            lines[1],
            "1,10,20,4,2,0,6,18,8,4,150.5,2,0.1,0.2,0.7,0.0824,0.05,partial,0.25,0.5,0.25,1.25"
        );
        assert_eq!(lines[2], "2,10,20,4,2,0,6,18,8,4,150.5,,,,,,,,,,,1.25");
        // Every row has as many cells as the header.
        let cells = |l: &str| l.split(',').count();
        assert!(lines.iter().all(|l| cells(l) == cells(lines[0])));
    }

    #[test]
    fn nan_is_an_error_not_a_cell() {
        let mut r = plain(4);
        r.ess = f64::NAN;
        let msg = csv_string(&[plain(0), r.clone()]).unwrap_err().to_string();
        assert!(
            msg.contains("frame 5") && msg.contains("ess is NaN"),
            "{msg}"
        );
        let mut r = plain(0);
        r.gamma_hat = Some(f64::INFINITY);
        assert!(
            csv_string(&[r])
                .unwrap_err()
                .to_string()
                .contains("gamma_hat is inf")
        );
        let mut r = plain(0);
        r.bbox.w = f64::NAN;
        assert!(boxes_string(&[r]).is_err());
        let mut a = plain(0);
        a.beta_probs = vec![0.5, 0.5];
        let mut b = plain(1);
        b.beta_probs = vec![1.0];
        assert!(csv_string(&[a, b]).is_err());
        let mut a = plain(0);
        a.alpha_probs = vec![1.0];
        assert!(csv_string(&[a]).is_err());
    }

    #[test]
    fn files_are_written_with_expected_contents() {
        let dir = tempfile::tempdir().unwrap();
        let mut r = plain(0);
        r.ellipse = Ellipse::new(180.0, 109.5, 52.0, 63.5, 0.0);
        r.bbox = r.ellipse.bounding_box();
        let records = [r, plain(1)];
        write_csv(&dir.path().join("track.csv"), &records).unwrap();
        write_boxes(&dir.path().join("boxes.txt"), &records).unwrap();
        let boxes = std::fs::read_to_string(dir.path().join("boxes.txt")).unwrap();
        assert_eq!(boxes, "128.00,46.00,104.00,127.00\n6.00,18.00,8.00,4.00\n");
        let csv = std::fs::read_to_string(dir.path().join("track.csv")).unwrap();
        assert_eq!(csv.lines().count(), 3);
        // A failing write leaves no file behind.
        let mut bad = plain(2);
        bad.millis = f64::NAN;
        assert!(write_csv(&dir.path().join("bad.csv"), &[bad]).is_err());
        assert!(!dir.path().join("bad.csv").exists());
    }

    #[test]
    fn track_tables_mark_untracked_frames_and_refuse_a_non_finite_box() {
        let dir = tempfile::tempdir().unwrap();
        let records = [plain(0), plain(1)];
        let names = ["t.csv", "b.txt"];
        write_track_tables(dir.path(), names, &records, CsvColumns::default(), 2).unwrap();
        let boxes = std::fs::read_to_string(dir.path().join("b.txt")).unwrap();
        assert_eq!(
            boxes,
            "0,0,0,0\n0,0,0,0\n6.00,18.00,8.00,4.00\n6.00,18.00,8.00,4.00\n"
        );
        assert_eq!(
            std::fs::read_to_string(dir.path().join("t.csv"))
                .unwrap()
                .lines()
                .count(),
            3
        );
        // A NaN box is an error, and no boxes file is left half-written.
        let mut bad = plain(2);
        bad.bbox.w = f64::NAN;
        let names = ["t2.csv", "b2.txt"];
        assert!(write_track_tables(dir.path(), names, &[bad], CsvColumns::default(), 0).is_err());
        assert!(!dir.path().join("b2.txt").exists());
    }

    #[test]
    fn summary_round_trips_and_rejects_nan() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("summary.json");
        let s = Summary {
            tool_version: "0.1.0".into(),
            sequence: "girl_mil".into(),
            tracker: "full".into(),
            particles: 200,
            seed: 7,
            frames: 502,
            seconds: 10.0,
            fps: 50.2,
            mean_millis: 19.9,
            frame_rate: Some(25.0),
            initial_box: Some(BoundingBox::new(128.0, 46.0, 104.0, 127.0)),
            status_counts: Some([500, 2, 0]),
            outputs: vec!["track.csv".into()],
            interrupted: None,
            ..Default::default()
        };
        write_summary(&path, &s).unwrap();
        let back: Summary = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_eq!(back, s);
        let bad = Summary { fps: f64::NAN, ..s };
        assert!(
            write_summary(&dir.path().join("s2.json"), &bad)
                .unwrap_err()
                .to_string()
                .contains("fps is NaN")
        );
        assert!(!dir.path().join("s2.json").exists());
    }
}
