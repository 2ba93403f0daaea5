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
use trackers::{Estimate, Frame, Preset, Tracker, TrackerConfig, build};
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

/// The command line: the scene, the preset, the number of particles and of seeds.
struct Cli {
    scene: String,
    preset_name: String,
    scenario: Scenario,
    preset: Preset,
    particles: usize,
    seeds: u64,
}

/// One rendered frame and the generator's truth for it.
type SceneFrame = (image::GrayImage, scene_synth::FrameTruth);

/// Sums over the seeds (and, for `ms` and `phases`, over their frames), in the order they are
/// run.
#[derive(Default)]
struct Totals {
    /// Mean IoU, summed over seeds.
    total: f64,
    /// Seeds whose run failed.
    fails: usize,
    /// Milliseconds per frame, summed over seeds and frames.
    ms: f64,
    /// Mean IoU after the occlusion, summed over seeds.
    post_total: f64,
    /// β̂ accuracy, γ̂ MAE and α̂ accuracy against the truth (frame 0 left out), summed over seeds.
    hidden: [f64; 3],
    /// Per phase: frames, β̂ right, γ̂ absolute error, α̂ right, IoU.
    phases: [[f64; 5]; 5],
}

/// Where the target is hidden in the scene, read from the truth's visible fractions.
struct Occlusion {
    vis: Vec<f64>,
    /// Frames after the last (almost) fully hidden one where the target is visible again: the
    /// reacquisition window of the occlusion scene (empty on the other scenes).
    post: Vec<usize>,
    /// The first frame where the target is hidden (visible ≤ 1 %).
    hidden_at: Option<usize>,
}

impl Occlusion {
    fn new(frames: &[SceneFrame]) -> Self {
        let vis: Vec<f64> = frames.iter().map(|(_, t)| t.visible_fraction).collect();
        let post: Vec<usize> = match vis.iter().rposition(|&v| v < 0.1) {
            Some(last) => (last..vis.len()).filter(|&k| vis[k] > 0.8).collect(),
            None => Vec::new(),
        };
        let hidden_at = vis.iter().position(|&v| v <= 0.01);
        Self {
            vis,
            post,
            hidden_at,
        }
    }

