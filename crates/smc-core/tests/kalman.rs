//! Linear-Gaussian models, where the exact filter is the Kalman filter: the particle filter's
//! filtered means and total log-evidence must match it within Monte Carlo error.
//!
//! Tolerances. With N particles the Monte Carlo error of a filtered mean is about
//! σ_k · sqrt(κ / N), σ_k the exact posterior standard deviation and κ ≥ 1 an inefficiency factor
//! (weight degeneracy plus the variance that resampling adds, a few units here). The error of the
//! log-evidence estimate log Ẑ accumulates over T steps, with standard deviation about
//! sqrt(T κ′ / N) (κ′ the per-step relative variance of the incremental weight). Each test states
//! the spread measured over 20 seeds when it was written; its tolerance is at least 4.5 standard
//! deviations of that spread (and about 3 times the largest error seen), while a wrong weight
//! update (a missing prior/proposal ratio, or a log-evidence that ignores the previous weights)
//! misses it by far more.

use std::f64::consts::PI;

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use smc_core::estimate::{weighted_mean, weighted_mean_covariance};
use smc_core::model::{Dynamics, FnObservation, Proposal};
use smc_core::rng::stream_rng;
use smc_core::{FilterSettings, ParticleFilter, ParticleSet, ResamplingScheme};

fn normal_log_pdf(x: f64, mean: f64, var: f64) -> f64 {
    -0.5 * ((x - mean).powi(2) / var + (2.0 * PI * var).ln())
}

fn gauss<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

// ---------------------------------------------------------------------------------------------
// 1-D: x_k = a x_{k−1} + N(0, q), z_k = x_k + N(0, r), x_0 ~ N(m0, p0).

#[derive(Clone, Copy)]
struct Ar1 {
    a: f64,
    q: f64,
}

impl Dynamics for Ar1 {
    type State = f64;
    fn sample<R: Rng + ?Sized>(&self, x: &f64, rng: &mut R) -> f64 {
        self.a * x + self.q.sqrt() * gauss(rng)
    }
    fn log_density(&self, x: &f64, y: &f64) -> f64 {
        normal_log_pdf(*y, self.a * x, self.q)
    }
}

/// A proposal that uses the measurement but is deliberately not the optimal one: it moves the
/// prior mean half way towards z and inflates the variance. The weights must then carry the ratio
/// p(x|x′)/q(x|x′, z) of Odobez Eq. 3 for the filter to stay exact.
struct TowardsMeasurement {
    model: Ar1,
    z: f64,
}

impl TowardsMeasurement {
    fn mean_var(&self, prev: f64) -> (f64, f64) {
        let prior_mean = self.model.a * prev;
        (prior_mean + 0.5 * (self.z - prior_mean), 1.5 * self.model.q)
    }
}

impl Proposal for TowardsMeasurement {
    type State = f64;
    fn sample<R: Rng + ?Sized>(&self, _i: usize, prev: &f64, rng: &mut R) -> f64 {
        let (m, v) = self.mean_var(*prev);
        m + v.sqrt() * gauss(rng)
    }
    fn log_density(&self, _i: usize, prev: &f64, next: &f64) -> f64 {
        let (m, v) = self.mean_var(*prev);
        normal_log_pdf(*next, m, v)
    }
}

struct Kalman1 {
    means: Vec<f64>,
    vars: Vec<f64>,
    log_evidence: f64,
}

fn kalman_1d(model: Ar1, r: f64, m0: f64, p0: f64, zs: &[f64]) -> Kalman1 {
    let (mut m, mut p) = (m0, p0);
    let mut out = Kalman1 {
        means: vec![],
        vars: vec![],
        log_evidence: 0.0,
    };
    for &z in zs {
        m *= model.a;
        p = model.a * model.a * p + model.q;
        let s = p + r;
        out.log_evidence += normal_log_pdf(z, m, s);
        let k = p / s;
        m += k * (z - m);
        p *= 1.0 - k;
        out.means.push(m);
        out.vars.push(p);
    }
    out
}

