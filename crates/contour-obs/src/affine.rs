//! The contour pose: a 2-D affine map from reference coordinates to image coordinates, and its
//! conversions to and from the two papers' state parameterisations.

use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};
use vision_core::{BoundingBox, Ellipse};

/// A contour pose p = A·r + t mapping reference coordinates r (the unit circle or a B-spline
/// template) to image coordinates p.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Affine2 {
    /// The linear part A.
    pub a: Matrix2<f64>,
    /// The translation t.
    pub t: Vector2<f64>,
}

impl Affine2 {
    /// A pose from its linear part and translation.
    pub fn new(a: Matrix2<f64>, t: Vector2<f64>) -> Self {
        Self { a, t }
    }

    /// The identity pose (the reference contour itself).
    pub fn identity() -> Self {
        Self::new(Matrix2::identity(), Vector2::zeros())
    }

    /// The pose that maps the unit circle onto an ellipse: A = R(θ)·diag(a, b), t = (cx, cy).
    pub fn from_ellipse(cx: f64, cy: f64, a: f64, b: f64, theta: f64) -> Self {
        let (s, c) = theta.sin_cos();
        Self::new(
            Matrix2::new(a * c, -b * s, a * s, b * c),
            Vector2::new(cx, cy),
        )
    }

    /// Odobez's state α = (Tx, Ty, s, e) (Odobez Eq. 11–12): s_x = 2es/(1+e), s_y = 2s/(1+e),
    /// A = diag(s_x, s_y), t = (Tx, Ty).
    pub fn from_odobez(tx: f64, ty: f64, s: f64, e: f64) -> Self {
        let sx = 2.0 * e * s / (1.0 + e);
        let sy = 2.0 * s / (1.0 + e);
        Self::new(Matrix2::new(sx, 0.0, 0.0, sy), Vector2::new(tx, ty))
    }

    /// Wu's affine shape space X = (a11, a12, a21, a22, t1, t2): A = [[a11, a12], [a21, a22]],
    /// t = (t1, t2).
    pub fn from_wu(x: [f64; 6]) -> Self {
        Self::new(
            Matrix2::new(x[0], x[1], x[2], x[3]),
            Vector2::new(x[4], x[5]),
        )
    }

    /// Back to Wu's shape space (always defined).
    pub fn to_wu(&self) -> [f64; 6] {
        [
            self.a[(0, 0)],
            self.a[(0, 1)],
            self.a[(1, 0)],
            self.a[(1, 1)],
            self.t.x,
            self.t.y,
        ]
    }

    /// Back to Odobez's (Tx, Ty, s, e): defined only when A is diagonal (off-diagonal terms below
    /// 1e−12 of the scale) with positive entries; `None` otherwise.
    pub fn to_odobez(&self) -> Option<[f64; 4]> {
        let (sx, sy) = (self.a[(0, 0)], self.a[(1, 1)]);
        let scale = sx.abs().max(sy.abs());
        let off = self.a[(0, 1)].abs().max(self.a[(1, 0)].abs());
        if !(sx > 0.0 && sy > 0.0) || off > 1e-12 * scale || !self.is_finite() {
            return None;
        }
        Some([self.t.x, self.t.y, 0.5 * (sx + sy), sx / sy])
    }

    /// The ellipse that this pose makes of the unit circle, with a ≥ b ≥ 0 and θ ∈ (−π/2, π/2].
    /// `None` when the pose is not finite.
    pub fn to_ellipse(&self) -> Option<Ellipse> {
        if !self.is_finite() {
            return None;
        }
        // The posed circle is {p : (p − t)ᵀ (A Aᵀ)⁻¹ (p − t) = 1}; the eigen-decomposition of the
        // symmetric M = A Aᵀ gives the squared semi-axes and their directions.
        let m = self.a * self.a.transpose();
        let (l1, l2, theta) = sym2_eigen(m[(0, 0)], m[(0, 1)], m[(1, 1)]);
        Some(Ellipse {
            cx: self.t.x,
            cy: self.t.y,
            a: l1.max(0.0).sqrt(),
            b: l2.max(0.0).sqrt(),
            angle: theta,
        })
    }

