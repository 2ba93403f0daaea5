//! What a particle smoother needs from the forward pass: the weighted particle set of every
//! filtering step and the ancestor index of every particle.
//!
//! A [`History`] is a sequence of [`Frame`]s, frame t holding the filtering approximation
//! p̂(x_t | z_{0:t}) = Σᵢ W_t^i δ(x_t^i) (the particle set after the weight update of step t) and
//! the ancestors a_t^i: particle i of frame t was propagated from particle a_t^i of frame t − 1.
//! The backward smoothers of [`crate::smooth`] use the states and weights; the ancestors give the
//! genealogy ([`History::ancestral_line`]), the degenerate "filter-smoother" of Kitagawa (1996).
//!
//! The filter records a history only when [`crate::FilterSettings::history`] asks it to; left at
//! `None` (the default) the filter neither clones nor stores anything. A history with a bounded
//! number of frames ([`HistorySettings::max_frames`]) keeps the last L + 1 frames, which is what
//! the fixed-lag smoother ([`crate::smooth::fixed_lag_weights`]) reads.

use std::collections::VecDeque;

use crate::error::{Error, Result};
use crate::particles::{ParticleSet, check_len};

/// Settings of a [`History`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HistorySettings {
    /// Keep at most this many frames, dropping the oldest (a sliding window for fixed-lag
    /// smoothing). `None` (the default) keeps every frame.
    pub max_frames: Option<usize>,
}

impl HistorySettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when `max_frames` is `Some(0)`.
    pub fn validate(&self) -> Result<()> {
        if self.max_frames == Some(0) {
            return Err(Error::InvalidSetting {
                name: "max_frames",
                reason: "must be at least 1".into(),
            });
        }
        Ok(())
    }
}

/// One recorded filtering step.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame<S> {
    /// The caller's step index (as passed to the filter).
    pub step: u64,
    /// The weighted particles after the weight update: the filtering approximation at this step.
    pub set: ParticleSet<S>,
    /// `ancestors[i]` is the index, in the previous frame, of the particle that particle i was
    /// propagated from; `None` when unknown (the first frame of a run, or a step whose
    /// resampling the filter did not see).
    pub ancestors: Option<Vec<usize>>,
}

/// The recorded forward pass of a particle filter: one [`Frame`] per step, oldest first.
///
/// # Examples
/// ```
/// use smc_core::{History, HistorySettings, ParticleSet};
/// let mut history = History::new(HistorySettings::default())?;
/// history.push(0, ParticleSet::from_states(vec![0.0, 1.0])?, None)?;
/// history.push(1, ParticleSet::from_states(vec![0.5, 1.5, 2.5])?, Some(vec![0, 1, 1]))?;
/// assert_eq!(history.len(), 2);
/// assert_eq!(history.ancestral_line(2)?, vec![1, 2]);
/// # Ok::<(), smc_core::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct History<S> {
    settings: HistorySettings,
    frames: VecDeque<Frame<S>>,
}

impl<S> History<S> {
    /// An empty history with validated settings.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] from [`HistorySettings::validate`].
    pub fn new(settings: HistorySettings) -> Result<Self> {
        settings.validate()?;
        Ok(Self {
            settings,
            frames: VecDeque::new(),
        })
    }

    /// The settings.
    #[must_use]
    pub fn settings(&self) -> &HistorySettings {
        &self.settings
    }

    /// Number of frames held.
    #[must_use]
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether no frame is held.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Frame `t` (0 is the oldest frame held); `None` out of range.
    #[must_use]
    pub fn frame(&self, t: usize) -> Option<&Frame<S>> {
        self.frames.get(t)
    }

    /// The frames, oldest first.
    pub fn frames(&self) -> impl ExactSizeIterator<Item = &Frame<S>> {
        self.frames.iter()
    }

    /// Removes every frame.
    pub fn clear(&mut self) {
        self.frames.clear();
    }

