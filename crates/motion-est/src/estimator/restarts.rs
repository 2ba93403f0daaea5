//! Re-starts of an unreliable fit from the motions that blocks of the region agree on (see
//! [`crate::restart`]), and the choice among the fits, with the occlusion between them (see
//! [`crate::occlusion`]).

use super::collect::RowTest;
use super::request::Frames;
use super::{MotionEstimate, MotionEstimator, Request, Workspace};
use crate::model::{ModelSpec, MotionModel};
use crate::pyramid::Level;
use crate::region::{PixelBox, Region};
use crate::{Result, occlusion, restart};

/// A fit, and whether it converged at a noise scale (see [`MotionEstimator::estimate_once`]).
type Fit = (MotionEstimate, bool);

/// The fewest blocks that make a starting motion of a re-start (see [`crate::restart`]).
const MIN_START_BLOCKS: usize = 4;

impl MotionEstimator {
    /// [`estimate_request`](Self::estimate_request) on the calling thread: one coarse-to-fine
    /// fit, and when it is not [`reliable`](MotionEstimate::reliable), re-starts from the motions
    /// that blocks of the region agree on (see [`crate::restart`]); the fit explaining most of
    /// the region's pixels, counting those a surface in front of it covers (see
    /// [`select`](Self::select)), is kept, and the first fit, flagged, when none can be
    /// compared.
    pub(super) fn estimate_here(
        &self,
        frames: Frames<'_>,
        request: &Request<'_>,
        ws: &mut Workspace,
    ) -> Result<MotionEstimate> {
        let first = self.estimate_once(frames, request, ws)?;
        if first.0.reliable {
            return Ok(first.0);
        }
        let (w, h) = frames.p0.image_size();
        let Some(bbox) = request.region.pixel_box(w, h) else {
            return Ok(first.0);
        };
        let Some(restarts) = self.restart_fits(frames, request, bbox, &first.0, ws) else {
            return Ok(first.0);
        };
        let mut fits = vec![first];
        fits.extend(restarts);
        let (best, share) = match (frames.p0.level(0), frames.p1.level(0)) {
            (Some(l0), Some(l1)) => {
                let fine = FullRes {
                    l0,
                    l1,
                    region: request.region,
                    bbox,
                };
                self.select(ws, &fine, &fits)
            }
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

    /// The fits warm-started from the motions that blocks of the region (box `bbox`) agree on,
    /// matched around the failed fit `first` and around the caller's guess; `None` when the
    /// matching level is missing.
    fn restart_fits(
        &self,
        frames: Frames<'_>,
        request: &Request<'_>,
        bbox: PixelBox,
        first: &MotionEstimate,
        ws: &mut Workspace,
    ) -> Option<Vec<Fit>> {
        let (spec, region) = (request.spec, request.region);
        let top = self
            .settings
            .levels
            .min(frames.p0.levels())
            .min(frames.p1.levels());
        let l = restart::matching_level(bbox, top);
        let (f0, f1) = (frames.p0.level(l)?, frames.p1.level(l)?);
        let mut vectors = Vec::new();
        let est = first;
        // Around the failed fit (between the motions present, or on one of them) and around the
        // caller's guess (zero without one): the failed fit may have wandered off both.
        let fitted = |x: f64, y: f64| est.displacement(x, y);
        let prior = |x: f64, y: f64| match request.initial {
            Some(p) => spec
                .model
                .displacement(p, x - est.origin[0], y - est.origin[1]),
            None => [0.0, 0.0],
        };
        restart::block_vectors(f0, f1, l, region, bbox, &[&fitted, &prior], &mut vectors);
        let min_blocks = (vectors.len() / 10).max(MIN_START_BLOCKS);
        let starts =
            restart::starting_motions(&vectors, est.origin, f64::from(1u32 << l), min_blocks);
        let mut fits = Vec::with_capacity(starts.len());
        for m in starts {
            let p = start_params(spec, &m.a);
            let warm = Request {
                origin: Some(est.origin),
                initial: Some(&p[..spec.len()]),
                ..*request
            };
            if let Ok(next) = self.estimate_once(frames, &warm, ws) {
                fits.push(next);
            }
        }
        Some(fits)
    }

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
    fn select(&self, ws: &mut Workspace, fine: &FullRes<'_>, fits: &[Fit]) -> (usize, f64) {
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
            .map(|(f, &u)| if u { fine.support(ws, &f.0, t) } else { 0.0 })
            .collect();
        let ests: Vec<&MotionEstimate> = fits.iter().map(|f| &f.0).collect();
        let hidden = self.occluded(ws, fine, &ests, &usable, t);
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
    /// [`Settings::margin`](super::Settings::margin) within the first frame's window; a region
    /// that fills that box has none. Only `usable` fits take part; `t` is the threshold on |DFD|
    /// (grey levels).
    fn occluded(
        &self,
        ws: &mut Workspace,
        fine: &FullRes<'_>,
        fits: &[&MotionEstimate],
        usable: &[bool],
        t: f64,
    ) -> Vec<Vec<(f64, f64)>> {
        let mut out = vec![vec![(0.0, 0.0); fits.len()]; fits.len()];
        let (l0, bbox, margin) = (fine.l0, fine.bbox, self.settings.margin);
        let cbox = PixelBox {
            i0: bbox.i0.saturating_sub(margin).max(l0.x0),
            j0: bbox.j0.saturating_sub(margin).max(l0.y0),
            i1: (bbox.i1 + margin).min(l0.x0 + l0.width - 1),
            j1: (bbox.j1 + margin).min(l0.y0 + l0.height - 1),
        };
        if cbox.i0 > cbox.i1 || cbox.j0 > cbox.j1 || usable.iter().filter(|&&u| u).count() < 2 {
            return out;
        }
        let test = RowTest::new(fine.region);
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
            .map(|(f, &u)| u.then(|| fine.labels(ws, cbox, f, t)))
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

/// The two frames' full-resolution levels and the region, where the re-start's fits are
/// compared.
struct FullRes<'a> {
    l0: &'a Level,
    l1: &'a Level,
    region: &'a Region<'a>,
    bbox: PixelBox,
}

impl FullRes<'_> {
    /// The weight of the region's pixels whose DFD under `est` is within `t` grey levels and
    /// whose sample stays in the image.
    fn support(&self, ws: &mut Workspace, est: &MotionEstimate, t: f64) -> f64 {
        ws.collect(self.l0, 0, self.region, self.bbox);
        self.evaluate(ws, est);
        ws.res
            .iter()
            .zip(&ws.valid)
            .zip(&ws.m)
            .filter(|((r, v), _)| **v != 0 && f64::from(r.abs()) < t)
            .map(|(_, m)| f64::from(*m))
            .sum()
    }

    /// What `est` does at each pixel of `cbox`: explains it (|DFD| < `t`), fails, or sends it
    /// outside the second frame's window (or the pixel is outside the first's).
    fn labels(
        &self,
        ws: &mut Workspace,
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
        ws.collect(self.l0, 0, &rect, cbox);
        self.evaluate(ws, est);
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

    /// The residuals of the listed pixels under `est`.
    fn evaluate(&self, ws: &mut Workspace, est: &MotionEstimate) {
        let mut theta = [0.0; 7];
        let n = est.params.len().min(7);
        theta[..n].copy_from_slice(&est.params[..n]);
        ws.evaluate(self.l0, self.l1, est.spec, &theta, est.origin, true);
    }
}

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
