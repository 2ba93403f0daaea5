//! The track status α of Wu et al. (W §6.3) and the failure rule of the evaluations.

use serde::{Deserialize, Serialize};

/// The tracker status α (W §6.3): locked on the target, partially occluded, or lost. The same
/// labels serve as the ground truth of synthetic scenes and as the tracker's self-evaluation.
///
/// Written to files in lower case as `locked`, `partial`, `lost`; `partially_occluded` is
/// accepted when reading.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TrackStatus {
    /// The target is tracked and mostly visible; `γ` is small (Wu: `α = 1`).
    Locked,
    /// The target is partially occluded; `γ` spreads over a wide range (Wu: `α = 2`).
    #[serde(rename = "partial", alias = "partially_occluded")]
    PartiallyOccluded,
    /// The target is lost or (almost) fully occluded; `γ` is large (Wu: `α = 3`).
    Lost,
}

impl TrackStatus {
    /// All statuses in index order.
    pub const ALL: [TrackStatus; 3] = [Self::Locked, Self::PartiallyOccluded, Self::Lost];

    /// 0-based index: row and column of Wu's `T_α`, and the order of probabilities in files.
    #[must_use]
    pub fn index(self) -> usize {
        match self {
            Self::Locked => 0,
            Self::PartiallyOccluded => 1,
            Self::Lost => 2,
        }
    }

    /// The status with a 0-based index, if any.
    #[must_use]
    pub fn from_index(index: usize) -> Option<Self> {
        Self::ALL.get(index).copied()
    }

    /// The lower-case name written to files: `locked`, `partial`, `lost`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Locked => "locked",
            Self::PartiallyOccluded => "partial",
            Self::Lost => "lost",
        }
    }
}

/// The IoU below which a frame counts towards a failure (docs/MODELS.md).
pub const FAILURE_IOU: f64 = 0.2;

/// How many consecutive frames below [`FAILURE_IOU`] make a failure (docs/MODELS.md).
pub const FAILURE_RUN: usize = 5;

/// The failure rule of docs/MODELS.md ("Evaluation protocol"; "What counts as a failed trial"):
/// a track fails at the [`FAILURE_RUN`]-th consecutive IoU below [`FAILURE_IOU`], the IoU of the
/// estimated and the true box ([`BoundingBox::iou`](crate::BoundingBox::iou)). Returns that position in `ious` (the per-labelled-frame
/// IoUs in order), or `None` when the track never fails.
///
/// # Examples
/// ```
/// use vision_core::first_failure;
///
/// assert_eq!(first_failure(&[0.9, 0.1, 0.1, 0.1, 0.1, 0.1, 0.8]), Some(5));
/// assert_eq!(first_failure(&[0.1, 0.1, 0.1, 0.1, 0.9, 0.1]), None);
/// ```
pub fn first_failure(ious: &[f64]) -> Option<usize> {
    let mut run = 0;
    for (i, &v) in ious.iter().enumerate() {
        run = if v < FAILURE_IOU { run + 1 } else { 0 };
        if run == FAILURE_RUN {
            return Some(i);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_failure_rule_needs_five_consecutive_frames_below_0_2() {
        assert_eq!(first_failure(&[]), None);
        assert_eq!(first_failure(&[0.0; 4]), None);
        assert_eq!(first_failure(&[0.0; 5]), Some(4));
        assert_eq!(first_failure(&[0.0; 50]), Some(4));
        // 0.2 itself is not below the threshold, and it resets the run.
        assert_eq!(first_failure(&[0.1, 0.1, 0.2, 0.1, 0.1, 0.1, 0.1]), None);
        assert_eq!(
            first_failure(&[0.1, 0.1, 0.2, 0.1, 0.1, 0.1, 0.1, 0.19]),
            Some(7)
        );
        // A NaN IoU is not below the threshold (it breaks the run, as any comparison fails).
        assert_eq!(
            first_failure(&[0.1, 0.1, f64::NAN, 0.1, 0.1, 0.1, 0.1]),
            None
        );
        // The first failure is reported, not a later one.
        let mut v = vec![0.9; 20];
        v[3..9].fill(0.0);
        v[12..20].fill(0.0);
        assert_eq!(first_failure(&v), Some(7));
    }

    #[test]
    fn status_names_indices_and_serde() {
        for (i, s) in TrackStatus::ALL.iter().enumerate() {
            assert_eq!(s.index(), i);
            assert_eq!(TrackStatus::from_index(i), Some(*s));
            let json = serde_json::to_string(s).unwrap();
            assert_eq!(json, format!("\"{}\"", s.name()));
            assert_eq!(serde_json::from_str::<TrackStatus>(&json).unwrap(), *s);
        }
        assert_eq!(TrackStatus::from_index(3), None);
        assert_eq!(
            serde_json::from_str::<TrackStatus>("\"partially_occluded\"").unwrap(),
            TrackStatus::PartiallyOccluded
        );
    }
}
