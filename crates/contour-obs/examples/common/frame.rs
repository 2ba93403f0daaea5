//! The benchmark's frame and hypotheses, shared by `benches/likelihoods.rs` and
//! `examples/obs_profile.rs`: a bright ellipse on a 320×240 background of random discs
//! (clutter), and 200 ellipse hypotheses around it with per-hypothesis λ and γ.

use contour_obs::Affine2;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

pub const W: usize = 320;
pub const H: usize = 240;
pub const N: usize = 200;

/// The frame (grey levels 0–255, row-major), the poses, λ and γ of every hypothesis.
pub struct Scene {
    pub data: Vec<f32>,
    pub poses: Vec<Affine2>,
    pub lambdas: Vec<f64>,
    pub gammas: Vec<f64>,
}

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

/// The benchmark's scene (seed 1).
pub fn scene() -> Scene {
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let data = frame(&mut rng);
    let poses = (0..N)
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
    let lambdas = (0..N).map(|i| 0.01 + 0.001 * i as f64).collect();
    let gammas = (0..N).map(|i| i as f64 / N as f64).collect();
    Scene {
        data,
        poses,
        lambdas,
        gammas,
    }
}
