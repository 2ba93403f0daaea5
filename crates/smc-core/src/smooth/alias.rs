//! Walker's alias method (Vose's construction): O(N) set-up, O(1) draws from a categorical
//! distribution. Backward simulation proposes I ~ W_t with it, once per accept–reject attempt.

/// An alias table over N outcomes.
#[derive(Debug, Clone, Default)]
pub(crate) struct AliasTable {
    /// Probability of keeping the drawn column.
    keep: Vec<f64>,
    /// The outcome taken when the column is not kept.
    alias: Vec<usize>,
    small: Vec<usize>,
    large: Vec<usize>,
}

impl AliasTable {
    /// Rebuilds the table for normalised, non-negative `weights` (Vose 1991, "A linear algorithm
    /// for generating random numbers with a given distribution").
    pub(crate) fn rebuild(&mut self, weights: &[f64]) {
        let n = weights.len();
        let scale = n as f64 / weights.iter().sum::<f64>();
        self.keep.clear();
        self.keep.extend(weights.iter().map(|w| w * scale));
        self.alias.clear();
        self.alias.extend(0..n);
        self.small.clear();
        self.large.clear();
        for (i, &p) in self.keep.iter().enumerate() {
            if p < 1.0 {
                self.small.push(i);
            } else {
                self.large.push(i);
            }
        }
        while let (Some(&s), Some(&l)) = (self.small.last(), self.large.last()) {
            self.small.pop();
            self.alias[s] = l;
            self.keep[l] -= 1.0 - self.keep[s];
            if self.keep[l] < 1.0 {
                self.large.pop();
                self.small.push(l);
            }
        }
        // What is left holds mass 1 up to rounding.
        for &i in self.large.iter().chain(self.small.iter()) {
            if self.keep[i] > 0.0 {
                self.keep[i] = 1.0;
            }
        }
    }

    /// Draws one outcome.
    #[inline]
    pub(crate) fn sample<R: rand::Rng + ?Sized>(&self, rng: &mut R) -> usize {
        let n = self.keep.len();
        let u: f64 = rng.random::<f64>() * n as f64;
        // `u < n`, so the column is in range; the fractional part decides between it and its alias.
        let column = (u as usize).min(n - 1);
        if u - (column as f64) < self.keep[column] {
            column
        } else {
            self.alias[column]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::stream_rng;

    #[test]
    fn draws_follow_the_weights_and_never_pick_zero_weights() {
        let w = [0.1, 0.0, 0.5, 0.25, 0.15, 0.0];
        let mut table = AliasTable::default();
        table.rebuild(&w);
        let mut rng = stream_rng(1, 2, 3);
        let draws = 200_000;
        let mut counts = [0usize; 6];
        for _ in 0..draws {
            counts[table.sample(&mut rng)] += 1;
        }
        for (c, p) in counts.iter().zip(w) {
            let freq = *c as f64 / draws as f64;
            // Binomial standard error ≤ sqrt(0.25 / 200000) ≈ 0.0011; 0.006 is over 5 of them.
            assert!(
                (freq - p).abs() < 0.006,
                "frequency {freq} for probability {p}"
            );
            if p == 0.0 {
                assert_eq!(*c, 0);
            }
        }
    }
}
