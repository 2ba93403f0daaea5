//! Contour templates in reference coordinates: the unit circle (the ellipse template) and a closed
//! uniform cubic B-spline, sampled at n points with outward unit normals.

use nalgebra::Vector2;

use crate::{Affine2, Error, Result};

/// A contour template in reference coordinates.
#[derive(Debug, Clone, PartialEq)]
pub enum Template {
    /// The unit circle: under a pose A, t it becomes the ellipse of [`Affine2::to_ellipse`].
    UnitCircle,
    /// A closed uniform cubic B-spline through these control points (at least 4, not all
    /// collinear), in reference coordinates.
    ClosedBSpline(Vec<[f64; 2]>),
}

/// A template sampled at n points, each with its outward unit normal, in reference coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Contour {
    points: Vec<Vector2<f64>>,
    normals: Vec<Vector2<f64>>,
}

impl Contour {
    /// Samples `template` at `n` points (≥ 3): equal angles on the unit circle starting at angle 0,
    /// equal parameter steps on a B-spline.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when n < 3; [`Error::Degenerate`] for a B-spline with fewer than 4
    /// control points, non-finite control points, zero enclosed area, or a zero tangent.
    pub fn new(template: &Template, n: usize) -> Result<Self> {
        if n < 3 {
            return Err(Error::InvalidSetting {
                name: "n_lines",
                reason: format!("a contour needs at least 3 points, got {n}"),
            });
        }
        match template {
            Template::UnitCircle => Ok(Self::unit_circle(n)),
            Template::ClosedBSpline(ctrl) => Self::bspline(ctrl, n),
        }
    }

    /// The unit circle sampled at `n` equal angles; the outward normal equals the point.
    pub fn unit_circle(n: usize) -> Self {
        let points: Vec<_> = (0..n)
            .map(|i| {
                let u = std::f64::consts::TAU * i as f64 / n as f64;
                Vector2::new(u.cos(), u.sin())
            })
            .collect();
        Self {
            normals: points.clone(),
            points,
        }
    }

