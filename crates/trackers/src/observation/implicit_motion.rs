//! Odobez's implicit motion likelihood p_c2 = exp(−λ_c d_c) (Eq. 22–23): d_c = 1 − ρ, the
//! normalised cross-correlation distance between the patch under the particle's contour in z_k
//! and the patch under its previous contour in z_{k−1} ([`motion_est::ImplicitMotionTerm`]).

use motion_est::{ImplicitMotionSettings, ImplicitMotionTerm};

use super::{FrameContext, ObservationTerm, add_each};
use crate::Result;
use crate::particle::Particle;

/// p_c2 as a term.
#[derive(Debug, Clone)]
pub struct ImplicitMotion {
    term: ImplicitMotionTerm,
}

impl ImplicitMotion {
    /// The term for `settings`.
    ///
    /// # Errors
    /// Invalid settings.
    pub fn new(settings: ImplicitMotionSettings) -> Result<Self> {
        Ok(Self {
            term: ImplicitMotionTerm::new(settings)?,
        })
    }
}

impl ObservationTerm for ImplicitMotion {
    fn name(&self) -> &'static str {
        "Odobez implicit motion likelihood p_c2 (Eq. 22-23)"
    }

    fn add_log_likelihoods(
        &self,
        frame: &FrameContext<'_>,
        particles: &[Particle],
        out: &mut [f64],
    ) {
        let len = self.term.patch_len();
        let (mut now, mut prev) = (vec![0.0; len], vec![0.0; len]);
        add_each(particles, out, |p| {
            let pose = frame.space.pose(&p.now);
            let pose_prev = frame.space.pose(&p.prev);
            self.term
                .log_likelihood(
                    frame.current,
                    frame.previous,
                    (&pose.a, [pose.t.x, pose.t.y]),
                    (&pose_prev.a, [pose_prev.t.x, pose_prev.t.y]),
                    &mut now,
                    &mut prev,
                )
                .ok()
        });
    }
}
