//! The observation models a tracker can multiply together, and their evaluation on one frame.
//!
//! - Odobez's shape likelihood p_sh (Eq. 19);
//! - the implicit motion likelihood p_c2 = exp(−λ_c d_c) (Eq. 22–23), d_c = 1 − ρ the NCC distance
//!   between the patch of c_k in z_k and the patch of c_{k−1} in z_{k−1};
//! - the motion consistency p_c1 = N(α̂_k; α_k, Λ̂_k) (Eq. 21), which cancels against Odobez's
//!   motion proposal (Eq. 24) but can be used with any proposal;
//! - Wu's Poisson-clutter likelihood with the particle's λ, mixed with the clutter-only term by the
//!   particle's γ (Wu Eq. 1–6, 11–12; γ = 0 is the plain Eq. 6), or with γ read as the hidden
//!   fraction of the contour, hidden as one arc ([`LikelihoodSettings::occlusion_arc`]).

use contour_obs::{
    LineTerms, MeasurementLines, OcclusionLikelihood, OdobezLikelihood, OdobezSettings, Template,
    WuSettings, occlusion_line_log,
};
use motion_est::NccSettings;
use serde::{Deserialize, Serialize};
use vision_core::GreyImage;

use crate::particle::Particle;
use crate::proposal::{ClusterMotion, log_motion_consistency};
use crate::space::ShapeSpace;
use crate::{Error, Result};

/// Settings of the implicit motion likelihood p_c2 (Odobez Eq. 22–23).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImplicitMotionSettings {
    /// λ_c of Eq. 22. Odobez does not give it. Default 10: a well-tracked patch has d_c ≈ 0.05–0.2,
    /// one that covers background moving differently d_c ≈ 0.5–1, so the term separates them by
    /// 3–10 nats, comparable to the shape likelihood's range (15 lines × up to 2 nats).
    pub lambda_c: f64,
    /// The reference grid R is an n×n lattice clipped to the disc (default 12: ≈ 113 samples).
    pub grid: usize,
    /// Radius of the disc relative to the contour (default 0.8): the patch stays inside the
    /// object, away from the outline the shape term measures (Odobez §4.4's independence argument).
    pub inner_radius: f64,
    /// How flat patches and samples outside the image are handled.
    pub ncc: NccSettings,
}

impl Default for ImplicitMotionSettings {
    fn default() -> Self {
        Self {
            lambda_c: 10.0,
            grid: 12,
            inner_radius: 0.8,
            ncc: NccSettings::default(),
        }
    }
}

