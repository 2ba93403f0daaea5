//! `track eval`: Odobez's Table 1, the accuracy of Wu's hidden processes, OTB benchmarks, and the
//! paired comparison of two trackers' OTB results over seeds.

use std::path::{Path, PathBuf};

use clap::Subcommand;
use scene_synth::Scenario;
use trackers::{Preset, SmootherSettings, TrackerConfig};
use vision_core::BoundingBox;

use crate::commands::run::{Overrides, tracker_config};
use crate::evaluation::{
    SyntheticSequence, TABLE1_COLUMNS, TABLE1_TRACKERS, switching_csv, switching_markdown,
    switching_scores, table1, table1_csv, table1_markdown,
};
use crate::groundtruth::{check_groundtruth_len, first_box_in_frame, load_groundtruth};
use crate::otb::Protocol;
use crate::output::{OutputGuard, write_atomic};
use crate::progress::progress;
use crate::sequence::FrameSource;
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
    /// Success AUC, precision at 20 px and frames/s on OTB folders (img/ + groundtruth_rect.txt;
    /// frames labelled 0,0,0,0 or NaN are not scored, nor is each run's start frame), under the
    /// OTB benchmark's protocols OPE, TRE and SRE, beside other trackers' boxes.
    #[command(after_help = OTB_HELP)]
    Otb(OtbArgs),
    /// Whether a variant helps or hurts each sequence, judged over seeds: the results of
    /// `track eval otb` for the base and the variant, one folder per seed in the same order,
    /// compared seed by seed (a one-sided paired t-test on each sequence's success AUC).
    #[command(after_help = PAIRED_HELP)]
    Paired(PairedArgs),
}

const PAIRED_HELP: &str = "\
Each --base folder is paired with the --variant folder in the same position: run both with the
same seeds (--seed 1, 2, 3 ...), on the same sequences. A sequence counts as helped (hurt) when the
mean of its paired differences in success AUC is positive (negative) by a one-sided t-test at
--level: a difference larger than that sequence's own seed-to-seed noise. Prints a Markdown
table per protocol; --out also writes it to a file.

Example:
  for s in 1 2 3; do
    track eval otb $SEQS --tracker head --seed $s --protocol tre --out base-$s
    track eval otb $SEQS --config variant.json --seed $s --protocol tre --out variant-$s
  done
  track eval paired --base base-1 --base base-2 --base base-3 \\
    --variant variant-1 --variant variant-2 --variant variant-3 --protocol tre";

/// Arguments of `track eval paired`.
#[derive(Debug, clap::Args)]
pub struct PairedArgs {
    /// A `track eval otb` output folder of the base, one per seed (repeatable, at least two).
    #[arg(long = "base", required = true)]
    pub base: Vec<PathBuf>,
    /// A `track eval otb` output folder of the variant, one per seed, in the base's order.
    #[arg(long = "variant", required = true)]
    pub variant: Vec<PathBuf>,
    /// Protocols to compare (repeatable; default: each of ope, tre, sre whose `otb.csv` every
    /// folder holds).
    #[arg(long = "protocol", value_enum)]
    pub protocols: Vec<Protocol>,
    /// The tracker's name in the `otb.csv` files (default: each file's only tracker).
    #[arg(long)]
    pub tracker: Option<String>,
    /// The one-sided level of the test.
    #[arg(long, default_value_t = 0.05)]
    pub level: f64,
    /// Also write the report (Markdown) to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

const OTB_HELP: &str = "\
Protocols (as ../shared/tools/opencv_peers.py runs them; one run starts from a box on a labelled
frame, tracks to the end and is scored on the labelled frames after its start frame):
  ope  one run from the first labelled frame and its true box;
  tre  10 runs, run i starting at the first labelled frame at or after floor(i*n/10)
       (n = frames; duplicate starts and starts with no labelled frame after them dropped);
  sre  12 runs from the first labelled frame: the box shifted by 10 % of its width and/or
       height (left, right, up, down, the four diagonals), then scaled about its centre by
       0.8, 0.9, 1.1 and 1.2.
A sequence's figure is the mean over its runs; the set's the mean over sequences.
With --frame-step K, every K-th frame is kept (and its ground-truth line), from the first: the
same footage at 1/K of its frame rate, the runs laid out on the frames kept.

