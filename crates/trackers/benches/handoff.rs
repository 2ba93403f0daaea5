//! What `filter.parallel` can gain on this machine: two equal pieces of work, about 100 µs each,
//! run one after the other or as a `rayon::join` on a pool of two threads, and the same join
//! after 1 ms of work on the calling thread alone (as between the parallel parts of one tracker
//! update, where the other thread has gone to sleep). The difference between the two joins is
//! the price of waking a sleeping thread, paid by every parallel part of an update.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_main};

/// About `n` nanoseconds of arithmetic on one core (a dependent chain of square roots).
fn work(n: u64) -> f64 {
    (0..n / 2).fold(0.0, |s, i| s + (i as f64).sqrt())
}

/// The two pieces' work and the lone work before them (nanoseconds, roughly).
const PIECE: u64 = 100_000;
const ALONE: u64 = 1_000_000;

fn handoff(c: &mut Criterion) {
    let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(2).build() else {
        return;
    };
    let mut group = c.benchmark_group("handoff");
    group.sample_size(30);
    for gap in [0, ALONE] {
        let id = |what: &str| BenchmarkId::new(what, format!("after_{}us_alone", gap / 1000));
        group.bench_function(id("one_thread"), |b| {
            b.iter(|| black_box(work(gap)) + black_box(work(PIECE)) + black_box(work(PIECE)));
        });
        group.bench_function(id("join"), |b| {
            pool.install(|| {
                b.iter(|| {
                    let alone = black_box(work(gap));
                    let (x, y) = rayon::join(|| work(PIECE), || work(PIECE));
                    alone + black_box(x) + black_box(y)
                });
            });
        });
    }
    group.finish();
}

#[allow(missing_docs)]
mod group {
    use criterion::criterion_group;
    criterion_group!(benches, super::handoff);
}

criterion_main!(group::benches);
