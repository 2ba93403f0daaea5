//! Particle smoothing from a recorded forward pass: marginals by forward filtering–backward
//! smoothing (FFBSm), whole trajectories by backward simulation (FFBS), and a fixed-lag variant.
//!
//! A filter gives p̂(x_t | z_{0:t}) = Σᵢ W_t^i δ(x_t^i) at every frame t = 0..T of a
//! [`History`]. A smoother reuses those particles and reweights or recombines them to
//! approximate p(x_t | z_{0:T}), using the frames after t. Everything rests on the backward
//! kernel, with f_{t+1} the transition density ([`TransitionDensity`]):
//!
//! **(S1)** B_t(i | j) = W_t^i f_{t+1}(x_{t+1}^j | x_t^i) / Σ_l W_t^l f_{t+1}(x_{t+1}^j | x_t^l),
//!
//! the particle approximation of p(x_t | x_{t+1}, z_{0:t}) (Doucet, Godsill & Andrieu 2000,
//! "On sequential Monte Carlo sampling methods for Bayesian filtering", the smoothing
//! recursion; Chopin & Papaspiliopoulos 2020, *An Introduction to Sequential Monte Carlo*,
//! Ch. 12, the backward kernel).
//!
//! - **FFBSm** ([`smooth_marginals`], [`MarginalSmoother`]): the smoothed weights
//!   **(S2)** w_{T|T}^i = W_T^i, w_{t|T}^i = Σ_j B_t(i | j) w_{t+1|T}^j
//!   (Doucet, Godsill & Andrieu 2000, the marginal smoothing recursion; Chopin &
//!   Papaspiliopoulos 2020, Ch. 12, the O(N²) FFBS marginal algorithm). The N_t × N_{t+1} matrix
//!   of (S1) is built column block by column block in log space with each column rescaled by its
//!   maximum (the rescaling cancels in (S1)), and the sum over j is a dense matrix–vector product
//!   done by `faer`. Cost O(N²) per step; memory O(N · [`SmootherSettings::block_columns`]).
//! - **FFBS** ([`sample_trajectories`]): M trajectories drawn from the particle approximation of
//!   p(x_{0:T} | z_{0:T}): J_T ~ W_T, then **(S3)** J_t ~ B_t(· | J_{t+1}) for t = T−1..0
//!   (Godsill, Doucet & West 2004, "Monte Carlo smoothing for nonlinear time series", the
//!   backward simulation algorithm). The exact draw of (S3) costs O(N) per trajectory and step,
//!   O(MN) in all. When the transition density is bounded, f_{t+1}(x′ | x) ≤ ε̄(x′), the draw is
//!   done by accept–reject: propose I ~ W_t, accept with probability
//!   **(S4)** f_{t+1}(x_{t+1}^j | x_t^I) / ε̄(x_{t+1}^j)
//!   (Douc, Garivier, Moulines & Olsson 2011, "Sequential Monte Carlo smoothing for general state
//!   space hidden Markov models", the accept–reject backward sampler), with expected O(1) cost per
//!   draw when the bound is tight. Because the acceptance rate can be tiny (a peaked transition
//!   against widely spread particles), at most [`SmootherSettings::max_rejections`] proposals are
//!   tried before the exact O(N) draw takes over (the hybrid scheme of Dau & Chopin 2022,
//!   "On the complexity of backward smoothing algorithms", arXiv:2207.00976): the draw is exact
//!   either way and never spins.
//! - **Fixed lag** ([`fixed_lag_weights`]): the recursion (S2) from the last frame T down to
//!   frame T − L reads only those L + 1 frames, and gives the FFBSm approximation of
//!   p(x_{T−L} | z_{0:T}). Near-online use takes this as the estimate of frame T − L once frame T
//!   is in, which is close to the full smoother when L spans a few correlation times of the model
//!   (the fixed-lag approximation, Doucet & Johansen 2011, "A tutorial on particle filtering and
//!   smoothing: fifteen years later", the smoothing section). With a history bounded to L + 1
//!   frames ([`crate::HistorySettings::max_frames`]) memory stays constant.
//!
//! **Randomness and threads.** Trajectory m draws from the generator of
//! (seed, frame, m) ([`crate::rng::backward_rng`]) and the marginal smoother sums in an order fixed
//! by [`SmootherSettings::block_columns`], so the results are bit-identical for any number of
//! rayon threads, with [`SmootherSettings::parallel`] on or off.
//!
//! # Example
//! Smoothing a bootstrap filter on x_k = 0.9 x_{k−1} + N(0, 1), z_k = x_k + N(0, 1):
//! ```
//! use smc_core::rand::Rng;
//! use smc_core::rand_distr::{Distribution, StandardNormal};
//! use smc_core::model::{Dynamics, FnObservation, PriorDensity};
//! use smc_core::smooth::{SmootherSettings, sample_trajectories, smooth_marginals};
//! use smc_core::{FilterSettings, HistorySettings, ParticleFilter, ParticleSet, ResamplingScheme};
//!
//! struct Ar1;
//! impl Dynamics for Ar1 {
//!     type State = f64;
//!     fn sample<R: Rng + ?Sized>(&self, x: &f64, rng: &mut R) -> f64 {
//!         let e: f64 = StandardNormal.sample(rng);
//!         0.9 * x + e
//!     }
//!     fn log_density(&self, x: &f64, y: &f64) -> f64 {
//!         -0.5 * (y - 0.9 * x).powi(2) - 0.5 * (2.0 * std::f64::consts::PI).ln()
//!     }
//! }
//!
//! let settings = FilterSettings { history: Some(HistorySettings::default()), ..FilterSettings::default() };
//! let mut filter = ParticleFilter::new(settings)?;
//! let mut set = ParticleSet::from_states(vec![0.0; 500])?;
//! for (k, z) in [0.5, 1.1, 0.7, -0.2].into_iter().enumerate() {
//!     let obs = FnObservation::new(move |x: &f64| -0.5 * (z - x).powi(2));
//!     filter.step_bootstrap(&mut set, &Ar1, &obs, &ResamplingScheme::Systematic, 7, k as u64)?;
//! }
//! let history = filter.take_history().ok_or(smc_core::Error::EmptyHistory)?;
//! // The Gaussian transition density is bounded by its value at the mode, 1/sqrt(2π).
//! let density = PriorDensity { dynamics: &Ar1, log_bound: Some(-0.5 * (2.0 * std::f64::consts::PI).ln()) };
//! let smoother = SmootherSettings::default();
//!
//! let marginals = smooth_marginals(&history, &density, &smoother)?;
//! let first = marginals.to_particle_set(&history, 0)?;
//! let mean = smc_core::estimate::weighted_mean(&first)?[0];
//!
//! let paths = sample_trajectories(&history, &density, 200, 11, &smoother)?;
//! let mean_ffbs = smc_core::estimate::weighted_mean(&paths.to_particle_set(&history, 0)?)?[0];
//! assert!((mean - mean_ffbs).abs() < 0.5);
//! # Ok::<(), smc_core::Error>(())
//! ```

