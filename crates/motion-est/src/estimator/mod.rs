//! Coarse-to-fine robust Gauss–Newton estimation of a parametric motion model (Odobez et al. 2003
//! §4.2, Eq. 13–14; their ref. 10, Odobez & Bouthemy 1995), with an honest covariance.
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
//! residuals with correlation ρ between two pixels, Cov(ψ, ψ) ≈ E\[ψ'\]²·ρ (first Hermite term), and
//! Var(ψ) = E\[ψ²\] at the same pixel; so Var(F) = E\[ψ'\]² Var(Σ_r u_r δDFD_r) with u_r = m_r J_r over
//! the pixels ρ does not reject, plus the same-pixel correction (E\[ψ²\] − E\[ψ'\]²) σ̂² Σ_r m_r² J_r J_rᵀ.
//! (Using the realised ψ'(DFD_r/σ̂)² instead would over-state the variance by E\[ψ'²\]/E\[ψ²\] ≈ 1.10
//! for Tukey.) The DFD is computed on pre-smoothed images, so δDFD_r = (K∗n₁)(r+d) −
//! (K∗n₀)(r) is correlated across pixels; with n₀, n₁ white of variance σₙ², Var(Σ u_r (K∗n)(r)) =
//! σₙ² Σ_s (K∗u)(s)(K∗u)(s)ᵀ for the first frame; for the second, u is first spread onto the
//! interpolation taps around r + d(r). Cov(Θ̂) = σₙ² H⁻¹ [meat₀ + meat₁] H⁻ᵀ. σₙ² itself is recovered
//! from the robust scale of the smoothed DFD, whose variance per pixel is σₙ²(ΣK² + q(f_x)q(f_y)),
//! where q accounts for the cubic interpolation of the second frame at fractional offset f.
//! Ignoring the smoothing (treating the DFD as white) and the robust weights is what makes the
//! original implementation under-report the error about 2.4×.
//!
//! # Layout
//! The public types and entry points are here; the stages live in submodules: [`Settings`]
//! (`settings`), [`MotionEstimate`] (`estimate`), [`Request`] (`request`), the buffers and the
//! region's row spans (`workspace`, `collect`), one coarse-to-fine fit (`fit`) and its
//! iterations at one level (`iterate`), the warp and interpolation (`warp`), the normal
//! equations (`normal`), the covariance (`covariance`), and the re-starts of an unreliable fit
//! (`restarts`).

mod collect;
mod covariance;
mod estimate;
mod fit;
mod iterate;
mod meat;
mod normal;
mod request;
mod restarts;
mod scale_at;
mod settings;
#[cfg(test)]
mod tests;
mod warp;
mod workspace;

use nalgebra::{SMatrix, SVector};
use vision_core::GreyImage;

use crate::model::ModelSpec;
use crate::pyramid::{Pyramid, Window};
use crate::region::Region;
use crate::{Error, Result};

pub use estimate::MotionEstimate;
use request::Frames;
pub use request::Request;
pub use settings::Settings;
use workspace::{BAND_PIXELS, on_pool};
pub use workspace::{FrameBuffers, Workspace};

pub(crate) type Mat7 = SMatrix<f64, 7, 7>;
type Vec7 = SVector<f64, 7>;

