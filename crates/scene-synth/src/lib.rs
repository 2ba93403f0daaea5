//! Deterministic synthetic clutter sequences with full ground truth for contour tracking.
//!
//! Four presets ([`Scenario`]) reproduce the situations the two papers are about:
//! - `mclutter`: static camera, background split into light / medium / heavy clutter regions
//!   whose edge densities along measurement lines match Wu's λ̄ = 0.01, 0.0824, 0.2144 per pixel
//!   (W §6.1, Fig. 3 and 10); the target wanders through every region;
//! - `occlusion`: the target passes behind an opaque occluder, free → partial → full → free
//!   (W §5, Fig. 13 and 15);
//! - `distractor`: a panning, zooming camera over an edge-rich background, a same-shape
//!   distractor circling close by and abrupt velocity jumps of 8–15 px/frame (O Fig. 6–7,
//!   Table 1);
//! - `zoom`: abrupt ±20–30 % scale changes and "head turns" where the interior texture slides
//!   while the outline stays (O Fig. 8).
//!
//! [`camera_zoom`] lays a known camera zoom over real footage instead: each frame cropped about a
//! point that follows the labelled target and resized back, the ground truth mapped alike.
//! [`stress`] lays every failure class of the stress suite over real footage alike.
//!
//! The target is an ellipse with a smooth random interior texture and an outline whose contrast
//! dips in low-contrast stretches. Clutter density is calibrated with the workspace's default
//! 1-D edge detector ([`edges`]). Every frame comes with a [`FrameTruth`]: ellipse, Odobez's
//! (Tx, Ty, s, e) (O Eq. 11–12), Wu's affine (a11 … t2), box, clutter class and density, visible
//! fraction and a status label.
//!
//! ```
//! use scene_synth::{Scenario, ScenarioParams, Scene};
//! let mut p = ScenarioParams::preset(Scenario::Mclutter);
//! p.frames = 5;
//! let scene = Scene::new(&p, 42)?;
//! let (frame, truth) = scene.render_frame(4)?;
//! assert_eq!(frame.width(), 320);
//! assert!((truth.ellipse.a - 22.0).abs() < 1e-9);
//! // Or write the OTB folder: scene_synth::write_sequence(dir, &scene)?;
//! # Ok::<(), scene_synth::Error>(())
//! ```
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod background;
pub mod camera_zoom;
pub mod edges;
mod error;
pub mod geometry;
pub mod params;
mod render;
pub mod stress;
pub mod texture;
pub mod trajectory;
mod truth;
mod writer;

// The README's example is compiled and run as a doctest, so it cannot go stale.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
mod readme_doctest {}

pub use error::{Error, Result};
pub use geometry::{OdobezState, WuAffine, point_and_normal};
pub use params::{
    BackgroundParams, CameraParams, ClutterClass, ClutterParams, DistractorParams, HeadTurnParams,
    JumpParams, MotionParams, OccluderParams, ScaleChangeParams, Scenario, ScenarioParams,
    StatusThresholds, TargetParams,
};
pub use render::{Scene, to_f32};
pub use truth::FrameTruth;
pub use writer::{BOX_CONVENTION, write_sequence};
