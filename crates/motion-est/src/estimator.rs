//! Coarse-to-fine robust Gauss–Newton estimation of a parametric motion model (Odobez et al. 2003
//! §4.2, Eq. 13–14; their reference [10], Odobez & Bouthemy 1995), with an honest covariance.
//!
//! At each pyramid level the displaced frame difference DFD(r) = z₁(r + d_Θ(r)) − z₀(r) − c is
//! linearised around the current Θ and Σ w_r (DFD + J_r δ)² is minimised, with IRLS weights
//! w_r = ψ(DFD/σ̂)/(DFD/σ̂) and σ̂ a robust scale (see [`crate::robust`]). J_r uses the mean of the
//! two frames' gradients (the first frame's gradient mapped through the current linear part), which
//! converges over larger displacements than either gradient alone.
//!
//! # Covariance
//! At convergence Θ̂ solves F(Θ) = Σ_r m_r σ̂ ψ(DFD_r/σ̂) J_r = 0, so Cov(Θ̂) = H⁻¹ Var(F) H⁻ᵀ with
//! H = Σ_r m_r ψ'(DFD_r/σ̂) J_r J_rᵀ (the sandwich estimator of M-estimation). For jointly Gaussian
//! residuals with correlation ρ between two pixels, Cov(ψ, ψ) ≈ E[ψ']²·ρ (first Hermite term), and
//! Var(ψ) = E[ψ²] at the same pixel; so Var(F) = E[ψ']² Var(Σ_r u_r δDFD_r) with u_r = m_r J_r over
//! the pixels ρ does not reject, plus the same-pixel correction (E[ψ²] − E[ψ']²) σ̂² Σ_r m_r² J_r J_rᵀ.
//! (Using the realised ψ'(DFD_r/σ̂)² instead would over-state the variance by E[ψ'²]/E[ψ²] ≈ 1.10
//! for Tukey.) The DFD is computed on pre-smoothed images, so δDFD_r = (K∗n₁)(r+d) −
//! (K∗n₀)(r) is correlated across pixels; with n₀, n₁ white of variance σₙ², Var(Σ u_r (K∗n)(r)) =
//! σₙ² Σ_s (K∗u)(s)(K∗u)(s)ᵀ for the first frame; for the second, u is first spread onto the
//! interpolation taps around r + d(r). Cov(Θ̂) = σₙ² H⁻¹ [meat₀ + meat₁] H⁻ᵀ. σₙ² itself is recovered
//! from the robust scale of the smoothed DFD, whose variance per pixel is σₙ²(ΣK² + q(f_x)q(f_y)),
//! where q accounts for the cubic interpolation of the second frame at fractional offset f.
//! Ignoring the smoothing (treating the DFD as white) and the robust weights is what makes the
//! original implementation under-report the error about 2.4×.

use std::ops::Range;

use nalgebra::{Matrix2, Matrix6, SMatrix, SVector};

use crate::image::ImageView;
use crate::meat::{Cell, Grid};
use crate::model::{ModelSpec, MotionModel};
use crate::pyramid::{Level, Pyramid, Window};
use crate::region::{PixelBox, Region};
use crate::robust::{RobustFunction, lower_quartile, robust_scale_from};
use crate::simd::simd;
use crate::{Error, Result, occlusion, restart};

pub(crate) type Mat7 = SMatrix<f64, 7, 7>;
type Vec7 = SVector<f64, 7>;

/// Settings of the estimator.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Settings {
    /// Maximum number of pyramid levels, including full resolution (default 5: reductions by up to
    /// 16, enough for displacements of ~20 px).
    pub levels: usize,
    /// Pre-smooth level 0 with the [1 4 6 4 1]/16 kernel (default true): it reduces noise in the
    /// gradients and aliasing of fine texture in the interpolation.
    pub presmooth: bool,
    /// Margin in level-0 pixels added around the region's box when pyramids are built for a single
    /// region (default 32). Pixels displaced beyond it are dropped like pixels leaving the image.
    pub margin: usize,
    /// The coarsest level used is the coarsest where the region still holds this many pixels
    /// (default 256).
    pub min_level_pixels: usize,
    /// The robust function (default Tukey biweight, c = 4.6851).
    pub robust: RobustFunction,
    /// Maximum Gauss–Newton iterations per level (default 20).
    pub max_iterations: usize,
    /// Convergence at full resolution: the largest displacement change of the region's box
    /// corners in one iteration, in pixels (default 5e-4).
    pub tolerance: f64,
    /// The same at coarser levels, in that level's pixels (default 0.01).
    pub coarse_tolerance: f64,
    /// Floor on the robust scale, in grey levels (default 0.1), so that noise-free images still get
    /// finite weights.
    pub min_scale: f64,
    /// Levels used when the estimate is warm-started from an initial guess
    /// ([`MotionEstimator::estimate_from`]); default 2 (full resolution and one reduction, enough
    /// to correct a guess that is off by a few pixels).
    #[serde(default = "default_warm_levels")]
    pub warm_levels: usize,
    /// The least [`MotionEstimate::inlier_fraction`] of a [`reliable`](MotionEstimate::reliable)
    /// estimate (default 0.5): the motion found must be that of a majority of the region's pixels
    /// that stay in the image, at the noise scale.
    #[serde(default = "default_min_inlier_fraction")]
    pub min_inlier_fraction: f64,
    /// The least inlier fraction of a re-started estimate that is reliable as the largest group
    /// (default 0.4): when the first fit is not reliable, the estimator re-starts from the
    /// motions that blocks of the region agree on and keeps the fit explaining most pixels; that
    /// fit is reliable below [`min_inlier_fraction`](Self::min_inlier_fraction) when its inlier
    /// fraction, plus the share of pixels that a surface in front of it covers in the second
    /// frame (when the order of the surfaces can be told), reaches this share. A block moving
    /// by a few pixels covers and uncovers pixels that no motion explains, so the dominant
    /// motion may explain less than half of the region.
    #[serde(default = "default_min_plurality_fraction")]
    pub min_plurality_fraction: f64,
    /// Ceiling on the scale of the IRLS weights at the two finest levels, grey levels (default
    /// 8 / 4.6851 ≈ 1.71: with Tukey's c, pixels whose DFD exceeds 8 grey levels get no weight, the
    /// fixed constant of Motion2D). Without it the scale measured at a compromise between two
    /// motions grows with the misfit (4–20 grey levels) and keeps the compromise (issue 16). It
    /// only acts when the noise scale exceeds it (σ ≳ 4 grey levels per frame with pre-smoothing);
    /// the reported scale, inlier fraction and covariance always use the noise scale.
    #[serde(default = "default_max_scale")]
    pub max_scale: f64,
}

fn default_max_scale() -> f64 {
    8.0 / 4.6851
}

fn default_warm_levels() -> usize {
    2
}

fn default_min_inlier_fraction() -> f64 {
    0.5
}

fn default_min_plurality_fraction() -> f64 {
    0.4
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            levels: 5,
            presmooth: true,
            margin: 32,
            min_level_pixels: 256,
            robust: RobustFunction::default(),
            max_iterations: 20,
            tolerance: 5e-4,
            coarse_tolerance: 0.01,
            min_scale: 0.1,
            warm_levels: default_warm_levels(),
            min_inlier_fraction: default_min_inlier_fraction(),
            min_plurality_fraction: default_min_plurality_fraction(),
            max_scale: default_max_scale(),
        }
    }
}

impl Settings {
    /// A preset for tracking, where an estimate feeds a particle filter's proposal whose noise is
    /// of the order of a pixel: the default settings with both tolerances loosened to 0.1 px (full
    /// resolution: from 5e-4; coarse levels: from 0.01 level pixels) and at most 8 iterations per
    /// level (instead of 20; 4 was too few for a cold start on a fast target, see
    /// `docs/results/motion-est.md`). Gauss–Newton's last step is then ≤ 0.1 px, but the estimate
    /// is much closer: on the issue's synthetic pairs the corner error is 0.0034 px (full frame)
    /// and 0.0102 px (64×64), within the default settings' bounds, and the covariance stays
    /// calibrated (ratio 0.91 on 64×64), because the final scale and covariance are always taken
    /// at Θ̂ (see `REUSE_STEP`; after a last step of at most `LINEAR_STEP` the residuals at Θ̂
    /// are the last evaluation's moved to first order, otherwise they are evaluated again). Non-convergence is still reported.
    pub fn tracking() -> Self {
        Self {
            tolerance: 0.1,
            coarse_tolerance: 0.1,
            max_iterations: 8,
            ..Self::default()
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the first bad field.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &'static str, reason: String| Err(Error::InvalidSetting { name, reason });
        if self.levels == 0 || self.levels > 16 {
            return bad("levels", format!("{} must be in 1..=16", self.levels));
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", "must be at least 1".into());
        }
        if self.warm_levels == 0 {
            return bad("warm_levels", "must be at least 1".into());
        }
        for (name, v) in [
            ("tolerance", self.tolerance),
            ("coarse_tolerance", self.coarse_tolerance),
            ("min_scale", self.min_scale),
            ("max_scale", self.max_scale),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(name, format!("{v} must be finite and positive"));
            }
        }
        for (name, v) in [
            ("min_inlier_fraction", self.min_inlier_fraction),
            ("min_plurality_fraction", self.min_plurality_fraction),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return bad(name, format!("{v} must be in [0, 1]"));
            }
        }
        self.robust.validate()
    }
}

/// The result of one estimate.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MotionEstimate {
    /// The model estimated.
    pub spec: ModelSpec,
    /// Parameters in level-0 pixels, laid out as in [`MotionModel`], offset last when estimated.
    pub params: Vec<f64>,
    /// Their covariance, row-major `params.len()`², in level-0 units.
    pub covariance: Vec<f64>,
    /// Origin of the coordinates (x, y) in the model, in image pixels.
    pub origin: [f64; 2],
    /// Final robust scale of the (pre-smoothed) DFD, grey levels.
    pub scale: f64,
    /// Standard deviation of the per-frame image noise implied by `scale`, grey levels.
    pub noise_sigma: f64,
    /// Among the region's pixels that stay inside the image at the estimate, the weighted share
    /// whose residual is within the robust function's constant c times the noise scale `scale`
    /// (Tukey: non-zero weight).
    pub inlier_fraction: f64,
    /// Gauss–Newton iterations per level, index 0 = full resolution; 0 for levels not used.
    pub iterations: Vec<usize>,
    /// Whether the full-resolution iterations met the tolerance.
    pub converged: bool,
    /// Whether the estimate can be trusted as the dominant motion of the region: it
    /// [`converged`](Self::converged), the pixels it explains at the noise scale are at least
    /// [`Settings::min_inlier_fraction`] (default: a majority) of the region's pixels that stay
    /// in the image, and that noise scale is at most twice [`Settings::max_scale`] (a larger one
    /// means that no group of pixels fits at the noise level: the fit sits between motions, and
    /// its inlier fraction is then high only because the scale measures the misfit). After a
    /// re-start from the motions that blocks of the region agree on, the fit explaining most
    /// pixels is also reliable from [`Settings::min_plurality_fraction`] of them, counting the pixels
    /// that a surface in front of it covers in the second frame. `false` when the dominant
    /// motion could not be separated from the rest (a compromise between motions, or a motion
    /// of a minority): treat the estimate as failed; its parameters and covariance do not
    /// describe the region's motion.
    #[serde(default)]
    pub reliable: bool,
}

impl MotionEstimate {
    /// The six affine parameters `[a1..a6]` of Odobez Eq. 13 (whatever the model).
    pub fn affine(&self) -> [f64; 6] {
        let p = self.padded();
        let a = self.spec.model.affine_map() * p;
        [a[0], a[1], a[2], a[3], a[4], a[5]]
    }

    /// Covariance of [`affine`](Self::affine).
    pub fn affine_covariance(&self) -> Matrix6<f64> {
        let m = self.spec.model.affine_map();
        m * self.padded_cov() * m.transpose()
    }

    /// Displacement at image point (x, y).
    pub fn displacement(&self, x: f64, y: f64) -> [f64; 2] {
        self.spec
            .model
            .displacement(&self.params, x - self.origin[0], y - self.origin[1])
    }

    /// 2×2 covariance of the displacement at image point (x, y).
    pub fn displacement_covariance(&self, x: f64, y: f64) -> Matrix2<f64> {
        let (dx, dy) = (x - self.origin[0], y - self.origin[1]);
        let g = SMatrix::<f64, 2, 6>::new(1.0, dx, dy, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, dx, dy);
        g * self.affine_covariance() * g.transpose()
    }

    fn padded(&self) -> Vec7 {
        let mut p = Vec7::zeros();
        for (i, v) in self.params.iter().enumerate().take(7) {
            p[i] = *v;
        }
        p
    }

    fn padded_cov(&self) -> Mat7 {
        let n = self.params.len();
        let mut c = Mat7::zeros();
        for i in 0..n.min(7) {
            for j in 0..n.min(7) {
                c[(i, j)] = self.covariance[i * n + j];
            }
        }
        c
    }
}

/// Per-estimate scratch buffers. Reuse one across estimates to avoid allocation.
#[derive(Debug, Clone, Default)]
pub struct Workspace {
    idx: Vec<u32>,
    m: Vec<f32>,
    res: Vec<f32>,
    gx: Vec<f32>,
    gy: Vec<f32>,
    fx: Vec<f32>,
    fy: Vec<f32>,
    qi: Vec<u32>,
    /// Integer sample positions of the listed pixels, for the covariance grids.
    pos: Vec<(u32, u32)>,
    u: Vec<[f32; 8]>,
    /// 0: the sample fell outside the second frame; otherwise valid (at full resolution, 2 where
    /// it was interpolated bicubically and 1 on the bilinear border).
    valid: Vec<u8>,
    scratch: Vec<f32>,
    /// Runs of consecutive region pixels on one row, from `collect`.
    spans: Vec<Span>,
    /// The spans cut into bands for concurrent processing of large regions.
    bands: Vec<Band>,
    /// Per span, the range of sample rows of its valid pixels (for the covariance grid's bands).
    span_rows: Vec<(u32, u32)>,
    /// Per band of the covariance's dense grid: its cells and a convolution buffer.
    grids: Vec<(Vec<Cell>, Vec<Cell>)>,
}

/// A run of `len` consecutive region pixels on level row `j` from column `i0`, stored from entry
/// `k0` of the workspace's per-pixel arrays.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Span {
    pub(crate) j: usize,
    pub(crate) i0: usize,
    pub(crate) len: usize,
    pub(crate) k0: usize,
}

impl Workspace {
    /// Empty buffers, grown on first use.
    pub fn new() -> Self {
        Self::default()
    }
}

