//! The observation models a tracker can multiply together, and their evaluation on one frame.
//!
//! The likelihood of a particle is a sum of log terms, each evaluated by the crate that
//! implements its equation (docs/MODELS.md):
//!
//! - Odobez's shape likelihood p_sh (Eq. 19), `contour_obs::OdobezLikelihood`;
//! - the implicit motion likelihood p_c2 = exp(−λ_c d_c) (Eq. 22–23), d_c = 1 − ρ the NCC distance
//!   between the patch of c_k in z_k and the patch of c_{k−1} in z_{k−1},
//!   [`motion_est::ImplicitMotionTerm`];
//! - the motion consistency p_c1 = N(α̂_k; α_k, Λ̂_k) (Eq. 21), which cancels against Odobez's
//!   motion proposal (Eq. 24) but can be used with any proposal; here, since it reads the
//!   particle's cluster;
//! - Wu's Poisson-clutter likelihood with the particle's λ and γ (Wu Eq. 1–6, 11–12) in the
//!   occlusion form chosen by [`LikelihoodSettings::occlusion_form`], [`contour_obs::WuTerm`].

pub use contour_obs::ReferenceLines;
use contour_obs::{
    MeasurementLines, OcclusionForm, OdobezLikelihood, OdobezSettings, Template, WuSettings,
    WuTerm, WuTermWorkspace,
};
pub use motion_est::ImplicitMotionSettings;
use motion_est::ImplicitMotionTerm;
use serde::{Deserialize, Serialize};
use vision_core::GreyImage;

use crate::particle::Particle;
use crate::proposal::{ClusterMotion, log_motion_consistency};
use crate::space::ShapeSpace;
use crate::{Error, Result};

/// Which likelihood terms a tracker multiplies.
///
/// In a configuration file (JSON or TOML, `track run --config`) Wu's occlusion form is one
/// table, e.g. in TOML
///
/// ```toml
/// [likelihood.occlusion_form]
/// form = "independent"          # or "arc", "neutral_arc", "ratio"
/// unknown_occluder_share = 0.5  # independent and arc only
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LikelihoodSettings {
    /// Odobez's shape likelihood (Eq. 19).
    pub shape: Option<OdobezSettings>,
    /// Odobez's implicit motion likelihood p_c2 (Eq. 22–23).
    pub implicit_motion: Option<ImplicitMotionSettings>,
    /// Odobez's motion consistency p_c1 (Eq. 21); needs motion estimates (any proposal).
    pub motion_consistency: bool,
    /// Wu's clutter (and occlusion) likelihood (Eq. 1–6, 11–12).
    pub clutter: Option<WuSettings>,
    /// The share of each measurement line on which background clutter can appear, in (0, 1]
    /// (default 1, Wu Eq. 1: the whole line; see [`contour_obs::WuTerm::clutter_line_fraction`]).
    /// The presets use 0.5 ([`crate::config::CLUTTER_LINE_FRACTION`]). Anything but 1 needs
    /// [`LikelihoodSettings::clutter`].
    #[serde(default = "one")]
    pub clutter_line_fraction: f64,
    /// How Wu's likelihood reads the particle's γ (default: Wu Eq. 11–12 as printed, each line
    /// hidden independently, no unknown occluder). Anything but the default needs
    /// [`LikelihoodSettings::clutter`]. See [`OcclusionForm`] for the forms.
    #[serde(default)]
    pub occlusion_form: OcclusionForm,
}

fn one() -> f64 {
    1.0
}

impl Default for LikelihoodSettings {
    fn default() -> Self {
        Self {
            shape: None,
            implicit_motion: None,
            motion_consistency: false,
            clutter: None,
            clutter_line_fraction: 1.0,
            occlusion_form: OcclusionForm::default(),
        }
    }
}

impl LikelihoodSettings {
    /// Checks every term, that at least one looks at the image, and that the settings of Wu's
    /// likelihood other than their defaults (line fraction, occlusion form) come with it.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`], or the error of the crate that owns the term's settings.
    pub fn validate(&self) -> Result<()> {
        if self.shape.is_none() && self.implicit_motion.is_none() && self.clutter.is_none() {
            return Err(Error::InvalidSetting {
                name: "likelihood",
                reason: "at least one of shape, implicit_motion or clutter is needed".into(),
            });
        }
        if self.clutter.is_none() && self.clutter_line_fraction != 1.0 {
            return Err(Error::InvalidSetting {
                name: "likelihood.clutter_line_fraction",
                reason: format!(
                    "{} is a setting of Wu's likelihood, which is off (no `clutter`)",
                    self.clutter_line_fraction
                ),
            });
        }
        if self.clutter.is_none() && self.occlusion_form != OcclusionForm::default() {
            return Err(Error::InvalidSetting {
                name: "likelihood.occlusion_form",
                reason: format!(
                    "{:?} is a form of Wu's likelihood, which is off (no `clutter`)",
                    self.occlusion_form
                ),
            });
        }
        if let Some(s) = &self.shape {
            s.validate()?;
        }
        if let Some(w) = &self.clutter {
            w.validate()?;
        }
        self.occlusion_form.validate()?;
        contour_obs::validate_clutter_line_fraction(self.clutter_line_fraction)?;
        if let Some(m) = &self.implicit_motion {
            m.validate()?;
        }
        Ok(())
    }
}

