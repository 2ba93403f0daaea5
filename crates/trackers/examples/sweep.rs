//! Runs a preset over a synthetic scene for several seeds and prints the mean IoU, the number of
//! failed trials and the time per frame: the harness used to choose the presets' defaults.
//!
//! `cargo run --release -p trackers --example sweep -- SCENE PRESET [PARTICLES] [SEEDS]`, with
//! SCENE one of mclutter, occlusion, distractor, zoom. Environment variables override settings:
//! FRAMES, RHO and SRHO (velocity retention of translation and shape), ST, SS, SSH (noise of
//! translation, scale and shape), LC (λ_c), TOL, IT, LEV, MINPIX (motion estimator), EST (use the
//! plain weighted mean), WIN and PD (Wu's window and detection probability), OA0 (no
//! occlusion-aware proposal), WS0 (no warm start), DEFSET (accurate motion settings),
//! FORM=independent|arc|neutral_arc|ratio and UO=share (the occlusion form of Wu's likelihood,
//! `contour_obs::OcclusionForm`, and its unknown-occluder share), LGR (κ of γ | locked,
//! `DynamicsSettings::locked_gamma_rate`), SREV (`DynamicsSettings::shape_reversion`), LOCKLO, LOCKHI, PARTLO, PARTHI (the status HMM's γ
//! ranges), SIGG (σ_γ of the random-walk γ), TLP (its locked → partially occluded probability), V (per-seed
//! lines), REACQ=1/0 (reacquisition jump on/off, `TrackerConfig::reacquisition`) with RQLOCK,
//! RQRATE, RQMAX, RQSPREAD, RQGROW, RQPG, RQVG, RQSG, RQBACK, RQSHAPE (its settings). Diagnostics: TRACE (one line per frame), LAND=k (likelihood landscape at frame k),
//! DUMP=k (frame k as a binary PGM on stdout). Besides the IoU it prints β̂ accuracy, γ̂ MAE and α̂
//! accuracy against the generator's truth (frame 0 left out, as `track eval switching`), and on a
//! scene where the target is hidden, the same split by phase of the occlusion (free before,
//! partly hidden going in, hidden, partly hidden coming out, free after; "share of γ̂ MAE" is
//! the phase's part of the overall γ̂ MAE), to see which phase the errors come from.