    fn bspline(ctrl: &[[f64; 2]], n: usize) -> Result<Self> {
        let m = ctrl.len();
        if m < 4 {
            return Err(Error::Degenerate {
                reason: format!("a closed cubic B-spline needs at least 4 control points, got {m}"),
            });
        }
        if ctrl.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Error::Degenerate {
                reason: "non-finite B-spline control point".into(),
            });
        }
        // The shoelace area of the control polygon fixes the traversal direction; for a positive
        // area the right-hand normal (τy, −τx) points outward (as for the unit circle).
        let area: f64 = (0..m)
            .map(|i| {
                let (p, q) = (ctrl[i], ctrl[(i + 1) % m]);
                p[0] * q[1] - q[0] * p[1]
            })
            .sum::<f64>()
            * 0.5;
        if area.abs() < 1e-12 {
            return Err(Error::Degenerate {
                reason: "B-spline control polygon encloses no area".into(),
            });
        }
        let sign = area.signum();
        let mut points = Vec::with_capacity(n);
        let mut normals = Vec::with_capacity(n);
        for i in 0..n {
            let u = m as f64 * i as f64 / n as f64;
            let j = (u.floor() as usize).min(m - 1);
            let t = u - j as f64;
            let p = |k: usize| {
                let c = ctrl[(j + k) % m];
                Vector2::new(c[0], c[1])
            };
            let (t2, t3) = (t * t, t * t * t);
            // Uniform cubic B-spline basis and its derivative.
            let b = [
                (1.0 - t).powi(3) / 6.0,
                (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
                (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
                t3 / 6.0,
            ];
            let db = [
                -(1.0 - t).powi(2) / 2.0,
                (3.0 * t2 - 4.0 * t) / 2.0,
                (-3.0 * t2 + 2.0 * t + 1.0) / 2.0,
                t2 / 2.0,
            ];
            let pt: Vector2<f64> = (0..4).map(|k| p(k) * b[k]).sum();
            let tau: Vector2<f64> = (0..4).map(|k| p(k) * db[k]).sum();
            let len = tau.norm();
            if len < 1e-12 {
                return Err(Error::Degenerate {
                    reason: format!("zero B-spline tangent at sample {i}"),
                });
            }
            points.push(pt);
            normals.push(Vector2::new(tau.y, -tau.x) * (sign / len));
        }
        Ok(Self { points, normals })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the contour has no points (never true for a constructed contour).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Reference points.
    pub fn points(&self) -> &[Vector2<f64>] {
        &self.points
    }

    /// Reference outward unit normals.
    pub fn normals(&self) -> &[Vector2<f64>] {
        &self.normals
    }

    /// Poses point `i`: returns the image point and its outward unit normal, or `None` for the
    /// normal when A is singular (the contour has collapsed and has no normal there).
    ///
    /// Normals are covectors and transform by A⁻ᵀ = adj(A)ᵀ/det A. Since (A⁻ᵀn)·(A n) = |n|² > 0,
    /// A⁻ᵀn points to the same side as the image of the outward direction, so it stays outward
    /// whatever the sign of det A.
    ///
    /// # Panics
    /// If `i ≥ len()`.
    #[inline]
    pub fn pose_point(&self, pose: &Affine2, i: usize) -> (Vector2<f64>, Option<Vector2<f64>>) {
        let (r, n) = (self.points[i], self.normals[i]);
        let p = pose.apply(r);
        let a = &pose.a;
        let det = a[(0, 0)] * a[(1, 1)] - a[(0, 1)] * a[(1, 0)];
        let m = Vector2::new(
            a[(1, 1)] * n.x - a[(1, 0)] * n.y,
            -a[(0, 1)] * n.x + a[(0, 0)] * n.y,
        ) * det.signum();
        // Plain √(x² + y²): libm's hypot is slow, and |m| is far from overflow for any pose
        // whose contour lies near an image.
        let len = (m.x * m.x + m.y * m.y).sqrt();
        let normal = (det != 0.0 && len > 1e-12 && len.is_finite()).then(|| m / len);
        (p, normal)
    }

    /// [`Self::pose_point`] for every point, into `out` (resized to n): the image point and the
    /// outward unit normal, with (NaN, NaN) for an undefined normal. The same arithmetic as
    /// `pose_point`, bit for bit, written as one branch-free loop so that the square roots
    /// and divisions of consecutive points overlap.
    #[inline(always)]
    pub(crate) fn pose_all(&self, pose: &Affine2, out: &mut Vec<(Vector2<f64>, Vector2<f64>)>) {
        let a = &pose.a;
        let det = a[(0, 0)] * a[(1, 1)] - a[(0, 1)] * a[(1, 0)];
        let sign = det.signum();
        out.resize(self.points.len(), (Vector2::zeros(), Vector2::zeros()));
        for ((o, r), n) in out.iter_mut().zip(&self.points).zip(&self.normals) {
            let p = pose.apply(*r);
            let m = Vector2::new(
                a[(1, 1)] * n.x - a[(1, 0)] * n.y,
                -a[(0, 1)] * n.x + a[(0, 0)] * n.y,
            ) * sign;
            let len = (m.x * m.x + m.y * m.y).sqrt();
            let defined = det != 0.0 && len > 1e-12 && len.is_finite();
            let normal = if defined {
                m / len
            } else {
                Vector2::new(f64::NAN, f64::NAN)
            };
            *o = (p, normal);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn posed_circle_normals_are_outward_and_perpendicular() {
        // On the ellipse (x/a)² + (y/b)² = 1 the outward normal is ∝ (x/a², y/b²).
        for &theta in &[0.0, 0.7, -2.0] {
            for &flip in &[1.0, -1.0] {
                let mut pose = Affine2::from_ellipse(5.0, 6.0, 9.0, 4.0, theta);
                // Mirroring the reference (det A < 0) describes the same ellipse.
                pose.a.column_mut(1).scale_mut(flip);
                let c = Contour::unit_circle(16);
                for i in 0..c.len() {
                    let (p, n) = c.pose_point(&pose, i);
                    let n = n.unwrap();
                    let (s, co) = theta.sin_cos();
                    let d = p - pose.t;
                    let (u, v) = (co * d.x + s * d.y, -s * d.x + co * d.y);
                    let g = Vector2::new(u / 81.0, v / 16.0);
                    let g_img = Vector2::new(co * g.x - s * g.y, s * g.x + co * g.y).normalize();
                    assert_relative_eq!(n, g_img, epsilon = 1e-12);
                }
            }
        }
    }

    #[test]
    fn pose_all_equals_pose_point_bit_for_bit() {
        let spline =
            Template::ClosedBSpline(vec![[1.0, 0.2], [0.1, 1.3], [-1.2, 0.0], [0.0, -0.9]]);
        let poses = [
            Affine2::from_ellipse(5.0, 6.0, 9.0, 4.0, 0.7),
            Affine2::from_wu([1.3, -0.4, 0.2, -0.8, 3.0, -2.0]),
            // Singular: no normals.
            Affine2::from_wu([1.0, 2.0, 2.0, 4.0, 0.0, 0.0]),
            Affine2::from_wu([1e-20, 0.0, 0.0, 1e-20, 1.0, 1.0]),
        ];
        let mut out = Vec::new();
        for template in [Template::UnitCircle, spline] {
            let c = Contour::new(&template, 13).unwrap();
            for pose in &poses {
                c.pose_all(pose, &mut out);
                assert_eq!(out.len(), c.len());
                for (i, (p, n)) in out.iter().enumerate() {
                    let (want_p, want_n) = c.pose_point(pose, i);
                    assert_eq!(*p, want_p);
                    match want_n {
                        Some(want) => assert_eq!(*n, want),
                        None => assert!(n.x.is_nan() && n.y.is_nan()),
                    }
                }
            }
        }
    }

    #[test]
    fn singular_pose_has_no_normal() {
        let pose = Affine2::from_wu([1.0, 2.0, 2.0, 4.0, 0.0, 0.0]);
        assert!(Contour::unit_circle(8).pose_point(&pose, 1).1.is_none());
    }

    #[test]
    fn bspline_normals_point_away_from_centre_either_orientation() {
        let square = vec![[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]];
        let mut rev = square.clone();
        rev.reverse();
        for ctrl in [square, rev] {
            let c = Contour::new(&Template::ClosedBSpline(ctrl), 12).unwrap();
            for (p, n) in c.points().iter().zip(c.normals()) {
                // The symmetric spline is centred on the origin and convex.
                assert!(p.dot(n) > 0.0, "{p} {n}");
                assert_relative_eq!(n.norm(), 1.0, epsilon = 1e-12);
            }
        }
        // At parameter 0 the curve is (P0 + 4 P1 + P2)/6 (basis (1/6, 2/3, 1/6, 0) at t = 0).
        let c = Contour::new(
            &Template::ClosedBSpline(vec![[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]]),
            4,
        )
        .unwrap();
        assert_relative_eq!(c.points()[0], Vector2::new(0.0, 2.0 / 3.0), epsilon = 1e-12);
    }

    #[test]
    fn rejects_degenerate_templates() {
        assert!(Contour::new(&Template::UnitCircle, 2).is_err());
        assert!(Contour::new(&Template::ClosedBSpline(vec![[0.0, 0.0]; 3]), 8).is_err());
        let line = vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]];
        assert!(Contour::new(&Template::ClosedBSpline(line), 8).is_err());
    }
}
