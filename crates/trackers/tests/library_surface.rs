//! The library as a user adds it: everything a tracker
//! reports is named through `trackers` alone, image-crate images become frames, a rotated
//! ellipse is refused by trackers of axis-aligned ones, and frame errors name the right frame.

use trackers::prelude::*;

/// A 96×72 grey disc of radius 14 at (30 + 2k, 36) on a textured background, as an image-crate
/// image.
fn disc(k: usize) -> image::GrayImage {
    image::GrayImage::from_fn(96, 72, |x, y| {
        let (x, y) = (f64::from(x), f64::from(y));
        let d = ((x - 30.0 - 2.0 * k as f64).powi(2) + (y - 36.0).powi(2)).sqrt();
        let texture = 20.0 * ((0.7 * x).sin() * (0.9 * y).cos());
        image::Luma([(if d < 14.0 { 200.0 } else { 60.0 + texture }) as u8])
    })
}

#[test]
fn every_field_of_an_estimate_is_named_through_trackers() {
    let mut tracker = build_preset("w-eval", 60, 3).unwrap();
    let first = FrameBuf::from(disc(0));
    let start = Ellipse::new(30.0, 36.0, 14.0, 14.0, 0.0);
    tracker.init(first.frame().unwrap(), start).unwrap();
    let next = FrameBuf::from(&image::DynamicImage::ImageLuma8(disc(1)));
    let estimate: Estimate = tracker.update(next.frame().unwrap()).unwrap();
    // Each field's type, spelt with `trackers::` paths only (this does not compile unless the
    // crate re-exports them).
    let Estimate {
        frame,
        ellipse,
        bbox,
        state,
        ess,
        diagnostics,
        clutter,
        gamma,
        status,
        motion_clusters,
        millis,
    } = estimate;
    let _: (usize, f64, f64, (usize, usize)) = (frame, ess, millis, motion_clusters);
    let ellipse: trackers::Ellipse = ellipse;
    let bbox: trackers::BoundingBox = bbox;
    let _: trackers::StateVector = state;
    let diagnostics: trackers::StepDiagnostics = diagnostics.unwrap();
    let clutter: trackers::ClutterEstimate = clutter.unwrap();
    let status: trackers::StatusEstimate = status.unwrap();
    let _: trackers::TrackStatus = status.alpha_hat;
    let _: Option<f64> = gamma;
    assert_eq!(frame, 1);
    assert!(bbox.iou(&ellipse.bounding_box()) > 0.999);
    assert!(diagnostics.ess > 0.0 && clutter.lambda_hat > 0.0);
    assert!((status.alpha_probs.iter().sum::<f64>() - 1.0).abs() < 1e-9);
}

#[test]
fn image_crate_frames_track_like_slices_of_grey_levels() {
    // The same run fed through FrameBuf (from image-crate images) and through slices of grey
    // levels 0–255 built by hand gives the same estimates, bit for bit.
    let via_image: Vec<Estimate> = {
        let mut t = build(Preset::M1.config(80, 5)).unwrap();
        let mut out = vec![
            t.init(
                FrameBuf::from(disc(0)).frame().unwrap(),
                Ellipse::new(30.0, 36.0, 14.0, 14.0, 0.0),
            )
            .unwrap(),
        ];
        for k in 1..5 {
            let owned = FrameBuf::from(image::DynamicImage::ImageLuma8(disc(k)));
            out.push(t.update(owned.frame().unwrap()).unwrap());
        }
        out
    };
    let by_hand: Vec<Estimate> = {
        let mut t = build(Preset::M1.config(80, 5)).unwrap();
        let grey = |k: usize| -> Vec<f32> { disc(k).pixels().map(|p| f32::from(p[0])).collect() };
        let g0 = grey(0);
        let mut out = vec![
            t.init(
                Frame::new(96, 72, &g0).unwrap(),
                Ellipse::new(30.0, 36.0, 14.0, 14.0, 0.0),
            )
            .unwrap(),
        ];
        for k in 1..5 {
            let g = grey(k);
            out.push(t.update(Frame::new(96, 72, &g).unwrap()).unwrap());
        }
        out
    };
    for (a, b) in via_image.iter().zip(&by_hand) {
        assert_eq!(a.ellipse, b.ellipse);
    }
    // And the disc moved right, 2 px per frame.
    let last = via_image.last().unwrap().ellipse;
    assert!((last.cx - 38.0).abs() < 2.0, "{last:?}");
}

#[test]
fn a_rotated_ellipse_is_refused_by_trackers_of_axis_aligned_ellipses() {
    let frame = FrameBuf::from(disc(0));
    let tilted = Ellipse::new(30.0, 36.0, 14.0, 8.0, 0.7);
    for preset in [Preset::M1, Preset::M3, Preset::Full, Preset::Head] {
        let mut tracker = build(preset.config(40, 1)).unwrap();
        let err = tracker.init(frame.frame().unwrap(), tilted).unwrap_err();
        match &err {
            trackers::Error::InvalidSetting { name, reason } => {
                assert_eq!(*name, "initial ellipse");
                assert!(
                    reason.contains("axis-aligned") && reason.contains("0.7"),
                    "{reason}"
                );
            }
            other => panic!("{preset}: {other:?}"),
        }
    }
    // A tracker in the affine space starts from the rotated ellipse itself.
    let mut wu = build(Preset::WFixed.config(40, 1)).unwrap();
    let e = wu.init(frame.frame().unwrap(), tilted).unwrap().ellipse;
    assert!(
        (e.angle.rem_euclid(std::f64::consts::PI) - 0.7).abs() < 1e-6,
        "{e:?}"
    );
    // A quarter turn is the same ellipse with its semi-axes swapped, for every tracker.
    let quarter = Ellipse::new(30.0, 36.0, 14.0, 8.0, std::f64::consts::FRAC_PI_2);
    for preset in [Preset::M1, Preset::Head] {
        let mut tracker = build(preset.config(40, 1)).unwrap();
        let e = tracker
            .init(frame.frame().unwrap(), quarter)
            .unwrap()
            .ellipse;
        // 16 px wide and 28 px tall, however the tracker writes it (a shape space may report the
        // longer axis first, at angle π/2).
        let [_, _, w, h] = e.bounding_box().to_array();
        assert!(
            (w - 16.0).abs() < 1e-6 && (h - 28.0).abs() < 1e-6,
            "{preset}: {e:?}"
        );
    }
}

#[test]
fn a_frame_of_another_size_is_named_by_its_index() {
    let small = image::GrayImage::from_pixel(40, 30, image::Luma([90]));
    for config in [
        Preset::M1.config(40, 1),
        TrackerConfig {
            // A tracker that shrinks its frames (a different code path).
            working_radius: Some(6.0),
            ..Preset::M1.config(40, 1)
        },
        Preset::Head.config(40, 1),
    ] {
        let mut tracker = build(config).unwrap();
        tracker
            .init(
                FrameBuf::from(disc(0)).frame().unwrap(),
                Ellipse::new(30.0, 36.0, 14.0, 14.0, 0.0),
            )
            .unwrap();
        for k in 1..3 {
            tracker
                .update(FrameBuf::from(disc(k)).frame().unwrap())
                .unwrap();
        }
        let err = tracker
            .update(FrameBuf::from(&small).frame().unwrap())
            .unwrap_err();
        assert!(
            matches!(err, trackers::Error::BadFrame { frame: 3, .. }),
            "{}: {err:?}",
            tracker.name()
        );
        assert!(err.to_string().starts_with("frame 3:"), "{err}");
    }
}
