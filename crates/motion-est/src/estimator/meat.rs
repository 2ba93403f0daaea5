//! The "meat" of the sandwich covariance (see [`crate::estimator`]): Σ_s v(s) v(s)ᵀ with
//! v = K ∗ U, where U holds the per-pixel vectors u = m E\[ψ'\] J scattered onto the noise samples
//! their residuals read — the pixel itself in the first frame, the 4×4 interpolation taps around
//! r + d(r) in the second — and K is the pre-smoothing kernel.
//!
//! The grid is a dense array of 8-lane cells, one lane per parameter (at most 7), so that every
//! step works on whole cells: a pixel's scatter is 16 cell updates, the separable convolution is
//! five cell products per pass, and the outer product of a cell is one broadcast product per
//! parameter. The loops are written on `[f32; 8]` and compiled for the best instruction set
//! available at run time ([`crate::simd::simd`]); the arithmetic (separate products and sums,
//! fixed order) is the same on every instruction set, so the result does not depend on the
//! machine's.

use super::Mat7;
use super::warp::cubic_weights;
use super::workspace::{Cell, Span};
use crate::pyramid::{KERNEL, Level};

/// The grid of one frame: `bw`×`bh` cells with origin (`ox`, `oy`) in the level, onto which the
/// per-pixel vectors `u` are scattered at `pos` (through the interpolation taps at fractions
/// (`fx`, `fy`) for the second frame, `l1`), then convolved.
pub(crate) struct Grid<'a> {
    /// Channels used (the model's parameter count).
    pub(crate) n: usize,
    pub(crate) bw: usize,
    pub(crate) bh: usize,
    pub(crate) ox: isize,
    pub(crate) oy: isize,
    /// Half-width of the smoothing kernel (0 without pre-smoothing).
    pub(crate) pad: usize,
    /// Taps before and after the sample position (1 and 2 for the second frame, else 0).
    pub(crate) taps: (usize, usize),
    pub(crate) presmooth: bool,
    pub(crate) l1: Option<&'a Level>,
    pub(crate) u: &'a [Cell],
    pub(crate) pos: &'a [(u32, u32)],
    pub(crate) valid: &'a [u8],
    pub(crate) fx: &'a [f32],
    pub(crate) fy: &'a [f32],
    pub(crate) spans: &'a [Span],
    /// Per span, the lowest and highest sample row of its valid pixels.
    pub(crate) span_rows: &'a [(u32, u32)],
}

