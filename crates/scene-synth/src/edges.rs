//! The workspace's default 1-D edge detector and edge-density measurement.
//!
//! Definition (shared with `contour-obs`): sample every 1 px along the line by bilinear
//! interpolation; correlate with a derivative of Gaussian, σ = 1 px, normalised so that a ramp of
//! slope 1 grey level/px answers 1; non-maximum suppression on |derivative|; keep maxima with
//! |derivative| ≥ 8 grey levels/px; sub-pixel offset from a parabola through the three samples
//! around the maximum. Edge density λ = edges per pixel of line (W §3, §6.1).

use rand::Rng;
use vision_core::GreyImage;

/// Settings of the 1-D edge detector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeDetector {
    /// Standard deviation of the derivative-of-Gaussian filter (px). Default 1.
    pub sigma: f64,
    /// Minimum |derivative| of an edge (grey levels per px). Default 8.
    pub threshold: f64,
}

impl Default for EdgeDetector {
    fn default() -> Self {
        Self {
            sigma: 1.0,
            threshold: 8.0,
        }
    }
}

impl EdgeDetector {
    /// Filter half-width in samples (3σ, rounded up).
    pub fn radius(&self) -> usize {
        (3.0 * self.sigma).ceil().max(1.0) as usize
    }

    /// Derivative-of-Gaussian taps d_k for k = −R..=R, normalised so Σ k·d_k = 1.
    pub fn kernel(&self) -> Vec<f64> {
        let r = self.radius() as i64;
        let raw: Vec<f64> = (-r..=r)
            .map(|k| {
                let k = k as f64;
                k * (-k * k / (2.0 * self.sigma * self.sigma)).exp()
            })
            .collect();
        let norm: f64 = (-r..=r).zip(&raw).map(|(k, d)| k as f64 * d).sum();
        raw.into_iter().map(|d| d / norm).collect()
    }

    /// Edges on a sampled profile: pushes sub-pixel sample positions into `out` (cleared first).
    /// Only samples with a full filter support and both neighbours can hold an edge.
    pub fn detect(
        &self,
        profile: &[f64],
        kernel: &[f64],
        response: &mut Vec<f64>,
        out: &mut Vec<f64>,
    ) {
        out.clear();
        response.clear();
        let r = kernel.len() / 2;
        if profile.len() < 2 * r + 3 {
            return;
        }
        for i in r..profile.len() - r {
            let mut acc = 0.0;
            for (j, d) in kernel.iter().enumerate() {
                acc += d * profile[i + j - r];
            }
            response.push(acc.abs());
        }
        for i in 1..response.len() - 1 {
            let (ym, y0, yp) = (response[i - 1], response[i], response[i + 1]);
            // Non-maximum suppression; the asymmetric comparison keeps one sample of a plateau
            // (the same choice as `contour-obs`).
            if y0 >= self.threshold && y0 >= ym && y0 > yp {
                let den = ym - 2.0 * y0 + yp;
                let off = if den < 0.0 {
                    (0.5 * (ym - yp) / den).clamp(-0.5, 0.5)
                } else {
                    0.0
                };
                out.push((i + r) as f64 + off);
            }
        }
    }
}

/// Bilinear sample of `img` at (x, y), clamped at the border (a point outside reads the nearest
/// border value); an image one pixel wide or high is interpolated along its other axis only.
pub fn bilinear(img: &GreyImage<'_>, x: f64, y: f64) -> f64 {
    bilinear_raw(img.width(), img.height(), img.data(), x, y)
}

