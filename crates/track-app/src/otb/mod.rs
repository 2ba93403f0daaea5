//! The OTB benchmark's protocols (Wu, Lim & Yang 2013/2015), as `track eval otb` runs them and as
//! `../shared/tools/opencv_peers.py` does, so that the figures of both are comparable.
//!
//! One *run* starts a tracker from a box on a labelled frame, tracks to the end of the sequence
//! and is scored on the labelled frames after its start frame ([`crate::metrics::score_run`]).
//!
//! - **OPE** (one-pass evaluation): one run from the first labelled frame and its true box.
//! - **TRE** (temporal robustness): [`TRE_RUNS`] runs, run `i` starting at the first labelled
//!   frame at or after ⌊i·n/10⌋ (n = frames) from its true box; a start already taken, or one with
//!   no labelled frame after it, is dropped.
//! - **SRE** (spatial robustness): 12 runs from the first labelled frame, from its true box with
//!   the centre shifted by 10 % of the box's width and/or height (left, right, up, down and the
//!   four diagonals, [`SRE_SHIFTS`]), then scaled about its centre by [`SRE_SCALES`].
//!
//! A sequence's figure is the mean over its runs; the set's figure is the mean over sequences.
//! Each run's boxes are written, and other trackers' read ([`read_boxes`]), as
//! `DIR/<protocol>/<tracker>/<sequence>[.<run>].txt` (no run suffix under OPE): one `x,y,w,h` line
//! per frame of the sequence, `0,0,0,0` before the start frame.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use vision_core::BoundingBox;

use crate::metrics::{SequenceMetrics, mean_metrics, roc_auc};
use crate::{AppError, Result};

pub mod eval;
pub mod page;
pub mod paired;
pub mod plots;
pub mod suite;

/// Runs of TRE per sequence (before dropping duplicate starts).
pub const TRE_RUNS: usize = 10;
/// SRE's shifts of the centre, in tenths of the box's width and height: left, right, up, down,
/// and the four diagonals (the order of the runs).
pub const SRE_SHIFTS: [(f64, f64); 8] = [
    (-1.0, 0.0),
    (1.0, 0.0),
    (0.0, -1.0),
    (0.0, 1.0),
    (-1.0, -1.0),
    (1.0, -1.0),
    (-1.0, 1.0),
    (1.0, 1.0),
];
/// SRE's scales of the box about its centre (the runs after the shifts).
pub const SRE_SCALES: [f64; 4] = [0.8, 0.9, 1.1, 1.2];

/// An OTB evaluation protocol.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, clap::ValueEnum)]
pub enum Protocol {
    /// One-pass evaluation: one run from the first labelled box.
    Ope,
    /// Temporal robustness: 10 runs started at evenly spaced labelled frames.
    Tre,
    /// Spatial robustness: 12 runs from shifted and scaled first boxes.
    Sre,
}

impl Protocol {
    /// The protocol's name in files and folders: `ope`, `tre` or `sre`.
    pub fn name(self) -> &'static str {
        match self {
            Protocol::Ope => "ope",
            Protocol::Tre => "tre",
            Protocol::Sre => "sre",
        }
    }

    /// The name in titles: `OPE`, `TRE` or `SRE`.
    pub fn title(self) -> &'static str {
        match self {
            Protocol::Ope => "OPE",
            Protocol::Tre => "TRE",
            Protocol::Sre => "SRE",
        }
    }
}

/// Where one run starts: the frame (0-based) and the box the tracker is given there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunStart {
    /// The start frame (given, never scored).
    pub frame: usize,
    /// The initial box.
    pub init: BoundingBox,
}

