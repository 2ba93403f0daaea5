//! The region tracker: a particle filter over an axis-aligned elliptical head (centre, log-scale,
//! log-aspect) weighted by the colour log-ratio inside the contour and the contrast across it,
//! with a lost/locked chain read from the estimate's colour and reacquisition over the whole frame
//! while the target is believed lost.

use std::time::Instant;

use dbn_switch::{StatusEstimate, TrackStatus};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use smc_core::rng::{particle_rng, resampler_rng};
use smc_core::{Resampler, Systematic};
use vision_core::{BoundingBox, Ellipse};

use super::settings::RegionSettings;
use super::status::LostChain;
use crate::appearance::calibration::Calibration;
use crate::appearance::colour::{ColourBins, Histogram, is_chromatic, log_ratios};
use crate::appearance::window::WorkingWindow;
use crate::config::TrackerConfig;
use crate::frame::Frame;
use crate::space::STATE_SLOTS;
use crate::tracker::{Estimate, Tracker, WeightedEllipse};
use crate::{Error, Result};

/// Most working pixels read from one frame: while the target is lost the window is the whole
/// frame, read coarser when needed to stay under this bound.
const MAX_WINDOW_PIXELS: f64 = 40_000.0;
/// The outer ellipse of the background ring, in target half-axes.
const RING_OUTER: f64 = 2.0;
/// The inner ellipse of the background ring: a margin that the target's own pixels near its
/// boundary do not reach.
const RING_INNER: f64 = 1.25;
/// Standard deviation of the log-scale of a particle drawn around the detection.
const REACQUIRE_SCALE_SPREAD: f64 = 0.1;
/// Samples across the template's disc (a TEMPLATE_GRID² grid clipped to the disc).
const TEMPLATE_GRID: usize = 12;
/// Share of the learnt colours in the models the weights read (the rest is the first frame's).
const LEARNT_SHARE: f64 = 0.5;
/// Most centres tried by the dense search of the window.
const MAX_DETECTION_CENTRES: f64 = 1024.0;
/// Spacing of the detection grid, in the target's geometric-mean half-axis.
const DETECTION_STRIDE: f64 = 0.25;
/// How far the long jumps reach, in `sigma_position`.
const JUMP_FACTOR: f64 = 4.0;
/// Strength of the pull of the log-aspect back to the initial aspect, per frame.
const ASPECT_REVERSION: f64 = 0.05;

/// One hypothesis: centre (full-resolution pixels), log-scale and log-aspect relative to the
/// initial ellipse.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Hypothesis {
    cx: f64,
    cy: f64,
    log_scale: f64,
    log_aspect: f64,
}

impl Hypothesis {
    fn ellipse(&self, base: (f64, f64)) -> Ellipse {
        let s = self.log_scale.exp();
        let r = (0.5 * self.log_aspect).exp();
        Ellipse {
            cx: self.cx,
            cy: self.cy,
            a: base.0 * s * r,
            b: base.1 * s / r,
            angle: 0.0,
        }
    }
}

/// The state kept between frames.
#[derive(Debug)]
struct Track {
    /// How pixels are binned, fixed at the first frame.
    bins: ColourBins,
    /// From the annotation to the tracked region, fixed at the first frame.
    calibration: Calibration,
    base: (f64, f64),
    particles: Vec<Hypothesis>,
    scratch: Vec<Hypothesis>,
    weights: Vec<f64>,
    estimate: Hypothesis,
    velocity: [f64; 2],
    /// The target's colour at the first frame, and as learnt since.
    initial: Histogram,
    target: Histogram,
    /// The background's colour at the first frame, and as learnt since.
    initial_background: Histogram,
    background: Histogram,
    chain: LostChain,
    /// The grey template of the first frame, and as learnt since (empty without the term).
    initial_template: Vec<f32>,
    template: Vec<f32>,
    size: (usize, usize),
}

impl Track {
    /// The target and background models the weights read: the first frame's colours and the
    /// learnt ones in equal parts, so that learning follows slow changes without drifting (a
    /// background model learnt only around the estimate would stop knowing the colours next to
    /// the target, such as hair beside a face, and the estimate would grow over them).
    fn models(&self) -> (Histogram, Histogram) {
        let mut target = self.initial.clone();
        target.blend(&self.target, LEARNT_SHARE);
        let mut background = self.initial_background.clone();
        background.blend(&self.background, LEARNT_SHARE);
        (target, background)
    }
}