/// [`bilinear`] on a row-major buffer of `width * height` values, both sides at least 1.
pub(crate) fn bilinear_raw(width: usize, height: usize, data: &[f32], x: f64, y: f64) -> f64 {
    let xm = (width - 1) as f64;
    let ym = (height - 1) as f64;
    let x = x.clamp(0.0, xm);
    let y = y.clamp(0.0, ym);
    let x0 = (x.floor() as usize).min(width.saturating_sub(2));
    let y0 = (y.floor() as usize).min(height.saturating_sub(2));
    let fx = x - x0 as f64;
    let fy = y - y0 as f64;
    let i = y0 * width + x0;
    let x1 = if width > 1 { 1 } else { 0 };
    let y1 = if height > 1 { width } else { 0 };
    let p00 = f64::from(data[i]);
    let p10 = f64::from(data[i + x1]);
    let p01 = f64::from(data[i + y1]);
    let p11 = f64::from(data[i + x1 + y1]);
    (p00 * (1.0 - fx) + p10 * fx) * (1.0 - fy) + (p01 * (1.0 - fx) + p11 * fx) * fy
}

/// A measurement segment from `p0` to `p1` (image coordinates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Start point.
    pub p0: [f64; 2],
    /// End point.
    pub p1: [f64; 2],
}

impl Segment {
    /// Length (px).
    pub fn length(&self) -> f64 {
        (self.p1[0] - self.p0[0]).hypot(self.p1[1] - self.p0[1])
    }
}

/// Reusable buffers for [`count_edges`].
#[derive(Debug, Default, Clone)]
pub struct EdgeScratch {
    profile: Vec<f64>,
    response: Vec<f64>,
    edges: Vec<f64>,
    kernel: Vec<f64>,
}

/// Number of edges on a segment. The profile is extended by R + 1 samples beyond both ends so
/// that the whole segment is testable, and only edges whose position lies in [0, length) count,
/// which makes the density estimate unbiased.
pub fn count_edges(
    img: &GreyImage<'_>,
    seg: &Segment,
    det: &EdgeDetector,
    s: &mut EdgeScratch,
) -> usize {
    let len = seg.length();
    if len <= 0.0 {
        return 0;
    }
    if s.kernel.len() != 2 * det.radius() + 1 {
        s.kernel = det.kernel();
    }
    let dx = (seg.p1[0] - seg.p0[0]) / len;
    let dy = (seg.p1[1] - seg.p0[1]) / len;
    let ext = det.radius() + 1;
    let n = len.floor() as usize + 1;
    s.profile.clear();
    for i in 0..n + 2 * ext {
        let t = i as f64 - ext as f64;
        s.profile
            .push(bilinear(img, seg.p0[0] + t * dx, seg.p0[1] + t * dy));
    }
    det.detect(&s.profile, &s.kernel, &mut s.response, &mut s.edges);
    s.edges
        .iter()
        .filter(|&&e| {
            let t = e - ext as f64;
            (0.0..len).contains(&t)
        })
        .count()
}

/// Measured edge density (edges per pixel of line) over a set of segments.
pub fn edge_density(img: &GreyImage<'_>, segments: &[Segment], det: &EdgeDetector) -> f64 {
    let mut s = EdgeScratch::default();
    let mut edges = 0usize;
    let mut length = 0.0;
    for seg in segments {
        edges += count_edges(img, seg, det, &mut s);
        length += seg.length();
    }
    if length > 0.0 {
        edges as f64 / length
    } else {
        0.0
    }
}

