//! Wu's occlusion likelihood (Eq. 11) with each line hidden independently with probability γ,
//! and a hidden line's count explained by background clutter (Eq. 12) mixed with an occluder
//! of unknown texture ([`crate::OcclusionForm::Independent`]; docs/MODELS.md, Wu Eq. 11–12).

use crate::{LineTerms, WuSettings, occlusion_line_log};

/// The terms of one line with its clutter-only part (the line hidden, Wu Eq. 12) replaced by
/// the mixture of background clutter and an unknown occluder: the count of a hidden line is
/// (1 − s) N(m; λ) + s U(m; 0..=L), the uniform being the least committal law of a count on a
/// line of L pixels. Unchanged with share s = 0.
pub(crate) fn hidden_line_terms(settings: &WuSettings, share: f64, t: LineTerms) -> LineTerms {
    if share <= 0.0 {
        return t;
    }
    let length = settings.lines.length as f64;
    let ln_window = settings.window.ln();
    // t.log_clutter = ln N(m; λ) − ln W; the uniform count law is 1/(L + 1).
    let ln_poisson = t.log_clutter + ln_window;
    let ln_count = ((1.0 - share) * ln_poisson.exp() + share / (length + 1.0)).ln();
    LineTerms {
        log_target: t.log_target,
        log_clutter: ln_count - ln_window,
    }
}

/// Wu's occlusion likelihood (Eq. 11) at occlusion `gamma` from the per-line terms `terms` of
/// [`crate::WuLikelihood::line_terms`], with the hidden lines' edge count a mixture of
/// background clutter and an unknown occluder of share `share` ([`hidden_line_terms`]).
pub(crate) fn log_independent(
    settings: &WuSettings,
    share: f64,
    terms: &[LineTerms],
    gamma: f64,
) -> f64 {
    terms
        .iter()
        .map(|t| occlusion_line_log(hidden_line_terms(settings, share, *t), gamma))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wu_line_terms;

    #[test]
    fn unknown_occluder_mixture_reduces_to_wu_and_to_the_uniform_count() {
        let w = WuSettings::default();
        // Two lines: 3 edges (one in the window) and none, at λ = 0.05 per pixel.
        let terms = [
            wu_line_terms(&[-7.5, 1.0, 9.0], 20.0, 0.05, &w).unwrap(),
            wu_line_terms(&[], 20.0, 0.05, &w).unwrap(),
        ];
        for gamma in [0.0, 0.3, 1.0] {
            // Share 0 is Wu's Eq. 11 exactly.
            let wu: f64 = terms.iter().map(|t| occlusion_line_log(*t, gamma)).sum();
            let got = log_independent(&w, 0.0, &terms, gamma);
            assert!((got - wu).abs() < 1e-12, "γ {gamma}: {got} vs {wu}");
        }
        // Share 1 at γ = 1: every line is 1/(L + 1) · 1/W, whatever its edges.
        let got = log_independent(&w, 1.0, &terms, 1.0);
        let want = 2.0 * (-(21.0f64).ln() - w.window.ln());
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        // The target term (γ = 0) never depends on the share.
        let a = log_independent(&w, 0.0, &terms, 0.0);
        let b = log_independent(&w, 0.5, &terms, 0.0);
        assert!((a - b).abs() < 1e-12);
    }
}
