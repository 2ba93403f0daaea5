//! A run is a pure function of (inputs, seed): the rayon path gives bit-identical results to the
//! sequential one for any number of threads.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use smc_core::model::{Dynamics, Observation, Proposal};
use smc_core::{
    FilterSettings, Labelled, ParticleFilter, ParticleSet, ResamplingScheme, StepDiagnostics,
};

type State = Labelled<[f64; 2]>;

/// A switching random walk: the label flips with probability 0.1, the step size depends on it.
struct Switching;

impl Dynamics for Switching {
    type State = State;
    fn sample<R: Rng + ?Sized>(&self, p: &State, rng: &mut R) -> State {
        let label = if rng.random::<f64>() < 0.1 {
            1 - p.label
        } else {
            p.label
        };
        let s = if label == 0 { 0.3 } else { 1.5 };
        let (a, b): (f64, f64) = (StandardNormal.sample(rng), StandardNormal.sample(rng));
        Labelled::new(label, [p.state[0] + s * a, p.state[1] + s * b])
    }
    fn log_density(&self, p: &State, n: &State) -> f64 {
        let switch = if p.label == n.label { 0.9f64 } else { 0.1 };
        let s: f64 = if n.label == 0 { 0.3 } else { 1.5 };
        let d0 = (n.state[0] - p.state[0]) / s;
        let d1 = (n.state[1] - p.state[1]) / s;
        switch.ln() - 0.5 * (d0 * d0 + d1 * d1) - 2.0 * s.ln()
    }
}

/// A per-particle proposal (its width depends on the particle index), as a tracker with one
/// motion estimate per cluster would have.
struct PerParticle;

impl Proposal for PerParticle {
    type State = State;
    fn sample<R: Rng + ?Sized>(&self, i: usize, p: &State, rng: &mut R) -> State {
        let mut next = Switching.sample(p, rng);
        let extra = 0.1 * (i % 5) as f64;
        let e: f64 = StandardNormal.sample(rng);
        next.state[0] += extra * e;
        next
    }
    fn log_density(&self, i: usize, p: &State, n: &State) -> f64 {
        // Not the exact density of `sample` (it ignores the extra jitter); any density works for
        // a determinism test, and this one keeps the ratio p/q non-trivial.
        Switching.log_density(p, n) - 0.01 * (i % 5) as f64
    }
}

/// An observation that overrides the batch form.
struct Target([f64; 2]);

impl Observation for Target {
    type State = State;
    fn log_likelihood(&self, p: &State) -> f64 {
        -0.5 * ((p.state[0] - self.0[0]).powi(2) + (p.state[1] - self.0[1]).powi(2))
    }
    fn log_likelihood_batch(&self, states: &[State], out: &mut [f64]) {
        for (s, o) in states.iter().zip(out.iter_mut()) {
            *o = self.log_likelihood(s);
        }
    }
}

/// Everything a run produces, as bits.
#[derive(Debug, PartialEq)]
struct Trace {
    states: Vec<(usize, u64, u64)>,
    log_weights: Vec<u64>,
    diagnostics: Vec<StepDiagnostics>,
}

fn run(parallel: bool, seed: u64, scheme: ResamplingScheme) -> Trace {
    let n = 3000;
    let init = (0..n).map(|i| Labelled::new(i % 2, [0.0, 0.0])).collect();
    let mut set = ParticleSet::from_states(init).unwrap();
    let settings = FilterSettings {
        parallel,
        resample_threshold: 0.7,
        parallel_min_chunk: 16,
        ..FilterSettings::default()
    };
    let mut filter = ParticleFilter::new(settings).unwrap();
    let mut diagnostics = Vec::new();
    for k in 0..15u64 {
        let target = Target([0.5 * k as f64, -0.2 * k as f64]);
        let d = filter
            .step(
                &mut set,
                &PerParticle,
                Some(&Switching),
                &target,
                &scheme,
                seed,
                k,
            )
            .unwrap();
        diagnostics.push(d);
    }
    Trace {
        states: set
            .states()
            .iter()
            .map(|p| (p.label, p.state[0].to_bits(), p.state[1].to_bits()))
            .collect(),
        log_weights: set.log_weights().iter().map(|w| w.to_bits()).collect(),
        diagnostics,
    }
}

#[test]
fn parallel_runs_are_bit_identical_to_sequential_for_any_thread_count() {
    for scheme in ResamplingScheme::ALL {
        let reference = run(false, 2024, scheme);
        // The run must exercise both branches of the resampling decision.
        assert!(reference.diagnostics.iter().any(|d| d.resampled));
        assert!(reference.diagnostics.iter().any(|d| !d.resampled));
        for threads in [1, 2, 3, 4] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let parallel = pool.install(|| run(true, 2024, scheme));
            assert!(
                parallel == reference,
                "{scheme:?} with {threads} threads differs"
            );
            let sequential_in_pool = pool.install(|| run(false, 2024, scheme));
            assert!(sequential_in_pool == reference);
        }
    }
}

#[test]
fn the_seed_decides_the_run() {
    let a = run(false, 1, ResamplingScheme::Systematic);
    let b = run(false, 1, ResamplingScheme::Systematic);
    let c = run(false, 2, ResamplingScheme::Systematic);
    assert_eq!(a, b);
    assert_ne!(a.states, c.states);
}
