//! The sandwich covariance of the estimate (see the module documentation of [`super`]).

use super::meat::Grid;
use super::warp::cubic_weights;
use super::workspace::{Span, map_bands};
use super::{Mat7, Workspace};
use crate::model::{ModelSpec, MotionModel};
use crate::pyramid::Level;
use crate::robust::RobustFunction;
use crate::simd::simd;
use crate::{Error, Result};

/// Variance gain Σk² of the 1-D binomial kernel (70/256).
const KERNEL_A: f64 = 70.0 / 256.0;

/// The covariance and the noise figures of the estimate.
pub(super) struct CovarianceOut {
    pub(super) matrix: Mat7,
    pub(super) noise_sigma: f64,
    pub(super) inlier_fraction: f64,
}

/// What the covariance needs besides the workspace's residuals: the model, the robust function
/// and its Gaussian moments (E\[ψ'\], E\[ψ²\]), and whether the images were pre-smoothed.
pub(super) struct NoiseModel {
    pub(super) spec: ModelSpec,
    pub(super) robust: RobustFunction,
    pub(super) moments: (f64, f64),
    pub(super) presmooth: bool,
}

/// Variance gain Σ h² of pre-smoothing followed by cubic interpolation at fraction f, 1-D, for
/// white noise: h(v) = Σ_t c_t(f) K(t − v).
fn interp_gain(f: f64, presmooth: bool) -> f64 {
    let c = cubic_weights(f as f32).map(f64::from);
    let k: &[f64] = if presmooth {
        &[1.0 / 16.0, 4.0 / 16.0, 6.0 / 16.0, 4.0 / 16.0, 1.0 / 16.0]
    } else {
        &[1.0]
    };
    let r = (k.len() / 2) as isize;
    let mut total = 0.0;
    // Noise sample offsets v from −1 − r to 2 + r.
    for v in (-1 - r)..=(2 + r) {
        let mut hv = 0.0;
        for (ti, ct) in c.iter().enumerate() {
            let t = ti as isize - 1;
            let u = t - v + r;
            if u >= 0 && (u as usize) < k.len() {
                hv += ct * k[u as usize];
            }
        }
        total += hv * hv;
    }
    total
}

impl Workspace {
    /// The sandwich covariance described in the module documentation (level 0, robust scale
    /// `s`, origin `o`; `l1` is the second frame's level 0, where the interpolation taps lie).
    pub(super) fn covariance(
        &mut self,
        model: &NoiseModel,
        s: f64,
        o: [f64; 2],
        l1: &Level,
    ) -> Result<CovarianceOut> {
        let n = model.spec.len();
        let (diag, hinv) = self.sensitivity(model, s, o)?;
        let (noise_var, inlier_fraction) = self.noise_vectors(model, s, o)?;
        let (e1, e2) = model.moments;
        // Meat: both frames' noise, each through the smoothing (and, for the second frame, the
        // interpolation at r + d(r)), projected on u.
        let presmooth = model.presmooth;
        let meat = self.meat(n, presmooth, None) + self.meat(n, presmooth, Some(l1));
        let total = meat * noise_var + diag * ((e2 - e1 * e1) * s * s);
        let mut cov = hinv * total * hinv.transpose();
        for i in 0..7 {
            for jj in 0..7 {
                if i >= n || jj >= n {
                    cov[(i, jj)] = 0.0;
                }
            }
        }
        Ok(CovarianceOut {
            matrix: cov,
            noise_sigma: noise_var.sqrt(),
            inlier_fraction,
        })
    }

