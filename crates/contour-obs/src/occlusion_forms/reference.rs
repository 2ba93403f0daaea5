//! The measurement lines of one reference pose, shared by every hypothesis of a frame.

use crate::log_poisson;

/// The measurement lines of one reference pose (a tracker's last estimate) on the current
/// frame, shared by every hypothesis of the forms that need them
/// ([`crate::OcclusionForm::needs_reference`]: the ratio and the neutral arc).
///
/// In the ratio form ([`crate::OcclusionForm::Ratio`]) the pose no longer carries the Poisson
/// law of the clutter counts (Wu Eq. 1), which is what λ and β are learnt from in Eq. 6. These
/// lines take that role: the same lines for every hypothesis, so they inform λ without
/// favouring any pose. Their edge density is also the density at which every hypothesis' ratio
/// is evaluated: with the hypothesis' own λ in the ratio, a light λ inflates Eq. 5's m(L)/μ and
/// every stray edge reads as the outline (docs/RESULTS.md). The neutral arc
/// ([`crate::OcclusionForm::NeutralArc`]) scores its hidden lines at this density.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReferenceLines {
    /// Edge count and observed length of each line.
    pub counts: Vec<(usize, f64)>,
    /// Edges per pixel over all the lines, `None` when nothing was observed. The lines are
    /// centred on the target's outline, so this is the clutter density times the clutter share
    /// of a line ([`crate::WuTerm::clutter_line_fraction`]), like the scaled λ of Eq. 1–5.
    pub density: Option<f64>,
}

impl ReferenceLines {
    /// Σ_i ln N(m_i; λ ℓ_i): the Poisson law of the reference lines' counts (Wu Eq. 1) at the
    /// (line-fraction-scaled) density `lambda`.
    pub fn log_counts(&self, lambda: f64) -> f64 {
        self.counts
            .iter()
            .map(|&(m, length)| log_poisson(m, lambda * length))
            .sum()
    }

    /// Forgets the lines (no form that needs them, or nothing to measure).
    pub fn clear(&mut self) {
        self.counts.clear();
        self.density = None;
    }
}