/// Which likelihood terms a tracker multiplies.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LikelihoodSettings {
    /// Odobez's shape likelihood (Eq. 19).
    pub shape: Option<OdobezSettings>,
    /// Odobez's implicit motion likelihood p_c2 (Eq. 22–23).
    pub implicit_motion: Option<ImplicitMotionSettings>,
    /// Odobez's motion consistency p_c1 (Eq. 21); needs motion estimates (any proposal).
    pub motion_consistency: bool,
    /// Wu's clutter (and occlusion) likelihood (Eq. 1–6, 11–12).
    pub clutter: Option<WuSettings>,
    /// The share of each measurement line on which background clutter can appear (default 1,
    /// Wu Eq. 1: the whole line). A line is centred on the contour, so about half of it lies on
    /// the target, which hides the background behind it: with 1, the particles' λ estimates the
    /// edge density of the whole line, about half the background density that Wu's λ̄ were learnt
    /// from (random lines thrown on the background, §6.1), and β̂ reads one class too light. The
    /// presets use 0.5: the Poisson mean becomes λ · 0.5 · L, so that λ stays a background
    /// density comparable with λ̄.
    #[serde(default = "one")]
    pub clutter_line_fraction: f64,
    /// The share s of an occluded line's edge count that comes from an occluding surface of
    /// unknown texture, in [0, 1] (default 0: Wu Eq. 12 as printed). Wu's clutter-only term
    /// p(Z_i | C) = N(m(L); λ)/W explains the edges seen on a hidden line as background clutter
    /// of density λ; but those edges belong to the occluder, whose texture need not look like
    /// the background at all. With s > 0 the count of an occluded line is (1 − s) N(m; λ) +
    /// s U(m; 0..=L), the uniform being the least committal law of a count on a line of L pixels.
    /// Without it, an edge-rich occluder (the `occlusion` scene's: several edges per line, more
    /// than any of Wu's learnt classes explains) makes every hypothesis hidden behind it
    /// improbable, so the occluded hypotheses are pushed off the occluder — away from where the
    /// target is.
    #[serde(default)]
    pub unknown_occluder_share: f64,
    /// Weigh the pose by Wu's likelihood as a ratio against the no-target explanation of the
    /// same lines, at the edge density of the lines of the last estimate, and learn λ from
    /// those lines (default false: Wu Eq. 6 / 11 as printed; no preset uses it). See
    /// `LikelihoodModel::log_ratio_line` and `ReferenceLines`. Measured (sweep, 200
    /// particles, seeds 1–4): on the `occlusion` scene it keeps the contour on a target sliding
    /// behind the occluder for longer (mean IoU over frames 36–54, target 90 % → 1 % visible:
    /// w-eval 0.65 → 0.78 and w-occ 0.49 → 0.78 with shape noise 0.001 and σ_T = 1), but no
    /// track survives the full occlusion, and on `mclutter` w-eval falls from 0.90 to 0.53 mean
    /// IoU (3 of 4 tracks lost): with 15 lines the edge counts that Eq. 6 keeps are part of
    /// what holds the pose.
    #[serde(default)]
    pub likelihood_ratio: bool,
    /// Read Wu's γ as the *fraction* of the contour that is hidden, the hidden lines one
    /// contiguous arc, instead of Eq. 11's independent per-line mixture (default false: Eq. 11
    /// as printed). See `LikelihoodModel::log_occlusion_arc`. Eq. 11 gives every line
    /// γ p(Z_i | C) + (1 − γ) p(Z_i | x_i, C), so a half-hidden target at its true pose pays
    /// ln 2 on each of its visible lines (≈ 5 nats for 15 lines at γ = 0.5) and the lines it
    /// loses need not be adjacent: "whole contour, half hidden" then loses to "shrunk onto the
    /// visible sliver" or "on the occluder's straight edge, γ ≈ 0". With the arc, a pose pays
    /// only for the arc's position (ln n at most) and an occluder must hide a connected part.
    #[serde(default)]
    pub occlusion_arc: bool,
    /// With [`LikelihoodSettings::occlusion_arc`]: score every hidden line by the same
    /// constant c = e^{E[ln N(m; μ)]}/W, the typical value of Eq. 12 on a background line (minus
    /// the Poisson law's entropy), μ at the edge density of the lines of the last estimate
    /// (`ReferenceLines`), the same for every particle — instead of Eq. 12 at the line's own
    /// edge count (default false). A hidden line then says nothing about where the hidden target
    /// is: with Eq. 12 at the observed count, a hypothesis hidden behind the edge-rich occluder
    /// is improbable for that reason alone and the hidden hypotheses flee to plain ground and
    /// off the frame. A line outside the image is hidden by the frame's border: it scores c when
    /// hidden and c e^{−10} when visible, so only the arc can cover it (γ rises as the contour
    /// leaves the frame). With the particle's own λ in c instead, light clutter made every line
    /// cheaper to hide than to see and every track went "lost" at once (measured: w-eval on
    /// `occlusion`, mean IoU 0.09, 4 of 4 lost by frame 31).
    #[serde(default)]
    pub neutral_hidden_lines: bool,
}

fn one() -> f64 {
    1.0
}

impl Default for LikelihoodSettings {
    fn default() -> Self {
        Self {
            shape: None,
            implicit_motion: None,
            motion_consistency: false,
            clutter: None,
            clutter_line_fraction: 1.0,
            unknown_occluder_share: 0.0,
            likelihood_ratio: false,
            occlusion_arc: false,
            neutral_hidden_lines: false,
        }
    }
}

