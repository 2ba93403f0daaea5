//! Tracker configuration: any shape space, any proposal, any product of likelihood terms, any
//! hidden switching processes — and the named presets of both papers ([`presets`]).
//!
//! A configuration names the pieces it uses and nothing else. Its printed form (JSON or TOML,
//! `track config`; the [`Serialize`] of [`TrackerConfig`], [`print`]) leaves out every section
//! and field the configured tracker does not read, and loading fills in what is missing with the
//! value the printer left out, so `parse(print(c)) == c`. A file that sets an unread setting to
//! anything else is refused by [`TrackerConfig::validate`], naming the setting and why it is not
//! read: a setting a tracker cannot honour is never silently ignored.

use dbn_switch::{ClutterConfig, OcclusionConfig, StatusConfig};
use serde::{Deserialize, Serialize};
use smc_core::{FilterSettings, ResamplingScheme};

use crate::appearance::AppearanceSettings;
use crate::dynamics::DynamicsSettings;
use crate::dynamics::reacquisition::ReacquisitionSettings;
use crate::observation::LikelihoodSettings;
use crate::space::ShapeSpace;
use crate::{Error, Result};
use vision_core::Ellipse;

mod parse;
mod presets;
mod print;
pub mod ranges;
mod unread;

pub use parse::ConfigFormat;

pub use presets::{
    CLUTTER_LINE_FRACTION, CONTOUR_SHAPE_TOLERANCE, FIXED_LAMBDA, HEAD_DETECTION_SHARE,
    HEAD_WORKING_RADIUS, OCCLUSION_ARC, Preset, SHAPE_VELOCITY_RETENTION, UNKNOWN_OCCLUDER_SHARE,
    W_OCC_SIGMA_GAMMA,
};

/// Settings of Odobez's motion proposal (Eq. 16) and of the motion estimates behind p_c1.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MotionSettings {
    /// The robust estimator (Odobez §4.2). Default `motion_est::Settings::tracking()`: 0.1 px
    /// tolerances, at most 8 iterations per level — a particle cloud needs no better.
    pub estimator: motion_est::Settings,
    /// Start each cluster's estimate from the last converged one before it (default true):
    /// clusters of one frame cover nearly the same region, so the estimator can skip its coarse
    /// levels.
    #[serde(default = "yes")]
    pub warm_start: bool,
    /// When the first cluster's motion cannot be estimated (no dominant motion within the
    /// estimator's reliability ceiling, or any other failure), estimate no later cluster of the
    /// frame: all fall back to the prior (default false: every cluster is estimated, as Odobez
    /// does; `head` too). A speed setting: the clusters of one head cover nearly the same region
    /// and nearly always fail together, and a failed estimate costs as much as a cold start, but
    /// the few later clusters that would have succeeded carry fast motion (docs/DECISIONS.md).
    #[serde(default)]
    pub fail_together: bool,
    /// Estimate a global intensity offset too (default false).
    pub offset: bool,
    /// Smallest number of clusters (Odobez: 20).
    pub min_clusters: usize,
    /// Clusters per particle (Odobez: 1/10).
    pub clusters_per_particle: f64,
    /// Lloyd iterations of the clustering (default 3).
    pub cluster_iterations: usize,
    /// Mix the prior into the motion proposal by each particle's occlusion γ (no effect without
    /// an occlusion model). See `proposal::MotionProposal::occlusion_aware`. Default false: it lost
    /// tracks on `mclutter` and did not carry the target through the full occlusion of the
    /// `occlusion` scene either (docs/DECISIONS.md).
    #[serde(default)]
    pub occlusion_aware: bool,
    /// The mean radius, in pixels, that the target is shrunk to for the motion estimates (see
    /// [`crate::working_scale`]; fixed at initialisation); `None`: the tracker's own pixels. Default
    /// [`MOTION_WORKING_RADIUS`]: the dominant affine motion of a region of ~800 pixels is
    /// already found to a small fraction of a pixel, so more pixels only cost time (an estimate
    /// costs as much as the region has pixels), while a large face's own fine motions (eyes,
    /// mouth, hair) weigh more in the robust fit the finer the resolution.
    #[serde(default = "default_motion_working_radius")]
    pub working_radius: Option<f64>,
    /// Pixels of the frame's own resolution read to test an estimate made at the working scale
    /// (default 2048; see `engine::motion`): the estimator's reliability ceiling is in grey
    /// levels of the frame's noise, which shrinking averages away, so a motion found on the
    /// shrunk frames is accepted only if its residual scale on the frame's pixels stays under
    /// the ceiling, as an estimate made there would have to. The scale of n residuals has a
    /// relative spread of about 1/√(2n), 1.6 % for 2048; more only costs time.
    #[serde(default = "default_frame_check_pixels")]
    pub frame_check_pixels: usize,
}

