//! `cargo xtask stress`: the stress suite. Every transform of `scene_synth::stress` laid over
//! every OTB folder of real footage, written as one OTB folder per transform and clip
//! (`OUT/<transform>/<clip>/`: `img/`, `groundtruth_rect.txt`, `stress.json`, and `visible.txt`
//! where occluders cover the head), with `OUT/suite.json` listing the suite, for `track eval
//! otb` and `opencv_peers.py` alike.
//!
//! Each frame is decoded once and made under every transform; frames are made in parallel
//! (rayon), and every random choice is laid out beforehand from a seed derived from the suite's
//! seed, the clip's name and the transform's (`scene_synth::stress::derive_seed`), so the output
//! does not depend on the number of threads.

use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use scene_synth::stress::{Donor, Pipeline, Plan, Transform, derive_seed, plan};
use serde::Serialize;
use track_app::groundtruth::{check_groundtruth_len, load_groundtruth};
use track_app::otb::boxes_text;
use track_app::output::{OutputGuard, write_atomic};
use track_app::render::encode_jpeg;
use track_app::sequence::{ImageFolder, decode_image};
use vision_core::BoundingBox;

/// Frames of each clip that occluders may be cut from (evenly spaced).
const DONOR_FRAMES: usize = 3;

/// Arguments of `stress`.
#[derive(Debug, clap::Args)]
pub struct StressArgs {
    /// OTB folders of real footage (`img/` and `groundtruth_rect.txt`, as `track eval otb`
    /// reads them).
    #[arg(required = true, value_name = "SEQUENCE")]
    pub sequences: Vec<PathBuf>,
    /// A transform, or several composed in order with commas (`grey,shake`: grey, then shake),
    /// written to `OUT/<names joined by +>` (repeatable; default: each of shake, occlude, tilt,
    /// grey, small, light and zoom alone).
    #[arg(long = "transform", value_name = "T[,T…]")]
    pub transforms: Vec<String>,
    /// Override a transform's setting, `TRANSFORM.FIELD=JSON` (repeatable), e.g.
    /// `--set shake.zoom=1.4` or `--set occlude.cover_max=0.6`; it applies wherever the
    /// transform appears. The settings and their defaults are in docs/STRESS.md.
    #[arg(long = "set", value_name = "T.FIELD=JSON")]
    pub set: Vec<String>,
    /// The suite's seed: the output is a pure function of the footage, the settings and it.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// JPEG quality of the frames written (1–100); every frame is written as JPEG.
    #[arg(long, default_value_t = 85,
          value_parser = clap::value_parser!(u8).range(1..=100))]
    pub jpeg_quality: u8,
    /// Output folder: `OUT/<transform>/<clip>`, each replaced whole if it exists.
    #[arg(long)]
    pub out: PathBuf,
}

/// A clip checked before any frame is made.
struct Clip {
    dir: PathBuf,
    name: String,
    frames: Vec<PathBuf>,
    truth: Vec<Option<BoundingBox>>,
    size: (u32, u32),
}

/// What `stress.json` records of a clip under a transform.
#[derive(Debug, Serialize)]
struct ClipRecord<'a> {
    generator: &'static str,
    source: &'a Path,
    clip: &'a str,
    transform: String,
    stages: &'a [Transform],
    classes: Vec<&'static str>,
    seed: u64,
    clip_seed: u64,
    stage_seeds: &'a [u64],
    derived: Vec<serde_json::Value>,
    frames: usize,
    source_size: [u32; 2],
    size: [u32; 2],
    jpeg_quality: u8,
    box_convention: &'static str,
    truth: &'static str,
    donors: &'a [String],
}

/// What `suite.json` records.
#[derive(Debug, Serialize)]
struct SuiteRecord<'a> {
    generator: &'static str,
    transforms: Vec<String>,
    clips: Vec<&'a str>,
    seed: u64,
    jpeg_quality: u8,
}

