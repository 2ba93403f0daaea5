//! The region's pixels at one level, as row spans.

use super::Workspace;
use super::workspace::Span;
use crate::pyramid::Level;
use crate::region::{PixelBox, Region};

/// Per-row candidate ranges and a trig-free weight test for [`Workspace::collect`]. The weight is
/// computed with exactly the arithmetic of [`Region::weight`] (same sine and cosine), so that an
/// ellipse and the mask rasterised from it select the same pixels.
pub(super) struct RowTest<'r, 'a> {
    region: &'r Region<'a>,
    /// sin θ, cos θ of an ellipse.
    sc: (f64, f64),
    /// The ellipse as A dx² + 2B dx dy + C dy² ≤ 1.
    quad: [f64; 3],
}

impl<'r, 'a> RowTest<'r, 'a> {
    pub(super) fn new(region: &'r Region<'a>) -> Self {
        let (mut sc, mut quad) = ((0.0, 1.0), [0.0; 3]);
        if let Region::Ellipse(e) = region {
            let (s, c) = e.angle.sin_cos();
            let (ia, ib) = (1.0 / (e.a * e.a), 1.0 / (e.b * e.b));
            sc = (s, c);
            quad = [
                c * c * ia + s * s * ib,
                c * s * (ia - ib),
                s * s * ia + c * c * ib,
            ];
        }
        Self { region, sc, quad }
    }

    /// Columns (level units) of row `j` that may hold region pixels, within [lo, hi]; empty when
    /// the first exceeds the second. For an ellipse: the analytic chord widened by one pixel on
    /// each side, so that rounding never loses a pixel the exact test admits.
    fn row(&self, j: usize, s: usize, lo: usize, hi: usize) -> (usize, usize) {
        let Region::Ellipse(e) = self.region else {
            return (lo, hi);
        };
        let [a, b, c] = self.quad;
        let dy = (j * s) as f64 - e.cy;
        let disc = (b * dy) * (b * dy) - a * (c * dy * dy - 1.0);
        let root = disc.max(0.0).sqrt();
        let x0 = (e.cx + (-b * dy - root) / a) / s as f64;
        let x1 = (e.cx + (-b * dy + root) / a) / s as f64;
        let first = (x0.ceil() - 1.0).max(lo as f64);
        let last = (x1.floor() + 1.0).min(hi as f64);
        if first.is_nan() || last.is_nan() || first > last {
            return (1, 0);
        }
        (first as usize, last as usize)
    }

    /// The weight of level-0 pixel (x, y), as [`Region::weight`].
    #[inline]
    pub(super) fn weight(&self, x: usize, y: usize) -> f32 {
        match self.region {
            Region::Ellipse(e) => {
                let (s, c) = self.sc;
                let (dx, dy) = (x as f64 - e.cx, y as f64 - e.cy);
                let u = (c * dx + s * dy) / e.a;
                let v = (-s * dx + c * dy) / e.b;
                if u * u + v * v <= 1.0 { 1.0 } else { 0.0 }
            }
            r => r.weight(x as f64, y as f64),
        }
    }
}

impl Workspace {
    /// Lists the region's pixels at level `l` inside the first pyramid's window, as row spans
    /// (no per-pixel region test for rectangles and ellipses: see [`RowTest`]).
    pub(super) fn collect(
        &mut self,
        level: &Level,
        l: usize,
        region: &Region<'_>,
        b: PixelBox,
    ) -> usize {
        self.collect_rows(level, l, region, b, 1)
    }

    /// [`collect`](Self::collect) on every `row_stride`-th row of the region's box only (from
    /// its first row), whole rows of the region each.
    pub(super) fn collect_rows(
        &mut self,
        level: &Level,
        l: usize,
        region: &Region<'_>,
        b: PixelBox,
        row_stride: usize,
    ) -> usize {
        self.idx.clear();
        self.m.clear();
        self.spans.clear();
        let s = 1usize << l;
        let i_lo = b.i0.div_ceil(s).max(level.x0);
        let i_hi = (b.i1 / s).min(level.x0 + level.width - 1);
        let j_lo = b.j0.div_ceil(s).max(level.y0);
        let j_hi = (b.j1 / s).min(level.y0 + level.height - 1);
        if i_lo > i_hi || j_lo > j_hi {
            return 0;
        }
        let test = RowTest::new(region);
        // Every pixel of a rectangle's (or the frame's) box is inside with weight 1: whole rows.
        let dense = matches!(region, Region::Full | Region::Rect { .. });
        for j in (j_lo..=j_hi).step_by(row_stride.max(1)) {
            let (a, z) = test.row(j, s, i_lo, i_hi);
            if dense && a <= z {
                let base = (j - level.y0) * level.width - level.x0;
                let k0 = self.idx.len();
                self.idx.extend((a..=z).map(|i| (base + i) as u32));
                self.m.resize(self.idx.len(), 1.0);
                self.spans.push(Span {
                    j,
                    i0: a,
                    len: z + 1 - a,
                    k0,
                });
                continue;
            }
            let mut run: Option<Span> = None;
            for i in a..=z {
                // Interior pixels of convex regions need no test (weight 1); masks always do.
                let wgt = test.weight(i * s, j * s);
                if wgt > 0.0 {
                    self.idx
                        .push(((j - level.y0) * level.width + (i - level.x0)) as u32);
                    self.m.push(wgt);
                    match run.as_mut() {
                        Some(r) if r.i0 + r.len == i => r.len += 1,
                        _ => {
                            if let Some(r) = run.take() {
                                self.spans.push(r);
                            }
                            run = Some(Span {
                                j,
                                i0: i,
                                len: 1,
                                k0: self.idx.len() - 1,
                            });
                        }
                    }
                }
            }
            if let Some(r) = run {
                self.spans.push(r);
            }
        }
        self.make_bands();
        self.idx.len()
    }
}
