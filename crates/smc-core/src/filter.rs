//! One step of the particle filter (Odobez Fig. 2 with the general update of Odobez Eq. 3;
//! Wu Fig. 6), whole or in pieces.
//!
//! # Order of a step
//! 1. **Resample if needed** ([`ParticleFilter::resample_if_needed`]): if ESS < threshold · N
//!    (always when threshold = 1, as both papers do), draw ancestors from the current normalised
//!    weights, copy the chosen particles, and reset the weights to 1/M. Both papers resample at the
//!    end of an iteration; doing it at the start of the next one is the same sequence of
//!    operations, but leaves the weighted set of step k available to the caller for estimation.
//! 2. **Propagate** ([`ParticleFilter::propagate`]): x_k^i ~ q(· | x_{k−1}^i, z_k), particle i
//!    drawing from its own generator derived from (seed, step, i).
//! 3. **Weight** ([`ParticleFilter::weight`]): log w_k^i = log W_{k−1}^i + log p(z_k | x_k^i) +
//!    log p(x_k^i | x_{k−1}^i) − log q(x_k^i | x_{k−1}^i, z_k) (Odobez Eq. 3; the last two terms
//!    are skipped for the bootstrap filter), then normalise by log-sum-exp.
//!
//! Since the set's weights W are always normalised, the log-evidence increment
//! log Σᵢ W_{k−1}^i w̃ᵢ, with w̃ the incremental weight, estimates log p(z_k | z_{1:k−1}) whether or not
//! step 1 resampled (W = 1/M after resampling), and the sum over steps estimates log p(z_{1:K}).

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::history::{History, HistorySettings};
use crate::model::{Bootstrap, Dynamics, Observation, Proposal};
use crate::particles::{ParticleSet, check_len};
use crate::resample::{Resampler, count_distinct};
use crate::rng::{particle_rng, resampler_rng};

/// Settings of a [`ParticleFilter`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FilterSettings {
    /// Resample when ESS < `resample_threshold` · N. Must lie in (0, 1]; 1.0 (the default)
    /// resamples at every step, as Odobez Fig. 2 and Wu Fig. 6 do.
    pub resample_threshold: f64,
    /// Number of particles after resampling; `None` (the default) keeps N. Only takes effect at
    /// steps that resample.
    pub output_size: Option<usize>,
    /// Propagate and weight particles on the rayon thread pool (a tracker built on this filter
    /// may run more of its work there too). Results are bit-identical to the sequential path for
    /// any number of threads, because every particle draws from its own generator. Default
    /// `false`: for cheap models the thread hand-off costs more than it saves.
    pub parallel: bool,
    /// Smallest number of particles handed to one rayon task (default 64).
    pub parallel_min_chunk: usize,
    /// Record every step's weighted particles and ancestors in a [`History`] for the smoothers of
    /// [`crate::smooth`] (see [`ParticleFilter::history`]). `None` (the default) records nothing
    /// and costs nothing.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub history: Option<HistorySettings>,
    /// Temper the likelihood so that its conditional effective sample size stays at or above
    /// this fraction of N ([`crate::temper::tempering_exponent`]): each step's likelihood is
    /// raised to the largest power φ ∈ (0, 1] that keeps the floor. With equal weights before the
    /// update and the bootstrap proposal, that is the ESS after weighting. `None` (the default): never tempered, the update of
    /// Odobez Eq. 3 as printed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_ess_fraction: Option<f64>,
}

impl Default for FilterSettings {
    fn default() -> Self {
        Self {
            resample_threshold: 1.0,
            output_size: None,
            parallel: false,
            parallel_min_chunk: 64,
            history: None,
            min_ess_fraction: None,
        }
    }
}

