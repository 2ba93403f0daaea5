//! Gaussian pyramids in f32 over a window of the image, with gradient images, in reusable buffers.
//!
//! Level 0 is the input, optionally pre-smoothed with the 5-tap binomial kernel [1 4 6 4 1]/16
//! (σ = 1 px); level l+1 is level l filtered with the same kernel and subsampled by two, so that
//! level-l pixel i has its centre at level-0 coordinate 2^l·i. Borders are clamped to the window,
//! which equals clamping to the image where the window touches the image border.

use vision_core::GreyImage;

use crate::simd::simd;
use crate::{Error, Result};

/// The 1-D binomial kernel [1 4 6 4 1]/16 used for pre-smoothing and reduction.
pub(crate) const KERNEL: [f32; 5] = [1.0 / 16.0, 4.0 / 16.0, 6.0 / 16.0, 4.0 / 16.0, 1.0 / 16.0];

/// An axis-aligned window of pixels [x0, x0 + width) × [y0, y0 + height).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Window {
    /// First column.
    pub x0: usize,
    /// First row.
    pub y0: usize,
    /// Number of columns.
    pub width: usize,
    /// Number of rows.
    pub height: usize,
}

impl Window {
    /// The whole `width`×`height` image.
    pub fn full(width: usize, height: usize) -> Self {
        Self {
            x0: 0,
            y0: 0,
            width,
            height,
        }
    }

    /// The inclusive pixel box (i0..=i1, j0..=j1) grown by `margin` on every side and clipped to a
    /// `width`×`height` image.
    pub fn around(
        i0: usize,
        j0: usize,
        i1: usize,
        j1: usize,
        margin: usize,
        width: usize,
        height: usize,
    ) -> Self {
        let x0 = i0.saturating_sub(margin);
        let y0 = j0.saturating_sub(margin);
        let x1 = (i1 + margin).min(width.saturating_sub(1));
        let y1 = (j1 + margin).min(height.saturating_sub(1));
        Self {
            x0,
            y0,
            width: x1 + 1 - x0.min(x1 + 1),
            height: y1 + 1 - y0.min(y1 + 1),
        }
    }
}

/// One pyramid level: the window it covers (in that level's pixel coordinates), the grey values and
/// the central-difference gradients, all row-major over the window.
#[derive(Debug, Clone, Default)]
pub struct Level {
    /// Window in this level's full-image coordinates.
    pub x0: usize,
    /// Window in this level's full-image coordinates.
    pub y0: usize,
    /// Window width.
    pub width: usize,
    /// Window height.
    pub height: usize,
    /// Grey values.
    pub data: Vec<f32>,
    /// ∂/∂x (central differences, one-sided at the window border).
    pub gx: Vec<f32>,
    /// ∂/∂y.
    pub gy: Vec<f32>,
}

/// A Gaussian pyramid over a window of one frame. Build it once per frame and share it between
/// many region estimates, or rebuild it in place (no allocation once the buffers are large enough).
#[derive(Debug, Clone, Default)]
pub struct Pyramid {
    levels: Vec<Level>,
    n_levels: usize,
    presmooth: bool,
    image_width: usize,
    image_height: usize,
    tmp: Vec<f32>,
}

impl Pyramid {
    /// An empty pyramid whose buffers grow on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// Allocating twin of [`build_into`](Self::build_into).
    ///
    /// # Errors
    /// As [`build_into`](Self::build_into).
    pub fn build(
        image: GreyImage<'_>,
        window: Option<Window>,
        levels: usize,
        presmooth: bool,
    ) -> Result<Self> {
        let mut p = Self::new();
        p.build_into(image, window, levels, presmooth)?;
        Ok(p)
    }

