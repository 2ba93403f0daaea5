//! `track run --smooth`: smoothed estimates written beside the filtered ones.

use crate::common;

use common::{DISC_INIT, disc_frames, s, track};

#[test]
fn run_smooth_writes_the_smoothed_track_beside_the_filtered_one() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "disc", 12);
    let out = dir.path().join("out");
    // w-eval on the disc frames into `out`, smoothed or not.
    let run_into = |smooth: bool| {
        let mut args = vec!["run", "--tracker", "w-eval", "--particles", "60", "--quiet"];
        if smooth {
            args.push("--smooth");
        }
        args.extend(["--init", DISC_INIT, "--out", s(&out), s(&frames)]);
        track(&args)
    };
    let run = run_into(true);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let filtered = std::fs::read_to_string(out.join("track.csv")).unwrap();
    let smoothed = std::fs::read_to_string(out.join("smoothed.csv")).unwrap();
    let header = |t: &str| t.lines().next().unwrap().to_owned();
    assert_eq!(header(&filtered), header(&smoothed));
    assert_eq!(filtered.lines().count(), 13);
    assert_eq!(smoothed.lines().count(), 13);
    let boxes = std::fs::read_to_string(out.join("smoothed_boxes.txt")).unwrap();
    assert_eq!(boxes.lines().count(), 12);
    // Without --smooth a rerun into the same folder leaves no stale smoothed files.
    let again = run_into(false);
    assert!(again.status.success());
    assert!(!out.join("smoothed.csv").exists() && !out.join("smoothed_boxes.txt").exists());
    // head runs on the same engine: it is smoothed too.
    let head_out = dir.path().join("head");
    let head = track(&[
        "run",
        "--smooth",
        "--quiet",
        "--init",
        DISC_INIT,
        "--out",
        s(&head_out),
        s(&frames),
    ]);
    assert!(head.status.success(), "{}", common::stderr(&head));
    let smoothed = std::fs::read_to_string(head_out.join("smoothed.csv")).unwrap();
    assert_eq!(smoothed.lines().count(), 13);
}
