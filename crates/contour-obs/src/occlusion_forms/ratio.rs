//! Wu's likelihood as a ratio against the no-target explanation of the same lines
//! ([`crate::OcclusionForm::Ratio`]; docs/MODELS.md, Wu Eq. 3–6, 11–12).

use crate::{LineTerms, log_poisson, occlusion_line_log};

/// The log of one line's likelihood ratio against the no-target explanation of the same line:
/// ln(γ + (1 − γ) p(Z_i | x_i, C)/p_bg(Z_i)), with p(Z_i | x_i, C) Wu's target term (Eq. 3–5)
/// at the particle's density over the line's clutter share (`t.log_target`), and
/// p_bg(Z_i) = N(m(L); λ ℓ)/W the same line with no target on it: background clutter along
/// the whole line (Eq. 12 at density `lambda_bg` over the observed length ℓ).
///
/// Why a ratio: the particles' lines sample different pixels, so Eq. 6 compares poses by how
/// probable their pixels are under the clutter law. A pose whose lines fall on an edge-rich
/// occluder is improbable for that reason alone, whatever the target does, and a hidden
/// target cannot coast behind it; a line off the image, with no edges, is the most probable
/// of all. In the ratio a hidden line (γ = 1) is exactly 1 — the image says nothing about
/// where a hidden target is — and an unobserved line is 1 at any γ. The numerator keeps
/// the target's own evidence: its outline near the contour point (Eq. 5) and its interior,
/// which hides the clutter on the inner part of the line, so a pose whose line crosses a
/// texture with many edges is less probable than the same line without the target
/// (f^m, f the clutter share). This is what the plain ratio at a single λ lacked (an
/// edge-rich texture was a honeypot through Eq. 5's m(L)/μ, docs/DECISIONS.md).
pub(crate) fn log_ratio_line(
    t: LineTerms,
    edges: usize,
    length: f64,
    observed: bool,
    lambda_bg: f64,
    ln_window: f64,
    gamma: f64,
) -> f64 {
    if !observed {
        return 0.0;
    }
    let ln_bg = log_poisson(edges, lambda_bg * length) - ln_window;
    occlusion_line_log(
        LineTerms {
            log_target: t.log_target - ln_bg,
            log_clutter: 0.0,
        },
        gamma,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{WuSettings, wu_line_terms};

    #[test]
    fn ratio_line_is_neutral_when_hidden_or_unobserved_and_penalises_texture() {
        let w = WuSettings::default();
        let (length, lambda, f) = (20.0, 0.08, 0.5);
        let ln_w = w.window.ln();
        let ratio = |edges: &[f64], observed: bool, gamma: f64| {
            let t = wu_line_terms(edges, length, f * lambda, &w).unwrap();
            log_ratio_line(t, edges.len(), length, observed, lambda, ln_w, gamma)
        };
        let clean = [0.3];
        let texture = [-9.0, -6.5, -3.0, 0.3, 2.5, 5.0, 8.0];
        // A hidden line (γ = 1) and an unobserved one carry no evidence about the pose.
        assert_eq!(ratio(&texture, true, 1.0), 0.0);
        assert_eq!(ratio(&clean, false, 0.3), 0.0);
        // At γ = 0: Wu's target term over the no-target term N(m; λℓ)/W of the same line.
        let t = wu_line_terms(&clean, length, f * lambda, &w).unwrap();
        let bg = -lambda * length + (lambda * length).ln() - ln_w;
        assert!((ratio(&clean, true, 0.0) - (t.log_target - bg)).abs() < 1e-12);
        // The outline alone at the contour point is evidence for the target; the same edge on
        // an edge-rich texture is evidence against it (the target would hide half the texture).
        assert!(ratio(&clean, true, 0.0) > 0.0);
        assert!(ratio(&texture, true, 0.0) < 0.0);
        // An empty window is evidence against a visible target, so γ raises it.
        assert!(ratio(&[], true, 0.0) < ratio(&[], true, 0.5));
    }
}
