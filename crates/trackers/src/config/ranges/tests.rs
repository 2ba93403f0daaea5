//! Every range has a setting and every setting a range; out-of-range values are refused by
//! name; values at either end of a range track.

use super::*;
use crate::Preset;

/// Every preset, and the variants that hold the settings no preset has (other robust
/// functions, the arc occlusion form, optional settings switched on).
fn variants() -> Vec<Value> {
    let mut out: Vec<Value> = Preset::ALL
        .iter()
        .map(|p| serde_json::to_value(p.config(50, 1)).unwrap())
        .collect();
    // The motion estimator's robust functions on a tracker that reads `motion`.
    let motion = serde_json::to_value(Preset::Full.config(50, 1)).unwrap();
    for robust in [
        serde_json::json!({"Cauchy": {"c": 2.3849}}),
        serde_json::json!({"Huber": {"c": 1.345}}),
    ] {
        let mut v = motion.clone();
        v["motion"]["estimator"]["robust"] = robust;
        out.push(v);
    }
    let mut v = serde_json::to_value(Preset::WEval.config(50, 1)).unwrap();
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
    // per frame; colour for the appearance terms (head).
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
