//! Every kind of bad input gives one clear error naming the file or value, a non-zero exit code,
//! no panic, and no output at all (the output folder is never created).

use crate::common;

use std::path::Path;

use common::{image_folder, otb_folder, s, track};
use track_app::AppError;

/// Runs `track run` on `seq` with `extra` arguments into a fresh output folder; returns the error
/// and checks that nothing was written.
fn run_fails(dir: &Path, seq: &str, extra: &[&str]) -> AppError {
    let out = dir.join("out");
    let mut args = vec!["run", seq, "--out", s(&out), "--quiet"];
    args.extend_from_slice(extra);
    let err = track(&args).expect_err("the run should fail");
    assert!(!out.exists(), "output was written despite the error: {err}");
    assert_ne!(err.exit_code(), 0);
    let line = err.to_string();
    assert!(
        !line.contains('\n') || matches!(err, AppError::InvalidSetting { .. }),
        "{line}"
    );
    err
}

#[test]
fn corrupt_image_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let img = image_folder(dir.path(), 4);
    std::fs::write(img.join("0003.png"), b"\x89PNG\r\n\x1a\nthis is not a png").unwrap();
    let err = run_fails(dir.path(), s(&img), &["--init", "14,20,32,32"]);
    assert_eq!(err.exit_code(), 3);
    assert!(err.to_string().contains("0003.png"), "{err}");
}

#[test]
fn truncated_image_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let img = image_folder(dir.path(), 4);
    let bytes = std::fs::read(img.join("0004.png")).unwrap();
    std::fs::write(img.join("0004.png"), &bytes[..bytes.len() / 2]).unwrap();
    let err = run_fails(dir.path(), s(&img), &["--init", "14,20,32,32"]);
    assert_eq!(err.exit_code(), 3);
    assert!(err.to_string().contains("0004.png"), "{err}");
}

#[test]
fn frames_of_different_sizes_are_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let img = image_folder(dir.path(), 3);
    image::GrayImage::new(50, 40)
        .save(img.join("0004.png"))
        .unwrap();
    let err = run_fails(dir.path(), s(&img), &["--init", "14,20,32,32"]);
    assert_eq!(err.exit_code(), 3);
    let msg = err.to_string();
    assert!(msg.contains("0004.png") && msg.contains("50"), "{msg}");
}

#[test]
fn empty_folder_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let err = run_fails(dir.path(), s(&empty), &["--init", "1,1,5,5"]);
    assert_eq!(err.exit_code(), 3);
    assert!(err.to_string().contains("empty"), "{err}");
}

#[test]
fn missing_sequence_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let err = run_fails(
        dir.path(),
        s(&dir.path().join("nope")),
        &["--init", "1,1,5,5"],
    );
    assert_eq!(err.exit_code(), 3);
    assert!(err.to_string().contains("nope"), "{err}");
}

#[test]
fn malformed_groundtruth_line_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(dir.path(), 4);
    std::fs::write(
        seq.join("groundtruth_rect.txt"),
        "14,20,32,32\n16,20,32\n18,20,32,32\n20,20,32,32\n",
    )
    .unwrap();
    let err = run_fails(dir.path(), s(&seq), &[]);
    assert_eq!(err.exit_code(), 3);
    let msg = err.to_string();
    assert!(
        msg.contains("groundtruth_rect.txt") && msg.contains("line 2"),
        "{msg}"
    );
}

#[test]
fn initial_box_outside_the_frame_or_empty_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let img = image_folder(dir.path(), 3);
    for (init, needle) in [("500,500,20,20", "outside"), ("10,10,0,20", "size")] {
        let err = run_fails(dir.path(), s(&img), &["--init", init]);
        assert_eq!(err.exit_code(), 2);
        assert!(err.to_string().contains(needle), "{err}");
    }
}

#[test]
fn unknown_preset_lists_the_known_ones() {
    let dir = tempfile::tempdir().unwrap();
    let img = image_folder(dir.path(), 3);
    let err = run_fails(
        dir.path(),
        s(&img),
        &["--init", "14,20,32,32", "--tracker", "m9"],
    );
    assert_eq!(err.exit_code(), 2);
    let msg = err.to_string();
    assert!(msg.contains("m9") && msg.contains("w-eval"), "{msg}");
}

