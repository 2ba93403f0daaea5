//! `track run`'s outputs: the output folder, checked before tracking, and what the frame loop
//! left, written after it (tables, animation, plots, report, summary).

use std::path::Path;

use image::RgbImage;
use trackers::TrackerConfig;
use vision_core::{BoundingBox, TrackStatus};

use super::thinned::Thinned;
use super::{Args, CheckedInput, STRIP_FRAMES, command_line, frames};
use super::{GIF_FRAME_MS, GIF_MAX_DELAY_MS};
use crate::metrics::{SequenceMetrics, score_run};
use crate::plots::{all_figures_with, write_figures};
use crate::record::{
    CsvColumns, FrameRecord, GifSummary, Interruption, Summary, status_counts, write_summary,
    write_track_tables,
};
use crate::render::{thumbnail, write_gif};
use crate::report::{ReportInput, strip_indices, summary_rows, write_report};
use crate::{AppError, Result};

/// The files `track run` writes in `--out`, besides `overlay/NNNN.png` and `plots/*.svg`.
pub const OUTPUT_FILES: [&str; 7] = [
    "track.csv",
    "boxes.txt",
    "smoothed.csv",
    "smoothed_boxes.txt",
    "summary.json",
    "track.gif",
    "report.html",
];

/// Whether `path` is named as an overlay `track run` writes (`<digits>.png` or `<digits>.jpg`).
fn is_overlay_name(path: &Path) -> bool {
    path.extension().is_some_and(|e| e == "png" || e == "jpg")
        && path
            .file_stem()
            .and_then(|s| s.to_str())
            .is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
}

/// Opens `--out` before tracking, through the output guard
/// ([`OutputGuard::folder`](crate::output::OutputGuard::folder)): refuses a folder that is, holds
/// or lies inside one of `inputs`, a symbolic link, or one in use by another command;
/// removes what `track` wrote there before (its manifest says what, and nothing else is ever
/// removed); then checks that no file of another origin takes the name of an output this run
/// will write, so that the run cannot fail on it halfway.
///
/// # Errors
/// [`AppError::Write`] naming the folder or the file.
pub fn prepare_out(
    out: &Path,
    inputs: &[&Path],
    overlay: bool,
    plots: bool,
) -> Result<crate::output::OutputFolder> {
    let folder = crate::output::OutputGuard::new(inputs).folder(out)?;
    for name in OUTPUT_FILES {
        folder.check_free(Path::new(name), None)?;
    }
    if overlay {
        folder.check_free(Path::new("overlay"), Some(&is_overlay_name))?;
    }
    if plots {
        folder.check_free(
            Path::new("plots"),
            Some(&|p: &Path| p.extension().is_some_and(|e| e == "svg")),
        )?;
    }
    Ok(folder)
}

/// Writes every output of a run from what the frame loop left, then reports the stop (a
/// signal or a stream error) as the run's error, or prints the summary.
pub(super) fn write_outputs(
    args: &Args,
    input: &CheckedInput,
    tracked: frames::Tracked,
    kept: Kept,
) -> Result<()> {
    let frames::Tracked {
        output,
        smoothed: tracked_smoothed,
        frames_read,
        wall_seconds,
        mut stop,
    } = tracked;
    let (config, start) = (&input.config, input.start);
    let records = output.records;
    let smoothed = tracked_smoothed;
    if records.is_empty() {
        return Err(stop.unwrap_or_else(|| {
            AppError::input(
                &args.sequence,
                "no frame to track after the first labelled one",
            )
        }));
    }
    let interrupted = interruption(&mut stop, records.len(), frames_read);
    let Kept {
        gif,
        strip,
        strip_known,
        mut written,
    } = kept;

    write_tables(
        args,
        config,
        start,
        &records,
        smoothed.as_deref(),
        &mut written,
    )?;
    let (figures, gif) = write_animation_and_plots(
        args,
        input,
        &records,
        smoothed.as_deref(),
        gif,
        &mut written,
    )?;
    if let Some(notice) = gif.as_ref().and_then(|g| g.notice())
        && !args.quiet
    {
        // A notice only: standard error that cannot be written is no reason to fail the run.
        let _ = std::io::Write::write_all(
            &mut std::io::stderr(),
            format!("note: {notice}\n").as_bytes(),
        );
    }
    let metrics = match &input.truth {
        Some(t) => score(start, &records, t, output.seconds)?,
        None => None,
    };
    if args.report {
        written.push("report.html".into());
    }
    written.push("summary.json".into());
    let mut summary = run_summary(
        input,
        &records,
        output.seconds,
        metrics,
        written,
        interrupted,
    );
    summary.wall_seconds = Some(wall_seconds);
    summary.gif = gif;
    if args.report {
        write_run_report(args, input, &summary, figures, strip, strip_known.is_some())?;
    }
    write_summary(&args.out.join("summary.json"), &summary)?;
    if let Some(e) = stop {
        return Err(e);
    }
    if !args.quiet {
        print_summary(&summary, &args.out)?;
    }
    Ok(())
}

