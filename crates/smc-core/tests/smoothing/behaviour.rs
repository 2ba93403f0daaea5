//! Determinism, recording, bad input and histories whose particle count changes.

use smc_core::model::TransitionDensity;
use smc_core::smooth::{BackwardMethod, SmootherSettings, fixed_lag_weights};
use smc_core::{
    Error, FilterSettings, History, HistorySettings, ParticleSet, sample_trajectories,
    smooth_marginals,
};

use super::models::*;

// ---------------------------------------------------------------------------------------------
// Determinism.

/// Everything the smoothers produce, as bits.
fn smoothed_bits(parallel: bool) -> (Vec<u64>, Vec<Vec<usize>>, Vec<u64>) {
    let (mut filter, _) = filter_2d(400, 8, filter_settings(0.5, parallel));
    let history = filter.take_history().unwrap();
    let settings = SmootherSettings {
        parallel,
        block_columns: 64,
        parallel_min_chunk: 8,
        ..SmootherSettings::default()
    };
    let model = ConstantVelocity::new();
    let marginals = smooth_marginals(&history, &model, &settings).unwrap();
    let weights = (0..history.len())
        .flat_map(|t| marginals.weights(t).unwrap().to_vec())
        .map(f64::to_bits)
        .collect();
    let paths = sample_trajectories(&history, &model, 300, 4, &settings).unwrap();
    let indices = (0..paths.frames())
        .map(|t| paths.indices(t).unwrap().to_vec())
        .collect();
    let filtered = history
        .frames()
        .flat_map(|f| f.set.log_weights().to_vec())
        .map(f64::to_bits)
        .collect();
    (weights, indices, filtered)
}

#[test]
fn smoothing_is_bit_identical_for_any_thread_count() {
    let reference = smoothed_bits(false);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        assert!(
            pool.install(|| smoothed_bits(true)) == reference,
            "{threads} threads"
        );
        assert!(
            pool.install(|| smoothed_bits(false)) == reference,
            "{threads} threads"
        );
    }
}

#[test]
fn the_seed_decides_the_trajectories() {
    let zs = simulate_1d();
    let mut filter = filter_1d(200, 1, &zs, filter_settings(1.0, false));
    let history = filter.take_history().unwrap();
    let s = SmootherSettings::default();
    let a = sample_trajectories(&history, &AR1, 50, 1, &s).unwrap();
    let b = sample_trajectories(&history, &AR1, 50, 1, &s).unwrap();
    let c = sample_trajectories(&history, &AR1, 50, 2, &s).unwrap();
    assert_eq!(a, b);
    assert_ne!(a.indices(0), c.indices(0));
    let path = a.path(&history, 7).unwrap();
    assert_eq!(path.len(), STEPS);
    assert_eq!(
        path[3],
        history.frame(3).unwrap().set.states()[a.indices(3).unwrap()[7]]
    );
}

// ---------------------------------------------------------------------------------------------
// Recording.

#[test]
fn the_filter_records_only_when_asked() {
    let zs = simulate_1d();
    let mut off = filter_1d(50, 1, &zs, FilterSettings::default());
    assert!(off.history().is_none() && off.take_history().is_none());

    // Adaptive resampling: frames after a step that did not resample have identity ancestors.
    let mut on = filter_1d(50, 1, &zs, filter_settings(0.5, false));
    let history = on.take_history().unwrap();
    assert_eq!(history.len(), STEPS);
    assert_eq!(on.history().map(History::len), Some(0));
    let mut identity = 0;
    for (k, frame) in history.frames().enumerate() {
        assert_eq!(frame.step, k as u64);
        let a = frame.ancestors.as_ref().unwrap();
        assert_eq!(a.len(), 50);
        if a.iter().enumerate().all(|(i, &p)| i == p) {
            identity += 1;
        }
    }
    assert!(identity > 0 && identity < STEPS);
    let line = history.ancestral_line(10).unwrap();
    assert_eq!((line.len(), line[STEPS - 1]), (STEPS, 10));
}

// ---------------------------------------------------------------------------------------------
// Bad input.

/// A transition density that returns a fixed value, to provoke each error.
struct Constant(f64, Option<f64>);

impl TransitionDensity for Constant {
    type State = f64;
    fn log_density(&self, _frame: usize, _x: &f64, _y: &f64) -> f64 {
        self.0
    }
    fn log_density_bound(&self, _frame: usize, _y: &f64) -> Option<f64> {
        self.1
    }
}

fn small_history() -> History<f64> {
    let mut h = History::new(HistorySettings::default()).unwrap();
    h.push(0, ParticleSet::from_states(vec![0.0, 1.0]).unwrap(), None)
        .unwrap();
    h.push(
        1,
        ParticleSet::from_states(vec![0.5, 1.5, 2.5]).unwrap(),
        Some(vec![0, 1, 1]),
    )
    .unwrap();
    h
}

