//! The evaluation protocol of docs/MODELS.md ("Evaluation protocol", after O Table 1).
//!
//! - Centre error: distance between the centres of the estimated and the true box, in pixels.
//! - Precision at 20 px: share of labelled frames whose centre error is at most 20 px.
//! - Success curve: for each IoU threshold t = 0, 0.05, …, 1 (21 values), the share of labelled
//!   frames whose IoU is strictly above t (the OTB toolkit's convention, so a perfect tracker scores
//!   0 at t = 1); its AUC is the mean of the 21 values.
//! - Trial failure: a trial fails once the IoU stays below 0.2 for 5 consecutive labelled frames
//!   ([`vision_core::first_failure`]).
//!
//! Only labelled frames count: sequences labelled every k-th frame (`0,0,0,0` elsewhere) are
//! evaluated on their labelled frames alone, and "consecutive" means consecutive labelled frames.

use serde::{Deserialize, Serialize};
use vision_core::{BoundingBox, first_failure};

use crate::{AppError, Result};

/// Centre-error threshold of the precision score, pixels.
pub const PRECISION_THRESHOLD_PX: f64 = 20.0;
/// Number of IoU thresholds of the success curve (0, 0.05, …, 1).
pub const SUCCESS_STEPS: usize = 21;

/// The IoU thresholds of the success curve: 0, 0.05, …, 1.
pub fn success_thresholds() -> [f64; SUCCESS_STEPS] {
    std::array::from_fn(|i| i as f64 / (SUCCESS_STEPS - 1) as f64)
}

/// Share of `errors` at most `threshold` (0 when `errors` is empty).
pub fn precision_at(errors: &[f64], threshold: f64) -> f64 {
    if errors.is_empty() {
        return 0.0;
    }
    errors.iter().filter(|&&e| e <= threshold).count() as f64 / errors.len() as f64
}

/// The success curve: for each threshold of [`success_thresholds`], the share of `ious` strictly
/// above it (all zeros when `ious` is empty).
pub fn success_curve(ious: &[f64]) -> [f64; SUCCESS_STEPS] {
    let n = ious.len().max(1) as f64;
    success_thresholds().map(|t| ious.iter().filter(|&&v| v > t).count() as f64 / n)
}

/// The largest centre-error threshold of the precision plot, pixels (OTB's: 50).
pub const PRECISION_CURVE_MAX_PX: usize = 50;

/// The precision curve: for each threshold 0, 1, …, [`PRECISION_CURVE_MAX_PX`] px, the share of
/// `errors` at most that far (see [`precision_at`]).
pub fn precision_curve(errors: &[f64]) -> Vec<f64> {
    (0..=PRECISION_CURVE_MAX_PX)
        .map(|t| precision_at(errors, t as f64))
        .collect()
}

/// Area under the success curve: the mean of its values.
pub fn success_auc(ious: &[f64]) -> f64 {
    success_curve(ious).iter().sum::<f64>() / SUCCESS_STEPS as f64
}

/// Frames per second.
///
/// # Errors
/// [`AppError::Computation`] when `seconds` is not a positive finite number.
pub fn frames_per_second(frames: usize, seconds: f64) -> Result<f64> {
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(AppError::computation(
            "frames per second",
            format!("elapsed time {seconds} s is not positive"),
        ));
    }
    Ok(frames as f64 / seconds)
}

/// Share of trials that never failed (O Table 1's success rate); 0 for no trials.
pub fn success_rate(failed: &[bool]) -> f64 {
    if failed.is_empty() {
        return 0.0;
    }
    failed.iter().filter(|&&f| !f).count() as f64 / failed.len() as f64
}