    /// The same-pixel term Σ m² J Jᵀ and the inverse of the sensitivity H = Σ m ψ' J Jᵀ (padded
    /// with the identity beyond the model's parameters).
    fn sensitivity(&self, model: &NoiseModel, s: f64, o: [f64; 2]) -> Result<(Mat7, Mat7)> {
        let (spec, robust) = (model.spec, model.robust);
        let n = spec.len();
        // Sensitivity H = Σ m ψ' J Jᵀ; when too many residuals sit where ψ' < 0 it may not be
        // positive definite, and the IRLS matrix (its expectation under a clean fit) is used.
        // One pass gives the sensitivity and the same-pixel term Σ m² J Jᵀ over the pixels a
        // redescending ρ does not reject (those carry no noise into Θ̂).
        let rej2 = robust.rejection().map(|r| (r * r) as f32);
        let same_pixel = move |z: f32, m: f32| -> f32 {
            let keep = rej2.is_none_or(|r2| z * z < r2);
            if keep { m * m } else { 0.0 }
        };
        let (diag, _, hs) = match robust {
            // Tukey's ψ' = (1 − u)(1 − 5u) for u = z²/c² < 1, else 0, in f32 and branch-free as
            // in `normal_equations`, so that the lanes vectorise.
            RobustFunction::Tukey { c } => {
                let ic2 = (1.0 / (c * c)) as f32;
                self.accumulate(spec, s, o, true, move |z: f32, m: f32| {
                    let u = z * z * ic2;
                    let t = (1.0 - u).max(0.0);
                    (same_pixel(z, m), m * t * (1.0 - 5.0 * u))
                })
            }
            r => self.accumulate(spec, s, o, true, move |z: f32, m: f32| {
                (same_pixel(z, m), m * r.psi_prime(f64::from(z)) as f32)
            }),
        };
        let mut hpad = hs;
        for i in n..7 {
            hpad[(i, i)] = 1.0;
        }
        let use_psi = hpad.cholesky().is_some();
        let mut sens = if use_psi {
            hs
        } else {
            self.normal_equations(spec, robust, s, o, false).0
        };
        for i in n..7 {
            sens[(i, i)] = 1.0;
        }
        let hinv = sens.try_inverse().ok_or(Error::Degenerate { level: 0 })?;
        if !hinv.iter().all(|v| v.is_finite()) {
            return Err(Error::Degenerate { level: 0 });
        }
        Ok((diag, hinv))
    }

    /// Fills the vectors u of the meat (see [`UVectors`]) and returns the per-frame noise
    /// variance implied by the scale `s` and the per-pixel variance gains, and the inlier
    /// fraction.
    fn noise_vectors(&mut self, model: &NoiseModel, s: f64, o: [f64; 2]) -> Result<(f64, f64)> {
        let presmooth = model.presmooth;
        let ka = if presmooth { KERNEL_A } else { 1.0 };
        let table: [f64; 65] = std::array::from_fn(|i| interp_gain(i as f64 / 64.0, presmooth));
        // Every entry is written by `UVectors::spans` (zero where a pixel carries no noise).
        self.u.resize(self.idx.len(), [0.0; 8]);
        let ctx = UVectors {
            spec: model.spec,
            e1: model.moments.0 as f32,
            c: model.robust.c(),
            rejection: model.robust.rejection(),
            s,
            o,
            ka,
            table: &table,
            res: &self.res,
            valid: &self.valid,
            m: &self.m,
            gx: &self.gx,
            gy: &self.gy,
            fx: &self.fx,
            fy: &self.fy,
        };
        let (gain, n_in, m_in, m_all) = if self.bands.len() > 1 {
            // Per-band sums, added in band order.
            let mut parts = Vec::with_capacity(self.bands.len());
            let mut rest = &mut self.u[..];
            for band in &self.bands {
                let (head, tail) = rest.split_at_mut(band.k1 - band.k0);
                parts.push((band, head));
                rest = tail;
            }
            let spans = &self.spans;
            let sums = map_bands(parts, |(band, u)| {
                simd(
                    #[inline(always)]
                    || ctx.spans(&spans[band.s0..band.s1], band.k0, u),
                )
            });
            let mut total = (0.0f64, 0usize, 0.0f64, 0.0f64);
            for (g, n, mi, ma) in sums {
                total = (total.0 + g, total.1 + n, total.2 + mi, total.3 + ma);
            }
            total
        } else {
            simd(
                #[inline(always)]
                || ctx.spans(&self.spans, 0, &mut self.u),
            )
        };
        if n_in == 0 {
            return Err(Error::Degenerate { level: 0 });
        }
        let noise_var = s * s / (gain / n_in as f64);
        let inlier_fraction = if m_all > 0.0 { m_in / m_all } else { 0.0 };
        Ok((noise_var, inlier_fraction))
    }

