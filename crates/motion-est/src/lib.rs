//! Robust multiresolution parametric motion estimation with an honest covariance, and the patch
//! sampler and NCC distance of the implicit motion likelihood — Odobez, Gatica-Perez & Ba 2003,
//! §4.2 (Eq. 13–15) and Eq. 22–23, after their ref. 10 (Odobez & Bouthemy 1995).
//!
//! * [`Pyramid`]: Gaussian pyramids in f32, over a window of the image, in reusable buffers.
//! * [`MotionEstimator`]: coarse-to-fine incremental Gauss–Newton with IRLS (Tukey biweight by
//!   default, Cauchy and Huber selectable) minimising Σ_{r∈R} ρ(z₁(r + d_Θ(r)) − z₀(r) − c) over a
//!   support [`Region`], for translation, translation + scale, or affine (Eq. 13) models with an
//!   optional intensity offset c. The result carries a covariance whose predicted errors match
//!   the observed ones (see [`estimator`] for its derivation).
//! * [`odobez_state_derivative`]: Eq. 15, affine parameters → (Ṫx, Ṫy, ṡ, ė) with covariance.
//! * [`sample_patch_into`], [`ncc_distance`]: Eq. 22–23; [`ImplicitMotionTerm`]: the implicit
//!   motion likelihood ln p_c2 = −λ_c d_c they make (Eq. 22).
//!
//! Images are borrowed [`vision_core::GreyImage`]s (row-major f32 grey levels, x right, y down, pixel (i, j)
//! centred at (i, j)). For many regions on the same frame pair, build both pyramids once with
//! [`MotionEstimator::build_pyramid_into`] and call [`MotionEstimator::estimate`] per region with
//! one [`Workspace`].
//!
//! # Example
//! ```
//! use motion_est::{ModelSpec, MotionEstimator, MotionModel, Region, Settings};
//! use vision_core::GreyImage;
//! // A smooth texture and a copy shifted by (1.5, −0.75) px.
//! let (w, h) = (96, 80);
//! let tex = |x: f64, y: f64| 128.0 + 40.0 * (0.31 * x + 0.1 * y).sin() + 30.0 * (0.23 * y - 0.05 * x).cos();
//! let f0: Vec<f32> = (0..w * h).map(|k| tex((k % w) as f64, (k / w) as f64) as f32).collect();
//! let f1: Vec<f32> = (0..w * h).map(|k| tex((k % w) as f64 - 1.5, (k / w) as f64 + 0.75) as f32).collect();
//! let est = MotionEstimator::new(Settings::default())?;
//! let r = est.estimate_images(
//!     GreyImage::new(w, h, &f0)?,
//!     GreyImage::new(w, h, &f1)?,
//!     &Region::Full,
//!     ModelSpec::new(MotionModel::Translation, false),
//!     None,
//! )?;
//! // An estimate that did not converge, or that no dominant motion explains, would be
//! // `Err(Error::Unreliable { .. })`: an `Ok` estimate is a reliable one.
//! assert!(r.converged && r.reliable);
//! assert!((r.params[0] - 1.5).abs() < 0.01 && (r.params[1] + 0.75).abs() < 0.01);
//! # Ok::<(), motion_est::Error>(())
//! ```
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

// The README's example is compiled and run as a doctest, so it cannot go stale.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
mod readme_doctest {}

pub mod error;
pub mod estimator;
mod implicit;
pub mod model;
mod occlusion;
pub mod odobez;
pub mod patch;
pub mod pyramid;
pub mod region;
mod restart;
pub mod robust;
mod simd;

pub use error::{Error, Result};
pub use estimator::{FrameBuffers, MotionEstimate, MotionEstimator, Request, Settings, Workspace};
pub use implicit::{ImplicitMotionSettings, ImplicitMotionTerm, PatchPose};
pub use model::{ModelSpec, MotionModel};
pub use odobez::odobez_state_derivative;
pub use patch::{
    NccSettings, UNINFORMATIVE_DISTANCE, ncc_distance, sample_patch, sample_patch_into,
    unit_disc_grid,
};
pub use pyramid::{Level, Pyramid, Window};
pub use region::{MaskView, Region};
pub use robust::RobustFunction;
