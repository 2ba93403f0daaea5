//! `track eval otb` in three steps, so that its runs can be spread over many machines:
//! [`plan`] (on the machine that holds the output folder), [`run`] (anywhere the sequences can be
//! read, one call per run), [`score`] (back where the plan was made).
//!
//! The steps do what `track eval otb` does, in the same order and with the same arithmetic: they
//! call its own checks of the sequences and tracker names, run starts
//! ([`crate::otb::run_starts`]), scoring ([`crate::metrics::score_run`] and
//! [`crate::metrics::with_self_evaluation`]) and writers of the tables, plots and index page, and
//! repeat its session loop from each start. A run's tracker is built from its seed alone, so a
//! run gives the same boxes wherever it runs, and [`score`] gathers the runs in the plan's order:
//! the tables are those of `track eval otb --seed SEED` on the same folders (frames/s aside,
//! which is a timing).
//! A [`RunSpec`] holds no floating-point number (the start box is found again from the ground
//! truth), so it crosses machines as JSON without a rounding.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use trackers::TrackerConfig;
use vision_core::BoundingBox;

use crate::commands::run::{Overrides, tracker_config};
use crate::groundtruth::{check_groundtruth_len, load_groundtruth};
use crate::otb::eval::{
    Prepared, RunOutcome, check_distinct, check_names, p_lost_of, prepare, score_tracked, sections,
    write_page, write_tables,
};
use crate::otb::{Protocol, boxes_path, boxes_text, run_starts, sequence_name};
use crate::output::{OutputGuard, write_atomic};
use crate::sequence::{FrameSource, open_sequence};
use crate::session::Session;
use crate::{AppError, Result};

/// A tracker of an evaluation: a preset (`--tracker NAME`) or a configuration file (`--config
/// PATH`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum TrackerSpec {
    /// A preset's name.
    Preset(String),
    /// A configuration file (JSON or TOML).
    Config(PathBuf),
}

/// Which trackers run, with the particles and seed that override theirs (`--particles`,
/// `--seed`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct TrackerRuns {
    /// The trackers, in the order of the tables (as `track eval otb`: presets, then files).
    pub trackers: Vec<TrackerSpec>,
    /// `--particles`.
    pub particles: Option<usize>,
    /// `--seed`.
    pub seed: Option<u64>,
}

impl TrackerRuns {
    /// The configuration of `tracker`, as `track eval otb` builds it.
    ///
    /// # Errors
    /// [`AppError::InvalidSetting`] for an unknown preset or a bad configuration file.
    pub fn config(&self, tracker: &TrackerSpec) -> Result<TrackerConfig> {
        let overrides = Overrides {
            particles: self.particles,
            seed: self.seed,
            parallel: false,
            edge_threshold: None,
        };
        match tracker {
            TrackerSpec::Preset(name) => {
                trackers::Preset::from_name(name)
                    .map_err(|e| AppError::setting("--tracker", e.to_string()))?;
                tracker_config(name, None, overrides)
            }
            TrackerSpec::Config(path) => tracker_config("", Some(path), overrides),
        }
    }

    /// Every tracker's configuration, the names checked as `track eval otb` checks them.
    ///
    /// # Errors
    /// As [`TrackerRuns::config`]; [`AppError::InvalidSetting`] for a name that cannot name a
    /// folder of box files, or a name given twice.
    pub fn configs(&self) -> Result<Vec<TrackerConfig>> {
        if self.trackers.is_empty() {
            return Err(AppError::setting("trackers", "give at least one tracker"));
        }
        let configs: Vec<TrackerConfig> = self
            .trackers
            .iter()
            .map(|t| self.config(t))
            .collect::<Result<_>>()?;
        check_names(configs.iter().map(|c| c.name.as_str()))?;
        Ok(configs)
    }
}

