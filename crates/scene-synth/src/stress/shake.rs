//! `shake`: abrupt camera motion. The picture is a crop of a slightly zoomed frame, as
//! `camera-zoom` crops, whose centre follows the target slowly and jumps, every few frames, by a
//! seeded offset of one to two target radii, often straight back (a reversal); the frame of each
//! jump is blurred along it.

use rand::Rng;
use rand_pcg::Pcg64Mcg;
use serde::{Deserialize, Serialize};
use vision_core::BoundingBox;

use super::{bad, held_centres, median_radius};
use crate::error::Result;

/// The settings of `shake`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Shake {
    /// The zoom of the crop (> 1): the crop is 1/zoom of the frame's width and height, which
    /// leaves the room the jumps need. Default 1.25.
    pub zoom: f64,
    /// The shortest jump, in target radii (a radius is the median over labelled boxes of
    /// (w + h)/4). Default 1.
    pub jump_min: f64,
    /// The longest jump, in target radii. Default 2.
    pub jump_max: f64,
    /// The fewest frames between two jumps (≥ 1). Default 3.
    pub gap_min: usize,
    /// The most frames between two jumps. Default 8.
    pub gap_max: usize,
    /// The probability that a jump goes back the way the previous one came. Default 0.5.
    pub reverse: f64,
    /// The largest offset from the slowly following aim, in target radii: a jump that would go
    /// further goes the other way. Default 2.
    pub max_offset: f64,
    /// The share of a jump smeared over its frame (a linear motion blur along it, centred on
    /// the frame's crop). Default 0.5.
    pub blur: f64,
    /// The share of the way from the aim to the target's labelled centre taken each frame, in
    /// (0, 1], as `camera-zoom`'s operator. Default 0.1.
    pub follow: f64,
}

impl Default for Shake {
    fn default() -> Self {
        Self {
            zoom: 1.25,
            jump_min: 1.0,
            jump_max: 2.0,
            gap_min: 3,
            gap_max: 8,
            reverse: 0.5,
            max_offset: 2.0,
            blur: 0.5,
            follow: 0.1,
        }
    }
}

impl Shake {
    /// Checks every field against its documented range.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] naming the first field out of range.
    pub fn validate(&self) -> Result<()> {
        if !(self.zoom.is_finite() && self.zoom > 1.0) {
            return bad("shake.zoom", "must be a finite number > 1");
        }
        if !(self.jump_min.is_finite()
            && self.jump_min > 0.0
            && self.jump_max >= self.jump_min
            && self.jump_max.is_finite())
        {
            return bad(
                "shake.jump_min",
                "need 0 < jump_min ≤ jump_max, both finite",
            );
        }
        if self.gap_min == 0 || self.gap_max < self.gap_min {
            return bad("shake.gap_min", "need 1 ≤ gap_min ≤ gap_max");
        }
        if !(0.0..=1.0).contains(&self.reverse) {
            return bad("shake.reverse", "must lie in [0, 1]");
        }
        if !(self.max_offset.is_finite() && self.max_offset >= self.jump_max) {
            return bad("shake.max_offset", "must be finite and ≥ jump_max");
        }
        if !(0.0..=4.0).contains(&self.blur) {
            return bad("shake.blur", "must lie in [0, 4]");
        }
        if !(self.follow > 0.0 && self.follow <= 1.0) {
            return bad("shake.follow", "must lie in (0, 1]");
        }
        Ok(())
    }

