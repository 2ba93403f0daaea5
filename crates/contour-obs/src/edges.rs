//! The 1-D edge detector along a measurement line: derivative of Gaussian, non-maximum suppression,
//! threshold, optional polarity, sub-pixel refinement by a parabola.
//!
//! This is the workspace's single definition of an "edge", so that an edge density per pixel means
//! the same in clutter learning, the scene generator and the likelihoods.

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// Which sign of intensity change counts as an edge, measured along the line's direction (for
/// measurement lines: outward along the contour normal).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Polarity {
    /// Either sign.
    #[default]
    Any,
    /// Intensity increases along the line (dark inside, bright outside).
    Rising,
    /// Intensity decreases along the line (bright inside, dark outside).
    Falling,
}

/// Settings of the 1-D edge detector.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EdgeSettings {
    /// Standard deviation of the derivative-of-Gaussian filter, in pixels along the line.
    /// Default 1 px (the workspace convention).
    pub sigma: f64,
    /// Minimum |derivative| of a kept maximum, in grey levels per pixel. Default 8. The filter is
    /// normalised so that an intensity ramp of slope g gives exactly g; an ideal step of height h
    /// gives h/(σ√(2π)) ≈ 0.4 h at σ = 1, so steps of about 20 grey levels and more are detected.
    pub threshold: f32,
    /// Which edges to keep. Default [`Polarity::Any`].
    pub polarity: Polarity,
}

impl Default for EdgeSettings {
    fn default() -> Self {
        Self {
            sigma: 1.0,
            threshold: 8.0,
            polarity: Polarity::Any,
        }
    }
}

impl EdgeSettings {
    /// Checks the ranges: σ in [0.3, 10] px, threshold finite and > 0.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the field.
    pub fn validate(&self) -> Result<()> {
        if !(0.3..=10.0).contains(&self.sigma) {
            return Err(Error::InvalidSetting {
                name: "edge.sigma",
                reason: format!("must be in [0.3, 10] px, got {}", self.sigma),
            });
        }
        if !(self.threshold.is_finite() && self.threshold > 0.0) {
            return Err(Error::InvalidSetting {
                name: "edge.threshold",
                reason: format!("must be finite and positive, got {}", self.threshold),
            });
        }
        Ok(())
    }

    /// Half-width of the filter in samples, ⌈3σ⌉.
    pub fn radius(&self) -> usize {
        (3.0 * self.sigma).ceil() as usize
    }
}

/// The edge detector with its filter taps and a reusable derivative buffer.
#[derive(Debug, Clone)]
pub struct EdgeDetector {
    settings: EdgeSettings,
    /// Taps w_1..w_r of the antisymmetric filter: d_k = Σ_j w_j (s_{k+j} − s_{k−j}).
    taps: Vec<f32>,
    deriv: Vec<f32>,
}

impl EdgeDetector {
    /// Builds the filter.
    ///
    /// # Errors
    /// As [`EdgeSettings::validate`].
    pub fn new(settings: &EdgeSettings) -> Result<Self> {
        settings.validate()?;
        let r = settings.radius();
        let s2 = 2.0 * settings.sigma * settings.sigma;
        // Derivative of Gaussian, w_j ∝ j·exp(−j²/2σ²), normalised so that Σ_j w_j·j over
        // j = −r..r equals 1: a ramp of slope g then yields exactly g.
        let raw: Vec<f64> = (1..=r)
            .map(|j| j as f64 * (-((j * j) as f64) / s2).exp())
            .collect();
        let norm: f64 = raw
            .iter()
            .enumerate()
            .map(|(i, w)| 2.0 * w * (i + 1) as f64)
            .sum();
        let taps = raw.iter().map(|w| (w / norm) as f32).collect();
        Ok(Self {
            settings: *settings,
            taps,
            deriv: Vec::new(),
        })
    }

    /// The settings.
    pub fn settings(&self) -> &EdgeSettings {
        &self.settings
    }

    /// Filter half-width in samples.
    pub fn radius(&self) -> usize {
        self.taps.len()
    }

