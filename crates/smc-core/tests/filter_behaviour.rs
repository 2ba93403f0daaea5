//! Behaviour of a filter step: settings validation, degenerate weights as typed errors at the step
//! where they appear, output sizes, the pieces API and the diagnostics.

use rand::Rng;
use smc_core::model::{Dynamics, FnObservation};
use smc_core::{
    Degeneracy, Error, FilterSettings, ParticleFilter, ParticleSet, ResamplingScheme, Systematic,
};

/// Deterministic dynamics x ← x + 1 plus a uniform jitter in [0, 1).
struct Shift;

impl Dynamics for Shift {
    type State = f64;
    fn sample<R: Rng + ?Sized>(&self, x: &f64, rng: &mut R) -> f64 {
        x + 1.0 + rng.random::<f64>()
    }
    fn log_density(&self, x: &f64, y: &f64) -> f64 {
        if (0.0..1.0).contains(&(y - x - 1.0)) {
            0.0
        } else {
            f64::NEG_INFINITY
        }
    }
}

fn set(n: usize) -> ParticleSet<f64> {
    ParticleSet::from_states((0..n).map(|i| i as f64).collect()).unwrap()
}

#[test]
fn invalid_settings_are_typed_errors() {
    for (settings, name) in [
        (
            FilterSettings {
                resample_threshold: 0.0,
                ..Default::default()
            },
            "resample_threshold",
        ),
        (
            FilterSettings {
                resample_threshold: 1.5,
                ..Default::default()
            },
            "resample_threshold",
        ),
        (
            FilterSettings {
                resample_threshold: f64::NAN,
                ..Default::default()
            },
            "resample_threshold",
        ),
        (
            FilterSettings {
                output_size: Some(0),
                ..Default::default()
            },
            "output_size",
        ),
        (
            FilterSettings {
                parallel_min_chunk: 0,
                ..Default::default()
            },
            "parallel_min_chunk",
        ),
    ] {
        match ParticleFilter::<f64>::new(settings) {
            Err(Error::InvalidSetting { name: got, .. }) => assert_eq!(got, name),
            other => panic!("expected InvalidSetting({name}), got {other:?}"),
        }
    }
    assert!(FilterSettings::default().validate().is_ok());
}

#[test]
fn a_nan_likelihood_is_an_error_at_its_step() {
    let mut s = set(50);
    let mut filter = ParticleFilter::new(FilterSettings::default()).unwrap();
    for k in 0..5u64 {
        // From step 3 on every likelihood is NaN, so the first offending particle is 0.
        let obs = FnObservation::new(move |x: &f64| {
            if k >= 3 && *x >= 0.0 {
                f64::NAN
            } else {
                -x.abs()
            }
        });
        let r = filter.step_bootstrap(&mut s, &Shift, &obs, &Systematic, 1, k);
        if k < 3 {
            let d = r.unwrap();
            assert!(d.log_evidence_increment.is_finite());
        } else {
            assert_eq!(
                r,
                Err(Error::DegenerateWeights {
                    step: 3,
                    reason: Degeneracy::NotANumber { index: 0 }
                })
            );
            // The weights are still a valid distribution.
            assert!(s.weights().iter().all(|w| w.is_finite()));
            break;
        }
    }
}

#[test]
fn all_zero_and_infinite_likelihoods_are_errors() {
    let mut filter = ParticleFilter::new(FilterSettings::default()).unwrap();
    let zero = FnObservation::new(|_: &f64| f64::NEG_INFINITY);
    assert_eq!(
        filter.step_bootstrap(&mut set(10), &Shift, &zero, &Systematic, 1, 9),
        Err(Error::DegenerateWeights {
            step: 9,
            reason: Degeneracy::AllZero
        })
    );
    let inf = FnObservation::new(|x: &f64| if *x > 5.0 { f64::INFINITY } else { 0.0 });
    assert!(matches!(
        filter.step_bootstrap(&mut set(10), &Shift, &inf, &Systematic, 1, 4),
        Err(Error::DegenerateWeights {
            step: 4,
            reason: Degeneracy::PositiveInfinity { .. }
        })
    ));
}

