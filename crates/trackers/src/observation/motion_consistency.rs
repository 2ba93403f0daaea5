//! Odobez's motion consistency p_c1(α̂_k, α_k) = N(α̂_k; α_k, Λ̂_k) (Eq. 21): how well the
//! particle's displacement agrees with the robust affine motion of its cluster. Numerically the
//! same Gaussian as the motion proposal (Eq. 16), which is why it cancels against q in Eq. 24;
//! with another proposal it is a term like any other.

use super::{FrameContext, ObservationTerm, add_each};
use crate::particle::Particle;
use crate::proposal::ClusterMotion;
use crate::space::{ShapeSpace, axpy};

/// p_c1 as a term (0 for a particle without a motion cluster).
#[derive(Debug, Clone, Copy, Default)]
pub struct MotionConsistency;

/// log p_c1 of a propagated particle, from the motion of its cluster; 0 when the particle has
/// no cluster.
pub fn log_motion_consistency(space: ShapeSpace, clusters: &[ClusterMotion], p: &Particle) -> f64 {
    match clusters.get(p.cluster as usize) {
        Some(motion) => {
            let mut mean = p.prev;
            axpy(&mut mean, 1.0, &motion.derivative);
            motion.log_density(space, &mean, &p.now)
        }
        None => 0.0,
    }
}

impl ObservationTerm for MotionConsistency {
    fn name(&self) -> &'static str {
        "Odobez motion consistency p_c1 (Eq. 21)"
    }

    fn add_log_likelihoods(
        &self,
        frame: &FrameContext<'_>,
        particles: &[Particle],
        out: &mut [f64],
    ) {
        add_each(particles, out, |p| {
            Some(log_motion_consistency(frame.space, frame.clusters, p))
        });
    }
}