/// What stopped the run early, for the summary; an interruption by a signal is given the number
/// of frames tracked.
fn interruption(
    stop: &mut Option<AppError>,
    tracked_frames: usize,
    frames_read: usize,
) -> Option<Interruption> {
    if let Some(AppError::Interrupted { frames, .. }) = stop {
        *frames = tracked_frames;
    }
    stop.as_ref().map(|e| Interruption {
        reason: match e {
            AppError::Interrupted { signal, .. } => (*signal).to_owned(),
            other => other.to_string(),
        },
        frames_read,
    })
}

/// Writes `track.csv` and `boxes.txt`, and their smoothed versions when there are smoothed
/// records, adding them to `written`.
fn write_tables(
    args: &Args,
    config: &TrackerConfig,
    start: usize,
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
    written: &mut Vec<String>,
) -> Result<()> {
    let columns = CsvColumns::of_tracker(config);
    let tables = [
        ("track.csv", "boxes.txt", Some(records)),
        ("smoothed.csv", "smoothed_boxes.txt", smoothed),
    ];
    for (csv, boxes, records) in tables {
        if let Some(records) = records {
            write_track_tables(&args.out, [csv, boxes], records, columns, start)?;
            written.extend([csv.to_owned(), boxes.to_owned()]);
        }
    }
    Ok(())
}

/// The run's `summary.json`.
fn run_summary(
    input: &CheckedInput,
    records: &[FrameRecord],
    seconds: f64,
    metrics: Option<SequenceMetrics>,
    outputs: Vec<String>,
    interrupted: Option<Interruption>,
) -> Summary {
    let config = &input.config;
    Summary {
        tool_version: env!("CARGO_PKG_VERSION").to_owned(),
        sequence: input.name.clone(),
        tracker: config.name.clone(),
        particles: config.particles,
        seed: config.seed,
        frames: records.len(),
        width: input.width,
        height: input.height,
        frame_rate: input.frame_rate,
        initial_box: Some(input.init.bounding_box()),
        seconds,
        fps: records.len() as f64 / seconds.max(1e-9),
        mean_millis: 1e3 * seconds / records.len().max(1) as f64,
        status_counts: status_counts(records),
        metrics,
        outputs,
        wall_seconds: None,
        gif: None,
        interrupted,
    }
}

/// Writes `report.html`: the summary's figures, the plots and the strip of overlays.
fn write_run_report(
    args: &Args,
    input: &CheckedInput,
    summary: &Summary,
    figures: Vec<crate::plots::Figure>,
    strip: Thinned<(String, RgbImage)>,
    strip_picked_in_advance: bool,
) -> Result<()> {
    let config = &input.config;
    let report = ReportInput {
        title: format!("{} — {}", input.name, config.name),
        subtitle: format!(
            "{} (tracker {}, {} particles, seed {})",
            command_line(std::env::args_os()),
            config.name,
            config.particles,
            config.seed
        ),
        metrics: tracker_rows(config, summary),
        figures,
        strip: strip_frames(strip, strip_picked_in_advance),
        notes: report_notes(config, summary),
    };
    write_report(&args.out.join("report.html"), &report)
}