    pub(crate) fn plan(
        &self,
        size: (u32, u32),
        truth: &[Option<BoundingBox>],
        rng: &mut Pcg64Mcg,
    ) -> ShakePlan {
        let (fw, fh) = (f64::from(size.0), f64::from(size.1));
        let r = median_radius(truth).unwrap_or(0.125 * fw.min(fh));
        let z = self.zoom;
        // The crop's centre keeps the crop inside the frame [−½, W − ½).
        let (lo_x, hi_x) = (fw / (2.0 * z) - 0.5, fw - 0.5 - fw / (2.0 * z));
        let (lo_y, hi_y) = (fh / (2.0 * z) - 0.5, fh - 0.5 - fh / (2.0 * z));
        let targets = held_centres(truth, size);
        let mut aim: Option<(f64, f64)> = None;
        let mut offset = (0.0_f64, 0.0_f64);
        let mut last_dir: Option<(f64, f64)> = None;
        let mut next_jump = rng.random_range(self.gap_min..=self.gap_max);
        let mut prev: Option<(f64, f64)> = None;
        let mut frames = Vec::with_capacity(truth.len());
        let mut jumps = Vec::new();
        for (k, &target) in targets.iter().enumerate() {
            aim = Some(match aim {
                None => target,
                Some((ax, ay)) => (
                    ax + self.follow * (target.0 - ax),
                    ay + self.follow * (target.1 - ay),
                ),
            });
            let jumped = k == next_jump;
            if jumped {
                next_jump = k + rng.random_range(self.gap_min..=self.gap_max);
                let len = r * rng.random_range(self.jump_min..=self.jump_max);
                let dir = match last_dir {
                    Some((dx, dy)) if rng.random_bool(self.reverse) => (-dx, -dy),
                    _ => {
                        let a = rng.random_range(0.0..std::f64::consts::TAU);
                        (a.cos(), a.sin())
                    }
                };
                let limit = self.max_offset * r;
                let ahead = (offset.0 + len * dir.0, offset.1 + len * dir.1);
                let (o, d) = if ahead.0.hypot(ahead.1) <= limit {
                    (ahead, dir)
                } else {
                    let back = (offset.0 - len * dir.0, offset.1 - len * dir.1);
                    (back, (-dir.0, -dir.1))
                };
                let n = o.0.hypot(o.1);
                offset = if n > limit {
                    (o.0 * limit / n, o.1 * limit / n)
                } else {
                    o
                };
                last_dir = Some(d);
            }
            let (ax, ay) = aim.unwrap_or(target);
            let centre = (
                (ax + offset.0).clamp(lo_x, hi_x.max(lo_x)),
                (ay + offset.1).clamp(lo_y, hi_y.max(lo_y)),
            );
            let blur = match prev {
                Some(p) if jumped => {
                    let step = (centre.0 - p.0, centre.1 - p.1);
                    jumps.push(step.0.hypot(step.1) / r);
                    (self.blur * step.0, self.blur * step.1)
                }
                _ => (0.0, 0.0),
            };
            prev = Some(centre);
            frames.push(ShakeFrame { centre, blur });
        }
        ShakePlan {
            zoom: z,
            size,
            radius: r,
            frames,
            jumps,
        }
    }
}

/// One frame's crop centre (source pixels) and blur (source displacement over the exposure).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ShakeFrame {
    centre: (f64, f64),
    blur: (f64, f64),
}

/// The planned crops of a clip.
#[derive(Debug, Clone)]
pub(crate) struct ShakePlan {
    zoom: f64,
    size: (u32, u32),
    radius: f64,
    frames: Vec<ShakeFrame>,
    /// The realised jumps, in target radii (smaller than asked where the frame has no room).
    jumps: Vec<f64>,
}

impl ShakePlan {
    fn half(&self) -> (f64, f64) {
        (
            0.5 * (f64::from(self.size.0) - 1.0),
            0.5 * (f64::from(self.size.1) - 1.0),
        )
    }

    /// x' = (x − cₓ)·z + (W − 1)/2: the crop's centre lands on the output frame's centre.
    pub(crate) fn map_box(&self, k: usize, b: &BoundingBox) -> BoundingBox {
        let (cx, cy) = self.frames[k].centre;
        let (hx, hy) = self.half();
        let z = self.zoom;
        BoundingBox::new((b.x - cx) * z + hx, (b.y - cy) * z + hy, b.w * z, b.h * z)
    }

    pub(crate) fn apply(&self, k: usize, frame: &image::RgbImage) -> image::RgbImage {
        let f = self.frames[k];
        let (hx, hy) = self.half();
        let s = 1.0 / self.zoom;
        let map = [s, 0.0, f.centre.0 - s * hx, 0.0, s, f.centre.1 - s * hy];
        let blur = (f.blur.0 != 0.0 || f.blur.1 != 0.0).then_some(f.blur);
        super::warp::warp(frame, self.size, &map, blur)
    }

    pub(crate) fn describe(&self) -> serde_json::Value {
        let mean = if self.jumps.is_empty() {
            0.0
        } else {
            self.jumps.iter().sum::<f64>() / self.jumps.len() as f64
        };
        serde_json::json!({
            "radius_px": self.radius,
            "jumps": self.jumps.len(),
            "mean_jump_radii": mean,
            "largest_jump_radii": self.jumps.iter().copied().fold(0.0, f64::max),
        })
    }
}
