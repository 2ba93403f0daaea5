//! The fast scan of measurement lines that lie wholly inside the image: bilinear samples, the
//! derivative-of-Gaussian responses and the edge candidates of many lines at once, as one bit
//! mask per line.
//!
//! It computes exactly what [`GreyView::sample_line`] and [`EdgeDetector`] compute on such a line
//! (the same fixed-point positions, interpolation, filter sums and suppression tests, in the same
//! order), so every edge is the same to the bit; lines that touch the border take the general
//! path.
//!
//! The speed comes from the layout. The lines of a scan are stored one after the other (structure
//! of arrays, one entry per sample). The pixel reads are the only scalar pass, done line by line as the lines are
//! added; interpolation, filter, |d| and suppression then run as single passes over all lines
//! at once (each entry depends only on entries of its own line), which the compiler vectorises.
//! Running each pass over all lines, rather than all passes over each line, also means a pass
//! never reads values that the previous pass stored moments before in a different width (scalar
//! stores read back as vectors), which would stall the processor's store forwarding.

use crate::image::FIX_BITS;
use crate::{EdgeDetector, GreyView, Polarity};

/// The most samples per line a scan takes; longer lines take the general path. 64 covers the
/// default lines (29 samples) and any line up to L = 56 px at σ = 1 px.
const SCAN_CAP: usize = 64;

/// The largest filter radius a scan takes (⌈3σ⌉ ≤ 30 for σ ≤ 10 px).
const MAX_RADIUS: usize = 30;

/// Eight candidates' flags make one byte-word of the mask gathering; the passes also run this
/// many entries past the last line, so that they end on whole vectors.
const BLOCK: usize = 8;

/// Entries past the last line, so that every pass can run over whole blocks and read its
/// neighbours (the filter reaches 2r ahead) without a bounds check per entry. The values there
/// are stale and nothing reads their results.
const SLACK: usize = 2 * MAX_RADIUS + 2 * BLOCK;

/// The fraction mask of a fixed-point position.
const FRAC: i32 = (1 << FIX_BITS) - 1;

