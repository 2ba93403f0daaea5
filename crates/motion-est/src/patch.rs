//! Patches for the implicit motion likelihood (Odobez et al. 2003, Eq. 22–23): a fixed reference
//! grid mapped into the image by a 2-D affine transform and sampled bilinearly, and the distance
//! d_c = 1 − ρ built on the normalised cross-correlation coefficient ρ (Eq. 23).

use nalgebra::Matrix2;
use vision_core::GreyImage;

use crate::{Error, Result};

/// A regular grid of reference points inside the unit disc (the reference contour of the shared
/// conventions): the centres of an `n`×`n` lattice over [−1, 1]² that fall inside the disc.
///
/// # Examples
/// ```
/// let g = motion_est::unit_disc_grid(16);
/// assert!(g.len() > 180 && g.len() < 220); // ≈ π/4 · 256
/// ```
pub fn unit_disc_grid(n: usize) -> Vec<[f64; 2]> {
    let mut out = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let x = -1.0 + (2.0 * i as f64 + 1.0) / n as f64;
            let y = -1.0 + (2.0 * j as f64 + 1.0) / n as f64;
            if x * x + y * y <= 1.0 {
                out.push([x, y]);
            }
        }
    }
    out
}

/// Samples `image` at p = A·r + t for every reference point r of `grid`, bilinearly, into `out`.
/// Points that fall outside [0, w−1] × [0, h−1] are written as NaN ("missing"); the count of valid
/// samples is returned.
///
/// # Errors
/// [`Error::DimensionMismatch`] when `out` and `grid` differ in length, [`Error::NonFinite`] for a
/// NaN transform or a NaN pixel read.
pub fn sample_patch_into(
    image: GreyImage<'_>,
    grid: &[[f64; 2]],
    a: &Matrix2<f64>,
    t: [f64; 2],
    out: &mut [f32],
) -> Result<usize> {
    if out.len() != grid.len() {
        return Err(Error::DimensionMismatch {
            what: "patch buffer",
            expected: grid.len(),
            got: out.len(),
        });
    }
    if let Some(index) = a.iter().chain(t.iter()).position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "patch transform",
            index,
        });
    }
    let (w, h) = (image.width(), image.height());
    let d = image.data();
    let (xmax, ymax) = ((w - 1) as f64, (h - 1) as f64);
    let mut valid = 0;
    for (r, o) in grid.iter().zip(out.iter_mut()) {
        let x = a[(0, 0)] * r[0] + a[(0, 1)] * r[1] + t[0];
        let y = a[(1, 0)] * r[0] + a[(1, 1)] * r[1] + t[1];
        if !(x >= 0.0 && y >= 0.0 && x <= xmax && y <= ymax) {
            *o = f32::NAN;
            continue;
        }
        let ix = (x as usize).min(w.saturating_sub(2));
        let iy = (y as usize).min(h.saturating_sub(2));
        let fx = (x - ix as f64) as f32;
        let fy = (y - iy as f64) as f32;
        let ix1 = (ix + 1).min(w - 1);
        let iy1 = (iy + 1).min(h - 1);
        let v00 = d[iy * w + ix];
        let v10 = d[iy * w + ix1];
        let v01 = d[iy1 * w + ix];
        let v11 = d[iy1 * w + ix1];
        let top = v00 + fx * (v10 - v00);
        let bot = v01 + fx * (v11 - v01);
        let v = top + fy * (bot - top);
        if !v.is_finite() {
            return Err(Error::NonFinite {
                what: "image",
                index: iy * w + ix,
            });
        }
        *o = v;
        valid += 1;
    }
    Ok(valid)
}

/// Allocating twin of [`sample_patch_into`].
///
/// # Errors
/// As [`sample_patch_into`].
pub fn sample_patch(
    image: GreyImage<'_>,
    grid: &[[f64; 2]],
    a: &Matrix2<f64>,
    t: [f64; 2],
) -> Result<Vec<f32>> {
    let mut out = vec![0.0; grid.len()];
    sample_patch_into(image, grid, a, t, &mut out)?;
    Ok(out)
}

/// Settings of the NCC distance.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NccSettings {
    /// Minimum share of sample pairs where both patches are valid (default 0.5); below it the
    /// distance is [`UNINFORMATIVE_DISTANCE`].
    pub min_valid_fraction: f64,
    /// Variance (grey levels², over the valid pairs) below which a patch counts as flat (default
    /// 1e-2: a tenth of a grey level of standard deviation).
    pub min_variance: f64,
}

impl Default for NccSettings {
    fn default() -> Self {
        Self {
            min_valid_fraction: 0.5,
            min_variance: 1e-2,
        }
    }
}

impl NccSettings {
    /// Checks the fields.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for a fraction outside (0, 1] or a negative variance.
    pub fn validate(&self) -> Result<()> {
        if !(self.min_valid_fraction > 0.0 && self.min_valid_fraction <= 1.0) {
            return Err(Error::InvalidSetting {
                name: "min_valid_fraction",
                reason: format!("{} must be in (0, 1]", self.min_valid_fraction),
            });
        }
        if !(self.min_variance.is_finite() && self.min_variance >= 0.0) {
            return Err(Error::InvalidSetting {
                name: "min_variance",
                reason: format!("{} must be finite and non-negative", self.min_variance),
            });
        }
        Ok(())
    }
}

