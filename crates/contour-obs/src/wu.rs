//! Wu Eq. 1–6: target feature (Gaussian inside a window W, with missed detection) plus Poisson
//! clutter on each measurement line; and Wu Eq. 11–12: the occlusion mixture with γ.

use serde::{Deserialize, Serialize};
use vision_core::GreyImage;

use crate::math::{LnFactorial, log_add_exp};
use crate::odobez::{Batch, check_len, ensure_workspace, run_batch};
use crate::poisson::log_poisson_with;
use crate::{Affine2, Contour, Error, LineSettings, MeasurementLines, Result, Template};

/// The largest window W in units of σ accepted by [`WuSettings::validate`].
const MAX_WINDOW_PER_SIGMA: f64 = 50.0;

/// Settings of Wu's likelihood (and of the occlusion mixture built on it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WuSettings {
    /// Measurement lines. Default: n = 15, L = 20 px (Wu §6).
    pub lines: LineSettings,
    /// σ of the target feature's Gaussian, Eq. 2, in pixels. Default 2 px (Wu §6).
    pub sigma: f64,
    /// Width of the window W centred on the contour point, in pixels. Wu does not give it.
    /// Default 4σ = 8 px: the window ±2σ holds 95 % of the target feature's Gaussian, while the
    /// clutter expected inside it, λW, stays below 2 even for Wu's heaviest clutter (λ = 0.21/px),
    /// so the sum in Eq. 5 is not swamped. With W = 4σ, Eq. 3's G(W/4) is G(σ) and Eq. 4's G(W/2)
    /// is G(2σ).
    pub window: f64,
    /// p(ψ1), the probability that the target feature is detected. Wu does not give it.
    /// Default 0.9; p(ψ0) = 1 − p(ψ1).
    pub p_detect: f64,
    /// The smallest clutter density used, in edges per pixel: smaller (or negative) λ is raised
    /// to it so that the Poisson term stays finite as λ → 0. Default 1e−4 (a hundredth of Wu's
    /// lightest learnt clutter).
    pub min_lambda: f64,
}

impl Default for WuSettings {
    fn default() -> Self {
        Self {
            lines: LineSettings::default(),
            sigma: 2.0,
            window: 8.0,
            p_detect: 0.9,
            min_lambda: 1e-4,
        }
    }
}

impl WuSettings {
    /// Checks σ > 0, 0 < W ≤ L, W ≤ 50σ, p(ψ1) in [0, 1], min λ > 0, and the lines.
    ///
    /// The bound W ≤ 50σ (the default is 4σ) keeps the Gaussian of Eq. 2 anywhere in the window
    /// above e^{−50²/8} ≈ 1e−136, a normal f64, so the per-line mixture can be formed in the
    /// linear domain without underflow.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the field.
    pub fn validate(&self) -> Result<()> {
        self.lines.validate()?;
        let bad = |name, reason: String| Err(Error::InvalidSetting { name, reason });
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            return bad(
                "sigma",
                format!("must be finite and positive, got {}", self.sigma),
            );
        }
        if !(self.window > 0.0 && self.window <= self.lines.length as f64) {
            return bad(
                "window",
                format!(
                    "must be in (0, L = {}], got {}",
                    self.lines.length, self.window
                ),
            );
        }
        if self.window > MAX_WINDOW_PER_SIGMA * self.sigma {
            return bad(
                "window",
                format!(
                    "must be at most {MAX_WINDOW_PER_SIGMA}σ = {} px, got {}",
                    MAX_WINDOW_PER_SIGMA * self.sigma,
                    self.window
                ),
            );
        }
        if !(0.0..=1.0).contains(&self.p_detect) {
            return bad(
                "p_detect",
                format!("must be in [0, 1], got {}", self.p_detect),
            );
        }
        if !(self.min_lambda.is_finite() && self.min_lambda > 0.0) {
            return bad(
                "min_lambda",
                format!("must be finite and positive, got {}", self.min_lambda),
            );
        }
        Ok(())
    }
}

/// The two per-line pieces of Wu's model, in logs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LineTerms {
    /// log p(Z_i | x_i, C): target and clutter (Eq. 3–5 mixed over ψ0, ψ1).
    pub log_target: f64,
    /// log p(Z_i | C) = log N(m(L); λ)/W: clutter only, target invisible (Eq. 12).
    pub log_clutter: f64,
}