    /// Σ_s v(s) v(s)ᵀ with v = K ∗ U, U the vectors u scattered onto the noise samples they read:
    /// the pixel itself for the first frame, the interpolation taps around r + d(r) in the second
    /// frame (`l1`). The grid's cells hold one lane per parameter (see `meat`).
    fn meat(&mut self, n: usize, presmooth: bool, l1: Option<&Level>) -> Mat7 {
        let pad = if presmooth { 2usize } else { 0 };
        // Tap offsets −1..=2 around (ix, iy) for the second frame.
        let (tap_lo, tap_hi) = if l1.is_some() {
            (1usize, 2usize)
        } else {
            (0, 0)
        };
        let Some((minx, miny, maxx, maxy)) = self.tap_positions(l1) else {
            return Mat7::zeros();
        };
        let ox = minx as isize - (tap_lo + pad) as isize;
        let oy = miny as isize - (tap_lo + pad) as isize;
        let bw = maxx - minx + 1 + tap_lo + tap_hi + 2 * pad;
        let bh = maxy - miny + 1 + tap_lo + tap_hi + 2 * pad;
        // Large regions: bands of grid rows, each scattering the pixels whose taps reach its rows
        // or the smoothing's halo around them, convolving, and summing the outer products over
        // its own rows only. The cut depends only on the grid, and the bands' sums are added in
        // order, so the result does not depend on the number of threads.
        let nb = if self.bands.len() > 1 {
            bh.div_ceil(GRID_BAND_ROWS)
        } else {
            1
        };
        let rows_per = bh.div_ceil(nb);
        if self.grids.len() < nb {
            self.grids.resize_with(nb, Default::default);
        }
        let grid = Grid {
            n,
            bw,
            bh,
            ox,
            oy,
            pad,
            taps: (tap_lo, tap_hi),
            presmooth,
            l1,
            u: &self.u,
            pos: &self.pos,
            valid: &self.valid,
            fx: &self.fx,
            fy: &self.fy,
            spans: &self.spans,
            span_rows: &self.span_rows,
        };
        let items: Vec<_> = self
            .grids
            .iter_mut()
            .take(nb)
            .enumerate()
            .map(|(b, buf)| (b * rows_per, ((b + 1) * rows_per).min(bh), buf))
            .collect();
        let parts = map_bands(items, |(r0, r1, (cells, tmp))| {
            simd(
                #[inline(always)]
                || grid.band(r0, r1, cells, tmp),
            )
        });
        let mut m = Mat7::zeros();
        for part in parts {
            m += part;
        }
        m
    }

    /// The noise samples the pixels read (the pixel itself, or with `l1` the top-left tap of its
    /// second-frame sample), stored per pixel, each span's range of sample rows, and their box
    /// (min x, min y, max x, max y) over the valid pixels; `None` without one. Once per pixel
    /// (one 32-bit division for the second frame), by bands for large regions (min and max do
    /// not depend on the order).
    fn tap_positions(&mut self, l1: Option<&Level>) -> Option<(usize, usize, usize, usize)> {
        self.pos.resize(self.idx.len(), (0, 0));
        self.span_rows.resize(self.spans.len(), (0, 0));
        let w1 = l1.map_or(1, |l| l.width as u32);
        let (spans, qi, valid) = (&self.spans[..], &self.qi[..], &self.valid[..]);
        let positions = |sp0: usize, kb: usize, pos: &mut [(u32, u32)], rows: &mut [(u32, u32)]| {
            let mut bbox = (u32::MAX, u32::MAX, 0u32, 0u32);
            for (t, sp) in spans[sp0..sp0 + rows.len()].iter().enumerate() {
                let (mut lo, mut hi) = (u32::MAX, 0u32);
                for k in sp.k0..sp.k0 + sp.len {
                    let (x, y) = match l1 {
                        None => ((sp.i0 + k - sp.k0) as u32, sp.j as u32),
                        Some(_) => {
                            let y = qi[k] / w1;
                            (qi[k] - y * w1, y)
                        }
                    };
                    pos[k - kb] = (x, y);
                    if valid[k] != 0 {
                        (bbox.0, bbox.2) = (bbox.0.min(x), bbox.2.max(x));
                        (lo, hi) = (lo.min(y), hi.max(y));
                    }
                }
                (bbox.1, bbox.3) = (bbox.1.min(lo), bbox.3.max(hi));
                rows[t] = (lo, hi);
            }
            bbox
        };
        let (minx, miny, maxx, maxy) = if self.parallel() {
            let mut parts = Vec::with_capacity(self.bands.len());
            let (mut pos, mut rows) = (&mut self.pos[..], &mut self.span_rows[..]);
            for band in &self.bands {
                let (p, p_rest) = pos.split_at_mut(band.k1 - band.k0);
                let (r, r_rest) = rows.split_at_mut(band.s1 - band.s0);
                parts.push((band, p, r));
                (pos, rows) = (p_rest, r_rest);
            }
            map_bands(parts, |(band, p, r)| positions(band.s0, band.k0, p, r))
                .into_iter()
                .fold((u32::MAX, u32::MAX, 0, 0), |a, b| {
                    (a.0.min(b.0), a.1.min(b.1), a.2.max(b.2), a.3.max(b.3))
                })
        } else {
            positions(0, 0, &mut self.pos, &mut self.span_rows)
        };
        if minx > maxx {
            return None;
        }
        Some((minx as usize, miny as usize, maxx as usize, maxy as usize))
    }
}

