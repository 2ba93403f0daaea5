//! Ellipse poses and the conversions to the trackers' state spaces.
//!
//! Conventions (shared by the workspace): x to the right, y down, pixel (i, j) centred at (i, j).
//! Ellipse (cx, cy, a, b, θ): semi-axis a along (cos θ, sin θ), b along (−sin θ, cos θ); as an
//! affine map of the unit circle, A = R(θ)·diag(a, b), t = (cx, cy).

use serde::{Deserialize, Serialize};

/// An ellipse in image coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Ellipse {
    /// Centre, x (px).
    pub cx: f64,
    /// Centre, y (px).
    pub cy: f64,
    /// Semi-axis along (cos θ, sin θ) (px).
    pub a: f64,
    /// Semi-axis along (−sin θ, cos θ) (px).
    pub b: f64,
    /// Orientation θ (radians).
    pub angle: f64,
}

/// Axis-aligned box, top-left corner plus size, in pixel-centre coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BoxRect {
    /// Left edge x (px).
    pub x: f64,
    /// Top edge y (px).
    pub y: f64,
    /// Width (px).
    pub w: f64,
    /// Height (px).
    pub h: f64,
}

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

impl Ellipse {
    /// The affine pose p = A·r + t of the unit circle: A = R(θ)·diag(a, b), t = (cx, cy).
    pub fn affine(&self) -> WuAffine {
        let (sn, cs) = self.angle.sin_cos();
        WuAffine {
            a11: cs * self.a,
            a12: -sn * self.b,
            a21: sn * self.a,
            a22: cs * self.b,
            t1: self.cx,
            t2: self.cy,
        }
    }

    /// Half-widths of the axis-aligned bounding box of the rotated ellipse.
    pub fn half_extents(&self) -> (f64, f64) {
        let (sn, cs) = self.angle.sin_cos();
        let hw = ((self.a * cs).powi(2) + (self.b * sn).powi(2)).sqrt();
        let hh = ((self.a * sn).powi(2) + (self.b * cs).powi(2)).sqrt();
        (hw, hh)
    }

    /// The axis-aligned bounding box.
    pub fn bounding_box(&self) -> BoxRect {
        let (hw, hh) = self.half_extents();
        BoxRect {
            x: self.cx - hw,
            y: self.cy - hh,
            w: 2.0 * hw,
            h: 2.0 * hh,
        }
    }

    /// Odobez's state (O Eq. 11–12). For an axis-aligned ellipse s = (a + b)/2 and e = a/b, so
    /// that s_x = 2es/(1+e) = a and s_y = 2s/(1+e) = b. A rotated ellipse has no exact (T, s, e)
    /// form; its bounding-box half-extents stand in for (a, b), which is exact at θ = 0.
    pub fn odobez(&self) -> OdobezState {
        let (sx, sy) = self.half_extents();
        OdobezState {
            tx: self.cx,
            ty: self.cy,
            s: 0.5 * (sx + sy),
            e: sx / sy,
        }
    }

    /// Area π·a·b (px²).
    pub fn area(&self) -> f64 {
        std::f64::consts::PI * self.a * self.b
    }

    /// The point of the contour at reference angle φ (the image of (cos φ, sin φ)) and the
    /// outward unit normal there.
    pub fn point_and_normal(&self, phi: f64) -> ([f64; 2], [f64; 2]) {
        let m = self.affine();
        let (s, c) = phi.sin_cos();
        let p = [m.a11 * c + m.a12 * s + m.t1, m.a21 * c + m.a22 * s + m.t2];
        // The normal is A^{-T}·(cos φ, sin φ), normalised.
        let det = m.a11 * m.a22 - m.a12 * m.a21;
        let nx = (m.a22 * c - m.a21 * s) / det;
        let ny = (-m.a12 * c + m.a11 * s) / det;
        let len = nx.hypot(ny);
        (p, [nx / len, ny / len])
    }

    /// Reference coordinates (u, v) of an image point: r = A⁻¹ (p − t).
    pub fn to_reference(&self, x: f64, y: f64) -> (f64, f64) {
        let (sn, cs) = self.angle.sin_cos();
        let dx = x - self.cx;
        let dy = y - self.cy;
        ((cs * dx + sn * dy) / self.a, (-sn * dx + cs * dy) / self.b)
    }

    /// Approximate signed distance (px) from an image point to the outline, negative inside.
    ///
    /// First-order: (ρ − 1)/|∇ρ| with ρ the normalised radius; exact on circles and accurate
    /// to well below 0.1 px within a pixel of the outline for the head-sized ellipses used here.
    pub fn signed_distance(&self, x: f64, y: f64) -> f64 {
        let (u, v) = self.to_reference(x, y);
        let rho = u.hypot(v);
        if rho < 1e-9 {
            return -self.a.min(self.b);
        }
        let g = ((u / self.a).powi(2) + (v / self.b).powi(2)).sqrt() / rho;
        (rho - 1.0) / g
    }
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
        let o = e.odobez();
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
            let (p, n) = e.point_and_normal(phi);
            assert_relative_eq!(e.signed_distance(p[0], p[1]), 0.0, epsilon = 1e-9);
            // One pixel out along the normal is one pixel away (first-order distance).
            let d = e.signed_distance(p[0] + n[0], p[1] + n[1]);
            assert!((d - 1.0).abs() < 0.05, "distance {d}");
            assert_relative_eq!(n[0].hypot(n[1]), 1.0, epsilon = 1e-12);
        }
    }
}
