//! The linear-Gaussian test models shared by the filter tests (`kalman.rs`) and the smoother
//! tests (`smoothing/`), and their exact Kalman filter: a 1-D AR(1) and a 2-D constant-velocity
//! model observed in position only.
#![allow(dead_code)] // each test crate uses its own part

use std::f64::consts::PI;

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use smc_core::model::Dynamics;

/// A standard normal draw.
pub fn gauss<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

/// ln N(x; mean, var).
pub fn normal_log_pdf(x: f64, mean: f64, var: f64) -> f64 {
    -0.5 * ((x - mean).powi(2) / var + (2.0 * PI * var).ln())
}

// ---------------------------------------------------------------------------------------------
// 1-D: x_k = a x_{k−1} + N(0, q), z_k = x_k + N(0, r), x_0 ~ N(m0, p0).

/// x_k = a x_{k−1} + N(0, q).
#[derive(Clone, Copy)]
pub struct Ar1 {
    pub a: f64,
    pub q: f64,
}

/// The AR(1) model of every 1-D test.
pub const AR1: Ar1 = Ar1 { a: 0.9, q: 0.5 };

impl Dynamics for Ar1 {
    type State = f64;
    fn sample<R: Rng + ?Sized>(&self, x: &f64, rng: &mut R) -> f64 {
        self.a * x + self.q.sqrt() * gauss(rng)
    }
    fn log_density(&self, x: &f64, y: &f64) -> f64 {
        normal_log_pdf(*y, self.a * x, self.q)
    }
}

/// The Kalman filter of a model observed through N(0, r) noise: predicted and filtered means and
/// (co)variances per step, and the total log-evidence ln p(z_1..z_T).
#[derive(Default)]
pub struct Kalman<M, P> {
    pub predicted_means: Vec<M>,
    pub predicted_covs: Vec<P>,
    pub means: Vec<M>,
    pub covs: Vec<P>,
    pub log_evidence: f64,
}

/// The Kalman filter of the AR(1) model from x_0 ~ N(m0, p0).
pub fn kalman_1d(model: Ar1, r: f64, m0: f64, p0: f64, zs: &[f64]) -> Kalman<f64, f64> {
    let (mut m, mut p) = (m0, p0);
    let mut out = Kalman::default();
    for &z in zs {
        m *= model.a;
        p = model.a * model.a * p + model.q;
        out.predicted_means.push(m);
        out.predicted_covs.push(p);
        let s = p + r;
        out.log_evidence += normal_log_pdf(z, m, s);
        let k = p / s;
        m += k * (z - m);
        p *= 1.0 - k;
        out.means.push(m);
        out.covs.push(p);
    }
    out
}

// ---------------------------------------------------------------------------------------------
// 2-D constant velocity: x = (position, velocity), x_k = F x_{k−1} + w, w ~ N(0, Q),
// Q = σ² [[dt³/3, dt²/2], [dt²/2, dt]] (continuous white-noise acceleration, dt = 1),
// z_k = position + N(0, r). Only the position is observed, so the velocity is inferred.

/// σ² of the acceleration noise.
pub const SIGMA2: f64 = 0.2;

/// A 2×2 matrix, row-major.
pub type M2 = [[f64; 2]; 2];

/// F, the transition matrix (dt = 1).
pub const F: M2 = [[1.0, 1.0], [0.0, 1.0]];

/// Q, the process noise covariance.
pub fn q_matrix() -> M2 {
    [[SIGMA2 / 3.0, SIGMA2 / 2.0], [SIGMA2 / 2.0, SIGMA2]]
}

/// a·b.
pub fn mul(a: &M2, b: &M2) -> M2 {
    let mut c = [[0.0; 2]; 2];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = a[i][0] * b[0][j] + a[i][1] * b[1][j];
        }
    }
    c
}

/// aᵀ.
pub fn transpose(a: &M2) -> M2 {
    [[a[0][0], a[1][0]], [a[0][1], a[1][1]]]
}

/// a + s·b.
pub fn add(a: &M2, b: &M2, s: f64) -> M2 {
    [
        [a[0][0] + s * b[0][0], a[0][1] + s * b[0][1]],
        [a[1][0] + s * b[1][0], a[1][1] + s * b[1][1]],
    ]
}

/// a⁻¹.
pub fn inverse(a: &M2) -> M2 {
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    [
        [a[1][1] / det, -a[0][1] / det],
        [-a[1][0] / det, a[0][0] / det],
    ]
}

/// The constant-velocity dynamics, with Q's Cholesky factor and inverse precomputed.
pub struct ConstantVelocity {
    /// Lower Cholesky factor of Q.
    pub l: M2,
    pub q_inv: M2,
    /// ln of N(·; ·, Q)'s normalising constant.
    pub log_norm: f64,
}

impl ConstantVelocity {
    pub fn new() -> Self {
        let q = q_matrix();
        let l00 = q[0][0].sqrt();
        let l10 = q[1][0] / l00;
        let l11 = (q[1][1] - l10 * l10).sqrt();
        let det = q[0][0] * q[1][1] - q[0][1] * q[1][0];
        Self {
            l: [[l00, 0.0], [l10, l11]],
            q_inv: inverse(&q),
            log_norm: -(2.0 * PI).ln() - 0.5 * det.ln(),
        }
    }

    /// F x.
    pub fn predict(x: &[f64; 2]) -> [f64; 2] {
        [x[0] + x[1], x[1]]
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

/// The Kalman filter of the constant-velocity model from x_0 ~ N(m0, p0), observed in position
/// with noise variance `r`.
pub fn kalman_2d(m0: [f64; 2], p0: M2, r: f64, zs: &[f64]) -> Kalman<[f64; 2], M2> {
    let q = q_matrix();
    let (mut m, mut p) = (m0, p0);
    let mut out = Kalman::default();
    for &z in zs {
        m = ConstantVelocity::predict(&m);
        p = add(&mul(&mul(&F, &p), &transpose(&F)), &q, 1.0);
        out.predicted_means.push(m);
        out.predicted_covs.push(p);
        // Update with H = [1, 0].
        let s = p[0][0] + r;
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