const MODEL_1D: Ar1 = Ar1 { a: 0.9, q: 0.5 };
const R_1D: f64 = 0.3;
const M0: f64 = 1.0;
const P0: f64 = 2.0;
const STEPS: usize = 50;
/// Particles in every accuracy test.
const N: usize = 50_000;

fn simulate_1d(seed: u64) -> Vec<f64> {
    let mut rng = stream_rng(seed, 0, 999);
    let mut x = M0 + P0.sqrt() * gauss(&mut rng);
    (0..STEPS)
        .map(|_| {
            x = MODEL_1D.sample(&x, &mut rng);
            x + R_1D.sqrt() * gauss(&mut rng)
        })
        .collect()
}

fn initial_1d(n: usize, seed: u64) -> ParticleSet<f64> {
    let mut rng = stream_rng(seed, u64::MAX, 0);
    let states = (0..n).map(|_| M0 + P0.sqrt() * gauss(&mut rng)).collect();
    ParticleSet::from_states(states).unwrap()
}

/// Runs the 1-D filter; returns the largest |error| of the mean in units of the Kalman posterior
/// standard deviation, and the error of the total log-evidence.
fn run_1d(n: usize, seed: u64, guided: bool, settings: FilterSettings) -> (f64, f64) {
    let zs = simulate_1d(1234);
    let exact = kalman_1d(MODEL_1D, R_1D, M0, P0, &zs);
    let mut set = initial_1d(n, seed);
    let mut filter = ParticleFilter::new(settings).unwrap();
    let scheme = ResamplingScheme::Systematic;
    let mut log_evidence = 0.0;
    let mut worst = 0.0f64;
    for (k, &z) in zs.iter().enumerate() {
        let obs = FnObservation::new(move |x: &f64| normal_log_pdf(z, *x, R_1D));
        let d = if guided {
            let q = TowardsMeasurement { model: MODEL_1D, z };
            filter
                .step(&mut set, &q, Some(&MODEL_1D), &obs, &scheme, seed, k as u64)
                .unwrap()
        } else {
            filter
                .step_bootstrap(&mut set, &MODEL_1D, &obs, &scheme, seed, k as u64)
                .unwrap()
        };
        log_evidence += d.log_evidence_increment;
        let mean = weighted_mean(&set).unwrap()[0];
        worst = worst.max((mean - exact.means[k]).abs() / exact.vars[k].sqrt());
    }
    (worst, log_evidence - exact.log_evidence)
}

#[test]
fn bootstrap_filter_matches_kalman_in_1d() {
    // Measured over 20 seeds at N = 50,000: worst-over-steps mean error 0.016 ± 0.003 σ (largest
    // 0.021 σ); log-evidence error 0.007 ± 0.042 (largest 0.11). Tolerances: 0.06 σ, and 0.2 for
    // the evidence (4.8 standard deviations).
    let (mean_err, evidence_err) = run_1d(N, 11, false, FilterSettings::default());
    assert!(mean_err < 0.06, "worst mean error {mean_err} posterior sd");
    assert!(
        evidence_err.abs() < 0.2,
        "log-evidence error {evidence_err}"
    );
}

#[test]
fn guided_proposal_with_adaptive_resampling_matches_kalman_in_1d() {
    // Non-bootstrap proposal (weights carry p/q, Odobez Eq. 3) and resampling only when
    // ESS < N/2, so that some steps do not resample and the log-evidence increment must use the
    // previous weights. Measured over 20 seeds at N = 50,000: worst mean error 0.013 ± 0.002 σ
    // (largest 0.019 σ); log-evidence error 0.007 ± 0.033 (largest 0.059). Tolerances: 0.06 σ,
    // and 0.15 for the evidence (4.5 standard deviations). Dropping the p/q factor biases the
    // mean towards z by several σ.
    let settings = FilterSettings {
        resample_threshold: 0.5,
        ..FilterSettings::default()
    };
    let (mean_err, evidence_err) = run_1d(N, 12, true, settings);
    assert!(mean_err < 0.06, "worst mean error {mean_err} posterior sd");
    assert!(
        evidence_err.abs() < 0.15,
        "log-evidence error {evidence_err}"
    );
}