/// The transforms to write, with the `--set` overrides applied.
fn pipelines(args: &StressArgs) -> Result<Vec<Pipeline>, String> {
    let specs: Vec<String> = if args.transforms.is_empty() {
        Transform::NAMES.iter().map(|s| (*s).to_owned()).collect()
    } else {
        args.transforms.clone()
    };
    let mut out: Vec<Pipeline> = Vec::new();
    for spec in &specs {
        let mut p: Pipeline = spec
            .parse()
            .map_err(|e| format!("--transform {spec}: {e}"))?;
        for set in &args.set {
            let (path, value) = set
                .split_once('=')
                .ok_or_else(|| format!("--set {set}: expected TRANSFORM.FIELD=JSON"))?;
            let (name, field) = path
                .split_once('.')
                .ok_or_else(|| format!("--set {set}: expected TRANSFORM.FIELD=JSON"))?;
            let _: Transform = name.parse().map_err(|e| format!("--set {set}: {e}"))?;
            for stage in &mut p.stages {
                if stage.name() == name {
                    *stage = stage
                        .with_setting(field, value)
                        .map_err(|e| format!("--set {set}: {e}"))?;
                }
            }
        }
        if out.iter().any(|q| q.name() == p.name()) {
            return Err(format!("--transform {spec} is given twice"));
        }
        out.push(p);
    }
    Ok(out)
}

/// Opens and checks one OTB folder; every error names it.
fn open_clip(dir: &Path) -> Result<Clip, String> {
    let named = |e: String| format!("{}: {e}", dir.display());
    if !dir.is_dir() {
        return Err(named("not a folder".to_owned()));
    }
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| named("not a folder name".to_owned()))?;
    let gt_path = dir.join("groundtruth_rect.txt");
    if !gt_path.is_file() {
        return Err(named(
            "not an OTB folder: groundtruth_rect.txt is missing".to_owned(),
        ));
    }
    let folder = ImageFolder::open(&dir.join("img")).map_err(|e| named(e.to_string()))?;
    let frames = folder.paths().to_vec();
    let truth = load_groundtruth(&gt_path).map_err(|e| named(e.to_string()))?;
    check_groundtruth_len(&truth, frames.len(), &gt_path).map_err(|e| named(e.to_string()))?;
    let first = frames
        .first()
        .ok_or_else(|| named("no frames in img/".to_owned()))?;
    let size = image::image_dimensions(first).map_err(|e| format!("{}: {e}", first.display()))?;
    Ok(Clip {
        dir: dir.to_path_buf(),
        name,
        frames,
        truth,
        size,
    })
}

/// A frame of a clip, decoded, checked against the clip's size.
fn read_frame(clip: &Clip, k: usize) -> Result<image::RgbImage, String> {
    let path = &clip.frames[k];
    let frame = decode_image(path).map_err(|e| e.to_string())?.to_rgb8();
    if frame.dimensions() != clip.size {
        return Err(format!(
            "{}: {} × {} px, the first frame {} × {} px",
            path.display(),
            frame.width(),
            frame.height(),
            clip.size.0,
            clip.size.1
        ));
    }
    Ok(frame)
}

