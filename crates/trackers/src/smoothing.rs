//! Offline smoothing of a recorded run: every frame's estimate given the whole sequence.
//!
//! A filter decides at frame t from frames 0..=t; on recorded video the frames after t are
//! available too. With [`smc_core::FilterSettings::history`] set, a [`crate::ParticleTracker`]
//! records its weighted particles; [`Tracker::smoothed`](crate::Tracker::smoothed) then reweights
//! them by forward filtering–backward smoothing ([`smc_core::smooth`], Eq. S1–S2 there) and
//! summarises each frame exactly as the filter does (pose, β̂ and its class probabilities, λ̂,
//! γ̂, α̂ and its probabilities).
//!
//! The transition density is the tracker's prior (`PriorTransition`), evaluated for any pair
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
//! [`dbn_switch::MarkovChain::smooth_filtered`] smooths them (`smooth_hidden`). Through the
//! joint kernel instead, the peaked kinematic density decides which particles carry weight
//! (smoothed ESS of 1–5 on the `occlusion` scene), and the hidden variables are whatever those
//! few near-ancestral lines happen to carry (docs/RESULTS.md).

use dbn_switch::{
    ClutterEstimate, ClutterHmm, MarkovChain, OcclusionProcess, OcclusionState, StatusEstimate,
    StatusHmm, TrackStatus, argmax,
};
use smc_core::{Frame, History, TransitionDensity};

use crate::Result;
use crate::dynamics::{ClutterProcess, OcclusionModel, TrackerDynamics};
use crate::particle::Particle;

/// What [`crate::Tracker::smoothed`] gives: the smoothed estimates and the run's switching
/// statistics.
#[derive(Debug, Clone, PartialEq)]
pub struct SmoothedRun {
    /// The smoothed estimate of every frame after the first, oldest first.
    pub estimates: Vec<crate::Estimate>,
    /// The expected statistics of the switching parameters (see [`SwitchingStatistics`]).
    pub statistics: SwitchingStatistics,
}

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

/// Per frame of `frames`, [`class_sums`] of its filtered particles.
fn frame_sums(
    frames: &[&Frame<Particle>],
    classes: usize,
    class_of: impl Fn(&Particle) -> usize + Copy,
    value: impl Fn(&Particle) -> f64 + Copy,
) -> Vec<(Vec<f64>, Vec<f64>)> {
    frames
        .iter()
        .map(|f| {
            let weighted = f.set.states().iter().zip(f.set.weights().iter().copied());
            class_sums(weighted, classes, class_of, value)
        })
        .collect()
}

/// The filtered class masses of [`frame_sums`], the input of `smooth_filtered`.
fn masses(sums: &[(Vec<f64>, Vec<f64>)]) -> Vec<Vec<f64>> {
    sums.iter().map(|(m, _)| m.clone()).collect()
}

/// E[value | class k] from a frame's class sums, `fallback` for a class without mass.
fn conditional_mean(mass: &[f64], sums: &[f64], k: usize, fallback: f64) -> f64 {
    if mass[k] > 0.0 {
        sums[k] / mass[k]
    } else {
        fallback
    }
}

/// Smooths the hidden processes of every frame of `history` (see the module docs), and gathers
/// the expected statistics that re-estimate their parameters ([`SwitchingStatistics`]).
///
/// # Errors
/// A filtered marginal the chain cannot have produced.
pub(crate) fn smooth_hidden(
    dynamics: &TrackerDynamics,
    history: &History<Particle>,
) -> Result<(Vec<SmoothedHidden>, SwitchingStatistics)> {
    let mut statistics = SwitchingStatistics::default();
    let frames: Vec<_> = history.frames().collect();
    let mut out = vec![
        SmoothedHidden {
            clutter: None,
            gamma: None,
            status: None,
        };
        frames.len()
    ];
    if let ClutterProcess::Switching(hmm) = &dynamics.clutter {
        smooth_clutter(hmm, &frames, &mut out, &mut statistics)?;
    }
    match &dynamics.occlusion {
        OcclusionModel::None => {}
        OcclusionModel::Status(hmm) => smooth_status(hmm, &frames, &mut out, &mut statistics)?,
        OcclusionModel::RandomWalk(walk) => {
            smooth_random_walk(walk, &frames, &mut out, &mut statistics)?;
        }
    }
    Ok((out, statistics))
}

