//! Tells the video tests (`tests/video.rs`) whether they can run: without `ffmpeg` on `PATH` they
//! are marked ignored, with the reason, so that `cargo test` shows them as skipped rather than
//! passed. `TRACK_REQUIRE_FFMPEG=1` (set by CI) never skips them, so a missing ffmpeg fails them;
//! `TRACK_SKIP_FFMPEG_TESTS=1` skips them whatever is installed.

use std::process::Command;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(ffmpeg_missing)");
    println!("cargo::rerun-if-env-changed=PATH");
    // Installing ffmpeg adds a file to a folder on PATH, which changes that folder's time: the
    // script runs again and the tests stop being ignored.
    if let Some(path) = std::env::var_os("PATH") {
        for dir in std::env::split_paths(&path).filter(|d| d.is_dir()) {
            println!("cargo::rerun-if-changed={}", dir.display());
        }
    }
    println!("cargo::rerun-if-env-changed=TRACK_REQUIRE_FFMPEG");
    println!("cargo::rerun-if-env-changed=TRACK_SKIP_FFMPEG_TESTS");
    let set = |name: &str| std::env::var(name).is_ok_and(|v| v == "1");
    let found = Command::new("ffmpeg")
        .arg("-version")
        .output()
        .is_ok_and(|o| o.status.success());
    if set("TRACK_SKIP_FFMPEG_TESTS") || !(found || set("TRACK_REQUIRE_FFMPEG")) {
        println!("cargo::rustc-cfg=ffmpeg_missing");
    }
}
