//! A camera zoom laid over real footage, with its ground truth (`cargo xtask camera-zoom`).
//!
//! The synthetic scenes change a target's size with exact truth, but on their own textures; the
//! development footage has real textures, but its heads hardly change size. This module crops
//! each real frame about a point that follows the target, as a camera operator would, and
//! resizes the crop back to the frame's size, so the target's size follows a known zoom while
//! every pixel is the footage's own. The ground truth is mapped by the same crop.
//!
//! The zoom goes smoothly from 1 up to [`CameraZoom::max_zoom`] and back, once every
//! [`CameraZoom::period`] frames: z(t) = 1 + (Z − 1)(1 − cos 2πt/P)/2, so the target grows
//! Z-fold over half a period, then shrinks back. The operator aims at the target's labelled
//! centre smoothed over frames (`aim += follow · (centre − aim)`), so the target still moves in
//! the picture, and the crop is kept inside the frame.
//!
//! ```
//! use scene_synth::camera_zoom::{CameraZoom, Operator};
//! use vision_core::BoundingBox;
//! let zoom = CameraZoom::new(2.0, 120.0)?;
//! assert_eq!(zoom.factor(0), 1.0);
//! assert!((zoom.factor(60) - 2.0).abs() < 1e-12);
//! let target = BoundingBox::new(150.0, 110.0, 20.0, 20.0);
//! let mut operator = Operator::new(zoom, (320, 240))?;
//! let crop = operator.next_crop(Some(&target));
//! assert_eq!(crop.map_box(&target), target); // z(0) = 1: the frame as it was
//! # Ok::<(), scene_synth::Error>(())
//! ```

use image::RgbImage;
use image::imageops::{self, FilterType};
use serde::Serialize;
use vision_core::BoundingBox;

use crate::error::{Error, Result};

/// How the zoom varies over a sequence, and how closely the operator follows the target.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CameraZoom {
    /// Z, the largest zoom (≥ 1): the target is Z times its size at the zoom's peak.
    pub max_zoom: f64,
    /// P, the frames from one zoom-out to the next (≥ 2): the size changes Z-fold in P/2 frames.
    pub period: f64,
    /// The share of the way from the operator's aim to the target's centre taken each frame, in
    /// (0, 1]: 1 centres every crop on the target (no motion left in the picture), small values
    /// leave the target's motion and follow it only slowly.
    pub follow: f64,
}

impl CameraZoom {
    /// The operator's default share, 0.1: the aim closes 10 % of its gap to the target a frame
    /// (a time constant of about ten frames), slow beside the head motions of the footage, so
    /// the target still moves in the picture, fast enough to keep it inside the crop.
    pub const DEFAULT_FOLLOW: f64 = 0.1;

    /// A zoom to `max_zoom` and back every `period` frames, followed at [`Self::DEFAULT_FOLLOW`].
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when `max_zoom` is below 1 or `period` below 2 (or either is
    /// not finite).
    pub fn new(max_zoom: f64, period: f64) -> Result<Self> {
        let zoom = Self {
            max_zoom,
            period,
            follow: Self::DEFAULT_FOLLOW,
        };
        zoom.validate()?;
        Ok(zoom)
    }

    /// Checks every field against its documented range.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first field out of range.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, reason: &str| {
            Err(Error::InvalidParameter {
                name,
                reason: reason.to_owned(),
            })
        };
        if !(self.max_zoom.is_finite() && self.max_zoom >= 1.0) {
            return bad("max_zoom", "must be a finite number ≥ 1");
        }
        if !(self.period.is_finite() && self.period >= 2.0) {
            return bad("period", "must be a finite number of frames ≥ 2");
        }
        if !(self.follow > 0.0 && self.follow <= 1.0) {
            return bad("follow", "must lie in (0, 1]");
        }
        Ok(())
    }

    /// z(t) = 1 + (Z − 1)(1 − cos 2πt/P)/2 at frame `t` (0-based): 1 at t = 0, Z at t = P/2.
    pub fn factor(&self, t: usize) -> f64 {
        let phase = std::f64::consts::TAU * t as f64 / self.period;
        1.0 + (self.max_zoom - 1.0) * 0.5 * (1.0 - phase.cos())
    }

    /// The same zoom with its largest factor lowered, when needed, so that a box of `largest`
    /// (width, height) zoomed fills at most `fill` of the frame's width and height (never
    /// below 1): a target larger than the crop would leave the picture.
    #[must_use]
    pub fn fitted(self, largest: (f64, f64), frame: (u32, u32), fill: f64) -> Self {
        let room =
            (fill * f64::from(frame.0) / largest.0).min(fill * f64::from(frame.1) / largest.1);
        let max_zoom = if room.is_finite() {
            self.max_zoom.min(room).max(1.0)
        } else {
            self.max_zoom
        };
        Self { max_zoom, ..self }
    }
}

