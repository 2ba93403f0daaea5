//! Smoothing a finite Markov chain backwards from its filtered marginals: p(s_t | Z_0..T) from
//! p(s_t | Z_0..t), t = 0..T, and the expected transition counts Σ_t p(s_t, s_{t+1} | Z_0..T)
//! that the re-estimation step of Baum–Welch needs.
//!
//! With f_t the filtered marginal, T the transition matrix and p_{t+1} = f_t T the prediction,
//! the smoothed marginals follow from the last one backwards (Rauch, Tung & Striebel's form of
//! the HMM smoother; Rabiner 1989's γ_t from α_t):
//!
//! **(H1)** s_T = f_T, s_t(i) = f_t(i) Σ_j T(i, j) s_{t+1}(j) / p_{t+1}(j),
//!
//! **(H2)** ξ_t(i, j) = f_t(i) T(i, j) s_{t+1}(j) / p_{t+1}(j), the two-step marginal.
//!
//! Both need only the filtered marginals, not the likelihoods that produced them, so a particle
//! tracker can smooth its hidden processes from the class probabilities it reports each frame.
//! A state with no predicted mass (p_{t+1}(j) = 0) passes none back.

use crate::error::{Error, Result};
use crate::markov::MarkovChain;

/// The smoothed marginals of a chain and its expected transition counts.
#[derive(Debug, Clone, PartialEq)]
pub struct SmoothedChain {
    /// `marginals[t][k] = p(state_t = k | Z_0..T)`.
    pub marginals: Vec<Vec<f64>>,
    /// `transitions[i][j] = Σ_t p(state_t = i, state_{t+1} = j | Z_0..T)` (Eq. H2 summed).
    pub transitions: Vec<Vec<f64>>,
}