/// β̂ and λ̂ of every frame from the smoothed {β, λ} HMM, with T_β's expected counts and the
/// λ sums of λ̄_k.
fn smooth_clutter(
    hmm: &ClutterHmm,
    frames: &[&Frame<Particle>],
    out: &mut [SmoothedHidden],
    statistics: &mut SwitchingStatistics,
) -> Result<()> {
    let n = hmm.n_classes();
    let sums = frame_sums(frames, n, |p| p.clutter.beta, |p| p.clutter.lambda);
    let smoothed = hmm.chain().smooth_filtered(&masses(&sums))?;
    let (mut occupancy, mut lambda_sums) = (vec![0.0; n], vec![0.0; n]);
    for ((o, s), (mass, lambda)) in out.iter_mut().zip(&smoothed.marginals).zip(&sums) {
        let overall = lambda.iter().sum::<f64>() / mass.iter().sum::<f64>();
        for k in 0..n {
            occupancy[k] += s[k];
            lambda_sums[k] += s[k] * conditional_mean(mass, lambda, k, overall);
        }
        o.clutter = Some(ClutterEstimate {
            beta_hat: argmax(s),
            beta_probs: s.clone(),
            lambda_hat: (0..n)
                .map(|k| s[k] * conditional_mean(mass, lambda, k, overall))
                .sum(),
        });
    }
    statistics.beta = Some(ChainCounts {
        transitions: smoothed.transitions,
        occupancy,
    });
    statistics.lambda_sums = Some(lambda_sums);
    Ok(())
}

/// α̂ and γ̂ of every frame from the smoothed status HMM {α, γ}, with T_α's expected counts.
fn smooth_status(
    hmm: &StatusHmm,
    frames: &[&Frame<Particle>],
    out: &mut [SmoothedHidden],
    statistics: &mut SwitchingStatistics,
) -> Result<()> {
    let sums = frame_sums(frames, 3, |p| p.status.alpha.index(), |p| p.status.gamma);
    let smoothed = hmm.chain().smooth_filtered(&masses(&sums))?;
    statistics.alpha = Some(ChainCounts::of(&smoothed));
    for ((o, s), (mass, gamma)) in out.iter_mut().zip(&smoothed.marginals).zip(&sums) {
        let mut gamma_hat = 0.0;
        for (k, status) in TrackStatus::ALL.into_iter().enumerate() {
            let r = hmm.range(status);
            gamma_hat += s[k] * conditional_mean(mass, gamma, k, 0.5 * (r.low + r.high));
        }
        o.gamma = Some(gamma_hat);
        o.status = Some(StatusEstimate {
            alpha_hat: TrackStatus::from_index(argmax(s)).unwrap_or(TrackStatus::Locked),
            alpha_probs: [s[0], s[1], s[2]],
            gamma_hat,
        });
    }
    Ok(())
}

/// γ̂ of every frame from the random walk smoothed as a [`GAMMA_BINS`]-bin chain, with the
/// expected squared steps of σ_γ.
fn smooth_random_walk(
    walk: &OcclusionProcess,
    frames: &[&Frame<Particle>],
    out: &mut [SmoothedHidden],
    statistics: &mut SwitchingStatistics,
) -> Result<()> {
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
    let bin = |p: &Particle| ((p.status.gamma.clamp(0.0, 1.0) * k as f64) as usize).min(k - 1);
    let sums = frame_sums(frames, k, bin, |p| p.status.gamma);
    let smoothed = chain.smooth_filtered(&masses(&sums))?;
    // E[(γ_{t+1} − γ_t)²] from the two-step marginals over the bins, less the variance that
    // binning adds (two uniform errors of a bin's width).
    let (mut squares, mut steps) = (0.0, 0.0);
    for (i, row) in smoothed.transitions.iter().enumerate() {
        for (j, x) in row.iter().enumerate() {
            squares += x * (centre(j) - centre(i)).powi(2);
            steps += x;
        }
    }
    let binning = 2.0 / (12.0 * (k * k) as f64);
    statistics.gamma_steps = Some(((squares - binning * steps).max(0.0), steps));
    for ((o, s), (mass, gamma)) in out.iter_mut().zip(&smoothed.marginals).zip(&sums) {
        o.gamma = Some(
            (0..k)
                .map(|j| s[j] * conditional_mean(mass, gamma, j, centre(j)))
                .sum(),
        );
    }
    Ok(())
}

/// Expected counts of one chain over a smoothed run.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainCounts {
    /// `transitions[i][j]`: Σ_t p(s_t = i, s_{t+1} = j | Z).
    pub transitions: Vec<Vec<f64>>,
    /// `occupancy[i]`: Σ_t p(s_t = i | Z).
    pub occupancy: Vec<f64>,
}

