//! Settings of the region tracker, with their defaults and `validate()`.

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// Everything that defines the region tracker ([`crate::region`]). Every field has a default
/// (`#[serde(default)]`), so a configuration file may give only what it changes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RegionSettings {
    /// Geometric-mean side of the target in working pixels: every frame is read at the scale that
    /// maps the current target to this size (never above full resolution), so the cost of a
    /// frame does not depend on the target's size in pixels. Default 32.
    pub working_size: f64,
    /// Half-size of the search window around the predicted target, in target half-axes (default
    /// 3: the window is three times the target's box each way).
    pub search: f64,
    /// Hue and saturation bins of the colour histogram (each; default 8); grey frames use
    /// `grey_bins`.
    pub hs_bins: usize,
    /// Value bins for unsaturated or dark pixels, and grey-level bins of a grey frame (default 8
    /// and twice that for grey frames).
    pub value_bins: usize,
    /// Outer ellipse of the ring that the colour contrast compares the inside with, in
    /// half-axes of the hypothesis (default 1.5).
    pub contrast_ring: f64,
    /// Weight of the colour log-ratio term, nats per unit of mean log-ratio (default 12).
    pub colour_weight: f64,
    /// Weight of the contour-gradient term, nats per unit of normalised gradient (default 1).
    pub gradient_weight: f64,
    /// Weight of the grey template term, nats per unit of normalised cross-correlation
    /// (Odobez Eq. 23's ρ) between the hypothesis' patch and the target's template (default 40).
    pub template_weight: f64,
    /// Learning rate of the template from locked frames (default 0.05).
    pub template_rate: f64,
    /// Smallest effective sample size after weighting, as a fraction of N: the likelihood is
    /// tempered (raised to the smallest power ≤ 1 that keeps this ESS) so that the weights never
    /// collapse onto one particle (default 0.3).
    pub min_ess_fraction: f64,
    /// Standard deviation of the centre's random walk, as a fraction of the target's
    /// geometric-mean half-size (default 0.15).
    pub sigma_position: f64,
    /// Probability that a particle takes a long jump of four times `sigma_position` (default
    /// 0.15): fast motion without a wide everyday spread.
    pub jump_probability: f64,
    /// Standard deviation of the log-scale random walk (default 0.01).
    pub sigma_scale: f64,
    /// Pull of the log-scale back towards the first frame's scale, per frame (default 0.02): the
    /// colour contrast prefers the whole head to a face box, and without the pull the estimate
    /// grows over hair and neck.
    pub scale_reversion: f64,
    /// Standard deviation of the log-aspect random walk (default 0.01).
    pub sigma_aspect: f64,
    /// Share of the velocity of the estimate carried into the prediction (default 0.5).
    pub velocity_retention: f64,
    /// Learning rate of the target colour model from locked frames (default 0.02).
    pub target_rate: f64,
    /// Learning rate of the background colour model (default 0.2).
    pub background_rate: f64,
    /// Probability of staying locked from one frame to the next in the lost/locked chain
    /// (default 0.95); the lost state's is the same.
    pub status_persistence: f64,
    /// Share of the particles drawn around the best colour contrast found by a dense search of
    /// the window (a data-driven component of the prior, as the detections of Okuma et al.'s
    /// boosted particle filter; default 0.2): fast motion is found where the random walk does
    /// not reach.
    pub detection_share: f64,
    /// Share of the particles drawn around the dense search's best centre while the target is
    /// believed lost, scaled by P(lost); the window is then the whole frame (default 0.5).
    pub reacquire_share: f64,
}

impl Default for RegionSettings {
    fn default() -> Self {
        Self {
            working_size: 32.0,
            search: 3.0,
            hs_bins: 8,
            value_bins: 8,
            contrast_ring: 1.5,
            colour_weight: 12.0,
            gradient_weight: 1.0,
            template_weight: 40.0,
            template_rate: 0.05,
            min_ess_fraction: 0.3,
            sigma_position: 0.15,
            jump_probability: 0.15,
            sigma_scale: 0.01,
            sigma_aspect: 0.01,
            scale_reversion: 0.02,
            velocity_retention: 0.5,
            target_rate: 0.02,
            background_rate: 0.2,
            status_persistence: 0.95,
            detection_share: 0.2,
            reacquire_share: 0.5,
        }
    }
}

fn check(name: &'static str, ok: bool, reason: &str) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::InvalidSetting {
            name,
            reason: reason.to_owned(),
        })
    }
}

fn unit(v: f64) -> bool {
    (0.0..=1.0).contains(&v)
}

impl RegionSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the first invalid field.
    pub fn validate(&self) -> Result<()> {
        check(
            "region.working_size",
            (8.0..=256.0).contains(&self.working_size),
            "must be between 8 and 256 working pixels",
        )?;
        check(
            "region.search",
            (1.0..=20.0).contains(&self.search),
            "must be between 1 and 20 half-axes",
        )?;
        check(
            "region.contrast_ring",
            (1.05..=4.0).contains(&self.contrast_ring),
            "must be between 1.05 and 4 half-axes",
        )?;
        check(
            "region.hs_bins",
            (2..=32).contains(&self.hs_bins),
            "must be between 2 and 32",
        )?;
        check(
            "region.value_bins",
            (2..=64).contains(&self.value_bins),
            "must be between 2 and 64",
        )?;
        for (name, v) in [
            ("region.colour_weight", self.colour_weight),
            ("region.gradient_weight", self.gradient_weight),
            ("region.template_weight", self.template_weight),
        ] {
            check(
                name,
                v.is_finite() && (0.0..=1e3).contains(&v),
                "must be in [0, 1000]",
            )?;
        }
        check(
            "region.colour_weight",
            self.colour_weight + self.gradient_weight + self.template_weight > 0.0,
            "the colour, gradient and template weights cannot all be 0",
        )?;
        check(
            "region.min_ess_fraction",
            unit(self.min_ess_fraction),
            "must be in [0, 1]",
        )?;
        for (name, v) in [
            ("region.sigma_position", self.sigma_position),
            ("region.sigma_scale", self.sigma_scale),
            ("region.sigma_aspect", self.sigma_aspect),
        ] {
            check(
                name,
                v.is_finite() && (0.0..=2.0).contains(&v),
                "must be in [0, 2]",
            )?;
        }
        for (name, v) in [
            ("region.jump_probability", self.jump_probability),
            ("region.velocity_retention", self.velocity_retention),
            ("region.target_rate", self.target_rate),
            ("region.template_rate", self.template_rate),
            ("region.scale_reversion", self.scale_reversion),
            ("region.background_rate", self.background_rate),
            ("region.reacquire_share", self.reacquire_share),
            ("region.detection_share", self.detection_share),
        ] {
            check(name, unit(v), "must be in [0, 1]")?;
        }
        check(
            "region.status_persistence",
            self.status_persistence > 0.5 && self.status_persistence < 1.0,
            "must be in (0.5, 1)",
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_are_named() {
        RegionSettings::default().validate().unwrap();
        let bad = RegionSettings {
            hs_bins: 1,
            ..RegionSettings::default()
        };
        assert!(bad.validate().unwrap_err().to_string().contains("hs_bins"));
        let nan = RegionSettings {
            sigma_scale: f64::NAN,
            ..RegionSettings::default()
        };
        assert!(
            nan.validate()
                .unwrap_err()
                .to_string()
                .contains("sigma_scale")
        );
        let none = RegionSettings {
            colour_weight: 0.0,
            gradient_weight: 0.0,
            template_weight: 0.0,
            ..RegionSettings::default()
        };
        assert!(none.validate().is_err());
    }
}
