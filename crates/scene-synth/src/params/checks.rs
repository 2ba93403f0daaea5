//! The validation of each section of the scenario parameters, in the order
//! `ScenarioParams::validate` runs them; each error names the first offending field by its dotted
//! path.

use super::{
    BackgroundParams, CameraParams, DistractorParams, HeadTurnParams, MotionParams, OccluderParams,
    ScaleChangeParams, StatusThresholds, TargetParams,
};
use crate::error::{Error, Result};

/// The error naming field `name` and what is wrong with it.
pub(super) fn bad(name: &'static str, reason: impl Into<String>) -> Error {
    Error::InvalidParameter {
        name,
        reason: reason.into(),
    }
}

/// Checks that every value of field `name` is finite.
pub(super) fn finite(name: &'static str, vals: &[f64]) -> Result<()> {
    if vals.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(bad(name, "not finite"))
    }
}

/// Checks that the range `r` is finite, ordered, and within lo ..= hi.
fn range(name: &'static str, r: [f64; 2], lo: f64, hi: f64) -> Result<()> {
    finite(name, &r)?;
    if r[0] >= lo && r[1] <= hi && r[0] <= r[1] {
        Ok(())
    } else {
        Err(bad(
            name,
            format!("expected {lo} ≤ min ≤ max ≤ {hi}, got {r:?}"),
        ))
    }
}

impl BackgroundParams {
    pub(super) fn check(&self) -> Result<()> {
        let bg = self;
        finite(
            "background",
            &[bg.grey, bg.texture_amplitude, bg.texture_scale, bg.extent],
        )?;
        if bg.texture_scale < 2.0 || !(1.0..=4.0).contains(&bg.extent) {
            return Err(bad(
                "background",
                "texture_scale ≥ 2 px and extent in [1, 4]",
            ));
        }
        let c = &bg.clutter;
        finite("background.clutter.densities", &c.densities)?;
        if c.densities.iter().any(|&d| !(0.0..=0.35).contains(&d)) {
            return Err(bad(
                "background.clutter.densities",
                "each density in [0, 0.35] edges/px",
            ));
        }
        if c.layout.is_empty() || c.layout.len() > 8 {
            return Err(bad("background.clutter.layout", "1 to 8 regions"));
        }
        if !(10.0..=200.0).contains(&c.line_length) || c.calibration_lines < 100 {
            return Err(bad(
                "background.clutter",
                "line_length in [10, 200], calibration_lines ≥ 100",
            ));
        }
        range("background.clutter.contrast", c.contrast, 0.0, 255.0)?;
        finite("background.clutter.size_scale", &c.size_scale)?;
        if c.size_scale.iter().any(|&s| !(0.3..=4.0).contains(&s)) {
            return Err(bad("background.clutter.size_scale", "each in [0.3, 4]"));
        }
        Ok(())
    }
}

impl TargetParams {
    /// `frame_side` is the frame's smaller side, which bounds the semi-axes.
    pub(super) fn check(&self, frame_side: f64) -> Result<()> {
        let t = self;
        finite(
            "target",
            &[
                t.grey,
                t.texture_amplitude,
                t.texture_scale,
                t.contrast_min,
                t.rim_width,
            ],
        )?;
        range(
            "target.semi_axes",
            [
                t.semi_axes[0].min(t.semi_axes[1]),
                t.semi_axes[0].max(t.semi_axes[1]),
            ],
            4.0,
            0.3 * frame_side,
        )?;
        if !(0.0..=1.0).contains(&t.contrast_min) || t.texture_scale <= 0.05 || t.rim_width < 0.5 {
            return Err(bad(
                "target",
                "contrast_min in [0, 1], texture_scale > 0.05, rim_width ≥ 0.5",
            ));
        }
        finite("target.stretch_half_width", &[t.stretch_half_width])?;
        if !(0.0..=1.5).contains(&t.stretch_half_width) {
            return Err(bad("target.stretch_half_width", "in [0, 1.5] rad"));
        }
        Ok(())
    }
}

impl MotionParams {
    pub(super) fn check(&self) -> Result<()> {
        let m = self;
        finite("motion", &[m.speed, m.margin])?;
        if !(0.0..=50.0).contains(&m.speed) || m.margin < 0.0 {
            return Err(bad("motion", "speed in [0, 50] px/frame, margin ≥ 0"));
        }
        if let Some(j) = &m.jumps {
            range("motion.jumps.speed", j.speed, 0.0, 60.0)?;
            if j.interval[0] == 0
                || j.interval[0] > j.interval[1]
                || j.duration[0] == 0
                || j.duration[0] > j.duration[1]
            {
                return Err(bad(
                    "motion.jumps",
                    "interval and duration ranges must be ≥ 1 and ordered",
                ));
            }
        }
        Ok(())
    }
}

impl OccluderParams {
    pub(super) fn check(&self) -> Result<()> {
        let o = self;
        range(
            "occluder.centre",
            [o.centre[0].min(o.centre[1]), o.centre[0].max(o.centre[1])],
            0.0,
            1.0,
        )?;
        finite(
            "occluder",
            &[o.size[0], o.size[1], o.grey, o.texture_amplitude],
        )?;
        if o.size[0] < 1.0 || o.size[1] < 1.0 {
            return Err(bad("occluder.size", "at least 1 px"));
        }
        Ok(())
    }
}

impl DistractorParams {
    pub(super) fn check(&self) -> Result<()> {
        let d = self;
        range("distractor.gap", d.gap, 0.0, 500.0)?;
        finite("distractor", &[d.angular_speed, d.gap_period, d.grey])?;
        if d.gap_period <= 0.0 {
            return Err(bad("distractor.gap_period", "positive"));
        }
        Ok(())
    }
}

impl CameraParams {
    pub(super) fn check(&self) -> Result<()> {
        let cam = self;
        finite(
            "camera",
            &[
                cam.pan_amplitude[0],
                cam.pan_amplitude[1],
                cam.pan_period,
                cam.zoom_amplitude,
                cam.zoom_period,
            ],
        )?;
        if cam.pan_period <= 0.0
            || cam.zoom_period <= 0.0
            || !(0.0..0.5).contains(&cam.zoom_amplitude)
        {
            return Err(bad(
                "camera",
                "positive periods, zoom_amplitude in [0, 0.5)",
            ));
        }
        Ok(())
    }
}

impl ScaleChangeParams {
    pub(super) fn check(&self) -> Result<()> {
        range("scale_changes.magnitude", self.magnitude, 0.0, 0.9)?;
        range("scale_changes.bounds", self.bounds, 0.2, 3.0)?;
        if self.duration == 0 {
            return Err(bad("scale_changes.duration", "at least one frame"));
        }
        Ok(())
    }
}

impl HeadTurnParams {
    pub(super) fn check(&self) -> Result<()> {
        finite("head_turn.shift", &[self.shift])?;
        if !(0.0..=1.0).contains(&self.shift.abs()) || self.duration == 0 {
            return Err(bad("head_turn", "|shift| ≤ 1, duration ≥ 1"));
        }
        Ok(())
    }
}

impl StatusThresholds {
    pub(super) fn check(&self) -> Result<()> {
        let st = self;
        finite("status", &[st.locked_min_visible, st.lost_max_visible])?;
        if !(0.0 <= st.lost_max_visible
            && st.lost_max_visible < st.locked_min_visible
            && st.locked_min_visible <= 1.0)
        {
            return Err(bad(
                "status",
                "0 ≤ lost_max_visible < locked_min_visible ≤ 1",
            ));
        }
        Ok(())
    }
}
