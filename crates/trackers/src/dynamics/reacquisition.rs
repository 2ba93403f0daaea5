//! The jump component of the transition prior: reacquisition after an occlusion, drawn around
//! the constant-velocity extrapolation of the last confidently locked estimate (or the
//! appearance's detection), and, in `head`, a jump for abrupt motion while the track is locked.
//!
//! Beyond both papers, in the spirit of Isard & Blake's ICONDENSATION (a share of the particles
//! from a second importance function, the rest from the prior). While the track is locked the
//! component is absent and the filter is exactly the preset's (unless the abrupt-motion jump
//! below is configured, as `head` configures it). Once the reported estimate stops
//! being locked (γ̂ high, α̂ not locked, or a contour whose size or elongation departs from the
//! remembered one), every particle jumps with probability η = min(η_max, r · gap), `gap` the
//! number of unlocked frames so far, to
//!
//! c_k = (α_k, α_{k−1}) with α_k ~ N(m_k, diag σ_k²), α_{k−1} = α_k − v,
//!
//! m_k the last locked pose — as remembered a few locked frames before the last one
//! ([`ReacquisitionSettings::rollback`]), since a track in trouble lags before any test flags it —
//! extrapolated at the remembered velocity v, σ_k growing with the gap, and its hidden status
//! redrawn as if it had been locked. With reacquisition on, the tracker also keeps every centre in
//! the frame: a lost track that runs off the image, where Wu's occluded lines are the most
//! probable of all, would otherwise never be back where the target reappears. The component is part of the *model*
//! (a hidden target may reappear where its last motion would have carried it), so the prior and
//! every proposal carry the same η: with the bootstrap filter the weights stay the likelihood, and
//! with the motion proposal the weight is the prior over the proposal density of the component
//! the particle came from. The two components have disjoint supports in c_k — a jump sets
//! α_{k−1} = α_k − v, a continuation keeps α_{k−1} equal to the previous α_k — so the mixture
//! density of a particle is that of its own component, times its share.
//!
//! **Abrupt motion** ([`ReacquisitionSettings::detection_share`] η_d > 0, with an appearance
//! model). While the track is locked, every particle jumps with probability η_d to a centre that
//! is a priori uniform over the appearance's search window W (area |W|), at rest: the target may
//! have moved anywhere it is searched for. Its size and shape go on as a continuation carries
//! them, so a head that jumps while the camera zooms keeps zooming: the jump draws a
//! continuation (from the prior, or from the motion proposal) and moves its centre only. The
//! centre is drawn around the appearance's detection d, N(d, σ²), so the jump's prior density is
//! η_d p_shape / |W| and the density it is drawn from η_d q_shape N(centre; d, σ²), p_shape and
//! q_shape the prior's and the proposal's continuation densities of the size and shape
//! ([`log_mixture_density`]): its particles carry the continuation's own ratio for the shape,
//! times 1 / (|W| N(centre; d, σ²)) for the centre ([`Reacquisition::uniform_area`]), and the
//! prior itself becomes a weighted proposal ([`crate::proposal::WeightedPrior`]). A jump that
//! kept the last estimate's shape instead escaped the prior's penalty on a fast zoom, and held
//! the box at the old size (docs/DECISIONS.md). A detection wins the posterior only where its likelihood
//! beats the continuation's by that factor, so one that merely ties with the target — a patch of
//! background while the face turns — does not capture the track as readily as a share of the
//! *model* would. Once the track is not locked, the reacquisition jump above takes over, its
//! Gaussian the prior itself.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::space::{STATE_SLOTS, ShapeSpace, StateVector};
use crate::{Error, Result};

