//! One coarse-to-fine fit: the inputs checked and the start level chosen, the levels from the
//! coarsest to full resolution, then the final pass at full resolution (scale and covariance at
//! Θ̂).

use super::covariance::NoiseModel;
use super::iterate::{LevelCtx, translation_active};
use super::request::Frames;
use super::{MotionEstimate, MotionEstimator, Request, Vec7, Workspace};
use crate::model::MotionModel;
use crate::region::PixelBox;
use crate::robust::robust_scale_from;
use crate::{Error, Result};

/// The largest last Gauss–Newton step (px) after which the final covariance reuses that
/// iteration's residuals instead of evaluating them again at Θ̂.
const REUSE_STEP: f64 = 0.01;

/// The largest last Gauss–Newton step (px) after which the final covariance takes the residuals at
/// Θ̂ to first order from the last evaluation (see `Workspace::linearise`) instead of evaluating
/// them again; larger last steps (and unconverged estimates) are evaluated afresh.
const LINEAR_STEP: f64 = 0.1;

/// The checked inputs of one request: the origin, the region's pixel box and the levels present
/// in both pyramids and allowed by the settings.
pub(super) struct Checked {
    /// The origin of the model's coordinates, image pixels.
    pub(super) origin: [f64; 2],
    /// The region's pixel box.
    pub(super) bbox: PixelBox,
    /// Levels present in both pyramids and allowed by the settings.
    pub(super) top: usize,
}

/// The checked inputs of one fit and the levels it uses.
struct Plan {
    /// The origin of the model's coordinates, image pixels.
    origin: [f64; 2],
    /// The region's pixel box.
    bbox: PixelBox,
    /// Levels present in both pyramids and allowed by the settings.
    top: usize,
    /// The coarsest level used.
    start: usize,
    /// Whether the workspace still lists the region's pixels at `start` (from choosing it).
    collected: bool,
}

/// Where the levels left the fit: the parameters (level 0), the iterations per level, whether
/// full resolution converged, and its last iteration's noise scale, step (px) and parameter
/// change.
struct Descent {
    theta: [f64; 7],
    iterations: Vec<usize>,
    converged: bool,
    last_scale: f64,
    last_step: f64,
    last_delta: Vec7,
}

impl MotionEstimator {
    /// One coarse-to-fine fit; also returns whether it converged at a noise scale (at most twice
    /// [`Settings::max_scale`](super::Settings::max_scale)), which lets it take part in the
    /// choice among re-start fits.
    pub(super) fn estimate_once(
        &self,
        frames: Frames<'_>,
        request: &Request<'_>,
        ws: &mut Workspace,
    ) -> Result<(MotionEstimate, bool)> {
        let plan = self.plan(frames, request, ws)?;
        let descent = self.descend(frames, request, &plan, ws)?;
        self.finish(frames, request, &plan, descent, ws)
    }

    /// Checks the request against the pyramids and the settings, and picks the coarsest level
    /// at which the region still has enough pixels (its pixel list is kept in `ws`).
    fn plan(&self, frames: Frames<'_>, request: &Request<'_>, ws: &mut Workspace) -> Result<Plan> {
        let st = &self.settings;
        let Checked { origin, bbox, top } = self.check(frames, request)?;
        let usable = if request.initial.is_some() {
            top.min(st.warm_levels)
        } else {
            top
        };
        // The coarsest level at which the region still has enough pixels; its pixel list is kept.
        let mut plan = Plan {
            origin,
            bbox,
            top,
            start: 0,
            collected: false,
        };
        for l in (1..usable).rev() {
            if let Some(level) = frames.p0.level(l)
                && ws.collect(level, l, request.region, bbox) >= st.min_level_pixels
            {
                plan.start = l;
                plan.collected = true;
                break;
            }
        }
        Ok(plan)
    }

