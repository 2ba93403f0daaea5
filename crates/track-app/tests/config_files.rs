//! A configuration names the pieces it uses and nothing else: `track config` prints
//! only what each preset's tracker reads and the file loads back as the preset; a file that sets
//! an unread setting, and `--edge-threshold` for a tracker without measurement lines, are refused
//! by name with exit 2; the files of the previous release (tests/fixtures/old_configs, written
//! by `track config` at commit 5c7d02c) load as today's presets, except the old `head`, which is
//! refused naming what replaced its `region`.

use std::path::{Path, PathBuf};

use trackers::{ConfigFormat, Preset, TrackerConfig};

use crate::common;

use common::{disc_frames, one_error_line, s, stdout, track};

/// The fixtures written by the previous release.
fn old_config(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/old_configs")
        .join(name)
}

/// An OTB folder `dir/name` of `n` disc frames of [`common::disc_image`], every frame labelled.
fn otb_folder(dir: &Path, name: &str, n: usize) -> PathBuf {
    let seq = dir.join(name);
    disc_frames(&seq, "img", n);
    let gt: String = (0..n)
        .map(|k| format!("{},24,24,24\n", 18 + 2 * k))
        .collect();
    std::fs::write(seq.join("groundtruth_rect.txt"), gt).unwrap();
    seq
}

/// `track config preset` (`--toml` when `toml`) as the user sees it.
fn printed(preset: Preset, toml: bool) -> String {
    let mut args = vec!["config", preset.name()];
    if toml {
        args.push("--toml");
    }
    let o = track(&args);
    assert!(o.status.success(), "{}", common::stderr(&o));
    stdout(&o)
}

/// The top-level keys of a printed JSON configuration.
fn keys(json: &str) -> Vec<String> {
    let v: serde_json::Value = serde_json::from_str(json).unwrap();
    v.as_object().unwrap().keys().cloned().collect()
}

#[test]
fn every_preset_prints_what_it_reads_and_loads_back_as_itself() {
    for preset in Preset::ALL {
        let expected = preset.config(trackers::DEFAULT_PARTICLES, trackers::DEFAULT_SEED);
        for (toml, format) in [(false, ConfigFormat::Json), (true, ConfigFormat::Toml)] {
            let text = printed(preset, toml);
            let back = TrackerConfig::parse(&text, format)
                .unwrap_or_else(|e| panic!("{preset} ({format:?}): {e}"));
            back.validate().unwrap();
            assert_eq!(back, expected, "{preset} ({format:?})");
        }
        let keys = keys(&printed(preset, false));
        let has = |k: &str| keys.iter().any(|x| x == k);
        assert_eq!(has("motion"), expected.needs_motion(), "{preset}: motion");
        assert_eq!(
            has("clutter"),
            expected.likelihood.clutter.is_some(),
            "{preset}: clutter"
        );
        assert_eq!(
            has("estimator"),
            matches!(expected.clutter, trackers::ClutterMode::Switching(_)),
            "{preset}: estimator"
        );
        for (key, set) in [
            ("reacquisition", expected.reacquisition.is_some()),
            ("working_radius", expected.working_radius.is_some()),
            ("appearance", expected.appearance.is_some()),
            (
                "occlusion",
                expected.occlusion != trackers::OcclusionMode::None,
            ),
        ] {
            assert_eq!(has(key), set, "{preset}: {key}");
        }
    }
    // head reads no contour likelihood term: no `likelihood`, `clutter` in either format; its
    // motion proposal reads `motion`.
    let head = printed(Preset::Head, true);
    assert!(head.contains("[motion"), "no [motion] in\n{head}");
    for table in ["[likelihood", "[clutter", "occlusion =", "estimator ="] {
        assert!(!head.contains(table), "{table} in\n{head}");
    }
}

#[test]
fn every_file_of_the_previous_release_loads_as_today_s_preset_but_head() {
    for preset in Preset::ALL {
        if preset == Preset::Head {
            continue;
        }
        let expected = preset.config(trackers::DEFAULT_PARTICLES, trackers::DEFAULT_SEED);
        for ext in ["json", "toml"] {
            let path = old_config(&format!("{}.{ext}", preset.name()));
            let text = std::fs::read_to_string(&path).unwrap();
            let old = TrackerConfig::parse(&text, ConfigFormat::of_path(&path))
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            old.validate()
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert_eq!(old, expected, "{}", path.display());
        }
    }
}

