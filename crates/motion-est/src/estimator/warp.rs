//! Residuals of the displaced frame difference and the Jacobian's gradients: the warp of the
//! second frame and its interpolation.

use std::ops::Range;

use super::workspace::{Span, map_bands};
use super::{Vec7, Workspace};
use crate::model::{ModelSpec, MotionModel};
use crate::pyramid::Level;
use crate::simd::simd;

/// The displacement of any model written as affine coefficients (a1..a6 of Eq. 13).
fn affine_coefficients(model: MotionModel, p: &[f64; 7]) -> [f64; 6] {
    match model {
        MotionModel::Translation => [p[0], 0.0, 0.0, p[1], 0.0, 0.0],
        MotionModel::Scale => [p[0], p[2], 0.0, p[1], 0.0, p[2]],
        MotionModel::Affine => [p[0], p[1], p[2], p[3], p[4], p[5]],
    }
}

#[inline(always)]
fn bilinear(d: &[f32], i00: usize, w: usize, fx: f32, fy: f32) -> f32 {
    let top = d[i00] + fx * (d[i00 + 1] - d[i00]);
    let bot = d[i00 + w] + fx * (d[i00 + w + 1] - d[i00 + w]);
    top + fy * (bot - top)
}

/// Keys' cubic convolution weights (a = −0.5) of the taps −1, 0, 1, 2 at fraction `f`.
#[inline(always)]
pub(crate) fn cubic_weights(f: f32) -> [f32; 4] {
    let f2 = f * f;
    let f3 = f2 * f;
    [
        -0.5 * f3 + f2 - 0.5 * f,
        1.5 * f3 - 2.5 * f2 + 1.0,
        -1.5 * f3 + 2.0 * f2 + 0.5 * f,
        0.5 * f3 - 0.5 * f2,
    ]
}

#[inline(always)]
fn bicubic(d: &[f32], i00: usize, w: usize, fx: f32, fy: f32) -> f32 {
    let wx = cubic_weights(fx);
    let wy = cubic_weights(fy);
    // Columns first: four rows of four taps, each one 4-lane load and multiply–add, then one dot
    // product with the x weights.
    let base = i00 - w - 1;
    let mut col = [0.0f32; 4];
    for (r, wyr) in wy.iter().enumerate() {
        let row: &[f32; 4] = match d[base + r * w..base + r * w + 4].try_into() {
            Ok(row) => row,
            Err(_) => unreachable!("a slice of length 4"),
        };
        for (c, v) in col.iter_mut().zip(row) {
            *c += wyr * v;
        }
    }
    (wx[0] * col[0] + wx[1] * col[1]) + (wx[2] * col[2] + wx[3] * col[3])
}

impl Workspace {
    /// Moves the residuals of the last full-resolution evaluation, at Θ, to Θ̂ = Θ − δ to first
    /// order: r(Θ̂) ≈ r(Θ) − J δ, with the Jacobian J that IRLS used at Θ (mapped gradients; the
    /// offset's −1), i.e. r −= ∇I·d_δ(x) − δ_c. Only the residuals move: the gradients, the
    /// sample positions and the interpolation taps stay those at Θ (the covariance reads them one
    /// step away, as when the residuals are reused below `REUSE_STEP`).
    ///
    /// The error is the second-order term ½ d_δᵀ ∇²I d_δ plus (∇I₁(q) − J)·d_δ, the difference
    /// between the second frame's gradient at the sample and the mapped first-frame gradient. For
    /// a step |d_δ| ≤ `LINEAR_STEP` = 0.1 px the first is ≤ 0.005 |∇²I| (grey levels/px²), and
    /// the second, dominated by the noise's gradient, ≤ 0.1 |∇n| ≈ 0.1 σ: both negligible against
    /// the noise σ, so the robust scale and the covariance are those at Θ̂ to well under their own
    /// sampling error (checked: accuracy and calibration tests, ratios moved by < 0.02).
    pub(super) fn linearise(&mut self, spec: ModelSpec, delta: &Vec7, o: [f64; 2]) {
        let ng = spec.model.geometric_len();
        let dc = if spec.offset { delta[ng] as f32 } else { 0.0 };
        let mut p = [0.0f64; 7];
        p[..ng].copy_from_slice(&delta.as_slice()[..ng]);
        let a = affine_coefficients(spec.model, &p);
        let (a1, a4) = (a[1] as f32, a[4] as f32);
        for sp in &self.spans {
            let y = sp.j as f64 - o[1];
            let x0 = sp.i0 as f64 - o[0];
            // d_δ(x, y) = (dx0 + a1 t, dy0 + a4 t) at pixel t of the span.
            let dx0 = (a[0] + a[1] * x0 + a[2] * y) as f32;
            let dy0 = (a[3] + a[4] * x0 + a[5] * y) as f32;
            let r = sp.k0..sp.k0 + sp.len;
            let it = self.res[r.clone()]
                .iter_mut()
                .zip(&self.gx[r.clone()])
                .zip(&self.gy[r]);
            for (t, ((res, &gx), &gy)) in it.enumerate() {
                let tf = t as f32;
                *res -= gx * (dx0 + a1 * tf) + gy * (dy0 + a4 * tf) - dc;
            }
        }
    }

