//! The estimator's settings and their defaults.

#[cfg(doc)]
use super::{MotionEstimate, MotionEstimator};
use crate::robust::RobustFunction;
use crate::{Error, Result};

/// Settings of the estimator.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Settings {
    /// Maximum number of pyramid levels, including full resolution (default 5: reductions by up to
    /// 16, enough for displacements of ~20 px).
    pub levels: usize,
    /// Pre-smooth level 0 with the [1 4 6 4 1]/16 kernel (default true): it reduces noise in the
    /// gradients and aliasing of fine texture in the interpolation.
    pub presmooth: bool,
    /// Margin in level-0 pixels added around the region's box when pyramids are built for a single
    /// region (default 32). Pixels displaced beyond it are dropped like pixels leaving the image.
    pub margin: usize,
    /// The coarsest level used is the coarsest where the region still holds this many pixels
    /// (default 256).
    pub min_level_pixels: usize,
    /// The robust function (default Tukey biweight, c = 4.6851).
    pub robust: RobustFunction,
    /// Maximum Gauss–Newton iterations per level (default 20).
    pub max_iterations: usize,
    /// Convergence at full resolution: the largest displacement change of the region's box
    /// corners in one iteration, in pixels (default 5e-4).
    pub tolerance: f64,
    /// The same at coarser levels, in that level's pixels (default 0.01).
    pub coarse_tolerance: f64,
    /// Floor on the robust scale, in grey levels (default 0.1), so that noise-free images still get
    /// finite weights.
    pub min_scale: f64,
    /// Levels used when the estimate is warm-started from an initial guess
    /// ([`MotionEstimator::estimate_from`]); default 2 (full resolution and one reduction, enough
    /// to correct a guess that is off by a few pixels).
    #[serde(default = "default_warm_levels")]
    pub warm_levels: usize,
    /// The least [`MotionEstimate::inlier_fraction`] of a [`reliable`](MotionEstimate::reliable)
    /// estimate (default 0.5): the motion found must be that of a majority of the region's pixels
    /// that stay in the image, at the noise scale.
    #[serde(default = "default_min_inlier_fraction")]
    pub min_inlier_fraction: f64,
    /// The least inlier fraction of a re-started estimate that is reliable as the largest group
    /// (default 0.4): when the first fit is not reliable, the estimator re-starts from the
    /// motions that blocks of the region agree on and keeps the fit explaining most pixels; that
    /// fit is reliable below [`min_inlier_fraction`](Self::min_inlier_fraction) when its inlier
    /// fraction, plus the share of pixels that a surface in front of it covers in the second
    /// frame (when the order of the surfaces can be told), reaches this share. A block moving
    /// by a few pixels covers and uncovers pixels that no motion explains, so the dominant
    /// motion may explain less than half of the region.
    #[serde(default = "default_min_plurality_fraction")]
    pub min_plurality_fraction: f64,
    /// Ceiling on the scale of the IRLS weights at the two finest levels, grey levels (default
    /// 8 / 4.6851 ≈ 1.71: with Tukey's c, pixels whose DFD exceeds 8 grey levels get no weight, the
    /// fixed constant of Motion2D). Without it the scale measured at a compromise between two
    /// motions grows with the misfit (4–20 grey levels) and keeps the compromise. It
    /// only acts when the noise scale exceeds it (σ ≳ 4 grey levels per frame with pre-smoothing);
    /// the reported scale, inlier fraction and covariance always use the noise scale.
    #[serde(default = "default_max_scale")]
    pub max_scale: f64,
}

fn default_max_scale() -> f64 {
    8.0 / 4.6851
}

fn default_warm_levels() -> usize {
    2
}

fn default_min_inlier_fraction() -> f64 {
    0.5
}

fn default_min_plurality_fraction() -> f64 {
    0.4
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            levels: 5,
            presmooth: true,
            margin: 32,
            min_level_pixels: 256,
            robust: RobustFunction::default(),
            max_iterations: 20,
            tolerance: 5e-4,
            coarse_tolerance: 0.01,
            min_scale: 0.1,
            warm_levels: default_warm_levels(),
            min_inlier_fraction: default_min_inlier_fraction(),
            min_plurality_fraction: default_min_plurality_fraction(),
            max_scale: default_max_scale(),
        }
    }
}

impl Settings {
    /// A preset for tracking, where an estimate feeds a particle filter's proposal whose noise is
    /// of the order of a pixel: the default settings with both tolerances loosened to 0.1 px (full
    /// resolution: from 5e-4; coarse levels: from 0.01 level pixels) and at most 8 iterations per
    /// level (instead of 20; fewer are too few for a cold start on a fast target). Gauss–Newton's
    /// last step is then ≤ 0.1 px, but the estimate is much closer, and the covariance stays
    /// calibrated, because the final scale and covariance are always taken at Θ̂ (see
    /// `REUSE_STEP`; after a last step of at most `LINEAR_STEP` the residuals at Θ̂ are the last
    /// evaluation's moved to first order, otherwise they are evaluated again). The accuracy and
    /// calibration tests check this preset against the same bounds as the defaults; measured
    /// figures: docs/RESULTS.md, "Motion estimation". Non-convergence is still reported.
    pub fn tracking() -> Self {
        Self {
            tolerance: 0.1,
            coarse_tolerance: 0.1,
            max_iterations: 8,
            ..Self::default()
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the first bad field.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &'static str, reason: String| Err(Error::InvalidSetting { name, reason });
        if self.levels == 0 || self.levels > 16 {
            return bad("levels", format!("{} must be in 1..=16", self.levels));
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", "must be at least 1".into());
        }
        if self.warm_levels == 0 {
            return bad("warm_levels", "must be at least 1".into());
        }
        for (name, v) in [
            ("tolerance", self.tolerance),
            ("coarse_tolerance", self.coarse_tolerance),
            ("min_scale", self.min_scale),
            ("max_scale", self.max_scale),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(name, format!("{v} must be finite and positive"));
            }
        }
        for (name, v) in [
            ("min_inlier_fraction", self.min_inlier_fraction),
            ("min_plurality_fraction", self.min_plurality_fraction),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return bad(name, format!("{v} must be in [0, 1]"));
            }
        }
        self.robust.validate()
    }
}
