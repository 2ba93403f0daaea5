//! The two state parameterisations of the papers and their map to a contour pose.
//!
//! Both are stored in a fixed `[f64; 6]` so that one particle type serves every tracker:
//! - [`ShapeSpace::Odobez`]: α = (Tx, Ty, s, e) (Odobez Eq. 11–12) in the first four slots;
//! - [`ShapeSpace::Affine`]: Wu's X = (a11, a12, a21, a22, t1, t2) (Wu §6).

use contour_obs::{Affine2, Ellipse};
use serde::{Deserialize, Serialize};

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
        let pose = Affine2::from_ellipse(e.cx, e.cy, e.a, e.b, e.theta);
        match self {
            ShapeSpace::Odobez => {
                let bb = pose.bounding_box();
                let (sx, sy) = (0.5 * bb.width(), 0.5 * bb.height());
                [e.cx, e.cy, 0.5 * (sx + sy), sx / sy, 0.0, 0.0]
            }
            ShapeSpace::Affine => pose.to_wu(),
        }
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

    /// The mean radius of a state in pixels: s for Odobez, √|det A| for Affine.
    pub fn scale(self, x: &StateVector) -> f64 {
        match self {
            ShapeSpace::Odobez => x[2],
            ShapeSpace::Affine => (x[0] * x[3] - x[1] * x[2]).abs().sqrt(),
        }
    }

    /// Keeps a sampled state inside the valid domain: mean radius within `[min, max]` pixels
    /// and, for Odobez, the aspect ratio in [1/4, 4]. Heavy-tailed (Cauchy) noise can otherwise
    /// produce a negative scale, which has no contour, and a contour can otherwise shrink onto a
    /// corner of the image where any likelihood is easy to satisfy.
    pub fn clamp(self, x: &mut StateVector, (min, max): (f64, f64)) {
        match self {
            ShapeSpace::Odobez => {
                x[2] = x[2].clamp(min, max);
                x[3] = x[3].clamp(0.25, 4.0);
            }
            ShapeSpace::Affine => {
                let s = self.scale(x);
                if (min..=max).contains(&s) {
                    return;
                }
                if s > 1e-9 {
                    let r = s.clamp(min, max) / s;
                    for v in &mut x[..4] {
                        *v *= r;
                    }
                } else {
                    let centre = [x[4], x[5]];
                    *x = [min, 0.0, 0.0, min, centre[0], centre[1]];
                }
            }
        }
    }
}

/// y ← y + a·x over every slot (unused slots of both are zero, so they stay zero).
pub fn axpy(y: &mut StateVector, a: f64, x: &StateVector) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// The axis-aligned box (x, y, w, h) of a pose's contour.
pub fn pose_box(pose: &Affine2) -> [f64; 4] {
    let bb = pose.bounding_box();
    [bb.x_min, bb.y_min, bb.width(), bb.height()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn odobez_round_trip_of_an_axis_aligned_ellipse() {
        let e = Ellipse {
            cx: 100.0,
            cy: 80.0,
            a: 30.0,
            b: 20.0,
            theta: 0.0,
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
            theta: 0.3,
        };
        let x = ShapeSpace::Affine.from_ellipse(&e);
        let back = ShapeSpace::Affine.pose(&x).to_ellipse().unwrap();
        assert!((back.a - 30.0).abs() < 1e-9 && (back.b - 20.0).abs() < 1e-9);
        assert!((back.theta - 0.3).abs() < 1e-9);
        assert!((ShapeSpace::Affine.scale(&x) - 600f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn clamp_restores_a_positive_scale() {
        let mut x = [10.0, 10.0, -3.0, 9.0, 0.0, 0.0];
        ShapeSpace::Odobez.clamp(&mut x, (2.0, 100.0));
        assert_eq!(x[2], 2.0);
        assert_eq!(x[3], 4.0);
    }
}
