//! The settings of the kinematic prior: the noise distribution and its scales, the velocity
//! retention, the bounds of the shape.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::space::{STATE_SLOTS, ShapeSpace, StateVector};
use crate::{Error, Result};

/// The distribution of the kinematic noise.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseKind {
    /// Gaussian (CONDENSATION's prior and proposal, Odobez M1/M2; Wu).
    Gaussian,
    /// Cauchy, heavy-tailed for abrupt changes (Odobez Eq. 17, M3).
    Cauchy,
}

impl NoiseKind {
    /// Draws one standard variate.
    pub fn sample<R: Rng + ?Sized>(self, rng: &mut R) -> f64 {
        match self {
            NoiseKind::Gaussian => StandardNormal.sample(rng),
            NoiseKind::Cauchy => {
                // Inverse CDF; u in (0, 1) excludes the poles of tan at ±π/2.
                let u: f64 = rng.random_range(f64::EPSILON..1.0 - f64::EPSILON);
                (std::f64::consts::PI * (u - 0.5)).tan()
            }
        }
    }

    /// log density of `x` under scale `sigma`.
    pub fn log_density(self, x: f64, sigma: f64) -> f64 {
        match self {
            NoiseKind::Gaussian => {
                let z = x / sigma;
                -0.5 * z * z - sigma.ln() - 0.5 * (2.0 * std::f64::consts::PI).ln()
            }
            NoiseKind::Cauchy => {
                sigma.ln() - std::f64::consts::PI.ln() - (x * x + sigma * sigma).ln()
            }
        }
    }
}

/// Settings of the kinematic prior.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicsSettings {
    /// Noise distribution. Default Gaussian.
    pub noise: NoiseKind,
    /// σ_T: translation noise in pixels per frame. Default 3 px (Odobez D2).
    pub sigma_translation: f64,
    /// σ_s: scale noise relative to the current scale. Default 0.01 (Odobez Table 1).
    pub sigma_scale: f64,
    /// Noise on the shape (Odobez's aspect ratio e, relative; the off-diagonal terms of Wu's A,
    /// relative to the scale). Default 0.01.
    pub sigma_shape: f64,
    /// ρ, the share of the last velocity carried into the prediction of the translation.
    /// Default 1 (Eq. 17).
    pub velocity_retention: f64,
    /// ρ for the size and shape components (s, e; the linear part of Wu's A). Default 1 (Eq. 17);
    /// below 1 the rate of change of size and shape decays, so that the random walk of their
    /// velocity does not deform the contour over long sequences.
    #[serde(default = "one")]
    pub shape_velocity_retention: f64,
    /// Smallest mean radius a state may take, pixels. Default 2.
    pub min_scale: f64,
    /// The range of the mean radius relative to the initial one (default [0.4, 2.5]): scale is
    /// bounded so that the contour cannot collapse onto, or swell over, a patch of clutter that
    /// happens to fit (seen when the target slides behind an occluder).
    #[serde(default = "default_scale_range")]
    pub scale_range: [f64; 2],
    /// The range of the elongation relative to the initial one (default [0.33, 3]): Odobez's
    /// aspect ratio e/e₀, or for Wu's affine space the ratio of the singular values of A (upper
    /// bound only). Tighter bounds ([0.67, 1.5], scale [0.6, 1.7]) were tried against a contour
    /// that collapses onto a thin occluding bar: the contour then sits at the bounds, no better.
    #[serde(default = "default_aspect_range")]
    pub aspect_range: [f64; 2],
    /// κ of the status HMM's γ | locked density: a truncated exponential ∝ e^{−κγ} on the locked
    /// range instead of Wu's uniform (0, the default: uniform). Drawn by mapping the uniform draw
    /// through the exponential's inverse distribution function, so the random streams do not
    /// change; the hidden variables are drawn from their prior, so no weight term is needed.
    /// κ > 0 pulls the free-target γ̂ below the locked range's mean; no preset uses it (why:
    /// docs/DECISIONS.md).
    #[serde(default)]
    pub locked_gamma_rate: f64,
    /// r, the pull of the size and shape components towards the target's remembered shape per
    /// frame (default 0: the papers' constant-acceleration model; no preset uses it). With r > 0
    /// the prediction of a size or shape component j is x_j + ρ (x_j − x'_j) + r (x̄_j − x_j),
    /// x̄ the shape anchor of `TrackerDynamics::shape_anchor` — Blake & Isard's second-order
    /// shape-space model with a mean shape, the mean being the shape the tracker remembers over
    /// its locked estimates (`reacquire::TrackMemory`, gain 0.05; the initial shape when
    /// reacquisition is off). Without an anchor the prediction is unchanged. It keeps a contour
    /// from shrinking onto the visible sliver of a target sliding behind an occluder, but under a
    /// zooming camera the slowly remembered size is the wrong mean, so it stays off
    /// (docs/DECISIONS.md).
    #[serde(default)]
    pub shape_reversion: f64,
    /// ε, the share of each particle's hidden-chain transitions (β, and α of the status HMM)
    /// drawn uniformly over the states instead of from `T` (default 0: the papers' prior
    /// proposal). A defensive proposal `q = (1 − ε)·T + ε·uniform`: the weight carries
    /// `T / q` (Odobez Eq. 3), so the filter's target is unchanged, while a sticky `T` (a learnt
    /// one, diagonal near 1) keeps particles in every class to switch to (the ratio:
    /// `TrackerDynamics::log_hidden_exploration_ratio`).
    #[serde(default)]
    pub hidden_exploration: f64,
}

