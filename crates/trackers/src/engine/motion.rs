//! The view stage's motion: the particles clustered, and each cluster's robust affine motion
//! from the previous frame to the current one (Odobez §5, Eq. 13–15), the mean and covariance
//! of the motion proposal (Eq. 16) and of the consistency term p_c1 (Eq. 21).
//!
//! The motion is estimated on frames shrunk so that the target's mean radius is
//! [`MotionSettings::working_radius`](crate::MotionSettings::working_radius) pixels
//! ([`MotionFrames`]), and mapped back to the tracker's pixels. Shrinking averages the frame's
//! noise away, while the estimator's reliability ceiling is in grey levels of that noise: a
//! region that holds no single motion (a head turning) fits the shrunk frames within the
//! ceiling and the frame's pixels beyond it. So each estimate made at the working scale is
//! tested again on the frame's own pixels
//! ([`MotionSettings::frame_check_pixels`](crate::MotionSettings::frame_check_pixels) of them)
//! and, above the ceiling, falls back to the prior as an estimate made there would: the working
//! scale buys speed without changing which motions are believed.

use motion_est::{ModelSpec, MotionEstimator, MotionModel, Pyramid, Region, Window, Workspace};
use nalgebra::Matrix6;
use vision_core::{Ellipse, GreyImage};

use super::scale::{Shrinker, WorkingScale};
use crate::Result;
use crate::TrackerConfig;
use crate::cluster::{Clustering, cluster_particles};
use crate::dynamics::TrackerDynamics;
use crate::frame::Frame;
use crate::particle::Particle;
use crate::proposal::{ClusterMotion, state_increment};
use crate::space::{STATE_SLOTS, StateVector, axpy};

/// The pyramids of the previous and the current frame that the motion is estimated between, at
/// the motion's working scale (fixed at initialisation from the target's size).
#[derive(Debug, Clone)]
pub(super) struct MotionFrames {
    scale: WorkingScale,
    shrinker: Shrinker,
    prev: Pyramid,
    now: Pyramid,
    /// The map from the tracker's pixels to the source frame's: the identity, or the
    /// `ScaledTracker`'s working scale when the tracker itself runs on shrunk frames.
    source_scale: WorkingScale,
    /// The source frame's grey levels offered for the next frame (see [`Self::offer_source`]),
    /// and whether they are there.
    staged: Vec<f32>,
    has_staged: bool,
    /// When any scale is not the identity, the previous and the current frame's grey levels at
    /// the source's own resolution (`size`), and level 0 of both over the window the estimates
    /// are tested on.
    prev_grey: Vec<f32>,
    now_grey: Vec<f32>,
    size: (usize, usize),
    prev_frame: Pyramid,
    now_frame: Pyramid,
    /// Each cluster's estimate of the frame (a buffer reused from frame to frame).
    candidates: Vec<Option<Candidate>>,
}

impl Default for MotionFrames {
    fn default() -> Self {
        Self {
            scale: WorkingScale::IDENTITY,
            shrinker: Shrinker::default(),
            prev: Pyramid::new(),
            now: Pyramid::new(),
            source_scale: WorkingScale::IDENTITY,
            staged: Vec::new(),
            has_staged: false,
            prev_grey: Vec::new(),
            now_grey: Vec::new(),
            size: (0, 0),
            prev_frame: Pyramid::new(),
            now_frame: Pyramid::new(),
            candidates: Vec::new(),
        }
    }
}

/// A cluster's motion estimated at the working scale, in the tracker's pixels, before its test
/// on the source frame's own pixels.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    /// The cluster's region; the motion is about its centre.
    region: Ellipse,
    affine: [f64; 6],
    covariance: Matrix6<f64>,
    /// The intensity offset, when estimated.
    offset: Option<f64>,
    converged: bool,
}

impl Candidate {
    /// The candidate in the pixels of the frame that `outer` maps the tracker's pixels to.
    fn in_source(self, outer: WorkingScale) -> Self {
        let (affine, covariance) = outer.affine_to_frame(self.affine, &self.covariance);
        Self {
            region: outer.to_frame(&self.region),
            affine,
            covariance,
            ..self
        }
    }

