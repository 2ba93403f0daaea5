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

/// A cluttered test image: random grey discs (grey 0–255, radius drawn from `radii`) on a
/// uniform background, then a bright (230) axis-aligned ellipse — edges of every strength, many
/// near the detection threshold. Shared by the benchmark scene and `tests/fast_paths.rs`.
pub struct DiscClutter {
    pub width: usize,
    pub height: usize,
    pub background: f32,
    pub discs: usize,
    pub radii: std::ops::Range<f64>,
    /// Centre x, centre y, semi-axis along x, semi-axis along y.
    pub ellipse: [f64; 4],
}

impl DiscClutter {
    /// The image, row-major, drawing the discs from `rng`.
    pub fn render(&self, rng: &mut Pcg64Mcg) -> Vec<f32> {
        let (w, h) = (self.width, self.height);
        let mut img = vec![self.background; w * h];
        for _ in 0..self.discs {
            let (cx, cy, r) = (
                rng.random_range(0.0..w as f64),
                rng.random_range(0.0..h as f64),
                rng.random_range(self.radii.clone()),
            );
            let g = rng.random_range(0.0..255.0) as f32;
            for y in 0..h {
                for x in 0..w {
                    if (x as f64 - cx).hypot(y as f64 - cy) <= r {
                        img[y * w + x] = g;
                    }
                }
            }
        }
        let [ex, ey, ea, eb] = self.ellipse;
        for y in 0..h {
            for x in 0..w {
                let (u, v) = ((x as f64 - ex) / ea, (y as f64 - ey) / eb);
                if u * u + v * v <= 1.0 {
                    img[y * w + x] = 230.0;
                }
            }
        }
        img
    }
}

/// The benchmark's scene (seed 1).
pub fn scene() -> Scene {
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let data = DiscClutter {
        width: W,
        height: H,
        background: 100.0,
        discs: 400,
        radii: 2.0..8.0,
        ellipse: [160.0, 120.0, 40.0, 28.0],
    }
    .render(&mut rng);
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
