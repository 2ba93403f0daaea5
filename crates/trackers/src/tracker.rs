//! The tracker: an object-safe `init` / `update` interface in the spirit of OpenCV's trackers,
//! and the particle tracker that implements every preset.

use std::time::Instant;

use dbn_switch::{
    ClutterEstimate, ClutterHmm, ClutterState, OcclusionProcess, StatusEstimate, StatusHmm,
    StatusState,
};
use motion_est::{MotionEstimator, Pyramid, Region, Workspace};
use rand_distr::{Distribution, StandardNormal};
use smc_core::smooth::{SmootherSettings, smooth_marginals};
use smc_core::{Bootstrap, ParticleFilter, ParticleSet, StepDiagnostics};
use vision_core::{BoundingBox, Ellipse, GreyImage};

use crate::appearance::Appearance;
use crate::cluster::{Clustering, cluster_particles};
use crate::config::{ClutterMode, OcclusionMode, PoseEstimator, ProposalKind, TrackerConfig};
use crate::dynamics::{ClutterProcess, OcclusionModel, TrackerDynamics};
use crate::frame::Frame;
use crate::monitor::visibility::{self, Visibility};
use crate::observation::{FrameContext, FrameObservation, LikelihoodModel, ReferenceLines};
use crate::particle::{Particle, default_status};
use crate::proposal::{ClusterMotion, ExploringPrior, MotionProposal, state_increment};
use crate::reacquire::{Reacquisition, TrackMemory};
use crate::smoothing::SmoothedRun;
use crate::space::{STATE_SLOTS, ShapeBounds, StateVector, UNBOUNDED_CENTRE, axpy, pose_box};
use crate::{Error, Result};

/// What a tracker reports for one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Frame index (0 = the initialisation frame).
    pub frame: usize,
    /// The estimated contour as an ellipse.
    pub ellipse: Ellipse,
    /// Its axis-aligned box.
    pub bbox: BoundingBox,
    /// The estimated shape-space state.
    pub state: StateVector,
    /// Effective sample size after weighting (N at the initialisation frame).
    pub ess: f64,
    /// The particle filter's diagnostics of this step (`None` at initialisation).
    pub diagnostics: Option<StepDiagnostics>,
    /// β̂, its class probabilities and λ̂ (`None` without clutter switching).
    pub clutter: Option<ClutterEstimate>,
    /// γ̂ = E\[γ\] (Wu Eq. 14), `None` without an occlusion model.
    pub gamma: Option<f64>,
    /// α̂ and its probabilities (`None` without the status HMM).
    pub status: Option<StatusEstimate>,
    /// Number of non-empty motion clusters, and how many of them fell back to the prior
    /// prediction because their motion could not be estimated (both 0 without motion). Clusters
    /// left empty by k-means (fewer distinct particles than K after resampling) are not counted:
    /// no particle uses them, so their motion is not estimated.
    pub motion_clusters: (usize, usize),
    /// Wall time of the update, milliseconds.
    pub millis: f64,
}

impl Estimate {
    /// The status this estimate reports: α̂ when the tracker has the status HMM, else from γ̂
    /// ([`status_from_gamma`]), else locked.
    pub fn track_status(&self) -> vision_core::TrackStatus {
        if let Some(s) = &self.status {
            return s.alpha_hat;
        }
        self.gamma
            .map_or(vision_core::TrackStatus::Locked, status_from_gamma)
    }
}

/// Tracker status thresholds on γ̂ for trackers that estimate occlusion but not α: the ranges of
/// Wu §6.3 (locked γ ≤ 0.2, lost γ ≥ 0.8, partially occluded between).
pub fn status_from_gamma(gamma: f64) -> vision_core::TrackStatus {
    if gamma <= 0.2 {
        vision_core::TrackStatus::Locked
    } else if gamma < 0.8 {
        vision_core::TrackStatus::PartiallyOccluded
    } else {
        vision_core::TrackStatus::Lost
    }
}

/// The point estimates of one step, before they become an [`Estimate`].
struct PosteriorSummary {
    state: StateVector,
    clutter: Option<ClutterEstimate>,
    gamma: Option<f64>,
    status: Option<StatusEstimate>,
}

