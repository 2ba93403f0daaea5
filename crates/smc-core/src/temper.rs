//! Adaptive tempering of importance weights: raise the likelihood to the largest power
//! φ ∈ (0, 1] that keeps the effective sample size at or above a floor.
//!
//! A likelihood that is sharp next to the prior's spread (a template that scores the true
//! position tens of nats above its surroundings) puts nearly all the mass on one particle, and
//! the next resampling collapses the set. Tempering weighs particles by p(z|x)^φ instead, with φ
//! chosen per step so that ESS(φ) ≥ `min_ess` (Jasra, Stephens, Doucet & Tsagaris 2011, §3.3:
//! the exponent chosen adaptively from the ESS; Neal 2001 for tempered importance weights). φ = 1
//! whenever the untempered weights already keep the floor, so a well-behaved step is untouched.
//!
//! **Why bisection finds it.** With l = log w and E_ψ the expectation under weights ∝ e^{ψ l},
//! log ESS(φ) = 2 log Σ e^{φ l} − log Σ e^{2φ l}, whose derivative is 2 E_φ[l] − 2 E_{2φ}[l]. Since
//! d/dψ E_ψ[l] = Var_ψ(l) ≥ 0, E_{2φ}[l] ≥ E_φ[l]: the ESS never grows with φ. The set
//! {φ : ESS(φ) ≥ min_ess} is therefore an interval (0, φ*], and bisection converges to φ*.

use crate::error::Degeneracy;
use crate::weights::{effective_sample_size, normalize_log_weights};

/// Bisection steps: φ is found to within 2⁻³⁰ of the largest exponent that keeps the floor.
pub const BISECTION_STEPS: usize = 30;

/// What [`temper`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tempered {
    /// The exponent φ ∈ [0, 1] applied to the log weights (1: untouched).
    pub exponent: f64,
    /// The effective sample size of the tempered weights.
    pub ess: f64,
}

