//! The view stage's motion: the particles clustered, and each cluster's robust affine motion
//! from the previous frame to the current one (Odobez §5, Eq. 13–15), the mean and covariance
//! of the motion proposal (Eq. 16) and of the consistency term p_c1 (Eq. 21).

use motion_est::Region;

use super::ParticleTracker;
use crate::cluster::cluster_particles;
use crate::frame::Frame;
use crate::proposal::{ClusterMotion, state_increment};
use crate::space::{STATE_SLOTS, axpy};
use crate::{Error, Result};

impl ParticleTracker {
    pub(super) fn estimate_cluster_motions(&mut self, frame: &Frame<'_>) -> Result<(usize, usize)> {
        let Some(set) = self.set.as_mut() else {
            return Err(Error::NotInitialised);
        };
        let space = self.config.space;
        std::mem::swap(&mut self.pyramid_prev, &mut self.pyramid_now);
        self.motion
            .build_pyramid_into(frame.grey(), &mut self.pyramid_now)?;
        let k = self.config.motion.cluster_count(set.len());
        cluster_particles(
            space,
            set.states_mut(),
            k,
            self.config.motion.cluster_iterations,
            &mut self.clustering,
        );
        // The mean previous state of each cluster, for the fallback prediction.
        let mut prev_means = std::mem::take(&mut self.prev_means);
        prev_means.clear();
        prev_means.resize(k, [0.0; STATE_SLOTS]);
        for p in set.states() {
            axpy(&mut prev_means[p.cluster as usize], 1.0, &p.prev);
        }
        let spec =
            motion_est::ModelSpec::new(motion_est::MotionModel::Affine, self.config.motion.offset);
        self.clusters.clear();
        let (mut used, mut failures) = (0, 0);
        let mut warm: Option<Vec<f64>> = None;
        for (c, mean) in self.clustering.means.iter().enumerate() {
            if self.clustering.sizes[c] == 0 {
                // No particle will read this entry; it only keeps the indices aligned.
                self.clusters
                    .push(ClusterMotion::fallback(&self.dynamics, mean, mean));
                continue;
            }
            used += 1;
            let size = self.clustering.sizes[c] as f64;
            let mean_prev = prev_means[c].map(|v| v / size);
            let pose = space.pose(mean);
            let sigmas = self.dynamics.settings.sigmas(space, mean);
            let motion = pose.to_ellipse().and_then(|e| {
                let region = Region::Ellipse(vision_core::Ellipse {
                    cx: e.cx,
                    cy: e.cy,
                    a: e.a,
                    b: e.b,
                    angle: e.angle,
                });
                let est = self
                    .motion
                    .estimate_from(
                        &self.pyramid_prev,
                        &self.pyramid_now,
                        &region,
                        spec,
                        Some([e.cx, e.cy]),
                        warm.as_deref(),
                        &mut self.motion_workspace,
                    )
                    // An estimate that could not separate the dominant motion from the rest is an
                    // error (`motion_est::Error::Unreliable`), as is any other failure: the
                    // cluster falls back to the prior prediction.
                    .ok()?;
                if self.config.motion.warm_start && est.converged {
                    warm = Some(est.params.clone());
                }
                let (d, cov) =
                    state_increment(space, mean, &est.affine(), &est.affine_covariance()).ok()?;
                ClusterMotion::new(space, d, &cov, &sigmas, est.converged)
            });
            let motion = motion.unwrap_or_else(|| {
                failures += 1;
                ClusterMotion::fallback(&self.dynamics, mean, &mean_prev)
            });
            self.clusters.push(motion);
        }
        self.prev_means = prev_means;
        Ok((used, failures))
    }
}
