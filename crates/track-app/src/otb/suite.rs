//! Stress suites in `track eval otb`: a folder written by `cargo xtask stress` holds one folder
//! per transform, each holding one OTB folder per clip (recognised by its `stress.json`), and
//! usually a `suite.json`. Given such a folder, `track eval otb` evaluates every clip under
//! every transform, named `<transform>/<clip>`, and prints, beside the per-clip tables, one
//! mean per transform and the mean over transforms. OTB folders given beside a suite are the
//! footage as shot, in their own column.
//!
//! Box files of a clip under a transform live below the transform's name:
//! `DIR/<transform>/<protocol>/<tracker>/<clip>[.<run>].txt`, as `opencv_peers.py
//! SUITE/<transform> --out DIR/<transform>` writes them; those of the footage as shot at
//! `DIR/<protocol>/<tracker>/<clip>[.<run>].txt`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::{Protocol, SequenceScore, boxes_path};
use crate::{AppError, Result};

/// The record `cargo xtask stress` writes in every clip folder of a suite.
pub const CLIP_RECORD: &str = "stress.json";
/// The record `cargo xtask stress` writes at the top of a suite.
pub const SUITE_RECORD: &str = "suite.json";
/// The column of the footage as shot, beside a suite's transforms.
pub const AS_SHOT: &str = "as shot";

/// A sequence to evaluate: its folder and, in a suite, its transform.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Entry {
    /// The OTB folder.
    pub dir: PathBuf,
    /// The transform's name when the folder is a clip of a suite.
    pub transform: Option<String>,
}

/// The sorted subfolders of `dir`, hidden ones (a generator's temporary folders) left out.
fn subfolders(dir: &Path) -> Result<Vec<PathBuf>> {
    let read = std::fs::read_dir(dir)
        .map_err(|e| AppError::input(dir, format!("cannot list the folder: {e}")))?;
    let mut out = Vec::new();
    for e in read {
        let e = e.map_err(|e| AppError::input(dir, format!("cannot list the folder: {e}")))?;
        let p = e.path();
        let hidden = e.file_name().to_string_lossy().starts_with('.');
        if p.is_dir() && !hidden {
            out.push(p);
        }
    }
    out.sort();
    Ok(out)
}

/// Whether `dir` is a suite: it holds `suite.json`, or a folder holding a clip folder with
/// `stress.json`.
pub fn is_suite(dir: &Path) -> bool {
    if dir.join(SUITE_RECORD).is_file() {
        return true;
    }
    dir.is_dir()
        && !dir.join("groundtruth_rect.txt").exists()
        && subfolders(dir).is_ok_and(|ts| {
            ts.iter().any(|t| {
                subfolders(t).is_ok_and(|cs| cs.iter().any(|c| c.join(CLIP_RECORD).is_file()))
            })
        })
}

/// The sequences of the `SEQUENCES` arguments: a suite becomes every clip under every
/// transform (transforms and clips in name order), any other folder stays as given.
///
/// # Errors
/// [`AppError::BadInput`] (exit 3) naming a suite that cannot be listed, or a transform folder
/// holding no clip.
pub fn expand(inputs: &[PathBuf]) -> Result<Vec<Entry>> {
    let mut out = Vec::new();
    for dir in inputs {
        if !is_suite(dir) {
            out.push(Entry {
                dir: dir.clone(),
                transform: None,
            });
            continue;
        }
        for t in subfolders(dir)? {
            let name = t
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let clips: Vec<PathBuf> = subfolders(&t)?
                .into_iter()
                .filter(|c| c.join(CLIP_RECORD).is_file())
                .collect();
            if clips.is_empty() {
                return Err(AppError::input(
                    &t,
                    format!(
                        "a folder of the stress suite {} holds no clip (no */{CLIP_RECORD})",
                        dir.display()
                    ),
                ));
            }
            out.extend(clips.into_iter().map(|c| Entry {
                dir: c,
                transform: Some(name.clone()),
            }));
        }
    }
    Ok(out)
}

/// The name of an entry in the tables: `<transform>/<clip>`, or the clip's alone.
pub fn display_name(transform: Option<&str>, clip: &str) -> String {
    transform.map_or_else(|| clip.to_owned(), |t| format!("{t}/{clip}"))
}

/// The box file of run `run` of `tracker` on `clip` under `transform` (see the module
/// documentation).
pub fn boxes_path_in(
    dir: &Path,
    transform: Option<&str>,
    protocol: Protocol,
    tracker: &str,
    clip: &str,
    run: usize,
) -> PathBuf {
    let base = transform.map_or_else(|| dir.to_path_buf(), |t| dir.join(t));
    boxes_path(&base, protocol, tracker, clip, run)
}

/// One tracker's mean success AUC and precision@20 px over the clips of each column.
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnMeans {
    /// The tracker.
    pub tracker: String,
    /// (column, mean success AUC, mean precision@20 px, clips), in the columns' order.
    pub columns: Vec<(String, f64, f64, usize)>,
    /// The mean over the transforms' columns (the footage as shot left out).
    pub over_transforms: Option<(f64, f64)>,
}

