//! `track eval otb`: every run of every protocol, tracker and sequence, spread over the cores
//! with rayon, then the tables, plots, boxes and index page of each protocol.
//!
//! Every run is independent (its own tracker, seeded with the same seed), and the results are
//! gathered in a fixed order, so they do not depend on the number of threads.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use trackers::TrackerConfig;
use vision_core::BoundingBox;

use super::{
    Protocol, RunStart, SequenceScore, boxes_text, ceiling_sentence, csv, in_start_convention,
    markdown, mean_over_runs, read_boxes, run_starts, sequence_name, set_means,
};
use crate::groundtruth::{check_groundtruth_len, first_box_in_frame, load_groundtruth};
use crate::metrics::{SequenceMetrics, mean_metrics, score_run, with_self_evaluation};
use crate::output::{OutputGuard, write_atomic};
use crate::progress::progress_of;
use crate::sequence::{Frame, FrameSource, open_sequence, read_every};
use crate::session::Session;
use crate::{AppError, Result};

/// Where P(lost) sits in a record's `alpha_probs` (locked, partially occluded, lost).
const LOST_INDEX: usize = 2;

/// A sequence checked before any tracking.
pub(crate) struct Prepared {
    pub(crate) dir: PathBuf,
    pub(crate) name: String,
    /// The clip's folder name, and its transform in a stress suite ([`super::suite`]).
    pub(crate) clip: String,
    pub(crate) transform: Option<String>,
    /// The sequence's frames, all of them.
    pub(crate) frames: usize,
    /// The ground truth of the frames kept (every `--frame-step`-th).
    pub(crate) truth: Vec<Option<BoundingBox>>,
    /// The runs of each protocol asked for, in the order of `protocols`.
    pub(crate) starts: Vec<Vec<RunStart>>,
}

/// One run's outcome.
pub(crate) struct RunOutcome {
    /// The box on every frame of the sequence (`None` before the start).
    pub(crate) boxes: Vec<Option<BoundingBox>>,
    pub(crate) metrics: SequenceMetrics,
    pub(crate) seconds: Option<f64>,
}

/// One protocol's rows, each tracker's means, charts and SRE ceiling.
pub(crate) type Section = (
    Protocol,
    Vec<SequenceScore>,
    Vec<SequenceScore>,
    Vec<super::plots::Chart>,
    Option<f64>,
);

/// A name used as a folder of box files: letters, digits, `-`, `_`, `.` and `+`, not `.`, `..`
/// or `plots`.
fn check_name(name: &str, what: &str) -> Result<()> {
    let ok = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | '.' | '+'))
        && name != "."
        && name != ".."
        && name != "plots";
    if ok {
        Ok(())
    } else {
        Err(AppError::setting(
            what,
            format!(
                "{name:?} cannot name a folder of box files: use letters, digits, -, _, . or + \
                 (and not `plots`)"
            ),
        ))
    }
}

/// Checks the trackers' names in order ([`check_name`], none given twice) and returns them.
pub(crate) fn check_names<'a>(all: impl IntoIterator<Item = &'a str>) -> Result<Vec<&'a str>> {
    let mut names: Vec<&str> = Vec::new();
    for name in all {
        check_name(name, "--tracker")?;
        if names.contains(&name) {
            return Err(AppError::setting(
                "--tracker",
                format!("{name} is given twice (trackers and --results names must differ)"),
            ));
        }
        names.push(name);
    }
    Ok(names)
}

/// Parses the `--results NAME=DIR` values.
fn parse_results(values: &[String]) -> Result<Vec<(String, PathBuf)>> {
    values
        .iter()
        .map(|v| {
            let (name, dir) = v.split_once('=').ok_or_else(|| {
                AppError::setting("--results", format!("{v:?} should be NAME=DIR"))
            })?;
            check_name(name, "--results")?;
            if dir.is_empty() {
                return Err(AppError::setting("--results", format!("{v:?} has no DIR")));
            }
            Ok((name.to_owned(), PathBuf::from(dir)))
        })
        .collect()
}

