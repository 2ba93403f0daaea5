//! The contour contrast of the appearance model ([`crate::appearance`]): the grey contrast
//! across the contour along its normals, in units of the window's mean gradient (Birchfield
//! 1998's perimeter gradient, normalised; `appearance::WorkingWindow::edge_strength`).

use super::{FrameContext, ObservationTerm, add_appearance_measure};
use crate::particle::Particle;

/// The contour contrast, `weight` nats per unit.
#[derive(Debug, Clone, Copy)]
pub struct ContourContrast {
    /// Nats per unit of contrast.
    pub weight: f64,
}

impl ObservationTerm for ContourContrast {
    fn name(&self) -> &'static str {
        "contour contrast"
    }

    fn add_log_likelihoods(
        &self,
        frame: &FrameContext<'_>,
        particles: &[Particle],
        out: &mut [f64],
    ) {
        add_appearance_measure(frame, particles, out, self.weight, |a, e| {
            Some(a.contour_contrast(e))
        });
    }
}
