//! Log-likelihood of 200 hypotheses on a 320×240 frame, with 15 and 40 measurement lines, for
//! each of the three likelihoods (sequential batches), and the rayon batches of Odobez and the
//! occlusion likelihood.

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use std::hint::black_box;

use contour_obs::{
    LineSettings, OcclusionLikelihood, OdobezLikelihood, OdobezSettings, Template, WuLikelihood,
    WuSettings,
};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use vision_core::GreyImage;

#[path = "../examples/common/frame.rs"]
mod frame;
use frame::{H, N, W, scene};

/// The three likelihoods on `lines`, built outside the timed loops.
fn models(lines: LineSettings) -> (OdobezLikelihood, WuLikelihood, OcclusionLikelihood) {
    let od = OdobezLikelihood::new(
        OdobezSettings {
            lines,
            ..Default::default()
        },
        &Template::UnitCircle,
    );
    let wu_s = WuSettings {
        lines,
        ..Default::default()
    };
    match (
        od,
        WuLikelihood::new(wu_s, &Template::UnitCircle),
        OcclusionLikelihood::new(wu_s, &Template::UnitCircle),
    ) {
        (Ok(a), Ok(b), Ok(c)) => (a, b, c),
        _ => panic!("bad settings"),
    }
}

fn bench(c: &mut Criterion) {
    let s = scene();
    let image = match GreyImage::new(W, H, &s.data) {
        Ok(v) => v,
        Err(e) => panic!("bad frame: {e}"),
    };
    let (poses, lambdas, gammas) = (s.poses, s.lambdas, s.gammas);
    let mut out = vec![0.0; N];
    let mut group = c.benchmark_group("log_likelihood_200_hypotheses");
    group.throughput(Throughput::Elements(N as u64));
    for n_lines in [15usize, 40] {
        let lines = LineSettings {
            n_lines,
            ..LineSettings::default()
        };
        let run = |r: contour_obs::Result<()>| {
            if let Err(e) = r {
                panic!("{e}");
            }
        };
        let (od, wu, occ) = models(lines);
        let mut ws = match od.workspace() {
            Ok(ws) => ws,
            Err(e) => panic!("{e}"),
        };
        group.bench_with_input(
            BenchmarkId::new("odobez_eq19", n_lines),
            &n_lines,
            |b, _| {
                b.iter(|| {
                    run(od.log_likelihood_batch(
                        &mut ws,
                        black_box(&image),
                        black_box(&poses),
                        &mut out,
                    ))
                })
            },
        );
        group.bench_with_input(BenchmarkId::new("wu_eq1_6", n_lines), &n_lines, |b, _| {
            b.iter(|| {
                run(wu.log_likelihood_batch(
                    &mut ws,
                    black_box(&image),
                    black_box(&poses),
                    &lambdas,
                    &mut out,
                ))
            })
        });
        group.bench_with_input(
            BenchmarkId::new("occlusion_eq11_12", n_lines),
            &n_lines,
            |b, _| {
                b.iter(|| {
                    run(occ.log_likelihood_batch(
                        &mut ws,
                        black_box(&image),
                        black_box(&poses),
                        &lambdas,
                        &gammas,
                        &mut out,
                    ))
                })
            },
        );
        group.bench_with_input(
            BenchmarkId::new("odobez_eq19_par", n_lines),
            &n_lines,
            |b, _| {
                b.iter(|| {
                    run(od.log_likelihood_batch_par(black_box(&image), black_box(&poses), &mut out))
                })
            },
        );
        group.bench_with_input(
            BenchmarkId::new("occlusion_eq11_12_par", n_lines),
            &n_lines,
            |b, _| {
                b.iter(|| {
                    run(occ.log_likelihood_batch_par(
                        black_box(&image),
                        black_box(&poses),
                        &lambdas,
                        &gammas,
                        &mut out,
                    ))
                })
            },
        );
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