/// Random isotropic segments of the given length lying entirely inside the axis-aligned
/// rectangle [x0, x1) × [y0, y1) shrunk by `margin`, and for which `keep` returns true.
/// Rejection sampling gives up after 50 tries per segment, so fewer segments may be returned.
#[allow(clippy::too_many_arguments)]
pub fn random_segments<R, F>(
    rng: &mut R,
    rect: [f64; 4],
    margin: f64,
    length: f64,
    count: usize,
    mut keep: F,
) -> Vec<Segment>
where
    R: Rng + ?Sized,
    F: FnMut(&Segment) -> bool,
{
    let [x0, y0, x1, y1] = [
        rect[0] + margin,
        rect[1] + margin,
        rect[2] - margin,
        rect[3] - margin,
    ];
    let mut out = Vec::with_capacity(count);
    if x1 <= x0 || y1 <= y0 {
        return out;
    }
    for _ in 0..count {
        for _ in 0..50 {
            let th = rng.random::<f64>() * std::f64::consts::PI;
            let (sn, cs) = th.sin_cos();
            let hx = 0.5 * length * cs;
            let hy = 0.5 * length * sn;
            let (lx, ux) = (x0 + hx.abs(), x1 - hx.abs());
            let (ly, uy) = (y0 + hy.abs(), y1 - hy.abs());
            if ux <= lx || uy <= ly {
                continue;
            }
            let cx = lx + rng.random::<f64>() * (ux - lx);
            let cy = ly + rng.random::<f64>() * (uy - ly);
            let seg = Segment {
                p0: [cx - hx, cy - hy],
                p1: [cx + hx, cy + hy],
            };
            if keep(&seg) {
                out.push(seg);
                break;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn kernel_answers_one_to_a_unit_ramp() {
        let det = EdgeDetector::default();
        let k = det.kernel();
        let ramp: Vec<f64> = (0..k.len()).map(|i| 3.0 * i as f64 + 7.0).collect();
        let resp: f64 = k.iter().zip(&ramp).map(|(d, f)| d * f).sum();
        assert_relative_eq!(resp, 3.0, epsilon = 1e-12);
    }

    #[test]
    fn a_step_midway_between_samples_is_found_at_its_sub_pixel_position() {
        let det = EdgeDetector::default();
        let k = det.kernel();
        // Step of 100 grey levels between samples 10 and 11: by symmetry the edge is at 10.5.
        let profile: Vec<f64> = (0..24)
            .map(|i| if i <= 10 { 20.0 } else { 120.0 })
            .collect();
        let (mut r, mut e) = (Vec::new(), Vec::new());
        det.detect(&profile, &k, &mut r, &mut e);
        assert_eq!(e.len(), 1);
        assert_relative_eq!(e[0], 10.5, epsilon = 1e-9);
        // A 10-level step gives a peak derivative of ≈ 0.4·10 < 8: no edge.
        let weak: Vec<f64> = profile.iter().map(|v| v * 0.1).collect();
        det.detect(&weak, &k, &mut r, &mut e);
        assert!(e.is_empty());
    }

    #[test]
    fn agrees_with_the_reference_detector_of_contour_obs() {
        // One definition of "edge" across the workspace: on random clutter-like profiles both
        // detectors must find the same edges (f32 vs f64 arithmetic: 1e-3 px).
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(17);
        let det = EdgeDetector::default();
        let k = det.kernel();
        let (mut r, mut mine) = (Vec::new(), Vec::new());
        let mut total = 0usize;
        for _ in 0..200 {
            let mut v = 128.0f64;
            let profile: Vec<f64> = (0..60)
                .map(|_| {
                    if rng.random::<f64>() < 0.15 {
                        v = rng.random_range(0.0..255.0);
                    }
                    v + rng.random_range(-2.0..2.0)
                })
                .collect();
            det.detect(&profile, &k, &mut r, &mut mine);
            let p32: Vec<f32> = profile.iter().map(|&x| x as f32).collect();
            let theirs =
                contour_obs::detect_edges(&p32, &contour_obs::EdgeSettings::default()).unwrap();
            assert_eq!(mine.len(), theirs.len(), "{mine:?} vs {theirs:?}");
            for (a, b) in mine.iter().zip(&theirs) {
                assert!((a - b).abs() < 1e-3, "{a} vs {b}");
            }
            total += mine.len();
        }
        assert!(total > 500);
    }

    #[test]
    fn stripes_of_known_period_give_the_known_density() {
        // Vertical bands 6 px wide: horizontal lines cross one step every 6 px.
        let (w, h) = (120, 20);
        let data: Vec<f32> = (0..w * h)
            .map(|i| if ((i % w) / 6) % 2 == 0 { 40.0 } else { 200.0 })
            .collect();
        let img = GreyImage::new(w, h, &data).unwrap();
        let seg = Segment {
            p0: [10.2, 10.0],
            p1: [106.2, 10.0],
        };
        let lambda = edge_density(&img, &[seg], &EdgeDetector::default());
        assert_relative_eq!(lambda, 1.0 / 6.0, epsilon = 1e-9);
    }
}