impl MarkovChain {
    /// Smooths the filtered marginals `filtered` (one probability vector per step, oldest
    /// first) by Eq. (H1) and sums Eq. (H2).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] when a vector's length is not the number of states;
    /// [`Error::NotAProbabilityVector`] when one has a negative or non-finite entry or sums to
    /// zero; [`Error::ZeroEvidence`] when a step's smoothed marginal has no mass (the filtered
    /// marginals contradict the chain).
    pub fn smooth_filtered(&self, filtered: &[Vec<f64>]) -> Result<SmoothedChain> {
        let n = self.n_states();
        let mut normalised = Vec::with_capacity(filtered.len());
        for (t, f) in filtered.iter().enumerate() {
            if f.len() != n {
                return Err(Error::DimensionMismatch {
                    name: format!("filtered marginal {t}"),
                    expected: n,
                    got: f.len(),
                });
            }
            let sum: f64 = f.iter().sum();
            if f.iter().any(|v| !v.is_finite() || *v < 0.0)
                || sum.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
            {
                return Err(Error::NotAProbabilityVector {
                    name: format!("filtered marginal {t}"),
                    sum,
                });
            }
            normalised.push(f.iter().map(|v| v / sum).collect::<Vec<f64>>());
        }
        let mut transitions = vec![vec![0.0; n]; n];
        let Some(last) = normalised.last() else {
            return Ok(SmoothedChain {
                marginals: Vec::new(),
                transitions,
            });
        };
        let mut marginals = vec![Vec::new(); normalised.len()];
        marginals[normalised.len() - 1] = last.clone();
        let mut predicted = vec![0.0; n];
        let mut ratio = vec![0.0; n];
        let mut xi = vec![vec![0.0; n]; n];
        for t in (0..normalised.len() - 1).rev() {
            let f = &normalised[t];
            self.predict_into(f, &mut predicted)?;
            for ((r, &s), &p) in ratio.iter_mut().zip(&marginals[t + 1]).zip(&predicted) {
                *r = if p > 0.0 { s / p } else { 0.0 };
            }
            let mut total = 0.0;
            for (i, row) in xi.iter_mut().enumerate() {
                for (j, x) in row.iter_mut().enumerate() {
                    *x = f[i] * self.prob(i, j) * ratio[j];
                    total += *x;
                }
            }
            if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                return Err(Error::ZeroEvidence { step: t });
            }
            let mut s = vec![0.0; n];
            for (i, row) in xi.iter().enumerate() {
                for (j, x) in row.iter().enumerate() {
                    let x = x / total;
                    s[i] += x;
                    transitions[i][j] += x;
                }
            }
            marginals[t] = s;
        }
        Ok(SmoothedChain {
            marginals,
            transitions,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force over every path of a short chain with per-step likelihoods.
    fn exact(
        chain: &MarkovChain,
        prior: &[f64],
        lik: &[Vec<f64>],
    ) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let n = chain.n_states();
        let t_len = lik.len();
        let mut marg = vec![vec![0.0; n]; t_len];
        let mut trans = vec![vec![0.0; n]; n];
        let mut total = 0.0;
        let paths = n.pow(t_len as u32);
        for code in 0..paths {
            let path: Vec<usize> = (0..t_len).map(|t| (code / n.pow(t as u32)) % n).collect();
            let mut p = prior[path[0]] * lik[0][path[0]];
            for t in 1..t_len {
                p *= chain.prob(path[t - 1], path[t]) * lik[t][path[t]];
            }
            total += p;
            for t in 0..t_len {
                marg[t][path[t]] += p;
                if t + 1 < t_len {
                    trans[path[t]][path[t + 1]] += p;
                }
            }
        }
        for m in &mut marg {
            m.iter_mut().for_each(|v| *v /= total);
        }
        for r in &mut trans {
            r.iter_mut().for_each(|v| *v /= total);
        }
        (marg, trans)
    }

    #[test]
    fn smoothing_the_filtered_marginals_gives_the_exact_posterior() {
        let chain = MarkovChain::new(&[
            vec![0.8, 0.15, 0.05],
            vec![0.1, 0.7, 0.2],
            vec![0.05, 0.25, 0.7],
        ])
        .unwrap();
        let prior = [0.5, 0.3, 0.2];
        let lik = vec![
            vec![0.9, 0.2, 0.1],
            vec![0.3, 0.6, 0.1],
            vec![0.05, 0.3, 0.9],
            vec![0.2, 0.2, 0.7],
            vec![0.6, 0.5, 0.1],
        ];
        // Forward filter by hand.
        let mut filtered = Vec::new();
        let mut belief: Vec<f64> = prior.iter().zip(&lik[0]).map(|(p, l)| p * l).collect();
        let s: f64 = belief.iter().sum();
        belief.iter_mut().for_each(|v| *v /= s);
        filtered.push(belief.clone());
        for l in &lik[1..] {
            let mut predicted = vec![0.0; 3];
            chain.predict_into(&belief, &mut predicted).unwrap();
            chain.update_in_place(&mut predicted, l, 0).unwrap();
            belief = predicted;
            filtered.push(belief.clone());
        }
        let smoothed = chain.smooth_filtered(&filtered).unwrap();
        let (marg, trans) = exact(&chain, &prior, &lik);
        for (a, b) in smoothed.marginals.iter().zip(&marg) {
            for (x, y) in a.iter().zip(b) {
                assert!((x - y).abs() < 1e-12, "{a:?} {b:?}");
            }
        }
        for (a, b) in smoothed.transitions.iter().zip(&trans) {
            for (x, y) in a.iter().zip(b) {
                assert!((x - y).abs() < 1e-12, "{a:?} {b:?}");
            }
        }
    }

    #[test]
    fn bad_marginals_are_refused() {
        let chain = MarkovChain::new(&[vec![0.9, 0.1], vec![0.2, 0.8]]).unwrap();
        assert!(chain.smooth_filtered(&[vec![0.5, 0.5], vec![1.0]]).is_err());
        assert!(chain.smooth_filtered(&[vec![0.5, f64::NAN]]).is_err());
        assert!(chain.smooth_filtered(&[vec![0.0, 0.0]]).is_err());
        // A certain state that the chain cannot leave contradicts a later certain other state.
        let absorbing = MarkovChain::new(&[vec![1.0, 0.0], vec![0.0, 1.0]]).unwrap();
        assert!(
            absorbing
                .smooth_filtered(&[vec![1.0, 0.0], vec![0.0, 1.0]])
                .is_err()
        );
        assert!(chain.smooth_filtered(&[]).unwrap().marginals.is_empty());
    }
}
