//! The calibrated clutter background (W §6.1: clutter is measured as edges per pixel of line).
//!
//! Each region receives a fixed random list of structures; the number of them actually drawn is
//! found by bisection so that the default edge detector, run along random isotropic segments
//! inside the region, measures the requested density λ.

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use vision_core::GreyImage;

use crate::edges::{EdgeDetector, edge_density, random_segments};
use crate::error::{Error, Result};
use crate::params::{BackgroundParams, ClutterClass};
use crate::texture::{Shape, smooth_noise};

/// Calibration stops once the measured density is within this fraction of the requested one
/// (or the count cannot be refined further).
const CALIBRATION_TOLERANCE: f64 = 0.01;

/// The i-th point of the R2 sequence (Kronecker sequence on the plastic number) in [0, 1)².
fn r2_point(start: [f64; 2], i: usize) -> [f64; 2] {
    const G: f64 = 1.324_717_957_244_746;
    let i = i as f64;
    [(start[0] + i / G).fract(), (start[1] + i / (G * G)).fract()]
}

/// A background texture with its clutter regions.
#[derive(Debug, Clone)]
pub struct Background {
    /// Width (px).
    pub width: usize,
    /// Height (px).
    pub height: usize,
    /// Row-major grey levels.
    pub data: Vec<f32>,
    /// Regions: vertical bands `[x0, x1)` and their class.
    pub regions: Vec<Region>,
}

/// One clutter region of the background.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region {
    /// First column.
    pub x0: usize,
    /// One past the last column.
    pub x1: usize,
    /// Clutter class.
    pub class: ClutterClass,
    /// Requested density (edges/px).
    pub requested: f64,
    /// Density measured after calibration (edges/px).
    pub measured: f64,
    /// Number of structures drawn.
    pub structures: usize,
}

impl Background {
    /// Builds and calibrates a `width` × `height` background.
    ///
    /// # Errors
    /// [`Error::Calibration`] when a region cannot reach its density (structures too large for
    /// the requested λ, or the region too small).
    pub fn generate(
        params: &BackgroundParams,
        width: usize,
        height: usize,
        seed: u64,
    ) -> Result<Self> {
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let noise = smooth_noise(&mut rng, width, height, params.texture_scale);
        let base: Vec<f32> = noise
            .iter()
            .map(|n| (params.grey + params.texture_amplitude * f64::from(*n)) as f32)
            .collect();
        let mut data = base.clone();
        let det = EdgeDetector::default();
        let c = &params.clutter;
        let nreg = c.layout.len();
        let mut regions = Vec::with_capacity(nreg);
        for (i, &class) in c.layout.iter().enumerate() {
            let x0 = i * width / nreg;
            let x1 = (i + 1) * width / nreg;
            let ci = usize::from(class.index() - 1);
            let requested = c.densities[ci];
            let scale = c.size_scale[ci];
            let rect = [x0 as f64, 0.0, x1 as f64, height as f64];
            let clip = [x0, 0, x1, height];
            // Enough structures to saturate the region: one per 4 px² at scale 1.
            let area = ((x1 - x0) * height) as f64;
            let n_max = (area / (4.0 * scale * scale)).ceil() as usize + 8;
            let shapes = region_structures(&mut rng, params, rect, scale, n_max);
            let margin = (det.radius() + 2) as f64;
            let segments = random_segments(
                &mut rng,
                rect,
                margin,
                c.line_length,
                c.calibration_lines,
                |_| true,
            );
            // Painting is sequential, so growing the count only paints the new structures on
            // top; shrinking it repaints the region from the base.
            let mut painted = 0usize;
            let mut measure = |n: usize| -> Result<f64> {
                if n < painted {
                    for y in 0..height {
                        let row = y * width;
                        data[row + x0..row + x1].copy_from_slice(&base[row + x0..row + x1]);
                    }
                    painted = 0;
                }
                for (s, g) in &shapes[painted..n] {
                    s.paint(&mut data, width, clip, *g);
                }
                painted = n;
                Ok(edge_density(
                    &GreyImage::new(width, height, &data)?,
                    &segments,
                    &det,
                ))
            };
            let n = calibrated_count(&mut measure, requested, n_max, class.index())?;
            let measured = measure(n)?;
            regions.push(Region {
                x0,
                x1,
                class,
                requested,
                measured,
                structures: n,
            });
        }
        Ok(Self {
            width,
            height,
            data,
            regions,
        })
    }

