//! Point estimates from a weighted particle set: weighted mean and covariance, the maximum-weight
//! particle, and per-label estimates for particles with a discrete mode (Wu §4:
//! β̂ = argmax_k Σ_{n: βₙ=k} πₙ, X̂ = the mean of the particles with label β̂).

use crate::error::{Error, Result};
use crate::particles::{Labelled, ParticleSet};

/// A state that can be read as a vector of reals, for the moment estimators.
pub trait AsVector {
    /// The state's coordinates.
    fn as_vector(&self) -> &[f64];
}

impl AsVector for f64 {
    fn as_vector(&self) -> &[f64] {
        std::slice::from_ref(self)
    }
}

impl<const N: usize> AsVector for [f64; N] {
    fn as_vector(&self) -> &[f64] {
        self
    }
}

impl AsVector for Vec<f64> {
    fn as_vector(&self) -> &[f64] {
        self
    }
}

impl<S: AsVector> AsVector for Labelled<S> {
    fn as_vector(&self) -> &[f64] {
        self.state.as_vector()
    }
}

/// Weighted mean and covariance Σᵢ Wᵢ (xᵢ − μ)(xᵢ − μ)ᵀ (the moments of the particle
/// approximation itself, no small-sample correction).
#[derive(Debug, Clone, PartialEq)]
pub struct MeanCovariance {
    /// The mean μ.
    pub mean: Vec<f64>,
    /// The covariance, row-major, `dim × dim`.
    pub covariance: Vec<f64>,
}

impl MeanCovariance {
    /// Dimension of the state.
    #[must_use]
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// Covariance entry (r, c); `None` out of range.
    #[must_use]
    pub fn cov(&self, r: usize, c: usize) -> Option<f64> {
        let d = self.dim();
        if r < d && c < d {
            self.covariance.get(r * d + c).copied()
        } else {
            None
        }
    }
}

/// Index, state and normalised weight of the heaviest particle (the posterior mode among the
/// particles).
#[must_use]
pub fn max_weight_particle<S>(set: &ParticleSet<S>) -> (usize, &S, f64) {
    let (i, w) = set.max_weight();
    // `max_weight` returns an index into the (non-empty) set.
    (i, &set.states()[i], w)
}

/// Writes the weighted mean of the particles, viewed through `view` (which writes a state's `dim`
/// coordinates into the slice it is given), into `mean`. Particles are restricted to those for
/// which `keep` is true; the mass of the kept particles is returned (the mean is left at zero when
/// it is 0).
fn masked_mean<S>(
    set: &ParticleSet<S>,
    dim: usize,
    view: &mut impl FnMut(&S, &mut [f64]),
    keep: &impl Fn(&S) -> bool,
    mean: &mut [f64],
    scratch: &mut [f64],
) -> f64 {
    mean.fill(0.0);
    let mut mass = 0.0;
    for (s, w) in set.iter() {
        if w == 0.0 || !keep(s) {
            continue;
        }
        view(s, &mut scratch[..dim]);
        mass += w;
        for (m, x) in mean.iter_mut().zip(scratch.iter()) {
            *m += w * x;
        }
    }
    if mass > 0.0 {
        for m in mean.iter_mut() {
            *m /= mass;
        }
    }
    mass
}

/// Weighted mean of states viewed through a closure that writes `dim` coordinates.
///
/// # Examples
/// ```
/// let set = smc_core::ParticleSet::from_states(vec![(1.0, 5.0), (3.0, 7.0)]).unwrap();
/// let m = smc_core::estimate::weighted_mean_by(&set, 2, |s, out| out.copy_from_slice(&[s.0, s.1]));
/// assert_eq!(m, vec![2.0, 6.0]);
/// ```
pub fn weighted_mean_by<S>(
    set: &ParticleSet<S>,
    dim: usize,
    mut view: impl FnMut(&S, &mut [f64]),
) -> Vec<f64> {
    let mut mean = vec![0.0; dim];
    let mut scratch = vec![0.0; dim];
    masked_mean(set, dim, &mut view, &|_| true, &mut mean, &mut scratch);
    mean
}