fn default_frame_check_pixels() -> usize {
    2048
}

/// The default of [`MotionSettings::working_radius`], the same as `head`'s whole-tracker
/// working radius ([`HEAD_WORKING_RADIUS`]), so that every preset sees the target's motion at
/// one resolution.
pub const MOTION_WORKING_RADIUS: f64 = HEAD_WORKING_RADIUS;

fn default_motion_working_radius() -> Option<f64> {
    Some(MOTION_WORKING_RADIUS)
}

impl Default for MotionSettings {
    fn default() -> Self {
        Self {
            estimator: motion_est::Settings::tracking(),
            offset: false,
            min_clusters: 20,
            clusters_per_particle: 0.1,
            cluster_iterations: 3,
            occlusion_aware: false,
            warm_start: true,
            fail_together: false,
            working_radius: default_motion_working_radius(),
            frame_check_pixels: default_frame_check_pixels(),
        }
    }
}

impl MotionSettings {
    /// K = max(min_clusters, N · clusters_per_particle), at most N.
    pub fn cluster_count(&self, n: usize) -> usize {
        ((n as f64 * self.clusters_per_particle) as usize)
            .max(self.min_clusters)
            .clamp(1, n.max(1))
    }
}

/// Which proposal draws the new particles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProposalKind {
    /// The transition prior (bootstrap / CONDENSATION).
    Prior,
    /// Odobez's motion proposal N(α_{k−1} + α̇, Λ̂ + Λ_wp) (Eq. 16).
    Motion,
}

/// How the clutter density λ of the particles is modelled. Read by Wu's likelihood only
/// ([`LikelihoodSettings::clutter`]); the default, which a file without `clutter` loads as, is
/// one fixed λ of [`FIXED_LAMBDA`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClutterMode {
    /// One fixed λ per pixel.
    Fixed {
        /// Edges per pixel.
        lambda: f64,
    },
    /// β switching (with λ | β fixed or Gaussian, per the config's `lambda_model`).
    Switching(ClutterConfig),
}

impl Default for ClutterMode {
    fn default() -> Self {
        ClutterMode::Fixed {
            lambda: FIXED_LAMBDA,
        }
    }
}

/// How occlusion is modelled.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OcclusionMode {
    /// No occlusion (γ = 0); the default.
    #[default]
    None,
    /// γ as a Gaussian random walk (Wu Eq. 13).
    RandomWalk(OcclusionConfig),
    /// The status HMM {α, γ} (Wu §6.3).
    Status(StatusConfig),
}

/// How the reported pose is computed from the particles. Read only with clutter switching
/// ([`ClutterMode::Switching`]): without it there is no clutter class β̂, and the pose is the
/// weighted mean.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoseEstimator {
    /// The weighted mean of the states; the default.
    #[default]
    Mean,
    /// The mean of the particles of the most probable clutter class β̂ (Wu §4); needs clutter
    /// switching.
    ClassConditionalMean,
}

