//! A finite Markov chain with a validated transition matrix: the `T_β` of Wu et al. Eq. 15 and
//! the `T_α` of §6.3.

use rand::Rng;

use crate::error::{Error, Result};

/// How far a row sum may be from 1 and still be a probability row. Loose enough for matrices
/// typed by hand in a configuration file with a few decimals (`1/3 ≈ 0.333333`), tight enough to
/// catch a wrong entry.
pub const ROW_SUM_TOLERANCE: f64 = 1e-6;

/// Below this pivot the linear system for the stationary distribution is treated as singular.
const SINGULAR_PIVOT: f64 = 1e-12;

/// A finite, time-homogeneous Markov chain on the states `0..n`.
///
/// `matrix[i][j] = p(next = j | previous = i)`, the convention of Wu et al. Eq. 15. Rows are
/// renormalised on construction, so that sampling and densities are exact even for a row typed
/// with a rounding error within [`ROW_SUM_TOLERANCE`].
#[derive(Debug, Clone, PartialEq)]
pub struct MarkovChain {
    n: usize,
    /// Row-major `n × n` transition probabilities.
    probs: Vec<f64>,
}

impl MarkovChain {
    /// Builds a chain from the rows of its transition matrix.
    ///
    /// # Errors
    /// [`Error::EmptyMatrix`], [`Error::NonSquareMatrix`], [`Error::InvalidProbability`] for a
    /// negative or non-finite entry, [`Error::InvalidTransitionMatrix`] for a row whose sum is
    /// not 1 within [`ROW_SUM_TOLERANCE`].
    ///
    /// # Examples
    /// ```
    /// let chain = dbn_switch::MarkovChain::new(&[vec![0.9, 0.1], vec![0.2, 0.8]])?;
    /// assert_eq!(chain.n_states(), 2);
    /// assert!(dbn_switch::MarkovChain::new(&[vec![0.9, 0.2], vec![0.2, 0.8]]).is_err());
    /// # Ok::<(), dbn_switch::Error>(())
    /// ```
    pub fn new<Row: AsRef<[f64]>>(rows: &[Row]) -> Result<Self> {
        validate_matrix(rows)?;
        let n = rows.len();
        let mut probs = Vec::with_capacity(n * n);
        for row in rows {
            let row = row.as_ref();
            let sum: f64 = row.iter().sum();
            probs.extend(row.iter().map(|p| p / sum));
        }
        Ok(Self { n, probs })
    }

    /// Number of states.
    #[must_use]
    pub fn n_states(&self) -> usize {
        self.n
    }

    /// The row `p(· | previous = i)`, or `None` when `i` is out of range.
    #[must_use]
    pub fn row(&self, i: usize) -> Option<&[f64]> {
        (i < self.n).then(|| &self.probs[i * self.n..(i + 1) * self.n])
    }

    /// `p(next = j | previous = i)`; 0 when either index is out of range.
    #[must_use]
    pub fn prob(&self, i: usize, j: usize) -> f64 {
        if i < self.n && j < self.n {
            self.probs[i * self.n + j]
        } else {
            0.0
        }
    }

    /// Draws the next state from `previous`.
    ///
    /// A label outside `0..n` carries no information about the next state, so the next one is
    /// then drawn uniformly; [`Self::log_transition`] uses the same rule, so sampling and density
    /// stay consistent.
    pub fn sample_next<R: Rng + ?Sized>(&self, previous: usize, rng: &mut R) -> usize {
        match self.row(previous) {
            Some(row) => sample_categorical(row, rng),
            None => rng.random_range(0..self.n),
        }
    }

