//! The fast scan of measurement lines that lie wholly inside the image: bilinear samples, the
//! derivative-of-Gaussian responses and the edge candidates of many lines at once, as one bit
//! mask per line.
//!
//! It computes exactly what [`sample_line`](crate::image::sample_line) and [`EdgeDetector`] compute on such a line
//! (the same fixed-point positions, interpolation, filter sums and suppression tests, in the same
//! order), so every edge is the same to the bit; lines that touch the border take the general
//! path.
//!
//! The speed comes from the layout. The lines of a scan are interleaved, sample-major: entry
//! k·n + l holds sample k of line l (n lines), so that every pass is one loop over all lines
//! and samples at once, each entry depending only on entries a multiple of n away (its own
//! line), which the compiler vectorises with whole vectors and no per-line set-up: positions,
//! then the pixel reads (the only scalar pass), interpolation, filter, suppression, and the
//! masks (one bit per sample and line, set across lines). Running each pass over all lines,
//! rather than all passes over each line, also means a pass never reads values that the
//! previous pass stored moments before in a different width (scalar stores read back as
//! vectors), which would stall the processor's store forwarding.

use vision_core::GreyImage;

use crate::image::FIX_BITS;
use nalgebra::Vector2;

use crate::{EdgeDetector, Polarity};

/// The most samples per line a scan takes; longer lines take the general path. 64 covers the
/// default lines (29 samples) and any line up to L = 56 px at σ = 1 px.
const SCAN_CAP: usize = 64;

/// Lines are placed in groups of this many lanes (8 f32 fill an AVX2 vector, half an AVX-512
/// one).
const LANES: usize = 8;

/// The largest filter radius a scan takes (⌈3σ⌉ ≤ 30 for σ ≤ 10 px).
const MAX_RADIUS: usize = 30;

/// The fraction mask of a fixed-point position.
const FRAC: i32 = (1 << FIX_BITS) - 1;

/// The edge scan of a set of lines; reused from hypothesis to hypothesis.
#[derive(Debug, Clone, Default)]
pub(crate) struct LineScan {
    /// First candidate offset, candidates per line, samples per line, filter radius.
    klo: i64,
    candidates: usize,
    count: usize,
    radius: usize,
    /// Lines added since [`Self::begin`]: n, the stride of the interleaved entries.
    lines: usize,
    /// Per line: the pixel index of its first sample's cell, and the fixed-point position of
    /// its first sample relative to that cell (fractions) and its step.
    base: Vec<i32>,
    x: Vec<i32>,
    y: Vec<i32>,
    sx: Vec<i32>,
    sy: Vec<i32>,
    /// Per entry k·n + l: the cell's pixel index, and the fractions.
    cell: Vec<i32>,
    fx: Vec<f32>,
    fy: Vec<f32>,
    /// The cells' pixel pairs, interleaved: (top left, top right) and (bottom left, bottom
    /// right) of entry i at 2i and 2i + 1.
    top: Vec<f32>,
    bottom: Vec<f32>,
    /// Samples.
    s: Vec<f32>,
    /// Filter responses (entry k·n + l is centred on sample k + r of line l).
    d: Vec<f32>,
    /// Per line: whether it is scanned ([`Self::place`]).
    valid: Vec<bool>,
    /// Edge flags (0 or 1); entry j·n + l is candidate j of line l (its response j + 1).
    flag: Vec<u8>,
    /// The edge mask of each line after [`Self::finish`].
    masks: Vec<u64>,
}

impl LineScan {
    /// Starts a scan of up to `max_lines` lines for the edge candidates at integer offsets
    /// `klo ..= khi`: samples at `klo − 1 − r ..= khi + 1 + r`, responses at
    /// `klo − 1 ..= khi + 1`. Returns false when such lines do not fit the scan (too long, or a
    /// filter too wide); every line then takes the general path.
    #[inline(always)]
    pub(crate) fn begin(
        &mut self,
        det: &EdgeDetector,
        klo: i64,
        khi: i64,
        max_lines: usize,
    ) -> bool {
        self.lines = 0;
        self.masks.clear();
        self.reset_lanes(0);
        let r = det.radius();
        let Ok(candidates) = usize::try_from(khi - klo + 1) else {
            return false;
        };
        let count = candidates + 2 + 2 * r;
        if count > SCAN_CAP || r > MAX_RADIUS {
            return false;
        }
        (self.klo, self.candidates, self.count, self.radius) = (klo, candidates, count, r);
        let len = max_lines.next_multiple_of(LANES) * count;
        if self.s.len() < len {
            for v in [&mut self.fx, &mut self.fy, &mut self.s, &mut self.d] {
                v.resize(len, 0.0);
            }
            self.top.resize(2 * len, 0.0);
            self.bottom.resize(2 * len, 0.0);
            self.cell.resize(len, 0);
            self.flag.resize(len, 0);
        }
        true
    }

