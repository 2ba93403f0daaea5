//! Throughput of one propagation step of each hidden process over a particle set, and of exact
//! forward filtering.

// `criterion_group!` generates a public function without documentation.
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use dbn_switch::{
    ClutterConfig, ClutterHmm, MarkovChain, OcclusionConfig, OcclusionProcess, StatusConfig,
    StatusHmm,
};
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

fn propagate(c: &mut Criterion) {
    let mut group = c.benchmark_group("propagate");
    let clutter = ClutterHmm::new(&ClutterConfig::default()).expect("default settings are valid");
    let occlusion =
        OcclusionProcess::new(&OcclusionConfig::default()).expect("default settings are valid");
    let status = StatusHmm::new(&StatusConfig::default()).expect("default settings are valid");
    for n in [200usize, 2000] {
        group.throughput(Throughput::Elements(n as u64));
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        let mut clutter_states: Vec<_> = (0..n).map(|_| clutter.sample_initial(&mut rng)).collect();
        group.bench_with_input(BenchmarkId::new("clutter_hmm", n), &n, |b, _| {
            b.iter(|| clutter.propagate_in_place(black_box(&mut clutter_states), &mut rng));
        });
        let mut occlusion_states = vec![occlusion.initial(); n];
        group.bench_with_input(BenchmarkId::new("occlusion", n), &n, |b, _| {
            b.iter(|| occlusion.propagate_in_place(black_box(&mut occlusion_states), &mut rng));
        });
        let mut status_states: Vec<_> = (0..n).map(|_| status.sample_initial(&mut rng)).collect();
        group.bench_with_input(BenchmarkId::new("status_hmm", n), &n, |b, _| {
            b.iter(|| status.propagate_in_place(black_box(&mut status_states), &mut rng));
        });
        let weights = vec![1.0 / n as f64; n];
        group.bench_with_input(BenchmarkId::new("clutter_estimate", n), &n, |b, _| {
            let mut probs = vec![0.0; 3];
            b.iter(|| clutter.estimate_into(black_box(&clutter_states), &weights, &mut probs));
        });
    }
    group.finish();
}

fn forward(c: &mut Criterion) {
    let mut group = c.benchmark_group("forward_filter");
    let chain =
        MarkovChain::new(&ClutterConfig::default().transition).expect("default settings are valid");
    for steps in [100usize, 10_000] {
        let likelihoods: Vec<[f64; 3]> = (0..steps)
            .map(|t| [0.2 + (t % 3) as f64 * 0.1, 0.3, 0.25])
            .collect();
        let mut out = vec![0.0; 3 * steps];
        group.throughput(Throughput::Elements(steps as u64));
        group.bench_with_input(BenchmarkId::new("three_states", steps), &steps, |b, _| {
            b.iter(|| {
                chain.forward_filter_into(&[1.0 / 3.0; 3], black_box(&likelihoods), &mut out)
            });
        });
    }
    group.finish();
}

criterion_group!(benches, propagate, forward);
criterion_main!(benches);