mod alias;
mod backward;
mod marginal;

pub use backward::{BackwardStats, Trajectories, sample_trajectories, sample_trajectories_into};
pub use marginal::{MarginalSmoother, SmoothedMarginals, fixed_lag_weights, smooth_marginals};

use crate::error::{Error, Result};
#[cfg(doc)]
use crate::history::History;
use crate::model::TransitionDensity;

/// How backward simulation draws from the backward kernel (S1).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum BackwardMethod {
    /// Accept–reject (S4) when [`TransitionDensity::log_density_bound`] gives a bound, the exact
    /// draw otherwise (the default).
    #[default]
    Auto,
    /// Always the exact O(N) draw per trajectory and step.
    Exact,
    /// Accept–reject (S4), falling back to the exact draw after
    /// [`SmootherSettings::max_rejections`] rejections; an error when a frame has no bound.
    Rejection,
}

/// Settings of the smoothers.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SmootherSettings {
    /// FFBSm: columns of the transition matrix (S1) held at once (default 256). Memory is
    /// 8 · N · `block_columns` bytes. It also fixes the order of the sums, so results do not
    /// depend on the thread count, only on this setting.
    pub block_columns: usize,
    /// FFBS: proposals tried by accept–reject (S4) for one trajectory at one step before the
    /// exact draw takes over. `None` (the default) allows N_t, the number of particles of the
    /// frame drawn from, as Dau & Chopin (2022) suggest: a draw then costs at most about twice
    /// the exact one, and a bounded number of evaluations when the acceptance rate is reasonable.
    /// A small fixed budget makes the rare fallbacks (next states far in the tails of the
    /// filter, where the acceptance rate is tiny) dominate the cost at large N. `Some(0)` is
    /// invalid.
    pub max_rejections: Option<usize>,
    /// FFBS: how to draw from the backward kernel (default [`BackwardMethod::Auto`]).
    pub backward: BackwardMethod,
    /// Spread columns (FFBSm) or trajectories (FFBS) over the rayon pool (default `false`).
    /// Results are bit-identical either way.
    pub parallel: bool,
    /// Smallest number of columns or trajectories handed to one rayon task (default 16).
    pub parallel_min_chunk: usize,
}

