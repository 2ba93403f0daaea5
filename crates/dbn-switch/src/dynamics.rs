//! The processes as [`smc_core::Dynamics`], so that smc-core filters can propagate them directly
//! or compose them with a target state. Each impl forwards to the inherent `sample_next` and
//! `log_transition`, whose documentation states how atoms and truncations are handled.

use rand::Rng;
use smc_core::Dynamics;

use crate::clutter::{ClutterHmm, ClutterState};
use crate::occlusion::{OcclusionProcess, OcclusionState};
use crate::status::{StatusHmm, StatusState};

impl Dynamics for ClutterHmm {
    type State = ClutterState;

    fn sample<R: Rng + ?Sized>(&self, previous: &ClutterState, rng: &mut R) -> ClutterState {
        self.sample_next(previous, rng)
    }

    fn log_density(&self, previous: &ClutterState, next: &ClutterState) -> f64 {
        self.log_transition(previous, next)
    }
}

impl Dynamics for OcclusionProcess {
    type State = OcclusionState;

    fn sample<R: Rng + ?Sized>(&self, previous: &OcclusionState, rng: &mut R) -> OcclusionState {
        self.sample_next(previous, rng)
    }

    fn log_density(&self, previous: &OcclusionState, next: &OcclusionState) -> f64 {
        self.log_transition(previous, next)
    }
}

impl Dynamics for StatusHmm {
    type State = StatusState;

    fn sample<R: Rng + ?Sized>(&self, previous: &StatusState, rng: &mut R) -> StatusState {
        self.sample_next(previous, rng)
    }

    fn log_density(&self, previous: &StatusState, next: &StatusState) -> f64 {
        self.log_transition(previous, next)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ClutterConfig, OcclusionConfig, StatusConfig};
    use rand::SeedableRng;
    use rand_pcg::Pcg64Mcg;

    /// Through the trait, a process behaves exactly as through its inherent methods: the same
    /// seed gives the same draws, and the density is the same function.
    fn same_through_trait<D: Dynamics>(
        process: &D,
        start: D::State,
        inherent_sample: impl Fn(&D::State, &mut Pcg64Mcg) -> D::State,
        inherent_log: impl Fn(&D::State, &D::State) -> f64,
    ) where
        D::State: PartialEq + std::fmt::Debug,
    {
        let mut a = Pcg64Mcg::seed_from_u64(99);
        let mut b = Pcg64Mcg::seed_from_u64(99);
        let mut state = start;
        for _ in 0..100 {
            let via_trait = process.sample(&state, &mut a);
            let direct = inherent_sample(&state, &mut b);
            assert_eq!(via_trait, direct);
            let l = process.log_density(&state, &via_trait);
            assert!(l.is_finite());
            assert_eq!(l.to_bits(), inherent_log(&state, &via_trait).to_bits());
            state = via_trait;
        }
    }

    #[test]
    fn dynamics_impls_forward_to_the_inherent_methods() {
        let clutter = ClutterHmm::new(&ClutterConfig::default()).unwrap();
        same_through_trait(
            &clutter,
            ClutterState {
                beta: 0,
                lambda: 0.01,
            },
            |s, r| clutter.sample_next(s, r),
            |p, n| clutter.log_transition(p, n),
        );
        let walk = OcclusionProcess::new(&OcclusionConfig::default()).unwrap();
        same_through_trait(
            &walk,
            walk.initial(),
            |s, r| walk.sample_next(s, r),
            |p, n| walk.log_transition(p, n),
        );
        let status = StatusHmm::new(&StatusConfig::default()).unwrap();
        let start = status.sample_initial(&mut Pcg64Mcg::seed_from_u64(1));
        same_through_trait(
            &status,
            start,
            |s, r| status.sample_next(s, r),
            |p, n| status.log_transition(p, n),
        );
    }
}
