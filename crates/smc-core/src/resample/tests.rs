//! Tests of the resampling schemes: exact cases and proptest invariants.

use super::*;
use crate::rng::stream_rng;
use proptest::prelude::*;

/// Every scheme, as a value.
const SCHEMES: [ResamplingScheme; 5] = ResamplingScheme::ALL;

#[test]
fn bad_inputs_are_typed_errors() {
    let mut rng = stream_rng(1, 0, 0);
    let mut out = Vec::new();
    for scheme in SCHEMES {
        assert!(matches!(
            scheme.resample(&[], 3, &mut rng, &mut out),
            Err(Error::InvalidSetting {
                name: "weights",
                ..
            })
        ));
        assert!(matches!(
            scheme.resample(&[1.0], 0, &mut rng, &mut out),
            Err(Error::InvalidSetting {
                name: "output_size",
                ..
            })
        ));
        assert_eq!(
            scheme.resample(&[0.0, 0.0], 2, &mut rng, &mut out),
            Err(Error::InvalidWeights {
                reason: Degeneracy::AllZero
            })
        );
        assert_eq!(
            scheme.resample(&[0.5, f64::NAN], 2, &mut rng, &mut out),
            Err(Error::InvalidWeights {
                reason: Degeneracy::NotANumber { index: 1 }
            })
        );
        assert_eq!(
            scheme.resample(&[0.5, -0.1, 0.6], 2, &mut rng, &mut out),
            Err(Error::InvalidWeights {
                reason: Degeneracy::OutOfRange {
                    index: 1,
                    value: -0.1
                }
            })
        );
        assert!(
            scheme
                .resample(&[0.5, f64::INFINITY], 2, &mut rng, &mut out)
                .is_err()
        );
    }
}

#[test]
fn systematic_grid_is_exact() {
    // Weights (0.1, 0.4, 0.5), M = 10, u = 0.5: grid 0.05, 0.15, …, 0.95 times 1 →
    // particle 0 gets the grid point 0.05 only, particle 1 the four in [0.1, 0.5), particle 2
    // the five in [0.5, 1).
    let mut out = Vec::new();
    Systematic
        .resample_with_offset(&[0.1, 0.4, 0.5], 10, 0.5, &mut out)
        .unwrap();
    assert_eq!(out, vec![0, 1, 1, 1, 1, 2, 2, 2, 2, 2]);
    // Unnormalised weights take the second, rescaled pass and give the same grid.
    Systematic
        .resample_with_offset(&[1.0, 4.0, 5.0], 10, 0.5, &mut out)
        .unwrap();
    assert_eq!(out, vec![0, 1, 1, 1, 1, 2, 2, 2, 2, 2]);
    // u = 0 puts the grid at 1, 2, …, 10: particle 0's interval (0, 1] holds one point.
    Systematic
        .resample_with_offset(&[0.1, 0.4, 0.5], 10, 0.0, &mut out)
        .unwrap();
    assert_eq!(out, vec![0, 1, 1, 1, 1, 2, 2, 2, 2, 2]);
}

#[test]
fn zero_weight_particles_never_get_offspring() {
    let w = [0.0, 0.3, 0.0, 0.7, 0.0];
    for scheme in SCHEMES {
        for seed in 0..200 {
            let mut rng = stream_rng(seed, 0, 0);
            let out = scheme.resample_vec(&w, 7, &mut rng).unwrap();
            assert!(out.iter().all(|&a| a == 1 || a == 3), "{scheme:?}: {out:?}");
        }
    }
}

#[test]
fn one_particle_takes_everything() {
    for scheme in SCHEMES {
        let mut rng = stream_rng(3, 0, 0);
        let out = scheme.resample_vec(&[0.0, 1.0, 0.0], 5, &mut rng).unwrap();
        assert_eq!(out, vec![1; 5], "{scheme:?}");
    }
}

#[test]
fn multinomial_counts_have_binomial_variance() {
    // Systematic-like schemes have variance ≤ 1/4; multinomial must show Binomial(M, w)
    // variance M w (1 − w). With w = 0.3, M = 20: 4.2. Over 4000 draws the sample variance
    // has relative standard error ≈ sqrt(2/4000) ≈ 2.2 %, so ±15 % is a 6-sigma bound that a
    // scheme with the wrong law (e.g. stratified, variance ≤ 0.5) cannot meet.
    let w = [0.3, 0.7];
    let draws = 4000;
    let mut counts = Vec::with_capacity(draws);
    for seed in 0..draws as u64 {
        let mut rng = stream_rng(seed, 1, 2);
        let out = Multinomial.resample_vec(&w, 20, &mut rng).unwrap();
        counts.push(out.iter().filter(|&&a| a == 0).count() as f64);
    }
    let mean = counts.iter().sum::<f64>() / draws as f64;
    let var = counts.iter().map(|c| (c - mean).powi(2)).sum::<f64>() / (draws - 1) as f64;
    assert!((mean - 6.0).abs() < 0.2, "mean {mean}");
    assert!((var / 4.2 - 1.0).abs() < 0.15, "variance {var}");
}