/// Everything that defines a tracker. Load from JSON or TOML ([`TrackerConfig::parse`]), or start
/// from a [`Preset`].
///
/// A configuration names the pieces it uses and nothing else: its serialized form (JSON or TOML,
/// `track config`) leaves out every section and field the tracker does not read (`motion`
/// without the motion proposal or motion consistency, `clutter` without Wu's likelihood, the
/// likelihood terms that are off, `estimator` without clutter switching, …), and loading fills
/// each in with its default, so a printed configuration parses back to itself.
/// [`TrackerConfig::validate`] refuses an unread setting at any other value, by its dotted path.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackerConfig {
    /// A name for reports.
    pub name: String,
    /// Number of particles.
    pub particles: usize,
    /// Seed of every random draw.
    pub seed: u64,
    /// Shape space of the particles.
    pub space: ShapeSpace,
    /// Kinematic prior.
    pub dynamics: DynamicsSettings,
    /// Proposal.
    pub proposal: ProposalKind,
    /// Motion estimation settings, read only by the motion proposal and p_c1
    /// ([`TrackerConfig::needs_motion`]); default [`MotionSettings::default`].
    #[serde(default)]
    pub motion: MotionSettings,
    /// Likelihood terms (default: none; a tracker then needs its appearance terms).
    #[serde(default)]
    pub likelihood: LikelihoodSettings,
    /// Clutter process, read only with Wu's likelihood (default: one fixed λ,
    /// [`ClutterMode::default`]).
    #[serde(default)]
    pub clutter: ClutterMode,
    /// Occlusion process (default none).
    #[serde(default)]
    pub occlusion: OcclusionMode,
    /// Particle filter settings (resampling threshold, parallelism).
    #[serde(default)]
    pub filter: FilterSettings,
    /// Resampling scheme.
    #[serde(default)]
    pub resampling: ResamplingScheme,
    /// Pose estimator, read only with clutter switching (default the mean).
    #[serde(default)]
    pub estimator: PoseEstimator,
    /// Spread of the initial particles around the initial ellipse, as a fraction of the dynamics
    /// noise (default 0.5).
    #[serde(default = "default_init_spread")]
    pub init_spread: f64,
    /// The reacquisition jump after an occlusion (see [`ReacquisitionSettings`](crate::ReacquisitionSettings)); `None`: off. On in
    /// w-occ, w-eval and full: it lets a track find the target again after a full occlusion
    /// (docs/DECISIONS.md). With Wu's Eq. 12 as printed the jump does not help: a lost track
    /// sits on γ ≈ 1 hypotheses that Eq. 12 rates above the reappearing target.
    #[serde(default)]
    pub reacquisition: Option<ReacquisitionSettings>,
    /// The mean radius, in pixels, that the target is shrunk to before tracking (see
    /// [`crate::working_scale`]); a target no larger is tracked at full resolution. `None` (the
    /// default, and every paper preset's): always full resolution, as the papers; `head`'s is
    /// [`HEAD_WORKING_RADIUS`]. Measured on the real development set, it helped some presets and
    /// hurt others (docs/DECISIONS.md).
    #[serde(default)]
    pub working_radius: Option<f64>,
    /// The appearance model and its colour-contrast, template and contour-contrast terms
    /// ([`crate::appearance`]); `None` (every paper preset): off. With it, the lock chain on
    /// the estimate's colour reports the track's status unless Wu's status process does.
    #[serde(default)]
    pub appearance: Option<AppearanceSettings>,
}

fn yes() -> bool {
    true
}

pub(crate) fn default_init_spread() -> f64 {
    0.5
}

