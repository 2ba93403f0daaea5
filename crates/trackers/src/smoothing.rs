//! Offline smoothing of a recorded run: every frame's estimate given the whole sequence.
//!
//! A filter decides at frame t from frames 0..=t; on recorded video the frames after t are
//! available too. With [`smc_core::FilterSettings::history`] set, a [`crate::ParticleTracker`]
//! records its weighted particles; [`Tracker::smoothed`](crate::Tracker::smoothed) then reweights
//! them by forward filtering–backward smoothing ([`smc_core::smooth`], Eq. S1–S2 there) and
//! summarises each frame exactly as the filter does (pose, β̂ and its class probabilities, λ̂,
//! γ̂, α̂ and its probabilities).
//!
//! The transition density is the tracker's prior ([`PriorTransition`]), evaluated for any pair
//! of particles whatever proposal drew them:
//! - the kinematics: the AR2 prediction from the earlier particle's current and previous states,
//!   with its Gaussian or Cauchy noise, as the density of the later particle's current state. The
//!   later particle's own previous state (a copy of its ancestor's) is left out: with it the
//!   second-order transition is a point mass and only a particle's own ancestor could precede it,
//!   which is no smoothing at all;
//! - the hidden processes: the {β, λ} HMM, the γ random walk, or the status HMM {α, γ}.
//!
//! The reacquisition jump and the shape anchor, which depend on the run's state at each frame,
//! are not part of the density.

use smc_core::TransitionDensity;

use crate::dynamics::TrackerDynamics;
use crate::particle::Particle;

/// A tracker's prior as the smoothers' transition density (see the module docs).
#[derive(Debug, Clone)]
pub struct PriorTransition {
    dynamics: TrackerDynamics,
}

impl PriorTransition {
    /// The prior of `dynamics`, without the run-time reacquisition jump and shape anchor.
    pub fn new(dynamics: &TrackerDynamics) -> Self {
        let mut dynamics = dynamics.clone();
        dynamics.reacquisition = None;
        dynamics.shape_anchor = None;
        Self { dynamics }
    }
}

impl TransitionDensity for PriorTransition {
    type State = Particle;

    fn log_density(&self, _frame: usize, previous: &Particle, next: &Particle) -> f64 {
        self.dynamics.log_transition(previous, next)
    }
}
