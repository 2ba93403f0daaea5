//! `cargo xtask camera-zoom`: OTB folders of real footage with a known camera zoom laid over
//! them (`scene_synth::camera_zoom`), written as OTB folders for `track eval otb` and
//! `opencv_peers.py` alike.

use std::path::{Path, PathBuf};

use scene_synth::camera_zoom::{CameraZoom, Operator};
use serde::Serialize;
use track_app::groundtruth::{check_groundtruth_len, load_groundtruth};
use track_app::otb::boxes_text;
use track_app::output::{OutputGuard, write_atomic};
use track_app::render::{encode_jpeg, encode_png};
use track_app::sequence::{ImageFolder, decode_image};

/// The share of the frame's width and height the largest labelled box may fill at the zoom's
/// peak: the largest zoom is lowered per sequence to keep it (a target larger than the crop
/// would leave the picture).
pub const FILL: f64 = 0.9;

/// JPEG quality of the frames written from JPEG footage: high, so that the re-encoding adds
/// little beside the footage's own compression.
const JPEG_QUALITY: u8 = 95;

/// Arguments of `camera-zoom`.
#[derive(Debug, clap::Args)]
pub struct CameraZoomArgs {
    /// OTB folders (`img/` and `groundtruth_rect.txt`, as `track eval otb` reads them).
    #[arg(required = true, value_name = "SEQUENCE")]
    pub sequences: Vec<PathBuf>,
    /// Z, the largest zoom (≥ 1), lowered per sequence so that the largest labelled box,
    /// zoomed, fills at most 90 % of the frame's width and height.
    #[arg(long, default_value_t = 2.0)]
    pub max_zoom: f64,
    /// P, the frames from one zoom-out to the next: the target grows Z-fold over P/2 frames,
    /// then shrinks back, z(t) = 1 + (Z − 1)(1 − cos 2πt/P)/2.
    #[arg(long, default_value_t = 120.0)]
    pub period: f64,
    /// The share of the way from the camera's aim to the target's labelled centre taken each
    /// frame, in (0, 1] (1 centres every frame on the target).
    #[arg(long, default_value_t = CameraZoom::DEFAULT_FOLLOW)]
    pub follow: f64,
    /// Output folder: one OTB folder per sequence, `OUT/<sequence's folder name>`. What an
    /// earlier run wrote there is replaced; no other file is touched, and no folder inside a
    /// sequence is accepted.
    #[arg(long)]
    pub out: PathBuf,
}

/// What `camera_zoom.json` records of a sequence.
#[derive(Debug, Serialize)]
struct ZoomRecord<'a> {
    generator: &'static str,
    source: &'a Path,
    requested_max_zoom: f64,
    fill: f64,
    zoom: CameraZoom,
    frames: usize,
    box_convention: &'static str,
}

/// Writes every sequence, calling `report` with a line for the terminal as each is complete.
///
/// # Errors
/// A message naming the sequence and the file for a bad setting, an unreadable or inconsistent
/// input, or an output that cannot be written (the output guard's refusals among them: an output
/// folder inside or holding a sequence, a file of another origin in an output's place). Every
/// file is written atomically and recorded in the output folder's manifest, so the partial
/// sequence of an interrupted run is removed by the next run into the folder.
pub fn run(args: &CameraZoomArgs, mut report: impl FnMut(&str)) -> Result<(), String> {
    let zoom = CameraZoom {
        max_zoom: args.max_zoom,
        period: args.period,
        follow: args.follow,
    };
    zoom.validate().map_err(|e| e.to_string())?;
    let mut names: Vec<&std::ffi::OsStr> = Vec::new();
    for seq in &args.sequences {
        let name = seq
            .file_name()
            .ok_or_else(|| format!("{}: not a folder name", seq.display()))?;
        if names.contains(&name) {
            return Err(format!(
                "two sequences are named {}: their outputs would collide",
                name.to_string_lossy()
            ));
        }
        names.push(name);
    }
    let _folder = OutputGuard::new(&args.sequences)
        .folder(&args.out)
        .map_err(|e| e.to_string())?;
    for (seq, name) in args.sequences.iter().zip(names) {
        report(&zoom_sequence(seq, name, zoom, &args.out)?);
    }
    Ok(())
}

