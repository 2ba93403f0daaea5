//! `track eval`: Odobez's Table 1, the accuracy of Wu's hidden processes, and OTB benchmarks.

use std::path::{Path, PathBuf};

use clap::Subcommand;
use scene_synth::Scenario;
use trackers::{Preset, SmootherSettings, TrackerConfig};
use vision_core::BoundingBox;

use crate::commands::run::{DEFAULT_PARTICLES, DEFAULT_SEED, Overrides, progress, tracker_config};
use crate::evaluation::{
    SyntheticSequence, TABLE1_COLUMNS, TABLE1_TRACKERS, switching_csv, switching_markdown,
    switching_scores, table1, table1_csv, table1_markdown,
};
use crate::groundtruth::{check_groundtruth_len, first_box_in_frame, load_groundtruth};
use crate::metrics::{SequenceMetrics, evaluate, mean_metrics, with_self_evaluation};
use crate::output::write_atomic;
use crate::sequence::{FrameSource, open_sequence};
use crate::session::Session;
use crate::{AppError, Result};

/// Arguments of `track eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// What to evaluate.
    #[command(subcommand)]
    pub what: Evaluation,
}

/// The evaluations.
#[derive(Debug, Subcommand)]
pub enum Evaluation {
    /// Odobez's Table 1: success rates of m1, m2, m3 and full over dynamics D1–D4 and particle
    /// counts S1–S2 on a synthetic scene.
    #[command(after_help = "Example:\n  track eval table1 --trials 50 --frames 120 --out results/")]
    Table1(Table1Args),
    /// Accuracy of β̂, γ̂ and α̂ against the generator's ground truth on the mclutter and
    /// occlusion scenes.
    #[command(after_help = "Example:\n  track eval switching --out results/")]
    Switching(SwitchingArgs),
    /// Precision at 20 px, success AUC and frames/s on OTB folders (img/ + groundtruth_rect.txt;
    /// frames labelled 0,0,0,0 are not scored).
    #[command(
        after_help = "Example:\n  track eval otb ../shared/data/real/girl_mil --tracker m1 --tracker full"
    )]
    Otb(OtbArgs),
}

