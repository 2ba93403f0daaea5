//! Writing a sequence to disk in the OTB layout plus full ground truth.
//!
//! ```text
//! DIR/img/0001.png …         8-bit grey frames
//! DIR/groundtruth_rect.txt   x,y,w,h of the target's box, one line per frame
//! DIR/groundtruth.csv        everything in FrameTruth, one row per frame
//! DIR/scene.json             every parameter, the seed, and the calibrated clutter densities
//! ```
//!
//! Every file is written atomically: to a temporary file in its own folder, renamed into place
//! once complete, so an interrupted run leaves complete files only.

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::{Error, Result};
use crate::params::ScenarioParams;
use crate::render::Scene;

/// One calibrated clutter region, as recorded in `scene.json`.
#[derive(Debug, Clone, Serialize)]
struct RegionRecord {
    x0: usize,
    x1: usize,
    class: u8,
    requested_density: f64,
    measured_density: f64,
    structures: usize,
}

#[derive(Debug, Clone, Serialize)]
struct SceneRecord<'a> {
    generator: &'static str,
    version: &'static str,
    seed: u64,
    params: &'a ScenarioParams,
    background_size: [usize; 2],
    regions: Vec<RegionRecord>,
    occluder_rect: Option<[f64; 4]>,
    box_convention: &'static str,
}

/// How the boxes of a written sequence are to be read, as its record files state it.
pub const BOX_CONVENTION: &str = "x,y = top-left corner, pixel (i, j) centred at (i, j), 0-based";

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes every frame and the ground truth of `scene` into `dir` (created if needed; existing
/// files are overwritten). Returns the number of frames written.
///
/// # Errors
/// [`Error::Io`], [`Error::Image`] or [`Error::Json`] when a file cannot be written.
pub fn write_sequence(dir: &Path, scene: &Scene) -> Result<usize> {
    let img_dir = dir.join("img");
    fs::create_dir_all(&img_dir).map_err(io_err(&img_dir))?;
    let (w, h) = scene.size();
    let mut out = vec![0u8; w * h];
    let mut scratch = Vec::new();
    let mut rect = String::new();
    let mut csv = String::from(crate::truth::FrameTruth::CSV_HEADER);
    csv.push('\n');
    for k in 0..scene.len() {
        let truth = scene.render_frame_into(k, &mut out, &mut scratch)?;
        let path: PathBuf = img_dir.join(format!("{:04}.png", k + 1));
        write_atomic(&path, |file| {
            use image::ImageEncoder;
            image::codecs::png::PngEncoder::new(file)
                .write_image(&out, w as u32, h as u32, image::ExtendedColorType::L8)
                .map_err(|source| Error::Image {
                    path: path.clone(),
                    source,
                })
        })?;
        rect.push_str(&truth.rect_line());
        rect.push('\n');
        csv.push_str(&truth.csv_row());
        csv.push('\n');
    }
    write_file(&dir.join("groundtruth_rect.txt"), rect.as_bytes())?;
    write_file(&dir.join("groundtruth.csv"), csv.as_bytes())?;
    let bg = scene.background();
    let record = SceneRecord {
        generator: "scene-synth",
        version: env!("CARGO_PKG_VERSION"),
        seed: scene.seed(),
        params: scene.params(),
        background_size: [bg.width, bg.height],
        regions: bg
            .regions
            .iter()
            .map(|r| RegionRecord {
                x0: r.x0,
                x1: r.x1,
                class: r.class.index(),
                requested_density: r.requested,
                measured_density: r.measured,
                structures: r.structures,
            })
            .collect(),
        occluder_rect: scene.occluder_rect(),
        box_convention: BOX_CONVENTION,
    };
    let mut json = serde_json::to_string_pretty(&record)?;
    json.push('\n');
    write_file(&dir.join("scene.json"), json.as_bytes())?;
    Ok(scene.len())
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |file| file.write_all(bytes).map_err(io_err(path)))
}