/// One run of an evaluation: which sequence, protocol, tracker and run number, and where it
/// starts. Plain data (no floating-point number): it crosses machines as JSON unchanged.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunSpec {
    /// The OTB folder.
    pub dir: PathBuf,
    /// The sequence's name (the folder's name), as in the box files' names.
    pub sequence: String,
    /// The protocol's name: `ope`, `tre` or `sre`.
    pub protocol: String,
    /// The tracker and the overrides.
    pub tracker: TrackerSpec,
    /// The tracker's name (its folder of box files).
    pub name: String,
    /// `--particles`.
    pub particles: Option<usize>,
    /// `--seed`.
    pub seed: Option<u64>,
    /// The run's number within its protocol (the `.RUN` of the box file).
    pub run: usize,
    /// The start frame (0-based).
    pub start: usize,
    /// The sequence's number of frames.
    pub frames: usize,
}

impl RunSpec {
    /// The protocol.
    ///
    /// # Errors
    /// [`AppError::InvalidSetting`] for an unknown protocol name.
    pub fn protocol(&self) -> Result<Protocol> {
        parse_protocol(&self.protocol)
    }

    fn runs(&self) -> TrackerRuns {
        TrackerRuns {
            trackers: vec![self.tracker.clone()],
            particles: self.particles,
            seed: self.seed,
        }
    }
}

/// A protocol from its name (`ope`, `tre`, `sre`, any case).
///
/// # Errors
/// [`AppError::InvalidSetting`] naming the protocol.
pub fn parse_protocol(name: &str) -> Result<Protocol> {
    <Protocol as clap::ValueEnum>::from_str(name, true).map_err(|_| {
        AppError::setting(
            "protocol",
            format!("{name:?} is not a protocol: give ope, tre or sre"),
        )
    })
}

/// What one run gave: the box and P(lost) of every tracked frame (the start frame first) and the
/// tracking time.
#[derive(Debug, Clone, PartialEq)]
pub struct RunResult {
    /// The box of each tracked frame, from the start frame on.
    pub boxes: Vec<BoundingBox>,
    /// P(lost) of each tracked frame, `None` for a tracker without a status process.
    pub p_lost: Vec<Option<f64>>,
    /// Tracking time, seconds.
    pub seconds: f64,
}

/// The ground truth of an OTB folder, checked against its frame count.
fn truth_of(dir: &Path, frames: usize) -> Result<Vec<Option<BoundingBox>>> {
    let sequence = open_sequence(&dir.to_string_lossy())?;
    let gt_path = sequence.groundtruth.ok_or_else(|| {
        AppError::input(dir, "not an OTB folder: groundtruth_rect.txt is missing")
    })?;
    let truth = load_groundtruth(&gt_path)?;
    check_groundtruth_len(&truth, frames, &gt_path)?;
    Ok(truth)
}

/// The protocols sorted, without repeats, as `track eval otb` runs them.
fn sorted(protocols: &[Protocol]) -> Vec<Protocol> {
    let mut p = protocols.to_vec();
    p.sort();
    p.dedup();
    p
}

/// Every run of `track eval otb SEQUENCES` with these trackers and protocols, checked as it
/// checks them, in its order: sequence, protocol, tracker, run.
///
/// # Errors
/// As `track eval otb`: a bad tracker or name (exit 2), a bad sequence or ground truth (exit 3).
pub fn plan(
    sequences: &[PathBuf],
    runs: &TrackerRuns,
    protocols: &[Protocol],
) -> Result<Vec<RunSpec>> {
    if sequences.is_empty() {
        return Err(AppError::setting("folders", "give at least one OTB folder"));
    }
    if protocols.is_empty() {
        return Err(AppError::setting("protocols", "give at least one protocol"));
    }
    let configs = runs.configs()?;
    let protocols = sorted(protocols);
    let prepared: Vec<Prepared> = sequences
        .iter()
        .map(|d| prepare(d, None, &protocols, 1))
        .collect::<Result<_>>()?;
    check_distinct(&prepared)?;
    let mut specs = Vec::new();
    for seq in &prepared {
        for (pi, protocol) in protocols.iter().enumerate() {
            for (tracker, config) in runs.trackers.iter().zip(&configs) {
                for (k, start) in seq.starts[pi].iter().enumerate() {
                    specs.push(RunSpec {
                        dir: seq.dir.clone(),
                        sequence: seq.name.clone(),
                        protocol: protocol.name().to_owned(),
                        tracker: tracker.clone(),
                        name: config.name.clone(),
                        particles: runs.particles,
                        seed: runs.seed,
                        run: k,
                        start: start.frame,
                        frames: seq.frames,
                    });
                }
            }
        }
    }
    Ok(specs)
}

