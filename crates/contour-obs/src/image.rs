//! A borrowed grey-level image view and bilinear sampling.

use crate::{Error, Result};

/// A borrowed, row-major grey image in f32 grey-level units (0–255).
///
/// Coordinates: x to the right, y down; pixel (i, j) has its centre at (i, j), so the image covers
/// the continuous square [0, width − 1] × [0, height − 1] for interpolation purposes.
#[derive(Debug, Clone, Copy)]
pub struct GreyView<'a> {
    width: usize,
    height: usize,
    data: &'a [f32],
}

impl<'a> GreyView<'a> {
    /// Wraps `data` (row-major, `width * height` values) after checking its size and that every
    /// pixel is finite.
    ///
    /// # Errors
    /// [`Error::ImageSize`] on a length mismatch, [`Error::ImageTooSmall`] when a side is below 2
    /// pixels (bilinear interpolation needs two samples per axis), [`Error::NonFinite`] at the
    /// first NaN or infinite pixel.
    pub fn new(width: usize, height: usize, data: &'a [f32]) -> Result<Self> {
        let expected = width.checked_mul(height).ok_or(Error::ImageSize {
            width,
            height,
            expected: usize::MAX,
            got: data.len(),
        })?;
        if data.len() != expected {
            return Err(Error::ImageSize {
                width,
                height,
                expected,
                got: data.len(),
            });
        }
        if width < 2 || height < 2 {
            return Err(Error::ImageTooSmall {
                width,
                height,
                min: 2,
            });
        }
        if let Some(index) = first_non_finite(data) {
            return Err(Error::NonFinite {
                what: "image pixel",
                index,
            });
        }
        Ok(Self {
            width,
            height,
            data,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The row-major pixel buffer.
    pub fn data(&self) -> &'a [f32] {
        self.data
    }

    /// Bilinear interpolation at (x, y), or `None` outside [0, width − 1] × [0, height − 1].
    pub fn sample(&self, x: f32, y: f32) -> Option<f32> {
        let xmax = (self.width - 1) as f32;
        let ymax = (self.height - 1) as f32;
        if !(0.0..=xmax).contains(&x) || !(0.0..=ymax).contains(&y) {
            return None;
        }
        Some(self.sample_inside(x, y))
    }

    /// Bilinear interpolation for a point known to be inside (or within rounding of) the image.
    /// Indices are clamped so that rounding can never index out of bounds.
    #[inline]
    pub(crate) fn sample_inside(&self, x: f32, y: f32) -> f32 {
        // Truncation equals floor for the non-negative coordinates of the image (and maps a
        // rounding-level negative to 0); it avoids a libm `floorf` call on baseline x86-64.
        let x0 = (x as i32).clamp(0, self.width as i32 - 2);
        let y0 = (y as i32).clamp(0, self.height as i32 - 2);
        let (fx, fy) = (x - x0 as f32, y - y0 as f32);
        let i = y0 as usize * self.width + x0 as usize;
        // One bounds check for the 2×2 neighbourhood.
        let quad = &self.data[i..i + self.width + 2];
        let (p00, p10) = (quad[0], quad[1]);
        let (p01, p11) = (quad[self.width], quad[self.width + 1]);
        let t = p00 + fx * (p10 - p00);
        let b = p01 + fx * (p11 - p01);
        t + fy * (b - t)
    }

    /// Samples the points c + k·n for the integer offsets k = `lo` ..= `hi` into `out[k − lo]`
    /// by bilinear interpolation. Every point must lie inside (or within rounding of) the image;
    /// indices are clamped as in [`Self::sample`], so rounding never reads out of bounds.
    ///
    /// Positions are stepped in fixed point with [`FIX_BITS`] fractional bits (exact integer
    /// additions; the start and the step are truncated once, so a position is within
    /// (1 + |k|)·2⁻²⁴ px of c + k·n, far finer than f32 at image scale). The integer part is the
    /// pixel and the fraction the weight, with no float-to-int conversion per sample. Positions
    /// are exactly linear in k, so the run lies between its end points: when both are inside
    /// [0, w − 1) × [0, h − 1) no index needs clamping and the loop drops the clamps.
    #[inline]
    pub(crate) fn sample_line(
        &self,
        c: (f64, f64),
        n: (f64, f64),
        lo: i64,
        hi: i64,
        out: &mut [f32],
    ) {
        let out = &mut out[..(hi - lo + 1) as usize];
        let one = (1i64 << FIX_BITS) as f64;
        // Truncation (one instruction; `round` is a libm call on baseline x86-64): ≤ 2⁻²⁴ px.
        let fix = |v: f64| (v * one) as i64;
        let (step_x, step_y) = (fix(n.0), fix(n.1));
        let (mut px, mut py) = (fix(c.0) + lo * step_x, fix(c.1) + lo * step_y);
        let (end_x, end_y) = (px + (hi - lo) * step_x, py + (hi - lo) * step_y);
        let (w, h) = (self.width as i64, self.height as i64);
        let frac_mask = (1i64 << FIX_BITS) - 1;
        let scale = 1.0 / one as f32;
        let wu = self.width;
        let limit_x = (w - 1) << FIX_BITS;
        let limit_y = (h - 1) << FIX_BITS;
        let clear = |p: i64, limit: i64| (0..limit).contains(&p);
        let fast = clear(px, limit_x)
            && clear(end_x, limit_x)
            && clear(py, limit_y)
            && clear(end_y, limit_y);
        if fast {
            for o in out.iter_mut() {
                let (x0, y0) = ((px >> FIX_BITS) as usize, (py >> FIX_BITS) as usize);
                let fx = (px & frac_mask) as f32 * scale;
                let fy = (py & frac_mask) as f32 * scale;
                *o = self.lerp(y0 * wu + x0, fx, fy);
                px += step_x;
                py += step_y;
            }
        } else {
            for o in out.iter_mut() {
                let x0 = (px >> FIX_BITS).clamp(0, w - 2);
                let y0 = (py >> FIX_BITS).clamp(0, h - 2);
                let fx = (px - (x0 << FIX_BITS)) as f32 * scale;
                let fy = (py - (y0 << FIX_BITS)) as f32 * scale;
                *o = self.lerp(y0 as usize * wu + x0 as usize, fx, fy);
                px += step_x;
                py += step_y;
            }
        }
    }
}

impl GreyView<'_> {
    /// Bilinear interpolation in the cell whose top-left pixel has index `i`, at fractions
    /// (`fx`, `fy`). One bounds check for the 2×2 neighbourhood.
    #[inline(always)]
    fn lerp(&self, i: usize, fx: f32, fy: f32) -> f32 {
        let w = self.width;
        let quad = &self.data[i..i + w + 2];
        let (p00, p10) = (quad[0], quad[1]);
        let (p01, p11) = (quad[w], quad[w + 1]);
        let t = p00 + fx * (p10 - p00);
        let b = p01 + fx * (p11 - p01);
        t + fy * (b - t)
    }
}

/// Fractional bits of the fixed-point positions of [`GreyView::sample_line`]: 2⁻²⁴ px
/// resolution, and room for coordinates up to 2³⁸ px in an i64.
pub(crate) const FIX_BITS: u32 = 24;

/// The index of the first NaN or infinite value. Blocks of 256 are first tested with an integer
/// OR over "all exponent bits set" (a reduction the compiler vectorises), so the common
/// all-finite frame costs one fast pass; only a bad block is searched element by element.
fn first_non_finite(data: &[f32]) -> Option<usize> {
    const EXPONENT: u32 = 0x7f80_0000;
    data.chunks(256).enumerate().find_map(|(b, block)| {
        let bad = block.iter().fold(0u32, |acc, v| {
            acc | u32::from(v.to_bits() & EXPONENT == EXPONENT)
        });
        if bad == 0 {
            None
        } else {
            block
                .iter()
                .position(|v| !v.is_finite())
                .map(|i| b * 256 + i)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_buffers() {
        assert!(matches!(
            GreyView::new(3, 2, &[0.0; 5]),
            Err(Error::ImageSize { .. })
        ));
        assert!(matches!(
            GreyView::new(1, 4, &[0.0; 4]),
            Err(Error::ImageTooSmall { .. })
        ));
        let mut d = [0.0; 6];
        d[4] = f32::NAN;
        assert_eq!(
            GreyView::new(3, 2, &d).unwrap_err(),
            Error::NonFinite {
                what: "image pixel",
                index: 4
            }
        );
    }

    #[test]
    fn the_first_non_finite_pixel_is_found_in_any_block() {
        let mut d = vec![1.5f32; 1000];
        assert_eq!(first_non_finite(&d), None);
        for (at, bad) in [
            (999, f32::NAN),
            (700, f32::INFINITY),
            (256, f32::NEG_INFINITY),
        ] {
            d[at] = bad;
            assert_eq!(first_non_finite(&d), Some(at));
        }
        // Large finite values and subnormals are finite.
        assert_eq!(
            first_non_finite(&[f32::MAX, -f32::MAX, 1e-45, 0.0, -0.0]),
            None
        );
    }

    #[test]
    fn bilinear_reproduces_a_plane_exactly() {
        // A plane 3x + 5y + 1 is reproduced exactly by bilinear interpolation (up to f32 rounding).
        let (w, h) = (6, 4);
        let d: Vec<f32> = (0..w * h)
            .map(|k| 3.0 * (k % w) as f32 + 5.0 * (k / w) as f32 + 1.0)
            .collect();
        let img = GreyView::new(w, h, &d).unwrap();
        for &(x, y) in &[(0.0, 0.0), (2.25, 1.5), (5.0, 3.0), (4.9, 0.1)] {
            let v = img.sample(x, y).unwrap();
            assert!((v - (3.0 * x + 5.0 * y + 1.0)).abs() < 1e-4, "{x},{y}: {v}");
        }
        assert_eq!(img.sample(-0.01, 1.0), None);
        assert_eq!(img.sample(1.0, 3.01), None);
    }
}
