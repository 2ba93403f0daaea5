//! Odobez et al. 2003 Eq. 15: from affine motion parameters to the derivative of the tracker state
//! α = (Tx, Ty, s, e), with the covariance propagated through the map's Jacobian.

use nalgebra::{Matrix4, Matrix6, SMatrix};

use crate::{Error, Result};

/// State derivative and its covariance from affine parameters `[a1..a6]` (Odobez Eq. 13, origin at
/// the object centre) and their covariance, for the current scale `s` and eccentricity `e`
/// (docs/MODELS.md): Ṫx = a1, Ṫy = a4, ṡ = s (a2·e + a6)/(1 + e), ė = e (a2 − a6). The map is linear in
/// the parameters, so the propagated covariance J Σ Jᵀ is exact. Cost: a few dozen flops.
///
/// # Errors
/// [`Error::NonFinite`] for a NaN input, [`Error::InvalidSetting`] for s ≤ 0 or e ≤ 0.
///
/// # Examples
/// ```
/// use motion_est::odobez_state_derivative;
/// use nalgebra::Matrix6;
/// let (d, c) = odobez_state_derivative(&[1.0, 0.02, 0.0, -2.0, 0.0, 0.02], &Matrix6::identity(), 30.0, 1.0)?;
/// assert!((d[2] - 0.6).abs() < 1e-12 && d[3].abs() < 1e-12);
/// assert!((c[(3, 3)] - 2.0).abs() < 1e-12);
/// # Ok::<(), motion_est::Error>(())
/// ```
pub fn odobez_state_derivative(
    params: &[f64; 6],
    covariance: &Matrix6<f64>,
    s: f64,
    e: f64,
) -> Result<([f64; 4], Matrix4<f64>)> {
    if let Some(index) = params.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "affine parameters",
            index,
        });
    }
    if let Some(index) = covariance.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "affine covariance",
            index,
        });
    }
    if !(s.is_finite() && s > 0.0 && e.is_finite() && e > 0.0) {
        return Err(Error::InvalidSetting {
            name: "state (s, e)",
            reason: format!("s = {s}, e = {e} must be finite and positive"),
        });
    }
    let [a1, a2, _, a4, _, a6] = *params;
    let k = s / (1.0 + e);
    let d = [a1, a4, k * (a2 * e + a6), e * (a2 - a6)];
    let mut j = SMatrix::<f64, 4, 6>::zeros();
    j[(0, 0)] = 1.0;
    j[(1, 3)] = 1.0;
    j[(2, 1)] = k * e;
    j[(2, 5)] = k;
    j[(3, 1)] = e;
    j[(3, 5)] = -e;
    let c = j * covariance * j.transpose();
    Ok((d, c))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_finite_differences_of_the_ellipse_axes() {
        // An affine flow with a2 = ds_x/s_x and a6 = ds_y/s_y changes s_x = 2es/(1+e) and
        // s_y = 2s/(1+e) (Eq. 11–12) to first order; Eq. 15 must give the matching (ṡ, ė).
        let (s, e) = (40.0, 0.8);
        let (sx, sy) = (2.0 * e * s / (1.0 + e), 2.0 * s / (1.0 + e));
        let (a2, a6) = (1e-6, -2e-6);
        let (sx1, sy1) = (sx * (1.0 + a2), sy * (1.0 + a6));
        // Invert Eq. 11–12: e = sx/sy, s = sy(1+e)/2.
        let e1 = sx1 / sy1;
        let s1 = sy1 * (1.0 + e1) / 2.0;
        let (d, _) =
            odobez_state_derivative(&[0.0, a2, 0.0, 0.0, 0.0, a6], &Matrix6::zeros(), s, e)
                .unwrap();
        assert!((d[2] - (s1 - s)).abs() < 1e-9 * s, "{} vs {}", d[2], s1 - s);
        assert!((d[3] - (e1 - e)).abs() < 1e-9, "{} vs {}", d[3], e1 - e);
    }

    #[test]
    fn covariance_is_propagated() {
        let mut c = Matrix6::zeros();
        c[(1, 1)] = 4.0;
        c[(5, 5)] = 1.0;
        c[(1, 5)] = 0.5;
        c[(5, 1)] = 0.5;
        let (_, p) = odobez_state_derivative(&[0.0; 6], &c, 10.0, 1.0).unwrap();
        // ṡ = 5 a2 + 5 a6: var = 25·4 + 25·1 + 2·25·0.5; ė = a2 − a6: var = 4 + 1 − 2·0.5.
        assert!((p[(2, 2)] - 150.0).abs() < 1e-9);
        assert!((p[(3, 3)] - 4.0).abs() < 1e-9);
        assert!((p[(2, 3)] - (5.0 * 4.0 - 5.0 * 1.0 + 5.0 * 0.5 - 5.0 * 0.5)).abs() < 1e-9);
        assert!(odobez_state_derivative(&[f64::NAN; 6], &c, 10.0, 1.0).is_err());
        assert!(odobez_state_derivative(&[0.0; 6], &c, 10.0, 0.0).is_err());
    }
}
