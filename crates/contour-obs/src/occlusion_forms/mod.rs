//! The forms of Wu's contour likelihood a tracker can choose, behind one validated choice
//! ([`OcclusionForm`]), and the term that evaluates the chosen one ([`WuTerm`]).
//!
//! Every form reads the per-line pieces of [`WuLikelihood::line_terms`] (Wu Eq. 3–5 for a
//! visible line, Eq. 12 for a hidden one) and combines them with the hypothesis' occlusion γ.
//! The table of docs/MODELS.md (Wu Eq. 6, 11, 12) names the function of each form.

mod arc;
mod independent;
mod ratio;
mod reference;

use serde::{Deserialize, Serialize};

pub use reference::ReferenceLines;

use vision_core::GreyImage;

use crate::{
    Affine2, Error, LineTerms, MeasurementLines, OcclusionLikelihood, Result, Template,
    WuLikelihood, WuSettings,
};

/// How Wu's likelihood reads a hypothesis' occlusion γ: the one choice among the forms
/// (docs/MODELS.md, Wu Eq. 6, 11–12). Each variant carries exactly the parameters it uses.
///
/// In a configuration file the variant is the `form` key, beside its parameters, e.g. in TOML
/// `{ form = "independent", unknown_occluder_share = 0.5 }`, `{ form = "neutral_arc" }` or
/// `{ form = "ratio" }`.
///
/// # Examples
/// ```
/// use contour_obs::OcclusionForm;
///
/// let form: OcclusionForm = serde_json::from_str(r#"{"form": "neutral_arc"}"#)?;
/// assert_eq!(form, OcclusionForm::NeutralArc);
/// assert!(OcclusionForm::Independent { unknown_occluder_share: 1.5 }.validate().is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "FormRepr", into = "FormRepr")]
pub enum OcclusionForm {
    /// Wu Eq. 11 as printed: every line hidden independently with probability γ,
    /// γ p(Z_i | C) + (1 − γ) p(Z_i | x_i, C); γ = 0 is Eq. 6 and γ = 1 is Eq. 12 on every line.
    ///
    /// `unknown_occluder_share` is the share s ∈ [0, 1] of a hidden line's edge count that comes
    /// from an occluding surface of unknown texture (0: Eq. 12 as printed). Wu's clutter-only
    /// term p(Z_i | C) = N(m(L); λ)/W explains the edges seen on a hidden line as background
    /// clutter of density λ; but those edges belong to the occluder, whose texture need not look
    /// like the background at all. With s > 0 the count of a hidden line is (1 − s) N(m; λ) +
    /// s U(m; 0..=L), the uniform being the least committal law of a count on a line of L
    /// pixels. Without it, an edge-rich occluder makes every hypothesis hidden behind it
    /// improbable, so the hidden hypotheses are pushed off the occluder — away from where the
    /// target is.
    Independent {
        /// The share s of a hidden line's count from an unknown occluder, in [0, 1].
        unknown_occluder_share: f64,
    },
    /// γ read as the hidden *fraction* of the contour, the hidden lines one contiguous arc,
    /// marginalised over the arc's start; γ = 0 is Eq. 6 and γ = 1 is Eq. 12 on every line.
    /// A hidden line scores Eq. 12 at its own count, mixed with the unknown occluder as in
    /// [`OcclusionForm::Independent`].
    ///
    /// Eq. 11 gives every line γ p(Z_i | C) + (1 − γ) p(Z_i | x_i, C), so a half-hidden target at
    /// its true pose pays ln 2 on each of its visible lines and the lines it loses need not be
    /// adjacent: "whole contour, half hidden" then loses to "shrunk onto the visible sliver" or
    /// "on the occluder's straight edge, γ ≈ 0". With the arc, a pose pays only for the arc's
    /// position (ln n at most) and an occluder must hide a connected part.
    Arc {
        /// The share s of a hidden line's count from an unknown occluder, in [0, 1].
        unknown_occluder_share: f64,
    },
    /// The arc of [`OcclusionForm::Arc`] with every hidden line scored by the same constant
    /// c = e^{E[ln N(m; μ)]}/W, the typical value of Eq. 12 on a background line (minus the
    /// Poisson law's entropy), μ at the edge density of the reference lines
    /// ([`ReferenceLines`]), the same for every hypothesis — instead of Eq. 12 at the line's own
    /// edge count. A hidden line then says nothing about where the hidden target is: with
    /// Eq. 12 at the observed count, a hypothesis hidden behind an edge-rich occluder is
    /// improbable for that reason alone and the hidden hypotheses flee to plain ground and off
    /// the frame. A line outside the image is hidden by the frame's border: it scores c when
    /// hidden and c e^{−10} when visible, so only the arc can cover it (γ rises as the contour
    /// leaves the frame). With the hypothesis' own λ in c instead, light clutter made every
    /// line cheaper to hide than to see (docs/RESULTS.md). No unknown-occluder share: the
    /// constant replaces the hidden line's count law whole.
    NeutralArc,
    /// The pose weighed by Wu's likelihood as a ratio against the no-target explanation of the
    /// same lines, each line ln(γ + (1 − γ) p(Z_i | x_i, C)/p_bg(Z_i)) (Eq. 3–5 over Eq. 12 on
    /// the whole line), at the edge density of the reference lines, times the Poisson law of
    /// the reference lines' counts at the hypothesis' λ (Eq. 1), which is what λ is learnt
    /// from. A hidden line (γ = 1) and a line outside the image score exactly 1. No
    /// unknown-occluder share: a hidden line is neutral already.
    Ratio,
}