use contour_obs::OcclusionForm;
use scene_synth::{Scenario, ScenarioParams, Scene};
use trackers::{Frame, Preset, build};
use vision_core::{Ellipse, FAILURE_RUN, GreyImage, first_failure};
fn env(k: &str) -> Option<f64> {
    std::env::var(k).ok().and_then(|v| v.parse().ok())
}
/// The occlusion form of Wu's likelihood from FORM (independent, arc, neutral_arc, ratio) and
/// UO (the unknown-occluder share of the independent form and the arc), over `current`.
fn occlusion_form(current: OcclusionForm) -> Option<OcclusionForm> {
    let form = std::env::var("FORM").ok();
    let share = env("UO");
    if form.is_none() && share.is_none() {
        return None;
    }
    let old_share = match current {
        OcclusionForm::Independent {
            unknown_occluder_share: s,
        }
        | OcclusionForm::Arc {
            unknown_occluder_share: s,
        } => s,
        _ => 0.0,
    };
    let unknown_occluder_share = share.unwrap_or(old_share);
    let arc = OcclusionForm::Arc {
        unknown_occluder_share,
    };
    let independent = OcclusionForm::Independent {
        unknown_occluder_share,
    };
    Some(match form.as_deref() {
        Some("arc") => arc,
        Some("neutral_arc") => OcclusionForm::NeutralArc,
        Some("ratio") => OcclusionForm::Ratio,
        Some("independent") => independent,
        Some(other) => panic!("FORM={other}: one of independent, arc, neutral_arc, ratio"),
        None if matches!(current, OcclusionForm::Arc { .. }) => arc,
        None => independent,
    })
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
    if let Some(k) = env("DUMP") {
        // The frame as a binary PGM on stdout, to look at.
        let (img, _) = &frames[k as usize];
        let d = scene_synth::to_f32(img);
        let mut out = format!("P5 {} {} 255\n", img.width(), img.height()).into_bytes();
        out.extend(d.iter().map(|&v| v.clamp(0.0, 255.0) as u8));
        std::io::Write::write_all(&mut std::io::stdout(), &out).unwrap();
        return;
    }
    if let Some(k) = env("LAND") {
        let (img, truth) = &frames[k as usize];
        let d = scene_synth::to_f32(img);
        landscape(img.width() as usize, img.height() as usize, &d, truth);
        return;
    }
    let mut total = 0.0;
    let mut fails = 0;
    let mut ms = 0.0;
    let mut post_total = 0.0;
    // β̂ accuracy, γ̂ MAE and α̂ accuracy against the truth (frame 0 left out), summed over seeds.
    let mut hidden = [0.0; 3];
    // Frames after the last (almost) fully hidden one where the target is visible again: the
    // reacquisition window of the occlusion scene (empty on the other scenes).
    let vis: Vec<f64> = frames.iter().map(|(_, t)| t.visible_fraction).collect();
    let post: Vec<usize> = match vis.iter().rposition(|&v| v < 0.1) {
        Some(last) => (last..vis.len()).filter(|&k| vis[k] > 0.8).collect(),
        None => Vec::new(),
    };
    // The phase of each frame: 0 free before the occlusion, 1 partly hidden going in, 2 hidden
    // (visible ≤ 1 %), 3 partly hidden coming out, 4 free after; None without an occlusion.
    let hidden_at = vis.iter().position(|&v| v <= 0.01);
    let phase = |k: usize| -> Option<usize> {
        let h = hidden_at?;
        Some(match vis[k] {
            v if v >= 0.99 => {
                if k < h {
                    0
                } else {
                    4
                }
            }
            v if v <= 0.01 => 2,
            _ => {
                if k < h {
                    1
                } else {
                    3
                }
            }
        })
    };
    // Per phase: frames, β̂ right, γ̂ absolute error, α̂ right, IoU.
    let mut phases = [[0.0; 5]; 5];
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
        if let Some(v) = env("SREV") {
            c.dynamics.shape_reversion = v;
        }
        if let Some(v) = env("LGR") {
            c.dynamics.locked_gamma_rate = v;
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
        if let Some(form) = occlusion_form(c.likelihood.occlusion_form) {
            c.likelihood.occlusion_form = form;
        }
        if env("REACQ").is_some_and(|v| v > 0.0) {
            c.reacquisition.get_or_insert_with(Default::default);
        }
        if env("REACQ") == Some(0.0) {
            c.reacquisition = None;
        }
        if let Some(r) = c.reacquisition.as_mut() {
            for (k, slot) in [
                ("RQLOCK", &mut r.lock_gamma),
                ("RQSHAPE", &mut r.shape_tolerance),
                ("RQRATE", &mut r.share_rate),
                ("RQMAX", &mut r.max_share),
                ("RQSPREAD", &mut r.spread),
                ("RQGROW", &mut r.spread_growth),
                ("RQPG", &mut r.position_gain),
                ("RQVG", &mut r.velocity_gain),
                ("RQSG", &mut r.shape_gain),
            ] {
                if let Some(v) = env(k) {
                    *slot = v;
                }
            }
            if let Some(v) = env("RQBACK") {
                r.rollback = v as usize;
            }
        }
        if let (Some(v), trackers::OcclusionMode::RandomWalk(oc)) = (env("SIGG"), &mut c.occlusion)
        {
            oc.sigma_gamma = v;
        }
        if let trackers::OcclusionMode::Status(sc) = &mut c.occlusion {
            for (k, slot) in [
                ("LOCKLO", &mut sc.locked.low),
                ("LOCKHI", &mut sc.locked.high),
                ("PARTLO", &mut sc.partially_occluded.low),
                ("PARTHI", &mut sc.partially_occluded.high),
            ] {
                if let Some(v) = env(k) {
                    *slot = v;
                }
            }
            if let Some(v) = env("TLP") {
                // locked → partially occluded, taken from locked → locked.
                sc.transition[0][1] = v;
                sc.transition[0][0] = 1.0 - v - sc.transition[0][2];
            }
        }
        if std::env::var("OA1").is_ok() {
            c.motion.occlusion_aware = true;
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
        let (mut gerr, mut aok, mut bok, mut nh) = (0.0, 0.0, 0.0, 0.0);
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
                        angle: e.angle,
                    },
                )
                .unwrap()
            } else {
                t.update(f).unwrap()
            };
            ms += est.millis;
            let iou = est.bbox.iou(&truth.bbox);
            ious.push(iou);
            if k > 0 {
                nh += 1.0;
                let g_err = (est.gamma.unwrap_or(0.0) - (1.0 - truth.visible_fraction)).abs();
                gerr += g_err;
                let ta = truth.status.index();
                let a_ok = f64::from(u8::from(
                    est.status.as_ref().map(|s| s.alpha_hat.index()) == Some(ta),
                ));
                aok += a_ok;
                let b_ok = f64::from(u8::from(
                    est.clutter.as_ref().map(|c| c.beta_hat + 1)
                        == Some(truth.clutter_class.into()),
                ));
                bok += b_ok;
                if let Some(ph) = phase(k) {
                    for (slot, v) in phases[ph].iter_mut().zip([1.0, b_ok, g_err, a_ok, iou]) {
                        *slot += v;
                    }
                }
            }
            if std::env::var("TRACE").is_ok() {
                println!(
                    "{k:3} ab ({:4.1},{:4.1}) truth ({:6.1},{:6.1}) vis {:.2} est ({:6.1},{:6.1}) iou {iou:.2} γ {:.2} α {:?} β {:?} (true {}) ess {:.0}",
                    est.ellipse.a,
                    est.ellipse.b,
                    e.cx,
                    e.cy,
                    truth.visible_fraction,
                    est.ellipse.cx,
                    est.ellipse.cy,
                    est.gamma.unwrap_or(f64::NAN),
                    est.status.as_ref().map(|s| s.alpha_hat),
                    est.clutter.as_ref().map(|c| c.beta_hat),
                    truth.clutter_class,
                    est.ess
                );
            }
        }
        let mean: f64 = ious.iter().sum::<f64>() / ious.len() as f64;
        let post_mean = post.iter().map(|&k| ious[k]).sum::<f64>() / post.len().max(1) as f64;
        post_total += post_mean;
        // The first frame of the failing run (docs/MODELS.md's rule, `first_failure`).
        let fail = first_failure(&ious).map(|end| end + 1 - FAILURE_RUN);
        if fail.is_some() {
            fails += 1;
        }
        total += mean;
        hidden[0] += bok / nh;
        hidden[1] += gerr / nh;
        hidden[2] += aok / nh;
        if std::env::var("V").is_ok() {
            println!(
                "seed {seed}: mean IoU {mean:.3} after occlusion {post_mean:.3} fail {fail:?} β {:.3} γ MAE {:.3} α {:.3}",
                bok / nh,
                gerr / nh,
                aok / nh
            );
        }
    }
    println!(
        "{} {}: mean IoU {:.3} (after occlusion {:.3}), failures {}/{}, {:.2} ms/frame",
        args[1],
        args[2],
        total / seeds as f64,
        post_total / seeds as f64,
        fails,
        seeds,
        ms / (seeds as f64 * frames.len() as f64)
    );
    println!(
        "  β̂ {:.3}, γ̂ MAE {:.3}, α̂ {:.3} (means over seeds)",
        hidden[0] / seeds as f64,
        hidden[1] / seeds as f64,
        hidden[2] / seeds as f64
    );
    let frames_scored: f64 = phases.iter().map(|p| p[0]).sum();
    if frames_scored > 0.0 {
        println!("  phase           frames  β̂      γ̂ MAE  share of γ̂ MAE  α̂      IoU");
        let names = [
            "free before",
            "partly in",
            "hidden",
            "partly out",
            "free after",
        ];
        for (name, p) in names.iter().zip(&phases) {
            if p[0] > 0.0 {
                println!(
                    "  {name:<14} {:7} {:6.3} {:6.3} {:15.3} {:6.3} {:6.3}",
                    p[0],
                    p[1] / p[0],
                    p[2] / p[0],
                    p[2] / frames_scored,
                    p[3] / p[0],
                    p[4] / p[0]
                );
            }
        }
    }
}