impl Default for SmootherSettings {
    fn default() -> Self {
        Self {
            block_columns: 256,
            max_rejections: None,
            backward: BackwardMethod::Auto,
            parallel: false,
            parallel_min_chunk: 16,
        }
    }
}

impl SmootherSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when `block_columns`, `max_rejections` or `parallel_min_chunk`
    /// is zero.
    pub fn validate(&self) -> Result<()> {
        for (name, value) in [
            ("block_columns", self.block_columns),
            ("max_rejections", self.max_rejections.unwrap_or(1)),
            ("parallel_min_chunk", self.parallel_min_chunk),
        ] {
            if value == 0 {
                return Err(Error::InvalidSetting {
                    name,
                    reason: "must be at least 1".into(),
                });
            }
        }
        Ok(())
    }
}

/// The unnormalised backward weights of the particles `previous` (log-weights `log_w`) of frame
/// `t` towards `x_next`, particle `j` of frame `t + 1` (Eq. (S1)): `out[i]` ∝ w_t^i ·
/// p(x_next | x_t^i), rescaled by their largest value so that the exponentials cannot
/// overflow. Returns their sum.
///
/// # Errors
/// A NaN or +∞ density ([`check_log_density`]), or every weight zero.
pub(crate) fn backward_weights<S, T>(
    transition: &T,
    previous: &[S],
    log_w: &[f64],
    t: usize,
    j: usize,
    x_next: &S,
    out: &mut [f64],
) -> Result<f64>
where
    T: TransitionDensity<State = S> + ?Sized,
{
    let mut max = f64::NEG_INFINITY;
    for (i, (entry, (x, lw))) in out.iter_mut().zip(previous.iter().zip(log_w)).enumerate() {
        let v = lw + check_log_density(transition.log_density(t + 1, x, x_next), t, j, i)?;
        *entry = v;
        max = max.max(v);
    }
    if max == f64::NEG_INFINITY {
        return Err(Error::DegenerateBackward {
            frame: t,
            particle: j,
            reason: crate::error::Degeneracy::AllZero,
        });
    }
    let mut sum = 0.0;
    for entry in out.iter_mut() {
        *entry = (*entry - max).exp();
        sum += *entry;
    }
    Ok(sum)
}

/// Checks one transition log-density: NaN and +∞ are errors.
fn check_log_density(value: f64, frame: usize, particle: usize, index: usize) -> Result<f64> {
    use crate::error::Degeneracy;
    if value.is_nan() {
        return Err(Error::DegenerateBackward {
            frame,
            particle,
            reason: Degeneracy::NotANumber { index },
        });
    }
    if value == f64::INFINITY {
        return Err(Error::DegenerateBackward {
            frame,
            particle,
            reason: Degeneracy::PositiveInfinity { index },
        });
    }
    Ok(value)
}
