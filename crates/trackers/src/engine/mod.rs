//! The one particle engine behind every preset: one frame is
//!
//! view → propose → weigh → temper → estimate → monitor → learn:
//!
//! 1. **view**: the frame at the tracker's working scale ([`crate::working_scale`]); the
//!    appearance window read around the last estimate ([`crate::appearance`]); the motion of
//!    each cluster of particles estimated (Odobez §5, [`motion`]);
//! 2. **propose**: resample, then draw every particle from the configured proposal, a mixture
//!    whose density is known (the AR2 prior, Odobez's motion proposal Eq. 16, the reacquisition
//!    component, hidden-chain exploration; [`crate::proposal`], [`crate::dynamics`]);
//! 3. **weigh**: the sum of the observation terms' log-likelihoods ([`crate::observation`]), times
//!    prior over proposal (Odobez Eq. 3);
//! 4. **temper** (opt-in, no preset): the likelihood raised to the power that keeps the
//!    conditional ESS above its floor ([`smc_core::temper`]);
//! 5. **estimate**: the weighted mean pose and the hidden processes' estimates ([`estimate`]);
//! 6. **monitor**: Wu's status with the visibility check, or the appearance's lock chain
//!    ([`crate::monitor`]), and the memory of the locked estimates ([`lock`]);
//! 7. **learn**: the appearance models from the estimate (held while lost only with
//!    [`AppearanceSettings::lock_holds_learning`](crate::AppearanceSettings::lock_holds_learning)).

mod estimate;
mod lock;
mod motion;
pub mod scale;

use std::time::Instant;

use dbn_switch::{ClutterHmm, ClutterState, OcclusionProcess, StatusHmm, StatusState};
use rand_distr::{Distribution, StandardNormal};
use smc_core::smooth::{SmootherSettings, smooth_marginals};
use smc_core::{Bootstrap, ParticleFilter, ParticleSet, StepDiagnostics};
use vision_core::{Ellipse, GreyImage};

use crate::api::{Estimate, Tracker, WeightedEllipse};
use crate::appearance::Appearance;
use crate::config::{ClutterMode, OcclusionMode, ProposalKind, TrackerConfig};
use crate::dynamics::reacquisition::TrackMemory;
use crate::dynamics::{ClutterProcess, OcclusionModel, TrackerDynamics};
use crate::frame::Frame;
use crate::monitor::visibility::{self, Visibility};
use crate::observation::{
    FrameContext, FrameObservation, LikelihoodModel, ObservationTerm, ReferenceLines,
};
use crate::particle::{Particle, default_status};
use crate::proposal::{MotionProposal, WeightedPrior};
use crate::smoothing::SmoothedRun;
use crate::space::{STATE_SLOTS, ShapeBounds, StateVector};
use crate::{Error, Result};
use estimate::PosteriorSummary;
use motion::MotionStage;
use scale::WorkingScale;

/// The smallest width and height of a frame a track can start on.
pub const MIN_FRAME_SIDE: usize = 2;

