//! Printing and parsing configurations, and the overrides on them.

use super::*;
use crate::Preset;

#[test]
fn every_preset_is_valid_and_round_trips_through_json() {
    for p in Preset::ALL {
        let c = p.config(200, 1);
        c.validate().unwrap();
        let json = serde_json::to_string(&c).unwrap();
        let back: TrackerConfig = serde_json::from_str(&json).unwrap();
        assert_eq!(back, c);
        assert_eq!(Preset::from_name(p.name()).unwrap(), p);
    }
}

#[test]
fn invalid_settings_are_rejected() {
    let mut c = Preset::M1.config(0, 1);
    assert!(matches!(
        c.validate(),
        Err(Error::InvalidSetting {
            name: "particles",
            ..
        })
    ));
    c.particles = 10;
    c.dynamics.sigma_translation = f64::NAN;
    assert!(c.validate().is_err());
    let mut w = Preset::WHmm.config(10, 1);
    if let ClutterMode::Switching(cfg) = &mut w.clutter {
        cfg.transition[0] = vec![0.5, 0.4, 0.3];
    }
    assert!(matches!(w.validate(), Err(Error::Switching(_))));
    assert!(matches!(
        Preset::from_name("m9"),
        Err(Error::UnknownPreset { .. })
    ));
}

#[test]
fn configurations_parse_as_track_config_prints_them() {
    for preset in Preset::ALL {
        let c = preset.config(DEFAULT_PARTICLES, DEFAULT_SEED);
        let json = serde_json::to_string_pretty(&c).unwrap();
        assert_eq!(TrackerConfig::parse(&json, ConfigFormat::Json).unwrap(), c);
        let toml = toml::to_string_pretty(&c).unwrap();
        assert_eq!(TrackerConfig::parse(&toml, ConfigFormat::Toml).unwrap(), c);
    }
    let e = TrackerConfig::parse("{", ConfigFormat::Json).unwrap_err();
    assert!(e.starts_with("invalid JSON: "), "{e}");
    let e = TrackerConfig::parse("name = \"x\"\nparticles = \"many\"\n", ConfigFormat::Toml)
        .unwrap_err();
    assert!(e.starts_with("invalid TOML at line 2, column "), "{e}");
    assert!(!e.contains('\n'), "{e}");
}

#[test]
fn config_format_follows_the_extension() {
    use std::path::Path;
    assert_eq!(
        ConfigFormat::of_path(Path::new("a.toml")),
        ConfigFormat::Toml
    );
    assert_eq!(
        ConfigFormat::of_path(Path::new("a.TOML")),
        ConfigFormat::Toml
    );
    assert_eq!(
        ConfigFormat::of_path(Path::new("a.json")),
        ConfigFormat::Json
    );
    assert_eq!(ConfigFormat::of_path(Path::new("a")), ConfigFormat::Json);
}

/// The top-level keys and the keys of `section` of the printed JSON of `c`, sorted.
fn printed_keys(c: &TrackerConfig, section: &str) -> (Vec<String>, Vec<String>) {
    let v = serde_json::to_value(c).unwrap();
    let keys = |v: &serde_json::Value| {
        v.as_object()
            .map(|o| o.keys().cloned().collect())
            .unwrap_or_default()
    };
    (keys(&v), keys(&v[section]))
}

