//! Motion estimation cost: pyramid build, and one estimate per region size and model,
//! including the pyramids of both frames, on a 320×240 synthetic pair.
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use motion_est::{
    FrameBuffers, ModelSpec, MotionEstimator, MotionModel, Pyramid, Region, Settings, Workspace,
};
use vision_core::GreyImage;

#[path = "../examples/common/pair.rs"]
mod pair;
use pair::{H, TRACK_CENTRE, W, WARM_GUESS, pair, tracking_ellipse};

fn region(size: usize) -> Region<'static> {
    if size >= W {
        Region::Full
    } else {
        Region::Rect {
            x: (W - size) as f64 / 2.0,
            y: (H - size) as f64 / 2.0,
            width: size as f64,
            height: size as f64,
        }
    }
}

/// Both frames' pyramids of the 0.03-noise pair, built once.
fn shared_pyramids(est: &MotionEstimator) -> (Pyramid, Pyramid) {
    let (f0, f1) = pair(0.03);
    let v0 = GreyImage::new(W, H, &f0).unwrap();
    let v1 = GreyImage::new(W, H, &f1).unwrap();
    let (mut p0, mut p1) = (Pyramid::new(), Pyramid::new());
    est.build_pyramid_into(v0, &mut p0).unwrap();
    est.build_pyramid_into(v1, &mut p1).unwrap();
    (p0, p1)
}

fn bench_pyramid(c: &mut Criterion) {
    let (f0, _) = pair(0.03);
    let v0 = GreyImage::new(W, H, &f0).unwrap();
    let est = MotionEstimator::new(Settings::default()).unwrap();

    let mut g = c.benchmark_group("pyramid");
    g.throughput(Throughput::Elements((W * H) as u64));
    let mut pyr = Pyramid::new();
    g.bench_function(BenchmarkId::new("build", "320x240"), |b| {
        b.iter(|| est.build_pyramid_into(black_box(v0), &mut pyr).unwrap())
    });
    g.finish();
}

/// One estimate including both frames' pyramids over the region's box plus margin.
fn bench_estimate_with_pyramids(c: &mut Criterion) {
    let (f0, f1) = pair(0.03);
    let (t0, t1) = pair(0.0);
    let v0 = GreyImage::new(W, H, &f0).unwrap();
    let v1 = GreyImage::new(W, H, &f1).unwrap();
    let (tv0, tv1) = (
        GreyImage::new(W, H, &t0).unwrap(),
        GreyImage::new(W, H, &t1).unwrap(),
    );
    let est = MotionEstimator::new(Settings::default()).unwrap();

    let mut g = c.benchmark_group("estimate_with_pyramids");
    let mut bufs = FrameBuffers::default();
    for model in [
        MotionModel::Translation,
        MotionModel::Scale,
        MotionModel::Affine,
    ] {
        let (f0v, f1v) = if model == MotionModel::Translation {
            (tv0, tv1)
        } else {
            (v0, v1)
        };
        for size in [32usize, 64, 128, W] {
            let r = region(size);
            let pixels = if size >= W { W * H } else { size * size };
            g.throughput(Throughput::Elements(pixels as u64));
            let label = if size >= W {
                "320x240".to_string()
            } else {
                format!("{size}x{size}")
            };
            g.bench_function(BenchmarkId::new(model.name(), label), |b| {
                b.iter(|| {
                    est.estimate_images_into(
                        black_box(f0v),
                        black_box(f1v),
                        &r,
                        ModelSpec::new(model, false),
                        None,
                        &mut bufs,
                    )
                    .or_else(motion_est::Error::into_unreliable)
                    .unwrap()
                })
            });
        }
    }
    g.finish();
}

/// Many regions per frame pair: pyramids built once, estimate only.
fn bench_estimate_shared_pyramids(c: &mut Criterion) {
    let est = MotionEstimator::new(Settings::default()).unwrap();
    let (p0, p1) = shared_pyramids(&est);
    let mut g = c.benchmark_group("estimate_shared_pyramids");
    let mut ws = Workspace::new();
    for size in [32usize, 64, 128] {
        let r = region(size);
        g.throughput(Throughput::Elements((size * size) as u64));
        g.bench_function(BenchmarkId::new("affine", format!("{size}x{size}")), |b| {
            b.iter(|| {
                est.estimate(
                    &p0,
                    &p1,
                    &r,
                    ModelSpec::new(MotionModel::Affine, false),
                    None,
                    &mut ws,
                )
                .or_else(motion_est::Error::into_unreliable)
                .unwrap()
            })
        });
    }
    g.finish();
}

/// The tracker's use (`pair::tracking_ellipse`) on shared full-frame pyramids, affine.
fn bench_tracking_ellipse(c: &mut Criterion) {
    let est = MotionEstimator::new(Settings::default()).unwrap();
    let (p0, p1) = shared_pyramids(&est);
    let mut ws = Workspace::new();
    let mut g = c.benchmark_group("tracking_ellipse_22x28");
    let ell = tracking_ellipse();
    g.throughput(Throughput::Elements(1935));
    g.bench_function(BenchmarkId::new("affine", "default"), |b| {
        b.iter(|| {
            est.estimate(
                &p0,
                &p1,
                black_box(&ell),
                ModelSpec::new(MotionModel::Affine, false),
                Some(TRACK_CENTRE),
                &mut ws,
            )
            .or_else(motion_est::Error::into_unreliable)
            .unwrap()
        })
    });
    let est_t = MotionEstimator::new(Settings::tracking()).unwrap();
    g.bench_function(BenchmarkId::new("affine", "tracking"), |b| {
        b.iter(|| {
            est_t
                .estimate(
                    &p0,
                    &p1,
                    black_box(&ell),
                    ModelSpec::new(MotionModel::Affine, false),
                    Some(TRACK_CENTRE),
                    &mut ws,
                )
                .or_else(motion_est::Error::into_unreliable)
                .unwrap()
        })
    });
    g.bench_function(BenchmarkId::new("affine", "tracking_warm"), |b| {
        b.iter(|| {
            est_t
                .estimate_from(
                    &p0,
                    &p1,
                    black_box(&ell),
                    ModelSpec::new(MotionModel::Affine, false),
                    Some(TRACK_CENTRE),
                    Some(&WARM_GUESS),
                    &mut ws,
                )
                .or_else(motion_est::Error::into_unreliable)
                .unwrap()
        })
    });
    g.finish();
}

criterion_group!(
    benches,
    bench_pyramid,
    bench_estimate_with_pyramids,
    bench_estimate_shared_pyramids,
    bench_tracking_ellipse
);
criterion_main!(benches);
