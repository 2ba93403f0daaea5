//! The monitor stage's memory: whether a reported estimate is locked, the constant-velocity
//! memory of the locked estimates, and the reacquisition component of the next frame's prior
//! (see [`crate::dynamics::reacquisition`]).

use dbn_switch::StatusEstimate;

use super::ParticleTracker;
use crate::dynamics::reacquisition::Reacquisition;
use crate::frame::Frame;
use crate::space::{STATE_SLOTS, StateVector, UNBOUNDED_CENTRE};

impl ParticleTracker {
    /// Records a locked estimate in the track memory of the reacquisition jump, keeping the last
    /// `rollback + 1` memories.
    pub(super) fn remember_if_locked(
        &mut self,
        state: &StateVector,
        gamma: Option<f64>,
        status: Option<&StatusEstimate>,
    ) {
        if self.is_locked(state, gamma, status)
            && let Some(settings) = &self.config.reacquisition
        {
            self.memory
                .observe(self.config.space, settings, state, self.frame);
            self.history.push_back(self.memory.clone());
            while self.history.len() > settings.rollback + 1 {
                self.history.pop_front();
            }
        }
    }

    /// The jump component of frame `frame` (see [`crate::dynamics::reacquisition`]): once the
    /// frames since the last locked one are not locked, the reacquisition jump; while locked,
    /// with [`ReacquisitionSettings::detection_share`](crate::ReacquisitionSettings) and an
    /// appearance model, the abrupt-motion jump to the appearance's detection.
    pub(super) fn reacquisition_component(&self, frame: usize) -> Option<Reacquisition> {
        let settings = self.config.reacquisition.as_ref()?;
        let space = self.config.space;
        let gap = frame.saturating_sub(self.memory.last_locked() + 1);
        let (share, mut mean, mut velocity, uniform_area) = if gap == 0 {
            // Locked: the abrupt-motion jump, when configured and there is a detection. A priori
            // the target is anywhere in the search window; the detection only proposes where.
            // The jump moves the centre only (`TrackerDynamics::sample_jump`).
            if settings.detection_share <= 0.0 {
                return None;
            }
            self.detection?;
            let area = self.appearance.as_ref()?.window_area();
            (
                settings.detection_share,
                self.last_state,
                [0.0; STATE_SLOTS],
                Some(area),
            )
        } else {
            let anchor = self.history.front().unwrap_or(&self.memory);
            let (mean, velocity) = anchor.extrapolate(space, frame);
            let share = (settings.share_rate * gap as f64).min(settings.max_share);
            (share, mean, velocity, None)
        };
        if share <= 0.0 {
            return None;
        }
        // With an appearance model, the jump is drawn around where the target's appearance is
        // best in the frame, at rest, rather than where its last motion would have carried it.
        if let Some(d) = self.detection {
            space.set_centre(&mut mean, d);
            space.set_centre(&mut velocity, [0.0, 0.0]);
        }
        let mut sigmas = self.dynamics.settings.sigmas(space, &mean);
        for (j, s) in sigmas.iter_mut().enumerate().take(space.dim()) {
            if space.is_translation(j) {
                *s = settings.spread + settings.spread_growth * gap as f64;
            }
        }
        Some(Reacquisition {
            share,
            mean,
            velocity,
            sigmas,
            uniform_area,
        })
    }

    /// The box the centre of every state is kept in: the frame when reacquisition is on (a lost
    /// track that runs off the image, where Wu's occluded lines are the most probable of all,
    /// would never come back), else unbounded.
    pub(super) fn centre_bounds(&self, frame: &Frame<'_>) -> [f64; 4] {
        if self.config.reacquisition.is_some() {
            [0.0, 0.0, frame.width() as f64, frame.height() as f64]
        } else {
            UNBOUNDED_CENTRE
        }
    }

    /// Whether a reported estimate is locked: γ̂ below the configured level, α̂ (if modelled)
    /// locked and the remembered shape. Without reacquisition settings every estimate is.
    fn is_locked(
        &self,
        state: &StateVector,
        gamma: Option<f64>,
        status: Option<&StatusEstimate>,
    ) -> bool {
        let Some(settings) = &self.config.reacquisition else {
            return true;
        };
        self.memory
            .shape_agrees(self.config.space, state, settings.shape_tolerance)
            && gamma.is_none_or(|g| g < settings.lock_gamma)
            && status.is_none_or(|s| s.alpha_hat == dbn_switch::TrackStatus::Locked)
    }
}
