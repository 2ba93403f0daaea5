//! `track eval paired`: whether a variant of a tracker helps or hurts each sequence, judged over
//! seeds. Each seed's run of the variant is paired with the same seed's run of the base (the
//! `otb.csv` files `track eval otb` writes), and a sequence counts as helped (hurt) when the mean
//! of the paired differences of its success AUC is positive (negative) by a one-sided t-test at
//! the given level. Pairing removes what the seeds share; the test asks for a difference larger
//! than the sequence's own seed-to-seed noise, so a small gain repeated on every seed counts and
//! one lucky seed on a volatile sequence does not (the rule of docs/DECISIONS.md).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use statrs::distribution::{ContinuousCDF, StudentsT};

use super::Protocol;
use crate::{AppError, Result};

/// The success AUC of each sequence (and the set's mean, sequence `mean`) of one tracker in one
/// `otb.csv`, in the file's order.
#[derive(Debug, Clone, PartialEq)]
pub struct AucTable {
    /// `(sequence, success AUC)`, the set's mean excluded.
    pub sequences: Vec<(String, f64)>,
    /// The set's mean success AUC.
    pub mean: f64,
    /// `(sequence, frames scored)`, from the `frames` column (empty for a file without it).
    pub frames: Vec<(String, usize)>,
    /// The file read.
    pub path: PathBuf,
}

/// Reads the success AUC of `tracker` (or of the file's only tracker) from `path`, an
/// `otb.csv` written by `track eval otb`.
///
/// # Errors
/// An unreadable file, a line that is not an `otb.csv` line, no rows of the tracker, several
/// trackers and none named, or a success AUC that is not a finite number.
pub fn read_auc(path: &Path, tracker: Option<&str>) -> Result<AucTable> {
    let bad = |reason: String| AppError::BadInput {
        path: path.to_owned(),
        reason,
    };
    let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let column = |name: &str| {
        header.iter().position(|h| *h == name).ok_or_else(|| {
            bad(format!(
                "no `{name}` column: not an otb.csv of `track eval otb`"
            ))
        })
    };
    let (seq, trk, auc) = (
        column("sequence")?,
        column("tracker")?,
        column("success_auc")?,
    );
    let frames_column = header.iter().position(|h| *h == "frames");
    let mut rows: Vec<(String, String, f64, Option<usize>)> = Vec::new();
    for (k, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let fields: Vec<&str> = line.split(',').collect();
        if fields.len() != header.len() {
            return Err(bad(format!(
                "line {} has {} fields, the header {}",
                k + 2,
                fields.len(),
                header.len()
            )));
        }
        let value: f64 = fields[auc]
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| bad(format!("line {}: success AUC `{}`", k + 2, fields[auc])))?;
        let frames = match frames_column {
            Some(c) => Some(
                fields[c]
                    .parse::<usize>()
                    .map_err(|_| bad(format!("line {}: frames `{}`", k + 2, fields[c])))?,
            ),
            None => None,
        };
        rows.push((
            fields[seq].to_owned(),
            fields[trk].to_owned(),
            value,
            frames,
        ));
    }
    let name = match tracker {
        Some(t) => t.to_owned(),
        None => {
            let mut names: Vec<&str> = rows.iter().map(|r| r.1.as_str()).collect();
            names.sort_unstable();
            names.dedup();
            match names.as_slice() {
                [one] => (*one).to_owned(),
                [] => return Err(bad("no rows".into())),
                many => {
                    return Err(bad(format!(
                        "several trackers ({}); name one with --tracker",
                        many.join(", ")
                    )));
                }
            }
        }
    };
    let mut table = AucTable {
        sequences: Vec::new(),
        mean: f64::NAN,
        frames: Vec::new(),
        path: path.to_owned(),
    };
    for (s, _, v, frames) in rows.into_iter().filter(|r| r.1 == name) {
        if s == "mean" {
            table.mean = v;
        } else {
            if let Some(f) = frames {
                table.frames.push((s.clone(), f));
            }
            table.sequences.push((s, v));
        }
    }
    if table.sequences.is_empty() || !table.mean.is_finite() {
        return Err(bad(format!("no rows of tracker `{name}`")));
    }
    Ok(table)
}

/// What the paired test says of one sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// The variant is better beyond the seeds' noise.
    Helps,
    /// The variant is worse beyond the seeds' noise.
    Hurts,
    /// Neither.
    Neither,
    /// The paired differences are all the same non-zero number: with no seed-to-seed variation
    /// the t-test has nothing to judge the difference against (the runs do not depend on the
    /// seed, or the same results were given twice).
    Untestable,
}