/// The two frames' pyramids and the workspace, for single-region use.
#[derive(Debug, Clone, Default)]
pub struct FrameBuffers {
    /// Pyramid of the first frame.
    pub pyramid0: Pyramid,
    /// Pyramid of the second frame.
    pub pyramid1: Pyramid,
    /// Scratch buffers.
    pub workspace: Workspace,
}

/// The robust multiresolution estimator. Cheap to copy; holds only settings.
#[derive(Debug, Clone, Copy)]
pub struct MotionEstimator {
    settings: Settings,
    /// (E[ψ'], E[ψ²]) under Gaussian noise, for the covariance.
    moments: (f64, f64),
}

/// Variance gain Σk² of the 1-D binomial kernel (70/256).
const KERNEL_A: f64 = 70.0 / 256.0;

/// The largest last Gauss–Newton step (px) after which the final covariance reuses that
/// iteration's residuals instead of evaluating them again at Θ̂.
const REUSE_STEP: f64 = 0.01;

/// The largest last Gauss–Newton step (px) after which the final covariance takes the residuals at
/// Θ̂ to first order from the last evaluation (see `Workspace::linearise`) instead of evaluating
/// them again; larger last steps (and unconverged estimates) are evaluated afresh.
const LINEAR_STEP: f64 = 0.1;

impl MotionEstimator {
    /// An estimator with validated settings.
    ///
    /// # Errors
    /// As [`Settings::validate`].
    pub fn new(settings: Settings) -> Result<Self> {
        settings.validate()?;
        Ok(Self {
            settings,
            moments: settings.robust.gaussian_moments(),
        })
    }

    /// The settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Builds a pyramid over the whole image with this estimator's settings, for multi-region use.
    ///
    /// # Errors
    /// As [`Pyramid::build_into`].
    pub fn build_pyramid_into(&self, image: ImageView<'_>, pyramid: &mut Pyramid) -> Result<()> {
        pyramid.build_into(image, None, self.settings.levels, self.settings.presmooth)
    }

    /// Estimates the motion of `region` between two frames: builds both pyramids only over the
    /// region's box plus [`Settings::margin`], in the caller's buffers, then estimates.
    /// `origin` defaults to [`Region::centre`].
    ///
    /// # Errors
    /// As [`estimate`](Self::estimate), plus image errors.
    pub fn estimate_images_into(
        &self,
        image0: ImageView<'_>,
        image1: ImageView<'_>,
        region: &Region<'_>,
        spec: ModelSpec,
        origin: Option<[f64; 2]>,
        buffers: &mut FrameBuffers,
    ) -> Result<MotionEstimate> {
        let (w, h) = (image0.width(), image0.height());
        if image1.width() != w || image1.height() != h {
            return Err(Error::DimensionMismatch {
                what: "second frame",
                expected: w * h,
                got: image1.width() * image1.height(),
            });
        }
        region.validate(w, h)?;
        let b = region.pixel_box(w, h).ok_or(Error::RegionTooSmall {
            got: 0,
            needed: spec.len() + 1,
        })?;
        let win = Window::around(b.i0, b.j0, b.i1, b.j1, self.settings.margin, w, h);
        on_pool(win.width * win.height >= 2 * BAND_PIXELS, || {
            self.estimate_window(image0, image1, region, spec, origin, buffers, win)
        })
    }

    /// The rest of [`estimate_images_into`](Self::estimate_images_into) once the window is known.
    #[allow(clippy::too_many_arguments)]
    fn estimate_window(
        &self,
        image0: ImageView<'_>,
        image1: ImageView<'_>,
        region: &Region<'_>,
        spec: ModelSpec,
        origin: Option<[f64; 2]>,
        buffers: &mut FrameBuffers,
        win: Window,
    ) -> Result<MotionEstimate> {
        let s = &self.settings;
        let (p0, p1) = (&mut buffers.pyramid0, &mut buffers.pyramid1);
        let mut build0 = move || p0.build_into(image0, Some(win), s.levels, s.presmooth);
        let mut build1 = move || p1.build_into(image1, Some(win), s.levels, s.presmooth);
        // Large windows: both frames at once (each pyramid is built exactly as alone).
        #[cfg(feature = "parallel")]
        let (r0, r1) = if win.width * win.height >= 2 * BAND_PIXELS {
            rayon::join(build0, build1)
        } else {
            (build0(), build1())
        };
        #[cfg(not(feature = "parallel"))]
        let (r0, r1) = (build0(), build1());
        r0?;
        r1?;
        self.estimate(
            &buffers.pyramid0,
            &buffers.pyramid1,
            region,
            spec,
            origin,
            &mut buffers.workspace,
        )
    }

    /// Allocating twin of [`estimate_images_into`](Self::estimate_images_into).
    ///
    /// # Errors
    /// As [`estimate_images_into`](Self::estimate_images_into).
    pub fn estimate_images(
        &self,
        image0: ImageView<'_>,
        image1: ImageView<'_>,
        region: &Region<'_>,
        spec: ModelSpec,
        origin: Option<[f64; 2]>,
    ) -> Result<MotionEstimate> {
        self.estimate_images_into(
            image0,
            image1,
            region,
            spec,
            origin,
            &mut FrameBuffers::default(),
        )
    }

    /// Estimates the motion of `region` from frame 0 to frame 1 on prebuilt pyramids (build them
    /// once per frame, e.g. with [`build_pyramid_into`](Self::build_pyramid_into), and call this for
    /// every region). `origin` defaults to [`Region::centre`].
    ///
    /// Non-convergence is reported in [`MotionEstimate::converged`], not as an error.
    ///
    /// # Errors
    /// [`Error::PyramidMismatch`] when the pyramids come from different image sizes or smoothing,
    /// region errors, [`Error::NonFinite`] for a NaN origin, [`Error::RegionTooSmall`] when fewer
    /// than `spec.len() + 1` pixels remain usable at full resolution, [`Error::Degenerate`] when the
    /// full-resolution normal equations are singular (no texture).
    pub fn estimate(
        &self,
        pyramid0: &Pyramid,
        pyramid1: &Pyramid,
        region: &Region<'_>,
        spec: ModelSpec,
        origin: Option<[f64; 2]>,
        ws: &mut Workspace,
    ) -> Result<MotionEstimate> {
        self.estimate_from(pyramid0, pyramid1, region, spec, origin, None, ws)
    }

    /// As [`estimate`](Self::estimate), warm-started from `initial` when given: parameters in
    /// level-0 pixels laid out as [`MotionEstimate::params`] (`spec.len()` values, about the same
    /// origin), e.g. a motion predicted from the previous frame. With a guess, only the
    /// [`Settings::warm_levels`] finest levels are used (coarse levels only serve to find a
    /// distant motion) and the translation-only warm-up is skipped.
    ///
    /// # Errors
    /// As [`estimate`](Self::estimate), plus [`Error::InvalidSetting`] when `initial` has the wrong
    /// length and [`Error::NonFinite`] when it holds a NaN or infinity.
    #[allow(clippy::too_many_arguments)]
    pub fn estimate_from(
        &self,
        pyramid0: &Pyramid,
        pyramid1: &Pyramid,
        region: &Region<'_>,
        spec: ModelSpec,
        origin: Option<[f64; 2]>,
        initial: Option<&[f64]>,
        ws: &mut Workspace,
    ) -> Result<MotionEstimate> {
        let (w, h) = pyramid0.image_size();
        let large = region.validate(w, h).is_ok()
            && region
                .pixel_box(w, h)
                .is_some_and(|b| (b.i1 - b.i0) * (b.j1 - b.j0) >= 2 * BAND_PIXELS);
        on_pool(large, || {
            self.estimate_from_here(pyramid0, pyramid1, region, spec, origin, initial, ws)
        })
    }

    /// [`estimate_from`](Self::estimate_from) on the calling thread: one coarse-to-fine fit, and
    /// when it is not [`reliable`](MotionEstimate::reliable), re-starts from the motions that
    /// blocks of the region agree on (see [`crate::restart`]); the fit explaining most of the
    /// region's pixels, counting those a surface in front of it covers (see
    /// [`select`](Self::select)), is kept, and the first fit, flagged, when none can be
    /// compared.
    #[allow(clippy::too_many_arguments)]
    fn estimate_from_here(
        &self,
        pyramid0: &Pyramid,
        pyramid1: &Pyramid,
        region: &Region<'_>,
        spec: ModelSpec,
        origin: Option<[f64; 2]>,
        initial: Option<&[f64]>,
        ws: &mut Workspace,
    ) -> Result<MotionEstimate> {
        let first = self.estimate_once(pyramid0, pyramid1, region, spec, origin, initial, ws)?;
        if first.0.reliable {
            return Ok(first.0);
        }
        let (w, h) = pyramid0.image_size();
        let Some(bbox) = region.pixel_box(w, h) else {
            return Ok(first.0);
        };
        let top = self
            .settings
            .levels
            .min(pyramid0.levels())
            .min(pyramid1.levels());
        let l = restart::matching_level(bbox, top);
        let (Some(f0), Some(f1)) = (pyramid0.level(l), pyramid1.level(l)) else {
            return Ok(first.0);
        };
        let mut vectors = Vec::new();
        let est = &first.0;
        // Around the failed fit (between the motions present, or on one of them) and around the
        // caller's guess (zero without one): the failed fit may have wandered off both.
        let fitted = |x: f64, y: f64| est.displacement(x, y);
        let prior = |x: f64, y: f64| match initial {
            Some(p) => spec
                .model
                .displacement(p, x - est.origin[0], y - est.origin[1]),
            None => [0.0, 0.0],
        };
        restart::block_vectors(f0, f1, l, region, bbox, &[&fitted, &prior], &mut vectors);
        let min_blocks = (vectors.len() / 10).max(MIN_START_BLOCKS);
        let starts =
            restart::starting_motions(&vectors, est.origin, f64::from(1u32 << l), min_blocks);
        let origin = Some(est.origin);
        let mut fits = vec![first];
        for m in starts {
            let p = start_params(spec, &m.a);
            if let Ok(next) = self.estimate_once(
                pyramid0,
                pyramid1,
                region,
                spec,
                origin,
                Some(&p[..spec.len()]),
                ws,
            ) {
                fits.push(next);
            }
        }
        let (best, share) = match (pyramid0.level(0), pyramid1.level(0)) {
            (Some(l0), Some(l1)) => self.select(ws, l0, l1, region, bbox, &fits),
            _ => (0, 0.0),
        };
        let best = fits.swap_remove(best);
        // The fit explaining most pixels among the motions the blocks agree on is the dominant
        // one even below a majority (part of the region may be explained by no motion: pixels
        // that a moving block covers or uncovers). The pixels it loses to a surface in front of
        // it count as its own.
        let (mut est, plural) = best;
        if plural && est.inlier_fraction + share >= self.settings.min_plurality_fraction {
            est.reliable = true;
        }
        Ok(est)
    }

    /// One coarse-to-fine fit; also returns whether it converged at a noise scale (at most twice
    /// [`Settings::max_scale`]), which lets it take part in the choice among re-start fits.
    #[allow(clippy::too_many_arguments)]
    fn estimate_once(
        &self,
        pyramid0: &Pyramid,
        pyramid1: &Pyramid,
        region: &Region<'_>,
        spec: ModelSpec,
        origin: Option<[f64; 2]>,
        initial: Option<&[f64]>,
        ws: &mut Workspace,
    ) -> Result<(MotionEstimate, bool)> {
        let st = &self.settings;
        if let Some(p) = initial {
            if p.len() != spec.len() {
                return Err(Error::InvalidSetting {
                    name: "initial",
                    reason: format!("{} values for a model of {}", p.len(), spec.len()),
                });
            }
            if let Some(index) = p.iter().position(|v| !v.is_finite()) {
                return Err(Error::NonFinite {
                    what: "initial",
                    index,
                });
            }
        }
        let (w, h) = pyramid0.image_size();
        if pyramid1.image_size() != (w, h) || pyramid0.levels() == 0 || pyramid1.levels() == 0 {
            return Err(Error::PyramidMismatch {
                reason: format!(
                    "image sizes {:?} and {:?} differ or a pyramid is empty",
                    pyramid0.image_size(),
                    pyramid1.image_size()
                ),
            });
        }
        if pyramid0.presmoothed() != st.presmooth || pyramid1.presmoothed() != st.presmooth {
            return Err(Error::PyramidMismatch {
                reason: format!("pyramids must be built with presmooth = {}", st.presmooth),
            });
        }
        region.validate(w, h)?;
        let origin = origin.unwrap_or_else(|| region.centre(w, h));
        for (index, v) in origin.into_iter().enumerate() {
            if !v.is_finite() {
                return Err(Error::NonFinite {
                    what: "origin",
                    index,
                });
            }
        }
        let n = spec.len();
        let ng = spec.model.geometric_len();
        let bbox = region.pixel_box(w, h).ok_or(Error::RegionTooSmall {
            got: 0,
            needed: n + 1,
        })?;
        let top = st.levels.min(pyramid0.levels()).min(pyramid1.levels());
        let usable = if initial.is_some() {
            top.min(st.warm_levels)
        } else {
            top
        };

        // The coarsest level at which the region still has enough pixels; its pixel list is kept.
        let mut start = 0;
        let mut collected = None;
        for l in (1..usable).rev() {
            if let Some(level) = pyramid0.level(l)
                && ws.collect(level, l, region, bbox) >= st.min_level_pixels
            {
                start = l;
                collected = Some(l);
                break;
            }
        }

        let mut theta = [0.0f64; 7];
        if let Some(p) = initial {
            theta[..n].copy_from_slice(p);
            spec.model.to_coarser_level(&mut theta[..ng], start);
        }
        let mut iterations = vec![0usize; top];
        let mut converged = false;
        let mut last_scale = st.min_scale;
        let mut last_step = f64::INFINITY;
        let mut last_delta = Vec7::zeros();
        for l in (0..=start).rev() {
            if l != start {
                spec.model.to_finer_level(&mut theta[..ng]);
            }
            let (Some(l0), Some(l1)) = (pyramid0.level(l), pyramid1.level(l)) else {
                continue;
            };
            let count = if collected == Some(l) {
                ws.idx.len()
            } else {
                ws.collect(l0, l, region, bbox)
            };
            if count < n + 1 {
                if l == 0 {
                    return Err(Error::RegionTooSmall {
                        got: count,
                        needed: n + 1,
                    });
                }
                continue;
            }
            let f = 0.5f64.powi(l as i32);
            let o = [origin[0] * f, origin[1] * f];
            let corners = box_corners(bbox, origin, f);
            let tol = if l == 0 {
                st.tolerance
            } else {
                st.coarse_tolerance
            };
            // A step larger than the level's window means divergence.
            let limit = (l1.width + l1.height) as f64;
            // At the start level the translation (and offset) is found first with the other
            // parameters frozen: with a large outlier share and a misaligned start, the full
            // model's first steps can otherwise wander into a wrong linear part.
            let warmup_active = translation_active(spec);
            let phases: &[Option<&[usize]>] =
                if l == start && spec.model != MotionModel::Translation && initial.is_none() {
                    &[Some(&warmup_active), None]
                } else {
                    &[None]
                };
            let cold_start = l == start && initial.is_none();
            let lv = LevelCtx {
                l0,
                l1,
                spec,
                o,
                corners,
                tol,
                limit,
                full_res: l == 0,
                level: l,
            };
            if cold_start {
                self.best_start(ws, &lv, &mut theta, &mut iterations[l]);
            }
            let run = self.iterate_level(ws, &lv, &mut theta, phases);
            iterations[l] += run.iterations;
            if run.iterations > 0 {
                last_scale = run.scale;
                last_step = run.step;
                last_delta = run.delta;
            }
            let level_converged = run.converged;
            if l == 0 {
                converged = level_converged;
            }
        }

        // Final pass at full resolution: residuals at Θ̂, scale, covariance.
        let (Some(l0), Some(l1)) = (pyramid0.level(0), pyramid1.level(0)) else {
            return Err(Error::PyramidMismatch {
                reason: "level 0 missing".into(),
            });
        };
        // After convergence the workspace still holds the residuals of the last iteration, taken
        // one step away from Θ̂: reused when that step was below `REUSE_STEP` px (their scale and
        // weights are then those at Θ̂ to well under the noise); otherwise evaluate afresh, so that
        // a loose tolerance (the tracking preset's 0.1 px) does not inflate the scale.
        let s = if converged && last_step <= REUSE_STEP {
            last_scale
        } else if converged && last_step <= LINEAR_STEP {
            // A step of at most 0.1 px: the residuals at Θ̂ to first order from the last
            // evaluation (see `Workspace::linearise`), and their scale seeded by the last one.
            ws.linearise(spec, &last_delta, origin);
            robust_scale_from(
                &ws.res,
                &ws.valid,
                &mut ws.scratch,
                st.min_scale,
                Some(last_scale),
            )
        } else {
            // After a converged level 0 the workspace still lists its pixels, and the last
            // iteration's scale, taken one step away, seeds the refinement at Θ̂.
            let count = if converged {
                ws.idx.len()
            } else {
                ws.collect(l0, 0, region, bbox)
            };
            let n_valid = ws.evaluate(l0, l1, spec, &theta, origin, true);
            if n_valid < n + 1 {
                return Err(Error::RegionTooSmall {
                    got: n_valid.min(count),
                    needed: n + 1,
                });
            }
            let seed = converged.then_some(last_scale);
            robust_scale_from(&ws.res, &ws.valid, &mut ws.scratch, st.min_scale, seed)
        };
        let cov = ws.covariance(spec, st.robust, self.moments, s, origin, st.presmooth, l1)?;
        if let Some(index) = theta.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                what: "parameters",
                index,
            });
        }
        let mut covariance = Vec::with_capacity(n * n);
        for i in 0..n {
            for j in 0..n {
                covariance.push(cov.matrix[(i, j)]);
            }
        }
        let est = MotionEstimate {
            spec,
            params: theta[..n].to_vec(),
            covariance,
            origin,
            scale: s,
            noise_sigma: cov.noise_sigma,
            inlier_fraction: cov.inlier_fraction,
            iterations,
            converged,
            reliable: converged
                && cov.inlier_fraction >= st.min_inlier_fraction
                && s <= 2.0 * st.max_scale,
        };
        let honest = converged && s <= 2.0 * st.max_scale;
        Ok((est, honest))
    }
}

