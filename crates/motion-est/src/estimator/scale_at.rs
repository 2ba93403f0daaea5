//! The noise scale of a given motion on two given frames: how a motion estimated on other
//! frames of the same scene (shrunk ones, say) is tested at these frames' resolution.

use super::request::Frames;
use super::{MotionEstimator, Request, Workspace};
use crate::model::ModelSpec;
use crate::region::Region;
use crate::robust::robust_scale_from;
use crate::{Error, Result};

impl MotionEstimator {
    /// The robust scale σ̂ (grey levels) of the displaced frame differences of the motion
    /// `params` over `region`, between level 0 of two pyramids built with this estimator's
    /// smoothing: the scale a fit at Θ = `params` would report (the same robust estimate, see
    /// [`crate::robust`]). `params` are laid out as [`MotionEstimate::params`](super::MotionEstimate::params)
    /// for `spec`, in level-0 pixels about `origin`. The region is read on every k-th row, k the
    /// smallest that lists at most `max_pixels` of its box's pixels (every row when the box is
    /// smaller): σ̂ from n residuals has a relative spread of about 1/√(2n).
    ///
    /// Only level 0 is read, so pyramids of one level do.
    ///
    /// # Errors
    /// As [`estimate_from`](Self::estimate_from) for the pyramids, the region, the origin and
    /// `params` (as `initial`); [`Error::RegionTooSmall`] when fewer than `spec.len() + 1` of the
    /// pixels read have a displaced sample inside the second frame; [`Error::InvalidSetting`]
    /// for `max_pixels` of 0.
    #[allow(clippy::too_many_arguments)]
    pub fn residual_scale(
        &self,
        pyramid0: &crate::Pyramid,
        pyramid1: &crate::Pyramid,
        region: &Region<'_>,
        spec: ModelSpec,
        params: &[f64],
        origin: [f64; 2],
        max_pixels: usize,
        ws: &mut Workspace,
    ) -> Result<f64> {
        if max_pixels == 0 {
            return Err(Error::InvalidSetting {
                name: "max_pixels",
                reason: "at least one pixel must be read".into(),
            });
        }
        let frames = Frames {
            p0: pyramid0,
            p1: pyramid1,
        };
        let request = Request {
            origin: Some(origin),
            initial: Some(params),
            ..Request::new(region, spec)
        };
        // The checks of a warm-started fit (sizes, smoothing, region, origin, parameters).
        let b = self.check(frames, &request)?.bbox;
        let (Some(l0), Some(l1)) = (pyramid0.level(0), pyramid1.level(0)) else {
            return Err(Error::PyramidMismatch {
                reason: "level 0 missing".into(),
            });
        };
        let rows = b.j1 + 1 - b.j0;
        let box_pixels = (b.i1 + 1 - b.i0) * rows;
        let stride = box_pixels.div_ceil(max_pixels).clamp(1, rows);
        ws.collect_rows(l0, 0, region, b, stride);
        let mut theta = [0.0; 7];
        theta[..params.len()].copy_from_slice(params);
        let n_valid = ws.evaluate(l0, l1, spec, &theta, origin, true);
        let needed = spec.len() + 1;
        if n_valid < needed {
            return Err(Error::RegionTooSmall {
                got: n_valid,
                needed,
            });
        }
        Ok(robust_scale_from(
            &ws.res,
            &ws.valid,
            &mut ws.scratch,
            self.settings.min_scale,
            None,
        ))
    }

    /// Whether a fit whose noise scale is `scale` stays under the reliability ceiling of
    /// [`MotionEstimate::reliable`](super::MotionEstimate::reliable): 2·[`Settings::max_scale`](super::Settings::max_scale).
    pub fn scale_within_ceiling(&self, scale: f64) -> bool {
        scale <= 2.0 * self.settings.max_scale
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    use rand_pcg::Pcg64;
    use vision_core::{Ellipse, GreyImage};

    use super::*;
    use crate::{MotionModel, Pyramid, Settings};

    const W: usize = 160;
    const H: usize = 120;
    const ORIGIN: [f64; 2] = [80.0, 60.0];
    const MOTION: [f64; 6] = [1.5, 0.01, -0.02, -0.8, 0.015, 0.0];

    fn tex(x: f64, y: f64) -> f64 {
        128.0
            + 40.0 * (0.21 * x + 0.05 * y).sin()
            + 30.0 * (0.13 * y - 0.07 * x).cos()
            + 20.0 * (0.29 * (x + y)).sin()
    }

    /// Frame 1(q) = frame 0(q − d(q)) for the affine `MOTION` about `ORIGIN`, with white noise
    /// of `sigma` grey levels on both.
    fn frames(sigma: f64, seed: u64) -> (Vec<f32>, Vec<f32>) {
        let mut rng = Pcg64::seed_from_u64(seed);
        let noise = Normal::new(0.0, sigma).unwrap();
        let a = MOTION;
        let (m11, m12, m21, m22) = (1.0 + a[1], a[2], a[4], 1.0 + a[5]);
        let det = m11 * m22 - m12 * m21;
        let mut f0 = Vec::with_capacity(W * H);
        let mut f1 = Vec::with_capacity(W * H);
        for k in 0..W * H {
            let (x, y) = ((k % W) as f64, (k / W) as f64);
            f0.push((tex(x, y) + noise.sample(&mut rng)) as f32);
            let (bx, by) = (x - ORIGIN[0] - a[0], y - ORIGIN[1] - a[3]);
            let (px, py) = (
                ORIGIN[0] + (m22 * bx - m12 * by) / det,
                ORIGIN[1] + (-m21 * bx + m11 * by) / det,
            );
            f1.push((tex(px, py) + noise.sample(&mut rng)) as f32);
        }
        (f0, f1)
    }

    fn region() -> Region<'static> {
        Region::Ellipse(Ellipse {
            cx: ORIGIN[0],
            cy: ORIGIN[1],
            a: 45.0,
            b: 35.0,
            angle: 0.3,
        })
    }