impl FilterSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when the threshold or the ESS floor is outside (0, 1] (or NaN),
    /// the output size is zero, the chunk size is zero, or the history settings are invalid.
    pub fn validate(&self) -> Result<()> {
        let t = self.resample_threshold;
        if !(t > 0.0 && t <= 1.0) {
            return Err(Error::InvalidSetting {
                name: "resample_threshold",
                reason: format!("{t} is outside (0, 1]"),
            });
        }
        if self.output_size == Some(0) {
            return Err(Error::InvalidSetting {
                name: "output_size",
                reason: "must be at least 1".into(),
            });
        }
        if self.parallel_min_chunk == 0 {
            return Err(Error::InvalidSetting {
                name: "parallel_min_chunk",
                reason: "must be at least 1".into(),
            });
        }
        if let Some(history) = &self.history {
            history.validate()?;
        }
        if let Some(f) = self.min_ess_fraction
            && !(f > 0.0 && f <= 1.0)
        {
            return Err(Error::InvalidSetting {
                name: "min_ess_fraction",
                reason: format!("{f} is outside (0, 1]"),
            });
        }
        Ok(())
    }
}

/// What the resampling stage of a step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResampleReport {
    /// ESS of the weights the step started with (before any resampling).
    pub ess: f64,
    /// Whether the set was resampled.
    pub resampled: bool,
    /// Number of distinct ancestors that survived (N when not resampled).
    pub distinct_ancestors: usize,
}

/// What the weighting stage of a step produced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WeightReport {
    /// log Σᵢ W_{k−1}^i w̃ᵢ: the estimate of log p(z_k | z_{1:k−1}).
    pub log_evidence_increment: f64,
    /// Largest normalised weight after the update.
    pub max_weight: f64,
    /// ESS after the update.
    pub ess: f64,
    /// The exponent the likelihood was raised to ([`FilterSettings::min_ess_fraction`]; 1 when
    /// not tempered).
    pub exponent: f64,
}

/// Per-step diagnostics of [`ParticleFilter::step`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepDiagnostics {
    /// ESS before resampling (of the weights the step started with).
    pub ess: f64,
    /// Whether the step resampled.
    pub resampled: bool,
    /// Number of distinct ancestors after resampling (N when not resampled).
    pub distinct_ancestors: usize,
    /// Largest normalised weight at the end of the step.
    pub max_weight: f64,
    /// Estimate of log p(z_k | z_{1:k−1}).
    pub log_evidence_increment: f64,
    /// ESS at the end of the step (after weighting).
    pub ess_after: f64,
    /// The exponent the likelihood was raised to (1 when not tempered).
    pub tempering_exponent: f64,
}

impl StepDiagnostics {
    /// The diagnostics of a step from the reports of its resampling and weighting stages.
    pub fn of(resampled: &ResampleReport, weighted: &WeightReport) -> Self {
        Self {
            ess: resampled.ess,
            resampled: resampled.resampled,
            distinct_ancestors: resampled.distinct_ancestors,
            max_weight: weighted.max_weight,
            log_evidence_increment: weighted.log_evidence_increment,
            ess_after: weighted.ess,
            tempering_exponent: weighted.exponent,
        }
    }
}

