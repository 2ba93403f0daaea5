//! Forward filtering–backward smoothing of marginals (FFBSm, Eq. (S2) of [`crate::smooth`]).

use faer::linalg::matmul::matmul;
use faer::{Accum, ColMut, ColRef, MatRef, Par};
use rayon::prelude::*;

use super::{SmootherSettings, backward_weights};
use crate::error::{Degeneracy, Error, Result};
use crate::history::History;
use crate::model::TransitionDensity;
use crate::particles::ParticleSet;

/// Smoothed marginal weights w_{t|T} of every frame of a [`History`] (Eq. (S2)), aligned with
/// the frames' particles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SmoothedMarginals {
    weights: Vec<Vec<f64>>,
}

impl SmoothedMarginals {
    /// Number of frames.
    #[must_use]
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// Whether there is no frame.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// The normalised smoothed weights of frame `t`; `None` out of range.
    #[must_use]
    pub fn weights(&self, t: usize) -> Option<&[f64]> {
        self.weights.get(t).map(Vec::as_slice)
    }

    /// The particles of frame `t` of `history` carrying their smoothed weights, for the
    /// estimators of [`crate::estimate`]. Clones the states.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] (`frame`) when `t` is out of range;
    /// [`Error::LengthMismatch`] when `history` is not the one that was smoothed.
    pub fn to_particle_set<S: Clone>(
        &self,
        history: &History<S>,
        t: usize,
    ) -> Result<ParticleSet<S>> {
        let (Some(frame), Some(w)) = (history.frame(t), self.weights.get(t)) else {
            return Err(frame_out_of_range(t, self.len()));
        };
        if frame.set.len() != w.len() {
            return Err(Error::LengthMismatch {
                what: "smoothed weights",
                expected: frame.set.len(),
                got: w.len(),
            });
        }
        ParticleSet::from_log_weights(
            frame.set.states().to_vec(),
            w.iter().map(|x| x.ln()).collect(),
        )
    }
}

pub(crate) fn frame_out_of_range(t: usize, len: usize) -> Error {
    Error::InvalidSetting {
        name: "frame",
        reason: format!("{t} out of range for {len} frames"),
    }
}

/// The FFBSm smoother with its reusable buffers (the column block of the transition matrix).
///
/// [`smooth_marginals`] is the allocating convenience around it.
#[derive(Debug, Clone)]
pub struct MarginalSmoother {
    settings: SmootherSettings,
    /// One column block of (S1), column-major, N_t × `block_columns`.
    block: Vec<f64>,
    /// w_{t+1|T}^j / Σ_l (column j of the block), for the columns of the block.
    scaled: Vec<f64>,
    /// Per-column status of the block: `Ok(column sum)` or the degeneracy found.
    status: Vec<std::result::Result<f64, Error>>,
}

impl MarginalSmoother {
    /// A smoother with validated settings.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] from [`SmootherSettings::validate`].
    pub fn new(settings: SmootherSettings) -> Result<Self> {
        settings.validate()?;
        Ok(Self {
            settings,
            block: Vec::new(),
            scaled: Vec::new(),
            status: Vec::new(),
        })
    }

    /// The settings.
    #[must_use]
    pub fn settings(&self) -> &SmootherSettings {
        &self.settings
    }

    /// Smooths every frame of `history` into `out` (its buffers are reused): Eq. (S2) from the
    /// last frame back to the first.
    ///
    /// # Errors
    /// [`Error::EmptyHistory`]; [`Error::DegenerateBackward`] when a transition log-density is NaN
    /// or +∞, or when a particle with positive smoothed weight has zero transition density from
    /// every particle of positive filtering weight in the frame before (the filter and the
    /// transition density disagree). `out` is unspecified after an error.
    pub fn smooth<S, T>(
        &mut self,
        history: &History<S>,
        transition: &T,
        out: &mut SmoothedMarginals,
    ) -> Result<()>
    where
        S: Sync,
        T: TransitionDensity<State = S> + ?Sized,
    {
        let frames = history.len();
        let last = history
            .frame(frames.wrapping_sub(1))
            .ok_or(Error::EmptyHistory)?;
        out.weights.resize_with(frames, Vec::new);
        out.weights[frames - 1].clear();
        out.weights[frames - 1].extend_from_slice(last.set.weights());
        for t in (0..frames - 1).rev() {
            let (head, tail) = out.weights.split_at_mut(t + 1);
            self.backward_step(history, transition, t, &tail[0], &mut head[t])?;
        }
        Ok(())
    }

    /// The fixed-lag estimate: the smoothed weights of frame `len − 1 − lag` (frame 0 when the
    /// history is shorter) given every frame up to the last, from Eq. (S2) run over those
    /// `lag + 1` frames only. Returns the frame index and writes its weights into `out`.
    ///
    /// # Errors
    /// As [`MarginalSmoother::smooth`].
    pub fn fixed_lag<S, T>(
        &mut self,
        history: &History<S>,
        transition: &T,
        lag: usize,
        out: &mut Vec<f64>,
    ) -> Result<usize>
    where
        S: Sync,
        T: TransitionDensity<State = S> + ?Sized,
    {
        let frames = history.len();
        let last = history
            .frame(frames.wrapping_sub(1))
            .ok_or(Error::EmptyHistory)?;
        let target = (frames - 1).saturating_sub(lag);
        let mut next = last.set.weights().to_vec();
        for t in (target..frames - 1).rev() {
            self.backward_step(history, transition, t, &next, out)?;
            std::mem::swap(&mut next, out);
        }
        std::mem::swap(&mut next, out);
        Ok(target)
    }

