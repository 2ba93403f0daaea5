//! Wu's occlusion likelihood with γ read as the hidden *fraction* of the contour, the hidden
//! lines one contiguous arc ([`crate::OcclusionForm::Arc`], [`crate::OcclusionForm::NeutralArc`];
//! docs/MODELS.md, Wu Eq. 11–12 and the occlusion arc). γ = 0 is Eq. 6 and γ = 1 is Eq. 12 on
//! every line, as with Eq. 11.

use super::independent::hidden_line_terms;
use crate::{LineTerms, MeasurementLines, WuSettings, poisson_neg_entropy};

/// The log-likelihood of a line outside the image under "the target is visible there", relative
/// to the neutral hidden-line constant ([`neutral_hidden_line`]): e^{−10}, so that a contour
/// leaving the frame is explained by its hidden arc (γ rises, as the visible fraction falls)
/// rather than by visible lines that nothing can contradict.
const UNOBSERVED_VISIBLE_PENALTY: f64 = -10.0;

/// The neutral hidden line c = e^{E[ln N(m; μ)]}/W, in logs: the typical value of Eq. 12 on a
/// background line of density `density` (minus the Poisson law's entropy), the same for every
/// particle.
pub(crate) fn neutral_hidden_line(settings: &WuSettings, density: f64) -> f64 {
    let mu = density * settings.lines.length as f64;
    poisson_neg_entropy(mu) - settings.window.ln()
}

/// Replaces the terms of every line outside the image by the neutral constant `c` (hidden) and
/// c e^{−10} (visible): the frame's border hides such a line, it says as little as a hidden
/// line, and only the hidden arc can cover it.
pub(crate) fn neutralise_unobserved(ws: &MeasurementLines, c: f64, terms: &mut [LineTerms]) {
    for (i, t) in terms.iter_mut().enumerate() {
        if !ws.is_observed(i) {
            *t = LineTerms {
                log_target: c + UNOBSERVED_VISIBLE_PENALTY,
                log_clutter: c,
            };
        }
    }
}

/// The occlusion likelihood with γ the hidden fraction of the contour, hidden as one contiguous
/// arc. A hidden line scores Eq. 12 mixed with the unknown occluder of share `share`
/// ([`hidden_line_terms`]), or the constant `neutral_hidden` when given.
///
/// With n lines and h = γ n, the arc covers k = ⌊h⌋ or k + 1 lines with probabilities
/// 1 − (h − k) and h − k (so that its mean length is γ n), and starts at any of the n lines
/// with probability 1/n:
///
/// p(Z | X, γ) = Σ_k P(k) (1/n) Σ_s Π_{i ∈ arc(s, k)} p(Z_i | C) Π_{i ∉ arc(s, k)} p(Z_i | x_i, C).
///
/// Each inner sum is Π_i p(Z_i | x_i, C) · (1/n) Σ_s exp(D(s, k)), D(s, k) the sum of
/// d_i = ln p(Z_i | C) − ln p(Z_i | x_i, C) over the arc, read from prefix sums of d around
/// the closed contour: O(n) per hypothesis. γ = 0 is Eq. 6 and γ = 1 is Eq. 12 on every
/// line, as with Eq. 11.
pub(crate) fn log_occlusion_arc(
    settings: &WuSettings,
    share: f64,
    terms: &[LineTerms],
    gamma: f64,
    neutral_hidden: Option<f64>,
) -> f64 {
    let n = terms.len();
    if n == 0 {
        return 0.0;
    }
    let mut visible = 0.0;
    // prefix[j] = Σ_{i < j} d_{i mod n}, j = 0..=2n.
    let mut prefix = Vec::with_capacity(2 * n + 1);
    prefix.push(0.0);
    let mut acc = 0.0;
    for t in terms {
        let mut t = hidden_line_terms(settings, share, *t);
        if let Some(c) = neutral_hidden {
            t.log_clutter = c;
        }
        visible += t.log_target;
        acc += t.log_clutter - t.log_target;
        prefix.push(acc);
    }
    for j in 0..n {
        let d = prefix[j + 1] - prefix[j];
        acc += d;
        prefix.push(acc);
    }
    let ln_n = (n as f64).ln();
    let arc = |k: usize| -> f64 {
        if k == 0 {
            return 0.0;
        }
        if k >= n {
            return prefix[n];
        }
        let sums = (0..n).map(|s| prefix[s + k] - prefix[s]);
        let max = sums.clone().fold(f64::NEG_INFINITY, f64::max);
        if !max.is_finite() {
            return max;
        }
        max + sums.map(|v| (v - max).exp()).sum::<f64>().ln() - ln_n
    };
    let h = gamma.clamp(0.0, 1.0) * n as f64;
    let k = h.floor() as usize;
    let f = h - k as f64;
    let value = if f <= 0.0 {
        arc(k)
    } else {
        let (a, b) = ((1.0 - f).ln() + arc(k), f.ln() + arc(k + 1));
        let m = a.max(b);
        if m.is_finite() {
            m + ((a - m).exp() + (b - m).exp()).ln()
        } else {
            m
        }
    };
    visible + value
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn occlusion_arc_is_eq6_and_eq12_at_the_ends_and_a_contiguous_mixture_between() {
        let w = WuSettings::default();
        let terms: Vec<LineTerms> = [0.3, -1.2, 2.0, -0.4, 0.9]
            .iter()
            .enumerate()
            .map(|(i, &a)| LineTerms {
                log_target: a,
                log_clutter: -0.5 * i as f64,
            })
            .collect();
        let all_target: f64 = terms.iter().map(|t| t.log_target).sum();
        let all_hidden: f64 = terms.iter().map(|t| t.log_clutter).sum();
        assert!((log_occlusion_arc(&w, 0.0, &terms, 0.0, None) - all_target).abs() < 1e-12);
        assert!((log_occlusion_arc(&w, 0.0, &terms, 1.0, None) - all_hidden).abs() < 1e-12);
        // γ = 0.5 with 5 lines: arcs of 2 and 3 lines, each with probability 1/2, any start.
        let n = terms.len();
        let arc = |k: usize| -> f64 {
            (0..n)
                .map(|s| {
                    (0..n)
                        .map(|i| {
                            let hidden = (i + n - s) % n < k;
                            if hidden {
                                terms[i].log_clutter
                            } else {
                                terms[i].log_target
                            }
                        })
                        .sum::<f64>()
                        .exp()
                })
                .sum::<f64>()
                / n as f64
        };
        let want = (0.5 * arc(2) + 0.5 * arc(3)).ln();
        let got = log_occlusion_arc(&w, 0.0, &terms, 0.5, None);
        assert!((got - want).abs() < 1e-9, "{got} vs {want}");
        // A neutral constant replaces every hidden line's term.
        let got = log_occlusion_arc(&w, 0.0, &terms, 1.0, Some(-2.0));
        assert!((got + 2.0 * n as f64).abs() < 1e-12);
    }
}