/// Settings of the reacquisition component.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReacquisitionSettings {
    /// The reported estimate is locked while γ̂ is below this (and α̂, if modelled, is locked).
    pub lock_gamma: f64,
    /// ... and while its scale and elongation are within this log-ratio of the remembered ones:
    /// a contour shrinking onto the visible part of a target that slides behind an occluder is
    /// not a confident lock, whatever γ̂ says (w-eval's α̂ stays "locked" on the sliver).
    /// `None` (the default, and `head`'s): no shape test, the status alone says whether the
    /// track is locked (the lock chain of the appearance terms reads the target's colour: a face
    /// that grows as it nears the camera is still held). The contour presets use 0.15
    /// ([`crate::CONTOUR_SHAPE_TOLERANCE`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shape_tolerance: Option<f64>,
    /// The jump starts from the memory as it was this many locked frames before the last one: a
    /// track in trouble lags behind its target for a few frames before any test flags it.
    pub rollback: usize,
    /// r: growth of the jump share per unlocked frame.
    pub share_rate: f64,
    /// η_max: the largest jump share.
    pub max_share: f64,
    /// η_d: the share of the prior whose centre jumps while the track is locked, its size and
    /// shape going on as a continuation's (abrupt motion; with an appearance model only). A
    /// priori the jump's centre is uniform over the appearance's
    /// search window, the window the target is believed to be in; it is drawn around the
    /// appearance's detection, so a particle there is weighted by 1 / (window area × the
    /// Gaussian's density): it wins only where its likelihood beats the continuation's by that
    /// much. 0, the default, draws no jump while locked; `head` draws
    /// [`crate::HEAD_DETECTION_SHARE`] (docs/DECISIONS.md measures both).
    pub detection_share: f64,
    /// Translation spread of the jump at the first unlocked frame, pixels.
    pub spread: f64,
    /// Growth of the translation spread per unlocked frame, pixels: the extrapolation's error
    /// grows with the gap. `head` sets it to 0, its jump being centred on the appearance's
    /// detection rather than on an extrapolation.
    pub spread_growth: f64,
    /// Gain of the position in the constant-velocity memory of the locked estimates (α of an
    /// α–β filter).
    pub position_gain: f64,
    /// Gain of the velocity (β of the α–β filter).
    pub velocity_gain: f64,
    /// Gain of the size and shape components (an exponential average: the target's shape is
    /// remembered from many locked frames, so that a contour shrinking onto a visible sliver
    /// does not become the shape of the reacquired target).
    pub shape_gain: f64,
}

impl Default for ReacquisitionSettings {
    fn default() -> Self {
        Self {
            lock_gamma: 0.15,
            shape_tolerance: None,
            rollback: 5,
            share_rate: 0.02,
            max_share: 0.3,
            detection_share: 0.0,
            spread: 3.0,
            spread_growth: 0.5,
            position_gain: 0.5,
            velocity_gain: 0.2,
            shape_gain: 0.05,
        }
    }
}

impl ReacquisitionSettings {
    /// Checks that every value is finite, the shares and gains in [0, 1] and the spread positive.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the field.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("reacquisition.lock_gamma", self.lock_gamma),
            ("reacquisition.max_share", self.max_share),
            ("reacquisition.detection_share", self.detection_share),
            ("reacquisition.position_gain", self.position_gain),
            ("reacquisition.velocity_gain", self.velocity_gain),
            ("reacquisition.shape_gain", self.shape_gain),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(Error::InvalidSetting {
                    name,
                    reason: format!("{v} must be in [0, 1]"),
                });
            }
        }
        for (name, v, positive) in [
            ("reacquisition.share_rate", self.share_rate, false),
            (
                "reacquisition.shape_tolerance",
                self.shape_tolerance.unwrap_or(1.0),
                true,
            ),
            ("reacquisition.spread", self.spread, true),
            ("reacquisition.spread_growth", self.spread_growth, false),
        ] {
            if !(v.is_finite() && (v > 0.0 || (!positive && v == 0.0))) {
                return Err(Error::InvalidSetting {
                    name,
                    reason: format!(
                        "{v} must be finite and {}",
                        if positive { "positive" } else { "non-negative" }
                    ),
                });
            }
        }
        Ok(())
    }
}

