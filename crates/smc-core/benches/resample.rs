//! Resampling cost per particle: every scheme at N = M = 10³ … 10⁶.
//!
//! Run with `cargo bench -p smc-core --bench resample`. Criterion's throughput is reported in
//! elements (particles) per second; ns/particle = 10⁹ / that figure.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_main};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_pcg::Pcg64Mcg;
use smc_core::weights::normalize_log_weights;
use smc_core::{Resampler, ResamplingScheme};

/// Normalised weights exp(g) with g ~ N(0, 1): a moderately uneven set (ESS ≈ N / e).
fn weights(n: usize) -> Vec<f64> {
    let mut rng = Pcg64Mcg::seed_from_u64(n as u64);
    let mut log_w: Vec<f64> = (0..n).map(|_| StandardNormal.sample(&mut rng)).collect();
    let mut w = Vec::with_capacity(n);
    // The log weights are finite, so normalisation cannot fail.
    let _ = normalize_log_weights(&mut log_w, &mut w);
    w
}

fn resampling(c: &mut Criterion) {
    let mut group = c.benchmark_group("resample");
    for n in [1_000usize, 10_000, 100_000, 1_000_000] {
        let w = weights(n);
        let mut ancestors = Vec::with_capacity(n);
        let mut rng = Pcg64Mcg::seed_from_u64(7);
        group.throughput(Throughput::Elements(n as u64));
        for scheme in ResamplingScheme::ALL {
            group.bench_with_input(BenchmarkId::new(scheme.name(), n), &w, |b, w| {
                b.iter(|| {
                    let r = scheme.resample(black_box(w), n, &mut rng, &mut ancestors);
                    black_box((r, ancestors.last().copied()))
                });
            });
        }
    }
    group.finish();
}

fn normalisation(c: &mut Criterion) {
    let mut group = c.benchmark_group("normalize_log_weights");
    for n in [1_000usize, 1_000_000] {
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        let source: Vec<f64> = (0..n).map(|_| StandardNormal.sample(&mut rng)).collect();
        let mut log_w = source.clone();
        let mut w = Vec::with_capacity(n);
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &source, |b, source| {
            b.iter(|| {
                log_w.copy_from_slice(source);
                black_box(normalize_log_weights(&mut log_w, &mut w))
            });
        });
    }
    group.finish();
}

/// The generated group function is public; this module keeps it out of the missing-docs lint.
#[allow(missing_docs)]
mod group {
    use super::{normalisation, resampling};
    use criterion::criterion_group;
    criterion_group!(benches, resampling, normalisation);
}
criterion_main!(group::benches);
