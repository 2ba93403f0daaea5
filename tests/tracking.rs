//! End-to-end tracking on generated sequences with exact ground truth: every preset follows a
//! short sequence, the motion proposal survives an abrupt motion that breaks CONDENSATION with
//! tight dynamics, the occlusion process rises with a real occlusion, the reacquisition jump
//! finds the target again after it, the detection jump keeps `head` on a target whose motion
//! outruns its prior, and `head` follows a target that zooms.

use scene_synth::{FrameTruth, Scenario, ScenarioParams, Scene};
use trackers::{Estimate, Preset, TrackerConfig, build};
use vision_core::{Ellipse, first_failure};

/// A rendered scene: frames (grey f32) and truth.
struct Clip {
    width: usize,
    height: usize,
    frames: Vec<Vec<f32>>,
    truth: Vec<FrameTruth>,
}

fn clip(scenario: Scenario, frames: usize) -> Clip {
    let mut p = ScenarioParams::preset(scenario);
    p.frames = frames;
    render(&p)
}

fn render(p: &ScenarioParams) -> Clip {
    let scene = Scene::new(p, 1).unwrap();
    let (width, height) = scene.size();
    let mut out = Clip {
        width,
        height,
        frames: Vec::new(),
        truth: Vec::new(),
    };
    for k in 0..scene.len() {
        let (img, t) = scene.render_frame(k).unwrap();
        out.frames.push(scene_synth::to_f32(&img));
        out.truth.push(t);
    }
    out
}

fn track(clip: &Clip, config: TrackerConfig) -> Vec<Estimate> {
    let mut tracker = build(config).unwrap();
    let e = clip.truth[0].ellipse;
    let start = Ellipse {
        cx: e.cx,
        cy: e.cy,
        a: e.a,
        b: e.b,
        angle: e.angle,
    };
    clip.frames
        .iter()
        .enumerate()
        .map(|(k, f)| {
            let frame = trackers::Frame::new(clip.width, clip.height, f).unwrap();
            if k == 0 {
                tracker.init(frame, start).unwrap()
            } else {
                tracker.update(frame).unwrap()
            }
        })
        .collect()
}

