//! Borrowed grey-level image views.

use crate::{Error, Result};

/// A borrowed row-major grey image in 0–255 grey-level units; pixel (i, j) is `data[j * width + i]`
/// and has its centre at (i, j).
#[derive(Debug, Clone, Copy)]
pub struct ImageView<'a> {
    width: usize,
    height: usize,
    data: &'a [f32],
}

impl<'a> ImageView<'a> {
    /// Wraps `data` as a `width`×`height` image.
    ///
    /// Finiteness is checked later, when a pyramid is built from the view (one pass, where the
    /// values are read anyway).
    ///
    /// # Errors
    /// [`Error::Empty`] for a zero dimension, [`Error::DimensionMismatch`] when
    /// `data.len() != width * height`.
    pub fn new(width: usize, height: usize, data: &'a [f32]) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(Error::Empty {
                what: "image",
                width,
                height,
            });
        }
        let expected = width.checked_mul(height).ok_or(Error::DimensionMismatch {
            what: "image",
            expected: usize::MAX,
            got: data.len(),
        })?;
        if data.len() != expected {
            return Err(Error::DimensionMismatch {
                what: "image",
                expected,
                got: data.len(),
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

    /// The row-major samples.
    pub fn data(&self) -> &'a [f32] {
        self.data
    }
}
