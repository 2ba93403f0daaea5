//! Frames as the trackers see them: the workspace's grey image ([`GreyImage`], validated once at
//! construction) and optionally the 8-bit RGB pixels of the same frame (the appearance terms'
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
/// the frame has colour, its 8-bit pixels, RGB or BGR.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    grey: GreyImage<'a>,
    colour: Option<&'a [u8]>,
    /// Where red, green and blue sit in a pixel of `colour`: `[0, 1, 2]` for RGB, `[2, 1, 0]`
    /// for BGR.
    channels: [usize; 3],
}

/// Channel offsets of RGB pixels.
const RGB: [usize; 3] = [0, 1, 2];
/// Channel offsets of BGR pixels (OpenCV's order).
const BGR: [usize; 3] = [2, 1, 0];

impl<'a> From<GreyImage<'a>> for Frame<'a> {
    /// A grey frame.
    fn from(grey: GreyImage<'a>) -> Self {
        Self {
            grey,
            colour: None,
            channels: RGB,
        }
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
    /// An error unless this frame has the size `first` of the track's first frame; `index` is
    /// the number the error gives this frame.
    ///
    /// # Errors
    /// [`Error::BadFrame`] naming both sizes.
    pub fn check_size(&self, first: (usize, usize), index: usize) -> Result<()> {
        if (self.width(), self.height()) == first {
            return Ok(());
        }
        Err(Error::BadFrame {
            frame: index,
            reason: format!(
                "{}×{} differs from the first frame's {}×{}",
                self.width(),
                self.height(),
                first.0,
                first.1
            ),
        })
    }

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
        Self::with_colour(width, height, grey, rgb, RGB)
    }

    /// Wraps `grey` and the same frame's interleaved 8-bit pixels in OpenCV's order, B G R per
    /// pixel: the trackers read them in place, without reordering them.
    ///
    /// # Errors
    /// As [`Frame::with_rgb`].
    pub fn with_bgr(width: usize, height: usize, grey: &'a [f32], bgr: &'a [u8]) -> Result<Self> {
        Self::with_colour(width, height, grey, bgr, BGR)
    }

    fn with_colour(
        width: usize,
        height: usize,
        grey: &'a [f32],
        colour: &'a [u8],
        channels: [usize; 3],
    ) -> Result<Self> {
        let mut frame = Self::new(width, height, grey)?;
        let expected = width.saturating_mul(height).saturating_mul(3);
        if colour.len() != expected {
            return Err(Error::RgbSize {
                width,
                height,
                expected,
                got: colour.len(),
            });
        }
        frame.colour = Some(colour);
        frame.channels = channels;
        Ok(frame)
    }

    /// The grey image.
    pub fn grey(&self) -> GreyImage<'a> {
        self.grey
    }

    /// The RGB pixels, when the frame has colour in RGB order (`None` for a BGR frame: see
    /// [`Frame::colour`]).
    pub fn rgb(&self) -> Option<&'a [u8]> {
        self.colour.filter(|_| self.channels == RGB)
    }

    /// The colour pixels, RGB or BGR, when the frame has colour, with the offsets of red, green
    /// and blue within a pixel: pixel `k`'s red is `pixels[3·k + offsets[0]]`.
    pub fn colour(&self) -> Option<(&'a [u8], [usize; 3])> {
        self.colour.map(|c| (c, self.channels))
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
/// Colour images keep their RGB pixels (the appearance terms of `head` read colour) and get their
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
    use crate::{Preset, build};
    use vision_core::{Ellipse, luma_bt601};

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

    /// A `w`×`h` RGB frame: a reddish disc at `cx` over a blue-green gradient.
    fn rgb_frame(w: usize, h: usize, cx: f64) -> Vec<u8> {
        let mut out = Vec::with_capacity(w * h * 3);
        for y in 0..h {
            for x in 0..w {
                let d = ((x as f64 - cx).powi(2) + (y as f64 - 40.0).powi(2)).sqrt();
                if d < 15.0 {
                    out.extend([210, 120, 90]);
                } else {
                    out.extend([30, (60 + x % 50) as u8, (90 + y % 70) as u8]);
                }
            }
        }
        out
    }

    #[test]
    fn bgr_frames_give_the_estimates_of_their_rgb_twins() {
        let (w, h) = (96, 80);
        for seed in [1, 2, 3] {
            let mut a = build(Preset::Head.config(60, seed)).unwrap();
            let mut b = build(Preset::Head.config(60, seed)).unwrap();
            let start = Ellipse::new(30.0, 40.0, 15.0, 15.0, 0.0);
            for k in 0..5 {
                let rgb = rgb_frame(w, h, 30.0 + 2.0 * k as f64);
                let bgr: Vec<u8> = rgb
                    .chunks_exact(3)
                    .flat_map(|p| [p[2], p[1], p[0]])
                    .collect();
                let grey: Vec<f32> = rgb
                    .chunks_exact(3)
                    .map(|p| luma_bt601(p[0], p[1], p[2]))
                    .collect();
                let fa = Frame::with_rgb(w, h, &grey, &rgb).unwrap();
                let fb = Frame::with_bgr(w, h, &grey, &bgr).unwrap();
                assert_eq!(fa.rgb(), Some(rgb.as_slice()));
                assert_eq!(fb.rgb(), None);
                assert_eq!(fb.colour(), Some((bgr.as_slice(), [2, 1, 0])));
                let (ea, eb) = if k == 0 {
                    (a.init(fa, start).unwrap(), b.init(fb, start).unwrap())
                } else {
                    (a.update(fa).unwrap(), b.update(fb).unwrap())
                };
                assert_eq!(ea.bbox, eb.bbox, "seed {seed}, frame {k}");
                assert_eq!(ea.status, eb.status);
            }
        }
    }

    #[test]
    fn a_grey_frame_after_a_colour_start_is_refused_not_lost() {
        let (w, h) = (96, 80);
        let start = Ellipse::new(30.0, 40.0, 15.0, 15.0, 0.0);
        let rgb = rgb_frame(w, h, 30.0);
        let grey: Vec<f32> = rgb
            .chunks_exact(3)
            .map(|p| luma_bt601(p[0], p[1], p[2]))
            .collect();
        // Colour, then grey: the colour model cannot read the grey frame; an error names it.
        let mut t = build(Preset::Head.config(60, 1)).unwrap();
        t.init(Frame::with_rgb(w, h, &grey, &rgb).unwrap(), start)
            .unwrap();
        let e = t.update(Frame::new(w, h, &grey).unwrap()).unwrap_err();
        assert!(matches!(e, Error::BadFrame { frame: 1, .. }), "{e:?}");
        assert!(e.to_string().contains("grey frame"), "{e}");
        // The colour frame after it is tracked as before.
        t.update(Frame::with_rgb(w, h, &grey, &rgb).unwrap())
            .unwrap();
        // Grey, then colour: the grey model reads the colour frame's grey levels, as it would
        // the grey frame, so the estimates are those of an all-grey track.
        let mut a = build(Preset::Head.config(60, 1)).unwrap();
        let mut b = build(Preset::Head.config(60, 1)).unwrap();
        a.init(Frame::new(w, h, &grey).unwrap(), start).unwrap();
        b.init(Frame::new(w, h, &grey).unwrap(), start).unwrap();
        let ea = a
            .update(Frame::with_rgb(w, h, &grey, &rgb).unwrap())
            .unwrap();
        let eb = b.update(Frame::new(w, h, &grey).unwrap()).unwrap();
        assert_eq!(ea.bbox, eb.bbox);
        assert_eq!(ea.status, eb.status);
    }

    #[test]
    fn a_frame_too_small_to_track_on_is_refused_at_init_not_at_update() {
        for p in Preset::ALL {
            for (w, h) in [(1, 1), (1, 6), (6, 1)] {
                let mut t = build(p.config(20, 1)).unwrap();
                let grey = vec![100.0f32; w * h];
                let start = Ellipse::new(w as f64 / 2.0, h as f64 / 2.0, 0.4, 0.4, 0.0);
                assert!(
                    t.init(Frame::new(w, h, &grey).unwrap(), start).is_err(),
                    "{} on {w}×{h}",
                    p.name()
                );
            }
            // From 2×2 every tracker tracks.
            let grey = [50.0f32, 200.0, 50.0, 200.0];
            let mut t = build(p.config(20, 1)).unwrap();
            let start = Ellipse::new(1.0, 1.0, 0.5, 0.5, 0.0);
            if t.init(Frame::new(2, 2, &grey).unwrap(), start).is_ok() {
                t.update(Frame::new(2, 2, &grey).unwrap()).unwrap();
            }
        }
    }

    #[test]
    fn colour_of_the_wrong_length_is_refused() {
        let grey = vec![0.0f32; 12];
        assert!(matches!(
            Frame::with_bgr(4, 3, &grey, &[0u8; 35]),
            Err(Error::RgbSize { .. })
        ));
        assert!(Frame::with_rgb(4, 3, &grey, &[0u8; 36]).is_ok());
    }
}