/// One sequence: its frames cropped and resized, its truth mapped, into `out/<name>`.
fn zoom_sequence(
    seq: &Path,
    name: &std::ffi::OsStr,
    zoom: CameraZoom,
    out: &Path,
) -> Result<String, String> {
    let folder = ImageFolder::open(&seq.join("img")).map_err(|e| e.to_string())?;
    let gt_path = seq.join("groundtruth_rect.txt");
    let truth = load_groundtruth(&gt_path).map_err(|e| e.to_string())?;
    let paths = folder.paths();
    check_groundtruth_len(&truth, paths.len(), &gt_path).map_err(|e| e.to_string())?;
    let largest = truth
        .iter()
        .flatten()
        .fold((0.0_f64, 0.0_f64), |(w, h), b| (w.max(b.w), h.max(b.h)));
    let dest = out.join(name);
    let img_dir = dest.join("img");

    let first = paths
        .first()
        .ok_or_else(|| format!("{}: no frames", seq.display()))?;
    let size = image::image_dimensions(first).map_err(|e| format!("{}: {e}", first.display()))?;
    let fitted = zoom.fitted(largest, size, FILL);
    let mut operator =
        Operator::new(fitted, size).map_err(|e| format!("{}: {e}", seq.display()))?;
    let mut mapped = Vec::with_capacity(truth.len());
    let mut crops = String::from("frame,zoom_x,zoom_y,crop_x,crop_y,crop_w,crop_h\n");
    for (k, (path, target)) in paths.iter().zip(&truth).enumerate() {
        let frame = decode_image(path).map_err(|e| e.to_string())?.to_rgb8();
        if frame.dimensions() != size {
            return Err(format!(
                "{}: {} × {} px, the first frame {} × {} px",
                path.display(),
                frame.width(),
                frame.height(),
                size.0,
                size.1
            ));
        }
        let crop = operator.next_crop(target.as_ref());
        let zoomed = crop.apply(&frame).map_err(|e| e.to_string())?;
        write_frame(&img_dir, path, &zoomed)?;
        mapped.push(target.as_ref().map(|b| crop.map_box(b)));
        let (zx, zy) = crop.zoom();
        crops.push_str(&format!(
            "{},{zx:.4},{zy:.4},{},{},{},{}\n",
            k + 1,
            crop.x,
            crop.y,
            crop.w,
            crop.h
        ));
    }
    write(
        &dest.join("groundtruth_rect.txt"),
        boxes_text(&mapped).as_bytes(),
    )?;
    write(&dest.join("camera_zoom.csv"), crops.as_bytes())?;
    let record = ZoomRecord {
        generator: "cargo xtask camera-zoom",
        source: seq,
        requested_max_zoom: zoom.max_zoom,
        fill: FILL,
        zoom: fitted,
        frames: paths.len(),
        box_convention: scene_synth::BOX_CONVENTION,
    };
    let json = serde_json::to_string_pretty(&record).map_err(|e| e.to_string())?;
    write(
        &dest.join("camera_zoom.json"),
        format!("{json}\n").as_bytes(),
    )?;
    Ok(format!(
        "{}: {} frames, zoom up to {:.2} (asked {}) every {} frames → {}",
        name.to_string_lossy(),
        paths.len(),
        fitted.max_zoom,
        zoom.max_zoom,
        zoom.period,
        dest.display()
    ))
}

