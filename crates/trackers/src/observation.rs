//! The observation models a tracker can multiply together, and their evaluation on one frame.
//!
//! - Odobez's shape likelihood p_sh (Eq. 19);
//! - the implicit motion likelihood p_c2 = exp(−λ_c d_c) (Eq. 22–23), d_c = 1 − ρ the NCC distance
//!   between the patch of c_k in z_k and the patch of c_{k−1} in z_{k−1};
//! - the motion consistency p_c1 = N(α̂_k; α_k, Λ̂_k) (Eq. 21), which cancels against Odobez's
//!   motion proposal (Eq. 24) but can be used with any proposal;
//! - Wu's Poisson-clutter likelihood with the particle's λ, mixed with the clutter-only term by the
//!   particle's γ (Wu Eq. 1–6, 11–12; γ = 0 is the plain Eq. 6).

use contour_obs::{
    GreyView, LineTerms, MeasurementLines, OcclusionLikelihood, OdobezLikelihood, OdobezSettings,
    Template, WuSettings, occlusion_line_log,
};
use motion_est::{ImageView, NccSettings};
use serde::{Deserialize, Serialize};

use crate::particle::Particle;
use crate::proposal::{ClusterMotion, log_motion_consistency};
use crate::space::ShapeSpace;
use crate::{Error, Result};

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

/// Which likelihood terms a tracker multiplies.
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
    /// The share of each measurement line on which background clutter can appear (default 1,
    /// Wu Eq. 1: the whole line). A line is centred on the contour, so about half of it lies on
    /// the target, which hides the background behind it: with 1, the particles' λ estimates the
    /// edge density of the whole line, about half the background density that Wu's λ̄ were learnt
    /// from (random lines thrown on the background, §6.1), and β̂ reads one class too light. The
    /// presets use 0.5: the Poisson mean becomes λ · 0.5 · L, so that λ stays a background
    /// density comparable with λ̄.
    #[serde(default = "one")]
    pub clutter_line_fraction: f64,
    /// The share s of an occluded line's edge count that comes from an occluding surface of
    /// unknown texture, in [0, 1] (default 0: Wu Eq. 12 as printed). Wu's clutter-only term
    /// p(Z_i | C) = N(m(L); λ)/W explains the edges seen on a hidden line as background clutter
    /// of density λ; but those edges belong to the occluder, whose texture need not look like
    /// the background at all. With s > 0 the count of an occluded line is (1 − s) N(m; λ) +
    /// s U(m; 0..=L), the uniform being the least committal law of a count on a line of L pixels.
    /// Without it, an edge-rich occluder (the `occlusion` scene's: several edges per line, more
    /// than any of Wu's learnt classes explains) makes every hypothesis hidden behind it
    /// improbable, so the occluded hypotheses are pushed off the occluder — away from where the
    /// target is.
    #[serde(default)]
    pub unknown_occluder_share: f64,
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
            unknown_occluder_share: 0.0,
        }
    }
}

impl LikelihoodSettings {
    /// Checks every term and that at least one looks at the image.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] or the observation crate's error.
    pub fn validate(&self) -> Result<()> {
        if self.shape.is_none() && self.implicit_motion.is_none() && self.clutter.is_none() {
            return Err(Error::InvalidSetting {
                name: "likelihood",
                reason: "at least one of shape, implicit_motion or clutter is needed".into(),
            });
        }
        if let Some(s) = &self.shape {
            s.validate()?;
        }
        if let Some(w) = &self.clutter {
            w.validate()?;
        }
        let s = self.unknown_occluder_share;
        if !(0.0..=1.0).contains(&s) {
            return Err(Error::InvalidSetting {
                name: "likelihood.unknown_occluder_share",
                reason: format!("{s} must be in [0, 1]"),
            });
        }
        let f = self.clutter_line_fraction;
        if !(f > 0.0 && f <= 1.0) {
            return Err(Error::InvalidSetting {
                name: "likelihood.clutter_line_fraction",
                reason: format!("{f} must be in (0, 1]"),
            });
        }
        if let Some(m) = &self.implicit_motion {
            if !(m.lambda_c.is_finite() && m.lambda_c >= 0.0) {
                return Err(Error::InvalidSetting {
                    name: "implicit_motion.lambda_c",
                    reason: format!("{} must be finite and non-negative", m.lambda_c),
                });
            }
            if !(2..=64).contains(&m.grid) {
                return Err(Error::InvalidSetting {
                    name: "implicit_motion.grid",
                    reason: format!("{} must be in 2..=64", m.grid),
                });
            }
            if !(m.inner_radius > 0.0 && m.inner_radius <= 1.5) {
                return Err(Error::InvalidSetting {
                    name: "implicit_motion.inner_radius",
                    reason: format!("{} must be in (0, 1.5]", m.inner_radius),
                });
            }
            m.ncc.validate()?;
        }
        Ok(())
    }
}