impl Default for OcclusionForm {
    /// Wu Eq. 11–12 as printed.
    fn default() -> Self {
        Self::Independent {
            unknown_occluder_share: 0.0,
        }
    }
}

/// The name of an [`OcclusionForm`] in a configuration file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum FormName {
    Independent,
    Arc,
    NeutralArc,
    Ratio,
}

/// The configuration-file shape of an [`OcclusionForm`]: its name under `form` and the
/// parameters beside it. A parameter the form does not use is refused, not ignored.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FormRepr {
    form: FormName,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    unknown_occluder_share: Option<f64>,
}

impl TryFrom<FormRepr> for OcclusionForm {
    type Error = String;

    fn try_from(r: FormRepr) -> std::result::Result<Self, String> {
        let share = r.unknown_occluder_share;
        Ok(match (r.form, share) {
            (FormName::Independent, s) => Self::Independent {
                unknown_occluder_share: s.unwrap_or(0.0),
            },
            (FormName::Arc, s) => Self::Arc {
                unknown_occluder_share: s.unwrap_or(0.0),
            },
            (FormName::NeutralArc, None) => Self::NeutralArc,
            (FormName::Ratio, None) => Self::Ratio,
            (FormName::NeutralArc | FormName::Ratio, Some(_)) => {
                return Err(format!(
                    "unknown_occluder_share is not a parameter of the form {:?}: only \
                     independent and arc have it",
                    r.form
                ));
            }
        })
    }
}

impl From<OcclusionForm> for FormRepr {
    fn from(f: OcclusionForm) -> Self {
        let (form, unknown_occluder_share) = match f {
            OcclusionForm::Independent {
                unknown_occluder_share: s,
            } => (FormName::Independent, Some(s)),
            OcclusionForm::Arc {
                unknown_occluder_share: s,
            } => (FormName::Arc, Some(s)),
            OcclusionForm::NeutralArc => (FormName::NeutralArc, None),
            OcclusionForm::Ratio => (FormName::Ratio, None),
        };
        Self {
            form,
            unknown_occluder_share,
        }
    }
}

impl OcclusionForm {
    /// Checks the unknown-occluder share is in [0, 1].
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming `unknown_occluder_share`.
    pub fn validate(&self) -> Result<()> {
        match *self {
            Self::Independent {
                unknown_occluder_share: s,
            }
            | Self::Arc {
                unknown_occluder_share: s,
            } if !(0.0..=1.0).contains(&s) => Err(Error::InvalidSetting {
                name: "unknown_occluder_share",
                reason: format!("must be in [0, 1], got {s}"),
            }),
            _ => Ok(()),
        }
    }

    /// Whether the form reads the [`ReferenceLines`] of the frame (the ratio and the neutral
    /// arc).
    pub fn needs_reference(&self) -> bool {
        matches!(self, Self::NeutralArc | Self::Ratio)
    }
}

/// Checks the clutter share f ∈ (0, 1] of a measurement line (see
/// [`WuTerm::clutter_line_fraction`]).
///
/// # Errors
/// [`Error::InvalidSetting`] naming `clutter_line_fraction`.
pub fn validate_clutter_line_fraction(f: f64) -> Result<()> {
    if !(f > 0.0 && f <= 1.0) {
        return Err(Error::InvalidSetting {
            name: "clutter_line_fraction",
            reason: format!("must be in (0, 1], got {f}"),
        });
    }
    Ok(())
}

