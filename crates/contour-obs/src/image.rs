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
        if let Some(index) = data.iter().position(|v| !v.is_finite()) {
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