impl TrackerConfig {
    /// Checks every part: every numeric setting against its range ([`crate::ranges`], the error
    /// naming the setting's dotted path, as `dynamics.sigma_translation`, and the range), then
    /// what ranges cannot say (a transition matrix whose rows sum to 1, terms that need each
    /// other).
    ///
    /// # Errors
    /// The first invalid setting, as [`Error::InvalidSetting`] or the owning crate's error.
    pub fn validate(&self) -> Result<()> {
        // Every numeric setting in a range that can work, named by its dotted path; the checks
        // below then cover what a range cannot say.
        crate::ranges::check_ranges(self)?;
        if !(1..=MAX_PARTICLES).contains(&self.particles) {
            return Err(Error::InvalidSetting {
                name: "particles",
                reason: format!("{} must be between 1 and {MAX_PARTICLES}", self.particles),
            });
        }
        if self.filter.output_size.is_some_and(|m| m > MAX_PARTICLES) {
            return Err(Error::InvalidSetting {
                name: "filter.output_size",
                reason: format!("must be at most {MAX_PARTICLES}"),
            });
        }
        if self.motion.cluster_iterations > MAX_CLUSTER_ITERATIONS {
            return Err(Error::InvalidSetting {
                name: "motion.cluster_iterations",
                reason: format!(
                    "{} must be at most {MAX_CLUSTER_ITERATIONS}",
                    self.motion.cluster_iterations
                ),
            });
        }
        if !(self.init_spread.is_finite() && self.init_spread >= 0.0) {
            return Err(Error::InvalidSetting {
                name: "init_spread",
                reason: format!("{} must be finite and non-negative", self.init_spread),
            });
        }
        if let Some(r) = self.working_radius
            && !(r.is_finite() && r >= 4.0)
        {
            return Err(Error::InvalidSetting {
                name: "working_radius",
                reason: format!("{r} must be at least 4 px (or absent: full resolution)"),
            });
        }
        self.dynamics.validate()?;
        self.likelihood.validate()?;
        if self.likelihood.is_empty() && self.appearance.is_none() {
            return Err(Error::InvalidSetting {
                name: "likelihood",
                reason: "at least one of shape, implicit_motion, clutter or appearance is needed"
                    .into(),
            });
        }
        if let Some(a) = &self.appearance {
            a.validate()?;
            if self.space != ShapeSpace::Odobez {
                return Err(Error::InvalidSetting {
                    name: "appearance",
                    reason: "the appearance terms read axis-aligned ellipses: they need the \
                             odobez shape space"
                        .into(),
                });
            }
        }
        if let Some(r) = &self.reacquisition {
            r.validate()?;
        }
        self.filter.validate()?;
        self.motion.estimator.validate()?;
        if !(self.motion.clusters_per_particle.is_finite()
            && self.motion.clusters_per_particle >= 0.0)
        {
            return Err(Error::InvalidSetting {
                name: "motion.clusters_per_particle",
                reason: format!(
                    "{} must be finite and non-negative",
                    self.motion.clusters_per_particle
                ),
            });
        }
        match &self.clutter {
            ClutterMode::Fixed { lambda } if !(lambda.is_finite() && *lambda > 0.0) => {
                return Err(Error::InvalidSetting {
                    name: "clutter.lambda",
                    reason: format!("{lambda} must be finite and positive"),
                });
            }
            ClutterMode::Switching(c) => c.validate()?,
            ClutterMode::Fixed { .. } => {}
        }
        match &self.occlusion {
            OcclusionMode::RandomWalk(c) => c.validate()?,
            OcclusionMode::Status(c) => c.validate()?,
            OcclusionMode::None => {}
        }
        if self.likelihood.clutter.is_none()
            && (matches!(self.clutter, ClutterMode::Switching(_))
                || !matches!(self.occlusion, OcclusionMode::None))
        {
            return Err(Error::InvalidSetting {
                name: "likelihood.clutter",
                reason: "clutter switching and occlusion need Wu's clutter likelihood".into(),
            });
        }
        // Last: a setting that is out of range or contradicts another is named for that first.
        self.check_unread()
    }

    /// Whether the tracker's status has a partially occluded state: Wu's α (the status HMM) or
    /// γ̂'s ranges. The lock chain of a tracker with appearance terms and no occlusion process
    /// says locked or lost only.
    pub fn has_partial_state(&self) -> bool {
        !(self.appearance.is_some() && self.occlusion == OcclusionMode::None)
    }

    /// Whether the tracker reports the probabilities of its status (Wu's status HMM, or the
    /// lock chain of the appearance terms).
    pub fn reports_status_probabilities(&self) -> bool {
        matches!(self.occlusion, OcclusionMode::Status(_)) || self.appearance.is_some()
    }

    /// Whether the likelihood is tempered ([`FilterSettings::min_ess_fraction`]).
    pub fn is_tempered(&self) -> bool {
        self.filter.min_ess_fraction.is_some()
    }

    /// Whether the tracker follows rotated contours: the affine shape space of Wu's trackers
    /// (`w-*`). Odobez's space (`m1`, `m2`, `m3`, `full`, `head`) tracks
    /// axis-aligned ellipses.
    pub fn rotates(&self) -> bool {
        self.space == ShapeSpace::Affine
    }

