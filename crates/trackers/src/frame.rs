//! Grey frames as the trackers see them: row-major f32 in grey levels, borrowed. A thin wrapper
//! over `contour_obs::GreyView`, which validates the size and the pixels once.

use contour_obs::GreyView;

use crate::{Error, Result};

/// A borrowed grey frame (row-major, `width`×`height`, grey levels 0–255).
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    view: GreyView<'a>,
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
        Ok(Self { view })
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