/// The weight of the region's pixels (level 0) whose DFD under `est` is within `t` grey levels
/// and whose sample stays in the image.
fn support_at(
    ws: &mut Workspace,
    l0: &Level,
    l1: &Level,
    region: &Region<'_>,
    bbox: PixelBox,
    est: &MotionEstimate,
    t: f64,
) -> f64 {
    ws.collect(l0, 0, region, bbox);
    let mut theta = [0.0; 7];
    let n = est.params.len().min(7);
    theta[..n].copy_from_slice(&est.params[..n]);
    ws.evaluate(l0, l1, est.spec, &theta, est.origin, true);
    ws.res
        .iter()
        .zip(&ws.valid)
        .zip(&ws.m)
        .filter(|((r, v), _)| **v != 0 && f64::from(r.abs()) < t)
        .map(|(_, m)| f64::from(*m))
        .sum()
}

impl MotionEstimator {
    /// Chooses among the fits of a re-start: returns the index of the dominant motion's fit and
    /// the share of the region's pixels it loses to a surface in front of it (0 when no order
    /// can be told). Only fits that are reliable or converged at a noise scale (the second
    /// field) take part; with none, the first fit is returned.
    ///
    /// The fits are compared by the weight of the pixels each explains within one threshold, c
    /// times the smallest noise scale among them (a fit between two close motions has a larger
    /// scale of its own and, at it, would count pixels of both), plus the pixels it loses to a
    /// surface in front of it when the order of the two can be told (see [`crate::occlusion`]).
    /// The first fit with the largest total wins.
    fn select(
        &self,
        ws: &mut Workspace,
        l0: &Level,
        l1: &Level,
        region: &Region<'_>,
        bbox: PixelBox,
        fits: &[(MotionEstimate, bool)],
    ) -> (usize, f64) {
        let usable: Vec<bool> = fits.iter().map(|f| f.0.reliable || f.1).collect();
        let Some(s_min) = fits
            .iter()
            .zip(&usable)
            .filter(|&(_, &u)| u)
            .map(|(f, _)| f.0.scale)
            .min_by(f64::total_cmp)
        else {
            return (0, 0.0);
        };
        let t = self.settings.robust.c() * s_min;
        let support: Vec<f64> = fits
            .iter()
            .zip(&usable)
            .map(|(f, &u)| {
                if u {
                    support_at(ws, l0, l1, region, bbox, &f.0, t)
                } else {
                    0.0
                }
            })
            .collect();
        let ests: Vec<&MotionEstimate> = fits.iter().map(|f| &f.0).collect();
        let hidden = self.occluded(ws, l0, l1, region, bbox, &ests, &usable, t);
        let credit = |k: usize| {
            hidden[k].iter().fold(
                (0.0, 0.0),
                |a: (f64, f64), h| if h.0 > a.0 { *h } else { a },
            )
        };
        let mut best: Option<usize> = None;
        for k in (0..fits.len()).filter(|&k| usable[k]) {
            let total = support[k] + credit(k).0;
            if best.is_none_or(|b| total > support[b] + credit(b).0) {
                best = Some(k);
            }
        }
        best.map_or((0, 0.0), |b| (b, credit(b).1))
    }

    /// For each pair of fits (x, y), the weight of the region's pixels x fails on because the
    /// surface moving by y covers them in the second frame, when x encloses y (see
    /// [`crate::occlusion`]), and that weight as a share of the region's pixels x keeps in the
    /// image; zeros otherwise. The surroundings are the region's box grown by
    /// [`Settings::margin`] within the first frame's window; a region that fills that box has
    /// none. Only `usable` fits take part; `t` is the threshold on |DFD| (grey levels).
    #[allow(clippy::too_many_arguments)]
    fn occluded(
        &self,
        ws: &mut Workspace,
        l0: &Level,
        l1: &Level,
        region: &Region<'_>,
        bbox: PixelBox,
        fits: &[&MotionEstimate],
        usable: &[bool],
        t: f64,
    ) -> Vec<Vec<(f64, f64)>> {
        let mut out = vec![vec![(0.0, 0.0); fits.len()]; fits.len()];
        let margin = self.settings.margin;
        let cbox = PixelBox {
            i0: bbox.i0.saturating_sub(margin).max(l0.x0),
            j0: bbox.j0.saturating_sub(margin).max(l0.y0),
            i1: (bbox.i1 + margin).min(l0.x0 + l0.width - 1),
            j1: (bbox.j1 + margin).min(l0.y0 + l0.height - 1),
        };
        if cbox.i0 > cbox.i1 || cbox.j0 > cbox.j1 || usable.iter().filter(|&&u| u).count() < 2 {
            return out;
        }
        let test = RowTest::new(region);
        let mut weight = Vec::with_capacity((cbox.i1 + 1 - cbox.i0) * (cbox.j1 + 1 - cbox.j0));
        for j in cbox.j0..=cbox.j1 {
            weight.extend((cbox.i0..=cbox.i1).map(|i| test.weight(i, j)));
        }
        if weight.iter().all(|&w| w > 0.0) {
            return out;
        }
        let labels: Vec<Option<occlusion::Labels>> = fits
            .iter()
            .zip(usable)
            .map(|(f, &u)| u.then(|| context_labels(ws, l0, l1, cbox, f, t)))
            .collect();
        let motion = |f: &MotionEstimate| occlusion::Motion {
            a: f.affine(),
            o: f.origin,
        };
        for (x, lx) in labels.iter().enumerate() {
            let Some(lx) = lx else { continue };
            let total: f64 = weight
                .iter()
                .zip(&lx.label)
                .filter(|&(_, &l)| l != occlusion::UNUSED)
                .map(|(&w, _)| f64::from(w))
                .sum();
            for (y, ly) in labels.iter().enumerate() {
                let Some(ly) = ly else { continue };
                if x == y || total <= 0.0 || !occlusion::surrounds(lx, ly, &weight) {
                    continue;
                }
                let h = occlusion::hidden(lx, &motion(fits[x]), ly, &motion(fits[y]), &weight);
                out[x][y] = (h, h / total);
            }
        }
        out
    }
}

/// What `est` does at each pixel of `cbox` (level 0): explains it (|DFD| < `t`), fails, or
/// sends it outside the second frame's window (or the pixel is outside the first's).
fn context_labels(
    ws: &mut Workspace,
    l0: &Level,
    l1: &Level,
    cbox: PixelBox,
    est: &MotionEstimate,
    t: f64,
) -> occlusion::Labels {
    let rect = Region::Rect {
        x: cbox.i0 as f64,
        y: cbox.j0 as f64,
        width: (cbox.i1 + 1 - cbox.i0) as f64,
        height: (cbox.j1 + 1 - cbox.j0) as f64,
    };
    let w = cbox.i1 + 1 - cbox.i0;
    let mut label = vec![occlusion::UNUSED; w * (cbox.j1 + 1 - cbox.j0)];
    ws.collect(l0, 0, &rect, cbox);
    let mut theta = [0.0; 7];
    let n = est.params.len().min(7);
    theta[..n].copy_from_slice(&est.params[..n]);
    ws.evaluate(l0, l1, est.spec, &theta, est.origin, true);
    for sp in &ws.spans {
        let row = (sp.j - cbox.j0) * w + (sp.i0 - cbox.i0);
        for k in 0..sp.len {
            let (r, v) = (ws.res[sp.k0 + k], ws.valid[sp.k0 + k]);
            label[row + k] = if v == 0 {
                occlusion::UNUSED
            } else if f64::from(r.abs()) < t {
                occlusion::EXPLAINS
            } else {
                occlusion::FAILS
            };
        }
    }
    occlusion::Labels {
        b: Some(cbox),
        label,
    }
}

/// The fewest blocks that make a starting motion of a re-start (see [`crate::restart`]).
const MIN_START_BLOCKS: usize = 4;

/// The parameters of `spec` (offset 0) closest to the affine motion `a` (the layout of
/// [`MotionModel::Affine`]): its translation, and for the scale model the mean of the diagonal.
fn start_params(spec: ModelSpec, a: &[f64; 6]) -> [f64; 7] {
    let mut p = [0.0; 7];
    match spec.model {
        MotionModel::Translation => (p[0], p[1]) = (a[0], a[3]),
        MotionModel::Scale => (p[0], p[1], p[2]) = (a[0], a[3], 0.5 * (a[1] + a[5])),
        MotionModel::Affine => p[..6].copy_from_slice(a),
    }
    p
}

/// What the iterations at one level need.
struct LevelCtx<'a> {
    l0: &'a Level,
    l1: &'a Level,
    spec: ModelSpec,
    /// The origin in level units.
    o: [f64; 2],
    corners: [(f64, f64); 4],
    tol: f64,
    /// A step larger than this means divergence.
    limit: f64,
    full_res: bool,
    level: usize,
}

/// The outcome of the iterations at one level.
struct LevelRun {
    iterations: usize,
    converged: bool,
    /// The noise scale at the last iteration.
    scale: f64,
    /// The last step (px) and its parameters.
    step: f64,
    delta: Vec7,
}

impl MotionEstimator {
    /// Gauss–Newton with IRLS at one level from `theta` (updated in place), over the `phases` of
    /// active parameters (`None`: all).
    ///
    /// The scale: at every iteration the noise scale of the current residuals (lower-quartile
    /// seed, see [`robust_scale_from`]), never an inflated one. With `anneal` (a cold start's
    /// first level) the first iteration uses instead the scale of all the residuals at the start
    /// (misregistration included: a near least-squares step into the basin), and the scale used
    /// is then halved every iteration until it reaches the noise scale; the level cannot converge
    /// before.
    fn iterate_level(
        &self,
        ws: &mut Workspace,
        lv: &LevelCtx<'_>,
        theta: &mut [f64; 7],
        phases: &[Option<&[usize]>],
    ) -> LevelRun {
        let st = &self.settings;
        let (spec, n) = (lv.spec, lv.spec.len());
        let mut run = LevelRun {
            iterations: 0,
            converged: false,
            scale: st.min_scale,
            step: f64::INFINITY,
            delta: Vec7::zeros(),
        };
        for &active in phases {
            run.converged = false;
            let mut prev_step = f64::INFINITY;
            // The smallest step so far and the iterations since it (coarse levels' stall test).
            let (mut least, mut since) = (f64::INFINITY, 0usize);
            for _ in 0..st.max_iterations {
                run.iterations += 1;
                let n_valid = ws.evaluate(lv.l0, lv.l1, spec, theta, lv.o, lv.full_res);
                if n_valid < n + 1 {
                    break;
                }
                // At coarse levels the scale is frozen after `FREEZE_SCALE` iterations: re-estimated
                // every iteration, it moves the Tukey weights of pixels near the threshold back
                // and forth and the iterations cycle up to the cap instead of converging.
                let noise = if lv.level == 0 || run.iterations <= FREEZE_SCALE {
                    robust_scale_from(&ws.res, &ws.valid, &mut ws.scratch, st.min_scale, None)
                } else {
                    run.scale
                };
                run.scale = noise;
                // The weights' scale: the noise scale, capped at the two finest levels.
                let s = if lv.level <= 1 {
                    noise.min(st.max_scale)
                } else {
                    noise
                };
                let (hm, b, _) = ws.normal_equations(spec, st.robust, s, lv.o, false);
                let solved = match active {
                    Some(idx) => solve_subset(&hm, &b, idx),
                    None => solve(&hm, &b, n),
                };
                let Some(delta) = solved else {
                    break;
                };
                let step = lv
                    .corners
                    .iter()
                    .map(|&(x, y)| {
                        let d = spec.model.displacement(delta.as_slice(), x, y);
                        d[0].hypot(d[1])
                    })
                    .fold(0.0, f64::max);
                if !(step.is_finite() && step < lv.limit) {
                    break;
                }
                for i in 0..n {
                    theta[i] -= delta[i];
                }
                run.step = step;
                run.delta = delta;
                if step < lv.tol || converging_below(step, prev_step, lv.tol) {
                    run.converged = true;
                    break;
                }
                prev_step = step;
                // A coarse level whose steps stopped shrinking has reached the precision its
                // pixels allow (pixels crossing the window's border and Tukey's threshold move
                // the fit back and forth by about the step): further iterations cycle up to the
                // cap (issue 16), and the next level only needs a start within its basin.
                if step < least {
                    (least, since) = (step, 0);
                } else {
                    since += 1;
                    if !lv.full_res && since >= STALL_ITERATIONS && least < STALL_STEP {
                        break;
                    }
                }
            }
        }
        run
    }