/// The constant-velocity memory of the locked estimates: an α–β filter on the translation and an
/// exponential average of the other components, updated only on locked frames.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackMemory {
    /// The filtered state at `frame`.
    state: StateVector,
    /// Its velocity per frame (translation only; zero elsewhere).
    velocity: StateVector,
    /// The last locked frame.
    frame: usize,
}

impl TrackMemory {
    /// A memory of a target at rest at `state`, locked at `frame`.
    pub fn new(state: StateVector, frame: usize) -> Self {
        Self {
            state,
            velocity: [0.0; STATE_SLOTS],
            frame,
        }
    }

    /// The remembered state (translation as of the last locked frame).
    pub fn state(&self) -> &StateVector {
        &self.state
    }

    /// The last locked frame.
    pub fn last_locked(&self) -> usize {
        self.frame
    }

    /// Whether `state` has the remembered scale and elongation, within a log-ratio `tolerance`
    /// (always without one).
    pub fn shape_agrees(
        &self,
        space: ShapeSpace,
        state: &StateVector,
        tolerance: Option<f64>,
    ) -> bool {
        let Some(tolerance) = tolerance else {
            return true;
        };
        let ratio = |a: f64, b: f64| (a / b).ln().abs();
        ratio(space.scale(state), space.scale(&self.state)) <= tolerance
            && ratio(space.elongation(state), space.elongation(&self.state)) <= tolerance
    }

    /// The remembered pose extrapolated to `frame`, and the velocity.
    pub fn extrapolate(&self, space: ShapeSpace, frame: usize) -> (StateVector, StateVector) {
        let k = frame.saturating_sub(self.frame) as f64;
        let mut x = self.state;
        for j in (0..space.dim()).filter(|&j| space.is_translation(j)) {
            x[j] += k * self.velocity[j];
        }
        (x, self.velocity)
    }

    /// Takes the locked estimate `state` of `frame` into the memory.
    pub fn observe(
        &mut self,
        space: ShapeSpace,
        settings: &ReacquisitionSettings,
        state: &StateVector,
        frame: usize,
    ) {
        let (predicted, _) = self.extrapolate(space, frame);
        let steps = frame.saturating_sub(self.frame).max(1) as f64;
        for j in 0..space.dim() {
            let residual = state[j] - predicted[j];
            if space.is_translation(j) {
                self.state[j] = predicted[j] + settings.position_gain * residual;
                self.velocity[j] += settings.velocity_gain * residual / steps;
            } else {
                self.state[j] = predicted[j] + settings.shape_gain * residual;
            }
        }
        self.frame = frame;
    }
}

/// The jump component of one frame (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reacquisition {
    /// The jump share of this frame, η = min(η_max, r · gap).
    pub share: f64,
    /// m_k, the extrapolated pose.
    pub mean: StateVector,
    /// v, the velocity α_k − α_{k−1} given to a jumping particle.
    pub velocity: StateVector,
    /// σ_k per component.
    pub sigmas: StateVector,
    /// The area of the region the jump's centre is a priori uniform over (the appearance's
    /// search window), the Gaussian around `mean` being only its proposal; `None`: the Gaussian
    /// is the prior itself. The prior's density is taken as 1 / area wherever the centre falls:
    /// the detection lies the target's contrast ring inside the window, and with a spread well
    /// below the ring's width (`head`'s 3 px against 24) the proposal's mass outside it is
    /// negligible.
    pub uniform_area: Option<f64>,
}

impl Reacquisition {
    /// Draws (α_k, α_{k−1}) of a jump.
    pub fn sample<R: Rng + ?Sized>(
        &self,
        space: ShapeSpace,
        rng: &mut R,
    ) -> (StateVector, StateVector) {
        let d = space.dim();
        let mut now = self.mean;
        for (x, sigma) in now.iter_mut().zip(&self.sigmas).take(d) {
            let z: f64 = StandardNormal.sample(rng);
            *x += sigma * z;
        }
        let mut prev = now;
        for (x, v) in prev.iter_mut().zip(&self.velocity).take(d) {
            *x -= v;
        }
        (now, prev)
    }