    /// Builds `levels` levels (at least 1) over `window` (the whole image when `None`), reusing this
    /// pyramid's buffers. Levels whose window would be narrower than 2 pixels are not built.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for zero levels or a window outside the image. (A NaN or
    /// infinite pixel cannot reach here: [`GreyImage::new`] rejects it.)
    pub fn build_into(
        &mut self,
        image: GreyImage<'_>,
        window: Option<Window>,
        levels: usize,
        presmooth: bool,
    ) -> Result<()> {
        if levels == 0 || levels > 16 {
            return Err(Error::InvalidSetting {
                name: "levels",
                reason: format!("{levels} must be in 1..=16"),
            });
        }
        let (w, h) = (image.width(), image.height());
        let win = window.unwrap_or(Window::full(w, h));
        if win.width == 0 || win.height == 0 || win.x0 + win.width > w || win.y0 + win.height > h {
            return Err(Error::InvalidSetting {
                name: "window",
                reason: format!("{win:?} is empty or outside the {w}×{h} image"),
            });
        }
        self.image_width = w;
        self.image_height = h;
        self.presmooth = presmooth;
        if self.levels.len() < levels {
            self.levels.resize_with(levels, Level::default);
        }
        // Level 0: copy the window (its pixels are finite: `GreyImage` checked them), then
        // optionally pre-smooth.
        {
            let l0 = &mut self.levels[0];
            l0.x0 = win.x0;
            l0.y0 = win.y0;
            l0.width = win.width;
            l0.height = win.height;
            l0.data.clear();
            let src = image.data();
            for j in 0..win.height {
                let start = (win.y0 + j) * w + win.x0;
                l0.data.extend_from_slice(&src[start..start + win.width]);
            }
            let tmp = &mut self.tmp;
            simd(
                #[inline(always)]
                || {
                    if presmooth {
                        smooth_in_place(&mut l0.data, win.width, win.height, tmp);
                    }
                    gradients(l0);
                },
            );
        }
        let mut built = 1;
        for l in 1..levels {
            let (parents, rest) = self.levels.split_at_mut(l);
            let parent = &parents[l - 1];
            let child = &mut rest[0];
            // Child pixel i sits on parent pixel 2i; keep those whose parent lies in the window.
            let cx0 = parent.x0.div_ceil(2);
            let cx1 = (parent.x0 + parent.width - 1) / 2;
            let cy0 = parent.y0.div_ceil(2);
            let cy1 = (parent.y0 + parent.height - 1) / 2;
            if cx1 < cx0 + 1 || cy1 < cy0 + 1 {
                break;
            }
            child.x0 = cx0;
            child.y0 = cy0;
            child.width = cx1 + 1 - cx0;
            child.height = cy1 + 1 - cy0;
            let tmp = &mut self.tmp;
            simd(
                #[inline(always)]
                || {
                    reduce(parent, child, tmp);
                    gradients(child);
                },
            );
            built += 1;
        }
        self.n_levels = built;
        Ok(())
    }

    /// Number of levels built.
    pub fn levels(&self) -> usize {
        self.n_levels
    }

    /// Level `l` (0 = full resolution), if built.
    pub fn level(&self, l: usize) -> Option<&Level> {
        if l < self.n_levels {
            self.levels.get(l)
        } else {
            None
        }
    }

    /// Whether level 0 was pre-smoothed.
    pub fn presmoothed(&self) -> bool {
        self.presmooth
    }

    /// Size of the image the pyramid was built from.
    pub fn image_size(&self) -> (usize, usize) {
        (self.image_width, self.image_height)
    }
}

#[inline(always)]
fn clampi(i: isize, n: usize) -> usize {
    i.clamp(0, n as isize - 1) as usize
}