// ---------------------------------------------------------------------------------------------
// 2-D constant velocity: x = (position, velocity), x_k = F x_{k−1} + w, w ~ N(0, Q),
// z_k = position + N(0, r). Only the position is observed, so the velocity is inferred.

const DT: f64 = 1.0;
/// Q = σ² [[dt³/3, dt²/2], [dt²/2, dt]] (continuous white-noise acceleration), σ² = 0.2.
const SIGMA2: f64 = 0.2;
const R_2D: f64 = 1.0;

fn q_matrix() -> [[f64; 2]; 2] {
    [
        [SIGMA2 * DT.powi(3) / 3.0, SIGMA2 * DT.powi(2) / 2.0],
        [SIGMA2 * DT.powi(2) / 2.0, SIGMA2 * DT],
    ]
}

struct ConstantVelocity {
    /// Lower Cholesky factor of Q.
    l: [[f64; 2]; 2],
    q_inv: [[f64; 2]; 2],
    log_norm: f64,
}

impl ConstantVelocity {
    fn new() -> Self {
        let q = q_matrix();
        let l00 = q[0][0].sqrt();
        let l10 = q[1][0] / l00;
        let l11 = (q[1][1] - l10 * l10).sqrt();
        let det = q[0][0] * q[1][1] - q[0][1] * q[1][0];
        Self {
            l: [[l00, 0.0], [l10, l11]],
            q_inv: [
                [q[1][1] / det, -q[0][1] / det],
                [-q[1][0] / det, q[0][0] / det],
            ],
            log_norm: -(2.0 * PI).ln() - 0.5 * det.ln(),
        }
    }
    fn predict(x: &[f64; 2]) -> [f64; 2] {
        [x[0] + DT * x[1], x[1]]
    }
}

impl Dynamics for ConstantVelocity {
    type State = [f64; 2];
    fn sample<R: Rng + ?Sized>(&self, x: &[f64; 2], rng: &mut R) -> [f64; 2] {
        let (e0, e1) = (gauss(rng), gauss(rng));
        let p = Self::predict(x);
        [
            p[0] + self.l[0][0] * e0,
            p[1] + self.l[1][0] * e0 + self.l[1][1] * e1,
        ]
    }
    fn log_density(&self, x: &[f64; 2], y: &[f64; 2]) -> f64 {
        let p = Self::predict(x);
        let d = [y[0] - p[0], y[1] - p[1]];
        let qi = self.q_inv;
        let quad =
            d[0] * (qi[0][0] * d[0] + qi[0][1] * d[1]) + d[1] * (qi[1][0] * d[0] + qi[1][1] * d[1]);
        self.log_norm - 0.5 * quad
    }
}

struct Kalman2 {
    means: Vec<[f64; 2]>,
    covs: Vec<[[f64; 2]; 2]>,
    log_evidence: f64,
}

fn kalman_2d(m0: [f64; 2], p0: [[f64; 2]; 2], zs: &[f64]) -> Kalman2 {
    let q = q_matrix();
    let (mut m, mut p) = (m0, p0);
    let mut out = Kalman2 {
        means: vec![],
        covs: vec![],
        log_evidence: 0.0,
    };
    for &z in zs {
        // Predict: m = F m, P = F P Fᵀ + Q with F = [[1, dt], [0, 1]].
        m = ConstantVelocity::predict(&m);
        let fp = [
            [p[0][0] + DT * p[1][0], p[0][1] + DT * p[1][1]],
            [p[1][0], p[1][1]],
        ];
        p = [
            [fp[0][0] + DT * fp[0][1] + q[0][0], fp[0][1] + q[0][1]],
            [fp[1][0] + DT * fp[1][1] + q[1][0], fp[1][1] + q[1][1]],
        ];
        // Update with H = [1, 0].
        let s = p[0][0] + R_2D;
        out.log_evidence += normal_log_pdf(z, m[0], s);
        let k = [p[0][0] / s, p[1][0] / s];
        let innovation = z - m[0];
        m = [m[0] + k[0] * innovation, m[1] + k[1] * innovation];
        p = [
            [p[0][0] - k[0] * p[0][0], p[0][1] - k[0] * p[0][1]],
            [p[1][0] - k[1] * p[0][0], p[1][1] - k[1] * p[0][1]],
        ];
        out.means.push(m);
        out.covs.push(p);
    }
    out
}

