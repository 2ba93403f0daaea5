//! Odobez's shape likelihood p_sh (Eq. 19): edges found along the measurement lines of the
//! contour, each line scored by the distance of its nearest edge to the contour
//! ([`contour_obs::OdobezLikelihood`]).

use contour_obs::{MeasurementLines, OdobezLikelihood, OdobezSettings, Template};

use super::{FrameContext, ObservationTerm, add_each};
use crate::Result;
use crate::particle::Particle;

/// p_sh as a term.
#[derive(Debug, Clone)]
pub struct ShapeTerm {
    likelihood: OdobezLikelihood,
    /// A fresh workspace, copied for every batch.
    workspace: MeasurementLines,
}

impl ShapeTerm {
    /// The term for `settings` on `template`.
    ///
    /// # Errors
    /// Invalid settings.
    pub fn new(settings: OdobezSettings, template: &Template) -> Result<Self> {
        let likelihood = OdobezLikelihood::new(settings, template)?;
        let workspace = likelihood.workspace()?;
        Ok(Self {
            likelihood,
            workspace,
        })
    }
}

impl ObservationTerm for ShapeTerm {
    fn name(&self) -> &'static str {
        "Odobez shape likelihood p_sh (Eq. 19)"
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
            self.likelihood
                .log_likelihood(&mut workspace, &frame.current, &pose)
                .ok()
        });
    }
}
