//! Bad inputs that used to lose data, give wrong results or unclear errors: outputs onto or into
//! an input, mixed grey and colour frames, a broken frame link, macOS metadata files, a paired
//! test without variation, textureless motion, a file given for an OTB folder, a missing results
//! folder, a refused output that left files behind, and `--smooth` for head.

use crate::common;

use std::path::{Path, PathBuf};

use common::{DISC_INIT, disc_frames, one_error_line, paired, s, stderr, stdout, track};

/// An OTB folder `dir/name` of `n` disc frames with a box on every line.
fn otb_folder(dir: &Path, name: &str, n: usize) -> PathBuf {
    let seq = dir.join(name);
    disc_frames(&seq, "img", n);
    let lines: Vec<String> = (0..n).map(|k| format!("{},24,24,24", 18 + 2 * k)).collect();
    std::fs::write(seq.join("groundtruth_rect.txt"), lines.join("\n") + "\n").unwrap();
    seq
}

/// Every file below `dir` with its bytes.
fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if std::fs::symlink_metadata(&p).unwrap().is_dir() {
                stack.push(p);
            } else {
                out.push((p.clone(), std::fs::read(&p).unwrap_or_default()));
            }
        }
    }
    out.sort();
    out
}

/// An `eval otb` results folder with one `ope/otb.csv`: sequence `seq`, tracker `head`, the
/// success AUC `auc` over `frames` frames.
fn results(dir: &Path, name: &str, auc: f64, frames: usize) -> PathBuf {
    let out = dir.join(name);
    std::fs::create_dir_all(out.join("ope")).unwrap();
    let csv = format!(
        "protocol,sequence,tracker,runs,frames,labelled,success_auc,precision_20,mean_iou,fps,lost_auc\n\
         ope,seq,head,1,{frames},{frames},{auc:.4},0.5,0.5,,\n\
         ope,mean,head,1,{frames},{frames},{auc:.4},0.5,0.5,,\n"
    );
    std::fs::write(out.join("ope/otb.csv"), csv).unwrap();
    out
}

/// `track run INPUT [EXTRA…] --tracker m1 --particles 20 --out OUT --quiet`: a quick run.
fn run_m1(input: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["run", s(input)];
    args.extend_from_slice(extra);
    args.extend([
        "--tracker",
        "m1",
        "--particles",
        "20",
        "--out",
        s(out),
        "--quiet",
    ]);
    track(&args)
}

