//! Offline smoothing of a recorded run: every frame's estimate given the whole sequence.
//!
//! A filter decides at frame t from frames 0..=t; on recorded video the frames after t are
//! available too. With [`smc_core::FilterSettings::history`] set, a [`crate::ParticleTracker`]
//! records its weighted particles; [`Tracker::smoothed`](crate::Tracker::smoothed) then reweights
//! them by forward filtering–backward smoothing ([`smc_core::smooth`], Eq. S1–S2 there) and
//! summarises each frame exactly as the filter does (pose, β̂ and its class probabilities, λ̂,
//! γ̂, α̂ and its probabilities).
//!
//! The transition density is the tracker's prior ([`PriorTransition`]), evaluated for any pair
//! of particles whatever proposal drew them:
//! - the kinematics: the AR2 prediction from the earlier particle's current and previous states,
//!   with its Gaussian or Cauchy noise, as the density of the later particle's current state. The
//!   later particle's own previous state (a copy of its ancestor's) is left out: with it the
//!   second-order transition is a point mass and only a particle's own ancestor could precede it,
//!   which is no smoothing at all;
//! - the hidden processes: the {β, λ} HMM, the γ random walk, or the status HMM {α, γ}.
//!
//! The reacquisition jump and the shape anchor, which depend on the run's state at each frame,
//! are not part of the density.
//!
//! The pose comes from that joint smoother; the hidden processes do not. Their prior does not
//! depend on the pose, so each is a Markov chain whose filtered marginals the tracker already
//! has (β's class probabilities, α's status probabilities, γ's histogram over
//! [`GAMMA_BINS`] bins of [0, 1] for the random walk), and the exact backward recursion of
//! [`dbn_switch::MarkovChain::smooth_filtered`] smooths them ([`smooth_hidden`]). Through the
//! joint kernel instead, the peaked kinematic density decides which particles carry weight
//! (smoothed ESS of 1–5 on the `occlusion` scene), and the hidden variables are whatever those
//! few near-ancestral lines happen to carry (docs/RESULTS.md).

use dbn_switch::{ClutterEstimate, MarkovChain, OcclusionState, Status, StatusEstimate, argmax};
use smc_core::{History, TransitionDensity};

use crate::Result;
use crate::dynamics::{ClutterProcess, OcclusionModel, TrackerDynamics};
use crate::particle::Particle;

/// Bins of γ ∈ [0, 1] for smoothing the random walk of Wu Eq. 13 as a finite chain.
pub const GAMMA_BINS: usize = 20;

/// The smoothed hidden processes of one frame (each `None` when the tracker does not model it).
#[derive(Debug, Clone, PartialEq)]
pub struct SmoothedHidden {
    /// β̂, its class probabilities and λ̂ = Σ_k P(β = k) E[λ | β = k] (the filtered conditional
    /// means).
    pub clutter: Option<ClutterEstimate>,
    /// γ̂ = Σ_s P(s) E[γ | s] over the statuses or the γ bins.
    pub gamma: Option<f64>,
    /// α̂ and its probabilities (the status HMM only).
    pub status: Option<StatusEstimate>,
}

/// Per frame, the weight of each class of a discrete label and the weighted sum of a value
/// within each class.
fn class_sums<'a>(
    particles: impl Iterator<Item = (&'a Particle, f64)>,
    classes: usize,
    class_of: impl Fn(&Particle) -> usize,
    value: impl Fn(&Particle) -> f64,
) -> (Vec<f64>, Vec<f64>) {
    let (mut mass, mut sums) = (vec![0.0; classes], vec![0.0; classes]);
    for (p, w) in particles {
        let k = class_of(p).min(classes - 1);
        mass[k] += w;
        sums[k] += w * value(p);
    }
    (mass, sums)
}

