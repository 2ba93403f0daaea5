//! Outputs never replace what is not a regular file, sizes that cannot fit
//! are refused before anything is allocated, a closed or full standard output is handled, a run
//! stops cleanly on a signal, and Y4M on standard input is streamed.
//!
//! These tests run the `track` binary, as a user would. Several are Unix-only (FIFOs, symbolic
//! links, signals, `/dev/full`).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

const TRACK: &str = env!("CARGO_BIN_EXE_track");

/// A `W×H` 4:2:0 Y4M of `n` frames: a bright disc of radius H/6 moving right 1 px a frame.
fn y4m(w: usize, h: usize, n: usize) -> Vec<u8> {
    let mut v = y4m_header(w, h);
    for k in 0..n {
        v.extend(y4m_frame(w, h, k));
    }
    v
}

fn y4m_header(w: usize, h: usize) -> Vec<u8> {
    format!("YUV4MPEG2 W{w} H{h} F25:1 Ip A1:1 C420jpeg\n").into_bytes()
}

fn y4m_frame(w: usize, h: usize, k: usize) -> Vec<u8> {
    let (cx, cy, r) = (
        w as f64 / 3.0 + (k % 20) as f64,
        h as f64 / 2.0,
        h as f64 / 6.0,
    );
    let mut v = b"FRAME\n".to_vec();
    for y in 0..h {
        for x in 0..w {
            let inside = (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2) < r * r;
            v.push(if inside { 200 } else { 40 });
        }
    }
    v.extend(std::iter::repeat_n(
        128u8,
        2 * w.div_ceil(2) * h.div_ceil(2),
    ));
    v
}

/// `--init` for the disc of [`y4m`] on its first frame.
fn init_box(w: usize, h: usize) -> String {
    let (cx, cy, r) = (w as f64 / 3.0, h as f64 / 2.0, h as f64 / 6.0);
    format!("{},{},{},{}", cx - r, cy - r, 2.0 * r, 2.0 * r)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn track(args: &[&str]) -> Output {
    Command::new(TRACK)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// One line on standard error, starting with `error:`, no panic and no backtrace.
fn assert_one_error_line(o: &Output) {
    let e = stderr(o);
    assert!(e.starts_with("error: ") && e.lines().count() == 1, "{e:?}");
    assert!(
        !e.contains("panicked") && !e.contains("RUST_BACKTRACE"),
        "{e}"
    );
}

/// Every file under `dir` whose name looks like a temporary output.
fn temporaries(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return found;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            found.extend(temporaries(&p));
        } else if p
            .file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.ends_with(track_app::output::TEMP_SUFFIX) || n.ends_with(".tmp"))
        {
            found.push(p);
        }
    }
    found
}

/// Waits until `path` exists (or `child` exits, or 60 s pass).
fn wait_for(path: &Path, child: &mut Child) {
    let start = Instant::now();
    while !path.exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "track exited before writing {}",
            path.display()
        );
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "{} never appeared",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Waits for `child` to exit, at most 30 s.
fn wait_exit(child: &mut Child) -> std::process::ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if start.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("track did not exit");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// track.csv, boxes.txt and summary.json agree on the number of frames; returns it.
fn consistent_frame_count(out: &Path) -> usize {
    let csv = std::fs::read_to_string(out.join("track.csv")).unwrap();
    let boxes = std::fs::read_to_string(out.join("boxes.txt")).unwrap();
    let frames = summary(out)["frames"].as_u64().unwrap() as usize;
    assert!(csv.ends_with('\n') && boxes.ends_with('\n'));
    assert_eq!(csv.lines().count(), frames + 1, "track.csv rows");
    assert_eq!(boxes.lines().count(), frames, "boxes.txt lines");
    frames
}

fn kill(child: &Child, signal: &str) {
    let ok = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok);
}

// ---------------------------------------------------------------------------------------------
// 1. Outputs never replace what is not a regular file.

