//! The range of every numeric setting of a [`TrackerConfig`], checked first by
//! [`TrackerConfig::validate`] so that a value that cannot work (`dynamics.sigma_translation =
//! 1e308` made the contour non-finite at frame 1) is refused before any frame, by the dotted path
//! of the configuration file and the range.
//!
//! The check reads the configuration as its JSON form, so the paths are those of the file
//! (`dynamics.sigma_translation`, `clutter.switching.lambda_mean`, `motion.estimator.robust.Tukey.c`)
//! and an element of a list is named with its index (`clutter.switching.transition[0][2]`). The
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
    SettingRange {
        low_inclusive: false,
        high_inclusive: false,
        ..closed("appearance.lock_persistence", 0.5, 1.0)
    },
    closed("appearance.max_detection_centres", 1.0, 1e6),
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
mod tests {
    use super::*;
    use crate::Preset;

    /// Every preset, and the variants that hold the settings no preset has (other robust
    /// functions, the arc occlusion form, optional settings switched on).
    fn variants() -> Vec<Value> {
        let mut out: Vec<Value> = Preset::ALL
            .iter()
            .map(|p| serde_json::to_value(p.config(50, 1)).unwrap())
            .collect();
        let base = serde_json::to_value(Preset::WEval.config(50, 1)).unwrap();
        for robust in [
            serde_json::json!({"Cauchy": {"c": 2.3849}}),
            serde_json::json!({"Huber": {"c": 1.345}}),
        ] {
            let mut v = base.clone();
            v["motion"]["estimator"]["robust"] = robust;
            out.push(v);
        }
        let mut v = base.clone();
        v["likelihood"]["occlusion_form"] =
            serde_json::json!({"form": "arc", "unknown_occluder_share": 0.5});
        v["filter"]["output_size"] = 40.into();
        v["filter"]["history"] = serde_json::json!({"max_frames": 10});
        v["working_radius"] = 12.0.into();
        out.push(v);
        // The appearance terms and tempering, on Odobez's space.
        let mut v = serde_json::to_value(Preset::M1.config(50, 1)).unwrap();
        v["appearance"] = serde_json::to_value(crate::AppearanceSettings::default()).unwrap();
        v["filter"]["min_ess_fraction"] = 0.3.into();
        out.push(v);
        for v in &out {
            serde_json::from_value::<TrackerConfig>(v.clone())
                .unwrap()
                .validate()
                .unwrap();
        }
        out
    }

    /// Sets the value at a dotted path with list indices (`a.b[0][2]`).
    fn set(v: &mut Value, path: &str, x: Value) {
        let mut at = v;
        for part in path.split('.') {
            let mut pieces = part.split('[');
            at = &mut at[pieces.next().unwrap()];
            for index in pieces {
                at = &mut at[index.trim_end_matches(']').parse::<usize>().unwrap()];
            }
        }
        *at = x;
    }

    /// A concrete path of `range` in `v`, and the value there.
    fn find(v: &Value, range: &SettingRange) -> Option<(String, Value)> {
        let mut leaves_out = Vec::new();
        leaves(v, &mut String::new(), &mut leaves_out);
        let (path, _) = leaves_out
            .into_iter()
            .find(|(p, x)| x.is_some() && range_of(p).is_some_and(|r| r.path == range.path))?;
        let mut at = v;
        for part in path.split('.') {
            let mut pieces = part.split('[');
            at = &at[pieces.next().unwrap()];
            for index in pieces {
                at = &at[index.trim_end_matches(']').parse::<usize>().unwrap()];
            }
        }
        Some((path, at.clone()))
    }