/// One sequence's paired comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct SequenceComparison {
    /// The sequence.
    pub sequence: String,
    /// Its success AUC, base and variant, each the mean over the seeds.
    pub base: f64,
    /// See `base`.
    pub variant: f64,
    /// The mean paired difference, variant − base.
    pub difference: f64,
    /// t = mean / (standard deviation / √n) of the differences (NaN when every difference is
    /// the same non-zero number: [`Verdict::Untestable`]; 0 when all are 0).
    pub t: f64,
    /// The verdict at the level asked for.
    pub verdict: Verdict,
}

/// One protocol's comparison over all sequences.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// The pairs (seeds) compared.
    pub pairs: usize,
    /// The one-sided critical value of t at the level asked for, n − 1 degrees of freedom.
    pub critical_t: f64,
    /// Each sequence, in the base's first file's order.
    pub sequences: Vec<SequenceComparison>,
    /// The set's mean success AUC, base and variant, each the mean over the seeds.
    pub base_mean: f64,
    /// See `base_mean`.
    pub variant_mean: f64,
}

impl Comparison {
    /// How many sequences the variant helps and hurts.
    pub fn counts(&self) -> (usize, usize) {
        let count = |v: Verdict| self.sequences.iter().filter(|s| s.verdict == v).count();
        (count(Verdict::Helps), count(Verdict::Hurts))
    }
}

/// The one-sided critical value of Student's t with `dof` degrees of freedom at `level`.
fn critical_t(dof: usize, level: f64) -> Result<f64> {
    let t = StudentsT::new(0.0, 1.0, dof as f64).map_err(|e| AppError::InvalidSetting {
        name: "--base and --variant".into(),
        reason: format!("Student's t with {dof} degrees of freedom: {e}"),
    })?;
    Ok(t.inverse_cdf(1.0 - level))
}

/// The standard deviation (and mean) of paired differences in success AUC below which they count
/// as not varying (as zero): far below the four decimals of `otb.csv`, far above rounding.
const NO_SPREAD: f64 = 1e-9;

/// The verdict on paired `differences` against the critical value, and t.
pub fn verdict(differences: &[f64], critical: f64) -> (Verdict, f64) {
    let n = differences.len() as f64;
    let mean = differences.iter().sum::<f64>() / n;
    let var = differences.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0);
    // AUCs are read with four decimals: a spread below a billionth is rounding, not seed noise.
    let t = if var.sqrt() > NO_SPREAD {
        mean / (var / n).sqrt()
    } else if mean.abs() <= NO_SPREAD {
        0.0
    } else {
        return (Verdict::Untestable, f64::NAN);
    };
    let v = if t > critical {
        Verdict::Helps
    } else if t < -critical {
        Verdict::Hurts
    } else {
        Verdict::Neither
    };
    (v, t)
}

/// Pairs `base[i]` with `variant[i]` (the same seed) and judges each sequence at `level`.
///
/// # Errors
/// Fewer than two pairs, different numbers of base and variant tables, a level outside (0, 0.5),
/// or tables that do not hold the same sequences.
pub fn compare(base: &[AucTable], variant: &[AucTable], level: f64) -> Result<Comparison> {
    if base.len() != variant.len() || base.len() < 2 {
        return Err(AppError::InvalidSetting {
            name: "--base and --variant".into(),
            reason: format!(
                "{} base and {} variant results: give the same number, at least two (one per \
                 seed, in the same order)",
                base.len(),
                variant.len()
            ),
        });
    }
    if !(level > 0.0 && level < 0.5) {
        return Err(AppError::InvalidSetting {
            name: "--level".into(),
            reason: format!("{level}: a one-sided level in (0, 0.5)"),
        });
    }
    let n = base.len();
    let critical = critical_t(n - 1, level)?;
    let names: Vec<&String> = base[0].sequences.iter().map(|(s, _)| s).collect();
    let auc = |table: &AucTable, name: &str| {
        table
            .sequences
            .iter()
            .find(|(s, _)| s == name)
            .map(|(_, v)| *v)
            .ok_or_else(|| AppError::InvalidSetting {
                name: "--base and --variant".into(),
                reason: format!(
                    "sequence `{name}` is missing from one of the results: compare runs of the \
                     same sequences"
                ),
            })
    };
    check_frames(base, variant)?;
    let mut sequences = Vec::with_capacity(names.len());
    for name in names {
        let mut differences = Vec::with_capacity(n);
        let (mut b_sum, mut v_sum) = (0.0, 0.0);
        for (b, v) in base.iter().zip(variant) {
            let (x, y) = (auc(b, name)?, auc(v, name)?);
            differences.push(y - x);
            b_sum += x;
            v_sum += y;
        }
        let (verdict, t) = verdict(&differences, critical);
        sequences.push(SequenceComparison {
            sequence: name.clone(),
            base: b_sum / n as f64,
            variant: v_sum / n as f64,
            difference: (v_sum - b_sum) / n as f64,
            t,
            verdict,
        });
    }
    for table in base.iter().chain(variant) {
        if table.sequences.len() != sequences.len() {
            return Err(AppError::InvalidSetting {
                name: "--base and --variant".into(),
                reason: "the results hold different sets of sequences: compare runs of the \
                         same sequences"
                    .into(),
            });
        }
    }
    let mean = |tables: &[AucTable]| tables.iter().map(|t| t.mean).sum::<f64>() / n as f64;
    Ok(Comparison {
        pairs: n,
        critical_t: critical,
        sequences,
        base_mean: mean(base),
        variant_mean: mean(variant),
    })
}