/// Every run of `protocol` on a sequence with ground truth `truth` (one entry per frame, `None`
/// for unlabelled frames), in the order of their run numbers (see the module documentation).
/// Empty when nothing is labelled; OPE and SRE runs are returned even when no labelled frame
/// follows the first one (they have nothing to score).
pub fn run_starts(truth: &[Option<BoundingBox>], protocol: Protocol) -> Vec<RunStart> {
    let labelled: Vec<usize> = (0..truth.len()).filter(|&i| truth[i].is_some()).collect();
    let Some((first, first_box)) = labelled.first().and_then(|&f| truth[f].map(|b| (f, b))) else {
        return Vec::new();
    };
    match protocol {
        Protocol::Ope => vec![RunStart {
            frame: first,
            init: first_box,
        }],
        Protocol::Tre => {
            let n = truth.len();
            let mut starts: Vec<usize> = Vec::new();
            for i in 0..TRE_RUNS {
                let from = i * n / TRE_RUNS;
                let Some(&s) = labelled.iter().find(|&&k| k >= from) else {
                    continue;
                };
                let later = labelled.last().is_some_and(|&l| l > s);
                if !starts.contains(&s) && later {
                    starts.push(s);
                }
            }
            starts
                .into_iter()
                .filter_map(|s| truth[s].map(|init| RunStart { frame: s, init }))
                .collect()
        }
        Protocol::Sre => {
            let BoundingBox { x, y, w, h } = first_box;
            // The same arithmetic, in the same order, as opencv_peers.py.
            let shifted = SRE_SHIFTS
                .iter()
                .map(|&(dx, dy)| BoundingBox::new(x + dx * 0.1 * w, y + dy * 0.1 * h, w, h));
            let scaled = SRE_SCALES.iter().map(|&s| {
                BoundingBox::new(
                    x + w / 2.0 - s * w / 2.0,
                    y + h / 2.0 - s * h / 2.0,
                    s * w,
                    s * h,
                )
            });
            shifted
                .chain(scaled)
                .map(|init| RunStart { frame: first, init })
                .collect()
        }
    }
}

/// The truth as a tracker that keeps the convention of the box it was given would report it: each
/// labelled box after `start` with the start box's offset and scale against the truth at the
/// start frame carried along (the centre moved by the same shares of the box's width and height,
/// the size scaled by the same factors). Under OPE and TRE the start box is the truth and this is
/// the truth; under SRE its score is what a tracker would score that followed the target exactly
/// and reported it in the convention of the box it is given, as a user's tracker should. Frames
/// up to the start, and all frames of a run whose start frame is unlabelled, are `None`.
pub fn in_start_convention(
    truth: &[Option<BoundingBox>],
    start: &RunStart,
) -> Vec<Option<BoundingBox>> {
    let Some(reference) = truth.get(start.frame).copied().flatten() else {
        return vec![None; truth.len()];
    };
    let (rx, ry) = reference.centre();
    let (sx, sy) = start.init.centre();
    let (dx, dy) = ((sx - rx) / reference.w, (sy - ry) / reference.h);
    let (kw, kh) = (start.init.w / reference.w, start.init.h / reference.h);
    truth
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let b = b.filter(|_| i > start.frame)?;
            let (cx, cy) = b.centre();
            let (w, h) = (kw * b.w, kh * b.h);
            Some(BoundingBox::new(
                cx + dx * b.w - 0.5 * w,
                cy + dy * b.h - 0.5 * h,
                w,
                h,
            ))
        })
        .collect()
}

/// The sentence under an SRE table that gives the success AUC `ceiling` of the truth in each
/// run's start convention ([`in_start_convention`]).
pub fn ceiling_sentence(ceiling: f64) -> String {
    format!(
        "The truth in each run's start convention (its start box's shift and scale carried \
         along) scores a success AUC of {ceiling:.3} on these sequences: what a tracker that \
         followed the target exactly and kept the convention of the box it is given would score."
    )
}