    /// Detects edges in `profile`, whose sample `i` lies at integer offset `first_offset + i`
    /// along the line (1 px apart). Only maxima at integer offsets k in [k_min, k_max] whose
    /// neighbours k ± 1 have a full filter support inside the profile are considered; their
    /// sub-pixel offsets are appended to `out` in increasing order. Returns how many integer
    /// offsets in [k_min, k_max] could be examined (the observed part of the line).
    pub fn detect(
        &mut self,
        profile: &[f32],
        first_offset: i64,
        k_min: i64,
        k_max: i64,
        out: &mut Vec<f64>,
    ) -> usize {
        let r = self.taps.len() as i64;
        let len = profile.len() as i64;
        // Candidate indices: derivatives at idx − 1 and idx + 1 need samples idx − 1 − r and
        // idx + 1 + r.
        let lo = (r + 1).max(k_min - first_offset);
        let hi = (len - 2 - r).min(k_max - first_offset);
        if hi < lo {
            return 0;
        }
        let (lo, hi) = (lo as usize, hi as usize);
        // Derivatives at lo − 1 ..= hi + 1, stored from index 0.
        self.fill_derivatives(profile, lo - 1, hi + 1);
        for (i, d) in self.deriv.windows(3).enumerate() {
            if let Some(delta) = self.peak(d[0], d[1], d[2]) {
                let k = first_offset + (lo + i) as i64;
                out.push(k as f64 + f64::from(delta));
            }
        }
        hi - lo + 1
    }

    /// The filter responses at `profile[from ..= to]` into the derivative buffer
    /// ([`Self::responses`]): d_i = Σ_j w_j (s_{i+j} − s_{i−j}). Needs `r ≤ from`, `to + r < profile.len()`.
    pub(crate) fn fill_derivatives(&mut self, profile: &[f32], from: usize, to: usize) {
        let r = self.taps.len();
        let n = to + 1 - from;
        let s = &profile[from - r..to + r + 1];
        self.deriv.clear();
        self.deriv.resize(n, 0.0);
        let d = &mut self.deriv[..n];
        // Each response is summed from 0.0 in increasing j, whatever the radius, so every path
        // gives the same bits. The common radius 3 (σ = 1) is written as one pass over
        // equal-length slices, which the compiler vectorises without bounds checks.
        if let [w1, w2, w3] = *self.taps {
            let (p1, m1) = (&s[4..4 + n], &s[2..2 + n]);
            let (p2, m2) = (&s[5..5 + n], &s[1..1 + n]);
            let (p3, m3) = (&s[6..6 + n], &s[..n]);
            for i in 0..n {
                let mut v = 0.0f32;
                v += w1 * (p1[i] - m1[i]);
                v += w2 * (p2[i] - m2[i]);
                v += w3 * (p3[i] - m3[i]);
                d[i] = v;
            }
        } else {
            for (i, di) in d.iter_mut().enumerate() {
                let mut v = 0.0f32;
                for (j, w) in self.taps.iter().enumerate() {
                    v += w * (s[i + r + j + 1] - s[i + r - j - 1]);
                }
                *di = v;
            }
        }
    }

    /// The responses of the last [`Self::fill_derivatives`].
    #[inline]
    pub(crate) fn responses(&self) -> &[f32] {
        &self.deriv
    }

    /// Whether the middle of three consecutive filter responses `dm`, `d`, `dp` is an edge
    /// (polarity, threshold, non-maximum suppression), and if so its sub-pixel shift in
    /// [−0.5, 0.5] from the parabola through |dm|, |d|, |dp|.
    #[inline]
    pub(crate) fn peak(&self, dm: f32, d: f32, dp: f32) -> Option<f32> {
        let keep = match self.settings.polarity {
            Polarity::Any => true,
            Polarity::Rising => d > 0.0,
            Polarity::Falling => d < 0.0,
        };
        let (am, a0, ap) = (dm.abs(), d.abs(), dp.abs());
        // Non-maximum suppression; the asymmetric comparison keeps one sample of a plateau.
        if keep && a0 >= self.settings.threshold && a0 >= am && a0 > ap {
            Some(Self::vertex(am, a0, ap))
        } else {
            None
        }
    }

