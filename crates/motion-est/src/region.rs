//! Support regions: the whole frame, a rectangle, an ellipse, or a weight mask.

use vision_core::Ellipse;

use crate::{Error, Result};

/// A borrowed per-pixel weight mask in [0, 1], the same size as the images; 0 excludes a pixel.
#[derive(Debug, Clone, Copy)]
pub struct MaskView<'a> {
    width: usize,
    height: usize,
    weights: &'a [f32],
}

impl<'a> MaskView<'a> {
    /// Wraps `weights` (row-major, `width`×`height`).
    ///
    /// # Errors
    /// [`Error::Empty`], [`Error::DimensionMismatch`], [`Error::NonFinite`] for a NaN, and
    /// [`Error::InvalidSetting`] for a weight outside [0, 1].
    pub fn new(width: usize, height: usize, weights: &'a [f32]) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(Error::Empty {
                what: "mask",
                width,
                height,
            });
        }
        if weights.len() != width * height {
            return Err(Error::DimensionMismatch {
                what: "mask",
                expected: width * height,
                got: weights.len(),
            });
        }
        for (index, &w) in weights.iter().enumerate() {
            if !w.is_finite() {
                return Err(Error::NonFinite {
                    what: "mask",
                    index,
                });
            }
            if !(0.0..=1.0).contains(&w) {
                return Err(Error::InvalidSetting {
                    name: "mask",
                    reason: format!("weight {w} at index {index} is outside [0, 1]"),
                });
            }
        }
        Ok(Self {
            width,
            height,
            weights,
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
}

/// The pixels over which the robust criterion Σ ρ(DFD) is summed (Odobez Eq. 14's R(c_k)).
///
/// At a coarse pyramid level, pixel (i, j) stands for level-0 position (2^l·i, 2^l·j) and takes the
/// region's weight there.
#[derive(Debug, Clone, Copy)]
pub enum Region<'a> {
    /// Every pixel of the image.
    Full,
    /// The pixels whose centres lie in [x, x + width) × [y, y + height).
    Rect {
        /// Left edge.
        x: f64,
        /// Top edge.
        y: f64,
        /// Width.
        width: f64,
        /// Height.
        height: f64,
    },
    /// The pixels whose centres lie inside (or on) the ellipse.
    Ellipse(Ellipse),
    /// Per-pixel weights (same size as the images).
    Mask(MaskView<'a>),
}

/// An inclusive integer pixel box (i0..=i1, j0..=j1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PixelBox {
    pub i0: usize,
    pub j0: usize,
    pub i1: usize,
    pub j1: usize,
}

fn clip_range(lo: f64, hi: f64, n: usize) -> Option<(usize, usize)> {
    // Pixels k with lo <= k <= hi, clipped to 0..n.
    let a = lo.ceil().max(0.0);
    let b = hi.floor().min(n as f64 - 1.0);
    // Also rejects NaN bounds.
    if !matches!(
        a.partial_cmp(&b),
        Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
    ) {
        return None;
    }
    Some((a as usize, b as usize))
}