/// The file of run `run` of `tracker` on `sequence` under `protocol`, below `dir`:
/// `dir/<protocol>/<tracker>/<sequence>[.<run>].txt`, without the run under OPE.
pub fn boxes_path(
    dir: &Path,
    protocol: Protocol,
    tracker: &str,
    sequence: &str,
    run: usize,
) -> PathBuf {
    let file = match protocol {
        Protocol::Ope => format!("{sequence}.txt"),
        _ => format!("{sequence}.{run}.txt"),
    };
    dir.join(protocol.name()).join(tracker).join(file)
}

/// Renders a run's boxes: one `x,y,w,h` line per frame with two decimals, `0,0,0,0` for a frame
/// without a box (those before the start frame), as `opencv_peers.py` and `track run`'s
/// `boxes.txt` write them.
pub fn boxes_text(boxes: &[Option<BoundingBox>]) -> String {
    let mut s = String::with_capacity(boxes.len() * 28);
    for b in boxes {
        match b {
            Some(b) => {
                let _ = writeln!(s, "{:.2},{:.2},{:.2},{:.2}", b.x, b.y, b.w, b.h);
            }
            None => s.push_str("0,0,0,0\n"),
        }
    }
    s
}

/// Parses a box file of another tracker (see [`boxes_text`]; fields separated by commas, tabs or
/// spaces): one box per frame, `None` for a line whose width or height is not positive (no box:
/// a miss when scored, as `opencv_peers.py` reads it). There must be exactly `frames` lines
/// (trailing blank lines aside).
///
/// # Errors
/// [`AppError::BadInput`] (exit 3) naming `path` and, for a bad line, its number.
pub fn parse_boxes(text: &str, path: &Path, frames: usize) -> Result<Vec<Option<BoundingBox>>> {
    let lines: Vec<&str> = text.lines().collect();
    let last = lines
        .iter()
        .rposition(|l| !l.trim().is_empty())
        .map_or(0, |l| l + 1);
    if last != frames {
        return Err(AppError::input(
            path,
            format!("{last} box lines for a sequence of {frames} frames"),
        ));
    }
    lines[..last]
        .iter()
        .enumerate()
        .map(|(i, line)| {
            let fields: Vec<&str> = line
                .split([',', '\t', ' '])
                .filter(|f| !f.is_empty())
                .collect();
            let bad = |why: String| AppError::input(path, format!("line {}: {why}", i + 1));
            if fields.len() != 4 {
                return Err(bad(format!(
                    "expected 4 numbers x,y,w,h, found {} in {:?}",
                    fields.len(),
                    line.trim()
                )));
            }
            let mut v = [0.0; 4];
            for (slot, f) in v.iter_mut().zip(&fields) {
                *slot = f
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| bad(format!("{f:?} is not a finite number")))?;
            }
            let [x, y, w, h] = v;
            Ok((w > 0.0 && h > 0.0).then(|| BoundingBox::new(x, y, w, h)))
        })
        .collect()
}

/// Reads a box file of another tracker ([`parse_boxes`]).
///
/// # Errors
/// [`AppError::BadInput`] (exit 3) naming the file: missing, unreadable or malformed.
pub fn read_boxes(path: &Path, frames: usize) -> Result<Vec<Option<BoundingBox>>> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        let why = if e.kind() == std::io::ErrorKind::NotFound {
            "missing: --results DIR must hold DIR/<protocol>/<tracker>/<sequence>[.<run>].txt for \
             every run (as opencv_peers.py --out DIR writes them)"
                .to_owned()
        } else {
            format!("cannot read: {e}")
        };
        AppError::input(path, why)
    })?;
    parse_boxes(&text, path, frames)
}

/// One sequence's figure for one tracker under one protocol: the mean over its runs.
#[derive(Debug, Clone, PartialEq)]
pub struct SequenceScore {
    /// The sequence.
    pub sequence: String,
    /// The tracker (a preset's name, a configuration's, or a `--results` name).
    pub tracker: String,
    /// Runs scored.
    pub runs: usize,
    /// Means over the runs (frames/s: all tracked frames over all tracking time; the lost ROC AUC
    /// pools the labelled frames of every run).
    pub metrics: SequenceMetrics,
}

