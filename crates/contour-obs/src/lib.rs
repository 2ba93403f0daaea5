//! The observation layer of both papers, usable without particles: contour templates under a 2-D
//! affine pose, measurement lines along the contour normals, a 1-D edge detector, three contour
//! likelihoods, the forms of Wu's occlusion likelihood and clutter learning.
//!
//! - [`Contour`] / [`Template`]: the unit circle (ellipse template, also from a conic fit,
//!   [`fit_ellipse`], Wu §6) or a closed cubic B-spline, sampled at n points with outward normals.
//!   [`Affine2`] converts from Odobez's (T, s, e) (Odobez Eq. 11–12), Wu's affine shape space and
//!   ellipses.
//! - [`MeasurementLines`]: lines of length L centred on the posed contour points along their
//!   normals, sampled by bilinear interpolation, with the edges of [`EdgeDetector`]. It is the
//!   reusable workspace of every likelihood (no allocation per hypothesis or per line).
//! - [`OdobezLikelihood`]: Odobez Eq. 19. [`WuLikelihood`]: Wu Eq. 1–6 with the (λL)^m Poisson
//!   term of docs/MODELS.md; per-line pieces by [`WuLikelihood::line_terms`].
//!   [`OcclusionLikelihood`]: Wu Eq. 11–12. All in logs, finite for lines without edges, contours
//!   leaving the image and λ → 0; each has a batch form over many poses on one frame.
//! - [`WuTerm`]: Wu's likelihood as a tracker's contour term, in the one [`OcclusionForm`] chosen
//!   (Eq. 11 as printed, optionally with an occluder of unknown texture; γ as one hidden arc,
//!   with Eq. 12 or a neutral constant on the hidden lines; or a ratio against the no-target
//!   lines, [`ReferenceLines`]). [`log_poisson`] is the Poisson law of Eq. 1, in logs.
//! - [`learn_clutter`]: Wu §6.1, random lines + k-means → [`ClutterModel`].
//!
//! Speed (the trackers evaluate hundreds of hypotheses per frame): the edge definition is the
//! workspace's 1-D one (derivative of Gaussian along the line, see [`EdgeDetector`]), evaluated
//! cheaply. Line positions are stepped in fixed point (2⁻²⁴ px, no float-to-int conversion per
//! sample). The lines of a hypothesis that lie wholly inside the image are scanned together:
//! pixel reads line by line, then interpolation, filter and suppression as single vectorised
//! passes over all of them, giving one edge bit mask per line; lines over the border take the
//! general path, and both give the same edges to the bit. [`OdobezLikelihood`] scans only the
//! part of each line where an edge can beat the floor K (|offset| < σ√(−2 ln K) + ½, 17 of 29
//! samples by default), with values equal bit for bit to Eq. 19 on all the line's edges. Wu's
//! likelihoods count each line's edges and form Gaussians only in the window, sharing the
//! line's Poisson factor and forming the rest of the mixture in the linear domain: at most one
//! `ln` per line. Each likelihood also has a rayon batch (`log_likelihood_batch_par`),
//! bit-identical to the sequential one. No per-frame precomputation is needed; the existing
//! signatures are kept.
//!
//! Conventions: x right, y down, pixel (i, j) centred at (i, j); grey images are row-major f32
//! in 0–255 ([`vision_core::GreyImage`], sampled through [`Bilinear`]); a pose maps reference r to image p = A·r + t.
//!
//! ```
//! use contour_obs::{Affine2, Template, WuLikelihood, WuSettings};
//! use vision_core::GreyImage;
//!
//! // A bright disc of radius 20 centred at (40, 30) on a dark 80×60 image.
//! let (w, h) = (80, 60);
//! let data: Vec<f32> = (0..w * h)
//!     .map(|k| {
//!         let (x, y) = ((k % w) as f64 - 40.0, (k / w) as f64 - 30.0);
//!         if x.hypot(y) < 20.0 { 200.0 } else { 20.0 }
//!     })
//!     .collect();
//! let image = GreyImage::new(w, h, &data)?;
//! let model = WuLikelihood::new(WuSettings::default(), &Template::UnitCircle)?;
//! let mut ws = model.workspace()?;
//! let poses = [
//!     Affine2::from_ellipse(40.0, 30.0, 20.0, 20.0, 0.0),
//!     Affine2::from_ellipse(46.0, 30.0, 20.0, 20.0, 0.0),
//! ];
//! let mut logl = [0.0; 2];
//! model.log_likelihood_batch(&mut ws, &image, &poses, &[0.05], &mut logl)?;
//! assert!(logl[0] > logl[1]);
//! # Ok::<(), contour_obs::Error>(())
//! ```
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod affine;
mod clutter;
mod conic;
mod contour;
mod edges;
mod error;
mod image;
mod lines;
mod math;
mod occlusion_forms;
mod odobez;
mod poisson;
mod scan;
mod wu;

// The README's example is compiled and run as a doctest, so it cannot go stale.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
mod readme_doctest {}

pub use affine::Affine2;
pub use clutter::{
    Cluster, ClutterModel, ClutterSettings, kmeans_1d, learn_clutter, line_densities,
};
pub use conic::fit_ellipse;
pub use contour::{Contour, Template};
pub use edges::{EdgeDetector, EdgeSettings, Polarity, detect_edges};
pub use error::{Error, Result};
pub use image::Bilinear;
pub use lines::{LineSettings, MAX_LINES, MeasurementLines};
pub use occlusion_forms::{
    OcclusionForm, ReferenceLines, WuTerm, WuTermWorkspace, validate_clutter_line_fraction,
};
pub use odobez::{OdobezLikelihood, OdobezSettings, odobez_line_log_term};
pub use poisson::{log_poisson, poisson_neg_entropy};
/// The `rand` crate whose `Rng` [`line_densities`] takes:
/// import it from here (`use contour_obs::rand::Rng;`) so that an application's own `rand`, whatever its
/// version, does not matter.
pub use rand;
pub use wu::{
    LineTerms, OcclusionLikelihood, WuLikelihood, WuSettings, occlusion_line_log, wu_line_terms,
};