/// Separable [1 4 6 4 1]/16 smoothing with clamped borders.
#[inline(always)]
fn smooth_in_place(data: &mut [f32], w: usize, h: usize, tmp: &mut Vec<f32>) {
    // Every entry is written below: resize without clearing (no zero fill of reused memory).
    tmp.resize(w * h, 0.0);
    let k = KERNEL;
    for j in 0..h {
        let row = &data[j * w..(j + 1) * w];
        let out = &mut tmp[j * w..(j + 1) * w];
        // Interior in five-tap windows (the same sums, in the same order, as the border's).
        if w >= 5 {
            for (o, v) in out[2..w - 2].iter_mut().zip(row.windows(5)) {
                *o = k[0] * v[0] + k[1] * v[1] + k[2] * v[2] + k[3] * v[3] + k[4] * v[4];
            }
        }
        for i in (0..w.min(2)).chain(w.saturating_sub(2).max(w.min(2))..w) {
            let mut s = 0.0;
            for (t, &kv) in k.iter().enumerate() {
                s += kv * row[clampi(i as isize + t as isize - 2, w)];
            }
            out[i] = s;
        }
    }
    vertical(tmp, w, h, 0, 1, data);
}

/// The vertical pass of the clamped-border binomial filter over the `w`-wide rows of `src` (`h`
/// rows), evaluated at rows `off + step·j` into the rows of `out`, as whole-row slices
/// (vectorisable). The sum runs in the order of the kernel's taps, from zero.
#[inline(always)]
fn vertical(src: &[f32], w: usize, h: usize, off: usize, step: usize, out: &mut [f32]) {
    let k = KERNEL;
    for (j, out) in out.chunks_exact_mut(w).enumerate() {
        let c = (off + step * j) as isize;
        let row = |t: isize| &src[clampi(c + t, h) * w..][..w];
        let (a, b, m, d, e) = (row(-2), row(-1), row(0), row(1), row(2));
        for (i, o) in out.iter_mut().enumerate() {
            let mut s = 0.0;
            s += k[0] * a[i];
            s += k[1] * b[i];
            s += k[2] * m[i];
            s += k[3] * d[i];
            s += k[4] * e[i];
            *o = s;
        }
    }
}

/// Filters `parent` with the binomial kernel at the child's sample positions only, then subsamples.
#[inline(always)]
fn reduce(parent: &Level, child: &mut Level, tmp: &mut Vec<f32>) {
    let (pw, ph) = (parent.width, parent.height);
    let (cw, ch) = (child.width, child.height);
    // Parent-window column of child column i.
    let off_x = 2 * child.x0 - parent.x0;
    let off_y = 2 * child.y0 - parent.y0;
    // Every entry is written below: resize without clearing.
    tmp.resize(ph * cw, 0.0);
    let k = KERNEL;
    // Child columns whose five taps all fall inside the parent row: i_lo..i_hi.
    let i_lo = (2usize.saturating_sub(off_x)).div_ceil(2).min(cw);
    let i_hi = if pw >= off_x + 3 {
        ((pw - off_x - 3) / 2 + 1).clamp(i_lo, cw)
    } else {
        i_lo
    };
    for j in 0..ph {
        let row = &parent.data[j * pw..(j + 1) * pw];
        let out = &mut tmp[j * cw..(j + 1) * cw];
        for (i, o) in out.iter_mut().enumerate().take(i_hi).skip(i_lo) {
            let v = &row[off_x + 2 * i - 2..off_x + 2 * i + 3];
            *o = k[0] * v[0] + k[1] * v[1] + k[2] * v[2] + k[3] * v[3] + k[4] * v[4];
        }
        for i in (0..i_lo).chain(i_hi..cw) {
            let c = (off_x + 2 * i) as isize;
            let mut s = 0.0;
            for (t, &kv) in k.iter().enumerate() {
                s += kv * row[clampi(c + t as isize - 2, pw)];
            }
            out[i] = s;
        }
    }
    child.data.resize(cw * ch, 0.0);
    vertical(tmp, cw, ph, off_y, 2, &mut child.data);
}