    /// The residuals and validity of the listed pixels under a whole-pixel translation Θ (its
    /// linear part zero, its translation whole level pixels), exactly as
    /// [`evaluate`](Self::evaluate) computes them, without the gradients; any other Θ is
    /// evaluated in full. The second frame is then read at its own pixels, where both
    /// interpolations return the pixel itself (Keys' weights are (0, 1, 0, 0) at fraction 0), so
    /// an interior sample is one read. What a cold start's search of translations ranks by.
    pub(super) fn residuals_at_shift(
        &mut self,
        l0: &Level,
        l1: &Level,
        spec: ModelSpec,
        theta: &[f64; 7],
        o: [f64; 2],
        full_res: bool,
    ) -> usize {
        let a = affine_coefficients(spec.model, theta);
        let whole = |v: f64| v.fract() == 0.0 && v.abs() < 1e9;
        if a[1] != 0.0 || a[2] != 0.0 || a[4] != 0.0 || a[5] != 0.0 || !whole(a[0]) || !whole(a[3])
        {
            return self.evaluate(l0, l1, spec, theta, o, full_res);
        }
        let n = self.idx.len();
        self.res.resize(n, 0.0);
        self.valid.resize(n, 0);
        let Some(warp) = Warp::new(l0, l1, spec, theta, o, full_res) else {
            self.valid.fill(0);
            return 0;
        };
        let (d1, w1, h1) = (&l1.data[..], l1.width, l1.height);
        let mut n_valid = 0;
        for sp in &self.spans {
            let first = self.idx[sp.k0] as usize;
            let z0 = &l0.data[first..first + sp.len];
            let r = sp.k0..sp.k0 + sp.len;
            let iter = self.res[r.clone()]
                .iter_mut()
                .zip(&mut self.valid[r])
                .zip(z0);
            for (t, ((res, valid), &z0)) in iter.enumerate() {
                let Some(q) = warp.sample(sp, sp.i0 + t) else {
                    *valid = 0;
                    continue;
                };
                let v = if full_res && q.ix >= 1 && q.iy >= 1 && q.ix + 2 < w1 && q.iy + 2 < h1 {
                    // Unclamped, so at fraction 0: the bicubic sample is the pixel.
                    *valid = 2;
                    d1[q.i00]
                } else {
                    *valid = 1;
                    bilinear(d1, q.i00, w1, q.fx, q.fy)
                };
                *res = v - z0 - warp.offset;
                n_valid += 1;
            }
        }
        n_valid
    }