/// A particle filter: settings plus the reusable buffers of a step.
///
/// # Examples
/// A bootstrap filter for a 1-D random walk observed in Gaussian noise:
/// ```
/// use smc_core::rand::Rng;
/// use smc_core::rand_distr::{Distribution, StandardNormal};
/// use smc_core::model::{Dynamics, FnObservation};
/// use smc_core::{FilterSettings, ParticleFilter, ParticleSet, ResamplingScheme};
///
/// struct Walk;
/// impl Dynamics for Walk {
///     type State = f64;
///     fn sample<R: Rng + ?Sized>(&self, x: &f64, rng: &mut R) -> f64 {
///         let e: f64 = StandardNormal.sample(rng);
///         x + e
///     }
///     fn log_density(&self, x: &f64, y: &f64) -> f64 {
///         -0.5 * (y - x).powi(2) - 0.5 * (2.0 * std::f64::consts::PI).ln()
///     }
/// }
///
/// let mut set = ParticleSet::from_states(vec![0.0; 1000])?;
/// let mut filter = ParticleFilter::new(FilterSettings::default())?;
/// let obs = FnObservation::new(|x: &f64| -0.5 * (x - 0.8).powi(2));
/// let d = filter.step_bootstrap(&mut set, &Walk, &obs, &ResamplingScheme::Systematic, 42, 0)?;
/// assert!(d.resampled && d.log_evidence_increment.is_finite());
/// # Ok::<(), smc_core::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct ParticleFilter<S> {
    settings: FilterSettings,
    ancestors: Vec<usize>,
    previous: Vec<S>,
    log_likelihoods: Vec<f64>,
    log_increments: Vec<f64>,
    /// Buffers of the tempering search (`FilterSettings::min_ess_fraction`), reused per step.
    temper_buffers: (Vec<f64>, Vec<f64>),
    seen: Vec<bool>,
    /// The recorded forward pass, when the settings ask for one.
    history: Option<History<S>>,
    /// Whether `ancestors` were set by a resampling stage not yet recorded.
    fresh_ancestors: bool,
}

impl<S: Clone + Send + Sync> ParticleFilter<S> {
    /// A filter with validated settings.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] from [`FilterSettings::validate`].
    pub fn new(settings: FilterSettings) -> Result<Self> {
        settings.validate()?;
        let history = settings.history.map(History::new).transpose()?;
        Ok(Self {
            history,
            fresh_ancestors: false,
            settings,
            ancestors: Vec::new(),
            previous: Vec::new(),
            log_likelihoods: Vec::new(),
            log_increments: Vec::new(),
            temper_buffers: (Vec::new(), Vec::new()),
            seen: Vec::new(),
        })
    }

    /// The settings.
    #[must_use]
    pub fn settings(&self) -> &FilterSettings {
        &self.settings
    }

    /// Ancestor index of each particle after the last [`ParticleFilter::resample_if_needed`]
    /// (the identity when it did not resample).
    #[must_use]
    pub fn ancestors(&self) -> &[usize] {
        &self.ancestors
    }

    /// The states x_{k−1} that the last [`ParticleFilter::propagate`] started from, aligned with
    /// the set's current states.
    #[must_use]
    pub fn previous_states(&self) -> &[S] {
        &self.previous
    }

    /// The recorded forward pass: one frame per completed weight stage (so one per
    /// [`ParticleFilter::step`]), with the weighted set after the update and the ancestors chosen
    /// by the resampling stage before it. `None` unless [`FilterSettings::history`] is set.
    #[must_use]
    pub fn history(&self) -> Option<&History<S>> {
        self.history.as_ref()
    }

    /// Takes the recorded history, leaving an empty one with the same settings in its place.
    /// `None` unless [`FilterSettings::history`] is set.
    pub fn take_history(&mut self) -> Option<History<S>> {
        let settings = *self.history.as_ref()?.settings();
        // The settings were validated when the history was first built.
        let empty = History::new(settings).ok()?;
        self.history.replace(empty)
    }

    fn record(&mut self, set: &ParticleSet<S>, step: u64) {
        let Some(history) = self.history.as_mut() else {
            return;
        };
        // Ancestors are only known when the resampling stage ran since the last record and they
        // index the previous frame; otherwise the genealogy of this frame is unknown.
        let fits = self.fresh_ancestors
            && self.ancestors.len() == set.len()
            && history
                .frame(history.len().wrapping_sub(1))
                .is_none_or(|previous| self.ancestors.iter().all(|&a| a < previous.set.len()));
        let ancestors = fits.then(|| self.ancestors.clone());
        self.fresh_ancestors = false;
        // The ancestors were checked above, so the push cannot fail; an unknown genealogy is
        // recorded as such rather than failing a valid filter step.
        if history.push(step, set.clone(), ancestors).is_err() {
            let _ = history.push(step, set.clone(), None);
        }
    }