    /// The phase of frame `k`: 0 free before the occlusion, 1 partly hidden going in, 2 hidden
    /// (visible ≤ 1 %), 3 partly hidden coming out, 4 free after; None without an occlusion.
    fn phase(&self, k: usize) -> Option<usize> {
        let h = self.hidden_at?;
        Some(match self.vis[k] {
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
    }
}

fn main() {
    let cli = parse_args();
    let frames = render_scene(cli.scenario);
    if show_diagnostic(&frames) {
        return;
    }
    let occlusion = Occlusion::new(&frames);
    let mut totals = Totals::default();
    for seed in 1..=cli.seeds {
        let c = configure(cli.preset.config(cli.particles, seed));
        run_seed(c, seed, &frames, &occlusion, &mut totals);
    }
    report(&cli, &totals, frames.len());
}

/// Reads SCENE PRESET [PARTICLES] [SEEDS] from the command line.
fn parse_args() -> Cli {
    let args: Vec<String> = std::env::args().collect();
    let scenario = match args[1].as_str() {
        "mclutter" => Scenario::Mclutter,
        "distractor" => Scenario::Distractor,
        "zoom" => Scenario::Zoom,
        _ => Scenario::Occlusion,
    };
    let preset = Preset::from_name(&args[2]).unwrap();
    let particles: usize = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(200);
    let seeds: u64 = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(3);
    Cli {
        scene: args[1].clone(),
        preset_name: args[2].clone(),
        scenario,
        preset,
        particles,
        seeds,
    }
}

/// The frames of the scenario's scene (FRAMES of them when set).
fn render_scene(scenario: Scenario) -> Vec<SceneFrame> {
    let mut p = ScenarioParams::preset(scenario);
    if let Some(f) = env("FRAMES") {
        p.frames = f as usize;
    }
    let scene = Scene::new(&p, 1).unwrap();
    (0..scene.len())
        .map(|k| scene.render_frame(k).unwrap())
        .collect()
}

/// Writes the frame DUMP as a binary PGM on stdout, or prints the likelihood landscape at frame
/// LAND; true when either was asked for (and nothing else is to be done).
fn show_diagnostic(frames: &[SceneFrame]) -> bool {
    if let Some(k) = env("DUMP") {
        // The frame as a binary PGM on stdout, to look at.
        let (img, _) = &frames[k as usize];
        let d = scene_synth::to_f32(img);
        let mut out = format!("P5 {} {} 255\n", img.width(), img.height()).into_bytes();
        out.extend(d.iter().map(|&v| v.clamp(0.0, 255.0) as u8));
        std::io::Write::write_all(&mut std::io::stdout(), &out).unwrap();
        return true;
    }
    if let Some(k) = env("LAND") {
        let (img, truth) = &frames[k as usize];
        let d = scene_synth::to_f32(img);
        landscape(img.width() as usize, img.height() as usize, &d, truth);
        return true;
    }
    false
}

/// The preset's configuration with the settings the environment overrides.
fn configure(mut c: TrackerConfig) -> TrackerConfig {
    override_dynamics(&mut c);
    override_likelihood(&mut c);
    override_reacquisition(&mut c);
    override_occlusion(&mut c);
    override_motion(&mut c);
    c
}

/// RHO, SRHO, SSH, ST, SREV, LGR, SS.
fn override_dynamics(c: &mut TrackerConfig) {
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
}

/// LC, the motion estimator's TOL, IT, LEV and MINPIX, EST, WIN, PD, FORM and UO.
fn override_likelihood(c: &mut TrackerConfig) {
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
}

/// REACQ and the RQ* settings of the reacquisition jump.
fn override_reacquisition(c: &mut TrackerConfig) {
    if env("REACQ").is_some_and(|v| v > 0.0) {
        c.reacquisition.get_or_insert_with(Default::default);
    }
    if env("REACQ") == Some(0.0) {
        c.reacquisition = None;
    }
    if let Some(r) = c.reacquisition.as_mut() {
        for (k, slot) in [
            ("RQLOCK", &mut r.lock_gamma),
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
}

/// SIGG of the random-walk γ; LOCKLO, LOCKHI, PARTLO, PARTHI and TLP of the status HMM.
fn override_occlusion(c: &mut TrackerConfig) {
    if let (Some(v), trackers::OcclusionMode::RandomWalk(oc)) = (env("SIGG"), &mut c.occlusion) {
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
}

/// OA1, OA0, WS0 and DEFSET (after the estimator's settings, which it replaces).
fn override_motion(c: &mut TrackerConfig) {
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
}

/// Tracks the scene with one seed's configuration and adds its scores to `totals`.
fn run_seed(
    c: TrackerConfig,
    seed: u64,
    frames: &[SceneFrame],
    occlusion: &Occlusion,
    totals: &mut Totals,
) {
    let mut t = build(c).unwrap();
    let mut ious = vec![];
    let (mut gerr, mut aok, mut bok, mut nh) = (0.0, 0.0, 0.0, 0.0);
    for (k, (img, truth)) in frames.iter().enumerate() {
        let est = track_frame(t.as_mut(), k, img, truth);
        totals.ms += est.millis;
        let iou = est.bbox.iou(&truth.bbox);
        ious.push(iou);
        if k > 0 {
            nh += 1.0;
            let (g_err, a_ok, b_ok) = frame_errors(&est, truth);
            gerr += g_err;
            aok += a_ok;
            bok += b_ok;
            if let Some(ph) = occlusion.phase(k) {
                for (slot, v) in totals.phases[ph]
                    .iter_mut()
                    .zip([1.0, b_ok, g_err, a_ok, iou])
                {
                    *slot += v;
                }
            }
        }
        if std::env::var("TRACE").is_ok() {
            trace(k, &est, truth, iou);
        }
    }
    let mean: f64 = ious.iter().sum::<f64>() / ious.len() as f64;
    let post = &occlusion.post;
    let post_mean = post.iter().map(|&k| ious[k]).sum::<f64>() / post.len().max(1) as f64;
    totals.post_total += post_mean;
    // The first frame of the failing run (docs/MODELS.md's rule, `first_failure`).
    let fail = first_failure(&ious).map(|end| end + 1 - FAILURE_RUN);
    if fail.is_some() {
        totals.fails += 1;
    }
    totals.total += mean;
    totals.hidden[0] += bok / nh;
    totals.hidden[1] += gerr / nh;
    totals.hidden[2] += aok / nh;
    if std::env::var("V").is_ok() {
        println!(
            "seed {seed}: mean IoU {mean:.3} after occlusion {post_mean:.3} fail {fail:?} β {:.3} γ MAE {:.3} α {:.3}",
            bok / nh,
            gerr / nh,
            aok / nh
        );
    }
}

/// Starts the tracker on the true ellipse at frame 0, updates it on the others.
fn track_frame(
    t: &mut dyn Tracker,
    k: usize,
    img: &image::GrayImage,
    truth: &scene_synth::FrameTruth,
) -> Estimate {
    let d = scene_synth::to_f32(img);
    let f = Frame::new(img.width() as usize, img.height() as usize, &d).unwrap();
    let e = truth.ellipse;
    if k == 0 {
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
    }
}

/// The γ̂ absolute error, and whether α̂ and β̂ are right (1 or 0), against the truth.
fn frame_errors(est: &Estimate, truth: &scene_synth::FrameTruth) -> (f64, f64, f64) {
    let g_err = (est.gamma.unwrap_or(0.0) - (1.0 - truth.visible_fraction)).abs();
    let ta = truth.status.index();
    let a_ok = f64::from(u8::from(
        est.status.as_ref().map(|s| s.alpha_hat.index()) == Some(ta),
    ));
    let b_ok = f64::from(u8::from(
        est.clutter.as_ref().map(|c| c.beta_hat + 1) == Some(truth.clutter_class.into()),
    ));
    (g_err, a_ok, b_ok)
}

/// One TRACE line: frame `k`'s estimate against the truth.
fn trace(k: usize, est: &Estimate, truth: &scene_synth::FrameTruth, iou: f64) {
    let e = truth.ellipse;
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

/// Prints the means over seeds, then the split by phase of the occlusion.
fn report(cli: &Cli, totals: &Totals, frames: usize) {
    let seeds = cli.seeds;
    println!(
        "{} {}: mean IoU {:.3} (after occlusion {:.3}), failures {}/{}, {:.2} ms/frame",
        cli.scene,
        cli.preset_name,
        totals.total / seeds as f64,
        totals.post_total / seeds as f64,
        totals.fails,
        seeds,
        totals.ms / (seeds as f64 * frames as f64)
    );
    println!(
        "  β̂ {:.3}, γ̂ MAE {:.3}, α̂ {:.3} (means over seeds)",
        totals.hidden[0] / seeds as f64,
        totals.hidden[1] / seeds as f64,
        totals.hidden[2] / seeds as f64
    );
    report_phases(&totals.phases);
}

/// The scores split by phase of the occlusion (nothing on a scene without one).
fn report_phases(phases: &[[f64; 5]; 5]) {
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
        for (name, p) in names.iter().zip(phases) {
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
