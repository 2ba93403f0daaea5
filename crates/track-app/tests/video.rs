//! Video files: `track run clip.mp4` decodes the file with ffmpeg through a pipe, frame
//! size and rate from the file, ffmpeg's errors in the message, a clear error when ffmpeg is
//! missing, and no ffmpeg process left behind.
//!
//! These tests need `ffmpeg` on `PATH`. Without it they are marked ignored, with the reason, by
//! the package's build script (`build.rs` sets `cfg(ffmpeg_missing)`), so `cargo test` reports
//! them as skipped and the suite passes on a fresh machine; with `TRACK_REQUIRE_FFMPEG=1` (set by
//! CI's `.ci/run`, which installs ffmpeg) a missing ffmpeg fails them instead, so CI never skips
//! them. `TRACK_SKIP_FFMPEG_TESTS=1` skips them whatever is installed. The missing-program test
//! runs always.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{one_error_line, s, summary, track};

/// Whether the tests that need ffmpeg should run: not with `TRACK_SKIP_FFMPEG_TESTS=1`; when
/// ffmpeg is on `PATH`; and when it is not, a failure under `TRACK_REQUIRE_FFMPEG=1`, a skip
/// with a notice otherwise.
fn ffmpeg_wanted() -> bool {
    let set = |name: &str| std::env::var(name).is_ok_and(|v| v == "1");
    if set("TRACK_SKIP_FFMPEG_TESTS") {
        eprintln!("TRACK_SKIP_FFMPEG_TESTS=1: skipping a test that needs ffmpeg");
        return false;
    }
    let found = Command::new("ffmpeg")
        .arg("-version")
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(
        found || !set("TRACK_REQUIRE_FFMPEG"),
        "ffmpeg is not on PATH and TRACK_REQUIRE_FFMPEG=1: install it (apt-get install ffmpeg)"
    );
    if !found {
        eprintln!("ffmpeg is not on PATH: skipping a test that needs it (apt-get install ffmpeg)");
    }
    found
}

/// Makes `dir/name` from ffmpeg's test pattern: `frames` frames of `size` at `rate` frames/s.
fn make_video(dir: &Path, name: &str, size: &str, rate: u32, frames: usize) -> PathBuf {
    let path = dir.join(name);
    let o = Command::new("ffmpeg")
        .args(["-v", "error", "-nostdin", "-y", "-f", "lavfi", "-i"])
        .arg(format!("testsrc=size={size}:rate={rate}"))
        .args(["-frames:v", &frames.to_string(), "-pix_fmt", "yuv420p"])
        .arg(&path)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    path
}

#[test]
#[cfg_attr(
    ffmpeg_missing,
    ignore = "needs ffmpeg on PATH (apt-get install ffmpeg); skipped"
)]
fn a_video_file_is_tracked_with_size_and_rate_from_the_file() {
    if !ffmpeg_wanted() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (name, rate) in [("x.mp4", 10), ("x.avi", 25), ("x.mkv", 12)] {
        let video = make_video(dir.path(), name, "160x120", rate, 12);
        let out = dir.path().join(format!("out-{name}"));
        let o = track(&[
            "run",
            s(&video),
            "--init",
            "40,30,60,50",
            "--tracker",
            "m1",
            "--particles",
            "50",
            "--out",
            s(&out),
            "--overlay",
            "--quiet",
        ]);
        assert!(o.status.success(), "{name}: {}", common::stderr(&o));
        let v = summary(&out);
        assert_eq!(v["frames"], 12, "{name}");
        assert_eq!(
            (v["width"].as_u64(), v["height"].as_u64()),
            (Some(160), Some(120))
        );
        assert_eq!(v["frame_rate"].as_f64(), Some(f64::from(rate)), "{name}");
        assert!(out.join("overlay/0012.png").is_file());
        let csv = std::fs::read_to_string(out.join("track.csv")).unwrap();
        assert_eq!(csv.lines().count(), 13);
    }
}

#[test]
#[cfg_attr(
    ffmpeg_missing,
    ignore = "needs ffmpeg on PATH (apt-get install ffmpeg); skipped"
)]
fn a_file_ffmpeg_cannot_decode_shows_ffmpegs_error() {
    if !ffmpeg_wanted() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("broken.mp4");
    std::fs::write(&bad, b"this is not a video at all").unwrap();
    let o = track(&[
        "run",
        s(&bad),
        "--init",
        "1,1,5,5",
        "--out",
        s(&dir.path().join("o")),
    ]);
    assert_eq!(o.status.code(), Some(3));
    let e = one_error_line(&o);
    assert!(e.contains("broken.mp4") && e.contains("ffmpeg"), "{e}");
    // ffmpeg's own words: "Invalid data found when processing input".
    assert!(e.contains("Invalid data"), "{e}");
    assert!(!dir.path().join("o").exists());
}

