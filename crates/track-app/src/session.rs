//! Running a tracker over frames: the glue between the `trackers` library and the files.
//!
//! A [`Session`] feeds frames to a [`Tracker`], turns each [`Estimate`] into a [`FrameRecord`]
//! and, when asked, draws the overlay of the frame (contour coloured by tracker status or clutter
//! class, the likely particles faintly, the ground-truth box).

use image::RgbImage;
use trackers::{Estimate, SmootherSettings, SwitchingStatistics, Tracker};

use vision_core::{BoundingBox, Ellipse, TrackStatus};

use crate::record::FrameRecord;
use crate::render::{
    INIT, Overlay, PARTICLE_MAX_ALPHA, clutter_colour, render_overlay, status_colour,
};
use crate::sequence::{Frame, Original};
use crate::{AppError, Result};

/// What colours the estimated contour in overlays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ColourBy {
    /// Tracker status α̂ (locked green, partial orange, lost red), as in Wu Fig. 15.
    #[default]
    Status,
    /// Clutter class β̂ (light blue, medium yellow, heavy magenta), as in Wu Fig. 10.
    Clutter,
}

/// The most particles drawn while the tracker is lost: they spread over the frame then, and more
/// of them would hide the estimate.
pub const LOST_PARTICLES: usize = 10;

/// Particles drawn fainter than this opacity are not drawn at all.
const MIN_PARTICLE_ALPHA: f64 = 0.02;

/// How a session draws overlays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrawOptions {
    /// What colours the contour.
    pub colour_by: ColourBy,
    /// How many of the heaviest particles to draw faintly ([`LOST_PARTICLES`] at most while the
    /// tracker is lost).
    pub particles: usize,
}

impl Default for DrawOptions {
    fn default() -> Self {
        Self {
            colour_by: ColourBy::Status,
            particles: 30,
        }
    }
}

pub use trackers::status_from_gamma;

/// The status shown for an estimate ([`trackers::Estimate::track_status`]).
pub fn display_status(e: &Estimate) -> TrackStatus {
    e.track_status()
}

/// Whether the estimate carries a tracker status: α̂ of a status process, or γ̂ read as one.
fn has_status(e: &Estimate) -> bool {
    e.status.is_some() || e.gamma.is_some()
}

/// The overlay's label: the 1-based frame number, then `init` on the initialisation frame, else
/// the clutter class when the contour is coloured by it and the status when the tracker has one.
pub fn overlay_label(frame: usize, e: &Estimate, init: bool, colour_by: ColourBy) -> String {
    let mut text = format!("frame {}", frame + 1);
    if init {
        text.push_str("  init");
        return text;
    }
    if let (ColourBy::Clutter, Some(c)) = (colour_by, &e.clutter) {
        text.push_str(&format!("  clutter {}", c.beta_hat));
    }
    if has_status(e) {
        text.push_str("  ");
        text.push_str(display_status(e).name());
    }
    text
}

/// The record of one estimate (frame index from the caller: the sequence's numbering).
pub fn record_of(frame: usize, e: &Estimate) -> FrameRecord {
    let mut r = FrameRecord::new(frame, e.ellipse, e.ess, e.millis);
    r.bbox = e.bbox;
    if let Some(c) = &e.clutter {
        r.beta_hat = Some(c.beta_hat);
        r.beta_probs = c.beta_probs.clone();
        r.lambda_hat = Some(c.lambda_hat);
    }
    r.gamma_hat = e.gamma;
    if let Some(s) = &e.status {
        r.alpha_hat = Some(s.alpha_hat);
        r.alpha_probs = s.alpha_probs.to_vec();
    }
    r
}

/// A tracker running over a sequence.
pub struct Session {
    tracker: Box<dyn Tracker>,
    draw: Option<DrawOptions>,
    records: Vec<FrameRecord>,
    overlays: Vec<RgbImage>,
    started: bool,
}

/// What a session produced.
#[derive(Debug, Clone, Default)]
pub struct SessionOutput {
    /// One record per frame given to the session.
    pub records: Vec<FrameRecord>,
    /// One overlay per frame, when drawing was asked for.
    pub overlays: Vec<RgbImage>,
    /// Total tracking time (sum of the per-frame times), seconds.
    pub seconds: f64,
}

impl Session {
    /// A session of `tracker`, drawing overlays when `draw` is given.
    pub fn new(tracker: Box<dyn Tracker>, draw: Option<DrawOptions>) -> Self {
        Self {
            tracker,
            draw,
            records: Vec::new(),
            overlays: Vec::new(),
            started: false,
        }
    }

    /// The tracker.
    pub fn tracker(&self) -> &dyn Tracker {
        self.tracker.as_ref()
    }

