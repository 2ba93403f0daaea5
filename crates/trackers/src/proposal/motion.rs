//! Odobez's motion proposal (Eq. 16): q(α_k | c_{k−1}, z_{1:k}) = N(α_k; α_{k−1} + α̇, Λ̂ + Λ_wp),
//! with the state derivative α̇ and its covariance from the robust affine motion of the particle's
//! cluster (Eq. 13–15).

use nalgebra::{Matrix2, Matrix6, SMatrix, Vector6};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::dynamics::TrackerDynamics;
use crate::dynamics::reacquisition::JumpDensity;
use crate::particle::Particle;
use crate::space::{Components, STATE_SLOTS, ShapeSpace, StateVector, axpy};

/// The motion of one cluster, as a Gaussian over the state increment.
#[derive(Debug, Clone, PartialEq)]
pub struct ClusterMotion {
    /// Mean state increment α̇ (unused slots zero).
    pub derivative: StateVector,
    /// Lower Cholesky factor of Λ = Λ̂ + Λ_wp over the used dimensions (identity elsewhere).
    pub chol: Matrix6<f64>,
    /// log det of the Cholesky factor (used dimensions).
    pub log_det_chol: f64,
    /// Whether the motion came from a converged estimate (false: fallback, see
    /// [`ClusterMotion::fallback`]).
    pub estimated: bool,
}

impl ClusterMotion {
    /// Builds the Gaussian from an increment and its covariance (used dimensions of `space`),
    /// adding the process noise `sigmas` on the diagonal. Returns `None` when the covariance is not
    /// positive definite or not finite.
    pub fn new(
        space: ShapeSpace,
        derivative: StateVector,
        covariance: &Matrix6<f64>,
        sigmas: &StateVector,
        estimated: bool,
    ) -> Option<Self> {
        let d = space.dim();
        let mut lambda = Matrix6::identity();
        for r in 0..d {
            for c in 0..d {
                lambda[(r, c)] = covariance[(r, c)];
            }
            lambda[(r, r)] += sigmas[r] * sigmas[r];
        }
        if lambda.iter().any(|v| !v.is_finite()) || derivative.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let chol = lambda.cholesky()?.l();
        let log_det_chol = (0..d).map(|i| chol[(i, i)].ln()).sum();
        Some(Self {
            derivative,
            chol,
            log_det_chol,
            estimated,
        })
    }

    /// The proposal used when a cluster's motion cannot be estimated (region outside the image,
    /// no texture): the AR2 prediction of the cluster mean as increment, process noise only. This
    /// keeps the tracker running where Odobez's proposal has nothing to say.
    pub fn fallback(
        dynamics: &TrackerDynamics,
        mean_now: &StateVector,
        mean_prev: &StateVector,
    ) -> Self {
        let space = dynamics.space;
        let pred =
            dynamics
                .settings
                .predict(space, mean_now, mean_prev, dynamics.shape_anchor.as_ref());
        let mut derivative = [0.0; STATE_SLOTS];
        for j in 0..space.dim() {
            derivative[j] = pred[j] - mean_now[j];
        }
        let sigmas = dynamics.settings.sigmas(space, mean_now);
        let mut chol = Matrix6::identity();
        for j in 0..space.dim() {
            chol[(j, j)] = sigmas[j];
        }
        let log_det_chol = (0..space.dim()).map(|j| sigmas[j].ln()).sum();
        Self {
            derivative,
            chol,
            log_det_chol,
            estimated: false,
        }
    }

    /// log N(x; mean, Λ) over the used dimensions among `which`: the marginal of the Gaussian
    /// over them (Λ's block of those rows and columns).
    pub fn log_density_over(
        &self,
        space: ShapeSpace,
        mean: &StateVector,
        x: &StateVector,
        which: Components,
    ) -> f64 {
        if which == Components::All {
            return self.log_density(space, mean, x);
        }
        let (mut kept, mut m) = ([0usize; STATE_SLOTS], 0);
        for j in (0..space.dim()).filter(|&j| which.includes(space, j)) {
            kept[m] = j;
            m += 1;
        }
        let full = self.chol * self.chol.transpose();
        let mut block = Matrix6::identity();
        let mut diff = Vector6::zeros();
        for (a, &i) in kept[..m].iter().enumerate() {
            diff[a] = x[i] - mean[i];
            for (b, &j) in kept[..m].iter().enumerate() {
                block[(a, b)] = full[(i, j)];
            }
        }
        let Some(chol) = block.cholesky() else {
            return f64::NEG_INFINITY;
        };
        let l = chol.l();
        let Some(z) = l.solve_lower_triangular(&diff) else {
            return f64::NEG_INFINITY;
        };
        let q: f64 = (0..m).map(|j| z[j] * z[j]).sum();
        let log_det: f64 = (0..m).map(|j| l[(j, j)].ln()).sum();
        -0.5 * q - log_det - 0.5 * m as f64 * (2.0 * std::f64::consts::PI).ln()
    }

