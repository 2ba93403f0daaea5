//! Golden outputs: `track run` with a few presets on a short synthetic scene, compared byte for
//! byte with the files under `assets/golden/` at the top of the workspace.
//!
//! The scene is the `mclutter` preset of `scene-synth` (three clutter bands) rendered with seed 1;
//! its first 15 frames (at the preset's speed) are written in the OTB layout in a temporary
//! folder (`img/0001.png`…, `groundtruth_rect.txt`); each preset then tracks it
//! with 100 particles, seed 7 and `--parallel`. The tracker's numerics do not depend on the
//! number of threads, so the files are the same under `RAYON_NUM_THREADS=1` and `=2`.
//!
//! What is compared: `boxes.txt` as written, and `track.csv` without its last column, `millis`
//! (the wall time of each frame, the only column that is not deterministic). `summary.json` is
//! not compared: it holds frames/s and mean times.
//!
//! A change that moves a tracker's output on purpose regenerates the files with
//!
//! ```sh
//! UPDATE_GOLDEN=1 cargo test -p track-app --test integration golden::
//! ```
//!
//! which rewrites `assets/golden/<preset>/{track.csv,boxes.txt}` (atomically: a temporary file
//! beside each, then a rename) instead of comparing, and says so on standard error. Review the
//! diff before committing it.

use crate::common;

use std::path::{Path, PathBuf};

use common::{s, track};
use scene_synth::{Scenario, Scene};

/// The presets whose outputs are kept: head (the appearance terms), CONDENSATION, Odobez's motion
/// proposal, Wu's switching model with the occlusion arc, and the combined tracker.
const PRESETS: [&str; 5] = ["head", "m1", "m3", "w-eval", "full"];

/// Frames tracked: the first of the 120-frame scene, so the whole test stays within a few seconds.
const FRAMES: usize = 15;

/// `assets/golden/` at the top of the workspace.
fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/golden")
}

/// `track.csv` without its `millis` column (the last one on every row).
fn without_millis(csv: &str) -> String {
    let mut out = String::with_capacity(csv.len());
    for line in csv.lines() {
        let kept = line.rsplit_once(',').map_or(line, |(head, _)| head);
        out.push_str(kept);
        out.push('\n');
    }
    out
}

/// Writes `text` to `path` through a temporary sibling and a rename.
fn write_atomic(path: &Path, text: &str) {
    let dir = path.parent().unwrap();
    std::fs::create_dir_all(dir).unwrap();
    let tmp = dir.join(format!(
        ".{}.tmp",
        path.file_name().unwrap().to_str().unwrap()
    ));
    std::fs::write(&tmp, text).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

#[test]
fn presets_reproduce_their_golden_tracks_on_a_short_clutter_scene() {
    let update = std::env::var("UPDATE_GOLDEN").is_ok_and(|v| v == "1");
    let dir = tempfile::tempdir().unwrap();
    let seq = dir.path().join("mclutter");
    let scene = Scene::preset(Scenario::Mclutter, 1).unwrap();
    std::fs::create_dir_all(seq.join("img")).unwrap();
    let mut rects = String::new();
    for k in 0..FRAMES {
        let (frame, truth) = scene.render_frame(k).unwrap();
        frame
            .save(seq.join("img").join(format!("{:04}.png", k + 1)))
            .unwrap();
        rects.push_str(&truth.rect_line());
        rects.push('\n');
    }
    std::fs::write(seq.join("groundtruth_rect.txt"), rects).unwrap();

    let mut mismatches = Vec::new();
    for preset in PRESETS {
        let out = dir.path().join(preset);
        let run = track(&[
            "run",
            "--tracker",
            preset,
            "--particles",
            "100",
            "--seed",
            "7",
            "--parallel",
            "--quiet",
            "--out",
            s(&out),
            s(&seq),
        ]);
        assert!(run.status.success(), "{preset}: {}", common::stderr(&run));
        let produced = [
            (
                "track.csv",
                without_millis(&std::fs::read_to_string(out.join("track.csv")).unwrap()),
            ),
            (
                "boxes.txt",
                std::fs::read_to_string(out.join("boxes.txt")).unwrap(),
            ),
        ];
        for (name, text) in produced {
            let golden = golden_dir().join(preset).join(name);
            if update {
                write_atomic(&golden, &text);
                eprintln!("UPDATE_GOLDEN=1: rewrote {}", golden.display());
                continue;
            }
            let expected = std::fs::read_to_string(&golden).unwrap_or_else(|e| {
                panic!(
                    "{}: {e}; run `UPDATE_GOLDEN=1 cargo test -p track-app --test integration golden::` to create it",
                    golden.display()
                )
            });
            if expected != text {
                let line = expected
                    .lines()
                    .zip(text.lines())
                    .position(|(a, b)| a != b)
                    .map_or_else(
                        || "the line count".to_owned(),
                        |i| format!("line {}", i + 1),
                    );
                mismatches.push(format!("{preset}/{name} differs at {line}"));
            }
        }
    }
    assert!(
        mismatches.is_empty(),
        "golden outputs differ ({}); if the change is intended, regenerate with \
         `UPDATE_GOLDEN=1 cargo test -p track-app --test integration golden::` and review the diff",
        mismatches.join("; ")
    );
}
