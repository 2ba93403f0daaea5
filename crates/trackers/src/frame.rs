//! Frames as the trackers see them: the workspace's grey image ([`GreyImage`], validated once at
//! construction) and optionally the 8-bit RGB pixels of the same frame (the region tracker's
//! colour model reads them; every other tracker reads grey).
//!
//! [`Frame`] borrows its pixels; [`FrameBuf`] owns them and is built from the image crate's
//! images (`FrameBuf::from(&image::open(path)?)`), with the grey levels 0–255 the trackers expect
//! ([`vision_core::ToGreyBuffer`]).

use std::ops::Deref;

use image::{DynamicImage, GrayImage, ImageBuffer, Luma, RgbImage};
use vision_core::{GreyBuffer, GreyImage, ToGreyBuffer};

use crate::{Error, Result};

/// A borrowed frame: a [`GreyImage`] (row-major, `width`×`height`, grey levels 0–255) and, when
/// the frame has colour, its RGB pixels.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    grey: GreyImage<'a>,
    rgb: Option<&'a [u8]>,
}

impl<'a> From<GreyImage<'a>> for Frame<'a> {
    /// A grey frame.
    fn from(grey: GreyImage<'a>) -> Self {
        Self { grey, rgb: None }
    }
}

impl<'a, C> TryFrom<&'a ImageBuffer<Luma<f32>, C>> for Frame<'a>
where
    C: Deref<Target = [f32]>,
{
    type Error = Error;

    /// A grey frame viewing an f32 buffer that holds grey levels 0–255 (a [`GreyBuffer`]; an
    /// image in the image crate's 0–1 scale goes through
    /// [`vision_core::grey_from_unit_range`] first).
    ///
    /// # Errors
    /// [`Error::Image`] as [`Frame::new`].
    fn try_from(buffer: &'a ImageBuffer<Luma<f32>, C>) -> Result<Self> {
        Ok(GreyImage::try_from(buffer)?.into())
    }
}

impl<'a> Frame<'a> {
    /// Wraps `data` as a grey frame ([`GreyImage::new`]).
    ///
    /// # Errors
    /// [`Error::Image`] when the size is zero, the length does not match, or a pixel is not
    /// finite. A frame does not know its place in a sequence, so the error names none.
    pub fn new(width: usize, height: usize, data: &'a [f32]) -> Result<Self> {
        Ok(GreyImage::new(width, height, data)?.into())
    }

    /// Wraps `grey` and the same frame's interleaved 8-bit RGB pixels (`3·width·height` bytes,
    /// row-major, R G B per pixel).
    ///
    /// # Errors
    /// As [`Frame::new`], and [`Error::RgbSize`] when `rgb` has the wrong length.
    pub fn with_rgb(width: usize, height: usize, grey: &'a [f32], rgb: &'a [u8]) -> Result<Self> {
        let mut frame = Self::new(width, height, grey)?;
        let expected = width.saturating_mul(height).saturating_mul(3);
        if rgb.len() != expected {
            return Err(Error::RgbSize {
                width,
                height,
                expected,
                got: rgb.len(),
            });
        }
        frame.rgb = Some(rgb);
        Ok(frame)
    }

    /// The grey image.
    pub fn grey(&self) -> GreyImage<'a> {
        self.grey
    }

    /// The RGB pixels, when the frame has colour.
    pub fn rgb(&self) -> Option<&'a [u8]> {
        self.rgb
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.grey.width()
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.grey.height()
    }

    /// The grey pixels, row-major.
    pub fn data(&self) -> &'a [f32] {
        self.grey.data()
    }
}

/// An owned frame: its grey levels 0–255 and, for a colour image, its 8-bit RGB pixels. Built
/// from the image crate's images with `From`; [`FrameBuf::frame`] lends it to a tracker.
///
/// Colour images keep their RGB pixels (the region tracker, `head`, reads colour) and get their
/// grey levels from the BT.601 luma weights; grey images have no colour. 16-bit and float images
/// are scaled to 0–255 ([`vision_core::ToGreyBuffer`]).
///
/// # Examples
/// ```
/// use trackers::{Frame, FrameBuf};
///
/// let decoded = image::DynamicImage::ImageRgb8(image::RgbImage::from_pixel(8, 6, image::Rgb([255, 0, 0])));
/// let owned = FrameBuf::from(&decoded);
/// let frame: Frame<'_> = owned.frame()?;
/// assert_eq!((frame.width(), frame.height()), (8, 6));
/// assert!(frame.rgb().is_some());
/// assert!((frame.data()[0] - 0.299 * 255.0).abs() < 1e-3);
/// # Ok::<(), trackers::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct FrameBuf {
    grey: GreyBuffer,
    rgb: Option<RgbImage>,
}

impl FrameBuf {
    /// The frame as a tracker takes it.
    ///
    /// # Errors
    /// [`Error::Image`] for an empty image or a grey level that is not finite (possible only for
    /// a float image); [`Error::RgbSize`] cannot happen, the RGB pixels having the grey image's
    /// size.
    pub fn frame(&self) -> Result<Frame<'_>> {
        let (w, h) = self.grey.dimensions();
        let (w, h) = (w as usize, h as usize);
        match &self.rgb {
            Some(rgb) => Frame::with_rgb(w, h, self.grey.as_raw(), rgb.as_raw()),
            None => Frame::new(w, h, self.grey.as_raw()),
        }
    }

    /// The grey levels.
    pub fn grey(&self) -> &GreyBuffer {
        &self.grey
    }

    /// The RGB pixels of a colour frame.
    pub fn rgb(&self) -> Option<&RgbImage> {
        self.rgb.as_ref()
    }
}