/// Refuses pairs whose base and variant scored a sequence on different numbers of frames (a
/// different `--frame-step`, or different footage): their success AUCs are not comparable.
fn check_frames(base: &[AucTable], variant: &[AucTable]) -> Result<()> {
    for (b, v) in base.iter().zip(variant) {
        for (seq, fb) in &b.frames {
            let Some((_, fv)) = v.frames.iter().find(|(s, _)| s == seq) else {
                continue;
            };
            if fb != fv {
                return Err(AppError::InvalidSetting {
                    name: "--base and --variant".into(),
                    reason: format!(
                        "sequence `{seq}` was scored on {fb} frames in {} but on {fv} in {}: \
                         compare runs on the same frames (the same sequences and --frame-step)",
                        b.path.display(),
                        v.path.display()
                    ),
                });
            }
        }
    }
    Ok(())
}

/// The `otb.csv` of `protocol` in each results folder.
pub fn csv_paths(dirs: &[PathBuf], protocol: Protocol) -> Vec<PathBuf> {
    dirs.iter()
        .map(|d| d.join(protocol.name()).join("otb.csv"))
        .collect()
}

/// A Markdown report of one protocol's comparison.
pub fn markdown(protocol: Protocol, c: &Comparison, level: f64) -> String {
    let (helps, hurts) = c.counts();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "## {}: the variant helps {helps} and hurts {hurts} of {} sequences\n\n\
         {} pairs (seeds); mean success AUC {:.3} → {:.3}; one-sided paired t-test at {} % \
         (|t| > {:.3})\n",
        protocol.title(),
        c.sequences.len(),
        c.pairs,
        c.base_mean,
        c.variant_mean,
        level * 100.0,
        c.critical_t
    );
    s.push_str("| sequence | base | variant | mean difference | t | verdict |\n");
    s.push_str("|---|---|---|---|---|---|\n");
    for q in &c.sequences {
        let verdict = match q.verdict {
            Verdict::Helps => "helps",
            Verdict::Hurts => "hurts",
            Verdict::Neither => "—",
            Verdict::Untestable => "untestable: no seed-to-seed variation",
        };
        let _ = writeln!(
            s,
            "| {} | {:.3} | {:.3} | {:+.4} | {} | {verdict} |",
            q.sequence,
            q.base,
            q.variant,
            q.difference,
            if q.t.is_finite() {
                format!("{:.2}", q.t)
            } else {
                "—".to_owned()
            }
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(values: &[(&str, f64)]) -> AucTable {
        let sequences: Vec<(String, f64)> =
            values.iter().map(|(s, v)| ((*s).to_owned(), *v)).collect();
        let mean = sequences.iter().map(|s| s.1).sum::<f64>() / sequences.len() as f64;
        AucTable {
            sequences,
            mean,
            frames: Vec::new(),
            path: PathBuf::new(),
        }
    }

    #[test]
    fn the_critical_values_are_students() {
        // One-sided 5 %: 6.314 (1 degree of freedom), 2.920 (2), 2.132 (4); 1 %: 6.965 (2).
        for (dof, level, want) in [
            (1, 0.05, 6.314),
            (2, 0.05, 2.920),
            (4, 0.05, 2.132),
            (2, 0.01, 6.965),
        ] {
            let t = critical_t(dof, level).unwrap();
            assert!((t - want).abs() < 1e-3, "{dof} dof at {level}: {t}");
        }
    }

    #[test]
    fn a_small_gain_on_every_seed_helps_and_one_lucky_seed_does_not() {
        let critical = critical_t(2, 0.05).unwrap();
        // +0.005 ± 0.001 on three seeds: far below a fixed 0.01, far above its own noise.
        assert_eq!(verdict(&[0.004, 0.005, 0.006], critical).0, Verdict::Helps);
        // One seed +0.2, the others −0.05: a larger mean gain, but no larger than the noise.
        assert_eq!(verdict(&[0.2, -0.05, -0.05], critical).0, Verdict::Neither);
        assert_eq!(
            verdict(&[-0.004, -0.005, -0.006], critical).0,
            Verdict::Hurts
        );
        // Identical differences: no seed-to-seed noise to judge them by (also when they differ
        // by rounding only), or no difference at all.
        assert_eq!(verdict(&[0.01, 0.01], critical).0, Verdict::Untestable);
        assert!(verdict(&[0.01, 0.01], critical).1.is_nan());
        assert_eq!(
            verdict(&[0.45 - 0.5, 0.55 - 0.6], critical).0,
            Verdict::Untestable
        );
        assert_eq!(verdict(&[0.0, 0.0, 0.0], critical), (Verdict::Neither, 0.0));
    }

    #[test]
    fn sequences_are_paired_seed_by_seed() {
        // Seed-to-seed swings shared by base and variant cancel in the pairs: a consistent gain of
        // 0.01 on `a` is found under swings of 0.2; `b` moves both ways.
        let base = [
            table(&[("a", 0.5), ("b", 0.6)]),
            table(&[("a", 0.7), ("b", 0.6)]),
            table(&[("a", 0.3), ("b", 0.6)]),
        ];
        let variant = [
            table(&[("a", 0.51), ("b", 0.65)]),
            table(&[("a", 0.711), ("b", 0.55)]),
            table(&[("a", 0.309), ("b", 0.6)]),
        ];
        let c = compare(&base, &variant, 0.05).unwrap();
        assert_eq!(c.pairs, 3);
        assert_eq!(c.sequences[0].verdict, Verdict::Helps);
        assert_eq!(c.sequences[1].verdict, Verdict::Neither);
        assert_eq!(c.counts(), (1, 0));
        assert!((c.sequences[0].difference - 0.01).abs() < 1e-12);
        let md = markdown(Protocol::Tre, &c, 0.05);
        assert!(md.contains("helps 1 and hurts 0 of 2"), "{md}");
    }

    #[test]
    fn a_file_of_several_trackers_needs_one_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("otb.csv");
        std::fs::write(
            &path,
            "protocol,sequence,tracker,runs,frames,labelled,success_auc,precision_20,mean_iou,fps,lost_auc\n\
             tre,a,head,10,100,90,0.7000,0.9,0.7,500.00,0.95\n\
             tre,a,csrt,10,100,90,0.6000,0.8,0.6,,\n\
             tre,mean,head,10,100,90,0.7000,0.9,0.7,500.00,0.95\n\
             tre,mean,csrt,10,100,90,0.6000,0.8,0.6,,\n",
        )
        .unwrap();
        let err = read_auc(&path, None).unwrap_err().to_string();
        assert!(err.contains("several trackers (csrt, head)"), "{err}");
        let csrt = read_auc(&path, Some("csrt")).unwrap();
        assert_eq!(csrt.sequences, [("a".to_owned(), 0.6)]);
        assert_eq!(csrt.mean, 0.6);
        assert!(read_auc(&path, Some("kcf")).is_err());
    }

    #[test]
    fn mismatched_results_are_errors() {
        let one = [table(&[("a", 0.5)])];
        assert!(compare(&one, &one, 0.05).is_err());
        let two = [table(&[("a", 0.5)]), table(&[("a", 0.6)])];
        let other = [table(&[("b", 0.5)]), table(&[("b", 0.6)])];
        assert!(compare(&two, &other, 0.05).is_err());
        assert!(compare(&two, &two[..1], 0.05).is_err());
        assert!(compare(&two, &two, 0.7).is_err());
        let more = [table(&[("a", 0.5), ("c", 0.1)]), table(&[("a", 0.6)])];
        assert!(compare(&two, &more, 0.05).is_err());
    }
}
