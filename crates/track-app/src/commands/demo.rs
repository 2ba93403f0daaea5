//! `track demo`: generate a synthetic scene in memory, track it with the `full` tracker and write
//! overlays, an animated GIF, plots and a report — no downloads, no files to prepare.

use std::path::PathBuf;

use trackers::Preset;
use vision_core::BoundingBox;

use crate::commands::eval::ScenarioArg;
use crate::commands::run::{DEFAULT_PARTICLES, DEFAULT_SEED, STRIP_FRAMES};
use crate::evaluation::SyntheticSequence;
use crate::metrics::score_run;
use crate::output::write_atomic;
use crate::plots::{PlotOptions, TruthAt, all_figures_with, write_figures};
use crate::record::{
    CsvColumns, GifSummary, Summary, status_counts, write_summary, write_track_tables,
};
use crate::render::{OverlayFormat, thumbnail, write_gif};
use crate::report::{ReportInput, strip_indices, summary_rows, write_report};
use crate::session::{ColourBy, DrawOptions, SessionOutput};
use crate::{AppError, Result};

/// Arguments of `track demo`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Example:\n  track demo            # writes ./track-demo/report.html and friends\n  \
    track demo --scenario occlusion --colour-by status --out demo-occlusion"
)]
pub struct Args {
    /// Output folder.
    #[arg(long, default_value = "track-demo")]
    pub out: PathBuf,
    /// The synthetic scenario (default: three regions of light, medium and heavy clutter that
    /// the target wanders through, Wu Fig. 3 and 10).
    #[arg(long, value_enum, default_value_t = ScenarioArg::Mclutter)]
    pub scenario: ScenarioArg,
    /// Tracker preset.
    #[arg(long, default_value = "full", value_parser = crate::commands::preset_parser())]
    pub tracker: String,
    /// Number of particles.
    #[arg(long, default_value_t = DEFAULT_PARTICLES)]
    pub particles: usize,
    /// Seed of the tracker and of the scene.
    #[arg(long, default_value_t = DEFAULT_SEED)]
    pub seed: u64,
    /// What colours the contour in overlays (default: the clutter class β̂, as in Wu Fig. 10).
    #[arg(long, value_enum, default_value_t = ColourBy::Clutter)]
    pub colour_by: ColourBy,
    /// No summary on standard output.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs `track demo`.
///
/// # Errors
/// See [`AppError`].
pub fn run(args: &Args) -> Result<()> {
    let started = std::time::Instant::now();
    let preset = Preset::from_name(&args.tracker)
        .map_err(|e| AppError::setting("--tracker", e.to_string()))?;
    if args.particles == 0 {
        return Err(AppError::setting("--particles", "must be at least 1"));
    }
    let config = preset.config(args.particles, args.seed);
    // The output folder is checked and locked before the work (crate::output::OutputFolder).
    let _folder = crate::output::OutputGuard::new::<&std::path::Path>([]).folder(&args.out)?;
    let seq = SyntheticSequence::render(args.scenario.into(), None, args.seed, &[])?;
    let draw = DrawOptions {
        colour_by: args.colour_by,
        ..DrawOptions::default()
    };
    let output = seq.track(config.clone(), Some(draw))?;
    let records = &output.records;

    let truth_boxes: Vec<Option<BoundingBox>> =
        (0..seq.frames.len()).map(|k| seq.truth_box(k)).collect();
    let mut written = write_tracks(args, &config, &output, &truth_boxes)?;
    let wall_seconds = started.elapsed().as_secs_f64();
    let options = PlotOptions::of_tracker(&config).with_truth(scene_truth(&seq));
    let figures = all_figures_with(records, None, &options)?;
    for p in write_figures(&args.out.join("plots"), &figures)? {
        if let Ok(rel) = p.strip_prefix(&args.out) {
            written.push(rel.display().to_string());
        }
    }
    // The one scorer of `track run` and `track eval otb`: frame 1 (the initialisation) is not
    // scored.
    let predicted: Vec<Option<BoundingBox>> = records.iter().map(|r| Some(r.bbox)).collect();
    let metrics = score_run(&predicted, &truth_boxes, 0, Some(output.seconds.max(1e-9)))?
        .ok_or_else(|| {
            AppError::computation("evaluation", "no labelled frame after the first to score")
        })?;
    written.extend(
        [
            "track.gif",
            "track.csv",
            "boxes.txt",
            "groundtruth_rect.txt",
            "report.html",
            "summary.json",
        ]
        .map(String::from),
    );
    let summary = Summary {
        tool_version: env!("CARGO_PKG_VERSION").to_owned(),
        sequence: format!("synthetic {} (seed {})", seq.name, args.seed),
        tracker: config.name.clone(),
        particles: config.particles,
        seed: config.seed,
        frames: records.len(),
        width: seq.frames.first().map_or(0, |f| f.grey.width() as usize),
        height: seq.frames.first().map_or(0, |f| f.grey.height() as usize),
        frame_rate: None,
        initial_box: Some(seq.initial_ellipse()?.bounding_box()),
        seconds: output.seconds,
        fps: records.len() as f64 / output.seconds.max(1e-9),
        mean_millis: 1e3 * output.seconds / records.len().max(1) as f64,
        status_counts: status_counts(records),
        metrics: Some(metrics.clone()),
        outputs: written,
        wall_seconds: Some(wall_seconds),
        gif: Some(GifSummary {
            frames: output.overlays.len(),
            tracked: records.len(),
            stride: 1,
            delay_ms: DEMO_GIF_MS,
        }),
        interrupted: None,
    };
    write_demo_report(args, &config, &seq.name, &output, &summary, figures)?;
    write_summary(&args.out.join("summary.json"), &summary)?;
    if !args.quiet {
        crate::output::print_stdout(&format!(
            "track demo: {} frames of the synthetic `{}` scene tracked by `{}` at {:.1} frames/s \
             (tracking alone)\n\
             \x20 mean IoU {:.3}, precision@20px {:.3}, success AUC {:.3}\n\
             \x20 open {} (overlays, plots, metrics)\n",
            records.len(),
            seq.name,
            config.name,
            summary.fps,
            metrics.mean_iou,
            metrics.precision_20,
            metrics.success_auc,
            args.out.join("report.html").display()
        ))?;
    }
    Ok(())
}

/// Display time of one frame of the demo's GIF, milliseconds (every frame is in it).
const DEMO_GIF_MS: u32 = 80;

/// Everything the scene's generator knows, as plot points: the box, the clutter class (0-based,
/// as β̂), the edge density, the occluded fraction and the status of every frame.
pub fn scene_truth(seq: &SyntheticSequence) -> Vec<TruthAt> {
    seq.truth
        .iter()
        .map(|t| TruthAt {
            bbox: Some(t.bbox),
            beta: usize::from(t.clutter_class).checked_sub(1),
            lambda: Some(t.edge_density),
            gamma: Some(1.0 - t.visible_fraction),
            alpha: Some(t.status),
        })
        .collect()
}

/// Writes the overlays, `track.gif`, `track.csv`, `boxes.txt` and the scene's
/// `groundtruth_rect.txt`; returns the overlays' names (the other files are listed by the
/// caller).
fn write_tracks(
    args: &Args,
    config: &trackers::TrackerConfig,
    output: &SessionOutput,
    truth_boxes: &[Option<BoundingBox>],
) -> Result<Vec<String>> {
    let records = &output.records;
    let mut written = Vec::new();
    for (k, img) in output.overlays.iter().enumerate() {
        let name = format!("overlay/{:04}.png", k + 1);
        OverlayFormat::Png.write(&args.out.join(&name), img)?;
        written.push(name);
    }
    write_gif(&args.out.join("track.gif"), &output.overlays, DEMO_GIF_MS)?;
    write_track_tables(
        &args.out,
        ["track.csv", "boxes.txt"],
        records,
        CsvColumns::of_tracker(config),
        0,
    )?;
    write_atomic(
        &args.out.join("groundtruth_rect.txt"),
        truth_boxes
            .iter()
            .flatten()
            .map(|b| format!("{:.2},{:.2},{:.2},{:.2}\n", b.x, b.y, b.w, b.h))
            .collect::<String>()
            .as_bytes(),
    )?;
    Ok(written)
}

/// Writes `report.html`: the summary's figures, the plots and a strip of overlays.
fn write_demo_report(
    args: &Args,
    config: &trackers::TrackerConfig,
    scene: &str,
    output: &SessionOutput,
    summary: &Summary,
    figures: Vec<crate::plots::Figure>,
) -> Result<()> {
    let strip = strip_indices(output.overlays.len(), STRIP_FRAMES)
        .into_iter()
        .filter_map(|k| {
            output
                .overlays
                .get(k)
                .map(|img| (format!("frame {}", k + 1), thumbnail(img, 200)))
        })
        .collect();
    write_report(
        &args.out.join("report.html"),
        &ReportInput {
            title: format!(
                "track demo — {} on the synthetic {} scene",
                config.name, scene
            ),
            subtitle: format!(
                "{} (scenario {}, tracker {}, {} particles, seed {})",
                crate::commands::run::command_line(std::env::args_os()),
                scene,
                config.name,
                config.particles,
                args.seed
            ),
            metrics: summary_rows(summary),
            figures,
            strip,
            notes: {
                let mut notes = crate::report::standard_notes(summary);
                notes.push(
                    "The plots draw the scene generator's truth (the true clutter class, edge \
                     density, occluded fraction and status) beside the estimates."
                        .to_owned(),
                );
                notes.push(crate::report::ess_note(config.is_tempered()));
                notes
            },
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scene_truth_gives_every_hidden_value_as_the_tracker_estimates_it() {
        let seq =
            SyntheticSequence::render(scene_synth::Scenario::Occlusion, Some(40), 1, &[]).unwrap();
        let truth = scene_truth(&seq);
        assert_eq!(truth.len(), 40);
        for (t, f) in truth.iter().zip(&seq.truth) {
            assert_eq!(t.bbox, Some(f.bbox));
            // β̂ is 0-based, the generator's classes 1-based.
            assert_eq!(t.beta, Some(usize::from(f.clutter_class) - 1));
            assert_eq!(t.lambda, Some(f.edge_density));
            assert_eq!(t.gamma, Some(1.0 - f.visible_fraction));
            assert_eq!(t.alpha, Some(f.status));
        }
    }
}