/// The scores of one tracked sequence against its ground truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SequenceMetrics {
    /// Frames tracked.
    pub frames: usize,
    /// Frames with a ground-truth box (the only ones scored).
    pub labelled_frames: usize,
    /// Share of labelled frames with centre error ≤ 20 px.
    pub precision_20: f64,
    /// Area under the success curve.
    pub success_auc: f64,
    /// The success curve itself (thresholds 0, 0.05, …, 1).
    pub success_curve: Vec<f64>,
    /// The precision curve (centre-error thresholds 0, 1, …, [`PRECISION_CURVE_MAX_PX`] px), for
    /// OTB's precision plot.
    #[serde(skip)]
    pub precision_curve: Vec<f64>,
    /// Mean IoU over labelled frames.
    pub mean_iou: f64,
    /// Mean centre error over labelled frames, pixels.
    pub mean_centre_error: f64,
    /// Frame index (0-based, in the whole sequence) at which the trial failed, if it did.
    pub failed_at_frame: Option<usize>,
    /// Frames per second of the tracker (`None` when no timing was given).
    pub fps: Option<f64>,
    /// How well the tracker knows it has lost the target: the ROC AUC of its P(lost) as a
    /// detector of the labelled frames whose IoU is below [`LOST_IOU`] (see [`roc_auc`]).
    /// `None` when the tracker reports no status, or every labelled frame is on one side.
    #[serde(default)]
    pub lost_auc: Option<f64>,
    /// The (P(lost), IoU < [`LOST_IOU`]) pairs behind `lost_auc`, one per labelled frame, kept
    /// so that a mean over sequences can pool the frames.
    #[serde(skip)]
    pub lost_scores: Vec<(f64, bool)>,
}

/// A frame whose box overlaps the truth by less than this IoU counts as lost in the
/// self-evaluation ([`SequenceMetrics::lost_auc`]).
pub const LOST_IOU: f64 = 0.2;

/// The area under the ROC curve of `scored` (score, is positive): the probability that a random
/// positive scores above a random negative, ties counting one half (the Mann–Whitney
/// statistic). `None` without positives or without negatives, or with a score that is not
/// finite.
pub fn roc_auc(scored: &[(f64, bool)]) -> Option<f64> {
    if scored.iter().any(|(s, _)| !s.is_finite()) {
        return None;
    }
    let mut sorted = scored.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let positives = sorted.iter().filter(|p| p.1).count();
    let negatives = sorted.len() - positives;
    if positives == 0 || negatives == 0 {
        return None;
    }
    // Sum of the positives' mid-ranks (1-based), tied scores sharing their mean rank.
    let mut rank_sum = 0.0;
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i;
        while j < sorted.len() && sorted[j].0 == sorted[i].0 {
            j += 1;
        }
        let mid = (i + 1 + j) as f64 / 2.0;
        rank_sum += mid * sorted[i..j].iter().filter(|p| p.1).count() as f64;
        i = j;
    }
    let p = positives as f64;
    Some((rank_sum - p * (p + 1.0) / 2.0) / (p * negatives as f64))
}

/// Adds the self-evaluation to `metrics`: `p_lost[i]` is the tracker's P(lost) at frame `i` of
/// `estimates` (as passed to [`evaluate`]), `None` when the tracker reports no status.
pub fn with_self_evaluation(
    mut metrics: SequenceMetrics,
    estimates: &[BoundingBox],
    truth: &[Option<BoundingBox>],
    p_lost: &[Option<f64>],
) -> SequenceMetrics {
    metrics.lost_scores = estimates
        .iter()
        .zip(truth)
        .zip(p_lost)
        .filter_map(|((est, gt), p)| Some((p.as_ref()?, gt.as_ref()?, est)))
        .map(|(&p, gt, est)| (p, est.iou(gt) < LOST_IOU))
        .collect();
    metrics.lost_auc = roc_auc(&metrics.lost_scores);
    metrics
}

