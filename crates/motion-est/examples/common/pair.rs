//! The synthetic 320×240 pair shared by the benchmark (`benches/motion.rs`) and the profiling
//! driver (`examples/motion_profile.rs`), included in both with `#[path]`.

use motion_est::Region;
use vision_core::Ellipse;

pub const W: usize = 320;
pub const H: usize = 240;

/// The tracker's use: an ellipse of semi-axes 22×28 px (an object of ~44×56 px, 1935 pixels),
/// centred on the frame centre, which is also the origin of its motion.
pub const TRACK_CENTRE: [f64; 2] = [159.5, 119.5];

/// The tracking ellipse's region.
pub fn tracking_ellipse() -> Region<'static> {
    Region::Ellipse(Ellipse {
        cx: TRACK_CENTRE[0],
        cy: TRACK_CENTRE[1],
        a: 22.0,
        b: 28.0,
        angle: 0.0,
    })
}

/// A warm start 0.5 px off the pair's true motion (3, −2) + 3 % zoom, in the layout of
/// `MotionEstimate::params` (affine, no offset).
pub const WARM_GUESS: [f64; 6] = [2.5, 0.03, 0.0, -1.6, 0.0, 0.03];

/// A textured pair: frame 1 is frame 0 displaced by (3, −2) px plus `zoom`·(x, y) about the centre
/// (zoom = 0 for the translation model, 0.03 — a 3 % zoom — for the others, so every model fits).
pub fn pair(zoom: f64) -> (Vec<f32>, Vec<f32>) {
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