/// The robust multiresolution estimator. Cheap to copy; holds only settings.
#[derive(Debug, Clone, Copy)]
pub struct MotionEstimator {
    settings: Settings,
    /// (E\[ψ'\], E\[ψ²\]) under Gaussian noise, for the covariance.
    moments: (f64, f64),
}

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
    pub fn build_pyramid_into(&self, image: GreyImage<'_>, pyramid: &mut Pyramid) -> Result<()> {
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
        image0: GreyImage<'_>,
        image1: GreyImage<'_>,
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
        let request = Request {
            origin,
            ..Request::new(region, spec)
        };
        on_pool(win.width * win.height >= 2 * BAND_PIXELS, || {
            self.estimate_window([image0, image1], &request, buffers, win)
        })
    }

    /// The rest of [`estimate_images_into`](Self::estimate_images_into) once the window is known.
    fn estimate_window(
        &self,
        images: [GreyImage<'_>; 2],
        request: &Request<'_>,
        buffers: &mut FrameBuffers,
        win: Window,
    ) -> Result<MotionEstimate> {
        let s = &self.settings;
        let [image0, image1] = images;
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
        self.estimate_request(
            &buffers.pyramid0,
            &buffers.pyramid1,
            request,
            &mut buffers.workspace,
        )
    }

    /// Allocating twin of [`estimate_images_into`](Self::estimate_images_into).
    ///
    /// # Errors
    /// As [`estimate_images_into`](Self::estimate_images_into).
    pub fn estimate_images(
        &self,
        image0: GreyImage<'_>,
        image1: GreyImage<'_>,
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
    /// every region). `origin` defaults to [`Region::centre`]. The same as
    /// [`estimate_request`](Self::estimate_request) with a cold start.
    ///
    /// # Errors
    /// [`Error::Unreliable`], carrying the estimate, when it is not
    /// [reliable](MotionEstimate::reliable) (among others, when it did not converge);
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
        let request = Request {
            origin,
            ..Request::new(region, spec)
        };
        self.estimate_request(pyramid0, pyramid1, &request, ws)
    }

    /// As [`estimate`](Self::estimate), warm-started from `initial` when given: parameters in
    /// level-0 pixels laid out as [`MotionEstimate::params`] (`spec.len()` values, about the same
    /// origin), e.g. a motion predicted from the previous frame. With a guess, only the
    /// [`Settings::warm_levels`] finest levels are used (coarse levels only serve to find a
    /// distant motion) and the translation-only warm-up is skipped. The same as
    /// [`estimate_request`](Self::estimate_request).
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
        let request = Request {
            origin,
            initial,
            ..Request::new(region, spec)
        };
        self.estimate_request(pyramid0, pyramid1, &request, ws)
    }

    /// Estimates the motion that `request` describes (region, model, origin, warm start) from
    /// frame 0 to frame 1 on prebuilt pyramids: see [`estimate`](Self::estimate) for a cold start
    /// and [`estimate_from`](Self::estimate_from) for a warm one.
    ///
    /// # Errors
    /// As [`estimate_from`](Self::estimate_from).
    ///
    /// # Examples
    /// ```
    /// use motion_est::{
    ///     ModelSpec, MotionEstimator, MotionModel, Pyramid, Region, Request, Settings, Workspace,
    /// };
    /// use vision_core::GreyImage;
    /// let (w, h) = (96, 80);
    /// let tex = |x: f64, y: f64| 128.0 + 40.0 * (0.31 * x + 0.1 * y).sin() + 30.0 * (0.23 * y - 0.05 * x).cos();
    /// let f0: Vec<f32> = (0..w * h).map(|k| tex((k % w) as f64, (k / w) as f64) as f32).collect();
    /// let f1: Vec<f32> = (0..w * h).map(|k| tex((k % w) as f64 - 1.5, (k / w) as f64) as f32).collect();
    /// let est = MotionEstimator::new(Settings::default())?;
    /// let (mut p0, mut p1) = (Pyramid::new(), Pyramid::new());
    /// est.build_pyramid_into(GreyImage::new(w, h, &f0)?, &mut p0)?;
    /// est.build_pyramid_into(GreyImage::new(w, h, &f1)?, &mut p1)?;
    /// let region = Region::Full;
    /// // Warm-started from a guess 0.4 px off.
    /// let guess = [1.1, 0.2];
    /// let request = Request::new(&region, ModelSpec::new(MotionModel::Translation, false))
    ///     .with_initial(&guess);
    /// let r = est.estimate_request(&p0, &p1, &request, &mut Workspace::new())?;
    /// assert!((r.params[0] - 1.5).abs() < 0.01 && r.params[1].abs() < 0.01);
    /// # Ok::<(), motion_est::Error>(())
    /// ```
    pub fn estimate_request(
        &self,
        pyramid0: &Pyramid,
        pyramid1: &Pyramid,
        request: &Request<'_>,
        ws: &mut Workspace,
    ) -> Result<MotionEstimate> {
        let (w, h) = pyramid0.image_size();
        let region = request.region;
        let large = region.validate(w, h).is_ok()
            && region
                .pixel_box(w, h)
                .is_some_and(|b| (b.i1 - b.i0) * (b.j1 - b.j0) >= 2 * BAND_PIXELS);
        let frames = Frames {
            p0: pyramid0,
            p1: pyramid1,
        };
        on_pool(large, || self.estimate_here(frames, request, ws)).and_then(reliable_only)
    }
}

/// `Ok` only for a [reliable](MotionEstimate::reliable) estimate; [`Error::Unreliable`] with the
/// estimate otherwise.
fn reliable_only(estimate: MotionEstimate) -> Result<MotionEstimate> {
    if estimate.reliable {
        Ok(estimate)
    } else {
        Err(Error::Unreliable {
            estimate: Box::new(estimate),
        })
    }
}
