//! Backward simulation of whole trajectories (FFBS, Eqs. (S3)–(S4) of [`crate::smooth`]).

use rand::Rng;
use rayon::prelude::*;

use super::alias::AliasTable;
use super::marginal::frame_out_of_range;
use super::{BackwardMethod, SmootherSettings, backward_weights, check_log_density};
use crate::error::{Error, Result};
use crate::history::History;
use crate::model::TransitionDensity;
use crate::particles::ParticleSet;
use crate::rng::backward_rng;

/// Counts of what backward simulation did, to judge the rejection sampler.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BackwardStats {
    /// Backward draws (trajectories × steps).
    pub draws: u64,
    /// Accept–reject proposals made (S4), accepted or not.
    pub proposals: u64,
    /// Draws settled by accept–reject.
    pub accepted: u64,
    /// Draws done by the exact O(N) categorical draw: every draw of a step without a bound,
    /// and the draws where accept–reject gave up after
    /// [`SmootherSettings::max_rejections`] proposals.
    pub exact: u64,
}

/// M trajectories drawn by backward simulation: at every frame t, the index of the particle
/// each trajectory passes through.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Trajectories {
    /// `indices[t][m]`: particle of frame t on trajectory m.
    indices: Vec<Vec<usize>>,
    stats: BackwardStats,
}

impl Trajectories {
    /// Number of frames.
    #[must_use]
    pub fn frames(&self) -> usize {
        self.indices.len()
    }

    /// Number of trajectories.
    #[must_use]
    pub fn trajectories(&self) -> usize {
        self.indices.first().map_or(0, Vec::len)
    }

    /// The particle index of every trajectory at frame `t`; `None` out of range.
    #[must_use]
    pub fn indices(&self, t: usize) -> Option<&[usize]> {
        self.indices.get(t).map(Vec::as_slice)
    }

    /// What the sampler did.
    #[must_use]
    pub fn stats(&self) -> BackwardStats {
        self.stats
    }

    /// The states of trajectory `m`, oldest first; `None` when `m` is out of range or `history`
    /// is not the one the trajectories were drawn from.
    #[must_use]
    pub fn path<S: Clone>(&self, history: &History<S>, m: usize) -> Option<Vec<S>> {
        self.indices
            .iter()
            .enumerate()
            .map(|(t, ix)| {
                let i = *ix.get(m)?;
                history.frame(t)?.set.states().get(i).cloned()
            })
            .collect()
    }

    /// The trajectories' states at frame `t` with equal weights 1/M: the FFBS approximation of
    /// p(x_t | z_{0:T}), for the estimators of [`crate::estimate`]. Clones the states.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] (`frame`) when `t` is out of range or `history` is not the one
    /// the trajectories were drawn from.
    pub fn to_particle_set<S: Clone>(
        &self,
        history: &History<S>,
        t: usize,
    ) -> Result<ParticleSet<S>> {
        let (Some(frame), Some(ix)) = (history.frame(t), self.indices.get(t)) else {
            return Err(frame_out_of_range(t, self.frames()));
        };
        let states = frame.set.states();
        let picked = ix
            .iter()
            .map(|&i| states.get(i).cloned())
            .collect::<Option<Vec<S>>>()
            .ok_or_else(|| frame_out_of_range(t, self.frames()))?;
        ParticleSet::from_states(picked)
    }
}

/// Per-task scratch buffer of the exact draw.
type Scratch = Vec<f64>;

/// Draws `trajectories` trajectories from the particle approximation of p(x_{0:T} | z_{0:T}) by
/// backward simulation (Eqs. (S3)–(S4)), trajectory m drawing from the generator of
/// (`seed`, frame, m). Allocating convenience around [`sample_trajectories_into`].
///
/// # Errors
/// As [`sample_trajectories_into`].
pub fn sample_trajectories<S, T>(
    history: &History<S>,
    transition: &T,
    trajectories: usize,
    seed: u64,
    settings: &SmootherSettings,
) -> Result<Trajectories>
where
    S: Sync,
    T: TransitionDensity<State = S> + ?Sized,
{
    let mut out = Trajectories::default();
    sample_trajectories_into(history, transition, trajectories, seed, settings, &mut out)?;
    Ok(out)
}

