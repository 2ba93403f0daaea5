//! Whether the paper trackers see a target at all: a check beyond both papers on the
//! self-evaluation α̂ of Wu §6.3.
//!
//! Wu's status α is inferred from the occlusion degree γ, the share of measurement lines whose
//! contour edge is hidden. In dense clutter (image noise, a checkerboard) every line finds an
//! edge near any contour, γ stays low, and α̂ would say "locked" on a frame with no target in it.
//! A target is seen when the observation singles out the estimate's place: the log-likelihood of
//! the most probable particle, as if fully visible, is compared with the same contour moved
//! [`SHIFT_RADII`] radii in [`SHIFTS`] directions, as a z-score
//!
//!   z = (ℓ(x̂) − mean_k ℓ(x̂ + d_k)) / sd_k ℓ(x̂ + d_k).
//!
//! A filter that climbs a featureless likelihood still finds a local maximum, so noise gives z
//! of one or two; a contour on a real target's edges stands out by several. z drives a two-state
//! (seen, unseen) chain, the same forward filter as the region tracker's
//! ([`crate::region::status::LostChain`]); the reported α probabilities are Wu's given that the
//! target is seen, and P(unseen) is added to "lost". The check only reports: the filter, its
//! hidden processes and the reacquisition memory are the papers' as before.

use dbn_switch::{Status, StatusEstimate};
use smc_core::{Observation, ParticleSet};

use crate::particle::{Particle, default_status};
use crate::region::status::LostChain;
use crate::space::ShapeSpace;

/// Directions the estimate's contour is moved to for the null placements.
pub const SHIFTS: usize = 16;
/// Distance of the null placements, in radii of the contour.
pub const SHIFT_RADII: f64 = 1.5;
/// z of an unseen target (a filter's local maximum on a featureless likelihood) and of a seen
/// one; the chain reads q = (z − Z_UNSEEN) / (Z_SEEN − Z_UNSEEN), about 0 and 1.
const Z_UNSEEN: f64 = 1.5;
const Z_SEEN: f64 = 4.0;
/// Bounds of q: one frame cannot outvote the chain's memory.
const Q_RANGE: (f64, f64) = (-1.0, 2.0);
/// Fewest null placements inside the frame for a z-score.
const MIN_PLACEMENTS: usize = 6;
/// Persistence of the seen/unseen chain.
const PERSISTENCE: f64 = 0.9;

/// The seen/unseen chain of one track.
#[derive(Debug, Clone, PartialEq)]
pub struct Visibility {
    chain: LostChain,
}

impl Default for Visibility {
    fn default() -> Self {
        Self {
            chain: LostChain::new(PERSISTENCE, 0.0),
        }
    }
}

impl Visibility {
    /// One forward step on the weighted set `set` under `observation`, for a frame of `size`;
    /// returns P(unseen). A frame without enough placements inside it leaves the chain to its
    /// prior.
    pub fn observe<O: Observation<State = Particle>>(
        &mut self,
        observation: &O,
        space: ShapeSpace,
        set: &ParticleSet<Particle>,
        size: (usize, usize),
    ) -> f64 {
        match saliency(observation, space, set, size) {
            Some(z) => {
                let q = ((z - Z_UNSEEN) / (Z_SEEN - Z_UNSEEN)).clamp(Q_RANGE.0, Q_RANGE.1);
                self.chain.observe(q);
            }
            // No observation: the prediction step alone (an uninformative q halfway).
            None => self.chain.observe(0.5),
        }
        self.chain.p_lost()
    }
}

/// Wu's status estimate given the target is seen, with P(`unseen`) moved to "lost".
pub fn fuse(status: &StatusEstimate, unseen: f64) -> StatusEstimate {
    let seen = 1.0 - unseen;
    let mut probs = status.alpha_probs.map(|p| p * seen);
    probs[Status::Lost.index()] += unseen;
    let best = (0..probs.len())
        .max_by(|&a, &b| probs[a].total_cmp(&probs[b]))
        .and_then(Status::from_index)
        .unwrap_or(Status::Lost);
    StatusEstimate {
        alpha_hat: best,
        alpha_probs: probs,
        gamma_hat: status.gamma_hat,
    }
}

/// The z-score of the most probable particle's log-likelihood against its contour moved to the
/// null placements inside the frame; `None` with too few placements or a non-finite spread.
pub fn saliency<O: Observation<State = Particle>>(
    observation: &O,
    space: ShapeSpace,
    set: &ParticleSet<Particle>,
    size: (usize, usize),
) -> Option<f64> {
    let best = set
        .weights()
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, _)| i)?;
    let mut particle = *set.states().get(best)?;
    particle.status = default_status();
    let at_estimate = observation.log_likelihood(&particle);
    let radius = space.scale(&particle.now);
    let slots: Vec<usize> = (0..particle.now.len())
        .filter(|&j| space.is_translation(j))
        .collect();
    let &[sx, sy] = slots.as_slice() else {
        return None;
    };
    let mut nulls = Vec::with_capacity(SHIFTS);
    for k in 0..SHIFTS {
        let t = std::f64::consts::TAU * k as f64 / SHIFTS as f64;
        let (dx, dy) = (
            SHIFT_RADII * radius * t.cos(),
            SHIFT_RADII * radius * t.sin(),
        );
        let mut moved = particle;
        for x in [&mut moved.now, &mut moved.prev] {
            x[sx] += dx;
            x[sy] += dy;
        }
        let [cx, cy] = space.centre(&moved.now);
        if (0.0..size.0 as f64).contains(&cx) && (0.0..size.1 as f64).contains(&cy) {
            let l = observation.log_likelihood(&moved);
            if l.is_finite() {
                nulls.push(l);
            }
        }
    }
    if nulls.len() < MIN_PLACEMENTS || !at_estimate.is_finite() {
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
            alpha_hat: Status::Locked,
            alpha_probs: [0.9, 0.08, 0.02],
            gamma_hat: 0.05,
        };
        let same = fuse(&status, 0.0);
        assert_eq!(same, status);
        let fused = fuse(&status, 0.8);
        assert_eq!(fused.alpha_hat, Status::Lost);
        assert!((fused.alpha_probs.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!((fused.alpha_probs[0] - 0.18).abs() < 1e-12);
    }
}
