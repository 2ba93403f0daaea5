//! The two state parameterisations of the papers and their map to a contour pose.
//!
//! Both are stored in a fixed `[f64; 6]` so that one particle type serves every tracker:
//! - [`ShapeSpace::Odobez`]: α = (Tx, Ty, s, e) (Odobez Eq. 11–12) in the first four slots;
//! - [`ShapeSpace::Affine`]: Wu's X = (a11, a12, a21, a22, t1, t2) (Wu §6).

use contour_obs::Affine2;
use nalgebra::Matrix2;
use serde::{Deserialize, Serialize};
use vision_core::{BoundingBox, Ellipse};

/// Number of slots of a state vector.
pub const STATE_SLOTS: usize = 6;

/// A state vector (unused slots are zero).
pub type StateVector = [f64; STATE_SLOTS];

/// Which shape space a tracker's particles live in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeSpace {
    /// Odobez's translation, scale and aspect ratio α = (Tx, Ty, s, e): an axis-aligned ellipse
    /// with semi-axes s_x = 2es/(1+e), s_y = 2s/(1+e) (Eq. 12).
    Odobez,
    /// Wu's affine shape space X = (a11, a12, a21, a22, t1, t2): p = A·r + t.
    Affine,
}

impl ShapeSpace {
    /// Number of used slots.
    pub fn dim(self) -> usize {
        match self {
            ShapeSpace::Odobez => 4,
            ShapeSpace::Affine => 6,
        }
    }

    /// The contour pose of a state.
    pub fn pose(self, x: &StateVector) -> Affine2 {
        match self {
            ShapeSpace::Odobez => Affine2::from_odobez(x[0], x[1], x[2], x[3]),
            ShapeSpace::Affine => Affine2::from_wu(*x),
        }
    }

    /// The state of an ellipse. Odobez's space has no rotation: a rotated ellipse is represented
    /// by its axis-aligned bounding ellipse's semi-axes (the half-width and half-height of its box).
    pub fn from_ellipse(self, e: &Ellipse) -> StateVector {
        let pose = Affine2::from_ellipse(e.cx, e.cy, e.a, e.b, e.angle);
        match self {
            ShapeSpace::Odobez => {
                let bb = pose.bounding_box();
                let (sx, sy) = (0.5 * bb.w, 0.5 * bb.h);
                [e.cx, e.cy, 0.5 * (sx + sy), sx / sy, 0.0, 0.0]
            }
            ShapeSpace::Affine => pose.to_wu(),
        }
    }

    /// The state of the contour mapped by p ↦ `factor`·p + (`offset`, `offset`) (a change of
    /// pixel grid, see [`crate::working_scale`]).
    pub fn map_pose(self, x: &StateVector, factor: f64, offset: f64) -> StateVector {
        let mut y = *x;
        match self {
            ShapeSpace::Odobez => {
                y[0] = factor * x[0] + offset;
                y[1] = factor * x[1] + offset;
                y[2] = factor * x[2];
            }
            ShapeSpace::Affine => {
                for v in &mut y[..4] {
                    *v *= factor;
                }
                y[4] = factor * x[4] + offset;
                y[5] = factor * x[5] + offset;
            }
        }
        y
    }

    /// Whether slot `j` is a translation component.
    pub fn is_translation(self, j: usize) -> bool {
        match self {
            ShapeSpace::Odobez => j < 2,
            ShapeSpace::Affine => j >= 4,
        }
    }

    /// The centre (translation) of a state.
    pub fn centre(self, x: &StateVector) -> [f64; 2] {
        match self {
            ShapeSpace::Odobez => [x[0], x[1]],
            ShapeSpace::Affine => [x[4], x[5]],
        }
    }

    /// Sets the centre (translation) of a state.
    pub fn set_centre(self, x: &mut StateVector, c: [f64; 2]) {
        let (tx, ty) = match self {
            ShapeSpace::Odobez => (0, 1),
            ShapeSpace::Affine => (4, 5),
        };
        x[tx] = c[0];
        x[ty] = c[1];
    }

    /// The mean radius of a state in pixels: s for Odobez, √|det A| for Affine.
    pub fn scale(self, x: &StateVector) -> f64 {
        match self {
            ShapeSpace::Odobez => x[2],
            ShapeSpace::Affine => (x[0] * x[3] - x[1] * x[2]).abs().sqrt(),
        }
    }

