//! The paper trackers' self-evaluation α̂ on frames with no target: on pure
//! noise and on a static checkerboard, `full` must not claim the track is locked, while on a
//! scene with a target it still says locked. Several noise draws and tracker seeds each.

use dbn_switch::TrackStatus;
use rand::{Rng, SeedableRng};
use trackers::{Frame, Preset, build};
use vision_core::Ellipse;

const W: usize = 320;
const H: usize = 240;
const FRAMES: usize = 25;
/// Frames left to the chains to forget the initial "locked".
const SETTLE: usize = 5;

/// Share of the frames after [`SETTLE`] on which α̂ is "locked".
fn locked_share(frames: &[Vec<f32>], size: (usize, usize), start: Ellipse, seed: u64) -> f64 {
    let mut tracker = build(Preset::Full.config(200, seed)).unwrap();
    let mut locked = 0;
    for (k, f) in frames.iter().enumerate() {
        let frame = Frame::new(size.0, size.1, f).unwrap();
        let e = if k == 0 {
            tracker.init(frame, start).unwrap()
        } else {
            tracker.update(frame).unwrap()
        };
        if k >= SETTLE && e.status.expect("full reports a status").alpha_hat == TrackStatus::Locked
        {
            locked += 1;
        }
    }
    f64::from(locked) / (frames.len() - SETTLE) as f64
}

fn start() -> Ellipse {
    Ellipse {
        cx: 160.0,
        cy: 125.0,
        a: 30.0,
        b: 35.0,
        angle: 0.0,
    }
}

#[test]
fn full_does_not_claim_a_lock_on_pure_noise() {
    for seed in 1..=3u64 {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let frames: Vec<Vec<f32>> = (0..FRAMES)
            .map(|_| (0..W * H).map(|_| rng.random_range(0.0..255.0)).collect())
            .collect();
        let share = locked_share(&frames, (W, H), start(), seed);
        assert!(
            share <= 0.2,
            "seed {seed}: locked on {share:.2} of the noise frames"
        );
    }
}

#[test]
fn full_does_not_claim_a_lock_on_a_static_checkerboard() {
    for (seed, cell) in [(1u64, 20usize), (2, 16), (3, 24)] {
        let board: Vec<f32> = (0..W * H)
            .map(|i| {
                let (x, y) = (i % W, i / W);
                if (x / cell + y / cell) % 2 == 0 {
                    30.0
                } else {
                    220.0
                }
            })
            .collect();
        let frames = vec![board; FRAMES];
        let share = locked_share(&frames, (W, H), start(), seed);
        assert!(
            share <= 0.2,
            "seed {seed}, cells of {cell} px: locked on {share:.2} of the frames"
        );
    }
}

#[test]
fn full_still_claims_a_lock_on_a_visible_target() {
    // A bright ellipse drifting across a dim, noisy background: a target any tracker sees.
    for seed in 1..=3u64 {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let target = |k: usize| Ellipse {
            cx: 120.0 + 3.0 * k as f64,
            ..start()
        };
        let frames: Vec<Vec<f32>> = (0..FRAMES)
            .map(|k| {
                let e = target(k);
                (0..W * H)
                    .map(|i| {
                        let (u, v) = (((i % W) as f64 - e.cx) / e.a, ((i / W) as f64 - e.cy) / e.b);
                        let level = if u * u + v * v <= 1.0 { 180.0 } else { 70.0 };
                        level + rng.random_range(-10.0..10.0)
                    })
                    .collect()
            })
            .collect();
        let share = locked_share(&frames, (W, H), target(0), seed);
        assert!(
            share >= 0.8,
            "seed {seed}: locked on only {share:.2} of the frames"
        );
    }
}
