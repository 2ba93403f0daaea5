//! Gauss–Newton with IRLS at one pyramid level, and the starting hypotheses of a cold start.

use super::{Mat7, MotionEstimator, Vec7, Workspace};
use crate::model::{ModelSpec, MotionModel};
use crate::pyramid::Level;
use crate::robust::{lower_quartile, robust_scale_from};

/// What the iterations at one level need.
pub(super) struct LevelCtx<'a> {
    pub(super) l0: &'a Level,
    pub(super) l1: &'a Level,
    pub(super) spec: ModelSpec,
    /// The origin in level units.
    pub(super) o: [f64; 2],
    pub(super) corners: [(f64, f64); 4],
    pub(super) tol: f64,
    /// A step larger than this means divergence.
    pub(super) limit: f64,
    pub(super) full_res: bool,
    pub(super) level: usize,
}

/// The outcome of the iterations at one level.
pub(super) struct LevelRun {
    pub(super) iterations: usize,
    pub(super) converged: bool,
    /// The noise scale at the last iteration.
    pub(super) scale: f64,
    /// The last step (px) and its parameters.
    pub(super) step: f64,
    pub(super) delta: Vec7,
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
    pub(super) fn iterate_level(
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
                // cap, and the next level only needs a start within its basin.
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

    /// Several starting hypotheses at a cold start's first level: the translations of
    /// a grid of ±[`START_RADIUS`] level pixels around `theta` are ranked by the lower quartile of
    /// |DFD| (small where a group of pixels fits), the best [`START_HYPOTHESES`] distinct ones
    /// are each refined by the translation-only Gauss–Newton with the noise scale, and the one
    /// explaining most pixels at the smallest of their noise scales is kept in `theta`. A single
    /// least-squares start would land between two motions of comparable support.
    pub(super) fn best_start(
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
                if ws.residuals_at_shift(lv.l0, lv.l1, spec, &t, lv.o, lv.full_res) < n + 1 {
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

/// Whether IRLS, which converges linearly, will take its next step below `tol`: the step shrank
/// from `prev` to `step`, the next one is predicted at step · (step / prev), and that must be below
/// `tol` with the step itself already within 20 tolerances (a guard against a step that shrank
/// by chance). Stopping here instead of taking one more iteration to see the small step saves
/// an iteration per level; the estimate is then within about that predicted step of the limit.
fn converging_below(step: f64, prev: f64, tol: f64) -> bool {
    prev.is_finite() && step < 20.0 * tol && step * (step / prev) < tol
}

/// Indices of the translation parameters (and the offset) of a model: at most three.
pub(super) fn translation_active(spec: ModelSpec) -> Vec<usize> {
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
