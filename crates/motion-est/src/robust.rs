//! M-estimators for iteratively reweighted least squares, and the robust residual scale.

use crate::simd::simd;
use crate::{Error, Result};

/// The robust function ρ of Odobez Eq. 14, applied to residuals divided by the robust scale.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum RobustFunction {
    /// Tukey's biweight: redescending, zero weight beyond `c` scales (default c = 4.6851, 95 %
    /// efficiency under Gaussian noise).
    Tukey {
        /// Rejection threshold in scale units.
        c: f64,
    },
    /// Cauchy (Lorentzian): w = 1 / (1 + (z/c)²) (usual c = 2.3849).
    Cauchy {
        /// Width in scale units.
        c: f64,
    },
    /// Huber: quadratic up to `c`, linear beyond (usual c = 1.345).
    Huber {
        /// Transition point in scale units.
        c: f64,
    },
}

impl Default for RobustFunction {
    fn default() -> Self {
        RobustFunction::Tukey { c: 4.6851 }
    }
}

impl RobustFunction {
    /// The tuning constant.
    pub fn c(self) -> f64 {
        match self {
            RobustFunction::Tukey { c }
            | RobustFunction::Cauchy { c }
            | RobustFunction::Huber { c } => c,
        }
    }

    /// Checks that the constant is finite and positive.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] otherwise.
    pub fn validate(self) -> Result<()> {
        let c = self.c();
        if !(c.is_finite() && c > 0.0) {
            return Err(Error::InvalidSetting {
                name: "robust.c",
                reason: format!("{c} must be finite and positive"),
            });
        }
        Ok(())
    }

    /// IRLS weight w(z) = ψ(z)/z for a residual z in scale units.
    #[inline]
    pub fn weight(self, z: f64) -> f64 {
        match self {
            RobustFunction::Tukey { c } => {
                let u = (z / c) * (z / c);
                if u < 1.0 { (1.0 - u) * (1.0 - u) } else { 0.0 }
            }
            RobustFunction::Cauchy { c } => 1.0 / (1.0 + (z / c) * (z / c)),
            RobustFunction::Huber { c } => {
                if z.abs() <= c {
                    1.0
                } else {
                    c / z.abs()
                }
            }
        }
    }