#[test]
fn printed_configurations_name_only_what_the_tracker_reads() {
    let has = |keys: &[String], k: &str| keys.iter().any(|x| x == k);
    let (head, dynamics) = printed_keys(&Preset::Head.config(50, 1), "dynamics");
    for k in ["likelihood", "clutter", "occlusion", "estimator"] {
        assert!(!has(&head, k), "head prints {k}");
    }
    // Its motion proposal reads the motion settings.
    assert!(has(&head, "motion"), "head does not print motion");
    for k in [
        "appearance",
        "reacquisition",
        "working_radius",
        "filter",
        "dynamics",
    ] {
        assert!(has(&head, k), "head lacks {k}");
    }
    assert!(!has(&dynamics, "locked_gamma_rate") && !has(&dynamics, "hidden_exploration"));
    assert!(has(&dynamics, "sigma_translation"));

    let (m1, likelihood) = printed_keys(&Preset::M1.config(50, 1), "likelihood");
    for k in [
        "motion",
        "clutter",
        "occlusion",
        "estimator",
        "reacquisition",
        "working_radius",
        "appearance",
    ] {
        assert!(!has(&m1, k), "m1 prints {k}");
    }
    assert_eq!(likelihood, ["shape"]);
    let (m3, likelihood) = printed_keys(&Preset::M3.config(50, 1), "likelihood");
    assert!(has(&m3, "motion") && !has(&m3, "clutter"));
    assert_eq!(
        likelihood,
        ["implicit_motion", "motion_consistency", "shape"]
    );

    let (fixed, likelihood) = printed_keys(&Preset::WFixed.config(50, 1), "likelihood");
    assert!(has(&fixed, "clutter") && !has(&fixed, "estimator") && !has(&fixed, "motion"));
    assert_eq!(
        likelihood,
        ["clutter", "clutter_line_fraction", "occlusion_form"]
    );
    let (hmm, dynamics) = printed_keys(&Preset::WHmm.config(50, 1), "dynamics");
    assert!(has(&hmm, "estimator") && !has(&hmm, "occlusion"));
    assert!(has(&dynamics, "hidden_exploration") && !has(&dynamics, "locked_gamma_rate"));
    let (eval, dynamics) = printed_keys(&Preset::WEval.config(50, 1), "dynamics");
    assert!(has(&eval, "occlusion") && has(&eval, "reacquisition"));
    assert!(has(&dynamics, "hidden_exploration") && has(&dynamics, "locked_gamma_rate"));

    // TOML the same: head's file has a [motion] table but no [likelihood] or [clutter].
    let toml = toml::to_string_pretty(&Preset::Head.config(50, 1)).unwrap();
    let table: toml::Table = toml.parse().unwrap();
    assert!(table.contains_key("motion"), "head's TOML has no [motion]");
    for k in ["likelihood", "clutter", "occlusion", "estimator"] {
        assert!(!table.contains_key(k), "head's TOML prints {k}");
    }
}

#[test]
fn an_unread_setting_off_its_default_is_printed_and_refused_on_loading() {
    let mut c = Preset::M1.config(50, 1);
    c.motion.offset = true;
    c.dynamics.locked_gamma_rate = 1.5;
    for (text, format) in [
        (
            serde_json::to_string_pretty(&c).unwrap(),
            ConfigFormat::Json,
        ),
        (toml::to_string_pretty(&c).unwrap(), ConfigFormat::Toml),
    ] {
        let back = TrackerConfig::parse(&text, format).unwrap();
        assert_eq!(back, c);
        assert!(matches!(
            back.validate(),
            Err(Error::InvalidSetting {
                name: "motion.offset",
                ..
            })
        ));
    }
}

#[test]
fn a_null_region_of_an_earlier_file_loads_and_a_set_one_is_refused() {
    let c = Preset::M1.config(50, 1);
    let mut v = serde_json::to_value(&c).unwrap();
    v["region"] = serde_json::Value::Null;
    let text = serde_json::to_string(&v).unwrap();
    assert_eq!(TrackerConfig::parse(&text, ConfigFormat::Json).unwrap(), c);
    v["region"] = serde_json::json!({"template_weight": 40.0});
    let text = serde_json::to_string(&v).unwrap();
    let e = TrackerConfig::parse(&text, ConfigFormat::Json).unwrap_err();
    assert!(
        e.contains("unknown field `region`") && e.contains("`appearance`"),
        "{e}"
    );
    // Any other unknown field stays an error, null or not.
    let mut v = serde_json::to_value(&c).unwrap();
    v["regions"] = serde_json::Value::Null;
    let text = serde_json::to_string(&v).unwrap();
    assert!(TrackerConfig::parse(&text, ConfigFormat::Json).is_err());
}

#[test]
fn the_edge_threshold_is_set_on_every_measurement_line_and_refused_without_them() {
    let mut full = Preset::Full.config(50, 1);
    full.set_edge_threshold(12.0).unwrap();
    assert_eq!(full.likelihood.clutter.unwrap().lines.edge.threshold, 12.0);
    let mut m1 = Preset::M1.config(50, 1);
    m1.set_edge_threshold(12.0).unwrap();
    assert_eq!(m1.likelihood.shape.unwrap().lines.edge.threshold, 12.0);
    let mut head = Preset::Head.config(50, 1);
    let before = head.clone();
    assert!(matches!(
        head.set_edge_threshold(12.0),
        Err(Error::InvalidSetting {
            name: "edge threshold",
            ..
        })
    ));
    assert_eq!(head, before);
}