    /// Appends a frame, dropping the oldest one when the history is full.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] when `ancestors` does not have one entry per particle;
    /// [`Error::InvalidSetting`] (`ancestors`) when an ancestor index is not below the size of
    /// the previous frame. The history is unchanged on error.
    pub fn push(
        &mut self,
        step: u64,
        set: ParticleSet<S>,
        ancestors: Option<Vec<usize>>,
    ) -> Result<()> {
        if let Some(a) = &ancestors {
            check_len("ancestors", set.len(), a.len())?;
            if let Some(previous) = self.frames.back() {
                let n = previous.set.len();
                if let Some(&bad) = a.iter().find(|&&i| i >= n) {
                    return Err(Error::InvalidSetting {
                        name: "ancestors",
                        reason: format!("index {bad} out of range for {n} particles"),
                    });
                }
            }
        }
        if let Some(max) = self.settings.max_frames {
            while self.frames.len() >= max {
                self.frames.pop_front();
            }
        }
        self.frames.push_back(Frame {
            step,
            set,
            ancestors,
        });
        Ok(())
    }

    /// The genealogy of particle `index` of the last frame: the index of its ancestor in every
    /// frame, oldest first (the last entry is `index`). Weighting these lines by the last frame's
    /// weights is the filter-smoother of Kitagawa (1996), whose paths collapse onto a few
    /// ancestors after repeated resampling; the backward smoothers of [`crate::smooth`] do not.
    ///
    /// # Errors
    /// [`Error::EmptyHistory`]; [`Error::InvalidSetting`] when `index` is out of range;
    /// [`Error::MissingAncestors`] when a frame after the first has no recorded ancestors.
    pub fn ancestral_line(&self, index: usize) -> Result<Vec<usize>> {
        let last = self.frames.back().ok_or(Error::EmptyHistory)?;
        if index >= last.set.len() {
            return Err(Error::InvalidSetting {
                name: "index",
                reason: format!("{index} out of range for {} particles", last.set.len()),
            });
        }
        let mut line = vec![0; self.frames.len()];
        let mut i = index;
        for (t, frame) in self.frames.iter().enumerate().rev() {
            line[t] = i;
            if t > 0 {
                let a = frame
                    .ancestors
                    .as_ref()
                    .ok_or(Error::MissingAncestors { frame: t })?;
                // Indices were checked against the previous frame when the frame was pushed.
                i = a[i];
            }
        }
        Ok(line)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(n: usize) -> ParticleSet<f64> {
        ParticleSet::from_states((0..n).map(|i| i as f64).collect()).unwrap()
    }

    #[test]
    fn bad_frames_are_rejected_and_leave_the_history_alone() {
        let mut h = History::new(HistorySettings::default()).unwrap();
        h.push(0, set(2), None).unwrap();
        let before = h.clone();
        assert!(matches!(
            h.push(1, set(3), Some(vec![0, 1])),
            Err(Error::LengthMismatch { .. })
        ));
        assert!(matches!(
            h.push(1, set(3), Some(vec![0, 1, 2])),
            Err(Error::InvalidSetting { .. })
        ));
        assert_eq!(h, before);
        assert!(
            History::<f64>::new(HistorySettings {
                max_frames: Some(0)
            })
            .is_err()
        );
    }

    #[test]
    fn a_bounded_history_keeps_the_last_frames() {
        let mut h = History::new(HistorySettings {
            max_frames: Some(2),
        })
        .unwrap();
        for k in 0..5 {
            h.push(k, set(3), Some(vec![2, 0, 1])).unwrap();
        }
        assert_eq!(h.len(), 2);
        assert_eq!(h.frame(0).map(|f| f.step), Some(3));
        assert_eq!(h.ancestral_line(0).unwrap(), vec![2, 0]);
    }

    #[test]
    fn genealogy_needs_frames_and_ancestors() {
        let mut h = History::<f64>::new(HistorySettings::default()).unwrap();
        assert_eq!(h.ancestral_line(0), Err(Error::EmptyHistory));
        h.push(0, set(2), None).unwrap();
        h.push(1, set(2), None).unwrap();
        assert_eq!(
            h.ancestral_line(0),
            Err(Error::MissingAncestors { frame: 1 })
        );
        assert!(h.ancestral_line(5).is_err());
    }
}
