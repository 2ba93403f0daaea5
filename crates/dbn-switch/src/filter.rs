//! Exact forward filtering of a finite Markov chain: the posterior class probabilities
//! `p(β_t | Z_1..t)` of Wu et al. Eq. 7–8 when the hidden process is discrete alone, given the
//! per-step observation likelihoods `p(Z_t | β_t = k)`.
//!
//! Trackers approximate the same recursion with particles; this exact version is the reference
//! the particle estimates are checked against, and is useful on its own for offline smoothing of
//! a sequence of per-class likelihoods.

use crate::error::{Error, Result};
use crate::markov::{MarkovChain, ROW_SUM_TOLERANCE};

/// Posterior class probabilities of a whole sequence and its log evidence.
#[derive(Debug, Clone, PartialEq)]
pub struct ForwardResult {
    /// `posteriors[t][k] = p(state_t = k | Z_0..t)`.
    pub posteriors: Vec<Vec<f64>>,
    /// `ln p(Z_0..T)`, the sum of the per-step log normalisers.
    pub log_evidence: f64,
}

impl MarkovChain {
    /// Prediction, Wu Eq. 8 for a discrete state: `out[j] = Σ_i posterior[i] T[i][j]`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] when either slice's length is not the number of states.
    pub fn predict_into(&self, posterior: &[f64], out: &mut [f64]) -> Result<()> {
        let n = self.n_states();
        check_len("posterior", n, posterior.len())?;
        check_len("prediction buffer", n, out.len())?;
        out.fill(0.0);
        for (i, &p) in posterior.iter().enumerate() {
            if let Some(row) = self.row(i) {
                for (o, &t) in out.iter_mut().zip(row) {
                    *o += p * t;
                }
            }
        }
        Ok(())
    }

    /// Correction, Wu Eq. 7: multiplies `belief` by `likelihood` in place and normalises it.
    /// Returns the log normaliser `ln Σ_k belief[k] likelihood[k]` (the step's log evidence).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`], [`Error::InvalidLikelihood`] for a negative or non-finite
    /// likelihood, [`Error::ZeroEvidence`] when every state gets zero mass. `step` only labels
    /// the error.
    pub fn update_in_place(
        &self,
        belief: &mut [f64],
        likelihood: &[f64],
        step: usize,
    ) -> Result<f64> {
        let n = self.n_states();
        check_len("belief", n, belief.len())?;
        check_len("likelihood", n, likelihood.len())?;
        for (state, &l) in likelihood.iter().enumerate() {
            if !l.is_finite() || l < 0.0 {
                return Err(Error::InvalidLikelihood {
                    step,
                    state,
                    value: l,
                });
            }
        }
        let mut z = 0.0;
        for (b, &l) in belief.iter_mut().zip(likelihood) {
            *b *= l;
            z += *b;
        }
        if !z.is_finite() || z <= 0.0 {
            return Err(Error::ZeroEvidence { step });
        }
        for b in belief.iter_mut() {
            *b /= z;
        }
        Ok(z.ln())
    }

    /// Forward filter over a whole sequence, writing the posteriors row by row into `out`
    /// (`likelihoods.len() × n`, row-major). `initial` is the distribution of the state at the
    /// first step before its observation; `likelihoods[t][k] = p(Z_t | state_t = k)`.
    /// Returns the log evidence `ln p(Z_0..T)`.
    ///
    /// # Errors
    /// [`Error::NotAProbabilityVector`] for a bad `initial`, and those of
    /// [`Self::predict_into`] and [`Self::update_in_place`].
    pub fn forward_filter_into<L: AsRef<[f64]>>(
        &self,
        initial: &[f64],
        likelihoods: &[L],
        out: &mut [f64],
    ) -> Result<f64> {
        let n = self.n_states();
        check_len("initial distribution", n, initial.len())?;
        check_probability_vector("initial distribution", initial)?;
        check_len("posterior buffer", n * likelihoods.len(), out.len())?;
        let mut log_evidence = 0.0;
        for (t, likelihood) in likelihoods.iter().enumerate() {
            let (done, rest) = out.split_at_mut(t * n);
            let current = &mut rest[..n];
            if t == 0 {
                current.copy_from_slice(initial);
            } else {
                self.predict_into(&done[(t - 1) * n..], current)?;
            }
            log_evidence += self.update_in_place(current, likelihood.as_ref(), t)?;
        }
        Ok(log_evidence)
    }

