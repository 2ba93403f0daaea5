//! `track eval otb` on a stress suite (`cargo xtask stress`'s layout): every clip under every
//! transform is evaluated, named `<transform>/<clip>`, with one mean per transform and the mean
//! over transforms beside the per-clip tables; `--results` reads box files laid out per
//! transform, as `opencv_peers.py SUITE/<transform> --out DIR/<transform>` writes them.

use std::fs;
use std::path::{Path, PathBuf};

use crate::common;

use common::{disc_frames, one_error_line, s, stdout, track};

const FRAMES: usize = 6;

/// The disc's true box on frame k of [`disc_frames`].
fn line(k: usize, shift: f64) -> String {
    format!("{},24,24,24", 18.0 + 2.0 * k as f64 + shift)
}

/// An OTB clip of disc frames at `dir`, with `stress.json` when `record`.
fn clip(dir: &Path, record: bool) {
    let parent = dir.parent().unwrap();
    let name = dir.file_name().unwrap().to_str().unwrap();
    disc_frames(parent, &format!("{name}/img"), FRAMES);
    let gt: String = (0..FRAMES).map(|k| line(k, 0.0) + "\n").collect();
    fs::write(dir.join("groundtruth_rect.txt"), gt).unwrap();
    if record {
        fs::write(dir.join("stress.json"), "{\"generator\": \"test\"}\n").unwrap();
    }
}

/// Box files of tracker `name` for `clip` (OPE), shifted by `shift` px, below `dir`.
fn results(dir: &Path, name: &str, clip: &str, shift: f64) {
    let d = dir.join("ope").join(name);
    fs::create_dir_all(&d).unwrap();
    let text: String = (0..FRAMES).map(|k| line(k, shift) + "\n").collect();
    fs::write(d.join(format!("{clip}.txt")), text).unwrap();
}

/// A suite of two transforms × two clips, the footage as shot beside it, and two trackers'
/// boxes: `exact` everywhere, `off` 12 px off under `shake` only.
fn fixture(tmp: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let suite = tmp.join("suite");
    let shot = tmp.join("shot");
    let peers = tmp.join("peers");
    for t in ["grey", "shake"] {
        for c in ["A", "B"] {
            clip(&suite.join(t).join(c), true);
            results(&peers.join(t), "exact", c, 0.0);
            results(
                &peers.join(t),
                "off",
                c,
                if t == "shake" { 12.0 } else { 0.0 },
            );
        }
    }
    fs::write(suite.join("suite.json"), "{}\n").unwrap();
    for c in ["A", "B"] {
        clip(&shot.join(c), false);
        results(&peers, "exact", c, 0.0);
        results(&peers, "off", c, 0.0);
    }
    (suite, shot, peers)
}

#[test]
fn a_suite_is_read_as_every_clip_under_every_transform_with_means_per_transform() {
    let tmp = tempfile::tempdir().unwrap();
    let (suite, shot, peers) = fixture(tmp.path());
    let out = tmp.path().join("eval");
    let exact = format!("exact={}", s(&peers));
    let off = format!("off={}", s(&peers));
    let o = track(&[
        "eval",
        "otb",
        s(&suite),
        s(&shot.join("A")),
        s(&shot.join("B")),
        "--results",
        &exact,
        "--results",
        &off,
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let printed = stdout(&o);
    assert!(printed.contains("Under stress (OPE)"), "{printed}");
    let table = fs::read_to_string(out.join("ope/suite.md")).unwrap();
    assert!(
        table.contains("| tracker | as shot | grey | shake | mean over transforms | its P20 |"),
        "{table}"
    );
    assert!(
        // IoU 1 passes every threshold but the last (IoU > 1): 20/21.
        table.contains("| exact | 0.952 | 0.952 | 0.952 | **0.952** | 1.000 |"),
        "{table}"
    );
    // 12 px off a 24 px box: IoU 1/3 on every scored frame, so success at thresholds 0 … 0.3
    // (7 of 21): AUC 1/3 under shake; the mean over transforms is (20/21 + 1/3)/2.
    assert!(
        table.contains("| off | 0.952 | 0.952 | 0.333 | **0.643** |"),
        "{table}"
    );
    let csv = fs::read_to_string(out.join("ope/suite.csv")).unwrap();
    assert!(csv.contains("ope,shake,off,2,0.3333,1.0000"), "{csv}");
    assert!(csv.contains("ope,mean,off,4,0.6429,1.0000"), "{csv}");
    // The per-clip tables name each clip under its transform.
    let per_clip = fs::read_to_string(out.join("ope/otb.md")).unwrap();
    assert!(per_clip.contains("| shake/A | off |"), "{per_clip}");
    assert!(per_clip.contains("| A | exact |"), "{per_clip}");
}

#[test]
fn a_tracker_s_boxes_on_a_suite_are_written_per_transform_and_read_back() {
    let tmp = tempfile::tempdir().unwrap();
    let (suite, _, _) = fixture(tmp.path());
    let out = tmp.path().join("eval");
    let o = track(&[
        "eval",
        "otb",
        s(&suite),
        "--tracker",
        "head",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    for t in ["grey", "shake"] {
        for c in ["A", "B"] {
            let f = out.join(t).join("ope/head").join(format!("{c}.txt"));
            assert_eq!(
                fs::read_to_string(&f).unwrap().lines().count(),
                FRAMES,
                "{f:?}"
            );
        }
    }
    // This command's own --out is a --results folder for the same suite.
    let again = tmp.path().join("again");
    let head = format!("head={}", s(&out));
    let o = track(&[
        "eval",
        "otb",
        s(&suite),
        "--results",
        &head,
        "--out",
        s(&again),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert!(
        fs::read_to_string(again.join("ope/suite.md"))
            .unwrap()
            .contains("| head |")
    );
}

#[test]
fn a_suite_s_missing_box_file_or_empty_transform_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let (suite, _, peers) = fixture(tmp.path());
    fs::remove_file(peers.join("shake/ope/exact/B.txt")).unwrap();
    let exact = format!("exact={}", s(&peers));
    let o = track(&[
        "eval",
        "otb",
        s(&suite),
        "--results",
        &exact,
        "--out",
        s(&tmp.path().join("e")),
    ]);
    let e = one_error_line(&o);
    assert!(
        e.contains("shake/ope/exact/B.txt") && e.contains("missing"),
        "{e}"
    );
    fs::create_dir_all(suite.join("tilt")).unwrap();
    let o = track(&[
        "eval",
        "otb",
        s(&suite),
        "--tracker",
        "head",
        "--out",
        s(&tmp.path().join("e")),
    ]);
    let e = one_error_line(&o);
    assert!(e.contains("tilt") && e.contains("holds no clip"), "{e}");
    assert_eq!(o.status.code(), Some(3));
}