    /// Whether the jump moves the centre only, the size and shape being a continuation's: the
    /// abrupt-motion jump, whose centre is uniform over the search window a priori.
    pub fn moves_centre_only(&self) -> bool {
        self.uniform_area.is_some()
    }

    /// Sets the centre of `now` to a draw around the jump's mean centre, and that of `prev` to
    /// the same point (at rest), leaving the size and shape of both: a continuation's state made
    /// a jump that moves the centre only.
    pub fn sample_centre<R: Rng + ?Sized>(
        &self,
        space: ShapeSpace,
        now: &mut StateVector,
        prev: &mut StateVector,
        rng: &mut R,
    ) {
        for j in (0..space.dim()).filter(|&j| space.is_translation(j)) {
            let z: f64 = StandardNormal.sample(rng);
            now[j] = self.mean[j] + self.sigmas[j] * z;
            prev[j] = now[j];
        }
    }

    /// Whether a particle with states (`now`, `prev`) can have come from a jump (rather than a
    /// continuation, which keeps α_{k−1} equal to its ancestor's α_k = `ancestor_now`).
    pub fn is_jump(ancestor_now: &StateVector, prev: &StateVector) -> bool {
        ancestor_now != prev
    }

    /// The log-density the jump draws α_k from: log N(α_k; m_k, diag σ_k²) over the used
    /// dimensions (the α_{k−1} part is a point mass); for a jump that moves the centre only
    /// ([`Reacquisition::moves_centre_only`]) the centre's Gaussian alone, the size and shape
    /// being a continuation's ([`log_mixture_density`] adds their density).
    pub fn log_density(&self, space: ShapeSpace, now: &StateVector) -> f64 {
        if self.moves_centre_only() {
            self.log_gaussian(space, now, |j| space.is_translation(j))
        } else {
            self.log_gaussian(space, now, |_| true)
        }
    }

    /// The jump's prior log-density: [`Reacquisition::log_density`], or with a centre uniform
    /// over the window ([`Reacquisition::uniform_area`]) −ln(area), the size and shape being a
    /// continuation's as in [`Reacquisition::log_density`].
    pub fn log_prior_density(&self, space: ShapeSpace, now: &StateVector) -> f64 {
        match self.uniform_area {
            Some(area) => -area.ln(),
            None => self.log_density(space, now),
        }
    }

    fn log_gaussian(
        &self,
        space: ShapeSpace,
        now: &StateVector,
        keep: impl Fn(usize) -> bool,
    ) -> f64 {
        (0..space.dim())
            .filter(|&j| keep(j))
            .map(|j| {
                let z = (now[j] - self.mean[j]) / self.sigmas[j];
                -0.5 * z * z - self.sigmas[j].ln() - 0.5 * (2.0 * std::f64::consts::PI).ln()
            })
            .sum()
    }
}

/// Which of a jump's densities a mixture density reads: the model's, or the one the jump is drawn
/// from. They differ only for a jump uniform over the window ([`Reacquisition::uniform_area`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JumpDensity {
    /// The prior's ([`Reacquisition::log_prior_density`]).
    Prior,
    /// The proposal's ([`Reacquisition::log_density`]).
    Sampling,
}

