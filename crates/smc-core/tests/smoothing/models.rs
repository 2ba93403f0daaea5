//! The test models (1-D AR(1), 2-D constant velocity), their exact Kalman/RTS smoothers, and
//! the comparison of a smoother's marginals with them.

use std::f64::consts::PI;

use smc_core::estimate::weighted_mean_covariance;
use smc_core::model::{Dynamics, FnObservation, TransitionDensity};
use smc_core::rng::stream_rng;
use smc_core::smooth::{BackwardMethod, SmootherSettings};
use smc_core::{
    FilterSettings, History, HistorySettings, ParticleFilter, ParticleSet, ResamplingScheme,
    sample_trajectories, smooth_marginals,
};

pub(crate) use crate::common::{
    AR1, Ar1, ConstantVelocity, F, M2, add, gauss, inverse, kalman_1d, kalman_2d, mul,
    normal_log_pdf, transpose,
};

/// Which smoother a run uses.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Method {
    /// The filter's own marginals, unsmoothed (the control).
    Filter,
    Ffbsm,
    FfbsExact,
    FfbsRejection,
}

/// Errors of one run against the RTS smoother, over every step and coordinate.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Errors {
    /// Worst |mean error| / smoothed sd.
    pub(crate) worst_mean: f64,
    /// RMS over steps of (mean error / smoothed sd).
    pub(crate) rms_mean: f64,
    /// Worst |variance / smoothed variance − 1|.
    pub(crate) worst_var: f64,
    /// RMS over steps of (variance / smoothed variance − 1).
    pub(crate) rms_var: f64,
}

/// Compares the smoothed marginals of `history` with exact means and variances (one entry per
/// step and coordinate).
pub(crate) fn errors<S, T>(
    history: &History<S>,
    transition: &T,
    method: Method,
    seed: u64,
    exact_mean: &[Vec<f64>],
    exact_var: &[Vec<f64>],
) -> Errors
where
    S: Clone + Sync + smc_core::AsVector,
    T: TransitionDensity<State = S>,
{
    let settings = SmootherSettings {
        backward: match method {
            Method::FfbsExact => BackwardMethod::Exact,
            _ => BackwardMethod::Rejection,
        },
        ..SmootherSettings::default()
    };
    let n = history.frame(0).unwrap().set.len();
    let sets: Vec<ParticleSet<S>> = match method {
        Method::Filter => history.frames().map(|f| f.set.clone()).collect(),
        Method::Ffbsm => {
            let m = smooth_marginals(history, transition, &settings).unwrap();
            (0..history.len())
                .map(|t| m.to_particle_set(history, t).unwrap())
                .collect()
        }
        Method::FfbsExact | Method::FfbsRejection => {
            let paths = sample_trajectories(history, transition, n, seed, &settings).unwrap();
            (0..history.len())
                .map(|t| paths.to_particle_set(history, t).unwrap())
                .collect()
        }
    };
    let (mut worst_mean, mut worst_var, mut sum_mean, mut sum_var, mut count) =
        (0.0f64, 0.0f64, 0.0, 0.0, 0.0);
    for (t, set) in sets.iter().enumerate() {
        let mc = weighted_mean_covariance(set).unwrap();
        for c in 0..mc.dim() {
            let z = (mc.mean[c] - exact_mean[t][c]) / exact_var[t][c].sqrt();
            let v = mc.cov(c, c).unwrap() / exact_var[t][c] - 1.0;
            worst_mean = worst_mean.max(z.abs());
            worst_var = worst_var.max(v.abs());
            sum_mean += z * z;
            sum_var += v * v;
            count += 1.0;
        }
    }
    Errors {
        worst_mean,
        rms_mean: (sum_mean / count).sqrt(),
        worst_var,
        rms_var: (sum_var / count).sqrt(),
    }
}

pub(crate) fn filter_settings(threshold: f64, parallel: bool) -> FilterSettings {
    FilterSettings {
        resample_threshold: threshold,
        parallel,
        history: Some(HistorySettings::default()),
        ..FilterSettings::default()
    }
}

// ---------------------------------------------------------------------------------------------
// 1-D: x_k = a x_{k−1} + N(0, q), z_k = x_k + N(0, r), x_0 ~ N(m0, p0); the filter observes
// z_1..z_T, so history frame t holds x_{t+1}.