/// Grid rows per band of the covariance grid for large regions (see `Workspace::meat`).
const GRID_BAND_ROWS: usize = 128;

/// The per-pixel vectors u = m E[ψ'] J of the covariance's meat, and the sums of the noise
/// model (variance gains, inlier counts and weights).
struct UVectors<'a> {
    spec: ModelSpec,
    e1: f32,
    c: f64,
    rejection: Option<f64>,
    s: f64,
    o: [f64; 2],
    ka: f64,
    table: &'a [f64; 65],
    res: &'a [f32],
    valid: &'a [u8],
    m: &'a [f32],
    gx: &'a [f32],
    gy: &'a [f32],
    fx: &'a [f32],
    fy: &'a [f32],
}

impl UVectors<'_> {
    /// Fills `u` (entries from `kb` on) over `spans`; returns (Σ variance gain, inlier count,
    /// inlier weight, total weight).
    #[inline(always)]
    fn spans(&self, spans: &[Span], kb: usize, u: &mut [[f32; 8]]) -> (f64, usize, f64, f64) {
        let (spec, s, c, o) = (self.spec, self.s, self.c, self.o);
        let ng = spec.model.geometric_len();
        let ka = self.ka;
        // f ∈ [0, 1): the 32-bit conversion is shorter than the saturating one to usize.
        let q = |f: f64| self.table[((f * 64.0 + 0.5) as i32).clamp(0, 64) as usize];
        let (mut gain, mut n_in, mut m_in, mut m_all) = (0.0f64, 0usize, 0.0f64, 0.0f64);
        for sp in spans {
            let y = (sp.j as f64 - o[1]) as f32;
            let x_first = (sp.i0 as f64 - o[0]) as f32;
            for k in sp.k0..sp.k0 + sp.len {
                let u = &mut u[k - kb];
                *u = [0.0; 8];
                if self.valid[k] == 0 {
                    continue;
                }
                // Only pixels that stay in the image count.
                m_all += f64::from(self.m[k]);
                let z = f64::from(self.res[k]) / s;
                if z.abs() < c {
                    let (fx, fy) = (f64::from(self.fx[k]), f64::from(self.fy[k]));
                    gain += ka * ka + q(fx) * q(fy);
                    n_in += 1;
                    m_in += f64::from(self.m[k]);
                }
                // Pixels a redescending ρ rejects carry no noise into Θ̂.
                if self.rejection.is_some_and(|r| z.abs() >= r) {
                    continue;
                }
                let me = self.m[k] * self.e1;
                let (gx, gy) = (self.gx[k] * me, self.gy[k] * me);
                let x = x_first + (k - sp.k0) as f32;
                match spec.model {
                    MotionModel::Translation => {
                        (u[0], u[1]) = (gx, gy);
                    }
                    MotionModel::Scale => {
                        (u[0], u[1], u[2]) = (gx, gy, gx * x + gy * y);
                    }
                    MotionModel::Affine => {
                        (u[0], u[1], u[2]) = (gx, gx * x, gx * y);
                        (u[3], u[4], u[5]) = (gy, gy * x, gy * y);
                    }
                }
                if spec.offset {
                    u[ng] = -me;
                }
            }
        }
        (gain, n_in, m_in, m_all)
    }
}