impl Default for DynamicsSettings {
    fn default() -> Self {
        Self {
            noise: NoiseKind::Gaussian,
            sigma_translation: 3.0,
            sigma_scale: 0.01,
            sigma_shape: 0.01,
            velocity_retention: 1.0,
            shape_velocity_retention: 1.0,
            min_scale: 2.0,
            scale_range: default_scale_range(),
            aspect_range: default_aspect_range(),
            locked_gamma_rate: 0.0,
            shape_reversion: 0.0,
            hidden_exploration: 0.0,
        }
    }
}

impl DynamicsSettings {
    /// Checks that every σ is finite and positive, ρ in [0, 1] and the minimum scale positive.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the field.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("dynamics.sigma_translation", self.sigma_translation),
            ("dynamics.sigma_scale", self.sigma_scale),
            ("dynamics.sigma_shape", self.sigma_shape),
            ("dynamics.min_scale", self.min_scale),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidSetting {
                    name,
                    reason: format!("{v} must be finite and positive"),
                });
            }
        }
        for (name, [lo, hi]) in [
            ("dynamics.scale_range", self.scale_range),
            ("dynamics.aspect_range", self.aspect_range),
        ] {
            if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= 1.0 && hi >= 1.0) {
                return Err(Error::InvalidSetting {
                    name,
                    reason: format!("[{lo}, {hi}] must satisfy 0 < low ≤ 1 ≤ high"),
                });
            }
        }
        for (name, v) in [
            ("dynamics.velocity_retention", self.velocity_retention),
            (
                "dynamics.shape_velocity_retention",
                self.shape_velocity_retention,
            ),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(Error::InvalidSetting {
                    name,
                    reason: format!("{v} must be in [0, 1]"),
                });
            }
        }
        if !(0.0..1.0).contains(&self.hidden_exploration) {
            return Err(Error::InvalidSetting {
                name: "dynamics.hidden_exploration",
                reason: format!("{} must be in [0, 1)", self.hidden_exploration),
            });
        }
        if !(0.0..=1.0).contains(&self.shape_reversion) {
            return Err(Error::InvalidSetting {
                name: "dynamics.shape_reversion",
                reason: format!("{} must be in [0, 1]", self.shape_reversion),
            });
        }
        if !(self.locked_gamma_rate.is_finite() && self.locked_gamma_rate >= 0.0) {
            return Err(Error::InvalidSetting {
                name: "dynamics.locked_gamma_rate",
                reason: format!("{} must be finite and non-negative", self.locked_gamma_rate),
            });
        }
        Ok(())
    }

    /// The per-component noise scales at state `x`.
    pub fn sigmas(&self, space: ShapeSpace, x: &StateVector) -> StateVector {
        let s = space.scale(x).max(self.min_scale);
        match space {
            ShapeSpace::Odobez => [
                self.sigma_translation,
                self.sigma_translation,
                self.sigma_scale * s,
                self.sigma_shape * x[3].abs().max(0.25),
                1.0,
                1.0,
            ],
            ShapeSpace::Affine => [
                self.sigma_scale * s,
                self.sigma_shape * s,
                self.sigma_shape * s,
                self.sigma_scale * s,
                self.sigma_translation,
                self.sigma_translation,
            ],
        }
    }

    /// The deterministic AR2 prediction x_{k−1} + ρ (x_{k−1} − x_{k−2}) in `space`, with the
    /// size and shape components pulled towards `anchor` by [`DynamicsSettings::shape_reversion`].
    pub fn predict(
        &self,
        space: ShapeSpace,
        now: &StateVector,
        prev: &StateVector,
        anchor: Option<&StateVector>,
    ) -> StateVector {
        let mut out = [0.0; STATE_SLOTS];
        for j in 0..STATE_SLOTS {
            let translation = space.is_translation(j);
            let rho = if translation {
                self.velocity_retention
            } else {
                self.shape_velocity_retention
            };
            out[j] = now[j] + rho * (now[j] - prev[j]);
            if let (false, Some(a)) = (translation, anchor) {
                out[j] += self.shape_reversion * (a[j] - now[j]);
            }
        }
        out
    }
}

fn one() -> f64 {
    1.0
}

fn default_scale_range() -> [f64; 2] {
    [0.4, 2.5]
}

fn default_aspect_range() -> [f64; 2] {
    [0.33, 3.0]
}