/// The mean over runs of one sequence: scores averaged per run, frames/s as the frames of all
/// runs over their total time (`None` when any run has no timing), the lost ROC AUC pooled.
/// `runs` holds each run's metrics and its tracking time. `None` for no run.
pub fn mean_over_runs(runs: &[(SequenceMetrics, Option<f64>)]) -> Option<SequenceMetrics> {
    let metrics: Vec<SequenceMetrics> = runs.iter().map(|(m, _)| m.clone()).collect();
    let mut mean = mean_metrics(&metrics)?;
    let seconds: Option<f64> = runs.iter().map(|(_, s)| *s).sum();
    mean.fps = seconds.filter(|s| *s > 0.0).map(|s| mean.frames as f64 / s);
    mean.lost_auc = roc_auc(&mean.lost_scores);
    Some(mean)
}

/// The set's figure of each tracker: the mean over its sequences ([`mean_metrics`]: frames/s is
/// the mean of the sequences' figures; the lost ROC AUC pools every labelled frame of every run).
/// Trackers in the order of their first row.
pub fn set_means(rows: &[SequenceScore]) -> Vec<SequenceScore> {
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        if !names.contains(&r.tracker.as_str()) {
            names.push(&r.tracker);
        }
    }
    names
        .into_iter()
        .filter_map(|name| {
            let mine: Vec<&SequenceScore> = rows.iter().filter(|r| r.tracker == name).collect();
            let metrics: Vec<SequenceMetrics> = mine.iter().map(|r| r.metrics.clone()).collect();
            Some(SequenceScore {
                sequence: "mean".to_owned(),
                tracker: name.to_owned(),
                runs: mine.iter().map(|r| r.runs).sum(),
                metrics: mean_metrics(&metrics)?,
            })
        })
        .collect()
}

fn fmt_opt(v: Option<f64>, decimals: usize) -> String {
    v.map_or_else(|| "—".to_owned(), |v| format!("{v:.decimals$}"))
}

/// `otb.md` of one protocol: a table of every sequence and tracker (runs, success AUC,
/// precision@20 px, mean IoU, frames/s, P(lost) ROC AUC) with each tracker's mean, then success
/// AUC per sequence with one row per tracker.
pub fn markdown(protocol: Protocol, rows: &[SequenceScore]) -> String {
    let means = set_means(rows);
    let mut s = format!(
        "{} ({}): the mean over each sequence's runs, then over sequences; the start frame and \
         unlabelled frames are not scored.\n\n\
         | Sequence | Tracker | Runs | Success AUC | Precision@20px | Mean IoU | Frames/s | Lost ROC AUC |\n\
         |---|---|---|---|---|---|---|---|\n",
        protocol.title(),
        match protocol {
            Protocol::Ope => "one run from the first labelled box",
            Protocol::Tre => "up to 10 runs started at evenly spaced labelled frames",
            Protocol::Sre => "12 runs from shifted and scaled first boxes",
        }
    );
    for name in means.iter().map(|m| &m.tracker) {
        let mine = rows
            .iter()
            .filter(|r| &r.tracker == name)
            .chain(means.iter().filter(|m| &m.tracker == name));
        for r in mine {
            let m = &r.metrics;
            let _ = writeln!(
                s,
                "| {} | {} | {} | {:.3} | {:.3} | {:.3} | {} | {} |",
                r.sequence,
                r.tracker,
                r.runs,
                m.success_auc,
                m.precision_20,
                m.mean_iou,
                fmt_opt(m.fps, 1),
                fmt_opt(m.lost_auc, 3)
            );
        }
    }
    let sequences = sequence_names(rows);
    let _ = write!(
        s,
        "\nSuccess AUC per sequence ({}):\n\n| tracker | {} | mean AUC | mean P20 |\n|---|{}---|---|\n",
        protocol.title(),
        sequences.join(" | "),
        "---|".repeat(sequences.len())
    );
    for mean in &means {
        let cells: Vec<String> = sequences
            .iter()
            .map(|seq| {
                rows.iter()
                    .find(|r| &r.sequence == seq && r.tracker == mean.tracker)
                    .map_or_else(
                        || "—".to_owned(),
                        |r| format!("{:.2}", r.metrics.success_auc),
                    )
            })
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | **{:.3}** | {:.3} |",
            mean.tracker,
            cells.join(" | "),
            mean.metrics.success_auc,
            mean.metrics.precision_20
        );
    }
    s
}