/// Prints Wu's log-likelihood (λ = medium, line fraction 0.5) of the true contour shifted
/// horizontally and scaled, for a few γ: where the likelihood pulls a partly hidden contour.
fn landscape(w: usize, h: usize, d: &[f32], truth: &scene_synth::FrameTruth) {
    use contour_obs::{OcclusionLikelihood, Template, WuSettings};
    let view = GreyImage::new(w, h, d).unwrap();
    let settings = WuSettings {
        window: env("WIN").unwrap_or(8.0),
        ..WuSettings::default()
    };
    let lik = OcclusionLikelihood::new(settings, &Template::UnitCircle).unwrap();
    let mut ws = lik.workspace().unwrap();
    let e = truth.ellipse;
    for scale in [1.0, 1.15] {
        for dx in (-16..=16).step_by(2) {
            let el = Ellipse {
                cx: e.cx + dx as f64,
                cy: e.cy,
                a: e.a * scale,
                b: e.b * scale,
                angle: e.angle,
            };
            let x = trackers::ShapeSpace::Affine.from_ellipse(&el);
            let pose = trackers::ShapeSpace::Affine.pose(&x);
            let vals: Vec<String> = [0.0, 0.3, 0.7, 1.0]
                .iter()
                .map(|&g| {
                    let v = lik
                        .log_likelihood(&mut ws, &view, &pose, 0.0412, g)
                        .unwrap();
                    let bg: f64 = (0..ws.len())
                        .map(|i| {
                            let m = ws.edges(i).len();
                            let mu = 0.0412 * ws.observed_length(i);
                            m as f64 * mu.ln() - mu - (1..=m).map(|j| (j as f64).ln()).sum::<f64>()
                        })
                        .sum();
                    format!("{v:7.2} [{:6.2}]", v - bg)
                })
                .collect();
            let edges: usize = (0..ws.len()).map(|i| ws.edges(i).len()).sum();
            println!("s {scale} dx {dx:3}: {} edges {edges}", vals.join(" "));
        }
    }
}
