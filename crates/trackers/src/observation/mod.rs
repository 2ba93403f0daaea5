//! The observation terms a tracker adds together, and their evaluation on one frame.
//!
//! Every term is an [`ObservationTerm`]: it adds its log-likelihood of each particle to the
//! particle's log weight, so the weight is their product (Odobez Eq. 18, 20). One file per term,
//! each with the equation it implements (docs/MODELS.md):
//!
//! - [`shape`]: Odobez's shape likelihood p_sh (Eq. 19), `contour_obs::OdobezLikelihood`;
//! - [`clutter`]: Wu's Poisson-clutter likelihood with the particle's λ and γ (Wu Eq. 1–6,
//!   11–12) in the occlusion form [`LikelihoodSettings::occlusion_form`], `contour_obs::WuTerm`;
//! - [`implicit_motion`]: Odobez's implicit motion likelihood p_c2 = exp(−λ_c d_c) (Eq. 22–23),
//!   [`motion_est::ImplicitMotionTerm`];
//! - [`motion_consistency`]: Odobez's motion consistency p_c1 = N(α̂_k; α_k, Λ̂_k) (Eq. 21);
//! - [`colour_contrast`], [`template`], [`contour_contrast`]: the appearance terms
//!   ([`crate::appearance`]).
//!
//! A term of your own implements [`ObservationTerm`] and joins a tracker through
//! [`crate::build_with_terms`] (`crates/trackers/examples/custom_term.rs`).

pub mod clutter;
pub mod colour_contrast;
pub mod contour_contrast;
pub mod implicit_motion;
pub mod motion_consistency;
pub mod shape;
pub mod template;

pub use contour_obs::ReferenceLines;
use contour_obs::{OcclusionForm, OdobezSettings, Template, WuSettings};
pub use motion_est::ImplicitMotionSettings;
use serde::{Deserialize, Serialize};
use vision_core::GreyImage;

use crate::appearance::{Appearance, AppearanceSettings};
use crate::particle::Particle;
use crate::proposal::ClusterMotion;
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
    /// Whether no term that looks at the image is on (a tracker then needs its appearance
    /// terms, [`crate::TrackerConfig::appearance`]).
    pub fn is_empty(&self) -> bool {
        self.shape.is_none() && self.implicit_motion.is_none() && self.clutter.is_none()
    }

    /// Checks every term, and that the settings of Wu's likelihood other than their defaults
    /// (line fraction, occlusion form) come with it.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`], or the error of the crate that owns the term's settings.
    pub fn validate(&self) -> Result<()> {
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

/// One factor of the likelihood p(z_k | x_k): a log-likelihood per particle, added to the
/// particle's log weight.
pub trait ObservationTerm: std::fmt::Debug + Send + Sync {
    /// The term's name, for messages and docs (`"odobez shape (Eq. 19)"`).
    fn name(&self) -> &'static str;

    /// Adds log p_term(z_k | `particles[i]`) to `out[i]` for every particle: element-wise (the
    /// engine may call it on any chunk of the set, from several threads), −∞ for a particle the
    /// term cannot score (a pose that is not finite), never NaN or +∞.
    fn add_log_likelihoods(
        &self,
        frame: &FrameContext<'_>,
        particles: &[Particle],
        out: &mut [f64],
    );
}

/// What the terms read of one frame.
#[derive(Debug, Clone, Copy)]
pub struct FrameContext<'a> {
    pub(crate) space: ShapeSpace,
    pub(crate) current: GreyImage<'a>,
    pub(crate) previous: GreyImage<'a>,
    pub(crate) clusters: &'a [ClusterMotion],
    pub(crate) reference: &'a ReferenceLines,
    pub(crate) appearance: Option<&'a Appearance>,
}

impl<'a> FrameContext<'a> {
    /// The current frame z_k, grey (in the tracker's working pixels).
    pub fn current(&self) -> GreyImage<'a> {
        self.current
    }

    /// The previous frame z_{k−1}, grey.
    pub fn previous(&self) -> GreyImage<'a> {
        self.previous
    }

    /// The shape space of the particles.
    pub fn space(&self) -> ShapeSpace {
        self.space
    }

    /// The contour of a particle as an ellipse (`None` when its pose is not finite).
    pub fn ellipse(&self, p: &Particle) -> Option<vision_core::Ellipse> {
        self.space.pose(&p.now).to_ellipse()
    }
}

/// Adds `weight` times `measure(appearance, ellipse)` to every particle's log-likelihood (−∞ for a
/// particle whose contour is not finite or that `measure` cannot score): the loop of the
/// appearance terms. Without an appearance model (a term built by hand on a tracker without
/// one) it adds nothing.
fn add_appearance_measure(
    frame: &FrameContext<'_>,
    particles: &[Particle],
    out: &mut [f64],
    weight: f64,
    mut measure: impl FnMut(&Appearance, &vision_core::Ellipse) -> Option<f64>,
) {
    let Some(appearance) = frame.appearance else {
        return;
    };
    add_each(particles, out, |p| {
        let e = frame.ellipse(p)?;
        measure(appearance, &e).map(|v| weight * v)
    });
}