/// The region tracker ([`crate::region`]).
#[derive(Debug)]
pub struct RegionTracker {
    config: TrackerConfig,
    settings: RegionSettings,
    track: Option<Track>,
    window: WorkingWindow,
    ratios: Vec<f32>,
    /// The template's sample points on the unit disc, and a buffer for one hypothesis' samples
    /// and for the template the weights read.
    grid: Vec<[f64; 2]>,
    samples: Vec<f32>,
    reference: Vec<f32>,
    log_weights: Vec<f64>,
    raw_log_weights: Vec<f64>,
    ancestors: Vec<usize>,
    frame: usize,
}

impl RegionTracker {
    /// A region tracker for `config`, whose `region` settings must be present.
    ///
    /// # Errors
    /// An invalid configuration, or one without region settings.
    pub fn new(config: TrackerConfig) -> Result<Self> {
        config.validate()?;
        let settings = config.region.ok_or(Error::InvalidSetting {
            name: "region",
            reason: "the region tracker needs region settings".into(),
        })?;
        Ok(Self {
            config,
            settings,
            track: None,
            window: WorkingWindow::default(),
            ratios: Vec::new(),
            grid: motion_est::unit_disc_grid(TEMPLATE_GRID),
            samples: Vec::new(),
            reference: Vec::new(),
            log_weights: Vec::new(),
            raw_log_weights: Vec::new(),
            ancestors: Vec::new(),
            frame: 0,
        })
    }

    /// The bins of a track started on `frame`: colour bins for a frame with colour, grey levels
    /// for a grey frame or a grey image stored as RGB.
    fn bins(&self, frame: &Frame<'_>) -> ColourBins {
        let s = &self.settings;
        // Chromaticity reads the spread of a pixel's components, whatever their order.
        if frame
            .colour()
            .is_some_and(|(pixels, _)| is_chromatic(pixels))
        {
            ColourBins::colour(s.hs_bins, s.value_bins)
        } else {
            ColourBins::grey(2 * s.value_bins)
        }
    }

    /// The window read around `centre` for a target of half-axes `(a, b)`, or the whole frame.
    fn read_window(
        &mut self,
        frame: &Frame<'_>,
        bins: &ColourBins,
        centre: [f64; 2],
        axes: (f64, f64),
        whole: bool,
    ) {
        let (fw, fh) = (frame.width() as f64, frame.height() as f64);
        let side = 2.0 * (axes.0 * axes.1).sqrt();
        let mut step = (side / self.settings.working_size).max(1.0);
        let rect = if whole {
            [0.0, 0.0, fw, fh]
        } else {
            let (hx, hy) = (self.settings.search * axes.0, self.settings.search * axes.1);
            [
                centre[0] - hx,
                centre[1] - hy,
                centre[0] + hx,
                centre[1] + hy,
            ]
        };
        let area = (rect[2].min(fw) - rect[0].max(0.0)) * (rect[3].min(fh) - rect[1].max(0.0));
        step = step.max((area.max(0.0) / MAX_WINDOW_PIXELS).sqrt());
        self.window.read(frame, bins, rect, step);
    }

    /// Colour histogram inside `e` (Epanechnikov-weighted, as Pérez et al.) and of the ring
    /// around it, on the current window.
    fn histograms(&self, bins: usize, e: &Ellipse) -> (Option<Histogram>, Option<Histogram>) {
        let (inside, ring) = self
            .window
            .target_and_ring_counts(bins, e, (RING_INNER, RING_OUTER));
        (Histogram::from_counts(inside), Histogram::from_counts(ring))
    }
}

fn bbox(e: &Ellipse) -> BoundingBox {
    BoundingBox::new(e.cx - e.a, e.cy - e.b, 2.0 * e.a, 2.0 * e.b)
}

fn normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

impl Tracker for RegionTracker {
    fn name(&self) -> &str {
        &self.config.name
    }

    fn config(&self) -> &TrackerConfig {
        &self.config
    }

