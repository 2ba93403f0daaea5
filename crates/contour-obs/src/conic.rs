//! Ellipse template by an algebraic conic fit to points (Wu §6: "a shape template was initialized
//! by conics fitting").

use nalgebra::{Matrix6, Vector6};
use vision_core::Ellipse;

use crate::affine::sym2_eigen;

use crate::{Error, Result};

/// Fits the conic A x² + B xy + C y² + D x + E y + F = 0 to `points` by algebraic least squares
/// (the unit-norm coefficient vector minimising Σ residual², on centred and scaled coordinates for
/// conditioning) and returns it as an ellipse with a ≥ b and θ ∈ (−π/2, π/2]. Exact for points
/// that lie on an ellipse.
///
/// # Errors
/// [`Error::NonFinite`] for a non-finite point; [`Error::Degenerate`] with fewer than 5 points or
/// when the best conic is not a real ellipse (a hyperbola, a parabola, a line pair).
pub fn fit_ellipse(points: &[[f64; 2]]) -> Result<Ellipse> {
    if let Some(index) = points
        .iter()
        .position(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(Error::NonFinite {
            what: "conic fit point",
            index,
        });
    }
    if points.len() < 5 {
        return Err(Error::Degenerate {
            reason: format!("a conic fit needs at least 5 points, got {}", points.len()),
        });
    }
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(sx, sy), p| (sx + p[0] / n, sy + p[1] / n));
    let scale = (points
        .iter()
        .map(|p| (p[0] - mx).powi(2) + (p[1] - my).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    if scale <= 0.0 {
        return Err(Error::Degenerate {
            reason: "all conic fit points coincide".into(),
        });
    }
    let mut scatter = Matrix6::<f64>::zeros();
    for p in points {
        let (x, y) = ((p[0] - mx) / scale, (p[1] - my) / scale);
        let row = Vector6::new(x * x, x * y, y * y, x, y, 1.0);
        scatter += row * row.transpose();
    }
    let eig = scatter.symmetric_eigen();
    let imin = eig.eigenvalues.imin();
    let c = eig.eigenvectors.column(imin);
    let (mut a, mut b, mut cc, d, e, f) = (c[0], c[1], c[2], c[3], c[4], c[5]);
    let disc = 4.0 * a * cc - b * b;
    if disc <= 1e-12 * (a * a + b * b + cc * cc) {
        return Err(Error::Degenerate {
            reason: "the fitted conic is not an ellipse".into(),
        });
    }
    // Centre: gradient of the conic vanishes.
    let cx = (b * e - 2.0 * cc * d) / disc;
    let cy = (b * d - 2.0 * a * e) / disc;
    let mut fc = a * cx * cx + b * cx * cy + cc * cy * cy + d * cx + e * cy + f;
    if fc > 0.0 {
        // Make the quadratic form positive definite so that the ellipse is {form = −fc > 0}.
        (a, b, cc) = (-a, -b, -cc);
        fc = -fc;
    }
    let (l1, l2, theta1) = sym2_eigen(a, 0.5 * b, cc);
    if !(l2 > 0.0 && fc < 0.0) {
        return Err(Error::Degenerate {
            reason: "the fitted conic is an imaginary or degenerate ellipse".into(),
        });
    }
    // The smaller eigenvalue belongs to the major axis, perpendicular to λ1's eigenvector.
    let major = (-fc / l2).sqrt() * scale;
    let minor = (-fc / l1).sqrt() * scale;
    let mut theta = theta1 + std::f64::consts::FRAC_PI_2;
    if theta > std::f64::consts::FRAC_PI_2 {
        theta -= std::f64::consts::PI;
    }
    Ok(Ellipse {
        cx: cx * scale + mx,
        cy: cy * scale + my,
        a: major,
        b: minor,
        angle: theta,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn recovers_an_exact_ellipse() {
        let (cx, cy, a, b, th) = (120.0, 80.0, 30.0, 12.0, 0.6f64);
        let pts: Vec<[f64; 2]> = (0..9)
            .map(|k| {
                // Uneven spacing over part of the ellipse: the fit must not depend on coverage.
                let u = 0.3 + 0.55 * k as f64;
                let (x, y) = (a * u.cos(), b * u.sin());
                [
                    cx + x * th.cos() - y * th.sin(),
                    cy + x * th.sin() + y * th.cos(),
                ]
            })
            .collect();
        let e = fit_ellipse(&pts).unwrap();
        for (got, want) in [(e.cx, cx), (e.cy, cy), (e.a, a), (e.b, b), (e.angle, th)] {
            assert_relative_eq!(got, want, epsilon = 1e-7);
        }
    }

    #[test]
    fn rejects_non_ellipses() {
        let line: Vec<[f64; 2]> = (0..6).map(|k| [k as f64, 2.0 * k as f64]).collect();
        assert!(fit_ellipse(&line).is_err());
        let hyperbola: Vec<[f64; 2]> = (1..8).map(|k| [k as f64, 1.0 / k as f64]).collect();
        assert!(fit_ellipse(&hyperbola).is_err());
        assert!(fit_ellipse(&[[0.0, 0.0]; 4]).is_err());
        assert!(fit_ellipse(&[[f64::NAN, 0.0]; 6]).is_err());
    }
}