    /// Residuals, gradients and validity of the listed pixels under Θ (level units, origin `o`).
    /// At full resolution (`full_res`) the second frame is sampled bicubically and the Jacobian uses
    /// the first frame's gradient mapped through (I + D)^−T; at coarse levels it is sampled
    /// bilinearly and the two frames' gradients are averaged (wider convergence basin).
    pub(super) fn evaluate(
        &mut self,
        l0: &Level,
        l1: &Level,
        spec: ModelSpec,
        theta: &[f64; 7],
        o: [f64; 2],
        full_res: bool,
    ) -> usize {
        let n = self.idx.len();
        self.res.resize(n, 0.0);
        self.gx.resize(n, 0.0);
        self.gy.resize(n, 0.0);
        self.fx.resize(n, 0.0);
        self.fy.resize(n, 0.0);
        self.qi.resize(n, 0);
        self.valid.resize(n, 0);
        let Some(ctx) = Warp::new(l0, l1, spec, theta, o, full_res) else {
            self.valid.fill(0);
            return 0;
        };
        let par = self.parallel();
        let out = Samples {
            res: &mut self.res,
            gx: &mut self.gx,
            gy: &mut self.gy,
            fx: &mut self.fx,
            fy: &mut self.fy,
            qi: &mut self.qi,
            valid: &mut self.valid,
        };
        let (spans, idx) = (&self.spans[..], &self.idx[..]);
        if !par {
            return simd(
                #[inline(always)]
                || ctx.spans(spans, idx, 0, out),
            );
        }
        // Every pixel's outputs depend on that pixel alone: the bands write disjoint slices.
        let mut outs = Vec::with_capacity(self.bands.len());
        let mut rest = out;
        for band in &self.bands {
            let (head, tail) = rest.split_at(band.k1 - band.k0);
            outs.push((band, head));
            rest = tail;
        }
        map_bands(outs, |(band, o)| {
            simd(
                #[inline(always)]
                || ctx.spans(&spans[band.s0..band.s1], idx, band.k0, o),
            )
        })
        .into_iter()
        .sum()
    }
}

/// The per-pixel outputs of `evaluate` for a run of pixels.
struct Samples<'a> {
    res: &'a mut [f32],
    gx: &'a mut [f32],
    gy: &'a mut [f32],
    fx: &'a mut [f32],
    fy: &'a mut [f32],
    qi: &'a mut [u32],
    valid: &'a mut [u8],
}

impl<'a> Samples<'a> {
    /// The first `mid` pixels and the rest.
    fn split_at(self, mid: usize) -> (Self, Self) {
        let (res, res2) = self.res.split_at_mut(mid);
        let (gx, gx2) = self.gx.split_at_mut(mid);
        let (gy, gy2) = self.gy.split_at_mut(mid);
        let (fx, fx2) = self.fx.split_at_mut(mid);
        let (fy, fy2) = self.fy.split_at_mut(mid);
        let (qi, qi2) = self.qi.split_at_mut(mid);
        let (valid, valid2) = self.valid.split_at_mut(mid);
        (
            Self {
                res,
                gx,
                gy,
                fx,
                fy,
                qi,
                valid,
            },
            Self {
                res: res2,
                gx: gx2,
                gy: gy2,
                fx: fx2,
                fy: fy2,
                qi: qi2,
                valid: valid2,
            },
        )
    }
}

/// The warp of `evaluate` in the second frame's window: q = c + B·r, the gradient map
/// (I + D)^−T, the intensity offset, both levels, and whether this is full resolution.
struct Warp<'l> {
    c: [f64; 2],
    b: [f64; 4],
    t: [f32; 4],
    offset: f32,
    l0: &'l Level,
    l1: &'l Level,
    full_res: bool,
}

impl<'l> Warp<'l> {
    /// The warp of Θ (level units, origin `o`) from the first frame's level `l0` into the
    /// second's `l1`; `None` when `l1` is too small to sample.
    fn new(
        l0: &'l Level,
        l1: &'l Level,
        spec: ModelSpec,
        theta: &[f64; 7],
        o: [f64; 2],
        full_res: bool,
    ) -> Option<Self> {
        let ng = spec.model.geometric_len();
        let offset = if spec.offset { theta[ng] } else { 0.0 } as f32;
        let a = affine_coefficients(spec.model, theta);
        // q = r + d(r) in the second frame's window: q = c + B·r.
        let (bx1, bx2, by1, by2) = (1.0 + a[1], a[2], a[4], 1.0 + a[5]);
        let cx = a[0] - a[1] * o[0] - a[2] * o[1] - l1.x0 as f64;
        let cy = a[3] - a[4] * o[0] - a[5] * o[1] - l1.y0 as f64;
        // (I + D)^−T = [[by2, −by1], [−bx2, bx1]] / det maps ∇z₀ to ∇z₁.
        let det = bx1 * by2 - bx2 * by1;
        let (t11, t12, t21, t22) = if det.abs() > 1e-6 {
            (
                (by2 / det) as f32,
                (-by1 / det) as f32,
                (-bx2 / det) as f32,
                (bx1 / det) as f32,
            )
        } else {
            (1.0, 0.0, 0.0, 1.0)
        };
        (l1.width >= 2 && l1.height >= 2).then_some(Self {
            c: [cx, cy],
            b: [bx1, bx2, by1, by2],
            t: [t11, t12, t21, t22],
            offset,
            l0,
            l1,
            full_res,
        })
    }
}

