//! Bilinear sampling of the workspace's grey image ([`GreyImage`]), with the one extra
//! requirement sampling has: at least two pixels per side.

use vision_core::GreyImage;

use crate::{Error, Result};

/// The smallest side bilinear interpolation can use: two samples per axis.
pub(crate) const MIN_SIDE: usize = 2;

/// Whether `image` can be sampled bilinearly (at least [`MIN_SIDE`] pixels per side).
#[inline]
pub(crate) fn samplable(image: &GreyImage<'_>) -> bool {
    image.width() >= MIN_SIDE && image.height() >= MIN_SIDE
}

/// Checks that `image` can be sampled bilinearly.
///
/// # Errors
/// [`Error::ImageTooSmall`] when a side is below 2 pixels.
pub(crate) fn check_samplable(image: &GreyImage<'_>) -> Result<()> {
    if samplable(image) {
        Ok(())
    } else {
        Err(Error::ImageTooSmall {
            width: image.width(),
            height: image.height(),
            min: MIN_SIDE,
        })
    }
}

/// Bilinear sampling of a [`GreyImage`]. Every method answers "outside" (or reads nothing) on an
/// image below 2×2 pixels, which has no interpolation cell.
pub trait Bilinear {
    /// Bilinear interpolation at (x, y), or `None` outside [0, width − 1] × [0, height − 1]
    /// (always `None` on an image with a side below 2 pixels).
    fn sample(&self, x: f32, y: f32) -> Option<f32>;
}

impl Bilinear for GreyImage<'_> {
    fn sample(&self, x: f32, y: f32) -> Option<f32> {
        if !samplable(self) {
            return None;
        }
        let xmax = (self.width() - 1) as f32;
        let ymax = (self.height() - 1) as f32;
        if !(0.0..=xmax).contains(&x) || !(0.0..=ymax).contains(&y) {
            return None;
        }
        Some(sample_inside(self, x, y))
    }
}

/// Bilinear interpolation for a point known to be inside (or within rounding of) the image.
/// Indices are clamped so that rounding can never index out of bounds.
#[inline]
fn sample_inside(image: &GreyImage<'_>, x: f32, y: f32) -> f32 {
    // Truncation equals floor for the non-negative coordinates of the image (and maps a
    // rounding-level negative to 0); it avoids a libm `floorf` call on baseline x86-64.
    let x0 = (x as i32).clamp(0, image.width() as i32 - 2);
    let y0 = (y as i32).clamp(0, image.height() as i32 - 2);
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let i = y0 as usize * image.width() + x0 as usize;
    // One bounds check for the 2×2 neighbourhood.
    let quad = &image.data()[i..i + image.width() + 2];
    let (p00, p10) = (quad[0], quad[1]);
    let (p01, p11) = (quad[image.width()], quad[image.width() + 1]);
    let t = p00 + fx * (p10 - p00);
    let b = p01 + fx * (p11 - p01);
    t + fy * (b - t)
}

/// Samples the points c + k·n for the integer offsets k = `lo` ..= `hi` into `out[k − lo]`
/// by bilinear interpolation. Every point must lie inside (or within rounding of) the image;
/// indices are clamped as in [`Bilinear::sample`], so rounding never reads out of bounds.
///
/// Positions are stepped in fixed point with [`FIX_BITS`] fractional bits (exact integer
/// additions; the start and the step are truncated once, so a position is within
/// (1 + |k|)·2⁻²⁴ px of c + k·n, far finer than f32 at image scale). The integer part is the
/// pixel and the fraction the weight, with no float-to-int conversion per sample. Positions
/// are exactly linear in k, so the run lies between its end points: when both are inside
/// [0, w − 1) × [0, h − 1) no index needs clamping and the loop drops the clamps.
#[inline]
pub(crate) fn sample_line(
    image: &GreyImage<'_>,
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
    let (w, h) = (image.width() as i64, image.height() as i64);
    let frac_mask = (1i64 << FIX_BITS) - 1;
    let scale = 1.0 / one as f32;
    let wu = image.width();
    let limit_x = (w - 1) << FIX_BITS;
    let limit_y = (h - 1) << FIX_BITS;
    let clear = |p: i64, limit: i64| (0..limit).contains(&p);
    let fast =
        clear(px, limit_x) && clear(end_x, limit_x) && clear(py, limit_y) && clear(end_y, limit_y);
    if fast {
        for o in out.iter_mut() {
            let (x0, y0) = ((px >> FIX_BITS) as usize, (py >> FIX_BITS) as usize);
            let fx = (px & frac_mask) as f32 * scale;
            let fy = (py & frac_mask) as f32 * scale;
            *o = lerp(image, y0 * wu + x0, fx, fy);
            px += step_x;
            py += step_y;
        }
    } else {
        for o in out.iter_mut() {
            let x0 = (px >> FIX_BITS).clamp(0, w - 2);
            let y0 = (py >> FIX_BITS).clamp(0, h - 2);
            let fx = (px - (x0 << FIX_BITS)) as f32 * scale;
            let fy = (py - (y0 << FIX_BITS)) as f32 * scale;
            *o = lerp(image, y0 as usize * wu + x0 as usize, fx, fy);
            px += step_x;
            py += step_y;
        }
    }
}

/// Bilinear interpolation in the cell whose top-left pixel has index `i`, at fractions
/// (`fx`, `fy`). One bounds check for the 2×2 neighbourhood.
#[inline(always)]
fn lerp(image: &GreyImage<'_>, i: usize, fx: f32, fy: f32) -> f32 {
    let w = image.width();
    let quad = &image.data()[i..i + w + 2];
    let (p00, p10) = (quad[0], quad[1]);
    let (p01, p11) = (quad[w], quad[w + 1]);
    let t = p00 + fx * (p10 - p00);
    let b = p01 + fx * (p11 - p01);
    t + fy * (b - t)
}

/// Fractional bits of the fixed-point positions of [`sample_line`]: 2⁻²⁴ px
/// resolution, and room for coordinates up to 2³⁸ px in an i64.
pub(crate) const FIX_BITS: u32 = 24;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn images_below_two_pixels_per_side_cannot_be_sampled() {
        let d = [0.0; 4];
        let thin = GreyImage::new(1, 4, &d).unwrap();
        assert_eq!(
            check_samplable(&thin).unwrap_err(),
            Error::ImageTooSmall {
                width: 1,
                height: 4,
                min: 2
            }
        );
        assert_eq!(thin.sample(0.0, 1.0), None);
        assert!(check_samplable(&GreyImage::new(2, 2, &d).unwrap()).is_ok());
    }

    #[test]
    fn bilinear_reproduces_a_plane_exactly() {
        // A plane 3x + 5y + 1 is reproduced exactly by bilinear interpolation (up to f32 rounding).
        let (w, h) = (6, 4);
        let d: Vec<f32> = (0..w * h)
            .map(|k| 3.0 * (k % w) as f32 + 5.0 * (k / w) as f32 + 1.0)
            .collect();
        let img = GreyImage::new(w, h, &d).unwrap();
        for &(x, y) in &[(0.0, 0.0), (2.25, 1.5), (5.0, 3.0), (4.9, 0.1)] {
            let v = img.sample(x, y).unwrap();
            assert!((v - (3.0 * x + 5.0 * y + 1.0)).abs() < 1e-4, "{x},{y}: {v}");
        }
        assert_eq!(img.sample(-0.01, 1.0), None);
        assert_eq!(img.sample(1.0, 3.01), None);
    }
}
