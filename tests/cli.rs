//! The `track` command line end to end on small generated sequences.

use crate::common;

use common::{otb_folder, s, track};

#[test]
fn run_on_an_otb_folder_writes_every_output() {
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(&dir.path().join("seq"), 12);
    let out = dir.path().join("out");
    track(&[
        "run",
        s(&seq),
        "--tracker",
        "m1",
        "--particles",
        "100",
        "--out",
        s(&out),
        "--overlay",
        "--gif",
        "--plots",
        "--report",
        "--quiet",
    ])
    .unwrap();
    let boxes = std::fs::read_to_string(out.join("boxes.txt")).unwrap();
    assert_eq!(boxes.lines().count(), 12);
    let csv = std::fs::read_to_string(out.join("track.csv")).unwrap();
    assert_eq!(csv.lines().count(), 13, "a header and one row per frame");
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .starts_with("frame,cx,cy,a,b,angle")
    );
    for f in [
        "track.gif",
        "report.html",
        "overlay/0001.png",
        "overlay/0012.png",
        "plots/ess.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} is missing");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["frames"], 12);
    // The disc moves 2 px per frame on a flat background: CONDENSATION must follow it closely.
    let iou = summary["metrics"]["mean_iou"].as_f64().unwrap();
    assert!(iou > 0.7, "mean IoU {iou}");
    // Atomic writes leave no temporary files behind.
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty());
}

#[test]
fn same_seed_same_boxes_whatever_the_threads() {
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(&dir.path().join("seq"), 8);
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec![
            "run",
            s(&seq),
            "--tracker",
            "full",
            "--particles",
            "60",
            "--seed",
            "5",
        ];
        args.extend_from_slice(&["--out", s(&out), "--quiet"]);
        args.extend_from_slice(extra);
        track(&args).unwrap();
        std::fs::read_to_string(out.join("boxes.txt")).unwrap()
    };
    let a = run("a", &[]);
    let b = run("b", &[]);
    let c = run("c", &["--parallel"]);
    assert_eq!(a, b);
    assert_eq!(a, c, "the parallel path must give the sequential result");
    let other_seed = {
        let out = dir.path().join("d");
        track(&[
            "run",
            s(&seq),
            "--tracker",
            "full",
            "--particles",
            "60",
            "--seed",
            "6",
            "--out",
            s(&out),
            "--quiet",
        ])
        .unwrap();
        std::fs::read_to_string(out.join("boxes.txt")).unwrap()
    };
    assert_ne!(a, other_seed, "the seed must matter");
}

#[test]
fn demo_writes_a_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    track(&[
        "demo",
        "--tracker",
        "m1",
        "--particles",
        "60",
        "--out",
        s(&out),
        "--quiet",
    ])
    .unwrap();
    for f in [
        "report.html",
        "track.gif",
        "track.csv",
        "summary.json",
        "plots/ess.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} is missing");
    }
}