impl TransitionDensity for Ar1 {
    type State = f64;
    fn log_density(&self, _frame: usize, x: &f64, y: &f64) -> f64 {
        // The normalising constant is evaluated once per call site by the optimiser only if it
        // sees through `ln`; spell it out so that the O(N²) loops pay one exp-free expression.
        -0.5 * (y - self.a * x).powi(2) / self.q + Self::LOG_NORM
    }
    fn log_density_bound(&self, _frame: usize, _y: &f64) -> Option<f64> {
        Some(-0.5 * (2.0 * PI * self.q).ln())
    }
}

impl Ar1 {
    /// −½ log(2π q) for q = 0.5, i.e. −½ log π.
    const LOG_NORM: f64 = -0.572_364_942_924_700_1;
}
pub(crate) const R_1D: f64 = 0.3;
pub(crate) const M0: f64 = 1.0;
pub(crate) const P0: f64 = 2.0;
pub(crate) const STEPS: usize = 25;
/// Filter particles (and FFBS trajectories) in the accuracy tests.
pub(crate) const N: usize = 500;

pub(crate) fn simulate_1d() -> Vec<f64> {
    let mut rng = stream_rng(1234, 0, 999);
    let mut x = M0 + P0.sqrt() * gauss(&mut rng);
    (0..STEPS)
        .map(|_| {
            x = AR1.sample(&x, &mut rng);
            x + R_1D.sqrt() * gauss(&mut rng)
        })
        .collect()
}

/// The Kalman filter followed by the RTS smoother (Särkkä 2013, Theorem 8.2): smoothed means
/// and variances, and the filtered variances.
pub(crate) fn rts_1d(zs: &[f64]) -> (Vec<Vec<f64>>, Vec<Vec<f64>>, Vec<f64>) {
    let k = kalman_1d(AR1, R_1D, M0, P0, zs);
    let (mut ms, mut ps) = (k.means, k.covs.clone());
    for t in (0..zs.len() - 1).rev() {
        let g = ps[t] * AR1.a / k.predicted_covs[t + 1];
        ms[t] += g * (ms[t + 1] - k.predicted_means[t + 1]);
        ps[t] += g * g * (ps[t + 1] - k.predicted_covs[t + 1]);
    }
    (
        ms.into_iter().map(|v| vec![v]).collect(),
        ps.into_iter().map(|v| vec![v]).collect(),
        k.covs,
    )
}

pub(crate) fn filter_1d(
    n: usize,
    seed: u64,
    zs: &[f64],
    settings: FilterSettings,
) -> ParticleFilter<f64> {
    let mut init = stream_rng(seed, u64::MAX, 0);
    let states = (0..n).map(|_| M0 + P0.sqrt() * gauss(&mut init)).collect();
    let mut set = ParticleSet::from_states(states).unwrap();
    let mut filter = ParticleFilter::new(settings).unwrap();
    for (k, &z) in zs.iter().enumerate() {
        let obs = FnObservation::new(move |x: &f64| normal_log_pdf(z, *x, R_1D));
        filter
            .step_bootstrap(
                &mut set,
                &AR1,
                &obs,
                &ResamplingScheme::Systematic,
                seed,
                k as u64,
            )
            .unwrap();
    }
    filter
}

pub(crate) fn errors_1d(seed: u64, method: Method) -> Errors {
    let zs = simulate_1d();
    let (mean, var, _) = rts_1d(&zs);
    let mut filter = filter_1d(N, seed, &zs, filter_settings(1.0, false));
    let history = filter.take_history().unwrap();
    errors(&history, &AR1, method, seed, &mean, &var)
}

/// Seeds of the accuracy tests.
pub(crate) const SEEDS: [u64; 3] = [1, 2, 3];

pub(crate) fn check(
    name: &str,
    e: Errors,
    worst_mean: f64,
    rms_mean: f64,
    worst_var: f64,
    rms_var: f64,
) {
    assert!(e.worst_mean < worst_mean, "{name}: {e:?}");
    assert!(e.rms_mean < rms_mean, "{name}: {e:?}");
    assert!(e.worst_var < worst_var, "{name}: {e:?}");
    assert!(e.rms_var < rms_var, "{name}: {e:?}");
}

// ---------------------------------------------------------------------------------------------
// 2-D constant velocity: x = (position, velocity), x_k = F x_{k−1} + w, w ~ N(0, Q),
// Q = σ² [[dt³/3, dt²/2], [dt²/2, dt]], z_k = position + N(0, r).