/// log((1 − η) e^{log_continue}) for a continuation and log(η q(α_k)) for a jump, q the jump's
/// `density`: the density of a particle under a mixture whose components have disjoint supports.
/// A jump that moves the centre only ([`Reacquisition::moves_centre_only`]) adds
/// `log_continue_shape`, the continuation's density of its size and shape (the marginal of
/// `log_continue`'s law over the components other than the centre).
#[allow(clippy::too_many_arguments)]
pub fn log_mixture_density(
    component: Option<&Reacquisition>,
    space: ShapeSpace,
    share: f64,
    jumped: bool,
    now: &StateVector,
    density: JumpDensity,
    log_continue: impl FnOnce() -> f64,
    log_continue_shape: impl FnOnce() -> f64,
) -> f64 {
    match component {
        Some(c) if share > 0.0 => {
            if jumped {
                let shape = if c.moves_centre_only() {
                    log_continue_shape()
                } else {
                    0.0
                };
                share.ln()
                    + shape
                    + match density {
                        JumpDensity::Prior => c.log_prior_density(space, now),
                        JumpDensity::Sampling => c.log_density(space, now),
                    }
            } else {
                (1.0 - share).ln() + log_continue()
            }
        }
        _ => log_continue(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn memory_learns_a_constant_velocity_and_extrapolates_it() {
        let space = ShapeSpace::Odobez;
        let s = ReacquisitionSettings::default();
        let mut m = TrackMemory::new([100.0, 50.0, 20.0, 1.0, 0.0, 0.0], 0);
        for k in 1..=100 {
            m.observe(
                space,
                &s,
                &[100.0 - 2.0 * k as f64, 50.0, 20.0, 1.0, 0.0, 0.0],
                k,
            );
        }
        let (x, v) = m.extrapolate(space, 110);
        assert!((v[0] + 2.0).abs() < 0.05, "{v:?}");
        assert!((x[0] - (100.0 - 220.0)).abs() < 1.0, "{x:?}");
        assert!((x[2] - 20.0).abs() < 1e-9 && v[2] == 0.0);
    }

    #[test]
    fn jump_has_the_stated_spread_and_velocity() {
        let space = ShapeSpace::Affine;
        let r = Reacquisition {
            share: 0.2,
            mean: [20.0, 0.0, 0.0, 15.0, 100.0, 80.0],
            velocity: [0.0, 0.0, 0.0, 0.0, -2.0, 0.5],
            sigmas: [0.2, 0.1, 0.1, 0.2, 5.0, 5.0],
            uniform_area: None,
        };
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        let n = 20_000;
        let (mut m, mut v) = (0.0, 0.0);
        for _ in 0..n {
            let (now, prev) = r.sample(space, &mut rng);
            assert!((now[4] - prev[4] + 2.0).abs() < 1e-12);
            assert!(Reacquisition::is_jump(&r.mean, &prev));
            m += now[4];
            v += (now[4] - 100.0).powi(2);
        }
        m /= n as f64;
        v /= n as f64;
        assert!((m - 100.0).abs() < 0.2, "{m}");
        assert!((v / 25.0 - 1.0).abs() < 0.05, "{v}");
    }

    #[test]
    fn mixture_density_weights_each_component_by_its_share() {
        let space = ShapeSpace::Odobez;
        let r = Reacquisition {
            share: 0.3,
            mean: [0.0; 6],
            velocity: [0.0; 6],
            sigmas: [1.0; 6],
            uniform_area: None,
        };
        let x = [0.5, -0.5, 0.0, 0.0, 0.0, 0.0];
        let never = || -> f64 { unreachable!() };
        for density in [JumpDensity::Prior, JumpDensity::Sampling] {
            // A jump that moves the whole pose reads neither continuation density.
            let jump = log_mixture_density(Some(&r), space, 0.3, true, &x, density, never, never);
            assert!((jump - (0.3f64.ln() + r.log_density(space, &x))).abs() < 1e-12);
            let cont =
                log_mixture_density(Some(&r), space, 0.3, false, &x, density, || -2.0, never);
            assert!((cont - (0.7f64.ln() - 2.0)).abs() < 1e-12);
            assert_eq!(
                log_mixture_density(None, space, 0.3, true, &x, density, || -2.0, never),
                -2.0
            );
            assert_eq!(
                log_mixture_density(Some(&r), space, 0.0, false, &x, density, || -2.0, never),
                -2.0
            );
        }
    }

    #[test]
    fn a_jump_uniform_over_the_window_is_weighted_by_prior_over_proposal() {
        // Odobez space: translation in slots 0 and 1, scale and shape in 2 and 3. The jump
        // moves the centre of a continuation's state, so its size and shape carry the
        // continuation's densities: here −1.5 under the prior and −0.5 under the proposal.
        let space = ShapeSpace::Odobez;
        let r = Reacquisition {
            share: 0.1,
            mean: [10.0, 20.0, 30.0, 1.0, 0.0, 0.0],
            velocity: [0.0; 6],
            sigmas: [3.0, 3.0, 0.3, 0.01, 1.0, 1.0],
            uniform_area: Some(4000.0),
        };
        assert!(r.moves_centre_only());
        let gaussian = |x: f64, m: f64, s: f64| {
            -0.5 * ((x - m) / s).powi(2) - s.ln() - 0.5 * (2.0 * std::f64::consts::PI).ln()
        };
        let (prior_shape, proposal_shape) = (-1.5, -0.5);
        for x in [
            [10.0, 20.0, 30.0, 1.0, 0.0, 0.0],
            [16.0, 14.0, 30.5, 0.99, 0.0, 0.0],
            [-40.0, 90.0, 29.0, 1.02, 0.0, 0.0],
        ] {
            // The centre's densities: N(centre; detection, σ²) drawn from, 1 / area a priori.
            let centre = gaussian(x[0], 10.0, 3.0) + gaussian(x[1], 20.0, 3.0);
            assert!((r.log_density(space, &x) - centre).abs() < 1e-9);
            assert!((r.log_prior_density(space, &x) + 4000f64.ln()).abs() < 1e-9);
            let jump = |density, shape: f64| {
                log_mixture_density(Some(&r), space, 0.1, true, &x, density, || 0.0, || shape)
            };
            let prior = jump(JumpDensity::Prior, prior_shape);
            let proposal = jump(JumpDensity::Sampling, proposal_shape);
            assert!((prior - (0.1f64.ln() + prior_shape - 4000f64.ln())).abs() < 1e-9);
            assert!((proposal - (0.1f64.ln() + proposal_shape + centre)).abs() < 1e-9);
            // The weight's ratio: 1 / (area · N(centre)) for the centre, the continuation's own
            // ratio for the size and shape.
            let ratio = prior - proposal;
            let expected = (prior_shape - proposal_shape) - 4000f64.ln() - centre;
            assert!((ratio - expected).abs() < 1e-9);
            // A continuation's prior and proposal are the same.
            let cont = |density| {
                log_mixture_density(Some(&r), space, 0.1, false, &x, density, || -3.0, || 0.0)
            };
            assert_eq!(cont(JumpDensity::Prior), cont(JumpDensity::Sampling));
        }
        // Without the window, the Gaussian is the prior too.
        let plain = Reacquisition {
            uniform_area: None,
            ..r
        };
        let x = [16.0, 14.0, 30.5, 0.99, 0.0, 0.0];
        assert_eq!(
            plain.log_prior_density(space, &x),
            plain.log_density(space, &x)
        );
    }

    #[test]
    fn invalid_settings_are_rejected() {
        assert!(ReacquisitionSettings::default().validate().is_ok());
        for bad in [
            ReacquisitionSettings {
                max_share: 1.5,
                ..Default::default()
            },
            ReacquisitionSettings {
                spread: 0.0,
                ..Default::default()
            },
            ReacquisitionSettings {
                share_rate: f64::NAN,
                ..Default::default()
            },
            ReacquisitionSettings {
                detection_share: -0.1,
                ..Default::default()
            },
            ReacquisitionSettings {
                detection_share: 1.5,
                ..Default::default()
            },
        ] {
            assert!(bad.validate().is_err());
        }
    }
}
