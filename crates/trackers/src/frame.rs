//! Frames as the trackers see them: the workspace's grey image ([`GreyImage`], validated once at
//! construction) and optionally the 8-bit RGB pixels of the same frame (the region tracker's
//! colour model reads them; every other tracker reads grey).

use vision_core::GreyImage;

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
        if Some(colour.len()) != width.checked_mul(height).and_then(|n| n.checked_mul(3)) {
            return Err(Error::BadFrame {
                frame: 0,
                reason: format!(
                    "{} colour bytes for a {width}x{height} frame (expected 3 per pixel)",
                    colour.len()
                ),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Preset, build};
    use vision_core::{Ellipse, luma_bt601};

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
    fn colour_of_the_wrong_length_is_refused() {
        let grey = vec![0.0f32; 12];
        assert!(matches!(
            Frame::with_bgr(4, 3, &grey, &[0u8; 35]),
            Err(Error::BadFrame { .. })
        ));
        assert!(Frame::with_rgb(4, 3, &grey, &[0u8; 36]).is_ok());
    }
}