/// The edge scan of a set of lines; reused from hypothesis to hypothesis.
#[derive(Debug, Clone, Default)]
pub(crate) struct LineScan {
    /// First candidate offset, candidates per line, samples per line, filter radius, stride.
    klo: i64,
    candidates: usize,
    count: usize,
    radius: usize,
    stride: usize,
    /// Lines added since [`Self::begin`].
    lines: usize,
    /// Cell offsets of each line's samples from its first sample's cell, and fractions.
    off: Vec<i32>,
    fx: Vec<f32>,
    fy: Vec<f32>,
    /// The cells' pixel pairs, interleaved: (top left, top right) and (bottom left, bottom
    /// right) of entry k at 2k and 2k + 1.
    top: Vec<f32>,
    bottom: Vec<f32>,
    /// Samples.
    s: Vec<f32>,
    /// Filter responses (entry i is centred on sample i + r).
    d: Vec<f32>,
    /// Edge flags (0 or 1); candidate j of a line is its response j + 1.
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
        let r = det.radius();
        let Ok(candidates) = usize::try_from(khi - klo + 1) else {
            return false;
        };
        let count = candidates + 2 + 2 * r;
        if count > SCAN_CAP || r > MAX_RADIUS {
            return false;
        }
        // Lines are packed: a pass over all lines computes a few entries that straddle two
        // lines, which nothing reads, rather than padding every line.
        let stride = count;
        (
            self.klo,
            self.candidates,
            self.count,
            self.radius,
            self.stride,
        ) = (klo, candidates, count, r, stride);
        let len = max_lines * stride + SLACK;
        if self.s.len() < len {
            self.top.resize(2 * len, 0.0);
            self.bottom.resize(2 * len, 0.0);
            for v in [&mut self.fx, &mut self.fy, &mut self.s, &mut self.d] {
                v.resize(len, 0.0);
            }
            self.off.resize(len, 0);
            self.flag.resize(len, 0);
        }
        true
    }

    /// Adds the line c + k·n and reads its pixels: returns its index in the scan, or `None`
    /// (nothing added) unless its samples all lie in [0, w − 1) × [0, h − 1), that is both end
    /// points do, positions being linear in k. Positions are stepped in fixed point exactly as
    /// [`GreyView::sample_line`]'s unclamped loop; relative to the first sample's cell they fit
    /// an i32 (fewer than 64 samples, |n| ≤ 2). At most `max_lines` lines may be added.
    #[inline(always)]
    pub(crate) fn push(
        &mut self,
        image: &GreyView<'_>,
        c: (f64, f64),
        n: (f64, f64),
    ) -> Option<usize> {
        let (width, height) = (image.width(), image.height());
        let one = (1i64 << FIX_BITS) as f64;
        let fix = |v: f64| (v * one) as i64;
        let (step_x, step_y) = (fix(n.0), fix(n.1));
        // |n| ≤ 2 keeps every relative position below 2⁶·2²⁵ = 2³¹, and a width below 2²⁴
        // every cell offset (|row| ≤ 2⁷).
        let step_max = 2i64 << FIX_BITS;
        if step_x.abs() > step_max || step_y.abs() > step_max || width >= 1 << 24 {
            return None;
        }
        let lo = self.klo - 1 - self.radius as i64;
        let (px, py) = (fix(c.0) + lo * step_x, fix(c.1) + lo * step_y);
        let last = self.count as i64 - 1;
        let (ex, ey) = (px + last * step_x, py + last * step_y);
        let limit_x = (width as i64 - 1) << FIX_BITS;
        let limit_y = (height as i64 - 1) << FIX_BITS;
        let clear = |p: i64, limit: i64| (0..limit).contains(&p);
        if !(clear(px, limit_x) && clear(ex, limit_x) && clear(py, limit_y) && clear(ey, limit_y)) {
            return None;
        }
        let line = self.lines;
        let at = line * self.stride;
        // Whole SSE vectors: the entries past this line's belong to the next line (which
        // rewrites them) or to the slack.
        let whole = at..at + self.stride.next_multiple_of(4);
        if self.s.len() < at + self.stride + SLACK {
            return None;
        }
        // Positions relative to the first sample's cell: the fraction bits are those of the
        // absolute position (the cell is a multiple of 2²⁴), the cell is the first one plus the
        // integer part.
        let base = (py >> FIX_BITS) as usize * width + (px >> FIX_BITS) as usize;
        let start = (
            (px & FRAC as i64) as i32,
            (py & FRAC as i64) as i32,
            step_x as i32,
            step_y as i32,
        );
        cells(
            &mut self.off[whole.clone()],
            &mut self.fx[whole.clone()],
            &mut self.fy[whole],
            width as i32,
            start,
            1.0 / one as f32,
        );
        let run = at..at + self.count;
        gather(
            image.data(),
            width,
            base,
            &self.off[run.clone()],
            &mut self.top[2 * run.start..2 * run.end],
            &mut self.bottom[2 * run.start..2 * run.end],
        );
        self.lines += 1;
        Some(line)
    }

    /// Interpolates, filters and suppresses all lines added, leaving one edge mask per line:
    /// [`Self::mask`].
    #[inline(always)]
    pub(crate) fn finish(&mut self, det: &EdgeDetector) {
        if self.lines == 0 {
            return;
        }
        let total = self.lines * self.stride;
        // Samples; the filter reads up to 2r entries past each response.
        let samples = total + 2 * self.radius + BLOCK;
        interpolate(
            &self.top[..2 * samples],
            &self.bottom[..2 * samples],
            &self.fx[..samples],
            &self.fy[..samples],
            &mut self.s[..samples],
        );
        // Responses and |d|; suppression reads two entries past each candidate.
        let responses = total + BLOCK;
        respond(det.taps(), &self.s, &mut self.d[..responses]);
        flags(det, &self.d, &mut self.flag[..total]);
        self.masks.clear();
        let keep = if self.candidates >= 64 {
            u64::MAX
        } else {
            (1u64 << self.candidates) - 1
        };
        let chunks = self.candidates.div_ceil(BLOCK);
        for line in 0..self.lines {
            let at = line * self.stride;
            let mut mask = 0u64;
            for b in 0..chunks {
                let from = at + b * BLOCK;
                let Some(&bytes) = self.flag.get(from..).and_then(|f| f.first_chunk::<BLOCK>())
                else {
                    break;
                };
                // Gathers the low bit of each of the eight bytes into the top byte: with bytes
                // b_i ∈ {0, 1}, the product's term b_i·2^(8i)·2^(56−7i) = b_i·2^(56+i), and
                // every other term lands on a distinct bit outside the top byte (no carries).
                // Bytes past the line's candidates belong to the next line (or are stale) and
                // are masked off.
                let bits = u64::from_le_bytes(bytes).wrapping_mul(0x0102_0408_1020_4080) >> 56;
                mask |= bits << (b * BLOCK);
            }
            self.masks.push(mask & keep);
        }
    }

    /// The edge mask of line `line` after [`Self::finish`]: bit j says that offset `klo + j` is
    /// an edge (threshold, polarity and non-maximum suppression as [`EdgeDetector::peak`]).
    #[inline]
    pub(crate) fn mask(&self, line: usize) -> u64 {
        self.masks.get(line).copied().unwrap_or(0)
    }

    /// The sub-pixel offset of candidate bit `j` of line `line`: the parabola vertex of
    /// [`EdgeDetector::vertex`] added to `klo + j`.
    #[inline]
    pub(crate) fn offset(&self, line: usize, j: u32) -> f64 {
        let i = line * self.stride + j as usize;
        let (am, a0, ap) = match self.d.get(i..i + 3) {
            Some(&[dm, d0, dp]) => (dm.abs(), d0.abs(), dp.abs()),
            _ => (0.0, 0.0, 0.0),
        };
        (self.klo + i64::from(j)) as f64 + f64::from(EdgeDetector::vertex(am, a0, ap))
    }
}