#[test]
fn output_size_changes_the_number_of_particles() {
    let settings = FilterSettings {
        output_size: Some(250),
        ..Default::default()
    };
    let mut filter = ParticleFilter::new(settings).unwrap();
    let mut s = set(100);
    let obs = FnObservation::new(|x: &f64| -0.1 * x);
    let d = filter
        .step_bootstrap(&mut s, &Shift, &obs, &ResamplingScheme::Residual, 3, 0)
        .unwrap();
    assert_eq!(s.len(), 250);
    assert_eq!(filter.ancestors().len(), 250);
    assert!(d.resampled);
    // Uniform weights in, uniform out: every one of the 100 particles survives (residual
    // resampling gives each at least ⌊250/100⌋ = 2 copies).
    assert_eq!(d.distinct_ancestors, 100);
}

#[test]
fn adaptive_threshold_skips_resampling_when_ess_is_high() {
    let settings = FilterSettings {
        resample_threshold: 0.5,
        ..Default::default()
    };
    let mut filter = ParticleFilter::new(settings).unwrap();
    let mut s = set(100);
    // A flat likelihood keeps the weights uniform: ESS = N, never below N/2.
    let flat = FnObservation::new(|_: &f64| 0.0);
    for k in 0..3 {
        let d = filter
            .step_bootstrap(&mut s, &Shift, &flat, &Systematic, 3, k)
            .unwrap();
        assert!(!d.resampled);
        assert_eq!(d.distinct_ancestors, 100);
        assert!((d.ess - 100.0).abs() < 1e-9);
        assert!(d.log_evidence_increment.abs() < 1e-12);
    }
    assert_eq!(filter.ancestors(), (0..100).collect::<Vec<_>>().as_slice());
    // One particle takes nearly all the mass: ESS ≈ 1, so the next step resamples and only a few
    // ancestors survive.
    let sharp = FnObservation::new(|x: &f64| -1000.0 * (x - 53.5).powi(2));
    let d = filter
        .step_bootstrap(&mut s, &Shift, &sharp, &Systematic, 3, 3)
        .unwrap();
    assert!(!d.resampled);
    assert!(d.max_weight > 0.5, "max weight {}", d.max_weight);
    assert!(d.ess_after < 2.0);
    let d = filter
        .step_bootstrap(&mut s, &Shift, &flat, &Systematic, 3, 4)
        .unwrap();
    assert!(d.resampled);
    assert!(d.ess < 2.0);
    assert!(
        d.distinct_ancestors <= 3,
        "{} distinct",
        d.distinct_ancestors
    );
}

#[test]
fn pieces_compose_to_the_whole_step() {
    // Resample, propagate, then weight with caller-computed likelihoods and the prior/proposal
    // ratio: the same as `step` with the same seed, bit for bit.
    let obs = FnObservation::new(|x: &f64| -0.5 * (x - 20.0).powi(2) / 9.0);
    let mut whole = set(200);
    let mut f1 = ParticleFilter::new(FilterSettings::default()).unwrap();
    let mut pieces = whole.clone();
    let mut f2 = ParticleFilter::new(FilterSettings::default()).unwrap();
    let proposal = smc_core::Bootstrap(&Shift);
    for k in 0..4 {
        let d = f1
            .step(&mut whole, &proposal, Some(&Shift), &obs, &Systematic, 8, k)
            .unwrap();
        let r = f2
            .resample_if_needed(&mut pieces, &Systematic, 8, k)
            .unwrap();
        f2.propagate(&mut pieces, &proposal, 8, k);
        let ll: Vec<f64> = pieces
            .states()
            .iter()
            .map(|x| -0.5 * (x - 20.0).powi(2) / 9.0)
            .collect();
        let w = f2
            .weight_with_log_likelihoods(&mut pieces, &proposal, Some(&Shift), &ll, k)
            .unwrap();
        assert_eq!(r.ess, d.ess);
        assert_eq!(w.log_evidence_increment, d.log_evidence_increment);
        assert_eq!(whole, pieces);
        assert_eq!(f1.previous_states(), f2.previous_states());
    }
    // With the prior given explicitly and equal to the proposal, the ratio is exactly 1, so the
    // weights equal the bootstrap ones.
    let mut boot = set(200);
    let mut f3 = ParticleFilter::new(FilterSettings::default()).unwrap();
    for k in 0..4 {
        f3.step_bootstrap(&mut boot, &Shift, &obs, &Systematic, 8, k)
            .unwrap();
    }
    assert_eq!(boot, whole);
}

