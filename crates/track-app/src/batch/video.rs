//! `track run` as a function: [`track_video`].

use std::path::Path;

use trackers::TrackerConfig;
use vision_core::{BoundingBox, Ellipse};

use crate::commands::run::prepare_out;
use crate::groundtruth::{BoxInFrame, check_groundtruth_len, first_box_in_frame, load_groundtruth};
use crate::metrics::{SequenceMetrics, score_run};
use crate::record::{
    CsvColumns, FrameRecord, Summary, status_counts, write_summary, write_track_tables,
};
use crate::sequence::{FrameSource, open_sequence};
use crate::session::Session;
use crate::{AppError, Result};

/// The files [`track_video`] writes into its output folder, as `track run` names them.
pub const VIDEO_OUTPUTS: [&str; 3] = ["track.csv", "boxes.txt", "summary.json"];

/// What one tracked sequence gave.
#[derive(Debug, Clone)]
pub struct VideoRun {
    /// The first frame tracked (0 unless an OTB folder's first labelled frame is later).
    pub start: usize,
    /// One record per tracked frame, from `start` on.
    pub records: Vec<FrameRecord>,
    /// What `summary.json` holds (written only when an output folder was given).
    pub summary: Summary,
}

/// Tracks `source` as `track run SOURCE --init X,Y,W,H` does with the tracker of `config`.
///
/// `source` is a video file (decoded by ffmpeg, which must be on `PATH`), a `.y4m` file, an image
/// folder or an OTB folder; standard input (`-`) is refused. `init` is the box on the first
/// frame; without it, an OTB folder starts at its first labelled box that lies in the frame, as
/// `track run` does. The sequence is checked whole before tracking (except a video, which is a
/// stream), then tracked frame by frame with the session loop of `track run`; with `out`, the
/// folder is prepared as `track run --out` prepares it and receives `track.csv`, `boxes.txt` and
/// `summary.json`, written by the same writers (the boxes and tables are byte for byte those of
/// `track run` with the same source, tracker and seed; the timings in `summary.json` differ).
///
/// # Errors
/// As `track run`: [`AppError::InvalidSetting`] for a box outside the frame or a missing one,
/// [`AppError::BadInput`] for a sequence that cannot be read, [`AppError::Computation`] when the
/// tracker fails, [`AppError::Write`] when an output cannot be written.
pub fn track_video(
    source: &str,
    init: Option<BoundingBox>,
    config: &TrackerConfig,
    out: Option<&Path>,
) -> Result<VideoRun> {
    let started = std::time::Instant::now();
    if source == "-" {
        return Err(AppError::setting(
            "source",
            "standard input cannot be read here: give a video file, an image folder or an OTB \
             folder",
        ));
    }
    let sequence = open_sequence(source)?;
    let (known_frames, width, height) = if sequence.source.is_stream() {
        let (w, h) = sequence
            .source
            .frame_size()
            .ok_or_else(|| AppError::input(source, "a stream without a frame size"))?;
        (None, w, h)
    } else {
        let info = sequence.source.validate_all()?;
        (Some(info.frames), info.width, info.height)
    };
    let truth = match (&sequence.groundtruth, known_frames) {
        (Some(path), Some(frames)) => {
            let t = load_groundtruth(path)?;
            check_groundtruth_len(&t, frames, path)?;
            Some(t)
        }
        _ => None,
    };
    let (start, ellipse) = match (init, truth.as_deref()) {
        (Some(b), _) => {
            b.validate_in_frame(width, height, "init")?;
            (0, b.inscribed_ellipse())
        }
        (None, Some(t)) => {
            let path = sequence
                .groundtruth
                .as_deref()
                .unwrap_or(Path::new("ground truth"));
            let (k, b) = first_box_in_frame(t, path, &sequence.name, width, height)?;
            (k, b.inscribed_ellipse())
        }
        (None, None) => {
            return Err(AppError::setting(
                "init",
                "this sequence has no ground truth: give the initial box (x, y, w, h)",
            ));
        }
    };
    let tracker =
        trackers::build(config.clone()).map_err(|e| AppError::setting("tracker", e.to_string()))?;
    let inputs: Vec<&Path> = [Some(Path::new(source)), sequence.groundtruth.as_deref()]
        .into_iter()
        .flatten()
        .collect();
    // The folder stays locked until the outputs are written, as in `track run`.
    let folder = out
        .map(|dir| prepare_out(dir, &inputs, false, false))
        .transpose()?;
    let name = sequence.name.clone();
    let frame_rate = sequence.source.frame_rate();
    let mut frames = sequence.source;
    let mut session = Session::new(tracker, None);
    while let Some(frame) = frames.next_frame()? {
        if frame.index < start {
            continue;
        }
        session.push(&frame, &ellipse, None)?;
    }
    let output = session.finish();
    let records = output.records;
    if records.is_empty() {
        return Err(AppError::input(
            source,
            "no frame to track after the first labelled one",
        ));
    }
    let metrics = match &truth {
        Some(t) => score(start, &records, t, output.seconds)?,
        None => None,
    };
    let seconds = output.seconds;
    let summary = Summary {
        tool_version: env!("CARGO_PKG_VERSION").to_owned(),
        sequence: name,
        tracker: config.name.clone(),
        particles: config.particles,
        seed: config.seed,
        frames: records.len(),
        width,
        height,
        frame_rate,
        initial_box: Some(ellipse_box(&ellipse)),
        seconds,
        fps: records.len() as f64 / seconds.max(1e-9),
        mean_millis: 1e3 * seconds / records.len().max(1) as f64,
        status_counts: status_counts(&records),
        metrics,
        outputs: if out.is_some() {
            VIDEO_OUTPUTS.map(str::to_owned).to_vec()
        } else {
            Vec::new()
        },
        wall_seconds: Some(started.elapsed().as_secs_f64()),
        gif: None,
        interrupted: None,
    };
    if let Some(dir) = out {
        let columns = CsvColumns::of_tracker(config);
        write_track_tables(dir, ["track.csv", "boxes.txt"], &records, columns, start)?;
        write_summary(&dir.join("summary.json"), &summary)?;
    }
    drop(folder);
    Ok(VideoRun {
        start,
        records,
        summary,
    })
}

/// The box of the initial contour, as `summary.json` gives it.
fn ellipse_box(e: &Ellipse) -> BoundingBox {
    e.bounding_box()
}

/// The scores of `track run` against the ground truth: the start frame is given, not tracked,
/// so it is not scored; `None` when no labelled frame follows it.
fn score(
    start: usize,
    records: &[FrameRecord],
    truth: &[Option<BoundingBox>],
    seconds: f64,
) -> Result<Option<SequenceMetrics>> {
    let predicted: Vec<Option<BoundingBox>> = std::iter::repeat_n(None, start)
        .chain(records.iter().map(|r| Some(r.bbox)))
        .collect();
    score_run(&predicted, truth, start, Some(seconds.max(1e-9)))
}