impl Grid<'_> {
    /// Σ v vᵀ over grid rows `r0..r1`, computed on rows `r0 − pad .. r1 + pad` (the halo the
    /// convolution reads) in `cells`, with `tmp` for the horizontal pass.
    #[inline(always)]
    pub(crate) fn band(
        &self,
        r0: usize,
        r1: usize,
        cells: &mut Vec<Cell>,
        tmp: &mut Vec<Cell>,
    ) -> Mat7 {
        let bw = self.bw;
        let (lr0, lr1) = (r0.saturating_sub(self.pad), (r1 + self.pad).min(self.bh));
        let lh = lr1 - lr0;
        // `cells` is all zeros between calls (`reduce` clears what it reads): grow it, and
        // scatter onto its first bw·lh cells.
        let need = bw * lh;
        if cells.len() < need {
            cells.resize(need, [0.0; 8]);
        }
        let cells = &mut cells[..need];
        self.scatter(lr0, lr1, cells);
        let (own0, own1) = (r0 - lr0, r1 - lr0);
        match self.n {
            2 => self.reduce::<2>(cells, tmp, lh, own0, own1),
            3 => self.reduce::<3>(cells, tmp, lh, own0, own1),
            4 => self.reduce::<4>(cells, tmp, lh, own0, own1),
            6 => self.reduce::<6>(cells, tmp, lh, own0, own1),
            _ => self.reduce::<7>(cells, tmp, lh, own0, own1),
        }
    }

    /// Scatters every valid pixel whose taps reach local rows `lr0..lr1` (only those rows).
    #[inline(always)]
    fn scatter(&self, lr0: usize, lr1: usize, cells: &mut [Cell]) {
        let bw = self.bw;
        let (tap_lo, tap_hi) = self.taps;
        let ntap = tap_lo + tap_hi + 1;
        for (sp, &(lo, hi)) in self.spans.iter().zip(self.span_rows) {
            // Grid rows the span's taps reach.
            if lo > hi {
                continue;
            }
            let first = (lo as isize - tap_lo as isize - self.oy) as usize;
            let last = (hi as isize - tap_lo as isize - self.oy) as usize + ntap;
            if last <= lr0 || first >= lr1 {
                continue;
            }
            for k in sp.k0..sp.k0 + sp.len {
                if self.valid[k] == 0 {
                    continue;
                }
                let u = &self.u[k];
                if u.iter().all(|&v| v == 0.0) {
                    continue;
                }
                let (x, y) = (self.pos[k].0 as usize, self.pos[k].1 as usize);
                let gy = (y as isize - tap_lo as isize - self.oy) as usize;
                if gy + ntap <= lr0 || gy >= lr1 {
                    continue;
                }
                let Some(l) = self.l1 else {
                    cells[(gy - lr0) * bw + (x as isize - self.ox) as usize] = *u;
                    continue;
                };
                let (fx, fy) = (self.fx[k], self.fy[k]);
                // The same taps as `evaluate`: cubic inside, bilinear on the border.
                let (wx, wy) = if x >= 1 && y >= 1 && x + 2 < l.width && y + 2 < l.height {
                    (cubic_weights(fx), cubic_weights(fy))
                } else {
                    ([0.0, 1.0 - fx, fx, 0.0], [0.0, 1.0 - fy, fy, 0.0])
                };
                let x0 = (x as isize - 1 - self.ox) as usize;
                for (r, &wyr) in wy.iter().enumerate() {
                    let g = gy + r;
                    if g < lr0 || g >= lr1 {
                        continue;
                    }
                    let su: Cell = std::array::from_fn(|c| wyr * u[c]);
                    let start = (g - lr0) * bw + x0;
                    for (cell, &wxc) in cells[start..start + 4].iter_mut().zip(&wx) {
                        for (v, &s) in cell.iter_mut().zip(&su) {
                            *v += s * wxc;
                        }
                    }
                }
            }
        }
    }

    /// Convolves (when pre-smoothing) and sums the outer products over local rows `own0..own1`:
    /// the horizontal pass over all `lh` rows into `tmp`, then row by row the vertical pass into
    /// a row buffer and its outer products. Leaves `cells` all zeros.
    #[inline(always)]
    fn reduce<const N: usize>(
        &self,
        cells: &mut [Cell],
        tmp: &mut Vec<Cell>,
        lh: usize,
        own0: usize,
        own1: usize,
    ) -> Mat7 {
        let bw = self.bw;
        let mut total = [[0.0f64; 8]; N];
        if !self.presmooth {
            outer_sum::<N>(&cells[own0 * bw..own1 * bw], &mut total);
            cells.fill([0.0; 8]);
            return symmetric(&total);
        }
        // Every cell of `tmp` is written before it is read: grow it, never clear it.
        let need = cells.len() + bw;
        if tmp.len() < need {
            tmp.resize(need, [0.0; 8]);
        }
        let (hor, row) = tmp[..need].split_at_mut(cells.len());
        horizontal(cells, bw, hor);
        let k = KERNEL;
        for j in own0..own1 {
            if j >= 2 && j + 2 < lh {
                let rows = &hor[(j - 2) * bw..(j + 3) * bw];
                let (a, rest) = rows.split_at(bw);
                let (b, rest) = rest.split_at(bw);
                let (c, rest) = rest.split_at(bw);
                let (d, e) = rest.split_at(bw);
                let src = a.iter().zip(b).zip(c).zip(d).zip(e);
                for (o, ((((a, b), c), d), e)) in row.iter_mut().zip(src) {
                    for l in 0..8 {
                        o[l] = k[0] * a[l] + k[1] * b[l] + k[2] * c[l] + k[3] * d[l] + k[4] * e[l];
                    }
                }
            } else {
                // Zero padding above and below the grid: the taps that fall inside.
                for (i, o) in row.iter_mut().enumerate() {
                    *o = [0.0; 8];
                    for (t, &kv) in k.iter().enumerate() {
                        let y = j as isize + t as isize - 2;
                        if y >= 0 && (y as usize) < lh {
                            let src = &hor[y as usize * bw + i];
                            for l in 0..8 {
                                o[l] += kv * src[l];
                            }
                        }
                    }
                }
            }
            outer_sum::<N>(row, &mut total);
        }
        symmetric(&total)
    }
}