#[cfg(unix)]
#[test]
fn learn_clutter_out_refuses_fifo_symlink_and_folder() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("bg.png");
    image::GrayImage::from_fn(120, 90, |x, y| {
        image::Luma([if (x / 3 + y / 5) % 2 == 0 { 30 } else { 220 }])
    })
    .save(&png)
    .unwrap();
    let fifo = dir.path().join("fifo.json");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let target = dir.path().join("target.json");
    std::fs::write(&target, "precious").unwrap();
    let link = dir.path().join("link.json");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let folder = dir.path().join("folder.json");
    std::fs::create_dir(&folder).unwrap();
    for (out, what) in [
        (&fifo, "FIFO"),
        (&link, "symbolic link"),
        (&folder, "folder"),
    ] {
        let o = track(&["learn-clutter", s(&png), "--lines", "200", "--out", s(out)]);
        assert_eq!(o.status.code(), Some(4), "{what}: {}", stderr(&o));
        assert_one_error_line(&o);
        assert!(stderr(&o).contains(what), "{}", stderr(&o));
    }
    use std::os::unix::fs::FileTypeExt;
    assert!(
        std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo()
    );
    assert!(std::fs::symlink_metadata(&link).unwrap().is_symlink());
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "precious");
    assert!(folder.is_dir());
    assert!(temporaries(dir.path()).is_empty());
    // A regular file of the user's is refused too (the output guard); one track wrote is
    // replaced.
    let file = dir.path().join("model.json");
    std::fs::write(&file, "old").unwrap();
    let learn = || {
        track(&[
            "learn-clutter",
            s(&png),
            "--lines",
            "200",
            "--out",
            s(&file),
        ])
    };
    let o = learn();
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "old");
    std::fs::remove_file(&file).unwrap();
    for _ in 0..2 {
        let o = learn();
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(std::fs::read_to_string(&file).unwrap().contains("clusters"));
    }
}