    fn chunk(&self, n: usize) -> usize {
        n.div_ceil(4 * rayon::current_num_threads().max(1))
            .max(self.settings.parallel_min_chunk)
    }

    /// Step 1: resamples `set` if its ESS is below threshold · N (always when the threshold is 1).
    /// The resampler draws from the generator of (`seed`, `step`, reserved stream).
    ///
    /// # Errors
    /// [`Error::DegenerateWeights`] if the resampler rejects the weights (cannot happen for a
    /// valid set), or whatever error the resampler returns.
    pub fn resample_if_needed<Rs: Resampler + ?Sized>(
        &mut self,
        set: &mut ParticleSet<S>,
        resampler: &Rs,
        seed: u64,
        step: u64,
    ) -> Result<ResampleReport> {
        let n = set.len();
        let ess = set.ess();
        let threshold = self.settings.resample_threshold;
        // Threshold 1 means "every step": do not let ESS = N(1 ± ε) decide.
        let resample = threshold >= 1.0 || ess < threshold * n as f64;
        self.fresh_ancestors = true;
        if !resample {
            self.ancestors.clear();
            self.ancestors.extend(0..n);
            return Ok(ResampleReport {
                ess,
                resampled: false,
                distinct_ancestors: n,
            });
        }
        let m = self.settings.output_size.unwrap_or(n);
        let mut rng = resampler_rng(seed, step);
        resampler
            .resample(set.weights(), m, &mut rng, &mut self.ancestors)
            .map_err(|e| e.at_step(step))?;
        check_len("ancestors", m, self.ancestors.len())?;
        if let Some(&bad) = self.ancestors.iter().find(|&&a| a >= n) {
            return Err(Error::InvalidSetting {
                name: "ancestors",
                reason: format!("resampler returned index {bad} for {n} particles"),
            });
        }
        let distinct = count_distinct(&self.ancestors, n, &mut self.seen);
        if self.settings.parallel {
            let states = &set.states;
            self.ancestors
                .par_iter()
                .with_min_len(self.settings.parallel_min_chunk)
                .map(|&a| states[a].clone())
                .collect_into_vec(&mut self.previous);
        } else {
            self.previous.clear();
            self.previous
                .extend(self.ancestors.iter().map(|&a| set.states[a].clone()));
        }
        std::mem::swap(&mut set.states, &mut self.previous);
        set.reset_weights();
        Ok(ResampleReport {
            ess,
            resampled: true,
            distinct_ancestors: distinct,
        })
    }

    /// Step 2: moves every particle, x^i ← q(· | x^i) drawn from the generator of
    /// (`seed`, `step`, i). Weights are not touched. Afterwards
    /// [`ParticleFilter::previous_states`] holds the states before the move.
    pub fn propagate<P: Proposal<State = S> + ?Sized>(
        &mut self,
        set: &mut ParticleSet<S>,
        proposal: &P,
        seed: u64,
        step: u64,
    ) {
        std::mem::swap(&mut set.states, &mut self.previous);
        let draw = |(i, prev): (usize, &S)| {
            let mut rng = particle_rng(seed, step, i);
            proposal.sample(i, prev, &mut rng)
        };
        if self.settings.parallel {
            self.previous
                .par_iter()
                .enumerate()
                .with_min_len(self.settings.parallel_min_chunk)
                .map(draw)
                .collect_into_vec(&mut set.states);
        } else {
            set.states.clear();
            set.states
                .extend(self.previous.iter().enumerate().map(draw));
        }
    }

