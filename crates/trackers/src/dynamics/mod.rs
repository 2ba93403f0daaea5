//! The transition prior p(c_k | c_{k−1}): second-order auto-regressive kinematics (Odobez Eq. 17;
//! Wu's "constant acceleration" model) and the hidden switching processes of Wu et al.
//!
//! Kinematics, per used component j of the shape space:
//! x_{k,j} = x_{k−1,j} + ρ (x_{k−1,j} − x_{k−2,j}) + σ_j ε, with ε standard Gaussian or standard
//! Cauchy (Odobez's ρ_c(x, σ²) = σ / π(x² + σ²)). ρ = 1 is Odobez Eq. 17 exactly
//! (2α_k − α_{k−1}); it is the second-order model that Blake & Isard's shape-space trackers (and Wu)
//! call "constant acceleration": the acceleration is white noise.
//!
//! The noise scale of the size components is relative (σ_s · s), so that Odobez's Table 1 pairs
//! (σ_T, σ_s) = (2 px, 0.01) keep their meaning whatever the target's size: Odobez's reference
//! region has s ≈ 1, ours is the unit circle, so s is in pixels.

use dbn_switch::{ClutterHmm, OcclusionProcess, OcclusionState, StatusHmm, StatusState};
use rand::Rng;

use crate::dynamics::reacquisition::{JumpDensity, Reacquisition, log_mixture_density};
use crate::particle::Particle;
use crate::space::{Components, ShapeBounds, ShapeSpace, StateVector};
pub mod reacquisition;
mod settings;
pub use settings::{DynamicsSettings, NoiseKind};

/// How the clutter density λ of a particle evolves.
#[derive(Debug, Clone)]
pub enum ClutterProcess {
    /// One fixed λ (edges per pixel) for every particle: Wu's single-model tracker.
    Fixed(f64),
    /// β switching with λ | β fixed or Gaussian (Wu §4, Fig. 5–6).
    Switching(ClutterHmm),
}

/// How the occlusion γ (and status α) of a particle evolves.
#[derive(Debug, Clone)]
pub enum OcclusionModel {
    /// No occlusion: γ = 0.
    None,
    /// Gaussian random walk with boundary mass (Wu Eq. 13).
    RandomWalk(OcclusionProcess),
    /// The status HMM {α, γ} (Wu §5, Fig. 9).
    Status(StatusHmm),
}

/// The full transition prior of a tracker's particles.
#[derive(Debug, Clone)]
pub struct TrackerDynamics {
    /// Shape space of the kinematic state.
    pub space: ShapeSpace,
    /// Kinematic settings.
    pub settings: DynamicsSettings,
    /// Clutter process.
    pub clutter: ClutterProcess,
    /// Occlusion process.
    pub occlusion: OcclusionModel,
    /// The domain of the states, set from the initial contour by the tracker.
    pub bounds: ShapeBounds,
    /// The jump component of the current frame, set by the tracker while the track is not
    /// locked, and while it is with an abrupt-motion share (see
    /// [`crate::dynamics::reacquisition`]); `None`: the plain prior.
    pub reacquisition: Option<Reacquisition>,
    /// The mean shape of [`DynamicsSettings::shape_reversion`], set by the tracker each frame
    /// (the shape remembered over the locked estimates); `None`: no pull.
    pub shape_anchor: Option<StateVector>,
}

impl TrackerDynamics {
    /// η, the probability that a particle jumps to the reacquisition component this frame (0
    /// without one).
    pub fn jump_share(&self) -> f64 {
        self.reacquisition.as_ref().map_or(0.0, |r| r.share)
    }

    /// Draws whether a particle jumps this frame; draws nothing when it cannot, so that without a
    /// reacquisition component the random streams are those of the plain prior.
    pub fn draws_jump<R: Rng + ?Sized>(&self, rng: &mut R) -> bool {
        let eta = self.jump_share();
        eta > 0.0 && rng.random::<f64>() < eta
    }

