//! Profiling driver: `cargo run --release -p motion-est --example motion_profile -- CASE N [THREADS]`
//! with CASE `full` (full-frame affine incl. both pyramids, as the bench), `track` (the bench's
//! 22×28 ellipse with `Settings::tracking()` on shared pyramids) or `warm` (the same with the
//! bench's warm start). Prints wall time per estimate.
#![allow(missing_docs, clippy::unwrap_used)]

use std::hint::black_box;
use std::time::Instant;

use motion_est::{
    FrameBuffers, ModelSpec, MotionEstimator, MotionModel, Pyramid, Region, Settings, Workspace,
};
use vision_core::GreyImage;

#[path = "common/pair.rs"]
mod pair;
use pair::{H, TRACK_CENTRE, W, WARM_GUESS, pair, tracking_ellipse};

/// Runs `f` `n` times in 20 batches; the minimum and median batch means (ms): the minimum is
/// the figure least affected by other processes on a shared machine.
fn batches(n: usize, mut f: impl FnMut()) -> String {
    let per = (n / 20).max(1);
    let mut means: Vec<f64> = (0..20)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..per {
                f();
            }
            t.elapsed().as_secs_f64() * 1e3 / per as f64
        })
        .collect();
    means.sort_by(f64::total_cmp);
    format!("min {:.4} ms, median {:.4} ms", means[0], means[10])
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let case = args.get(1).map_or("full", String::as_str).to_string();
    let n: usize = args.get(2).map_or(100, |s| s.parse().unwrap());
    let threads: usize = args.get(3).map_or(0, |s| s.parse().unwrap());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let (f0, f1) = pair(0.03);
    let v0 = GreyImage::new(W, H, &f0).unwrap();
    let v1 = GreyImage::new(W, H, &f1).unwrap();
    let spec = ModelSpec::new(MotionModel::Affine, false);
    pool.install(|| match case.as_str() {
        "full" => {
            let est = MotionEstimator::new(Settings::default()).unwrap();
            let mut bufs = FrameBuffers::default();
            let times = batches(n, || {
                black_box(
                    est.estimate_images_into(v0, v1, &Region::Full, spec, None, &mut bufs)
                        .or_else(motion_est::Error::into_unreliable)
                        .unwrap(),
                );
            });
            println!("full: {times}");
            let r = est
                .estimate_images_into(v0, v1, &Region::Full, spec, None, &mut bufs)
                .or_else(motion_est::Error::into_unreliable)
                .unwrap();
            let h = r
                .params
                .iter()
                .chain(&r.covariance)
                .fold(0u64, |h, v| h.rotate_left(7) ^ v.to_bits());
            println!("result bits hash {h:016x}");
        }
        _ => {
            // `track`: cold start; `warm`: the bench's warm start 0.5 px off the true motion.
            let est = MotionEstimator::new(Settings::tracking()).unwrap();
            let (mut p0, mut p1) = (Pyramid::new(), Pyramid::new());
            est.build_pyramid_into(v0, &mut p0).unwrap();
            est.build_pyramid_into(v1, &mut p1).unwrap();
            let mut ws = Workspace::new();
            let ell = tracking_ellipse();
            let initial = (case == "warm").then_some(&WARM_GUESS[..]);
            let mut run = || {
                est.estimate_from(&p0, &p1, &ell, spec, Some(TRACK_CENTRE), initial, &mut ws)
                    .or_else(motion_est::Error::into_unreliable)
                    .unwrap()
            };
            let t = Instant::now();
            for _ in 0..n {
                black_box(run());
            }
            println!(
                "{case}: {:.4} ms",
                t.elapsed().as_secs_f64() * 1e3 / n as f64
            );
            let r = run();
            let h = r
                .params
                .iter()
                .chain(&r.covariance)
                .fold(0u64, |h, v| h.rotate_left(7) ^ v.to_bits());
            println!(
                "iterations {:?}, converged {}, scale {:.6}, params {:?}",
                r.iterations, r.converged, r.scale, r.params
            );
            println!("result bits hash {h:016x}");
        }
    });
}