/// Writes `track.gif` and `plots/*.svg` when asked for, adding them to `written`; returns the
/// figures, which the report shows too (none when neither plots nor a report are asked for),
/// and what the GIF holds.
fn write_animation_and_plots(
    args: &Args,
    input: &CheckedInput,
    records: &[FrameRecord],
    smoothed: Option<&[FrameRecord]>,
    gif: Thinned<RgbImage>,
    written: &mut Vec<String>,
) -> Result<(Vec<crate::plots::Figure>, Option<GifSummary>)> {
    let mut gif_summary = None;
    if args.gif {
        let stride = gif.stride();
        let frames: Vec<RgbImage> = gif.into_items().into_iter().map(|(_, f)| f).collect();
        let delay_ms = gif_delay_ms(stride);
        write_gif(&args.out.join("track.gif"), &frames, delay_ms)?;
        written.push("track.gif".into());
        gif_summary = Some(GifSummary {
            frames: frames.len(),
            tracked: records.len(),
            stride,
            delay_ms,
        });
    }
    let figures = if args.plots || args.report {
        let options = crate::plots::PlotOptions::of_tracker(&input.config)
            .with_truth(truth_points(input.truth.as_deref()));
        all_figures_with(records, smoothed, &options)?
    } else {
        Vec::new()
    };
    if args.plots {
        for p in write_figures(&args.out.join("plots"), &figures)? {
            if let Ok(rel) = p.strip_prefix(&args.out) {
                written.push(rel.display().to_string());
            }
        }
    }
    Ok((figures, gif_summary))
}

/// The display time of a GIF frame that stands for `stride` frames: `stride` twelfths of a
/// second, at most [`GIF_MAX_DELAY_MS`].
pub fn gif_delay_ms(stride: usize) -> u32 {
    u32::try_from(stride)
        .unwrap_or(u32::MAX)
        .saturating_mul(GIF_FRAME_MS)
        .min(GIF_MAX_DELAY_MS)
}

/// The ground-truth boxes of an OTB folder as plot points (frame index = position).
fn truth_points(truth: Option<&[Option<BoundingBox>]>) -> Vec<crate::plots::TruthAt> {
    truth
        .unwrap_or_default()
        .iter()
        .map(|b| crate::plots::TruthAt {
            bbox: *b,
            ..Default::default()
        })
        .collect()
}

/// The report's metrics rows for the tracker of `config`: a tracker without a partial state
/// (the lock chain) counts its frames locked / lost.
fn tracker_rows(config: &TrackerConfig, summary: &Summary) -> Vec<(String, String)> {
    let mut rows = summary_rows(summary);
    if !config.has_partial_state()
        && let Some([l, _, o]) = summary.status_counts
    {
        for (name, value) in &mut rows {
            if name == "frames locked / partial / lost" {
                let unstated = summary.frames.saturating_sub(l + o);
                *name = "frames locked / lost".to_owned();
                *value = format!("{l} / {o}{}", crate::report::unstated_text(unstated));
            }
        }
    }
    rows
}

/// Notes under the report's metrics: what the ESS means for this tracker, what its status
/// probabilities are.
fn report_notes(config: &TrackerConfig, summary: &Summary) -> Vec<String> {
    let mut notes = crate::report::standard_notes(summary);
    notes.push(crate::report::ess_note(config.is_tempered()));
    notes
}

/// The overlays kept for the report's strip: all of them when the frames were picked in
/// advance (known length), else evenly spaced ones among those the stream kept.
fn strip_frames(
    strip: Thinned<(String, RgbImage)>,
    picked_in_advance: bool,
) -> Vec<(String, RgbImage)> {
    let kept: Vec<_> = strip.into_items().into_iter().map(|(_, f)| f).collect();
    if picked_in_advance {
        return kept;
    }
    let ks = strip_indices(kept.len(), STRIP_FRAMES);
    kept.into_iter()
        .enumerate()
        .filter(|(i, _)| ks.contains(i))
        .map(|(_, f)| f)
        .collect()
}

