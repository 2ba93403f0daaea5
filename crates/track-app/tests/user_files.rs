//! `track` never deletes or overwrites a file it did not write: links in
//! the output folder, an output folder that holds the input, two runs into one folder, the
//! temporaries of a killed run, and a signal before tracking begins. These run the binary, as a
//! user would.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::{self, DISC_INIT, TRACK, disc_frames, one_error_line, s, track};

/// A folder of the user's with digit-named PNGs and SVGs that `track` must never touch.
fn photos(dir: &Path) -> PathBuf {
    let photos = dir.join("photos");
    std::fs::create_dir_all(&photos).unwrap();
    for name in ["0001.png", "0002.png", "holiday.svg"] {
        std::fs::write(photos.join(name), name.as_bytes()).unwrap();
    }
    photos
}

/// The user's files of [`photos`] are all there, unchanged, and nothing was added.
fn assert_photos_intact(photos: &Path) {
    let mut names: Vec<String> = std::fs::read_dir(photos)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["0001.png", "0002.png", "holiday.svg"]);
    for name in names {
        assert_eq!(std::fs::read(photos.join(&name)).unwrap(), name.as_bytes());
    }
}

/// `track run FRAMES --init DISC_INIT --out OUT --quiet EXTRA...` (the default tracker).
fn run_disc(frames: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "run",
        s(frames),
        "--init",
        DISC_INIT,
        "--out",
        s(out),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    track(&args)
}

/// Every file below `dir` whose name marks it as a temporary output.
fn temporaries(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            found.extend(temporaries(&p));
        } else if p
            .to_string_lossy()
            .ends_with(track_app::output::TEMP_SUFFIX)
        {
            found.push(p);
        }
    }
    found
}

fn wait_exit(child: &mut Child) -> std::process::ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("track did not exit");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Waits until `ready()` holds while `child` runs.
fn wait_until(child: &mut Child, what: &str, ready: impl Fn() -> bool) {
    let start = Instant::now();
    while !ready() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "track exited before {what}"
        );
        assert!(start.elapsed() < Duration::from_secs(60), "never: {what}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[cfg(unix)]
#[test]
fn a_linked_overlay_folder_is_never_emptied() {
    let dir = tempfile::tempdir().unwrap();
    let photos = photos(dir.path());
    let frames = disc_frames(dir.path(), "frames", 3);
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink(&photos, out.join("overlay")).unwrap();
    let run = |extra: &[&str]| run_disc(&frames, &out, &[&["--tracker", "m1"], extra].concat());
    // Without --overlay the link is not used: the run succeeds and leaves it alone.
    let o = run(&[]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert_photos_intact(&photos);
    // Run again (so there is an earlier run to clean up), then with --overlay: refused, exit 4,
    // naming the link, before any tracking.
    let o = run(&[]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let o = run(&["--overlay"]);
    assert_eq!(o.status.code(), Some(4));
    let e = one_error_line(&o);
    assert!(e.contains("overlay") && e.contains("symbolic link"), "{e}");
    assert_photos_intact(&photos);
}

#[cfg(unix)]
#[test]
fn a_linked_plots_folder_is_refused_and_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    let photos = photos(dir.path());
    let frames = disc_frames(dir.path(), "frames", 3);
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink(&photos, out.join("plots")).unwrap();
    let o = track(&[
        "run",
        s(&frames),
        "--init",
        DISC_INIT,
        "--tracker",
        "w-eval",
        "--plots",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(4));
    let e = one_error_line(&o);
    assert!(e.contains("plots") && e.contains("symbolic link"), "{e}");
    assert_photos_intact(&photos);
    assert!(!out.join("track.csv").exists());
}

#[test]
fn an_output_folder_holding_the_input_is_refused_and_the_input_kept() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let frames = disc_frames(&out, "overlay", 4);
    let before: Vec<Vec<u8>> = (1..=4)
        .map(|k| std::fs::read(frames.join(format!("{k:04}.png"))).unwrap())
        .collect();
    let o = track(&[
        "run",
        s(&frames),
        "--init",
        DISC_INIT,
        "--tracker",
        "m1",
        "--overlay",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(4));
    let e = one_error_line(&o);
    assert!(e.contains("contains the input"), "{e}");
    for (k, bytes) in before.iter().enumerate() {
        let now = std::fs::read(frames.join(format!("{:04}.png", k + 1))).unwrap();
        assert_eq!(&now, bytes, "frame {} changed", k + 1);
    }
}

#[cfg(unix)]
#[test]
fn an_output_folder_that_is_a_link_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "frames", 2);
    let real = dir.path().join("real");
    std::fs::create_dir(&real).unwrap();
    let link = dir.path().join("link");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    let o = track(&["run", s(&frames), "--init", DISC_INIT, "--out", s(&link)]);
    assert_eq!(o.status.code(), Some(4));
    let e = one_error_line(&o);
    assert!(e.contains("symbolic link"), "{e}");
    assert_eq!(std::fs::read_dir(&real).unwrap().count(), 0);
}

#[test]
fn a_file_of_the_users_named_like_an_output_is_refused_not_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "frames", 2);
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("boxes.txt"), "my own boxes").unwrap();
    let o = run_disc(&frames, &out, &[]);
    assert_eq!(o.status.code(), Some(4));
    let e = one_error_line(&o);
    assert!(
        e.contains("boxes.txt") && e.contains("not written by track"),
        "{e}"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("boxes.txt")).unwrap(),
        "my own boxes"
    );
    // A file of the user's beside the outputs survives every later run.
    std::fs::rename(out.join("boxes.txt"), out.join("notes.txt")).unwrap();
    for _ in 0..2 {
        let o = run_disc(&frames, &out, &[]);
        assert!(o.status.success(), "{}", common::stderr(&o));
    }
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "my own boxes"
    );
    assert!(out.join("boxes.txt").is_file());
}