/// The particle-filter tracker behind every preset.
#[derive(Debug)]
pub struct ParticleTracker {
    config: TrackerConfig,
    dynamics: TrackerDynamics,
    likelihood: LikelihoodModel,
    filter: ParticleFilter<Particle>,
    set: Option<ParticleSet<Particle>>,
    /// The motion of each cluster of particles (with the motion proposal or the motion terms).
    motion: MotionStage,
    previous: Vec<f32>,
    /// Reused per frame: the hidden parts of the particles, as the estimators take them.
    clutter_states: Vec<ClutterState>,
    status_states: Vec<StatusState>,
    /// The last reported state, and the edge counts along its lines on the current frame (the
    /// reference lines of the ratio form, see [`FrameObservation::reference`]).
    last_state: StateVector,
    reference: ReferenceLines,
    /// The constant-velocity memory of the locked estimates (see [`crate::dynamics::reacquisition`]).
    memory: TrackMemory,
    /// The memory after each of the last locked frames, oldest first: the anchor of the jump is
    /// the oldest (see [`crate::dynamics::reacquisition::ReacquisitionSettings::rollback`]).
    history: std::collections::VecDeque<TrackMemory>,
    /// Whether a target is seen at all (with the status HMM only; see
    /// [`crate::monitor::visibility`]).
    visibility: Option<Visibility>,
    /// The target's appearance and its lock chain, when the configuration has them.
    appearance: Option<Appearance>,
    /// This frame's best appearance detection while the track is not locked, and while it is
    /// with [`crate::ReacquisitionSettings::detection_share`] > 0 when the detection reads as the
    /// target (`Appearance::looks_like_target`): where the jump component draws (see
    /// [`crate::dynamics::reacquisition`]).
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
            likelihood: LikelihoodModel::new(&config.likelihood, config.appearance.as_ref())?,
            filter: ParticleFilter::new(config.filter.clone())?,
            motion: MotionStage::new(config.motion.estimator)?,
            set: None,
            previous: Vec::new(),
            clutter_states: Vec::new(),
            status_states: Vec::new(),
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
                clusters: self.motion.clusters(),
                reference: &self.reference,
                appearance: self.appearance.as_ref(),
            },
        };
        let filter = &mut self.filter;
        let weighted = match self.config.proposal {
            ProposalKind::Prior
                if self.config.dynamics.hidden_exploration > 0.0
                    || self.dynamics.jump_needs_weighting() =>
            {
                let proposal = WeightedPrior(&self.dynamics);
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
                    clusters: self.motion.clusters(),
                    occlusion_aware: self.config.motion.occlusion_aware,
                };
                let prior = Some(&self.dynamics);
                propagate_and_weight(filter, set, &proposal, prior, &observation, seed, step)
            }
        };
        Ok(weighted?)
    }

    /// The index of the last frame processed (0 after `init`).
    /// Adds an observation term of the user's after the configured ones.
    pub(crate) fn push_term(&mut self, term: Box<dyn ObservationTerm>) {
        self.likelihood.push(term);
    }

    /// The pixels of the next frame whose colour the next update reads, `[x0, y0, x1, y1]` (x1
    /// and y1 excluded; [`Appearance::next_footprint`] around the last estimate); `None` when
    /// that is not known (no appearance model, or not started).
    pub(crate) fn next_colour_footprint(&self) -> Option<[usize; 4]> {
        let appearance = self.appearance.as_ref()?;
        self.set.as_ref()?;
        let last = self.config.space.pose(&self.last_state).to_ellipse()?;
        Some(appearance.next_footprint(self.size.0, self.size.1, &last))
    }

    /// The frame that the next frame given to this tracker was shrunk from, and the scale
    /// from this tracker's pixels to its (`ScaledTracker`): motions estimated on this tracker's
    /// frames are tested on its pixels (see `engine::motion`). Nothing without motion estimates.
    pub(crate) fn offer_source_frame(&mut self, frame: &Frame<'_>, scale: WorkingScale) {
        if self.config.needs_motion() {
            self.motion.offer_source(frame, scale);
        }
    }

    pub(crate) fn frames_done(&self) -> usize {
        self.frame
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
        // A frame one pixel wide or high has no gradient across it: every measurement would
        // fail at the first update, so the track is refused at its start.
        if frame.width() < MIN_FRAME_SIDE || frame.height() < MIN_FRAME_SIDE {
            return Err(Error::BadFrame {
                frame: 0,
                reason: format!(
                    "{}×{} is too small to track on: both sides need at least {MIN_FRAME_SIDE} \
                     pixels",
                    frame.width(),
                    frame.height()
                ),
            });
        }
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
            aspect: space.elongation_bounds(e0, d.aspect_range),
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
                .start(&frame, &tracked, self.config.motion.working_radius)?;
        }
        self.report(centre, start.elapsed().as_secs_f64() * 1e3)
    }

    fn update(&mut self, frame: Frame<'_>) -> Result<Estimate> {
        let start = Instant::now();
        if self.set.is_none() {
            return Err(Error::NotInitialised);
        }
        frame.check_size(self.size, self.frame + 1)?;
        // A grey frame after a colour start: the colour model would find no target colour on it
        // and report the target lost, frame after frame, while it is in view. Refused instead.
        if frame.colour().is_none()
            && self
                .appearance
                .as_ref()
                .is_some_and(Appearance::reads_colour)
        {
            return Err(Error::BadFrame {
                frame: self.frame + 1,
                reason: "a grey frame, but the track started on a colour frame and its colour \
                         model reads colour: give every frame in colour (a grey frame as RGB \
                         with equal channels tracks no better), or every frame in grey"
                    .into(),
            });
        }
        let step = self.frame as u64 + 1;
        let seed = self.config.seed;
        let resampled = {
            let Some(set) = self.set.as_mut() else {
                return Err(Error::NotInitialised);
            };
            self.filter
                .resample_if_needed(set, &self.config.resampling, seed, step)?
        };
        // The motion of each cluster and the appearance's detection read disjoint parts of the
        // tracker: with `filter.parallel` they run concurrently (the same results either way).
        let Some(set) = self.set.as_mut() else {
            return Err(Error::NotInitialised);
        };
        let parallel = self.config.filter.parallel;
        let (config, dynamics, motion) = (&self.config, &self.dynamics, &mut self.motion);
        let mut estimate_motion = || {
            if config.needs_motion() {
                motion.estimate(set.states_mut(), config, dynamics, &frame)
            } else {
                Ok((0, 0))
            }
        };
        let detect = DetectionStage {
            config,
            last_state: &self.last_state,
            unlocked: self.frame > self.memory.last_locked(),
        };
        let appearance = &mut self.appearance;
        let (motion_clusters, detection) = if parallel {
            rayon::join(estimate_motion, || detect.run(appearance.as_mut(), &frame))
        } else {
            (estimate_motion(), detect.run(appearance.as_mut(), &frame))
        };
        let motion_clusters = motion_clusters?;
        self.detection = detection;
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
        // The appearance learns from every estimate it holds; its lock chain is the status of a
        // tracker without Wu's status process.
        if let Some(appearance) = &mut self.appearance
            && let Some(e) = self.config.space.pose(&state).to_ellipse()
        {
            appearance.observe(&e)?;
        }
        let status = status.or_else(|| self.appearance.as_ref().map(Appearance::status));
        self.frame += 1;
        self.last_state = state;
        self.remember_if_locked(&state, gamma, status.as_ref());
        self.previous.clear();
        self.previous.extend_from_slice(frame.data());
        let mut report = self.report(state, 0.0)?;
        report.ess = weighted.ess;
        report.diagnostics = Some(StepDiagnostics::of(&resampled, &weighted));
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

/// The appearance's part of a frame before the particles move: its read of the frame, and the
/// detection the reacquisition's jump draws at.
struct DetectionStage<'a> {
    config: &'a TrackerConfig,
    last_state: &'a StateVector,
    /// Whether the last locked frame is before the last one.
    unlocked: bool,
}

impl DetectionStage<'_> {
    /// Reads `frame` into `appearance` around the last estimate and returns where the jump
    /// component draws this frame, if anywhere.
    fn run(&self, appearance: Option<&mut Appearance>, frame: &Frame<'_>) -> Option<[f64; 2]> {
        let appearance = appearance?;
        let e = self.config.space.pose(self.last_state).to_ellipse()?;
        appearance.read(frame, &e);
        let jumps = self
            .config
            .reacquisition
            .as_ref()
            .is_some_and(|r| self.unlocked || r.detection_share > 0.0);
        if !jumps {
            return None;
        }
        let detection = appearance.detect(&e);
        if self.unlocked {
            return detection;
        }
        // While locked, the abrupt-motion jump draws only at a detection that reads as the
        // target: where it has just vanished, the best patch of background would take the track
        // before the lock chain says lost.
        detection.filter(|&[x, y]| appearance.looks_like_target(&Ellipse { cx: x, cy: y, ..e }))
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
