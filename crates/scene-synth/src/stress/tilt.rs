//! `tilt`: in-plane rotation of the picture about the target, swinging to ±45° and back over
//! tens of frames: θ(t) = s·A·sin(2πt/P), with the sign s and the period P seeded.
//!
//! The rotation is about the target's labelled centre (held over unlabelled frames), so the
//! head's own motion is kept. Where the rotated picture reaches beyond the frame, the frame is
//! reflected at its edges (its own pixels, no black corners). Positive angles turn the picture
//! clockwise on screen (y points down): p' = R(θ)(p − c) + c with R = [[cos, −sin], [sin, cos]].
//!
//! The truth is the axis-aligned box of the rotated ellipse inscribed in the labelled box:
//! centre c, half-extents √(a²cos²θ + b²sin²θ) and √(a²sin²θ + b²cos²θ), a = w/2, b = h/2. A
//! head is an ellipse, not a box: the box's corners are background, and the rotated box's own
//! bounding box would grow by up to 40 % at 45° with background alone.

use rand::Rng;
use rand_pcg::Pcg64Mcg;
use serde::{Deserialize, Serialize};
use vision_core::BoundingBox;

use super::{bad, held_centres};
use crate::error::Result;

/// The settings of `tilt`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Tilt {
    /// A, the largest angle in degrees (0 < A ≤ 90). Default 45.
    pub max_angle_deg: f64,
    /// The shortest period P, in frames (≥ 4): the picture turns from 0 to ±A in P/4 frames.
    /// Default 60.
    pub period_min: f64,
    /// The longest period, in frames. Default 120.
    pub period_max: f64,
}

impl Default for Tilt {
    fn default() -> Self {
        Self {
            max_angle_deg: 45.0,
            period_min: 60.0,
            period_max: 120.0,
        }
    }
}

impl Tilt {
    /// Checks every field against its documented range.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] naming the first field out of range.
    pub fn validate(&self) -> Result<()> {
        if !(self.max_angle_deg > 0.0 && self.max_angle_deg <= 90.0) {
            return bad("tilt.max_angle_deg", "must lie in (0, 90]");
        }
        if !(self.period_min >= 4.0
            && self.period_max.is_finite()
            && self.period_max >= self.period_min)
        {
            return bad(
                "tilt.period_min",
                "need 4 ≤ period_min ≤ period_max, finite",
            );
        }
        Ok(())
    }

    pub(crate) fn plan(
        &self,
        size: (u32, u32),
        truth: &[Option<BoundingBox>],
        rng: &mut Pcg64Mcg,
    ) -> TiltPlan {
        let period = if self.period_max > self.period_min {
            rng.random_range(self.period_min..=self.period_max)
        } else {
            self.period_min
        };
        let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let amp = sign * self.max_angle_deg.to_radians();
        let angles = (0..truth.len())
            .map(|t| amp * (std::f64::consts::TAU * t as f64 / period).sin())
            .collect();
        TiltPlan {
            size,
            period,
            sign,
            angles,
            centres: held_centres(truth, size),
        }
    }
}

/// The planned angles and centres of a clip.
#[derive(Debug, Clone)]
pub(crate) struct TiltPlan {
    size: (u32, u32),
    period: f64,
    sign: f64,
    angles: Vec<f64>,
    centres: Vec<(f64, f64)>,
}

/// The axis-aligned box of the ellipse inscribed in `b`, turned by `theta` about `centre`.
pub fn rotated_ellipse_box(b: &BoundingBox, theta: f64, centre: (f64, f64)) -> BoundingBox {
    let (c, s) = (theta.cos(), theta.sin());
    let (bx, by) = b.centre();
    let (dx, dy) = (bx - centre.0, by - centre.1);
    let (nx, ny) = (c * dx - s * dy + centre.0, s * dx + c * dy + centre.1);
    let (a, e) = (0.5 * b.w, 0.5 * b.h);
    let hx = (a * a * c * c + e * e * s * s).sqrt();
    let hy = (a * a * s * s + e * e * c * c).sqrt();
    BoundingBox::new(nx - hx, ny - hy, 2.0 * hx, 2.0 * hy)
}

impl TiltPlan {
    pub(crate) fn angle(&self, k: usize) -> f64 {
        self.angles[k]
    }

    pub(crate) fn map_box(&self, k: usize, b: &BoundingBox) -> BoundingBox {
        rotated_ellipse_box(b, self.angles[k], self.centres[k])
    }

    pub(crate) fn apply(&self, k: usize, frame: &image::RgbImage) -> image::RgbImage {
        let (c, s) = (self.angles[k].cos(), self.angles[k].sin());
        let (cx, cy) = self.centres[k];
        // The inverse rotation: p = Rᵀ(p' − c) + c.
        let map = [c, s, cx - c * cx - s * cy, -s, c, cy + s * cx - c * cy];
        super::warp::warp(frame, self.size, &map, None)
    }

    pub(crate) fn describe(&self) -> serde_json::Value {
        serde_json::json!({ "period_frames": self.period, "sign": self.sign })
    }
}