    fn init(&mut self, frame: Frame<'_>, ellipse: Ellipse) -> Result<Estimate> {
        let start = Instant::now();
        // Axis-aligned: a rotated ellipse is refused, a quarter turn written at angle 0.
        let e = self.config.initial_ellipse(&ellipse)?;
        let bins = self.bins(&frame);
        self.read_window(&frame, &bins, [e.cx, e.cy], (e.a, e.b), false);
        let (target, background) = self.histograms(bins.len(), &e);
        let (Some(target), Some(background)) = (target, background) else {
            return Err(Error::InvalidSetting {
                name: "initial ellipse",
                reason: format!(
                    "{} covers no pixel of the frame or leaves no background around it in the \
                     frame; start from a smaller box inside the frame",
                    crate::tracker::describe(&ellipse)
                ),
            });
        };
        log_ratios(&target, &background, &mut self.ratios);
        self.window.integrate(&self.ratios);
        let calibration = Calibration::search(&self.window, &e, self.settings.contrast_ring);
        let annotated = e;
        let e = calibration.tracked(&annotated);
        let mut template = vec![0.0; self.grid.len()];
        self.window.patch(&e, &self.grid, &mut template)?;
        let estimate = Hypothesis {
            cx: e.cx,
            cy: e.cy,
            log_scale: 0.0,
            log_aspect: 0.0,
        };
        let n = self.config.particles;
        let chain = LostChain::new(
            self.settings.status_persistence,
            target.bhattacharyya(&background),
        );
        self.track = Some(Track {
            bins,
            calibration,
            base: (e.a, e.b),
            particles: vec![estimate; n],
            scratch: Vec::with_capacity(n),
            weights: vec![1.0 / n as f64; n],
            estimate,
            velocity: [0.0; 2],
            initial: target.clone(),
            target,
            initial_background: background.clone(),
            background,
            chain,
            initial_template: template.clone(),
            template,
            size: (frame.width(), frame.height()),
        });
        self.frame = 0;
        Ok(Estimate {
            frame: 0,
            ellipse: annotated,
            bbox: bbox(&annotated),
            state: [0.0; STATE_SLOTS],
            ess: n as f64,
            diagnostics: None,
            clutter: None,
            gamma: Some(0.0),
            status: Some(StatusEstimate {
                alpha_hat: TrackStatus::Locked,
                alpha_probs: [1.0, 0.0, 0.0],
                gamma_hat: 0.0,
            }),
            motion_clusters: (0, 0),
            millis: start.elapsed().as_secs_f64() * 1e3,
        })
    }

    fn update(&mut self, frame: Frame<'_>) -> Result<Estimate> {
        let start = Instant::now();
        let mut track = self.track.take().ok_or(Error::NotInitialised)?;
        let result = self.step(&mut track, &frame, start);
        self.track = Some(track);
        result
    }

    fn particles(&self, max: usize) -> Vec<WeightedEllipse> {
        let Some(track) = &self.track else {
            return Vec::new();
        };
        let mut all: Vec<WeightedEllipse> = track
            .particles
            .iter()
            .zip(&track.weights)
            .map(|(p, &w)| WeightedEllipse {
                ellipse: track.calibration.reported(&p.ellipse(track.base)),
                weight: w,
            })
            .collect();
        all.sort_by(|a, b| b.weight.total_cmp(&a.weight));
        all.truncate(max);
        all
    }
}

impl RegionTracker {
    /// One frame: prediction, weighting, the estimate, the lost/locked chain and the model
    /// updates, then resampling.
    fn step(&mut self, track: &mut Track, frame: &Frame<'_>, start: Instant) -> Result<Estimate> {
        self.check_frame_size(track, frame)?;
        self.frame += 1;
        let t = self.frame as u64;
        let current = track.estimate.ellipse(track.base);
        self.predict(track, frame, &current, t);
        let ess = self.weigh(track, &current, t)?;
        let (mean, e) = self.mean_estimate(track)?;
        self.update_status_and_models(track, &mean, &e)?;
        track.estimate = mean;
        self.resample(track, t)?;

        let status = track.chain.estimate();
        let reported = track.calibration.reported(&e);
        Ok(Estimate {
            frame: self.frame,
            ellipse: reported,
            bbox: bbox(&reported),
            state: [0.0; STATE_SLOTS],
            ess,
            diagnostics: None,
            clutter: None,
            gamma: Some(status.gamma_hat),
            status: Some(status),
            motion_clusters: (0, 0),
            millis: start.elapsed().as_secs_f64() * 1e3,
        })
    }

