//! The prior as the proposal, weighted by the ratio of what it is to what it draws from: hidden
//! chains drawn from an exploring transition ([`crate::DynamicsSettings::hidden_exploration`]),
//! and an abrupt-motion jump whose centre is a priori uniform over the search window but is
//! drawn around the appearance's detection
//! ([`crate::ReacquisitionSettings::detection_share`]).

use rand::Rng;

use crate::dynamics::TrackerDynamics;
use crate::particle::Particle;

/// The prior as the proposal when its hidden chains explore
/// ([`crate::DynamicsSettings::hidden_exploration`] > 0) or its jump is drawn from other than its
/// prior (`TrackerDynamics::jump_needs_weighting`): draws as the prior does, and its density is
/// the density it draws from (`TrackerDynamics::log_sampling_density`) less the exploration
/// ratio, so that Eq. 3's weight is the likelihood times `T / q` of the hidden chains and of the
/// jump. Otherwise the trackers use [`smc_core::Bootstrap`], whose densities cancel unevaluated.
#[derive(Debug, Clone, Copy)]
pub struct WeightedPrior<'a>(pub &'a TrackerDynamics);

impl smc_core::Proposal for WeightedPrior<'_> {
    type State = Particle;

    fn sample<R: Rng + ?Sized>(&self, _index: usize, previous: &Particle, rng: &mut R) -> Particle {
        smc_core::Dynamics::sample(self.0, previous, rng)
    }

    fn log_density(&self, _index: usize, previous: &Particle, next: &Particle) -> f64 {
        self.0.log_sampling_density(previous, next)
            - self.0.log_hidden_exploration_ratio(previous, next)
    }
}