/// Tempers `log_weights` in place so that their effective sample size is at least `min_ess`:
/// replaces them by the normalised φ · log w for the largest φ ∈ (0, 1] that keeps the floor
/// (φ = 1 when the weights already do), fills `weights` with the normalised linear weights, and
/// returns φ and the resulting ESS. `scratch` holds the untempered values between trials (kept
/// by the caller so that the hot loop does not allocate).
///
/// A floor above the number of finite weights cannot be met: φ then tends to 0, where every
/// particle with a finite log weight counts equally.
///
/// # Errors
/// [`Degeneracy`] when the log weights hold a NaN or a +∞, or are all −∞; the log weights are
/// then left as they were.
///
/// # Examples
/// ```
/// use smc_core::temper::temper;
/// // One particle 40 nats above the others: its weight would be ~1 and the ESS ~1.
/// let mut lw = vec![0.0; 100];
/// lw[0] = 40.0;
/// let (mut w, mut scratch) = (Vec::new(), Vec::new());
/// let t = temper(&mut lw, &mut w, &mut scratch, 30.0)?;
/// assert!(t.exponent < 1.0 && t.ess >= 30.0);
/// # Ok::<(), smc_core::Degeneracy>(())
/// ```
pub fn temper(
    log_weights: &mut [f64],
    weights: &mut Vec<f64>,
    scratch: &mut Vec<f64>,
    min_ess: f64,
) -> Result<Tempered, Degeneracy> {
    scratch.clear();
    scratch.extend_from_slice(log_weights);
    let raw = &*scratch;
    let apply = |phi: f64, lw: &mut [f64], w: &mut Vec<f64>| -> Result<f64, Degeneracy> {
        for (t, r) in lw.iter_mut().zip(raw) {
            // 0 · −∞ would be NaN: a particle with no likelihood keeps none at any exponent.
            *t = if r.is_infinite() { *r } else { phi * r };
        }
        normalize_log_weights(lw, w)?;
        Ok(effective_sample_size(w))
    };
    let restore = |lw: &mut [f64]| lw.copy_from_slice(raw);
    let ess = apply(1.0, log_weights, weights).inspect_err(|_| restore(log_weights))?;
    if ess >= min_ess {
        return Ok(Tempered { exponent: 1.0, ess });
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..BISECTION_STEPS {
        let mid = 0.5 * (lo + hi);
        if apply(mid, log_weights, weights)? >= min_ess {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let ess = apply(lo, log_weights, weights)?;
    Ok(Tempered { exponent: lo, ess })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn run(lw: &[f64], min_ess: f64) -> (Vec<f64>, Vec<f64>, Tempered) {
        let mut lw = lw.to_vec();
        let (mut w, mut s) = (Vec::new(), Vec::new());
        let t = temper(&mut lw, &mut w, &mut s, min_ess).unwrap();
        (lw, w, t)
    }

    #[test]
    fn weights_that_keep_the_floor_are_only_normalised() {
        let lw = [0.0, -0.1, -0.2, -0.3];
        let (out, w, t) = run(&lw, 3.0);
        assert_eq!(t.exponent, 1.0);
        let mut expected = lw.to_vec();
        let mut we = Vec::new();
        normalize_log_weights(&mut expected, &mut we).unwrap();
        assert_eq!(out, expected);
        assert_eq!(w, we);
        assert!((t.ess - effective_sample_size(&w)).abs() < 1e-12);
    }

    #[test]
    fn a_dominant_particle_is_tempered_to_the_floor_exactly() {
        // One particle 40 nats up among 199 equal ones: ESS(1) ≈ 1. The tempered ESS sits on
        // the floor (bisection to 2⁻³⁰ in φ), and a slightly larger φ would fall below it.
        let mut lw = vec![0.0; 200];
        lw[7] = 40.0;
        let (out, w, t) = run(&lw, 60.0);
        assert!(t.exponent > 0.0 && t.exponent < 1.0, "{t:?}");
        assert!(t.ess >= 60.0 && t.ess < 60.0 + 1e-4, "{t:?}");
        // The closed form: weights ∝ e^{40φ} (one) and 1 (199 others).
        let a = (40.0 * t.exponent).exp();
        let ess = (a + 199.0).powi(2) / (a * a + 199.0);
        assert!((ess - t.ess).abs() < 1e-9, "{ess} vs {}", t.ess);
        let above = {
            let b = (40.0 * (t.exponent + 1e-6)).exp();
            (b + 199.0).powi(2) / (b * b + 199.0)
        };
        assert!(above < 60.0);
        // The log weights are the normalised tempered ones.
        for (l, wi) in out.iter().zip(&w) {
            assert!((l.exp() - wi).abs() < 1e-15);
        }
    }

    #[test]
    fn minus_infinity_stays_without_mass_and_degenerate_weights_are_an_error() {
        let (out, w, t) = run(&[f64::NEG_INFINITY, 30.0, 0.0, 0.0], 2.5);
        assert_eq!(out[0], f64::NEG_INFINITY);
        assert_eq!(w[0], 0.0);
        assert!(t.ess >= 2.5 && t.exponent < 1.0, "{t:?}");
        for bad in [
            vec![f64::NAN, 0.0],
            vec![f64::INFINITY, 0.0],
            vec![f64::NEG_INFINITY; 3],
        ] {
            let mut lw = bad.clone();
            let (mut w, mut s) = (Vec::new(), Vec::new());
            assert!(temper(&mut lw, &mut w, &mut s, 1.0).is_err());
            assert_eq!(format!("{lw:?}"), format!("{bad:?}"), "left as they were");
        }
    }

    #[test]
    fn an_unreachable_floor_tends_to_equal_weights() {
        let (_, w, t) = run(&[5.0, 0.0, -3.0], 10.0);
        assert!(t.exponent < 1e-8, "{t:?}");
        assert!(w.iter().all(|x| (x - 1.0 / 3.0).abs() < 1e-7), "{w:?}");
    }

    proptest! {
        #[test]
        fn the_floor_is_kept_and_phi_is_the_largest_that_keeps_it(
            lw in prop::collection::vec(-50.0f64..50.0, 2..300),
            frac in 0.05f64..0.95,
            shift in -1e3f64..1e3,
        ) {
            let min_ess = frac * lw.len() as f64;
            let (_, w, t) = run(&lw, min_ess);
            prop_assert!(t.ess >= min_ess * (1.0 - 1e-12));
            prop_assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-9);
            if t.exponent < 1.0 {
                // Just above φ the floor is lost (ESS never grows with φ).
                let mut up: Vec<f64> = lw.iter().map(|l| (t.exponent + 1e-7) * l).collect();
                let mut wu = Vec::new();
                normalize_log_weights(&mut up, &mut wu).unwrap();
                prop_assert!(effective_sample_size(&wu) < min_ess + 1e-6 * min_ess);
            }
            // A constant added to every log weight changes nothing.
            let shifted: Vec<f64> = lw.iter().map(|l| l + shift).collect();
            let (_, ws, ts) = run(&shifted, min_ess);
            prop_assert!((ts.exponent - t.exponent).abs() < 1e-6);
            for (a, b) in w.iter().zip(&ws) {
                prop_assert!((a - b).abs() < 1e-6);
            }
        }
    }
}