#[test]
fn an_empty_history_is_an_error() {
    let s = SmootherSettings::default();
    let empty = History::<f64>::new(HistorySettings::default()).unwrap();
    assert_eq!(smooth_marginals(&empty, &AR1, &s), Err(Error::EmptyHistory));
    assert_eq!(
        sample_trajectories(&empty, &AR1, 5, 0, &s),
        Err(Error::EmptyHistory)
    );
    assert_eq!(
        fixed_lag_weights(&empty, &AR1, 2, &s),
        Err(Error::EmptyHistory)
    );
}

#[test]
fn degenerate_transition_densities_are_errors() {
    let s = SmootherSettings::default();
    let h = small_history();
    let neg = Constant(f64::NEG_INFINITY, None);
    for result in [
        smooth_marginals(&h, &neg, &s).map(|_| ()),
        sample_trajectories(&h, &neg, 5, 0, &s).map(|_| ()),
    ] {
        assert!(
            matches!(
                result,
                Err(Error::DegenerateBackward {
                    frame: 0,
                    reason: smc_core::Degeneracy::AllZero,
                    ..
                })
            ),
            "{result:?}"
        );
    }
    let nan = Constant(f64::NAN, None);
    assert!(matches!(
        smooth_marginals(&h, &nan, &s),
        Err(Error::DegenerateBackward {
            reason: smc_core::Degeneracy::NotANumber { index: 0 },
            ..
        })
    ));
    let inf = Constant(f64::INFINITY, Some(0.0));
    assert!(matches!(
        sample_trajectories(&h, &inf, 5, 0, &s),
        Err(Error::DegenerateBackward {
            reason: smc_core::Degeneracy::PositiveInfinity { .. },
            ..
        })
    ));
    let above = Constant(1.0, Some(0.0));
    assert!(matches!(
        sample_trajectories(&h, &above, 5, 0, &s),
        Err(Error::BoundExceeded { frame: 1, .. })
    ));
}

#[test]
fn invalid_smoother_settings_are_errors() {
    let s = SmootherSettings::default();
    let h = small_history();
    let rejection = SmootherSettings {
        backward: BackwardMethod::Rejection,
        ..SmootherSettings::default()
    };
    assert!(matches!(
        sample_trajectories(&h, &Constant(0.0, None), 5, 0, &rejection),
        Err(Error::InvalidSetting {
            name: "backward",
            ..
        })
    ));
    assert!(matches!(
        sample_trajectories(&h, &AR1, 0, 0, &s),
        Err(Error::InvalidSetting {
            name: "trajectories",
            ..
        })
    ));
    for bad in [
        SmootherSettings {
            block_columns: 0,
            ..SmootherSettings::default()
        },
        SmootherSettings {
            max_rejections: Some(0),
            ..SmootherSettings::default()
        },
        SmootherSettings {
            parallel_min_chunk: 0,
            ..SmootherSettings::default()
        },
    ] {
        assert!(matches!(
            smooth_marginals(&h, &AR1, &bad),
            Err(Error::InvalidSetting { .. })
        ));
    }
}

#[test]
fn results_read_against_another_history_are_errors() {
    let s = SmootherSettings::default();
    let h = small_history();
    let m = smooth_marginals(&h, &AR1, &s).unwrap();
    let mut other = History::new(HistorySettings::default()).unwrap();
    other
        .push(0, ParticleSet::from_states(vec![0.0; 4]).unwrap(), None)
        .unwrap();
    assert!(matches!(
        m.to_particle_set(&other, 0),
        Err(Error::LengthMismatch { .. })
    ));
    assert!(matches!(
        m.to_particle_set(&h, 2),
        Err(Error::InvalidSetting { .. })
    ));
}

#[test]
fn a_single_frame_is_its_own_smoother() {
    let s = SmootherSettings::default();
    let mut one = History::new(HistorySettings::default()).unwrap();
    let set = ParticleSet::from_log_weights(vec![0.0, 1.0], vec![0.0, 1.0]).unwrap();
    one.push(0, set.clone(), None).unwrap();
    assert_eq!(
        smooth_marginals(&one, &AR1, &s).unwrap().weights(0),
        Some(set.weights())
    );
}

#[test]
fn a_history_that_resamples_to_a_new_size_smooths() {
    // Frames of different sizes (the filter's output_size): the N_t × N_{t+1} matrix is not
    // square. The smoothed weights must still sum to one and put zero mass where the filter did.
    let h = small_history();
    let m = smooth_marginals(
        &h,
        &AR1,
        &SmootherSettings {
            block_columns: 2,
            ..SmootherSettings::default()
        },
    )
    .unwrap();
    let w0 = m.weights(0).unwrap();
    assert_eq!(w0.len(), 2);
    assert!((w0.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    // Exact two-by-three computation of (S2) for comparison.
    let f = |x: f64, y: f64| (-0.5 * (y - 0.9 * x).powi(2) / 0.5).exp();
    let (xs, ys) = ([0.0, 1.0], [0.5, 1.5, 2.5]);
    let mut want = [0.0; 2];
    for y in ys {
        let d: f64 = xs.iter().map(|&x| 0.5 * f(x, y)).sum();
        for (i, &x) in xs.iter().enumerate() {
            want[i] += (1.0 / 3.0) * 0.5 * f(x, y) / d;
        }
    }
    for (got, want) in w0.iter().zip(want) {
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
}