    /// The region holding column `x` (clamped into the texture); `None` only for a background
    /// without regions, which [`Background::generate`] never builds.
    pub fn region_at(&self, x: f64) -> Option<&Region> {
        let n = self.regions.len();
        let i = if x.is_finite() && self.width > 0 {
            (x.max(0.0) * n as f64 / self.width as f64).floor() as usize
        } else {
            0
        };
        self.regions.get(i.min(n.saturating_sub(1)))
    }

    /// Borrowed view of the texture.
    ///
    /// # Errors
    /// [`Error::GreyImage`] for a texture that is empty or holds a non-finite value, which
    /// [`Background::generate`] never builds.
    pub fn view(&self) -> Result<GreyImage<'_>> {
        Ok(GreyImage::new(self.width, self.height, &self.data)?)
    }
}

/// The `n_max` structures that may be painted in the region `rect` (x0, y0, x1, y1), in the
/// order calibration paints them, each with its grey level.
///
/// Centres follow the R2 low-discrepancy sequence from a random start, so that every prefix of
/// the list (every count tried by the calibration) is spread evenly over the region: the density
/// is then uniform within the region, not only on average.
fn region_structures(
    rng: &mut Pcg64Mcg,
    params: &BackgroundParams,
    rect: [f64; 4],
    scale: f64,
    n_max: usize,
) -> Vec<(Shape, f32)> {
    let c = &params.clutter;
    let start = [rng.random::<f64>(), rng.random::<f64>()];
    (0..n_max)
        .map(|i| {
            let u = r2_point(start, i);
            let pos = [
                rect[0] + u[0] * (rect[2] - rect[0]),
                rect[1] + u[1] * (rect[3] - rect[1]),
            ];
            let s = Shape::random(rng, pos, scale);
            let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
            let g = params.grey + sign * rng.random_range(c.contrast[0]..=c.contrast[1]);
            (s, g.clamp(0.0, 255.0) as f32)
        })
        .collect()
}

/// The number of structures, at most `n_max`, whose measured edge density `measure(n)` comes
/// closest to `requested` (within [`CALIBRATION_TOLERANCE`] it stops early).
///
/// λ(n) grows with n until the structures cover each other. The requested density is bracketed
/// by growing n geometrically from a pilot count, then closed in by false position (λ is close
/// to linear in n), with bisection as a safeguard when one end stalls.
///
/// # Errors
/// [`Error::Calibration`] when even `n_max` structures stay below the requested density.
fn calibrated_count(
    measure: &mut impl FnMut(usize) -> Result<f64>,
    requested: f64,
    n_max: usize,
    class: u8,
) -> Result<usize> {
    let tol = CALIBRATION_TOLERANCE * requested;
    let mut lo = (0usize, measure(0)?);
    let mut best = lo;
    let mut hi = None;
    if lo.1 < requested - tol {
        let mut n = (n_max / 64).max(1);
        loop {
            let l = measure(n)?;
            if (l - requested).abs() < (best.1 - requested).abs() {
                best = (n, l);
            }
            if l >= requested {
                hi = Some((n, l));
                break;
            }
            lo = (n, l);
            if n == n_max {
                return Err(Error::Calibration {
                    class,
                    requested,
                    reached: l,
                });
            }
            let grow = if l > 0.0 {
                (1.2 * requested / l).clamp(1.3, 4.0)
            } else {
                4.0
            };
            n = ((n as f64 * grow).ceil() as usize).min(n_max);
        }
    }
    let mut stalled = 0u32;
    while let Some(h) = hi {
        if h.0 - lo.0 <= 1 || (best.1 - requested).abs() <= tol {
            break;
        }
        let frac = (requested - lo.1) / (h.1 - lo.1).max(1e-12);
        let mut mid = lo.0 + (frac * (h.0 - lo.0) as f64).round() as usize;
        if stalled >= 2 {
            mid = (lo.0 + h.0) / 2;
            stalled = 0;
        }
        let mid = mid.clamp(lo.0 + 1, h.0 - 1);
        let l = measure(mid)?;
        if (l - requested).abs() < (best.1 - requested).abs() {
            best = (mid, l);
        }
        if l < requested {
            lo = (mid, l);
            stalled += 1;
        } else {
            hi = Some((mid, l));
            stalled = 0;
        }
    }
    Ok(best.0)
}