    /// Step 3: evaluates the observation model on every particle (through
    /// [`Observation::log_likelihood_batch`], in chunks on the parallel path) and applies the
    /// weight update, see [`ParticleFilter::weight_with_log_likelihoods`].
    ///
    /// # Errors
    /// As [`ParticleFilter::weight_with_log_likelihoods`].
    pub fn weight<P, D, O>(
        &mut self,
        set: &mut ParticleSet<S>,
        proposal: &P,
        prior: Option<&D>,
        observation: &O,
        step: u64,
    ) -> Result<WeightReport>
    where
        P: Proposal<State = S> + ?Sized,
        D: Dynamics<State = S> + ?Sized,
        O: Observation<State = S> + ?Sized,
    {
        let mut log_likelihoods = std::mem::take(&mut self.log_likelihoods);
        self.evaluate(set, observation, &mut log_likelihoods);
        let result = match self.settings.min_ess_fraction {
            Some(fraction) => self.temper_and_weight(
                set,
                proposal,
                prior,
                &mut log_likelihoods,
                step,
                fraction * set.len() as f64,
            ),
            None => self.weight_with_log_likelihoods(set, proposal, prior, &log_likelihoods, step),
        };
        self.log_likelihoods = log_likelihoods;
        result
    }

    /// log p(z | x^i) of every particle into `out` (through [`Observation::log_likelihood_batch`],
    /// in chunks on the parallel path).
    fn evaluate<O: Observation<State = S> + ?Sized>(
        &self,
        set: &ParticleSet<S>,
        observation: &O,
        out: &mut Vec<f64>,
    ) {
        let n = set.len();
        out.clear();
        out.resize(n, 0.0);
        if self.settings.parallel {
            let chunk = self.chunk(n);
            set.states
                .par_chunks(chunk)
                .zip(out.par_chunks_mut(chunk))
                .for_each(|(s, o)| observation.log_likelihood_batch(s, o));
        } else {
            observation.log_likelihood_batch(&set.states, out);
        }
    }

    /// The weighting of [`ParticleFilter::weight`] with a tempered likelihood
    /// ([`FilterSettings::min_ess_fraction`], [`crate::temper`]): the log-likelihoods are first
    /// multiplied by the largest exponent φ ∈ (0, 1] that keeps the conditional effective sample
    /// size of the updated weights at or above `min_ess`. Only the likelihood is tempered: the previous
    /// weights and the prior-over-proposal ratio enter at full strength.
    fn temper_and_weight<P, D>(
        &mut self,
        set: &mut ParticleSet<S>,
        proposal: &P,
        prior: Option<&D>,
        log_likelihoods: &mut [f64],
        step: u64,
        min_ess: f64,
    ) -> Result<WeightReport>
    where
        P: Proposal<State = S> + ?Sized,
        D: Dynamics<State = S> + ?Sized,
    {
        let n = set.len();
        // What the update adds besides the likelihood: the previous log weight and log p/q.
        let mut offsets = std::mem::take(&mut self.log_increments);
        offsets.clear();
        offsets.extend_from_slice(set.log_weights());
        if let Some(prior) = prior {
            check_len("previous states", n, self.previous.len())?;
            for (i, (o, (prev, next))) in offsets
                .iter_mut()
                .zip(self.previous.iter().zip(set.states.iter()))
                .enumerate()
            {
                *o += prior.log_density(prev, next) - proposal.log_density(i, prev, next);
            }
        }
        let (weights, scratch) = &mut self.temper_buffers;
        let tempered =
            crate::temper::tempering_exponent(log_likelihoods, &offsets, min_ess, weights, scratch);
        self.log_increments = offsets;
        let tempered = tempered.map_err(|e| match e {
            Error::InvalidWeights { reason } => Error::DegenerateWeights { step, reason },
            other => other,
        })?;
        crate::temper::apply_exponent(log_likelihoods, tempered.exponent);
        let report =
            self.weight_with_log_likelihoods(set, proposal, prior, log_likelihoods, step)?;
        Ok(WeightReport {
            exponent: tempered.exponent,
            ..report
        })
    }

