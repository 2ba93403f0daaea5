//! The layers a frame is composited from: the objects' appearance (interior texture and outline
//! contrast), the occluder, and the independent random stream of each layer.

use std::f64::consts::PI;

use rand::Rng;

use crate::params::OccluderParams;
use crate::texture::smooth_noise;
/// Independent random streams derived from the seed, so that changing one layer's parameters
/// does not reshuffle the others.
#[derive(Clone, Copy)]
pub(super) enum Stream {
    Background = 1,
    Target = 2,
    Distractor = 3,
    Occluder = 4,
    Trajectory = 5,
    Noise = 6,
}

/// SplitMix64 finaliser: decorrelates (seed, stream, frame) into a generator seed.
pub(super) fn mix(seed: u64, stream: Stream, frame: u64) -> u64 {
    let mut z = seed
        .wrapping_add((stream as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15))
        .wrapping_add(frame.wrapping_mul(0xD1B5_4A32_D192_ED03));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Half-extent of the target texture in reference units: the unit disc plus the largest head
/// turn shift plus a border.
const TEX_EXTENT: f64 = 2.2;
/// Target texture samples per reference unit.
const TEX_RES: f64 = 40.0;
/// Entries of the outline-contrast table over the reference angle.
const KAPPA_LEN: usize = 512;

/// An object's appearance: interior texture in reference coordinates and the outline contrast
/// factor κ(φ) over the reference angle.
#[derive(Debug, Clone)]
pub(super) struct Appearance {
    size: usize,
    tex: Vec<f32>,
    kappa: Vec<f32>,
}

impl Appearance {
    pub(super) fn new<R: Rng + ?Sized>(
        rng: &mut R,
        grey: f64,
        amplitude: f64,
        scale: f64,
        kappa_min: f64,
        stretches: usize,
        half_width: f64,
    ) -> Self {
        let size = (2.0 * TEX_EXTENT * TEX_RES).ceil() as usize + 1;
        let noise = smooth_noise(rng, size, size, (scale * TEX_RES).max(2.0));
        let tex = noise
            .iter()
            .map(|n| (grey + amplitude * f64::from(*n)) as f32)
            .collect();
        let centres: Vec<f64> = (0..stretches)
            .map(|_| rng.random::<f64>() * 2.0 * PI)
            .collect();
        let kappa = (0..KAPPA_LEN)
            .map(|i| {
                let phi = -PI + (i as f64 + 0.5) * 2.0 * PI / KAPPA_LEN as f64;
                // A stretch is a smooth dip of κ to kappa_min, flat over its half-width and
                // fading in over as much again.
                let dip = centres
                    .iter()
                    .map(|c| {
                        let d = (phi - c + PI).rem_euclid(2.0 * PI) - PI;
                        let t = ((d.abs() - half_width) / half_width.max(1e-6)).clamp(0.0, 1.0);
                        1.0 - t * t * (3.0 - 2.0 * t)
                    })
                    .fold(0.0f64, f64::max);
                (1.0 - (1.0 - kappa_min) * dip) as f32
            })
            .collect();
        Self { size, tex, kappa }
    }

    #[inline]
    pub(super) fn texture(&self, u: f64, v: f64) -> f64 {
        let max = (self.size - 2) as f64;
        let x = ((u + TEX_EXTENT) * TEX_RES).clamp(0.0, max);
        let y = ((v + TEX_EXTENT) * TEX_RES).clamp(0.0, max);
        let (ix, iy) = (x as usize, y as usize);
        let (fx, fy) = (x - ix as f64, y - iy as f64);
        let i = iy * self.size + ix;
        let t = &self.tex;
        let top = f64::from(t[i]) * (1.0 - fx) + f64::from(t[i + 1]) * fx;
        let bot = f64::from(t[i + self.size]) * (1.0 - fx) + f64::from(t[i + self.size + 1]) * fx;
        top * (1.0 - fy) + bot * fy
    }

    #[inline]
    pub(super) fn kappa(&self, u: f64, v: f64) -> f64 {
        let phi = v.atan2(u);
        let i = (((phi + PI) / (2.0 * PI)) * KAPPA_LEN as f64) as usize;
        f64::from(self.kappa[i.min(KAPPA_LEN - 1)])
    }
}

/// The opaque occluder: an axis-aligned rectangle in frame coordinates with its own texture.
#[derive(Debug, Clone)]
pub(super) struct Occluder {
    /// (x0, y0, x1, y1) in frame pixels.
    pub(super) rect: [f64; 4],
    /// The texture, row-major, `tex_w` wide.
    pub(super) tex: Vec<f32>,
    pub(super) tex_w: usize,
    /// The frame pixel of the texture's first sample.
    pub(super) ox: usize,
    pub(super) oy: usize,
}

fn overlap(a0: f64, a1: f64, b0: f64, b1: f64) -> f64 {
    (a1.min(b1) - a0.max(b0)).max(0.0)
}

impl Occluder {
    /// Fraction of pixel (x, y) covered by the occluder (exact box-filter coverage).
    #[inline]
    pub(super) fn alpha(&self, x: f64, y: f64) -> f64 {
        let [x0, y0, x1, y1] = self.rect;
        overlap(x - 0.5, x + 0.5, x0, x1) * overlap(y - 0.5, y + 0.5, y0, y1)
    }

    /// The occluder of `o` in a `w` × `h` frame, its texture drawn from `rng`.
    pub(super) fn new<R: Rng + ?Sized>(
        o: &OccluderParams,
        w: usize,
        h: usize,
        rng: &mut R,
    ) -> Self {
        let cx = o.centre[0] * (w as f64 - 1.0);
        let cy = o.centre[1] * (h as f64 - 1.0);
        let rect = [
            cx - 0.5 * o.size[0],
            cy - 0.5 * o.size[1],
            cx + 0.5 * o.size[0],
            cy + 0.5 * o.size[1],
        ];
        let ox = (rect[0] - 1.0).floor().max(0.0) as usize;
        let oy = (rect[1] - 1.0).floor().max(0.0) as usize;
        let tex_w = (o.size[0].ceil() as usize + 3)
            .min(w.saturating_sub(ox))
            .max(1);
        let tex_h = (o.size[1].ceil() as usize + 3)
            .min(h.saturating_sub(oy))
            .max(1);
        let noise = smooth_noise(rng, tex_w, tex_h, 6.0);
        // Vertical stripes (period 9 px) plus smooth noise: an edge-rich occluder, as a
        // real one would be.
        let tex = (0..tex_w * tex_h)
            .map(|i| {
                let x = (i % tex_w) as f64;
                let s = (2.0 * PI * x / 9.0).sin();
                (o.grey + o.texture_amplitude * (0.6 * s + 0.4 * f64::from(noise[i]))) as f32
            })
            .collect();
        Occluder {
            rect,
            tex,
            tex_w,
            ox,
            oy,
        }
    }
}