/// Tracks one run of a [`plan`]: the sequence read from its first frame, the tracker started on
/// the run's start frame from the run's box (found again from the ground truth), then updated to
/// the end, as `track eval otb` tracks each run.
///
/// # Errors
/// A bad tracker (exit 2), a sequence that cannot be read or changed since the plan (exit 3), a
/// tracker failure (exit 5).
pub fn run(spec: &RunSpec) -> Result<RunResult> {
    let protocol = spec.protocol()?;
    let runs = spec.runs();
    let config = runs.config(&spec.tracker)?;
    let truth = truth_of(&spec.dir, spec.frames)?;
    let start = run_starts(&truth, protocol)
        .get(spec.run)
        .copied()
        .filter(|s| s.frame == spec.start)
        .ok_or_else(|| {
            AppError::input(
                &spec.dir,
                format!(
                    "{} run {} does not start at frame {}: the ground truth changed since the \
                     plan",
                    protocol.title(),
                    spec.run,
                    spec.start + 1
                ),
            )
        })?;
    let tracker =
        trackers::build(config).map_err(|e| AppError::setting("--tracker", e.to_string()))?;
    let mut session = Session::new(tracker, None);
    let init = start.init.inscribed_ellipse();
    let mut source = open_sequence(&spec.dir.to_string_lossy())?.source;
    let mut read = 0;
    while let Some(frame) = source.next_frame()? {
        read += 1;
        if frame.index >= start.frame {
            session.push(&frame, &init, None)?;
        }
    }
    if read != spec.frames {
        return Err(AppError::input(
            &spec.dir,
            format!(
                "{read} frames read, {} expected: the folder changed during the evaluation",
                spec.frames
            ),
        ));
    }
    let output = session.finish();
    Ok(RunResult {
        boxes: output.records.iter().map(|r| r.bbox).collect(),
        p_lost: output.records.iter().map(p_lost_of).collect(),
        seconds: output.seconds,
    })
}

/// Scores a run's result against the truth; `None` when no labelled frame follows its start.
fn outcome(
    spec: &RunSpec,
    result: &RunResult,
    truth: &[Option<BoundingBox>],
) -> Result<Option<RunOutcome>> {
    let start = spec.start;
    if result.boxes.len() + start != truth.len() || result.p_lost.len() != result.boxes.len() {
        return Err(AppError::computation(
            format!("{} run {} of {}", spec.protocol, spec.run, spec.sequence),
            format!(
                "{} boxes and {} P(lost) from frame {} for a sequence of {} frames",
                result.boxes.len(),
                result.p_lost.len(),
                start + 1,
                truth.len()
            ),
        ));
    }
    score_tracked(&result.boxes, &result.p_lost, truth, start, result.seconds)
}

/// The tables of one protocol: `otb.md` and `otb.csv` as `track eval otb` writes them.
#[derive(Debug, Clone, PartialEq)]
pub struct ProtocolTables {
    /// The protocol.
    pub protocol: Protocol,
    /// `otb.md`.
    pub markdown: String,
    /// `otb.csv`.
    pub csv: String,
}

