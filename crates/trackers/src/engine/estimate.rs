//! The estimate stage: the weighted mean pose (or the mean of the estimated clutter class, Wu §4)
//! and the estimates of the hidden processes, reported in the frame's convention.

use dbn_switch::{ClutterEstimate, StatusEstimate};
use smc_core::ParticleSet;
use vision_core::Ellipse;

use super::ParticleTracker;
use crate::api::Estimate;
use crate::config::PoseEstimator;
use crate::dynamics::{ClutterProcess, OcclusionModel};
use crate::particle::Particle;
use crate::space::{STATE_SLOTS, StateVector, axpy, pose_box};
use crate::{Error, Result};

/// The point estimates of one step, before they become an [`Estimate`].
pub(super) struct PosteriorSummary {
    pub(super) state: StateVector,
    pub(super) clutter: Option<ClutterEstimate>,
    pub(super) gamma: Option<f64>,
    pub(super) status: Option<StatusEstimate>,
}

impl ParticleTracker {
    pub(super) fn estimate(&mut self, set: &ParticleSet<Particle>) -> Result<PosteriorSummary> {
        let weights = set.weights();
        let states = set.states();
        let clutter = match &self.dynamics.clutter {
            ClutterProcess::Switching(hmm) => {
                self.clutter_states.clear();
                self.clutter_states.extend(states.iter().map(|p| p.clutter));
                Some(hmm.estimate(&self.clutter_states, weights)?)
            }
            ClutterProcess::Fixed(_) => None,
        };
        let (gamma, status) = match &self.dynamics.occlusion {
            OcclusionModel::None => (None, None),
            OcclusionModel::RandomWalk(_) => (
                Some(
                    states
                        .iter()
                        .zip(weights)
                        .map(|(p, w)| p.status.gamma * w)
                        .sum(),
                ),
                None,
            ),
            OcclusionModel::Status(hmm) => {
                self.status_states.clear();
                self.status_states.extend(states.iter().map(|p| p.status));
                let e = hmm.estimate(&self.status_states, weights)?;
                (Some(e.gamma_hat), Some(e))
            }
        };
        let mean = self.pose_mean(states, weights, clutter.as_ref())?;
        Ok(PosteriorSummary {
            state: mean,
            clutter,
            gamma,
            status,
        })
    }

    /// The reported pose: the weighted mean of the states, or with
    /// [`PoseEstimator::ClassConditionalMean`] the mean of the particles of class β̂ (Wu §4).
    pub(super) fn pose_mean(
        &self,
        states: &[Particle],
        weights: &[f64],
        clutter: Option<&ClutterEstimate>,
    ) -> Result<StateVector> {
        let class = match (self.config.estimator, clutter) {
            (PoseEstimator::ClassConditionalMean, Some(c)) => Some(c.beta_hat),
            _ => None,
        };
        let mut mean = [0.0; STATE_SLOTS];
        let mut mass = 0.0;
        for (p, &w) in states.iter().zip(weights) {
            if class.is_none_or(|b| p.clutter.beta == b) {
                mass += w;
                axpy(&mut mean, w, &p.now);
            }
        }
        if mass.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(Error::Smc(smc_core::Error::InvalidSetting {
                name: "weights",
                reason: "no weight on the estimated class".into(),
            }));
        }
        for v in &mut mean {
            *v /= mass;
        }
        Ok(mean)
    }

    /// The ellipse reported for a tracked one: in the annotation's convention
    /// ([`Appearance::reported`]).
    pub(super) fn reported(&self, e: &Ellipse) -> Ellipse {
        self.appearance.as_ref().map_or(*e, |a| a.reported(e))
    }

    pub(super) fn report(&self, state: StateVector, millis: f64) -> Result<Estimate> {
        let pose = self.config.space.pose(&state);
        let tracked = pose.to_ellipse().ok_or(Error::BadFrame {
            frame: self.frame,
            reason: "the estimated contour is not finite".into(),
        })?;
        let ellipse = self.reported(&tracked);
        let bbox = match &self.appearance {
            Some(_) => ellipse.bounding_box(),
            None => pose_box(&pose),
        };
        Ok(Estimate {
            frame: self.frame,
            ellipse,
            bbox,
            state,
            ess: self.config.particles as f64,
            diagnostics: None,
            clutter: None,
            gamma: None,
            status: None,
            motion_clusters: (0, 0),
            millis,
        })
    }
}