    #[test]
    fn every_numeric_setting_has_a_range_and_every_range_a_setting() {
        let variants = variants();
        for v in &variants {
            let config: TrackerConfig = serde_json::from_value(v.clone()).unwrap();
            for (path, _) in numeric_settings(&config).unwrap() {
                let known = range_of(&path).is_some()
                    || UNBOUNDED_SETTINGS.contains(&path.as_str())
                    // `null` of an optional group that is off (`region`, `likelihood.shape`).
                    || v.pointer(&format!("/{}", path.replace('.', "/")))
                        .is_some_and(Value::is_null)
                        && !path.contains('[');
                assert!(known, "{path} of {} has no range", config.name);
            }
        }
        for range in SETTING_RANGES {
            assert!(
                variants.iter().any(|v| find(v, range).is_some()),
                "{} is in no configuration",
                range.path
            );
        }
    }

    #[test]
    fn every_setting_out_of_its_range_is_refused_by_name_with_the_range() {
        let variants = variants();
        let mut cases = 0;
        for range in SETTING_RANGES {
            let (v, (path, current)) = variants
                .iter()
                .find_map(|v| find(v, range).map(|f| (v, f)))
                .unwrap();
            let integer = current.is_u64();
            let (low, high) = (range.low, range.high);
            let mut bad: Vec<Value> = Vec::new();
            if integer {
                if low >= 1.0 {
                    bad.push(((low - 1.0) as u64).into());
                }
                bad.push(((high + 1.0) as u64).into());
            } else {
                bad.push(if range.low_inclusive {
                    (low - low.abs().max(1.0)).into()
                } else {
                    low.into()
                });
                bad.push(if range.high_inclusive {
                    (high + high.abs().max(1.0)).into()
                } else {
                    high.into()
                });
                bad.push(1e308.into());
                bad.push((-1e308).into());
            }
            for x in bad {
                let mut w = v.clone();
                set(&mut w, &path, x.clone());
                let config: TrackerConfig =
                    serde_json::from_value(w).unwrap_or_else(|e| panic!("{path} = {x}: {e}"));
                let err = config.validate().unwrap_err();
                match &err {
                    Error::InvalidSetting { name, reason } => {
                        assert_eq!(*name, range.path, "{path} = {x}: {err}");
                        assert!(reason.contains(&range.interval()), "{err}");
                    }
                    other => panic!("{path} = {x}: {other}"),
                }
                cases += 1;
            }
        }
        assert!(cases > 300, "{cases}");
    }