    /// Several starting hypotheses at a cold start's first level (issue 16): the translations of
    /// a grid of ±[`START_RADIUS`] level pixels around `theta` are ranked by the lower quartile of
    /// |DFD| (small where a group of pixels fits), the best [`START_HYPOTHESES`] distinct ones
    /// are each refined by the translation-only Gauss–Newton with the noise scale, and the one
    /// explaining most pixels at the smallest of their noise scales is kept in `theta`. A single
    /// least-squares start would land between two motions of comparable support.
    fn best_start(
        &self,
        ws: &mut Workspace,
        lv: &LevelCtx<'_>,
        theta: &mut [f64; 7],
        iterations: &mut usize,
    ) {
        let st = &self.settings;
        let spec = lv.spec;
        let n = spec.len();
        let tr = translation_active(spec);
        let (tx, ty) = (tr[0], tr[1]);
        let r = START_RADIUS as i32;
        let mut ranked: Vec<(f64, [f64; 2])> =
            Vec::with_capacity(((2 * r + 1) * (2 * r + 1)) as usize);
        for dy in -r..=r {
            for dx in -r..=r {
                let mut t = *theta;
                t[tx] += f64::from(dx);
                t[ty] += f64::from(dy);
                if ws.evaluate(lv.l0, lv.l1, spec, &t, lv.o, lv.full_res) < n + 1 {
                    continue;
                }
                let q = lower_quartile(&ws.res, &ws.valid, &mut ws.scratch);
                ranked.push((q, [t[tx], t[ty]]));
            }
        }
        ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut picked: Vec<[f64; 2]> = Vec::with_capacity(START_HYPOTHESES);
        for &(_, t) in &ranked {
            if picked.len() == START_HYPOTHESES {
                break;
            }
            if picked
                .iter()
                .all(|p| (p[0] - t[0]).abs().max((p[1] - t[1]).abs()) > 1.5)
            {
                picked.push(t);
            }
        }
        let warmup = [Some(&tr[..])];
        let mut cands: Vec<([f64; 7], f64)> = Vec::with_capacity(picked.len());
        for t in picked {
            let mut th = *theta;
            (th[tx], th[ty]) = (t[0], t[1]);
            let run = self.iterate_level(ws, lv, &mut th, &warmup);
            *iterations += run.iterations + 1;
            cands.push((th, run.scale));
        }
        let Some(s) = cands.iter().map(|c| c.1).min_by(f64::total_cmp) else {
            return;
        };
        let c = st.robust.c() * s;
        let mut best = (0usize, *theta);
        for (th, _) in &cands {
            if ws.evaluate(lv.l0, lv.l1, spec, th, lv.o, lv.full_res) < n + 1 {
                continue;
            }
            let count = ws
                .res
                .iter()
                .zip(&ws.valid)
                .filter(|&(&r, &v)| v != 0 && f64::from(r.abs()) < c)
                .count();
            if count > best.0 {
                best = (count, *th);
            }
        }
        *theta = best.1;
    }
}

/// The half-width, in level pixels, of the grid of starting translations (see
/// `MotionEstimator::best_start`).
const START_RADIUS: usize = 2;

/// Iterations without a step smaller than the smallest so far after which a coarse level stops
/// (see `iterate_level`).
const STALL_ITERATIONS: usize = 3;

/// The stall test only applies once a step smaller than this (level pixels) was taken: the fit is
/// then within the next level's basin.
const STALL_STEP: f64 = 0.25;

/// Iterations after which the scale of a coarse level is kept (see `iterate_level`).
const FREEZE_SCALE: usize = 3;

/// The starting hypotheses refined at a cold start's first level.
const START_HYPOTHESES: usize = 3;

struct CovarianceOut {
    matrix: Mat7,
    noise_sigma: f64,
    inlier_fraction: f64,
}

/// Per-row candidate ranges and a trig-free weight test for [`Workspace::collect`]. The weight is
/// computed with exactly the arithmetic of [`Region::weight`] (same sine and cosine), so that an
/// ellipse and the mask rasterised from it select the same pixels.
struct RowTest<'r, 'a> {
    region: &'r Region<'a>,
    /// sin θ, cos θ of an ellipse.
    sc: (f64, f64),
    /// The ellipse as A dx² + 2B dx dy + C dy² ≤ 1.
    quad: [f64; 3],
}

impl<'r, 'a> RowTest<'r, 'a> {
    fn new(region: &'r Region<'a>) -> Self {
        let (mut sc, mut quad) = ((0.0, 1.0), [0.0; 3]);
        if let Region::Ellipse(e) = region {
            let (s, c) = e.theta.sin_cos();
            let (ia, ib) = (1.0 / (e.a * e.a), 1.0 / (e.b * e.b));
            sc = (s, c);
            quad = [
                c * c * ia + s * s * ib,
                c * s * (ia - ib),
                s * s * ia + c * c * ib,
            ];
        }
        Self { region, sc, quad }
    }

    /// Columns (level units) of row `j` that may hold region pixels, within [lo, hi]; empty when
    /// the first exceeds the second. For an ellipse: the analytic chord widened by one pixel on
    /// each side, so that rounding never loses a pixel the exact test admits.
    fn row(&self, j: usize, s: usize, lo: usize, hi: usize) -> (usize, usize) {
        let Region::Ellipse(e) = self.region else {
            return (lo, hi);
        };
        let [a, b, c] = self.quad;
        let dy = (j * s) as f64 - e.cy;
        let disc = (b * dy) * (b * dy) - a * (c * dy * dy - 1.0);
        let root = disc.max(0.0).sqrt();
        let x0 = (e.cx + (-b * dy - root) / a) / s as f64;
        let x1 = (e.cx + (-b * dy + root) / a) / s as f64;
        let first = (x0.ceil() - 1.0).max(lo as f64);
        let last = (x1.floor() + 1.0).min(hi as f64);
        if first.is_nan() || last.is_nan() || first > last {
            return (1, 0);
        }
        (first as usize, last as usize)
    }

    /// The weight of level-0 pixel (x, y), as [`Region::weight`].
    #[inline]
    fn weight(&self, x: usize, y: usize) -> f32 {
        match self.region {
            Region::Ellipse(e) => {
                let (s, c) = self.sc;
                let (dx, dy) = (x as f64 - e.cx, y as f64 - e.cy);
                let u = (c * dx + s * dy) / e.a;
                let v = (-s * dx + c * dy) / e.b;
                if u * u + v * v <= 1.0 { 1.0 } else { 0.0 }
            }
            r => r.weight(x as f64, y as f64),
        }
    }
}

/// Whether IRLS, which converges linearly, will take its next step below `tol`: the step shrank
/// from `prev` to `step`, the next one is predicted at step · (step / prev), and that must be below
/// `tol` with the step itself already within 20 tolerances (a guard against a step that shrank
/// by chance). Stopping here instead of taking one more iteration to see the small step saves
/// an iteration per level; the estimate is then within about that predicted step of the limit.
fn converging_below(step: f64, prev: f64, tol: f64) -> bool {
    prev.is_finite() && step < 20.0 * tol && step * (step / prev) < tol
}

