//! The capability traits of a state-space model (Odobez Eq. 3): the transition prior, the
//! proposal, the observation model.
//!
//! The weight update is w ∝ w′ · p(z|x) · p(x|x′) / q(x|x′, z). The bootstrap filter is the special
//! case q = p(x|x′), where the last two factors cancel; [`Bootstrap`] turns any [`Dynamics`] into
//! that proposal, and the filter then skips both density evaluations.

use std::marker::PhantomData;

/// The transition prior p(x | x′) (the dynamics).
pub trait Dynamics: Sync {
    /// The state type.
    type State: Clone + Send + Sync;

    /// Draws x ~ p(· | `previous`).
    fn sample<R: rand::Rng + ?Sized>(&self, previous: &Self::State, rng: &mut R) -> Self::State;

    /// log p(`next` | `previous`). May be −∞; must not be NaN or +∞ for a valid pair.
    fn log_density(&self, previous: &Self::State, next: &Self::State) -> f64;
}

/// The importance (proposal) distribution q(x | x′, z).
///
/// `index` is the particle index, so that a proposal may differ per particle (for instance one
/// motion estimate per cluster of particles, Odobez Eq. 16).
pub trait Proposal: Sync {
    /// The state type.
    type State: Clone + Send + Sync;

    /// Draws x ~ q(· | `previous`, z) for particle `index`.
    fn sample<R: rand::Rng + ?Sized>(
        &self,
        index: usize,
        previous: &Self::State,
        rng: &mut R,
    ) -> Self::State;

    /// log q(`next` | `previous`, z) for particle `index`.
    fn log_density(&self, index: usize, previous: &Self::State, next: &Self::State) -> f64;
}

/// The observation model log p(z | x) for one frame (the measurement z is held by the value).
pub trait Observation: Sync {
    /// The state type.
    type State;

    /// log p(z | `state`). May be −∞; NaN and +∞ are reported as degenerate weights.
    fn log_likelihood(&self, state: &Self::State) -> f64;

    /// Writes log p(z | `states[i]`) into `out[i]`. The default loops over
    /// [`Observation::log_likelihood`]; override it when a batch is cheaper (shared setup,
    /// vectorisation). It must be element-wise: the filter may call it on contiguous chunks of the
    /// particle set (the parallel path), and the results must not depend on the chunking.
    ///
    /// # Panics
    /// The default panics if the lengths differ; the filter always passes equal lengths.
    fn log_likelihood_batch(&self, states: &[Self::State], out: &mut [f64]) {
        assert_eq!(states.len(), out.len(), "states and out differ in length");
        for (s, o) in states.iter().zip(out.iter_mut()) {
            *o = self.log_likelihood(s);
        }
    }
}

/// Uses a transition prior as the proposal: the bootstrap (CONDENSATION) filter, Odobez H3.
///
/// The particle index is ignored. When the filter is given no separate prior, the prior and
/// proposal densities are not evaluated (they would cancel).
#[derive(Debug, Clone, Copy)]
pub struct Bootstrap<'a, D>(pub &'a D);

impl<D: Dynamics> Proposal for Bootstrap<'_, D> {
    type State = D::State;

    fn sample<R: rand::Rng + ?Sized>(
        &self,
        _index: usize,
        previous: &Self::State,
        rng: &mut R,
    ) -> Self::State {
        self.0.sample(previous, rng)
    }

    fn log_density(&self, _index: usize, previous: &Self::State, next: &Self::State) -> f64 {
        self.0.log_density(previous, next)
    }
}

/// An observation model given by a closure `Fn(&S) -> f64` returning log p(z | x).
///
/// # Examples
/// ```
/// use smc_core::model::{FnObservation, Observation};
/// let obs = FnObservation::new(|x: &f64| -0.5 * (x - 1.0).powi(2));
/// assert_eq!(obs.log_likelihood(&1.0), 0.0);
/// ```
pub struct FnObservation<S, F> {
    f: F,
    _state: PhantomData<fn(&S)>,
}

impl<S, F: Fn(&S) -> f64 + Sync> FnObservation<S, F> {
    /// Wraps the closure.
    pub fn new(f: F) -> Self {
        Self {
            f,
            _state: PhantomData,
        }
    }
}

impl<S, F: Fn(&S) -> f64 + Sync> Observation for FnObservation<S, F> {
    type State = S;

    fn log_likelihood(&self, state: &S) -> f64 {
        (self.f)(state)
    }
}

/// The transition density p(x_t | x_{t−1}) as a particle smoother needs it: evaluated for any
/// pair of particles, whatever proposal moved them, with an optional upper bound.
///
/// The backward kernel of every smoother in [`crate::smooth`] is
/// B_t(i | j) ∝ W_t^i · p(x_{t+1}^j | x_t^i), Eq. (S1) there (Doucet, Godsill & Andrieu 2000;
/// Godsill, Doucet & West 2004).
/// `frame` is the history index of the *next* state, so that a time-varying model can tell its
/// transitions apart; time-invariant models ignore it.
pub trait TransitionDensity: Sync {
    /// The state type.
    type State: Sync;

    /// log p(`next` | `previous`) for the transition into history frame `frame`. May be −∞;
    /// NaN and +∞ are reported as [`crate::Error::DegenerateBackward`].
    fn log_density(&self, frame: usize, previous: &Self::State, next: &Self::State) -> f64;

    /// An upper bound on log p(`next` | x) over every x, or `None` (the default) when there is
    /// none (or it is unknown). With a bound, backward simulation uses the accept–reject sampler
    /// of Douc, Garivier, Moulines & Olsson (2011), with expected cost O(1) per trajectory and
    /// step when the bound is tight; without one it uses the exact O(N) draw. A Gaussian
    /// transition N(x_t; A x_{t−1}, Q) is bounded by −½ log det(2πQ).
    fn log_density_bound(&self, frame: usize, next: &Self::State) -> Option<f64> {
        let _ = (frame, next);
        None
    }
}

/// Any [`Dynamics`] as a [`TransitionDensity`] (time-invariant), with an optional constant bound
/// on its log-density.
///
/// # Examples
/// ```
/// use smc_core::model::{Dynamics, PriorDensity, TransitionDensity};
/// # struct Walk;
/// # impl Dynamics for Walk {
/// #     type State = f64;
/// #     fn sample<R: smc_core::rand::Rng + ?Sized>(&self, x: &f64, _: &mut R) -> f64 { *x }
/// #     fn log_density(&self, x: &f64, y: &f64) -> f64 { -0.5 * (y - x).powi(2) }
/// # }
/// let density = PriorDensity { dynamics: &Walk, log_bound: Some(0.0) };
/// assert_eq!(density.log_density(1, &0.0, &1.0), -0.5);
/// assert_eq!(density.log_density_bound(1, &1.0), Some(0.0));
/// ```
#[derive(Debug, Clone, Copy)]
pub struct PriorDensity<'a, D> {
    /// The dynamics whose [`Dynamics::log_density`] is the transition density.
    pub dynamics: &'a D,
    /// sup over (x, x′) of log p(x′ | x), if known.
    pub log_bound: Option<f64>,
}

impl<D: Dynamics> TransitionDensity for PriorDensity<'_, D> {
    type State = D::State;

    fn log_density(&self, _frame: usize, previous: &D::State, next: &D::State) -> f64 {
        self.dynamics.log_density(previous, next)
    }

    fn log_density_bound(&self, _frame: usize, _next: &D::State) -> Option<f64> {
        self.log_bound
    }
}