/// Scores the runs of a [`plan`] (each with its [`run`]'s result, in any order) and writes into
/// `out` what `track eval otb` writes there: per protocol `P/otb.md`, `P/otb.csv`, `P/plots/*.svg`
/// and every run's boxes `P/TRACKER/SEQ[.RUN].txt`, then `index.html` (headed by `command`).
/// `sequences`, `runs` and `protocols` are those given to [`plan`]; `results` must hold every
/// run of that plan.
///
/// # Errors
/// A run missing or given twice, or a result of the wrong length ([`AppError::Computation`]);
/// a ground truth that cannot be read (exit 3); an output that cannot be written (exit 4).
pub fn score(
    out: &Path,
    sequences: &[PathBuf],
    runs: &TrackerRuns,
    protocols: &[Protocol],
    results: &[(RunSpec, RunResult)],
    command: &str,
) -> Result<Vec<ProtocolTables>> {
    let configs = runs.configs()?;
    let names: Vec<&str> = configs.iter().map(|c| c.name.as_str()).collect();
    let protocols = sorted(protocols);
    // The one output guard of every command: the folder is checked against the sequences
    // (never one of them nor inside one), then locked, as `track eval otb` does.
    let _folder = OutputGuard::new(sequences).folder(out)?;
    // The sequences again, from their ground truth (the frames were checked by the plan).
    let mut prepared = Vec::new();
    for dir in sequences {
        let frames = results
            .iter()
            .find(|(s, _)| s.dir == *dir)
            .map(|(s, _)| s.frames)
            .ok_or_else(|| {
                AppError::computation("scoring", format!("no run of {}", dir.display()))
            })?;
        let truth = truth_of(dir, frames)?;
        let starts = protocols.iter().map(|&p| run_starts(&truth, p)).collect();
        prepared.push(Prepared {
            dir: dir.clone(),
            name: sequence_name(dir),
            clip: sequence_name(dir),
            transform: None,
            frames,
            truth,
            starts,
        });
    }
    check_distinct(&prepared)?;
    // scored[protocol] holds (sequence, tracker, outcomes), every run found by its spec.
    let mut scored: Vec<Vec<(usize, String, Vec<RunOutcome>)>> =
        protocols.iter().map(|_| Vec::new()).collect();
    for (si, seq) in prepared.iter().enumerate() {
        for (pi, &protocol) in protocols.iter().enumerate() {
            for &name in &names {
                let mut mine = Vec::new();
                for k in 0..seq.starts[pi].len() {
                    let found: Vec<&(RunSpec, RunResult)> = results
                        .iter()
                        .filter(|(s, _)| {
                            s.dir == seq.dir
                                && s.protocol == protocol.name()
                                && s.name == name
                                && s.run == k
                        })
                        .collect();
                    let [(spec, result)] = found.as_slice() else {
                        return Err(AppError::computation(
                            "scoring",
                            format!(
                                "{} results for {} run {k} of {name} on {}: one was expected",
                                found.len(),
                                protocol.title(),
                                seq.name
                            ),
                        ));
                    };
                    if let Some(o) = outcome(spec, result, &seq.truth)? {
                        let path = boxes_path(out, protocol, name, &seq.name, k);
                        write_atomic(&path, boxes_text(&o.boxes).as_bytes())?;
                        mine.push(o);
                    }
                }
                scored[pi].push((si, name.to_owned(), mine));
            }
        }
    }
    let sections = sections(&protocols, &names, &prepared, &scored)?;
    let tables = write_tables(out, &sections, &prepared, "")?
        .into_iter()
        .map(|(protocol, markdown, csv)| ProtocolTables {
            protocol,
            markdown,
            csv,
        })
        .collect();
    write_page(out, command, &sections)?;
    Ok(tables)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn protocols_parse_by_name_and_unknown_ones_are_refused() {
        assert_eq!(parse_protocol("tre").unwrap(), Protocol::Tre);
        assert_eq!(parse_protocol("SRE").unwrap(), Protocol::Sre);
        assert!(parse_protocol("xyz").is_err());
    }

    #[test]
    fn a_run_spec_crosses_json_unchanged() {
        let spec = RunSpec {
            dir: PathBuf::from("data/girl"),
            sequence: "girl".into(),
            protocol: "tre".into(),
            tracker: TrackerSpec::Preset("head".into()),
            name: "head".into(),
            particles: Some(120),
            seed: Some(3),
            run: 4,
            start: 200,
            frames: 500,
        };
        let text = serde_json::to_string(&spec).unwrap();
        assert_eq!(serde_json::from_str::<RunSpec>(&text).unwrap(), spec);
    }

    #[test]
    fn tracker_names_are_checked_as_track_eval_otb_checks_them() {
        let twice = TrackerRuns {
            trackers: vec![
                TrackerSpec::Preset("head".into()),
                TrackerSpec::Preset("head".into()),
            ],
            particles: None,
            seed: None,
        };
        assert!(twice.configs().is_err());
        let unknown = TrackerRuns {
            trackers: vec![TrackerSpec::Preset("nope".into())],
            particles: None,
            seed: None,
        };
        assert!(unknown.configs().is_err());
    }
}