/// Precomputed constants of the per-line model.
///
/// Every piece of a line's likelihood carries the Poisson factor N(m(L); λ) of its clutter count
/// (Eq. 3–5, 12; for Eq. 5 through N(m − 1) = N(m)·m/μ), so a line's terms are
/// ln N(m(L); λ) + ln X with a linear-domain mixture X:
/// - target, Eq. 3–5: X = p(ψ0)G(W/4) + p(ψ1)·(mean of G over the window's edges)·m(L)/μ, or
///   p(ψ0)G(W/4) + p(ψ1)G(W/2) when the window is empty (a constant);
/// - clutter only, Eq. 12: X = 1/W;
/// - occlusion, Eq. 11: X = γ/W + (1 − γ)·X_target.
///
/// One `ln` per line with edges in its window, none otherwise, instead of the log-sum-exp of the
/// log-domain form. [`WuSettings::validate`] bounds W/σ so that every G(z), |z| ≤ W/2, is a
/// normal f64 and X cannot underflow.
#[derive(Debug, Clone)]
struct LineModel {
    half_window: f64,
    inv_two_var: f64,
    /// p(ψ0)·G(W/4).
    miss: f64,
    /// p(ψ1)/(σ√(2π)): G(z) = e^{−z²/2σ²}/(σ√(2π)).
    detect_scale: f64,
    /// X for a line without an edge in its window, and its log.
    x_empty: f64,
    ln_x_empty: f64,
    /// 1/W and ln(1/W).
    inv_window: f64,
    ln_inv_window: f64,
    min_lambda: f64,
    ln_fact: LnFactorial,
}

/// One hypothesis' clutter density, with ln μ cached for full-length lines.
#[derive(Debug, Clone, Copy)]
struct Density {
    lambda: f64,
    full_length: f64,
    mu_full: f64,
    ln_mu_full: f64,
}

impl Density {
    fn new(lambda: f64, full_length: f64) -> Self {
        let mu_full = lambda * full_length;
        Self {
            lambda,
            full_length,
            mu_full,
            ln_mu_full: mu_full.ln(),
        }
    }

    /// μ = λ·length and ln μ; the same bits whether cached or not.
    #[inline]
    fn mu(&self, length: f64) -> (f64, f64) {
        if length == self.full_length {
            (self.mu_full, self.ln_mu_full)
        } else {
            let mu = self.lambda * length;
            (mu, mu.ln())
        }
    }
}

impl LineModel {
    fn new(s: &WuSettings) -> Self {
        let inv_two_var = 1.0 / (2.0 * s.sigma * s.sigma);
        let norm = s.sigma * (2.0 * std::f64::consts::PI).sqrt();
        let g = |z: f64| (-z * z * inv_two_var).exp() / norm;
        let miss = (1.0 - s.p_detect) * g(s.window / 4.0);
        let x_empty = miss + s.p_detect * g(s.window / 2.0);
        let inv_window = 1.0 / s.window;
        Self {
            half_window: 0.5 * s.window,
            inv_two_var,
            miss,
            detect_scale: s.p_detect / norm,
            x_empty,
            ln_x_empty: x_empty.ln(),
            inv_window,
            ln_inv_window: inv_window.ln(),
            min_lambda: s.min_lambda,
            ln_fact: LnFactorial::new(s.lines.length + 2),
        }
    }

    /// ln N(m(L); λ) with mean μ = λ·length (docs/MODELS.md: (λL)^m e^{−λL}/m!), and the target's
    /// mixture X (see the type docs), `None` for an empty window (X = `x_empty`).
    #[inline]
    fn split(&self, edges: &[f64], length: f64, density: &Density) -> (f64, Option<f64>) {
        self.split_counted(edges.len(), edges, length, density)
    }

    /// [`Self::split`] for a line with `m_l` edges of which `candidates` holds (increasing) at
    /// least those within the window.
    #[inline]
    fn split_counted(
        &self,
        m_l: usize,
        candidates: &[f64],
        length: f64,
        density: &Density,
    ) -> (f64, Option<f64>) {
        let (mu, ln_mu) = density.mu(length);
        let ln_n = log_poisson_with(m_l, mu, ln_mu, self.ln_fact.get(m_l));
        let mut m_w = 0usize;
        let mut sum_g = 0.0;
        for z in candidates {
            if z.abs() <= self.half_window {
                m_w += 1;
                sum_g += (-z * z * self.inv_two_var).exp();
            }
        }
        if m_w == 0 {
            // Eq. 3 + Eq. 4.
            return (ln_n, None);
        }
        // Eq. 3 + Eq. 5: the mean Gaussian over the window's features; one feature is the
        // target, so m(L) − 1 are clutter: N(m − 1) = N(m)·m/μ.
        let x = self.miss + self.detect_scale * (sum_g / m_w as f64) * (m_l as f64 / mu);
        (ln_n, Some(x))
    }