#[test]
fn invalid_counts_and_values_are_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let img = image_folder(dir.path(), 3);
    let err = run_fails(
        dir.path(),
        s(&img),
        &["--init", "14,20,32,32", "--particles", "0"],
    );
    assert_eq!(err.exit_code(), 2);
    assert!(err.to_string().contains("particles"), "{err}");
    let err = run_fails(dir.path(), s(&img), &["--init", "14,20,nan,32"]);
    assert_eq!(err.exit_code(), 2);
    assert!(err.to_string().contains("nan"), "{err}");
    let err = run_fails(
        dir.path(),
        s(&img),
        &["--init", "14,20,32,32", "--particles", "-5"],
    );
    assert_eq!(err.exit_code(), 2);
}

/// A configuration file in TOML with one value changed by `edit`.
fn config_with(dir: &Path, edit: impl FnOnce(&mut toml::Table)) -> std::path::PathBuf {
    let config = trackers::Preset::WHmm.config(50, 1);
    let mut table: toml::Table = toml::from_str(&toml::to_string(&config).unwrap()).unwrap();
    edit(&mut table);
    let path = dir.join("tracker.toml");
    std::fs::write(&path, toml::to_string(&table).unwrap()).unwrap();
    path
}

#[test]
fn configuration_with_nan_or_a_bad_matrix_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let img = image_folder(dir.path(), 3);
    let nan = config_with(dir.path(), |t| {
        t["dynamics"]["sigma_translation"] = toml::Value::Float(f64::NAN);
    });
    let err = run_fails(
        dir.path(),
        s(&img),
        &["--init", "14,20,32,32", "--config", s(&nan)],
    );
    assert_eq!(err.exit_code(), 2);
    assert!(err.to_string().contains("sigma_translation"), "{err}");

    let bad_rows = config_with(dir.path(), |t| {
        let row = toml::Value::Array(vec![0.5.into(), 0.4.into(), 0.3.into()]);
        t["clutter"]["switching"]["transition"][0] = row;
    });
    let err = run_fails(
        dir.path(),
        s(&img),
        &["--init", "14,20,32,32", "--config", s(&bad_rows)],
    );
    assert_eq!(err.exit_code(), 2);
    let msg = err.to_string();
    assert!(msg.contains("row") && msg.contains("1.2"), "{msg}");

    let broken = dir.path().join("broken.json");
    std::fs::write(&broken, "{ not json").unwrap();
    let err = run_fails(
        dir.path(),
        s(&img),
        &["--init", "14,20,32,32", "--config", s(&broken)],
    );
    // A configuration file is a setting, so one that does not parse is exit 2, like one
    // with a value out of range (it was 3).
    assert_eq!(err.exit_code(), 2);
    assert!(err.to_string().contains("broken.json"), "{err}");
}

fn y4m(header: &str, frames: &[&[u8]]) -> Vec<u8> {
    let mut v = format!("{header}\n").into_bytes();
    for f in frames {
        v.extend_from_slice(b"FRAME\n");
        v.extend_from_slice(f);
    }
    v
}

#[test]
fn y4m_with_unsupported_colour_space_or_truncated_frame_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let bad_colour = dir.path().join("c422.y4m");
    std::fs::write(
        &bad_colour,
        y4m("YUV4MPEG2 W8 H8 F25:1 C411", &[&[0u8; 128]]),
    )
    .unwrap();
    let err = run_fails(dir.path(), s(&bad_colour), &["--init", "1,1,4,4"]);
    assert_eq!(err.exit_code(), 3);
    assert!(err.to_string().contains("C411"), "{err}");

    let truncated = dir.path().join("cut.y4m");
    let full = [0u8; 96];
    std::fs::write(
        &truncated,
        y4m("YUV4MPEG2 W8 H8 F25:1 C420jpeg", &[&full, &full[..40]]),
    )
    .unwrap();
    let err = run_fails(dir.path(), s(&truncated), &["--init", "1,1,4,4"]);
    assert_eq!(err.exit_code(), 3);
    assert!(err.to_string().contains("cut.y4m"), "{err}");
}