/// A zoomed frame, named as its source: PNG from PNG footage, JPEG (quality 95) otherwise.
fn write_frame(dir: &Path, source: &Path, frame: &image::RgbImage) -> Result<(), String> {
    let stem = source
        .file_stem()
        .ok_or_else(|| format!("{}: no file name", source.display()))?;
    let png = source
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    let path = dir
        .join(stem)
        .with_extension(if png { "png" } else { "jpg" });
    let bytes = if png {
        encode_png(frame)
    } else {
        encode_jpeg(frame, JPEG_QUALITY)
    }
    .map_err(|e| format!("{}: {e}", path.display()))?;
    write(&path, &bytes)
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), String> {
    write_atomic(path, bytes).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    /// A small OTB folder: a bright square moving right on a dark textured background.
    fn otb_folder(dir: &Path, frames: usize, truth_lines: usize) {
        fs::create_dir_all(dir.join("img")).unwrap();
        let mut gt = String::new();
        for k in 0..frames {
            let x0 = 20 + 2 * k as u32;
            let img = image::RgbImage::from_fn(96, 64, |i, j| {
                if (x0..x0 + 12).contains(&i) && (24..36).contains(&j) {
                    image::Rgb([240, 200, 180])
                } else {
                    image::Rgb([((i * 7 + j * 3) % 50) as u8; 3])
                }
            });
            img.save(dir.join("img").join(format!("{:04}.png", k + 1)))
                .unwrap();
            if k < truth_lines {
                gt.push_str(&format!("{x0},24,12,12\n"));
            }
        }
        fs::write(dir.join("groundtruth_rect.txt"), gt).unwrap();
    }

    /// A temporary folder holding an OTB folder `name` (see [`otb_folder`]), and the output
    /// folder's path beside it.
    fn fixture(
        name: &str,
        frames: usize,
        truth_lines: usize,
    ) -> (tempfile::TempDir, PathBuf, PathBuf) {
        let tmp = tempfile::tempdir().unwrap();
        let seq = tmp.path().join(name);
        otb_folder(&seq, frames, truth_lines);
        let out = tmp.path().join("zoomed");
        (tmp, seq, out)
    }

    fn args(seq: PathBuf, out: PathBuf) -> CameraZoomArgs {
        CameraZoomArgs {
            sequences: vec![seq],
            max_zoom: 2.0,
            period: 8.0,
            follow: 0.5,
            out,
        }
    }

    #[test]
    fn a_zoomed_sequence_is_an_otb_folder_whose_truth_follows_the_zoom() {
        let (_tmp, seq, out) = fixture("square", 9, 9);
        let mut lines = Vec::new();
        run(&args(seq, out.clone()), |l| lines.push(l.to_owned())).unwrap();
        assert_eq!(lines.len(), 1);
        assert!(
            lines[0].starts_with("square: 9 frames, zoom up to 2.00"),
            "{lines:?}"
        );
        let dest = out.join("square");
        let frames = ImageFolder::open(&dest.join("img")).unwrap();
        assert_eq!(frames.paths().len(), 9);
        let truth = load_groundtruth(&dest.join("groundtruth_rect.txt")).unwrap();
        assert_eq!(truth.len(), 9);
        let first = truth[0].unwrap();
        // Frame 1 is unzoomed; frame 5 (t = 4, half the period) is zoomed twofold.
        assert_eq!(first.to_array(), [20.0, 24.0, 12.0, 12.0]);
        let peak = truth[4].unwrap();
        assert!(
            (peak.w - 24.0).abs() < 0.6 && (peak.h - 24.0).abs() < 0.6,
            "{peak:?}"
        );
        // The zoomed square is where the mapped truth says: its centre pixel is bright.
        let img = decode_image(&frames.paths()[4]).unwrap().to_rgb8();
        let (cx, cy) = peak.centre();
        assert!(img.get_pixel(cx as u32, cy as u32).0[0] > 200);
        let record = fs::read_to_string(dest.join("camera_zoom.json")).unwrap();
        assert!(record.contains("\"max_zoom\": 2.0"), "{record}");
        let crops = fs::read_to_string(dest.join("camera_zoom.csv")).unwrap();
        assert_eq!(crops.lines().count(), 10);
        // Nothing else is left in the output folder but its lock and manifest.
        let mut names: Vec<String> = fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, [".track-lock", ".track-outputs", "square"]);
    }

    #[test]
    fn bad_settings_and_inconsistent_inputs_are_refused_with_nothing_written() {
        let (_tmp, seq, out) = fixture("short", 4, 3);
        let mut a = args(seq.clone(), out.clone());
        a.max_zoom = 0.5;
        assert!(run(&a, |_| ()).unwrap_err().contains("max_zoom"));
        let err = run(&args(seq, out.clone()), |_| ()).unwrap_err();
        assert!(err.contains("3 ground-truth lines for 4 frames"), "{err}");
        assert!(!out.exists(), "a partial sequence was left");
        // An output folder inside the sequence is refused, and nothing is written there.
        let (_tmp, seq, _) = fixture("square", 4, 4);
        let err = run(&args(seq.clone(), seq.join("zoomed")), |_| ()).unwrap_err();
        assert!(err.contains("inside the input folder"), "{err}");
        assert!(!seq.join("zoomed").exists());
    }
}