    /// An error unless `frame` has the size of the track's first frame.
    fn check_frame_size(&self, track: &Track, frame: &Frame<'_>) -> Result<()> {
        if (frame.width(), frame.height()) != track.size {
            return Err(Error::BadFrame {
                frame: self.frame + 1,
                reason: format!(
                    "{}x{} frame after {}x{} frames",
                    frame.width(),
                    frame.height(),
                    track.size.0,
                    track.size.1
                ),
            });
        }
        Ok(())
    }

    /// Reads the window around the drifted estimate (the whole frame while the target is
    /// believed lost), integrates its log-ratios and returns the best centre of the `current`
    /// ellipse in it, where the detection jumps land.
    fn read_and_detect(
        &mut self,
        track: &Track,
        frame: &Frame<'_>,
        current: &Ellipse,
        drift: [f64; 2],
    ) -> Option<[f64; 2]> {
        let s = self.settings;
        let p_lost = track.chain.p_lost();
        let bins = track.bins;
        let centre = [current.cx + drift[0], current.cy + drift[1]];
        self.read_window(frame, &bins, centre, (current.a, current.b), p_lost > 0.5);
        let (target, background) = track.models();
        log_ratios(&target, &background, &mut self.ratios);
        self.window.integrate(&self.ratios);
        let [x0, y0, x1, y1] = self.window.bounds();
        let cells = (x1 - x0) * (y1 - y0) / (self.window.step() * self.window.step());
        let stride = (DETECTION_STRIDE * (current.a * current.b).sqrt() / self.window.step())
            .max((cells / MAX_DETECTION_CENTRES).sqrt());
        self.window
            .best_centre((current.a, current.b), s.contrast_ring, stride)
            .map(|(c, _)| c)
    }

    /// Prediction: a random walk around the drifted state, a share of long jumps, and (more
    /// often while the target is believed lost) a share of draws around the detection.
    fn predict(&mut self, track: &mut Track, frame: &Frame<'_>, current: &Ellipse, t: u64) {
        let s = self.settings;
        let seed = self.config.seed;
        let p_lost = track.chain.p_lost();
        let sigma = s.sigma_position * (current.a * current.b).sqrt();
        let (fw, fh) = (frame.width() as f64, frame.height() as f64);
        let drift = [
            s.velocity_retention * track.velocity[0],
            s.velocity_retention * track.velocity[1],
        ];
        // The window and its log-ratio integral image are read before the prediction.
        let detection = self.read_and_detect(track, frame, current, drift);
        let detect_share = s.detection_share.max(s.reacquire_share * p_lost);
        track.scratch.clear();
        for (i, p) in track.particles.iter().enumerate() {
            let mut rng = particle_rng(seed, t, i);
            let jump = rng.random::<f64>() < detect_share;
            let q = if let (true, Some(d)) = (jump, detection) {
                Hypothesis {
                    cx: (d[0] + sigma * normal(&mut rng)).clamp(0.0, fw),
                    cy: (d[1] + sigma * normal(&mut rng)).clamp(0.0, fh),
                    log_scale: track.estimate.log_scale + REACQUIRE_SCALE_SPREAD * normal(&mut rng),
                    log_aspect: track.estimate.log_aspect,
                }
            } else {
                let k = if rng.random::<f64>() < s.jump_probability {
                    JUMP_FACTOR
                } else {
                    1.0
                };
                Hypothesis {
                    cx: (p.cx + drift[0] + k * sigma * normal(&mut rng)).clamp(0.0, fw),
                    cy: (p.cy + drift[1] + k * sigma * normal(&mut rng)).clamp(0.0, fh),
                    log_scale: (1.0 - s.scale_reversion) * p.log_scale
                        + s.sigma_scale * normal(&mut rng),
                    log_aspect: (1.0 - ASPECT_REVERSION) * p.log_aspect
                        + s.sigma_aspect * normal(&mut rng),
                }
            };
            track.scratch.push(q);
        }
        std::mem::swap(&mut track.particles, &mut track.scratch);
    }