/// The region box's corners relative to the origin, in level units (factor f = 2^−l).
fn box_corners(b: PixelBox, origin: [f64; 2], f: f64) -> [(f64, f64); 4] {
    let x0 = (b.i0 as f64 - origin[0]) * f;
    let x1 = (b.i1 as f64 - origin[0]) * f;
    let y0 = (b.j0 as f64 - origin[1]) * f;
    let y1 = (b.j1 as f64 - origin[1]) * f;
    [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
}

/// Eight consecutive pixels of a span in f32 lanes: residuals, gradients and the two weights.
#[derive(Default)]
struct Group {
    r: [f32; 8],
    gx: [f32; 8],
    gy: [f32; 8],
    w: [f32; 8],
    wp: [f32; 8],
}

/// f32 lane accumulators of the normal equations (upper triangles).
struct Lanes<const N: usize> {
    h: [[[f32; 8]; N]; N],
    hp: [[[f32; 8]; N]; N],
    b: [[f32; 8]; N],
}

impl<const N: usize> Default for Lanes<N> {
    fn default() -> Self {
        Self {
            h: [[[0.0; 8]; N]; N],
            hp: [[[0.0; 8]; N]; N],
            b: [[0.0; 8]; N],
        }
    }
}

impl<const N: usize> Lanes<N> {
    #[inline(always)]
    fn add<const PSI: bool>(
        &mut self,
        j: &[[f32; 8]; N],
        w: &[f32; 8],
        wp: &[f32; 8],
        r: &[f32; 8],
    ) {
        for a in 0..N {
            let wa: [f32; 8] = std::array::from_fn(|l| w[l] * j[a][l]);
            for l in 0..8 {
                self.b[a][l] += wa[l] * r[l];
            }
            for (hab, jb) in self.h[a].iter_mut().zip(j.iter()).skip(a) {
                for l in 0..8 {
                    hab[l] += wa[l] * jb[l];
                }
            }
            if PSI {
                let pa: [f32; 8] = std::array::from_fn(|l| wp[l] * j[a][l]);
                for (hab, jb) in self.hp[a].iter_mut().zip(j.iter()).skip(a) {
                    for l in 0..8 {
                        hab[l] += pa[l] * jb[l];
                    }
                }
            }
        }
    }

    /// Adds the lane sums to `h`, `hp` (only with `PSI`: otherwise its lanes stayed zero) and
    /// `b`, and clears the lanes.
    fn flush<const PSI: bool>(
        &mut self,
        h: &mut [[f64; N]; N],
        hp: &mut [[f64; N]; N],
        b: &mut [f64; N],
    ) {
        let sum = |lanes: &mut [f32; 8]| {
            let total = lanes.iter().map(|&v| f64::from(v)).sum::<f64>();
            *lanes = [0.0; 8];
            total
        };
        for a in 0..N {
            b[a] += sum(&mut self.b[a]);
            for bb in a..N {
                h[a][bb] += sum(&mut self.h[a][bb]);
                if PSI {
                    hp[a][bb] += sum(&mut self.hp[a][bb]);
                }
            }
        }
    }
}

/// The displacement of any model written as affine coefficients (a1..a6 of Eq. 13).
fn affine_coefficients(model: MotionModel, p: &[f64; 7]) -> [f64; 6] {
    match model {
        MotionModel::Translation => [p[0], 0.0, 0.0, p[1], 0.0, 0.0],
        MotionModel::Scale => [p[0], p[2], 0.0, p[1], 0.0, p[2]],
        MotionModel::Affine => [p[0], p[1], p[2], p[3], p[4], p[5]],
    }
}

/// Indices of the translation parameters (and the offset) of a model: at most three.
fn translation_active(spec: ModelSpec) -> Vec<usize> {
    let mut v = match spec.model {
        MotionModel::Translation | MotionModel::Scale => vec![0, 1],
        MotionModel::Affine => vec![0, 3],
    };
    if spec.offset {
        v.push(spec.model.geometric_len());
    }
    v
}

/// Solves the sub-system of H δ = b on the indices `idx`, leaving the other unknowns at zero.
fn solve_subset(h: &Mat7, b: &Vec7, idx: &[usize]) -> Option<Vec7> {
    let mut m = Mat7::identity();
    let mut r = Vec7::zeros();
    for (a, &i) in idx.iter().enumerate() {
        r[a] = b[i];
        for (c, &j) in idx.iter().enumerate() {
            m[(a, c)] = h[(i, j)];
        }
    }
    let x = solve(&m, &r, idx.len())?;
    let mut out = Vec7::zeros();
    for (a, &i) in idx.iter().enumerate() {
        out[i] = x[a];
    }
    Some(out)
}

/// Solves H δ = b for the first n unknowns (the rest padded with the identity) by Cholesky.
fn solve(h: &Mat7, b: &Vec7, n: usize) -> Option<Vec7> {
    let mut m = *h;
    for i in n..7 {
        m[(i, i)] = 1.0;
    }
    let chol = m.cholesky()?;
    let x = chol.solve(b);
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[inline(always)]
fn bilinear(d: &[f32], i00: usize, w: usize, fx: f32, fy: f32) -> f32 {
    let top = d[i00] + fx * (d[i00 + 1] - d[i00]);
    let bot = d[i00 + w] + fx * (d[i00 + w + 1] - d[i00 + w]);
    top + fy * (bot - top)
}

/// Keys' cubic convolution weights (a = −0.5) of the taps −1, 0, 1, 2 at fraction `f`.
#[inline(always)]
pub(crate) fn cubic_weights(f: f32) -> [f32; 4] {
    let f2 = f * f;
    let f3 = f2 * f;
    [
        -0.5 * f3 + f2 - 0.5 * f,
        1.5 * f3 - 2.5 * f2 + 1.0,
        -1.5 * f3 + 2.0 * f2 + 0.5 * f,
        0.5 * f3 - 0.5 * f2,
    ]
}

#[inline(always)]
fn bicubic(d: &[f32], i00: usize, w: usize, fx: f32, fy: f32) -> f32 {
    let wx = cubic_weights(fx);
    let wy = cubic_weights(fy);
    // Columns first: four rows of four taps, each one 4-lane load and multiply–add, then one dot
    // product with the x weights.
    let base = i00 - w - 1;
    let mut col = [0.0f32; 4];
    for (r, wyr) in wy.iter().enumerate() {
        let row: &[f32; 4] = match d[base + r * w..base + r * w + 4].try_into() {
            Ok(row) => row,
            Err(_) => unreachable!("a slice of length 4"),
        };
        for (c, v) in col.iter_mut().zip(row) {
            *c += wyr * v;
        }
    }
    (wx[0] * col[0] + wx[1] * col[1]) + (wx[2] * col[2] + wx[3] * col[3])
}

/// Variance gain Σ h² of pre-smoothing followed by cubic interpolation at fraction f, 1-D, for
/// white noise: h(v) = Σ_t c_t(f) K(t − v).
fn interp_gain(f: f64, presmooth: bool) -> f64 {
    let c = cubic_weights(f as f32).map(f64::from);
    let k: &[f64] = if presmooth {
        &[1.0 / 16.0, 4.0 / 16.0, 6.0 / 16.0, 4.0 / 16.0, 1.0 / 16.0]
    } else {
        &[1.0]
    };
    let r = (k.len() / 2) as isize;
    let mut total = 0.0;
    // Noise sample offsets v from −1 − r to 2 + r.
    for v in (-1 - r)..=(2 + r) {
        let mut hv = 0.0;
        for (ti, ct) in c.iter().enumerate() {
            let t = ti as isize - 1;
            let u = t - v + r;
            if u >= 0 && (u as usize) < k.len() {
                hv += ct * k[u as usize];
            }
        }
        total += hv * hv;
    }
    total
}

impl Workspace {
    /// Lists the region's pixels at level `l` inside the first pyramid's window, as row spans
    /// (no per-pixel region test for rectangles and ellipses: see [`RowTest`]).
    fn collect(&mut self, level: &Level, l: usize, region: &Region<'_>, b: PixelBox) -> usize {
        self.idx.clear();
        self.m.clear();
        self.spans.clear();
        let s = 1usize << l;
        let i_lo = b.i0.div_ceil(s).max(level.x0);
        let i_hi = (b.i1 / s).min(level.x0 + level.width - 1);
        let j_lo = b.j0.div_ceil(s).max(level.y0);
        let j_hi = (b.j1 / s).min(level.y0 + level.height - 1);
        if i_lo > i_hi || j_lo > j_hi {
            return 0;
        }
        let test = RowTest::new(region);
        // Every pixel of a rectangle's (or the frame's) box is inside with weight 1: whole rows.
        let dense = matches!(region, Region::Full | Region::Rect { .. });
        for j in j_lo..=j_hi {
            let (a, z) = test.row(j, s, i_lo, i_hi);
            if dense && a <= z {
                let base = (j - level.y0) * level.width - level.x0;
                let k0 = self.idx.len();
                self.idx.extend((a..=z).map(|i| (base + i) as u32));
                self.m.resize(self.idx.len(), 1.0);
                self.spans.push(Span {
                    j,
                    i0: a,
                    len: z + 1 - a,
                    k0,
                });
                continue;
            }
            let mut run: Option<Span> = None;
            for i in a..=z {
                // Interior pixels of convex regions need no test (weight 1); masks always do.
                let wgt = test.weight(i * s, j * s);
                if wgt > 0.0 {
                    self.idx
                        .push(((j - level.y0) * level.width + (i - level.x0)) as u32);
                    self.m.push(wgt);
                    match run.as_mut() {
                        Some(r) if r.i0 + r.len == i => r.len += 1,
                        _ => {
                            if let Some(r) = run.take() {
                                self.spans.push(r);
                            }
                            run = Some(Span {
                                j,
                                i0: i,
                                len: 1,
                                k0: self.idx.len() - 1,
                            });
                        }
                    }
                }
            }
            if let Some(r) = run {
                self.spans.push(r);
            }
        }
        self.make_bands();
        self.idx.len()
    }

    /// Moves the residuals of the last full-resolution evaluation, at Θ, to Θ̂ = Θ − δ to first
    /// order: r(Θ̂) ≈ r(Θ) − J δ, with the Jacobian J that IRLS used at Θ (mapped gradients; the
    /// offset's −1), i.e. r −= ∇I·d_δ(x) − δ_c. Only the residuals move: the gradients, the
    /// sample positions and the interpolation taps stay those at Θ (the covariance reads them one
    /// step away, as when the residuals are reused below `REUSE_STEP`).
    ///
    /// The error is the second-order term ½ d_δᵀ ∇²I d_δ plus (∇I₁(q) − J)·d_δ, the difference
    /// between the second frame's gradient at the sample and the mapped first-frame gradient. For
    /// a step |d_δ| ≤ `LINEAR_STEP` = 0.1 px the first is ≤ 0.005 |∇²I| (grey levels/px²), and
    /// the second, dominated by the noise's gradient, ≤ 0.1 |∇n| ≈ 0.1 σ: both negligible against
    /// the noise σ, so the robust scale and the covariance are those at Θ̂ to well under their own
    /// sampling error (checked: accuracy and calibration tests, ratios moved by < 0.02).
    fn linearise(&mut self, spec: ModelSpec, delta: &Vec7, o: [f64; 2]) {
        let ng = spec.model.geometric_len();
        let dc = if spec.offset { delta[ng] as f32 } else { 0.0 };
        let mut p = [0.0f64; 7];
        p[..ng].copy_from_slice(&delta.as_slice()[..ng]);
        let a = affine_coefficients(spec.model, &p);
        let (a1, a4) = (a[1] as f32, a[4] as f32);
        for sp in &self.spans {
            let y = sp.j as f64 - o[1];
            let x0 = sp.i0 as f64 - o[0];
            // d_δ(x, y) = (dx0 + a1 t, dy0 + a4 t) at pixel t of the span.
            let dx0 = (a[0] + a[1] * x0 + a[2] * y) as f32;
            let dy0 = (a[3] + a[4] * x0 + a[5] * y) as f32;
            let r = sp.k0..sp.k0 + sp.len;
            let it = self.res[r.clone()]
                .iter_mut()
                .zip(&self.gx[r.clone()])
                .zip(&self.gy[r]);
            for (t, ((res, &gx), &gy)) in it.enumerate() {
                let tf = t as f32;
                *res -= gx * (dx0 + a1 * tf) + gy * (dy0 + a4 * tf) - dc;
            }
        }
    }

    /// Cuts the spans into bands of consecutive spans holding at least [`BAND_PIXELS`] pixels
    /// each (the last one may hold fewer). The cut depends only on the region's pixels.
    fn make_bands(&mut self) {
        self.bands.clear();
        let mut start = 0;
        for (i, sp) in self.spans.iter().enumerate() {
            let k1 = sp.k0 + sp.len;
            let k0 = self.spans[start].k0;
            if k1 - k0 >= BAND_PIXELS || i + 1 == self.spans.len() {
                self.bands.push(Band {
                    s0: start,
                    s1: i + 1,
                    k0,
                    k1,
                });
                start = i + 1;
            }
        }
    }

    /// Whether the region is large enough (more than one band) for the bands to be processed
    /// concurrently. Small regions stay on one thread without touching the pool.
    fn parallel(&self) -> bool {
        cfg!(feature = "parallel") && self.bands.len() > 1
    }

    /// Residuals, gradients and validity of the listed pixels under Θ (level units, origin `o`).
    /// At full resolution (`full_res`) the second frame is sampled bicubically and the Jacobian uses
    /// the first frame's gradient mapped through (I + D)^−T; at coarse levels it is sampled
    /// bilinearly and the two frames' gradients are averaged (wider convergence basin).
    fn evaluate(
        &mut self,
        l0: &Level,
        l1: &Level,
        spec: ModelSpec,
        theta: &[f64; 7],
        o: [f64; 2],
        full_res: bool,
    ) -> usize {
        let n = self.idx.len();
        let ng = spec.model.geometric_len();
        let c = if spec.offset { theta[ng] } else { 0.0 } as f32;
        self.res.resize(n, 0.0);
        self.gx.resize(n, 0.0);
        self.gy.resize(n, 0.0);
        self.fx.resize(n, 0.0);
        self.fy.resize(n, 0.0);
        self.qi.resize(n, 0);
        self.valid.resize(n, 0);
        let a = affine_coefficients(spec.model, theta);
        // q = r + d(r) in the second frame's window: q = c + B·r.
        let (bx1, bx2, by1, by2) = (1.0 + a[1], a[2], a[4], 1.0 + a[5]);
        let cx = a[0] - a[1] * o[0] - a[2] * o[1] - l1.x0 as f64;
        let cy = a[3] - a[4] * o[0] - a[5] * o[1] - l1.y0 as f64;
        // (I + D)^−T = [[by2, −by1], [−bx2, bx1]] / det maps ∇z₀ to ∇z₁.
        let det = bx1 * by2 - bx2 * by1;
        let (t11, t12, t21, t22) = if det.abs() > 1e-6 {
            (
                (by2 / det) as f32,
                (-by1 / det) as f32,
                (-bx2 / det) as f32,
                (bx1 / det) as f32,
            )
        } else {
            (1.0, 0.0, 0.0, 1.0)
        };
        let (w1, h1) = (l1.width, l1.height);
        if w1 < 2 || h1 < 2 {
            self.valid.fill(0);
            return 0;
        }
        let par = self.parallel();
        let ctx = Warp {
            c: [cx, cy],
            b: [bx1, bx2, by1, by2],
            t: [t11, t12, t21, t22],
            offset: c,
            l0,
            l1,
            full_res,
        };
        let out = Samples {
            res: &mut self.res,
            gx: &mut self.gx,
            gy: &mut self.gy,
            fx: &mut self.fx,
            fy: &mut self.fy,
            qi: &mut self.qi,
            valid: &mut self.valid,
        };
        let (spans, idx) = (&self.spans[..], &self.idx[..]);
        if !par {
            return simd(
                #[inline(always)]
                || ctx.spans(spans, idx, 0, out),
            );
        }
        // Every pixel's outputs depend on that pixel alone: the bands write disjoint slices.
        let mut outs = Vec::with_capacity(self.bands.len());
        let mut rest = out;
        for band in &self.bands {
            let (head, tail) = rest.split_at(band.k1 - band.k0);
            outs.push((band, head));
            rest = tail;
        }
        map_bands(outs, |(band, o)| {
            simd(
                #[inline(always)]
                || ctx.spans(&spans[band.s0..band.s1], idx, band.k0, o),
            )
        })
        .into_iter()
        .sum()
    }

    /// IRLS normal equations H = Σ m w J Jᵀ and g = Σ m w J r, and, with `with_psi`, the sensitivity
    /// Σ m ψ'(r/s) J Jᵀ of the sandwich covariance, in one pass.
    fn normal_equations(
        &self,
        spec: ModelSpec,
        robust: RobustFunction,
        s: f64,
        o: [f64; 2],
        with_psi: bool,
    ) -> (Mat7, Vec7, Mat7) {
        // The weight functions in f32, monomorphised so that the lane loops vectorise. Tukey is
        // written branch-free: t = max(1 − u, 0) gives w = t² and ψ' = t(1 − 5u), both 0 for u ≥ 1.
        match robust {
            RobustFunction::Tukey { c } => {
                let ic2 = (1.0 / (c * c)) as f32;
                self.accumulate(spec, s, o, with_psi, move |z: f32, m: f32| {
                    let u = z * z * ic2;
                    let t = (1.0 - u).max(0.0);
                    (m * t * t, m * t * (1.0 - 5.0 * u))
                })
            }
            r => self.accumulate(spec, s, o, with_psi, move |z: f32, m: f32| {
                let z = f64::from(z);
                (m * r.weight(z) as f32, m * r.psi_prime(z) as f32)
            }),
        }
    }

    /// The `cnt` ≤ 8 pixels from entry `k` as f32 lanes, with their weights (w, w₂) =
    /// `weights(r/s, m)`. Invalid pixels and unused lanes get zero values and weights (their stored
    /// values may be stale).
    #[inline(always)]
    fn group<F: Fn(f32, f32) -> (f32, f32)>(
        &self,
        k: usize,
        cnt: usize,
        inv_s: f32,
        weights: &F,
    ) -> Group {
        let mut g = Group::default();
        let mut m = [0.0f32; 8];
        for (l, ml) in m.iter_mut().enumerate().take(cnt) {
            if self.valid[k + l] != 0 {
                g.r[l] = self.res[k + l];
                g.gx[l] = self.gx[k + l];
                g.gy[l] = self.gy[k + l];
                *ml = self.m[k + l];
            }
        }
        for (l, &ml) in m.iter().enumerate() {
            (g.w[l], g.wp[l]) = weights(g.r[l] * inv_s, ml);
        }
        g
    }

    /// Σ w J Jᵀ, Σ w J r and, with `second`, Σ w₂ J Jᵀ, where (w, w₂) = `weights(r/s, m)`.
    ///
    /// Along a row span y is constant, so every Jacobian entry (as in
    /// `MotionModel::gradient_row`) is one of a few per-pixel lane rows times 1 or y: translation
    /// (gx, gy), scale (gx, gy, gx·x + gy·y), affine (gx, gx·x, gy, gy·x), then −1 for the offset.
    /// The lanes accumulate the rows' moments over a span, which is folded into H, H₂ and g with
    /// the factors y^(i+j): for the affine model 14 lane sums per pixel instead of the 27 of J Jᵀ.
    fn accumulate<F: Fn(f32, f32) -> (f32, f32) + Sync>(
        &self,
        spec: ModelSpec,
        s: f64,
        o: [f64; 2],
        second: bool,
        weights: F,
    ) -> (Mat7, Vec7, Mat7) {
        // Parameter a is lane row map[a].0 times y^map[a].1.
        let (geometric, row_count): (&[(usize, usize)], usize) = match spec.model {
            MotionModel::Translation => (&[(0, 0), (1, 0)], 2),
            MotionModel::Scale => (&[(0, 0), (1, 0), (2, 0)], 3),
            MotionModel::Affine => (&[(0, 0), (1, 0), (0, 1), (2, 0), (3, 0), (2, 1)], 4),
        };
        let mut map = [(0usize, 0usize); 7];
        map[..geometric.len()].copy_from_slice(geometric);
        map[geometric.len()] = (row_count, 0);
        let rows = |g: &Group, x: &[f32; 8], y: f32| -> [[f32; 8]; 5] {
            // Rows past the model's are the offset's −1.
            let mut r = [[-1.0f32; 8]; 5];
            (r[0], r[1]) = (g.gx, g.gy);
            match spec.model {
                MotionModel::Translation => {}
                MotionModel::Scale => {
                    r[2] = std::array::from_fn(|l| g.gx[l] * x[l] + g.gy[l] * y);
                }
                MotionModel::Affine => {
                    r[1] = std::array::from_fn(|l| g.gx[l] * x[l]);
                    r[2] = g.gy;
                    r[3] = std::array::from_fn(|l| g.gy[l] * x[l]);
                }
            }
            r
        };
        // Lane rows P and parameters N, known at compile time for each model.
        macro_rules! spans {
            ($p:literal, $n:literal) => {{
                let map: [(usize, usize); $n] = std::array::from_fn(|a| map[a]);
                if second {
                    self.accumulate_spans::<$p, $n, true, _, _>(s, o, &weights, rows, &map)
                } else {
                    self.accumulate_spans::<$p, $n, false, _, _>(s, o, &weights, rows, &map)
                }
            }};
        }
        match (spec.model, spec.offset) {
            (MotionModel::Translation, false) => spans!(2, 2),
            (MotionModel::Translation, true) => spans!(3, 3),
            (MotionModel::Scale, false) => spans!(3, 3),
            (MotionModel::Scale, true) => spans!(4, 4),
            (MotionModel::Affine, false) => spans!(4, 6),
            (MotionModel::Affine, true) => spans!(5, 7),
        }
    }

    /// The span walk of [`accumulate`](Self::accumulate): eight contiguous pixels at a time in f32
    /// lanes (residual scaling, weights and the `P` lane rows computed in the lanes), the moments
    /// flushed to f64 at the end of each span (and every 64 groups, so that f32 sums stay short),
    /// then folded into the parameters' matrices through `map`.
    fn accumulate_spans<const P: usize, const N: usize, const PSI: bool, F, R>(
        &self,
        s: f64,
        o: [f64; 2],
        weights: &F,
        rows: R,
        map: &[(usize, usize); N],
    ) -> (Mat7, Vec7, Mat7)
    where
        F: Fn(f32, f32) -> (f32, f32) + Sync,
        R: Fn(&Group, &[f32; 8], f32) -> [[f32; 8]; 5] + Sync,
    {
        let band = |spans: &[Span]| {
            simd(
                #[inline(always)]
                || self.accumulate_band::<P, N, PSI, F, R>(spans, s, o, weights, &rows, map),
            )
        };
        // Bands whenever the region has several, with or without the `parallel` feature, so that
        // the sums are the same either way.
        let (mut hm, bv, mut hpm) = if self.bands.len() > 1 {
            // Per-band sums, added in band order.
            let parts = map_bands(self.bands.clone(), |b| band(&self.spans[b.s0..b.s1]));
            let mut total = (Mat7::zeros(), Vec7::zeros(), Mat7::zeros());
            for (h, b, hp) in parts {
                total.0 += h;
                total.1 += b;
                total.2 += hp;
            }
            total
        } else {
            band(&self.spans)
        };
        for a in 0..N {
            for c in a + 1..N {
                hm[(c, a)] = hm[(a, c)];
                hpm[(c, a)] = hpm[(a, c)];
            }
        }
        (hm, bv, hpm)
    }

    /// [`accumulate_spans`](Self::accumulate_spans) over some spans: upper triangles only.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn accumulate_band<const P: usize, const N: usize, const PSI: bool, F, R>(
        &self,
        spans: &[Span],
        s: f64,
        o: [f64; 2],
        weights: &F,
        rows: &R,
        map: &[(usize, usize); N],
    ) -> (Mat7, Vec7, Mat7)
    where
        F: Fn(f32, f32) -> (f32, f32),
        R: Fn(&Group, &[f32; 8], f32) -> [[f32; 8]; 5],
    {
        let mut acc = Lanes::<P>::default();
        let (mut hm, mut hpm, mut bv) = (Mat7::zeros(), Mat7::zeros(), Vec7::zeros());
        let inv_s = (1.0 / s) as f32;
        for sp in spans {
            let y = sp.j as f64 - o[1];
            let x_first = (sp.i0 as f64 - o[0]) as f32;
            let (mut h, mut hp, mut b) = ([[0.0f64; P]; P], [[0.0f64; P]; P], [0.0f64; P]);
            let mut groups = 0usize;
            for t in (0..sp.len).step_by(8) {
                let g = self.group(sp.k0 + t, (sp.len - t).min(8), inv_s, weights);
                let xl: [f32; 8] = std::array::from_fn(|l| x_first + (t + l) as f32);
                let all = rows(&g, &xl, y as f32);
                let pl: [[f32; 8]; P] = std::array::from_fn(|a| all[a]);
                acc.add::<PSI>(&pl, &g.w, &g.wp, &g.r);
                groups += 1;
                if groups == 64 {
                    acc.flush::<PSI>(&mut h, &mut hp, &mut b);
                    groups = 0;
                }
            }
            acc.flush::<PSI>(&mut h, &mut hp, &mut b);
            let y_pow = [1.0, y, y * y];
            for (a, &(ia, pa)) in map.iter().enumerate() {
                bv[a] += b[ia] * y_pow[pa];
                for (c, &(ic, pc)) in map.iter().enumerate().skip(a) {
                    let (i, j) = (ia.min(ic), ia.max(ic));
                    let f = y_pow[pa + pc];
                    hm[(a, c)] += h[i][j] * f;
                    if PSI {
                        hpm[(a, c)] += hp[i][j] * f;
                    }
                }
            }
        }
        (hm, bv, hpm)
    }

    /// The sandwich covariance described in the module documentation (level 0, origin `o`; `l1`
    /// is the second frame's level 0, where the interpolation taps lie).
    #[allow(clippy::too_many_arguments)]
    fn covariance(
        &mut self,
        spec: ModelSpec,
        robust: RobustFunction,
        moments: (f64, f64),
        s: f64,
        o: [f64; 2],
        presmooth: bool,
        l1: &Level,
    ) -> Result<CovarianceOut> {
        let n = spec.len();
        let c = robust.c();
        // Sensitivity H = Σ m ψ' J Jᵀ; when too many residuals sit where ψ' < 0 it may not be
        // positive definite, and the IRLS matrix (its expectation under a clean fit) is used.
        // One pass gives the sensitivity and the same-pixel term Σ m² J Jᵀ over the pixels a
        // redescending ρ does not reject (those carry no noise into Θ̂).
        let rej2 = robust.rejection().map(|r| (r * r) as f32);
        let same_pixel = move |z: f32, m: f32| -> f32 {
            let keep = rej2.is_none_or(|r2| z * z < r2);
            if keep { m * m } else { 0.0 }
        };
        let (diag, _, hs) = match robust {
            // Tukey's ψ' = (1 − u)(1 − 5u) for u = z²/c² < 1, else 0, in f32 and branch-free as
            // in `normal_equations`, so that the lanes vectorise.
            RobustFunction::Tukey { c } => {
                let ic2 = (1.0 / (c * c)) as f32;
                self.accumulate(spec, s, o, true, move |z: f32, m: f32| {
                    let u = z * z * ic2;
                    let t = (1.0 - u).max(0.0);
                    (same_pixel(z, m), m * t * (1.0 - 5.0 * u))
                })
            }
            r => self.accumulate(spec, s, o, true, move |z: f32, m: f32| {
                (same_pixel(z, m), m * r.psi_prime(f64::from(z)) as f32)
            }),
        };
        let mut hpad = hs;
        for i in n..7 {
            hpad[(i, i)] = 1.0;
        }
        let use_psi = hpad.cholesky().is_some();
        let mut sens = if use_psi {
            hs
        } else {
            self.normal_equations(spec, robust, s, o, false).0
        };
        for i in n..7 {
            sens[(i, i)] = 1.0;
        }
        let hinv = sens.try_inverse().ok_or(Error::Degenerate { level: 0 })?;
        if !hinv.iter().all(|v| v.is_finite()) {
            return Err(Error::Degenerate { level: 0 });
        }

        // Noise variance from the scale and the per-pixel variance gains; inlier fraction; u.
        let ka = if presmooth { KERNEL_A } else { 1.0 };
        let table: [f64; 65] = std::array::from_fn(|i| interp_gain(i as f64 / 64.0, presmooth));
        // Every entry is written by `UVectors::spans` (zero where a pixel carries no noise).
        self.u.resize(self.idx.len(), [0.0; 8]);
        let (e1, e2) = moments;
        let ctx = UVectors {
            spec,
            e1: e1 as f32,
            c,
            rejection: robust.rejection(),
            s,
            o,
            ka,
            table: &table,
            res: &self.res,
            valid: &self.valid,
            m: &self.m,
            gx: &self.gx,
            gy: &self.gy,
            fx: &self.fx,
            fy: &self.fy,
        };
        let (gain, n_in, m_in, m_all) = if self.bands.len() > 1 {
            // Per-band sums, added in band order.
            let mut parts = Vec::with_capacity(self.bands.len());
            let mut rest = &mut self.u[..];
            for band in &self.bands {
                let (head, tail) = rest.split_at_mut(band.k1 - band.k0);
                parts.push((band, head));
                rest = tail;
            }
            let spans = &self.spans;
            let sums = map_bands(parts, |(band, u)| {
                simd(
                    #[inline(always)]
                    || ctx.spans(&spans[band.s0..band.s1], band.k0, u),
                )
            });
            let mut total = (0.0f64, 0usize, 0.0f64, 0.0f64);
            for (g, n, mi, ma) in sums {
                total = (total.0 + g, total.1 + n, total.2 + mi, total.3 + ma);
            }
            total
        } else {
            simd(
                #[inline(always)]
                || ctx.spans(&self.spans, 0, &mut self.u),
            )
        };
        if n_in == 0 {
            return Err(Error::Degenerate { level: 0 });
        }
        let noise_var = s * s / (gain / n_in as f64);
        let inlier_fraction = if m_all > 0.0 { m_in / m_all } else { 0.0 };

        // Meat: both frames' noise, each through the smoothing (and, for the second frame, the
        // interpolation at r + d(r)), projected on u.
        let meat = self.meat(n, presmooth, None) + self.meat(n, presmooth, Some(l1));
        let total = meat * noise_var + diag * ((e2 - e1 * e1) * s * s);
        let mut cov = hinv * total * hinv.transpose();
        for i in 0..7 {
            for jj in 0..7 {
                if i >= n || jj >= n {
                    cov[(i, jj)] = 0.0;
                }
            }
        }
        Ok(CovarianceOut {
            matrix: cov,
            noise_sigma: noise_var.sqrt(),
            inlier_fraction,
        })
    }

    /// Σ_s v(s) v(s)ᵀ with v = K ∗ U, U the vectors u scattered onto the noise samples they read:
    /// the pixel itself for the first frame, the interpolation taps around r + d(r) in the second
    /// frame (`l1`). The grid is stored as `n` channel planes so that the convolution and the
    /// outer products run over contiguous rows.
    fn meat(&mut self, n: usize, presmooth: bool, l1: Option<&Level>) -> Mat7 {
        let pad = if presmooth { 2usize } else { 0 };
        // Tap offsets −1..=2 around (ix, iy) for the second frame.
        let (tap_lo, tap_hi) = if l1.is_some() {
            (1usize, 2usize)
        } else {
            (0, 0)
        };
        // Tap positions once per pixel (one 32-bit division for the second frame), then the box,
        // and each span's range of rows; by bands for large regions (min and max do not depend
        // on the order).
        self.pos.resize(self.idx.len(), (0, 0));
        self.span_rows.resize(self.spans.len(), (0, 0));
        let w1 = l1.map_or(1, |l| l.width as u32);
        let (spans, qi, valid) = (&self.spans[..], &self.qi[..], &self.valid[..]);
        let positions = |sp0: usize, kb: usize, pos: &mut [(u32, u32)], rows: &mut [(u32, u32)]| {
            let mut bbox = (u32::MAX, u32::MAX, 0u32, 0u32);
            for (t, sp) in spans[sp0..sp0 + rows.len()].iter().enumerate() {
                let (mut lo, mut hi) = (u32::MAX, 0u32);
                for k in sp.k0..sp.k0 + sp.len {
                    let (x, y) = match l1 {
                        None => ((sp.i0 + k - sp.k0) as u32, sp.j as u32),
                        Some(_) => {
                            let y = qi[k] / w1;
                            (qi[k] - y * w1, y)
                        }
                    };
                    pos[k - kb] = (x, y);
                    if valid[k] != 0 {
                        (bbox.0, bbox.2) = (bbox.0.min(x), bbox.2.max(x));
                        (lo, hi) = (lo.min(y), hi.max(y));
                    }
                }
                (bbox.1, bbox.3) = (bbox.1.min(lo), bbox.3.max(hi));
                rows[t] = (lo, hi);
            }
            bbox
        };
        let (minx, miny, maxx, maxy) = if self.parallel() {
            let mut parts = Vec::with_capacity(self.bands.len());
            let (mut pos, mut rows) = (&mut self.pos[..], &mut self.span_rows[..]);
            for band in &self.bands {
                let (p, p_rest) = pos.split_at_mut(band.k1 - band.k0);
                let (r, r_rest) = rows.split_at_mut(band.s1 - band.s0);
                parts.push((band, p, r));
                (pos, rows) = (p_rest, r_rest);
            }
            map_bands(parts, |(band, p, r)| positions(band.s0, band.k0, p, r))
                .into_iter()
                .fold((u32::MAX, u32::MAX, 0, 0), |a, b| {
                    (a.0.min(b.0), a.1.min(b.1), a.2.max(b.2), a.3.max(b.3))
                })
        } else {
            positions(0, 0, &mut self.pos, &mut self.span_rows)
        };
        if minx > maxx {
            return Mat7::zeros();
        }
        let (minx, miny, maxx, maxy) = (minx as usize, miny as usize, maxx as usize, maxy as usize);
        let ox = minx as isize - (tap_lo + pad) as isize;
        let oy = miny as isize - (tap_lo + pad) as isize;
        let bw = maxx - minx + 1 + tap_lo + tap_hi + 2 * pad;
        let bh = maxy - miny + 1 + tap_lo + tap_hi + 2 * pad;
        // Large regions: bands of grid rows, each scattering the pixels whose taps reach its rows
        // or the smoothing's halo around them, convolving, and summing the outer products over
        // its own rows only. The cut depends only on the grid, and the bands' sums are added in
        // order, so the result does not depend on the number of threads.
        let nb = if self.bands.len() > 1 {
            bh.div_ceil(GRID_BAND_ROWS)
        } else {
            1
        };
        let rows_per = bh.div_ceil(nb);
        if self.grids.len() < nb {
            self.grids.resize_with(nb, Default::default);
        }
        let grid = Grid {
            n,
            bw,
            bh,
            ox,
            oy,
            pad,
            taps: (tap_lo, tap_hi),
            presmooth,
            l1,
            u: &self.u,
            pos: &self.pos,
            valid: &self.valid,
            fx: &self.fx,
            fy: &self.fy,
            spans: &self.spans,
            span_rows: &self.span_rows,
        };
        let items: Vec<_> = self
            .grids
            .iter_mut()
            .take(nb)
            .enumerate()
            .map(|(b, buf)| (b * rows_per, ((b + 1) * rows_per).min(bh), buf))
            .collect();
        let parts = map_bands(items, |(r0, r1, (cells, tmp))| {
            simd(
                #[inline(always)]
                || grid.band(r0, r1, cells, tmp),
            )
        });
        let mut m = Mat7::zeros();
        for part in parts {
            m += part;
        }
        m
    }
}

/// Grid rows per band of the covariance grid for large regions (see `Workspace::meat`).
const GRID_BAND_ROWS: usize = 128;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::region::{Ellipse, MaskView};

    const W: usize = 128;
    const H: usize = 96;

    fn tex(x: f64, y: f64) -> f64 {
        128.0
            + 30.0 * (0.31 * x + 0.1 * y).sin()
            + 25.0 * (0.23 * y - 0.05 * x + 1.0).cos()
            + 20.0 * (0.45 * x + 0.37 * y + 2.0).sin()
            + 15.0 * (0.6 * x - 0.52 * y).cos()
    }

    /// Noise-free f32 pair: frame 1(q) = frame 0(q − d) for d = `a` about `origin` (inverted exactly).
    fn pair(a: [f64; 6], origin: [f64; 2], offset: f64) -> (Vec<f32>, Vec<f32>) {
        let f0 = (0..W * H)
            .map(|k| tex((k % W) as f64, (k / W) as f64) as f32)
            .collect();
        let (m11, m12, m21, m22) = (1.0 + a[1], a[2], a[4], 1.0 + a[5]);
        let det = m11 * m22 - m12 * m21;
        let f1 = (0..W * H)
            .map(|k| {
                let (bx, by) = (
                    (k % W) as f64 - origin[0] - a[0],
                    (k / W) as f64 - origin[1] - a[3],
                );
                let x = origin[0] + (m22 * bx - m12 * by) / det;
                let y = origin[1] + (-m21 * bx + m11 * by) / det;
                (tex(x, y) + offset) as f32
            })
            .collect();
        (f0, f1)
    }

    fn views<'a>(f0: &'a [f32], f1: &'a [f32]) -> (ImageView<'a>, ImageView<'a>) {
        (
            ImageView::new(W, H, f0).unwrap(),
            ImageView::new(W, H, f1).unwrap(),
        )
    }

    /// The affine motion, its origin and the tilted ellipse that several tests share: a region
    /// small enough to stay on the calling thread.
    const SHARED_MOTION: [f64; 6] = [0.8, 0.01, -0.01, 0.5, 0.015, -0.005];
    const SHARED_ORIGIN: [f64; 2] = [60.0, 50.0];
    fn shared_ellipse() -> Ellipse {
        Ellipse {
            cx: 60.0,
            cy: 50.0,
            a: 30.0,
            b: 20.0,
            theta: 0.4,
        }
    }

    #[test]
    fn scale_model_and_offset_are_recovered() {
        // Noise-free smooth texture: only interpolation error remains, far below 0.01 px at the
        // corners (0.01 / 60 px ≈ 2e-4 on the scale parameter) and 0.05 grey levels on the offset.
        let origin = [63.5, 47.5];
        let (f0, f1) = pair([1.2, 0.02, 0.0, -0.7, 0.0, 0.02], origin, 6.0);
        let (v0, v1) = views(&f0, &f1);
        let est = MotionEstimator::new(Settings::default()).unwrap();
        let r = est
            .estimate_images(
                v0,
                v1,
                &Region::Full,
                ModelSpec::new(MotionModel::Scale, true),
                Some(origin),
            )
            .unwrap();
        assert!(r.converged);
        assert!((r.params[0] - 1.2).abs() < 0.01, "{:?}", r.params);
        assert!((r.params[1] + 0.7).abs() < 0.01, "{:?}", r.params);
        assert!((r.params[2] - 0.02).abs() < 2e-4, "{:?}", r.params);
        assert!((r.params[3] - 6.0).abs() < 0.05, "{:?}", r.params);
        assert_eq!(r.covariance.len(), 16);
        let a = r.affine();
        assert_eq!(a[1], a[5]);
    }

    #[test]
    fn every_instruction_set_gives_the_same_bits() {
        // The dispatched hot loops (this CPU's best instruction set) against the baseline build of
        // the same loops, on a region small enough to stay on this thread: parameters,
        // covariance, scale and inlier fraction bit for bit, with the offset and the tracking
        // preset's first-order path too.
        let origin = SHARED_ORIGIN;
        let (f0, f1) = pair(SHARED_MOTION, origin, 3.0);
        let (v0, v1) = views(&f0, &f1);
        let region = Region::Ellipse(shared_ellipse());
        for settings in [Settings::default(), Settings::tracking()] {
            let est = MotionEstimator::new(settings).unwrap();
            let spec = ModelSpec::new(MotionModel::Affine, true);
            let run = || {
                est.estimate_images(v0, v1, &region, spec, Some(origin))
                    .unwrap()
            };
            let best = run();
            let (base, dispatches) = crate::simd::tests::on_baseline(run);
            // Pyramids, evaluations, normal equations, scale, covariance: dozens of loops.
            assert!(dispatches > 20, "{dispatches}");
            let bits = |r: &MotionEstimate| {
                let mut v: Vec<u64> = r.params.iter().map(|x| x.to_bits()).collect();
                v.extend(r.covariance.iter().map(|x| x.to_bits()));
                v.extend([r.scale.to_bits(), r.inlier_fraction.to_bits()]);
                v
            };
            assert_eq!(bits(&best), bits(&base));
            assert!(best.converged);
        }
    }

    #[test]
    fn ellipse_and_equivalent_mask_give_the_same_estimate() {
        let origin = SHARED_ORIGIN;
        let (f0, f1) = pair(SHARED_MOTION, origin, 0.0);
        let (v0, v1) = views(&f0, &f1);
        let e = shared_ellipse();
        let ell = Region::Ellipse(e);
        let weights: Vec<f32> = (0..W * H)
            .map(|k| ell.weight((k % W) as f64, (k / W) as f64))
            .collect();
        let mask = Region::Mask(MaskView::new(W, H, &weights).unwrap());
        let est = MotionEstimator::new(Settings::default()).unwrap();
        let spec = ModelSpec::new(MotionModel::Affine, false);
        let a = est
            .estimate_images(v0, v1, &ell, spec, Some(origin))
            .unwrap();
        let b = est
            .estimate_images(v0, v1, &mask, spec, Some(origin))
            .unwrap();
        // Same pixels, same weights, same pyramid window: identical arithmetic.
        assert_eq!(a.params, b.params);
        assert!(
            (a.params[0] - 0.8).abs() < 0.01 && (a.params[3] - 0.5).abs() < 0.01,
            "{:?}",
            a.params
        );
    }

    #[test]
    fn shared_full_pyramids_match_region_pyramids() {
        // The region window has a 32 px margin, so the two pyramids agree where the region reads
        // them; the estimates differ only by rounding (< 1e-4 px at the corners).
        let origin = [64.0, 48.0];
        let (f0, f1) = pair([1.5, 0.0, 0.0, -1.0, 0.0, 0.0], origin, 0.0);
        let (v0, v1) = views(&f0, &f1);
        let est = MotionEstimator::new(Settings::default()).unwrap();
        let region = Region::Rect {
            x: 40.0,
            y: 30.0,
            width: 48.0,
            height: 36.0,
        };
        let spec = ModelSpec::new(MotionModel::Affine, false);
        let single = est.estimate_images(v0, v1, &region, spec, None).unwrap();
        let (mut p0, mut p1) = (Pyramid::new(), Pyramid::new());
        est.build_pyramid_into(v0, &mut p0).unwrap();
        est.build_pyramid_into(v1, &mut p1).unwrap();
        let mut ws = Workspace::new();
        let shared = est
            .estimate(&p0, &p1, &region, spec, None, &mut ws)
            .unwrap();
        for (x, y) in [(40.0, 30.0), (87.0, 65.0)] {
            let (a, b) = (single.displacement(x, y), shared.displacement(x, y));
            assert!(
                (a[0] - b[0]).abs() < 1e-4 && (a[1] - b[1]).abs() < 1e-4,
                "{a:?} vs {b:?}"
            );
        }
        assert!((single.params[0] - 1.5).abs() < 0.01);
    }

    #[test]
    fn non_convergence_is_a_status_not_an_error() {
        let origin = [63.5, 47.5];
        let (f0, f1) = pair([2.5, 0.0, 0.0, 1.5, 0.0, 0.0], origin, 0.0);
        let (v0, v1) = views(&f0, &f1);
        let settings = Settings {
            max_iterations: 1,
            levels: 1,
            ..Settings::default()
        };
        let r = MotionEstimator::new(settings)
            .unwrap()
            .estimate_images(
                v0,
                v1,
                &Region::Full,
                ModelSpec::new(MotionModel::Affine, false),
                None,
            )
            .unwrap();
        assert!(!r.converged && !r.reliable);
        // The starting hypotheses' iterations are counted too.
        assert!(r.iterations.len() == 1 && r.iterations[0] >= 2, "{r:?}");
    }

    #[test]
    fn flat_images_and_bad_inputs_are_errors() {
        let flat = vec![100.0f32; W * H];
        let v = ImageView::new(W, H, &flat).unwrap();
        let est = MotionEstimator::new(Settings::default()).unwrap();
        let r = est.estimate_images(
            v,
            v,
            &Region::Full,
            ModelSpec::new(MotionModel::Affine, false),
            None,
        );
        assert!(matches!(r, Err(Error::Degenerate { .. })), "{r:?}");

        let small = vec![0.0f32; 16];
        let s = ImageView::new(4, 4, &small).unwrap();
        let r = est.estimate_images(
            v,
            s,
            &Region::Full,
            ModelSpec::new(MotionModel::Affine, false),
            None,
        );
        assert!(matches!(r, Err(Error::DimensionMismatch { .. })));
        let outside = Region::Rect {
            x: 500.0,
            y: 0.0,
            width: 10.0,
            height: 10.0,
        };
        let r = est.estimate_images(
            v,
            v,
            &outside,
            ModelSpec::new(MotionModel::Affine, false),
            None,
        );
        assert!(matches!(r, Err(Error::RegionTooSmall { .. })));
        let r = est.estimate_images(
            v,
            v,
            &Region::Full,
            ModelSpec::new(MotionModel::Affine, false),
            Some([f64::NAN, 0.0]),
        );
        assert!(matches!(r, Err(Error::NonFinite { what: "origin", .. })));
        let bad = Settings {
            tolerance: 0.0,
            ..Settings::default()
        };
        assert!(MotionEstimator::new(bad).is_err());
    }

    #[test]
    fn lane_normal_equations_match_a_scalar_f64_reference() {
        // The f32 lane accumulation over row spans against a direct f64 sum with
        // `MotionModel::gradient_row`, for every model, with an offset and a redescending ρ
        // rejecting some pixels. f32 products summed in f64 every 64 groups: relative agreement
        // to 1e-4 of the largest entry (f32 epsilon 6e-8 × a few hundred terms per flush, with
        // margin).
        let origin = SHARED_ORIGIN;
        let (f0, f1) = pair(SHARED_MOTION, origin, 3.0);
        let (v0, v1) = views(&f0, &f1);
        let settings = Settings::default();
        let est = MotionEstimator::new(settings).unwrap();
        let (mut p0, mut p1) = (Pyramid::new(), Pyramid::new());
        est.build_pyramid_into(v0, &mut p0).unwrap();
        est.build_pyramid_into(v1, &mut p1).unwrap();
        let region = Region::Ellipse(shared_ellipse());
        let (l0, l1) = (p0.level(0).unwrap(), p1.level(0).unwrap());
        let bbox = region.pixel_box(W, H).unwrap();
        let robust = RobustFunction::default();
        for spec in [
            ModelSpec::new(MotionModel::Translation, false),
            ModelSpec::new(MotionModel::Scale, true),
            ModelSpec::new(MotionModel::Affine, false),
            ModelSpec::new(MotionModel::Affine, true),
        ] {
            let mut ws = Workspace::new();
            ws.collect(l0, 0, &region, bbox);
            // A rough Θ so that residuals are large and Tukey rejects some pixels.
            let theta = [0.5, 0.0, 0.0, 0.3, 0.0, 0.0, 0.0];
            ws.evaluate(l0, l1, spec, &theta, origin, true);
            let s = 2.0;
            let rejected = (0..ws.idx.len())
                .filter(|&k| ws.valid[k] != 0 && f64::from(ws.res[k]).abs() >= robust.c() * s)
                .count();
            assert!(rejected > 0, "{spec:?}: no pixel rejected");
            let (h, b, hp) = ws.normal_equations(spec, robust, s, origin, true);
            let (n, ng) = (spec.len(), spec.model.geometric_len());
            let (mut hr, mut br, mut hpr) = (Mat7::zeros(), Vec7::zeros(), Mat7::zeros());
            let mut j = [0.0f64; 7];
            let pixels = ws
                .spans
                .iter()
                .flat_map(|sp| (0..sp.len).map(move |t| (sp.k0 + t, sp.i0 + t, sp.j)));
            for (k, i, jj) in pixels {
                if ws.valid[k] == 0 {
                    continue;
                }
                let r = f64::from(ws.res[k]);
                let (x, y) = (i as f64 - origin[0], jj as f64 - origin[1]);
                spec.model
                    .gradient_row(f64::from(ws.gx[k]), f64::from(ws.gy[k]), x, y, &mut j);
                if spec.offset {
                    j[ng] = -1.0;
                }
                let (w, wp) = (robust.weight(r / s), robust.psi_prime(r / s));
                for a in 0..n {
                    br[a] += w * j[a] * r;
                    for c in 0..n {
                        hr[(a, c)] += w * j[a] * j[c];
                        hpr[(a, c)] += wp * j[a] * j[c];
                    }
                }
            }
            for (got, want) in [(h, hr), (hp, hpr)] {
                let scale = want.abs().max();
                assert!(scale > 0.0);
                assert!((got - want).abs().max() < 1e-4 * scale, "{spec:?}");
            }
            assert!((b - br).abs().max() < 1e-4 * br.abs().max(), "{spec:?}");
        }
    }

    #[test]
    fn pixels_leaving_the_image_are_dropped() {
        // A 4 px shift to the right: the last 4 columns of frame 0 have no match in frame 1 and
        // count neither as inliers nor in the total (issue 16: the fraction is over the pixels
        // that stay in the image), so a pure shift reads close to 1. Noise-free, the robust scale
        // is tiny, so a few columns next to the clamped image border fall outside c·σ̂: allow up
        // to 8 columns.
        let origin = [63.5, 47.5];
        let (f0, f1) = pair([4.0, 0.0, 0.0, 0.0, 0.0, 0.0], origin, 0.0);
        let (v0, v1) = views(&f0, &f1);
        let r = MotionEstimator::new(Settings::default())
            .unwrap()
            .estimate_images(
                v0,
                v1,
                &Region::Full,
                ModelSpec::new(MotionModel::Translation, false),
                None,
            )
            .unwrap();
        assert!(r.converged && (r.params[0] - 4.0).abs() < 0.01, "{r:?}");
        let f = r.inlier_fraction;
        assert!((1.0 - 8.0 / 124.0..=1.0).contains(&f), "{f}");
        assert!(r.reliable);
    }
}

