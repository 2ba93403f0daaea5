//! Hidden-chain exploration: the prior as the proposal, with its hidden chains drawn from an
//! exploring transition ([`crate::DynamicsSettings::hidden_exploration`]).

use rand::Rng;

use crate::dynamics::TrackerDynamics;
use crate::particle::Particle;

/// The prior as the proposal when its hidden chains explore
/// ([`crate::DynamicsSettings::hidden_exploration`] > 0): draws as the prior does, and its density
/// is the prior's kinematic density less the exploration ratio, so that Eq. 3's weight is the
/// likelihood times `T / q` of the hidden chains. With ε = 0 the trackers use
/// [`smc_core::Bootstrap`] instead, whose densities cancel unevaluated.
#[derive(Debug, Clone, Copy)]
pub struct ExploringPrior<'a>(pub &'a TrackerDynamics);

impl smc_core::Proposal for ExploringPrior<'_> {
    type State = Particle;

    fn sample<R: Rng + ?Sized>(&self, _index: usize, previous: &Particle, rng: &mut R) -> Particle {
        smc_core::Dynamics::sample(self.0, previous, rng)
    }

    fn log_density(&self, _index: usize, previous: &Particle, next: &Particle) -> f64 {
        smc_core::Dynamics::log_density(self.0, previous, next)
            - self.0.log_hidden_exploration_ratio(previous, next)
    }
}