    /// The per-line set-up (cell bases, fixed-point positions and steps, validity) for `lanes`
    /// lanes, all zero (invalid).
    fn reset_lanes(&mut self, lanes: usize) {
        for v in [
            &mut self.base,
            &mut self.x,
            &mut self.y,
            &mut self.sx,
            &mut self.sy,
        ] {
            v.clear();
            v.resize(lanes, 0);
        }
        self.valid.clear();
        self.valid.resize(lanes, false);
    }

    /// Places line l = c + k·n for every (c, n) of `lines` (n = (NaN, NaN): undefined) at lane
    /// l of the scan, in one branch-free pass. A line is scanned ([`Self::scanned`]) when
    /// `inside(c, n)` (its end points lie in the image, [`crate::lines`]'s test, branch-free)
    /// and its samples
    /// all lie in [0, w − 1) × [0, h − 1), that is both end points do in fixed point, positions
    /// being linear in k; the other lanes read the first cell and nothing reads their masks.
    /// Positions are stepped in fixed point exactly as [`sample_line`](crate::image::sample_line)'s unclamped
    /// loop; relative to the first sample's cell they fit an i32 (fewer than 64 samples,
    /// |n| ≤ 2). At most `max_lines` lines.
    #[inline(always)]
    pub(crate) fn place(
        &mut self,
        image: &GreyImage<'_>,
        lines: &[(Vector2<f64>, Vector2<f64>)],
        inside: impl Fn(Vector2<f64>, Vector2<f64>) -> bool,
    ) {
        let n = lines.len();
        // Lanes padded to whole groups of LANES, so that the passes run on whole vectors; the
        // padding lanes read the first cell and are never scanned.
        let lanes = n.next_multiple_of(LANES);
        if lanes * self.count > self.s.len() {
            return;
        }
        let (width, height) = (image.width() as i64, image.height() as i64);
        let one = (1i64 << FIX_BITS) as f64;
        let fix = |v: f64| trunc_i64(v * one);
        // |n| ≤ 2 keeps every relative position below 2⁶·2²⁵ = 2³¹, and an image below 2³¹
        // pixels every cell index.
        let step_max = 2u64 << FIX_BITS;
        let small = image.data().len() < 1 << 31;
        let lo = self.klo - 1 - self.radius as i64;
        let last = self.count as i64 - 1;
        let limit_x = (width - 1) << FIX_BITS;
        let limit_y = (height - 1) << FIX_BITS;
        let clear = |p: i64, limit: i64| (p >= 0) & (p < limit);
        self.reset_lanes(lanes);
        let (base, x, y) = (&mut self.base[..n], &mut self.x[..n], &mut self.y[..n]);
        let (sx, sy, valid) = (&mut self.sx[..n], &mut self.sy[..n], &mut self.valid[..n]);
        let lines = &lines[..n];
        for l in 0..n {
            let (c, d) = lines[l];
            let (step_x, step_y) = (fix(d.x), fix(d.y));
            // Wrapping: a huge step gives garbage here, which the step test then rejects.
            let px = fix(c.x).wrapping_add(lo.wrapping_mul(step_x));
            let py = fix(c.y).wrapping_add(lo.wrapping_mul(step_y));
            let ex = px.wrapping_add(last.wrapping_mul(step_x));
            let ey = py.wrapping_add(last.wrapping_mul(step_y));
            let ok = inside(c, d)
                & small
                & (step_x.unsigned_abs() <= step_max)
                & (step_y.unsigned_abs() <= step_max)
                & clear(px, limit_x)
                & clear(ex, limit_x)
                & clear(py, limit_y)
                & clear(ey, limit_y);
            let pick = |v: i64| if ok { v } else { 0 };
            let (px, py) = (pick(px), pick(py));
            // Positions relative to the first sample's cell: the fraction bits are those of
            // the absolute position (the cell is a multiple of 2²⁴), the cell is the first one
            // plus the integer part.
            base[l] = ((py >> FIX_BITS) * width + (px >> FIX_BITS)) as i32;
            x[l] = (px & FRAC as i64) as i32;
            y[l] = (py & FRAC as i64) as i32;
            sx[l] = pick(step_x) as i32;
            sy[l] = pick(step_y) as i32;
            valid[l] = ok;
        }
        self.lines = lanes;
    }