/// Each tracker's means per column, when some sequence is a clip of a suite: `groups` gives
/// each sequence's column (its transform, or [`AS_SHOT`]). Columns: the footage as shot first,
/// then the transforms in the order of their first sequence. `None` without a suite.
pub fn column_means(
    rows: &[SequenceScore],
    groups: &[(String, String)],
) -> Option<Vec<ColumnMeans>> {
    if groups.iter().all(|(_, g)| g == AS_SHOT) {
        return None;
    }
    let mut columns: Vec<&str> = Vec::new();
    if groups.iter().any(|(_, g)| g == AS_SHOT) {
        columns.push(AS_SHOT);
    }
    for (_, g) in groups {
        if !columns.contains(&g.as_str()) {
            columns.push(g);
        }
    }
    let group_of = |seq: &str| {
        groups
            .iter()
            .find(|(s, _)| s == seq)
            .map(|(_, g)| g.as_str())
    };
    let mut trackers: Vec<&str> = Vec::new();
    for r in rows {
        if !trackers.contains(&r.tracker.as_str()) {
            trackers.push(&r.tracker);
        }
    }
    Some(
        trackers
            .into_iter()
            .map(|tracker| {
                let cols: Vec<(String, f64, f64, usize)> = columns
                    .iter()
                    .filter_map(|&c| {
                        let mine: Vec<&SequenceScore> = rows
                            .iter()
                            .filter(|r| r.tracker == tracker && group_of(&r.sequence) == Some(c))
                            .collect();
                        let n = mine.len();
                        (n > 0).then(|| {
                            let auc = mine.iter().map(|r| r.metrics.success_auc).sum::<f64>();
                            let p20 = mine.iter().map(|r| r.metrics.precision_20).sum::<f64>();
                            (c.to_owned(), auc / n as f64, p20 / n as f64, n)
                        })
                    })
                    .collect();
                let transforms: Vec<&(String, f64, f64, usize)> =
                    cols.iter().filter(|c| c.0 != AS_SHOT).collect();
                let over_transforms = (!transforms.is_empty()).then(|| {
                    let n = transforms.len() as f64;
                    (
                        transforms.iter().map(|c| c.1).sum::<f64>() / n,
                        transforms.iter().map(|c| c.2).sum::<f64>() / n,
                    )
                });
                ColumnMeans {
                    tracker: tracker.to_owned(),
                    columns: cols,
                    over_transforms,
                }
            })
            .collect(),
    )
}

/// `suite.md` of one protocol: success AUC per transform (each the mean over its clips), the
/// mean over transforms, and the footage as shot when given.
pub fn markdown(protocol: Protocol, means: &[ColumnMeans]) -> String {
    let columns: Vec<&str> = means
        .first()
        .map(|m| m.columns.iter().map(|c| c.0.as_str()).collect())
        .unwrap_or_default();
    let mut s = format!(
        "Under stress ({}): success AUC, the mean over each transform's clips (each clip's figure \
         the mean over its runs); the last columns are the mean over transforms{}.\n\n\
         | tracker | {} | mean over transforms | its P20 |\n|---|{}---|---|\n",
        protocol.title(),
        if columns.contains(&AS_SHOT) {
            ", the footage as shot left out"
        } else {
            ""
        },
        columns.join(" | "),
        "---|".repeat(columns.len())
    );
    for m in means {
        let cells: Vec<String> = columns
            .iter()
            .map(|c| {
                m.columns
                    .iter()
                    .find(|x| x.0 == *c)
                    .map_or_else(|| "—".to_owned(), |x| format!("{:.3}", x.1))
            })
            .collect();
        let (auc, p20) = m.over_transforms.map_or_else(
            || ("—".to_owned(), "—".to_owned()),
            |(a, p)| (format!("**{a:.3}**"), format!("{p:.3}")),
        );
        let _ = writeln!(
            s,
            "| {} | {} | {auc} | {p20} |",
            m.tracker,
            cells.join(" | ")
        );
    }
    s
}

/// `suite.csv` of one protocol: one line per tracker and column, then each tracker's mean over
/// transforms (column `mean`).
pub fn csv(protocol: Protocol, means: &[ColumnMeans]) -> String {
    let mut s = String::from("protocol,column,tracker,clips,success_auc,precision_20\n");
    for m in means {
        for (c, auc, p20, n) in &m.columns {
            let _ = writeln!(
                s,
                "{},{c},{},{n},{auc:.4},{p20:.4}",
                protocol.name(),
                m.tracker
            );
        }
        if let Some((auc, p20)) = m.over_transforms {
            let n: usize = m
                .columns
                .iter()
                .filter(|c| c.0 != AS_SHOT)
                .map(|c| c.3)
                .sum();
            let _ = writeln!(
                s,
                "{},mean,{},{n},{auc:.4},{p20:.4}",
                protocol.name(),
                m.tracker
            );
        }
    }
    s
}