impl ChainCounts {
    fn of(smoothed: &dbn_switch::SmoothedChain) -> Self {
        let n = smoothed.transitions.len();
        let mut occupancy = vec![0.0; n];
        for m in &smoothed.marginals {
            for (o, v) in occupancy.iter_mut().zip(m) {
                *o += v;
            }
        }
        Self {
            transitions: smoothed.transitions.clone(),
            occupancy,
        }
    }

    fn add(&mut self, other: &Self) {
        for (a, b) in self.transitions.iter_mut().zip(&other.transitions) {
            for (x, y) in a.iter_mut().zip(b) {
                *x += y;
            }
        }
        for (x, y) in self.occupancy.iter_mut().zip(&other.occupancy) {
            *x += y;
        }
    }

    /// The maximum-likelihood transition matrix: each row of expected counts normalised; a
    /// row with no count keeps `fallback`'s row.
    pub fn transition_matrix(&self, fallback: &[Vec<f64>]) -> Vec<Vec<f64>> {
        self.transitions
            .iter()
            .zip(fallback)
            .map(|(row, old)| {
                let total: f64 = row.iter().sum();
                if total > 1e-9 {
                    row.iter().map(|x| x / total).collect()
                } else {
                    old.clone()
                }
            })
            .collect()
    }
}

/// The expected sufficient statistics of the switching parameters over one or more smoothed
/// runs: the E-step of expectation–maximisation (Baum–Welch on the particle approximation).
/// [`SwitchingStatistics::maximise`] is the M-step.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SwitchingStatistics {
    /// The clutter classes β (with the {β, λ} HMM).
    pub beta: Option<ChainCounts>,
    /// Σ_t p(β_t = k | Z) E[λ_t | β_t = k], for λ̄_k.
    pub lambda_sums: Option<Vec<f64>>,
    /// The statuses α (with the status HMM).
    pub alpha: Option<ChainCounts>,
    /// Σ E[(γ_{t+1} − γ_t)²] and the number of steps (with the γ random walk).
    pub gamma_steps: Option<(f64, f64)>,
}

impl SwitchingStatistics {
    /// Adds another run's statistics (of the same tracker).
    pub fn add(&mut self, other: &Self) {
        fn merge<T: Clone>(a: &mut Option<T>, b: &Option<T>, f: impl FnOnce(&mut T, &T)) {
            match (a.as_mut(), b) {
                (Some(x), Some(y)) => f(x, y),
                (None, Some(y)) => *a = Some(y.clone()),
                _ => {}
            }
        }
        merge(&mut self.beta, &other.beta, ChainCounts::add);
        merge(&mut self.alpha, &other.alpha, ChainCounts::add);
        merge(&mut self.lambda_sums, &other.lambda_sums, |x, y| {
            x.iter_mut().zip(y).for_each(|(a, b)| *a += b)
        });
        merge(&mut self.gamma_steps, &other.gamma_steps, |x, y| {
            x.0 += y.0;
            x.1 += y.1;
        });
    }

    /// The M-step: writes into `config` the transition matrices T_β and T_α, σ_γ of the γ random
    /// walk and, when `lambda` is set, the class means λ̄_k, each where the statistics have it.
    /// The result is validated.
    ///
    /// # Errors
    /// A configuration the new values make invalid.
    pub fn maximise(&self, config: &mut crate::TrackerConfig, lambda: bool) -> Result<()> {
        use crate::config::{ClutterMode, OcclusionMode};
        if let (ClutterMode::Switching(c), Some(beta)) = (&mut config.clutter, &self.beta) {
            c.transition = beta.transition_matrix(&c.transition);
            if let (true, Some(sums)) = (lambda, &self.lambda_sums) {
                for ((mean, s), occ) in c.lambda_mean.iter_mut().zip(sums).zip(&beta.occupancy) {
                    if *occ > 1e-9 {
                        *mean = s / occ;
                    }
                }
            }
        }
        match (&mut config.occlusion, &self.alpha, self.gamma_steps) {
            (OcclusionMode::Status(c), Some(alpha), _) => {
                c.transition = alpha.transition_matrix(&c.transition);
            }
            (OcclusionMode::RandomWalk(c), _, Some((squares, steps))) if steps > 0.0 => {
                c.sigma_gamma = (squares / steps).sqrt().max(1e-3);
            }
            _ => {}
        }
        config.validate()
    }
}

/// A tracker's prior as the smoothers' transition density (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct PriorTransition {
    dynamics: TrackerDynamics,
}

impl PriorTransition {
    /// The prior of `dynamics`, without the run-time reacquisition jump and shape anchor.
    pub(crate) fn new(dynamics: &TrackerDynamics) -> Self {
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