/// The built likelihood terms (templates sampled, grids laid out), and a fresh set of their
/// workspaces that every batch copies.
#[derive(Debug, Clone)]
pub struct LikelihoodModel {
    space: ShapeSpace,
    shape: Option<OdobezLikelihood>,
    implicit: Option<ImplicitMotionTerm>,
    motion_consistency: bool,
    clutter: Option<WuTerm>,
    scratch: Scratch,
}

impl LikelihoodModel {
    /// Builds the terms for the unit-circle template, and their workspaces.
    ///
    /// # Errors
    /// Invalid settings, or a workspace that cannot be built: the error is the model's, never
    /// a term silently missing from the particles' likelihood.
    pub fn new(space: ShapeSpace, settings: &LikelihoodSettings) -> Result<Self> {
        settings.validate()?;
        let template = Template::UnitCircle;
        let shape = settings
            .shape
            .map(|s| OdobezLikelihood::new(s, &template))
            .transpose()?;
        let implicit = settings
            .implicit_motion
            .map(ImplicitMotionTerm::new)
            .transpose()?;
        let clutter = settings
            .clutter
            .map(|w| {
                let fraction = settings.clutter_line_fraction;
                WuTerm::new(w, settings.occlusion_form, fraction, &template)
            })
            .transpose()?;
        let patch = implicit.as_ref().map_or(0, ImplicitMotionTerm::patch_len);
        let scratch = Scratch {
            shape_lines: shape.as_ref().map(|s| s.workspace()).transpose()?,
            clutter: clutter.as_ref().map(WuTerm::workspace).transpose()?,
            patch_now: vec![0.0; patch],
            patch_prev: vec![0.0; patch],
        };
        Ok(Self {
            space,
            shape,
            implicit,
            motion_consistency: settings.motion_consistency,
            clutter,
            scratch,
        })
    }

    /// The edge counts and observed lengths of the lines of state `x` on `image` into `out`
    /// (cleared first; left empty unless the occlusion form reads them,
    /// [`OcclusionForm::needs_reference`]): the reference lines of
    /// [`FrameObservation::reference`].
    ///
    /// # Errors
    /// A non-finite state.
    pub fn reference_counts(
        &self,
        image: &GreyImage<'_>,
        x: &crate::space::StateVector,
        out: &mut ReferenceLines,
    ) -> Result<()> {
        match &self.clutter {
            Some(wu) => Ok(wu.reference_lines(image, &self.space.pose(x), out)?),
            None => {
                out.clear();
                Ok(())
            }
        }
    }
}

/// Per-thread scratch buffers of the likelihood terms: a copy of [`LikelihoodModel`]'s fresh
/// set, with a workspace exactly for each term the model has.
#[derive(Debug, Clone)]
struct Scratch {
    shape_lines: Option<MeasurementLines>,
    clutter: Option<WuTermWorkspace>,
    patch_now: Vec<f32>,
    patch_prev: Vec<f32>,
}

/// The likelihood of one frame, ready for the particle filter.
#[derive(Debug, Clone, Copy)]
pub struct FrameObservation<'a> {
    /// The terms.
    pub model: &'a LikelihoodModel,
    /// The current frame z_k.
    pub current: GreyImage<'a>,
    /// The previous frame z_{k−1} (for p_c2).
    pub previous: GreyImage<'a>,
    /// Cluster motions (for p_c1).
    pub clusters: &'a [ClusterMotion],
    /// The lines at the tracker's last estimate on the current frame (read by the occlusion
    /// forms that need them, [`OcclusionForm::needs_reference`]; empty otherwise).
    pub reference: &'a ReferenceLines,
}

impl FrameObservation<'_> {
    fn scratch(&self) -> Scratch {
        self.model.scratch.clone()
    }

    /// The log-likelihood of one particle: the sum of the log terms the model enables (Odobez
    /// Eq. 18, 20); −∞ when a term cannot be computed for it (a pose that is not finite), so
    /// that such a particle simply dies.
    fn evaluate(&self, p: &Particle, scratch: &mut Scratch) -> f64 {
        let m = self.model;
        let pose = m.space.pose(&p.now);
        let mut total = 0.0;
        // Odobez's shape likelihood p_sh (Eq. 19), by contour-obs.
        if let (Some(shape), Some(ws)) = (&m.shape, scratch.shape_lines.as_mut()) {
            match shape.log_likelihood(ws, &self.current, &pose) {
                Ok(v) => total += v,
                Err(_) => return f64::NEG_INFINITY,
            }
        }
        // Wu's contour likelihood in its occlusion form (Wu Eq. 1–6, 11–12), by contour-obs.
        if let (Some(wu), Some(ws)) = (&m.clutter, scratch.clutter.as_mut()) {
            let (lambda, gamma) = (p.clutter.lambda, p.gamma());
            match wu.log_likelihood(ws, &self.current, &pose, lambda, gamma, self.reference) {
                Ok(v) => total += v,
                Err(_) => return f64::NEG_INFINITY,
            }
        }
        // Odobez's implicit motion likelihood p_c2 (Eq. 22–23), by motion-est.
        if let Some(implicit) = &m.implicit {
            let pose_prev = m.space.pose(&p.prev);
            let (now_view, prev_view) = (self.current, self.previous);
            match implicit.log_likelihood(
                now_view,
                prev_view,
                (&pose.a, [pose.t.x, pose.t.y]),
                (&pose_prev.a, [pose_prev.t.x, pose_prev.t.y]),
                &mut scratch.patch_now,
                &mut scratch.patch_prev,
            ) {
                Ok(v) => total += v,
                Err(_) => return f64::NEG_INFINITY,
            }
        }
        // Odobez's motion consistency p_c1 (Eq. 21), here: it reads the particle's cluster.
        if m.motion_consistency {
            total += log_motion_consistency(m.space, self.clusters, p);
        }
        total
    }
}

