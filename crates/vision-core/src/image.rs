//! The one grey image of the workspace: a borrowed, validated, row-major f32 view, and the image
//! crate's `ImageBuffer<Luma<f32>, Vec<f32>>` as its owned form.

use std::ops::Deref;

use image::{ImageBuffer, Luma};

use crate::{Error, Result};

/// An owned grey frame: the image crate's f32 luma buffer, grey levels 0–255, row-major.
pub type GreyBuffer = ImageBuffer<Luma<f32>, Vec<f32>>;

/// The grey level of an 8-bit RGB pixel, with the ITU-R BT.601 luma weights
/// (0.299 R + 0.587 G + 0.114 B, in f32, in this order): the one conversion from colour to the
/// workspace's grey frames, so that every reader of colour frames (image folders, the Python
/// binding) gives the trackers the same grey levels.
#[inline]
pub fn luma_bt601(r: u8, g: u8, b: u8) -> f32 {
    0.299 * f32::from(r) + 0.587 * f32::from(g) + 0.114 * f32::from(b)
}

/// A borrowed, row-major grey image in f32 grey levels (0–255), checked once at construction:
/// both sides at least one pixel, `width · height` values, every value finite.
///
/// Coordinates: x to the right, y down; pixel (i, j) is `data[j · width + i]` and has its centre
/// at (i, j), so the image covers [0, width − 1] × [0, height − 1] for interpolation. Operations
/// with further needs check them where they apply (bilinear sampling needs two pixels per side).
///
/// # Examples
/// ```
/// use vision_core::{GreyBuffer, GreyImage};
///
/// let buffer = GreyBuffer::from_fn(4, 3, |x, y| image::Luma([(x + 10 * y) as f32]));
/// let view = GreyImage::try_from(&buffer)?;
/// assert_eq!((view.width(), view.height()), (4, 3));
/// assert_eq!(view.get(3, 2), Some(23.0));
/// assert_eq!(GreyBuffer::from(view), buffer);
/// # Ok::<(), vision_core::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GreyImage<'a> {
    width: usize,
    height: usize,
    data: &'a [f32],
}

impl<'a> GreyImage<'a> {
    /// Wraps `data` (row-major, `width * height` values) after checking its size and that every
    /// pixel is finite.
    ///
    /// # Errors
    /// [`Error::Empty`] for a zero side, [`Error::ImageSize`] on a length mismatch,
    /// [`Error::NonFinite`] at the first NaN or infinite pixel.
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
        if width == 0 || height == 0 {
            return Err(Error::Empty { width, height });
        }
        if let Some(index) = first_non_finite(data) {
            return Err(Error::NonFinite { index });
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

    /// The pixel at column `x`, row `y`, or `None` outside the image.
    pub fn get(&self, x: usize, y: usize) -> Option<f32> {
        (x < self.width && y < self.height).then(|| self.data[y * self.width + x])
    }

    /// An owned copy as the image crate's buffer.
    pub fn to_buffer(&self) -> GreyBuffer {
        GreyBuffer::from(*self)
    }
}

impl<'a, C> TryFrom<&'a ImageBuffer<Luma<f32>, C>> for GreyImage<'a>
where
    C: Deref<Target = [f32]>,
{
    type Error = Error;

    /// Views an image-crate f32 luma buffer, with the checks of [`GreyImage::new`].
    fn try_from(buffer: &'a ImageBuffer<Luma<f32>, C>) -> Result<Self> {
        let (w, h) = buffer.dimensions();
        GreyImage::new(w as usize, h as usize, buffer.as_raw())
    }
}

impl From<GreyImage<'_>> for GreyBuffer {
    /// Copies the pixels into an image-crate buffer. The sides fit in `u32`, since the buffer
    /// they came from holds `width · height` values.
    fn from(view: GreyImage<'_>) -> Self {
        let (w, h) = (view.width as u32, view.height as u32);
        GreyBuffer::from_fn(w, h, |x, y| {
            Luma([view.data[y as usize * view.width + x as usize]])
        })
    }
}

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
        assert_eq!(
            GreyImage::new(3, 2, &[0.0; 5]).unwrap_err(),
            Error::ImageSize {
                width: 3,
                height: 2,
                expected: 6,
                got: 5
            }
        );
        assert_eq!(
            GreyImage::new(0, 4, &[]).unwrap_err(),
            Error::Empty {
                width: 0,
                height: 4
            }
        );
        assert!(matches!(
            GreyImage::new(usize::MAX, 2, &[0.0; 4]),
            Err(Error::ImageSize {
                expected: usize::MAX,
                ..
            })
        ));
        let mut d = [0.0; 6];
        d[4] = f32::NAN;
        assert_eq!(
            GreyImage::new(3, 2, &d).unwrap_err(),
            Error::NonFinite { index: 4 }
        );
        // One pixel per side is a valid image.
        assert!(GreyImage::new(1, 1, &[7.0]).is_ok());
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
    fn image_crate_buffers_convert_both_ways() {
        let buffer = GreyBuffer::from_fn(5, 2, |x, y| Luma([x as f32 + 100.0 * y as f32]));
        let view = GreyImage::try_from(&buffer).unwrap();
        assert_eq!((view.width(), view.height()), (5, 2));
        assert_eq!(view.data(), buffer.as_raw().as_slice());
        assert_eq!(view.get(4, 1), Some(104.0));
        assert_eq!(view.get(5, 0), None);
        assert_eq!(view.get(0, 2), None);
        assert_eq!(view.to_buffer(), buffer);
        // A buffer over a borrowed slice converts too.
        let raw = [1.0f32, 2.0, 3.0, 4.0];
        let borrowed = ImageBuffer::<Luma<f32>, &[f32]>::from_raw(2, 2, &raw[..]).unwrap();
        assert_eq!(GreyImage::try_from(&borrowed).unwrap().data(), &raw);
        // The checks apply to image-crate buffers as to slices.
        let bad = GreyBuffer::from_fn(2, 2, |x, _| Luma([if x == 1 { f32::NAN } else { 0.0 }]));
        assert_eq!(
            GreyImage::try_from(&bad).unwrap_err(),
            Error::NonFinite { index: 1 }
        );
        let empty = GreyBuffer::new(0, 3);
        assert!(matches!(
            GreyImage::try_from(&empty),
            Err(Error::Empty { .. })
        ));
    }
}