    /// Whether lane `line` of the last [`Self::place`] is scanned.
    #[inline]
    pub(crate) fn scanned(&self, line: usize) -> bool {
        self.valid.get(line).copied().unwrap_or(false)
    }

    /// Samples, interpolates, filters and suppresses all lines added, leaving one edge mask per
    /// line: [`Self::mask`].
    #[inline(always)]
    pub(crate) fn finish(&mut self, image: &GreyImage<'_>, det: &EdgeDetector) {
        let n = self.lines;
        if n == 0 {
            return;
        }
        let (count, r) = (self.count, self.radius);
        let samples = count * n;
        cells(
            &mut self.cell[..samples],
            &mut self.fx[..samples],
            &mut self.fy[..samples],
            image.width() as i32,
            (&self.base, &self.x, &self.y, &self.sx, &self.sy),
            1.0 / (1i64 << FIX_BITS) as f32,
        );
        gather(
            image.data(),
            image.width(),
            &self.cell[..samples],
            &mut self.top[..2 * samples],
            &mut self.bottom[..2 * samples],
        );
        interpolate(
            &self.top[..2 * samples],
            &self.bottom[..2 * samples],
            &self.fx[..samples],
            &self.fy[..samples],
            &mut self.s[..samples],
        );
        // Responses at sample offsets r ..= count − 1 − r of every line.
        let responses = (count - 2 * r) * n;
        respond(det.taps(), n, &self.s[..samples], &mut self.d[..responses]);
        let flagged = self.candidates * n;
        flags(det, n, &self.d[..responses], &mut self.flag[..flagged]);
        self.masks.clear();
        self.masks.resize(n, 0);
        // A group of lanes at a time, its masks kept in registers over the candidates (no
        // read-modify-write of stored masks from one candidate to the next).
        let flag = &self.flag[..flagged];
        for (g, masks) in self.masks.chunks_exact_mut(LANES).enumerate() {
            let mut acc = [0u64; LANES];
            for (j, row) in flag.chunks_exact(n).enumerate() {
                let Some(f) = row.get(g * LANES..).and_then(|f| f.first_chunk::<LANES>()) else {
                    break;
                };
                for t in 0..LANES {
                    acc[t] |= u64::from(f[t]) << j;
                }
            }
            masks.copy_from_slice(&acc);
        }
    }

    /// The edge mask of line `line` after [`Self::finish`]: bit j says that offset `klo + j` is
    /// an edge (threshold, polarity and non-maximum suppression as [`EdgeDetector::peak`]).
    #[inline]
    pub(crate) fn mask(&self, line: usize) -> u64 {
        self.masks.get(line).copied().unwrap_or(0)
    }

    /// The sub-pixel offsets of the edges of line `line` whose bits are set in `mask` (a subset of
    /// [`Self::mask`]), in increasing order.
    #[inline]
    pub(crate) fn offsets(&self, line: usize, mut mask: u64) -> impl Iterator<Item = f64> + '_ {
        std::iter::from_fn(move || {
            (mask != 0).then(|| {
                let j = mask.trailing_zeros();
                mask &= mask - 1;
                self.offset(line, j)
            })
        })
    }

    /// The sub-pixel offset of candidate bit `j` of line `line`: the parabola vertex of
    /// [`EdgeDetector::vertex`] added to `klo + j`.
    #[inline]
    pub(crate) fn offset(&self, line: usize, j: u32) -> f64 {
        let n = self.lines;
        let i = j as usize * n + line;
        let a = |i: usize| self.d.get(i).map_or(0.0, |d| d.abs());
        let (am, a0, ap) = (a(i), a(i + n), a(i + 2 * n));
        (self.klo + i64::from(j)) as f64 + f64::from(EdgeDetector::vertex(am, a0, ap))
    }
}

