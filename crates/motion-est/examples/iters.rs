//! Motion estimation cost (issue 3): pyramid build, and one estimate per region size and model,
//! including the pyramids of both frames, on a 320×240 synthetic pair.
#![allow(missing_docs, clippy::unwrap_used)]

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput};
use motion_est::{
    Ellipse, FrameBuffers, ImageView, ModelSpec, MotionEstimator, MotionModel, Pyramid, Region,
    Settings, Workspace,
};

const W: usize = 320;
const H: usize = 240;

/// A textured pair: frame 1 is frame 0 displaced by (3, −2) px plus `zoom`·(x, y) about the centre
/// (zoom = 0 for the translation model, 0.03 — a 3 % zoom — for the others, so every model fits).
fn pair(zoom: f64) -> (Vec<f32>, Vec<f32>) {
    let comps: Vec<[f64; 3]> = (0..60)
        .map(|i| {
            let f = i as f64;
            let lambda = 3.0 + 37.0 * ((f * 0.618_034) % 1.0);
            let dir = f * 2.399_963;
            let k = std::f64::consts::TAU / lambda;
            [k * dir.cos(), k * dir.sin(), f * 1.3]
        })
        .collect();
    let tex = |x: f64, y: f64| {
        128.0
            + 7.3
                * comps
                    .iter()
                    .map(|c| (c[0] * x + c[1] * y + c[2]).sin())
                    .sum::<f64>()
    };
    let (cx, cy) = (159.5, 119.5);
    let f0 = (0..W * H)
        .map(|k| tex((k % W) as f64, (k / W) as f64) as f32)
        .collect();
    let f1 = (0..W * H)
        .map(|k| {
            let (x, y) = ((k % W) as f64 - cx, (k / W) as f64 - cy);
            // Inverse of d = (3 + zoom·x, −2 + zoom·y).
            tex(cx + (x - 3.0) / (1.0 + zoom), cy + (y + 2.0) / (1.0 + zoom)) as f32
        })
        .collect();
    (f0, f1)
}

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

fn main() {
    let (f0, f1) = pair(0.03);
    let v0 = ImageView::new(W, H, &f0).unwrap();
    let v1 = ImageView::new(W, H, &f1).unwrap();
    let _ = (
        region(32),
        Workspace::new(),
        FrameBuffers::default(),
        BenchmarkId::new("a", 1),
        Throughput::Elements(1),
    );
    let _ = black_box(1);
    let _: Option<fn(&mut Criterion)> = None;
    for st in [Settings::default(), Settings::tracking()] {
        let est = MotionEstimator::new(st).unwrap();
        let (mut p0, mut p1) = (Pyramid::new(), Pyramid::new());
        est.build_pyramid_into(v0, &mut p0).unwrap();
        est.build_pyramid_into(v1, &mut p1).unwrap();
        let ell = Region::Ellipse(Ellipse {
            cx: 159.5,
            cy: 119.5,
            a: 22.0,
            b: 28.0,
            theta: 0.0,
        });
        let mut ws = Workspace::new();
        let r = est
            .estimate(
                &p0,
                &p1,
                &ell,
                ModelSpec::new(MotionModel::Affine, false),
                Some([159.5, 119.5]),
                &mut ws,
            )
            .unwrap();
        println!("{:?} {:?}", r.iterations, r.params);
        let r = est
            .estimate_images(
                v0,
                v1,
                &Region::Full,
                ModelSpec::new(MotionModel::Affine, false),
                None,
            )
            .unwrap();
        println!("full {:?}", r.iterations);
        let r = est
            .estimate_images(
                v0,
                v1,
                &region(64),
                ModelSpec::new(MotionModel::Affine, false),
                None,
            )
            .unwrap();
        println!("64 {:?}", r.iterations);
    }
}
