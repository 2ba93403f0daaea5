//! The IRLS normal equations, accumulated in f32 lanes along the row spans.

use super::workspace::{Span, map_bands};
use super::{Mat7, Vec7, Workspace};
use crate::model::{ModelSpec, MotionModel};
use crate::robust::RobustFunction;
use crate::simd::simd;

/// Eight consecutive pixels of a span in f32 lanes: residuals, gradients and the two weights.
#[derive(Default)]
struct Group {
    r: [f32; 8],
    gx: [f32; 8],
    gy: [f32; 8],
    w: [f32; 8],
    wp: [f32; 8],
}

/// f32 lane accumulators of the normal equations (upper triangles).
struct Lanes<const N: usize> {
    h: [[[f32; 8]; N]; N],
    hp: [[[f32; 8]; N]; N],
    b: [[f32; 8]; N],
}

impl<const N: usize> Default for Lanes<N> {
    fn default() -> Self {
        Self {
            h: [[[0.0; 8]; N]; N],
            hp: [[[0.0; 8]; N]; N],
            b: [[0.0; 8]; N],
        }
    }
}

impl<const N: usize> Lanes<N> {
    #[inline(always)]
    fn add<const PSI: bool>(
        &mut self,
        j: &[[f32; 8]; N],
        w: &[f32; 8],
        wp: &[f32; 8],
        r: &[f32; 8],
    ) {
        for a in 0..N {
            let wa: [f32; 8] = std::array::from_fn(|l| w[l] * j[a][l]);
            for l in 0..8 {
                self.b[a][l] += wa[l] * r[l];
            }
            for (hab, jb) in self.h[a].iter_mut().zip(j.iter()).skip(a) {
                for l in 0..8 {
                    hab[l] += wa[l] * jb[l];
                }
            }
            if PSI {
                let pa: [f32; 8] = std::array::from_fn(|l| wp[l] * j[a][l]);
                for (hab, jb) in self.hp[a].iter_mut().zip(j.iter()).skip(a) {
                    for l in 0..8 {
                        hab[l] += pa[l] * jb[l];
                    }
                }
            }
        }
    }

    /// Adds the lane sums to `h`, `hp` (only with `PSI`: otherwise its lanes stayed zero) and
    /// `b`, and clears the lanes.
    fn flush<const PSI: bool>(
        &mut self,
        h: &mut [[f64; N]; N],
        hp: &mut [[f64; N]; N],
        b: &mut [f64; N],
    ) {
        let sum = |lanes: &mut [f32; 8]| {
            let total = lanes.iter().map(|&v| f64::from(v)).sum::<f64>();
            *lanes = [0.0; 8];
            total
        };
        for a in 0..N {
            b[a] += sum(&mut self.b[a]);
            for bb in a..N {
                h[a][bb] += sum(&mut self.h[a][bb]);
                if PSI {
                    hp[a][bb] += sum(&mut self.hp[a][bb]);
                }
            }
        }
    }
}

impl Workspace {
    /// IRLS normal equations H = Σ m w J Jᵀ and g = Σ m w J r, and, with `with_psi`, the sensitivity
    /// Σ m ψ'(r/s) J Jᵀ of the sandwich covariance, in one pass.
    pub(super) fn normal_equations(
        &self,
        spec: ModelSpec,
        robust: RobustFunction,
        s: f64,
        o: [f64; 2],
        with_psi: bool,
    ) -> (Mat7, Vec7, Mat7) {
        // The weight functions in f32, monomorphised so that the lane loops vectorise. Tukey is
        // written branch-free: t = max(1 − u, 0) gives w = t² and ψ' = t(1 − 5u), both 0 for u ≥ 1.
        match robust {
            RobustFunction::Tukey { c } => {
                let ic2 = (1.0 / (c * c)) as f32;
                self.accumulate(spec, s, o, with_psi, move |z: f32, m: f32| {
                    let u = z * z * ic2;
                    let t = (1.0 - u).max(0.0);
                    (m * t * t, m * t * (1.0 - 5.0 * u))
                })
            }
            r => self.accumulate(spec, s, o, with_psi, move |z: f32, m: f32| {
                let z = f64::from(z);
                (m * r.weight(z) as f32, m * r.psi_prime(z) as f32)
            }),
        }
    }