    /// Keeps a sampled state inside the valid domain `bounds`: mean radius within
    /// `bounds.scale` pixels and elongation within `bounds.aspect` (Odobez: e in that range;
    /// affine: the ratio of the singular values of A at most `bounds.aspect.1`, the area kept).
    /// Heavy-tailed (Cauchy) noise can otherwise produce a negative scale, which has no contour,
    /// and a contour can otherwise collapse onto a thin bar of clutter that fits its lines. The
    /// centre is kept in `bounds.centre`.
    pub fn clamp(self, x: &mut StateVector, bounds: &ShapeBounds) {
        let (tx, ty) = match self {
            ShapeSpace::Odobez => (0, 1),
            ShapeSpace::Affine => (4, 5),
        };
        let c = bounds.centre;
        x[tx] = x[tx].clamp(c[0], c[2]);
        x[ty] = x[ty].clamp(c[1], c[3]);
        let (min, max) = bounds.scale;
        match self {
            ShapeSpace::Odobez => {
                x[2] = x[2].clamp(min, max);
                x[3] = x[3].clamp(bounds.aspect.0, bounds.aspect.1);
            }
            ShapeSpace::Affine => {
                let a = Matrix2::new(x[0], x[1], x[2], x[3]);
                let svd = a.svd(true, true);
                let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
                    *x = [min, 0.0, 0.0, min, x[4], x[5]];
                    return;
                };
                let (s1, s2) = (svd.singular_values[0], svd.singular_values[1]);
                let scale = (s1 * s2).sqrt();
                if scale.is_nan() || scale <= 1e-9 {
                    *x = [min, 0.0, 0.0, min, x[4], x[5]];
                    return;
                }
                // Limit the elongation, keeping the area, then the scale.
                let ratio = (s1 / s2.max(1e-12)).min(bounds.aspect.1.max(1.0));
                let target = scale.clamp(min, max);
                let (t1, t2) = (target * ratio.sqrt(), target / ratio.sqrt());
                if (t1 - s1).abs() > 1e-12 * s1 || (t2 - s2).abs() > 1e-12 * s1 {
                    let m = u * Matrix2::new(t1, 0.0, 0.0, t2) * v_t;
                    x[0] = m[(0, 0)];
                    x[1] = m[(0, 1)];
                    x[2] = m[(1, 0)];
                    x[3] = m[(1, 1)];
                }
            }
        }
    }

    /// The elongation bounds of [`ShapeBounds::aspect`] for a target whose initial elongation is
    /// `e0`: `range` (relative to `e0`, as `DynamicsSettings::aspect_range`) times `e0`, within
    /// [1/4, 4] and always holding `e0`. Odobez's e = width / height is below 1 for a tall
    /// target, so its upper bound may be below 1 too; the affine elongation is at least 1.
    pub(crate) fn elongation_bounds(self, e0: f64, range: [f64; 2]) -> (f64, f64) {
        let (lo, hi) = (range[0] * e0, range[1] * e0);
        match self {
            ShapeSpace::Odobez => (lo.max(0.25).min(e0), hi.min(4.0).max(e0)),
            ShapeSpace::Affine => (lo.max(0.25), hi.clamp(1.0, 4.0)),
        }
    }

    /// The elongation of a state: e for Odobez, the ratio of the singular values of A (≥ 1)
    /// for affine.
    pub fn elongation(self, x: &StateVector) -> f64 {
        match self {
            ShapeSpace::Odobez => x[3],
            ShapeSpace::Affine => {
                let sv = Matrix2::new(x[0], x[1], x[2], x[3]).singular_values();
                sv[0].max(sv[1]) / sv[0].min(sv[1]).max(1e-12)
            }
        }
    }
}

/// The domain a tracker's states are kept in (see [`ShapeSpace::clamp`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShapeBounds {
    /// Smallest and largest mean radius, pixels.
    pub scale: (f64, f64),
    /// Smallest and largest elongation (Odobez e; affine: only the upper bound is used).
    pub aspect: (f64, f64),
    /// The box the centre is kept in, `[x_min, y_min, x_max, y_max]` (unbounded by default).
    pub centre: [f64; 4],
}

/// No bound on the centre.
pub const UNBOUNDED_CENTRE: [f64; 4] = [
    f64::NEG_INFINITY,
    f64::NEG_INFINITY,
    f64::INFINITY,
    f64::INFINITY,
];

impl ShapeBounds {
    /// Bounds that only keep a state valid: radius ≥ `min_scale`, e in [1/4, 4].
    pub fn loose(min_scale: f64) -> Self {
        Self {
            scale: (min_scale, f64::INFINITY),
            aspect: (0.25, 4.0),
            centre: UNBOUNDED_CENTRE,
        }
    }
}

/// y ← y + a·x over every slot (unused slots of both are zero, so they stay zero).
pub fn axpy(y: &mut StateVector, a: f64, x: &StateVector) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// The axis-aligned box of a pose's contour.
pub fn pose_box(pose: &Affine2) -> BoundingBox {
    pose.bounding_box()
}

/// An ellipse in words, for messages.
pub(crate) fn describe(e: &Ellipse) -> String {
    format!(
        "the ellipse centred at ({}, {}) with semi-axes {} and {} at angle {} rad",
        e.cx, e.cy, e.a, e.b, e.angle
    )
}