/// The horizontal pass of the binomial convolution with zero padding, every row of `cells`
/// (width `w`) into `out` (same length): the interior in five-cell windows, the two border cells
/// of each side with the taps that fall inside. Each row of `cells` is cleared once read (while
/// it is in cache), which is cheaper than clearing the grid before the next scatter.
#[inline(always)]
fn horizontal(cells: &mut [Cell], w: usize, out: &mut [Cell]) {
    let k = KERNEL;
    let (lo, hi) = (w.min(2), w.saturating_sub(2).max(w.min(2)));
    for (row, o) in cells.chunks_exact_mut(w).zip(out.chunks_exact_mut(w)) {
        if w >= 5 {
            for (o, v) in o[2..w - 2].iter_mut().zip(row.windows(5)) {
                for l in 0..8 {
                    o[l] = k[0] * v[0][l]
                        + k[1] * v[1][l]
                        + k[2] * v[2][l]
                        + k[3] * v[3][l]
                        + k[4] * v[4][l];
                }
            }
        }
        for i in (0..lo).chain(hi..w) {
            let mut acc = [0.0f32; 8];
            for (t, &kv) in k.iter().enumerate() {
                let x = i as isize + t as isize - 2;
                if x >= 0 && (x as usize) < w {
                    let src = &row[x as usize];
                    for l in 0..8 {
                        acc[l] += kv * src[l];
                    }
                }
            }
            o[i] = acc;
        }
        row.fill([0.0; 8]);
    }
}

/// Adds Σ v vᵀ over `cells` to `total`: row a of the outer product, v[a]·v, accumulates in f32
/// lanes over at most 64 cells, then in f64, so that the f32 sums stay short.
#[inline(always)]
fn outer_sum<const N: usize>(cells: &[Cell], total: &mut [[f64; 8]; N]) {
    for chunk in cells.chunks(64) {
        let mut lanes = [[0.0f32; 8]; N];
        for v in chunk {
            for (a, row) in lanes.iter_mut().enumerate() {
                let va = v[a];
                for l in 0..8 {
                    row[l] += va * v[l];
                }
            }
        }
        for (t, l) in total.iter_mut().zip(&lanes) {
            for i in 0..8 {
                t[i] += f64::from(l[i]);
            }
        }
    }
}

/// The symmetric matrix of the sums' upper triangle (rows and columns past `N` zero).
fn symmetric<const N: usize>(total: &[[f64; 8]; N]) -> Mat7 {
    let mut m = Mat7::zeros();
    for a in 0..N {
        for b in a..N {
            m[(a, b)] = total[a][b];
            m[(b, a)] = total[a][b];
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn convolution_and_outer_sum_match_direct_sums() {
        // The horizontal pass then the fused vertical pass and outer sums against the direct 5×5
        // zero-padded convolution and an f64 outer sum, on grids narrower and wider than the
        // kernel, over all rows and over an inner band of rows. f32 arithmetic on values ≤ 1.
        for (w, h) in [(1usize, 1usize), (3, 4), (4, 9), (9, 7), (23, 17), (70, 80)] {
            let cells: Vec<Cell> = (0..w * h)
                .map(|i| {
                    std::array::from_fn(|c| {
                        if c < 3 {
                            ((i * 37 + c * 53) % 11) as f32 / 11.0 - 0.4
                        } else {
                            0.0
                        }
                    })
                })
                .collect();
            let grid = Grid {
                n: 3,
                bw: w,
                bh: h,
                ox: 0,
                oy: 0,
                pad: 2,
                taps: (0, 0),
                presmooth: true,
                l1: None,
                u: &[],
                pos: &[],
                valid: &[],
                fx: &[],
                fy: &[],
                spans: &[],
                span_rows: &[],
            };
            let conv = |i: usize, j: usize, c: usize| -> f64 {
                let mut want = 0.0f64;
                for (ty, ky) in KERNEL.iter().enumerate() {
                    for (tx, kx) in KERNEL.iter().enumerate() {
                        let (x, y) = (i as isize + tx as isize - 2, j as isize + ty as isize - 2);
                        if x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h {
                            want += f64::from(ky * kx)
                                * f64::from(cells[y as usize * w + x as usize][c]);
                        }
                    }
                }
                want
            };
            for (own0, own1) in [(0, h), (h / 3, h - h / 4)] {
                let mut grid_cells = cells.clone();
                let m = grid.reduce::<3>(&mut grid_cells, &mut Vec::new(), h, own0, own1);
                // The grid is left cleared for the next scatter.
                assert!(grid_cells.iter().all(|c| c.iter().all(|&v| v == 0.0)));
                for a in 0..3 {
                    for b in 0..3 {
                        let mut want = 0.0;
                        for j in own0..own1 {
                            for i in 0..w {
                                want += conv(i, j, a) * conv(i, j, b);
                            }
                        }
                        assert!(
                            (m[(a, b)] - want).abs() < 1e-5 * (1.0 + want.abs()),
                            "{w}x{h} rows {own0}..{own1} ({a}, {b}): {} vs {want}",
                            m[(a, b)]
                        );
                    }
                }
                assert_eq!(m[(3, 3)], 0.0);
            }
        }
    }
}
