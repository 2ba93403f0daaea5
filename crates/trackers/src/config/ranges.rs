//! The range of every numeric setting of a [`TrackerConfig`], checked first by
//! [`TrackerConfig::validate`] so that a value that cannot work (`dynamics.sigma_translation =
//! 1e308` made the contour non-finite at frame 1) is refused before any frame, by the dotted path
//! of the configuration file and the range.
//!
//! The check reads the configuration as its JSON form, so the paths are those of the file
//! (`dynamics.sigma_translation`, `clutter.switching.lambda_mean`, `motion.estimator.robust.Tukey.c`)
//! and an element of a list is named with its index (`clutter.switching.transition[0][2]`). The
//! JSON form leaves out the settings the tracker does not read while they hold their defaults
//! (which are in range); an unread setting at another value is in it, so it is checked here
//! before [`TrackerConfig::validate`] refuses it as unread. The
//! owning crates' own checks still run after it, for what a range cannot say (rows of a
//! transition matrix that sum to 1, a window no longer than a measurement line, `low < high`).
//!
//! The bounds are wide: they keep every value where the arithmetic stays finite and the model
//! means something, not where a tracker works best.

use serde_json::Value;

use crate::config::{MAX_CLUSTER_ITERATIONS, MAX_PARTICLES, TrackerConfig};
use crate::{Error, Result};

/// The range of one setting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SettingRange {
    /// The dotted path of the setting in a configuration file; a list's elements share the
    /// list's range unless an element has its own entry (`dynamics.scale_range[0]`).
    pub path: &'static str,
    /// Least value.
    pub low: f64,
    /// Whether the least value itself is allowed.
    pub low_inclusive: bool,
    /// Greatest value.
    pub high: f64,
    /// Whether the greatest value itself is allowed.
    pub high_inclusive: bool,
    /// Whether the setting may be absent (`null`: an optional setting that is off).
    pub optional: bool,
}

impl SettingRange {
    /// Whether `v` lies in the range (a NaN never does).
    pub fn contains(&self, v: f64) -> bool {
        let above = if self.low_inclusive {
            v >= self.low
        } else {
            v > self.low
        };
        let below = if self.high_inclusive {
            v <= self.high
        } else {
            v < self.high
        };
        above && below
    }

    /// The range in interval notation: `(0, 1000]`.
    pub fn interval(&self) -> String {
        format!(
            "{}{}, {}{}",
            if self.low_inclusive { '[' } else { '(' },
            number(self.low),
            number(self.high),
            if self.high_inclusive { ']' } else { ')' }
        )
    }
}

