//! A tracker on a folder of frames through the library API.
//!
//! ```sh
//! cargo run --release -p trackers --example track_folder -- FOLDER x,y,w,h [PRESET]
//! ```
//!
//! reads the images of FOLDER (any format the `image` crate reads) in the natural order of their
//! names (`2.png` before `10.png`, as `track run`), starts the preset (default `head`) from the
//! box x,y,w,h on the first one and prints one line per frame:
//! the box, and the status probabilities where the tracker has them. Without arguments it writes
//! a short synthetic sequence into a temporary folder and tracks that, so the example runs as is.
//! The `track` command line does the same with every output a user needs (`track run`).

use std::path::{Path, PathBuf};

use trackers::{Ellipse, FrameBuf, Preset, build};

type Failure = Box<dyn std::error::Error>;

fn main() -> Result<(), Failure> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (folder, init, preset) = match args.as_slice() {
        [] => (
            synthetic_sequence()?,
            [18.0, 24.0, 24.0, 24.0],
            Preset::Head,
        ),
        [folder, init, rest @ ..] => (
            PathBuf::from(folder),
            parse_box(init)?,
            match rest.first() {
                Some(name) => Preset::from_name(name)?,
                None => Preset::Head,
            },
        ),
        _ => return Err("usage: track_folder FOLDER x,y,w,h [PRESET]".into()),
    };
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&folder)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    // Natural order, as `track run` reads a folder: 2.png before 10.png.
    vision_core::sort_natural(&mut paths);
    let mut tracker = build(preset.config(200, 1))?;
    let [x, y, w, h] = init;
    let start = Ellipse {
        cx: x + w / 2.0,
        cy: y + h / 2.0,
        a: w / 2.0,
        b: h / 2.0,
        angle: 0.0,
    };
    for (k, path) in paths.iter().enumerate() {
        // Colour images keep their RGB pixels (head reads colour); grey levels 0–255 come from
        // the BT.601 luma weights, as in `track run`.
        let owned = FrameBuf::from(&image::open(path)?);
        let frame = owned.frame()?;
        let estimate = if k == 0 {
            tracker.init(frame, start)?
        } else {
            tracker.update(frame)?
        };
        let [bx, by, bw, bh] = estimate.bbox.to_array();
        let status = estimate
            .status
            .map(|s| format!("  P(locked, partial, lost) = {:.2?}", s.alpha_probs))
            .unwrap_or_default();
        println!("{}: {bx:.1},{by:.1},{bw:.1},{bh:.1}{status}", name(path));
    }
    if args.is_empty() {
        std::fs::remove_dir_all(&folder)?;
    }
    Ok(())
}

fn parse_box(s: &str) -> Result<[f64; 4], Failure> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [x, y, w, h] if *w > 0.0 && *h > 0.0 => Ok([*x, *y, *w, *h]),
        _ => Err(format!("{s:?} is not a box x,y,w,h with positive size").into()),
    }
}

fn name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Twelve 96×72 frames of a skin-coloured disc moving right on a dark background.
fn synthetic_sequence() -> Result<PathBuf, Failure> {
    let dir = std::env::temp_dir().join(format!("track_folder_example_{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    for k in 0..12 {
        let cx = 30.0 + 2.0 * k as f64;
        let img = image::RgbImage::from_fn(96, 72, |x, y| {
            let inside = (f64::from(x) - cx).powi(2) + (f64::from(y) - 36.0).powi(2) < 144.0;
            if inside {
                image::Rgb([220, 180, 150])
            } else {
                image::Rgb([30, 40, 50])
            }
        });
        // Unpadded numbers (1.png … 12.png): read in natural order, not as 1, 10, 11, 12, 2, ….
        img.save(dir.join(format!("{}.png", k + 1)))?;
    }
    Ok(dir)
}