impl Region<'_> {
    /// Checks the region's geometry against an image of `width`×`height`.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for NaN geometry, [`Error::InvalidSetting`] for non-positive sizes,
    /// [`Error::DimensionMismatch`] for a mask of another size.
    pub fn validate(&self, width: usize, height: usize) -> Result<()> {
        match *self {
            Region::Full => Ok(()),
            Region::Rect {
                x,
                y,
                width: w,
                height: h,
            } => {
                for (index, v) in [x, y, w, h].into_iter().enumerate() {
                    if !v.is_finite() {
                        return Err(Error::NonFinite {
                            what: "rectangle",
                            index,
                        });
                    }
                }
                if w <= 0.0 || h <= 0.0 {
                    return Err(Error::InvalidSetting {
                        name: "rectangle",
                        reason: format!("size {w}×{h} must be positive"),
                    });
                }
                Ok(())
            }
            Region::Ellipse(e) => {
                for (index, v) in [e.cx, e.cy, e.a, e.b, e.angle].into_iter().enumerate() {
                    if !v.is_finite() {
                        return Err(Error::NonFinite {
                            what: "ellipse",
                            index,
                        });
                    }
                }
                if e.a <= 0.0 || e.b <= 0.0 {
                    return Err(Error::InvalidSetting {
                        name: "ellipse",
                        reason: format!("semi-axes {}, {} must be positive", e.a, e.b),
                    });
                }
                Ok(())
            }
            Region::Mask(m) => {
                if m.width != width || m.height != height {
                    return Err(Error::DimensionMismatch {
                        what: "mask",
                        expected: width * height,
                        got: m.width * m.height,
                    });
                }
                Ok(())
            }
        }
    }

    /// The region's pixel bounding box clipped to the image, or `None` when it holds no pixel.
    pub(crate) fn pixel_box(&self, width: usize, height: usize) -> Option<PixelBox> {
        let (xr, yr) = match *self {
            Region::Full => ((0, width - 1), (0, height - 1)),
            Region::Rect {
                x,
                y,
                width: w,
                height: h,
            } => {
                // Centres in [x, x + w): the last admitted pixel is ceil(x + w) − 1.
                let xr = clip_range(x, (x + w).ceil() - 1.0, width)?;
                let yr = clip_range(y, (y + h).ceil() - 1.0, height)?;
                (xr, yr)
            }
            Region::Ellipse(e) => {
                let (s, c) = e.angle.sin_cos();
                let hx = (e.a * e.a * c * c + e.b * e.b * s * s).sqrt();
                let hy = (e.a * e.a * s * s + e.b * e.b * c * c).sqrt();
                (
                    clip_range(e.cx - hx, e.cx + hx, width)?,
                    clip_range(e.cy - hy, e.cy + hy, height)?,
                )
            }
            Region::Mask(m) => {
                let (mut i0, mut j0, mut i1, mut j1) = (usize::MAX, usize::MAX, 0, 0);
                for j in 0..m.height {
                    let row = &m.weights[j * m.width..(j + 1) * m.width];
                    for (i, &w) in row.iter().enumerate() {
                        if w > 0.0 {
                            i0 = i0.min(i);
                            i1 = i1.max(i);
                            j0 = j0.min(j);
                            j1 = j1.max(j);
                        }
                    }
                }
                if i0 == usize::MAX {
                    return None;
                }
                ((i0, i1), (j0, j1))
            }
        };
        Some(PixelBox {
            i0: xr.0,
            i1: xr.1,
            j0: yr.0,
            j1: yr.1,
        })
    }

    /// Weight of level-0 pixel position (x, y) (integers here, passed as f64).
    #[inline]
    pub(crate) fn weight(&self, x: f64, y: f64) -> f32 {
        match *self {
            Region::Full => 1.0,
            Region::Rect {
                x: rx,
                y: ry,
                width: w,
                height: h,
            } => {
                if x >= rx && x < rx + w && y >= ry && y < ry + h {
                    1.0
                } else {
                    0.0
                }
            }
            Region::Ellipse(e) => {
                let (s, c) = e.angle.sin_cos();
                let (dx, dy) = (x - e.cx, y - e.cy);
                let u = (c * dx + s * dy) / e.a;
                let v = (-s * dx + c * dy) / e.b;
                if u * u + v * v <= 1.0 { 1.0 } else { 0.0 }
            }
            Region::Mask(m) => {
                let (i, j) = (x as usize, y as usize);
                if i < m.width && j < m.height {
                    m.weights[j * m.width + i]
                } else {
                    0.0
                }
            }
        }
    }

    /// The region's natural centre, the default origin of the displacement coordinates: the
    /// image or rectangle centre, the ellipse centre, or the mask's weighted centroid.
    pub fn centre(&self, width: usize, height: usize) -> [f64; 2] {
        match *self {
            Region::Full => [(width as f64 - 1.0) / 2.0, (height as f64 - 1.0) / 2.0],
            Region::Rect {
                x,
                y,
                width: w,
                height: h,
            } => [x + (w - 1.0) / 2.0, y + (h - 1.0) / 2.0],
            Region::Ellipse(e) => [e.cx, e.cy],
            Region::Mask(m) => {
                let (mut sw, mut sx, mut sy) = (0.0f64, 0.0f64, 0.0f64);
                for j in 0..m.height {
                    for i in 0..m.width {
                        let w = f64::from(m.weights[j * m.width + i]);
                        sw += w;
                        sx += w * i as f64;
                        sy += w * j as f64;
                    }
                }
                if sw > 0.0 {
                    [sx / sw, sy / sw]
                } else {
                    [(width as f64 - 1.0) / 2.0, (height as f64 - 1.0) / 2.0]
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rect_box_and_weight_agree() {
        let r = Region::Rect {
            x: 10.0,
            y: 20.0,
            width: 64.0,
            height: 32.0,
        };
        let b = r.pixel_box(320, 240).unwrap();
        assert_eq!((b.i0, b.i1, b.j0, b.j1), (10, 73, 20, 51));
        assert_eq!(r.weight(73.0, 51.0), 1.0);
        assert_eq!(r.weight(74.0, 51.0), 0.0);
        assert_eq!(r.centre(320, 240), [41.5, 35.5]);
    }

    #[test]
    fn rotated_ellipse_box_contains_all_its_pixels() {
        let e = Region::Ellipse(Ellipse {
            cx: 50.0,
            cy: 40.0,
            a: 20.0,
            b: 8.0,
            angle: 0.6,
        });
        let b = e.pixel_box(200, 200).unwrap();
        let mut count = 0;
        for j in 0..200 {
            for i in 0..200 {
                if e.weight(i as f64, j as f64) > 0.0 {
                    count += 1;
                    assert!(i >= b.i0 && i <= b.i1 && j >= b.j0 && j <= b.j1);
                }
            }
        }
        // Area π·a·b ≈ 502.7 pixels; pixel counting is within a few per cent.
        assert!((count as f64 - 502.7).abs() < 25.0, "{count}");
    }

    #[test]
    fn mask_validation_and_box() {
        let mut w = vec![0.0f32; 12];
        w[5] = 0.5;
        let m = MaskView::new(4, 3, &w).unwrap();
        let b = Region::Mask(m).pixel_box(4, 3).unwrap();
        assert_eq!((b.i0, b.i1, b.j0, b.j1), (1, 1, 1, 1));
        w[0] = 2.0;
        assert!(MaskView::new(4, 3, &w).is_err());
        w[0] = f32::NAN;
        assert!(matches!(
            MaskView::new(4, 3, &w),
            Err(Error::NonFinite { index: 0, .. })
        ));
        assert!(
            Region::Rect {
                x: 500.0,
                y: 0.0,
                width: 5.0,
                height: 5.0
            }
            .pixel_box(10, 10)
            .is_none()
        );
    }
}
