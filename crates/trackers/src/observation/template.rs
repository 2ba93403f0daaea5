//! The template term of the appearance model ([`crate::appearance`]): the normalised
//! cross-correlation ρ (Odobez Eq. 23) between the grey patch under the contour and the
//! target's template.

use super::{FrameContext, ObservationTerm, add_appearance_measure};
use crate::appearance::Appearance;
use crate::particle::Particle;

/// ρ, `weight` nats per unit.
#[derive(Debug, Clone, Copy)]
pub struct TemplateMatch {
    /// Nats per unit of ρ.
    pub weight: f64,
}

impl ObservationTerm for TemplateMatch {
    fn name(&self) -> &'static str {
        "template match"
    }

    fn add_log_likelihoods(
        &self,
        frame: &FrameContext<'_>,
        particles: &[Particle],
        out: &mut [f64],
    ) {
        let mut matcher = frame.appearance.and_then(Appearance::template_matcher);
        add_appearance_measure(frame, particles, out, self.weight, |_, e| {
            matcher.as_mut()?.similarity(e)
        });
    }
}
