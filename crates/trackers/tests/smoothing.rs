//! Smoothing a recorded run (`Tracker::smoothed`): the smoothed estimates cover every
//! updated frame, the last one is the filter's own, and a tracker that records nothing says so.

use trackers::{Frame, Preset, SmootherSettings, TrackerConfig, build};
use vision_core::Ellipse;

/// The disc's first-frame contour.
const START: Ellipse = Ellipse {
    cx: 45.0,
    cy: 45.0,
    a: 22.0,
    b: 22.0,
    angle: 0.0,
};

/// A bright disc of radius 22 on a textured background, moving 2 px right per frame.
fn frame_at(k: usize) -> (usize, usize, Vec<f32>) {
    let (w, h) = (120, 90);
    let data = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64, (i / w) as f64);
            let d = ((x - 45.0 - 2.0 * k as f64).powi(2) + (y - 45.0).powi(2)).sqrt();
            let texture = 20.0 * ((0.7 * x).sin() * (0.9 * y).cos());
            (if d < 22.0 { 200.0 } else { 60.0 + texture }) as f32
        })
        .collect();
    (w, h, data)
}

fn recording(preset: Preset, seed: u64) -> TrackerConfig {
    let mut config = preset.config(100, seed);
    config.filter.history = Some(Default::default());
    config
}

#[test]
fn the_smoothed_run_covers_every_frame_and_ends_where_the_filter_ends() {
    let start = START;
    for preset in [Preset::M1, Preset::WHmm, Preset::WEval, Preset::Full] {
        for seed in 1..=2 {
            let mut tracker = build(recording(preset, seed)).unwrap();
            let (w, h, first) = frame_at(0);
            tracker
                .init(Frame::new(w, h, &first).unwrap(), start)
                .unwrap();
            let mut filtered = Vec::new();
            for k in 1..=12 {
                let (w, h, pixels) = frame_at(k);
                filtered.push(tracker.update(Frame::new(w, h, &pixels).unwrap()).unwrap());
            }
            let smoothed = tracker
                .smoothed(&SmootherSettings::default())
                .unwrap()
                .estimates;
            assert_eq!(smoothed.len(), filtered.len(), "{preset}");
            for (k, e) in smoothed.iter().enumerate() {
                assert_eq!(e.frame, k + 1, "{preset}");
                assert!(e.ellipse.cx.is_finite() && e.ess >= 1.0 - 1e-9, "{preset}");
                // The smoothed track follows the disc as the filtered one does.
                assert!(
                    (e.ellipse.cx - (45.0 + 2.0 * (k + 1) as f64)).abs() < 6.0,
                    "{preset} {k}"
                );
            }
            // At the last frame the smoother's weights are the filter's.
            let (last_s, last_f) = (smoothed.last().unwrap(), filtered.last().unwrap());
            assert!(
                (last_s.ellipse.cx - last_f.ellipse.cx).abs() < 1e-9,
                "{preset}"
            );
            assert!(
                (last_s.ellipse.a - last_f.ellipse.a).abs() < 1e-9,
                "{preset}"
            );
            match (last_s.gamma, last_f.gamma) {
                (Some(a), Some(b)) => assert!((a - b).abs() < 1e-9, "{preset}: {a} {b}"),
                (a, b) => assert_eq!(a, b, "{preset}"),
            }
            assert_eq!(
                last_s.clutter.as_ref().map(|c| c.beta_hat),
                last_f.clutter.as_ref().map(|c| c.beta_hat)
            );
            // The same run smooths to the same result.
            assert_eq!(
                smoothed,
                tracker
                    .smoothed(&SmootherSettings::default())
                    .unwrap()
                    .estimates
            );
        }
    }
}

#[test]
fn a_tracker_that_records_nothing_cannot_be_smoothed() {
    let mut tracker = build(Preset::WEval.config(50, 1)).unwrap();
    let (w, h, first) = frame_at(0);
    let start = START;
    tracker
        .init(Frame::new(w, h, &first).unwrap(), start)
        .unwrap();
    let (w, h, next) = frame_at(1);
    tracker.update(Frame::new(w, h, &next).unwrap()).unwrap();
    let err = tracker.smoothed(&SmootherSettings::default()).unwrap_err();
    assert!(err.to_string().contains("filter.history"), "{err}");
    let mut head = build(Preset::Head.config(50, 1)).unwrap();
    assert!(head.smoothed(&SmootherSettings::default()).is_err());
}