    /// log N(x; mean, Λ) over the used dimensions.
    pub fn log_density(&self, space: ShapeSpace, mean: &StateVector, x: &StateVector) -> f64 {
        let d = space.dim();
        let mut diff = Vector6::zeros();
        for j in 0..d {
            diff[j] = x[j] - mean[j];
        }
        let Some(z) = self.chol.solve_lower_triangular(&diff) else {
            return f64::NEG_INFINITY;
        };
        let q: f64 = (0..d).map(|j| z[j] * z[j]).sum();
        -0.5 * q - self.log_det_chol - 0.5 * d as f64 * (2.0 * std::f64::consts::PI).ln()
    }
}

/// The state increment and its covariance implied by an affine motion `[a1..a6]` (Odobez Eq. 13,
/// origin at the state's centre) with covariance `cov`, for a state `x` of `space`.
///
/// Odobez space: Eq. 15 (via [`motion_est::odobez_state_derivative`]). Affine space: the motion
/// maps the posed contour p = A r + t to p + d(p − t), so ΔA = M A and Δt = (a1, a4), with
/// M = [[a2, a3], [a5, a6]]; the map is linear in the parameters and the covariance is J Σ Jᵀ.
///
/// # Errors
/// The motion crate's error for non-finite input or a non-positive scale.
pub fn state_increment(
    space: ShapeSpace,
    x: &StateVector,
    params: &[f64; 6],
    cov: &Matrix6<f64>,
) -> motion_est::Result<(StateVector, Matrix6<f64>)> {
    match space {
        ShapeSpace::Odobez => {
            let (d, c) = motion_est::odobez_state_derivative(params, cov, x[2], x[3])?;
            let mut out = Matrix6::zeros();
            out.fixed_view_mut::<4, 4>(0, 0).copy_from(&c);
            Ok(([d[0], d[1], d[2], d[3], 0.0, 0.0], out))
        }
        ShapeSpace::Affine => {
            let a = Matrix2::new(x[0], x[1], x[2], x[3]);
            // Row order of the state: a11, a12, a21, a22, t1, t2; columns: a1..a6.
            let mut j = SMatrix::<f64, 6, 6>::zeros();
            // ΔA11 = a2 A11 + a3 A21, ΔA12 = a2 A12 + a3 A22.
            j[(0, 1)] = a[(0, 0)];
            j[(0, 2)] = a[(1, 0)];
            j[(1, 1)] = a[(0, 1)];
            j[(1, 2)] = a[(1, 1)];
            // ΔA21 = a5 A11 + a6 A21, ΔA22 = a5 A12 + a6 A22.
            j[(2, 4)] = a[(0, 0)];
            j[(2, 5)] = a[(1, 0)];
            j[(3, 4)] = a[(0, 1)];
            j[(3, 5)] = a[(1, 1)];
            j[(4, 0)] = 1.0;
            j[(5, 3)] = 1.0;
            let p = Vector6::from_row_slice(params);
            let d = j * p;
            Ok((
                [d[0], d[1], d[2], d[3], d[4], d[5]],
                j * cov * j.transpose(),
            ))
        }
    }
}