    /// (E[ψ'(Z)], E[ψ(Z)²]) for Z ~ N(0, 1), by Simpson quadrature on [−12, 12]: the constants of
    /// the M-estimator's asymptotic variance under Gaussian noise.
    pub fn gaussian_moments(self) -> (f64, f64) {
        const STEPS: usize = 2400;
        let (a, b) = (-12.0f64, 12.0f64);
        let h = (b - a) / STEPS as f64;
        let (mut e1, mut e2) = (0.0, 0.0);
        for i in 0..=STEPS {
            let z = a + i as f64 * h;
            let wgt = if i == 0 || i == STEPS {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let p = (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
            let psi = z * self.weight(z);
            e1 += wgt * p * self.psi_prime(z);
            e2 += wgt * p * psi * psi;
        }
        (e1 * h / 3.0, e2 * h / 3.0)
    }

    /// The residual (in scale units) beyond which a pixel has no influence at all, if any (Tukey).
    pub fn rejection(self) -> Option<f64> {
        match self {
            RobustFunction::Tukey { c } => Some(c),
            RobustFunction::Cauchy { .. } | RobustFunction::Huber { .. } => None,
        }
    }

    /// ψ'(z), the derivative of the influence function, which is what the estimate's sensitivity
    /// to noise depends on (sandwich covariance).
    #[inline]
    pub fn psi_prime(self, z: f64) -> f64 {
        match self {
            RobustFunction::Tukey { c } => {
                let u = (z / c) * (z / c);
                if u < 1.0 {
                    (1.0 - u) * (1.0 - 5.0 * u)
                } else {
                    0.0
                }
            }
            RobustFunction::Cauchy { c } => {
                let u = (z / c) * (z / c);
                (1.0 - u) / ((1.0 + u) * (1.0 + u))
            }
            RobustFunction::Huber { c } => {
                if z.abs() <= c {
                    1.0
                } else {
                    0.0
                }
            }
        }
    }
}

/// Every `stride`-th valid |residual|, at most ~512 of them, into `scratch`.
fn subsample(res: &[f32], valid: &[u8], scratch: &mut Vec<f32>) {
    scratch.clear();
    let n_valid = valid.iter().filter(|&&v| v != 0).count();
    let stride = (n_valid / 512).max(1);
    // Every stride-th valid residual, from the first (a countdown: no division per residual).
    let mut skip = 0usize;
    for (&r, &v) in res.iter().zip(valid) {
        if v != 0 {
            if skip == 0 {
                scratch.push(r.abs());
                skip = stride;
            }
            skip -= 1;
        }
    }
}

/// The Gaussian-consistent scale of the `q`-quantile of |r| (on the subsample of [`subsample`]),
/// `None` when no residual is valid.
fn quantile_scale(res: &[f32], valid: &[u8], scratch: &mut Vec<f32>, q: f64) -> Option<f64> {
    subsample(res, valid, scratch);
    if scratch.is_empty() {
        return None;
    }
    let k = ((scratch.len() as f64 * q) as usize).min(scratch.len() - 1);
    let (_, v, _) = scratch.select_nth_unstable_by(k, f32::total_cmp);
    // The quartile of |z| for z ~ N(0, 1): Φ⁻¹((1 + q)/2) (the only quantile used).
    debug_assert!(q == 0.25);
    let z = 0.318_64;
    Some(f64::from(*v) / z)
}

/// The Gaussian-consistent lower quartile of |r|: small when a quarter of the pixels fit.
pub(crate) fn lower_quartile(res: &[f32], valid: &[u8], scratch: &mut Vec<f32>) -> f64 {
    quantile_scale(res, valid, scratch, 0.25).unwrap_or(f64::INFINITY)
}

/// Robust scale of the residuals `res` where `valid` is set: the noise scale of the best-fitting
/// group of pixels. Seeded by the Gaussian-consistent lower quartile of |r| (on a strided
/// subsample of at most ~1k values), then refined by up to six passes of the Gaussian-consistent
/// RMS of the residuals within 2.5 scales. Never below `min_scale`.
///
/// The refinement's map s ↦ RMS(|r| < 2.5 s) has several fixed points when the residuals mix
/// groups of different spread: the noise of the pixels that fit, and larger ones that take in
/// outliers and misfit. Started below the noise (the lower quartile is below the inliers' own
/// scale as long as they are more than a quarter of the pixels), it climbs to the smallest fixed
/// point, the noise; started from the median alone it may settle on an inflated one.
///
/// With `seed` (a scale from residuals that differ little, e.g. the previous iteration's at the
/// same level) the quantile is skipped and the refinement starts from the seed: the refinement has
/// the same fixed point and needs one or two passes from there.
pub(crate) fn robust_scale_from(
    res: &[f32],
    valid: &[u8],
    scratch: &mut Vec<f32>,
    min_scale: f64,
    seed: Option<f64>,
) -> f64 {
    let mut s = match seed {
        Some(s) if s.is_finite() && s > 0.0 => s.max(min_scale),
        _ => match quantile_scale(res, valid, scratch, 0.25) {
            None => return min_scale,
            Some(s) => s.max(min_scale),
        },
    };
    // E[z² | |z| < 2.5] for a standard normal: 1 − 2·2.5·φ(2.5)/(2Φ(2.5) − 1).
    const TRUNC: f64 = 2.5;
    const CONSISTENCY: f64 = 0.911_25;
    for _ in 0..6 {
        let (sum, n) = truncated_sum(res, valid, (TRUNC * s) as f32);
        if n == 0 {
            break;
        }
        let next = (sum / (n as f64 * CONSISTENCY)).sqrt().max(min_scale);
        let done = (next - s).abs() < 0.005 * s;
        s = next;
        if done {
            break;
        }
    }
    s
}

/// Values per block of [`truncated_sum`].
const BLOCK: usize = 1024;

/// Σ r² and the count over valid residuals with |r| < t: branch-free, eight f32 lanes per block
/// of [`BLOCK`] values, the blocks' sums added in f64 in block order (whether the blocks were
/// computed concurrently — long inputs with the `parallel` feature — or not).
fn truncated_sum(res: &[f32], valid: &[u8], t: f32) -> (f64, usize) {
    let add = |(s, n): (f64, usize), (bs, bn): (f64, usize)| (s + bs, n + bn);
    #[cfg(feature = "parallel")]
    if res.len() > 16 * BLOCK {
        // Tasks of 16 blocks (fewer, larger tasks than one per block); the block sums come back
        // in block order and are added in it.
        use rayon::prelude::*;
        let parts: Vec<(f64, usize)> = res
            .par_chunks(16 * BLOCK)
            .zip(valid.par_chunks(16 * BLOCK))
            .flat_map_iter(|(rs, vs)| {
                simd(
                    #[inline(always)]
                    || block_sums(rs, vs, t).collect::<Vec<_>>(),
                )
            })
            .collect();
        return parts.into_iter().fold((0.0, 0), add);
    }
    // The same block sums, added as they come (no buffer).
    simd(
        #[inline(always)]
        || block_sums(res, valid, t).fold((0.0, 0), add),
    )
}

/// The [`truncated_block`] sums of the blocks of a run of values, in block order.
#[inline(always)]
fn block_sums<'a>(
    res: &'a [f32],
    valid: &'a [u8],
    t: f32,
) -> impl Iterator<Item = (f64, usize)> + 'a {
    res.chunks(BLOCK)
        .zip(valid.chunks(BLOCK))
        .map(move |(rb, vb)| truncated_block(rb, vb, t))
}

