//! Property tests: invariants that must hold for every valid input.

use proptest::prelude::*;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

use crate::{
    ClutterConfig, ClutterHmm, ClutterState, MarkovChain, OcclusionConfig, OcclusionProcess,
    OcclusionState, StatusConfig, StatusHmm, StatusState, TrackStatus,
};

/// A random row-stochastic `n × n` matrix with strictly positive entries.
fn stochastic_matrix(n: usize) -> impl Strategy<Value = Vec<Vec<f64>>> {
    prop::collection::vec(prop::collection::vec(0.01f64..1.0, n), n).prop_map(|rows| {
        rows.into_iter()
            .map(|r| {
                let s: f64 = r.iter().sum();
                r.into_iter().map(|x| x / s).collect()
            })
            .collect()
    })
}

proptest! {
    #[test]
    fn forward_posteriors_are_distributions_and_stationary_is_fixed(
        matrix in stochastic_matrix(3),
        likelihoods in prop::collection::vec(prop::collection::vec(1e-6f64..10.0, 3), 1..20),
    ) {
        let chain = MarkovChain::new(&matrix).unwrap();
        let result = chain.forward_filter(&[1.0 / 3.0; 3], &likelihoods).unwrap();
        for p in &result.posteriors {
            prop_assert!(p.iter().all(|&x| (0.0..=1.0).contains(&x)));
            prop_assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
        prop_assert!(result.log_evidence.is_finite());
        let pi = chain.stationary().unwrap();
        let mut next = [0.0; 3];
        chain.predict_into(&pi, &mut next).unwrap();
        for (a, b) in pi.iter().zip(next) {
            prop_assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn sampled_transitions_are_in_support(seed in any::<u64>(), beta in 0usize..3, gamma in 0.0f64..=1.0) {
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let clutter = ClutterHmm::new(&ClutterConfig::default()).unwrap();
        let prev = ClutterState { beta, lambda: 0.05 };
        let next = clutter.sample_next(&prev, &mut rng);
        prop_assert!(next.beta < 3 && next.lambda > 0.0);
        prop_assert!(clutter.log_transition(&prev, &next).is_finite());

        let walk = OcclusionProcess::new(&OcclusionConfig::default()).unwrap();
        let prev = OcclusionState { gamma };
        let next = walk.sample_next(&prev, &mut rng);
        prop_assert!((0.0..=1.0).contains(&next.gamma));
        prop_assert!(walk.log_transition(&prev, &next).is_finite());

        let status = StatusHmm::new(&StatusConfig::default()).unwrap();
        let prev = StatusState { alpha: TrackStatus::ALL[beta], gamma };
        let next = status.sample_next(&prev, &mut rng);
        prop_assert!(status.range(next.alpha).contains(next.gamma));
        prop_assert!(status.log_transition(&prev, &next).is_finite());
    }
}
