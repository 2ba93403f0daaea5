//! Whether the paper trackers see a target at all: a check beyond both papers on the
//! self-evaluation α̂ of Wu §6.3.
//!
//! Wu's status α is inferred from the occlusion degree γ, the share of measurement lines whose
//! contour edge is hidden. In dense clutter (image noise, a checkerboard) every line finds an
//! edge near any contour, γ stays low, and α̂ would say "locked" on a frame with no target in it.
//! A target is seen when its contour stands out from the rest of the image: the mean grey-level
//! difference across the most probable particle's contour (one and a half pixels inside against
//! outside, along the normal) is compared with the same contour moved [`SHIFT_RADII`] radii in
//! [`SHIFTS`] directions, as a z-score
//!
//!   z = (c(x̂) − mean_k c(x̂ + d_k)) / sd_k c(x̂ + d_k).
//!
//! The contrast is read from the image, not from the preset's likelihood, so the test means the
//! same for every preset (a likelihood-based score was tried: Wu's likelihood on his own
//! `mclutter` scene scores a visible target no higher than noise). A filter that climbs a
//! featureless image still finds a local maximum, so noise and a checkerboard give z of about
//! −1 to 2; a contour on a real target's edges stands out by several. z drives a two-state
//! (seen, unseen) chain, the same forward filter as the appearance trackers' lock chain
//! ([`crate::monitor::lock::LockChain`]); the reported α probabilities are Wu's given that the
//! target is seen, and P(unseen) is added to "lost". The check only reports: the filter, its
//! hidden processes and the reacquisition memory are the papers' as before.

use dbn_switch::{StatusEstimate, TrackStatus};
use vision_core::Ellipse;

use crate::monitor::lock::LockChain;

/// Directions the estimate's contour is moved to for the null placements.
pub const SHIFTS: usize = 16;
/// Distance of the null placements, in radii of the contour.
pub const SHIFT_RADII: f64 = 1.5;
/// z of an unseen target (a filter's local maximum on a featureless image) and of a seen
/// one; the chain reads q = (z − Z_UNSEEN) / (Z_SEEN − Z_UNSEEN), about 0 and 1.
const Z_UNSEEN: f64 = 0.0;
const Z_SEEN: f64 = 2.5;
/// Bounds of q: one frame cannot outvote the chain's memory.
const Q_RANGE: (f64, f64) = (-1.0, 2.0);
/// Fewest null placements inside the frame for a z-score.
const MIN_PLACEMENTS: usize = 6;
/// Persistence of the seen/unseen chain.
const PERSISTENCE: f64 = 0.95;
/// Spread of q under either state, and its centres (seen, unseen): q is scaled so that the two
/// z's above map to 1 and 0, read as the appearance trackers' lock chain reads its q by default.
const SPREAD: f64 = 0.3;
const CENTRES: [f64; 2] = [1.0, 0.0];

/// The seen/unseen chain of one track.
#[derive(Debug, Clone, PartialEq)]
pub struct Visibility {
    chain: LockChain,
}

impl Visibility {
    /// A chain that starts seen.
    ///
    /// # Errors
    /// None in practice: the persistence is a valid constant.
    pub fn new() -> crate::Result<Self> {
        Ok(Self {
            chain: LockChain::new(PERSISTENCE, SPREAD, CENTRES)?,
        })
    }

    /// One forward step on the estimate `estimate` in the grey frame `grey` of `size`; returns
    /// P(unseen). A frame where the contour or too many null placements fall outside the frame
    /// leaves the chain as it was.
    pub fn observe(&mut self, grey: &[f32], size: (usize, usize), estimate: &Ellipse) -> f64 {
        // Where no test is possible (the contour or its null placements leave the frame) the
        // chain keeps its belief rather than drifting towards "unseen".
        if let Some(z) = edge_saliency(grey, size, estimate) {
            let q = ((z - Z_UNSEEN) / (Z_SEEN - Z_UNSEEN)).clamp(Q_RANGE.0, Q_RANGE.1);
            self.chain.observe(q);
        }
        self.chain.p_lost()
    }
}

/// Wu's status estimate given the target is seen, with P(`unseen`) moved to "lost".
pub fn fuse(status: &StatusEstimate, unseen: f64) -> StatusEstimate {
    let seen = 1.0 - unseen;
    let mut probs = status.alpha_probs.map(|p| p * seen);
    probs[TrackStatus::Lost.index()] += unseen;
    let best = (0..probs.len())
        .max_by(|&a, &b| probs[a].total_cmp(&probs[b]))
        .and_then(TrackStatus::from_index)
        .unwrap_or(TrackStatus::Lost);
    StatusEstimate {
        alpha_hat: best,
        alpha_probs: probs,
        gamma_hat: status.gamma_hat,
    }
}

/// Points read on a contour by [`edge_saliency`].
const CONTOUR_POINTS: usize = 48;

/// Mean absolute grey-level difference across the ellipse `e` (inside against outside, one and
/// a half pixels either side of the contour along its normal, nearest pixel) at
/// [`CONTOUR_POINTS`] points, and how many of them fell inside the frame.
fn contour_contrast(grey: &[f32], (w, h): (usize, usize), e: &Ellipse) -> (f64, usize) {
    e.contrast_across(CONTOUR_POINTS, 1.5, |x, y| {
        let (i, j) = (x.round(), y.round());
        (i >= 0.0 && j >= 0.0 && (i as usize) < w && (j as usize) < h)
            .then(|| f64::from(grey[j as usize * w + i as usize]))
    })
}

/// The z-score of the contrast across the estimate's contour against the same contour moved to
/// the null placements inside the frame.
pub fn edge_saliency(grey: &[f32], size: (usize, usize), e: &Ellipse) -> Option<f64> {
    let (at_estimate, n) = contour_contrast(grey, size, e);
    if n < CONTOUR_POINTS / 2 {
        return None;
    }
    let radius = (e.a * e.b).sqrt();
    let (mut placements, mut count) = ([0.0; SHIFTS], 0);
    for k in 0..SHIFTS {
        let t = std::f64::consts::TAU * k as f64 / SHIFTS as f64;
        let moved = Ellipse {
            cx: e.cx + SHIFT_RADII * radius * t.cos(),
            cy: e.cy + SHIFT_RADII * radius * t.sin(),
            ..*e
        };
        let (v, m) = contour_contrast(grey, size, &moved);
        if m == CONTOUR_POINTS {
            placements[count] = v;
            count += 1;
        }
    }
    let nulls = &placements[..count];
    if nulls.len() < MIN_PLACEMENTS {
        return None;
    }
    let n = nulls.len() as f64;
    let mean = nulls.iter().sum::<f64>() / n;
    let sd = (nulls.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / n).sqrt();
    (sd > 1e-9).then(|| (at_estimate - mean) / sd)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fusing_moves_the_unseen_mass_to_lost() {
        let status = StatusEstimate {
            alpha_hat: TrackStatus::Locked,
            alpha_probs: [0.9, 0.08, 0.02],
            gamma_hat: 0.05,
        };
        let same = fuse(&status, 0.0);
        assert_eq!(same, status);
        let fused = fuse(&status, 0.8);
        assert_eq!(fused.alpha_hat, TrackStatus::Lost);
        assert!((fused.alpha_probs.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!((fused.alpha_probs[0] - 0.18).abs() < 1e-12);
    }
}