/// The caller-owned buffers of one [`WuTerm`] evaluation (one per thread).
#[derive(Debug, Clone)]
pub struct WuTermWorkspace {
    lines: MeasurementLines,
    terms: Vec<LineTerms>,
}

/// Wu's contour likelihood in the chosen [`OcclusionForm`], at a hypothesis' clutter density λ
/// and occlusion γ: the contour term of a tracker's likelihood (docs/MODELS.md, Wu Eq. 1–6,
/// 11–12).
#[derive(Debug, Clone)]
pub struct WuTerm {
    likelihood: OcclusionLikelihood,
    form: OcclusionForm,
    clutter_line_fraction: f64,
}

impl WuTerm {
    /// The term for `template` sampled at `settings.lines.n_lines` points, in `form`, with the
    /// Poisson mean of a line λ · `clutter_line_fraction` · L.
    ///
    /// # Errors
    /// Invalid settings, form or fraction; a degenerate template.
    pub fn new(
        settings: WuSettings,
        form: OcclusionForm,
        clutter_line_fraction: f64,
        template: &Template,
    ) -> Result<Self> {
        form.validate()?;
        validate_clutter_line_fraction(clutter_line_fraction)?;
        Ok(Self {
            likelihood: OcclusionLikelihood::new(settings, template)?,
            form,
            clutter_line_fraction,
        })
    }

    /// The form.
    pub fn form(&self) -> OcclusionForm {
        self.form
    }

    /// The share f of each measurement line on which background clutter can appear (Wu Eq. 1:
    /// the whole line, f = 1). A line is centred on the contour, so about half of it lies on the
    /// target, which hides the background behind it: the Poisson mean is λ · f · L, so that λ
    /// stays a background density comparable with Wu's learnt λ̄ (§6.1).
    pub fn clutter_line_fraction(&self) -> f64 {
        self.clutter_line_fraction
    }

    /// The underlying Wu likelihood (Eq. 6).
    pub fn wu(&self) -> &WuLikelihood {
        self.likelihood.wu()
    }

    /// A fresh workspace for this term.
    ///
    /// # Errors
    /// Never for validated settings.
    pub fn workspace(&self) -> Result<WuTermWorkspace> {
        Ok(WuTermWorkspace {
            lines: self.likelihood.workspace()?,
            terms: vec![LineTerms::default(); self.wu().contour().len()],
        })
    }

    /// The edge counts and observed lengths of the lines of `pose` on `image` into `out`
    /// (cleared first; left empty when the form does not need them,
    /// [`OcclusionForm::needs_reference`]).
    ///
    /// # Errors
    /// A non-finite pose.
    pub fn reference_lines(
        &self,
        image: &GreyImage<'_>,
        pose: &Affine2,
        out: &mut ReferenceLines,
    ) -> Result<()> {
        out.clear();
        if !self.form.needs_reference() {
            return Ok(());
        }
        let wu = self.wu();
        let mut ws = wu.workspace()?;
        let mut terms = vec![LineTerms::default(); wu.contour().len()];
        wu.line_terms(&mut ws, image, pose, 0.1, &mut terms)?;
        out.counts
            .extend((0..ws.len()).map(|i| (ws.edges(i).len(), ws.observed_length(i))));
        let (count, length) = out
            .counts
            .iter()
            .fold((0, 0.0), |(c, l), &(m, len)| (c + m, l + len));
        // Floored at a tenth of Wu's lightest learnt class, so that an edge-free neighbourhood
        // does not make every stray edge decisive.
        out.density = (length > 0.0).then(|| (count as f64 / length).max(1e-3));
        Ok(())
    }