impl LikelihoodSettings {
    /// Checks every term and that at least one looks at the image.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] or the observation crate's error.
    pub fn validate(&self) -> Result<()> {
        if self.shape.is_none() && self.implicit_motion.is_none() && self.clutter.is_none() {
            return Err(Error::InvalidSetting {
                name: "likelihood",
                reason: "at least one of shape, implicit_motion or clutter is needed".into(),
            });
        }
        if let Some(s) = &self.shape {
            s.validate()?;
        }
        if let Some(w) = &self.clutter {
            w.validate()?;
        }
        let s = self.unknown_occluder_share;
        if !(0.0..=1.0).contains(&s) {
            return Err(Error::InvalidSetting {
                name: "likelihood.unknown_occluder_share",
                reason: format!("{s} must be in [0, 1]"),
            });
        }
        let f = self.clutter_line_fraction;
        if !(f > 0.0 && f <= 1.0) {
            return Err(Error::InvalidSetting {
                name: "likelihood.clutter_line_fraction",
                reason: format!("{f} must be in (0, 1]"),
            });
        }
        if let Some(m) = &self.implicit_motion {
            if !(m.lambda_c.is_finite() && m.lambda_c >= 0.0) {
                return Err(Error::InvalidSetting {
                    name: "implicit_motion.lambda_c",
                    reason: format!("{} must be finite and non-negative", m.lambda_c),
                });
            }
            if !(2..=64).contains(&m.grid) {
                return Err(Error::InvalidSetting {
                    name: "implicit_motion.grid",
                    reason: format!("{} must be in 2..=64", m.grid),
                });
            }
            if !(m.inner_radius > 0.0 && m.inner_radius <= 1.5) {
                return Err(Error::InvalidSetting {
                    name: "implicit_motion.inner_radius",
                    reason: format!("{} must be in (0, 1.5]", m.inner_radius),
                });
            }
            m.ncc.validate()?;
        }
        Ok(())
    }
}

/// The built likelihood terms (templates sampled, grids laid out).
#[derive(Debug, Clone)]
pub struct LikelihoodModel {
    space: ShapeSpace,
    shape: Option<OdobezLikelihood>,
    implicit: Option<(ImplicitMotionSettings, Vec<[f64; 2]>)>,
    motion_consistency: bool,
    clutter: Option<OcclusionLikelihood>,
    clutter_line_fraction: f64,
    unknown_occluder_share: f64,
    likelihood_ratio: bool,
    occlusion_arc: bool,
    neutral_hidden_lines: bool,
}

impl LikelihoodModel {
    /// Builds the terms for the unit-circle template.
    ///
    /// # Errors
    /// Invalid settings.
    pub fn new(space: ShapeSpace, settings: &LikelihoodSettings) -> Result<Self> {
        settings.validate()?;
        let template = Template::UnitCircle;
        Ok(Self {
            space,
            shape: settings
                .shape
                .map(|s| OdobezLikelihood::new(s, &template))
                .transpose()?,
            implicit: settings.implicit_motion.map(|m| {
                let grid = motion_est::unit_disc_grid(m.grid)
                    .into_iter()
                    .map(|[x, y]| [x * m.inner_radius, y * m.inner_radius])
                    .collect();
                (m, grid)
            }),
            motion_consistency: settings.motion_consistency,
            clutter: settings
                .clutter
                .map(|w| OcclusionLikelihood::new(w, &template))
                .transpose()?,
            clutter_line_fraction: settings.clutter_line_fraction,
            unknown_occluder_share: settings.unknown_occluder_share,
            likelihood_ratio: settings.likelihood_ratio && settings.clutter.is_some(),
            occlusion_arc: settings.occlusion_arc,
            neutral_hidden_lines: settings.neutral_hidden_lines,
        })
    }