    /// The pixel box (min x, min y, max x, max y) that the region covers in the previous frame
    /// and, moved by the motion, in the current one.
    fn reach(&self) -> [f64; 4] {
        let e = &self.region;
        let (hw, hh) = e.half_extents();
        let a = &self.affine;
        let mut b = [e.cx - hw, e.cy - hh, e.cx + hw, e.cy + hh];
        for (dx, dy) in [(-hw, -hh), (hw, -hh), (-hw, hh), (hw, hh)] {
            let x = e.cx + dx + a[0] + a[1] * dx + a[2] * dy;
            let y = e.cy + dy + a[3] + a[4] * dx + a[5] * dy;
            b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
        }
        b
    }
}

/// Pixels around the tested regions' reach that level 0 is built over: the smoothing's and the
/// bicubic interpolation's half-widths (2 px each), so that no pixel read sees a clamped border
/// the full frame would not have.
const TEST_WINDOW_MARGIN: usize = 4;

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

    /// The frame the tracker's next frame was shrunk from (`ScaledTracker`), `scale` mapping the
    /// tracker's pixels to its: the estimates are then tested on its pixels. Without an offer,
    /// the tracker's own frame is the source.
    pub(super) fn offer_source(&mut self, frame: &Frame<'_>, scale: WorkingScale) {
        self.staged.clear();
        self.staged.extend_from_slice(frame.data());
        self.has_staged = true;
        self.source_scale = scale;
        self.size = (frame.width(), frame.height());
    }

    /// Whether estimates are made at the source's own resolution (nothing to test).
    fn at_source_resolution(&self) -> bool {
        self.scale.is_identity() && self.source_scale.is_identity()
    }

    /// The next frame: the current pyramid becomes the previous one.
    pub(super) fn advance(&mut self, estimator: &MotionEstimator, frame: &Frame<'_>) -> Result<()> {
        std::mem::swap(&mut self.prev, &mut self.now);
        std::mem::swap(&mut self.prev_grey, &mut self.now_grey);
        self.build(estimator, frame)
    }

    fn build(&mut self, estimator: &MotionEstimator, frame: &Frame<'_>) -> Result<()> {
        if self.has_staged {
            std::mem::swap(&mut self.now_grey, &mut self.staged);
            self.has_staged = false;
        } else {
            self.source_scale = WorkingScale::IDENTITY;
            self.size = (frame.width(), frame.height());
            if !self.scale.is_identity() {
                self.now_grey.clear();
                self.now_grey.extend_from_slice(frame.data());
            }
        }
        if self.scale.is_identity() {
            estimator.build_pyramid_into(frame.grey(), &mut self.now)?;
        } else {
            let grey = self.shrinker.shrink_grey(frame)?;
            estimator.build_pyramid_into(grey, &mut self.now)?;
        }
        Ok(())
    }

    /// Drops (sets to `None`) every candidate whose residual scale on the source frame's own
    /// pixels (`max_pixels` of its region) exceeds the estimator's reliability ceiling, or cannot
    /// be measured; nothing when the estimates were made at the source's resolution, where the
    /// estimator tested them itself.
    fn test_at_frame_resolution(
        &mut self,
        estimator: &MotionEstimator,
        candidates: &mut [Option<Candidate>],
        max_pixels: usize,
        ws: &mut Workspace,
    ) -> Result<()> {
        if self.at_source_resolution() {
            return Ok(());
        }
        let outer = self.source_scale;
        let Some(reach) = candidates
            .iter()
            .flatten()
            .map(|c| c.in_source(outer).reach())
            .reduce(|a, b| {
                [
                    a[0].min(b[0]),
                    a[1].min(b[1]),
                    a[2].max(b[2]),
                    a[3].max(b[3]),
                ]
            })
        else {
            return Ok(());
        };
        let (w, h) = self.size;
        let pixel = |v: f64, n: usize| (v.max(0.0) as usize).min(n - 1);
        let window = Window::around(
            pixel(reach[0].floor(), w),
            pixel(reach[1].floor(), h),
            pixel(reach[2].ceil(), w),
            pixel(reach[3].ceil(), h),
            TEST_WINDOW_MARGIN,
            w,
            h,
        );
        // Level 0 only, smoothed as the estimator's own level 0: all the test reads.
        let presmooth = estimator.settings().presmooth;
        let prev = GreyImage::new(w, h, &self.prev_grey)?;
        self.prev_frame
            .build_into(prev, Some(window), 1, presmooth)?;
        let now = GreyImage::new(w, h, &self.now_grey)?;
        self.now_frame.build_into(now, Some(window), 1, presmooth)?;
        for slot in candidates.iter_mut() {
            let Some(c) = slot.map(|c| c.in_source(outer)) else {
                continue;
            };
            let spec = ModelSpec::new(MotionModel::Affine, c.offset.is_some());
            let mut params = [0.0; 7];
            params[..6].copy_from_slice(&c.affine);
            params[6] = c.offset.unwrap_or(0.0);
            let holds = estimator
                .residual_scale(
                    &self.prev_frame,
                    &self.now_frame,
                    &Region::Ellipse(c.region),
                    spec,
                    &params[..spec.len()],
                    [c.region.cx, c.region.cy],
                    max_pixels,
                    ws,
                )
                .is_ok_and(|s| estimator.scale_within_ceiling(s));
            if !holds {
                *slot = None;
            }
        }
        Ok(())
    }
}