    /// The log-likelihood of `pose` on `image` at the hypothesis' background clutter density
    /// `lambda` (per pixel, before the line fraction) and occlusion `gamma`, in the chosen form;
    /// `reference` as filled by [`Self::reference_lines`] for this frame.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite pose or λ, or a NaN γ; [`Error::OutOfRange`] for γ
    /// outside [0, 1] in the independent form without an unknown occluder.
    pub fn log_likelihood(
        &self,
        ws: &mut WuTermWorkspace,
        image: &GreyImage<'_>,
        pose: &Affine2,
        lambda: f64,
        gamma: f64,
        reference: &ReferenceLines,
    ) -> Result<f64> {
        let lambda = self.clutter_line_fraction * lambda;
        match self.form {
            // Eq. 11 as printed: the linear-domain mixture of `OcclusionLikelihood`.
            OcclusionForm::Independent {
                unknown_occluder_share: s,
            } if s <= 0.0 => {
                self.likelihood
                    .log_likelihood(&mut ws.lines, image, pose, lambda, gamma)
            }
            OcclusionForm::Independent {
                unknown_occluder_share: s,
            } => {
                self.line_terms(ws, image, pose, lambda)?;
                let settings = self.wu().settings();
                Ok(independent::log_independent(settings, s, &ws.terms, gamma))
            }
            OcclusionForm::Arc {
                unknown_occluder_share: s,
            } => {
                self.line_terms(ws, image, pose, lambda)?;
                let settings = self.wu().settings();
                Ok(arc::log_occlusion_arc(settings, s, &ws.terms, gamma, None))
            }
            OcclusionForm::NeutralArc => {
                self.line_terms(ws, image, pose, lambda)?;
                let settings = self.wu().settings();
                // The same constant for every hypothesis (see the variant).
                let density = reference.density.unwrap_or(lambda);
                let c = arc::neutral_hidden_line(settings, density);
                arc::neutralise_unobserved(&ws.lines, c, &mut ws.terms);
                Ok(arc::log_occlusion_arc(
                    settings,
                    0.0,
                    &ws.terms,
                    gamma,
                    Some(c),
                ))
            }
            OcclusionForm::Ratio => self.log_ratio(ws, image, pose, lambda, gamma, reference),
        }
    }

    /// The ratio form ([`OcclusionForm::Ratio`]) at the scaled density `lambda`.
    fn log_ratio(
        &self,
        ws: &mut WuTermWorkspace,
        image: &GreyImage<'_>,
        pose: &Affine2,
        lambda: f64,
        gamma: f64,
        reference: &ReferenceLines,
    ) -> Result<f64> {
        // Pose and background both at the reference density (see `ReferenceLines`).
        let lambda_ref = reference.density.unwrap_or(lambda);
        self.line_terms(ws, image, pose, lambda_ref)?;
        let ln_window = self.wu().settings().window.ln();
        let lines = &ws.lines;
        let ratio: f64 = (0..lines.len())
            .map(|i| {
                ratio::log_ratio_line(
                    ws.terms[i],
                    lines.edges(i).len(),
                    lines.observed_length(i),
                    lines.is_observed(i),
                    lambda_ref / self.clutter_line_fraction,
                    ln_window,
                    gamma,
                )
            })
            .sum();
        Ok(ratio + reference.log_counts(lambda))
    }