/// Pixels per band: large regions are cut into bands of whole row spans of at least this many
/// pixels, which are processed concurrently with the `parallel` feature (see [`Band`]).
const BAND_PIXELS: usize = 8192;

/// Consecutive spans `s0..s1` of the region, holding pixels `k0..k1`. The cut depends only on the
/// region (never on the number of threads), and every per-band partial sum is combined in band
/// order, so results are bit-identical whether bands run in parallel or not.
#[derive(Debug, Clone, Copy, Default)]
struct Band {
    s0: usize,
    s1: usize,
    k0: usize,
    k1: usize,
}

/// Runs `f` on a thread of rayon's pool when the work is `large` (and the `parallel` feature is
/// on) and the caller is not already one: the bands of a large region are then forked from a
/// pool thread, which the other threads steal from while still spinning, instead of each fork
/// being injected from outside and the caller sleeping until it is done (measured: that handoff
/// cost ~2 ms per full-frame estimate). The result does not depend on where `f` runs.
fn on_pool<R: Send>(large: bool, f: impl FnOnce() -> R + Send) -> R {
    #[cfg(feature = "parallel")]
    if large && rayon::current_thread_index().is_none() {
        return rayon::scope(|_| f());
    }
    let _ = large;
    f()
}

/// `f` over `items` in order: concurrently on rayon's pool with the `parallel` feature (and more
/// than one item), sequentially otherwise. The results come back in the items' order.
fn map_bands<I: Send, T: Send>(items: Vec<I>, f: impl Fn(I) -> T + Sync + Send) -> Vec<T> {
    #[cfg(feature = "parallel")]
    if items.len() > 1 {
        use rayon::prelude::*;
        return items.into_par_iter().map(f).collect();
    }
    items.into_iter().map(f).collect()
}