/// The distance given when the patches carry no usable evidence (a flat patch, or too few valid
/// pairs): 1, the distance of two uncorrelated patches (ρ = 0), so such a comparison neither
/// favours nor penalises a hypothesis relative to unrelated content.
pub const UNINFORMATIVE_DISTANCE: f64 = 1.0;

/// d_c = 1 − ρ ∈ [0, 2], with ρ the normalised cross-correlation coefficient of Odobez Eq. 23
/// computed over the pairs where both samples are valid (non-NaN). Returns
/// [`UNINFORMATIVE_DISTANCE`] when fewer than `min_valid_fraction` of the pairs are valid or when
/// either patch is flat (variance below `min_variance`).
///
/// # Errors
/// [`Error::DimensionMismatch`] for patches of different lengths, [`Error::InvalidSetting`] for bad
/// settings.
///
/// # Examples
/// ```
/// use motion_est::{ncc_distance, NccSettings};
/// let a = [1.0, 2.0, 3.0, 4.0];
/// let b = [10.0, 20.0, 30.0, 40.0]; // affine in a: ρ = 1
/// assert!(ncc_distance(&a, &b, &NccSettings::default())?.abs() < 1e-12);
/// # Ok::<(), motion_est::Error>(())
/// ```
pub fn ncc_distance(a: &[f32], b: &[f32], settings: &NccSettings) -> Result<f64> {
    settings.validate()?;
    if a.len() != b.len() {
        return Err(Error::DimensionMismatch {
            what: "second patch",
            expected: a.len(),
            got: b.len(),
        });
    }
    if a.is_empty() {
        return Ok(UNINFORMATIVE_DISTANCE);
    }
    let (mut n, mut sa, mut sb) = (0usize, 0.0f64, 0.0f64);
    for (&x, &y) in a.iter().zip(b) {
        if x.is_finite() && y.is_finite() {
            n += 1;
            sa += f64::from(x);
            sb += f64::from(y);
        }
    }
    if (n as f64) < settings.min_valid_fraction * a.len() as f64 || n < 2 {
        return Ok(UNINFORMATIVE_DISTANCE);
    }
    let (ma, mb) = (sa / n as f64, sb / n as f64);
    let (mut saa, mut sbb, mut sab) = (0.0f64, 0.0f64, 0.0f64);
    for (&x, &y) in a.iter().zip(b) {
        if x.is_finite() && y.is_finite() {
            let (dx, dy) = (f64::from(x) - ma, f64::from(y) - mb);
            saa += dx * dx;
            sbb += dy * dy;
            sab += dx * dy;
        }
    }
    let floor = settings.min_variance * n as f64;
    if saa <= floor || sbb <= floor {
        return Ok(UNINFORMATIVE_DISTANCE);
    }
    let rho = (sab / (saa * sbb).sqrt()).clamp(-1.0, 1.0);
    Ok(1.0 - rho)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampler_reproduces_a_linear_image_and_marks_outside() {
        // Bilinear interpolation is exact on a linear image.
        let (w, h) = (40, 30);
        let data: Vec<f32> = (0..w * h)
            .map(|k| (2 * (k % w) + 3 * (k / w)) as f32)
            .collect();
        let img = GreyImage::new(w, h, &data).unwrap();
        let grid = [
            [0.0, 0.0],
            [1.0, 0.0],
            [0.0, 1.0],
            [0.5, -0.25],
            [10.0, 0.0],
        ];
        let a = Matrix2::new(4.0, 1.0, -1.0, 3.0);
        let t = [12.3, 10.7];
        let p = sample_patch(img, &grid, &a, t).unwrap();
        for (r, v) in grid.iter().zip(&p).take(4) {
            let x = 4.0 * r[0] + r[1] + t[0];
            let y = -r[0] + 3.0 * r[1] + t[1];
            assert!((f64::from(*v) - (2.0 * x + 3.0 * y)).abs() < 1e-3);
        }
        assert!(p[4].is_nan());
    }

    #[test]
    fn ncc_defined_values() {
        let s = NccSettings::default();
        let a = [1.0, 5.0, 2.0, 8.0, 3.0, 4.0];
        let neg: Vec<f32> = a.iter().map(|v| 100.0 - 2.0 * v).collect();
        assert!((ncc_distance(&a, &neg, &s).unwrap() - 2.0).abs() < 1e-12);
        let flat = [7.0; 6];
        assert_eq!(ncc_distance(&a, &flat, &s).unwrap(), UNINFORMATIVE_DISTANCE);
        assert_eq!(
            ncc_distance(&flat, &flat, &s).unwrap(),
            UNINFORMATIVE_DISTANCE
        );
        // Missing samples are skipped: the valid pairs below are exactly correlated.
        let b = [2.0, 10.0, f32::NAN, 16.0, 6.0, f32::NAN];
        assert!(ncc_distance(&a, &b, &s).unwrap().abs() < 1e-12);
        // Too few valid pairs.
        let c = [f32::NAN, f32::NAN, f32::NAN, f32::NAN, 1.0, 2.0];
        assert_eq!(ncc_distance(&a, &c, &s).unwrap(), UNINFORMATIVE_DISTANCE);
        assert!(ncc_distance(&a, &a[..3], &s).is_err());
    }
}