/// One frame's crop: the rectangle of the source frame that fills the output frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Crop {
    /// Left column of the crop in the source frame.
    pub x: u32,
    /// Top row of the crop in the source frame.
    pub y: u32,
    /// Width of the crop (source pixels).
    pub w: u32,
    /// Height of the crop (source pixels).
    pub h: u32,
    /// Width of the output frame (the source frame's).
    pub out_w: u32,
    /// Height of the output frame (the source frame's).
    pub out_h: u32,
}

impl Crop {
    /// The zoom along x and y: output pixels per source pixel (the crop's sides are whole
    /// pixels, so the two differ by at most one pixel's worth).
    pub fn zoom(&self) -> (f64, f64) {
        (
            f64::from(self.out_w) / f64::from(self.w),
            f64::from(self.out_h) / f64::from(self.h),
        )
    }

    /// A point of the source frame in the output frame, in the workspace's convention (pixel
    /// (i, j) centred at (i, j)): the resize maps pixel edges onto pixel edges, so
    /// x' = (x − x₀ + ½) · zₓ − ½.
    fn map_point(&self, x: f64, y: f64) -> (f64, f64) {
        let (zx, zy) = self.zoom();
        (
            (x - f64::from(self.x) + 0.5) * zx - 0.5,
            (y - f64::from(self.y) + 0.5) * zy - 0.5,
        )
    }

    /// A box of the source frame (the target's ground truth) in the output frame.
    pub fn map_box(&self, b: &BoundingBox) -> BoundingBox {
        let (x0, y0) = self.map_point(b.x, b.y);
        let (zx, zy) = self.zoom();
        BoundingBox::new(x0, y0, b.w * zx, b.h * zy)
    }

    /// The output frame: the crop of `frame` resized (bilinear) to the output size.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] when `frame` is not the size the crop was laid out on (the
    /// crop would reach beyond it).
    pub fn apply(&self, frame: &RgbImage) -> Result<RgbImage> {
        if frame.dimensions() != (self.out_w, self.out_h) {
            return Err(Error::DimensionMismatch {
                expected: (self.out_w as usize) * (self.out_h as usize),
                got: (frame.width() as usize) * (frame.height() as usize),
            });
        }
        let sub = imageops::crop_imm(frame, self.x, self.y, self.w, self.h);
        if (self.w, self.h) == (self.out_w, self.out_h) {
            return Ok(sub.to_image());
        }
        Ok(imageops::resize(
            &*sub,
            self.out_w,
            self.out_h,
            FilterType::Triangle,
        ))
    }
}

/// The camera operator: lays out each frame's crop from the zoom and the target's labelled
/// box, frame after frame.
#[derive(Debug, Clone)]
pub struct Operator {
    zoom: CameraZoom,
    frame: (u32, u32),
    aim: Option<(f64, f64)>,
    t: usize,
}

impl Operator {
    /// An operator for frames of `frame` = (width, height) pixels.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when the zoom is out of range or the frame is empty.
    pub fn new(zoom: CameraZoom, frame: (u32, u32)) -> Result<Self> {
        zoom.validate()?;
        if frame.0 == 0 || frame.1 == 0 {
            return Err(Error::InvalidParameter {
                name: "frame",
                reason: format!("an empty frame ({} × {})", frame.0, frame.1),
            });
        }
        Ok(Self {
            zoom,
            frame,
            aim: None,
            t: 0,
        })
    }