    /// The `cnt` ≤ 8 pixels from entry `k` as f32 lanes, with their weights (w, w₂) =
    /// `weights(r/s, m)`. Invalid pixels and unused lanes get zero values and weights (their stored
    /// values may be stale).
    #[inline(always)]
    fn group<F: Fn(f32, f32) -> (f32, f32)>(
        &self,
        k: usize,
        cnt: usize,
        inv_s: f32,
        weights: &F,
    ) -> Group {
        let mut g = Group::default();
        let mut m = [0.0f32; 8];
        for (l, ml) in m.iter_mut().enumerate().take(cnt) {
            if self.valid[k + l] != 0 {
                g.r[l] = self.res[k + l];
                g.gx[l] = self.gx[k + l];
                g.gy[l] = self.gy[k + l];
                *ml = self.m[k + l];
            }
        }
        for (l, &ml) in m.iter().enumerate() {
            (g.w[l], g.wp[l]) = weights(g.r[l] * inv_s, ml);
        }
        g
    }

    /// Σ w J Jᵀ, Σ w J r and, with `second`, Σ w₂ J Jᵀ, where (w, w₂) = `weights(r/s, m)`.
    ///
    /// Along a row span y is constant, so every Jacobian entry (as in
    /// `MotionModel::gradient_row`) is one of a few per-pixel lane rows times 1 or y: translation
    /// (gx, gy), scale (gx, gy, gx·x + gy·y), affine (gx, gx·x, gy, gy·x), then −1 for the offset.
    /// The lanes accumulate the rows' moments over a span, which is folded into H, H₂ and g with
    /// the factors y^(i+j): for the affine model 14 lane sums per pixel instead of the 27 of J Jᵀ.
    pub(super) fn accumulate<F: Fn(f32, f32) -> (f32, f32) + Sync>(
        &self,
        spec: ModelSpec,
        s: f64,
        o: [f64; 2],
        second: bool,
        weights: F,
    ) -> (Mat7, Vec7, Mat7) {
        // Parameter a is lane row map[a].0 times y^map[a].1.
        let (geometric, row_count): (&[(usize, usize)], usize) = match spec.model {
            MotionModel::Translation => (&[(0, 0), (1, 0)], 2),
            MotionModel::Scale => (&[(0, 0), (1, 0), (2, 0)], 3),
            MotionModel::Affine => (&[(0, 0), (1, 0), (0, 1), (2, 0), (3, 0), (2, 1)], 4),
        };
        let mut map = [(0usize, 0usize); 7];
        map[..geometric.len()].copy_from_slice(geometric);
        map[geometric.len()] = (row_count, 0);
        let rows = |g: &Group, x: &[f32; 8], y: f32| -> [[f32; 8]; 5] {
            // Rows past the model's are the offset's −1.
            let mut r = [[-1.0f32; 8]; 5];
            (r[0], r[1]) = (g.gx, g.gy);
            match spec.model {
                MotionModel::Translation => {}
                MotionModel::Scale => {
                    r[2] = std::array::from_fn(|l| g.gx[l] * x[l] + g.gy[l] * y);
                }
                MotionModel::Affine => {
                    r[1] = std::array::from_fn(|l| g.gx[l] * x[l]);
                    r[2] = g.gy;
                    r[3] = std::array::from_fn(|l| g.gy[l] * x[l]);
                }
            }
            r
        };
        // Lane rows P and parameters N, known at compile time for each model.
        macro_rules! spans {
            ($p:literal, $n:literal) => {{
                let map: [(usize, usize); $n] = std::array::from_fn(|a| map[a]);
                if second {
                    self.accumulate_spans::<$p, $n, true, _, _>(s, o, &weights, rows, &map)
                } else {
                    self.accumulate_spans::<$p, $n, false, _, _>(s, o, &weights, rows, &map)
                }
            }};
        }
        match (spec.model, spec.offset) {
            (MotionModel::Translation, false) => spans!(2, 2),
            (MotionModel::Translation, true) => spans!(3, 3),
            (MotionModel::Scale, false) => spans!(3, 3),
            (MotionModel::Scale, true) => spans!(4, 4),
            (MotionModel::Affine, false) => spans!(4, 6),
            (MotionModel::Affine, true) => spans!(5, 7),
        }
    }