/// Scores `estimates` (one box per frame) against `truth` (one entry per frame, `None` for
/// unlabelled frames), every labelled frame included. `seconds` is the tracking time, for
/// frames/s. A tracked run, whose first frame is given rather than tracked, is scored by
/// [`score_run`] instead.
///
/// # Errors
/// [`AppError::Computation`] when the lengths differ, nothing is labelled, an estimate on a
/// labelled frame is not finite (named by frame), or `seconds` is not positive.
pub fn evaluate(
    estimates: &[BoundingBox],
    truth: &[Option<BoundingBox>],
    seconds: Option<f64>,
) -> Result<SequenceMetrics> {
    if estimates.len() != truth.len() {
        return Err(AppError::computation(
            "evaluation",
            format!(
                "{} estimated boxes for {} ground-truth frames",
                estimates.len(),
                truth.len()
            ),
        ));
    }
    let predicted: Vec<Option<BoundingBox>> = estimates.iter().copied().map(Some).collect();
    score_frames(&predicted, truth, 0, seconds)?
        .ok_or_else(|| AppError::computation("evaluation", "no labelled frame to score"))
}

/// Scores one run of a tracker: the one scorer of `track run`, `track demo` and `track eval otb`
/// (and the OTB toolkit's, and `opencv_peers.py`'s).
///
/// The tracker was started on frame `start` from a given box, so that frame is not scored, nor
/// any before it: only the labelled frames after `start` count. `predicted[i]` is the box on
/// frame `i` of the sequence (entries up to `start` are ignored; `predicted` may stop early, for
/// an interrupted run); `None`, or a box of zero width or height, is a frame the tracker gave no
/// box for, scored as a miss (IoU 0, centre error infinite: outside every precision threshold,
/// and left out of the mean centre error). `seconds` is the tracking time of the
/// `predicted.len() - start` frames from `start` on, for frames/s.
///
/// Returns `None` when no labelled frame follows `start` within `predicted`.
///
/// # Errors
/// [`AppError::Computation`] when `predicted` is longer than `truth`, a box on a scored frame is
/// not finite (named by frame), or `seconds` is not positive.
pub fn score_run(
    predicted: &[Option<BoundingBox>],
    truth: &[Option<BoundingBox>],
    start: usize,
    seconds: Option<f64>,
) -> Result<Option<SequenceMetrics>> {
    if predicted.len() > truth.len() {
        return Err(AppError::computation(
            "evaluation",
            format!(
                "{} estimated boxes for {} ground-truth frames",
                predicted.len(),
                truth.len()
            ),
        ));
    }
    score_frames(predicted, truth, start + 1, seconds)
}

/// Scores the labelled frames from `first_scored` on (see [`score_run`]); `None` without any.
fn score_frames(
    predicted: &[Option<BoundingBox>],
    truth: &[Option<BoundingBox>],
    first_scored: usize,
    seconds: Option<f64>,
) -> Result<Option<SequenceMetrics>> {
    let ctx = "evaluation";
    let mut ious = Vec::new();
    let mut errors = Vec::new();
    let mut frames_of = Vec::new();
    for (i, (est, gt)) in predicted.iter().zip(truth).enumerate().skip(first_scored) {
        let Some(gt) = gt else { continue };
        match est {
            Some(b) if !b.is_finite() => {
                return Err(AppError::computation(
                    ctx,
                    format!("the estimated box of frame {} is not finite", i + 1),
                ));
            }
            Some(b) if b.w > 0.0 && b.h > 0.0 => {
                ious.push(b.iou(gt));
                errors.push(b.centre_distance(gt));
            }
            _ => {
                ious.push(0.0);
                errors.push(f64::INFINITY);
            }
        }
        frames_of.push(i);
    }
    if ious.is_empty() {
        return Ok(None);
    }
    let n = ious.len() as f64;
    let boxed: Vec<f64> = errors.iter().copied().filter(|e| e.is_finite()).collect();
    let tracked = predicted.len() - first_scored.saturating_sub(1).min(predicted.len());
    Ok(Some(SequenceMetrics {
        frames: tracked,
        labelled_frames: ious.len(),
        precision_20: precision_at(&errors, PRECISION_THRESHOLD_PX),
        success_auc: success_auc(&ious),
        success_curve: success_curve(&ious).to_vec(),
        precision_curve: precision_curve(&errors),
        mean_iou: ious.iter().sum::<f64>() / n,
        mean_centre_error: if boxed.is_empty() {
            f64::INFINITY
        } else {
            boxed.iter().sum::<f64>() / boxed.len() as f64
        },
        failed_at_frame: first_failure(&ious).map(|k| frames_of[k]),
        fps: seconds.map(|s| frames_per_second(tracked, s)).transpose()?,
        lost_auc: None,
        lost_scores: Vec::new(),
    }))
}