    /// Checks the request against the pyramids and the settings: the initial parameters, the
    /// pyramids' sizes and smoothing, the region and the origin.
    pub(super) fn check(&self, frames: Frames<'_>, request: &Request<'_>) -> Result<Checked> {
        let st = &self.settings;
        let (pyramid0, pyramid1) = (frames.p0, frames.p1);
        let (region, spec) = (request.region, request.spec);
        if let Some(p) = request.initial {
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
        let origin = request.origin.unwrap_or_else(|| region.centre(w, h));
        for (index, v) in origin.into_iter().enumerate() {
            if !v.is_finite() {
                return Err(Error::NonFinite {
                    what: "origin",
                    index,
                });
            }
        }
        let bbox = region.pixel_box(w, h).ok_or(Error::RegionTooSmall {
            got: 0,
            needed: spec.len() + 1,
        })?;
        let top = st.levels.min(pyramid0.levels()).min(pyramid1.levels());
        Ok(Checked { origin, bbox, top })
    }

    /// The Gauss–Newton iterations of every level from `plan.start` down to full resolution,
    /// each level starting from the previous one's parameters.
    fn descend(
        &self,
        frames: Frames<'_>,
        request: &Request<'_>,
        plan: &Plan,
        ws: &mut Workspace,
    ) -> Result<Descent> {
        let st = &self.settings;
        let (spec, region, initial) = (request.spec, request.region, request.initial);
        let (n, ng) = (spec.len(), spec.model.geometric_len());
        let (start, origin, bbox) = (plan.start, plan.origin, plan.bbox);
        let mut d = Descent {
            theta: [0.0f64; 7],
            iterations: vec![0usize; plan.top],
            converged: false,
            last_scale: st.min_scale,
            last_step: f64::INFINITY,
            last_delta: Vec7::zeros(),
        };
        if let Some(p) = initial {
            d.theta[..n].copy_from_slice(p);
            spec.model.to_coarser_level(&mut d.theta[..ng], start);
        }
        for l in (0..=start).rev() {
            if l != start {
                spec.model.to_finer_level(&mut d.theta[..ng]);
            }
            let (Some(l0), Some(l1)) = (frames.p0.level(l), frames.p1.level(l)) else {
                continue;
            };
            let count = if plan.collected && l == start {
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
            let lv = LevelCtx {
                l0,
                l1,
                spec,
                o: [origin[0] * f, origin[1] * f],
                corners: box_corners(bbox, origin, f),
                tol: if l == 0 {
                    st.tolerance
                } else {
                    st.coarse_tolerance
                },
                // A step larger than the level's window means divergence.
                limit: (l1.width + l1.height) as f64,
                full_res: l == 0,
                level: l,
            };
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
            if l == start && initial.is_none() {
                self.best_start(ws, &lv, &mut d.theta, &mut d.iterations[l]);
            }
            let run = self.iterate_level(ws, &lv, &mut d.theta, phases);
            d.iterations[l] += run.iterations;
            if run.iterations > 0 {
                d.last_scale = run.scale;
                d.last_step = run.step;
                d.last_delta = run.delta;
            }
            if l == 0 {
                d.converged = run.converged;
            }
        }
        Ok(d)
    }

    /// The final pass at full resolution: the residuals and their scale at Θ̂, the covariance,
    /// and the estimate.
    fn finish(
        &self,
        frames: Frames<'_>,
        request: &Request<'_>,
        plan: &Plan,
        d: Descent,
        ws: &mut Workspace,
    ) -> Result<(MotionEstimate, bool)> {
        let st = &self.settings;
        let spec = request.spec;
        let n = spec.len();
        let origin = plan.origin;
        let (Some(l0), Some(l1)) = (frames.p0.level(0), frames.p1.level(0)) else {
            return Err(Error::PyramidMismatch {
                reason: "level 0 missing".into(),
            });
        };
        let converged = d.converged;
        // After convergence the workspace still holds the residuals of the last iteration, taken
        // one step away from Θ̂: reused when that step was below `REUSE_STEP` px (their scale and
        // weights are then those at Θ̂ to well under the noise); otherwise evaluate afresh, so that
        // a loose tolerance (the tracking preset's 0.1 px) does not inflate the scale.
        let s = if converged && d.last_step <= REUSE_STEP {
            d.last_scale
        } else if converged && d.last_step <= LINEAR_STEP {
            // A step of at most 0.1 px: the residuals at Θ̂ to first order from the last
            // evaluation (see `Workspace::linearise`), and their scale seeded by the last one.
            ws.linearise(spec, &d.last_delta, origin);
            robust_scale_from(
                &ws.res,
                &ws.valid,
                &mut ws.scratch,
                st.min_scale,
                Some(d.last_scale),
            )
        } else {
            // After a converged level 0 the workspace still lists its pixels, and the last
            // iteration's scale, taken one step away, seeds the refinement at Θ̂.
            let count = if converged {
                ws.idx.len()
            } else {
                ws.collect(l0, 0, request.region, plan.bbox)
            };
            let n_valid = ws.evaluate(l0, l1, spec, &d.theta, origin, true);
            if n_valid < n + 1 {
                return Err(Error::RegionTooSmall {
                    got: n_valid.min(count),
                    needed: n + 1,
                });
            }
            let seed = converged.then_some(d.last_scale);
            robust_scale_from(&ws.res, &ws.valid, &mut ws.scratch, st.min_scale, seed)
        };
        let model = NoiseModel {
            spec,
            robust: st.robust,
            moments: self.moments,
            presmooth: st.presmooth,
        };
        let cov = ws.covariance(&model, s, origin, l1)?;
        if let Some(index) = d.theta.iter().position(|v| !v.is_finite()) {
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
        let honest = converged && self.scale_within_ceiling(s);
        let est = MotionEstimate {
            spec,
            params: d.theta[..n].to_vec(),
            covariance,
            origin,
            scale: s,
            noise_sigma: cov.noise_sigma,
            inlier_fraction: cov.inlier_fraction,
            iterations: d.iterations,
            converged,
            reliable: honest && cov.inlier_fraction >= st.min_inlier_fraction,
        };
        Ok((est, honest))
    }
}

/// The region box's corners relative to the origin, in level units (factor f = 2^−l).
fn box_corners(b: PixelBox, origin: [f64; 2], f: f64) -> [(f64, f64); 4] {
    let x0 = (b.i0 as f64 - origin[0]) * f;
    let x1 = (b.i1 as f64 - origin[0]) * f;
    let y0 = (b.j0 as f64 - origin[1]) * f;
    let y1 = (b.j1 as f64 - origin[1]) * f;
    [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
}