    /// Step 3 with likelihoods computed by the caller: applies Odobez Eq. 3,
    /// log w^i += `log_likelihoods[i]` + log p(x^i | x′^i) − log q(x^i | x′^i, z), with x′ the
    /// [`ParticleFilter::previous_states`]. With `prior = None` (bootstrap: q is the prior) the two
    /// densities cancel and neither is evaluated, and `proposal` is not used.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] when `log_likelihoods` or (with a prior) the previous states do not
    /// match the set; [`Error::DegenerateWeights`] when an increment is NaN or +∞ or all updated
    /// weights are zero (the set is then unchanged).
    pub fn weight_with_log_likelihoods<P, D>(
        &mut self,
        set: &mut ParticleSet<S>,
        proposal: &P,
        prior: Option<&D>,
        log_likelihoods: &[f64],
        step: u64,
    ) -> Result<WeightReport>
    where
        P: Proposal<State = S> + ?Sized,
        D: Dynamics<State = S> + ?Sized,
    {
        let n = set.len();
        check_len("log_likelihoods", n, log_likelihoods.len())?;
        let log_evidence_increment = match prior {
            None => set.reweight(log_likelihoods, step)?,
            Some(prior) => {
                check_len("previous states", n, self.previous.len())?;
                let mut increments = std::mem::take(&mut self.log_increments);
                let corrected = |((i, ll), (prev, next)): ((usize, &f64), (&S, &S))| {
                    ll + prior.log_density(prev, next) - proposal.log_density(i, prev, next)
                };
                if self.settings.parallel {
                    log_likelihoods
                        .par_iter()
                        .enumerate()
                        .zip(self.previous.par_iter().zip(set.states.par_iter()))
                        .with_min_len(self.settings.parallel_min_chunk)
                        .map(corrected)
                        .collect_into_vec(&mut increments);
                } else {
                    increments.clear();
                    increments.extend(
                        log_likelihoods
                            .iter()
                            .enumerate()
                            .zip(self.previous.iter().zip(set.states.iter()))
                            .map(corrected),
                    );
                }
                let result = set.reweight(&increments, step);
                self.log_increments = increments;
                result?
            }
        };
        self.record(set, step);
        let (_, max_weight) = set.max_weight();
        Ok(WeightReport {
            log_evidence_increment,
            max_weight,
            ess: set.ess(),
            exponent: 1.0,
        })
    }

    /// A whole step: resample if needed, propagate with `proposal`, weight with `observation`
    /// and, when `prior` is given, the density ratio p/q (Odobez Eq. 3).
    ///
    /// # Errors
    /// As the three stages.
    #[allow(clippy::too_many_arguments)]
    pub fn step<P, D, O, Rs>(
        &mut self,
        set: &mut ParticleSet<S>,
        proposal: &P,
        prior: Option<&D>,
        observation: &O,
        resampler: &Rs,
        seed: u64,
        step: u64,
    ) -> Result<StepDiagnostics>
    where
        P: Proposal<State = S> + ?Sized,
        D: Dynamics<State = S> + ?Sized,
        O: Observation<State = S> + ?Sized,
        Rs: Resampler + ?Sized,
    {
        let resampled = self.resample_if_needed(set, resampler, seed, step)?;
        self.propagate(set, proposal, seed, step);
        let weighted = self.weight(set, proposal, prior, observation, step)?;
        Ok(StepDiagnostics::of(&resampled, &weighted))
    }

    /// A bootstrap (CONDENSATION) step: the dynamics are the proposal, the weight is the
    /// likelihood alone.
    ///
    /// # Errors
    /// As [`ParticleFilter::step`].
    pub fn step_bootstrap<D, O, Rs>(
        &mut self,
        set: &mut ParticleSet<S>,
        dynamics: &D,
        observation: &O,
        resampler: &Rs,
        seed: u64,
        step: u64,
    ) -> Result<StepDiagnostics>
    where
        D: Dynamics<State = S>,
        O: Observation<State = S> + ?Sized,
        Rs: Resampler + ?Sized,
    {
        self.step(
            set,
            &Bootstrap(dynamics),
            None::<&D>,
            observation,
            resampler,
            seed,
            step,
        )
    }
}
