//! `cargo xtask`: project automation. Thin by design: generation logic lives in library crates.

mod camera_zoom;
mod stress;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use scene_synth::{Scenario, ScenarioParams, Scene, write_sequence};

/// Project automation for the contour-tracking workspace.
#[derive(Debug, Parser)]
#[command(name = "cargo xtask")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Write a synthetic clutter sequence with full ground truth (OTB layout + groundtruth.csv +
    /// scene.json).
    GenClutter(GenClutter),
    /// Lay a known camera zoom over OTB folders of real footage: each frame cropped about a point
    /// that follows the labelled target and resized back, the ground truth mapped alike, written
    /// as OTB folders (`OUT/<sequence>`: img/, groundtruth_rect.txt, camera_zoom.csv and .json).
    CameraZoom(camera_zoom::CameraZoomArgs),
    /// The stress suite: every failure class (shake, occlude, tilt, grey, small, light, zoom)
    /// laid over OTB folders of real footage, with the truth mapped alike, written as OTB
    /// folders `OUT/<transform>/<clip>` (img/, groundtruth_rect.txt, stress.json, visible.txt).
    Stress(stress::StressArgs),
}

/// Arguments of `gen-clutter`.
#[derive(Debug, clap::Args)]
struct GenClutter {
    /// Scenario preset: mclutter, occlusion, distractor or zoom.
    #[arg(long, required_unless_present = "all", conflicts_with = "all")]
    scenario: Option<String>,
    /// Write every scenario into subfolders `DIR/<scenario>`.
    #[arg(long)]
    all: bool,
    /// Random seed (the output is a pure function of the parameters and the seed).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Number of frames (default: the preset's, 120).
    #[arg(long)]
    frames: Option<usize>,
    /// Frame size WxH (default 320x240).
    #[arg(long, value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// Override a parameter: a dotted path and a JSON value, e.g. `--set target.contrast_min=0.3`
    /// or `--set occluder=null`. Repeatable; applied in order after --frames/--size.
    #[arg(long = "set", value_name = "PATH=JSON")]
    set: Vec<String>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got `{s}`"))?;
    let w = w
        .trim()
        .parse()
        .map_err(|e| format!("bad width `{w}`: {e}"))?;
    let h = h
        .trim()
        .parse()
        .map_err(|e| format!("bad height `{h}`: {e}"))?;
    Ok((w, h))
}

fn params_for(sc: Scenario, args: &GenClutter) -> Result<ScenarioParams, String> {
    let mut p = ScenarioParams::preset(sc);
    if let Some(n) = args.frames {
        p.frames = n;
    }
    if let Some((w, h)) = args.size {
        p.width = w;
        p.height = h;
    }
    for spec in &args.set {
        p = p.with_override(spec).map_err(|e| e.to_string())?;
    }
    p.validate().map_err(|e| e.to_string())?;
    Ok(p)
}

/// Writes the sequence of `scene` into `dir` through track's output guard: what an earlier run
/// wrote there is replaced, no other file is touched. The scene is written to a temporary
/// folder first, then each file atomically into `dir`.
fn write_guarded(dir: &std::path::Path, scene: &Scene) -> Result<usize, String> {
    let _folder = track_app::output::OutputGuard::new::<&std::path::Path>([])
        .folder(dir)
        .map_err(|e| e.to_string())?;
    let tmp = tempfile::tempdir().map_err(|e| e.to_string())?;
    let n = write_sequence(tmp.path(), scene).map_err(|e| e.to_string())?;
    copy_tree(tmp.path(), dir)?;
    Ok(n)
}

/// Copies every file below `from` to the same place below `to`, atomically.
fn copy_tree(from: &std::path::Path, to: &std::path::Path) -> Result<(), String> {
    let entries = std::fs::read_dir(from).map_err(|e| format!("{}: {e}", from.display()))?;
    for entry in entries {
        let entry = entry.map_err(|e| format!("{}: {e}", from.display()))?;
        let (src, dst) = (entry.path(), to.join(entry.file_name()));
        if src.is_dir() {
            copy_tree(&src, &dst)?;
        } else {
            let bytes = std::fs::read(&src).map_err(|e| format!("{}: {e}", src.display()))?;
            track_app::output::write_atomic(&dst, &bytes).map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}

fn gen_clutter(args: &GenClutter) -> Result<(), String> {
    let jobs: Vec<(Scenario, PathBuf)> = if args.all {
        Scenario::ALL
            .iter()
            .map(|&sc| (sc, args.out.join(sc.name())))
            .collect()
    } else {
        let name = args.scenario.as_deref().unwrap_or_default();
        let sc: Scenario = name
            .parse()
            .map_err(|e: scene_synth::Error| e.to_string())?;
        vec![(sc, args.out.clone())]
    };
    for (sc, dir) in jobs {
        let p = params_for(sc, args)?;
        let scene = Scene::new(&p, args.seed).map_err(|e| format!("{sc}: {e}"))?;
        let n = write_guarded(&dir, &scene).map_err(|e| format!("{sc}: {e}"))?;
        let dens: Vec<String> = scene
            .background()
            .regions
            .iter()
            .map(|r| format!("β={} λ={:.4}", r.class.index(), r.measured))
            .collect();
        println!(
            "{sc}: {n} frames {}x{} → {} ({})",
            p.width,
            p.height,
            dir.display(),
            dens.join(", ")
        );
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::GenClutter(args) => gen_clutter(args),
        Command::CameraZoom(args) => camera_zoom::run(args, |line| println!("{line}")),
        Command::Stress(args) => stress::run(args, |line| println!("{line}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_and_sizes_parse() {
        let p = ScenarioParams::preset(Scenario::Occlusion);
        let q = p.with_override("target.contrast_min=0.3").unwrap();
        assert_eq!(q.target.contrast_min, 0.3);
        assert!(p.with_override("occluder=null").unwrap().occluder.is_none());
        assert!(p.with_override("nonsense").is_err());
        assert_eq!(parse_size("640x480").unwrap(), (640, 480));
        assert!(parse_size("640").is_err());
    }
}