/// Arguments of `track eval table1`.
#[derive(Debug, clap::Args)]
pub struct Table1Args {
    /// The synthetic scenario.
    #[arg(long, value_enum, default_value_t = ScenarioArg::Distractor)]
    pub scenario: ScenarioArg,
    /// Trials (seeds 1..=N) per cell.
    #[arg(long, default_value_t = 50)]
    pub trials: usize,
    /// Frames of the scene (default: the scenario's length).
    #[arg(long)]
    pub frames: Option<usize>,
    /// Seed of the scene (the trials' seeds are 1..=trials).
    #[arg(long, default_value_t = 1)]
    pub scene_seed: u64,
    /// Trackers (repeatable; default m1, m2, m3, full).
    #[arg(long = "tracker")]
    pub trackers: Vec<String>,
    /// Override a scene parameter, `dotted.path=JSON` (repeatable), e.g.
    /// `--set target.contrast_min=0.05` (see `cargo xtask gen-clutter --help`).
    #[arg(long = "set", value_name = "PATH=JSON")]
    pub set: Vec<String>,
    /// Folder for table1.md and table1.csv.
    #[arg(long, default_value = "track-eval")]
    pub out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// Arguments of `track eval switching`.
#[derive(Debug, clap::Args)]
pub struct SwitchingArgs {
    /// Trackers (default w-hmm, w-occ, w-eval, full), particles and seed.
    #[command(flatten)]
    pub run: TrackerRuns,
    /// Frames of each scene (default: the scenario's length).
    #[arg(long)]
    pub frames: Option<usize>,
    /// Runs per scene and tracker: run k renders the scene with seed 1 + k and tracks it with
    /// seed SEED + k; the table gives the mean and range.
    #[arg(long, default_value_t = 1)]
    pub seeds: usize,
    /// Also smooth each run (forward filtering–backward smoothing of the recorded particles)
    /// and score the smoothed estimates, as rows "TRACKER smoothed".
    #[arg(long)]
    pub smooth: bool,
    /// A tracker configuration file (JSON or TOML, as `track config` or `track
    /// learn-switching` write), run beside the presets (repeatable).
    #[arg(long = "config")]
    pub configs: Vec<PathBuf>,
    /// Folder for switching.md and switching.csv.
    #[arg(long, default_value = "track-eval")]
    pub out: PathBuf,
}

/// Arguments of `track eval otb`.
#[derive(Debug, clap::Args)]
pub struct OtbArgs {
    /// OTB folders.
    #[arg(required = true)]
    pub sequences: Vec<PathBuf>,
    /// Trackers (default head when no --config is given), particles and seed (both also
    /// override those of a --config file).
    #[command(flatten)]
    pub run: TrackerRuns,
    /// Edge threshold of the measurement lines, grey levels per pixel (default: the
    /// preset's, 8); see `track run --help`.
    #[arg(long, value_parser = crate::commands::run::parse_edge_threshold)]
    pub edge_threshold: Option<f32>,
    /// A tracker configuration file (JSON or TOML, as `track config PRESET` prints), run
    /// beside the presets (repeatable).
    #[arg(long = "config")]
    pub configs: Vec<PathBuf>,
    /// Folder for otb.md and otb.csv.
    #[arg(long, default_value = "track-eval")]
    pub out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// Which trackers an evaluation runs, with how many particles and which seed.
#[derive(Debug, clap::Args)]
pub struct TrackerRuns {
    /// A tracker preset (repeatable; the default depends on the evaluation).
    #[arg(long = "tracker")]
    pub trackers: Vec<String>,
    /// Particles.
    #[arg(long, default_value_t = DEFAULT_PARTICLES)]
    pub particles: usize,
    /// Tracker seed.
    #[arg(long, default_value_t = DEFAULT_SEED)]
    pub seed: u64,
}

impl TrackerRuns {
    /// The configurations to run: the `--tracker` presets (`default` when neither a preset nor a
    /// `--config` file is given) and then the `--config` files, each with these particles and
    /// seed and the edge threshold, when given.
    fn configs(
        &self,
        files: &[PathBuf],
        default: &[Preset],
        edge_threshold: Option<f32>,
    ) -> Result<Vec<TrackerConfig>> {
        let overrides = || Overrides {
            particles: Some(self.particles),
            seed: Some(self.seed),
            parallel: false,
            edge_threshold,
        };
        let default = if files.is_empty() { default } else { &[] };
        let mut runs = Vec::new();
        for p in presets(&self.trackers, default)? {
            runs.push(tracker_config(p.name(), None, overrides())?);
        }
        for path in files {
            // With a file, the preset name is not read.
            runs.push(tracker_config("", Some(path), overrides())?);
        }
        Ok(runs)
    }
}

/// The synthetic scenarios, for the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ScenarioArg {
    /// Static camera, three clutter regions.
    Mclutter,
    /// The target passes behind an occluder.
    Occlusion,
    /// Camera motion, a distractor, abrupt velocity changes.
    Distractor,
    /// Abrupt zooms and head turns.
    Zoom,
}

impl From<ScenarioArg> for Scenario {
    fn from(s: ScenarioArg) -> Self {
        match s {
            ScenarioArg::Mclutter => Scenario::Mclutter,
            ScenarioArg::Occlusion => Scenario::Occlusion,
            ScenarioArg::Distractor => Scenario::Distractor,
            ScenarioArg::Zoom => Scenario::Zoom,
        }
    }
}

fn presets(names: &[String], default: &[Preset]) -> Result<Vec<Preset>> {
    if names.is_empty() {
        return Ok(default.to_vec());
    }
    names
        .iter()
        .map(|n| Preset::from_name(n).map_err(|e| AppError::setting("--tracker", e.to_string())))
        .collect()
}

fn positive(name: &str, v: usize) -> Result<()> {
    if v == 0 {
        return Err(AppError::setting(name, "must be at least 1"));
    }
    Ok(())
}

/// Runs `track eval`.
///
/// # Errors
/// See [`AppError`].
pub fn run(args: &Args) -> Result<()> {
    match &args.what {
        Evaluation::Table1(a) => run_table1(a),
        Evaluation::Switching(a) => run_switching(a),
        Evaluation::Otb(a) => run_otb(a),
    }
}

/// `track eval table1`: writes table1.md and table1.csv and prints the table.
fn run_table1(args: &Table1Args) -> Result<()> {
    let Table1Args {
        scenario,
        trials,
        frames,
        scene_seed,
        trackers,
        set,
        out,
        quiet,
    } = args;
    positive("--trials", *trials)?;
    if let Some(f) = frames {
        positive("--frames", *f)?;
    }
    let trackers = presets(trackers, &TABLE1_TRACKERS)?;
    let _folder = crate::output::OutputFolder::open(out, &[])?;
    let seq = SyntheticSequence::render((*scenario).into(), *frames, *scene_seed, set)?;
    let bar = progress(
        (trackers.len() * TABLE1_COLUMNS.len()) as u64,
        *quiet,
        "table 1 cells",
    );
    let rows = table1(&seq, &trackers, &TABLE1_COLUMNS, *trials, &|| bar.inc(1))?;
    bar.finish_and_clear();
    let md = format!(
        "Odobez Table 1 protocol on the synthetic `{}` scene ({} frames, scene seed {}{}).\n\n{}",
        seq.name,
        seq.frames.len(),
        scene_seed,
        if set.is_empty() {
            String::new()
        } else {
            format!(", overrides {}", set.join(" "))
        },
        table1_markdown(&rows, &TABLE1_COLUMNS, *trials)
    );
    write_atomic(&out.join("table1.md"), md.as_bytes())?;
    write_atomic(
        &out.join("table1.csv"),
        table1_csv(&rows, &TABLE1_COLUMNS, *trials).as_bytes(),
    )?;
    crate::output::println_stdout(&md)?;
    Ok(())
}

/// `track eval switching`: writes switching.md and switching.csv and prints the table.
fn run_switching(args: &SwitchingArgs) -> Result<()> {
    let SwitchingArgs {
        run,
        frames,
        seeds,
        smooth,
        configs,
        out,
    } = args;
    positive("--particles", run.particles)?;
    positive("--seeds", *seeds)?;
    let runs = run.configs(
        configs,
        &[Preset::WHmm, Preset::WOcc, Preset::WEval, Preset::Full],
        None,
    )?;
    let seed = &run.seed;
    let _folder = crate::output::OutputFolder::open(out, &[])?;
    let smoother = SmootherSettings::default();
    let mut rows = Vec::new();
    for scenario in [Scenario::Mclutter, Scenario::Occlusion] {
        for k in 0..*seeds as u64 {
            let seq = SyntheticSequence::render(scenario, *frames, 1 + k, &[])?;
            for run in &runs {
                let config = TrackerConfig {
                    seed: *seed + k,
                    ..run.clone()
                };
                let name = run.name.clone();
                if *smooth {
                    let (output, smoothed, _) = seq.track_and_smooth(config, &smoother)?;
                    rows.push(switching_scores(&seq, &name, &output.records));
                    let smoothed_name = format!("{name} smoothed");
                    rows.push(switching_scores(&seq, &smoothed_name, &smoothed));
                } else {
                    let output = seq.track(config, None)?;
                    rows.push(switching_scores(&seq, &name, &output.records));
                }
            }
        }
    }
    let md = switching_markdown(&rows);
    write_atomic(&out.join("switching.md"), md.as_bytes())?;
    write_atomic(&out.join("switching.csv"), switching_csv(&rows).as_bytes())?;
    crate::output::println_stdout(&md)?;
    Ok(())
}

/// `track eval otb`: writes otb.md and otb.csv and prints the table.
fn run_otb(args: &OtbArgs) -> Result<()> {
    let OtbArgs {
        sequences,
        run,
        edge_threshold,
        configs,
        out,
        quiet,
    } = args;
    let runs = run.configs(configs, &[Preset::Head], *edge_threshold)?;
    // Results are written after every sequence is tracked: an output folder that cannot be
    // made, or is in use, is found before that.
    let inputs: Vec<&Path> = sequences.iter().map(PathBuf::as_path).collect();
    let _folder = crate::output::OutputFolder::open(out, &inputs)?;
    let mut rows: Vec<(String, String, SequenceMetrics)> = Vec::new();
    for config in &runs {
        let mut per_tracker = Vec::new();
        for dir in sequences {
            let m = evaluate_otb(dir, config, *quiet)?;
            rows.push((sequence_name(dir), config.name.clone(), m.clone()));
            per_tracker.push(m);
        }
        if let Some(mean) = mean_metrics(&per_tracker) {
            rows.push(("mean".to_owned(), config.name.clone(), mean));
        }
    }
    let md = otb_markdown(&rows);
    write_atomic(&out.join("otb.md"), md.as_bytes())?;
    write_atomic(&out.join("otb.csv"), otb_csv(&rows).as_bytes())?;
    crate::output::println_stdout(&md)?;
    Ok(())
}

fn sequence_name(dir: &Path) -> String {
    dir.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| dir.display().to_string())
}