    /// Allocating twin of [`Self::forward_filter_into`].
    ///
    /// # Errors
    /// As [`Self::forward_filter_into`].
    ///
    /// # Examples
    /// ```
    /// let chain = dbn_switch::MarkovChain::new(&[vec![0.9, 0.1], vec![0.2, 0.8]])?;
    /// let result = chain.forward_filter(&[0.5, 0.5], &[vec![0.6, 0.2]])?;
    /// assert!((result.posteriors[0][0] - 0.75).abs() < 1e-12);
    /// # Ok::<(), dbn_switch::Error>(())
    /// ```
    pub fn forward_filter<L: AsRef<[f64]>>(
        &self,
        initial: &[f64],
        likelihoods: &[L],
    ) -> Result<ForwardResult> {
        let n = self.n_states();
        let mut flat = vec![0.0; n * likelihoods.len()];
        let log_evidence = self.forward_filter_into(initial, likelihoods, &mut flat)?;
        Ok(ForwardResult {
            posteriors: flat.chunks(n).map(<[f64]>::to_vec).collect(),
            log_evidence,
        })
    }
}

fn check_len(name: &str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(Error::DimensionMismatch {
            name: name.to_owned(),
            expected,
            got,
        })
    }
}

/// Checks that `p` has non-negative finite entries summing to 1 within [`ROW_SUM_TOLERANCE`].
pub(crate) fn check_probability_vector(name: &str, p: &[f64]) -> Result<()> {
    let valid = p.iter().all(|x| x.is_finite() && *x >= 0.0);
    let sum: f64 = if valid { p.iter().sum() } else { f64::NAN };
    if valid && (sum - 1.0).abs() <= ROW_SUM_TOLERANCE {
        Ok(())
    } else {
        Err(Error::NotAProbabilityVector {
            name: name.to_owned(),
            sum,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Three steps of a two-state chain, computed by hand with exact fractions.
    ///
    /// T = [[0.9, 0.1], [0.2, 0.8]], initial (1/2, 1/2),
    /// likelihoods L0 = (0.6, 0.2), L1 = (0.3, 0.9), L2 = (0.5, 0.25).
    ///
    /// Step 0: prior (1/2, 1/2); prior·L0 = (3/10, 1/10), Z0 = 2/5; posterior (3/4, 1/4).
    /// Step 1: prior = (3/4·0.9 + 1/4·0.2, 3/4·0.1 + 1/4·0.8) = (29/40, 11/40);
    ///         prior·L1 = (87/400, 99/400), Z1 = 186/400 = 93/200; posterior (29/62, 33/62).
    /// Step 2: prior = (29/62·0.9 + 33/62·0.2, 29/62·0.1 + 33/62·0.8)
    ///               = (32.7/62, 29.3/62) = (327/620, 293/620);
    ///         prior·L2 = (327/1240, 293/2480), Z2 = 947/2480; posterior (654/947, 293/947).
    /// Evidence Z0·Z1·Z2 = (2·93·947)/(5·200·2480) = 176142/2480000 = 2841/40000.
    #[test]
    fn forward_filter_reproduces_hand_computed_three_step_example() {
        let chain = MarkovChain::new(&[[0.9, 0.1], [0.2, 0.8]]).unwrap();
        let likelihoods = [[0.6, 0.2], [0.3, 0.9], [0.5, 0.25]];
        let result = chain.forward_filter(&[0.5, 0.5], &likelihoods).unwrap();
        let expected = [
            [3.0 / 4.0, 1.0 / 4.0],
            [29.0 / 62.0, 33.0 / 62.0],
            [654.0 / 947.0, 293.0 / 947.0],
        ];
        for (got, want) in result.posteriors.iter().zip(expected) {
            for (g, w) in got.iter().zip(want) {
                assert_relative_eq!(*g, w, epsilon = 1e-12);
            }
        }
        assert_relative_eq!(
            result.log_evidence,
            (2841.0f64 / 40000.0).ln(),
            epsilon = 1e-12
        );
    }

    #[test]
    fn forward_filter_rejects_bad_inputs() {
        let chain = MarkovChain::new(&[[0.9, 0.1], [0.2, 0.8]]).unwrap();
        assert!(matches!(
            chain.forward_filter(&[0.5, 0.5], &[[0.5, f64::NAN]]),
            Err(Error::InvalidLikelihood {
                step: 0,
                state: 1,
                ..
            })
        ));
        assert!(matches!(
            chain.forward_filter(&[0.5, 0.5], &[[0.5, 0.5], [0.0, 0.0]]),
            Err(Error::ZeroEvidence { step: 1 })
        ));
        assert!(matches!(
            chain.forward_filter(&[0.7, 0.5], &[[0.5, 0.5]]),
            Err(Error::NotAProbabilityVector { .. })
        ));
        assert!(matches!(
            chain.forward_filter(&[0.5, 0.5], &[vec![0.5, 0.5, 0.1]]),
            Err(Error::DimensionMismatch {
                expected: 2,
                got: 3,
                ..
            })
        ));
    }
}