    /// One step of Eq. (S2): w_{t|T} from w_{t+1|T} (`next`).
    fn backward_step<S, T>(
        &mut self,
        history: &History<S>,
        transition: &T,
        t: usize,
        next: &[f64],
        out: &mut Vec<f64>,
    ) -> Result<()>
    where
        S: Sync,
        T: TransitionDensity<State = S> + ?Sized,
    {
        let (Some(here), Some(after)) = (history.frame(t), history.frame(t + 1)) else {
            return Err(frame_out_of_range(t + 1, history.len()));
        };
        let previous = here.set.states();
        let log_w = here.set.log_weights();
        let following = after.set.states();
        if next.len() != following.len() {
            return Err(Error::LengthMismatch {
                what: "smoothed weights of the next frame",
                expected: following.len(),
                got: next.len(),
            });
        }
        let n = previous.len();
        out.clear();
        out.resize(n, 0.0);
        let width = self.settings.block_columns.min(following.len());
        self.block.resize(n * width, 0.0);
        let parallel = self.settings.parallel;
        let min_chunk = self.settings.parallel_min_chunk;
        for start in (0..following.len()).step_by(width) {
            let end = (start + width).min(following.len());
            let cols = end - start;
            let block = &mut self.block[..n * cols];
            // Column j of the block: A_ij = exp(log W_t^i + log f(x_{t+1}^j | x_t^i) − c_j) with
            // c_j the column maximum, so that every entry is in [0, 1] and the column sum is ≥ 1.
            // The factor exp(−c_j) cancels in (S1).
            let fill = |(jj, column): (usize, &mut [f64])| -> std::result::Result<f64, Error> {
                let j = start + jj;
                if next[j] == 0.0 {
                    // A particle without smoothed mass contributes nothing; skip its densities.
                    column.fill(0.0);
                    return Ok(f64::INFINITY);
                }
                backward_weights(transition, previous, log_w, t, j, &following[j], column)
            };
            if parallel {
                block
                    .par_chunks_mut(n)
                    .enumerate()
                    .with_min_len(min_chunk)
                    .map(fill)
                    .collect_into_vec(&mut self.status);
            } else {
                self.status.clear();
                self.status
                    .extend(block.chunks_mut(n).enumerate().map(fill));
            }
            self.scaled.clear();
            for (jj, status) in self.status.drain(..).enumerate() {
                // The first failing column (in column order) is reported, whatever the threads.
                self.scaled.push(next[start + jj] / status?);
            }
            // out += A_block · (w_{t+1|T} / column sums): the sum over j in (S2).
            matmul(
                ColMut::from_slice_mut(out.as_mut_slice()),
                Accum::Add,
                MatRef::from_column_major_slice(&*block, n, cols),
                ColRef::from_slice(self.scaled.as_slice()),
                1.0,
                Par::Seq,
            );
        }
        // The weights sum to one in exact arithmetic; renormalise away the rounding.
        let sum: f64 = out.iter().sum();
        if !(sum > 0.0 && sum.is_finite()) {
            return Err(Error::DegenerateBackward {
                frame: t,
                particle: 0,
                reason: Degeneracy::AllZero,
            });
        }
        out.iter_mut().for_each(|w| *w /= sum);
        Ok(())
    }
}

/// Smoothed marginals of every frame of `history` by FFBSm (Eq. (S2)): O(N²) transition-density
/// evaluations per step. Allocating convenience around [`MarginalSmoother::smooth`].
///
/// # Errors
/// As [`MarginalSmoother::smooth`], and [`Error::InvalidSetting`] for invalid settings.
pub fn smooth_marginals<S, T>(
    history: &History<S>,
    transition: &T,
    settings: &SmootherSettings,
) -> Result<SmoothedMarginals>
where
    S: Sync,
    T: TransitionDensity<State = S> + ?Sized,
{
    let mut smoother = MarginalSmoother::new(settings.clone())?;
    let mut out = SmoothedMarginals::default();
    smoother.smooth(history, transition, &mut out)?;
    Ok(out)
}

/// Fixed-lag smoothing: the frame index `len − 1 − lag` (or 0) and its smoothed weights given
/// all frames of `history`, see [`MarginalSmoother::fixed_lag`]. O(lag · N²).
///
/// # Errors
/// As [`MarginalSmoother::smooth`], and [`Error::InvalidSetting`] for invalid settings.
pub fn fixed_lag_weights<S, T>(
    history: &History<S>,
    transition: &T,
    lag: usize,
    settings: &SmootherSettings,
) -> Result<(usize, Vec<f64>)>
where
    S: Sync,
    T: TransitionDensity<State = S> + ?Sized,
{
    let mut smoother = MarginalSmoother::new(settings.clone())?;
    let mut out = Vec::new();
    let t = smoother.fixed_lag(history, transition, lag, &mut out)?;
    Ok((t, out))
}