/// Central-difference gradients, one-sided on the window border.
#[inline(always)]
fn gradients(level: &mut Level) {
    let (w, h) = (level.width, level.height);
    // Both are fully written below when the level is at least 2×2; otherwise they stay zero.
    if w < 2 || h < 2 {
        level.gx.clear();
        level.gy.clear();
    }
    level.gx.resize(w * h, 0.0);
    level.gy.resize(w * h, 0.0);
    let d = &level.data;
    for j in 0..h {
        let row = &d[j * w..(j + 1) * w];
        let gx = &mut level.gx[j * w..(j + 1) * w];
        if w >= 2 {
            gx[0] = row[1] - row[0];
            gx[w - 1] = row[w - 1] - row[w - 2];
            for i in 1..w - 1 {
                gx[i] = 0.5 * (row[i + 1] - row[i - 1]);
            }
        }
        let gy = &mut level.gy[j * w..(j + 1) * w];
        if h >= 2 {
            let (up, down, half) = if j == 0 {
                (0, 1, 1.0)
            } else if j == h - 1 {
                (h - 2, h - 1, 1.0)
            } else {
                (j - 1, j + 1, 0.5)
            };
            let (up, down) = (&d[up * w..][..w], &d[down * w..][..w]);
            for ((g, &dn), &u) in gy.iter_mut().zip(down).zip(up) {
                *g = half * (dn - u);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(w: usize, h: usize) -> Vec<f32> {
        (0..w * h)
            .map(|k| (3 * (k % w) + 2 * (k / w)) as f32)
            .collect()
    }

    #[test]
    fn linear_ramp_is_preserved_inside() {
        // The binomial kernel is symmetric with unit sum, so a linear ramp is reproduced exactly
        // away from the clamped border, and level-l pixel i sits at level-0 coordinate 2^l·i.
        let (w, h) = (64, 48);
        let data = ramp(w, h);
        let img = GreyImage::new(w, h, &data).unwrap();
        let p = Pyramid::build(img, None, 3, true).unwrap();
        assert_eq!(p.levels(), 3);
        let l2 = p.level(2).unwrap();
        assert_eq!((l2.width, l2.height), (16, 12));
        let (i, j) = (8, 6);
        let v = l2.data[j * l2.width + i];
        assert!((v - (3.0 * 32.0 + 2.0 * 24.0)).abs() < 1e-3, "{v}");
        // Gradient per level-2 pixel = 4 × level-0 gradient.
        assert!((l2.gx[j * l2.width + i] - 12.0).abs() < 1e-3);
        assert!((l2.gy[j * l2.width + i] - 8.0).abs() < 1e-3);
    }

    #[test]
    fn window_pyramid_matches_full_pyramid_inside() {
        // Away from the window edge (margin ≫ kernel reach) the windowed pyramid equals the full one.
        let (w, h) = (96, 80);
        let data: Vec<f32> = (0..w * h)
            .map(|k| ((k % w) as f32 * 0.37).sin() * 50.0 + ((k / w) as f32 * 0.23).cos() * 40.0)
            .collect();
        let img = GreyImage::new(w, h, &data).unwrap();
        let full = Pyramid::build(img, None, 3, true).unwrap();
        let win = Window::around(40, 30, 60, 50, 24, w, h);
        let part = Pyramid::build(img, Some(win), 3, true).unwrap();
        for l in 0..3 {
            let (a, b) = (full.level(l).unwrap(), part.level(l).unwrap());
            let s = 1usize << l;
            let (ci, cj) = (50 / s, 40 / s);
            let va = a.data[(cj - a.y0) * a.width + ci - a.x0];
            let vb = b.data[(cj - b.y0) * b.width + ci - b.x0];
            assert!((va - vb).abs() < 1e-3, "level {l}: {va} vs {vb}");
        }
    }

    #[test]
    fn nan_is_reported_with_its_index() {
        // The view rejects the NaN at construction, before any pyramid is built.
        let mut data = ramp(8, 8);
        data[19] = f32::NAN;
        let err = Error::from(GreyImage::new(8, 8, &data).unwrap_err());
        assert_eq!(
            err,
            Error::Image(vision_core::Error::NonFinite { index: 19 })
        );
    }
}