    /// A jump of `previous`: the kinematic pair from the reacquisition component (for a jump
    /// that moves the centre only, the state `continuation` draws, as the proposal would draw a
    /// continuation, with its centre moved), the clutter from its transition and the status from
    /// the transition of a locked target (a target that reappears is seen whole, whatever the
    /// ancestor believed).
    pub fn sample_jump<R: Rng + ?Sized>(
        &self,
        previous: &Particle,
        rng: &mut R,
        continuation: impl FnOnce(&mut R) -> StateVector,
    ) -> Particle {
        let mut next = *previous;
        if let Some(r) = &self.reacquisition {
            if r.moves_centre_only() {
                next.now = continuation(rng);
                next.prev = previous.now;
                r.sample_centre(self.space, &mut next.now, &mut next.prev, rng);
            } else {
                let (now, prev) = r.sample(self.space, rng);
                next.now = now;
                next.prev = prev;
            }
            self.space.clamp(&mut next.now, &self.bounds);
        }
        let locked = Particle {
            status: match &self.occlusion {
                OcclusionModel::RandomWalk(walk) => StatusState {
                    gamma: walk.initial().gamma,
                    ..previous.status
                },
                _ => StatusState {
                    alpha: dbn_switch::TrackStatus::Locked,
                    gamma: 0.0,
                },
            },
            ..*previous
        };
        self.sample_hidden(&locked, &mut next, rng);
        next
    }

    /// The density of `next` under the mixture of the jump (share η, its `density`) and the
    /// continuation whose log-density over `Components` `log_continue` computes (see
    /// [`crate::dynamics::reacquisition::log_mixture_density`]).
    pub fn log_with_jump(
        &self,
        previous: &Particle,
        next: &Particle,
        density: JumpDensity,
        log_continue: impl Fn(Components) -> f64,
    ) -> f64 {
        log_mixture_density(
            self.reacquisition.as_ref(),
            self.space,
            self.jump_share(),
            Reacquisition::is_jump(&previous.now, &next.prev),
            &next.now,
            density,
            || log_continue(Components::All),
            || log_continue(Components::SizeAndShape),
        )
    }

    /// Whether the jump's prior differs from the density it is drawn from (a centre uniform over
    /// the search window, drawn around the detection), so that the prior as the proposal must
    /// weigh its particles by their ratio.
    pub fn jump_needs_weighting(&self) -> bool {
        self.reacquisition
            .as_ref()
            .is_some_and(|r| r.share > 0.0 && r.uniform_area.is_some())
    }

    /// The density the prior draws `next` from: [`smc_core::Dynamics::log_density`] with the
    /// jump's proposal in place of its prior.
    pub fn log_sampling_density(&self, previous: &Particle, next: &Particle) -> f64 {
        self.log_with_jump(previous, next, JumpDensity::Sampling, |which| {
            self.log_kinematic_density_over(previous, next, which)
        })
    }

    /// Draws the hidden variables of the next step from their transitions (Wu Fig. 6 steps 2b–2c
    /// and Eq. 13). Every proposal of this crate draws them this way, so their prior and proposal
    /// densities cancel in the weight (Odobez Eq. 3) and are never evaluated.
    pub fn sample_hidden<R: Rng + ?Sized>(
        &self,
        previous: &Particle,
        next: &mut Particle,
        rng: &mut R,
    ) {
        next.clutter = match &self.clutter {
            ClutterProcess::Fixed(lambda) => dbn_switch::ClutterState {
                beta: previous.clutter.beta,
                lambda: *lambda,
            },
            ClutterProcess::Switching(hmm) => {
                hmm.sample_next_exploring(&previous.clutter, self.settings.hidden_exploration, rng)
            }
        };
        next.status = match &self.occlusion {
            OcclusionModel::None => previous.status,
            OcclusionModel::RandomWalk(walk) => StatusState {
                alpha: previous.status.alpha,
                gamma: walk
                    .sample_next(
                        &OcclusionState {
                            gamma: previous.status.gamma,
                        },
                        rng,
                    )
                    .gamma,
            },
            OcclusionModel::Status(hmm) => self.locked_gamma(
                hmm,
                hmm.sample_next_exploring(&previous.status, self.settings.hidden_exploration, rng),
            ),
        };
    }