/// Smooths the hidden processes of every frame of `history` (see the module docs).
///
/// # Errors
/// A filtered marginal the chain cannot have produced.
pub fn smooth_hidden(
    dynamics: &TrackerDynamics,
    history: &History<Particle>,
) -> Result<Vec<SmoothedHidden>> {
    let frames: Vec<_> = history.frames().collect();
    let weighted = |t: usize| {
        let set = &frames[t].set;
        set.states().iter().zip(set.weights().iter().copied())
    };
    let conditional_mean = |mass: &[f64], sums: &[f64], k: usize, fallback: f64| {
        if mass[k] > 0.0 {
            sums[k] / mass[k]
        } else {
            fallback
        }
    };
    let mut out = vec![
        SmoothedHidden {
            clutter: None,
            gamma: None,
            status: None,
        };
        frames.len()
    ];
    if let ClutterProcess::Switching(hmm) = &dynamics.clutter {
        let n = hmm.n_classes();
        let sums: Vec<_> = (0..frames.len())
            .map(|t| class_sums(weighted(t), n, |p| p.clutter.beta, |p| p.clutter.lambda))
            .collect();
        let filtered: Vec<Vec<f64>> = sums.iter().map(|(m, _)| m.clone()).collect();
        let smoothed = hmm.chain().smooth_filtered(&filtered)?;
        for ((o, s), (mass, lambda)) in out.iter_mut().zip(&smoothed.marginals).zip(&sums) {
            let overall = lambda.iter().sum::<f64>() / mass.iter().sum::<f64>();
            o.clutter = Some(ClutterEstimate {
                beta_hat: argmax(s),
                beta_probs: s.clone(),
                lambda_hat: (0..n)
                    .map(|k| s[k] * conditional_mean(mass, lambda, k, overall))
                    .sum(),
            });
        }
    }
    match &dynamics.occlusion {
        OcclusionModel::None => {}
        OcclusionModel::Status(hmm) => {
            let sums: Vec<_> = (0..frames.len())
                .map(|t| {
                    class_sums(
                        weighted(t),
                        3,
                        |p| p.status.alpha.index(),
                        |p| p.status.gamma,
                    )
                })
                .collect();
            let filtered: Vec<Vec<f64>> = sums.iter().map(|(m, _)| m.clone()).collect();
            let smoothed = hmm.chain().smooth_filtered(&filtered)?;
            for ((o, s), (mass, gamma)) in out.iter_mut().zip(&smoothed.marginals).zip(&sums) {
                let mut gamma_hat = 0.0;
                for (k, status) in Status::ALL.into_iter().enumerate() {
                    let r = hmm.range(status);
                    gamma_hat += s[k] * conditional_mean(mass, gamma, k, 0.5 * (r.low + r.high));
                }
                o.gamma = Some(gamma_hat);
                o.status = Some(StatusEstimate {
                    alpha_hat: Status::from_index(argmax(s)).unwrap_or(Status::Locked),
                    alpha_probs: [s[0], s[1], s[2]],
                    gamma_hat,
                });
            }
        }
        OcclusionModel::RandomWalk(walk) => {
            let k = GAMMA_BINS;
            let edge = |j: usize| j as f64 / k as f64;
            let centre = |j: usize| (j as f64 + 0.5) / k as f64;
            let rows: Vec<Vec<f64>> = (0..k)
                .map(|i| {
                    let from = OcclusionState { gamma: centre(i) };
                    let cdf = |j: usize| match j {
                        0 => 0.0,
                        j if j >= k => 1.0,
                        j => walk.transition_cdf(&from, edge(j)),
                    };
                    (0..k).map(|j| cdf(j + 1) - cdf(j)).collect()
                })
                .collect();
            let chain = MarkovChain::new(&rows)?;
            let bin =
                |p: &Particle| ((p.status.gamma.clamp(0.0, 1.0) * k as f64) as usize).min(k - 1);
            let sums: Vec<_> = (0..frames.len())
                .map(|t| class_sums(weighted(t), k, bin, |p| p.status.gamma))
                .collect();
            let filtered: Vec<Vec<f64>> = sums.iter().map(|(m, _)| m.clone()).collect();
            let smoothed = chain.smooth_filtered(&filtered)?;
            for ((o, s), (mass, gamma)) in out.iter_mut().zip(&smoothed.marginals).zip(&sums) {
                o.gamma = Some(
                    (0..k)
                        .map(|j| s[j] * conditional_mean(mass, gamma, j, centre(j)))
                        .sum(),
                );
            }
        }
    }
    Ok(out)
}

/// A tracker's prior as the smoothers' transition density (see the module docs).
#[derive(Debug, Clone)]
pub struct PriorTransition {
    dynamics: TrackerDynamics,
}

impl PriorTransition {
    /// The prior of `dynamics`, without the run-time reacquisition jump and shape anchor.
    pub fn new(dynamics: &TrackerDynamics) -> Self {
        let mut dynamics = dynamics.clone();
        dynamics.reacquisition = None;
        dynamics.shape_anchor = None;
        Self { dynamics }
    }
}

impl TransitionDensity for PriorTransition {
    type State = Particle;

    fn log_density(&self, _frame: usize, previous: &Particle, next: &Particle) -> f64 {
        self.dynamics.log_transition(previous, next)
    }
}