/// Reads a sequence's ground truth and frame count, checks its first box against the frame, keeps
/// every `step`-th frame's line from the first, and lays out the runs of each protocol on those.
pub(crate) fn prepare(
    dir: &Path,
    transform: Option<&str>,
    protocols: &[Protocol],
    step: usize,
) -> Result<Prepared> {
    let (sequence, gt_path) = super::open_otb(dir)?;
    let info = sequence.source.validate_all()?;
    let truth = load_groundtruth(&gt_path)?;
    check_groundtruth_len(&truth, info.frames, &gt_path)?;
    // The frames `--frame-step` leaves out count as unlabelled, so that the box checked is the
    // first one kept, named by its line in the file.
    let kept: Vec<Option<BoundingBox>> = truth
        .iter()
        .enumerate()
        .map(|(i, b)| b.filter(|_| i % step == 0))
        .collect();
    if kept.iter().all(Option::is_none) {
        return Err(AppError::input(
            &gt_path,
            format!(
                "no labelled box on the frames --frame-step {step} keeps (1, {}, …)",
                step + 1
            ),
        ));
    }
    first_box_in_frame(&kept, &gt_path, &sequence.name, info.width, info.height)?;
    let truth: Vec<Option<BoundingBox>> = kept.into_iter().step_by(step).collect();
    let starts: Vec<Vec<RunStart>> = protocols.iter().map(|&p| run_starts(&truth, p)).collect();
    for (p, runs) in protocols.iter().zip(&starts) {
        let scorable = runs
            .iter()
            .any(|r| truth[r.frame + 1..].iter().any(Option::is_some));
        if !scorable {
            return Err(AppError::input(
                &gt_path,
                format!(
                    "no labelled frame after the start frame of any {} run of sequence {}: \
                     nothing to score (the start frame is given, not tracked)",
                    p.title(),
                    sequence.name
                ),
            ));
        }
    }
    Ok(Prepared {
        dir: dir.to_path_buf(),
        name: super::suite::display_name(transform, &sequence_name(dir)),
        clip: sequence_name(dir),
        transform: transform.map(str::to_owned),
        frames: info.frames,
        truth,
        starts,
    })
}