/// Writes the suite, calling `report` with a line for the terminal as each clip is complete.
///
/// # Errors
/// A message naming the folder or file for a bad setting, an unreadable or inconsistent input,
/// or an output that cannot be written. The output folder is taken through track's output guard
/// (never into an input, never over a file track did not write; what an earlier run wrote is
/// removed first), every file is written atomically, and a clip's `stress.json` is written last,
/// so a clip an interrupted run left incomplete is not read as part of the suite.
pub fn run(args: &StressArgs, mut report: impl FnMut(&str)) -> Result<(), String> {
    let pipelines = pipelines(args)?;
    let clips: Vec<Clip> = args
        .sequences
        .iter()
        .map(|d| open_clip(d))
        .collect::<Result<_, _>>()?;
    for (i, c) in clips.iter().enumerate() {
        if clips[..i].iter().any(|d| d.name == c.name) {
            return Err(format!(
                "two sequences are named {}: their outputs would collide",
                c.name
            ));
        }
    }
    // Occluders are cut from other clips' frames; from the clip's own with a single clip.
    let donors: Vec<Vec<Donor>> = if pipelines.iter().any(Pipeline::needs_donors) {
        clips
            .iter()
            .map(|c| {
                let n = c.frames.len();
                (0..DONOR_FRAMES.min(n))
                    .map(|j| {
                        let k = (2 * j + 1) * n / (2 * DONOR_FRAMES.min(n));
                        Ok(Donor {
                            frame: read_frame(c, k)?,
                            target: c.truth[k],
                        })
                    })
                    .collect::<Result<Vec<_>, String>>()
            })
            .collect::<Result<_, _>>()?
    } else {
        clips.iter().map(|_| Vec::new()).collect()
    };
    let _folder = OutputGuard::new(&args.sequences)
        .folder(&args.out)
        .map_err(|e| e.to_string())?;
    for (ci, clip) in clips.iter().enumerate() {
        let started = Instant::now();
        let (pool, donor_names): (Vec<Donor>, Vec<String>) = if clips.len() == 1 {
            (donors[ci].clone(), vec![clip.name.clone()])
        } else {
            let mut pool = Vec::new();
            let mut names = Vec::new();
            for (di, d) in donors.iter().enumerate().filter(|(di, _)| *di != ci) {
                pool.extend(d.iter().cloned());
                names.push(clips[di].name.clone());
            }
            (pool, names)
        };
        let plans: Vec<(Plan, u64)> = pipelines
            .iter()
            .map(|p| {
                let clip_seed = derive_seed(args.seed, &[&clip.name, &p.name()]);
                plan(p, clip.size, &clip.truth, &pool, clip_seed)
                    .map(|planned| (planned, clip_seed))
                    .map_err(|e| format!("{} under {}: {e}", clip.dir.display(), p.name()))
            })
            .collect::<Result<_, _>>()?;
        let dirs: Vec<PathBuf> = pipelines
            .iter()
            .map(|p| args.out.join(p.name()).join(&clip.name))
            .collect();
        (0..clip.frames.len())
            .into_par_iter()
            .try_for_each(|k| -> Result<(), String> {
                let frame = read_frame(clip, k)?;
                let source = &clip.frames[k];
                let stem = source
                    .file_stem()
                    .ok_or_else(|| format!("{}: no file name", source.display()))?;
                for ((planned, _), dir) in plans.iter().zip(&dirs) {
                    let made = planned
                        .apply(k, &frame)
                        .map_err(|e| format!("{}: {e}", source.display()))?;
                    let path = dir.join("img").join(stem).with_extension("jpg");
                    let bytes = encode_jpeg(&made, args.jpeg_quality)
                        .map_err(|e| format!("{}: {e}", path.display()))?;
                    write(&path, &bytes)?;
                }
                Ok(())
            })?;
        for ((p, (planned, clip_seed)), dir) in pipelines.iter().zip(&plans).zip(&dirs) {
            finish_clip(args, clip, p, planned, *clip_seed, &donor_names, dir)?;
        }
        report(&format!(
            "{}: {} frames × {} transforms → {} ({:.1} s)",
            clip.name,
            clip.frames.len(),
            pipelines.len(),
            args.out.display(),
            started.elapsed().as_secs_f64()
        ));
    }
    let suite = SuiteRecord {
        generator: "cargo xtask stress",
        transforms: pipelines.iter().map(Pipeline::name).collect(),
        clips: clips.iter().map(|c| c.name.as_str()).collect(),
        seed: args.seed,
        jpeg_quality: args.jpeg_quality,
    };
    let json = serde_json::to_string_pretty(&suite).map_err(|e| e.to_string())?;
    write(&args.out.join("suite.json"), format!("{json}\n").as_bytes())
}