    /// Draws the next state from the defensive mixture `q = (1 − ε)·T[previous] + ε·uniform`, a
    /// proposal that keeps exploring every state however sticky `T` is; with `ε = 0` it draws
    /// nothing more than [`Self::sample_next`]. Weight by [`Self::log_exploration_ratio`].
    pub fn sample_next_exploring<R: Rng + ?Sized>(
        &self,
        previous: usize,
        exploration: f64,
        rng: &mut R,
    ) -> usize {
        if exploration > 0.0 && rng.random::<f64>() < exploration {
            rng.random_range(0..self.n)
        } else {
            self.sample_next(previous, rng)
        }
    }

    /// `ln T[previous][next] − ln q(next | previous)`, the importance ratio of a state drawn by
    /// [`Self::sample_next_exploring`] with the same `ε` (0 when `ε = 0`).
    #[must_use]
    pub fn log_exploration_ratio(&self, previous: usize, next: usize, exploration: f64) -> f64 {
        if exploration <= 0.0 {
            return 0.0;
        }
        let p = self.log_transition(previous, next);
        let q = ((1.0 - exploration) * p.exp() + exploration / self.n as f64).ln();
        p - q
    }

    /// `ln p(next | previous)`; `−∞` for an impossible transition or a `next` out of range, and
    /// `−ln n` for a `previous` out of range (see [`Self::sample_next`]).
    #[must_use]
    pub fn log_transition(&self, previous: usize, next: usize) -> f64 {
        if next >= self.n {
            f64::NEG_INFINITY
        } else if previous >= self.n {
            -(self.n as f64).ln()
        } else {
            self.probs[previous * self.n + next].ln()
        }
    }

    /// Writes a path of `out.len()` states starting with `start` (so `out[0] = start`).
    pub fn sample_path_into<R: Rng + ?Sized>(&self, start: usize, out: &mut [usize], rng: &mut R) {
        let mut state = start;
        for (t, slot) in out.iter_mut().enumerate() {
            if t > 0 {
                state = self.sample_next(state, rng);
            }
            *slot = state;
        }
    }

    /// Allocating twin of [`Self::sample_path_into`].
    pub fn sample_path<R: Rng + ?Sized>(
        &self,
        start: usize,
        len: usize,
        rng: &mut R,
    ) -> Vec<usize> {
        let mut out = vec![0; len];
        self.sample_path_into(start, &mut out, rng);
        out
    }

    /// The stationary distribution `π = π T`, `Σ π = 1`, solved exactly by Gaussian elimination
    /// with partial pivoting on `(Tᵀ − I)` with one equation replaced by the normalisation.
    ///
    /// # Errors
    /// [`Error::NoUniqueStationary`] when the chain is reducible (the system is singular).
    pub fn stationary(&self) -> Result<Vec<f64>> {
        let n = self.n;
        // Augmented system A π = b, A = Tᵀ − I with the last row replaced by ones.
        let mut a = vec![0.0; n * (n + 1)];
        let w = n + 1;
        for i in 0..n {
            for j in 0..n {
                a[i * w + j] = self.probs[j * n + i] - if i == j { 1.0 } else { 0.0 };
            }
        }
        for j in 0..n {
            a[(n - 1) * w + j] = 1.0;
        }
        a[(n - 1) * w + n] = 1.0;
        for col in 0..n {
            let pivot = (col..n)
                .max_by(|&r, &s| a[r * w + col].abs().total_cmp(&a[s * w + col].abs()))
                .unwrap_or(col);
            if a[pivot * w + col].abs() < SINGULAR_PIVOT {
                return Err(Error::NoUniqueStationary);
            }
            if pivot != col {
                for k in 0..w {
                    a.swap(pivot * w + k, col * w + k);
                }
            }
            let p = a[col * w + col];
            for r in 0..n {
                if r != col {
                    let f = a[r * w + col] / p;
                    if f != 0.0 {
                        for k in col..w {
                            a[r * w + k] -= f * a[col * w + k];
                        }
                    }
                }
            }
        }
        let pi: Vec<f64> = (0..n)
            .map(|i| (a[i * w + n] / a[i * w + i]).max(0.0))
            .collect();
        let sum: f64 = pi.iter().sum();
        Ok(pi.into_iter().map(|p| p / sum).collect())
    }