/// `v as i64` for |v| < 2⁵⁰ (fixed-point positions of lines inside any image), in float and
/// integer arithmetic that vectorises (the saturating conversion `as` does not). Other values
/// give an unspecified integer, without panicking.
#[inline(always)]
fn trunc_i64(v: f64) -> i64 {
    // Adding 1.5·2⁵² rounds to an integer (to nearest) and puts it in the low mantissa bits.
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    let r = (v + MAGIC) - MAGIC;
    // Towards zero: one step back where rounding went away from zero (exact for |v| < 2⁵⁰).
    let r = if v >= 0.0 && r > v {
        r - 1.0
    } else if v < 0.0 && r < v {
        r + 1.0
    } else {
        r
    };
    ((r + MAGIC).to_bits() as i64).wrapping_sub(MAGIC.to_bits() as i64)
}

/// Per line: its first cell, its position (x, y) relative to it and its step (sx, sy), as
/// [`LineScan`] keeps them.
type Starts<'a> = (&'a [i32], &'a [i32], &'a [i32], &'a [i32], &'a [i32]);

/// The cell indices (row · width + column) and the fractions of the fixed-point positions of
/// every line's samples: entry k·n + l is line l's position (x, y) + k·(sx, sy) relative to its
/// first cell `base`. One vector pass over the lines per sample.
#[inline(always)]
fn cells(
    cell: &mut [i32],
    fx: &mut [f32],
    fy: &mut [f32],
    width: i32,
    (base, x, y, sx, sy): Starts<'_>,
    scale: f32,
) {
    let n = base.len();
    let (x, y, sx, sy) = (&x[..n], &y[..n], &sx[..n], &sy[..n]);
    let rows = cell
        .chunks_exact_mut(n)
        .zip(fx.chunks_exact_mut(n))
        .zip(fy.chunks_exact_mut(n));
    for (k, ((cell, fx), fy)) in rows.enumerate() {
        let (cell, fx, fy) = (&mut cell[..n], &mut fx[..n], &mut fy[..n]);
        // (x, y) + k·(sx, sy), the same integers as stepping k times (no overflow: every
        // relative position fits an i32), without reading back positions stored by the
        // previous sample (a store-forwarding stall with wide vectors).
        let k = k as i32;
        for l in 0..n {
            let (xk, yk) = (x[l] + k * sx[l], y[l] + k * sy[l]);
            cell[l] = base[l] + (yk >> FIX_BITS) * width + (xk >> FIX_BITS);
            fx[l] = (xk & FRAC) as f32 * scale;
            fy[l] = (yk & FRAC) as f32 * scale;
        }
    }
}

/// The 2×2 cells' pixel pairs at `cell[i]`: the only scalar pass (two 8-byte reads and writes
/// per sample). Kept out of line so that its loop gets the registers to itself.
///
/// One bounds check for the whole pass instead of one per sample: every cell is clamped (a
/// conditional move, never taken for the cells of [`LineScan::place`], which all lie in the
/// image) to the largest one, `last`, and the pixels are read from `data[..last + width + 2]`,
/// so the compiler can prove every read in bounds (indices and width below 2³², no overflow).
/// An image of a single row has no 2×2 cell: no line of it is scanned, and nothing is read.
#[inline(never)]
fn gather(data: &[f32], width: usize, cell: &[i32], top: &mut [f32], bottom: &mut [f32]) {
    let n = cell.len();
    let (top, bottom) = (&mut top[..2 * n], &mut bottom[..2 * n]);
    let (Ok(w), Ok(len)) = (u32::try_from(width), u32::try_from(data.len())) else {
        return;
    };
    let Some(last) = len.checked_sub(w.saturating_add(2)) else {
        return;
    };
    let (w, last) = (w as usize, last as usize);
    let data = &data[..last + w + 2];
    let quad = |c: i32| {
        let i = (c as u32 as usize).min(last);
        let quad = &data[i..i + w + 2];
        ([quad[0], quad[1]], [quad[w], quad[w + 1]])
    };
    // Two samples per iteration.
    let (pairs, rest) = cell.as_chunks::<2>();
    let (top2, top1) = top.as_chunks_mut::<4>();
    let (bottom2, bottom1) = bottom.as_chunks_mut::<4>();
    for ((&[c0, c1], t), b) in pairs.iter().zip(top2).zip(bottom2) {
        let ((t0, b0), (t1, b1)) = (quad(c0), quad(c1));
        *t = [t0[0], t0[1], t1[0], t1[1]];
        *b = [b0[0], b0[1], b1[0], b1[1]];
    }
    if let (Some(&c), true, true) = (rest.first(), top1.len() == 2, bottom1.len() == 2) {
        let (t, b) = quad(c);
        top1.copy_from_slice(&t);
        bottom1.copy_from_slice(&b);
    }
}