    /// ln p − ln q of the hidden chains of `next` (β, and α of the status HMM) drawn by
    /// [`TrackerDynamics::sample_hidden`] with [`DynamicsSettings::hidden_exploration`]: the
    /// importance ratio every proposal adds to the weight; exactly 0 when ε = 0. A jump
    /// ([`TrackerDynamics::sample_jump`]) draws α from a locked target, and so is weighted.
    pub fn log_hidden_exploration_ratio(&self, previous: &Particle, next: &Particle) -> f64 {
        let eps = self.settings.hidden_exploration;
        if eps <= 0.0 {
            return 0.0;
        }
        let clutter = match &self.clutter {
            ClutterProcess::Fixed(_) => 0.0,
            ClutterProcess::Switching(hmm) => {
                hmm.chain()
                    .log_exploration_ratio(previous.clutter.beta, next.clutter.beta, eps)
            }
        };
        let status = match &self.occlusion {
            OcclusionModel::Status(hmm) => {
                let from = if Reacquisition::is_jump(&previous.now, &next.prev) {
                    dbn_switch::TrackStatus::Locked
                } else {
                    previous.status.alpha
                };
                hmm.chain()
                    .log_exploration_ratio(from.index(), next.status.alpha.index(), eps)
            }
            _ => 0.0,
        };
        clutter + status
    }

    /// Reshapes a γ drawn uniformly on the locked range into the truncated exponential of
    /// [`DynamicsSettings::locked_gamma_rate`] (unchanged for the other statuses or κ = 0).
    pub fn locked_gamma(&self, hmm: &StatusHmm, state: StatusState) -> StatusState {
        let kappa = self.settings.locked_gamma_rate;
        if kappa <= 0.0 || state.alpha != dbn_switch::TrackStatus::Locked {
            return state;
        }
        let r = hmm.range(dbn_switch::TrackStatus::Locked);
        let width = r.high - r.low;
        if width <= 0.0 {
            return state;
        }
        let u = ((state.gamma - r.low) / width).clamp(0.0, 1.0);
        let gamma = r.low - (-u * (-(-kappa * width).exp_m1())).ln_1p() / kappa;
        StatusState {
            gamma: gamma.clamp(r.low, r.high),
            ..state
        }
    }

    /// ln p(next | previous) of a whole particle under the prior, whatever proposal drew it: the
    /// kinematic density ([`TrackerDynamics::log_kinematic_density`]) plus the hidden variables'
    /// transitions ([`TrackerDynamics::log_hidden_density`]). This is the transition density of
    /// the smoothers (see [`crate::smoothing`]); the reacquisition jump is not part of it.
    pub fn log_transition(&self, previous: &Particle, next: &Particle) -> f64 {
        self.log_kinematic_density(previous, next) + self.log_hidden_density(previous, next)
    }

    /// ln p of the hidden variables of `next` given `previous`: the {β, λ} HMM (Wu Fig. 5), the
    /// γ random walk (Wu Eq. 13) or the status HMM {α, γ} (Wu §6.3; γ | α uniform on its range,
    /// or the truncated exponential of [`DynamicsSettings::locked_gamma_rate`] when locked).
    /// Variables a tracker does not model contribute 0.
    pub fn log_hidden_density(&self, previous: &Particle, next: &Particle) -> f64 {
        let clutter = match &self.clutter {
            ClutterProcess::Fixed(_) => 0.0,
            ClutterProcess::Switching(hmm) => hmm.log_transition(&previous.clutter, &next.clutter),
        };
        let status = match &self.occlusion {
            OcclusionModel::None => 0.0,
            OcclusionModel::RandomWalk(walk) => walk.log_transition(
                &OcclusionState {
                    gamma: previous.status.gamma,
                },
                &OcclusionState {
                    gamma: next.status.gamma,
                },
            ),
            OcclusionModel::Status(hmm) => {
                let (alpha, gamma) = (next.status.alpha, next.status.gamma);
                let kappa = self.settings.locked_gamma_rate;
                let r = hmm.range(alpha);
                let width = r.high - r.low;
                let log_gamma = if alpha == dbn_switch::TrackStatus::Locked
                    && kappa > 0.0
                    && width > 0.0
                    && r.contains(gamma)
                {
                    kappa.ln() - kappa * (gamma - r.low) - (-(-kappa * width).exp_m1()).ln()
                } else {
                    hmm.log_gamma_density(alpha, gamma)
                };
                hmm.chain()
                    .log_transition(previous.status.alpha.index(), alpha.index())
                    + log_gamma
            }
        };
        clutter + status
    }

    /// The mean and the noise scales of p(x_k | x_{k−1}, x_{k−2}).
    fn kinematic_law(&self, previous: &Particle) -> (StateVector, StateVector) {
        let mean = self.settings.predict(
            self.space,
            &previous.now,
            &previous.prev,
            self.shape_anchor.as_ref(),
        );
        (mean, self.settings.sigmas(self.space, &previous.now))
    }