    /// Expected number of consecutive steps spent in state `i` once entered: the dwell time is
    /// geometric with mean `1 / (1 − T_ii)` (infinite for an absorbing state).
    #[must_use]
    pub fn mean_dwell_time(&self, i: usize) -> Option<f64> {
        (i < self.n).then(|| 1.0 / (1.0 - self.probs[i * self.n + i]))
    }
}

/// Checks a transition matrix without building a chain.
///
/// # Errors
/// As [`MarkovChain::new`].
pub fn validate_matrix<Row: AsRef<[f64]>>(rows: &[Row]) -> Result<()> {
    let n = rows.len();
    if n == 0 {
        return Err(Error::EmptyMatrix);
    }
    for (i, row) in rows.iter().enumerate() {
        let row = row.as_ref();
        if row.len() != n {
            return Err(Error::NonSquareMatrix {
                rows: n,
                row: i,
                cols: row.len(),
            });
        }
        for (j, &p) in row.iter().enumerate() {
            if !p.is_finite() || p < 0.0 {
                return Err(Error::InvalidProbability {
                    row: i,
                    col: j,
                    value: p,
                });
            }
        }
        let sum: f64 = row.iter().sum();
        if (sum - 1.0).abs() > ROW_SUM_TOLERANCE {
            return Err(Error::InvalidTransitionMatrix { row: i, sum });
        }
    }
    Ok(())
}