    /// The log of one line's likelihood ratio against the no-target explanation of the same
    /// line: ln(γ + (1 − γ) p(Z_i | x_i, C)/p_bg(Z_i)), with p(Z_i | x_i, C) Wu's target term
    /// (Eq. 3–5) at the particle's density over the line's clutter share (`log_target`), and
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
    /// edge-rich texture was a honeypot through Eq. 5's m(L)/μ, docs/RESULTS.md).
    fn log_ratio_line(
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

    /// Wu's occlusion likelihood (Eq. 11) at occlusion `gamma` from the per-line terms `terms`
    /// of [`contour_obs::WuLikelihood::line_terms`], with the occluded lines' edge count a mixture
    /// of background clutter and an unknown occluder (see
    /// [`LikelihoodSettings::unknown_occluder_share`]).
    fn log_occlusion_with_unknown_occluder(
        &self,
        settings: &WuSettings,
        terms: &[LineTerms],
        gamma: f64,
    ) -> f64 {
        terms
            .iter()
            .map(|t| occlusion_line_log(self.hidden_line_terms(settings, *t), gamma))
            .sum()
    }

    /// The terms of one line with its clutter-only part (the line hidden, Eq. 12) replaced by
    /// the mixture of background clutter and an unknown occluder (see
    /// [`LikelihoodSettings::unknown_occluder_share`]; unchanged with share 0).
    fn hidden_line_terms(&self, settings: &WuSettings, t: LineTerms) -> LineTerms {
        let s = self.unknown_occluder_share;
        if s <= 0.0 {
            return t;
        }
        let length = settings.lines.length as f64;
        let ln_window = settings.window.ln();
        // t.log_clutter = ln N(m; λ) − ln W; the uniform count law is 1/(L + 1).
        let ln_poisson = t.log_clutter + ln_window;
        let ln_count = ((1.0 - s) * ln_poisson.exp() + s / (length + 1.0)).ln();
        LineTerms {
            log_target: t.log_target,
            log_clutter: ln_count - ln_window,
        }
    }

    /// The occlusion likelihood with γ the hidden fraction of the contour, hidden as one
    /// contiguous arc ([`LikelihoodSettings::occlusion_arc`]).
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
    fn log_occlusion_arc(
        &self,
        settings: &WuSettings,
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
            let mut t = self.hidden_line_terms(settings, *t);
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

    /// The edge counts and observed lengths of the lines of state `x` on `image` into `out`
    /// (cleared first; left empty without the ratio form): the reference lines of
    /// [`FrameObservation::reference`].
    ///
    /// # Errors
    /// A non-finite state.
    pub fn reference_counts(
        &self,
        image: &GreyImage<'_>,
        x: &crate::space::StateVector,
        out: &mut ReferenceLines,
    ) -> Result<()> {
        out.counts.clear();
        out.density = None;
        let Some(clutter) = self
            .clutter
            .as_ref()
            .filter(|_| self.likelihood_ratio || self.neutral_hidden_lines)
        else {
            return Ok(());
        };
        let wu = clutter.wu();
        let mut ws = wu.workspace()?;
        let mut terms = vec![LineTerms::default(); wu.contour().len()];
        wu.line_terms(&mut ws, image, &self.space.pose(x), 0.1, &mut terms)?;
        out.counts
            .extend((0..ws.len()).map(|i| (ws.edges(i).len(), ws.observed_length(i))));
        let (count, length) = out
            .counts
            .iter()
            .fold((0, 0.0), |(c, l), &(m, len)| (c + m, l + len));
        // Floored at a tenth of Wu's lightest learnt class, so that an edge-free neighbourhood
        // does not make every stray edge decisive.
        out.density = (length > 0.0).then(|| (count as f64 / length).max(1e-3));
        Ok(())
    }
}

/// Per-thread scratch buffers of the likelihood terms.
#[derive(Debug, Default)]
struct Scratch {
    shape_lines: Option<MeasurementLines>,
    clutter_lines: Option<MeasurementLines>,
    patch_now: Vec<f32>,
    patch_prev: Vec<f32>,
    line_terms: Vec<LineTerms>,
}

/// The likelihood of one frame, ready for the particle filter.
#[derive(Debug, Clone, Copy)]
pub struct FrameObservation<'a> {
    /// The terms.
    pub model: &'a LikelihoodModel,
    /// The current frame z_k.
    pub current: GreyImage<'a>,
    /// The previous frame z_{k−1} (for p_c2).
    pub previous: GreyImage<'a>,
    /// Cluster motions (for p_c1).
    pub clusters: &'a [ClusterMotion],
    /// The lines at the tracker's last estimate on the current frame (used by
    /// [`LikelihoodSettings::likelihood_ratio`]; empty otherwise).
    pub reference: &'a ReferenceLines,
}

/// The measurement lines of one reference pose (the tracker's last estimate) on the current
/// frame, shared by every particle of the ratio form ([`LikelihoodSettings::likelihood_ratio`]).
///
/// In the ratio form the pose no longer carries the Poisson law of the clutter counts (Wu
/// Eq. 1), which is what λ and β are learnt from in Eq. 6. These lines take that role: the
/// same lines for every particle, so they inform λ without favouring any pose. Their edge
/// density is also the density at which every particle's ratio is evaluated: with the
/// particle's own λ in the ratio, a light λ inflates Eq. 5's m(L)/μ and every stray edge reads
/// as the outline (measured: w-eval on `mclutter` lost 4 of 4 tracks, β̂ mostly "light").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReferenceLines {
    /// Edge count and observed length of each line.
    pub counts: Vec<(usize, f64)>,
    /// Edges per pixel over all the lines, `None` when nothing was observed. The lines are
    /// centred on the target's outline, so this is the clutter density times the clutter share
    /// of a line ([`LikelihoodSettings::clutter_line_fraction`]), like the particles' λ in
    /// Eq. 1–5.
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
}

