//! Runs a preset over a synthetic scene for several seeds and prints the mean IoU, the number of
//! failed trials and the time per frame: the harness used to choose the presets' defaults.
//!
//! `cargo run --release -p trackers --example sweep -- SCENE PRESET [PARTICLES] [SEEDS]`, with
//! SCENE one of mclutter, occlusion, distractor, zoom. Environment variables override settings:
//! FRAMES, RHO and SRHO (velocity retention of translation and shape), ST, SS, SSH (noise of
//! translation, scale and shape), LC (λ_c), TOL, IT, LEV, MINPIX (motion estimator), EST (use the
//! plain weighted mean), WIN and PD (Wu's window and detection probability), OA0 (no
//! occlusion-aware proposal), WS0 (no warm start), DEFSET (accurate motion settings), V (per-seed
//! lines).

use contour_obs::Ellipse;
use scene_synth::{Scenario, ScenarioParams, Scene};
use trackers::{Frame, Preset, build};
fn env(k: &str) -> Option<f64> {
    std::env::var(k).ok().and_then(|v| v.parse().ok())
}
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let sc = match args[1].as_str() {
        "mclutter" => Scenario::Mclutter,
        "distractor" => Scenario::Distractor,
        "zoom" => Scenario::Zoom,
        _ => Scenario::Occlusion,
    };
    let preset = Preset::from_name(&args[2]).unwrap();
    let n: usize = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(200);
    let seeds: u64 = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(3);
    let mut p = ScenarioParams::preset(sc);
    if let Some(f) = env("FRAMES") {
        p.frames = f as usize;
    }
    let scene = Scene::new(&p, 1).unwrap();
    let frames: Vec<_> = (0..scene.len())
        .map(|k| scene.render_frame(k).unwrap())
        .collect();
    let mut total = 0.0;
    let mut fails = 0;
    let mut ms = 0.0;
    for seed in 1..=seeds {
        let mut c = preset.config(n, seed);
        if let Some(v) = env("RHO") {
            c.dynamics.velocity_retention = v;
        }
        if let Some(v) = env("SRHO") {
            c.dynamics.shape_velocity_retention = v;
        }
        if let Some(v) = env("SSH") {
            c.dynamics.sigma_shape = v;
        }
        if let Some(v) = env("ST") {
            c.dynamics.sigma_translation = v;
        }
        if let Some(v) = env("SS") {
            c.dynamics.sigma_scale = v;
        }
        if let (Some(v), Some(m)) = (env("LC"), c.likelihood.implicit_motion.as_mut()) {
            m.lambda_c = v;
        }
        if let Some(v) = env("TOL") {
            c.motion.estimator.tolerance = v;
            c.motion.estimator.coarse_tolerance = v.max(0.01);
        }
        if let Some(v) = env("IT") {
            c.motion.estimator.max_iterations = v as usize;
        }
        if let Some(v) = env("LEV") {
            c.motion.estimator.levels = v as usize;
        }
        if let Some(v) = env("MINPIX") {
            c.motion.estimator.min_level_pixels = v as usize;
        }
        if std::env::var("EST").is_ok() {
            c.estimator = trackers::PoseEstimator::Mean;
        }
        if let (Some(v), Some(w)) = (env("WIN"), c.likelihood.clutter.as_mut()) {
            w.window = v;
        }
        if let (Some(v), Some(w)) = (env("PD"), c.likelihood.clutter.as_mut()) {
            w.p_detect = v;
        }
        if std::env::var("OA0").is_ok() {
            c.motion.occlusion_aware = false;
        }
        if std::env::var("WS0").is_ok() {
            c.motion.warm_start = false;
        }
        if std::env::var("DEFSET").is_ok() {
            c.motion.estimator = motion_est::Settings::default();
        }
        let mut t = build(c).unwrap();
        let mut ious = vec![];
        for (k, (img, truth)) in frames.iter().enumerate() {
            let d = scene_synth::to_f32(img);
            let f = Frame::new(img.width() as usize, img.height() as usize, &d).unwrap();
            let e = truth.ellipse;
            let est = if k == 0 {
                t.init(
                    f,
                    Ellipse {
                        cx: e.cx,
                        cy: e.cy,
                        a: e.a,
                        b: e.b,
                        theta: e.angle,
                    },
                )
                .unwrap()
            } else {
                t.update(f).unwrap()
            };
            ms += est.millis;
            let b = est.bbox;
            let g = truth.bbox;
            let ix = (b[0] + b[2]).min(g.x + g.w) - b[0].max(g.x);
            let iy = (b[1] + b[3]).min(g.y + g.h) - b[1].max(g.y);
            let inter = ix.max(0.0) * iy.max(0.0);
            let iou = inter / (b[2] * b[3] + g.w * g.h - inter);
            ious.push(iou);
        }
        let mean: f64 = ious.iter().sum::<f64>() / ious.len() as f64;
        let fail = ious.windows(5).position(|w| w.iter().all(|&v| v < 0.2));
        if fail.is_some() {
            fails += 1;
        }
        total += mean;
        if std::env::var("V").is_ok() {
            println!("seed {seed}: mean IoU {mean:.3} fail {fail:?}");
        }
    }
    println!(
        "{} {}: mean IoU {:.3}, failures {}/{}, {:.2} ms/frame",
        args[1],
        args[2],
        total / seeds as f64,
        fails,
        seeds,
        ms / (seeds as f64 * frames.len() as f64)
    );
}