/// Odobez's motion proposal over a set of cluster motions; particle i uses the cluster stored in
/// its `cluster` field. The hidden variables are drawn from their transitions
/// (`TrackerDynamics::sample_hidden`).
#[derive(Debug, Clone, Copy)]
pub struct MotionProposal<'a> {
    /// The prior, for the hidden variables and the shape space.
    pub dynamics: &'a TrackerDynamics,
    /// One motion per cluster.
    pub clusters: &'a [ClusterMotion],
    /// Mix the prior into the proposal by the particle's occlusion γ: q = (1 − γ) q_motion +
    /// γ p(α_k | α_{k−1}). Beyond both papers: the image motion of an occluded target's region is
    /// the occluder's, so a particle that believes its target hidden coasts on its own dynamics
    /// instead of following the occluder. With γ = 0 this is Odobez's Eq. 16 exactly; the weight
    /// uses the mixture density (Eq. 3), so the filter stays correct for any γ.
    pub occlusion_aware: bool,
}

impl MotionProposal<'_> {
    fn cluster(&self, p: &Particle) -> Option<&ClusterMotion> {
        self.clusters.get(p.cluster as usize)
    }

    /// The proposal mean α_{k−1} + α̇ for a particle.
    fn mean(&self, previous: &Particle, motion: &ClusterMotion) -> StateVector {
        let mut m = previous.now;
        axpy(&mut m, 1.0, &motion.derivative);
        m
    }
}