    /// The ellipse `e` as this configuration's tracker starts from it, exactly; every tracker's
    /// `init` goes through it, so a library user and the command line get the same answer.
    ///
    /// A tracker that [rotates](Self::rotates) takes any ellipse. The others take an ellipse at a
    /// multiple of π/2 (within [`AXIS_ANGLE_TOLERANCE`]), written at angle 0 with the semi-axes
    /// swapped at odd multiples, and a circle at any angle (the same circle). Any other angle
    /// cannot be represented (`m1` would start from the rotated ellipse's bounding ellipse, `head`
    /// would drop the angle), so it is refused rather than silently changed.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] named `initial ellipse`: a value that is not finite, a semi-axis
    /// that is not positive, or a rotated, non-circular ellipse for a tracker that cannot rotate.
    ///
    /// # Examples
    /// ```
    /// use trackers::{Ellipse, Preset};
    ///
    /// let m1 = Preset::M1.config(100, 1);
    /// let quarter = Ellipse::new(50.0, 40.0, 20.0, 10.0, std::f64::consts::FRAC_PI_2);
    /// assert_eq!(m1.initial_ellipse(&quarter)?, Ellipse::new(50.0, 40.0, 10.0, 20.0, 0.0));
    /// assert!(m1.initial_ellipse(&Ellipse::new(50.0, 40.0, 20.0, 10.0, 0.7)).is_err());
    /// let tilted = Ellipse::new(50.0, 40.0, 20.0, 10.0, 0.7);
    /// assert_eq!(Preset::WFixed.config(100, 1).initial_ellipse(&tilted)?, tilted);
    /// # Ok::<(), trackers::Error>(())
    /// ```
    pub fn initial_ellipse(&self, e: &Ellipse) -> Result<Ellipse> {
        crate::space::check_initial(e)?;
        if self.rotates() {
            return Ok(*e);
        }
        if e.a == e.b {
            return Ok(Ellipse::new(e.cx, e.cy, e.a, e.b, 0.0));
        }
        let quarter = std::f64::consts::FRAC_PI_2;
        let k = (e.angle / quarter).round();
        if (e.angle - k * quarter).abs() <= AXIS_ANGLE_TOLERANCE {
            let odd = k.rem_euclid(2.0) == 1.0;
            let (a, b) = if odd { (e.b, e.a) } else { (e.a, e.b) };
            return Ok(Ellipse::new(e.cx, e.cy, a, b, 0.0));
        }
        Err(Error::InvalidSetting {
            name: "initial ellipse",
            reason: format!(
                "the {} tracker follows axis-aligned ellipses only, so it cannot start from an \
                 ellipse at angle {} rad; give an angle that is a multiple of π/2 (or a box), or \
                 use a tracker that rotates (w-fixed, w-switch, w-hmm, w-occ, w-eval)",
                self.name, e.angle
            ),
        })
    }

    /// Whether motion must be estimated every frame: the motion proposal or motion consistency
    /// (p_c1). Only then is [`TrackerConfig::motion`] read.
    pub fn needs_motion(&self) -> bool {
        self.proposal == ProposalKind::Motion || self.likelihood.motion_consistency
    }

    /// Whether the tracker has measurement lines, whose edge detector `--edge-threshold` sets:
    /// Odobez's shape likelihood or Wu's clutter likelihood.
    pub fn has_measurement_lines(&self) -> bool {
        self.likelihood.shape.is_some() || self.likelihood.clutter.is_some()
    }

    /// Sets the 1-D edge detector's threshold, in grey levels per pixel, of every
    /// measurement-line term.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] named `edge threshold` when the tracker has no measurement
    /// lines ([`TrackerConfig::has_measurement_lines`]): the threshold would be ignored.
    pub fn set_edge_threshold(&mut self, threshold: f32) -> Result<()> {
        if !self.has_measurement_lines() {
            return Err(Error::InvalidSetting {
                name: "edge threshold",
                reason: format!(
                    "the `{}` tracker has no measurement lines (neither `likelihood.shape` nor \
                     `likelihood.clutter`), so an edge threshold would not be read",
                    self.name
                ),
            });
        }
        if let Some(shape) = self.likelihood.shape.as_mut() {
            shape.lines.edge.threshold = threshold;
        }
        if let Some(clutter) = self.likelihood.clutter.as_mut() {
            clutter.lines.edge.threshold = threshold;
        }
        Ok(())
    }
}

/// Largest difference, in radians, between the angle of an initial ellipse and a multiple of π/2
/// that a tracker of axis-aligned ellipses accepts as that multiple (angles typed to six
/// decimals); see [`TrackerConfig::initial_ellipse`].
pub const AXIS_ANGLE_TOLERANCE: f64 = 1e-6;

/// Most particles a configuration may ask for: beyond this a frame takes seconds and the
/// particle sets gigabytes, which is never what a tracker needs.
pub const MAX_PARTICLES: usize = 1_000_000;

/// Most Lloyd iterations of the motion clustering (it settles in a handful).
pub const MAX_CLUSTER_ITERATIONS: usize = 100;

/// Number of particles of a preset when the caller names none (`track run`, `track config`, the
/// Python binding).
pub const DEFAULT_PARTICLES: usize = 200;

/// Seed of a preset when the caller names none.
pub const DEFAULT_SEED: u64 = 1;

#[cfg(test)]
mod tests;