    /// The vertex of the parabola through the three |derivative| samples `am`, `a0`, `ap` of a
    /// maximum, as a shift from the middle one, clamped to [−0.5, 0.5].
    #[inline]
    pub(crate) fn vertex(am: f32, a0: f32, ap: f32) -> f32 {
        let den = am - 2.0 * a0 + ap;
        let delta = if den < 0.0 {
            0.5 * (am - ap) / den
        } else {
            0.0
        };
        delta.clamp(-0.5, 0.5)
    }

    /// Taps w_1 … w_r of the antisymmetric filter.
    #[inline]
    pub(crate) fn taps(&self) -> &[f32] {
        &self.taps
    }
}

/// Allocating convenience: the sub-pixel edge offsets of a whole profile, with sample `i` at
/// offset `i`.
///
/// # Errors
/// As [`EdgeSettings::validate`].
pub fn detect_edges(profile: &[f32], settings: &EdgeSettings) -> Result<Vec<f64>> {
    let mut det = EdgeDetector::new(settings)?;
    let mut out = Vec::new();
    det.detect(profile, 0, i64::MIN / 2, i64::MAX / 2, &mut out);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(n: usize, at: f64, height: f32) -> Vec<f32> {
        // An area-sampled step: pixel i covers [i − 0.5, i + 0.5].
        (0..n)
            .map(|i| height * ((i as f64 + 0.5 - at).clamp(0.0, 1.0) as f32))
            .collect()
    }

    #[test]
    fn ramp_gives_its_slope() {
        let mut det = EdgeDetector::new(&EdgeSettings::default()).unwrap();
        let ramp: Vec<f32> = (0..20).map(|i| 3.0 * i as f32).collect();
        let mut out = Vec::new();
        det.detect(&ramp, 0, 0, 19, &mut out);
        // The filter is normalised so that a ramp's derivative is its slope, everywhere
        // (tolerance: f32 rounding of the taps).
        assert!(!det.deriv.is_empty());
        for d in &det.deriv {
            assert!((d - 3.0).abs() < 1e-4, "{d}");
        }
    }

    #[test]
    fn sub_pixel_step_location() {
        // The parabola vertex on a Gaussian-blurred area-sampled step has a bias well below
        // 0.1 px for offsets across a pixel; 0.1 px is the bound checked.
        for k in 0..10 {
            let at = 10.0 + 0.1 * k as f64;
            let e = detect_edges(&step(21, at, 100.0), &EdgeSettings::default()).unwrap();
            assert_eq!(e.len(), 1, "{at}: {e:?}");
            assert!((e[0] - at).abs() < 0.1, "{at}: {e:?}");
        }
    }

    #[test]
    fn threshold_and_polarity() {
        let s = EdgeSettings::default();
        // Step of 15 grey levels: peak response 15/√(2π) ≈ 6 < 8.
        assert!(detect_edges(&step(21, 10.0, 15.0), &s).unwrap().is_empty());
        assert_eq!(detect_edges(&step(21, 10.0, 30.0), &s).unwrap().len(), 1);
        let rising = EdgeSettings {
            polarity: Polarity::Rising,
            ..s
        };
        let falling = EdgeSettings {
            polarity: Polarity::Falling,
            ..s
        };
        assert_eq!(
            detect_edges(&step(21, 10.0, 50.0), &rising).unwrap().len(),
            1
        );
        assert!(
            detect_edges(&step(21, 10.0, 50.0), &falling)
                .unwrap()
                .is_empty()
        );
        assert!(detect_edges(&[0.0; 30], &s).unwrap().is_empty());
    }

    #[test]
    fn validates() {
        assert!(
            EdgeSettings {
                sigma: 0.0,
                ..Default::default()
            }
            .validate()
            .is_err()
        );
        assert!(
            EdgeSettings {
                threshold: f32::NAN,
                ..Default::default()
            }
            .validate()
            .is_err()
        );
    }
}