/// The view stage's motion from one frame to the next: the frames' pyramids, the clustering of
/// the particles, and each cluster's motion as the motion proposal reads it.
#[derive(Debug, Clone)]
pub(super) struct MotionStage {
    estimator: MotionEstimator,
    frames: MotionFrames,
    workspace: Workspace,
    clustering: Clustering,
    clusters: Vec<ClusterMotion>,
    /// Reused per frame: the mean previous state of each cluster.
    prev_means: Vec<StateVector>,
}

impl MotionStage {
    pub(super) fn new(settings: motion_est::Settings) -> Result<Self> {
        Ok(Self {
            estimator: MotionEstimator::new(settings)?,
            frames: MotionFrames::default(),
            workspace: Workspace::new(),
            clustering: Clustering::default(),
            clusters: Vec::new(),
            prev_means: Vec::new(),
        })
    }

    /// Each cluster's motion of the last [`Self::estimate`], indexed by `Particle::cluster`.
    pub(super) fn clusters(&self) -> &[ClusterMotion] {
        &self.clusters
    }

    /// Sets the working scale for `target` and builds the first frame's pyramid (see
    /// [`MotionFrames::start`]).
    pub(super) fn start(
        &mut self,
        frame: &Frame<'_>,
        target: &Ellipse,
        working_radius: Option<f64>,
    ) -> Result<()> {
        self.frames
            .start(&self.estimator, frame, target, working_radius)
    }

    /// See [`MotionFrames::offer_source`].
    pub(super) fn offer_source(&mut self, frame: &Frame<'_>, scale: WorkingScale) {
        self.frames.offer_source(frame, scale);
    }

