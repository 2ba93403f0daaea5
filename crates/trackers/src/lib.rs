//! Particle-filter contour trackers composed from the workspace's layers: `smc-core` (the filter),
//! `motion-est` (robust affine motion, NCC patches), `contour-obs` (contours, measurement lines,
//! likelihoods) and `dbn-switch` (hidden clutter, occlusion and status processes).
//!
//! Any proposal goes with any product of observation terms ([`TrackerConfig`]); the papers'
//! trackers are named [`Preset`]s:
//!
//! | preset | paper | proposal | weight |
//! |---|---|---|---|
//! | `m1` | Odobez M1 (CONDENSATION) | Gaussian AR2 prior | p_sh (Eq. 19) |
//! | `m2` | Odobez M2 | Gaussian AR2 prior | p_sh · p_c2 (Eq. 19, 22–23) |
//! | `m3` | Odobez M3 | motion, Eq. 16 | p_sh · p_c2 · p_c1 · p(c_k\|c_{k−1}) / q = Eq. 24 |
//! | `w-fixed` | Wu, one λ | Gaussian AR2 (affine) | Wu Eq. 1–6 |
//! | `w-switch` | Wu §6.1 without HMM | prior, β switching | Wu Eq. 1–6 at λ̄_β |
//! | `w-hmm` | Wu Fig. 5–6 | prior, {β, λ} HMM | Wu Eq. 1–6 at λ |
//! | `w-occ` | Wu §5 | prior, {β, λ} HMM, γ walk (σ_γ 0.3), reacquisition | Wu Eq. 11–12, γ as one hidden arc |
//! | `w-eval` | Wu §6.3 | prior, {β, λ} HMM, {α, γ} HMM, reacquisition | Wu Eq. 11–12, γ as one hidden arc |
//! | `full` | neither | motion, Eq. 16, all hidden processes | Wu Eq. 11–12 · p_c2 · p_c1 · prior / q |
//! | `head` | neither (recommended for real footage) | motion, Eq. 16 (one cluster), Gaussian AR2 prior, at a working scale | colour contrast · template ([`appearance`]) · prior / q |
//!
//! # Example
//! ```
//! use vision_core::Ellipse;
//! use trackers::{Frame, Preset, build};
//!
//! // A bright disc of radius 20 on a dark background, moving 2 px right per frame.
//! let (w, h) = (96, 72);
//! let frame_at = |k: usize| -> Vec<f32> {
//!     (0..w * h)
//!         .map(|i| {
//!             let (x, y) = ((i % w) as f64, (i / w) as f64);
//!             let d = ((x - 40.0 - 2.0 * k as f64).powi(2) + (y - 36.0).powi(2)).sqrt();
//!             if d < 20.0 { 200.0 } else { 40.0 }
//!         })
//!         .collect()
//! };
//! let mut tracker = build(Preset::M1.config(100, 7))?;
//! let first = frame_at(0);
//! let start = Ellipse { cx: 40.0, cy: 36.0, a: 20.0, b: 20.0, angle: 0.0 };
//! tracker.init(Frame::new(w, h, &first)?, start)?;
//! let mut last = None;
//! for k in 1..6 {
//!     let pixels = frame_at(k);
//!     last = Some(tracker.update(Frame::new(w, h, &pixels)?)?);
//! }
//! let e = last.unwrap().ellipse;
//! assert!((e.cx - 50.0).abs() < 2.0 && (e.cy - 36.0).abs() < 2.0);
//! # Ok::<(), trackers::Error>(())
//! ```
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

#[cfg(doctest)]
#[doc = include_str!("../README.md")]
mod readme_doctest {}

mod api;
pub mod appearance;
mod build;
mod cluster;
mod config;
mod dynamics;
mod engine;
mod error;
mod frame;
mod monitor;
pub mod observation;
mod particle;
pub mod proposal;
pub mod smoothing;
mod space;
pub use engine::scale as working_scale;

pub use api::{Estimate, Tracker, WeightedEllipse, status_from_gamma};
pub use appearance::{AppearanceSettings, HistogramSettings};
pub use build::{build, build_preset, build_with_terms};
pub use config::{
    AXIS_ANGLE_TOLERANCE, CLUTTER_LINE_FRACTION, CONTOUR_SHAPE_TOLERANCE, ClutterMode,
    ConfigFormat, DEFAULT_PARTICLES, DEFAULT_SEED, FIXED_LAMBDA, HEAD_DETECTION_SHARE,
    HEAD_WORKING_RADIUS, MAX_CLUSTER_ITERATIONS, MAX_PARTICLES, MOTION_WORKING_RADIUS,
    MotionSettings, OCCLUSION_ARC, OcclusionMode, PoseEstimator, Preset, ProposalKind,
    SHAPE_VELOCITY_RETENTION, TrackerConfig, UNKNOWN_OCCLUDER_SHARE, W_OCC_SIGMA_GAMMA, ranges,
};
pub use dynamics::reacquisition::ReacquisitionSettings;
pub use dynamics::{DynamicsSettings, NoiseKind};
pub use engine::ParticleTracker;
pub use error::{Error, Result};
pub use frame::{Frame, FrameBuf};
pub use observation::{FrameContext, ImplicitMotionSettings, LikelihoodSettings, ObservationTerm};
pub use particle::Particle;
pub use smc_core::smooth::SmootherSettings;
pub use smoothing::{ChainCounts, SmoothedRun, SwitchingStatistics};
pub use space::{STATE_SLOTS, ShapeSpace, StateVector};
pub use working_scale::{ScaledTracker, WorkingScale};

// The types of `Estimate`'s public fields, and of a tracker's inputs, so that a user needs no
// other crate of the workspace to read what a tracker reports.
pub use dbn_switch::{ClutterEstimate, StatusEstimate};
pub use smc_core::StepDiagnostics;
pub use vision_core::{BoundingBox, Ellipse, GreyBuffer, GreyImage, ToGreyBuffer, TrackStatus};

/// What a program that runs a tracker needs, in one import: `use trackers::prelude::*;`.
pub mod prelude {
    pub use crate::{
        BoundingBox, ClutterEstimate, Ellipse, Estimate, Frame, FrameBuf, GreyImage, Preset,
        StatusEstimate, StepDiagnostics, ToGreyBuffer, TrackStatus, Tracker, TrackerConfig, build,
        build_preset,
    };
}