#[test]
fn multinomial_output_is_sorted() {
    // Sorted uniforms merged with the cumulative weights give sorted ancestors: a cheap check that
    // the exponential spacings are increasing and the merge is monotone.
    let w: Vec<f64> = (1..=50).map(f64::from).collect();
    let mut rng = stream_rng(9, 9, 9);
    let out = Multinomial.resample_vec(&w, 500, &mut rng).unwrap();
    assert!(out.windows(2).all(|p| p[0] <= p[1]));
}

/// Weights with a few exact zeros and a wide dynamic range.
fn weights_strategy(max_len: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(
        prop_oneof![1 => Just(0.0), 6 => 0.0f64..1.0, 1 => 0.0f64..1e-6],
        1..max_len,
    )
    .prop_filter("some positive weight", |w| w.iter().any(|&x| x > 0.0))
    .prop_map(|w| {
        let total: f64 = w.iter().sum();
        w.into_iter().map(|x| x / total).collect()
    })
}

/// Rounding slack for the floor/ceil bounds: cumulative sums of up to 300 terms carry a relative
/// error of order 300·ε ≈ 7e-14, times M ≤ 1000, far below 1e-9.
const SLACK: f64 = 1e-9;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Every scheme returns exactly M indices, all in range, so offspring counts sum to M.
    #[test]
    fn offspring_counts_sum_to_output_size(
        w in weights_strategy(300), m in 1usize..1000, seed in any::<u64>())
    {
        for scheme in SCHEMES {
            let mut rng = stream_rng(seed, 0, 0);
            let out = scheme.resample_vec(&w, m, &mut rng).unwrap();
            prop_assert_eq!(out.len(), m);
            let counts = offspring_counts(&out, w.len());
            prop_assert_eq!(counts.iter().sum::<usize>(), m, "{:?}", scheme);
        }
    }

    /// The count bounds each scheme guarantees (see the module table): systematic and SSP
    /// ⌊M w⌋..⌈M w⌉, stratified ⌊M w⌋ − 1..⌈M w⌉ + 1, residual at least ⌊M w⌋.
    #[test]
    fn offspring_counts_respect_scheme_bounds(
        w in weights_strategy(300), m in 1usize..1000, seed in any::<u64>())
    {
        let mut rng = stream_rng(seed, 0, 0);
        let n = w.len();
        let sys = offspring_counts(&Systematic.resample_vec(&w, m, &mut rng).unwrap(), n);
        let strat = offspring_counts(&Stratified.resample_vec(&w, m, &mut rng).unwrap(), n);
        let res = offspring_counts(&Residual.resample_vec(&w, m, &mut rng).unwrap(), n);
        let ssp = offspring_counts(&Ssp.resample_vec(&w, m, &mut rng).unwrap(), n);
        for i in 0..n {
            let expected = m as f64 * w[i];
            let lo = (expected - SLACK).floor();
            let hi = (expected + SLACK).ceil();
            let (s, t, r, p) = (sys[i] as f64, strat[i] as f64, res[i] as f64, ssp[i] as f64);
            prop_assert!(lo <= p && p <= hi, "ssp: particle {} count {} vs M w = {}", i, p, expected);
            prop_assert!(lo <= s && s <= hi, "systematic: particle {} count {} vs M w = {}", i, s, expected);
            prop_assert!(lo - 1.0 <= t && t <= hi + 1.0, "stratified: particle {} count {} vs M w = {}", i, t, expected);
            prop_assert!(lo <= r, "residual: particle {} count {} vs M w = {}", i, r, expected);
        }
    }

    /// Unbiasedness: over R = 2000 independent draws the mean count of particle i is M wᵢ.
    /// Its standard error is at most sqrt(max(M wᵢ(1 − wᵢ), 1/4) / R): M wᵢ(1 − wᵢ) is the
    /// multinomial variance (residual and stratified are no larger) and 1/4 bounds the variance
    /// of any count taking two adjacent values (systematic, SSP). The bound allows 6 standard errors
    /// plus 1e-9, so a false alarm has probability ~1e-9 per comparison.
    #[test]
    fn mean_offspring_count_is_m_w(
        w in weights_strategy(12), m in 1usize..60, seed in any::<u64>())
    {
        let draws = 2000u64;
        let n = w.len();
        let mut out = Vec::with_capacity(m);
        for scheme in SCHEMES {
            let mut totals = vec![0usize; n];
            for r in 0..draws {
                let mut rng = stream_rng(seed, r, 1);
                scheme.resample(&w, m, &mut rng, &mut out).unwrap();
                for &a in &out {
                    totals[a] += 1;
                }
            }
            for i in 0..n {
                let expected = m as f64 * w[i];
                let mean = totals[i] as f64 / draws as f64;
                let var = (expected * (1.0 - w[i])).max(0.25);
                let tol = 6.0 * (var / draws as f64).sqrt() + 1e-9;
                prop_assert!((mean - expected).abs() <= tol,
                    "{:?}: particle {} mean {} vs M w = {} (tol {})", scheme, i, mean, expected, tol);
            }
        }
    }
}