/// Tracks one OTB folder with `config` from its first labelled box (the frames before it are
/// skipped); returns the session (to finish, or to smooth first), the index of the first tracked
/// frame and the ground truth.
pub(crate) fn track_otb(
    dir: &Path,
    config: &TrackerConfig,
    quiet: bool,
) -> Result<(Session, usize, Vec<Option<BoundingBox>>)> {
    let spec = dir.to_string_lossy();
    let mut sequence = open_sequence(&spec)?;
    let gt_path = sequence.groundtruth.clone().ok_or_else(|| {
        AppError::input(dir, "not an OTB folder: groundtruth_rect.txt is missing")
    })?;
    let info = sequence.source.validate_all()?;
    let truth = load_groundtruth(&gt_path)?;
    check_groundtruth_len(&truth, info.frames, &gt_path)?;
    let (start, init_box) =
        first_box_in_frame(&truth, &gt_path, &sequence.name, info.width, info.height)?;
    let init = init_box.inscribed_ellipse();
    let tracker = &config.name;
    let mut session = Session::new(
        trackers::build(config.clone())
            .map_err(|e| AppError::setting("--tracker", e.to_string()))?,
        None,
    );
    let bar = progress(
        info.frames as u64,
        quiet,
        &format!("{tracker} on {}", sequence.name),
    );
    while let Some(frame) = sequence.source.next_frame()? {
        bar.inc(1);
        if frame.index >= start {
            session.push(&frame, &init, None)?;
        }
    }
    bar.finish_and_clear();
    Ok((session, start, truth))
}