fn ious(clip: &Clip, estimates: &[Estimate]) -> Vec<f64> {
    estimates
        .iter()
        .zip(&clip.truth)
        .map(|(e, t)| e.bbox.iou(&t.bbox))
        .collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// docs/MODELS.md's failure rule: IoU below 0.2 for 5 consecutive frames.
fn failed(ious: &[f64]) -> bool {
    first_failure(ious).is_some()
}

#[test]
fn every_preset_follows_a_short_cluttered_sequence() {
    // 40 frames, 200 particles, seeds 1–3; the mean IoU over the three runs must exceed the
    // preset's threshold. Thresholds sit about 0.1 below what each preset measured
    // (docs/RESULTS.md), so that they catch a broken tracker (a lost track scores below 0.3)
    // without flaking on Monte Carlo noise. Most presets run on the three-band clutter scene;
    // w-occ and w-eval run on the distractor scene: on this 40-frame clip's heavy-clutter band
    // their occlusion hypotheses (γ near 1 makes the pose irrelevant) win often enough that they
    // lose the target in all three runs (measured mean IoU 0.30 and 0.23; on the 120-frame
    // `mclutter` scene they measure 0.91 over seeds 1–8) — a known weakness of Wu's occlusion
    // model with W = 8, reported rather than hidden. On the distractor scene w-occ measures 0.81
    // and w-eval 0.88.
    let mclutter = clip(Scenario::Mclutter, 40);
    let distractor = clip(Scenario::Distractor, 40);
    let cases = [
        (Preset::M1, &mclutter, 0.8),
        (Preset::M2, &mclutter, 0.8),
        (Preset::M3, &mclutter, 0.85),
        (Preset::WFixed, &mclutter, 0.8),
        (Preset::WSwitch, &mclutter, 0.8),
        (Preset::WHmm, &mclutter, 0.78),
        (Preset::WOcc, &distractor, 0.7),
        (Preset::WEval, &distractor, 0.75),
        (Preset::Full, &mclutter, 0.8),
    ];
    let mut report = Vec::new();
    for (preset, clip, threshold) in cases {
        let m = mean(
            &(1..=3)
                .map(|seed| mean(&ious(clip, &track(clip, preset.config(200, seed)))))
                .collect::<Vec<_>>(),
        );
        report.push(format!("{preset}: {m:.3} (threshold {threshold})"));
        assert!(m > threshold, "{}", report.join("\n"));
    }
    println!("{}", report.join("\n"));
}

#[test]
fn motion_proposal_survives_abrupt_motion_that_breaks_tight_condensation() {
    // The distractor scene has velocity jumps of 8–15 px/frame. With tight dynamics (σ_T = 1 px)
    // the prior cannot reach the target after a jump; the motion proposal measures the jump.
    let clip = clip(Scenario::Distractor, 120);
    let tight = |preset: Preset| {
        let mut c = preset.config(200, 1);
        c.dynamics.sigma_translation = 1.0;
        c
    };
    let m1 = ious(&clip, &track(&clip, tight(Preset::M1)));
    let m3_estimates = track(&clip, tight(Preset::M3));
    let m3 = ious(&clip, &m3_estimates);
    println!("m1 mean IoU {:.3}, m3 mean IoU {:.3}", mean(&m1), mean(&m3));
    // On this textured scene the clusters that hold particles get their own motion estimates:
    // at least one is estimated every frame (clusters left empty by k-means are not counted, see
    // `Estimate::motion_clusters`), and falling back to the prior prediction is rare — it happens
    // only where the estimator flags its fit as unreliable (`motion_est::Error::Unreliable`), as
    // while the distractor crosses the target.
    let mut frames_with_fallbacks = 0;
    for (k, e) in m3_estimates.iter().enumerate().skip(1) {
        let (used, fallbacks) = e.motion_clusters;
        assert!((1..=20).contains(&used), "frame {k}: {used} clusters");
        frames_with_fallbacks += usize::from(fallbacks > 0);
    }
    println!("frames with fallbacks: {frames_with_fallbacks}");
    assert!(
        frames_with_fallbacks * 10 <= m3_estimates.len(),
        "{frames_with_fallbacks} of {} frames had clusters falling back",
        m3_estimates.len()
    );
    assert!(failed(&m1), "m1 with σ_T = 1 px should lose the target");
    assert!(!failed(&m3), "m3 should never lose it");
    assert!(mean(&m3) > 0.8, "m3 mean IoU {}", mean(&m3));
}

#[test]
fn reacquisition_finds_the_target_after_a_full_occlusion() {
    // The frames after the last (almost) fully hidden one where the target is more than 80 %
    // visible again. Without the reacquisition jump every preset scores 0 there for every seed
    // (docs/DECISIONS.md); with it w-eval measured 0.80, 0.79, 0.89, 0.78 over seeds 1–4 (mean
    // 0.81), and 0.905, 0.783, 0.906, 0.902 (mean 0.874) since its occlusion arc. The threshold
    // on the mean over the four seeds is 0.6: one seed that stays lost would leave at most 0.6.
    let clip = clip(Scenario::Occlusion, 120);
    let visible: Vec<f64> = clip.truth.iter().map(|t| t.visible_fraction).collect();
    let last_hidden = visible.iter().rposition(|&v| v < 0.1).unwrap();
    let after: Vec<usize> = (last_hidden..visible.len())
        .filter(|&k| visible[k] > 0.8)
        .collect();
    assert!(after.len() >= 20, "reacquisition window {}", after.len());
    let per_seed: Vec<f64> = (1..=4)
        .map(|seed| {
            let iou = ious(&clip, &track(&clip, Preset::WEval.config(200, seed)));
            mean(&after.iter().map(|&k| iou[k]).collect::<Vec<_>>())
        })
        .collect();
    println!("w-eval IoU after the occlusion, seeds 1–4: {per_seed:.3?}");
    let m = mean(&per_seed);
    assert!(
        m > 0.6,
        "mean IoU after the occlusion {m:.3} ({per_seed:.3?})"
    );
}

/// γ̂ over the frames before the target is first hidden (fully visible ones), while it is hidden
/// (visible fraction < 0.1) and after it is last hidden (fully visible again).
fn gamma_phases(clip: &Clip, estimates: &[Estimate]) -> (f64, f64, f64) {
    let gamma: Vec<f64> = estimates.iter().map(|e| e.gamma.unwrap_or(0.0)).collect();
    let visible: Vec<f64> = clip.truth.iter().map(|t| t.visible_fraction).collect();
    let hidden: Vec<usize> = (0..visible.len()).filter(|&k| visible[k] < 0.1).collect();
    let (first, last) = (hidden[0], hidden[hidden.len() - 1]);
    let pick = |ks: Vec<usize>| mean(&ks.iter().map(|&k| gamma[k]).collect::<Vec<_>>());
    (
        pick((1..first).filter(|&k| visible[k] > 0.99).collect()),
        pick(hidden.clone()),
        pick(
            (last..visible.len())
                .filter(|&k| visible[k] > 0.99)
                .collect(),
        ),
    )
}

/// γ̂ of `preset` over `seeds` on the occlusion scene must rise while the target is hidden and
/// fall after it: each seed by more than 0.3 both ways, and on average below 0.2 free and after,
/// above 0.5 hidden. A tracker whose γ̂ stays flat, or stays high once the target is lost, fails.
fn assert_rise_and_fall(preset: Preset, seeds: std::ops::RangeInclusive<u64>) {
    let clip = clip(Scenario::Occlusion, 120);
    let phases: Vec<(f64, f64, f64)> = seeds
        .clone()
        .map(|seed| gamma_phases(&clip, &track(&clip, preset.config(200, seed))))
        .collect();
    println!("{preset} γ̂ free / hidden / after, seeds {seeds:?}: {phases:.3?}");
    for &(free, hidden, after) in &phases {
        assert!(hidden - free > 0.3, "{preset}: no rise: {phases:.3?}");
        assert!(hidden - after > 0.3, "{preset}: no fall: {phases:.3?}");
    }
    let avg = |f: fn(&(f64, f64, f64)) -> f64| mean(&phases.iter().map(f).collect::<Vec<_>>());
    let (free, hidden, after) = (avg(|p| p.0), avg(|p| p.1), avg(|p| p.2));
    assert!(free < 0.2, "{preset}: γ̂ while free {free:.3}");
    assert!(hidden > 0.5, "{preset}: γ̂ while hidden {hidden:.3}");
    assert!(after < 0.2, "{preset}: γ̂ after {after:.3}");
}

#[test]
fn occlusion_estimate_rises_while_hidden_and_falls_after() {
    // w-occ's γ̂ rises during the occlusion and falls after it. Both occlusion presets
    // read γ as the hidden fraction of the contour, hidden as one arc whose lines all score one
    // constant (`contour_obs::OcclusionForm::NeutralArc`), so "whole contour
    // at the true pose, partly hidden" beats "shrunk onto the visible sliver", the hidden target
    // coasts, and the reacquisition jump finds it again. w-occ's γ is Wu's random walk with
    // σ_γ = 0.3 (`W_OCC_SIGMA_GAMMA`), w-eval's the status HMM's.
    //
    // Measured γ̂ free / hidden / after: w-occ, seeds 1–8: 0.068 / 0.818 / 0.068,
    // 0.083 / 0.929 / 0.093, 0.065 / 0.886 / 0.091, 0.138 / 0.621 / 0.088, 0.097 / 0.800 / 0.076,
    // 0.075 / 0.720 / 0.083, 0.126 / 0.930 / 0.112, 0.073 / 0.909 / 0.073; w-eval, seeds 1–4:
    // 0.113 / 0.772 / 0.112, 0.116 / 0.617 / 0.111, 0.129 / 0.793 / 0.105, 0.106 / 0.865 / 0.105.
    // Wu's Eq. 11–12 as printed (w-occ without the occlusion arc) rose to 0.93 and stayed there to
    // the end, lost; with the arc but σ_γ = 0.1, γ̂ did not rise on seeds 1, 3 and 6.
    assert_rise_and_fall(Preset::WOcc, 1..=8);
    assert_rise_and_fall(Preset::WEval, 1..=4);
}

#[test]
fn the_detection_jump_keeps_head_on_a_target_that_outruns_its_prior() {
    // Every third frame of the distractor scene: velocity jumps of 24–45 px between frames,
    // beyond head's constant-velocity prior. A share of the prior drawn around the
    // appearance's detection (uniform over the search window a priori) brings particles there.
    let full = clip(Scenario::Distractor, 240);
    let clip = Clip {
        width: full.width,
        height: full.height,
        frames: full.frames.iter().step_by(3).cloned().collect(),
        truth: full.truth.iter().step_by(3).cloned().collect(),
    };
    for seed in 1..=4 {
        let run = |share: f64| {
            let mut c = Preset::Head.config(200, seed);
            c.reacquisition.as_mut().unwrap().detection_share = share;
            mean(&ious(&clip, &track(&clip, c)))
        };
        let (without, with) = (run(0.0), run(0.1));
        println!("seed {seed}: mean IoU {without:.3} without the jump, {with:.3} with it");
        assert!(
            with > without + 0.03,
            "seed {seed}: {with:.3} with the jump, {without:.3} without"
        );
    }
}

#[test]
fn head_follows_a_target_that_zooms_out_and_back() {
    // The zoom scene with two changes of 60 % over 10 frames: the target's size goes from 50 px
    // to 20 px and back to 32 px. Held-out footage had targets that zoom; a pull of the size
    // towards a remembered one (`dynamics.shape_reversion` 0.05, which gains on the development
    // set) fails here: the box stays near 43 px while the target is 20 px, as did an
    // abrupt-motion jump that kept the last estimate's size (docs/DECISIONS.md).
    // The per-seed mean IoU moves with the draws alone: `head`'s, over seeds 1–40, averages
    // 0.684 with a spread (s.d.) of 0.081, five seeds below 0.6 and the lowest at 0.469 (with
    // five motion clusters 0.694, 0.065 and three), so neither one seed nor a mean over eight
    // can judge it. The test reads 24 seeds (`head`: mean 0.681, four below 0.6) and asks for a
    // mean above 0.665, about two standard errors of a 24-seed mean under the 40-seed ones, and
    // at most five seeds below 0.6, which `head`'s own rate exceeds on few draws of 24; the size
    // pull scores 0.648.
    let mut p = ScenarioParams::preset(Scenario::Zoom);
    p.frames = 200;
    let changes = p.scale_changes.as_mut().unwrap();
    changes.count = 2;
    changes.magnitude = [0.6, 0.6];
    changes.bounds = [0.4, 2.0];
    changes.duration = 10;
    let clip = render(&p);
    let sizes: Vec<f64> = clip.truth.iter().map(|t| t.bbox.area().sqrt()).collect();
    let (small, large) = sizes
        .iter()
        .fold((f64::MAX, 0.0_f64), |(lo, hi), &s| (lo.min(s), hi.max(s)));
    assert!(
        large > 2.0 * small,
        "the scene zooms by {:.2}",
        large / small
    );
    let means: Vec<f64> = (1..=24)
        .map(|seed| {
            let m = mean(&ious(&clip, &track(&clip, Preset::Head.config(200, seed))));
            println!("seed {seed}: head's mean IoU through the zoom {m:.3}");
            m
        })
        .collect();
    let collapsed = means.iter().filter(|&&m| m < 0.6).count();
    assert!(
        collapsed <= 5,
        "{collapsed} of 24 seeds collapsed: {means:.3?}"
    );
    assert!(
        mean(&means) > 0.665,
        "mean IoU over seeds 1–24: {means:.3?}"
    );
}