    /// The crop of the next frame. `target` is its labelled box (`None` for an unlabelled
    /// frame, where the operator holds the aim). Before the first labelled box the operator
    /// aims at the frame's centre.
    pub fn next_crop(&mut self, target: Option<&BoundingBox>) -> Crop {
        let (fw, fh) = (f64::from(self.frame.0), f64::from(self.frame.1));
        if let Some(b) = target.filter(|b| b.is_finite() && b.w > 0.0 && b.h > 0.0) {
            let centre = b.centre();
            self.aim = Some(match self.aim {
                None => centre,
                Some((ax, ay)) => (
                    ax + self.zoom.follow * (centre.0 - ax),
                    ay + self.zoom.follow * (centre.1 - ay),
                ),
            });
        }
        let (ax, ay) = self.aim.unwrap_or((0.5 * (fw - 1.0), 0.5 * (fh - 1.0)));
        let z = self.zoom.factor(self.t);
        self.t += 1;
        let side = |full: u32| ((f64::from(full) / z).round() as u32).clamp(1, full);
        let (w, h) = (side(self.frame.0), side(self.frame.1));
        // The crop's corner puts the aim at its centre (pixel centres at integers), kept inside.
        let corner = |aim: f64, side: u32, full: u32| {
            (aim + 0.5 - 0.5 * f64::from(side))
                .round()
                .clamp(0.0, f64::from(full - side)) as u32
        };
        Crop {
            x: corner(ax, w, self.frame.0),
            y: corner(ay, h, self.frame.1),
            w,
            h,
            out_w: self.frame.0,
            out_h: self.frame.1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    #[test]
    fn the_zoom_rises_from_one_to_its_peak_at_half_a_period_and_back() {
        let z = CameraZoom::new(2.5, 40.0).unwrap();
        assert_eq!(z.factor(0), 1.0);
        assert_abs_diff_eq!(z.factor(20), 2.5, epsilon = 1e-12);
        assert_abs_diff_eq!(z.factor(40), 1.0, epsilon = 1e-12);
        assert!(z.factor(10) > 1.0 && z.factor(10) < 2.5);
        assert_abs_diff_eq!(z.factor(10), z.factor(30), epsilon = 1e-12);
    }

    #[test]
    fn out_of_range_settings_are_refused_by_name() {
        for (zoom, period, name) in [
            (0.5, 40.0, "max_zoom"),
            (f64::NAN, 40.0, "max_zoom"),
            (2.0, 1.0, "period"),
            (2.0, f64::INFINITY, "period"),
        ] {
            match CameraZoom::new(zoom, period) {
                Err(Error::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
                other => panic!("{zoom}, {period}: {other:?}"),
            }
        }
        let mut z = CameraZoom::new(2.0, 40.0).unwrap();
        z.follow = 0.0;
        assert!(matches!(
            Operator::new(z, (10, 10)),
            Err(Error::InvalidParameter { name: "follow", .. })
        ));
        z.follow = 0.1;
        assert!(Operator::new(z, (0, 10)).is_err());
    }

    #[test]
    fn the_largest_zoom_is_lowered_so_the_largest_box_stays_in_the_picture() {
        let z = CameraZoom::new(2.0, 120.0).unwrap();
        // FaceOcc1-like: a 154 × 180 px box in a 352 × 288 frame fits 0.9 · 288 / 180 = 1.44.
        assert_abs_diff_eq!(
            z.fitted((154.0, 180.0), (352, 288), 0.9).max_zoom,
            1.44,
            epsilon = 1e-12
        );
        assert_eq!(z.fitted((20.0, 20.0), (320, 240), 0.9).max_zoom, 2.0);
        // A box already larger than the frame: no zoom at all, never a zoom-out.
        assert_eq!(z.fitted((400.0, 300.0), (320, 240), 0.9).max_zoom, 1.0);
    }

    /// A frame with one bright rectangle on black, in the workspace's pixel convention: the
    /// pixels whose centres lie inside `b` are lit.
    fn frame_with(b: &BoundingBox, size: (u32, u32)) -> RgbImage {
        RgbImage::from_fn(size.0, size.1, |i, j| {
            let (x, y) = (f64::from(i), f64::from(j));
            let inside = x >= b.x && x < b.x + b.w && y >= b.y && y < b.y + b.h;
            image::Rgb(if inside { [255; 3] } else { [0; 3] })
        })
    }

    /// The lit region of a frame, as a box: the bounds of the columns and rows whose pixels
    /// are more than half lit.
    fn lit_box(frame: &RgbImage) -> BoundingBox {
        let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
        for (i, j, p) in frame.enumerate_pixels() {
            if p.0[0] > 127 {
                (x0, y0, x1, y1) = (x0.min(i), y0.min(j), x1.max(i), y1.max(j));
            }
        }
        BoundingBox::from_corners(
            f64::from(x0),
            f64::from(y0),
            f64::from(x1 + 1),
            f64::from(y1 + 1),
        )
    }

    #[test]
    fn the_mapped_truth_lands_where_the_resized_pixels_show_the_target() {
        let size = (320, 240);
        let target = BoundingBox::new(140.0, 90.0, 30.0, 40.0);
        let frame = frame_with(&target, size);
        let zoom = CameraZoom::new(2.0, 20.0).unwrap();
        let mut operator = Operator::new(zoom, size).unwrap();
        for t in 0..12 {
            let crop = operator.next_crop(Some(&target));
            let (zx, zy) = crop.zoom();
            assert_abs_diff_eq!(zx, zoom.factor(t), epsilon = 0.02);
            assert_abs_diff_eq!(zy, zoom.factor(t), epsilon = 0.02);
            let mapped = crop.map_box(&target);
            let seen = lit_box(&crop.apply(&frame).unwrap());
            // Within one output pixel on every side, whatever the zoom.
            for (a, b) in mapped.to_array().iter().zip(seen.to_array()) {
                assert!(
                    (a - b).abs() <= 1.0,
                    "frame {t}: mapped {mapped:?}, seen {seen:?}"
                );
            }
        }
    }

    #[test]
    fn the_crop_follows_the_target_slowly_and_stays_inside_the_frame() {
        let size = (320, 240);
        let zoom = CameraZoom::new(3.0, 8.0).unwrap();
        let mut operator = Operator::new(zoom, size).unwrap();
        let start = BoundingBox::new(150.0, 110.0, 20.0, 20.0); // centred at (160, 120)
        operator.next_crop(Some(&start));
        // The target jumps to (60, 60): the aim closes a tenth of the gap a frame.
        let moved = BoundingBox::new(50.0, 50.0, 20.0, 20.0);
        let c = operator.next_crop(Some(&moved));
        let centre = |c: &Crop| {
            (
                f64::from(c.x) + 0.5 * f64::from(c.w) - 0.5,
                f64::from(c.y) + 0.5 * f64::from(c.h) - 0.5,
            )
        };
        let (cx, cy) = centre(&c);
        assert!(
            (cx - 150.0).abs() <= 0.5 && (cy - 114.0).abs() <= 0.5,
            "{c:?}"
        );
        for _ in 0..60 {
            let c = operator.next_crop(Some(&BoundingBox::new(0.0, 0.0, 20.0, 20.0)));
            assert!(c.x + c.w <= size.0 && c.y + c.h <= size.1, "{c:?}");
        }
        // By now the aim is near (10, 10): the crop is held against the frame's corner.
        let c = operator.next_crop(None);
        assert_eq!((c.x, c.y), (0, 0), "{c:?}");
    }

    #[test]
    fn a_frame_of_another_size_is_refused() {
        let mut operator = Operator::new(CameraZoom::new(2.0, 10.0).unwrap(), (64, 48)).unwrap();
        let crop = operator.next_crop(None);
        assert!(matches!(
            crop.apply(&RgbImage::new(32, 48)),
            Err(Error::DimensionMismatch { .. })
        ));
    }
}