    #[test]
    fn the_issue_s_translation_noise_is_refused_and_its_bound_tracks() {
        let mut c = Preset::M1.config(50, 1);
        c.dynamics.sigma_translation = 1e308;
        let e = c.validate().unwrap_err().to_string();
        assert_eq!(
            e,
            "invalid tracker setting `dynamics.sigma_translation`: 1e308 is outside (0, 1000], \
             the range that can work"
        );
        // Not-a-number and infinities (a TOML file may hold `nan` and `inf`), in a list too.
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut c = Preset::M1.config(50, 1);
            c.dynamics.sigma_translation = x;
            let e = c.validate().unwrap_err().to_string();
            assert!(
                e.contains("dynamics.sigma_translation") && e.contains("not a finite number"),
                "{e}"
            );
            let mut h = Preset::Head.config(50, 1);
            if let Some(a) = &mut h.appearance {
                a.colour_weight = x;
            }
            assert!(
                h.validate()
                    .unwrap_err()
                    .to_string()
                    .contains("appearance.colour_weight")
            );
            let mut w = Preset::WHmm.config(50, 1);
            if let crate::ClutterMode::Switching(cfg) = &mut w.clutter {
                cfg.lambda_mean[1] = x;
            }
            let e = w.validate().unwrap_err().to_string();
            assert!(
                e.contains("clutter.switching.lambda_mean") && e.contains("element [1]"),
                "{e}"
            );
        }
        // At the bound the filter runs, and its contour stays finite.
        c.dynamics.sigma_translation = 1000.0;
        let mut t = crate::build(c).unwrap();
        let pixels: Vec<f32> = (0..64 * 48)
            .map(|i| if (i % 64) / 16 % 2 == 0 { 40.0 } else { 200.0 })
            .collect();
        let frame = crate::Frame::new(64, 48, &pixels).unwrap();
        t.init(
            frame,
            vision_core::Ellipse::new(32.0, 24.0, 10.0, 10.0, 0.0),
        )
        .unwrap();
        for _ in 0..5 {
            let e = t.update(frame).unwrap().ellipse;
            assert!(
                [e.cx, e.cy, e.a, e.b].iter().all(|v| v.is_finite()),
                "{e:?}"
            );
        }
    }

    #[test]
    fn every_setting_at_either_end_of_its_range_tracks_with_finite_contours() {
        // A 96×72 frame: a bright disc of radius 14 on a textured background, moving 2 px right
        // per frame; colour for the region tracker.
        let frames: Vec<(Vec<f32>, Vec<u8>)> = (0..4)
            .map(|k| {
                let mut grey = Vec::with_capacity(96 * 72);
                let mut rgb = Vec::with_capacity(3 * 96 * 72);
                for i in 0..96 * 72 {
                    let (x, y) = ((i % 96) as f64, (i / 96) as f64);
                    let d = ((x - 40.0 - 2.0 * k as f64).powi(2) + (y - 36.0).powi(2)).sqrt();
                    let t = 20.0 * ((0.7 * x).sin() * (0.9 * y).cos());
                    let p = if d < 14.0 {
                        [210.0, 150.0, 120.0]
                    } else {
                        [60.0 + t, 90.0 + t, 120.0]
                    };
                    let p = p.map(|c: f64| c.clamp(0.0, 255.0) as u8);
                    rgb.extend(p);
                    grey.push(
                        0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2]),
                    );
                }
                (grey, rgb)
            })
            .collect();
        let variants = variants();
        let (mut ran, mut skipped) = (0, Vec::new());
        for range in SETTING_RANGES {
            // The particle count's bound is a cost limit, not a numerical one.
            if range.path == "particles" {
                continue;
            }
            let (v, (path, current)) = variants
                .iter()
                .find_map(|v| find(v, range).map(|f| (v, f)))
                .unwrap();
            let nudge = |x: f64, up: bool| {
                let step = 1e-9 * x.abs().max(1.0);
                if up { x + step } else { x - step }
            };
            let low = if range.low_inclusive {
                range.low
            } else {
                nudge(range.low, true)
            };
            let high = if range.high_inclusive {
                range.high
            } else {
                nudge(range.high, false)
            };
            for x in [low, high] {
                let value: Value = if current.is_u64() {
                    (x as u64).into()
                } else {
                    x.into()
                };
                let mut w = v.clone();
                set(&mut w, &path, value);
                let config: TrackerConfig = serde_json::from_value(w).unwrap();
                if config.validate().is_err() {
                    // A bound that another setting's check refuses on its own (a transition
                    // entry of 0 breaks its row's sum; a window longer than the line).
                    skipped.push(format!("{path} = {x}"));
                    continue;
                }
                let name = config.name.clone();
                let mut t = crate::build(config).unwrap();
                let frame =
                    |k: usize| crate::Frame::with_rgb(96, 72, &frames[k].0, &frames[k].1).unwrap();
                let start = vision_core::Ellipse::new(40.0, 36.0, 14.0, 14.0, 0.0);
                t.init(frame(0), start)
                    .unwrap_or_else(|e| panic!("{name}: {path} = {x}: {e}"));
                for k in 1..4 {
                    let e = t
                        .update(frame(k))
                        .unwrap_or_else(|e| panic!("{name}: {path} = {x}, frame {k}: {e}"))
                        .ellipse;
                    assert!(
                        [e.cx, e.cy, e.a, e.b, e.angle]
                            .iter()
                            .all(|v| v.is_finite()),
                        "{name}: {path} = {x}: {e:?}"
                    );
                }
                ran += 1;
            }
        }
        eprintln!("{ran} bounds tracked; skipped: {skipped:?}");
        assert!(
            ran > 180 && skipped.len() < 20,
            "{ran} ran, skipped {skipped:?}"
        );
    }
}