impl From<GreyBuffer> for FrameBuf {
    /// A grey frame from grey levels 0–255 (checked by [`FrameBuf::frame`]).
    fn from(grey: GreyBuffer) -> Self {
        Self { grey, rgb: None }
    }
}

impl From<&GrayImage> for FrameBuf {
    /// A grey frame: the 8-bit levels as they are.
    fn from(img: &GrayImage) -> Self {
        img.to_grey_buffer().into()
    }
}

impl From<GrayImage> for FrameBuf {
    /// A grey frame: the 8-bit levels as they are.
    fn from(img: GrayImage) -> Self {
        (&img).into()
    }
}

impl From<RgbImage> for FrameBuf {
    /// A colour frame: the RGB pixels, and BT.601 luma as grey.
    fn from(rgb: RgbImage) -> Self {
        Self {
            grey: rgb.to_grey_buffer(),
            rgb: Some(rgb),
        }
    }
}

impl From<&RgbImage> for FrameBuf {
    /// A colour frame: the RGB pixels, and BT.601 luma as grey.
    fn from(rgb: &RgbImage) -> Self {
        rgb.clone().into()
    }
}

impl From<&DynamicImage> for FrameBuf {
    /// A decoded image: grey variants (with or without alpha, 8 or 16 bits) give a grey frame,
    /// the others a colour frame with their 8-bit RGB pixels. The grey levels are those of
    /// [`vision_core::ToGreyBuffer`] on the image itself (16-bit precision kept).
    fn from(img: &DynamicImage) -> Self {
        let grey = img.to_grey_buffer();
        let rgb = match img {
            DynamicImage::ImageLuma8(_)
            | DynamicImage::ImageLumaA8(_)
            | DynamicImage::ImageLuma16(_)
            | DynamicImage::ImageLumaA16(_) => None,
            other => Some(other.to_rgb8()),
        };
        Self { grey, rgb }
    }
}

impl From<DynamicImage> for FrameBuf {
    /// As `From<&DynamicImage>`.
    fn from(img: DynamicImage) -> Self {
        (&img).into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_errors_name_no_frame_index() {
        let e = Frame::new(3, 2, &[0.0; 5]).unwrap_err();
        assert!(matches!(e, Error::Image(_)), "{e:?}");
        assert!(!e.to_string().contains("frame 0"), "{e}");
        let e = Frame::with_rgb(2, 2, &[0.0; 4], &[0; 11]).unwrap_err();
        assert!(
            matches!(
                e,
                Error::RgbSize {
                    width: 2,
                    height: 2,
                    expected: 12,
                    got: 11
                }
            ),
            "{e:?}"
        );
        assert!(!e.to_string().contains("frame 0"), "{e}");
    }

    #[test]
    fn image_crate_images_become_frames_in_grey_levels() {
        let grey = GrayImage::from_fn(6, 4, |x, y| Luma([(30 * x + y) as u8]));
        let owned = FrameBuf::from(&grey);
        let f = owned.frame().unwrap();
        assert!(f.rgb().is_none());
        assert_eq!(f.data()[5 + 6 * 3], 153.0);
        // The same through DynamicImage, 8 or 16 bits, and through a GreyBuffer view.
        for d in [
            DynamicImage::ImageLuma8(grey.clone()),
            DynamicImage::ImageLuma16(DynamicImage::ImageLuma8(grey.clone()).to_luma16()),
        ] {
            let o = FrameBuf::from(&d);
            assert_eq!(o.frame().unwrap().data(), f.data());
            assert!(o.rgb().is_none());
        }
        let buffer = grey.to_grey_buffer();
        assert_eq!(Frame::try_from(&buffer).unwrap().data(), f.data());

        let rgb = RgbImage::from_fn(6, 4, |x, y| image::Rgb([40 * x as u8, 60 * y as u8, 200]));
        let owned = FrameBuf::from(&rgb);
        let f = owned.frame().unwrap();
        assert_eq!(f.rgb(), Some(rgb.as_raw().as_slice()));
        let p = rgb.get_pixel(2, 3);
        let expected = 0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2]);
        assert_eq!(f.data()[2 + 6 * 3], expected);
        let from_dynamic = FrameBuf::from(DynamicImage::ImageRgba8(
            DynamicImage::ImageRgb8(rgb.clone()).to_rgba8(),
        ));
        assert_eq!(from_dynamic, owned);

        // A float buffer with a NaN is refused when lent, naming no frame.
        let bad = GreyBuffer::from_fn(2, 2, |x, _| Luma([if x == 1 { f32::NAN } else { 1.0 }]));
        assert!(matches!(FrameBuf::from(bad).frame(), Err(Error::Image(_))));
        assert!(matches!(
            FrameBuf::from(GrayImage::new(0, 3)).frame(),
            Err(Error::Image(_))
        ));
    }
}
