//! Particle smoothing cost per particle and step, against N, on the 1-D linear-Gaussian model
//! x_k = 0.9 x_{k−1} + N(0, 0.5), z_k = x_k + N(0, 0.3) over 20 frames:
//!
//! - `ffbsm`: marginal smoothing (FFBSm), O(N²) per step;
//! - `ffbs_exact`: backward simulation of M = N trajectories with the exact draw, O(N²) per step;
//! - `ffbs_rejection`: the same with accept–reject (Douc et al. 2011) and its fallback,
//!   O(N) expected per step.
//!
//! Run with `cargo bench -p smc-core --bench smooth`. Throughput is in particle·steps
//! (N × 19 backward steps): ns per particle·step = 10⁹ / the elements-per-second figure.

use std::f64::consts::PI;
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_main};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use smc_core::model::{Dynamics, FnObservation, TransitionDensity};
use smc_core::rng::stream_rng;
use smc_core::smooth::{
    BackwardMethod, MarginalSmoother, SmoothedMarginals, SmootherSettings, Trajectories,
    sample_trajectories_into,
};
use smc_core::{FilterSettings, History, HistorySettings, ParticleFilter, ParticleSet};

const FRAMES: usize = 20;

struct Ar1;

impl Ar1 {
    const A: f64 = 0.9;
    const Q: f64 = 0.5;
    /// −½ log(2π Q).
    const LOG_NORM: f64 = -0.572_364_942_924_700_1;
}

impl Dynamics for Ar1 {
    type State = f64;
    fn sample<R: Rng + ?Sized>(&self, x: &f64, rng: &mut R) -> f64 {
        let e: f64 = StandardNormal.sample(rng);
        Self::A * x + Self::Q.sqrt() * e
    }
    fn log_density(&self, x: &f64, y: &f64) -> f64 {
        -0.5 * (y - Self::A * x).powi(2) / Self::Q + Self::LOG_NORM
    }
}

impl TransitionDensity for Ar1 {
    type State = f64;
    fn log_density(&self, _frame: usize, x: &f64, y: &f64) -> f64 {
        -0.5 * (y - Self::A * x).powi(2) / Self::Q + Self::LOG_NORM
    }
    fn log_density_bound(&self, _frame: usize, _y: &f64) -> Option<f64> {
        Some(Self::LOG_NORM)
    }
}

/// A recorded bootstrap filter run with `n` particles.
fn history(n: usize) -> History<f64> {
    let mut rng = stream_rng(1, 0, 999);
    let mut x = 0.0;
    let zs: Vec<f64> = (0..FRAMES)
        .map(|_| {
            x = Ar1.sample(&x, &mut rng);
            let e: f64 = StandardNormal.sample(&mut rng);
            x + 0.3f64.sqrt() * e
        })
        .collect();
    let settings = FilterSettings {
        history: Some(HistorySettings::default()),
        ..FilterSettings::default()
    };
    let mut filter = ParticleFilter::new(settings).expect("valid settings");
    let mut init = stream_rng(2, 0, 0);
    let states = (0..n)
        .map(|_| StandardNormal.sample(&mut init))
        .collect::<Vec<f64>>();
    let mut set = ParticleSet::from_states(states).expect("non-empty");
    for (k, z) in zs.into_iter().enumerate() {
        let obs = FnObservation::new(move |x: &f64| {
            -0.5 * (z - x).powi(2) / 0.3 - 0.5 * (2.0 * PI * 0.3).ln()
        });
        filter
            .step_bootstrap(
                &mut set,
                &Ar1,
                &obs,
                &smc_core::ResamplingScheme::Systematic,
                3,
                k as u64,
            )
            .expect("finite weights");
    }
    filter.take_history().expect("recording is on")
}

fn configure<'a>(
    c: &'a mut Criterion,
    name: &str,
) -> criterion::BenchmarkGroup<'a, criterion::measurement::WallTime> {
    let mut group = c.benchmark_group(name);
    group.sample_size(10);
    group.warm_up_time(std::time::Duration::from_millis(500));
    group.measurement_time(std::time::Duration::from_secs(3));
    group
}

fn ffbsm(c: &mut Criterion) {
    let mut group = configure(c, "ffbsm");
    for n in [100usize, 300, 1_000, 3_000] {
        let h = history(n);
        let mut smoother = MarginalSmoother::new(SmootherSettings::default()).expect("valid");
        let mut out = SmoothedMarginals::default();
        group.throughput(Throughput::Elements((n * (FRAMES - 1)) as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &h, |b, h| {
            b.iter(|| {
                let r = smoother.smooth(black_box(h), &Ar1, &mut out);
                black_box((r, out.weights(0).map(|w| w[0])))
            });
        });
    }
    group.finish();
}

fn ffbs(c: &mut Criterion, method: BackwardMethod, name: &str, sizes: &[usize]) {
    let mut group = configure(c, name);
    let settings = SmootherSettings {
        backward: method,
        ..SmootherSettings::default()
    };
    for &n in sizes {
        let h = history(n);
        let mut out = Trajectories::default();
        group.throughput(Throughput::Elements((n * (FRAMES - 1)) as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &h, |b, h| {
            b.iter(|| {
                let r = sample_trajectories_into(black_box(h), &Ar1, n, 5, &settings, &mut out);
                black_box((r, out.indices(0).map(|i| i[0])))
            });
        });
    }
    group.finish();
}

fn ffbs_exact(c: &mut Criterion) {
    ffbs(
        c,
        BackwardMethod::Exact,
        "ffbs_exact",
        &[100, 300, 1_000, 3_000],
    );
}

fn ffbs_rejection(c: &mut Criterion) {
    ffbs(
        c,
        BackwardMethod::Rejection,
        "ffbs_rejection",
        &[100, 1_000, 10_000, 100_000],
    );
}

/// The generated group function is public; this module keeps it out of the missing-docs lint.
#[allow(missing_docs)]
mod group {
    use super::{ffbs_exact, ffbs_rejection, ffbsm};
    use criterion::criterion_group;
    criterion_group!(benches, ffbsm, ffbs_exact, ffbs_rejection);
}
criterion_main!(group::benches);