/// Adds `log_likelihood(particle)` to each particle's entry of `out`, −∞ where it is `None` (a
/// particle the term cannot score): the loop every term runs.
fn add_each(
    particles: &[Particle],
    out: &mut [f64],
    mut log_likelihood: impl FnMut(&Particle) -> Option<f64>,
) {
    for (p, o) in particles.iter().zip(out) {
        *o += log_likelihood(p).unwrap_or(f64::NEG_INFINITY);
    }
}

/// The terms a configuration enables, in a fixed order (shape, clutter, implicit motion, motion
/// consistency, colour contrast, template, contour contrast), then any of the user's.
#[derive(Debug, Default)]
pub struct LikelihoodModel {
    terms: Vec<Box<dyn ObservationTerm>>,
    /// Wu's term again, for the reference lines of the ratio occlusion form.
    reference: Option<clutter::ClutterTerm>,
}

impl LikelihoodModel {
    /// Builds the terms of `settings` and of `appearance` for the unit-circle template.
    ///
    /// # Errors
    /// Invalid settings, or a workspace that cannot be built: the error is the model's, never
    /// a term silently missing from the particles' likelihood.
    pub fn new(
        settings: &LikelihoodSettings,
        appearance: Option<&AppearanceSettings>,
    ) -> Result<Self> {
        settings.validate()?;
        let template = Template::UnitCircle;
        let mut terms: Vec<Box<dyn ObservationTerm>> = Vec::new();
        if let Some(s) = settings.shape {
            terms.push(Box::new(shape::ShapeTerm::new(s, &template)?));
        }
        let reference = settings
            .clutter
            .map(|w| {
                let (form, fraction) = (settings.occlusion_form, settings.clutter_line_fraction);
                clutter::ClutterTerm::new(w, form, fraction, &template)
            })
            .transpose()?;
        if let Some(term) = &reference {
            terms.push(Box::new(term.clone()));
        }
        if let Some(m) = settings.implicit_motion {
            terms.push(Box::new(implicit_motion::ImplicitMotion::new(m)?));
        }
        if settings.motion_consistency {
            terms.push(Box::new(motion_consistency::MotionConsistency));
        }
        if let Some(a) = appearance {
            if a.colour_weight > 0.0 {
                terms.push(Box::new(colour_contrast::ColourContrast {
                    weight: a.colour_weight,
                }));
            }
            if a.template_weight > 0.0 {
                terms.push(Box::new(template::TemplateMatch {
                    weight: a.template_weight,
                }));
            }
            if a.contour_weight > 0.0 {
                terms.push(Box::new(contour_contrast::ContourContrast {
                    weight: a.contour_weight,
                }));
            }
        }
        Ok(Self { terms, reference })
    }

    /// Adds a term (a user's own, see [`crate::build_with_terms`]) after the configured ones.
    pub fn push(&mut self, term: Box<dyn ObservationTerm>) {
        self.terms.push(term);
    }

    /// The edge counts and observed lengths of the lines of state `x` on `image` into `out`
    /// (cleared first; left empty unless the occlusion form reads them,
    /// [`OcclusionForm::needs_reference`]): the reference lines of [`FrameContext`].
    ///
    /// # Errors
    /// A non-finite state.
    pub fn reference_counts(
        &self,
        space: ShapeSpace,
        image: &GreyImage<'_>,
        x: &crate::space::StateVector,
        out: &mut ReferenceLines,
    ) -> Result<()> {
        match &self.reference {
            Some(wu) => wu.reference_lines(image, &space.pose(x), out),
            None => {
                out.clear();
                Ok(())
            }
        }
    }
}

/// The likelihood of one frame, ready for the particle filter: the sum of the model's terms.
#[derive(Debug, Clone, Copy)]
pub struct FrameObservation<'a> {
    /// The terms.
    pub model: &'a LikelihoodModel,
    /// What they read of the frame.
    pub frame: FrameContext<'a>,
}

impl smc_core::Observation for FrameObservation<'_> {
    type State = Particle;

    fn log_likelihood(&self, state: &Particle) -> f64 {
        let mut out = [0.0];
        self.log_likelihood_batch(std::slice::from_ref(state), &mut out);
        out[0]
    }

    /// Every term over the batch in turn, each with one workspace per batch.
    fn log_likelihood_batch(&self, states: &[Particle], out: &mut [f64]) {
        out.fill(0.0);
        for term in &self.model.terms {
            term.add_log_likelihoods(&self.frame, states, out);
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