    /// Weights: contrast across each hypothesis' contour, and its template and edge terms when
    /// enabled, tempered to keep the effective sample size. Returns that sample size.
    fn weigh(&mut self, track: &mut Track, current: &Ellipse, t: u64) -> Result<f64> {
        let s = self.settings;
        self.reference.clear();
        self.reference.extend(
            track
                .initial_template
                .iter()
                .zip(&track.template)
                .map(|(a, b)| {
                    ((1.0 - LEARNT_SHARE) * f64::from(*a) + LEARNT_SHARE * f64::from(*b)) as f32
                }),
        );
        self.samples.resize(self.grid.len(), 0.0);
        let ncc = motion_est::NccSettings::default();
        self.log_weights.clear();
        let reference = self.window.area(current);
        for p in &track.particles {
            let e = p.ellipse(track.base);
            let mut lw = s.colour_weight * self.window.contrast(&e, s.contrast_ring, reference);
            if s.template_weight > 0.0 {
                self.window.patch(&e, &self.grid, &mut self.samples)?;
                let d = motion_est::ncc_distance(&self.reference, &self.samples, &ncc)?;
                lw += s.template_weight * (1.0 - d);
            }
            if s.gradient_weight > 0.0 {
                lw += s.gradient_weight * self.window.edge_strength(&e);
            }
            self.log_weights.push(lw);
        }
        let n = track.particles.len();
        let tempered = smc_core::temper::temper(
            &mut self.log_weights,
            &mut track.weights,
            &mut self.raw_log_weights,
            s.min_ess_fraction * n as f64,
        )
        .map_err(|reason| Error::Smc(smc_core::Error::DegenerateWeights { step: t, reason }))?;
        Ok(tempered.ess)
    }

    /// The estimate: the weighted mean hypothesis and its ellipse, an error when not finite.
    fn mean_estimate(&self, track: &Track) -> Result<(Hypothesis, Ellipse)> {
        let mut mean = Hypothesis::default();
        for (p, &w) in track.particles.iter().zip(&track.weights) {
            mean.cx += w * p.cx;
            mean.cy += w * p.cy;
            mean.log_scale += w * p.log_scale;
            mean.log_aspect += w * p.log_aspect;
        }
        let e = mean.ellipse(track.base);
        if ![e.cx, e.cy, e.a, e.b].iter().all(|v| v.is_finite()) {
            return Err(Error::BadFrame {
                frame: self.frame,
                reason: "the estimated contour is not finite".into(),
            });
        }
        Ok((mean, e))
    }

    /// Status from the estimate's colour; model updates from locked frames only.
    fn update_status_and_models(
        &mut self,
        track: &mut Track,
        mean: &Hypothesis,
        e: &Ellipse,
    ) -> Result<()> {
        let s = self.settings;
        let (inside, ring) = self.histograms(track.bins.len(), e);
        let similarity = inside
            .as_ref()
            .map_or(0.0, |h| h.bhattacharyya(&track.initial));
        track.chain.update(similarity);
        let p_lost = track.chain.p_lost();
        if p_lost < 0.5 {
            if let Some(ring) = &ring {
                track.background.blend(ring, s.background_rate);
            }
            if let Some(inside) = &inside {
                track
                    .target
                    .blend(inside, s.target_rate * (1.0 - 2.0 * p_lost));
            }
            track.velocity = [mean.cx - track.estimate.cx, mean.cy - track.estimate.cy];
            if s.template_rate > 0.0 {
                self.update_template(track, e, p_lost)?;
            }
        } else {
            track.velocity = [0.0; 2];
        }
        Ok(())
    }

    /// Blends the grey samples inside `e` into the learnt template, at a rate that falls to
    /// nothing as the target's probability of being lost reaches one half.
    fn update_template(&mut self, track: &mut Track, e: &Ellipse, p_lost: f64) -> Result<()> {
        self.window.patch(e, &self.grid, &mut self.samples)?;
        let rate = (self.settings.template_rate * (1.0 - 2.0 * p_lost)) as f32;
        for (t, v) in track.template.iter_mut().zip(&self.samples) {
            if v.is_finite() {
                *t = (1.0 - rate) * *t + rate * v;
            }
        }
        Ok(())
    }

    /// Resampling (every frame, systematic), leaving equal weights.
    fn resample(&mut self, track: &mut Track, t: u64) -> Result<()> {
        let n = track.particles.len();
        let mut rng = resampler_rng(self.config.seed, t);
        Systematic.resample(&track.weights, n, &mut rng, &mut self.ancestors)?;
        track.scratch.clear();
        track
            .scratch
            .extend(self.ancestors.iter().map(|&i| track.particles[i]));
        std::mem::swap(&mut track.particles, &mut track.scratch);
        track.weights.fill(1.0 / n as f64);
        Ok(())
    }
}