    /// Both pieces for one line; the density already validated and clamped.
    #[inline]
    fn terms(&self, edges: &[f64], length: f64, density: &Density) -> LineTerms {
        let (ln_n, x) = self.split(edges, length, density);
        LineTerms {
            log_target: ln_n + x.map_or(self.ln_x_empty, f64::ln),
            log_clutter: ln_n + self.ln_inv_window,
        }
    }
}

/// The occlusion mixture's constants for one γ (Eq. 11).
#[derive(Debug, Clone, Copy)]
struct Mixture {
    /// γ/W.
    clutter: f64,
    /// 1 − γ.
    target: f64,
    /// ln(γ/W + (1 − γ)·x_empty): a line without an edge in its window.
    ln_empty: f64,
}

impl Mixture {
    fn new(model: &LineModel, gamma: f64) -> Self {
        let (clutter, target) = (gamma * model.inv_window, 1.0 - gamma);
        Self {
            clutter,
            target,
            ln_empty: (clutter + target * model.x_empty).ln(),
        }
    }

    /// ln(γ p(Z_i|C) + (1 − γ) p(Z_i|x_i, C)) for one line. At γ = 0 and γ = 1 the sum is
    /// exactly X_target and 1/W, so the value equals `log_target` / `log_clutter` bit for bit.
    #[inline]
    fn line_log(
        &self,
        model: &LineModel,
        m_l: usize,
        candidates: &[f64],
        length: f64,
        density: &Density,
    ) -> f64 {
        let (ln_n, x) = model.split_counted(m_l, candidates, length, density);
        ln_n + x.map_or(self.ln_empty, |x| (self.clutter + self.target * x).ln())
    }
}

/// Both per-line pieces of Wu's model for one line with edge offsets `edges` (relative to the
/// contour point), observed over `length` pixels, at clutter density `lambda` per pixel (raised to
/// `settings.min_lambda` if below). Allocates a small table; the likelihoods use a cached one.
///
/// # Errors
/// [`Error::NonFinite`] for a non-finite λ or length; invalid settings.
pub fn wu_line_terms(
    edges: &[f64],
    length: f64,
    lambda: f64,
    settings: &WuSettings,
) -> Result<LineTerms> {
    settings.validate()?;
    if !length.is_finite() || length <= 0.0 {
        return Err(Error::NonFinite {
            what: "line length",
            index: 0,
        });
    }
    let lambda = clamp_lambda(lambda, settings.min_lambda, 0)?;
    Ok(LineModel::new(settings).terms(edges, length, &Density::new(lambda, length)))
}

fn clamp_lambda(lambda: f64, min: f64, index: usize) -> Result<f64> {
    if !lambda.is_finite() {
        return Err(Error::NonFinite {
            what: "lambda",
            index,
        });
    }
    Ok(lambda.max(min))
}

fn check_gamma(gamma: f64, index: usize) -> Result<f64> {
    if gamma.is_nan() {
        return Err(Error::NonFinite {
            what: "gamma",
            index,
        });
    }
    if !(0.0..=1.0).contains(&gamma) {
        return Err(Error::OutOfRange {
            what: "gamma",
            index,
            value: gamma,
            range: "[0, 1]",
        });
    }
    Ok(gamma)
}

/// The occlusion mixture for one line (Wu Eq. 11): log(γ p(Z_i|C) + (1 − γ) p(Z_i|x_i, C)).
/// Exactly `log_clutter` at γ = 1 and `log_target` at γ = 0.
pub fn occlusion_line_log(terms: LineTerms, gamma: f64) -> f64 {
    log_add_exp(
        gamma.ln() + terms.log_clutter,
        (1.0 - gamma).ln() + terms.log_target,
    )
}

/// Wu's likelihood p(Z | X, C) = Π_i p(Z_i | x_i, C) (Eq. 6) for one contour template. Immutable;
/// the caller owns the [`MeasurementLines`] workspace (one per thread).
#[derive(Debug, Clone)]
pub struct WuLikelihood {
    settings: WuSettings,
    contour: Contour,
    model: LineModel,
}