impl MotionProposal<'_> {
    /// The weight of the prior in the proposal of a particle: its previous occlusion γ when
    /// `occlusion_aware`, else 0. See [`MotionProposal::occlusion_aware`].
    fn prior_share(&self, previous: &Particle) -> f64 {
        if self.occlusion_aware {
            previous.status.gamma.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

impl smc_core::Proposal for MotionProposal<'_> {
    type State = Particle;

    fn sample<R: Rng + ?Sized>(&self, _index: usize, previous: &Particle, rng: &mut R) -> Particle {
        if self.dynamics.draws_jump(rng) {
            return self
                .dynamics
                .sample_jump(previous, rng, |rng| self.sample_kinematics(previous, rng));
        }
        let mut next = *previous;
        next.prev = previous.now;
        next.now = self.sample_kinematics(previous, rng);
        self.dynamics.sample_hidden(previous, &mut next, rng);
        next
    }

    /// The density of the particle's component: the jump (share η, drawn as the prior draws it,
    /// see [`ReacquisitionSettings`](crate::ReacquisitionSettings)) or the continuation below,
    /// times 1 − η; less the hidden chains' exploration ratio
    /// (`TrackerDynamics::log_hidden_exploration_ratio`, 0 by default).
    fn log_density(&self, _index: usize, previous: &Particle, next: &Particle) -> f64 {
        self.dynamics
            .log_with_jump(previous, next, JumpDensity::Sampling, |which| {
                self.log_continuation_density(previous, next, which)
            })
            - self.dynamics.log_hidden_exploration_ratio(previous, next)
    }
}

impl MotionProposal<'_> {
    /// Draws the kinematic state of a continuation: Eq. 16, or the prior with probability γ
    /// (see [`MotionProposal::occlusion_aware`]) or for a particle without a cluster motion.
    fn sample_kinematics<R: Rng + ?Sized>(&self, previous: &Particle, rng: &mut R) -> StateVector {
        let use_prior = self.prior_share(previous) > rng.random::<f64>();
        match self.cluster(previous) {
            Some(motion) if !use_prior => {
                let mut now = self.mean(previous, motion);
                let d = self.dynamics.space.dim();
                let mut z = Vector6::zeros();
                for j in 0..d {
                    z[j] = StandardNormal.sample(rng);
                }
                let e = motion.chol * z;
                for j in 0..d {
                    now[j] += e[j];
                }
                self.dynamics.space.clamp(&mut now, &self.dynamics.bounds);
                now
            }
            _ => self.dynamics.sample_kinematics(previous, rng),
        }
    }

    /// log q of a continuation over `which` components: Eq. 16, or its mixture with
    /// the prior by γ.
    fn log_continuation_density(
        &self,
        previous: &Particle,
        next: &Particle,
        which: Components,
    ) -> f64 {
        let Some(motion) = self.cluster(previous) else {
            return self
                .dynamics
                .log_kinematic_density_over(previous, next, which);
        };
        let log_motion = motion.log_density_over(
            self.dynamics.space,
            &self.mean(previous, motion),
            &next.now,
            which,
        );
        let share = self.prior_share(previous);
        if share <= 0.0 {
            return log_motion;
        }
        // The mixture (1 − γ) q_motion + γ p_prior, in logs.
        let a = (1.0 - share).ln() + log_motion;
        let b = share.ln()
            + self
                .dynamics
                .log_kinematic_density_over(previous, next, which);
        let m = a.max(b);
        if m == f64::NEG_INFINITY {
            return m;
        }
        m + ((a - m).exp() + (b - m).exp()).ln()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::proposal::WeightedPrior;

    #[test]
    fn affine_increment_matches_a_direct_warp() {
        // A pose, an affine motion about its centre; compare the increment with warping points.
        let x = [20.0, 3.0, -2.0, 15.0, 100.0, 80.0];
        let params = [1.5, 0.02, -0.01, -0.7, 0.015, 0.03];
        let (d, _) = state_increment(ShapeSpace::Affine, &x, &params, &Matrix6::zeros()).unwrap();
        for r in [[1.0, 0.0], [0.0, 1.0], [0.6, -0.8]] {
            let p = [
                x[0] * r[0] + x[1] * r[1] + x[4],
                x[2] * r[0] + x[3] * r[1] + x[5],
            ];
            let (rx, ry) = (p[0] - x[4], p[1] - x[5]);
            let warped = [
                p[0] + params[0] + params[1] * rx + params[2] * ry,
                p[1] + params[3] + params[4] * rx + params[5] * ry,
            ];
            let y: Vec<f64> = x.iter().zip(&d).map(|(a, b)| a + b).collect();
            let q = [
                y[0] * r[0] + y[1] * r[1] + y[4],
                y[2] * r[0] + y[3] * r[1] + y[5],
            ];
            assert!((q[0] - warped[0]).abs() < 1e-12 && (q[1] - warped[1]).abs() < 1e-12);
        }
    }

    #[test]
    fn gaussian_density_matches_the_closed_form_for_a_diagonal_covariance() {
        let mut cov = Matrix6::zeros();
        cov[(0, 0)] = 4.0;
        cov[(1, 1)] = 1.0;
        let m = ClusterMotion::new(
            ShapeSpace::Odobez,
            [0.0; 6],
            &cov,
            &[0.0, 0.0, 1.0, 1.0, 0.0, 0.0],
            true,
        )
        .unwrap();
        let x = [2.0, -1.0, 0.5, 0.0, 0.0, 0.0];
        let expected =
            -0.5 * (1.0 + 1.0 + 0.25) - (2.0f64).ln() - 2.0 * (2.0 * std::f64::consts::PI).ln();
        assert!((m.log_density(ShapeSpace::Odobez, &[0.0; 6], &x) - expected).abs() < 1e-12);
    }

    #[test]
    fn a_marginal_density_reads_the_block_of_the_kept_components() {
        // Translation and scale correlated; the marginal over the size and shape is the
        // Gaussian of Λ's block, here diagonal: the scale's and the shape's own.
        let space = ShapeSpace::Odobez;
        let mut cov = Matrix6::zeros();
        cov[(0, 0)] = 4.0;
        cov[(1, 1)] = 1.0;
        cov[(2, 2)] = 0.5;
        cov[(0, 2)] = 0.8;
        cov[(2, 0)] = 0.8;
        let m = ClusterMotion::new(space, [0.0; 6], &cov, &[0.0, 0.0, 1.0, 0.5, 0.0, 0.0], true)
            .unwrap();
        let x = [2.0, -1.0, 0.7, -0.2, 0.0, 0.0];
        let gaussian = |x: f64, var: f64| {
            -0.5 * x * x / var - 0.5 * var.ln() - 0.5 * (2.0 * std::f64::consts::PI).ln()
        };
        let shape = m.log_density_over(space, &[0.0; 6], &x, Components::SizeAndShape);
        assert!((shape - (gaussian(0.7, 1.5) + gaussian(-0.2, 0.25))).abs() < 1e-12);
        // Every component kept: the full density; a correlated pair is not the product of
        // its marginals (the centre's: its block, diagonal here).
        let all = m.log_density_over(space, &[0.0; 6], &x, Components::All);
        assert_eq!(all, m.log_density(space, &[0.0; 6], &x));
        let centre = gaussian(2.0, 4.0) + gaussian(-1.0, 1.0);
        assert!((all - (centre + shape)).abs() > 1e-3);
    }

    #[test]
    fn the_abrupt_motion_jump_moves_a_continuations_centre_and_keeps_its_ratio() {
        use crate::dynamics::reacquisition::Reacquisition;
        use smc_core::{Dynamics, Proposal};
        let (mut dynamics, clusters, mut previous) = setup();
        // The ancestor was growing: its size velocity must survive the jump.
        previous.prev[2] = 24.0;
        let area = 5000.0;
        dynamics.reacquisition = Some(Reacquisition {
            share: 1.0,
            mean: [150.0, 60.0, 0.0, 0.0, 0.0, 0.0],
            velocity: [0.0; 6],
            sigmas: [3.0, 3.0, 1.0, 1.0, 1.0, 1.0],
            uniform_area: Some(area),
        });
        let proposal = MotionProposal {
            dynamics: &dynamics,
            clusters: &clusters,
            occlusion_aware: false,
        };
        let mut rng = <rand_pcg::Pcg64Mcg as rand::SeedableRng>::seed_from_u64(11);
        let (n, mut scale) = (4000, 0.0);
        for _ in 0..n {
            let next = proposal.sample(0, &previous, &mut rng);
            // At rest at its new centre; its previous size is the ancestor's.
            assert_eq!(next.now[..2], next.prev[..2]);
            assert_eq!(next.prev[2..4], previous.now[2..4]);
            assert!(Reacquisition::is_jump(&previous.now, &next.prev));
            scale += next.now[2];
            // p / q: 1 / (area · N(centre)) for the centre, the continuation's p / q for the
            // size and shape (the prior's AR2 over the motion's Gaussian).
            let shape = Components::SizeAndShape;
            let centre = dynamics
                .reacquisition
                .as_ref()
                .unwrap()
                .log_density(dynamics.space, &next.now);
            let continuation = dynamics.log_kinematic_density_over(&previous, &next, shape)
                - clusters[0].log_density_over(
                    dynamics.space,
                    &proposal.mean(&previous, &clusters[0]),
                    &next.now,
                    shape,
                );
            let weight = Dynamics::log_density(&dynamics, &previous, &next)
                - proposal.log_density(0, &previous, &next);
            let expected = continuation - area.ln() - centre;
            assert!((weight - expected).abs() < 1e-9, "{weight} vs {expected}");
        }
        // The size is the motion proposal's: the ancestor's plus the cluster's 0.3.
        assert!(
            (scale / n as f64 - 25.3).abs() < 0.02,
            "{}",
            scale / n as f64
        );
    }

    fn setup() -> (
        crate::dynamics::TrackerDynamics,
        Vec<ClusterMotion>,
        Particle,
    ) {
        use crate::dynamics::{ClutterProcess, DynamicsSettings, OcclusionModel, TrackerDynamics};
        let dynamics = TrackerDynamics {
            space: ShapeSpace::Odobez,
            settings: DynamicsSettings::default(),
            clutter: ClutterProcess::Fixed(0.05),
            occlusion: OcclusionModel::None,
            bounds: crate::space::ShapeBounds::loose(2.0),
            reacquisition: None,
            shape_anchor: None,
        };
        let mut cov = Matrix6::zeros();
        cov[(0, 0)] = 0.5;
        cov[(1, 1)] = 0.3;
        cov[(0, 1)] = 0.1;
        cov[(1, 0)] = 0.1;
        let sigmas = dynamics
            .settings
            .sigmas(ShapeSpace::Odobez, &[100.0, 80.0, 25.0, 1.0, 0.0, 0.0]);
        let motion = ClusterMotion::new(
            ShapeSpace::Odobez,
            [2.0, -1.0, 0.3, 0.0, 0.0, 0.0],
            &cov,
            &sigmas,
            true,
        )
        .unwrap();
        let mut p = Particle::at_rest(
            [100.0, 80.0, 25.0, 1.0, 0.0, 0.0],
            dbn_switch::ClutterState {
                beta: 0,
                lambda: 0.05,
            },
            crate::particle::default_status(),
        );
        p.cluster = 0;
        (dynamics, vec![motion], p)
    }

    #[test]
    fn explored_hidden_chains_are_weighted_by_t_over_q() {
        use crate::dynamics::ClutterProcess;
        use smc_core::{Dynamics, Proposal};
        let (mut dynamics, clusters, mut previous) = setup();
        dynamics.clutter = ClutterProcess::Switching(
            dbn_switch::ClutterHmm::new(&dbn_switch::ClutterConfig::default()).unwrap(),
        );
        previous.clutter.lambda = 0.01;
        fn motion<'a>(d: &'a TrackerDynamics, clusters: &'a [ClusterMotion]) -> MotionProposal<'a> {
            MotionProposal {
                dynamics: d,
                clusters,
                occlusion_aware: false,
            }
        }
        // ε = 0: no ratio, and the motion proposal's density is the plain one.
        let mut rng = <rand_pcg::Pcg64Mcg as rand::SeedableRng>::seed_from_u64(3);
        let next = motion(&dynamics, &clusters).sample(0, &previous, &mut rng);
        assert_eq!(dynamics.log_hidden_exploration_ratio(&previous, &next), 0.0);
        let plain = motion(&dynamics, &clusters).log_density(0, &previous, &next);
        dynamics.settings.hidden_exploration = 0.25;
        let chain = match &dynamics.clutter {
            ClutterProcess::Switching(hmm) => hmm.chain().clone(),
            ClutterProcess::Fixed(_) => unreachable!(),
        };
        let mut switched = 0;
        for _ in 0..400 {
            for next in [
                WeightedPrior(&dynamics).sample(0, &previous, &mut rng),
                motion(&dynamics, &clusters).sample(0, &previous, &mut rng),
            ] {
                let (i, j) = (previous.clutter.beta, next.clutter.beta);
                switched += usize::from(i != j);
                let t = chain.prob(i, j);
                let q = 0.75 * t + 0.25 / chain.n_states() as f64;
                let ratio = (t / q).ln();
                assert!(
                    (dynamics.log_hidden_exploration_ratio(&previous, &next) - ratio).abs() < 1e-12
                );
                // Eq. 3's p / q is the hidden chains' T / q.
                let weight = Dynamics::log_density(&dynamics, &previous, &next)
                    - WeightedPrior(&dynamics).log_density(0, &previous, &next);
                assert!((weight - ratio).abs() < 1e-9, "{weight} vs {ratio}");
            }
        }
        assert!(switched > 0);
        // The same particle's motion density moves by the ratio only.
        dynamics.settings.hidden_exploration = 0.0;
        assert_eq!(
            motion(&dynamics, &clusters).log_density(0, &previous, &next),
            plain
        );
    }

    #[test]
    fn motion_consistency_equals_the_proposal_density_so_eq_24_holds() {
        // p_c1 (Eq. 21) of a propagated particle is the motion proposal's density (Eq. 16) of
        // the same move: their ratio in Eq. 3 is exactly 1, which is Odobez's Eq. 24.
        use rand::SeedableRng;
        use smc_core::Proposal;
        let (dynamics, clusters, previous) = setup();
        let q = MotionProposal {
            dynamics: &dynamics,
            clusters: &clusters,
            occlusion_aware: false,
        };
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
        for _ in 0..20 {
            let next = q.sample(0, &previous, &mut rng);
            let log_q = q.log_density(0, &previous, &next);
            let log_pc1 = crate::observation::motion_consistency::log_motion_consistency(
                ShapeSpace::Odobez,
                &clusters,
                &next,
            );
            assert!((log_q - log_pc1).abs() < 1e-12, "{log_q} vs {log_pc1}");
        }
    }

    #[test]
    fn occlusion_aware_density_is_the_gamma_mixture() {
        use smc_core::Proposal;
        let (dynamics, clusters, mut previous) = setup();
        previous.status.gamma = 0.3;
        let mut next = previous;
        next.prev = previous.now;
        next.now = [101.5, 79.0, 25.2, 1.0, 0.0, 0.0];
        let aware = MotionProposal {
            dynamics: &dynamics,
            clusters: &clusters,
            occlusion_aware: true,
        };
        let plain = MotionProposal {
            dynamics: &dynamics,
            clusters: &clusters,
            occlusion_aware: false,
        };
        let expected = (0.7 * plain.log_density(0, &previous, &next).exp()
            + 0.3 * dynamics.log_kinematic_density(&previous, &next).exp())
        .ln();
        assert!((aware.log_density(0, &previous, &next) - expected).abs() < 1e-10);
    }
}
