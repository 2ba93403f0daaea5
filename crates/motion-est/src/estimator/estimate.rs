//! The result of one estimate.

use nalgebra::{Matrix2, Matrix6, SMatrix};

#[cfg(doc)]
use super::Settings;
use super::{Mat7, Vec7};
use crate::model::ModelSpec;
#[cfg(doc)]
use crate::model::MotionModel;

/// The result of one estimate.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MotionEstimate {
    /// The model estimated.
    pub spec: ModelSpec,
    /// Parameters in level-0 pixels, laid out as in [`MotionModel`], offset last when estimated.
    pub params: Vec<f64>,
    /// Their covariance, row-major `params.len()`², in level-0 units.
    pub covariance: Vec<f64>,
    /// Origin of the coordinates (x, y) in the model, in image pixels.
    pub origin: [f64; 2],
    /// Final robust scale of the (pre-smoothed) DFD, grey levels.
    pub scale: f64,
    /// Standard deviation of the per-frame image noise implied by `scale`, grey levels.
    pub noise_sigma: f64,
    /// Among the region's pixels that stay inside the image at the estimate, the weighted share
    /// whose residual is within the robust function's constant c times the noise scale `scale`
    /// (Tukey: non-zero weight).
    pub inlier_fraction: f64,
    /// Gauss–Newton iterations per level, index 0 = full resolution; 0 for levels not used.
    pub iterations: Vec<usize>,
    /// Whether the full-resolution iterations met the tolerance. Always true in an `Ok` result
    /// of the estimator (a reliable estimate converged); false only in the estimate that
    /// [`Error::Unreliable`](crate::Error::Unreliable) carries.
    pub converged: bool,
    /// Whether the estimate can be trusted as the dominant motion of the region: it
    /// [`converged`](Self::converged), the pixels it explains at the noise scale are at least
    /// [`Settings::min_inlier_fraction`] (default: a majority) of the region's pixels that stay
    /// in the image, and that noise scale is at most twice [`Settings::max_scale`] (a larger one
    /// means that no group of pixels fits at the noise level: the fit sits between motions, and
    /// its inlier fraction is then high only because the scale measures the misfit). After a
    /// re-start from the motions that blocks of the region agree on, the fit explaining most
    /// pixels is also reliable from [`Settings::min_plurality_fraction`] of them, counting the pixels
    /// that a surface in front of it covers in the second frame. `false` when the dominant
    /// motion could not be separated from the rest (a compromise between motions, or a motion
    /// of a minority): treat the estimate as failed; its parameters and covariance do not
    /// describe the region's motion. The estimator returns such an estimate only inside
    /// [`Error::Unreliable`](crate::Error::Unreliable), never as `Ok`.
    #[serde(default)]
    pub reliable: bool,
}

impl MotionEstimate {
    /// The six affine parameters `[a1..a6]` of Odobez Eq. 13 (whatever the model).
    pub fn affine(&self) -> [f64; 6] {
        let p = self.padded();
        let a = self.spec.model.affine_map() * p;
        [a[0], a[1], a[2], a[3], a[4], a[5]]
    }

    /// Covariance of [`affine`](Self::affine).
    pub fn affine_covariance(&self) -> Matrix6<f64> {
        let m = self.spec.model.affine_map();
        m * self.padded_cov() * m.transpose()
    }

    /// Displacement at image point (x, y).
    pub fn displacement(&self, x: f64, y: f64) -> [f64; 2] {
        self.spec
            .model
            .displacement(&self.params, x - self.origin[0], y - self.origin[1])
    }

    /// 2×2 covariance of the displacement at image point (x, y).
    pub fn displacement_covariance(&self, x: f64, y: f64) -> Matrix2<f64> {
        let (dx, dy) = (x - self.origin[0], y - self.origin[1]);
        let g = SMatrix::<f64, 2, 6>::new(1.0, dx, dy, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, dx, dy);
        g * self.affine_covariance() * g.transpose()
    }

    fn padded(&self) -> Vec7 {
        let mut p = Vec7::zeros();
        for (i, v) in self.params.iter().enumerate().take(7) {
            p[i] = *v;
        }
        p
    }

    fn padded_cov(&self) -> Mat7 {
        let n = self.params.len();
        let mut c = Mat7::zeros();
        for i in 0..n.min(7) {
            for j in 0..n.min(7) {
                c[(i, j)] = self.covariance[i * n + j];
            }
        }
        c
    }
}