#[test]
fn a_paired_report_never_replaces_a_file_of_the_users() {
    let dir = tempfile::tempdir().unwrap();
    let b: Vec<PathBuf> = (1..=2)
        .map(|k| results(dir.path(), &format!("b{k}"), 0.5 + 0.01 * k as f64, 20))
        .collect();
    let v: Vec<PathBuf> = (1..=2)
        .map(|k| results(dir.path(), &format!("v{k}"), 0.4 + 0.02 * k as f64, 20))
        .collect();
    let (b, v): (Vec<&Path>, Vec<&Path>) = (
        b.iter().map(PathBuf::as_path).collect(),
        v.iter().map(PathBuf::as_path).collect(),
    );
    let notes = dir.path().join("notes.md");
    std::fs::write(&notes, "my notes").unwrap();
    let mut perms = std::fs::metadata(&notes).unwrap().permissions();
    perms.set_readonly(true);
    std::fs::set_permissions(&notes, perms).unwrap();
    let o = paired(&b, &v, &["--out", s(&notes)]);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    assert!(one_error_line(&o).contains("not written by track"));
    assert_eq!(std::fs::read_to_string(&notes).unwrap(), "my notes");
    // Its own report, written once, it replaces.
    let report = dir.path().join("report.md");
    for _ in 0..2 {
        let o = paired(&b, &v, &["--out", s(&report)]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    assert!(std::fs::read_to_string(&report).unwrap().contains("helps"));
}

#[test]
fn a_paired_report_is_never_written_over_its_input() {
    let dir = tempfile::tempdir().unwrap();
    let b1 = results(dir.path(), "b1", 0.5, 20);
    let b2 = results(dir.path(), "b2", 0.52, 20);
    let v1 = results(dir.path(), "v1", 0.6, 20);
    let v2 = results(dir.path(), "v2", 0.61, 20);
    let before = files(&b1);
    let target = b1.join("ope/otb.csv");
    let o = paired(&[&b1, &b2], &[&v1, &v2], &["--out", s(&target)]);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    assert!(one_error_line(&o).contains("input"), "{}", stderr(&o));
    assert_eq!(files(&b1), before);
    // And the input still reads.
    let o = paired(&[&b1, &b2], &[&v1, &v2], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn a_run_refuses_an_output_folder_inside_its_sequence() {
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(dir.path(), "seq", 4);
    let before = files(&seq);
    let img = seq.join("img");
    let o = run_m1(&seq, &img, &["--gif"]);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    assert!(one_error_line(&o).contains("inside the input folder"));
    assert_eq!(files(&seq), before);
    // The sequence still runs.
    let out = dir.path().join("out");
    let o = run_m1(&seq, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A `w`×`h` colour frame: a saturated red disc at (30, 40) over a blue-green gradient.
fn colour_frame(w: u32, h: u32) -> image::RgbImage {
    image::RgbImage::from_fn(w, h, |x, y| {
        let d = (f64::from(x) - 30.0).hypot(f64::from(y) - 40.0);
        if d < 15.0 {
            image::Rgb([210, 120, 90])
        } else {
            image::Rgb([30, (60 + x % 50) as u8, (90 + y % 70) as u8])
        }
    })
}

#[test]
fn a_grey_frame_among_colour_frames_is_an_error_naming_it_not_a_lost_target() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    let colour = colour_frame(96, 80);
    let grey = image::DynamicImage::ImageRgb8(colour.clone()).to_luma8();
    colour.save(frames.join("0001.png")).unwrap();
    colour.save(frames.join("0002.png")).unwrap();
    grey.save(frames.join("0003.png")).unwrap();
    colour.save(frames.join("0004.png")).unwrap();
    let out = dir.path().join("out");
    let o = track(&[
        "run",
        s(&frames),
        "--init",
        "15,25,30,30",
        "--tracker",
        "head",
        "--particles",
        "60",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let e = one_error_line(&o);
    assert!(e.contains("0003.png") && e.contains("grey frame"), "{e}");
}

#[cfg(unix)]
#[test]
fn a_broken_frame_link_is_an_error_and_macos_metadata_is_not_a_frame() {
    let dir = tempfile::tempdir().unwrap();
    let frames = disc_frames(dir.path(), "frames", 4);
    // macOS's AppleDouble file beside a frame: not an image at all.
    std::fs::write(frames.join("._0001.png"), b"\x00\x05\x16\x07 metadata").unwrap();
    let out = dir.path().join("out");
    let o = run_m1(&frames, &out, &["--init", DISC_INIT]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("track.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 4, "{csv}");
    // A link to nothing, named as a frame: an error naming it (exit 3), as a 0-byte frame is.
    std::os::unix::fs::symlink(dir.path().join("gone.png"), frames.join("0003b.png")).unwrap();
    let o = run_m1(&frames, &out, &["--init", DISC_INIT]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let e = one_error_line(&o);
    assert!(
        e.contains("0003b.png") && e.contains("symbolic link"),
        "{e}"
    );
}

#[test]
fn a_paired_test_without_variation_or_on_different_frames_says_so() {
    let dir = tempfile::tempdir().unwrap();
    // The same difference on every seed: no noise to judge it by.
    let b1 = results(dir.path(), "b1", 0.5, 20);
    let b2 = results(dir.path(), "b2", 0.6, 20);
    let v1 = results(dir.path(), "v1", 0.45, 20);
    let v2 = results(dir.path(), "v2", 0.55, 20);
    let o = paired(&[&b1, &b2], &[&v1, &v2], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(!text.contains("inf"), "{text}");
    let row = text.lines().find(|l| l.starts_with("| seq ")).unwrap();
    assert!(
        row.contains("untestable") && !row.contains("hurts"),
        "{row}"
    );
    // Scored on 20 frames against 10: not comparable.
    let v3 = results(dir.path(), "v3", 0.45, 10);
    let v4 = results(dir.path(), "v4", 0.50, 10);
    let o = paired(&[&b1, &b2], &[&v3, &v4], &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = one_error_line(&o);
    assert!(e.contains("20 frames") && e.contains("on 10"), "{e}");
}

#[test]
fn a_missing_results_folder_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let b1 = results(dir.path(), "b1", 0.5, 20);
    let v1 = results(dir.path(), "v1", 0.45, 20);
    let v2 = results(dir.path(), "v2", 0.55, 20);
    let missing = dir.path().join("does-not-exist");
    let o = paired(&[&b1, &missing], &[&v1, &v2], &[]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let e = one_error_line(&o);
    assert!(
        e.contains("does-not-exist") && e.contains("no such folder"),
        "{e}"
    );
    // A folder without the protocol the others have is named too.
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let o = paired(&[&b1, &empty], &[&v1, &v2], &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = one_error_line(&o);
    assert!(e.contains("empty") && e.contains("ope/otb.csv"), "{e}");
}

#[test]
fn motion_json_on_textureless_frames_is_the_failure_object() {
    let dir = tempfile::tempdir().unwrap();
    let flat = dir.path().join("c.png");
    image::GrayImage::from_pixel(64, 48, image::Luma([128]))
        .save(&flat)
        .unwrap();
    let o = track(&["motion", s(&flat), s(&flat), "--json"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(stdout(&o).trim()).unwrap();
    assert_eq!(v["status"], "failed");
    assert!(v["reason"].as_str().is_some_and(|r| !r.is_empty()), "{v}");
}

#[test]
fn eval_otb_on_a_file_says_it_is_not_an_otb_folder() {
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(dir.path(), "seq", 3);
    let out = dir.path().join("out");
    let o = track(&[
        "eval",
        "otb",
        s(&seq.join("groundtruth_rect.txt")),
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let e = one_error_line(&o);
    assert!(
        e.contains("not an OTB folder") && !e.contains("ffmpeg"),
        "{e}"
    );
    // A refused evaluation leaves nothing: not even the folder it would have made.
    assert!(!out.exists());
}

#[test]
fn a_refused_evaluation_leaves_no_lock_or_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let seq = otb_folder(dir.path(), "seq", 3);
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("index.html"), "my page").unwrap();
    let o = track(&[
        "eval",
        "otb",
        s(&seq),
        "--tracker",
        "m1",
        "--particles",
        "20",
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    assert!(one_error_line(&o).contains("index.html"));
    let names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["index.html"]);
}

#[test]
fn smooth_help_says_what_it_does_for_head() {
    // `--smooth` smooths head as any tracker (tests/smoothing_cli.rs); the help says so.
    let o = track(&["run", "--help"]);
    assert!(o.status.success());
    let help = stdout(&o).split_whitespace().collect::<Vec<_>>().join(" ");
    let smooth = &help[help.find("--smooth").unwrap()..];
    let smooth = &smooth[..smooth.find("--quiet").unwrap_or(smooth.len())];
    assert!(!smooth.contains("not for the head"), "{smooth}");
    assert!(smooth.contains("head included"), "{smooth}");
}

#[cfg(unix)]
#[test]
fn eval_otb_stopped_by_sigterm_writes_the_tables_of_the_runs_finished() {
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    // A short first sequence, then long ones: the signal comes once the first is written.
    let mut seqs = vec![otb_folder(dir.path(), "a-short", 4)];
    for name in ["b-long", "c-long"] {
        seqs.push(otb_folder(dir.path(), name, 40));
    }
    let out = dir.path().join("out");
    let mut args = vec!["eval".to_owned(), "otb".to_owned()];
    args.extend(seqs.iter().map(|p| s(p).to_owned()));
    args.extend(
        [
            "--tracker",
            "m1",
            "--particles",
            "4000",
            "--protocol",
            "tre",
            "--out",
            s(&out),
            "--quiet",
        ]
        .map(str::to_owned),
    );
    let mut child = std::process::Command::new(common::TRACK)
        .args(&args)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let first = out.join("tre/m1/a-short.1.txt");
    let start = Instant::now();
    while !first.exists() {
        assert!(child.try_wait().unwrap().is_none(), "eval otb ended early");
        assert!(start.elapsed() < Duration::from_secs(120), "no box file");
        std::thread::sleep(Duration::from_millis(5));
    }
    let ok = std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(143), "{}", stderr(&o));
    let e = one_error_line(&o);
    assert!(
        e.contains("interrupted by SIGTERM") && e.contains("runs"),
        "{e}"
    );
    let md = std::fs::read_to_string(out.join("tre/otb.md")).unwrap();
    assert!(md.contains("Interrupted by SIGTERM"), "{md}");
    let csv = std::fs::read_to_string(out.join("tre/otb.csv")).unwrap();
    assert!(csv.contains(",a-short,m1,"), "{csv}");
    assert!(out.join("index.html").is_file());
    // No run started after the signal: the last sequence has no box file.
    assert!(!out.join("tre/m1/c-long.1.txt").exists());
}