/// Weighted mean and covariance of states viewed through a closure that writes `dim`
/// coordinates (two passes, so the covariance does not suffer from cancellation).
pub fn weighted_mean_covariance_by<S>(
    set: &ParticleSet<S>,
    dim: usize,
    mut view: impl FnMut(&S, &mut [f64]),
) -> MeanCovariance {
    let mut mean = vec![0.0; dim];
    let mut x = vec![0.0; dim];
    masked_mean(set, dim, &mut view, &|_| true, &mut mean, &mut x);
    let mut covariance = vec![0.0; dim * dim];
    for (s, w) in set.iter() {
        if w == 0.0 {
            continue;
        }
        view(s, &mut x);
        for (xi, mi) in x.iter_mut().zip(&mean) {
            *xi -= mi;
        }
        for (row, &xr) in covariance.chunks_exact_mut(dim.max(1)).zip(x.iter()) {
            for (c, &xc) in row.iter_mut().zip(x.iter()) {
                *c += w * xr * xc;
            }
        }
    }
    MeanCovariance { mean, covariance }
}

/// Dimension shared by every state, or an error.
fn common_dim<S: AsVector>(set: &ParticleSet<S>) -> Result<usize> {
    let dim = set.states().first().map_or(0, |s| s.as_vector().len());
    match set.states().iter().find(|s| s.as_vector().len() != dim) {
        Some(s) => Err(Error::DimensionMismatch {
            expected: dim,
            got: s.as_vector().len(),
        }),
        None => Ok(dim),
    }
}

/// Weighted mean of [`AsVector`] states.
///
/// # Errors
/// [`Error::DimensionMismatch`] when the states differ in dimension.
pub fn weighted_mean<S: AsVector>(set: &ParticleSet<S>) -> Result<Vec<f64>> {
    let dim = common_dim(set)?;
    Ok(weighted_mean_by(set, dim, |s, out| {
        out.copy_from_slice(s.as_vector());
    }))
}

/// Weighted mean and covariance of [`AsVector`] states.
///
/// # Errors
/// [`Error::DimensionMismatch`] when the states differ in dimension.
pub fn weighted_mean_covariance<S: AsVector>(set: &ParticleSet<S>) -> Result<MeanCovariance> {
    let dim = common_dim(set)?;
    Ok(weighted_mean_covariance_by(set, dim, |s, out| {
        out.copy_from_slice(s.as_vector());
    }))
}

/// Posterior mass of each label: entry k is Σ_{i: label(xᵢ)=k} Wᵢ (Wu §4).
///
/// # Errors
/// [`Error::LabelOutOfRange`] when a particle's label is not below `n_labels`.
pub fn label_posterior<S>(
    set: &ParticleSet<S>,
    n_labels: usize,
    label_of: impl Fn(&S) -> usize,
) -> Result<Vec<f64>> {
    let mut mass = vec![0.0; n_labels];
    for (s, w) in set.iter() {
        let label = label_of(s);
        match mass.get_mut(label) {
            Some(m) => *m += w,
            None => return Err(Error::LabelOutOfRange { label, n_labels }),
        }
    }
    Ok(mass)
}

/// The label with the largest mass (the first on ties); `None` for an empty slice.
#[must_use]
pub fn argmax_label(label_mass: &[f64]) -> Option<usize> {
    crate::weights::argmax(label_mass).map(|(k, _)| k)
}

/// Weighted mean of the particles with label `label`, weights renormalised within the class
/// (Wu §4: X̂ is the class-conditional mean). `None` when the class has no mass.
pub fn label_conditional_mean_by<S>(
    set: &ParticleSet<S>,
    label: usize,
    label_of: impl Fn(&S) -> usize,
    dim: usize,
    mut view: impl FnMut(&S, &mut [f64]),
) -> Option<Vec<f64>> {
    let mut mean = vec![0.0; dim];
    let mut scratch = vec![0.0; dim];
    let mass = masked_mean(
        set,
        dim,
        &mut view,
        &|s| label_of(s) == label,
        &mut mean,
        &mut scratch,
    );
    (mass > 0.0).then_some(mean)
}

/// The estimate of Wu §4 for labelled particles: the most probable label and the mean of the
/// particles that carry it.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelEstimate {
    /// β̂ = argmax_k of the label mass.
    pub label: usize,
    /// Mass of every label.
    pub label_mass: Vec<f64>,
    /// X̂ = mean of the states with label β̂, weights renormalised within the class.
    pub mean: Vec<f64>,
}

