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
//! log ESS(φ) = 2 log Σ e^{φ l} − log Σ e^{2φ l}, whose derivative is 2 E_φ\[l\] − 2 E_{2φ}\[l\]. Since
//! d/dψ E_ψ\[l\] = Var_ψ(l) ≥ 0, E_{2φ}\[l\] ≥ E_φ\[l\]: the ESS never grows with φ. The set
//! {φ : ESS(φ) ≥ min_ess} is therefore an interval (0, φ*], and bisection converges to φ*.

use crate::error::{Degeneracy, Error};
use crate::particles::check_len;
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
    let tempered = largest_exponent(min_ess, |phi| apply(phi, log_weights, weights));
    if tempered.is_err() {
        log_weights.copy_from_slice(raw);
    }
    let (exponent, ess) = tempered?;
    Ok(Tempered { exponent, ess })
}

/// The largest φ ∈ (0, 1] with `measure(φ)` ≥ `min` (1 when φ = 1 does; found to 2⁻³⁰ by
/// bisection, since the ESS and the conditional ESS never grow with φ), and the measure there.
/// The last call of `measure` is at the φ returned, so whatever it fills holds that φ's weights.
fn largest_exponent<E>(
    min: f64,
    mut measure: impl FnMut(f64) -> Result<f64, E>,
) -> Result<(f64, f64), E> {
    let at_one = measure(1.0)?;
    if at_one >= min {
        return Ok((1.0, at_one));
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..BISECTION_STEPS {
        let mid = 0.5 * (lo + hi);
        if measure(mid)? >= min {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok((lo, measure(lo)?))
}

/// The largest exponent φ ∈ (0, 1] whose tempered likelihood keeps a *conditional* effective
/// sample size of at least `min_cess` (φ = 1 when the untempered likelihood already does), for
/// an update whose log weights are `offsets[i]` + φ · `log_likelihoods[i]`: the offsets (the
/// previous log weights and the prior-over-proposal ratio of Odobez Eq. 3) enter at full
/// strength, only the likelihood is tempered. `weights` receives the normalised updated weights
/// at that φ; `scratch` is a buffer.
///
/// The conditional ESS (Zhou, Johansen & Aston 2016, §3.2) measures what the likelihood alone
/// does to the weights the offsets give, b ∝ exp(offsets): with u_i = p(z | x_i)^φ,
/// CESS(φ) = N (Σ b_i u_i)² / Σ b_i u_i². With equal offsets it is the ESS of the updated
/// weights, as [`temper`] uses. Unlike the ESS, it can always be met (CESS(0) = N), so an update
/// whose offsets are themselves uneven (a proposal far from the prior) never drives φ to 0 and
/// the data out.
///
/// # Errors
/// [`Error::LengthMismatch`] when the slices differ in length; [`Error::InvalidWeights`] when
/// some value is NaN or +∞ or every updated weight is zero.
///
/// # Examples
/// ```
/// use smc_core::temper::tempering_exponent;
/// let mut ll = vec![0.0; 100];
/// ll[0] = 40.0;
/// let offsets = vec![-(100f64).ln(); 100];
/// let (mut w, mut s) = (Vec::new(), Vec::new());
/// let t = tempering_exponent(&ll, &offsets, 30.0, &mut w, &mut s)?;
/// assert!(t.exponent < 1.0 && t.ess >= 30.0 - 1e-6);
/// # Ok::<(), smc_core::Error>(())
/// ```
pub fn tempering_exponent(
    log_likelihoods: &[f64],
    offsets: &[f64],
    min_cess: f64,
    weights: &mut Vec<f64>,
    scratch: &mut Vec<f64>,
) -> crate::Result<Tempered> {
    check_len("offsets", log_likelihoods.len(), offsets.len())?;
    let invalid = |reason| Error::InvalidWeights { reason };
    // b: the normalised weights of the offsets alone.
    scratch.clear();
    scratch.extend_from_slice(offsets);
    let mut base = Vec::with_capacity(offsets.len());
    normalize_log_weights(scratch, &mut base).map_err(invalid)?;
    let n = log_likelihoods.len() as f64;
    let mut apply = |phi: f64, w: &mut Vec<f64>| -> crate::Result<f64> {
        scratch.clear();
        scratch.extend(log_likelihoods.iter().zip(offsets).map(|(&l, &o)| {
            // 0 · −∞ would be NaN: a particle with no likelihood keeps none at any exponent.
            if l.is_infinite() { l + o } else { phi * l + o }
        }));
        normalize_log_weights(scratch, w).map_err(invalid)?;
        // w_i ∝ b_i u_i, so u_i ∝ w_i / b_i where b_i > 0 (w_i = 0 where b_i = 0).
        let (mut first, mut second) = (0.0, 0.0);
        for (&wi, &bi) in w.iter().zip(&base) {
            if bi > 0.0 {
                first += wi;
                second += wi * wi / bi;
            }
        }
        Ok(if second > 0.0 {
            n * first * first / second
        } else {
            0.0
        })
    };
    let (exponent, _) = largest_exponent(min_cess, |phi| apply(phi, weights))?;
    Ok(Tempered {
        exponent,
        ess: effective_sample_size(weights),
    })
}

/// `log_likelihoods` raised to the power `exponent` in place (−∞ stays −∞).
pub fn apply_exponent(log_likelihoods: &mut [f64], exponent: f64) {
    if exponent == 1.0 {
        return;
    }
    for l in log_likelihoods {
        if l.is_finite() {
            *l *= exponent;
        }
    }
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

    #[test]
    fn offsets_are_not_tempered_and_zero_offsets_agree_with_temper() {
        let mut ll = vec![0.0; 50];
        ll[3] = 30.0;
        let zeros = vec![0.0; 50];
        let (mut w, mut s) = (Vec::new(), Vec::new());
        let t = tempering_exponent(&ll, &zeros, 20.0, &mut w, &mut s).unwrap();
        let (_, w2, t2) = run(&ll, 20.0);
        assert_eq!(t, t2);
        assert_eq!(w, w2);
        // An offset of −∞ keeps a particle out whatever φ; a large offset on another particle
        // is kept at full strength (only the likelihood is tempered).
        let mut offsets = vec![0.0; 50];
        offsets[3] = f64::NEG_INFINITY;
        let t = tempering_exponent(&ll, &offsets, 20.0, &mut w, &mut s).unwrap();
        assert_eq!(t.exponent, 1.0);
        assert_eq!(w[3], 0.0);
        // Uneven offsets alone (one particle e^8 above the rest) are not tempered away: the
        // conditional ESS measures the likelihood only, and is N at φ = 0.
        let mut offsets = vec![0.0; 50];
        offsets[5] = 8.0;
        let t = tempering_exponent(&ll, &offsets, 20.0, &mut w, &mut s).unwrap();
        assert!(t.exponent > 0.0 && t.exponent < 1.0, "{t:?}");
        let b: Vec<f64> = {
            let mut o = offsets.clone();
            let mut b = Vec::new();
            normalize_log_weights(&mut o, &mut b).unwrap();
            b
        };
        let u: Vec<f64> = ll.iter().map(|l| (t.exponent * l).exp()).collect();
        let first: f64 = b.iter().zip(&u).map(|(b, u)| b * u).sum();
        let second: f64 = b.iter().zip(&u).map(|(b, u)| b * u * u).sum();
        let cess = 50.0 * first * first / second;
        assert!((cess - 20.0).abs() < 1e-4, "{cess}");
        for i in 0..50 {
            assert!((w[i] - b[i] * u[i] / first).abs() < 1e-12);
        }
        assert!(tempering_exponent(&ll, &offsets[..3], 1.0, &mut w, &mut s).is_err());
        let mut scaled = ll.clone();
        apply_exponent(&mut scaled, 0.5);
        assert_eq!(scaled[3], 15.0);
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
