//! Smooth random textures and anti-aliased clutter structures.

use rand::Rng;

/// Smooth value noise in [−1, 1]: random values on a grid of spacing `scale` px, interpolated
/// with a C¹ smoothstep. Its gradient is at most ≈ 1.5·2/scale per px (per unit amplitude), which
/// is how the callers keep textures below the edge threshold.
pub fn smooth_noise<R: Rng + ?Sized>(
    rng: &mut R,
    width: usize,
    height: usize,
    scale: f64,
) -> Vec<f32> {
    let gw = (width as f64 / scale).ceil() as usize + 2;
    let gh = (height as f64 / scale).ceil() as usize + 2;
    let grid: Vec<f64> = (0..gw * gh)
        .map(|_| rng.random::<f64>() * 2.0 - 1.0)
        .collect();
    let smooth = |t: f64| t * t * (3.0 - 2.0 * t);
    let mut out = vec![0.0f32; width * height];
    for y in 0..height {
        let gy = y as f64 / scale;
        let iy = gy.floor() as usize;
        let fy = smooth(gy - iy as f64);
        for x in 0..width {
            let gx = x as f64 / scale;
            let ix = gx.floor() as usize;
            let fx = smooth(gx - ix as f64);
            let g = |i: usize, j: usize| grid[j * gw + i];
            let top = g(ix, iy) * (1.0 - fx) + g(ix + 1, iy) * fx;
            let bot = g(ix, iy + 1) * (1.0 - fx) + g(ix + 1, iy + 1) * fx;
            out[y * width + x] = (top * (1.0 - fy) + bot * fy) as f32;
        }
    }
    out
}

/// One clutter structure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// A disc.
    Disc {
        /// Centre.
        c: [f64; 2],
        /// Radius.
        r: f64,
    },
    /// An elliptical blob.
    Blob {
        /// Centre.
        c: [f64; 2],
        /// Semi-axes.
        ab: [f64; 2],
        /// Orientation.
        angle: f64,
    },
    /// A thick segment (capsule).
    Bar {
        /// One end.
        p0: [f64; 2],
        /// The other end.
        p1: [f64; 2],
        /// Half the thickness.
        half_width: f64,
    },
}

impl Shape {
    /// A random structure centred at `c`, sizes multiplied by `scale`: 40 % bars (two edges per
    /// crossing, the most edge-efficient), 30 % discs, 30 % blobs.
    pub fn random<R: Rng + ?Sized>(rng: &mut R, c: [f64; 2], scale: f64) -> Self {
        let kind = rng.random::<f64>();
        let th = rng.random::<f64>() * std::f64::consts::PI;
        if kind < 0.4 {
            let half = 0.5 * rng.random_range(6.0..18.0) * scale;
            let (s, co) = th.sin_cos();
            Shape::Bar {
                p0: [c[0] - half * co, c[1] - half * s],
                p1: [c[0] + half * co, c[1] + half * s],
                half_width: rng.random_range(0.9..1.6) * scale,
            }
        } else if kind < 0.7 {
            Shape::Disc {
                c,
                r: rng.random_range(2.0..5.0) * scale,
            }
        } else {
            Shape::Blob {
                c,
                ab: [
                    rng.random_range(3.0..8.0) * scale,
                    rng.random_range(1.5..4.0) * scale,
                ],
                angle: th,
            }
        }
    }

    /// Approximate signed distance (px), negative inside.
    pub fn signed_distance(&self, x: f64, y: f64) -> f64 {
        match *self {
            Shape::Disc { c, r } => (x - c[0]).hypot(y - c[1]) - r,
            Shape::Blob { c, ab, angle } => {
                let (s, co) = angle.sin_cos();
                let (dx, dy) = (x - c[0], y - c[1]);
                let u = (co * dx + s * dy) / ab[0];
                let v = (-s * dx + co * dy) / ab[1];
                let rho = u.hypot(v);
                if rho < 1e-9 {
                    return -ab[1].min(ab[0]);
                }
                let g = ((u / ab[0]).powi(2) + (v / ab[1]).powi(2)).sqrt() / rho;
                (rho - 1.0) / g
            }
            Shape::Bar { p0, p1, half_width } => {
                let (ex, ey) = (p1[0] - p0[0], p1[1] - p0[1]);
                let l2 = ex * ex + ey * ey;
                let t = if l2 > 0.0 {
                    (((x - p0[0]) * ex + (y - p0[1]) * ey) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (x - p0[0] - t * ex).hypot(y - p0[1] - t * ey) - half_width
            }
        }
    }

    /// Bounding box [x0, y0, x1, y1].
    pub fn bounds(&self) -> [f64; 4] {
        match *self {
            Shape::Disc { c, r } => [c[0] - r, c[1] - r, c[0] + r, c[1] + r],
            Shape::Blob { c, ab, .. } => {
                let m = ab[0].max(ab[1]);
                [c[0] - m, c[1] - m, c[0] + m, c[1] + m]
            }
            Shape::Bar {
                p0,
                p1,
                half_width: h,
            } => [
                p0[0].min(p1[0]) - h,
                p0[1].min(p1[1]) - h,
                p0[0].max(p1[0]) + h,
                p0[1].max(p1[1]) + h,
            ],
        }
    }

    /// Paints the shape with grey level `grey` into a `width`-wide row-major buffer, clipped to
    /// the pixel rectangle `clip` = [x0, y0, x1, y1) and anti-aliased by coverage ≈ clamp(½ − d).
    pub fn paint(&self, buf: &mut [f32], width: usize, clip: [usize; 4], grey: f32) {
        let b = self.bounds();
        let x0 = ((b[0] - 1.0).floor().max(clip[0] as f64)) as usize;
        let y0 = ((b[1] - 1.0).floor().max(clip[1] as f64)) as usize;
        let x1 = ((b[2] + 2.0).ceil().max(0.0) as usize).min(clip[2]);
        let y1 = ((b[3] + 2.0).ceil().max(0.0) as usize).min(clip[3]);
        for y in y0..y1 {
            for x in x0..x1 {
                let alpha = (0.5 - self.signed_distance(x as f64, y as f64)).clamp(0.0, 1.0) as f32;
                if alpha > 0.0 {
                    let p = &mut buf[y * width + x];
                    *p += alpha * (grey - *p);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn smooth_noise_is_bounded_and_gentle() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
        let n = smooth_noise(&mut rng, 64, 48, 12.0);
        assert!(n.iter().all(|v| v.abs() <= 1.0));
        // Largest horizontal step: ≤ 1.5 · 2 / scale per px (smoothstep slope 1.5, span 2).
        let max_step = (0..48)
            .flat_map(|y| (0..63).map(move |x| (y, x)))
            .map(|(y, x)| (n[y * 64 + x + 1] - n[y * 64 + x]).abs())
            .fold(0.0f32, f32::max);
        assert!(max_step <= 3.0 / 12.0 + 1e-6, "{max_step}");
    }

    #[test]
    fn painted_disc_covers_its_area() {
        let mut buf = vec![0.0f32; 40 * 40];
        Shape::Disc {
            c: [20.3, 19.6],
            r: 8.0,
        }
        .paint(&mut buf, 40, [0, 0, 40, 40], 1.0);
        let area: f32 = buf.iter().sum();
        // Coverage anti-aliasing: the summed alpha equals the area to within ~1 %.
        let exact = std::f32::consts::PI * 64.0;
        assert!((area - exact).abs() < 0.01 * exact, "{area} vs {exact}");
    }
}
