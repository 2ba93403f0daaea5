//! What every tracker offers: an object-safe `init` / `update` interface in the spirit of
//! OpenCV's trackers ([`Tracker`]), and what it reports for a frame ([`Estimate`]).

use smc_core::StepDiagnostics;
use smc_core::smooth::SmootherSettings;
use vision_core::{BoundingBox, Ellipse};

use crate::config::TrackerConfig;
use crate::frame::Frame;
use crate::smoothing::SmoothedRun;
use crate::space::StateVector;
use crate::{Error, Result};
use dbn_switch::{ClutterEstimate, StatusEstimate};

/// What a tracker reports for one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Frame index (0 = the initialisation frame).
    pub frame: usize,
    /// The estimated contour as an ellipse.
    pub ellipse: Ellipse,
    /// Its axis-aligned box.
    pub bbox: BoundingBox,
    /// The estimated shape-space state, of the region the filter tracks: with appearance terms,
    /// the annotation scaled by the first frame's calibration (`ellipse` is in the annotation's
    /// convention), in the frame's pixels.
    pub state: StateVector,
    /// Effective sample size after weighting (N at the initialisation frame).
    pub ess: f64,
    /// The particle filter's diagnostics of this step (`None` at initialisation).
    pub diagnostics: Option<StepDiagnostics>,
    /// β̂, its class probabilities and λ̂ (`None` without clutter switching).
    pub clutter: Option<ClutterEstimate>,
    /// γ̂ = E\[γ\] (Wu Eq. 14), `None` without an occlusion model.
    pub gamma: Option<f64>,
    /// α̂ and its probabilities (`None` without the status HMM).
    pub status: Option<StatusEstimate>,
    /// Number of non-empty motion clusters, and how many of them fell back to the prior
    /// prediction because their motion could not be estimated (both 0 without motion). Clusters
    /// left empty by k-means (fewer distinct particles than K after resampling) are not counted:
    /// no particle uses them, so their motion is not estimated.
    pub motion_clusters: (usize, usize),
    /// Wall time of the update, milliseconds: everything the tracker does with the frame,
    /// shrinking it to the working scale included.
    pub millis: f64,
}

impl Estimate {
    /// The status this estimate reports: α̂ when the tracker has the status HMM, else from γ̂
    /// ([`status_from_gamma`]), else locked.
    pub fn track_status(&self) -> vision_core::TrackStatus {
        if let Some(s) = &self.status {
            return s.alpha_hat;
        }
        self.gamma
            .map_or(vision_core::TrackStatus::Locked, status_from_gamma)
    }
}

/// Tracker status thresholds on γ̂ for trackers that estimate occlusion but not α: the ranges of
/// Wu §6.3 (locked γ ≤ 0.2, lost γ ≥ 0.8, partially occluded between).
pub fn status_from_gamma(gamma: f64) -> vision_core::TrackStatus {
    if gamma <= 0.2 {
        vision_core::TrackStatus::Locked
    } else if gamma < 0.8 {
        vision_core::TrackStatus::PartiallyOccluded
    } else {
        vision_core::TrackStatus::Lost
    }
}

/// A weighted particle, for drawing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WeightedEllipse {
    /// The particle's contour.
    pub ellipse: Ellipse,
    /// Its normalised weight.
    pub weight: f64,
}

/// An object tracker: initialise on a frame, then update frame by frame. Object-safe, so an
/// application can pick the tracker at run time (`Box<dyn Tracker>`).
pub trait Tracker: Send {
    /// The tracker's name (its preset or configuration name).
    fn name(&self) -> &str;

    /// Its configuration.
    fn config(&self) -> &TrackerConfig;

    /// Starts tracking `ellipse` on `frame` (frame 0).
    ///
    /// # Errors
    /// An invalid frame or ellipse.
    fn init(&mut self, frame: Frame<'_>, ellipse: Ellipse) -> Result<Estimate>;

    /// Processes the next frame.
    ///
    /// # Errors
    /// [`Error::NotInitialised`], a frame of another size, or a degenerate filter.
    fn update(&mut self, frame: Frame<'_>) -> Result<Estimate>;

    /// The `max` most heavily weighted particles, heaviest first.
    fn particles(&self, max: usize) -> Vec<WeightedEllipse>;

    /// The smoothed estimate of every frame after the first, given all frames processed so far
    /// (see [`crate::smoothing`]), oldest first, `frame` numbered as in [`Tracker::update`]'s
    /// estimates; and the expected statistics of the switching parameters over the run (the E-step
    /// of learning them). Needs a configuration that records its particles
    /// ([`smc_core::FilterSettings::history`]).
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when the tracker records nothing (the default implementation),
    /// or the smoother's error.
    fn smoothed(&mut self, settings: &SmootherSettings) -> Result<SmoothedRun> {
        let _ = settings;
        Err(Error::InvalidSetting {
            name: "filter.history",
            reason: format!("the {} tracker cannot be smoothed", self.name()),
        })
    }
}

#[cfg(test)]
mod status_tests {
    use super::*;
    use crate::{Preset, build};
    use vision_core::TrackStatus;

    #[test]
    fn status_from_gamma_follows_wu_ranges() {
        assert_eq!(status_from_gamma(0.0), TrackStatus::Locked);
        assert_eq!(status_from_gamma(0.2), TrackStatus::Locked);
        assert_eq!(status_from_gamma(0.21), TrackStatus::PartiallyOccluded);
        assert_eq!(status_from_gamma(0.79), TrackStatus::PartiallyOccluded);
        assert_eq!(status_from_gamma(0.8), TrackStatus::Lost);
    }

    #[test]
    fn track_status_prefers_alpha_then_gamma() {
        let (w, h) = (48, 40);
        let pixels: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 200) as f32).collect();
        let mut tracker = build(Preset::M1.config(20, 1)).unwrap();
        let start = Ellipse::new(24.0, 20.0, 8.0, 10.0, 0.0);
        let mut e = tracker
            .init(Frame::new(w, h, &pixels).unwrap(), start)
            .unwrap();
        assert!(e.status.is_none() && e.gamma.is_none());
        assert_eq!(e.track_status(), TrackStatus::Locked);
        e.gamma = Some(0.9);
        assert_eq!(e.track_status(), TrackStatus::Lost);
        e.status = Some(StatusEstimate {
            alpha_hat: TrackStatus::PartiallyOccluded,
            alpha_probs: [0.2, 0.5, 0.3],
            gamma_hat: 0.9,
        });
        assert_eq!(e.track_status(), TrackStatus::PartiallyOccluded);
    }
}
