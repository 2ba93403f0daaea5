//! The colour contrast of the appearance model ([`crate::appearance`]): the target-against-
//! background log-ratios summed inside the contour, less the target-like evidence just outside
//! it (`appearance::WorkingWindow::contrast`).

use super::{FrameContext, ObservationTerm, add_appearance_measure};
use crate::particle::Particle;

/// The colour contrast, `weight` nats per unit.
#[derive(Debug, Clone, Copy)]
pub struct ColourContrast {
    /// Nats per unit of contrast.
    pub weight: f64,
}

impl ObservationTerm for ColourContrast {
    fn name(&self) -> &'static str {
        "colour contrast"
    }

    fn add_log_likelihoods(
        &self,
        frame: &FrameContext<'_>,
        particles: &[Particle],
        out: &mut [f64],
    ) {
        add_appearance_measure(frame, particles, out, self.weight, |a, e| {
            Some(a.colour_contrast(e))
        });
    }
}
