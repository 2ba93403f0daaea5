//! Synthetic frame pairs with exactly known warps: an analytic texture (a sum of sinusoids of
//! random wavelength 3–40 px) sampled at the warped coordinates, plus Gaussian noise, rounded to
//! 8 bits.
#![allow(dead_code)]

use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

/// A sum of `n` sinusoids with wavelengths uniform in [3, 40] px, uniform directions and phases,
/// equal amplitudes giving a standard deviation of `std` grey levels around 128.
pub struct Texture {
    comps: Vec<[f64; 3]>,
    amp: f64,
}

impl Texture {
    pub fn new(seed: u64, n: usize, std: f64) -> Self {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
        let comps = (0..n)
            .map(|_| {
                let lambda: f64 = rng.random_range(3.0..40.0);
                let dir: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                let phase: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                let k = std::f64::consts::TAU / lambda;
                [k * dir.cos(), k * dir.sin(), phase]
            })
            .collect();
        Self {
            comps,
            amp: std * (2.0 / n as f64).sqrt(),
        }
    }

    /// Writes the texture at points p0 + i·dp, i = 0..out.len(), into `out`, rotating each
    /// sinusoid's phasor along the row instead of evaluating a sine per point.
    pub fn row(&self, p0: [f64; 2], dp: [f64; 2], out: &mut [f64]) {
        out.fill(128.0);
        for c in &self.comps {
            let phi = c[0] * p0[0] + c[1] * p0[1] + c[2];
            let d = c[0] * dp[0] + c[1] * dp[1];
            let (mut s, mut co) = phi.sin_cos();
            let (ds, dc) = d.sin_cos();
            for v in out.iter_mut() {
                *v += self.amp * s;
                (s, co) = (s * dc + co * ds, co * dc - s * ds);
            }
        }
    }

    pub fn eval(&self, x: f64, y: f64) -> f64 {
        let s: f64 = self
            .comps
            .iter()
            .map(|c| (c[0] * x + c[1] * y + c[2]).sin())
            .sum();
        128.0 + self.amp * s
    }
}

/// An affine displacement d(r) = (a1 + a2 x + a3 y, a4 + a5 x + a6 y), x, y relative to `origin`.
#[derive(Clone, Copy, Debug)]
pub struct Affine {
    pub a: [f64; 6],
    pub origin: [f64; 2],
}

impl Affine {
    pub fn displacement(&self, x: f64, y: f64) -> [f64; 2] {
        let (dx, dy) = (x - self.origin[0], y - self.origin[1]);
        let a = &self.a;
        [a[0] + a[1] * dx + a[2] * dy, a[3] + a[4] * dx + a[5] * dy]
    }

    /// The point r with r + d(r) = q.
    pub fn inverse(&self, qx: f64, qy: f64) -> [f64; 2] {
        let a = &self.a;
        let (m11, m12, m21, m22) = (1.0 + a[1], a[2], a[4], 1.0 + a[5]);
        let det = m11 * m22 - m12 * m21;
        let (bx, by) = (qx - self.origin[0] - a[0], qy - self.origin[1] - a[3]);
        [
            self.origin[0] + (m22 * bx - m12 * by) / det,
            self.origin[1] + (-m21 * bx + m11 * by) / det,
        ]
    }

    /// The full-frame test motion: 2° rotation, 3 % scale, slight shear, translation `t`.
    pub fn issue(origin: [f64; 2], t: [f64; 2]) -> Self {
        let (s, c) = 2.0f64.to_radians().sin_cos();
        let k = 1.03;
        let shear = 0.005;
        Self {
            a: [t[0], k * c - 1.0, -k * s + shear, t[1], k * s, k * c - 1.0],
            origin,
        }
    }
}

/// A textured block moving independently: in frame 0 it covers `rect` (x, y, w, h) showing
/// `texture` shifted to the block; in frame 1 the block is translated by `shift`.
pub struct Block {
    pub rect: [f64; 4],
    pub shift: [f64; 2],
    pub texture: Texture,
}

impl Block {
    fn value(&self, x: f64, y: f64, frame1: bool) -> Option<f64> {
        let (ox, oy) = if frame1 {
            (self.rect[0] + self.shift[0], self.rect[1] + self.shift[1])
        } else {
            (self.rect[0], self.rect[1])
        };
        let inside = x >= ox && x < ox + self.rect[2] && y >= oy && y < oy + self.rect[3];
        inside.then(|| self.texture.eval(x - ox, y - oy))
    }
}

/// Noise-free frames (f64) of a scene: frame 0 = texture, frame 1 = texture warped by `warp`, plus
/// `offset` grey levels, with an optional independent block drawn over both.
pub fn clean_pair(
    w: usize,
    h: usize,
    tex: &Texture,
    warp: &Affine,
    offset: f64,
    block: Option<&Block>,
) -> (Vec<f64>, Vec<f64>) {
    let mut f0 = Vec::with_capacity(w * h);
    let mut f1 = Vec::with_capacity(w * h);
    for j in 0..h {
        for i in 0..w {
            let (x, y) = (i as f64, j as f64);
            let v0 = block
                .and_then(|b| b.value(x, y, false))
                .unwrap_or_else(|| tex.eval(x, y));
            let v1 = block.and_then(|b| b.value(x, y, true)).map_or_else(
                || {
                    let r = warp.inverse(x, y);
                    tex.eval(r[0], r[1]) + offset
                },
                |v| v + offset,
            );
            f0.push(v0);
            f1.push(v1);
        }
    }
    (f0, f1)
}

/// Adds N(0, σ²) noise and rounds to 8 bits.
pub fn noisy(clean: &[f64], sigma: f64, seed: u64) -> Vec<f32> {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let n = Normal::new(0.0, sigma).unwrap();
    clean
        .iter()
        .map(|v| (v + n.sample(&mut rng)).round().clamp(0.0, 255.0) as f32)
        .collect()
}

/// Mean and squared-mean corner errors of an estimate over the inclusive pixel box
/// (x0, y0, x1, y1), plus the predicted mean squared corner error from the covariance.
pub fn corner_errors(
    est: &motion_est::MotionEstimate,
    truth: &Affine,
    b: [f64; 4],
) -> (f64, f64, f64) {
    let corners = [(b[0], b[1]), (b[2], b[1]), (b[0], b[3]), (b[2], b[3])];
    let (mut mean, mut sq, mut pred) = (0.0, 0.0, 0.0);
    for (x, y) in corners {
        let d = est.displacement(x, y);
        let t = truth.displacement(x, y);
        let e = (d[0] - t[0]).hypot(d[1] - t[1]);
        mean += e / 4.0;
        sq += e * e / 4.0;
        pred += est.displacement_covariance(x, y).trace() / 4.0;
    }
    (mean, sq, pred)
}