Outputs in --out, per protocol P: P/otb.md, P/otb.csv, P/plots/success.svg and precision.svg
(every tracker over the set) and success_SEQ.svg, precision_SEQ.svg (each sequence), and each
run's boxes as P/TRACKER/SEQ[.RUN].txt (readable again with --results); index.html shows it all.

Examples:
  track eval otb ../shared/data/real/girl_mil --tracker m1 --tracker full
  track eval otb ../shared/data/real/* --protocol tre --protocol sre --results csrt=peers/
  track eval otb ../shared/data/real/* --protocol tre --frame-step 2 --out half-rate/";

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
    /// its seed (--seed, or the preset's or file's) + k; the table gives the mean and range.
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
    /// OTB folders, or stress suites (`cargo xtask stress --out SUITE`): every clip under every
    /// transform, with a mean per transform (see `track_app::otb::suite`).
    #[arg(required = true)]
    pub sequences: Vec<PathBuf>,
    /// Trackers (default head when neither --config nor --results is given), particles and seed
    /// (both, when given, also override those of a --config file).
    #[command(flatten)]
    pub run: TrackerRuns,
    /// Edge threshold of the measurement lines, grey levels per pixel (default: the
    /// preset's, 8); see `track run --help`. Refused (exit 2) when a tracker run has no
    /// measurement lines (head, the default), which would not read it.
    #[arg(long, value_parser = crate::commands::run::parse_edge_threshold)]
    pub edge_threshold: Option<f32>,
    /// A tracker configuration file (JSON or TOML, as `track config PRESET` prints), run
    /// beside the presets (repeatable).
    #[arg(long = "config")]
    pub configs: Vec<PathBuf>,
    /// Protocol (repeatable): ope, tre or sre.
    #[arg(long = "protocol", value_enum, default_values_t = [Protocol::Ope])]
    pub protocols: Vec<Protocol>,
    // The help text shows the path pattern as typed; rustdoc would read its <…> as HTML.
    #[allow(rustdoc::invalid_html_tags)]
    /// Another tracker's boxes, NAME=DIR (repeatable): DIR/<protocol>/NAME/<sequence>[.<run>].txt
    /// for every run, as `opencv_peers.py --out DIR` writes them (or this command's own --out).
    #[arg(long = "results", value_name = "NAME=DIR")]
    pub results: Vec<String>,
    /// Track and score every K-th frame of each sequence, from its first: the footage at 1/K of
    /// its frame rate, where the target moves K times as far between frames (default 1, every
    /// frame). The runs of each protocol are laid out on the frames kept, and each box file holds
    /// one line per frame kept, so --results reads box files written with the same step.
    #[arg(long, value_name = "K", default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub frame_step: u32,
    /// Folder for the tables, plots, boxes and index.html (see below).
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
    /// Particles [default: 200, or a configuration file's own]. Given, it applies to every
    /// tracker run, presets and --config files alike.
    #[arg(long)]
    pub particles: Option<usize>,
    /// Tracker seed [default: 1, or a configuration file's own]. Given, it applies to every
    /// tracker run.
    #[arg(long)]
    pub seed: Option<u64>,
}

impl TrackerRuns {
    /// The configurations to run: the `--tracker` presets (`default` when neither a preset nor a
    /// `--config` file is given) and then the `--config` files, each with these particles and
    /// seed and the edge threshold, when given (otherwise a preset's defaults and a file's own).
    pub(crate) fn configs(
        &self,
        files: &[PathBuf],
        default: &[Preset],
        edge_threshold: Option<f32>,
    ) -> Result<Vec<TrackerConfig>> {
        let overrides = || Overrides {
            particles: self.particles,
            seed: self.seed,
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
        Evaluation::Paired(a) => run_paired(a),
    }
}

/// `track eval paired`: prints (and with `--out` writes) the paired comparison per protocol.
fn run_paired(args: &PairedArgs) -> Result<()> {
    use crate::otb::paired::{compare, csv_paths, markdown, read_auc};
    // The report file is claimed before anything is read: never an input, never a file of the
    // user's.
    let out = match &args.out {
        Some(path) => Some(OutputGuard::new(args.base.iter().chain(&args.variant)).file(path)?),
        None => None,
    };
    // Each folder named, before anything is read from it.
    for dir in args.base.iter().chain(&args.variant) {
        if !dir.is_dir() {
            let reason = if dir.exists() {
                "not a folder: give the --out folder of a `track eval otb` run"
            } else {
                "no such folder: give the --out folder of a `track eval otb` run"
            };
            return Err(AppError::input(dir, reason));
        }
    }
    let protocols: Vec<Protocol> = if args.protocols.is_empty() {
        [Protocol::Ope, Protocol::Tre, Protocol::Sre]
            .into_iter()
            .filter(|&p| {
                csv_paths(&args.base, p)
                    .iter()
                    .chain(&csv_paths(&args.variant, p))
                    .all(|f| f.is_file())
            })
            .collect()
    } else {
        args.protocols.clone()
    };
    if protocols.is_empty() {
        // Name a folder that lacks a protocol some other folder has, or else the first one.
        let dirs: Vec<&PathBuf> = args.base.iter().chain(&args.variant).collect();
        let has = |d: &PathBuf, p: Protocol| d.join(p.name()).join("otb.csv").is_file();
        let partial = [Protocol::Ope, Protocol::Tre, Protocol::Sre]
            .into_iter()
            .find_map(|p| {
                let missing = dirs.iter().find(|d| !has(d, p))?;
                dirs.iter()
                    .any(|d| has(d, p))
                    .then(|| format!("{} has no {}/otb.csv", missing.display(), p.name()))
            });
        let named = partial
            .or_else(|| {
                dirs.first()
                    .map(|d| format!("{} has no ope/, tre/ or sre/otb.csv", d.display()))
            })
            .unwrap_or_default();
        return Err(AppError::InvalidSetting {
            name: "--base and --variant".into(),
            reason: format!(
                "no protocol has an otb.csv in every folder (PROTOCOL/otb.csv, as `track eval \
                 otb --out` writes): {named}"
            ),
        });
    }
    let mut report = String::new();
    for protocol in protocols {
        let read = |dirs: &[PathBuf]| -> Result<Vec<_>> {
            csv_paths(dirs, protocol)
                .iter()
                .map(|f| read_auc(f, args.tracker.as_deref()))
                .collect()
        };
        let comparison = compare(&read(&args.base)?, &read(&args.variant)?, args.level)?;
        report.push_str(&markdown(protocol, &comparison, args.level));
        report.push('\n');
    }
    if let Some(out) = out {
        out.write(report.as_bytes())?;
    }
    crate::output::println_stdout(report.trim_end())?;
    Ok(())
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
    let _folder = OutputGuard::new::<&Path>([]).folder(out)?;
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
    if let Some(n) = run.particles {
        positive("--particles", n)?;
    }
    positive("--seeds", *seeds)?;
    let runs = run.configs(
        configs,
        &[Preset::WHmm, Preset::WOcc, Preset::WEval, Preset::Full],
        None,
    )?;
    let _folder = OutputGuard::new(configs).folder(out)?;
    let smoother = SmootherSettings::default();
    let mut rows = Vec::new();
    for scenario in [Scenario::Mclutter, Scenario::Occlusion] {
        for k in 0..*seeds as u64 {
            let seq = SyntheticSequence::render(scenario, *frames, 1 + k, &[])?;
            for run in &runs {
                let config = TrackerConfig {
                    seed: run.seed + k,
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

/// `track eval otb`: the trackers' configurations (head by default, unless `--results` gives
/// the boxes to score), then [`crate::otb::eval::run`].
fn run_otb(args: &OtbArgs) -> Result<()> {
    let default: &[Preset] = if args.results.is_empty() {
        &[Preset::Head]
    } else {
        &[]
    };
    let configs = args
        .run
        .configs(&args.configs, default, args.edge_threshold)?;
    crate::otb::eval::run(crate::otb::eval::Evaluation {
        sequences: &args.sequences,
        configs,
        config_files: &args.configs,
        protocols: &args.protocols,
        results: &args.results,
        frame_step: args.frame_step,
        out: &args.out,
        quiet: args.quiet,
    })
}

/// Tracks one OTB folder with `config` from its first labelled box (the frames before it are
/// skipped); returns the session (to finish, or to smooth first), the index of the first tracked
/// frame and the ground truth.
pub(crate) fn track_otb(
    dir: &Path,
    config: &TrackerConfig,
    quiet: bool,
) -> Result<(Session, usize, Vec<Option<BoundingBox>>)> {
    let (mut sequence, gt_path) = crate::otb::open_otb(dir)?;
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
