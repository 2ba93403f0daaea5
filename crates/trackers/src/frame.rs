//! Frames as the trackers see them: the workspace's grey image ([`GreyImage`], validated once at
//! construction) and optionally the 8-bit RGB pixels of the same frame (the region tracker's
//! colour model reads them; every other tracker reads grey).

use vision_core::GreyImage;

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

impl<'a> Frame<'a> {
    /// Wraps `data` as a grey frame ([`GreyImage::new`]).
    ///
    /// # Errors
    /// [`Error::BadFrame`] when the size is zero, the length does not match, or a pixel is not
    /// finite.
    pub fn new(width: usize, height: usize, data: &'a [f32]) -> Result<Self> {
        let grey = GreyImage::new(width, height, data).map_err(|e| Error::BadFrame {
            frame: 0,
            reason: e.to_string(),
        })?;
        Ok(grey.into())
    }

    /// Wraps `grey` and the same frame's interleaved 8-bit RGB pixels (`3·width·height` bytes,
    /// row-major, R G B per pixel).
    ///
    /// # Errors
    /// As [`Frame::new`], and [`Error::BadFrame`] when `rgb` has the wrong length.
    pub fn with_rgb(width: usize, height: usize, grey: &'a [f32], rgb: &'a [u8]) -> Result<Self> {
        let mut frame = Self::new(width, height, grey)?;
        if Some(rgb.len()) != width.checked_mul(height).and_then(|n| n.checked_mul(3)) {
            return Err(Error::BadFrame {
                frame: 0,
                reason: format!(
                    "{} RGB bytes for a {width}x{height} frame (expected 3 per pixel)",
                    rgb.len()
                ),
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
