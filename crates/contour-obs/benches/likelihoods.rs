//! Log-likelihood of 200 hypotheses on a 320×240 frame, with 15 and 40 measurement lines, for
//! each of the three likelihoods (sequential batches), and the rayon batches of Odobez and the
//! occlusion likelihood.

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use std::hint::black_box;

use contour_obs::{
    Affine2, GreyView, LineSettings, OcclusionLikelihood, OdobezLikelihood, OdobezSettings,
    Template, WuLikelihood, WuSettings,
};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

const W: usize = 320;
const H: usize = 240;
const N: usize = 200;

/// A bright ellipse on a background of random discs (clutter), grey levels 0–255.
fn frame(rng: &mut Pcg64Mcg) -> Vec<f32> {
    let mut img = vec![100.0f32; W * H];
    for _ in 0..400 {
        let (cx, cy, r) = (
            rng.random_range(0.0..W as f64),
            rng.random_range(0.0..H as f64),
            rng.random_range(2.0..8.0),
        );
        let g = rng.random_range(0.0..255.0) as f32;
        for y in 0..H {
            for x in 0..W {
                if (x as f64 - cx).hypot(y as f64 - cy) <= r {
                    img[y * W + x] = g;
                }
            }
        }
    }
    for y in 0..H {
        for x in 0..W {
            let (u, v) = ((x as f64 - 160.0) / 40.0, (y as f64 - 120.0) / 28.0);
            if u * u + v * v <= 1.0 {
                img[y * W + x] = 230.0;
            }
        }
    }
    img
}

fn bench(c: &mut Criterion) {
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let data = frame(&mut rng);
    let image = match GreyView::new(W, H, &data) {
        Ok(v) => v,
        Err(e) => panic!("bad frame: {e}"),
    };
    let poses: Vec<Affine2> = (0..N)
        .map(|_| {
            Affine2::from_ellipse(
                160.0 + rng.random_range(-8.0..8.0),
                120.0 + rng.random_range(-8.0..8.0),
                40.0 * rng.random_range(0.9..1.1),
                28.0 * rng.random_range(0.9..1.1),
                rng.random_range(-0.1..0.1),
            )
        })
        .collect();
    let lambdas: Vec<f64> = (0..N).map(|i| 0.01 + 0.001 * i as f64).collect();
    let gammas: Vec<f64> = (0..N).map(|i| i as f64 / N as f64).collect();
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
        let (od, wu, occ) = match (
            od,
            WuLikelihood::new(wu_s, &Template::UnitCircle),
            OcclusionLikelihood::new(wu_s, &Template::UnitCircle),
        ) {
            (Ok(a), Ok(b), Ok(c)) => (a, b, c),
            _ => panic!("bad settings"),
        };
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
