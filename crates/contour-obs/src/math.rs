//! Small log-domain helpers.

/// log(eᵃ + eᵇ), exact when either is −∞.
#[inline]
pub(crate) fn log_add_exp(a: f64, b: f64) -> f64 {
    let (hi, lo) = if a >= b { (a, b) } else { (b, a) };
    if lo == f64::NEG_INFINITY {
        hi
    } else {
        hi + (lo - hi).exp().ln_1p()
    }
}

/// ln m!, by a table for small m and a sum beyond.
#[derive(Debug, Clone)]
pub(crate) struct LnFactorial {
    table: Vec<f64>,
}

impl LnFactorial {
    /// A table for m ≤ `max`.
    pub(crate) fn new(max: usize) -> Self {
        let mut table = Vec::with_capacity(max + 1);
        let mut acc = 0.0;
        table.push(0.0);
        for m in 1..=max {
            acc += (m as f64).ln();
            table.push(acc);
        }
        Self { table }
    }

    #[inline]
    pub(crate) fn get(&self, m: usize) -> f64 {
        match self.table.get(m) {
            Some(v) => *v,
            // Accumulated in the same order as the table, so that every m gives the bits of
            // the plain sum ln 2 + ln 3 + … + ln m (`crate::log_poisson`).
            None => {
                let last = self.table.len() - 1;
                (last + 1..=m).fold(self.table[last], |acc, k| acc + (k as f64).ln())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_add_matches_direct() {
        assert!((log_add_exp(1.0_f64.ln(), 3.0_f64.ln()) - 4.0_f64.ln()).abs() < 1e-15);
        assert_eq!(log_add_exp(f64::NEG_INFINITY, -2.0), -2.0);
        assert!((log_add_exp(-1000.0, -1000.0) - (-1000.0 + 2.0_f64.ln())).abs() < 1e-12);
    }

    #[test]
    fn ln_factorial() {
        let f = LnFactorial::new(3);
        assert!((f.get(3) - 6.0_f64.ln()).abs() < 1e-15);
        assert!((f.get(5) - 120.0_f64.ln()).abs() < 1e-13);
        assert_eq!(f.get(0), 0.0);
    }
}