/// Wu §4 estimate for [`Labelled`] particles whose state is an [`AsVector`].
///
/// # Errors
/// [`Error::LabelOutOfRange`], [`Error::DimensionMismatch`], or [`Error::InvalidSetting`] when
/// `n_labels` is 0.
pub fn labelled_estimate<S: AsVector>(
    set: &ParticleSet<Labelled<S>>,
    n_labels: usize,
) -> Result<LabelEstimate> {
    let label_mass = label_posterior(set, n_labels, |p| p.label)?;
    let label = argmax_label(&label_mass).ok_or_else(|| Error::InvalidSetting {
        name: "n_labels",
        reason: "must be at least 1".into(),
    })?;
    let dim = common_dim(set)?;
    // The winning class has positive mass, since the masses sum to 1.
    let mean = label_conditional_mean_by(
        set,
        label,
        |p| p.label,
        dim,
        |p, out| {
            out.copy_from_slice(p.as_vector());
        },
    )
    .unwrap_or_else(|| vec![0.0; dim]);
    Ok(LabelEstimate {
        label,
        label_mass,
        mean,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn mean_and_covariance_of_a_known_discrete_distribution() {
        // Weights (1/2, 1/4, 1/4) on (0,0), (2,0), (0,4): mean (0.5, 1),
        // var x = 0.5·0.25 + 0.25·2.25 + 0.25·0.25 = 0.75, var y = 0.75·1 + 0.25·9 = 3,
        // cov = 0.5·(−0.5)(−1) + 0.25·(1.5)(−1) + 0.25·(−0.5)(3) = −0.5.
        let set = ParticleSet::from_log_weights(
            vec![[0.0, 0.0], [2.0, 0.0], [0.0, 4.0]],
            vec![2f64.ln(), 0.0, 0.0],
        )
        .unwrap();
        let mc = weighted_mean_covariance(&set).unwrap();
        assert_relative_eq!(mc.mean[0], 0.5, epsilon = 1e-14);
        assert_relative_eq!(mc.mean[1], 1.0, epsilon = 1e-14);
        assert_relative_eq!(mc.cov(0, 0).unwrap(), 0.75, epsilon = 1e-14);
        assert_relative_eq!(mc.cov(1, 1).unwrap(), 3.0, epsilon = 1e-14);
        assert_relative_eq!(mc.cov(0, 1).unwrap(), -0.5, epsilon = 1e-14);
        assert_relative_eq!(mc.cov(1, 0).unwrap(), -0.5, epsilon = 1e-14);
        let (i, s, w) = max_weight_particle(&set);
        assert_eq!((i, *s), (0, [0.0, 0.0]));
        assert_relative_eq!(w, 0.5, epsilon = 1e-14);
    }

    #[test]
    fn mixed_dimensions_are_an_error() {
        let set = ParticleSet::from_states(vec![vec![1.0], vec![1.0, 2.0]]).unwrap();
        assert_eq!(
            weighted_mean(&set),
            Err(Error::DimensionMismatch {
                expected: 1,
                got: 2
            })
        );
    }

    #[test]
    fn label_estimate_follows_wu_section_4() {
        // Label 1 holds 0.6 of the mass split over states 10 and 20 in ratio 1:2, so X̂ = 50/3;
        // the single heaviest particle (0.4, label 0) is not the estimate.
        let states = vec![
            Labelled::new(0, 0.0),
            Labelled::new(1, 10.0),
            Labelled::new(1, 20.0),
        ];
        let set =
            ParticleSet::from_log_weights(states, vec![0.4f64.ln(), 0.2f64.ln(), 0.4f64.ln()])
                .unwrap();
        let est = labelled_estimate(&set, 3).unwrap();
        assert_eq!(est.label, 1);
        assert_relative_eq!(est.label_mass[0], 0.4, epsilon = 1e-14);
        assert_relative_eq!(est.label_mass[1], 0.6, epsilon = 1e-14);
        assert_eq!(est.label_mass[2], 0.0);
        assert_relative_eq!(est.mean[0], 50.0 / 3.0, epsilon = 1e-12);
        assert_eq!(
            label_posterior(&set, 1, |p| p.label),
            Err(Error::LabelOutOfRange {
                label: 1,
                n_labels: 1
            })
        );
        assert_eq!(
            label_conditional_mean_by(&set, 2, |p| p.label, 1, |p, o| o[0] = p.state),
            None
        );
    }
}