/// The log-likelihood of a line outside the image under "the target is visible there", relative
/// to the hidden-line constant of [`LikelihoodSettings::neutral_hidden_lines`]: e^{−10}, so that
/// a contour leaving the frame is explained by its hidden arc (γ rises, as the visible fraction
/// falls) rather than by visible lines that nothing can contradict.
const UNOBSERVED_VISIBLE_PENALTY: f64 = -10.0;

/// E[ln N(m; μ)] for m ~ N(·; μ): minus the entropy of the Poisson law (the sum is cut where
/// the remaining mass is negligible).
fn poisson_neg_entropy(mu: f64) -> f64 {
    let mu = mu.max(1e-12);
    let top = (mu + 12.0 * mu.sqrt() + 12.0) as usize;
    let mut ln_p = -mu;
    let mut sum = 0.0;
    for m in 0..=top {
        if m > 0 {
            ln_p += mu.ln() - (m as f64).ln();
        }
        sum += ln_p.exp() * ln_p;
    }
    sum
}

/// ln N(m; μ) = m ln μ − μ − ln m! (μ floored at 1e−12 so that an empty line stays finite).
fn log_poisson(m: usize, mu: f64) -> f64 {
    let mu = mu.max(1e-12);
    let ln_fact: f64 = (2..=m).map(|j| (j as f64).ln()).sum();
    m as f64 * mu.ln() - mu - ln_fact
}