#[test]
fn wrong_lengths_are_errors() {
    let mut filter = ParticleFilter::new(FilterSettings::default()).unwrap();
    let mut s = set(10);
    let proposal = smc_core::Bootstrap(&Shift);
    assert!(matches!(
        filter.weight_with_log_likelihoods(&mut s, &proposal, None::<&Shift>, &[0.0; 9], 0),
        Err(Error::LengthMismatch { .. })
    ));
    // A prior needs the previous states, which only `propagate` provides.
    assert!(matches!(
        filter.weight_with_log_likelihoods(&mut s, &proposal, Some(&Shift), &[0.0; 10], 0),
        Err(Error::LengthMismatch { .. })
    ));
}

#[test]
fn a_tempered_step_keeps_the_ess_floor_and_tempers_the_likelihood_only() {
    // A likelihood so sharp that untempered weights sit on a handful of particles.
    let obs = FnObservation::new(|x: &f64| -0.5 * (x - 40.0).powi(2) / 0.01);
    for seed in [1, 2, 3] {
        let settings = FilterSettings {
            min_ess_fraction: Some(0.3),
            ..FilterSettings::default()
        };
        let mut tempered_set = set(200);
        let mut tempered = ParticleFilter::new(settings.clone()).unwrap();
        let mut plain_set = set(200);
        let mut plain = ParticleFilter::new(FilterSettings::default()).unwrap();
        for k in 0..3 {
            let d = tempered
                .step_bootstrap(&mut tempered_set, &Shift, &obs, &Systematic, seed, k)
                .unwrap();
            let p = plain
                .step_bootstrap(&mut plain_set, &Shift, &obs, &Systematic, seed, k)
                .unwrap();
            assert!(d.ess_after >= 0.3 * 200.0 * (1.0 - 1e-9), "{d:?}");
            assert!(
                p.ess_after < 0.3 * 200.0,
                "the test needs a sharp likelihood: {p:?}"
            );
            assert!(
                d.tempering_exponent > 0.0 && d.tempering_exponent < 1.0,
                "{d:?}"
            );
            assert_eq!(p.tempering_exponent, 1.0);
            // The weights are the likelihood raised to φ, normalised.
            let mut expected: Vec<f64> = tempered_set
                .states()
                .iter()
                .map(|x| d.tempering_exponent * -0.5 * (x - 40.0).powi(2) / 0.01)
                .collect();
            let mut w = Vec::new();
            smc_core::weights::normalize_log_weights(&mut expected, &mut w).unwrap();
            for (a, b) in w.iter().zip(tempered_set.weights()) {
                assert!((a - b).abs() < 1e-12, "{a} vs {b}");
            }
        }
    }
    // A likelihood that keeps the floor is not tempered: the same set as without the setting.
    let flat = FnObservation::new(|x: &f64| -0.5 * (x - 40.0).powi(2) / 1e4);
    let (mut a, mut b) = (set(100), set(100));
    let settings = FilterSettings {
        min_ess_fraction: Some(0.3),
        ..FilterSettings::default()
    };
    let mut fa = ParticleFilter::new(settings).unwrap();
    let mut fb = ParticleFilter::new(FilterSettings::default()).unwrap();
    let da = fa
        .step_bootstrap(&mut a, &Shift, &flat, &Systematic, 4, 0)
        .unwrap();
    fb.step_bootstrap(&mut b, &Shift, &flat, &Systematic, 4, 0)
        .unwrap();
    assert_eq!(da.tempering_exponent, 1.0);
    assert_eq!(a, b);
    for bad in [0.0, -0.1, 1.5, f64::NAN] {
        let settings = FilterSettings {
            min_ess_fraction: Some(bad),
            ..FilterSettings::default()
        };
        assert!(ParticleFilter::<f64>::new(settings).is_err(), "{bad}");
    }
}