/// A number as a person reads it: `1e308` rather than 309 digits, `0.5` as is.
fn number(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

const fn closed(path: &'static str, low: f64, high: f64) -> SettingRange {
    SettingRange {
        path,
        low,
        low_inclusive: true,
        high,
        high_inclusive: true,
        optional: false,
    }
}

/// (low, high]: a positive quantity.
const fn positive(path: &'static str, high: f64) -> SettingRange {
    SettingRange {
        low_inclusive: false,
        ..closed(path, 0.0, high)
    }
}

const fn optional(range: SettingRange) -> SettingRange {
    SettingRange {
        optional: true,
        ..range
    }
}

/// Settings that take any value of their type (a seed).
pub const UNBOUNDED_SETTINGS: [&str; 1] = ["seed"];

/// The range of every numeric setting, by dotted path.
pub const SETTING_RANGES: &[SettingRange] = &[
    closed("particles", 1.0, MAX_PARTICLES as f64),
    closed("init_spread", 0.0, 10.0),
    optional(closed("working_radius", 4.0, 1000.0)),
    // dynamics
    positive("dynamics.sigma_translation", 1000.0),
    positive("dynamics.sigma_scale", 1.0),
    positive("dynamics.sigma_shape", 1.0),
    closed("dynamics.velocity_retention", 0.0, 1.0),
    closed("dynamics.shape_velocity_retention", 0.0, 1.0),
    closed("dynamics.min_scale", 0.5, 1000.0),
    positive("dynamics.scale_range[0]", 1.0),
    closed("dynamics.scale_range[1]", 1.0, 100.0),
    positive("dynamics.aspect_range[0]", 1.0),
    closed("dynamics.aspect_range[1]", 1.0, 100.0),
    closed("dynamics.locked_gamma_rate", 0.0, 100.0),
    closed("dynamics.shape_reversion", 0.0, 1.0),
    SettingRange {
        high_inclusive: false,
        ..closed("dynamics.hidden_exploration", 0.0, 1.0)
    },
    // motion
    optional(closed("motion.working_radius", 4.0, 1000.0)),
    closed("motion.frame_check_pixels", 16.0, 16_777_216.0),
    closed("motion.estimator.levels", 1.0, 16.0),
    closed("motion.estimator.margin", 0.0, 4096.0),
    closed("motion.estimator.min_level_pixels", 16.0, 16_777_216.0),
    positive("motion.estimator.robust.Tukey.c", 100.0),
    positive("motion.estimator.robust.Cauchy.c", 100.0),
    positive("motion.estimator.robust.Huber.c", 100.0),
    closed("motion.estimator.max_iterations", 1.0, 1000.0),
    positive("motion.estimator.tolerance", 10.0),
    positive("motion.estimator.coarse_tolerance", 10.0),
    positive("motion.estimator.min_scale", 255.0),
    closed("motion.estimator.warm_levels", 1.0, 16.0),
    closed("motion.estimator.min_inlier_fraction", 0.0, 1.0),
    closed("motion.estimator.min_plurality_fraction", 0.0, 1.0),
    positive("motion.estimator.max_scale", 255.0),
    closed("motion.min_clusters", 1.0, MAX_PARTICLES as f64),
    closed("motion.clusters_per_particle", 0.0, 1.0),
    closed(
        "motion.cluster_iterations",
        0.0,
        MAX_CLUSTER_ITERATIONS as f64,
    ),
    // likelihood
    closed(
        "likelihood.shape.lines.n_lines",
        3.0,
        contour_obs::MAX_LINES as f64,
    ),
    closed("likelihood.shape.lines.length", 2.0, 1000.0),
    closed("likelihood.shape.lines.edge.sigma", 0.3, 10.0),
    positive("likelihood.shape.lines.edge.threshold", 1000.0),
    closed("likelihood.shape.lines.min_observed_fraction", 0.0, 1.0),
    positive("likelihood.shape.sigma", 1000.0),
    positive("likelihood.shape.k_floor", 1.0),
    closed("likelihood.implicit_motion.lambda_c", 0.0, 1000.0),
    closed("likelihood.implicit_motion.grid", 2.0, 64.0),
    positive("likelihood.implicit_motion.inner_radius", 1.5),
    positive("likelihood.implicit_motion.ncc.min_valid_fraction", 1.0),
    closed("likelihood.implicit_motion.ncc.min_variance", 0.0, 16384.0),
    closed(
        "likelihood.clutter.lines.n_lines",
        3.0,
        contour_obs::MAX_LINES as f64,
    ),
    closed("likelihood.clutter.lines.length", 2.0, 1000.0),
    closed("likelihood.clutter.lines.edge.sigma", 0.3, 10.0),
    positive("likelihood.clutter.lines.edge.threshold", 1000.0),
    closed("likelihood.clutter.lines.min_observed_fraction", 0.0, 1.0),
    positive("likelihood.clutter.sigma", 1000.0),
    positive("likelihood.clutter.window", 1000.0),
    closed("likelihood.clutter.p_detect", 0.0, 1.0),
    positive("likelihood.clutter.min_lambda", 1.0),
    positive("likelihood.clutter_line_fraction", 1.0),
    closed("likelihood.occlusion_form.unknown_occluder_share", 0.0, 1.0),
    // clutter
    positive("clutter.fixed.lambda", 10.0),
    closed("clutter.switching.transition", 0.0, 1.0),
    positive("clutter.switching.lambda_mean", 10.0),
    positive("clutter.switching.lambda_std", 10.0),
    // occlusion
    positive("occlusion.random_walk.sigma_gamma", 1.0),
    closed("occlusion.random_walk.initial_gamma", 0.0, 1.0),
    closed("occlusion.status.transition", 0.0, 1.0),
    closed("occlusion.status.locked.low", 0.0, 1.0),
    closed("occlusion.status.locked.high", 0.0, 1.0),
    closed("occlusion.status.partially_occluded.low", 0.0, 1.0),
    closed("occlusion.status.partially_occluded.high", 0.0, 1.0),
    closed("occlusion.status.lost.low", 0.0, 1.0),
    closed("occlusion.status.lost.high", 0.0, 1.0),
    // filter
    positive("filter.resample_threshold", 1.0),
    optional(closed("filter.output_size", 1.0, MAX_PARTICLES as f64)),
    closed("filter.parallel_min_chunk", 1.0, MAX_PARTICLES as f64),
    optional(closed("filter.history.max_frames", 1.0, 1e9)),
    optional(positive("filter.min_ess_fraction", 1.0)),
    // reacquisition
    closed("reacquisition.lock_gamma", 0.0, 1.0),
    optional(positive("reacquisition.shape_tolerance", 10.0)),
    closed("reacquisition.rollback", 0.0, 1000.0),
    closed("reacquisition.share_rate", 0.0, 1.0),
    closed("reacquisition.max_share", 0.0, 1.0),
    closed("reacquisition.detection_share", 0.0, 1.0),
    positive("reacquisition.spread", 1000.0),
    closed("reacquisition.spread_growth", 0.0, 100.0),
    closed("reacquisition.position_gain", 0.0, 1.0),
    closed("reacquisition.velocity_gain", 0.0, 1.0),
    closed("reacquisition.shape_gain", 0.0, 1.0),
    // appearance
    closed("appearance.search", 1.0, 20.0),
    closed("appearance.hs_bins", 2.0, 32.0),
    closed("appearance.value_bins", 2.0, 64.0),
    closed("appearance.contrast_ring", 1.05, 4.0),
    closed("appearance.background_ring", 1.0, 8.0),
    closed("appearance.colour_weight", 0.0, 1000.0),
    closed("appearance.template_weight", 0.0, 1000.0),
    closed("appearance.contour_weight", 0.0, 1000.0),
    closed("appearance.template_grid", 4.0, 64.0),
    closed("appearance.learnt_share", 0.0, 1.0),
    closed("appearance.target_rate", 0.0, 1.0),
    closed("appearance.background_rate", 0.0, 1.0),
    closed("appearance.template_rate", 0.0, 1.0),
    // The saturation bins span the threshold to 1, so it stays clear of 1.
    closed("appearance.histogram.min_saturation", 0.0, 0.9),
    closed("appearance.histogram.min_value", 0.0, 1.0),
    closed("appearance.histogram.min_chromatic_share", 0.0, 1.0),
    positive("appearance.histogram.bin_floor", 1.0),
    positive("appearance.histogram.max_log_ratio", 100.0),
    SettingRange {
        low_inclusive: false,
        high_inclusive: false,
        ..closed("appearance.lock_persistence", 0.5, 1.0)
    },
    positive("appearance.lock_spread", 10.0),
    // q is 1 for the first frame's target and 0 for its background: the locked centre near the
    // one, the lost centre near the other (`validate` keeps the locked one above).
    closed("appearance.lock_centres[0]", 0.5, 2.0),
    closed("appearance.lock_centres[1]", -1.0, 0.5),
    // Below 1 the rescaling of q = (ρ − ρ_bg) / (1 − ρ_bg) divides by 0.
    SettingRange {
        high_inclusive: false,
        ..closed("appearance.max_background_similarity", 0.0, 1.0)
    },
    closed("appearance.max_detection_centres", 1.0, 1e6),
    closed("appearance.max_window_pixels", 1e3, 1e8),
    closed("appearance.calibration_scales", 0.5, 2.0),
];

/// The entry for a concrete path (`a.b[1][2]`): its own entry, or the list's (`a.b`).
pub fn range_of(path: &str) -> Option<&'static SettingRange> {
    SETTING_RANGES.iter().find(|r| r.path == path).or_else(|| {
        let list = path.split('[').next()?;
        (list != path)
            .then(|| SETTING_RANGES.iter().find(|r| r.path == list))
            .flatten()
    })
}