    /// Draws the kinematic part x_k ~ p(x_k | x_{k−1}, x_{k−2}).
    pub fn sample_kinematics<R: Rng + ?Sized>(
        &self,
        previous: &Particle,
        rng: &mut R,
    ) -> StateVector {
        let (mut x, sigma) = self.kinematic_law(previous);
        for j in 0..self.space.dim() {
            x[j] += sigma[j] * self.settings.noise.sample(rng);
        }
        self.space.clamp(&mut x, &self.bounds);
        x
    }

    /// log p(x_k | x_{k−1}, x_{k−2}) of the kinematic part (Odobez Eq. 17 for Cauchy noise).
    pub fn log_kinematic_density(&self, previous: &Particle, next: &Particle) -> f64 {
        self.log_kinematic_density_over(previous, next, Components::All)
    }

    /// [`TrackerDynamics::log_kinematic_density`] over `which` components: the marginal, the
    /// components being independent.
    pub fn log_kinematic_density_over(
        &self,
        previous: &Particle,
        next: &Particle,
        which: Components,
    ) -> f64 {
        let (mean, sigma) = self.kinematic_law(previous);
        (0..self.space.dim())
            .filter(|&j| which.includes(self.space, j))
            .map(|j| {
                self.settings
                    .noise
                    .log_density(next.now[j] - mean[j], sigma[j])
            })
            .sum()
    }
}

impl smc_core::Dynamics for TrackerDynamics {
    type State = Particle;

    fn sample<R: Rng + ?Sized>(&self, previous: &Particle, rng: &mut R) -> Particle {
        if self.draws_jump(rng) {
            return self.sample_jump(previous, rng, |rng| self.sample_kinematics(previous, rng));
        }
        let mut next = *previous;
        next.prev = previous.now;
        next.now = self.sample_kinematics(previous, rng);
        self.sample_hidden(previous, &mut next, rng);
        next
    }