impl Warp<'_> {
    /// `evaluate` over `spans`, whose pixels start at entry `kb` (where `out` starts); `idx` is
    /// the whole pixel list. Returns the number of valid samples.
    ///
    /// Full resolution: the sample loop computes only the residual and where it was taken; the
    /// Jacobian's gradients (the first frame's, mapped through (I + D)^−T) are read from
    /// contiguous rows in a second, vectorisable loop. Coarse levels: bilinear values and
    /// second-frame gradients in the sample loop, then the first frame's mapped gradients
    /// averaged in the same way; the sample positions are not stored (only the full-resolution
    /// covariance reads them). A span's pixels are consecutive in the first frame's level, so
    /// its rows there are plain slices.
    #[inline(always)]
    fn spans(&self, spans: &[Span], idx: &[u32], kb: usize, mut out: Samples<'_>) -> usize {
        let mut n_valid = 0;
        for sp in spans {
            let r = sp.k0 - kb..sp.k0 - kb + sp.len;
            let first = idx[sp.k0] as usize;
            if self.full_res {
                n_valid += self.full_res_span(sp, first, r.clone(), &mut out);
                self.map_gradients::<false>(first, &mut out.gx[r.clone()], &mut out.gy[r]);
            } else {
                n_valid += self.coarse_span(sp, first, r.clone(), &mut out);
                self.map_gradients::<true>(first, &mut out.gx[r.clone()], &mut out.gy[r]);
            }
        }
        n_valid
    }

    /// The second frame's sample position of column `x` on the span's row.
    #[inline(always)]
    fn sample(&self, sp: &Span, x: usize) -> Option<Sample> {
        let [cx, cy] = self.c;
        let [bx1, bx2, by1, by2] = self.b;
        let (y, x) = (sp.j as f64, x as f64);
        let (w1, h1) = (self.l1.width, self.l1.height);
        let (qx, qy) = (cx + bx2 * y + bx1 * x, cy + by2 * y + by1 * x);
        Sample::at(qx, qy, (w1 - 1) as f64, (h1 - 1) as f64, w1, h1)
    }

    /// Full resolution, one span (entries `r`, first pixel `first` in the first frame's level):
    /// where each sample falls and which taps it uses (`valid` 2 for the bicubic interior, 1 for
    /// the bilinear border), then the residuals. Bicubic: bilinear interpolation error on fine
    /// texture would bias the estimate and inflate the residual scale. (Two short loops keep the
    /// interpolation's operands in registers; one long loop spilled them.)
    #[inline(always)]
    fn full_res_span(
        &self,
        sp: &Span,
        first: usize,
        r: Range<usize>,
        out: &mut Samples<'_>,
    ) -> usize {
        let (w1, h1) = (self.l1.width, self.l1.height);
        let pos = out.fx[r.clone()]
            .iter_mut()
            .zip(&mut out.fy[r.clone()])
            .zip(&mut out.qi[r.clone()])
            .zip(&mut out.valid[r.clone()]);
        for (t, (((fxo, fyo), qio), valid)) in pos.enumerate() {
            *valid = match self.sample(sp, sp.i0 + t) {
                Some(Sample {
                    ix,
                    iy,
                    fx,
                    fy,
                    i00,
                }) => {
                    (*fxo, *fyo, *qio) = (fx, fy, i00 as u32);
                    if ix >= 1 && iy >= 1 && ix + 2 < w1 && iy + 2 < h1 {
                        2
                    } else {
                        1
                    }
                }
                None => 0,
            };
        }
        let (d1, z0) = (&self.l1.data[..], &self.l0.data[first..first + sp.len]);
        let vals = out.res[r.clone()]
            .iter_mut()
            .zip(&out.fx[r.clone()])
            .zip(&out.fy[r.clone()])
            .zip(&out.qi[r.clone()])
            .zip(&out.valid[r])
            .zip(z0);
        let mut n_valid = 0;
        for (((((res, &fx), &fy), &qi), &valid), &z0) in vals {
            let i00 = qi as usize;
            let v = match valid {
                0 => continue,
                2 => bicubic(d1, i00, w1, fx, fy),
                _ => bilinear(d1, i00, w1, fx, fy),
            };
            *res = v - z0 - self.offset;
            n_valid += 1;
        }
        n_valid
    }

    /// A coarse level, one span: bilinear residuals and the second frame's gradients.
    #[inline(always)]
    fn coarse_span(
        &self,
        sp: &Span,
        first: usize,
        r: Range<usize>,
        out: &mut Samples<'_>,
    ) -> usize {
        let (l1, w1) = (self.l1, self.l1.width);
        let z0 = &self.l0.data[first..first + sp.len];
        let iter = out.res[r.clone()]
            .iter_mut()
            .zip(&mut out.gx[r.clone()])
            .zip(&mut out.gy[r.clone()])
            .zip(&mut out.valid[r])
            .zip(z0);
        let mut n_valid = 0;
        for (t, ((((res, gxo), gyo), valid), &z0)) in iter.enumerate() {
            let Some(Sample { fx, fy, i00, .. }) = self.sample(sp, sp.i0 + t) else {
                *valid = 0;
                continue;
            };
            *res = bilinear(&l1.data, i00, w1, fx, fy) - z0 - self.offset;
            *gxo = bilinear(&l1.gx, i00, w1, fx, fy);
            *gyo = bilinear(&l1.gy, i00, w1, fx, fy);
            *valid = 1;
            n_valid += 1;
        }
        n_valid
    }

    /// The first frame's gradients at the span's pixels (from `first` in its level) mapped
    /// through (I + D)^−T into `gx`, `gy`; with `AVERAGE` (coarse levels) averaged with what they
    /// hold, the second frame's gradients.
    #[inline(always)]
    fn map_gradients<const AVERAGE: bool>(&self, first: usize, gx: &mut [f32], gy: &mut [f32]) {
        let [t11, t12, t21, t22] = self.t;
        let n = gx.len();
        let (g0x, g0y) = (&self.l0.gx[first..first + n], &self.l0.gy[first..first + n]);
        for (((gxo, gyo), &ax), &ay) in gx.iter_mut().zip(gy).zip(g0x).zip(g0y) {
            if AVERAGE {
                *gxo = 0.5 * (*gxo + t11 * ax + t12 * ay);
                *gyo = 0.5 * (*gyo + t21 * ax + t22 * ay);
            } else {
                *gxo = t11 * ax + t12 * ay;
                *gyo = t21 * ax + t22 * ay;
            }
        }
    }
}

/// Where a warped position falls in the second frame: the top-left pixel of its 2×2 cell, the
/// fractional offsets and the flat index; `None` outside [0, xmax] × [0, ymax].
#[derive(Debug, Clone, Copy)]
struct Sample {
    ix: usize,
    iy: usize,
    fx: f32,
    fy: f32,
    i00: usize,
}

impl Sample {
    #[inline(always)]
    fn at(qx: f64, qy: f64, xmax: f64, ymax: f64, w1: usize, h1: usize) -> Option<Self> {
        if !(qx >= 0.0 && qy >= 0.0 && qx <= xmax && qy <= ymax) {
            return None;
        }
        // In range (checked above, and images are far smaller than 2³¹ pixels): the 32-bit
        // conversion is a few instructions shorter than the saturating one to usize.
        let ix = (qx as i32 as usize).min(w1 - 2);
        let iy = (qy as i32 as usize).min(h1 - 2);
        Some(Self {
            ix,
            iy,
            fx: (qx - ix as f64) as f32,
            fy: (qy - iy as f64) as f32,
            i00: iy * w1 + ix,
        })
    }
}