    /// Each line's [`LineTerms`] of `pose` at the scaled density `lambda` into the workspace.
    fn line_terms(
        &self,
        ws: &mut WuTermWorkspace,
        image: &GreyImage<'_>,
        pose: &Affine2,
        lambda: f64,
    ) -> Result<()> {
        let wu = self.wu();
        ws.terms.resize(wu.contour().len(), LineTerms::default());
        wu.line_terms(&mut ws.lines, image, pose, lambda, &mut ws.terms)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bright disc of radius 20 at (40, 30) on a dark 80×60 image with a textured strip.
    fn image() -> Vec<f32> {
        let (w, h) = (80, 60);
        (0..w * h)
            .map(|k| {
                let (x, y) = ((k % w) as f64 - 40.0, (k / w) as f64 - 30.0);
                let strip = if (k % w) > 60 && (k % 3) == 0 {
                    60.0
                } else {
                    0.0
                };
                if x.hypot(y) < 20.0 {
                    200.0
                } else {
                    20.0 + strip
                }
            })
            .collect()
    }

    fn term(form: OcclusionForm) -> WuTerm {
        WuTerm::new(WuSettings::default(), form, 0.5, &Template::UnitCircle).unwrap()
    }

    #[test]
    fn invalid_forms_and_fractions_are_refused_by_name() {
        for s in [-0.1, 1.5, f64::NAN] {
            for form in [
                OcclusionForm::Independent {
                    unknown_occluder_share: s,
                },
                OcclusionForm::Arc {
                    unknown_occluder_share: s,
                },
            ] {
                let err = form.validate().unwrap_err().to_string();
                assert!(err.contains("unknown_occluder_share"), "{err}");
                let t = WuTerm::new(WuSettings::default(), form, 0.5, &Template::UnitCircle);
                assert!(t.is_err());
            }
        }
        for f in [0.0, -0.5, 1.5, f64::NAN] {
            let form = OcclusionForm::default();
            let err = WuTerm::new(WuSettings::default(), form, f, &Template::UnitCircle)
                .unwrap_err()
                .to_string();
            assert!(err.contains("clutter_line_fraction"), "{err}");
        }
        for form in [
            OcclusionForm::default(),
            OcclusionForm::Arc {
                unknown_occluder_share: 1.0,
            },
            OcclusionForm::NeutralArc,
            OcclusionForm::Ratio,
        ] {
            assert!(form.validate().is_ok());
        }
        // Parameters a form does not use cannot be given to it.
        let bad = r#"{"form": "ratio", "unknown_occluder_share": 0.5}"#;
        let err = serde_json::from_str::<OcclusionForm>(bad)
            .unwrap_err()
            .to_string();
        assert!(err.contains("unknown_occluder_share"), "{err}");
        let unknown = r#"{"form": "arc", "neutral_hidden_lines": true}"#;
        assert!(serde_json::from_str::<OcclusionForm>(unknown).is_err());
        // Every form survives a round trip.
        for form in [
            OcclusionForm::default(),
            OcclusionForm::Arc {
                unknown_occluder_share: 0.25,
            },
            OcclusionForm::NeutralArc,
            OcclusionForm::Ratio,
        ] {
            let json = serde_json::to_string(&form).unwrap();
            assert_eq!(serde_json::from_str::<OcclusionForm>(&json).unwrap(), form);
        }
        let good = r#"{"form": "independent", "unknown_occluder_share": 0.5}"#;
        assert_eq!(
            serde_json::from_str::<OcclusionForm>(good).unwrap(),
            OcclusionForm::Independent {
                unknown_occluder_share: 0.5
            }
        );
    }

    #[test]
    fn every_form_is_eq6_at_gamma_0_and_eq12_at_gamma_1() {
        let data = image();
        let image = GreyImage::new(80, 60, &data).unwrap();
        let pose = Affine2::from_ellipse(42.0, 31.0, 18.0, 17.0, 0.0);
        let (lambda, f) = (0.08, 0.5);
        let plain = term(OcclusionForm::default());
        let wu = plain.wu();
        let mut lines = wu.workspace().unwrap();
        // Eq. 6 and Σ_i Eq. 12 at the line-fraction-scaled density.
        let eq6 = wu
            .log_likelihood(&mut lines, &image, &pose, f * lambda)
            .unwrap();
        let mut terms = vec![LineTerms::default(); wu.contour().len()];
        wu.line_terms(&mut lines, &image, &pose, f * lambda, &mut terms)
            .unwrap();
        let eq12: f64 = terms.iter().map(|t| t.log_clutter).sum();
        let none = ReferenceLines::default();
        let eval = |t: &WuTerm, gamma: f64, reference: &ReferenceLines| {
            let mut ws = t.workspace().unwrap();
            t.log_likelihood(&mut ws, &image, &pose, lambda, gamma, reference)
                .unwrap()
        };
        // Eq. 11 as printed is Eq. 6 at γ = 0, bit for bit, and Eq. 12 at γ = 1.
        assert_eq!(eval(&plain, 0.0, &none), eq6);
        assert!((eval(&plain, 1.0, &none) - eq12).abs() < 1e-9);
        for share in [0.0, 0.5] {
            for form in [
                OcclusionForm::Independent {
                    unknown_occluder_share: share,
                },
                OcclusionForm::Arc {
                    unknown_occluder_share: share,
                },
            ] {
                let t = term(form);
                assert!((eval(&t, 0.0, &none) - eq6).abs() < 1e-9, "{form:?}");
                if share == 0.0 {
                    assert!((eval(&t, 1.0, &none) - eq12).abs() < 1e-9, "{form:?}");
                }
            }
        }
        // The neutral arc: Eq. 6 at γ = 0 (every line of this pose is in the image), and at
        // γ = 1 the neutral constant on every line, at the reference density.
        let neutral = term(OcclusionForm::NeutralArc);
        let mut reference = ReferenceLines::default();
        neutral
            .reference_lines(&image, &pose, &mut reference)
            .unwrap();
        let density = reference.density.unwrap();
        assert!((eval(&neutral, 0.0, &reference) - eq6).abs() < 1e-9);
        let c = arc::neutral_hidden_line(wu.settings(), density);
        let n = wu.contour().len() as f64;
        assert!((eval(&neutral, 1.0, &reference) - n * c).abs() < 1e-9);
        // The ratio: at γ = 1 every line is neutral and only the reference counts remain.
        let ratio = term(OcclusionForm::Ratio);
        let want = reference.log_counts(f * lambda);
        assert!((eval(&ratio, 1.0, &reference) - want).abs() < 1e-9);
        // Forms without reference lines leave them empty.
        plain
            .reference_lines(&image, &pose, &mut reference)
            .unwrap();
        assert_eq!(reference, ReferenceLines::default());
    }
}