/// Draws an index from a normalised probability row by inversion.
pub(crate) fn sample_categorical<R: Rng + ?Sized>(row: &[f64], rng: &mut R) -> usize {
    let u: f64 = rng.random();
    let mut acc = 0.0;
    for (j, &p) in row.iter().enumerate() {
        acc += p;
        if u < acc {
            return j;
        }
    }
    // Rounding can leave the cumulative sum a hair below 1: fall back to the last state with
    // non-zero probability, never to one that is impossible.
    row.iter().rposition(|&p| p > 0.0).unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::run_lengths;
    use approx::assert_relative_eq;
    use rand::SeedableRng;
    use rand_pcg::Pcg64Mcg;

    #[test]
    fn exploring_draws_weighted_by_their_ratio_recover_the_transition_row() {
        // A sticky chain: q = (1 − ε) T + ε/n visits every state, and the importance weights
        // T / q bring the weighted frequencies back to T's row, on each of several draws.
        let chain = MarkovChain::new(&[
            vec![0.98, 0.02, 0.0],
            vec![0.01, 0.98, 0.01],
            vec![0.0, 0.03, 0.97],
        ])
        .unwrap();
        let (n, eps) = (200_000, 0.2);
        for seed in [1, 2, 3] {
            let mut rng = Pcg64Mcg::seed_from_u64(seed);
            for previous in 0..3 {
                let (mut visits, mut weighted, mut total) = ([0usize; 3], [0.0; 3], 0.0);
                for _ in 0..n {
                    let next = chain.sample_next_exploring(previous, eps, &mut rng);
                    let w = chain.log_exploration_ratio(previous, next, eps).exp();
                    visits[next] += 1;
                    weighted[next] += w;
                    total += w;
                }
                for j in 0..3 {
                    let q = (1.0 - eps) * chain.prob(previous, j) + eps / 3.0;
                    let freq = visits[j] as f64 / n as f64;
                    // Binomial sd at most sqrt(0.25 / n) ≈ 0.0011: 5 sd.
                    assert!(
                        (freq - q).abs() < 0.0056,
                        "seed {seed} {previous}→{j}: {freq} vs q {q}"
                    );
                    let p = weighted[j] / total;
                    assert!(
                        (p - chain.prob(previous, j)).abs() < 0.0056,
                        "seed {seed} {previous}→{j}: weighted {p} vs T {}",
                        chain.prob(previous, j)
                    );
                }
            }
        }
    }

    #[test]
    fn exploration_zero_draws_as_the_chain_and_weighs_nothing() {
        let chain = MarkovChain::new(&[vec![0.9, 0.1], vec![0.2, 0.8]]).unwrap();
        let mut a = Pcg64Mcg::seed_from_u64(7);
        let mut b = Pcg64Mcg::seed_from_u64(7);
        for step in 0..1000 {
            let previous = step % 2;
            assert_eq!(
                chain.sample_next_exploring(previous, 0.0, &mut a),
                chain.sample_next(previous, &mut b)
            );
            assert_eq!(
                chain.log_exploration_ratio(previous, 1 - previous, 0.0),
                0.0
            );
        }
    }

    #[test]
    fn invalid_matrices_are_rejected_with_the_right_error() {
        let empty: [Vec<f64>; 0] = [];
        assert!(matches!(MarkovChain::new(&empty), Err(Error::EmptyMatrix)));
        assert!(matches!(
            MarkovChain::new(&[vec![0.5, 0.5], vec![1.0]]),
            Err(Error::NonSquareMatrix {
                rows: 2,
                row: 1,
                cols: 1
            })
        ));
        assert!(matches!(
            MarkovChain::new(&[vec![1.2, -0.2], vec![0.5, 0.5]]),
            Err(Error::InvalidProbability { row: 0, col: 1, value }) if value == -0.2
        ));
        assert!(matches!(
            MarkovChain::new(&[vec![0.5, 0.5], vec![f64::NAN, 0.5]]),
            Err(Error::InvalidProbability { row: 1, col: 0, .. })
        ));
        match MarkovChain::new(&[vec![0.5, 0.5], vec![0.3, 0.6]]) {
            Err(Error::InvalidTransitionMatrix { row, sum }) => {
                assert_eq!(row, 1);
                assert_relative_eq!(sum, 0.9, epsilon = 1e-15);
            }
            other => panic!("expected InvalidTransitionMatrix, got {other:?}"),
        }
        // A hand-typed 1/3 row is within tolerance and gets renormalised.
        let chain = MarkovChain::new(&[[0.333_333_3, 0.333_333_3, 0.333_333_3]; 3]);
        assert!(chain.is_ok());
    }

    #[test]
    fn stationary_distribution_solves_pi_t_equals_pi() {
        // Wu §6.3 T_α. By hand, from π T = π: the third column gives π3 = 0.2 (π1 + π2), the
        // second 0.46 π2 = 0.14 π1, so π2 = 7/23 π1, π3 = 6/23 π1, and Σ π = 1 gives
        // π = (23, 7, 6) / 36 (first column: 0.8·23 + 0.4·7 + 0.3·6 = 23 ✓).
        let chain = MarkovChain::new(&[[0.8, 0.1, 0.1], [0.4, 0.5, 0.1], [0.3, 0.2, 0.5]]).unwrap();
        let pi = chain.stationary().unwrap();
        for (p, expected) in pi.iter().zip([23.0 / 36.0, 7.0 / 36.0, 6.0 / 36.0]) {
            assert_relative_eq!(*p, expected, epsilon = 1e-14);
        }
        for j in 0..3 {
            let next: f64 = (0..3).map(|i| pi[i] * chain.prob(i, j)).sum();
            assert_relative_eq!(next, pi[j], epsilon = 1e-14);
        }
        assert_relative_eq!(pi.iter().sum::<f64>(), 1.0, epsilon = 1e-14);
        // A reducible chain (two absorbing states) has no unique stationary distribution.
        let reducible = MarkovChain::new(&[[1.0, 0.0], [0.0, 1.0]]).unwrap();
        assert!(matches!(
            reducible.stationary(),
            Err(Error::NoUniqueStationary)
        ));
    }

    #[test]
    fn out_of_range_labels_are_uniform_and_consistent() {
        let chain = MarkovChain::new(&[[0.9, 0.1], [0.2, 0.8]]).unwrap();
        assert_eq!(chain.log_transition(0, 2), f64::NEG_INFINITY);
        assert_relative_eq!(chain.log_transition(5, 1), -(2f64).ln());
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        assert!((0..100).all(|_| chain.sample_next(9, &mut rng) < 2));
        // An impossible transition is never sampled.
        let sticky = MarkovChain::new(&[[1.0, 0.0], [0.5, 0.5]]).unwrap();
        assert!((0..1000).all(|_| sticky.sample_next(0, &mut rng) == 0));
    }

    /// Asymptotic variance of the empirical frequency of state `k` over a stationary path,
    /// times the path length: `π_k(1 − π_k) + 2 π_k Σ_{t≥1} (Tᵗ_kk − π_k)`. The series is summed
    /// until its terms vanish (geometric with the second eigenvalue, ≤ 0.7 here).
    fn frequency_variance(chain: &MarkovChain, pi: &[f64], k: usize) -> f64 {
        let n = chain.n_states();
        let mut row: Vec<f64> = (0..n).map(|j| if j == k { 1.0 } else { 0.0 }).collect();
        let mut next = vec![0.0; n];
        let mut sum = 0.0;
        for _ in 0..2000 {
            chain.predict_into(&row, &mut next).unwrap();
            std::mem::swap(&mut row, &mut next);
            sum += row[k] - pi[k];
        }
        pi[k] * (1.0 - pi[k]) + 2.0 * pi[k] * sum
    }

    /// Sampled chains (Wu's T_β and T_α, 10⁶ steps each, seeded): the empirical state
    /// frequencies match the stationary distribution within 4 asymptotic standard errors (from
    /// the chain's own autocorrelation, above), and the mean dwell time of each state matches
    /// the geometric mean `1/(1 − T_kk)` within 4 standard errors `√T_kk/(1 − T_kk)/√runs`.
    #[test]
    fn sampled_chains_match_stationary_distribution_and_dwell_times() {
        let matrices = [
            (
                "T_beta",
                [[0.8, 0.1, 0.1], [0.1, 0.8, 0.1], [0.1, 0.1, 0.8]],
            ),
            (
                "T_alpha",
                [[0.8, 0.1, 0.1], [0.4, 0.5, 0.1], [0.3, 0.2, 0.5]],
            ),
        ];
        let mut rng = Pcg64Mcg::seed_from_u64(7);
        let len = 1_000_000;
        for (name, m) in matrices {
            let chain = MarkovChain::new(&m).unwrap();
            let pi = chain.stationary().unwrap();
            let start = sample_categorical(&pi, &mut rng);
            let path = chain.sample_path(start, len, &mut rng);
            let mut counts = [0usize; 3];
            for &s in &path {
                counts[s] += 1;
            }
            let runs = run_lengths(&path, 3);
            for k in 0..3 {
                let freq = counts[k] as f64 / len as f64;
                let se = (frequency_variance(&chain, &pi, k) / len as f64).sqrt();
                eprintln!(
                    "{name} state {k}: frequency {freq:.5} vs π {:.5} (SE {se:.5})",
                    pi[k]
                );
                assert!(
                    (freq - pi[k]).abs() < 4.0 * se,
                    "{name} state {k}: {freq} vs {}",
                    pi[k]
                );

                let p = chain.prob(k, k);
                let expected = chain.mean_dwell_time(k).unwrap();
                let mean = runs[k].iter().sum::<usize>() as f64 / runs[k].len() as f64;
                let se = p.sqrt() / (1.0 - p) / (runs[k].len() as f64).sqrt();
                eprintln!(
                    "{name} state {k}: mean dwell {mean:.4} vs {expected:.4} (SE {se:.4}, {} runs)",
                    runs[k].len()
                );
                assert!(
                    (mean - expected).abs() < 4.0 * se,
                    "{name} state {k}: dwell {mean}"
                );
            }
        }
    }
}