/// [`sample_trajectories`] writing into `out`, whose buffers are reused.
///
/// # Errors
/// [`Error::InvalidSetting`] for invalid settings, zero trajectories, or
/// [`BackwardMethod::Rejection`] at a step without a bound; [`Error::EmptyHistory`];
/// [`Error::DegenerateBackward`] when a transition log-density is NaN or +∞ or a backward kernel
/// (S1) is all zero; [`Error::BoundExceeded`] when a density is above its declared bound.
/// `out` is unspecified after an error.
pub fn sample_trajectories_into<S, T>(
    history: &History<S>,
    transition: &T,
    trajectories: usize,
    seed: u64,
    settings: &SmootherSettings,
    out: &mut Trajectories,
) -> Result<()>
where
    S: Sync,
    T: TransitionDensity<State = S> + ?Sized,
{
    settings.validate()?;
    if trajectories == 0 {
        return Err(Error::InvalidSetting {
            name: "trajectories",
            reason: "must be at least 1".into(),
        });
    }
    let frames = history.len();
    let last = history
        .frame(frames.wrapping_sub(1))
        .ok_or(Error::EmptyHistory)?;
    out.indices.resize_with(frames, Vec::new);
    out.stats = BackwardStats::default();
    let mut table = AliasTable::default();

    // J_T ~ W_T.
    table.rebuild(last.set.weights());
    let terminal = &mut out.indices[frames - 1];
    terminal.clear();
    terminal
        .extend((0..trajectories).map(|m| table.sample(&mut backward_rng(seed, frames - 1, m))));

    for t in (0..frames - 1).rev() {
        let (Some(here), Some(after)) = (history.frame(t), history.frame(t + 1)) else {
            return Err(frame_out_of_range(t + 1, frames));
        };
        table.rebuild(here.set.weights());
        let step = BackwardStep {
            transition,
            frame: t,
            previous: here.set.states(),
            log_w: here.set.log_weights(),
            following: after.set.states(),
            table: &table,
            settings,
            seed,
        };
        let (head, tail) = out.indices.split_at_mut(t + 1);
        let next = &tail[0];
        let results: Vec<Result<(usize, Draw)>> = if settings.parallel {
            next.par_iter()
                .enumerate()
                .with_min_len(settings.parallel_min_chunk)
                .map_init(Scratch::new, |scratch, (m, &j)| step.draw(m, j, scratch))
                .collect()
        } else {
            let mut scratch = Scratch::new();
            next.iter()
                .enumerate()
                .map(|(m, &j)| step.draw(m, j, &mut scratch))
                .collect()
        };
        let current = &mut head[t];
        current.clear();
        for r in results {
            // The first failing trajectory (in index order) is reported, whatever the threads.
            let (i, draw) = r?;
            current.push(i);
            out.stats.draws += 1;
            out.stats.proposals += draw.proposals;
            if draw.exact {
                out.stats.exact += 1;
            } else {
                out.stats.accepted += 1;
            }
        }
    }
    Ok(())
}

/// How one backward draw was made.
#[derive(Debug, Clone, Copy)]
struct Draw {
    proposals: u64,
    exact: bool,
}

/// Everything one backward step t ← t + 1 shares between trajectories.
struct BackwardStep<'a, S, T: ?Sized> {
    transition: &'a T,
    frame: usize,
    previous: &'a [S],
    log_w: &'a [f64],
    following: &'a [S],
    table: &'a AliasTable,
    settings: &'a SmootherSettings,
    seed: u64,
}

impl<S, T: TransitionDensity<State = S> + ?Sized> BackwardStep<'_, S, T> {
    /// J_t for trajectory `m`, which is at particle `j` of frame t + 1 (Eq. (S3)).
    fn draw(&self, m: usize, j: usize, scratch: &mut Scratch) -> Result<(usize, Draw)> {
        let t = self.frame;
        let x_next = self
            .following
            .get(j)
            .ok_or_else(|| frame_out_of_range(t + 1, t + 1))?;
        let mut rng = backward_rng(self.seed, t, m);
        let bound = match self.settings.backward {
            BackwardMethod::Exact => None,
            BackwardMethod::Auto => self.transition.log_density_bound(t + 1, x_next),
            BackwardMethod::Rejection => Some(
                self.transition
                    .log_density_bound(t + 1, x_next)
                    .ok_or_else(|| Error::InvalidSetting {
                        name: "backward",
                        reason: format!(
                            "rejection sampling needs a density bound at frame {}",
                            t + 1
                        ),
                    })?,
            ),
        };
        let mut proposals = 0;
        if let Some(log_bound) = bound {
            // Accept–reject (S4): propose I ~ W_t, accept with probability f / ε̄.
            let slack = 1e-9 * log_bound.abs().max(1.0);
            let budget = self.settings.max_rejections.unwrap_or(self.previous.len());
            for _ in 0..budget {
                proposals += 1;
                let i = self.table.sample(&mut rng);
                let lf = check_log_density(
                    self.transition
                        .log_density(t + 1, &self.previous[i], x_next),
                    t,
                    j,
                    i,
                )?;
                if lf > log_bound + slack {
                    return Err(Error::BoundExceeded {
                        frame: t + 1,
                        log_density: lf,
                        log_bound,
                    });
                }
                let u: f64 = rng.random();
                if u.ln() < lf - log_bound {
                    return Ok((
                        i,
                        Draw {
                            proposals,
                            exact: false,
                        },
                    ));
                }
            }
        }
        // The exact draw from (S1): one pass for the log-weights, one for the inverse CDF.
        scratch.clear();
        scratch.resize(self.previous.len(), 0.0);
        let sum = backward_weights(
            self.transition,
            self.previous,
            self.log_w,
            t,
            j,
            x_next,
            scratch,
        )?;
        let target = rng.random::<f64>() * sum;
        let mut acc = 0.0;
        let mut pick = None;
        for (i, &v) in scratch.iter().enumerate() {
            acc += v;
            if v > 0.0 {
                pick = Some(i);
                if acc > target {
                    break;
                }
            }
        }
        // `backward_weights` succeeded, so some entry is positive and `pick` is set.
        let i = pick.unwrap_or(0);
        Ok((
            i,
            Draw {
                proposals,
                exact: true,
            },
        ))
    }
}