impl smc_core::Observation for FrameObservation<'_> {
    type State = Particle;

    fn log_likelihood(&self, state: &Particle) -> f64 {
        self.evaluate(state, &mut self.scratch())
    }

    /// One set of scratch buffers per batch (per chunk on the parallel path), none per particle.
    fn log_likelihood_batch(&self, states: &[Particle], out: &mut [f64]) {
        let mut scratch = self.scratch();
        for (s, o) in states.iter().zip(out.iter_mut()) {
            *o = self.evaluate(s, &mut scratch);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn share_outside_the_unit_interval_is_rejected() {
        let settings = LikelihoodSettings {
            clutter: Some(WuSettings::default()),
            occlusion_form: OcclusionForm::Independent {
                unknown_occluder_share: 1.5,
            },
            ..LikelihoodSettings::default()
        };
        assert!(settings.validate().is_err());
    }

    #[test]
    fn a_line_fraction_without_wu_likelihood_is_rejected_by_name() {
        let settings = LikelihoodSettings {
            shape: Some(OdobezSettings::default()),
            clutter_line_fraction: 0.5,
            ..LikelihoodSettings::default()
        };
        let err = settings.validate().unwrap_err().to_string();
        assert!(err.contains("likelihood.clutter_line_fraction"), "{err}");
        let bad_fraction = LikelihoodSettings {
            clutter: Some(WuSettings::default()),
            clutter_line_fraction: 1.5,
            ..LikelihoodSettings::default()
        };
        let err = bad_fraction.validate().unwrap_err().to_string();
        assert!(err.contains("clutter_line_fraction"), "{err}");
    }

    #[test]
    fn an_occlusion_form_without_wu_likelihood_is_rejected_by_name() {
        for form in [
            OcclusionForm::Ratio,
            OcclusionForm::NeutralArc,
            OcclusionForm::Arc {
                unknown_occluder_share: 0.0,
            },
            OcclusionForm::Independent {
                unknown_occluder_share: 0.5,
            },
        ] {
            let settings = LikelihoodSettings {
                shape: Some(OdobezSettings::default()),
                occlusion_form: form,
                ..LikelihoodSettings::default()
            };
            let err = settings.validate().unwrap_err().to_string();
            assert!(err.contains("likelihood.occlusion_form"), "{err}");
            // With Wu's likelihood the same form is valid.
            let with_wu = LikelihoodSettings {
                clutter: Some(WuSettings::default()),
                ..settings
            };
            assert!(with_wu.validate().is_ok(), "{form:?}");
        }
    }

    #[test]
    fn the_occlusion_form_loads_from_json_and_the_old_booleans_are_refused() {
        let settings = LikelihoodSettings {
            clutter: Some(WuSettings::default()),
            occlusion_form: OcclusionForm::Arc {
                unknown_occluder_share: 0.25,
            },
            ..LikelihoodSettings::default()
        };
        let json = serde_json::to_string(&settings).unwrap();
        assert!(json.contains(r#""occlusion_form":{"form":"arc","unknown_occluder_share":0.25}"#));
        let back: LikelihoodSettings = serde_json::from_str(&json).unwrap();
        assert_eq!(back, settings);
        let s: LikelihoodSettings =
            serde_json::from_str(r#"{"occlusion_form": {"form": "ratio"}}"#).unwrap();
        assert_eq!(s.occlusion_form, OcclusionForm::Ratio);
        // The share is not a parameter of the neutral arc: refused, not ignored.
        let bad = r#"{"occlusion_form": {"form": "neutral_arc", "unknown_occluder_share": 0.5}}"#;
        assert!(serde_json::from_str::<LikelihoodSettings>(bad).is_err());
        // The booleans of the earlier shape are refused with the field's name.
        let old = r#"{"occlusion_arc": true}"#;
        let err = serde_json::from_str::<LikelihoodSettings>(old)
            .unwrap_err()
            .to_string();
        assert!(err.contains("occlusion_arc"), "{err}");
    }
}