#[cfg(unix)]
#[test]
fn run_refuses_an_output_name_taken_by_a_fifo_or_symlink_before_tracking() {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("v.y4m");
    std::fs::write(&video, y4m(64, 48, 5)).unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let fifo = out.join("track.csv");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let o = track(&[
        "run",
        s(&video),
        "--init",
        &init_box(64, 48),
        "--out",
        s(&out),
        "--overlay",
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    assert_one_error_line(&o);
    assert!(stderr(&o).contains("track.csv") && stderr(&o).contains("FIFO"));
    // Found before tracking: no overlay was written.
    assert!(!out.join("overlay").exists());
    std::fs::remove_file(&fifo).unwrap();
    let elsewhere = dir.path().join("elsewhere.json");
    std::fs::write(&elsewhere, "keep").unwrap();
    std::os::unix::fs::symlink(&elsewhere, out.join("summary.json")).unwrap();
    let o = track(&[
        "run",
        s(&video),
        "--init",
        &init_box(64, 48),
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    assert!(stderr(&o).contains("symbolic link"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&elsewhere).unwrap(), "keep");
    assert!(temporaries(dir.path()).is_empty());
}

// ---------------------------------------------------------------------------------------------
// 2. Sizes that cannot fit.

#[test]
fn y4m_header_claiming_a_huge_frame_is_refused_from_file_and_stdin() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = b"YUV4MPEG2 W4000000 H4000000 F25:1 C420jpeg\nFRAME\n".to_vec();
    bytes.extend([0u8; 4600]);
    let video = dir.path().join("huge.y4m");
    std::fs::write(&video, &bytes).unwrap();
    let out = dir.path().join("out");
    let o = track(&[
        "run",
        s(&video),
        "--init",
        "1,1,5,5",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert_one_error_line(&o);
    assert!(stderr(&o).contains("huge.y4m") && stderr(&o).contains("too large"));
    let mut child = Command::new(TRACK)
        .args(["run", "-", "--init", "1,1,5,5", "--out", s(&out), "--quiet"])
        .stdin(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The header alone must be enough to refuse it: the rest of the input never comes.
    let mut stdin = child.stdin.take().unwrap();
    stdin.write_all(&bytes[..44]).unwrap();
    let o = {
        let status = wait_exit(&mut child);
        drop(stdin);
        let mut err = String::new();
        std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
        (status, err)
    };
    assert_eq!(o.0.code(), Some(3), "{}", o.1);
    assert!(
        o.1.starts_with("error: -: Y4M frame size 4000000×4000000 is too large"),
        "{}",
        o.1
    );
    assert!(!out.exists());
}

#[test]
fn learn_clutter_huge_line_counts_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("bg.png");
    image::GrayImage::new(64, 64).save(&png).unwrap();
    for lines in ["10000000000", "18446744073709551615", "10000001"] {
        let o = track(&["learn-clutter", s(&png), "--lines", lines]);
        assert_eq!(o.status.code(), Some(2), "{lines}: {}", stderr(&o));
        assert_one_error_line(&o);
        assert!(stderr(&o).contains("--lines") && stderr(&o).contains("maximum"));
    }
    let o = track(&["learn-clutter", s(&png), "--k", "1000000000"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--k"), "{}", stderr(&o));
}

/// A configuration with one value edited.
fn config_with(dir: &Path, key: &str, value: serde_json::Value) -> PathBuf {
    let o = track(&["config", "full"]);
    let mut c: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mut node = &mut c;
    for k in key.split('.') {
        node = &mut node[k];
    }
    *node = value;
    let path = dir.join(format!("{key}.json"));
    std::fs::write(&path, c.to_string()).unwrap();
    path
}

#[test]
fn huge_tracker_settings_are_refused_before_allocation() {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("v.y4m");
    std::fs::write(&video, y4m(64, 48, 3)).unwrap();
    let init = init_box(64, 48);
    let out = dir.path().join("out");
    let big = serde_json::json!(1_000_000_000u64);
    let mut cases: Vec<Vec<String>> = vec![vec!["--particles".into(), "1000000000".into()]];
    for key in [
        "particles",
        "filter.output_size",
        "likelihood.clutter.lines.n_lines",
        "motion.cluster_iterations",
    ] {
        let c = config_with(dir.path(), key, big.clone());
        cases.push(vec!["--config".into(), s(&c).into()]);
    }
    for extra in cases {
        let mut args = vec![
            "run",
            s(&video),
            "--init",
            &init,
            "--out",
            s(&out),
            "--quiet",
        ];
        args.extend(extra.iter().map(String::as_str));
        let o = track(&args);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", stderr(&o));
        assert_one_error_line(&o);
        assert!(!out.exists());
    }
}

// ---------------------------------------------------------------------------------------------
// 3. Standard output closed or full.

/// Runs `track args` with its standard output's reading end closed at once.
fn with_closed_stdout(args: &[&str]) -> Output {
    let mut child = Command::new(TRACK)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    child.wait_with_output().unwrap()
}

/// The commands that print, each with its arguments (files made in `dir`).
fn printing_commands(dir: &Path) -> Vec<Vec<String>> {
    let video = dir.join("v.y4m");
    std::fs::write(&video, y4m(64, 48, 4)).unwrap();
    let f0 = dir.join("f0.png");
    let f1 = dir.join("f1.png");
    let frame = |dx: u32| {
        image::GrayImage::from_fn(64, 48, move |x, y| {
            image::Luma([((x + dx) * 7 % 256) as u8 ^ (y * 13 % 256) as u8])
        })
    };
    frame(0).save(&f0).unwrap();
    frame(1).save(&f1).unwrap();
    let p = |p: &Path| p.to_str().unwrap().to_owned();
    let v = |a: &[&str]| a.iter().map(|s| (*s).to_owned()).collect::<Vec<_>>();
    vec![
        // Help and version go to standard output like everything else.
        v(&["--help"]),
        v(&["run", "--help"]),
        v(&["--version"]),
        v(&["config", "full"]),
        v(&["config", "w-eval", "--toml"]),
        vec![
            "motion".into(),
            p(&f0),
            p(&f1),
            "--json".into(),
            "--model".into(),
            "translation".into(),
        ],
        vec![
            "learn-clutter".into(),
            p(&f0),
            "--lines".into(),
            "200".into(),
        ],
        vec![
            "run".into(),
            p(&video),
            "--init".into(),
            init_box(64, 48),
            "--out".into(),
            p(&dir.join("run-out")),
            "--particles".into(),
            "50".into(),
        ],
    ]
}

#[test]
fn closed_stdout_ends_quietly() {
    let dir = tempfile::tempdir().unwrap();
    for args in printing_commands(dir.path()) {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = with_closed_stdout(&args);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", stderr(&o));
        assert!(o.stderr.is_empty(), "{args:?}: {}", stderr(&o));
    }
}

#[cfg(target_os = "linux")]
#[test]
fn full_stdout_is_exit_4_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    for args in printing_commands(dir.path()) {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = Command::new(TRACK)
            .args(&args)
            .stdin(Stdio::null())
            .stdout(std::fs::File::create("/dev/full").unwrap())
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(4), "{args:?}: {}", stderr(&o));
        assert_one_error_line(&o);
        assert!(stderr(&o).contains("standard output"), "{}", stderr(&o));
    }
}

#[cfg(target_os = "linux")]
#[test]
fn eval_with_closed_or_full_stdout() {
    let args = ["eval", "switching", "--frames", "12", "--particles", "20"];
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("eval");
    let mut a = args.to_vec();
    a.extend(["--out", s(&out)]);
    let o = with_closed_stdout(&a);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = Command::new(TRACK)
        .args(&a)
        .stdout(std::fs::File::create("/dev/full").unwrap())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
}

// ---------------------------------------------------------------------------------------------
// 4. Interrupts, earlier runs, unwritable --out.

#[cfg(unix)]
#[test]
fn sigterm_during_run_writes_the_frames_tracked_and_no_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("long.y4m");
    std::fs::write(&video, y4m(96, 72, 3000)).unwrap();
    let out = dir.path().join("out");
    let mut child = Command::new(TRACK)
        .args([
            "run",
            s(&video),
            "--init",
            &init_box(96, 72),
            "--out",
            s(&out),
            "--overlay",
            "--gif",
            "--report",
            "--particles",
            "400",
            "--quiet",
        ])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for(&out.join("overlay/0008.png"), &mut child);
    kill(&child, "-TERM");
    let status = wait_exit(&mut child);
    assert_eq!(status.code(), Some(143));
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    assert!(
        err.starts_with("error: interrupted by SIGTERM after"),
        "{err}"
    );
    let frames = consistent_frame_count(&out);
    assert!((8..3000).contains(&frames), "{frames}");
    let s = summary(&out);
    assert_eq!(s["interrupted"]["reason"], "SIGTERM");
    assert!(s["interrupted"]["frames_read"].as_u64().unwrap() >= frames as u64);
    for f in ["track.gif", "report.html"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // Every overlay written belongs to a tracked frame.
    assert_eq!(
        std::fs::read_dir(out.join("overlay")).unwrap().count(),
        frames
    );
    assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
}

#[cfg(unix)]
#[test]
fn sigint_while_waiting_for_standard_input_stops_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut child = Command::new(TRACK)
        .args([
            "run",
            "-",
            "--init",
            &init_box(64, 48),
            "--out",
            s(&out),
            "--overlay",
            "--quiet",
        ])
        .stdin(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    stdin.write_all(&y4m(64, 48, 6)).unwrap();
    stdin.flush().unwrap();
    wait_for(&out.join("overlay/0006.png"), &mut child);
    // The writer stays open and silent: track is blocked waiting for a seventh frame.
    kill(&child, "-INT");
    let status = wait_exit(&mut child);
    drop(stdin);
    assert_eq!(status.code(), Some(130));
    assert_eq!(consistent_frame_count(&out), 6);
    assert_eq!(summary(&out)["interrupted"]["reason"], "SIGINT");
    assert!(temporaries(&out).is_empty());
}

#[test]
fn a_new_run_leaves_nothing_of_the_previous_one() {
    let dir = tempfile::tempdir().unwrap();
    let long = dir.path().join("long.y4m");
    std::fs::write(&long, y4m(64, 48, 12)).unwrap();
    let short = dir.path().join("short.y4m");
    std::fs::write(&short, y4m(64, 48, 4)).unwrap();
    let out = dir.path().join("out");
    let init = init_box(64, 48);
    let o = track(&[
        "run",
        s(&long),
        "--init",
        &init,
        "--out",
        s(&out),
        "--overlay",
        "--gif",
        "--plots",
        "--report",
        "--particles",
        "50",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_dir(out.join("overlay")).unwrap().count(), 12);
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    std::fs::write(out.join("overlay/logo.png"), "mine").unwrap();
    let o = track(&[
        "run",
        s(&short),
        "--init",
        &init,
        "--out",
        s(&out),
        "--particles",
        "50",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(consistent_frame_count(&out), 4);
    for gone in [
        "track.gif",
        "report.html",
        "overlay/0001.png",
        "overlay/0012.png",
    ] {
        assert!(
            !out.join(gone).exists(),
            "{gone} of the previous run is still there"
        );
    }
    assert_eq!(std::fs::read_dir(out.join("plots")).unwrap().count(), 0);
    // Files that are not the run's are kept.
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
    assert!(out.join("overlay/logo.png").exists());
    let outputs = summary(&out)["outputs"].clone();
    assert_eq!(
        outputs,
        serde_json::json!(["track.csv", "boxes.txt", "summary.json"])
    );
}

#[test]
fn an_unwritable_out_is_found_before_tracking() {
    let dir = tempfile::tempdir().unwrap();
    let video = dir.path().join("v.y4m");
    std::fs::write(&video, y4m(64, 48, 3)).unwrap();
    let file = dir.path().join("a-file");
    std::fs::write(&file, "x").unwrap();
    for out in [file.clone(), file.join("sub")] {
        let o = track(&[
            "run",
            s(&video),
            "--init",
            &init_box(64, 48),
            "--out",
            s(&out),
            "--particles",
            "20000",
            "--quiet",
        ]);
        assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
        assert_one_error_line(&o);
        assert!(stderr(&o).contains("a-file"), "{}", stderr(&o));
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
}

// ---------------------------------------------------------------------------------------------
// 5. Y4M on standard input is streamed.

/// Peak resident memory of a process, kB (Linux).
#[cfg(target_os = "linux")]
fn peak_rss_kb(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap()
}

#[cfg(target_os = "linux")]
#[test]
fn stdin_is_tracked_as_it_arrives_in_constant_memory() {
    let (w, h) = (320, 240);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut child = Command::new(TRACK)
        .args([
            "run",
            "-",
            "--init",
            &init_box(w, h),
            "--out",
            s(&out),
            "--overlay",
            "--particles",
            "50",
            "--tracker",
            "m1",
            "--quiet",
        ])
        .stdin(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    stdin.write_all(&y4m_header(w, h)).unwrap();
    for k in 0..20 {
        stdin.write_all(&y4m_frame(w, h, k)).unwrap();
    }
    stdin.flush().unwrap();
    // Overlays appear while the input is still open: nothing waits for the end of input.
    wait_for(&out.join("overlay/0020.png"), &mut child);
    let early = peak_rss_kb(child.id());
    // 400 more frames: 46 MB of input, which a buffering reader would hold.
    for k in 20..420 {
        stdin.write_all(&y4m_frame(w, h, k)).unwrap();
    }
    stdin.flush().unwrap();
    wait_for(&out.join("overlay/0420.png"), &mut child);
    let late = peak_rss_kb(child.id());
    drop(stdin);
    let status = wait_exit(&mut child);
    assert!(status.success());
    assert_eq!(consistent_frame_count(&out), 420);
    assert!(summary(&out).get("interrupted").is_none());
    // Constant memory: the peak grows by less than a fifth of the input read since.
    assert!(
        late < early + 9_000,
        "peak RSS {early} kB after 20 frames, {late} kB after 420"
    );
}

#[test]
fn a_stream_cut_mid_frame_keeps_the_frames_tracked() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut bytes = y4m(64, 48, 7);
    bytes.truncate(bytes.len() - 100);
    let mut child = Command::new(TRACK)
        .args([
            "run",
            "-",
            "--init",
            &init_box(64, 48),
            "--out",
            s(&out),
            "--quiet",
        ])
        .stdin(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(&bytes).unwrap();
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert_one_error_line(&o);
    assert!(
        stderr(&o).contains("truncated Y4M: frame 7"),
        "{}",
        stderr(&o)
    );
    assert_eq!(consistent_frame_count(&out), 6);
    let reason = summary(&out)["interrupted"]["reason"]
        .as_str()
        .unwrap()
        .to_owned();
    assert!(reason.contains("truncated"), "{reason}");
}