    /// The span walk of [`accumulate`](Self::accumulate): eight contiguous pixels at a time in f32
    /// lanes (residual scaling, weights and the `P` lane rows computed in the lanes), the moments
    /// flushed to f64 at the end of each span (and every 64 groups, so that f32 sums stay short),
    /// then folded into the parameters' matrices through `map`.
    fn accumulate_spans<const P: usize, const N: usize, const PSI: bool, F, R>(
        &self,
        s: f64,
        o: [f64; 2],
        weights: &F,
        rows: R,
        map: &[(usize, usize); N],
    ) -> (Mat7, Vec7, Mat7)
    where
        F: Fn(f32, f32) -> (f32, f32) + Sync,
        R: Fn(&Group, &[f32; 8], f32) -> [[f32; 8]; 5] + Sync,
    {
        let band = |spans: &[Span]| {
            simd(
                #[inline(always)]
                || self.accumulate_band::<P, N, PSI, F, R>(spans, s, o, weights, &rows, map),
            )
        };
        // Bands whenever the region has several, with or without the `parallel` feature, so that
        // the sums are the same either way.
        let (mut hm, bv, mut hpm) = if self.bands.len() > 1 {
            // Per-band sums, added in band order.
            let parts = map_bands(self.bands.clone(), |b| band(&self.spans[b.s0..b.s1]));
            let mut total = (Mat7::zeros(), Vec7::zeros(), Mat7::zeros());
            for (h, b, hp) in parts {
                total.0 += h;
                total.1 += b;
                total.2 += hp;
            }
            total
        } else {
            band(&self.spans)
        };
        for a in 0..N {
            for c in a + 1..N {
                hm[(c, a)] = hm[(a, c)];
                hpm[(c, a)] = hpm[(a, c)];
            }
        }
        (hm, bv, hpm)
    }

    /// [`accumulate_spans`](Self::accumulate_spans) over some spans: upper triangles only.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn accumulate_band<const P: usize, const N: usize, const PSI: bool, F, R>(
        &self,
        spans: &[Span],
        s: f64,
        o: [f64; 2],
        weights: &F,
        rows: &R,
        map: &[(usize, usize); N],
    ) -> (Mat7, Vec7, Mat7)
    where
        F: Fn(f32, f32) -> (f32, f32),
        R: Fn(&Group, &[f32; 8], f32) -> [[f32; 8]; 5],
    {
        let mut acc = Lanes::<P>::default();
        let (mut hm, mut hpm, mut bv) = (Mat7::zeros(), Mat7::zeros(), Vec7::zeros());
        let inv_s = (1.0 / s) as f32;
        for sp in spans {
            let y = sp.j as f64 - o[1];
            let x_first = (sp.i0 as f64 - o[0]) as f32;
            let (mut h, mut hp, mut b) = ([[0.0f64; P]; P], [[0.0f64; P]; P], [0.0f64; P]);
            let mut groups = 0usize;
            for t in (0..sp.len).step_by(8) {
                let g = self.group(sp.k0 + t, (sp.len - t).min(8), inv_s, weights);
                let xl: [f32; 8] = std::array::from_fn(|l| x_first + (t + l) as f32);
                let all = rows(&g, &xl, y as f32);
                let pl: [[f32; 8]; P] = std::array::from_fn(|a| all[a]);
                acc.add::<PSI>(&pl, &g.w, &g.wp, &g.r);
                groups += 1;
                if groups == 64 {
                    acc.flush::<PSI>(&mut h, &mut hp, &mut b);
                    groups = 0;
                }
            }
            acc.flush::<PSI>(&mut h, &mut hp, &mut b);
            let y_pow = [1.0, y, y * y];
            for (a, &(ia, pa)) in map.iter().enumerate() {
                bv[a] += b[ia] * y_pow[pa];
                for (c, &(ic, pc)) in map.iter().enumerate().skip(a) {
                    let (i, j) = (ia.min(ic), ia.max(ic));
                    let f = y_pow[pa + pc];
                    hm[(a, c)] += h[i][j] * f;
                    if PSI {
                        hpm[(a, c)] += hp[i][j] * f;
                    }
                }
            }
        }
        (hm, bv, hpm)
    }
}
