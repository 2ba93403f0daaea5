//! The particle smoothers against RTS, and fixed-lag smoothing.

use smc_core::model::FnObservation;
use smc_core::rng::stream_rng;
use smc_core::smooth::{BackwardMethod, SmootherSettings, fixed_lag_weights};
use smc_core::{
    FilterSettings, HistorySettings, ParticleFilter, ParticleSet, ResamplingScheme,
    sample_trajectories, smooth_marginals,
};

use super::models::*;

// ---------------------------------------------------------------------------------------------
// Accuracy against RTS.

#[test]
fn ffbsm_matches_rts_in_1d() {
    // Measured over 20 seeds at N = 500, 25 steps: worst mean error 0.186 ± 0.072 σ (largest
    // 0.348), RMS 0.068 ± 0.013 σ; worst relative variance error 0.241 ± 0.111 (largest 0.599),
    // RMS 0.082 ± 0.020. The unsmoothed filter: RMS mean error 0.511 ± 0.011 σ.
    for seed in SEEDS {
        check(
            "FFBSm 1-D",
            errors_1d(seed, Method::Ffbsm),
            0.52,
            0.13,
            0.75,
            0.18,
        );
    }
    let control = errors_1d(SEEDS[0], Method::Filter);
    assert!(
        control.rms_mean > 0.4,
        "the filter alone should miss: {control:?}"
    );
}

#[test]
fn ffbs_matches_rts_in_1d_with_both_backward_draws() {
    // Measured over 20 seeds at N = M = 500, 25 steps, exact draw: worst mean error
    // 0.197 ± 0.059 σ (largest 0.362), RMS 0.077 ± 0.011 σ; worst relative variance error
    // 0.263 ± 0.097 (largest 0.572), RMS 0.102 ± 0.019. Accept–reject: 0.216 ± 0.067 (0.345),
    // 0.081 ± 0.013; 0.257 ± 0.093 (0.557), 0.101 ± 0.018.
    for seed in SEEDS {
        check(
            "FFBS exact 1-D",
            errors_1d(seed, Method::FfbsExact),
            0.55,
            0.14,
            0.75,
            0.2,
        );
        check(
            "FFBS reject 1-D",
            errors_1d(seed, Method::FfbsRejection),
            0.55,
            0.14,
            0.75,
            0.2,
        );
    }
}

#[test]
fn ffbsm_matches_rts_in_2d() {
    // Constant velocity, position observed, adaptive resampling. Measured over 20 seeds at
    // N = 500, 25 steps, per coordinate: worst mean error 0.274 ± 0.061 σ (largest 0.354), RMS
    // 0.122 ± 0.022 σ; worst relative variance error 0.344 ± 0.074 (largest 0.538), RMS
    // 0.130 ± 0.023. The unsmoothed filter: RMS variance error 1.85 ± 0.04.
    for seed in SEEDS {
        check(
            "FFBSm 2-D",
            errors_2d(seed, Method::Ffbsm),
            0.55,
            0.23,
            0.7,
            0.24,
        );
    }
    let control = errors_2d(SEEDS[0], Method::Filter);
    assert!(
        control.rms_var > 1.5,
        "the filter alone should miss: {control:?}"
    );
}

#[test]
fn ffbs_matches_rts_in_2d_with_both_backward_draws() {
    // Measured over 20 seeds at N = M = 500, 25 steps, exact draw: worst mean error
    // 0.294 ± 0.065 σ (largest 0.425), RMS 0.128 ± 0.021 σ; worst relative variance error
    // 0.389 ± 0.080 (largest 0.529), RMS 0.149 ± 0.023. Accept–reject with a budget of 10
    // proposals (many draws fell back to the exact draw: the transition is narrow beside the
    // filter's spread): 0.298 ± 0.056 (0.386), 0.132 ± 0.024; 0.392 ± 0.107 (0.645),
    // 0.145 ± 0.031. The draw is exact whatever the budget, so the same spread applies to the
    // default budget used here.
    for seed in SEEDS {
        check(
            "FFBS exact 2-D",
            errors_2d(seed, Method::FfbsExact),
            0.6,
            0.25,
            0.9,
            0.29,
        );
        check(
            "FFBS reject 2-D",
            errors_2d(seed, Method::FfbsRejection),
            0.6,
            0.25,
            0.9,
            0.29,
        );
    }
}