    /// Clusters the (resampled) particles and estimates each cluster's motion from the previous
    /// frame to `frame` (Odobez §5); returns the clusters used and those that fell back to the
    /// prior.
    ///
    /// The clusters are estimated in order, each from the last converged estimate before it
    /// ([`MotionSettings::warm_start`](crate::MotionSettings::warm_start)); with
    /// [`MotionSettings::fail_together`](crate::MotionSettings::fail_together) none after a
    /// first cluster whose estimate failed.
    pub(super) fn estimate(
        &mut self,
        set: &mut [Particle],
        config: &TrackerConfig,
        dynamics: &TrackerDynamics,
        frame: &Frame<'_>,
    ) -> Result<(usize, usize)> {
        let space = config.space;
        self.frames.advance(&self.estimator, frame)?;
        let k = config.motion.cluster_count(set.len());
        cluster_particles(
            space,
            set,
            k,
            config.motion.cluster_iterations,
            &mut self.clustering,
        );
        // The mean previous state of each cluster, for the fallback prediction.
        let mut prev_means = std::mem::take(&mut self.prev_means);
        prev_means.clear();
        prev_means.resize(k, [0.0; STATE_SLOTS]);
        for p in set.iter() {
            axpy(&mut prev_means[p.cluster as usize], 1.0, &p.prev);
        }
        let spec = ModelSpec::new(MotionModel::Affine, config.motion.offset);
        // Each cluster's motion at the working scale, in the tracker's pixels.
        let mut candidates = std::mem::take(&mut self.frames.candidates);
        candidates.clear();
        let scale = self.frames.scale;
        let mut warm: Option<Vec<f64>> = None;
        // With `fail_together`, no cluster is estimated after a first one whose estimate failed.
        let mut given_up = false;
        for (c, mean) in self.clustering.means.iter().enumerate() {
            let region = (self.clustering.sizes[c] > 0)
                .then(|| space.pose(mean).to_ellipse())
                .flatten()
                .filter(|_| !given_up);
            let candidate = region.and_then(|frame_region| {
                let e = scale.to_working(&frame_region);
                let est = self
                    .estimator
                    .estimate_from(
                        &self.frames.prev,
                        &self.frames.now,
                        &Region::Ellipse(e),
                        spec,
                        Some([e.cx, e.cy]),
                        warm.as_deref(),
                        &mut self.workspace,
                    )
                    // An estimate that could not separate the dominant motion from the rest is
                    // an error (`motion_est::Error::Unreliable`), as is any other failure: the
                    // cluster falls back to the prior prediction.
                    .ok()?;
                // A start for the next cluster's estimate, whatever its test below.
                if config.motion.warm_start && est.converged {
                    warm = Some(est.params.clone());
                }
                let (affine, covariance) =
                    scale.affine_to_frame(est.affine(), &est.affine_covariance());
                Some(Candidate {
                    region: frame_region,
                    affine,
                    covariance,
                    offset: spec.offset.then(|| est.params[6]),
                    converged: est.converged,
                })
            });
            given_up |=
                config.motion.fail_together && c == 0 && region.is_some() && candidate.is_none();
            candidates.push(candidate);
        }
        self.frames.test_at_frame_resolution(
            &self.estimator,
            &mut candidates,
            config.motion.frame_check_pixels,
            &mut self.workspace,
        )?;
        self.clusters.clear();
        let (mut used, mut failures) = (0, 0);
        for (c, (mean, candidate)) in self.clustering.means.iter().zip(&candidates).enumerate() {
            if self.clustering.sizes[c] == 0 {
                // No particle will read this entry; it only keeps the indices aligned.
                self.clusters
                    .push(ClusterMotion::fallback(dynamics, mean, mean));
                continue;
            }
            used += 1;
            let size = self.clustering.sizes[c] as f64;
            let mean_prev = prev_means[c].map(|v| v / size);
            let sigmas = dynamics.settings.sigmas(space, mean);
            let motion = candidate.and_then(|m| {
                let (d, cov) = state_increment(space, mean, &m.affine, &m.covariance).ok()?;
                ClusterMotion::new(space, d, &cov, &sigmas, m.converged)
            });
            let motion = motion.unwrap_or_else(|| {
                failures += 1;
                ClusterMotion::fallback(dynamics, mean, &mean_prev)
            });
            self.clusters.push(motion);
        }
        self.prev_means = prev_means;
        self.frames.candidates = candidates;
        Ok((used, failures))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use motion_est::{ModelSpec, MotionModel, Settings, Workspace};

    /// The frames' size, and the target in them: a face of about 65 px in radius, shrunk by
    /// about 4 at a 16 px working radius.
    const W: usize = 320;
    const H: usize = 240;
    fn face() -> Ellipse {
        Ellipse {
            cx: 160.0,
            cy: 120.0,
            a: 60.0,
            b: 70.0,
            angle: 0.0,
        }
    }

    /// The affine motion of `region` (in `frames`' pixels, about its centre) from the previous
    /// to the current frame of `frames`, estimated cold.
    fn estimate_in(
        frames: &MotionFrames,
        estimator: &MotionEstimator,
        region: &Ellipse,
        ws: &mut Workspace,
    ) -> motion_est::Result<motion_est::MotionEstimate> {
        estimator.estimate(
            &frames.prev,
            &frames.now,
            &Region::Ellipse(*region),
            ModelSpec::new(MotionModel::Affine, false),
            Some([region.cx, region.cy]),
            ws,
        )
    }

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
        let (w, h) = (W, H);
        let target = face();
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
        let est = estimate_in(&frames, &estimator, &e, &mut Workspace::new()).unwrap();
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

    /// Frame 0: the texture plus white noise of `sigma`; frame 1: frame 0's texture moved by
    /// (3, −2) px, its own noise.
    fn noisy_pair(w: usize, h: usize, sigma: f64, seed: u64) -> (Vec<f32>, Vec<f32>) {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let noise = Normal::new(0.0, sigma).unwrap();
        let mut draw = |x: f64, y: f64| (f64::from(texture(x, y)) + noise.sample(&mut rng)) as f32;
        let mut f0 = Vec::with_capacity(w * h);
        let mut f1 = Vec::with_capacity(w * h);
        for k in 0..w * h {
            let (x, y) = ((k % w) as f64, (k / w) as f64);
            f0.push(draw(x, y));
            f1.push(draw(x - 3.0, y + 2.0));
        }
        (f0, f1)
    }

    #[test]
    fn a_motion_the_frames_own_pixels_reject_falls_back_as_at_full_resolution() {
        // Noise that the estimator's ceiling rejects at the frame's resolution is averaged away
        // on the shrunk frames, where the same motion fits within it. The test on the frame's
        // pixels must give the full-resolution verdict: reject under strong noise, keep under
        // weak noise, over several noise draws, whether the motion's own working scale or the
        // whole tracker's shrank the frames.
        let (w, h) = (W, H);
        let target = face();
        let estimator = MotionEstimator::new(Settings::tracking()).unwrap();
        let mut ws = Workspace::new();
        for seed in 1..=3 {
            for (sigma, believed) in [(14.0, false), (2.0, true)] {
                let (g0, g1) = noisy_pair(w, h, sigma, seed);
                let (f0, f1) = (
                    Frame::new(w, h, &g0).unwrap(),
                    Frame::new(w, h, &g1).unwrap(),
                );
                // The estimator's own verdict at the frame's resolution.
                let mut full = MotionFrames::default();
                full.start(&estimator, &f0, &target, None).unwrap();
                full.advance(&estimator, &f1).unwrap();
                let at_full = estimate_in(&full, &estimator, &target, &mut ws);
                assert_eq!(
                    at_full.is_ok(),
                    believed,
                    "σ {sigma}, seed {seed}: {at_full:?}"
                );
                // At the working scale the estimate is reliable either way...
                let mut frames = MotionFrames::default();
                frames.start(&estimator, &f0, &target, Some(16.0)).unwrap();
                frames.advance(&estimator, &f1).unwrap();
                let scale = frames.scale;
                let e = scale.to_working(&target);
                let est = estimate_in(&frames, &estimator, &e, &mut ws)
                    .unwrap_or_else(|err| panic!("σ {sigma}, seed {seed}: {err}"));
                let (affine, covariance) =
                    scale.affine_to_frame(est.affine(), &est.affine_covariance());
                assert!((affine[0] - 3.0).abs() < 0.3 && (affine[3] + 2.0).abs() < 0.3);
                // ...and the test on the frame's pixels gives the full-resolution verdict.
                let mut candidates = [Some(Candidate {
                    region: target,
                    affine,
                    covariance,
                    offset: None,
                    converged: est.converged,
                })];
                frames
                    .test_at_frame_resolution(&estimator, &mut candidates, 2048, &mut ws)
                    .unwrap();
                assert_eq!(candidates[0].is_some(), believed, "σ {sigma}, seed {seed}");
                // The same for a tracker that itself runs on the shrunk frames (`ScaledTracker`,
                // its motion at its own resolution) and is offered the frames they came from.
                let outer = WorkingScale::for_target(&target, 16.0);
                let mut shrinker = Shrinker::for_frames(outer, w, h);
                let s0 = shrinker.shrink_grey(&f0).unwrap().data().to_vec();
                let s1 = shrinker.shrink_grey(&f1).unwrap().data().to_vec();
                let (ow, oh) = outer.working_size(w, h);
                let (w0, w1) = (
                    Frame::new(ow, oh, &s0).unwrap(),
                    Frame::new(ow, oh, &s1).unwrap(),
                );
                let inner_target = outer.to_working(&target);
                let mut inner = MotionFrames::default();
                inner.offer_source(&f0, outer);
                inner
                    .start(&estimator, &w0, &inner_target, Some(16.0))
                    .unwrap();
                assert!(inner.scale.is_identity());
                inner.offer_source(&f1, outer);
                inner.advance(&estimator, &w1).unwrap();
                let est = estimate_in(&inner, &estimator, &inner_target, &mut ws)
                    .unwrap_or_else(|err| panic!("σ {sigma}, seed {seed}: {err}"));
                let mut candidates = [Some(Candidate {
                    region: inner_target,
                    affine: est.affine(),
                    covariance: est.affine_covariance(),
                    offset: None,
                    converged: est.converged,
                })];
                inner
                    .test_at_frame_resolution(&estimator, &mut candidates, 2048, &mut ws)
                    .unwrap();
                assert_eq!(
                    candidates[0].is_some(),
                    believed,
                    "σ {sigma}, seed {seed}, scaled"
                );
            }
        }
    }
}
