//! Per-frame ground truth: everything in `groundtruth.csv`.

use serde::{Deserialize, Serialize};

use vision_core::{BoundingBox, Ellipse, TrackStatus};

use crate::geometry::{OdobezState, WuAffine};
use crate::params::StatusThresholds;

impl StatusThresholds {
    /// The status label of a visible fraction v (Wu's α, W §6.3). With γ ≈ 1 − v and Wu's γ
    /// ranges (locked γ ∈ [0, 0.2], lost γ ∈ [0.8, 1]): locked if v ≥ 0.8, lost if v ≤ 0.2,
    /// partially occluded in between (the thresholds of `self`).
    pub fn status(&self, v: f64) -> TrackStatus {
        if v >= self.locked_min_visible {
            TrackStatus::Locked
        } else if v <= self.lost_max_visible {
            TrackStatus::Lost
        } else {
            TrackStatus::PartiallyOccluded
        }
    }
}

/// Ground truth of one frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameTruth {
    /// 0-based frame index (the image file is `img/{frame+1:04}.png`).
    pub frame: usize,
    /// The target's outline.
    pub ellipse: Ellipse,
    /// Odobez's state (O Eq. 11–12).
    pub odobez: OdobezState,
    /// Wu's affine shape space.
    pub affine: WuAffine,
    /// Axis-aligned bounding box of the ellipse.
    pub bbox: BoundingBox,
    /// Clutter class (Wu's β, 1–3) of the background region under the target's centre.
    pub clutter_class: u8,
    /// Edge density of that region in this frame (edges/px): the density measured at
    /// calibration divided by the camera zoom.
    pub edge_density: f64,
    /// Fraction of the target's area that is visible: inside the frame and not behind the
    /// occluder (anti-aliased coverage).
    pub visible_fraction: f64,
    /// Status label from the visible fraction.
    pub status: TrackStatus,
    /// The distractor's outline, if the scenario has one.
    pub distractor: Option<Ellipse>,
}

impl FrameTruth {
    /// Header of `groundtruth.csv`.
    pub const CSV_HEADER: &'static str = "frame,cx,cy,a,b,angle,tx,ty,s,e,a11,a12,a21,a22,t1,t2,\
box_x,box_y,box_w,box_h,clutter_class,edge_density,visible_fraction,status";

    /// One CSV row (1-based frame number, fixed precision so files are byte-stable).
    pub fn csv_row(&self) -> String {
        // Adding 0.0 turns −0.0 into 0.0, so that no "-0.0000" appears in the files.
        let z = |x: f64| x + 0.0;
        let e = &self.ellipse;
        let o = &self.odobez;
        let w = &self.affine;
        let b = &self.bbox;
        format!(
            "{},{:.4},{:.4},{:.4},{:.4},{:.6},{:.4},{:.4},{:.4},{:.6},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},\
{:.3},{:.3},{:.3},{:.3},{},{:.5},{:.4},{}",
            self.frame + 1,
            z(e.cx),
            z(e.cy),
            z(e.a),
            z(e.b),
            z(e.angle),
            z(o.tx),
            z(o.ty),
            z(o.s),
            z(o.e),
            z(w.a11),
            z(w.a12),
            z(w.a21),
            z(w.a22),
            z(w.t1),
            z(w.t2),
            z(b.x),
            z(b.y),
            z(b.w),
            z(b.h),
            self.clutter_class,
            z(self.edge_density),
            z(self.visible_fraction),
            self.status.name()
        )
    }

    /// One `groundtruth_rect.txt` line: x,y,w,h.
    pub fn rect_line(&self) -> String {
        let b = &self.bbox;
        format!("{:.3},{:.3},{:.3},{:.3}", b.x + 0.0, b.y + 0.0, b.w, b.h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_thresholds_follow_wu_gamma_ranges() {
        let t = StatusThresholds::default();
        assert_eq!(t.status(1.0), TrackStatus::Locked);
        assert_eq!(t.status(0.8), TrackStatus::Locked);
        assert_eq!(t.status(0.79), TrackStatus::PartiallyOccluded);
        assert_eq!(t.status(0.21), TrackStatus::PartiallyOccluded);
        assert_eq!(t.status(0.2), TrackStatus::Lost);
        assert_eq!(t.status(0.0), TrackStatus::Lost);
    }
}