/// The per-pixel outputs of `evaluate` for a run of pixels.
struct Samples<'a> {
    res: &'a mut [f32],
    gx: &'a mut [f32],
    gy: &'a mut [f32],
    fx: &'a mut [f32],
    fy: &'a mut [f32],
    qi: &'a mut [u32],
    valid: &'a mut [u8],
}

impl<'a> Samples<'a> {
    /// The first `mid` pixels and the rest.
    fn split_at(self, mid: usize) -> (Self, Self) {
        let (res, res2) = self.res.split_at_mut(mid);
        let (gx, gx2) = self.gx.split_at_mut(mid);
        let (gy, gy2) = self.gy.split_at_mut(mid);
        let (fx, fx2) = self.fx.split_at_mut(mid);
        let (fy, fy2) = self.fy.split_at_mut(mid);
        let (qi, qi2) = self.qi.split_at_mut(mid);
        let (valid, valid2) = self.valid.split_at_mut(mid);
        (
            Self {
                res,
                gx,
                gy,
                fx,
                fy,
                qi,
                valid,
            },
            Self {
                res: res2,
                gx: gx2,
                gy: gy2,
                fx: fx2,
                fy: fy2,
                qi: qi2,
                valid: valid2,
            },
        )
    }
}

/// The warp of `evaluate` in the second frame's window: q = c + B·r, the gradient map
/// (I + D)^−T, the intensity offset, both levels, and whether this is full resolution.
struct Warp<'l> {
    c: [f64; 2],
    b: [f64; 4],
    t: [f32; 4],
    offset: f32,
    l0: &'l Level,
    l1: &'l Level,
    full_res: bool,
}

