//! Temporary profiling harness.
#![allow(missing_docs, clippy::unwrap_used)]
use motion_est::*;
use std::time::Instant;
const W: usize = 320;
const H: usize = 240;
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
    let tex = |x: f64, y: f64| 128.0 + 7.3 * comps.iter().map(|c| (c[0] * x + c[1] * y + c[2]).sin()).sum::<f64>();
    let (cx, cy) = (159.5, 119.5);
    let f0 = (0..W * H).map(|k| tex((k % W) as f64, (k / W) as f64) as f32).collect();
    let f1 = (0..W * H)
        .map(|k| {
            let (x, y) = ((k % W) as f64 - cx, (k / W) as f64 - cy);
            tex(cx + (x - 3.0) / (1.0 + zoom), cy + (y + 2.0) / (1.0 + zoom)) as f32
        })
        .collect();
    (f0, f1)
}
fn main() {
    let which = std::env::args().nth(1).unwrap_or("ell".into());
    let tracking = std::env::args().nth(2).is_some_and(|s| s == "t");
    let (f0, f1) = pair(0.03);
    let v0 = ImageView::new(W, H, &f0).unwrap();
    let v1 = ImageView::new(W, H, &f1).unwrap();
    let settings = if tracking { Settings::tracking() } else { Settings::default() };
    let est = MotionEstimator::new(settings).unwrap();
    let (mut p0, mut p1) = (Pyramid::new(), Pyramid::new());
    est.build_pyramid_into(v0, &mut p0).unwrap();
    est.build_pyramid_into(v1, &mut p1).unwrap();
    let mut ws = Workspace::new();
    let region = match which.as_str() {
        "ell" => Region::Ellipse(Ellipse { cx: 159.5, cy: 119.5, a: 22.0, b: 28.0, theta: 0.0 }),
        "r64" => Region::Rect { x: 128.0, y: 88.0, width: 64.0, height: 64.0 },
        _ => Region::Full,
    };
    let spec = ModelSpec::new(MotionModel::Affine, false);
    let r = est.estimate(&p0, &p1, &region, spec, Some([159.5, 119.5]), &mut ws).unwrap();
    println!("{:?} it {:?} conv {} scale {}", r.params, r.iterations, r.converged, r.scale);
    println!("cov diag {:?}", (0..6).map(|i| r.covariance[i * 7].sqrt()).collect::<Vec<_>>());
    let n = if which == "full" { 200 } else { 3000 };
    let t = Instant::now();
    for _ in 0..n {
        std::hint::black_box(est.estimate(&p0, &p1, &region, spec, Some([159.5, 119.5]), &mut ws).unwrap());
    }
    println!("shared: {:.4} ms/call", t.elapsed().as_secs_f64() * 1e3 / n as f64);
    let mut bufs = FrameBuffers::default();
    let t = Instant::now();
    let n2 = n / 4;
    for _ in 0..n2 {
        std::hint::black_box(est.estimate_images_into(v0, v1, &region, spec, Some([159.5, 119.5]), &mut bufs).unwrap());
    }
    println!("with pyramids: {:.4} ms/call", t.elapsed().as_secs_f64() * 1e3 / n2 as f64);
}