/// Opens the OTB folder `dir` (`img/` and `groundtruth_rect.txt`); returns the sequence and its
/// ground-truth file. A file given instead (`SEQ/groundtruth_rect.txt`, a video) is refused as
/// not an OTB folder, before any decoder is asked to read it.
///
/// # Errors
/// [`AppError::BadInput`] naming `dir`.
pub(crate) fn open_otb(dir: &Path) -> Result<(crate::sequence::Sequence, PathBuf)> {
    if !dir.is_dir() {
        let reason = if dir.exists() {
            "not an OTB folder but a file: give the folder that holds img/ and \
             groundtruth_rect.txt"
        } else {
            "no such folder"
        };
        return Err(AppError::input(dir, reason));
    }
    let sequence = crate::sequence::open_sequence(&dir.to_string_lossy())?;
    let gt_path = sequence.groundtruth.clone().ok_or_else(|| {
        AppError::input(dir, "not an OTB folder: groundtruth_rect.txt is missing")
    })?;
    Ok((sequence, gt_path))
}

/// The name of the sequence in folder `dir`: the folder's name.
pub(crate) fn sequence_name(dir: &Path) -> String {
    dir.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| dir.display().to_string())
}

/// The sequences of `rows`, in the order of their first row.
pub fn sequence_names(rows: &[SequenceScore]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for r in rows {
        if !names.contains(&r.sequence) {
            names.push(r.sequence.clone());
        }
    }
    names
}