/// The built likelihood terms (templates sampled, grids laid out).
#[derive(Debug, Clone)]
pub struct LikelihoodModel {
    space: ShapeSpace,
    shape: Option<OdobezLikelihood>,
    implicit: Option<(ImplicitMotionSettings, Vec<[f64; 2]>)>,
    motion_consistency: bool,
    clutter: Option<OcclusionLikelihood>,
    clutter_line_fraction: f64,
    unknown_occluder_share: f64,
}

impl LikelihoodModel {
    /// Builds the terms for the unit-circle template.
    ///
    /// # Errors
    /// Invalid settings.
    pub fn new(space: ShapeSpace, settings: &LikelihoodSettings) -> Result<Self> {
        settings.validate()?;
        let template = Template::UnitCircle;
        Ok(Self {
            space,
            shape: settings
                .shape
                .map(|s| OdobezLikelihood::new(s, &template))
                .transpose()?,
            implicit: settings.implicit_motion.map(|m| {
                let grid = motion_est::unit_disc_grid(m.grid)
                    .into_iter()
                    .map(|[x, y]| [x * m.inner_radius, y * m.inner_radius])
                    .collect();
                (m, grid)
            }),
            motion_consistency: settings.motion_consistency,
            clutter: settings
                .clutter
                .map(|w| OcclusionLikelihood::new(w, &template))
                .transpose()?,
            clutter_line_fraction: settings.clutter_line_fraction,
            unknown_occluder_share: settings.unknown_occluder_share,
        })
    }

    /// Wu's occlusion likelihood (Eq. 11) at occlusion `gamma` from the per-line terms `terms`
    /// of [`contour_obs::WuLikelihood::line_terms`], with the occluded lines' edge count a mixture
    /// of background clutter and an unknown occluder (see
    /// [`LikelihoodSettings::unknown_occluder_share`]).
    fn log_occlusion_with_unknown_occluder(
        &self,
        settings: &WuSettings,
        terms: &[LineTerms],
        gamma: f64,
    ) -> f64 {
        let s = self.unknown_occluder_share;
        let length = settings.lines.length as f64;
        let ln_window = settings.window.ln();
        terms
            .iter()
            .map(|t| {
                // t.log_clutter = ln N(m; λ) − ln W; the uniform count law is 1/(L + 1).
                let ln_poisson = t.log_clutter + ln_window;
                let ln_count = ((1.0 - s) * ln_poisson.exp() + s / (length + 1.0)).ln();
                let terms = LineTerms {
                    log_target: t.log_target,
                    log_clutter: ln_count - ln_window,
                };
                occlusion_line_log(terms, gamma)
            })
            .sum()
    }

    /// Whether a term needs motion estimates.
    pub fn needs_motion(&self) -> bool {
        self.motion_consistency
    }

    /// Whether a term needs the previous frame.
    pub fn needs_previous_frame(&self) -> bool {
        self.implicit.is_some()
    }

    /// Whether Wu's clutter term is used.
    pub fn has_clutter_term(&self) -> bool {
        self.clutter.is_some()
    }
}

/// Per-thread scratch buffers of the likelihood terms.
#[derive(Debug, Default)]
struct Scratch {
    shape_lines: Option<MeasurementLines>,
    clutter_lines: Option<MeasurementLines>,
    patch_now: Vec<f32>,
    patch_prev: Vec<f32>,
    line_terms: Vec<LineTerms>,
}

/// The likelihood of one frame, ready for the particle filter.
#[derive(Debug, Clone, Copy)]
pub struct FrameObservation<'a> {
    /// The terms.
    pub model: &'a LikelihoodModel,
    /// The current frame z_k.
    pub current: GreyView<'a>,
    /// The previous frame z_{k−1} (for p_c2).
    pub previous: GreyView<'a>,
    /// Cluster motions (for p_c1).
    pub clusters: &'a [ClusterMotion],
}

