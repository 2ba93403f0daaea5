//! Odobez's implicit motion likelihood p_c2 ∝ exp(−λ_c d_c) (Eq. 22–23; docs/MODELS.md), d_c the
//! NCC distance between the patch of a hypothesis in the current frame and the patch of its
//! previous state in the previous frame.

use nalgebra::Matrix2;
use serde::{Deserialize, Serialize};

use crate::patch::{NccSettings, ncc_distance, sample_patch_into, unit_disc_grid};
use crate::{Error, Result};
use vision_core::GreyImage;

/// Settings of the implicit motion likelihood p_c2 (Odobez Eq. 22–23).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImplicitMotionSettings {
    /// λ_c of Eq. 22. Odobez does not give it. Default 10: a well-tracked patch has d_c ≈ 0.05–0.2,
    /// one that covers background moving differently d_c ≈ 0.5–1, so the term separates them by
    /// 3–10 nats, comparable to the shape likelihood's range (15 lines × up to 2 nats).
    pub lambda_c: f64,
    /// The reference grid R is an n×n lattice clipped to the disc (default 12: ≈ 113 samples).
    pub grid: usize,
    /// Radius of the disc relative to the contour (default 0.8): the patch stays inside the
    /// object, away from the outline the shape term measures (Odobez §4.4's independence argument).
    pub inner_radius: f64,
    /// How flat patches and samples outside the image are handled.
    pub ncc: NccSettings,
}

impl Default for ImplicitMotionSettings {
    fn default() -> Self {
        Self {
            lambda_c: 10.0,
            grid: 12,
            inner_radius: 0.8,
            ncc: NccSettings::default(),
        }
    }
}

impl ImplicitMotionSettings {
    /// Checks λ_c finite and non-negative, the grid in 2..=64, the radius in (0, 1.5] and the
    /// NCC settings.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the field.
    pub fn validate(&self) -> Result<()> {
        if !(self.lambda_c.is_finite() && self.lambda_c >= 0.0) {
            return Err(Error::InvalidSetting {
                name: "implicit_motion.lambda_c",
                reason: format!("{} must be finite and non-negative", self.lambda_c),
            });
        }
        if !(2..=64).contains(&self.grid) {
            return Err(Error::InvalidSetting {
                name: "implicit_motion.grid",
                reason: format!("{} must be in 2..=64", self.grid),
            });
        }
        if !(self.inner_radius > 0.0 && self.inner_radius <= 1.5) {
            return Err(Error::InvalidSetting {
                name: "implicit_motion.inner_radius",
                reason: format!("{} must be in (0, 1.5]", self.inner_radius),
            });
        }
        self.ncc.validate()
    }
}

/// A patch pose: p = A·r + t.
pub type PatchPose<'a> = (&'a Matrix2<f64>, [f64; 2]);

/// The implicit motion term ln p_c2 = −λ_c d_c (Odobez Eq. 22–23), its grid laid out.
#[derive(Debug, Clone)]
pub struct ImplicitMotionTerm {
    settings: ImplicitMotionSettings,
    grid: Vec<[f64; 2]>,
}

impl ImplicitMotionTerm {
    /// The term with the reference grid R: [`unit_disc_grid`] shrunk to the inner radius.
    ///
    /// # Errors
    /// Invalid settings.
    pub fn new(settings: ImplicitMotionSettings) -> Result<Self> {
        settings.validate()?;
        let r = settings.inner_radius;
        let grid = unit_disc_grid(settings.grid)
            .into_iter()
            .map(|[x, y]| [x * r, y * r])
            .collect();
        Ok(Self { settings, grid })
    }

    /// The settings.
    pub fn settings(&self) -> &ImplicitMotionSettings {
        &self.settings
    }

    /// The number of samples of a patch: the length of each buffer of [`Self::log_likelihood`].
    pub fn patch_len(&self) -> usize {
        self.grid.len()
    }

    /// ln p_c2 = −λ_c d_c: the NCC distance (Eq. 23, as 1 − ρ) between the patch of `now` on
    /// `current` and the patch of `prev` on `previous`, sampled into the caller's buffers
    /// `patch_now` and `patch_prev` ([`Self::patch_len`] each).
    ///
    /// # Errors
    /// As [`sample_patch_into`] and [`ncc_distance`].
    pub fn log_likelihood(
        &self,
        current: GreyImage<'_>,
        previous: GreyImage<'_>,
        now: PatchPose<'_>,
        prev: PatchPose<'_>,
        patch_now: &mut [f32],
        patch_prev: &mut [f32],
    ) -> Result<f64> {
        sample_patch_into(current, &self.grid, now.0, now.1, patch_now)?;
        sample_patch_into(previous, &self.grid, prev.0, prev.1, patch_prev)?;
        let d = ncc_distance(patch_now, patch_prev, &self.settings.ncc)?;
        Ok(-(self.settings.lambda_c * d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_patch_twice_scores_zero_and_a_flat_one_minus_lambda_c() {
        let (w, h) = (40, 40);
        let tex: Vec<f32> = (0..w * h)
            .map(|k| (((k % w) * 7 + (k / w) * 13) % 50) as f32)
            .collect();
        let flat = vec![100.0f32; w * h];
        let term = ImplicitMotionTerm::new(ImplicitMotionSettings::default()).unwrap();
        let n = term.patch_len();
        let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
        let m = Matrix2::new(8.0, 0.0, 0.0, 8.0);
        let view = |d| GreyImage::new(w, h, d).unwrap();
        let pose = (&m, [20.0, 20.0]);
        let same = term
            .log_likelihood(view(&tex), view(&tex), pose, pose, &mut a, &mut b)
            .unwrap();
        assert!(same.abs() < 1e-9, "{same}");
        // A flat patch has no correlation: d_c = 1, the uninformative distance.
        let flat = term
            .log_likelihood(view(&tex), view(&flat), pose, pose, &mut a, &mut b)
            .unwrap();
        assert_eq!(flat, -10.0);
        assert!(
            ImplicitMotionSettings {
                grid: 1,
                ..Default::default()
            }
            .validate()
            .is_err()
        );
    }
}