/// Checks an initial ellipse: finite, with positive semi-axes.
///
/// # Errors
/// [`crate::Error::InvalidSetting`] naming the ellipse.
pub(crate) fn check_initial(ellipse: &Ellipse) -> crate::Result<()> {
    let values = [ellipse.cx, ellipse.cy, ellipse.a, ellipse.b, ellipse.angle];
    if values.iter().any(|v| !v.is_finite()) || !(ellipse.a > 0.0 && ellipse.b > 0.0) {
        return Err(crate::Error::InvalidSetting {
            name: "initial ellipse",
            reason: format!(
                "{} must be finite with positive semi-axes",
                describe(ellipse)
            ),
        });
    }
    Ok(())
}

/// Which components of a kinematic state a density reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Components {
    /// Every used component.
    All,
    /// The size and shape: every used component but the centre (what an abrupt-motion jump
    /// keeps of a continuation, see [`crate::dynamics::reacquisition`]).
    SizeAndShape,
}

impl Components {
    /// Whether slot `j` of a state of `space` is among these components.
    pub fn includes(self, space: ShapeSpace, j: usize) -> bool {
        match self {
            Components::All => true,
            Components::SizeAndShape => !space.is_translation(j),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elongation_bounds_are_relative_to_the_initial_elongation_whichever_way_it_leans() {
        // A tall target (Odobez e = width / height = 0.7): the range [1, 1] fixes e, and the
        // default [0.33, 3] reaches above and below e0 alike. The bound was once clamped to at
        // least 1, so a tall target's aspect could always drift to a round one.
        let o = ShapeSpace::Odobez;
        assert_eq!(o.elongation_bounds(0.7, [1.0, 1.0]), (0.7, 0.7));
        let (lo, hi) = o.elongation_bounds(0.7, [0.9, 1.1]);
        assert!((lo - 0.63).abs() < 1e-12 && (hi - 0.77).abs() < 1e-12);
        let (lo, hi) = o.elongation_bounds(0.2, [0.33, 3.0]);
        assert!(
            (lo - 0.2).abs() < 1e-12 && (hi - 0.6).abs() < 1e-12,
            "{lo} {hi}"
        );
        // Past [1/4, 4] the bounds stop there but still hold e0.
        let (lo, hi) = o.elongation_bounds(10.0, [0.33, 3.0]);
        assert!((lo - 3.3).abs() < 1e-12 && hi == 10.0, "{lo} {hi}");
        // The affine elongation is a ratio of singular values, at least 1.
        let (_, hi) = ShapeSpace::Affine.elongation_bounds(1.0, [0.33, 3.0]);
        assert_eq!(hi, 3.0);
        assert_eq!(ShapeSpace::Affine.elongation_bounds(1.0, [1.0, 1.0]).1, 1.0);
    }

    #[test]
    fn odobez_round_trip_of_an_axis_aligned_ellipse() {
        let e = Ellipse {
            cx: 100.0,
            cy: 80.0,
            a: 30.0,
            b: 20.0,
            angle: 0.0,
        };
        let x = ShapeSpace::Odobez.from_ellipse(&e);
        assert!((x[2] - 25.0).abs() < 1e-12 && (x[3] - 1.5).abs() < 1e-12);
        let back = ShapeSpace::Odobez.pose(&x).to_ellipse().unwrap();
        assert!((back.a - 30.0).abs() < 1e-9 && (back.b - 20.0).abs() < 1e-9);
        assert!((back.cx - 100.0).abs() < 1e-12);
    }

    #[test]
    fn affine_round_trip_keeps_rotation() {
        let e = Ellipse {
            cx: 50.0,
            cy: 60.0,
            a: 30.0,
            b: 20.0,
            angle: 0.3,
        };
        let x = ShapeSpace::Affine.from_ellipse(&e);
        let back = ShapeSpace::Affine.pose(&x).to_ellipse().unwrap();
        assert!((back.a - 30.0).abs() < 1e-9 && (back.b - 20.0).abs() < 1e-9);
        assert!((back.angle - 0.3).abs() < 1e-9);
        assert!((ShapeSpace::Affine.scale(&x) - 600f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn clamp_restores_a_positive_scale() {
        let mut x = [10.0, 10.0, -3.0, 9.0, 0.0, 0.0];
        ShapeSpace::Odobez.clamp(&mut x, &ShapeBounds::loose(2.0));
        assert_eq!(x[2], 2.0);
        assert_eq!(x[3], 4.0);
    }

    #[test]
    fn affine_elongation_is_limited_keeping_area_and_orientation() {
        let e = Ellipse {
            cx: 0.0,
            cy: 0.0,
            a: 40.0,
            b: 10.0,
            angle: 0.4,
        };
        let mut x = ShapeSpace::Affine.from_ellipse(&e);
        let bounds = ShapeBounds {
            scale: (2.0, 1e3),
            aspect: (0.5, 2.0),
            centre: UNBOUNDED_CENTRE,
        };
        ShapeSpace::Affine.clamp(&mut x, &bounds);
        let back = ShapeSpace::Affine.pose(&x).to_ellipse().unwrap();
        assert!((back.a / back.b - 2.0).abs() < 1e-9);
        assert!((back.a * back.b - 400.0).abs() < 1e-6);
        assert!((back.angle - 0.4).abs() < 1e-9);
    }
}
