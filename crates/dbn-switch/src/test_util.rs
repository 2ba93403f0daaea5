//! Statistics shared by the tests.

/// The 0.1 % critical value of the asymptotic Kolmogorov distribution: for `n` i.i.d. draws from
/// a continuous CDF, `P(√n · D > 1.95) ≈ 0.001`. For a CDF with atoms the statistic is
/// stochastically smaller, so the same bound is conservative there.
pub(crate) const KS_BOUND_COEFF: f64 = 1.95;

/// Kolmogorov–Smirnov statistic `sup_x |F_n(x) − F(x)|` of `samples` (sorted in place) against a
/// CDF `cdf` (right-continuous) with left limits `cdf_left(x) = F(x⁻)`, which differ from `cdf`
/// only at atoms. Between distinct sample values `F_n` is flat and `F` monotone, so the supremum
/// is attained at the left or right limit at a sample value.
pub(crate) fn ks_statistic(
    samples: &mut [f64],
    cdf: impl Fn(f64) -> f64,
    cdf_left: impl Fn(f64) -> f64,
) -> f64 {
    samples.sort_by(f64::total_cmp);
    let n = samples.len() as f64;
    let mut d: f64 = 0.0;
    let mut i = 0;
    while i < samples.len() {
        let v = samples[i];
        let mut j = i;
        while j < samples.len() && samples[j] == v {
            j += 1;
        }
        d = d.max((i as f64 / n - cdf_left(v)).abs());
        d = d.max((j as f64 / n - cdf(v)).abs());
        i = j;
    }
    d
}

/// Lengths of the maximal runs of each state in a path, per state (the last, censored run is
/// dropped so that every counted run is complete).
pub(crate) fn run_lengths(path: &[usize], n_states: usize) -> Vec<Vec<usize>> {
    let mut runs = vec![Vec::new(); n_states];
    let mut start = 0;
    for t in 1..path.len() {
        if path[t] != path[t - 1] {
            if start > 0 {
                // The first run may have been entered before the path began: also censored.
                runs[path[t - 1]].push(t - start);
            }
            start = t;
        }
    }
    runs
}
