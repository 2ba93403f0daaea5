//! Grey frames as the trackers see them: row-major f32 in grey levels, borrowed.

use crate::{Error, Result};

/// A borrowed grey frame (row-major, `width`×`height`, grey levels 0–255).
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    width: usize,
    height: usize,
    data: &'a [f32],
}

impl<'a> Frame<'a> {
    /// Wraps `data`.
    ///
    /// # Errors
    /// [`Error::BadFrame`] when the size is zero, the length does not match, or a pixel is not
    /// finite.
    pub fn new(width: usize, height: usize, data: &'a [f32]) -> Result<Self> {
        let bad = |reason: String| Err(Error::BadFrame { frame: 0, reason });
        if width < 2 || height < 2 {
            return bad(format!("{width}×{height} is too small"));
        }
        if data.len() != width * height {
            return bad(format!(
                "{} pixels given for a {width}×{height} frame",
                data.len()
            ));
        }
        if let Some(i) = data.iter().position(|v| !v.is_finite()) {
            return bad(format!("pixel {i} is not finite"));
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

    /// The pixels, row-major.
    pub fn data(&self) -> &'a [f32] {
        self.data
    }

    pub(crate) fn grey_view(&self) -> Result<contour_obs::GreyView<'a>> {
        Ok(contour_obs::GreyView::new(
            self.width,
            self.height,
            self.data,
        )?)
    }

    pub(crate) fn image_view(&self) -> Result<motion_est::ImageView<'a>> {
        Ok(motion_est::ImageView::new(
            self.width,
            self.height,
            self.data,
        )?)
    }
}