/// The mean of each score over several sequences (the last row of `track eval otb`): precision,
/// AUC, mean IoU, centre error and frames/s are averaged per sequence (each sequence weighs the
/// same); frame counts are summed; `failed_at_frame` is `None`; the self-evaluation ROC AUC
/// pools the labelled frames of every sequence. `None` for an empty list.
pub fn mean_metrics(all: &[SequenceMetrics]) -> Option<SequenceMetrics> {
    if all.is_empty() {
        return None;
    }
    let n = all.len() as f64;
    let mean = |f: &dyn Fn(&SequenceMetrics) -> f64| all.iter().map(f).sum::<f64>() / n;
    let fps = all
        .iter()
        .map(|m| m.fps)
        .collect::<Option<Vec<f64>>>()
        .map(|v| v.iter().sum::<f64>() / n);
    let pooled: Vec<(f64, bool)> = all.iter().flat_map(|m| m.lost_scores.clone()).collect();
    Some(SequenceMetrics {
        frames: all.iter().map(|m| m.frames).sum(),
        labelled_frames: all.iter().map(|m| m.labelled_frames).sum(),
        precision_20: mean(&|m| m.precision_20),
        success_auc: mean(&|m| m.success_auc),
        success_curve: (0..SUCCESS_STEPS)
            .map(|i| mean(&|m| m.success_curve.get(i).copied().unwrap_or(0.0)))
            .collect(),
        precision_curve: (0..=PRECISION_CURVE_MAX_PX)
            .map(|i| mean(&|m| m.precision_curve.get(i).copied().unwrap_or(0.0)))
            .collect(),
        mean_iou: mean(&|m| m.mean_iou),
        mean_centre_error: mean(&|m| m.mean_centre_error),
        failed_at_frame: None,
        fps,
        // Pooled over every labelled frame of every sequence, not averaged per sequence.
        lost_auc: roc_auc(&pooled),
        lost_scores: pooled,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn roc_auc_is_the_mann_whitney_statistic() {
        // Perfect separation, perfect inversion, and ties at one half.
        let sep = [(0.9, true), (0.8, true), (0.1, false), (0.2, false)];
        assert_relative_eq!(roc_auc(&sep).unwrap(), 1.0);
        let inv = sep.map(|(s, l)| (s, !l));
        assert_relative_eq!(roc_auc(&inv).unwrap(), 0.0);
        let ties = [(0.5, true), (0.5, false), (0.5, true), (0.5, false)];
        assert_relative_eq!(roc_auc(&ties).unwrap(), 0.5);
        // One of the four positive–negative pairs misordered.
        let mixed = [(0.9, true), (0.3, true), (0.4, false), (0.1, false)];
        assert_relative_eq!(roc_auc(&mixed).unwrap(), 0.75);
        assert!(roc_auc(&[(0.3, true)]).is_none());
        assert!(roc_auc(&[(f64::NAN, true), (0.1, false)]).is_none());
    }

    #[test]
    fn thresholds_are_exact_twentieths() {
        let t = success_thresholds();
        assert_eq!(t[0], 0.0);
        assert_eq!(t[20], 1.0);
        assert_relative_eq!(t[1], 0.05, epsilon = 1e-15);
        assert_relative_eq!(t[14], 0.7, epsilon = 1e-15);
    }

    #[test]
    fn precision_by_hand() {
        // 20 is included (≤), 20.5 is not.
        assert_eq!(precision_at(&[0.0, 20.0, 20.5, 100.0], 20.0), 0.5);
        assert_eq!(precision_at(&[], 20.0), 0.0);
    }

    #[test]
    fn success_curve_and_auc_by_hand() {
        // IoU 1: above every threshold but 1 → 20 of 21. IoU 0.5: above 0, 0.05, …, 0.45 → 10.
        // IoU 0: above none → 0. AUC = (20 + 10 + 0) / (3 · 21) = 30/63.
        let ious = [1.0, 0.5, 0.0];
        let curve = success_curve(&ious);
        assert_relative_eq!(curve[0], 2.0 / 3.0, epsilon = 1e-15);
        assert_relative_eq!(curve[10], 1.0 / 3.0, epsilon = 1e-15);
        assert_eq!(curve[20], 0.0);
        assert_relative_eq!(success_auc(&ious), 30.0 / 63.0, epsilon = 1e-15);
        // A perfect tracker scores 20/21 (OTB's strict > at t = 1).
        assert_relative_eq!(success_auc(&[1.0; 4]), 20.0 / 21.0, epsilon = 1e-15);
        assert_eq!(success_auc(&[]), 0.0);
    }

    #[test]
    fn failure_needs_five_consecutive_low_frames() {
        let low = 0.1;
        let ok = 0.5;
        assert_eq!(
            first_failure(&[ok, low, low, low, low, ok, low, low, low, low]),
            None
        );
        assert_eq!(first_failure(&[ok, low, low, low, low, low, ok]), Some(5));
        // 0.2 itself is not below the threshold.
        assert_eq!(first_failure(&[0.2; 10]), None);
        assert_eq!(first_failure(&[0.199_999; 5]), Some(4));
        assert_eq!(success_rate(&[false, true, false, false]), 0.75);
        assert_eq!(success_rate(&[]), 0.0);
    }

    #[test]
    fn evaluate_skips_unlabelled_frames() {
        let gt_box = BoundingBox::new(0.0, 0.0, 10.0, 10.0);
        let shifted = BoundingBox::new(5.0, 0.0, 10.0, 10.0); // IoU 1/3, centre error 5
        let far = BoundingBox::new(100.0, 100.0, 10.0, 10.0); // IoU 0, centre error 100√2
        // Unlabelled frames carry garbage estimates that must not count.
        let estimates = [gt_box, far, shifted, far, far];
        let truth = [Some(gt_box), None, Some(gt_box), Some(gt_box), None];
        let m = evaluate(&estimates, &truth, Some(2.5)).unwrap();
        assert_eq!(m.frames, 5);
        assert_eq!(m.labelled_frames, 3);
        assert_relative_eq!(m.precision_20, 2.0 / 3.0, epsilon = 1e-15);
        assert_relative_eq!(m.mean_iou, (1.0 + 1.0 / 3.0) / 3.0, epsilon = 1e-15);
        assert_relative_eq!(
            m.mean_centre_error,
            (5.0 + 100.0 * 2f64.sqrt()) / 3.0,
            epsilon = 1e-12
        );
        // IoU 1 → 20 thresholds, IoU 1/3 → above 0 … 0.30 → 7, IoU 0 → 0. AUC = 27/63.
        assert_relative_eq!(m.success_auc, 27.0 / 63.0, epsilon = 1e-15);
        assert_eq!(m.fps, Some(2.0));
        assert_eq!(m.failed_at_frame, None);
    }

    #[test]
    fn evaluate_reports_failure_frame_and_bad_inputs() {
        let gt = BoundingBox::new(0.0, 0.0, 10.0, 10.0);
        let far = BoundingBox::new(50.0, 50.0, 10.0, 10.0);
        // Labelled every other frame (0, 2, 4, …); the 5th labelled miss is at frame index 8.
        let estimates = vec![far; 12];
        let truth: Vec<_> = (0..12).map(|i| (i % 2 == 0).then_some(gt)).collect();
        let m = evaluate(&estimates, &truth, None).unwrap();
        assert_eq!(m.failed_at_frame, Some(8));
        assert_eq!(m.fps, None);
        assert!(evaluate(&estimates[..3], &truth, None).is_err());
        assert!(
            evaluate(&[far], &[None], None)
                .unwrap_err()
                .to_string()
                .contains("no labelled")
        );
        let nan = BoundingBox::new(f64::NAN, 0.0, 1.0, 1.0);
        let msg = evaluate(&[gt, nan], &[Some(gt), Some(gt)], None)
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("frame 2") && msg.contains("not finite"),
            "{msg}"
        );
        assert!(evaluate(&[gt], &[Some(gt)], Some(0.0)).is_err());
        assert!(frames_per_second(3, f64::NAN).is_err());
    }

    #[test]
    fn score_run_skips_the_start_frame_and_counts_missing_boxes_as_misses() {
        let gt = BoundingBox::new(0.0, 0.0, 10.0, 10.0);
        let far = BoundingBox::new(100.0, 100.0, 10.0, 10.0);
        let truth = [None, Some(gt), Some(gt), None, Some(gt), Some(gt)];
        // Started on frame 1 far off (never scored); frames 2 and 4 right, frame 5 no box.
        let pred = [None, Some(far), Some(gt), Some(far), Some(gt), None];
        let m = score_run(&pred, &truth, 1, Some(2.5)).unwrap().unwrap();
        assert_eq!(m.labelled_frames, 3);
        assert_eq!(m.frames, 5, "frames 1–5 tracked");
        assert_eq!(m.fps, Some(2.0));
        assert_relative_eq!(m.precision_20, 2.0 / 3.0, epsilon = 1e-15);
        assert_relative_eq!(m.success_auc, 40.0 / 63.0, epsilon = 1e-15);
        assert_relative_eq!(m.mean_iou, 2.0 / 3.0, epsilon = 1e-15);
        // The miss has no centre error: the mean is over frames with a box.
        assert_eq!(m.mean_centre_error, 0.0);
        assert_eq!(m.precision_curve.len(), PRECISION_CURVE_MAX_PX + 1);
        assert_relative_eq!(m.precision_curve[0], 2.0 / 3.0, epsilon = 1e-15);
        // A zero-size box is a miss too; an interrupted run is scored on what it tracked.
        let zero = BoundingBox::new(0.0, 0.0, 0.0, 10.0);
        let m = score_run(&[None, Some(gt), Some(zero)], &truth, 1, None)
            .unwrap()
            .unwrap();
        assert_eq!((m.labelled_frames, m.success_auc), (1, 0.0));
        // Nothing labelled after the start: no score, not an error.
        assert_eq!(score_run(&pred[..2], &truth, 1, None).unwrap(), None);
        assert_eq!(score_run(&pred, &truth, 5, None).unwrap(), None);
        // Longer than the truth, or a non-finite box on a scored frame: an error.
        assert!(score_run(&[None; 7], &truth, 1, None).is_err());
        let nan = BoundingBox::new(f64::NAN, 0.0, 1.0, 1.0);
        let msg = score_run(&[None, Some(gt), Some(nan)], &truth, 1, None)
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("frame 3") && msg.contains("not finite"),
            "{msg}"
        );
        // …but one on the start frame is not looked at.
        assert!(score_run(&[None, Some(nan), Some(gt)], &truth, 1, None).is_ok());
    }

    #[test]
    fn mean_over_sequences() {
        let gt = BoundingBox::new(0.0, 0.0, 10.0, 10.0);
        let a = evaluate(&[gt], &[Some(gt)], Some(1.0)).unwrap();
        let b = evaluate(
            &[BoundingBox::new(40.0, 0.0, 10.0, 10.0)],
            &[Some(gt)],
            Some(0.5),
        )
        .unwrap();
        let m = mean_metrics(&[a, b]).unwrap();
        assert_eq!(m.precision_20, 0.5);
        assert_relative_eq!(m.success_auc, 10.0 / 21.0, epsilon = 1e-15);
        assert_eq!(m.fps, Some(1.5));
        assert_eq!(m.frames, 2);
        assert!(mean_metrics(&[]).is_none());
    }
}