#[test]
fn track_run_takes_an_old_file_and_refuses_the_old_head_naming_what_replaced_region() {
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(dir.path(), "disc", 4);
    // `track run` on the sequence with an old configuration file, 50 particles.
    let run_with = |file: &str| {
        let out = dir.path().join(file);
        let config = old_config(file);
        track(&[
            "run",
            s(&seq),
            "--config",
            s(&config),
            "--particles",
            "50",
            "--out",
            s(&out),
            "--quiet",
        ])
    };
    for file in ["m1.json", "w-fixed.toml"] {
        let o = run_with(file);
        assert!(o.status.success(), "{file}: {}", common::stderr(&o));
    }
    for file in ["head.json", "head.toml"] {
        let o = run_with(file);
        assert_eq!(o.status.code(), Some(2), "{file}");
        let e = one_error_line(&o);
        for word in ["--config", "region", "appearance", "track config head"] {
            assert!(e.contains(word), "{file}: {word} not in {e}");
        }
    }
}

#[test]
fn a_file_that_sets_an_unread_setting_is_refused_by_its_path() {
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(dir.path(), "disc", 4);
    let cases: [(Preset, &str, serde_json::Value, &str); 4] = [
        (
            Preset::WHmm,
            "motion",
            serde_json::json!({"warm_start": false}),
            "`motion.warm_start`",
        ),
        (
            Preset::M1,
            "clutter",
            serde_json::json!({"fixed": {"lambda": 0.2}}),
            "`clutter.lambda`",
        ),
        (
            Preset::M2,
            "estimator",
            serde_json::json!("class_conditional_mean"),
            "`estimator`",
        ),
        (
            Preset::WFixed,
            "dynamics",
            serde_json::Value::Null,
            "`dynamics.hidden_exploration`",
        ),
    ];
    for (preset, key, value, named) in cases {
        let mut v: serde_json::Value = serde_json::from_str(&printed(preset, false)).unwrap();
        if key == "dynamics" {
            v["dynamics"]["hidden_exploration"] = 0.2.into();
        } else {
            v[key] = value;
        }
        let file = dir.path().join(format!("{}.json", preset.name()));
        std::fs::write(&file, serde_json::to_string_pretty(&v).unwrap()).unwrap();
        let out = dir.path().join(format!("out-{}", preset.name()));
        let o = track(&[
            "run",
            s(&seq),
            "--config",
            s(&file),
            "--out",
            s(&out),
            "--quiet",
        ]);
        assert_eq!(o.status.code(), Some(2), "{preset}");
        let e = one_error_line(&o);
        assert!(e.contains(named) && e.contains("not read"), "{preset}: {e}");
        assert!(!out.join("track.csv").exists(), "{preset}: tracked anyway");
    }
    // The same sections at the values the printer leaves out load: the previous release wrote
    // them into every file.
    let mut v: serde_json::Value = serde_json::from_str(&printed(Preset::Head, false)).unwrap();
    v["clutter"] = serde_json::json!({"fixed": {"lambda": trackers::FIXED_LAMBDA}});
    v["estimator"] = "mean".into();
    let text = serde_json::to_string(&v).unwrap();
    let c = TrackerConfig::parse(&text, ConfigFormat::Json).unwrap();
    c.validate().unwrap();
    assert_eq!(c, Preset::Head.config(200, 1));
}

#[test]
fn edge_threshold_is_refused_for_a_tracker_without_measurement_lines() {
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(dir.path(), "disc", 4);
    let out = dir.path().join("run-head");
    let o = track(&[
        "run",
        s(&seq),
        "--tracker",
        "head",
        "--edge-threshold",
        "12",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = one_error_line(&o);
    assert!(
        e.contains("--edge-threshold") && e.contains("measurement lines"),
        "{e}"
    );
    assert!(!out.join("track.csv").exists());

    // A head configuration file is refused alike.
    let file = dir.path().join("head.toml");
    std::fs::write(&file, printed(Preset::Head, true)).unwrap();
    let o = track(&[
        "run",
        s(&seq),
        "--config",
        s(&file),
        "--edge-threshold",
        "12",
        "--out",
        s(&dir.path().join("run-head-file")),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(one_error_line(&o).contains("--edge-threshold"));

    // track eval otb: head is its default tracker, and one tracker without lines is enough.
    for trackers in [&[][..], &["--tracker", "m1", "--tracker", "head"][..]] {
        let mut args = vec![
            "eval",
            "otb",
            s(&seq),
            "--edge-threshold",
            "12",
            "--quiet",
            "--out",
        ];
        let eval_out = dir.path().join(format!("eval-{}", trackers.len()));
        args.push(s(&eval_out));
        args.extend_from_slice(trackers);
        let o = track(&args);
        assert_eq!(o.status.code(), Some(2), "{trackers:?}");
        assert!(
            one_error_line(&o).contains("--edge-threshold"),
            "{trackers:?}"
        );
    }

    // A tracker with measurement lines takes it.
    let out = dir.path().join("run-m1");
    let o = track(&[
        "run",
        s(&seq),
        "--tracker",
        "m1",
        "--particles",
        "50",
        "--edge-threshold",
        "12",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));

    // track demo has no such option: clap refuses it, exit 2.
    let o = track(&["demo", "--tracker", "head", "--edge-threshold", "12"]);
    assert_eq!(o.status.code(), Some(2));
}
