//! A particle filter on a model with no image in sight: the univariate nonlinear growth model
//! that Gordon, Salmond & Smith (1993) used to introduce the bootstrap filter.
//!
//! ```text
//! x_k = x_{k−1}/2 + 25 x_{k−1} / (1 + x_{k−1}²) + 8 cos(1.2 k) + v_k,   v_k ~ N(0, 10)
//! z_k = x_k² / 20 + w_k,                                                 w_k ~ N(0, 1)
//! ```
//!
//! The measurement sees only x², so the posterior is often bimodal (±x): the weighted mean can
//! sit between the two modes while the heaviest particle picks one. The example simulates a
//! trajectory, filters it, and prints the truth, both estimates and the effective sample size.
//!
//! Run it with `cargo run --release -p smc-core --example nonlinear_growth [PARTICLES] [SEED]`.
#![allow(clippy::print_stdout)]

use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use rand_pcg::Pcg64Mcg;
use smc_core::estimate::weighted_mean;
use smc_core::model::{Dynamics, FnObservation};
use smc_core::{FilterSettings, ParticleFilter, ParticleSet, ResamplingScheme};

/// Variance of the process noise v_k.
const PROCESS_VARIANCE: f64 = 10.0;
/// Variance of the measurement noise w_k.
const MEASUREMENT_VARIANCE: f64 = 1.0;
/// Number of time steps.
const STEPS: u64 = 50;

/// The deterministic part of the transition at step `k`.
fn drift(x: f64, k: u64) -> f64 {
    0.5 * x + 25.0 * x / (1.0 + x * x) + 8.0 * (1.2 * k as f64).cos()
}

/// The transition from step k − 1 to step k. The model depends on time, so the filter is given a
/// new value of this type at each step.
struct Growth {
    k: u64,
}

impl Dynamics for Growth {
    type State = f64;

    fn sample<R: Rng + ?Sized>(&self, previous: &f64, rng: &mut R) -> f64 {
        let noise: f64 = rand_distr::StandardNormal.sample(rng);
        drift(*previous, self.k) + PROCESS_VARIANCE.sqrt() * noise
    }

    fn log_density(&self, previous: &f64, next: &f64) -> f64 {
        let r = next - drift(*previous, self.k);
        -0.5 * r * r / PROCESS_VARIANCE
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let particles: usize = args.next().map_or(Ok(1000), |a| a.parse())?;
    let seed: u64 = args.next().map_or(Ok(1), |a| a.parse())?;

    // Only the simulation of the truth uses this generator; the filter derives its own random
    // streams from the seed, the step and the particle index.
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let prior = Normal::new(0.0, 5.0_f64.sqrt())?;
    let process = Normal::new(0.0, PROCESS_VARIANCE.sqrt())?;
    let sensor = Normal::new(0.0, MEASUREMENT_VARIANCE.sqrt())?;

    let mut x = prior.sample(&mut rng);
    let initial: Vec<f64> = (0..particles).map(|_| prior.sample(&mut rng)).collect();
    let mut set = ParticleSet::from_states(initial)?;
    // The default settings resample at every step, as the bootstrap filter of the paper does.
    let mut filter = ParticleFilter::new(FilterSettings::default())?;

    println!("   k      truth   weighted mean   heaviest particle      ESS");
    let (mut squared_error, mut squared_error_best) = (0.0, 0.0);
    for k in 1..=STEPS {
        x = drift(x, k) + process.sample(&mut rng);
        let z = x * x / 20.0 + sensor.sample(&mut rng);

        let likelihood = FnObservation::new(move |x: &f64| {
            let r = z - x * x / 20.0;
            -0.5 * r * r / MEASUREMENT_VARIANCE
        });
        let diagnostics = filter.step_bootstrap(
            &mut set,
            &Growth { k },
            &likelihood,
            &ResamplingScheme::Systematic,
            seed,
            k,
        )?;

        let mean = weighted_mean(&set)?[0];
        let best = set.states()[set.max_weight().0];
        squared_error += (mean - x).powi(2);
        squared_error_best += (best - x).powi(2);
        println!(
            "{k:4} {x:10.2} {mean:15.2} {best:19.2} {:8.0}",
            diagnostics.ess
        );
    }
    let n = STEPS as f64;
    println!(
        "RMS error over {STEPS} steps: weighted mean {:.2}, heaviest particle {:.2}",
        (squared_error / n).sqrt(),
        (squared_error_best / n).sqrt()
    );
    Ok(())
}