impl FrameObservation<'_> {
    fn scratch(&self) -> Scratch {
        let m = self.model;
        Scratch {
            shape_lines: m.shape.as_ref().and_then(|s| s.workspace().ok()),
            clutter_lines: m.clutter.as_ref().and_then(|c| c.workspace().ok()),
            patch_now: vec![0.0; m.implicit.as_ref().map_or(0, |(_, g)| g.len())],
            patch_prev: vec![0.0; m.implicit.as_ref().map_or(0, |(_, g)| g.len())],
            line_terms: Vec::new(),
        }
    }

    /// The log-likelihood of one particle; −∞ when a term cannot be computed for it (a pose that
    /// is not finite), so that such a particle simply dies.
    fn evaluate(&self, p: &Particle, scratch: &mut Scratch) -> f64 {
        let m = self.model;
        let pose = m.space.pose(&p.now);
        let mut total = 0.0;
        if let (Some(shape), Some(ws)) = (&m.shape, scratch.shape_lines.as_mut()) {
            match shape.log_likelihood(ws, &self.current, &pose) {
                Ok(v) => total += v,
                Err(_) => return f64::NEG_INFINITY,
            }
        }
        if let (Some(clutter), Some(ws)) = (&m.clutter, scratch.clutter_lines.as_mut()) {
            let lambda = m.clutter_line_fraction * p.clutter.lambda;
            let value = if m.likelihood_ratio {
                let wu = clutter.wu();
                let terms = &mut scratch.line_terms;
                terms.resize(wu.contour().len(), LineTerms::default());
                // Pose and background both at the reference density (see `ReferenceLines`).
                let lambda_ref = self.reference.density.unwrap_or(lambda);
                wu.line_terms(ws, &self.current, &pose, lambda_ref, terms)
                    .map(|()| {
                        let ln_window = wu.settings().window.ln();
                        let ratio: f64 = (0..ws.len())
                            .map(|i| {
                                LikelihoodModel::log_ratio_line(
                                    terms[i],
                                    ws.edges(i).len(),
                                    ws.observed_length(i),
                                    ws.is_observed(i),
                                    lambda_ref / m.clutter_line_fraction,
                                    ln_window,
                                    p.gamma(),
                                )
                            })
                            .sum();
                        ratio + self.reference.log_counts(lambda)
                    })
            } else if m.occlusion_arc {
                let wu = clutter.wu();
                let terms = &mut scratch.line_terms;
                terms.resize(wu.contour().len(), LineTerms::default());
                wu.line_terms(ws, &self.current, &pose, lambda, terms)
                    .map(|()| {
                        let neutral = m.neutral_hidden_lines.then(|| {
                            // The same constant for every particle (see the setting).
                            let density = self.reference.density.unwrap_or(lambda);
                            let mu = density * wu.settings().lines.length as f64;
                            poisson_neg_entropy(mu) - wu.settings().window.ln()
                        });
                        if let Some(c) = neutral {
                            // The frame's border hides a line outside the image: it says as
                            // little as a hidden line, and only the hidden arc can cover it.
                            for (i, t) in terms.iter_mut().enumerate() {
                                if !ws.is_observed(i) {
                                    *t = LineTerms {
                                        log_target: c + UNOBSERVED_VISIBLE_PENALTY,
                                        log_clutter: c,
                                    };
                                }
                            }
                        }
                        m.log_occlusion_arc(wu.settings(), terms, p.gamma(), neutral)
                    })
            } else if m.unknown_occluder_share > 0.0 {
                let wu = clutter.wu();
                let terms = &mut scratch.line_terms;
                terms.resize(wu.contour().len(), LineTerms::default());
                wu.line_terms(ws, &self.current, &pose, lambda, terms)
                    .map(|()| {
                        m.log_occlusion_with_unknown_occluder(wu.settings(), terms, p.gamma())
                    })
            } else {
                clutter.log_likelihood(ws, &self.current, &pose, lambda, p.gamma())
            };
            match value {
                Ok(v) => total += v,
                Err(_) => return f64::NEG_INFINITY,
            }
        }
        if let Some((settings, grid)) = &m.implicit {
            let pose_prev = m.space.pose(&p.prev);
            let (now_view, prev_view) = (self.current, self.previous);
            let sampled = motion_est::sample_patch_into(
                now_view,
                grid,
                &pose.a,
                [pose.t.x, pose.t.y],
                &mut scratch.patch_now,
            )
            .and_then(|_| {
                motion_est::sample_patch_into(
                    prev_view,
                    grid,
                    &pose_prev.a,
                    [pose_prev.t.x, pose_prev.t.y],
                    &mut scratch.patch_prev,
                )
            })
            .and_then(|_| {
                motion_est::ncc_distance(&scratch.patch_now, &scratch.patch_prev, &settings.ncc)
            });
            match sampled {
                Ok(d) => total -= settings.lambda_c * d,
                Err(_) => return f64::NEG_INFINITY,
            }
        }
        if m.motion_consistency {
            total += log_motion_consistency(m.space, self.clusters, p);
        }
        total
    }
}

