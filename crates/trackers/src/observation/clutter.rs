//! Wu's Poisson-clutter contour likelihood (Wu Eq. 1–6) with the particle's clutter density λ
//! and occlusion degree γ (Eq. 11–12), in the configured occlusion form
//! ([`contour_obs::WuTerm`]).

use contour_obs::{OcclusionForm, ReferenceLines, Template, WuSettings, WuTerm, WuTermWorkspace};
use vision_core::GreyImage;

use super::{FrameContext, ObservationTerm, add_each};
use crate::Result;
use crate::particle::Particle;

/// Wu's likelihood as a term.
#[derive(Debug, Clone)]
pub struct ClutterTerm {
    term: WuTerm,
    /// A fresh workspace, copied for every batch.
    workspace: WuTermWorkspace,
}

impl ClutterTerm {
    /// The term for `settings` in occlusion form `form`, clutter on `line_fraction` of each
    /// line, on `template`.
    ///
    /// # Errors
    /// Invalid settings.
    pub fn new(
        settings: WuSettings,
        form: OcclusionForm,
        line_fraction: f64,
        template: &Template,
    ) -> Result<Self> {
        let term = WuTerm::new(settings, form, line_fraction, template)?;
        let workspace = term.workspace()?;
        Ok(Self { term, workspace })
    }

    /// The edge counts and observed lengths of the lines of `pose` on `image` (the reference
    /// lines of the ratio form, [`OcclusionForm::needs_reference`]).
    ///
    /// # Errors
    /// A non-finite pose.
    pub fn reference_lines(
        &self,
        image: &GreyImage<'_>,
        pose: &contour_obs::Affine2,
        out: &mut ReferenceLines,
    ) -> Result<()> {
        Ok(self.term.reference_lines(image, pose, out)?)
    }
}

impl ObservationTerm for ClutterTerm {
    fn name(&self) -> &'static str {
        "Wu clutter and occlusion likelihood (Eq. 1-6, 11-12)"
    }

    fn add_log_likelihoods(
        &self,
        frame: &FrameContext<'_>,
        particles: &[Particle],
        out: &mut [f64],
    ) {
        let mut workspace = self.workspace.clone();
        add_each(particles, out, |p| {
            let pose = frame.space.pose(&p.now);
            let (lambda, gamma) = (p.clutter.lambda, p.gamma());
            let reference = frame.reference;
            self.term
                .log_likelihood(
                    &mut workspace,
                    &frame.current,
                    &pose,
                    lambda,
                    gamma,
                    reference,
                )
                .ok()
        });
    }
}