/// What a run keeps of its overlays while it tracks, and the outputs written so far.
pub(super) struct Kept {
    /// Frames for the animated GIF.
    gif: Thinned<RgbImage>,
    /// Labelled thumbnails for the report's strip.
    strip: Thinned<(String, RgbImage)>,
    /// The strip's frames (relative to the start), when the length is known in advance.
    strip_known: Option<Vec<usize>>,
    /// Output files written, relative to `--out`.
    written: Vec<String>,
}

impl Kept {
    pub(super) fn new(args: &Args, known_frames: Option<usize>, start: usize) -> Self {
        // With a known length the GIF takes every k-th overlay and the strip fixed frames; a
        // stream keeps evenly spaced frames in bounded memory ([`Thinned`]). A stride the user
        // gives is kept, and the GIF ends when it is full.
        let cap = args.gif_frames as usize;
        let gif = match args.gif_stride {
            Some(k) => Thinned::truncating(cap, k as usize),
            None => Thinned::new(
                cap,
                known_frames.map_or(1, |n| n.saturating_sub(start).div_ceil(cap)),
            ),
        };
        Self {
            gif,
            strip: Thinned::new(2 * STRIP_FRAMES, 1),
            strip_known: known_frames.map(|n| strip_indices(n - start, STRIP_FRAMES)),
            written: Vec::new(),
        }
    }

    /// Writes or keeps the overlay `img` of frame `index` (the `k`-th tracked) as the run's
    /// options ask.
    ///
    /// # Errors
    /// [`AppError::Write`] when the overlay PNG cannot be written.
    pub(super) fn overlay(
        &mut self,
        args: &Args,
        index: usize,
        k: usize,
        img: RgbImage,
    ) -> Result<()> {
        if args.overlay {
            let format = args.overlay_format;
            let name = format!("overlay/{:04}.{}", index + 1, format.extension());
            format.write(&args.out.join(&name), &img)?;
            self.written.push(name);
        }
        if args.report {
            let label = format!("frame {}", index + 1);
            let wanted = match &self.strip_known {
                Some(ks) => ks.contains(&k),
                None => self.strip.wants(k),
            };
            if wanted {
                self.strip.push(k, (label, thumbnail(&img, 200)));
            }
        }
        if args.gif {
            self.gif.push(k, img);
        }
        Ok(())
    }
}

/// Scores the tracked frames against the ground truth with the one scorer of `track eval otb`
/// ([`score_run`]): the start frame is given, not tracked, so it is not scored. `None` when no
/// labelled frame follows it.
pub(crate) fn score(
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

fn print_summary(s: &Summary, out: &Path) -> Result<()> {
    let mut text = format!(
        "{}: {} frames with {} ({} particles) at {:.1} frames/s tracking alone{}\n",
        s.sequence,
        s.frames,
        s.tracker,
        s.particles,
        s.fps,
        s.wall_seconds
            .map(|w| format!(", {:.1} frames/s wall clock", s.frames as f64 / w.max(1e-9)))
            .unwrap_or_default()
    );
    if let Some(m) = &s.metrics {
        text.push_str(&format!(
            "  precision@20px {:.3}, success AUC {:.3}, mean IoU {:.3}{}\n",
            m.precision_20,
            m.success_auc,
            m.mean_iou,
            m.failed_at_frame
                .map(|f| format!(", lost at frame {}", f + 1))
                .unwrap_or_default()
        ));
    }
    if let Some(c) = s.status_counts {
        let unstated = s.frames.saturating_sub(c.iter().sum());
        text.push_str(&format!(
            "  status: {} locked, {} partial, {} lost{}\n",
            c[TrackStatus::Locked.index()],
            c[TrackStatus::PartiallyOccluded.index()],
            c[TrackStatus::Lost.index()],
            crate::report::unstated_text(unstated)
        ));
    }

    text.push_str(&format!("  outputs in {}\n", out.display()));
    crate::output::print_stdout(&text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gif_frames_show_longer_for_a_larger_stride_up_to_a_quarter_second() {
        assert_eq!(gif_delay_ms(1), 83);
        assert_eq!(gif_delay_ms(2), 166);
        assert_eq!(gif_delay_ms(4), GIF_MAX_DELAY_MS);
        assert_eq!(gif_delay_ms(usize::MAX), GIF_MAX_DELAY_MS);
    }
}