    /// Feeds one frame: the first initialises the tracker on `init`, the others update it.
    /// `truth` is the frame's ground-truth box, drawn in the overlay.
    ///
    /// # Errors
    /// [`AppError::Computation`] naming the frame when the tracker fails.
    pub fn push(
        &mut self,
        frame: &Frame,
        init: &Ellipse,
        truth: Option<BoundingBox>,
    ) -> Result<&FrameRecord> {
        let (w, h) = (frame.grey.width() as usize, frame.grey.height() as usize);
        let grey = frame.grey.as_raw();
        let view = match &frame.original {
            Original::Rgb(rgb) => trackers::Frame::with_rgb(w, h, grey, rgb.as_raw()),
            Original::Luma(_) => trackers::Frame::new(w, h, grey),
        }
        .map_err(|e| AppError::input(&frame.name, e.to_string()))?;
        let failed = |e| AppError::computation(format!("tracking {}", frame.name), e);
        let estimate = if self.started {
            self.tracker.update(view).map_err(|e| match e {
                // A frame the tracker cannot read (a grey frame after a colour start): the
                // input's fault, named by its file.
                trackers::Error::BadFrame { reason, .. } => AppError::input(&frame.name, reason),
                other => failed(other),
            })
        } else {
            self.tracker.init(view, *init).map_err(|e| match e {
                // The tracker cannot start from this box: a setting (exit 2), not a failure.
                trackers::Error::InvalidSetting {
                    name: "initial ellipse",
                    reason,
                } => AppError::setting(
                    "the initial box (--init, or the first labelled box)",
                    reason,
                ),
                // A frame the tracker cannot start on (too small): the input's fault.
                trackers::Error::BadFrame { reason, .. } => AppError::input(&frame.name, reason),
                other => failed(other),
            })
        }?;
        let init = !self.started;
        self.started = true;
        if let Some(draw) = self.draw {
            self.overlays
                .push(self.overlay(frame, &estimate, truth, draw, init));
        }
        self.records.push(record_of(frame.index, &estimate));
        self.records
            .last()
            .ok_or_else(|| AppError::computation("tracking", "no record"))
    }

    /// The overlay of `e` on `frame`. The initialisation frame shows the initial contour in
    /// [`INIT`] without particles: the tracker has estimated nothing there yet, and its initial
    /// particles, equally weighted around the start, would draw as one thick band.
    fn overlay(
        &self,
        frame: &Frame,
        e: &Estimate,
        truth: Option<BoundingBox>,
        draw: DrawOptions,
        init: bool,
    ) -> RgbImage {
        let status = display_status(e);
        let colour = match (init, draw.colour_by, &e.clutter) {
            (true, _, _) => INIT,
            (false, ColourBy::Clutter, Some(c)) => clutter_colour(c.beta_hat),
            _ => status_colour(status),
        };
        let mut overlay = Overlay::new(e.ellipse, colour);
        if !init {
            let lost = has_status(e) && status == TrackStatus::Lost;
            let n = if lost {
                draw.particles.min(LOST_PARTICLES)
            } else {
                draw.particles
            };
            let particles = self.tracker.particles(n);
            let heaviest = particles.first().map_or(1.0, |p| p.weight).max(1e-300);
            // Opacity in proportion to the weight: a particle ten times lighter than the
            // heaviest is ten times fainter, so the cloud shows where the weight is.
            overlay.particles = particles
                .iter()
                .map(|p| (p.ellipse, PARTICLE_MAX_ALPHA * (p.weight / heaviest)))
                .filter(|(_, a)| *a >= MIN_PARTICLE_ALPHA)
                .collect();
        }
        overlay.groundtruth = truth;
        overlay.label = Some(overlay_label(frame.index, e, init, draw.colour_by));
        render_overlay(&frame.original.to_rgb(), &overlay)
    }

    /// Takes the overlay of the last frame pushed (when drawing), so that a long run can write
    /// overlays as it goes instead of keeping them all.
    pub fn take_overlay(&mut self) -> Option<RgbImage> {
        self.overlays.pop()
    }

    /// The smoothed record of every frame so far (see `trackers::smoothing`): the first
    /// frame's record as filtered (the initialisation), then the tracker's smoothed estimates;
    /// and the run's switching statistics.
    ///
    /// # Errors
    /// [`AppError::Computation`] when the tracker cannot be smoothed (its configuration records
    /// no particles) or the smoother fails.
    pub fn smoothed(
        &mut self,
        settings: &SmootherSettings,
    ) -> Result<(Vec<FrameRecord>, SwitchingStatistics)> {
        let run = self
            .tracker
            .smoothed(settings)
            .map_err(|e| AppError::computation("smoothing", e))?;
        let estimates = run.estimates;
        let mut records: Vec<FrameRecord> = self.records.first().cloned().into_iter().collect();
        for e in &estimates {
            let Some(filtered) = self.records.get(e.frame) else {
                return Err(AppError::computation(
                    "smoothing",
                    format!(
                        "a smoothed estimate of frame {} that was never tracked",
                        e.frame
                    ),
                ));
            };
            let mut r = record_of(filtered.frame, e);
            r.millis = filtered.millis;
            records.push(r);
        }
        Ok((records, run.statistics))
    }

    /// Ends the session.
    pub fn finish(self) -> SessionOutput {
        let seconds = self.records.iter().map(|r| r.millis).sum::<f64>() / 1e3;
        SessionOutput {
            records: self.records,
            overlays: self.overlays,
            seconds,
        }
    }
}