/// Runs the 2-D filter; returns the worst mean error (posterior sd units), the worst relative
/// variance error, and the log-evidence error.
fn run_2d(n: usize, seed: u64) -> (f64, f64, f64) {
    let m0: [f64; 2] = [0.0, 1.0];
    let p0: [[f64; 2]; 2] = [[1.0, 0.0], [0.0, 0.5]];
    let model = ConstantVelocity::new();
    let mut rng = stream_rng(77, 0, 999);
    let mut x = [
        m0[0] + gauss(&mut rng),
        m0[1] + p0[1][1].sqrt() * gauss(&mut rng),
    ];
    let zs: Vec<f64> = (0..STEPS)
        .map(|_| {
            x = model.sample(&x, &mut rng);
            x[0] + R_2D.sqrt() * gauss(&mut rng)
        })
        .collect();
    let exact = kalman_2d(m0, p0, &zs);

    let mut init = stream_rng(seed, u64::MAX, 0);
    let states = (0..n)
        .map(|_| {
            [
                m0[0] + gauss(&mut init),
                m0[1] + p0[1][1].sqrt() * gauss(&mut init),
            ]
        })
        .collect();
    let mut set = ParticleSet::from_states(states).unwrap();
    // The parallel path and multinomial resampling, to cover both in an accuracy test.
    let settings = FilterSettings {
        parallel: true,
        ..FilterSettings::default()
    };
    let mut filter = ParticleFilter::new(settings).unwrap();
    let mut log_evidence = 0.0;
    let (mut worst_mean, mut worst_var) = (0.0f64, 0.0f64);
    for (k, &z) in zs.iter().enumerate() {
        let obs = FnObservation::new(move |x: &[f64; 2]| normal_log_pdf(z, x[0], R_2D));
        let d = filter
            .step_bootstrap(
                &mut set,
                &model,
                &obs,
                &ResamplingScheme::Multinomial,
                seed,
                k as u64,
            )
            .unwrap();
        log_evidence += d.log_evidence_increment;
        let mc = weighted_mean_covariance(&set).unwrap();
        for c in 0..2 {
            let sd = exact.covs[k][c][c].sqrt();
            worst_mean = worst_mean.max((mc.mean[c] - exact.means[k][c]).abs() / sd);
            let var_ratio = mc.cov(c, c).unwrap() / exact.covs[k][c][c];
            worst_var = worst_var.max((var_ratio - 1.0).abs());
        }
    }
    (worst_mean, worst_var, log_evidence - exact.log_evidence)
}

#[test]
fn bootstrap_filter_matches_kalman_in_2d() {
    // Parallel path and multinomial resampling. Measured over 20 seeds at N = 50,000: worst mean
    // error 0.028 ± 0.007 σ (largest 0.048 σ); worst relative variance error 0.031 ± 0.007
    // (largest 0.044; a sample variance has relative error ≈ sqrt(2κ/N) ≈ 0.01–0.02 per step);
    // log-evidence error −0.004 ± 0.060 (largest 0.13). Tolerances: 0.12 σ, 0.12, and 0.3
    // (5 standard deviations).
    let (worst_mean, worst_var, evidence_err) = run_2d(N, 5);
    assert!(
        worst_mean < 0.12,
        "worst mean error {worst_mean} posterior sd"
    );
    assert!(
        worst_var < 0.12,
        "worst relative variance error {worst_var}"
    );
    assert!(
        evidence_err.abs() < 0.3,
        "log-evidence error {evidence_err}"
    );
}
