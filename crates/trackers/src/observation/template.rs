//! The template term of the appearance model ([`crate::appearance`]): the normalised
//! cross-correlation ρ (Odobez Eq. 23) between the grey patch under the contour and the
//! target's template.

use super::{FrameContext, ObservationTerm};
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
        let Some(appearance) = frame.appearance else {
            return;
        };
        let mut samples = appearance.samples();
        for (p, o) in particles.iter().zip(out) {
            let rho = frame
                .ellipse(p)
                .and_then(|e| appearance.template_similarity(&e, &mut samples));
            *o += rho.map_or(f64::NEG_INFINITY, |r| self.weight * r);
        }
    }
}