/// Writes a clip's truth and records into its folder, once its frames are written: a clip
/// without `stress.json` is not read as part of the suite.
fn finish_clip(
    args: &StressArgs,
    clip: &Clip,
    pipeline: &Pipeline,
    planned: &Plan,
    clip_seed: u64,
    donors: &[String],
    dir: &Path,
) -> Result<(), String> {
    write(
        &dir.join("groundtruth_rect.txt"),
        boxes_text(planned.truth()).as_bytes(),
    )?;
    if let Some(visible) = planned.visible() {
        let text: String = visible
            .iter()
            .map(|v| v.map_or_else(|| "nan\n".to_owned(), |v| format!("{v:.4}\n")))
            .collect();
        write(&dir.join("visible.txt"), text.as_bytes())?;
    }
    let record = ClipRecord {
        generator: "cargo xtask stress",
        source: &clip.dir,
        clip: &clip.name,
        transform: pipeline.name(),
        stages: &pipeline.stages,
        classes: pipeline.stages.iter().map(Transform::class).collect(),
        seed: args.seed,
        clip_seed,
        stage_seeds: planned.seeds(),
        derived: planned.describe(),
        frames: clip.frames.len(),
        source_size: [clip.size.0, clip.size.1],
        size: [planned.size().0, planned.size().1],
        jpeg_quality: args.jpeg_quality,
        box_convention: scene_synth::BOX_CONVENTION,
        truth: "the labelled box mapped by each stage's geometry (crop, zoom, scale); under \
                tilt the axis-aligned box of the turned ellipse inscribed in the box; occluders \
                leave the whole head's box, visible.txt gives the share of it left visible",
        donors,
    };
    let json = serde_json::to_string_pretty(&record).map_err(|e| e.to_string())?;
    write(&dir.join("stress.json"), format!("{json}\n").as_bytes())?;
    Ok(())
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), String> {
    write_atomic(path, bytes).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    /// A small OTB folder: a bright ellipse moving right on a textured background of `tone`.
    fn otb_folder(dir: &Path, frames: usize, tone: u8) {
        fs::create_dir_all(dir.join("img")).unwrap();
        let mut gt = String::new();
        for k in 0..frames {
            let x0 = 30.0 + 2.0 * k as f64;
            let img = image::RgbImage::from_fn(96, 64, |i, j| {
                let (dx, dy) = ((f64::from(i) - x0 - 6.0) / 6.0, (f64::from(j) - 30.0) / 8.0);
                if dx * dx + dy * dy < 1.0 {
                    image::Rgb([240, 200, 180])
                } else {
                    image::Rgb([tone.wrapping_add(((i * 7 + j * 3) % 50) as u8); 3])
                }
            });
            img.save(dir.join("img").join(format!("{:04}.png", k + 1)))
                .unwrap();
            gt.push_str(&format!("{x0},22,12,16\n"));
        }
        fs::write(dir.join("groundtruth_rect.txt"), gt).unwrap();
    }

    fn args(sequences: Vec<PathBuf>, out: PathBuf) -> StressArgs {
        StressArgs {
            sequences,
            transforms: Vec::new(),
            set: vec!["occlude.gap_min=2".into(), "occlude.gap_max=3".into()],
            seed: 3,
            jpeg_quality: 90,
            out,
        }
    }

    /// Every file below `dir`, with its bytes, in a fixed order.
    fn tree(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
        let mut files = Vec::new();
        let mut stack = vec![dir.to_path_buf()];
        while let Some(d) = stack.pop() {
            for e in fs::read_dir(&d).unwrap() {
                let p = e.unwrap().path();
                // The output guard's manifest is bookkeeping (in the order files were written),
                // not output.
                if p.file_name()
                    .is_some_and(|n| n == track_app::output::MANIFEST_NAME)
                {
                    continue;
                }
                if p.is_dir() {
                    stack.push(p);
                } else {
                    let bytes = fs::read(&p).unwrap();
                    files.push((p.strip_prefix(dir).unwrap().to_path_buf(), bytes));
                }
            }
        }
        files.sort();
        files
    }

    #[test]
    fn stress_writes_one_otb_folder_per_transform_and_clip_deterministically() {
        let tmp = tempfile::tempdir().unwrap();
        let (a, b) = (tmp.path().join("Alpha"), tmp.path().join("Beta"));
        otb_folder(&a, 12, 0);
        otb_folder(&b, 12, 100);
        let out = tmp.path().join("suite");
        let mut lines = Vec::new();
        run(&args(vec![a.clone(), b.clone()], out.clone()), |l| {
            lines.push(l.to_owned())
        })
        .unwrap();
        assert_eq!(lines.len(), 2, "{lines:?}");
        for t in Transform::NAMES {
            for clip in ["Alpha", "Beta"] {
                let dir = out.join(t).join(clip);
                let frames = ImageFolder::open(&dir.join("img")).unwrap();
                assert_eq!(frames.paths().len(), 12, "{t}/{clip}");
                let truth = load_groundtruth(&dir.join("groundtruth_rect.txt")).unwrap();
                assert_eq!(truth.len(), 12, "{t}/{clip}");
                let record: serde_json::Value =
                    serde_json::from_str(&fs::read_to_string(dir.join("stress.json")).unwrap())
                        .unwrap();
                assert_eq!(record["transform"], t);
                assert_eq!(record["seed"], 3);
                assert_eq!(record["stages"][0]["name"], t);
                assert_eq!(dir.join("visible.txt").exists(), t == "occlude", "{t}");
            }
        }
        // Occluders of Alpha are cut from Beta's frames only.
        let rec = fs::read_to_string(out.join("occlude/Alpha/stress.json")).unwrap();
        assert!(rec.contains("\"Beta\"") && !rec.contains("\"donors\": [\n    \"Alpha\""));
        let visible = fs::read_to_string(out.join("occlude/Alpha/visible.txt")).unwrap();
        assert_eq!(visible.lines().count(), 12);
        assert!(
            visible.lines().any(|l| l.parse::<f64>().unwrap() < 0.75),
            "{visible}"
        );
        assert!(out.join("suite.json").is_file());

        // The same inputs, settings and seed: the same bytes, file for file.
        let again = tmp.path().join("again");
        run(&args(vec![a.clone(), b.clone()], again.clone()), |_| ()).unwrap();
        assert_eq!(tree(&out), tree(&again));
        // Another seed: other frames under a seeded transform.
        let other = tmp.path().join("other");
        let mut a2 = args(vec![a, b], other.clone());
        a2.seed = 4;
        a2.transforms = vec!["grey,shake".into()];
        run(&a2, |_| ()).unwrap();
        assert_ne!(
            tree(&other.join("grey+shake")),
            tree(&out.join("shake")),
            "a composed transform has its own folder and frames"
        );
        assert!(!other.join("shake").exists());
    }

    #[test]
    fn a_bad_input_folder_is_named_in_the_error() {
        let tmp = tempfile::tempdir().unwrap();
        let good = tmp.path().join("Good");
        otb_folder(&good, 4, 0);
        let missing = tmp.path().join("Missing");
        let err = run(
            &args(vec![good.clone(), missing.clone()], tmp.path().join("o")),
            |_| (),
        )
        .unwrap_err();
        assert!(
            err.contains("Missing") && err.contains("not a folder"),
            "{err}"
        );
        let bare = tmp.path().join("Bare");
        fs::create_dir_all(bare.join("img")).unwrap();
        let err = run(&args(vec![bare], tmp.path().join("o")), |_| ()).unwrap_err();
        assert!(
            err.contains("Bare") && err.contains("groundtruth_rect.txt"),
            "{err}"
        );
        let short = tmp.path().join("Short");
        otb_folder(&short, 4, 0);
        fs::write(short.join("groundtruth_rect.txt"), "1,2,3,4\n").unwrap();
        let err = run(&args(vec![short], tmp.path().join("o")), |_| ()).unwrap_err();
        assert!(
            err.contains("Short") && err.contains("1 ground-truth lines for 4 frames"),
            "{err}"
        );
        let mut bad = args(vec![good.clone()], tmp.path().join("o"));
        bad.transforms = vec!["wobble".into()];
        assert!(run(&bad, |_| ()).unwrap_err().contains("wobble"));
        let mut bad = args(vec![good], tmp.path().join("o"));
        bad.set = vec!["shake.zoom=0.5".into()];
        assert!(run(&bad, |_| ()).unwrap_err().contains("shake.zoom"));
    }

    #[test]
    fn the_suite_goes_through_the_output_guard() {
        let tmp = tempfile::tempdir().unwrap();
        let clip = tmp.path().join("Alpha");
        otb_folder(&clip, 4, 0);
        let quick = |out: PathBuf| {
            let mut a = args(vec![clip.clone()], out);
            a.transforms = vec!["grey".into()];
            a
        };
        // Into an input: refused, and nothing written there.
        let err = run(&quick(clip.join("suite")), |_| ()).unwrap_err();
        assert!(err.contains("inside") || err.contains("input"), "{err}");
        assert!(!clip.join("suite").exists());
        // A file of the user's where an output goes: refused, and kept.
        let out = tmp.path().join("suite");
        fs::create_dir_all(&out).unwrap();
        fs::write(out.join("suite.json"), "mine").unwrap();
        assert!(run(&quick(out.clone()), |_| ()).is_err());
        assert_eq!(fs::read_to_string(out.join("suite.json")).unwrap(), "mine");
        // Its own earlier output is replaced.
        fs::remove_file(out.join("suite.json")).unwrap();
        run(&quick(out.clone()), |_| ()).unwrap();
        run(&quick(out.clone()), |_| ()).unwrap();
        assert!(out.join("grey/Alpha/stress.json").is_file());
    }
}