/// Every numeric setting of `config` (and every `null` where a number belongs), with its path.
fn leaves(value: &Value, path: &mut String, out: &mut Vec<(String, Option<f64>)>) {
    match value {
        Value::Number(n) => out.push((path.clone(), n.as_f64())),
        Value::Null => out.push((path.clone(), None)),
        Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                let len = path.len();
                path.push_str(&format!("[{i}]"));
                leaves(item, path, out);
                path.truncate(len);
            }
        }
        Value::Object(fields) => {
            for (key, item) in fields {
                let len = path.len();
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(key);
                leaves(item, path, out);
                path.truncate(len);
            }
        }
        Value::Bool(_) | Value::String(_) => {}
    }
}

/// The numeric settings of `config` as (dotted path, value); `None` for a `null`, which a
/// non-finite number also becomes in JSON.
///
/// # Errors
/// [`Error::InvalidSetting`] if the configuration cannot be written as JSON (it always can).
pub fn numeric_settings(config: &TrackerConfig) -> Result<Vec<(String, Option<f64>)>> {
    let value = serde_json::to_value(config).map_err(|e| Error::InvalidSetting {
        name: "configuration",
        reason: e.to_string(),
    })?;
    let mut out = Vec::new();
    leaves(&value, &mut String::new(), &mut out);
    Ok(out)
}

/// Checks every numeric setting of `config` against [`SETTING_RANGES`].
///
/// # Errors
/// [`Error::InvalidSetting`] named by the setting's dotted path, with the value and the range.
pub fn check_ranges(config: &TrackerConfig) -> Result<()> {
    for (path, value) in numeric_settings(config)? {
        let Some(range) = range_of(&path) else {
            continue;
        };
        let element = path
            .strip_prefix(range.path)
            .filter(|rest| !rest.is_empty())
            .map(|rest| format!(" (element {rest})"))
            .unwrap_or_default();
        let bad = match value {
            Some(v) if range.contains(v) => None,
            Some(v) => Some(number(v)),
            None if range.optional => None,
            None => Some("not a finite number".to_owned()),
        };
        if let Some(shown) = bad {
            return Err(Error::InvalidSetting {
                name: range.path,
                reason: format!(
                    "{shown}{element} is outside {}, the range that can work",
                    range.interval()
                ),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