/// `otb.csv` of one protocol: one line per sequence and tracker, then each tracker's mean
/// (sequence `mean`); empty fields where a tracker reports no timing or no status.
pub fn csv(protocol: Protocol, rows: &[SequenceScore]) -> String {
    let mut s = String::from(
        "protocol,sequence,tracker,runs,frames,labelled,success_auc,precision_20,mean_iou,fps,lost_auc\n",
    );
    let means = set_means(rows);
    for r in rows.iter().chain(&means) {
        let m = &r.metrics;
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{:.4},{:.4},{:.4},{},{}",
            protocol.name(),
            r.sequence,
            r.tracker,
            r.runs,
            m.frames,
            m.labelled_frames,
            m.success_auc,
            m.precision_20,
            m.mean_iou,
            m.fps.map(|f| format!("{f:.2}")).unwrap_or_default(),
            m.lost_auc.map(|a| format!("{a:.4}")).unwrap_or_default()
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(x: f64, y: f64, w: f64, h: f64) -> Option<BoundingBox> {
        Some(BoundingBox::new(x, y, w, h))
    }

    #[test]
    fn ope_starts_at_the_first_labelled_frame() {
        let truth = [None, None, b(1.0, 2.0, 3.0, 4.0), b(5.0, 6.0, 7.0, 8.0)];
        let runs = run_starts(&truth, Protocol::Ope);
        assert_eq!(
            runs,
            [RunStart {
                frame: 2,
                init: BoundingBox::new(1.0, 2.0, 3.0, 4.0)
            }]
        );
        assert!(run_starts(&[None, None], Protocol::Tre).is_empty());
        assert!(run_starts(&[], Protocol::Sre).is_empty());
    }

    #[test]
    fn tre_starts_by_hand_with_unlabelled_frames() {
        // 25 frames labelled on even frames only, and not frame 24: ⌊i·25/10⌋ = 0, 2, 5, 7,
        // 10, 12, 15, 17, 20, 22 → first labelled at or after: 0, 2, 6, 8, 10, 12, 16, 18, 20,
        // 22. Frame 22 is the last labelled frame: no later one to score, so it is dropped.
        let truth: Vec<_> = (0..25)
            .map(|i| (i % 2 == 0 && i < 24).then(|| BoundingBox::new(i as f64, 1.0, 10.0, 10.0)))
            .collect();
        let runs = run_starts(&truth, Protocol::Tre);
        let frames: Vec<usize> = runs.iter().map(|r| r.frame).collect();
        assert_eq!(frames, [0, 2, 6, 8, 10, 12, 16, 18, 20]);
        for r in &runs {
            assert_eq!(
                Some(r.init),
                truth[r.frame],
                "each TRE run starts from the true box"
            );
        }
    }

    #[test]
    fn tre_on_a_very_short_sequence_drops_duplicate_starts() {
        // 3 frames: ⌊i·3/10⌋ = 0,0,0,0,1,1,1,2,2,2 → starts 0, 1 (2 has nothing after it).
        let truth = [
            b(0.0, 0.0, 4.0, 4.0),
            b(1.0, 0.0, 4.0, 4.0),
            b(2.0, 0.0, 4.0, 4.0),
        ];
        let frames: Vec<usize> = run_starts(&truth, Protocol::Tre)
            .iter()
            .map(|r| r.frame)
            .collect();
        assert_eq!(frames, [0, 1]);
        // One labelled frame: TRE has no run; OPE and SRE still start there.
        let one = [None, b(0.0, 0.0, 4.0, 4.0), None];
        assert!(run_starts(&one, Protocol::Tre).is_empty());
        assert_eq!(run_starts(&one, Protocol::Sre).len(), 12);
    }

    #[test]
    fn the_start_convention_carries_the_start_box_s_shift_and_scale() {
        let truth = vec![
            Some(BoundingBox::new(10.0, 20.0, 40.0, 50.0)),
            None,
            Some(BoundingBox::new(30.0, 20.0, 80.0, 100.0)),
        ];
        let runs = run_starts(&truth, Protocol::Sre);
        // Run 1 is shifted right by a tenth of the width: 8 px on a box twice as wide.
        let shifted = in_start_convention(&truth, &runs[1]);
        assert_eq!(shifted[0], None);
        assert_eq!(shifted[1], None);
        let b = shifted[2].unwrap();
        assert!(
            (b.x - 38.0).abs() < 1e-9 && (b.y - 20.0).abs() < 1e-9,
            "{b:?}"
        );
        assert!(
            (b.w - 80.0).abs() < 1e-9 && (b.h - 100.0).abs() < 1e-9,
            "{b:?}"
        );
        // Run 8 is scaled by 0.8 about the centre.
        let b = in_start_convention(&truth, &runs[8])[2].unwrap();
        assert!(
            (b.w - 64.0).abs() < 1e-9 && (b.h - 80.0).abs() < 1e-9,
            "{b:?}"
        );
        assert!((b.centre().0 - 70.0).abs() < 1e-9 && (b.centre().1 - 70.0).abs() < 1e-9);
        // OPE's start is the truth: the truth comes back after the start frame.
        let ope = run_starts(&truth, Protocol::Ope);
        let same = in_start_convention(&truth, &ope[0]);
        assert_eq!(same[2], truth[2]);
        assert_eq!(same[0], None);
    }

    #[test]
    fn sre_boxes_by_hand() {
        let truth = [None, b(100.0, 50.0, 40.0, 20.0), b(0.0, 0.0, 1.0, 1.0)];
        let runs = run_starts(&truth, Protocol::Sre);
        assert_eq!(runs.len(), 12);
        assert!(runs.iter().all(|r| r.frame == 1));
        let boxes: Vec<[f64; 4]> = runs
            .iter()
            .map(|r| [r.init.x, r.init.y, r.init.w, r.init.h])
            .collect();
        // 10 % of 40 = 4 px horizontally, 10 % of 20 = 2 px vertically.
        let expected = [
            [96.0, 50.0, 40.0, 20.0],
            [104.0, 50.0, 40.0, 20.0],
            [100.0, 48.0, 40.0, 20.0],
            [100.0, 52.0, 40.0, 20.0],
            [96.0, 48.0, 40.0, 20.0],
            [104.0, 48.0, 40.0, 20.0],
            [96.0, 52.0, 40.0, 20.0],
            [104.0, 52.0, 40.0, 20.0],
            // Centre (120, 60) kept: 0.8 → 32×16, 0.9 → 36×18, 1.1 → 44×22, 1.2 → 48×24.
            [104.0, 52.0, 32.0, 16.0],
            [102.0, 51.0, 36.0, 18.0],
            [98.0, 49.0, 44.0, 22.0],
            [96.0, 48.0, 48.0, 24.0],
        ];
        for (got, want) in boxes.iter().zip(&expected) {
            for (g, w) in got.iter().zip(want) {
                assert!((g - w).abs() < 1e-9, "{got:?} against {want:?}");
            }
        }
    }

    #[test]
    fn box_files_round_trip_and_bad_ones_name_file_and_line() {
        let boxes = vec![None, b(1.5, 2.25, 30.0, 40.125), b(-3.0, 4.0, 5.0, 6.0)];
        let text = boxes_text(&boxes);
        assert_eq!(
            text,
            "0,0,0,0\n1.50,2.25,30.00,40.12\n-3.00,4.00,5.00,6.00\n"
        );
        let p = Path::new("R/tre/csrt/Boy.3.txt");
        let back = parse_boxes(&text, p, 3).unwrap();
        assert_eq!(back[0], None);
        assert_eq!(back[2], boxes[2]);
        // Tabs and spaces as in OTB files; trailing blank lines ignored.
        assert_eq!(
            parse_boxes("1\t2\t3\t4\n0 0 0 0\n\n", p, 2).unwrap(),
            [b(1.0, 2.0, 3.0, 4.0), None]
        );
        for (text, what) in [
            ("1,2,3,4\n", "1 box lines for a sequence of 3 frames"),
            ("1,2,3,4\n1,2,3\n1,2,3,4\n", "line 2: expected 4 numbers"),
            (
                "1,2,3,4\n1,2,3,4\n1,x,3,4\n",
                "line 3: \"x\" is not a finite",
            ),
            (
                "1,2,3,4\n1,2,NaN,4\n1,2,3,4\n",
                "line 2: \"NaN\" is not a finite",
            ),
        ] {
            let e = parse_boxes(text, p, 3).unwrap_err();
            let msg = e.to_string();
            assert!(
                msg.contains("R/tre/csrt/Boy.3.txt") && msg.contains(what),
                "{msg}"
            );
            assert_eq!(e.exit_code(), 3);
        }
        let e = read_boxes(Path::new("/nonexistent/ope/x/y.txt"), 3).unwrap_err();
        assert!(e.to_string().contains("missing"), "{e}");
        assert_eq!(e.exit_code(), 3);
    }

    #[test]
    fn box_paths_follow_the_peers_layout() {
        let d = Path::new("R");
        assert_eq!(
            boxes_path(d, Protocol::Ope, "kcf", "Boy", 0),
            Path::new("R/ope/kcf/Boy.txt")
        );
        assert_eq!(
            boxes_path(d, Protocol::Sre, "kcf", "Boy", 11),
            Path::new("R/sre/kcf/Boy.11.txt")
        );
    }
}
