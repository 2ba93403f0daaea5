//! The conversions of an ellipse pose ([`vision_core::Ellipse`]) to the trackers' state spaces.
//!
//! Conventions (shared by the workspace): x to the right, y down, pixel (i, j) centred at (i, j).
//! Ellipse (cx, cy, a, b, θ): semi-axis a along (cos θ, sin θ), b along (−sin θ, cos θ); as an
//! affine map of the unit circle, A = R(θ)·diag(a, b), t = (cx, cy).

use serde::{Deserialize, Serialize};
use vision_core::Ellipse;

/// Odobez et al.'s state α = (Tx, Ty, s, e) (O Eq. 11–12).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OdobezState {
    /// Translation x.
    pub tx: f64,
    /// Translation y.
    pub ty: f64,
    /// Scale s (mean of the two semi-axes).
    pub s: f64,
    /// Eccentricity e = s_x / s_y.
    pub e: f64,
}

/// Wu et al.'s affine shape space X = (a11, a12, a21, a22, t1, t2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WuAffine {
    /// Row 1, column 1 of A.
    pub a11: f64,
    /// Row 1, column 2 of A.
    pub a12: f64,
    /// Row 2, column 1 of A.
    pub a21: f64,
    /// Row 2, column 2 of A.
    pub a22: f64,
    /// Translation x.
    pub t1: f64,
    /// Translation y.
    pub t2: f64,
}

impl WuAffine {
    /// The affine pose p = A·r + t of the unit circle under `e`: A = R(θ)·diag(a, b), t = (cx, cy).
    pub fn from_ellipse(e: &Ellipse) -> Self {
        let (sn, cs) = e.angle.sin_cos();
        WuAffine {
            a11: cs * e.a,
            a12: -sn * e.b,
            a21: sn * e.a,
            a22: cs * e.b,
            t1: e.cx,
            t2: e.cy,
        }
    }
}

impl OdobezState {
    /// Odobez's state of `e` (O Eq. 11–12). For an axis-aligned ellipse s = (a + b)/2 and
    /// e = a/b, so that s_x = 2es/(1+e) = a and s_y = 2s/(1+e) = b. A rotated ellipse has no
    /// exact (T, s, e) form; its bounding-box half-extents stand in for (a, b), which is exact at
    /// θ = 0.
    pub fn from_ellipse(e: &Ellipse) -> Self {
        let (sx, sy) = e.half_extents();
        OdobezState {
            tx: e.cx,
            ty: e.cy,
            s: 0.5 * (sx + sy),
            e: sx / sy,
        }
    }
}

/// The point of the contour of `e` at reference angle φ (the image of (cos φ, sin φ)) and the
/// outward unit normal there.
pub fn point_and_normal(e: &Ellipse, phi: f64) -> ([f64; 2], [f64; 2]) {
    let m = WuAffine::from_ellipse(e);
    let (s, c) = phi.sin_cos();
    let p = [m.a11 * c + m.a12 * s + m.t1, m.a21 * c + m.a22 * s + m.t2];
    // The normal is A^{-T}·(cos φ, sin φ), normalised.
    let det = m.a11 * m.a22 - m.a12 * m.a21;
    let nx = (m.a22 * c - m.a21 * s) / det;
    let ny = (-m.a12 * c + m.a11 * s) / det;
    let len = nx.hypot(ny);
    (p, [nx / len, ny / len])
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn odobez_state_matches_the_semi_axes_when_axis_aligned() {
        let e = Ellipse {
            cx: 10.0,
            cy: 20.0,
            a: 30.0,
            b: 20.0,
            angle: 0.0,
        };
        let o = OdobezState::from_ellipse(&e);
        // O Eq. 12: s_x = 2es/(1+e), s_y = 2s/(1+e).
        assert_relative_eq!(2.0 * o.e * o.s / (1.0 + o.e), 30.0, epsilon = 1e-12);
        assert_relative_eq!(2.0 * o.s / (1.0 + o.e), 20.0, epsilon = 1e-12);
        let b = e.bounding_box();
        assert_relative_eq!(b.x, -20.0, epsilon = 1e-12);
        assert_relative_eq!(b.h, 40.0, epsilon = 1e-12);
    }

    #[test]
    fn contour_points_have_zero_signed_distance_and_unit_normals() {
        let e = Ellipse {
            cx: 50.0,
            cy: 40.0,
            a: 25.0,
            b: 32.0,
            angle: 0.4,
        };
        for k in 0..16 {
            let phi = k as f64 * 0.39;
            let (p, n) = point_and_normal(&e, phi);
            assert_relative_eq!(e.signed_distance(p[0], p[1]), 0.0, epsilon = 1e-9);
            // One pixel out along the normal is one pixel away (first-order distance).
            let d = e.signed_distance(p[0] + n[0], p[1] + n[1]);
            assert!((d - 1.0).abs() < 0.05, "distance {d}");
            assert_relative_eq!(n[0].hypot(n[1]), 1.0, epsilon = 1e-12);
        }
    }
}
