//! `track run` as a function: [`track_video`].

use std::path::Path;

use trackers::TrackerConfig;
use vision_core::{BoundingBox, Ellipse};

use crate::commands::run::{checked_truth, prepare_out, score};
use crate::groundtruth::{BoxInFrame, first_box_in_frame};
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
    let truth = checked_truth(sequence.groundtruth.as_deref(), known_frames)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::commands::run::{Overrides, tracker_config};
    use image::{Rgb, RgbImage};

    /// Six frames of a bright ellipse moving right over a fixed texture.
    fn clip(dir: &Path) {
        std::fs::create_dir_all(dir).unwrap();
        for k in 0..6u32 {
            RgbImage::from_fn(64, 48, |x, y| {
                let dx = f64::from(x) - (24.0 + 2.0 * f64::from(k));
                let dy = f64::from(y) - 24.0;
                if dx * dx / 100.0 + dy * dy / 144.0 <= 1.0 {
                    Rgb([220, 170, 140])
                } else {
                    Rgb([((x * 7 + y * 3) % 90 + 40) as u8; 3])
                }
            })
            .save(dir.join(format!("{:04}.png", k + 1)))
            .unwrap();
        }
    }

    #[test]
    fn track_video_writes_the_boxes_and_tables_of_track_run() {
        let dir = tempfile::tempdir().unwrap();
        let frames = dir.path().join("clip");
        clip(&frames);
        let (cli, lib) = (dir.path().join("cli"), dir.path().join("lib"));
        crate::cli::try_main_from_args([
            "track",
            "run",
            frames.to_str().unwrap(),
            "--init",
            "14,12,20,24",
            "--particles",
            "50",
            "--seed",
            "2",
            "--quiet",
            "--out",
            cli.to_str().unwrap(),
        ])
        .unwrap();
        let overrides = Overrides {
            particles: Some(50),
            seed: Some(2),
            ..Overrides::default()
        };
        let config = tracker_config("head", None, overrides).unwrap();
        let init = BoundingBox::new(14.0, 12.0, 20.0, 24.0);
        let run = track_video(frames.to_str().unwrap(), Some(init), &config, Some(&lib)).unwrap();
        assert_eq!(run.records.len(), 6);
        assert_eq!(run.start, 0);
        let read = |p: &Path| std::fs::read_to_string(p).unwrap();
        assert_eq!(read(&lib.join("boxes.txt")), read(&cli.join("boxes.txt")));
        // track.csv: the same but for the last column, the time of each frame.
        let columns = |p: &Path| -> Vec<String> {
            read(p)
                .lines()
                .map(|l| l.rsplit_once(',').unwrap().0.to_owned())
                .collect()
        };
        assert_eq!(
            columns(&lib.join("track.csv")),
            columns(&cli.join("track.csv"))
        );
        // Another seed tracks otherwise: the comparison is not vacuous.
        let other = TrackerConfig {
            seed: 9,
            ..config.clone()
        };
        let again = track_video(frames.to_str().unwrap(), Some(init), &other, None).unwrap();
        assert_ne!(
            again.records.iter().map(|r| r.bbox).collect::<Vec<_>>(),
            run.records.iter().map(|r| r.bbox).collect::<Vec<_>>()
        );
    }

    #[test]
    fn standard_input_and_a_missing_box_are_refused() {
        let config = trackers::Preset::Head.config(20, 1);
        assert!(matches!(
            track_video("-", None, &config, None),
            Err(AppError::InvalidSetting { .. })
        ));
        let dir = tempfile::tempdir().unwrap();
        clip(dir.path());
        assert!(matches!(
            track_video(dir.path().to_str().unwrap(), None, &config, None),
            Err(AppError::InvalidSetting { .. })
        ));
    }
}