pub(crate) const R_2D: f64 = 1.0;
pub(crate) const CV_M0: [f64; 2] = [0.0, 1.0];
pub(crate) const CV_P0: M2 = [[1.0, 0.0], [0.0, 0.5]];

impl TransitionDensity for ConstantVelocity {
    type State = [f64; 2];
    fn log_density(&self, _frame: usize, x: &[f64; 2], y: &[f64; 2]) -> f64 {
        Dynamics::log_density(self, x, y)
    }
    fn log_density_bound(&self, _frame: usize, _y: &[f64; 2]) -> Option<f64> {
        Some(self.log_norm)
    }
}

pub(crate) fn simulate_2d(model: &ConstantVelocity) -> Vec<f64> {
    let mut rng = stream_rng(77, 0, 999);
    let mut x = [
        CV_M0[0] + gauss(&mut rng),
        CV_M0[1] + CV_P0[1][1].sqrt() * gauss(&mut rng),
    ];
    (0..STEPS)
        .map(|_| {
            x = model.sample(&x, &mut rng);
            x[0] + R_2D.sqrt() * gauss(&mut rng)
        })
        .collect()
}

/// Kalman filter and RTS smoother (Särkkä 2013, Theorem 8.2) for the constant-velocity model:
/// smoothed means and variances per coordinate.
pub(crate) fn rts_2d(zs: &[f64]) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let k = kalman_2d(CV_M0, CV_P0, R_2D, zs);
    let (mut ms, mut ps) = (k.means, k.covs);
    for t in (0..zs.len() - 1).rev() {
        // G = P_t Fᵀ (P⁻_{t+1})⁻¹; m_t += G (m_{t+1}^s − m⁻_{t+1}); P_t += G (P_{t+1}^s − P⁻_{t+1}) Gᵀ.
        let g = mul(
            &mul(&ps[t], &transpose(&F)),
            &inverse(&k.predicted_covs[t + 1]),
        );
        let dm = [
            ms[t + 1][0] - k.predicted_means[t + 1][0],
            ms[t + 1][1] - k.predicted_means[t + 1][1],
        ];
        ms[t] = [
            ms[t][0] + g[0][0] * dm[0] + g[0][1] * dm[1],
            ms[t][1] + g[1][0] * dm[0] + g[1][1] * dm[1],
        ];
        let dp = add(&ps[t + 1], &k.predicted_covs[t + 1], -1.0);
        ps[t] = add(&ps[t], &mul(&mul(&g, &dp), &transpose(&g)), 1.0);
    }
    (
        ms.iter().map(|m| m.to_vec()).collect(),
        ps.iter().map(|p| vec![p[0][0], p[1][1]]).collect(),
    )
}

pub(crate) fn filter_2d(
    n: usize,
    seed: u64,
    settings: FilterSettings,
) -> (ParticleFilter<[f64; 2]>, Vec<f64>) {
    let model = ConstantVelocity::new();
    let zs = simulate_2d(&model);
    let mut init = stream_rng(seed, u64::MAX, 0);
    let states = (0..n)
        .map(|_| {
            [
                CV_M0[0] + gauss(&mut init),
                CV_M0[1] + CV_P0[1][1].sqrt() * gauss(&mut init),
            ]
        })
        .collect();
    let mut set = ParticleSet::from_states(states).unwrap();
    let mut filter = ParticleFilter::new(settings).unwrap();
    for (k, &z) in zs.iter().enumerate() {
        let obs = FnObservation::new(move |x: &[f64; 2]| normal_log_pdf(z, x[0], R_2D));
        filter
            .step_bootstrap(
                &mut set,
                &model,
                &obs,
                &ResamplingScheme::Multinomial,
                seed,
                k as u64,
            )
            .unwrap();
    }
    (filter, zs)
}

pub(crate) fn errors_2d(seed: u64, method: Method) -> Errors {
    // Adaptive resampling (ESS < N/2) so that some frames carry uneven weights into the smoother.
    let (mut filter, zs) = filter_2d(N, seed, filter_settings(0.5, false));
    let (mean, var) = rts_2d(&zs);
    let history = filter.take_history().unwrap();
    errors(
        &history,
        &ConstantVelocity::new(),
        method,
        seed,
        &mean,
        &var,
    )
}