/// Writes `path` through `fill` into a temporary sibling, then syncs it and renames it over
/// `path`.
///
/// The temporary file lives in the destination's own folder because a rename is atomic only
/// within one file system. `tempfile` deletes it when it is dropped before `persist`, so an
/// error at any step, in `fill` or after, leaves no partial file behind.
fn write_atomic(path: &Path, fill: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let tmp = tempfile::Builder::new()
        .prefix(".scene-synth-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(io_err(path))?;
    let mut writer = BufWriter::with_capacity(1 << 16, tmp);
    fill(&mut writer)?;
    let tmp = writer
        .into_inner()
        .map_err(|e| io_err(path)(e.into_error()))?;
    // Temporary files are created readable by their owner only; the sequence is ordinary data.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(fs::Permissions::from_mode(0o644))
            .map_err(io_err(path))?;
    }
    tmp.as_file().sync_all().map_err(io_err(path))?;
    tmp.persist(path).map_err(|e| io_err(path)(e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Scenario;

    fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
        let mut out = Vec::new();
        let mut stack = vec![dir.to_path_buf()];
        while let Some(d) = stack.pop() {
            for entry in fs::read_dir(&d).unwrap() {
                let p = entry.unwrap().path();
                if p.is_dir() {
                    stack.push(p);
                } else {
                    out.push((
                        p.strip_prefix(dir).unwrap().to_path_buf(),
                        fs::read(&p).unwrap(),
                    ));
                }
            }
        }
        out.sort();
        out
    }

    #[test]
    fn the_same_seed_gives_byte_identical_files() {
        for sc in Scenario::ALL {
            let mut p = ScenarioParams::preset(sc);
            p.frames = 6;
            let (a, b, c) = (
                tempfile::tempdir().unwrap(),
                tempfile::tempdir().unwrap(),
                tempfile::tempdir().unwrap(),
            );
            // Two scenes built independently from the same (params, seed).
            write_sequence(a.path(), &Scene::new(&p, 77).unwrap()).unwrap();
            write_sequence(b.path(), &Scene::new(&p, 77).unwrap()).unwrap();
            write_sequence(c.path(), &Scene::new(&p, 78).unwrap()).unwrap();
            let (fa, fb, fc) = (files(a.path()), files(b.path()), files(c.path()));
            assert_eq!(fa.len(), 6 + 3);
            assert!(fa == fb, "{sc}: same seed, different bytes");
            assert!(fa != fc, "{sc}: different seeds, same bytes");
        }
    }

    #[test]
    fn files_are_complete_and_no_temporary_file_remains() {
        let mut p = ScenarioParams::preset(Scenario::Zoom);
        p.frames = 3;
        let scene = Scene::new(&p, 5).unwrap();
        let dir = tempfile::tempdir().unwrap();
        // Earlier, longer outputs are replaced whole, not overwritten in place.
        fs::write(dir.path().join("scene.json"), " ".repeat(1 << 16)).unwrap();
        write_sequence(dir.path(), &scene).unwrap();
        let written = files(dir.path());
        let names: Vec<_> = written.iter().map(|(p, _)| p.clone()).collect();
        let expected: Vec<PathBuf> = [
            "groundtruth.csv",
            "groundtruth_rect.txt",
            "img/0001.png",
            "img/0002.png",
            "img/0003.png",
            "scene.json",
        ]
        .iter()
        .map(PathBuf::from)
        .collect();
        assert_eq!(names, expected);
        for (name, bytes) in &written {
            if name.extension().is_some_and(|e| e == "png") {
                // A PNG stream ends with its IEND chunk: the file is complete.
                assert!(bytes.ends_with(b"IEND\xaeB`\x82"), "{}", name.display());
            }
        }
        let json: serde_json::Value =
            serde_json::from_slice(&fs::read(dir.path().join("scene.json")).unwrap()).unwrap();
        assert_eq!(json["seed"], 5);
    }

    #[test]
    fn a_failed_write_leaves_no_temporary_file() {
        let mut p = ScenarioParams::preset(Scenario::Zoom);
        p.frames = 2;
        let scene = Scene::new(&p, 5).unwrap();
        let dir = tempfile::tempdir().unwrap();
        // A folder where the second frame should go: its rename fails.
        fs::create_dir_all(dir.path().join("img/0002.png")).unwrap();
        assert!(matches!(
            write_sequence(dir.path(), &scene),
            Err(Error::Io { .. })
        ));
        let mut img: Vec<_> = fs::read_dir(dir.path().join("img"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        img.sort();
        assert_eq!(img, ["0001.png", "0002.png"]);
        assert!(dir.path().join("img/0002.png").is_dir());
        // Nothing was written after the failure.
        assert!(!dir.path().join("groundtruth.csv").exists());
    }

    #[test]
    fn written_files_follow_the_otb_layout() {
        let mut p = ScenarioParams::preset(Scenario::Zoom);
        p.frames = 3;
        let scene = Scene::new(&p, 5).unwrap();
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(write_sequence(dir.path(), &scene).unwrap(), 3);
        let img = image::open(dir.path().join("img/0003.png"))
            .unwrap()
            .to_luma8();
        assert_eq!(img, scene.render_frame(2).unwrap().0);
        let rect = fs::read_to_string(dir.path().join("groundtruth_rect.txt")).unwrap();
        let first: Vec<f64> = rect
            .lines()
            .next()
            .unwrap()
            .split(',')
            .map(|v| v.parse().unwrap())
            .collect();
        let t0 = scene.truth(0).unwrap();
        assert_eq!(first.len(), 4);
        assert!((first[0] - t0.bbox.x).abs() < 1e-3 && (first[3] - t0.bbox.h).abs() < 1e-3);
        let csv = fs::read_to_string(dir.path().join("groundtruth.csv")).unwrap();
        assert_eq!(csv.lines().count(), 4);
        let cols = csv.lines().next().unwrap().split(',').count();
        assert!(csv.lines().all(|l| l.split(',').count() == cols));
        let json: serde_json::Value =
            serde_json::from_str(&fs::read_to_string(dir.path().join("scene.json")).unwrap())
                .unwrap();
        assert_eq!(json["seed"], 5);
        let back: ScenarioParams = serde_json::from_value(json["params"].clone()).unwrap();
        assert_eq!(back, p);
    }
}