impl Warp<'_> {
    /// `evaluate` over `spans`, whose pixels start at entry `kb` (where `out` starts); `idx` is
    /// the whole pixel list. Returns the number of valid samples.
    ///
    /// Full resolution: the sample loop computes only the residual and where it was taken; the
    /// Jacobian's gradients (the first frame's, mapped through (I + D)^−T) are read from
    /// contiguous rows in a second, vectorisable loop. Coarse levels: bilinear values and
    /// second-frame gradients in the sample loop, then the first frame's mapped gradients
    /// averaged in the same way; the sample positions are not stored (only the full-resolution
    /// covariance reads them). A span's pixels are consecutive in the first frame's level, so
    /// its rows there are plain slices.
    #[inline(always)]
    fn spans(&self, spans: &[Span], idx: &[u32], kb: usize, mut out: Samples<'_>) -> usize {
        let mut n_valid = 0;
        for sp in spans {
            let r = sp.k0 - kb..sp.k0 - kb + sp.len;
            let first = idx[sp.k0] as usize;
            if self.full_res {
                n_valid += self.full_res_span(sp, first, r.clone(), &mut out);
                self.map_gradients::<false>(first, &mut out.gx[r.clone()], &mut out.gy[r]);
            } else {
                n_valid += self.coarse_span(sp, first, r.clone(), &mut out);
                self.map_gradients::<true>(first, &mut out.gx[r.clone()], &mut out.gy[r]);
            }
        }
        n_valid
    }

    /// The second frame's sample position of column `x` on the span's row.
    #[inline(always)]
    fn sample(&self, sp: &Span, x: usize) -> Option<Sample> {
        let [cx, cy] = self.c;
        let [bx1, bx2, by1, by2] = self.b;
        let (y, x) = (sp.j as f64, x as f64);
        let (w1, h1) = (self.l1.width, self.l1.height);
        let (qx, qy) = (cx + bx2 * y + bx1 * x, cy + by2 * y + by1 * x);
        Sample::at(qx, qy, (w1 - 1) as f64, (h1 - 1) as f64, w1, h1)
    }

    /// Full resolution, one span (entries `r`, first pixel `first` in the first frame's level):
    /// where each sample falls and which taps it uses (`valid` 2 for the bicubic interior, 1 for
    /// the bilinear border), then the residuals. Bicubic: bilinear interpolation error on fine
    /// texture would bias the estimate and inflate the residual scale. (Two short loops keep the
    /// interpolation's operands in registers; one long loop spilled them.)
    #[inline(always)]
    fn full_res_span(
        &self,
        sp: &Span,
        first: usize,
        r: Range<usize>,
        out: &mut Samples<'_>,
    ) -> usize {
        let (w1, h1) = (self.l1.width, self.l1.height);
        let pos = out.fx[r.clone()]
            .iter_mut()
            .zip(&mut out.fy[r.clone()])
            .zip(&mut out.qi[r.clone()])
            .zip(&mut out.valid[r.clone()]);
        for (t, (((fxo, fyo), qio), valid)) in pos.enumerate() {
            *valid = match self.sample(sp, sp.i0 + t) {
                Some(Sample {
                    ix,
                    iy,
                    fx,
                    fy,
                    i00,
                }) => {
                    (*fxo, *fyo, *qio) = (fx, fy, i00 as u32);
                    if ix >= 1 && iy >= 1 && ix + 2 < w1 && iy + 2 < h1 {
                        2
                    } else {
                        1
                    }
                }
                None => 0,
            };
        }
        let (d1, z0) = (&self.l1.data[..], &self.l0.data[first..first + sp.len]);
        let vals = out.res[r.clone()]
            .iter_mut()
            .zip(&out.fx[r.clone()])
            .zip(&out.fy[r.clone()])
            .zip(&out.qi[r.clone()])
            .zip(&out.valid[r])
            .zip(z0);
        let mut n_valid = 0;
        for (((((res, &fx), &fy), &qi), &valid), &z0) in vals {
            let i00 = qi as usize;
            let v = match valid {
                0 => continue,
                2 => bicubic(d1, i00, w1, fx, fy),
                _ => bilinear(d1, i00, w1, fx, fy),
            };
            *res = v - z0 - self.offset;
            n_valid += 1;
        }
        n_valid
    }

    /// A coarse level, one span: bilinear residuals and the second frame's gradients.
    #[inline(always)]
    fn coarse_span(
        &self,
        sp: &Span,
        first: usize,
        r: Range<usize>,
        out: &mut Samples<'_>,
    ) -> usize {
        let (l1, w1) = (self.l1, self.l1.width);
        let z0 = &self.l0.data[first..first + sp.len];
        let iter = out.res[r.clone()]
            .iter_mut()
            .zip(&mut out.gx[r.clone()])
            .zip(&mut out.gy[r.clone()])
            .zip(&mut out.valid[r])
            .zip(z0);
        let mut n_valid = 0;
        for (t, ((((res, gxo), gyo), valid), &z0)) in iter.enumerate() {
            let Some(Sample { fx, fy, i00, .. }) = self.sample(sp, sp.i0 + t) else {
                *valid = 0;
                continue;
            };
            *res = bilinear(&l1.data, i00, w1, fx, fy) - z0 - self.offset;
            *gxo = bilinear(&l1.gx, i00, w1, fx, fy);
            *gyo = bilinear(&l1.gy, i00, w1, fx, fy);
            *valid = 1;
            n_valid += 1;
        }
        n_valid
    }

    /// The first frame's gradients at the span's pixels (from `first` in its level) mapped
    /// through (I + D)^−T into `gx`, `gy`; with `AVERAGE` (coarse levels) averaged with what they
    /// hold, the second frame's gradients.
    #[inline(always)]
    fn map_gradients<const AVERAGE: bool>(&self, first: usize, gx: &mut [f32], gy: &mut [f32]) {
        let [t11, t12, t21, t22] = self.t;
        let n = gx.len();
        let (g0x, g0y) = (&self.l0.gx[first..first + n], &self.l0.gy[first..first + n]);
        for (((gxo, gyo), &ax), &ay) in gx.iter_mut().zip(gy).zip(g0x).zip(g0y) {
            if AVERAGE {
                *gxo = 0.5 * (*gxo + t11 * ax + t12 * ay);
                *gyo = 0.5 * (*gyo + t21 * ax + t22 * ay);
            } else {
                *gxo = t11 * ax + t12 * ay;
                *gyo = t21 * ax + t22 * ay;
            }
        }
    }
}

/// The per-pixel vectors u = m E[ψ'] J of the covariance's meat, and the sums of the noise
/// model (variance gains, inlier counts and weights).
struct UVectors<'a> {
    spec: ModelSpec,
    e1: f32,
    c: f64,
    rejection: Option<f64>,
    s: f64,
    o: [f64; 2],
    ka: f64,
    table: &'a [f64; 65],
    res: &'a [f32],
    valid: &'a [u8],
    m: &'a [f32],
    gx: &'a [f32],
    gy: &'a [f32],
    fx: &'a [f32],
    fy: &'a [f32],
}

impl UVectors<'_> {
    /// Fills `u` (entries from `kb` on) over `spans`; returns (Σ variance gain, inlier count,
    /// inlier weight, total weight).
    #[inline(always)]
    fn spans(&self, spans: &[Span], kb: usize, u: &mut [[f32; 8]]) -> (f64, usize, f64, f64) {
        let (spec, s, c, o) = (self.spec, self.s, self.c, self.o);
        let ng = spec.model.geometric_len();
        let ka = self.ka;
        // f ∈ [0, 1): the 32-bit conversion is shorter than the saturating one to usize.
        let q = |f: f64| self.table[((f * 64.0 + 0.5) as i32).clamp(0, 64) as usize];
        let (mut gain, mut n_in, mut m_in, mut m_all) = (0.0f64, 0usize, 0.0f64, 0.0f64);
        for sp in spans {
            let y = (sp.j as f64 - o[1]) as f32;
            let x_first = (sp.i0 as f64 - o[0]) as f32;
            for k in sp.k0..sp.k0 + sp.len {
                let u = &mut u[k - kb];
                *u = [0.0; 8];
                if self.valid[k] == 0 {
                    continue;
                }
                // Only pixels that stay in the image count (issue 16).
                m_all += f64::from(self.m[k]);
                let z = f64::from(self.res[k]) / s;
                if z.abs() < c {
                    let (fx, fy) = (f64::from(self.fx[k]), f64::from(self.fy[k]));
                    gain += ka * ka + q(fx) * q(fy);
                    n_in += 1;
                    m_in += f64::from(self.m[k]);
                }
                // Pixels a redescending ρ rejects carry no noise into Θ̂.
                if self.rejection.is_some_and(|r| z.abs() >= r) {
                    continue;
                }
                let me = self.m[k] * self.e1;
                let (gx, gy) = (self.gx[k] * me, self.gy[k] * me);
                let x = x_first + (k - sp.k0) as f32;
                match spec.model {
                    MotionModel::Translation => {
                        (u[0], u[1]) = (gx, gy);
                    }
                    MotionModel::Scale => {
                        (u[0], u[1], u[2]) = (gx, gy, gx * x + gy * y);
                    }
                    MotionModel::Affine => {
                        (u[0], u[1], u[2]) = (gx, gx * x, gx * y);
                        (u[3], u[4], u[5]) = (gy, gy * x, gy * y);
                    }
                }
                if spec.offset {
                    u[ng] = -me;
                }
            }
        }
        (gain, n_in, m_in, m_all)
    }
}

/// Where a warped position falls in the second frame: the top-left pixel of its 2×2 cell, the
/// fractional offsets and the flat index; `None` outside [0, xmax] × [0, ymax].
#[derive(Debug, Clone, Copy)]
struct Sample {
    ix: usize,
    iy: usize,
    fx: f32,
    fy: f32,
    i00: usize,
}

impl Sample {
    #[inline(always)]
    fn at(qx: f64, qy: f64, xmax: f64, ymax: f64, w1: usize, h1: usize) -> Option<Self> {
        if !(qx >= 0.0 && qy >= 0.0 && qx <= xmax && qy <= ymax) {
            return None;
        }
        // In range (checked above, and images are far smaller than 2³¹ pixels): the 32-bit
        // conversion is a few instructions shorter than the saturating one to usize.
        let ix = (qx as i32 as usize).min(w1 - 2);
        let iy = (qy as i32 as usize).min(h1 - 2);
        Some(Self {
            ix,
            iy,
            fx: (qx - ix as f64) as f32,
            fy: (qy - iy as f64) as f32,
            i00: iy * w1 + ix,
        })
    }
}
