//! Accuracy against exact ground truth: synthetic 8-bit pairs whose warp is known
//! exactly, σ = 2 grey-level noise, mean corner error of the region below the accuracy bounds.
//!
//! Each case averages the mean corner error over three independent noise draws, so that a bound is
//! checked against the estimator's typical error rather than one lucky or unlucky draw; the
//! per-draw spread is about ±40 % of the mean (noise-limited estimates), and the bounds are
//! the original implementation's own figures, so no extra tolerance is added.
#![allow(missing_docs)]

use crate::common;

use common::*;
use motion_est::{FrameBuffers, ModelSpec, MotionEstimator, MotionModel, Region, Settings};
use vision_core::GreyImage;

const W: usize = 320;
const H: usize = 240;
const CENTRE: [f64; 2] = [159.5, 119.5];

struct Case<'a> {
    warp: Affine,
    offset: f64,
    block: Option<Block>,
    region: Region<'a>,
    corners: [f64; 4],
    spec: ModelSpec,
}

/// Mean corner error averaged over `draws` noise draws; also asserts convergence of every draw.
fn run(case: &Case<'_>, draws: u64, seed: u64) -> f64 {
    run_with(case, draws, seed, Settings::default(), None)
}

/// As `run`, with other settings and optionally a warm start from `initial`.
fn run_with(
    case: &Case<'_>,
    draws: u64,
    seed: u64,
    settings: Settings,
    initial: Option<&[f64]>,
) -> f64 {
    let tex = Texture::new(seed, 300, 40.0);
    let (c0, c1) = clean_pair(W, H, &tex, &case.warp, case.offset, case.block.as_ref());
    let est = MotionEstimator::new(settings).unwrap();
    let mut bufs = FrameBuffers::default();
    let mut total = 0.0;
    for d in 0..draws {
        let f0 = noisy(&c0, 2.0, 1000 * seed + 2 * d);
        let f1 = noisy(&c1, 2.0, 1000 * seed + 2 * d + 1);
        for (p, f) in [(&mut bufs.pyramid0, &f0), (&mut bufs.pyramid1, &f1)] {
            est.build_pyramid_into(GreyImage::new(W, H, f).unwrap(), p)
                .unwrap();
        }
        let r = est
            .estimate_from(
                &bufs.pyramid0,
                &bufs.pyramid1,
                &case.region,
                case.spec,
                Some(case.warp.origin),
                initial,
                &mut bufs.workspace,
            )
            .unwrap();
        assert!(r.converged, "draw {d} did not converge: {r:?}");
        let (mean, _, _) = corner_errors(&r, &case.warp, case.corners);
        eprintln!(
            "draw {d}: mean corner error {mean:.5} px, iterations {:?}",
            r.iterations
        );
        total += mean;
    }
    total / draws as f64
}

fn full_frame(t: [f64; 2], offset: f64, block: Option<Block>, with_offset: bool) -> Case<'static> {
    Case {
        warp: Affine::issue(CENTRE, t),
        offset,
        block,
        region: Region::Full,
        corners: [0.0, 0.0, (W - 1) as f64, (H - 1) as f64],
        spec: ModelSpec::new(MotionModel::Affine, with_offset),
    }
}

/// The 64×64 region used by the region cases, at (128, 88).
fn region_case(block: Option<Block>) -> Case<'static> {
    let (x, y) = (128.0, 88.0);
    Case {
        warp: Affine::issue([x + 31.5, y + 31.5], [3.0, -2.0]),
        offset: 0.0,
        block,
        region: Region::Rect {
            x,
            y,
            width: 64.0,
            height: 64.0,
        },
        corners: [x, y, x + 63.0, y + 63.0],
        spec: ModelSpec::new(MotionModel::Affine, false),
    }
}

#[test]
fn full_frame_affine() {
    let e = run(&full_frame([3.0, -2.0], 0.0, None, false), 3, 1);
    eprintln!("full frame: {e:.5}");
    assert!(e <= 0.0045, "{e}");
}

#[test]
fn full_frame_with_independent_block() {
    // A 160×120 block (25 % of the frame) with its own texture, moving by (6, −4) px.
    let block = Block {
        rect: [40.0, 30.0, 160.0, 120.0],
        shift: [6.0, -4.0],
        texture: Texture::new(77, 300, 40.0),
    };
    let e = run(&full_frame([3.0, -2.0], 0.0, Some(block), false), 3, 2);
    eprintln!("25 % block: {e:.5}");
    assert!(e <= 0.007, "{e}");
}

#[test]
fn full_frame_brightness_change() {
    let e = run(&full_frame([3.0, -2.0], 12.0, None, true), 3, 3);
    eprintln!("+12 brightness: {e:.5}");
    assert!(e <= 0.008, "{e}");
}

#[test]
fn full_frame_large_translation() {
    // 17 px translation plus the affine part; `run` asserts convergence.
    let e = run(&full_frame([15.0, -8.0], 0.0, None, false), 2, 4);
    eprintln!("17 px: {e:.5}");
    assert!(e <= 0.05, "{e}");
}

#[test]
fn region_64_affine() {
    let e = run(&region_case(None), 3, 5);
    eprintln!("64×64: {e:.5}");
    assert!(e <= 0.015, "{e}");
}

// The 64×64 region with a 39 % independent block, formerly one configuration on one texture draw
// (0.021 px, a lucky draw: 4 of 5 fresh draws failed), is covered by `tests/breakdown.rs` over
// positions, motions, textures and draws.

#[test]
fn tracking_preset_accuracy() {
    // The tracking preset stops at 0.01 px steps instead of 5e-4 px; Gauss–Newton converges
    // quadratically near the optimum, so the last accepted step is already far below the noise
    // limit and the accuracy bounds must still hold.
    let t = Settings::tracking();
    let e = run_with(&full_frame([3.0, -2.0], 0.0, None, false), 2, 1, t, None);
    eprintln!("tracking, full frame: {e:.5}");
    assert!(e <= 0.0045, "{e}");
    let e = run_with(&region_case(None), 3, 5, t, None);
    eprintln!("tracking, 64×64: {e:.5}");
    assert!(e <= 0.015, "{e}");
}

#[test]
fn warm_start_from_a_nearby_guess() {
    // A guess 1.2 px off in translation and 1 % off in the linear part: with two levels the
    // estimate must reach the same accuracy as the cold start (the 64×64 bound).
    let case = region_case(None);
    let a = case.warp.a;
    let guess = [a[0] - 1.0, a[1] + 0.01, a[2], a[3] + 0.7, a[4], a[5] - 0.01];
    let e = run_with(&case, 3, 5, Settings::default(), Some(&guess));
    eprintln!("warm start, 64×64: {e:.5}");
    assert!(e <= 0.015, "{e}");
}