#[test]
fn rejection_sampler_accepts_and_falls_back_within_its_budget() {
    let zs = simulate_1d();
    let mut filter = filter_1d(500, 9, &zs, filter_settings(1.0, false));
    let history = filter.take_history().unwrap();
    for max_rejections in [Some(1), Some(10), None] {
        let settings = SmootherSettings {
            backward: BackwardMethod::Rejection,
            max_rejections,
            ..SmootherSettings::default()
        };
        let paths = sample_trajectories(&history, &AR1, 500, 3, &settings).unwrap();
        let s = paths.stats();
        assert_eq!(s.draws, 500 * (STEPS as u64 - 1));
        assert_eq!(s.accepted + s.exact, s.draws);
        // A budget of one or ten proposals leaves some draws to the exact fallback.
        assert!(s.accepted > 0, "{s:?}");
        assert!(max_rejections.is_none() || s.exact > 0, "{s:?}");
        assert!(s.proposals <= max_rejections.unwrap_or(500) as u64 * s.draws);
    }
    let exact = SmootherSettings {
        backward: BackwardMethod::Exact,
        ..SmootherSettings::default()
    };
    let s = sample_trajectories(&history, &AR1, 500, 3, &exact)
        .unwrap()
        .stats();
    assert_eq!((s.proposals, s.exact), (0, s.draws));
}

// ---------------------------------------------------------------------------------------------
// Fixed lag.

#[test]
fn fixed_lag_on_a_bounded_history_matches_rts_given_the_data_so_far() {
    // The filter keeps the last L + 1 = 6 frames. After the first k + 1 observations, the
    // fixed-lag weights of frame k − 5 are FFBSm given z_{0:k}, whose exact value is the RTS
    // smoother run on z_{0:k}. Tolerances as for FFBSm in 1-D (worst and RMS, here over the
    // 20 windows of one run in place of the steps of one smoothing).
    let lag = 5;
    let zs = simulate_1d();
    let settings = FilterSettings {
        history: Some(HistorySettings {
            max_frames: Some(lag + 1),
        }),
        ..FilterSettings::default()
    };
    let mut init = stream_rng(21, u64::MAX, 0);
    let states = (0..N).map(|_| M0 + P0.sqrt() * gauss(&mut init)).collect();
    let mut set = ParticleSet::from_states(states).unwrap();
    let mut filter = ParticleFilter::new(settings).unwrap();
    let mut checked = 0;
    let mut sum_sq = [0.0; 2];
    for (k, &z) in zs.iter().enumerate() {
        let obs = FnObservation::new(move |x: &f64| normal_log_pdf(z, *x, R_1D));
        filter
            .step_bootstrap(
                &mut set,
                &AR1,
                &obs,
                &ResamplingScheme::Systematic,
                21,
                k as u64,
            )
            .unwrap();
        let history = filter.history().unwrap();
        assert!(history.len() <= lag + 1);
        let (t, w) = fixed_lag_weights(history, &AR1, lag, &SmootherSettings::default()).unwrap();
        if k < lag {
            assert_eq!(t, 0);
            continue;
        }
        assert_eq!(t, 0);
        assert_eq!(history.frame(0).unwrap().step, (k - lag) as u64);
        let (mean, var, _) = rts_1d(&zs[..=k]);
        let states = history.frame(0).unwrap().set.states();
        let m: f64 = states.iter().zip(&w).map(|(x, w)| x * w).sum();
        let v: f64 = states
            .iter()
            .zip(&w)
            .map(|(x, w)| w * (x - m).powi(2))
            .sum();
        let exact_m = mean[k - lag][0];
        let exact_v = var[k - lag][0];
        let (z, r) = ((m - exact_m) / exact_v.sqrt(), v / exact_v - 1.0);
        assert!(z.abs() < 0.52, "step {k}: mean {m} vs {exact_m}");
        assert!(r.abs() < 0.75, "step {k}: variance {v} vs {exact_v}");
        sum_sq[0] += z * z;
        sum_sq[1] += r * r;
        checked += 1;
    }
    assert_eq!(checked, STEPS - lag);
    let rms = sum_sq.map(|s| (s / checked as f64).sqrt());
    assert!(rms[0] < 0.13 && rms[1] < 0.18, "RMS errors {rms:?}");
}

#[test]
fn fixed_lag_over_the_whole_history_is_the_full_smoother() {
    let zs = simulate_1d();
    let mut filter = filter_1d(300, 5, &zs, filter_settings(1.0, false));
    let history = filter.take_history().unwrap();
    let settings = SmootherSettings::default();
    let full = smooth_marginals(&history, &AR1, &settings).unwrap();
    for lag in [0, 3, STEPS - 1, STEPS + 10] {
        let (t, w) = fixed_lag_weights(&history, &AR1, lag, &settings).unwrap();
        assert_eq!(t, (STEPS - 1).saturating_sub(lag));
        assert_eq!(Some(w.as_slice()), full.weights(t));
    }
}