    /// The kinematic density only: the hidden variables are drawn from their own transitions by
    /// every proposal, so their densities cancel (see [`TrackerDynamics::sample_hidden`]); with a
    /// reacquisition component, the mixture density of the particle's component.
    fn log_density(&self, previous: &Particle, next: &Particle) -> f64 {
        self.log_with_jump(previous, next, JumpDensity::Prior, |which| {
            self.log_kinematic_density_over(previous, next, which)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particle::default_status;
    use rand::SeedableRng;
    use rand_pcg::Pcg64Mcg;

    #[test]
    fn locked_gamma_follows_the_truncated_exponential() {
        let hmm = StatusHmm::new(&dbn_switch::StatusConfig::default()).unwrap();
        let mut d = dynamics(NoiseKind::Gaussian);
        let locked = |gamma| StatusState {
            alpha: dbn_switch::TrackStatus::Locked,
            gamma,
        };
        // κ = 0: unchanged.
        assert_eq!(d.locked_gamma(&hmm, locked(0.13)).gamma, 0.13);
        d.settings.locked_gamma_rate = 10.0;
        // Uniform draws on [0, 0.2] map to the truncated exponential: ends fixed, mean
        // 1/κ − w e^{−κw}/(1 − e^{−κw}) ≈ 0.0687, other statuses untouched.
        assert!(d.locked_gamma(&hmm, locked(0.0)).gamma.abs() < 1e-12);
        assert!((d.locked_gamma(&hmm, locked(0.2)).gamma - 0.2).abs() < 1e-12);
        let n = 10_000;
        let mean = (0..n)
            .map(|i| {
                d.locked_gamma(&hmm, locked(0.2 * (i as f64 + 0.5) / n as f64))
                    .gamma
            })
            .sum::<f64>()
            / n as f64;
        let w: f64 = 0.2;
        let expected = 0.1 - w * (-10.0 * w).exp() / (1.0 - (-10.0 * w).exp());
        assert!((mean - expected).abs() < 1e-3, "{mean} vs {expected}");
        let partial = StatusState {
            alpha: dbn_switch::TrackStatus::PartiallyOccluded,
            gamma: 0.5,
        };
        assert_eq!(d.locked_gamma(&hmm, partial).gamma, 0.5);
        d.settings.locked_gamma_rate = -1.0;
        assert!(d.settings.validate().is_err());
    }

    fn dynamics(noise: NoiseKind) -> TrackerDynamics {
        TrackerDynamics {
            space: ShapeSpace::Odobez,
            settings: DynamicsSettings {
                noise,
                ..DynamicsSettings::default()
            },
            clutter: ClutterProcess::Fixed(0.05),
            occlusion: OcclusionModel::None,
            bounds: ShapeBounds::loose(2.0),
            reacquisition: None,
            shape_anchor: None,
        }
    }

    #[test]
    fn shape_reversion_pulls_size_and_shape_but_not_translation() {
        let mut settings = DynamicsSettings {
            shape_velocity_retention: 0.5,
            ..DynamicsSettings::default()
        };
        let now = [100.0, 50.0, 20.0, 1.2, 0.0, 0.0];
        let prev = [98.0, 51.0, 21.0, 1.2, 0.0, 0.0];
        let anchor = [0.0, 0.0, 30.0, 1.0, 0.0, 0.0];
        let plain = settings.predict(ShapeSpace::Odobez, &now, &prev, None);
        // r = 0 (the default) ignores the anchor.
        assert_eq!(
            settings.predict(ShapeSpace::Odobez, &now, &prev, Some(&anchor)),
            plain
        );
        assert_eq!(plain, [102.0, 49.0, 19.5, 1.2, 0.0, 0.0]);
        settings.shape_reversion = 0.1;
        let pulled = settings.predict(ShapeSpace::Odobez, &now, &prev, Some(&anchor));
        // Translation keeps Eq. 17; s and e move by r (x̄ − x) towards the anchor.
        assert_eq!(pulled[..2], plain[..2]);
        assert!((pulled[2] - (19.5 + 0.1 * (30.0 - 20.0))).abs() < 1e-12);
        assert!((pulled[3] - (1.2 + 0.1 * (1.0 - 1.2))).abs() < 1e-12);
        settings.shape_reversion = 1.5;
        assert!(settings.validate().is_err());
        settings.shape_reversion = f64::NAN;
        assert!(settings.validate().is_err());
    }

    #[test]
    fn densities_integrate_to_one() {
        // Trapezoid rule over ±2000σ; the Cauchy tail beyond holds 2/(π·2000) ≈ 3e-4 of the mass.
        for (kind, tol) in [(NoiseKind::Gaussian, 1e-9), (NoiseKind::Cauchy, 5e-4)] {
            let sigma = 1.7;
            let h = 0.01;
            let mut total = 0.0;
            let mut x = -2000.0 * sigma;
            while x < 2000.0 * sigma {
                total += h * kind.log_density(x, sigma).exp();
                x += h;
            }
            assert!((total - 1.0).abs() < tol, "{kind:?}: {total}");
        }
    }

    #[test]
    fn gaussian_kinematics_have_the_ar2_mean_and_stated_spread() {
        let d = dynamics(NoiseKind::Gaussian);
        let p = Particle {
            now: [100.0, 50.0, 20.0, 1.0, 0.0, 0.0],
            prev: [98.0, 51.0, 20.0, 1.0, 0.0, 0.0],
            ..Particle::at_rest(
                [0.0; 6],
                dbn_switch::ClutterState {
                    beta: 0,
                    lambda: 0.05,
                },
                default_status(),
            )
        };
        let mut rng = Pcg64Mcg::seed_from_u64(7);
        let n = 20_000;
        let (mut m, mut v) = (0.0, 0.0);
        for _ in 0..n {
            let x = d.sample_kinematics(&p, &mut rng);
            m += x[0];
            v += (x[0] - 102.0).powi(2);
        }
        m /= n as f64;
        v /= n as f64;
        // Standard error of the mean: 3/√20000 ≈ 0.021; 5 standard errors.
        assert!((m - 102.0).abs() < 0.11, "mean {m}");
        // Relative standard error of a variance estimate: √(2/n) = 1%; 5 standard errors.
        assert!((v / 9.0 - 1.0).abs() < 0.05, "variance {v}");
    }

    #[test]
    fn cauchy_median_absolute_deviation_is_sigma() {
        let kind = NoiseKind::Cauchy;
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        let mut xs: Vec<f64> = (0..20_001).map(|_| kind.sample(&mut rng).abs()).collect();
        xs.sort_by(f64::total_cmp);
        // The median of |X| for a standard Cauchy is 1; its standard error here is ≈ 0.011.
        assert!((xs[10_000] - 1.0).abs() < 0.05, "{}", xs[10_000]);
    }
}
