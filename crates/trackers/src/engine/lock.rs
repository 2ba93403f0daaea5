//! The monitor stage's memory: whether a reported estimate is locked, the constant-velocity
//! memory of the locked estimates, and the reacquisition component of the next frame's prior
//! (see [`crate::dynamics::reacquisition`]).

use dbn_switch::StatusEstimate;

use super::ParticleTracker;
use crate::dynamics::reacquisition::Reacquisition;
use crate::frame::Frame;
use crate::space::{StateVector, UNBOUNDED_CENTRE};

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

    /// The reacquisition jump of frame `frame`: present when the configuration asks for it and
    /// the frames since the last locked one are not locked (see [`crate::dynamics::reacquisition`]).
    pub(super) fn reacquisition_component(&self, frame: usize) -> Option<Reacquisition> {
        let settings = self.config.reacquisition.as_ref()?;
        let gap = frame.saturating_sub(self.memory.last_locked() + 1);
        let share = (settings.share_rate * gap as f64).min(settings.max_share);
        if gap == 0 || share <= 0.0 {
            return None;
        }
        let space = self.config.space;
        let anchor = self.history.front().unwrap_or(&self.memory);
        let (mut mean, mut velocity) = anchor.extrapolate(space, frame);
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
