//! The view stage's motion: the particles clustered, and each cluster's robust affine motion
//! from the previous frame to the current one (Odobez §5, Eq. 13–15), the mean and covariance
//! of the motion proposal (Eq. 16) and of the consistency term p_c1 (Eq. 21).
//!
//! The motion is estimated on frames shrunk so that the target's mean radius is
//! [`MotionSettings::working_radius`](crate::MotionSettings::working_radius) pixels
//! ([`MotionFrames`]), and mapped back to the tracker's pixels.

use motion_est::{MotionEstimator, Pyramid, Region};
use vision_core::Ellipse;

use super::ParticleTracker;
use super::scale::{Shrinker, WorkingScale};
use crate::cluster::cluster_particles;
use crate::frame::Frame;
use crate::proposal::{ClusterMotion, state_increment};
use crate::space::{STATE_SLOTS, axpy};
use crate::{Error, Result};

/// The pyramids of the previous and the current frame that the motion is estimated between, at
/// the motion's working scale (fixed at initialisation from the target's size).
#[derive(Debug, Clone)]
pub(super) struct MotionFrames {
    scale: WorkingScale,
    shrinker: Shrinker,
    prev: Pyramid,
    now: Pyramid,
}

impl Default for MotionFrames {
    fn default() -> Self {
        Self {
            scale: WorkingScale::IDENTITY,
            shrinker: Shrinker::default(),
            prev: Pyramid::new(),
            now: Pyramid::new(),
        }
    }
}

impl MotionFrames {
    /// Sets the working scale for `target` (`None`: the frame's own pixels) and builds the
    /// first frame's pyramid.
    pub(super) fn start(
        &mut self,
        estimator: &MotionEstimator,
        frame: &Frame<'_>,
        target: &Ellipse,
        working_radius: Option<f64>,
    ) -> Result<()> {
        self.scale = WorkingScale::for_radius(target, working_radius);
        self.shrinker = Shrinker::for_frames(self.scale, frame.width(), frame.height());
        self.build(estimator, frame)
    }

    /// The next frame: the current pyramid becomes the previous one.
    pub(super) fn advance(&mut self, estimator: &MotionEstimator, frame: &Frame<'_>) -> Result<()> {
        std::mem::swap(&mut self.prev, &mut self.now);
        self.build(estimator, frame)
    }

    fn build(&mut self, estimator: &MotionEstimator, frame: &Frame<'_>) -> Result<()> {
        if self.scale.is_identity() {
            estimator.build_pyramid_into(frame.grey(), &mut self.now)?;
        } else {
            let grey = self.shrinker.shrink_grey(frame)?;
            estimator.build_pyramid_into(grey, &mut self.now)?;
        }
        Ok(())
    }
}

impl ParticleTracker {
    pub(super) fn estimate_cluster_motions(&mut self, frame: &Frame<'_>) -> Result<(usize, usize)> {
        let Some(set) = self.set.as_mut() else {
            return Err(Error::NotInitialised);
        };
        let space = self.config.space;
        self.motion_frames.advance(&self.motion, frame)?;
        let scale = self.motion_frames.scale;
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
                let e = scale.to_working(&e);
                let region = Region::Ellipse(e);
                let est = self
                    .motion
                    .estimate_from(
                        &self.motion_frames.prev,
                        &self.motion_frames.now,
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
                let (affine, affine_cov) =
                    scale.affine_to_frame(est.affine(), &est.affine_covariance());
                let (d, cov) = state_increment(space, mean, &affine, &affine_cov).ok()?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use motion_est::{ModelSpec, MotionModel, Settings, Workspace};

    /// A smooth texture of several wavelengths, at (x, y) in frame pixels.
    fn texture(x: f64, y: f64) -> f32 {
        (100.0
            + 40.0 * (0.21 * x + 0.05 * y).sin()
            + 30.0 * (0.13 * y - 0.07 * x).cos()
            + 20.0 * (0.09 * (x + y)).sin() * (0.17 * y).cos()) as f32
    }

    #[test]
    fn motion_estimated_on_shrunk_frames_maps_back_to_the_frames_affine_motion() {
        // Frame 1 is frame 0 moved by a known affine displacement about the target's centre; the
        // motion estimated on both frames shrunk to a 16 px working radius must come back, in
        // frame pixels, as that displacement.
        let (w, h) = (320usize, 240usize);
        let target = Ellipse {
            cx: 160.0,
            cy: 120.0,
            a: 60.0,
            b: 70.0,
            angle: 0.0,
        };
        let truth = [5.0, 0.02, -0.01, -3.0, 0.015, 0.01];
        let frame0: Vec<f32> = (0..w * h)
            .map(|k| texture((k % w) as f64, (k / w) as f64))
            .collect();
        // frame1(p + d(p)) = frame0(p): frame1(q) = frame0(p) with p − c = (I + A)⁻¹(q − c − t).
        let [t0, a11, a12, t1, a21, a22] = truth;
        let (m11, m12, m21, m22) = (1.0 + a11, a12, a21, 1.0 + a22);
        let det = m11 * m22 - m12 * m21;
        let frame1: Vec<f32> = (0..w * h)
            .map(|k| {
                let (qx, qy) = (
                    (k % w) as f64 - target.cx - t0,
                    (k / w) as f64 - target.cy - t1,
                );
                let px = (m22 * qx - m12 * qy) / det;
                let py = (m11 * qy - m21 * qx) / det;
                texture(target.cx + px, target.cy + py)
            })
            .collect();
        let estimator = MotionEstimator::new(Settings::tracking()).unwrap();
        let mut frames = MotionFrames::default();
        let f0 = Frame::new(w, h, &frame0).unwrap();
        let f1 = Frame::new(w, h, &frame1).unwrap();
        frames.start(&estimator, &f0, &target, Some(16.0)).unwrap();
        frames.advance(&estimator, &f1).unwrap();
        let scale = frames.scale;
        assert!(scale.factor() > 4.0);
        let e = scale.to_working(&target);
        let est = estimator
            .estimate_from(
                &frames.prev,
                &frames.now,
                &Region::Ellipse(e),
                ModelSpec::new(MotionModel::Affine, false),
                Some([e.cx, e.cy]),
                None,
                &mut Workspace::new(),
            )
            .unwrap();
        let (affine, cov) = scale.affine_to_frame(est.affine(), &est.affine_covariance());
        for (i, (got, want)) in affine.iter().zip(truth).enumerate() {
            let tolerance = if i % 3 == 0 { 0.05 } else { 0.002 };
            assert!(
                (got - want).abs() < tolerance,
                "a{}: {got} vs {want}",
                i + 1
            );
        }
        // The translations' variance is in frame pixels²: f² times the working one's.
        let working = est.affine_covariance();
        let f2 = scale.factor().powi(2);
        assert!((cov[(0, 0)] - f2 * working[(0, 0)]).abs() <= 1e-12 * cov[(0, 0)].abs());
        assert_eq!(cov[(1, 1)], working[(1, 1)]);
    }
}