/// A run that reads Y4M from a pipe the test holds open, so that it waits, holding its folder.
#[cfg(unix)]
fn waiting_run(out: &Path) -> (Child, std::process::ChildStdin) {
    use std::io::Write;
    let mut child = Command::new(TRACK)
        .args([
            "run",
            "-",
            "--init",
            "18,24,24,24",
            "--tracker",
            "m1",
            "--out",
            s(out),
        ])
        .args(["--quiet"])
        .stdin(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let mut header = b"YUV4MPEG2 W96 H72 F25:1 C420jpeg\nFRAME\n".to_vec();
    header.extend(std::iter::repeat_n(60u8, 96 * 72 + 2 * 48 * 36));
    stdin.write_all(&header).unwrap();
    stdin.flush().unwrap();
    (child, stdin)
}

#[cfg(unix)]
#[test]
fn two_runs_into_one_folder_at_once_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "frames", 2);
    let out = dir.path().join("out");
    let (mut first, stdin) = waiting_run(&out);
    let manifest = out.join(track_app::output::MANIFEST_NAME);
    wait_until(&mut first, "the first run holds the folder", || {
        manifest.exists()
    });
    let o = run_disc(&frames, &out, &[]);
    assert_eq!(o.status.code(), Some(4));
    let e = one_error_line(&o);
    assert!(e.contains("in use by another track command"), "{e}");
    // The first run finishes as if alone: one frame, its own summary.
    drop(stdin);
    assert!(wait_exit(&mut first).success());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["frames"], 1);
    // Free again once it has finished.
    let o = run_disc(&frames, &out, &[]);
    assert!(o.status.success(), "{}", common::stderr(&o));
}

#[cfg(unix)]
#[test]
fn the_temporaries_of_a_killed_run_are_removed_by_the_next() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "frames", 3);
    let out = dir.path().join("out");
    // SIGKILL at any moment of a run that writes overlays; whatever it leaves, the next run
    // into the folder removes, and leaves its own complete outputs only.
    for delay_ms in [0u64, 40, 120] {
        let (mut child, stdin) = waiting_run(&out);
        let manifest = out.join(track_app::output::MANIFEST_NAME);
        wait_until(&mut child, "the run holds the folder", || manifest.exists());
        std::thread::sleep(Duration::from_millis(delay_ms));
        child.kill().unwrap();
        wait_exit(&mut child);
        drop(stdin);
        // What a SIGKILL during a write leaves behind, recorded as the run records it.
        let stray = out.join(format!(
            ".summary.json.xyz{}",
            track_app::output::TEMP_SUFFIX
        ));
        std::fs::write(&stray, "half").unwrap();
        let mut m = std::fs::OpenOptions::new()
            .append(true)
            .open(&manifest)
            .unwrap();
        std::io::Write::write_all(&mut m, b"summary.json\n").unwrap();
        let o = run_disc(&frames, &out, &["--overlay"]);
        assert!(o.status.success(), "{}", common::stderr(&o));
        assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
        assert!(out.join("summary.json").is_file());
    }
}

#[cfg(target_os = "linux")]
#[test]
fn a_signal_during_the_folder_check_ends_the_run_with_a_message() {
    // A folder of frames large enough that the pre-scan (every frame decoded before tracking)
    // takes a while; the signal is sent once the scan is seen reading the folder.
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    let noise = image::RgbImage::from_fn(1200, 900, |x, y| {
        let mut h = x.wrapping_mul(73_856_093) ^ y.wrapping_mul(19_349_663);
        h ^= h >> 13;
        h = h.wrapping_mul(0x5bd1_e995);
        h ^= h >> 15;
        let [a, b, c, _] = h.to_le_bytes();
        image::Rgb([a, b, c])
    });
    noise.save(frames.join("0001.png")).unwrap();
    let frame_bytes = std::fs::metadata(frames.join("0001.png")).unwrap().len();
    for k in 2..=400 {
        std::fs::hard_link(frames.join("0001.png"), frames.join(format!("{k:04}.png"))).unwrap();
    }
    let out = dir.path().join("out");
    let mut child = Command::new(TRACK)
        .args([
            "run",
            s(&frames),
            "--init",
            "100,100,200,200",
            "--out",
            s(&out),
        ])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The bytes the process has read (`rchar` of /proc/PID/io): past two frames, the scan is
    // under way.
    let io = PathBuf::from(format!("/proc/{}/io", child.id()));
    let read_bytes = || -> u64 {
        let text = std::fs::read_to_string(&io).unwrap_or_default();
        text.lines()
            .find_map(|l| l.strip_prefix("rchar: "))
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or(0)
    };
    wait_until(&mut child, "the pre-scan reads two frames", || {
        read_bytes() > 2 * frame_bytes
    });
    let ok = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok);
    let status = wait_exit(&mut child);
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    assert_eq!(status.code(), Some(143), "{err}");
    assert!(
        err.starts_with("error: interrupted by SIGTERM before tracking began")
            && err.lines().count() == 1,
        "{err}"
    );
    assert!(!out.exists(), "nothing is written");
}