impl smc_core::Observation for FrameObservation<'_> {
    type State = Particle;

    fn log_likelihood(&self, state: &Particle) -> f64 {
        self.evaluate(state, &mut self.scratch())
    }

    /// One set of scratch buffers per batch (per chunk on the parallel path), none per particle.
    fn log_likelihood_batch(&self, states: &[Particle], out: &mut [f64]) {
        let mut scratch = self.scratch();
        for (s, o) in states.iter().zip(out.iter_mut()) {
            *o = self.evaluate(s, &mut scratch);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(share: f64) -> LikelihoodModel {
        let settings = LikelihoodSettings {
            clutter: Some(WuSettings::default()),
            unknown_occluder_share: share,
            ..LikelihoodSettings::default()
        };
        LikelihoodModel::new(ShapeSpace::Affine, &settings).unwrap()
    }

    #[test]
    fn unknown_occluder_mixture_reduces_to_wu_and_to_the_uniform_count() {
        let w = WuSettings::default();
        // Two lines: 3 edges (one in the window) and none, at λ = 0.05 per pixel.
        let terms = [
            contour_obs::wu_line_terms(&[-7.5, 1.0, 9.0], 20.0, 0.05, &w).unwrap(),
            contour_obs::wu_line_terms(&[], 20.0, 0.05, &w).unwrap(),
        ];
        for gamma in [0.0, 0.3, 1.0] {
            // Share 0 is Wu's Eq. 11 exactly.
            let wu: f64 = terms.iter().map(|t| occlusion_line_log(*t, gamma)).sum();
            let got = model(0.0).log_occlusion_with_unknown_occluder(&w, &terms, gamma);
            assert!((got - wu).abs() < 1e-12, "γ {gamma}: {got} vs {wu}");
        }
        // Share 1 at γ = 1: every line is 1/(L + 1) · 1/W, whatever its edges.
        let got = model(1.0).log_occlusion_with_unknown_occluder(&w, &terms, 1.0);
        let want = 2.0 * (-(21.0f64).ln() - w.window.ln());
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        // The target term (γ = 0) never depends on the share.
        let a = model(0.0).log_occlusion_with_unknown_occluder(&w, &terms, 0.0);
        let b = model(0.5).log_occlusion_with_unknown_occluder(&w, &terms, 0.0);
        assert!((a - b).abs() < 1e-12);
    }

    #[test]
    fn ratio_line_is_neutral_when_hidden_or_unobserved_and_penalises_texture() {
        let w = WuSettings::default();
        let (length, lambda, f) = (20.0, 0.08, 0.5);
        let ln_w = w.window.ln();
        let ratio = |edges: &[f64], observed: bool, gamma: f64| {
            let t = contour_obs::wu_line_terms(edges, length, f * lambda, &w).unwrap();
            LikelihoodModel::log_ratio_line(t, edges.len(), length, observed, lambda, ln_w, gamma)
        };
        let clean = [0.3];
        let texture = [-9.0, -6.5, -3.0, 0.3, 2.5, 5.0, 8.0];
        // A hidden line (γ = 1) and an unobserved one carry no evidence about the pose.
        assert_eq!(ratio(&texture, true, 1.0), 0.0);
        assert_eq!(ratio(&clean, false, 0.3), 0.0);
        // At γ = 0: Wu's target term over the no-target term N(m; λℓ)/W of the same line.
        let t = contour_obs::wu_line_terms(&clean, length, f * lambda, &w).unwrap();
        let bg = -lambda * length + (lambda * length).ln() - ln_w;
        assert!((ratio(&clean, true, 0.0) - (t.log_target - bg)).abs() < 1e-12);
        // The outline alone at the contour point is evidence for the target; the same edge on
        // an edge-rich texture is evidence against it (the target would hide half the texture).
        assert!(ratio(&clean, true, 0.0) > 0.0);
        assert!(ratio(&texture, true, 0.0) < 0.0);
        // An empty window is evidence against a visible target, so γ raises it.
        assert!(ratio(&[], true, 0.0) < ratio(&[], true, 0.5));
    }

    #[test]
    fn occlusion_arc_is_eq6_and_eq12_at_the_ends_and_a_contiguous_mixture_between() {
        let w = WuSettings::default();
        let m = model(0.0);
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
        assert!((m.log_occlusion_arc(&w, &terms, 0.0, None) - all_target).abs() < 1e-12);
        assert!((m.log_occlusion_arc(&w, &terms, 1.0, None) - all_hidden).abs() < 1e-12);
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
        let got = m.log_occlusion_arc(&w, &terms, 0.5, None);
        assert!((got - want).abs() < 1e-9, "{got} vs {want}");
        // A neutral constant replaces every hidden line's term.
        let got = m.log_occlusion_arc(&w, &terms, 1.0, Some(-2.0));
        assert!((got + 2.0 * n as f64).abs() < 1e-12);
    }

    #[test]
    fn poisson_neg_entropy_matches_known_values() {
        // H(Poisson(1)) = 1.3048 nats; μ → 0: the law is a point mass.
        assert!((poisson_neg_entropy(1.0) + 1.304_842_24).abs() < 1e-6);
        assert!(poisson_neg_entropy(1e-9).abs() < 1e-6);
    }

    #[test]
    fn share_outside_the_unit_interval_is_rejected() {
        let settings = LikelihoodSettings {
            clutter: Some(WuSettings::default()),
            unknown_occluder_share: 1.5,
            ..LikelihoodSettings::default()
        };
        assert!(settings.validate().is_err());
    }
}
