//! Frames as the trackers see them: row-major f32 grey levels, borrowed, and optionally the 8-bit
//! RGB pixels of the same frame (the region tracker's colour model reads them; every other tracker
//! reads grey). A thin wrapper over `contour_obs::GreyView`, which validates the size and the
//! pixels once.

use contour_obs::GreyView;

use crate::{Error, Result};

/// A borrowed grey frame (row-major, `width`×`height`, grey levels 0–255).
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    view: GreyView<'a>,
    rgb: Option<&'a [u8]>,
}

impl<'a> Frame<'a> {
    /// Wraps `data`.
    ///
    /// # Errors
    /// [`Error::BadFrame`] when the size is zero, the length does not match, or a pixel is not
    /// finite.
    pub fn new(width: usize, height: usize, data: &'a [f32]) -> Result<Self> {
        let view = GreyView::new(width, height, data).map_err(|e| Error::BadFrame {
            frame: 0,
            reason: e.to_string(),
        })?;
        Ok(Self { view, rgb: None })
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

    /// The RGB pixels, when the frame has colour.
    pub fn rgb(&self) -> Option<&'a [u8]> {
        self.rgb
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.view.width()
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.view.height()
    }

    /// The pixels, row-major.
    pub fn data(&self) -> &'a [f32] {
        self.view.data()
    }

    pub(crate) fn grey_view(&self) -> GreyView<'a> {
        self.view
    }

    pub(crate) fn image_view(&self) -> Result<motion_est::ImageView<'a>> {
        Ok(motion_est::ImageView::new(
            self.width(),
            self.height(),
            self.data(),
        )?)
    }
}