/// Two sequences of one name would write the same box files.
pub(crate) fn check_distinct(prepared: &[Prepared]) -> Result<()> {
    for (i, p) in prepared.iter().enumerate() {
        if prepared[..i].iter().any(|q| q.name == p.name) {
            return Err(AppError::setting(
                "SEQUENCES",
                format!(
                    "two sequences are named {} ({}): their box files would collide",
                    p.name,
                    p.dir.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Tracks one run: `config` started at `start` on `frames` (the whole sequence).
fn track_run(
    frames: &[Frame],
    truth: &[Option<BoundingBox>],
    config: &TrackerConfig,
    start: &RunStart,
) -> Result<Option<RunOutcome>> {
    let tracker = trackers::build(config.clone())
        .map_err(|e| AppError::setting("--tracker", e.to_string()))?;
    let mut session = Session::new(tracker, None);
    let init = start.init.inscribed_ellipse();
    for frame in &frames[start.frame..] {
        session.push(frame, &init, None)?;
    }
    let output = session.finish();
    let tracked: Vec<BoundingBox> = output.records.iter().map(|r| r.bbox).collect();
    let p_lost: Vec<Option<f64>> = output.records.iter().map(p_lost_of).collect();
    score_tracked(&tracked, &p_lost, truth, start.frame, output.seconds)
}

/// P(lost) of a record: its `alpha_probs` entry for the lost status, `None` without one.
pub(crate) fn p_lost_of(record: &crate::record::FrameRecord) -> Option<f64> {
    record.alpha_probs.get(LOST_INDEX).copied()
}

/// Scores a run tracked from frame `start`: `tracked` and `p_lost` hold the box and P(lost) of
/// every tracked frame, the start frame first, and `seconds` the tracking time. `None` when no
/// labelled frame follows the start.
pub(crate) fn score_tracked(
    tracked: &[BoundingBox],
    p_lost: &[Option<f64>],
    truth: &[Option<BoundingBox>],
    start: usize,
    seconds: f64,
) -> Result<Option<RunOutcome>> {
    let boxes: Vec<Option<BoundingBox>> = std::iter::repeat_n(None, start)
        .chain(tracked.iter().copied().map(Some))
        .collect();
    let seconds = seconds.max(1e-9);
    let Some(metrics) = score_run(&boxes, truth, start, Some(seconds))? else {
        return Ok(None);
    };
    // The self-evaluation over the scored frames (those after the start).
    let metrics = with_self_evaluation(
        metrics,
        &tracked[1.min(tracked.len())..],
        &truth[start + 1..],
        &p_lost[1.min(p_lost.len())..],
    );
    Ok(Some(RunOutcome {
        boxes,
        metrics,
        seconds: Some(seconds),
    }))
}

/// The success AUC of the truth in each run's start convention ([`in_start_convention`]),
/// averaged as the tables average a tracker's runs ([`mean_metrics`]: over each sequence's runs,
/// then over sequences); `None` without a scored run.
pub(crate) fn convention_ceiling(prepared: &[Prepared], pi: usize) -> Result<Option<f64>> {
    let mut sequences = Vec::new();
    for seq in prepared {
        let mut runs = Vec::new();
        for start in &seq.starts[pi] {
            let boxes = in_start_convention(&seq.truth, start);
            runs.extend(score_run(&boxes, &seq.truth, start.frame, None)?);
        }
        sequences.extend(mean_metrics(&runs));
    }
    Ok(mean_metrics(&sequences).map(|m| m.success_auc))
}

/// What `track eval otb` evaluates: its command line with the trackers' configurations built
/// (the command builds them, so that this module knows nothing of the command line).
#[derive(Debug)]
pub struct Evaluation<'a> {
    /// OTB folders.
    pub sequences: &'a [PathBuf],
    /// The tracker runs, presets first, then configuration files.
    pub configs: Vec<TrackerConfig>,
    /// The configuration files read (inputs, which no output may touch).
    pub config_files: &'a [PathBuf],
    /// The protocols asked for (in any order, repeats allowed).
    pub protocols: &'a [Protocol],
    /// Other trackers' boxes, `NAME=DIR`.
    pub results: &'a [String],
    /// Track and score every K-th frame.
    pub frame_step: u32,
    /// The output folder.
    pub out: &'a Path,
    /// No progress bar.
    pub quiet: bool,
}

/// Runs `track eval otb`.
///
/// # Errors
/// See [`AppError`]: bad settings (exit 2), a bad sequence, ground truth or `--results` file
/// (exit 3, naming it), an output that cannot be written (exit 4).
pub fn run(evaluation: Evaluation<'_>) -> Result<()> {
    let Evaluation {
        sequences,
        configs,
        config_files,
        protocols,
        results,
        frame_step,
        out,
        quiet,
    } = evaluation;
    // First of all, so that a signal at any point ends the evaluation cleanly.
    let signals = crate::signals::StopSignals::install()?;
    let step = frame_step as usize;
    let results = parse_results(results)?;
    let mut protocols = protocols.to_vec();
    protocols.sort();
    protocols.dedup();
    let names = check_names(
        configs
            .iter()
            .map(|c| c.name.as_str())
            .chain(results.iter().map(|r| r.0.as_str())),
    )?;
    let mut inputs: Vec<&Path> = sequences.iter().map(PathBuf::as_path).collect();
    inputs.extend(results.iter().map(|r| r.1.as_path()));
    inputs.extend(config_files.iter().map(PathBuf::as_path));
    // Results are written after every run: an output folder that cannot be made, or is in use,
    // is found before that.
    let folder = OutputGuard::new(inputs).folder(out)?;
    // The tables and the page, checked now rather than after every run.
    for p in &protocols {
        for name in ["otb.md", "otb.csv"] {
            folder.check_free(&Path::new(p.name()).join(name), None)?;
        }
    }
    folder.check_free(Path::new("index.html"), None)?;
    // A stress suite stands for every clip under every transform.
    let prepared: Vec<Prepared> = super::suite::expand(sequences)?
        .iter()
        .map(|e| prepare(&e.dir, e.transform.as_deref(), &protocols, step))
        .collect::<Result<_>>()?;
    check_distinct(&prepared)?;
    // Other trackers' boxes, read and scored before any tracking, so that a missing file is
    // found at once. rows[protocol] holds (sequence, tracker, runs' outcomes) in a fixed order.
    let mut scored: Vec<Vec<(usize, String, Vec<RunOutcome>)>> =
        protocols.iter().map(|_| Vec::new()).collect();
    for (si, seq) in prepared.iter().enumerate() {
        for (pi, &protocol) in protocols.iter().enumerate() {
            for (name, dir) in &results {
                let mut outcomes = Vec::new();
                for (k, start) in seq.starts[pi].iter().enumerate() {
                    let path = super::suite::boxes_path_in(
                        dir,
                        seq.transform.as_deref(),
                        protocol,
                        name,
                        &seq.clip,
                        k,
                    );
                    let boxes = read_boxes(&path, seq.truth.len())?;
                    if let Some(metrics) = score_run(&boxes, &seq.truth, start.frame, None)? {
                        outcomes.push(RunOutcome {
                            boxes: Vec::new(),
                            metrics,
                            seconds: None,
                        });
                    }
                }
                scored[pi].push((si, name.clone(), outcomes));
            }
        }
    }
    let total: usize = prepared
        .iter()
        .map(|s| s.starts.iter().map(Vec::len).sum::<usize>() * configs.len())
        .sum();
    signals.stop_if_received()?;
    let bar = progress_of(total as u64, quiet, "OTB", "runs");
    // Runs finished, for the tables' note when a signal stops the evaluation.
    let mut finished = 0;
    for (si, seq) in prepared.iter().enumerate() {
        if signals.received().is_some() {
            break;
        }
        bar.set_message(format!("OTB ({})", seq.name));
        let mut source = open_sequence(&seq.dir.to_string_lossy())?.source;
        let (frames, read) = read_every(&mut source, step)?;
        if read != seq.frames {
            return Err(AppError::input(
                &seq.dir,
                format!(
                    "{read} frames read, {} expected: the folder changed during the evaluation",
                    seq.frames
                ),
            ));
        }
        let jobs: Vec<(usize, usize, usize)> = (0..protocols.len())
            .flat_map(|pi| {
                (0..configs.len())
                    .flat_map(move |ci| (0..seq.starts[pi].len()).map(move |k| (pi, ci, k)))
            })
            .collect();
        // A run not started because a signal came is `None`; the runs in progress finish.
        let outcomes: Vec<Option<Option<RunOutcome>>> = jobs
            .par_iter()
            .map(|&(pi, ci, k)| {
                if signals.received().is_some() {
                    return Ok(None);
                }
                let r = track_run(&frames, &seq.truth, &configs[ci], &seq.starts[pi][k]);
                bar.inc(1);
                r.map(Some)
            })
            .collect::<Result<_>>()?;
        finished += outcomes.iter().filter(|o| o.is_some()).count();
        drop(frames);
        let mut outcomes = outcomes.into_iter();
        for (pi, &protocol) in protocols.iter().enumerate() {
            for config in &configs {
                let mut mine = Vec::new();
                for k in 0..seq.starts[pi].len() {
                    if let Some(Some(Some(o))) = outcomes.next() {
                        let path = super::suite::boxes_path_in(
                            out,
                            seq.transform.as_deref(),
                            protocol,
                            &config.name,
                            &seq.clip,
                            k,
                        );
                        write_atomic(&path, boxes_text(&o.boxes).as_bytes())?;
                        mine.push(o);
                    }
                }
                scored[pi].push((si, config.name.clone(), mine));
            }
        }
    }
    bar.finish_and_clear();
    let interrupted = signals.received().filter(|_| finished < total);
    let sections = sections(&protocols, &names, &prepared, &scored)?;
    // The notes above each table, the frame step's first.
    let mut head = String::new();
    if step > 1 {
        head.push_str(&format!(
            "One frame in {step} of each sequence, from its first (`--frame-step {step}`): \
             the footage at 1/{step} of its frame rate.\n\n"
        ));
    }
    if let Some((signal, _)) = interrupted {
        head.push_str(&format!(
            "**Interrupted by {signal}**: {finished} of {total} tracker runs finished; these \
             tables hold those runs only (each row's `runs` column says how many).\n\n"
        ));
    }
    let mut printed = String::new();
    for (protocol, md, _) in write_tables(out, &sections, &prepared, &head)? {
        printed.push_str(&format!("## {}\n\n{md}\n", protocol.title()));
    }
    let mut command = std::env::args().collect::<Vec<_>>().join(" ");
    if let Some((signal, _)) = interrupted {
        command.push_str(&format!(
            " — interrupted by {signal}: {finished} of {total} runs finished"
        ));
    }
    write_page(out, &command, &sections)?;
    crate::output::print_stdout(&printed)?;
    match interrupted {
        Some((signal, number)) => Err(AppError::InterruptedRuns {
            signal,
            number,
            runs: finished,
            total,
            out: out.to_path_buf(),
        }),
        None => Ok(()),
    }
}

/// Each protocol's rows, means, charts and SRE ceiling, from `scored[protocol]` (sequence,
/// tracker, runs' outcomes). Rows in a fixed order: trackers (in the order of `names`), then
/// sequences.
pub(crate) fn sections(
    protocols: &[Protocol],
    names: &[&str],
    prepared: &[Prepared],
    scored: &[Vec<(usize, String, Vec<RunOutcome>)>],
) -> Result<Vec<Section>> {
    let mut sections = Vec::new();
    for (pi, &protocol) in protocols.iter().enumerate() {
        let mut rows = Vec::new();
        for name in names {
            for (si, seq) in prepared.iter().enumerate() {
                let Some((_, _, outcomes)) = scored[pi]
                    .iter()
                    .find(|(s, n, _)| *s == si && n.as_str() == *name)
                else {
                    continue;
                };
                let runs: Vec<(SequenceMetrics, Option<f64>)> = outcomes
                    .iter()
                    .map(|o| (o.metrics.clone(), o.seconds))
                    .collect();
                if let Some(metrics) = mean_over_runs(&runs) {
                    rows.push(SequenceScore {
                        sequence: seq.name.clone(),
                        tracker: (*name).to_owned(),
                        runs: runs.len(),
                        metrics,
                    });
                }
            }
        }
        let means = set_means(&rows);
        let charts = super::plots::protocol_charts(protocol, &rows, &means)?;
        let ceiling = if protocol == Protocol::Sre {
            convention_ceiling(prepared, pi)?
        } else {
            None
        };
        sections.push((protocol, rows, means, charts, ceiling));
    }
    Ok(sections)
}

/// Writes each protocol's `otb.md` (with `head` above it), `otb.csv` and plots into `out`, and
/// under a stress suite its `suite.md` and `suite.csv`; returns each protocol's markdown and csv.
pub(crate) fn write_tables(
    out: &Path,
    sections: &[Section],
    prepared: &[Prepared],
    head: &str,
) -> Result<Vec<(Protocol, String, String)>> {
    let groups: Vec<(String, String)> = prepared
        .iter()
        .map(|p| {
            let g = p.transform.as_deref().unwrap_or(super::suite::AS_SHOT);
            (p.name.clone(), g.to_owned())
        })
        .collect();
    let mut tables = Vec::new();
    for (protocol, rows, _, charts, ceiling) in sections {
        let dir = out.join(protocol.name());
        let mut md = markdown(*protocol, rows);
        // Under a stress suite: the mean per transform before the per-clip tables.
        if let Some(means) = super::suite::column_means(rows, &groups) {
            let table = super::suite::markdown(*protocol, &means);
            write_atomic(&dir.join("suite.md"), table.as_bytes())?;
            write_atomic(
                &dir.join("suite.csv"),
                super::suite::csv(*protocol, &means).as_bytes(),
            )?;
            md = format!("{table}\n{md}");
        }
        if let Some(c) = ceiling {
            md.push_str(&format!("\n{}\n", ceiling_sentence(*c)));
        }
        let md = format!("{head}{md}");
        let table = csv(*protocol, rows);
        write_atomic(&dir.join("otb.md"), md.as_bytes())?;
        write_atomic(&dir.join("otb.csv"), table.as_bytes())?;
        for c in charts {
            write_atomic(&dir.join("plots").join(&c.file), c.svg.as_bytes())?;
        }
        tables.push((*protocol, md, table));
    }
    Ok(tables)
}

/// Writes `index.html`, headed by `command`.
pub(crate) fn write_page(out: &Path, command: &str, sections: &[Section]) -> Result<()> {
    let page_sections: Vec<super::page::ProtocolSection<'_>> = sections
        .iter()
        .map(
            |(protocol, rows, means, charts, ceiling)| super::page::ProtocolSection {
                protocol: *protocol,
                rows,
                means,
                charts,
                ceiling: *ceiling,
            },
        )
        .collect();
    write_atomic(
        &out.join("index.html"),
        super::page::render(command, &page_sections).as_bytes(),
    )
}