/// Bilinear interpolation of the cells at the fractions (`fx`, `fy`), into `s`, as
/// `image::lerp`.
#[inline(always)]
fn interpolate(top: &[f32], bottom: &[f32], fx: &[f32], fy: &[f32], s: &mut [f32]) {
    let n = s.len();
    let (top, bottom) = (&top[..2 * n], &bottom[..2 * n]);
    let (fx, fy) = (&fx[..n], &fy[..n]);
    for k in 0..n {
        let (p00, p10) = (top[2 * k], top[2 * k + 1]);
        let (p01, p11) = (bottom[2 * k], bottom[2 * k + 1]);
        let t = p00 + fx[k] * (p10 - p00);
        let b = p01 + fx[k] * (p11 - p01);
        s[k] = t + fy[k] * (b - t);
    }
}

/// `d[i] = Σ_j w_j (s_{i+(r+j)n} − s_{i+(r−j)n})` for every entry of `d` (n lines
/// interleaved), summed from 0.0 in increasing j as [`EdgeDetector::fill_derivatives`] (radius 3
/// unrolled). Needs `d.len() + 2rn ≤ s.len()`.
#[inline(always)]
fn respond(taps: &[f32], n: usize, s: &[f32], d: &mut [f32]) {
    let m = d.len();
    let at = |k: usize| &s[k * n..k * n + m];
    if let [w1, w2, w3] = *taps {
        let (p1, m1) = (at(4), at(2));
        let (p2, m2) = (at(5), at(1));
        let (p3, m3) = (at(6), at(0));
        for i in 0..m {
            // The general path sums from 0.0, which differs only in the sign of a zero
            // response: nothing downstream (|d|, d > 0, d < 0) can tell.
            d[i] = w1 * (p1[i] - m1[i]) + w2 * (p2[i] - m2[i]) + w3 * (p3[i] - m3[i]);
        }
    } else {
        let r = taps.len();
        d.fill(0.0);
        for (j, w) in taps.iter().enumerate() {
            let (p, q) = (at(r + j + 1), at(r - j - 1));
            for i in 0..m {
                d[i] += w * (p[i] - q[i]);
            }
        }
    }
}

/// `flag[i]` = whether response i + n is an edge (n lines interleaved): polarity, threshold and
/// non-maximum suppression on |d| as [`EdgeDetector::peak`]. Needs `flag.len() + 2n ≤ d.len()`.
#[inline(always)]
fn flags(det: &EdgeDetector, n: usize, d: &[f32], flag: &mut [u8]) {
    // The polarity test as a loop-invariant closure, so that `Any` costs nothing.
    let threshold = det.settings().threshold;
    match det.settings().polarity {
        Polarity::Any => flags_with(n, d, flag, threshold, |_| true),
        Polarity::Rising => flags_with(n, d, flag, threshold, |d| d > 0.0),
        Polarity::Falling => flags_with(n, d, flag, threshold, |d| d < 0.0),
    }
}

#[inline(always)]
fn flags_with(n: usize, d: &[f32], flag: &mut [u8], threshold: f32, keep: impl Fn(f32) -> bool) {
    let m = flag.len();
    let (dm, d0, dp) = (&d[..m], &d[n..n + m], &d[2 * n..2 * n + m]);
    for j in 0..m {
        let (am, a0, ap) = (dm[j].abs(), d0[j].abs(), dp[j].abs());
        // The asymmetric comparison keeps one sample of a plateau.
        let edge = keep(d0[j]) & (a0 >= threshold) & (a0 >= am) & (a0 > ap);
        flag[j] = u8::from(edge);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trunc_i64_is_the_conversion_in_range() {
        let mut values = vec![0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 1.5, -1.5, 2.5, -2.5];
        let big = (1u64 << 50) as f64;
        values.extend([big - 1.0, -(big - 1.0), big - 0.5, -(big - 0.5)]);
        let mut x = 0.123_456_789f64;
        for _ in 0..10_000 {
            // Pseudo-random magnitudes over the whole range, fractions of every kind.
            x = (x * 9_301.0 + 49_297.0) % 233_280.0;
            let v = (x / 233_280.0 - 0.5) * 2f64.powi((x as i32) % 51);
            values.push(v);
            values.push(v * 16_777_216.0 % big);
        }
        for v in values {
            assert_eq!(trunc_i64(v), v as i64, "{v}");
        }
    }
}