#[test]
fn without_ffmpeg_the_error_names_the_missing_program() {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("clip.mov");
    std::fs::write(&video, b"not decoded: ffmpeg is not found first").unwrap();
    let empty = dir.path().join("empty-path");
    std::fs::create_dir(&empty).unwrap();
    let o = Command::new(common::TRACK)
        .args([
            "run",
            s(&video),
            "--init",
            "1,1,5,5",
            "--out",
            s(&dir.path().join("o")),
        ])
        .env("PATH", &empty)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3));
    let e = one_error_line(&o);
    assert!(
        e.contains("clip.mov") && e.contains("`ffmpeg`") && e.contains("PATH"),
        "{e}"
    );
}

/// Whether process `pid` exists at all (running or a zombie not yet reaped).
#[cfg(target_os = "linux")]
fn process_exists(pid: u32) -> bool {
    Path::new(&format!("/proc/{pid}")).exists()
}

#[cfg(target_os = "linux")]
#[test]
#[cfg_attr(
    ffmpeg_missing,
    ignore = "needs ffmpeg on PATH (apt-get install ffmpeg); skipped"
)]
fn dropping_a_video_source_kills_and_reaps_ffmpeg() {
    use track_app::sequence::{FrameSource, open_sequence};
    if !ffmpeg_wanted() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // Long enough that ffmpeg is still writing when the source is dropped.
    let video = make_video(dir.path(), "long.mkv", "320x240", 25, 500);
    let mut seq = open_sequence(s(&video)).unwrap();
    let pid = seq.source.stopper().and_then(|h| h.pid()).unwrap();
    assert!(seq.source.next_frame().unwrap().is_some());
    assert!(process_exists(pid));
    drop(seq);
    // Killed and reaped: not even a zombie is left.
    assert!(!process_exists(pid), "ffmpeg {pid} is still there");
}

#[cfg(target_os = "linux")]
#[test]
#[cfg_attr(
    ffmpeg_missing,
    ignore = "needs ffmpeg on PATH (apt-get install ffmpeg); skipped"
)]
fn sigterm_during_a_video_run_writes_the_frames_tracked_and_leaves_no_ffmpeg() {
    use std::time::{Duration, Instant};
    if !ffmpeg_wanted() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let video = make_video(dir.path(), "long.mp4", "320x240", 25, 600);
    let out = dir.path().join("out");
    let mut child = Command::new(common::TRACK)
        .args([
            "run",
            s(&video),
            "--init",
            "100,80,80,60",
            "--tracker",
            "m1",
            "--particles",
            "50",
            "--out",
            s(&out),
            "--overlay",
            "--quiet",
        ])
        .stdin(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !out.join("overlay/0003.png").exists() {
        assert!(child.try_wait().unwrap().is_none(), "track ended early");
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no overlay appeared"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // ffmpeg is a child of track.
    let children: Vec<u32> = std::fs::read_dir(format!("/proc/{}/task", child.id()))
        .unwrap()
        .flatten()
        .flat_map(|t| {
            std::fs::read_to_string(t.path().join("children"))
                .unwrap_or_default()
                .split_whitespace()
                .map(|p| p.parse().unwrap())
                .collect::<Vec<u32>>()
        })
        .collect();
    assert_eq!(children.len(), 1, "{children:?}");
    let ok = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok);
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(143));
    // track reaped ffmpeg before it exited: the process is gone, not an orphan still decoding.
    assert!(
        !process_exists(children[0]),
        "ffmpeg {} outlived track",
        children[0]
    );
    let v = summary(&out);
    let frames = v["frames"].as_u64().unwrap();
    assert!((3..600).contains(&frames), "{frames}");
    assert_eq!(v["interrupted"]["reason"], "SIGTERM");
    let csv = std::fs::read_to_string(out.join("track.csv")).unwrap();
    assert_eq!(csv.lines().count() as u64, frames + 1);
}

#[test]
fn ffprobe_gives_a_videos_frame_count_for_the_progress_bar() {
    if !ffmpeg_wanted() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // MP4 states the count; Matroska does not, so it comes from duration × rate.
    use track_app::sequence::FrameSource as _;
    for (name, frames) in [("count.mp4", 17), ("count.mkv", 23)] {
        let video = make_video(dir.path(), name, "64x48", 25, frames);
        let seq = track_app::sequence::open_sequence(s(&video)).unwrap();
        assert_eq!(seq.source.expected_frames(), Some(frames), "{name}");
        assert!(seq.source.is_stream());
    }
}