/// Tracks one OTB folder from its first labelled box and scores it.
fn evaluate_otb(dir: &Path, config: &TrackerConfig, quiet: bool) -> Result<SequenceMetrics> {
    let (session, start, truth) = track_otb(dir, config, quiet)?;
    let output = session.finish();
    let boxes: Vec<_> = output.records.iter().map(|r| r.bbox).collect();
    // The initialisation frame is given, not tracked: it is not scored (as in PEERS.md).
    let mut scored = truth[start..start + boxes.len()].to_vec();
    if let Some(first) = scored.first_mut() {
        *first = None;
    }
    let p_lost: Vec<Option<f64>> = output
        .records
        .iter()
        .map(|r| r.alpha_probs.get(LOST_INDEX).copied())
        .collect();
    let metrics = evaluate(&boxes, &scored, Some(output.seconds.max(1e-9)))?;
    Ok(with_self_evaluation(metrics, &boxes, &scored, &p_lost))
}

/// Where P(lost) sits in a record's `alpha_probs` (locked, partially occluded, lost).
const LOST_INDEX: usize = 2;

fn otb_markdown(rows: &[(String, String, SequenceMetrics)]) -> String {
    let mut s = String::from(
        "| Sequence | Tracker | Precision@20px | Success AUC | Mean IoU | Frames/s | Lost ROC AUC | Failed at |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for (seq, tracker, m) in rows {
        s.push_str(&format!(
            "| {seq} | {tracker} | {:.3} | {:.3} | {:.3} | {:.1} | {} | {} |\n",
            m.precision_20,
            m.success_auc,
            m.mean_iou,
            m.fps.unwrap_or(0.0),
            m.lost_auc
                .map(|a| format!("{a:.3}"))
                .unwrap_or_else(|| "—".into()),
            m.failed_at_frame
                .map(|f| (f + 1).to_string())
                .unwrap_or_else(|| "—".into())
        ));
    }
    s
}

fn otb_csv(rows: &[(String, String, SequenceMetrics)]) -> String {
    let mut s = String::from(
        "sequence,tracker,frames,labelled,precision_20,success_auc,mean_iou,fps,lost_auc,failed_at\n",
    );
    for (seq, tracker, m) in rows {
        s.push_str(&format!(
            "{seq},{tracker},{},{},{:.4},{:.4},{:.4},{:.2},{},{}\n",
            m.frames,
            m.labelled_frames,
            m.precision_20,
            m.success_auc,
            m.mean_iou,
            m.fps.unwrap_or(0.0),
            m.lost_auc.map(|a| format!("{a:.4}")).unwrap_or_default(),
            m.failed_at_frame
                .map(|f| (f + 1).to_string())
                .unwrap_or_default()
        ));
    }
    s
}
