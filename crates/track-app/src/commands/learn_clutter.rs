//! `track learn-clutter`: clutter densities from training images (Wu et al. §6.1).

use std::path::{Path, PathBuf};

use contour_obs::{ClutterSettings, learn_clutter};
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;
use vision_core::GreyImage;

use crate::{AppError, Result};

/// Arguments of `track learn-clutter`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:\n  \
    track learn-clutter background/*.png --out clutter.json\n  \
    track learn-clutter frame.png --lines 20000 --k 3 --seed 7")]
pub struct Args {
    /// Training images (any format the `image` crate reads: PNG, JPEG, GIF), converted to grey.
    #[arg(required = true, value_name = "IMAGES")]
    pub images: Vec<PathBuf>,
    /// Number of random measurement lines thrown over all images.
    #[arg(long, default_value_t = 20_000)]
    pub lines: usize,
    /// Number of clutter classes (k-means clusters).
    #[arg(long, default_value_t = 3)]
    pub k: usize,
    /// Measurement line length L in pixels (even).
    #[arg(long, default_value_t = 20)]
    pub length: usize,
    /// Seed of the random lines and of the k-means++ initialisation.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output JSON file; without it the JSON is printed to standard output.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

/// Largest `--lines`: 500 times the default; the densities alone take 8 bytes a line (80 MB), and
/// a larger sample does not change three cluster means measurably.
pub const MAX_LINES: usize = 10_000_000;
/// Largest `--k`: Wu §6.1 uses three classes; k-means++ costs k passes over the lines.
pub const MAX_K: usize = 64;

/// Runs `track learn-clutter`: writes `{"clusters": [{"mean", "std", "weight"}, …]}` sorted by
/// mean, densities in edges per pixel.
///
/// # Errors
/// [`AppError::InvalidSetting`] for bad settings, [`AppError::BadInput`] for an unreadable or too
/// small image, [`AppError::Computation`] when clustering fails (for example fewer distinct
/// densities than k), [`AppError::Write`] when the output cannot be written.
pub fn run(args: &Args) -> Result<()> {
    if args.lines > MAX_LINES {
        return Err(AppError::setting(
            "--lines",
            format!("{} is more than the maximum, {MAX_LINES}", args.lines),
        ));
    }
    if args.lines == 0 {
        return Err(AppError::setting("--lines", "must be at least 1"));
    }
    if args.k == 0 {
        return Err(AppError::setting("--k", "must be at least 1 clutter class"));
    }
    if args.k > MAX_K {
        return Err(AppError::setting(
            "--k",
            format!("{} is more than the maximum, {MAX_K}", args.k),
        ));
    }
    // Refused before the work, not after it.
    let out = match &args.out {
        Some(path) => Some(crate::output::OutputGuard::new(&args.images).file(path)?),
        None => None,
    };
    let settings = ClutterSettings {
        lines: args.lines,
        k: args.k,
        length: args.length,
        ..ClutterSettings::default()
    };
    settings
        .validate()
        .map_err(|e| AppError::setting("learn-clutter", e.to_string()))?;
    let loaded: Vec<(usize, usize, Vec<f32>)> = args
        .images
        .iter()
        .map(|p| load_grey(p))
        .collect::<Result<_>>()?;
    let mut views = Vec::with_capacity(loaded.len());
    for ((w, h, data), path) in loaded.iter().zip(&args.images) {
        views.push(GreyImage::new(*w, *h, data).map_err(|e| AppError::input(path, e.to_string()))?);
    }
    let mut rng = Pcg64Mcg::seed_from_u64(args.seed);
    let model = learn_clutter(&views, &settings, &mut rng).map_err(|e| match e {
        contour_obs::Error::ImageTooSmall { width, height, .. } => {
            let path = views
                .iter()
                .zip(&args.images)
                .find(|(v, _)| v.width() == width && v.height() == height)
                .map_or_else(|| PathBuf::from("<images>"), |(_, p)| p.clone());
            AppError::input(path, e.to_string())
        }
        other => AppError::computation("learning clutter", other),
    })?;
    let mut json = model
        .to_json()
        .map_err(|e| AppError::computation("serialising the clutter model", e))?;
    json.push('\n');
    match out {
        Some(file) => file.write(json.as_bytes()),
        None => crate::output::print_stdout(&json),
    }
}

/// Loads an image as row-major grey f32 in 0–255 grey levels, as `track run` reads it
/// ([`vision_core::ToGreyBuffer`]).
fn load_grey(path: &Path) -> Result<(usize, usize, Vec<f32>)> {
    let grey = vision_core::ToGreyBuffer::to_grey_buffer(&crate::sequence::decode_image(path)?);
    let (w, h) = grey.dimensions();
    Ok((w as usize, h as usize, grey.into_raw()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::try_main_from_args;

    /// Writes a PNG: a 4-px black and white checkerboard, or a flat grey image.
    fn write_png(path: &Path, checker: bool) {
        let img = image::GrayImage::from_fn(200, 150, |x, y| {
            let dark = checker && (x / 4 + y / 4) % 2 == 0;
            image::Luma([if dark { 30 } else { 220 }])
        });
        img.save(path).unwrap();
    }

    #[test]
    fn writes_json_clusters_sorted_by_mean() {
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("a.png");
        write_png(&png, true);
        let flat = dir.path().join("flat.png");
        write_png(&flat, false);
        let out = dir.path().join("sub/clutter.json");
        try_main_from_args([
            "track",
            "learn-clutter",
            png.to_str().unwrap(),
            flat.to_str().unwrap(),
            "--lines",
            "2000",
            "--k",
            "2",
            "--seed",
            "5",
            "--out",
            out.to_str().unwrap(),
        ])
        .unwrap();
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        let cl = v["clusters"].as_array().unwrap();
        assert_eq!(cl.len(), 2, "{v}");
        // Lines on the flat image see no edge; a 20 px line on a 4 px checkerboard typically
        // crosses 5–7 square sides (density ≈ 0.3), except near its diagonals, which run along
        // same-coloured squares. So the light cluster is the flat image plus a few near-diagonal
        // lines (mean well below 0.01), the heavy one the checkerboard, each holding about half
        // the lines (equal areas; with 2000 lines ±5 % is more than 4 standard deviations).
        assert!(cl[0]["mean"].as_f64().unwrap() < 0.01);
        assert!(cl[1]["mean"].as_f64().unwrap() >= 0.2);
        assert!((cl[0]["weight"].as_f64().unwrap() - 0.5).abs() < 0.05);
        let w: f64 = cl.iter().map(|c| c["weight"].as_f64().unwrap()).sum();
        assert!((w - 1.0).abs() < 1e-12);
    }

    #[test]
    fn bad_inputs_have_their_exit_codes() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("missing.png");
        let e =
            try_main_from_args(["track", "learn-clutter", missing.to_str().unwrap()]).unwrap_err();
        assert_eq!(e.exit_code(), 3);
        let png = dir.path().join("a.png");
        write_png(&png, true);
        let e = try_main_from_args(["track", "learn-clutter", png.to_str().unwrap(), "--k", "0"])
            .unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let tiny = dir.path().join("tiny.png");
        image::GrayImage::new(10, 10).save(&tiny).unwrap();
        let e = try_main_from_args(["track", "learn-clutter", tiny.to_str().unwrap()]).unwrap_err();
        assert_eq!(e.exit_code(), 3);
    }
}