    #[test]
    fn the_residual_scale_of_a_fitted_motion_is_the_scale_the_fit_reports() {
        // Over several noise draws and levels: the scale of the fit's own parameters, read on
        // every row and on a fifth of the pixels, matches the fit's reported scale; a motion
        // 2 px off scores far above it.
        let est = MotionEstimator::new(Settings::default()).unwrap();
        let spec = ModelSpec::new(MotionModel::Affine, false);
        let mut ws = Workspace::new();
        for (seed, sigma) in [(1, 1.0), (2, 3.0), (3, 6.0)] {
            let (f0, f1) = frames(sigma, seed);
            let p0 = Pyramid::build(GreyImage::new(W, H, &f0).unwrap(), None, 4, true).unwrap();
            let p1 = Pyramid::build(GreyImage::new(W, H, &f1).unwrap(), None, 4, true).unwrap();
            let r = region();
            let fit = est
                .estimate(&p0, &p1, &r, spec, Some(ORIGIN), &mut ws)
                .or_else(Error::into_unreliable)
                .unwrap();
            let every = est
                .residual_scale(&p0, &p1, &r, spec, &fit.params, ORIGIN, 1 << 20, &mut ws)
                .unwrap();
            assert!(
                (every / fit.scale - 1.0).abs() < 0.02,
                "σ {sigma}: {every} against the fit's {}",
                fit.scale
            );
            let budget = est
                .residual_scale(&p0, &p1, &r, spec, &fit.params, ORIGIN, 1000, &mut ws)
                .unwrap();
            assert!(
                (budget / fit.scale - 1.0).abs() < 0.1,
                "σ {sigma}: {budget} on a fifth of the rows against {}",
                fit.scale
            );
            let mut off = fit.params.clone();
            off[0] += 2.0;
            let wrong = est
                .residual_scale(&p0, &p1, &r, spec, &off, ORIGIN, 1000, &mut ws)
                .unwrap();
            assert!(
                wrong > 1.5 * fit.scale,
                "σ {sigma}: {wrong} for a motion 2 px off"
            );
            // The ceiling the estimator's own reliability uses.
            assert_eq!(
                est.scale_within_ceiling(fit.scale),
                fit.scale <= 2.0 * est.settings().max_scale
            );
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        let est = MotionEstimator::new(Settings::default()).unwrap();
        let spec = ModelSpec::new(MotionModel::Affine, false);
        let mut ws = Workspace::new();
        let (f0, f1) = frames(1.0, 4);
        let p0 = Pyramid::build(GreyImage::new(W, H, &f0).unwrap(), None, 1, true).unwrap();
        let p1 = Pyramid::build(GreyImage::new(W, H, &f1).unwrap(), None, 1, true).unwrap();
        let rough = Pyramid::build(GreyImage::new(W, H, &f1).unwrap(), None, 1, false).unwrap();
        let r = region();
        let ok = est.residual_scale(&p0, &p1, &r, spec, &MOTION, ORIGIN, 100, &mut ws);
        assert!(ok.is_ok_and(f64::is_finite));
        let short = est.residual_scale(&p0, &p1, &r, spec, &MOTION[..4], ORIGIN, 100, &mut ws);
        assert!(matches!(short, Err(Error::InvalidSetting { .. })));
        let mut nan = MOTION;
        nan[2] = f64::NAN;
        let bad = est.residual_scale(&p0, &p1, &r, spec, &nan, ORIGIN, 100, &mut ws);
        assert!(matches!(bad, Err(Error::NonFinite { .. })));
        let none = est.residual_scale(&p0, &p1, &r, spec, &MOTION, ORIGIN, 0, &mut ws);
        assert!(matches!(none, Err(Error::InvalidSetting { .. })));
        let mixed = est.residual_scale(&p0, &rough, &r, spec, &MOTION, ORIGIN, 100, &mut ws);
        assert!(matches!(mixed, Err(Error::PyramidMismatch { .. })));
        // A motion that carries every pixel out of the second frame.
        let mut away = MOTION;
        away[0] = 1000.0;
        let gone = est.residual_scale(&p0, &p1, &r, spec, &away, ORIGIN, 100, &mut ws);
        assert!(matches!(gone, Err(Error::RegionTooSmall { .. })));
    }
}