/// A weighted particle, for drawing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WeightedEllipse {
    /// The particle's contour.
    pub ellipse: Ellipse,
    /// Its normalised weight.
    pub weight: f64,
}

/// An object tracker: initialise on a frame, then update frame by frame. Object-safe, so an
/// application can pick the tracker at run time (`Box<dyn Tracker>`).
pub trait Tracker: Send {
    /// The tracker's name (its preset or configuration name).
    fn name(&self) -> &str;

    /// Its configuration.
    fn config(&self) -> &TrackerConfig;

    /// Starts tracking `ellipse` on `frame` (frame 0).
    ///
    /// # Errors
    /// An invalid frame or ellipse.
    fn init(&mut self, frame: Frame<'_>, ellipse: Ellipse) -> Result<Estimate>;

    /// Processes the next frame.
    ///
    /// # Errors
    /// [`Error::NotInitialised`], a frame of another size, or a degenerate filter.
    fn update(&mut self, frame: Frame<'_>) -> Result<Estimate>;

    /// The `max` most heavily weighted particles, heaviest first.
    fn particles(&self, max: usize) -> Vec<WeightedEllipse>;

    /// The smoothed estimate of every frame after the first, given all frames processed so far
    /// (see [`crate::smoothing`]), oldest first, `frame` numbered as in [`Tracker::update`]'s
    /// estimates; and the expected statistics of the switching parameters over the run (the E-step
    /// of learning them). Needs a configuration that records its particles
    /// ([`smc_core::FilterSettings::history`]).
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when the tracker records nothing (the default implementation),
    /// or the smoother's error.
    fn smoothed(&mut self, settings: &SmootherSettings) -> Result<SmoothedRun> {
        let _ = settings;
        Err(Error::InvalidSetting {
            name: "filter.history",
            reason: format!("the {} tracker cannot be smoothed", self.name()),
        })
    }
}

/// An ellipse in words, for messages.
pub(crate) fn describe(e: &Ellipse) -> String {
    format!(
        "the ellipse centred at ({}, {}) with semi-axes {} and {} at angle {} rad",
        e.cx, e.cy, e.a, e.b, e.angle
    )
}

/// Checks an initial ellipse: finite, with positive semi-axes.
///
/// # Errors
/// [`Error::InvalidSetting`] naming the ellipse.
pub(crate) fn check_initial(ellipse: &Ellipse) -> Result<()> {
    let values = [ellipse.cx, ellipse.cy, ellipse.a, ellipse.b, ellipse.angle];
    if values.iter().any(|v| !v.is_finite()) || !(ellipse.a > 0.0 && ellipse.b > 0.0) {
        return Err(Error::InvalidSetting {
            name: "initial ellipse",
            reason: format!(
                "{} must be finite with positive semi-axes",
                describe(ellipse)
            ),
        });
    }
    Ok(())
}

/// Builds the tracker a configuration describes.
///
/// # Errors
/// An invalid configuration.
pub fn build(config: TrackerConfig) -> Result<Box<dyn Tracker>> {
    Ok(Box::new(crate::working_scale::ScaledTracker::new(config)?))
}

/// Builds the tracker a configuration describes, with `terms` of your own added to its
/// likelihood (see [`crate::observation::ObservationTerm`]). The terms see the frames and
/// particles in the tracker's working pixels ([`crate::working_scale`]).
///
/// # Errors
/// An invalid configuration.
pub fn build_with_terms(
    config: TrackerConfig,
    terms: Vec<Box<dyn crate::ObservationTerm>>,
) -> Result<Box<dyn Tracker>> {
    let mut inner = ParticleTracker::new(config)?;
    for term in terms {
        inner.likelihood.push(term);
    }
    Ok(Box::new(crate::working_scale::ScaledTracker::from_tracker(
        inner,
    )))
}

/// The particle-filter tracker behind every preset.
#[derive(Debug)]
pub struct ParticleTracker {
    config: TrackerConfig,
    dynamics: TrackerDynamics,
    likelihood: LikelihoodModel,
    filter: ParticleFilter<Particle>,
    set: Option<ParticleSet<Particle>>,
    motion: MotionEstimator,
    pyramid_prev: Pyramid,
    pyramid_now: Pyramid,
    motion_workspace: Workspace,
    clustering: Clustering,
    clusters: Vec<ClusterMotion>,
    previous: Vec<f32>,
    /// Reused per frame: the hidden parts of the particles, as the estimators take them.
    clutter_states: Vec<ClutterState>,
    status_states: Vec<StatusState>,
    /// Reused per frame: the mean previous state of each motion cluster.
    prev_means: Vec<StateVector>,
    /// The last reported state, and the edge counts along its lines on the current frame (the
    /// reference lines of the ratio form, see [`FrameObservation::reference`]).
    last_state: StateVector,
    reference: ReferenceLines,
    /// The constant-velocity memory of the locked estimates (see [`crate::reacquire`]).
    memory: TrackMemory,
    /// The memory after each of the last locked frames, oldest first: the anchor of the jump is
    /// the oldest (see [`crate::reacquire::ReacquisitionSettings::rollback`]).
    history: std::collections::VecDeque<TrackMemory>,
    /// Whether a target is seen at all (with the status HMM only; see
    /// [`crate::monitor::visibility`]).
    visibility: Option<Visibility>,
    /// The target's appearance and its lock chain, when the configuration has them.
    appearance: Option<Appearance>,
    /// This frame's best appearance detection while the track is not locked: where the
    /// reacquisition component draws (see [`crate::reacquire`]).
    detection: Option<[f64; 2]>,
    size: (usize, usize),
    frame: usize,
}

impl ParticleTracker {
    /// A tracker for `config`.
    ///
    /// # Errors
    /// An invalid configuration.
    pub fn new(config: TrackerConfig) -> Result<Self> {
        config.validate()?;
        let clutter = match &config.clutter {
            ClutterMode::Fixed { lambda } => ClutterProcess::Fixed(*lambda),
            ClutterMode::Switching(c) => ClutterProcess::Switching(ClutterHmm::new(c)?),
        };
        let occlusion = match &config.occlusion {
            OcclusionMode::None => OcclusionModel::None,
            OcclusionMode::RandomWalk(c) => OcclusionModel::RandomWalk(OcclusionProcess::new(c)?),
            OcclusionMode::Status(c) => OcclusionModel::Status(StatusHmm::new(c)?),
        };
        Ok(Self {
            dynamics: TrackerDynamics {
                space: config.space,
                settings: config.dynamics,
                clutter,
                occlusion,
                bounds: ShapeBounds::loose(config.dynamics.min_scale),
                reacquisition: None,
                shape_anchor: None,
            },
            likelihood: LikelihoodModel::new(
                config.space,
                &config.likelihood,
                config.appearance.as_ref(),
            )?,
            filter: ParticleFilter::new(config.filter.clone())?,
            motion: MotionEstimator::new(config.motion.estimator)?,
            set: None,
            pyramid_prev: Pyramid::new(),
            pyramid_now: Pyramid::new(),
            motion_workspace: Workspace::new(),
            clustering: Clustering::default(),
            clusters: Vec::new(),
            previous: Vec::new(),
            clutter_states: Vec::new(),
            status_states: Vec::new(),
            prev_means: Vec::new(),
            last_state: [0.0; STATE_SLOTS],
            reference: ReferenceLines::default(),
            memory: TrackMemory::new([0.0; STATE_SLOTS], 0),
            history: std::collections::VecDeque::new(),
            visibility: None,
            appearance: None,
            detection: None,
            size: (0, 0),
            frame: 0,
            config,
        })
    }

    fn initial_hidden(&self, index: usize) -> (ClutterState, StatusState) {
        let mut rng = smc_core::rng::stream_rng(self.config.seed, u64::MAX, index as u64);
        let clutter = match &self.dynamics.clutter {
            ClutterProcess::Fixed(lambda) => ClutterState {
                beta: 0,
                lambda: *lambda,
            },
            ClutterProcess::Switching(hmm) => hmm.sample_initial(&mut rng),
        };
        let status = match &self.dynamics.occlusion {
            OcclusionModel::None => default_status(),
            OcclusionModel::RandomWalk(walk) => StatusState {
                gamma: walk.initial().gamma,
                ..default_status()
            },
            OcclusionModel::Status(hmm) => self
                .dynamics
                .locked_gamma(hmm, hmm.sample_initial(&mut rng)),
        };
        (clutter, status)
    }

    /// Clusters the (resampled) particles and estimates each cluster's motion from the previous
    /// frame to the current one (Odobez §5).
    /// Propagates `set` to this frame with the configured proposal and weights it (Odobez Eq. 3)
    /// by the frame's observation terms; sets the prior's reacquisition component and shape
    /// anchor for the frame first.
    fn weigh_frame(
        &mut self,
        frame: &Frame<'_>,
        set: &mut ParticleSet<Particle>,
        seed: u64,
        step: u64,
    ) -> Result<smc_core::WeightReport> {
        self.dynamics.reacquisition = self.reacquisition_component(self.frame + 1);
        // The mean shape of the shape-space dynamics: the shape remembered over the locked
        // estimates (see `DynamicsSettings::shape_reversion`).
        self.dynamics.shape_anchor =
            (self.config.dynamics.shape_reversion > 0.0).then(|| *self.memory.state());
        let current = frame.grey();
        let previous = GreyImage::new(self.size.0, self.size.1, &self.previous)?;
        self.likelihood.reference_counts(
            self.config.space,
            &current,
            &self.last_state,
            &mut self.reference,
        )?;
        let observation = FrameObservation {
            model: &self.likelihood,
            frame: FrameContext {
                space: self.config.space,
                current,
                previous,
                clusters: &self.clusters,
                reference: &self.reference,
                appearance: self.appearance.as_ref(),
            },
        };
        let filter = &mut self.filter;
        let weighted = match self.config.proposal {
            ProposalKind::Prior if self.config.dynamics.hidden_exploration > 0.0 => {
                let proposal = ExploringPrior(&self.dynamics);
                let prior = Some(&self.dynamics);
                propagate_and_weight(filter, set, &proposal, prior, &observation, seed, step)
            }
            ProposalKind::Prior => {
                let proposal = Bootstrap(&self.dynamics);
                propagate_and_weight(filter, set, &proposal, None, &observation, seed, step)
            }
            ProposalKind::Motion => {
                let proposal = MotionProposal {
                    dynamics: &self.dynamics,
                    clusters: &self.clusters,
                    occlusion_aware: self.config.motion.occlusion_aware,
                };
                let prior = Some(&self.dynamics);
                propagate_and_weight(filter, set, &proposal, prior, &observation, seed, step)
            }
        };
        Ok(weighted?)
    }

    /// Records a locked estimate in the track memory of the reacquisition jump, keeping the last
    /// `rollback + 1` memories.
    fn remember_if_locked(
        &mut self,
        state: &StateVector,
        gamma: Option<f64>,
        status: Option<&StatusEstimate>,
    ) {
        if self.is_locked(state, gamma, status)
            && let Some(settings) = &self.config.reacquisition
        {
            self.memory
                .observe(self.config.space, settings, state, self.frame);
            self.history.push_back(self.memory.clone());
            while self.history.len() > settings.rollback + 1 {
                self.history.pop_front();
            }
        }
    }

    fn estimate_cluster_motions(&mut self, frame: &Frame<'_>) -> Result<(usize, usize)> {
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

    fn estimate(&mut self, set: &ParticleSet<Particle>) -> Result<PosteriorSummary> {
        let weights = set.weights();
        let states = set.states();
        let clutter = match &self.dynamics.clutter {
            ClutterProcess::Switching(hmm) => {
                self.clutter_states.clear();
                self.clutter_states.extend(states.iter().map(|p| p.clutter));
                Some(hmm.estimate(&self.clutter_states, weights)?)
            }
            ClutterProcess::Fixed(_) => None,
        };
        let (gamma, status) = match &self.dynamics.occlusion {
            OcclusionModel::None => (None, None),
            OcclusionModel::RandomWalk(_) => (
                Some(
                    states
                        .iter()
                        .zip(weights)
                        .map(|(p, w)| p.status.gamma * w)
                        .sum(),
                ),
                None,
            ),
            OcclusionModel::Status(hmm) => {
                self.status_states.clear();
                self.status_states.extend(states.iter().map(|p| p.status));
                let e = hmm.estimate(&self.status_states, weights)?;
                (Some(e.gamma_hat), Some(e))
            }
        };
        let mean = self.pose_mean(states, weights, clutter.as_ref())?;
        Ok(PosteriorSummary {
            state: mean,
            clutter,
            gamma,
            status,
        })
    }

    /// The reported pose: the weighted mean of the states, or with
    /// [`PoseEstimator::ClassConditionalMean`] the mean of the particles of class β̂ (Wu §4).
    fn pose_mean(
        &self,
        states: &[Particle],
        weights: &[f64],
        clutter: Option<&ClutterEstimate>,
    ) -> Result<StateVector> {
        let class = match (self.config.estimator, clutter) {
            (PoseEstimator::ClassConditionalMean, Some(c)) => Some(c.beta_hat),
            _ => None,
        };
        let mut mean = [0.0; STATE_SLOTS];
        let mut mass = 0.0;
        for (p, &w) in states.iter().zip(weights) {
            if class.is_none_or(|b| p.clutter.beta == b) {
                mass += w;
                axpy(&mut mean, w, &p.now);
            }
        }
        if mass.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(Error::Smc(smc_core::Error::InvalidSetting {
                name: "weights",
                reason: "no weight on the estimated class".into(),
            }));
        }
        for v in &mut mean {
            *v /= mass;
        }
        Ok(mean)
    }

    /// The ellipse reported for a tracked one: in the annotation's convention
    /// ([`Appearance::reported`]).
    fn reported(&self, e: &Ellipse) -> Ellipse {
        self.appearance.as_ref().map_or(*e, |a| a.reported(e))
    }

    fn report(&self, state: StateVector, millis: f64) -> Result<Estimate> {
        let pose = self.config.space.pose(&state);
        let tracked = pose.to_ellipse().ok_or(Error::BadFrame {
            frame: self.frame,
            reason: "the estimated contour is not finite".into(),
        })?;
        let ellipse = self.reported(&tracked);
        let bbox = match &self.appearance {
            Some(_) => ellipse.bounding_box(),
            None => pose_box(&pose),
        };
        Ok(Estimate {
            frame: self.frame,
            ellipse,
            bbox,
            state,
            ess: self.config.particles as f64,
            diagnostics: None,
            clutter: None,
            gamma: None,
            status: None,
            motion_clusters: (0, 0),
            millis,
        })
    }

    /// The reacquisition jump of frame `frame`: present when the configuration asks for it and
    /// the frames since the last locked one are not locked (see [`crate::reacquire`]).
    fn reacquisition_component(&self, frame: usize) -> Option<Reacquisition> {
        let settings = self.config.reacquisition.as_ref()?;
        let gap = frame.saturating_sub(self.memory.last_locked() + 1);
        let share = (settings.share_rate * gap as f64).min(settings.max_share);
        if gap == 0 || share <= 0.0 {
            return None;
        }
        let space = self.config.space;
        let anchor = self.history.front().unwrap_or(&self.memory);
        let (mut mean, mut velocity) = anchor.extrapolate(space, frame);
        // With an appearance model, the jump is drawn around where the target's appearance is
        // best in the frame, at rest, rather than where its last motion would have carried it.
        if let Some(d) = self.detection {
            space.set_centre(&mut mean, d);
            space.set_centre(&mut velocity, [0.0, 0.0]);
        }
        let mut sigmas = self.dynamics.settings.sigmas(space, &mean);
        for (j, s) in sigmas.iter_mut().enumerate().take(space.dim()) {
            if space.is_translation(j) {
                *s = settings.spread + settings.spread_growth * gap as f64;
            }
        }
        Some(Reacquisition {
            share,
            mean,
            velocity,
            sigmas,
        })
    }

    /// The box the centre of every state is kept in: the frame when reacquisition is on (a lost
    /// track that runs off the image, where Wu's occluded lines are the most probable of all,
    /// would never come back), else unbounded.
    fn centre_bounds(&self, frame: &Frame<'_>) -> [f64; 4] {
        if self.config.reacquisition.is_some() {
            [0.0, 0.0, frame.width() as f64, frame.height() as f64]
        } else {
            UNBOUNDED_CENTRE
        }
    }

    /// Whether a reported estimate is locked: γ̂ below the configured level, α̂ (if modelled)
    /// locked and the remembered shape. Without reacquisition settings every estimate is.
    fn is_locked(
        &self,
        state: &StateVector,
        gamma: Option<f64>,
        status: Option<&StatusEstimate>,
    ) -> bool {
        let Some(settings) = &self.config.reacquisition else {
            return true;
        };
        self.memory
            .shape_agrees(self.config.space, state, settings.shape_tolerance)
            && gamma.is_none_or(|g| g < settings.lock_gamma)
            && status.is_none_or(|s| s.alpha_hat == dbn_switch::TrackStatus::Locked)
    }

    /// The index of the last frame processed (0 after `init`).
    pub(crate) fn frames_done(&self) -> usize {
        self.frame
    }

    fn check_frame(&self, frame: &Frame<'_>) -> Result<()> {
        if (frame.width(), frame.height()) != self.size {
            return Err(Error::BadFrame {
                frame: self.frame + 1,
                reason: format!(
                    "{}×{} differs from the first frame's {}×{}",
                    frame.width(),
                    frame.height(),
                    self.size.0,
                    self.size.1
                ),
            });
        }
        Ok(())
    }
}

impl Tracker for ParticleTracker {
    fn name(&self) -> &str {
        &self.config.name
    }

    fn config(&self) -> &TrackerConfig {
        &self.config
    }

    fn init(&mut self, frame: Frame<'_>, ellipse: Ellipse) -> Result<Estimate> {
        let start = Instant::now();
        // Exactly what the shape space can represent, or an error (a rotated ellipse for a
        // tracker of axis-aligned ones).
        let ellipse = self.config.initial_ellipse(&ellipse)?;
        let appearance = self.config.appearance.as_ref();
        self.appearance = appearance
            .map(|settings| Appearance::start(settings.clone(), &frame, &ellipse))
            .transpose()?;
        // The region the appearance terms follow for this annotation (the annotation itself
        // without them); estimates are reported back in the annotation's convention.
        let tracked = self
            .appearance
            .as_ref()
            .map_or(ellipse, |a| a.tracked(&ellipse));
        let space = self.config.space;
        let centre = space.from_ellipse(&tracked);
        let s0 = space.scale(&centre);
        let d = &self.config.dynamics;
        let (e0, min) = (space.elongation(&centre), d.min_scale);
        self.dynamics.bounds = ShapeBounds {
            scale: (
                (d.scale_range[0] * s0).max(min),
                (d.scale_range[1] * s0).max(min),
            ),
            aspect: (
                (d.aspect_range[0] * e0).max(0.25),
                (d.aspect_range[1] * e0).clamp(1.0, 4.0),
            ),
            centre: self.centre_bounds(&frame),
        };
        let sigmas = self.dynamics.settings.sigmas(space, &centre);
        let spread = self.config.init_spread;
        let particles: Vec<Particle> = (0..self.config.particles)
            .map(|i| {
                let mut rng = smc_core::rng::particle_rng(self.config.seed, u64::MAX, i);
                let mut x = centre;
                for j in 0..space.dim() {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    x[j] += spread * sigmas[j] * z;
                }
                space.clamp(&mut x, &self.dynamics.bounds);
                let (clutter, status) = self.initial_hidden(i);
                Particle::at_rest(x, clutter, status)
            })
            .collect();
        self.set = Some(ParticleSet::from_states(particles)?);
        self.size = (frame.width(), frame.height());
        self.previous.clear();
        self.previous.extend_from_slice(frame.data());
        self.frame = 0;
        self.visibility = matches!(self.dynamics.occlusion, OcclusionModel::Status(_))
            .then(Visibility::new)
            .transpose()?;

        self.last_state = centre;
        self.memory = TrackMemory::new(centre, 0);
        self.history.clear();
        self.history.push_back(self.memory.clone());
        self.dynamics.reacquisition = None;
        if self.config.needs_motion() {
            self.motion
                .build_pyramid_into(frame.grey(), &mut self.pyramid_now)?;
        }
        self.report(centre, start.elapsed().as_secs_f64() * 1e3)
    }

    fn update(&mut self, frame: Frame<'_>) -> Result<Estimate> {
        let start = Instant::now();
        if self.set.is_none() {
            return Err(Error::NotInitialised);
        }
        self.check_frame(&frame)?;
        let step = self.frame as u64 + 1;
        let seed = self.config.seed;
        let resampled = {
            let Some(set) = self.set.as_mut() else {
                return Err(Error::NotInitialised);
            };
            self.filter
                .resample_if_needed(set, &self.config.resampling, seed, step)?
        };
        let motion_clusters = if self.config.needs_motion() {
            self.estimate_cluster_motions(&frame)?
        } else {
            (0, 0)
        };
        self.detection = None;
        if let Some(appearance) = &mut self.appearance {
            let last = self.config.space.pose(&self.last_state).to_ellipse();
            if let Some(e) = last {
                appearance.read(&frame, &e);
                let unlocked = self.frame > self.memory.last_locked();
                if unlocked && self.config.reacquisition.is_some() {
                    self.detection = appearance.detect((e.a, e.b));
                }
            }
        }
        let Some(mut set) = self.set.take() else {
            return Err(Error::NotInitialised);
        };
        let weighted = match self.weigh_frame(&frame, &mut set, seed, step) {
            Ok(w) => w,
            Err(e) => {
                self.set = Some(set);
                return Err(e);
            }
        };
        let visibility = self.visibility.as_mut().and_then(|v| {
            let (_, best, _) = smc_core::estimate::max_weight_particle(&set);
            let contour = self.config.space.pose(&best.now).to_ellipse()?;
            Some(v.observe(frame.data(), self.size, &contour))
        });
        let estimated = self.estimate(&set);
        self.set = Some(set);
        let PosteriorSummary {
            state,
            clutter,
            gamma,
            status,
        } = estimated?;
        let status = match (&mut self.appearance, status) {
            (Some(appearance), None) => {
                if let Some(e) = self.config.space.pose(&state).to_ellipse() {
                    appearance.observe(&e)?;
                }
                Some(appearance.status())
            }
            (_, status) => status,
        };
        self.frame += 1;
        self.last_state = state;
        self.remember_if_locked(&state, gamma, status.as_ref());
        self.previous.clear();
        self.previous.extend_from_slice(frame.data());
        let mut report = self.report(state, 0.0)?;
        report.ess = weighted.ess;
        report.diagnostics = Some(StepDiagnostics {
            ess: resampled.ess,
            resampled: resampled.resampled,
            distinct_ancestors: resampled.distinct_ancestors,
            max_weight: weighted.max_weight,
            log_evidence_increment: weighted.log_evidence_increment,
            ess_after: weighted.ess,
            tempering_exponent: weighted.exponent,
        });
        report.clutter = clutter;
        report.gamma = gamma;
        report.status = match (status, visibility) {
            (Some(s), Some(unseen)) => Some(visibility::fuse(&s, unseen)),
            (s, _) => s,
        };
        report.motion_clusters = motion_clusters;
        report.millis = start.elapsed().as_secs_f64() * 1e3;
        Ok(report)
    }

    fn smoothed(&mut self, settings: &SmootherSettings) -> Result<SmoothedRun> {
        let Some(history) = self.filter.history() else {
            return Err(Error::InvalidSetting {
                name: "filter.history",
                reason: "the tracker records no particles: set filter.history to smooth".into(),
            });
        };
        if history.is_empty() {
            return Ok(SmoothedRun {
                estimates: Vec::new(),
                statistics: Default::default(),
            });
        }
        let transition = crate::smoothing::PriorTransition::new(&self.dynamics);
        let marginals = smooth_marginals(history, &transition, settings)?;
        let (hidden, statistics) = crate::smoothing::smooth_hidden(&self.dynamics, history)?;
        let estimates = hidden
            .into_iter()
            .zip(history.frames())
            .enumerate()
            .map(|(t, (h, frame))| {
                let weights = marginals.weights(t).unwrap_or_default();
                // The pose of the smoothed class β̂, as the filter takes its own.
                let state = self.pose_mean(frame.set.states(), weights, h.clutter.as_ref())?;
                let mut e = self.report(state, 0.0)?;
                e.frame = frame.step as usize;
                e.ess = smc_core::weights::effective_sample_size(weights);
                e.clutter = h.clutter;
                e.gamma = h.gamma;
                e.status = h.status;
                Ok(e)
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(SmoothedRun {
            estimates,
            statistics,
        })
    }

    fn particles(&self, max: usize) -> Vec<WeightedEllipse> {
        let Some(set) = &self.set else {
            return Vec::new();
        };
        let mut order: Vec<usize> = (0..set.len()).collect();
        let w = set.weights();
        order.sort_by(|&a, &b| w[b].total_cmp(&w[a]).then(a.cmp(&b)));
        order
            .into_iter()
            .take(max)
            .filter_map(|i| {
                let ellipse = self.config.space.pose(&set.states()[i].now).to_ellipse()?;
                Some(WeightedEllipse {
                    ellipse: self.reported(&ellipse),
                    weight: w[i],
                })
            })
            .collect()
    }
}

/// Odobez Eq. 3 for one frame: draws every particle from `proposal`, then weights it by the
/// observation times p/q (`prior = None`: q is the prior and the ratio is 1, never evaluated).
fn propagate_and_weight<P: smc_core::Proposal<State = Particle>>(
    filter: &mut ParticleFilter<Particle>,
    set: &mut ParticleSet<Particle>,
    proposal: &P,
    prior: Option<&TrackerDynamics>,
    observation: &FrameObservation<'_>,
    seed: u64,
    step: u64,
) -> smc_core::Result<smc_core::WeightReport> {
    filter.propagate(set, proposal, seed, step);
    filter.weight(set, proposal, prior, observation, step)
}

#[cfg(test)]
mod status_tests {
    use super::*;
    use crate::Preset;
    use vision_core::TrackStatus;

    #[test]
    fn status_from_gamma_follows_wu_ranges() {
        assert_eq!(status_from_gamma(0.0), TrackStatus::Locked);
        assert_eq!(status_from_gamma(0.2), TrackStatus::Locked);
        assert_eq!(status_from_gamma(0.21), TrackStatus::PartiallyOccluded);
        assert_eq!(status_from_gamma(0.79), TrackStatus::PartiallyOccluded);
        assert_eq!(status_from_gamma(0.8), TrackStatus::Lost);
    }

    #[test]
    fn track_status_prefers_alpha_then_gamma() {
        let (w, h) = (48, 40);
        let pixels: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 200) as f32).collect();
        let mut tracker = build(Preset::M1.config(20, 1)).unwrap();
        let start = Ellipse::new(24.0, 20.0, 8.0, 10.0, 0.0);
        let mut e = tracker
            .init(Frame::new(w, h, &pixels).unwrap(), start)
            .unwrap();
        assert!(e.status.is_none() && e.gamma.is_none());
        assert_eq!(e.track_status(), TrackStatus::Locked);
        e.gamma = Some(0.9);
        assert_eq!(e.track_status(), TrackStatus::Lost);
        e.status = Some(StatusEstimate {
            alpha_hat: TrackStatus::PartiallyOccluded,
            alpha_probs: [0.2, 0.5, 0.3],
            gamma_hat: 0.9,
        });
        assert_eq!(e.track_status(), TrackStatus::PartiallyOccluded);
    }
}