/// The cell offsets (row · width + column, relative to the first cell) and the fractions of the
/// fixed-point positions (x, y) + k·(sx, sy): one vector pass.
#[inline(always)]
fn cells(
    off: &mut [i32],
    fx: &mut [f32],
    fy: &mut [f32],
    width: i32,
    (mut x, mut y, sx, sy): (i32, i32, i32, i32),
    scale: f32,
) {
    let n = off.len();
    let (fx, fy) = (&mut fx[..n], &mut fy[..n]);
    for k in 0..n {
        off[k] = (y >> FIX_BITS) * width + (x >> FIX_BITS);
        fx[k] = (x & FRAC) as f32 * scale;
        fy[k] = (y & FRAC) as f32 * scale;
        x += sx;
        y += sy;
    }
}

/// The 2×2 cells' pixel pairs at `base + off[k]`: the only scalar pass (two 8-byte reads and
/// writes per sample). Kept out of line so that its loop gets the registers to itself.
#[inline(never)]
fn gather(
    data: &[f32],
    width: usize,
    base: usize,
    off: &[i32],
    top: &mut [f32],
    bottom: &mut [f32],
) {
    let n = off.len();
    let (top, bottom) = (&mut top[..2 * n], &mut bottom[..2 * n]);
    let cell = |o: i32| {
        let i = base.wrapping_add_signed(o as isize);
        // One bounds check for the 2×2 cell.
        let quad = &data[i..i + width + 2];
        ([quad[0], quad[1]], [quad[width], quad[width + 1]])
    };
    // Two samples per iteration.
    let (pairs, rest) = off.as_chunks::<2>();
    let (top2, top1) = top.as_chunks_mut::<4>();
    let (bottom2, bottom1) = bottom.as_chunks_mut::<4>();
    for ((&[o0, o1], t), b) in pairs.iter().zip(top2).zip(bottom2) {
        let ((t0, b0), (t1, b1)) = (cell(o0), cell(o1));
        *t = [t0[0], t0[1], t1[0], t1[1]];
        *b = [b0[0], b0[1], b1[0], b1[1]];
    }
    if let (Some(&o), true, true) = (rest.first(), top1.len() == 2, bottom1.len() == 2) {
        let (t, b) = cell(o);
        top1.copy_from_slice(&t);
        bottom1.copy_from_slice(&b);
    }
}

/// Bilinear interpolation of the cells at the fractions (`fx`, `fy`), into `s`, as
/// `GreyView::lerp`.
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

/// `d[i] = Σ_j w_j (s_{i+r+j} − s_{i+r−j})` for every entry of `d`, summed from 0.0 in
/// increasing j as [`EdgeDetector::fill_derivatives`] (radius 3 unrolled). Needs
/// `d.len() + 2r ≤ s.len()`.
#[inline(always)]
fn respond(taps: &[f32], s: &[f32], d: &mut [f32]) {
    let m = d.len();
    if let [w1, w2, w3] = *taps {
        let s = &s[..m + 6];
        let (p1, m1) = (&s[4..4 + m], &s[2..2 + m]);
        let (p2, m2) = (&s[5..5 + m], &s[1..1 + m]);
        let (p3, m3) = (&s[6..6 + m], &s[..m]);
        for i in 0..m {
            // The general path sums from 0.0, which differs only in the sign of a zero
            // response: nothing downstream (|d|, d > 0, d < 0) can tell.
            d[i] = w1 * (p1[i] - m1[i]) + w2 * (p2[i] - m2[i]) + w3 * (p3[i] - m3[i]);
        }
    } else {
        let r = taps.len();
        let s = &s[..m + 2 * r];
        d.fill(0.0);
        for (j, w) in taps.iter().enumerate() {
            let (p, q) = (&s[r + j + 1..r + j + 1 + m], &s[r - j - 1..r - j - 1 + m]);
            for i in 0..m {
                d[i] += w * (p[i] - q[i]);
            }
        }
    }
}

/// `flag[j]` = whether response j + 1 is an edge: polarity, threshold and non-maximum
/// suppression on |d| as [`EdgeDetector::peak`]. Needs `flag.len() + 2 ≤ d.len()`.
#[inline(always)]
fn flags(det: &EdgeDetector, d: &[f32], flag: &mut [u8]) {
    // The polarity test as a loop-invariant closure, so that `Any` costs nothing.
    let threshold = det.settings().threshold;
    match det.settings().polarity {
        Polarity::Any => flags_with(d, flag, threshold, |_| true),
        Polarity::Rising => flags_with(d, flag, threshold, |d| d > 0.0),
        Polarity::Falling => flags_with(d, flag, threshold, |d| d < 0.0),
    }
}

#[inline(always)]
fn flags_with(d: &[f32], flag: &mut [u8], threshold: f32, keep: impl Fn(f32) -> bool) {
    let n = flag.len();
    let (dm, d0, dp) = (&d[..n], &d[1..n + 1], &d[2..n + 2]);
    for j in 0..n {
        let (am, a0, ap) = (dm[j].abs(), d0[j].abs(), dp[j].abs());
        // The asymmetric comparison keeps one sample of a plateau.
        let edge = keep(d0[j]) & (a0 >= threshold) & (a0 >= am) & (a0 > ap);
        flag[j] = u8::from(edge);
    }
}