impl WuLikelihood {
    /// The likelihood for `template` sampled at `settings.lines.n_lines` points.
    ///
    /// # Errors
    /// Invalid settings or a degenerate template.
    pub fn new(settings: WuSettings, template: &Template) -> Result<Self> {
        settings.validate()?;
        let contour = Contour::new(template, settings.lines.n_lines)?;
        Ok(Self {
            model: LineModel::new(&settings),
            settings,
            contour,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &WuSettings {
        &self.settings
    }

    /// The sampled contour.
    pub fn contour(&self) -> &Contour {
        &self.contour
    }

    /// A fresh workspace for this likelihood.
    ///
    /// # Errors
    /// Never for validated settings.
    pub fn workspace(&self) -> Result<MeasurementLines> {
        MeasurementLines::new(&self.settings.lines)
    }

    /// Extracts the lines of `pose` and writes each line's [`LineTerms`] into `out` (length n).
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite pose or λ; [`Error::LengthMismatch`] for `out`.
    pub fn line_terms(
        &self,
        ws: &mut MeasurementLines,
        image: &GreyImage<'_>,
        pose: &Affine2,
        lambda: f64,
        out: &mut [LineTerms],
    ) -> Result<()> {
        check_len("line terms", self.contour.len(), out.len())?;
        let lambda = clamp_lambda(lambda, self.model.min_lambda, 0)?;
        self.extract(ws, image, pose)?;
        let density = self.density(lambda);
        for (i, o) in out.iter_mut().enumerate() {
            *o = self
                .model
                .terms(ws.edges(i), ws.observed_length(i), &density);
        }
        Ok(())
    }

    fn density(&self, lambda: f64) -> Density {
        Density::new(lambda, self.settings.lines.length as f64)
    }

    fn extract(
        &self,
        ws: &mut MeasurementLines,
        image: &GreyImage<'_>,
        pose: &Affine2,
    ) -> Result<()> {
        ensure_workspace(ws, &self.settings.lines)?;
        ws.extract(image, &self.contour, pose)
    }

    /// log p(Z | X, C) = Σ_i log p(Z_i | x_i, C) (Wu Eq. 1–6) at clutter density λ per pixel.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite pose or λ.
    pub fn log_likelihood(
        &self,
        ws: &mut MeasurementLines,
        image: &GreyImage<'_>,
        pose: &Affine2,
        lambda: f64,
    ) -> Result<f64> {
        let lambda = clamp_lambda(lambda, self.model.min_lambda, 0)?;
        let density = self.density(lambda);
        let model = &self.model;
        self.sum_lines(ws, image, pose, |m_l, candidates, length| {
            let (ln_n, x) = model.split_counted(m_l, candidates, length, &density);
            ln_n + x.map_or(model.ln_x_empty, f64::ln)
        })
    }

    /// Σ over the lines of `pose` of `line(m(L), candidate offsets, observed length)`
    /// ([`MeasurementLines::count_edges_in`]), in line order. The workspace is left with no lines.
    #[inline]
    fn sum_lines<F>(
        &self,
        ws: &mut MeasurementLines,
        image: &GreyImage<'_>,
        pose: &Affine2,
        mut line: F,
    ) -> Result<f64>
    where
        F: FnMut(usize, &[f64], f64) -> f64,
    {
        ensure_workspace(ws, &self.settings.lines)?;
        crate::image::check_samplable(image)?;
        if !pose.is_finite() {
            return Err(Error::NonFinite {
                what: "pose",
                index: 0,
            });
        }
        let window = ws.window_bits(self.model.half_window);
        let half = self.settings.lines.half_length() as i64;
        ws.clear();
        ws.scan_lines(image, &self.contour, pose, -half, half);
        // −0.0, the neutral element of `Iterator::sum` for floats.
        let mut total = -0.0;
        for i in 0..self.contour.len() {
            let (length, m_l) = ws.count_edges_in(image, i, window);
            total += line(m_l, ws.candidates(), length);
        }
        ws.clear();
        Ok(total)
    }

    /// [`Self::log_likelihood`] for every pose; `lambdas` holds one shared λ or one per pose.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] for `out` or `lambdas`; [`Error::NonFinite`] with the index of
    /// the first bad pose or λ.
    pub fn log_likelihood_batch(
        &self,
        ws: &mut MeasurementLines,
        image: &GreyImage<'_>,
        poses: &[Affine2],
        lambdas: &[f64],
        out: &mut [f64],
    ) -> Result<()> {
        let mode = Batch::Sequential(ws);
        let params = [("lambdas", lambdas)];
        run_batch(mode, poses, params, out, |ws, pose, [lambda]| {
            self.log_likelihood(ws, image, pose, lambda)
        })
    }

    /// [`Self::log_likelihood_batch`] on the rayon thread pool, one workspace per task
    /// (allocated per call); bit-identical results, and the error of the lowest failing index.
    ///
    /// # Errors
    /// As [`Self::log_likelihood_batch`].
    pub fn log_likelihood_batch_par(
        &self,
        image: &GreyImage<'_>,
        poses: &[Affine2],
        lambdas: &[f64],
        out: &mut [f64],
    ) -> Result<()> {
        let mode = Batch::Parallel(&self.settings.lines);
        let params = [("lambdas", lambdas)];
        run_batch(mode, poses, params, out, |ws, pose, [lambda]| {
            self.log_likelihood(ws, image, pose, lambda)
        })
    }
}

/// Wu's occlusion likelihood p(Z | X, C, O) = Π_i {γ p(Z_i|C) + (1 − γ) p(Z_i|x_i, C)}
/// (Eq. 11–12), γ = 0 no occlusion, γ = 1 complete occlusion.
#[derive(Debug, Clone)]
pub struct OcclusionLikelihood {
    wu: WuLikelihood,
}

impl OcclusionLikelihood {
    /// The likelihood for `template` sampled at `settings.lines.n_lines` points.
    ///
    /// # Errors
    /// Invalid settings or a degenerate template.
    pub fn new(settings: WuSettings, template: &Template) -> Result<Self> {
        Ok(Self {
            wu: WuLikelihood::new(settings, template)?,
        })
    }

    /// The underlying Wu likelihood (γ = 0).
    pub fn wu(&self) -> &WuLikelihood {
        &self.wu
    }

    /// A fresh workspace for this likelihood.
    ///
    /// # Errors
    /// Never for validated settings.
    pub fn workspace(&self) -> Result<MeasurementLines> {
        self.wu.workspace()
    }

    /// log p(Z | X, C, O) at clutter density λ and occlusion γ ∈ [0, 1].
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite pose, λ or a NaN γ; [`Error::OutOfRange`] for γ
    /// outside [0, 1].
    pub fn log_likelihood(
        &self,
        ws: &mut MeasurementLines,
        image: &GreyImage<'_>,
        pose: &Affine2,
        lambda: f64,
        gamma: f64,
    ) -> Result<f64> {
        let gamma = check_gamma(gamma, 0)?;
        let lambda = clamp_lambda(lambda, self.wu.model.min_lambda, 0)?;
        let density = self.wu.density(lambda);
        let model = &self.wu.model;
        let mix = Mixture::new(model, gamma);
        self.wu
            .sum_lines(ws, image, pose, |m_l, candidates, length| {
                mix.line_log(model, m_l, candidates, length, &density)
            })
    }

    /// [`Self::log_likelihood`] for every pose; `lambdas` and `gammas` each hold one shared value
    /// or one per pose.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] for `out`, `lambdas` or `gammas`; per-pose errors as
    /// [`Self::log_likelihood`] with the hypothesis index.
    pub fn log_likelihood_batch(
        &self,
        ws: &mut MeasurementLines,
        image: &GreyImage<'_>,
        poses: &[Affine2],
        lambdas: &[f64],
        gammas: &[f64],
        out: &mut [f64],
    ) -> Result<()> {
        let mode = Batch::Sequential(ws);
        let params = [("lambdas", lambdas), ("gammas", gammas)];
        run_batch(mode, poses, params, out, |ws, pose, [l, g]| {
            self.log_likelihood(ws, image, pose, l, g)
        })
    }

    /// [`Self::log_likelihood_batch`] on the rayon thread pool, one workspace per task
    /// (allocated per call); bit-identical results, and the error of the lowest failing index.
    ///
    /// # Errors
    /// As [`Self::log_likelihood_batch`].
    pub fn log_likelihood_batch_par(
        &self,
        image: &GreyImage<'_>,
        poses: &[Affine2],
        lambdas: &[f64],
        gammas: &[f64],
        out: &mut [f64],
    ) -> Result<()> {
        let mode = Batch::Parallel(&self.wu.settings.lines);
        let params = [("lambdas", lambdas), ("gammas", gammas)];
        run_batch(mode, poses, params, out, |ws, pose, [l, g]| {
            self.log_likelihood(ws, image, pose, l, g)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn gauss(z: f64, s: f64) -> f64 {
        (-z * z / (2.0 * s * s)).exp() / (s * (2.0 * std::f64::consts::PI).sqrt())
    }

    fn poisson(m: u32, mu: f64) -> f64 {
        mu.powi(m as i32) * (-mu).exp() / (1..=m).map(f64::from).product::<f64>()
    }

    #[test]
    fn terms_equal_hand_computed_values() {
        let s = WuSettings::default();
        // λ = 0.1 /px, L = 20: μ = 2. Edges at −7.5, 1 and 3.5: m(L) = 3; W = 8 → |z| ≤ 4 → m(W) = 2.
        let t = wu_line_terms(&[-7.5, 1.0, 3.5], 20.0, 0.1, &s).unwrap();
        let miss = 0.1 * gauss(2.0, 2.0) * poisson(3, 2.0);
        let det = 0.9 * (gauss(1.0, 2.0) + gauss(3.5, 2.0)) / 2.0 * poisson(2, 2.0);
        assert_relative_eq!(t.log_target, (miss + det).ln(), epsilon = 1e-12);
        assert_relative_eq!(t.log_clutter, (poisson(3, 2.0) / 8.0).ln(), epsilon = 1e-12);
        // No edge in the window: Eq. 4; observed length 10 → μ = 1.
        let t = wu_line_terms(&[9.0], 10.0, 0.1, &s).unwrap();
        let want =
            0.1 * gauss(2.0, 2.0) * poisson(1, 1.0) + 0.9 * gauss(4.0, 2.0) * poisson(1, 1.0);
        assert_relative_eq!(t.log_target, want.ln(), epsilon = 1e-12);
        // No edge at all.
        let t = wu_line_terms(&[], 20.0, 0.05, &s).unwrap();
        let want = (0.1 * gauss(2.0, 2.0) + 0.9 * gauss(4.0, 2.0)) * (-1.0f64).exp();
        assert_relative_eq!(t.log_target, want.ln(), epsilon = 1e-12);
    }

    #[test]
    fn finite_as_lambda_vanishes() {
        let s = WuSettings::default();
        for lambda in [0.0, -1.0, 1e-300] {
            let t = wu_line_terms(&[0.5, 2.0, 6.0], 20.0, lambda, &s).unwrap();
            assert!(t.log_target.is_finite() && t.log_clutter.is_finite());
            // Clamped to min_lambda: identical to λ = 1e−4.
            let u = wu_line_terms(&[0.5, 2.0, 6.0], 20.0, 1e-4, &s).unwrap();
            assert_eq!(t, u);
        }
        assert!(wu_line_terms(&[], 20.0, f64::NAN, &s).is_err());
    }

    #[test]
    fn occlusion_mixture_limits() {
        let t = LineTerms {
            log_target: -3.2,
            log_clutter: -5.7,
        };
        assert_eq!(occlusion_line_log(t, 1.0), -5.7);
        assert_eq!(occlusion_line_log(t, 0.0), -3.2);
        let mid = occlusion_line_log(t, 0.25);
        assert_relative_eq!(
            mid,
            (0.25 * (-5.7f64).exp() + 0.75 * (-3.2f64).exp()).ln(),
            epsilon = 1e-12
        );
        assert!(check_gamma(1.5, 3).is_err());
        assert!(check_gamma(f64::NAN, 3).is_err());
    }

    #[test]
    fn settings_validate() {
        assert!(WuSettings::default().validate().is_ok());
        for bad in [
            WuSettings {
                window: 0.0,
                ..Default::default()
            },
            WuSettings {
                window: 21.0,
                ..Default::default()
            },
            WuSettings {
                p_detect: 1.1,
                ..Default::default()
            },
            // W = 60σ: G(W/2) = e^{−450} would underflow the linear-domain mixture.
            WuSettings {
                sigma: 0.1,
                window: 6.0,
                ..Default::default()
            },
            WuSettings {
                min_lambda: 0.0,
                ..Default::default()
            },
        ] {
            assert!(bad.validate().is_err());
        }
    }
}