/// [`truncated_sum`] of one block.
#[inline(always)]
fn truncated_block(rb: &[f32], vb: &[u8], t: f32) -> (f64, usize) {
    let (mut sum, mut n) = (0.0f64, 0usize);
    let mut lanes = [0.0f32; 8];
    let mut counts = [0u32; 8];
    let (rc, vc) = (rb.chunks_exact(8), vb.chunks_exact(8));
    let (rt, vt) = (rc.remainder(), vc.remainder());
    for (r8, v8) in rc.zip(vc) {
        for l in 0..8 {
            // `&`, not `&&`: no branch, so the lanes vectorise.
            let keep = (v8[l] != 0) & (r8[l].abs() < t);
            lanes[l] += if keep { r8[l] * r8[l] } else { 0.0 };
            counts[l] += u32::from(keep);
        }
    }
    for (&r, &v) in rt.iter().zip(vt) {
        if v != 0 && r.abs() < t {
            sum += f64::from(r * r);
            n += 1;
        }
    }
    sum += lanes.iter().map(|&v| f64::from(v)).sum::<f64>();
    n += counts.iter().map(|&c| c as usize).sum::<usize>();
    (sum, n)
}

/// [`robust_scale_from`] without a seed.
#[cfg(test)]
fn robust_scale(res: &[f32], valid: &[u8], scratch: &mut Vec<f32>, min_scale: f64) -> f64 {
    robust_scale_from(res, valid, scratch, min_scale, None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn psi_prime_is_derivative_of_psi() {
        for f in [
            RobustFunction::default(),
            RobustFunction::Cauchy { c: 2.3849 },
            RobustFunction::Huber { c: 1.345 },
        ] {
            for &z in &[0.1, 0.9, 2.0, 3.3, 4.0] {
                let psi = |z: f64| z * f.weight(z);
                let h = 1e-6;
                let num = (psi(z + h) - psi(z - h)) / (2.0 * h);
                assert!((num - f.psi_prime(z)).abs() < 1e-5, "{f:?} at {z}");
            }
        }
    }

    #[test]
    fn gaussian_moments_match_known_efficiency() {
        // Tukey c = 4.6851 and Huber c = 1.345 are the constants of 95 % Gaussian efficiency:
        // E[ψ']² / E[ψ²] = 0.95.
        for f in [
            RobustFunction::default(),
            RobustFunction::Huber { c: 1.345 },
        ] {
            let (e1, e2) = f.gaussian_moments();
            assert!(
                (e1 * e1 / e2 - 0.95).abs() < 0.002,
                "{f:?}: {}",
                e1 * e1 / e2
            );
        }
    }

    #[test]
    fn scale_ignores_forty_percent_outliers() {
        // 60 % N(0, 2²) inliers, 40 % uniform ±60 outliers: the scale must come back within 10 %
        // of 2 (sampling error on 20k values is ~1 %; the outliers that fall inside the ±2.5σ
        // window, 3 % of all values with mean square 8, bias the fixed point up by ~5–8 %), where
        // the plain RMS would be ~22.
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
        let normal = Normal::new(0.0f32, 2.0).unwrap();
        let res: Vec<f32> = (0..20_000)
            .map(|i| {
                if i % 5 < 3 {
                    normal.sample(&mut rng)
                } else {
                    rand::Rng::random_range(&mut rng, -60.0f32..60.0)
                }
            })
            .collect();
        let valid = vec![1u8; res.len()];
        let s = robust_scale(&res, &valid, &mut Vec::new(), 1e-3);
        assert!((s - 2.0).abs() < 0.2, "{s}");
    }

    #[test]
    fn scale_of_a_misaligned_fit_is_the_noise_of_the_group_that_fits() {
        // A fit between two motions with the larger group nearly aligned: 55 % N(0, 0.8²) and
        // 45 % misfit N(0, 15²). The median of |r| sits at the inliers' 90th percentile and the
        // truncated refinement from 1.4826·median may settle on a scale of several grey levels;
        // seeded below the noise by the lower quartile it climbs to the smallest fixed point,
        // within 15 % of 0.8 (misfit values inside ±2.5σ, 2 % of all, bias it up a little).
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        let (inl, out) = (
            Normal::new(0.0f32, 0.8).unwrap(),
            Normal::new(0.0f32, 15.0).unwrap(),
        );
        let res: Vec<f32> = (0..20_000)
            .map(|i| {
                if i % 20 < 11 {
                    inl.sample(&mut rng)
                } else {
                    out.sample(&mut rng)
                }
            })
            .collect();
        let valid = vec![1u8; res.len()];
        let s = robust_scale(&res, &valid, &mut Vec::new(), 1e-3);
        assert!((s - 0.8).abs() < 0.12, "{s}");
    }
}
