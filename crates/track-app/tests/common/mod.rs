//! Helpers shared by the end-to-end tests of messages, failures and video files: run the
//! `track` binary as a user would and read what it wrote.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output, Stdio};

/// The `track` binary built for these tests.
pub const TRACK: &str = env!("CARGO_BIN_EXE_track");

/// A path as text (the tests make only UTF-8 paths).
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs `track args` with no standard input.
pub fn track(args: &[&str]) -> Output {
    Command::new(TRACK)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

/// Standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Standard output as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Exactly one line on standard error, starting with `error:`, no panic; returns it.
pub fn one_error_line(o: &Output) -> String {
    let e = stderr(o);
    assert!(e.starts_with("error: ") && e.lines().count() == 1, "{e:?}");
    assert!(
        !e.contains("panicked") && !e.contains("RUST_BACKTRACE"),
        "{e}"
    );
    e
}

/// Writes `n` 96×72 PNG frames `0001.png…` into `dir/name`: a bright disc of radius 12 on a dark
/// background, its centre at x = 30 + 2k on frame k; returns the folder.
pub fn disc_frames(dir: &Path, name: &str, n: usize) -> std::path::PathBuf {
    let folder = dir.join(name);
    std::fs::create_dir_all(&folder).unwrap();
    for k in 0..n {
        disc_image(30.0 + 2.0 * k as f64)
            .save(folder.join(format!("{:04}.png", k + 1)))
            .unwrap();
    }
    folder
}

/// A 96×72 RGB frame with a bright disc of radius 12 centred at (`cx`, 36).
pub fn disc_image(cx: f64) -> image::RgbImage {
    image::RgbImage::from_fn(96, 72, |x, y| {
        let inside = (f64::from(x) - cx).powi(2) + (f64::from(y) - 36.0).powi(2) < 144.0;
        if inside {
            image::Rgb([220, 200, 180])
        } else {
            image::Rgb([30, 40, 50])
        }
    })
}

/// `--init` around the disc of [`disc_image`] centred at x = 30.
pub const DISC_INIT: &str = "18,24,24,24";

/// The header row of `out/track.csv`.
pub fn csv_header(out: &Path) -> String {
    let csv = std::fs::read_to_string(out.join("track.csv")).unwrap();
    csv.lines().next().unwrap().to_owned()
}

/// `out/summary.json`.
pub fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// `track eval paired` of the `base` folders against the `variant` folders, with `extra`
/// arguments.
pub fn paired<P: AsRef<Path>>(base: &[P], variant: &[P], extra: &[&str]) -> Output {
    let mut args = vec!["eval", "paired"];
    for b in base {
        args.extend(["--base", s(b.as_ref())]);
    }
    for v in variant {
        args.extend(["--variant", s(v.as_ref())]);
    }
    args.extend_from_slice(extra);
    track(&args)
}