impl FrameObservation<'_> {
    fn scratch(&self) -> Scratch {
        let m = self.model;
        Scratch {
            shape_lines: m.shape.as_ref().and_then(|s| s.workspace().ok()),
            clutter_lines: m.clutter.as_ref().and_then(|c| c.workspace().ok()),
            patch_now: vec![0.0; m.implicit.as_ref().map_or(0, |(_, g)| g.len())],
            patch_prev: vec![0.0; m.implicit.as_ref().map_or(0, |(_, g)| g.len())],
            line_terms: Vec::new(),
        }
    }

    /// The log-likelihood of one particle; −∞ when a term cannot be computed for it (a pose that
    /// is not finite), so that such a particle simply dies.
    fn evaluate(&self, p: &Particle, scratch: &mut Scratch) -> f64 {
        let m = self.model;
        let pose = m.space.pose(&p.now);
        let mut total = 0.0;
        if let (Some(shape), Some(ws)) = (&m.shape, scratch.shape_lines.as_mut()) {
            match shape.log_likelihood(ws, &self.current, &pose) {
                Ok(v) => total += v,
                Err(_) => return f64::NEG_INFINITY,
            }
        }
        if let (Some(clutter), Some(ws)) = (&m.clutter, scratch.clutter_lines.as_mut()) {
            let lambda = m.clutter_line_fraction * p.clutter.lambda;
            let value = if m.unknown_occluder_share > 0.0 {
                let wu = clutter.wu();
                let terms = &mut scratch.line_terms;
                terms.resize(wu.contour().len(), LineTerms::default());
                wu.line_terms(ws, &self.current, &pose, lambda, terms)
                    .map(|()| {
                        m.log_occlusion_with_unknown_occluder(wu.settings(), terms, p.gamma())
                    })
            } else {
                clutter.log_likelihood(ws, &self.current, &pose, lambda, p.gamma())
            };
            match value {
                Ok(v) => total += v,
                Err(_) => return f64::NEG_INFINITY,
            }
        }
        if let Some((settings, grid)) = &m.implicit {
            let pose_prev = m.space.pose(&p.prev);
            let views = (
                ImageView::new(
                    self.current.width(),
                    self.current.height(),
                    self.current.data(),
                ),
                ImageView::new(
                    self.previous.width(),
                    self.previous.height(),
                    self.previous.data(),
                ),
            );
            let (Ok(now_view), Ok(prev_view)) = views else {
                return f64::NEG_INFINITY;
            };
            let sampled = motion_est::sample_patch_into(
                now_view,
                grid,
                &pose.a,
                [pose.t.x, pose.t.y],
                &mut scratch.patch_now,
            )
            .and_then(|_| {
                motion_est::sample_patch_into(
                    prev_view,
                    grid,
                    &pose_prev.a,
                    [pose_prev.t.x, pose_prev.t.y],
                    &mut scratch.patch_prev,
                )
            })
            .and_then(|_| {
                motion_est::ncc_distance(&scratch.patch_now, &scratch.patch_prev, &settings.ncc)
            });
            match sampled {
                Ok(d) => total -= settings.lambda_c * d,
                Err(_) => return f64::NEG_INFINITY,
            }
        }
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

    fn model(share: f64) -> LikelihoodModel {
        let settings = LikelihoodSettings {
            clutter: Some(WuSettings::default()),
            unknown_occluder_share: share,
            ..LikelihoodSettings::default()
        };
        LikelihoodModel::new(ShapeSpace::Affine, &settings).unwrap()
    }

    #[test]
    fn unknown_occluder_mixture_reduces_to_wu_and_to_the_uniform_count() {
        let w = WuSettings::default();
        // Two lines: 3 edges (one in the window) and none, at λ = 0.05 per pixel.
        let terms = [
            contour_obs::wu_line_terms(&[-7.5, 1.0, 9.0], 20.0, 0.05, &w).unwrap(),
            contour_obs::wu_line_terms(&[], 20.0, 0.05, &w).unwrap(),
        ];
        for gamma in [0.0, 0.3, 1.0] {
            // Share 0 is Wu's Eq. 11 exactly.
            let wu: f64 = terms.iter().map(|t| occlusion_line_log(*t, gamma)).sum();
            let got = model(0.0).log_occlusion_with_unknown_occluder(&w, &terms, gamma);
            assert!((got - wu).abs() < 1e-12, "γ {gamma}: {got} vs {wu}");
        }
        // Share 1 at γ = 1: every line is 1/(L + 1) · 1/W, whatever its edges.
        let got = model(1.0).log_occlusion_with_unknown_occluder(&w, &terms, 1.0);
        let want = 2.0 * (-(21.0f64).ln() - w.window.ln());
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        // The target term (γ = 0) never depends on the share.
        let a = model(0.0).log_occlusion_with_unknown_occluder(&w, &terms, 0.0);
        let b = model(0.5).log_occlusion_with_unknown_occluder(&w, &terms, 0.0);
        assert!((a - b).abs() < 1e-12);
    }

    #[test]
    fn share_outside_the_unit_interval_is_rejected() {
        let settings = LikelihoodSettings {
            clutter: Some(WuSettings::default()),
            unknown_occluder_share: 1.5,
            ..LikelihoodSettings::default()
        };
        assert!(settings.validate().is_err());
    }
}