    /// Maps a reference point to image coordinates.
    pub fn apply(&self, r: Vector2<f64>) -> Vector2<f64> {
        self.a * r + self.t
    }

    /// det A.
    pub fn determinant(&self) -> f64 {
        self.a.determinant()
    }

    /// Whether every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.a.iter().chain(self.t.iter()).all(|v| v.is_finite())
    }

    /// The axis-aligned bounding box of the posed unit circle: half-width √(a11² + a12²),
    /// half-height √(a21² + a22²).
    pub fn bounding_box(&self) -> BoundingBox {
        let hw = self.a[(0, 0)].hypot(self.a[(0, 1)]);
        let hh = self.a[(1, 0)].hypot(self.a[(1, 1)]);
        BoundingBox::from_corners(self.t.x - hw, self.t.y - hh, self.t.x + hw, self.t.y + hh)
    }
}

impl From<Ellipse> for Affine2 {
    fn from(e: Ellipse) -> Self {
        Affine2::from_ellipse(e.cx, e.cy, e.a, e.b, e.angle)
    }
}

/// Eigen-decomposition of the symmetric matrix [[p, q], [q, r]]: returns (λ1 ≥ λ2, θ) where θ ∈
/// (−π/2, π/2] is the direction of λ1's eigenvector.
pub(crate) fn sym2_eigen(p: f64, q: f64, r: f64) -> (f64, f64, f64) {
    let mean = 0.5 * (p + r);
    let d = (0.5 * (p - r)).hypot(q);
    let mut theta = 0.5 * (2.0 * q).atan2(p - r);
    if theta <= -std::f64::consts::FRAC_PI_2 {
        theta += std::f64::consts::PI;
    }
    (mean + d, mean - d, theta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn ellipse_round_trip_and_box() {
        let p = Affine2::from_ellipse(10.0, -4.0, 7.0, 3.0, 0.4);
        let e = p.to_ellipse().unwrap();
        assert_relative_eq!(e.a, 7.0, epsilon = 1e-12);
        assert_relative_eq!(e.b, 3.0, epsilon = 1e-12);
        assert_relative_eq!(e.angle, 0.4, epsilon = 1e-12);
        assert_relative_eq!(e.cx, 10.0);
        // Bounding box of a rotated ellipse: half-width √(a²cos²θ + b²sin²θ).
        let bb = p.bounding_box();
        let hw = (49.0 * 0.4f64.cos().powi(2) + 9.0 * 0.4f64.sin().powi(2)).sqrt();
        assert_relative_eq!(bb.w, 2.0 * hw, epsilon = 1e-12);
        // And it touches the densest sampling of the posed circle.
        let max_x = (0..100_000)
            .map(|k| {
                p.apply(Vector2::new(
                    (k as f64 * 1e-4 * std::f64::consts::TAU).cos(),
                    (k as f64 * 1e-4 * std::f64::consts::TAU).sin(),
                ))
                .x
            })
            .fold(f64::MIN, f64::max);
        assert_relative_eq!(max_x, bb.max_corner().0, epsilon = 1e-6);
    }

    #[test]
    fn odobez_conversions() {
        // Axis-aligned ellipse: s = (a + b)/2, e = a/b with a the horizontal semi-axis.
        let p = Affine2::from_odobez(3.0, 4.0, 5.0, 1.5);
        let e = Affine2::from_ellipse(3.0, 4.0, 6.0, 4.0, 0.0);
        assert_relative_eq!(p.a, e.a, epsilon = 1e-12);
        let back = p.to_odobez().unwrap();
        assert_relative_eq!(back[2], 5.0, epsilon = 1e-12);
        assert_relative_eq!(back[3], 1.5, epsilon = 1e-12);
        assert!(
            Affine2::from_ellipse(0.0, 0.0, 2.0, 1.0, 0.3)
                .to_odobez()
                .is_none()
        );
    }

    #[test]
    fn wu_round_trip() {
        let x = [1.0, 0.2, -0.3, 2.0, 5.0, 6.0];
        assert_eq!(Affine2::from_wu(x).to_wu(), x);
        assert_relative_eq!(Affine2::from_wu(x).determinant(), 2.06, epsilon = 1e-12);
    }
}
