//! Helpers shared by the end-to-end tests: tiny sequences written to temporary folders.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use image::{GrayImage, Luma};

/// A 96×72 frame: a bright disc of radius 16 centred at (`cx`, 36) on a dark background.
pub fn disc_frame(cx: f64) -> GrayImage {
    GrayImage::from_fn(96, 72, |x, y| {
        let d = ((x as f64 - cx).powi(2) + (y as f64 - 36.0).powi(2)).sqrt();
        Luma([if d < 16.0 { 200 } else { 40 }])
    })
}

/// Writes `n` disc frames (moving 2 px per frame) into `dir/img/` and returns the folder.
pub fn image_folder(dir: &Path, n: usize) -> PathBuf {
    let img = dir.join("img");
    std::fs::create_dir_all(&img).unwrap();
    for k in 0..n {
        disc_frame(30.0 + 2.0 * k as f64)
            .save(img.join(format!("{:04}.png", k + 1)))
            .unwrap();
    }
    img
}

/// An OTB folder of `n` disc frames with a ground-truth box on every frame.
pub fn otb_folder(dir: &Path, n: usize) -> PathBuf {
    image_folder(dir, n);
    let gt: String = (0..n)
        .map(|k| format!("{},20,32,32\n", 14.0 + 2.0 * k as f64))
        .collect();
    std::fs::write(dir.join("groundtruth_rect.txt"), gt).unwrap();
    dir.to_path_buf()
}

/// Runs the `track` command line in-process.
pub fn track(args: &[&str]) -> Result<(), track_app::AppError> {
    let mut all = vec!["track"];
    all.extend_from_slice(args);
    track_app::cli::try_main_from_args(all)
}

/// A path as a `&str` (test paths are UTF-8).
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}
