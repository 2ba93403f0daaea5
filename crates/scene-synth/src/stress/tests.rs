//! Every transform's truth mapping, checked on a synthetic scene whose true box is known exactly:
//! a bright ellipse inscribed in the box, on a dark textured background, moving over the frames.
//! The transformed frame's bright region must be where the mapped truth says.

use super::*;
use image::Rgb;

const SIZE: (u32, u32) = (160, 120);
const FRAMES: usize = 120;

/// The true box of frame `k`: a 24 × 30 px head swaying, at most 3 px a frame.
fn true_box(k: usize) -> BoundingBox {
    let t = k as f64;
    BoundingBox::new(
        60.0 + 20.0 * (0.15 * t).sin(),
        40.0 + 8.0 * (0.1 * t).sin(),
        24.0,
        30.0,
    )
}

fn truth() -> Vec<Option<BoundingBox>> {
    (0..FRAMES).map(|k| Some(true_box(k))).collect()
}

/// Frame `k`: pixels whose centres lie inside the ellipse inscribed in the true box are bright
/// (230, 220, 210), the rest a dark texture (under 60 in every channel).
fn frame(k: usize) -> RgbImage {
    let b = true_box(k);
    let (cx, cy) = b.centre();
    let (a, e) = (0.5 * b.w, 0.5 * b.h);
    RgbImage::from_fn(SIZE.0, SIZE.1, |i, j| {
        let (dx, dy) = ((f64::from(i) - cx) / a, (f64::from(j) - cy) / e);
        if dx * dx + dy * dy < 1.0 {
            Rgb([230, 220, 210])
        } else {
            let t = ((i * 7 + j * 13) % 40) as u8;
            Rgb([t + 10, t + 5, t])
        }
    })
}

/// The bright region's box, in the same convention as the truth: the columns and rows of the
/// pixels brighter than `threshold` (red channel), each pixel covering [i − ½, i + ½).
fn lit_box(img: &RgbImage, threshold: u8) -> BoundingBox {
    let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
    for (i, j, p) in img.enumerate_pixels() {
        if p.0[0] > threshold {
            (x0, y0, x1, y1) = (x0.min(i), y0.min(j), x1.max(i), y1.max(j));
        }
    }
    assert!(x0 <= x1, "no bright pixel");
    BoundingBox::from_corners(
        f64::from(x0) - 0.5,
        f64::from(y0) - 0.5,
        f64::from(x1) + 0.5,
        f64::from(y1) + 0.5,
    )
}

/// The donor frames of the tests: pure green, unlabelled, so an occluder's pixels are known.
fn donors() -> Vec<Donor> {
    vec![Donor {
        frame: RgbImage::from_pixel(64, 48, Rgb([0, 255, 0])),
        target: None,
    }]
}

fn planned(spec: &str, seed: u64) -> Plan {
    plan(&spec.parse().unwrap(), SIZE, &truth(), &donors(), seed).unwrap()
}

/// Checks that on every frame the bright region of the transformed frame and the mapped truth
/// agree within `tol` px on every side. The ellipse is drawn by pixel centres and measured by
/// whole pixels (half a pixel each way), and resampling moves a thresholded edge by up to half
/// a pixel more: 1.5 px covers both.
fn assert_truth_matches(spec: &str, tol: f64) {
    let p = planned(spec, 5);
    for k in 0..FRAMES {
        let out = p.apply(k, &frame(k)).unwrap();
        assert_eq!(out.dimensions(), p.size());
        let want = p.truth()[k].unwrap();
        let seen = lit_box(&out, 128);
        let edges = |b: &BoundingBox| [b.x, b.y, b.x + b.w, b.y + b.h];
        for (a, b) in edges(&want).iter().zip(edges(&seen)) {
            assert!(
                (a - b).abs() <= tol,
                "{spec}, frame {k}: truth {want:?}, seen {seen:?}"
            );
        }
    }
}

#[test]
fn stress_shake_maps_the_truth_with_the_crop_and_jumps_with_reversals() {
    assert_truth_matches("shake", 1.5);
    let p = planned("shake", 5);
    // The picture jumps: the truth moves by at least one radius · zoom on some frames, far more
    // than the head's own 3 px per frame.
    let r = 0.25 * (24.0 + 30.0) * 1.25;
    let t = p.truth();
    let jumps: Vec<(f64, f64)> = (1..FRAMES)
        .map(|k| {
            let (a, b) = (t[k - 1].unwrap().centre(), t[k].unwrap().centre());
            (b.0 - a.0, b.1 - a.1)
        })
        .filter(|d| d.0.hypot(d.1) > 0.6 * r)
        .collect();
    assert!(jumps.len() >= 10, "{jumps:?}");
    // The target keeps its size times the zoom.
    assert!((t[3].unwrap().w - 24.0 * 1.25).abs() < 1e-9);
}

#[test]
fn stress_tilt_truth_is_the_box_of_the_turned_ellipse() {
    assert_truth_matches("tilt", 1.5);
    let p = planned("tilt", 5);
    let largest = (0..FRAMES)
        .map(|k| p.angle(k).unwrap().abs())
        .fold(0.0, f64::max);
    // 120 frames reach a quarter of the longest period (120): the full 45°, to a frame.
    assert!(largest.to_degrees() > 44.0, "{}", largest.to_degrees());
    // Worked by hand: a 20 × 40 box turned by 90° has the box of a 40 × 20 ellipse.
    let b = rotated_ellipse_box(
        &BoundingBox::new(0.0, 0.0, 20.0, 40.0),
        std::f64::consts::FRAC_PI_2,
        (10.0, 20.0),
    );
    for (g, w) in b.to_array().iter().zip([-10.0, 10.0, 40.0, 20.0]) {
        assert!((g - w).abs() < 1e-9, "{b:?}");
    }
}

#[test]
fn stress_small_scales_frame_and_truth_alike() {
    assert_truth_matches("small", 1.5);
    let p = planned("small", 5);
    // 20 / 24 of 160 × 120.
    assert_eq!(p.size(), (133, 100));
    assert!((p.truth()[0].unwrap().w - 24.0 * 133.0 / 160.0).abs() < 1e-9);
}

#[test]
fn stress_zoom_is_camera_zoom_and_maps_the_truth() {
    assert_truth_matches("zoom", 1.5);
    let p = planned("zoom", 5);
    // Frame 0 is unzoomed; the zoom grows after.
    assert_eq!(p.truth()[0], Some(true_box(0)));
    assert!(p.truth()[60].unwrap().w > 24.0 * 1.9);
}

#[test]
fn stress_grey_and_light_keep_the_truth_and_change_only_the_pixels() {
    // Drawing by pixel centres, measuring by whole pixels: half a pixel, and a hundredth for
    // the ellipse's curve across the half pixel to the nearest column at its apex.
    assert_truth_matches("grey", 0.51);
    let p = planned("grey", 5);
    assert_eq!(p.truth(), truth().as_slice());
    let out = p.apply(0, &RgbImage::from_pixel(4, 4, Rgb([255, 0, 0])).clone());
    assert!(out.is_err(), "a frame of another size is refused");
    let grey = p.apply(0, &frame(0)).unwrap();
    // 0.299·230 + 0.587·220 + 0.114·210 = 221.92 → 222.
    let (cx, cy) = true_box(0).centre();
    assert_eq!(grey.get_pixel(cx as u32, cy as u32).0, [222; 3]);

    let p = planned("light", 5);
    assert_eq!(p.truth(), truth().as_slice());
    // On a mid-grey frame every pixel stays within half to double of the gamma-mapped grey:
    // 64^γ for γ ∈ [0.8, 1.25] lies in [34, 85] (of 255), so within [17, 170].
    let mid = RgbImage::from_pixel(SIZE.0, SIZE.1, Rgb([64; 3]));
    let lights: Vec<u8> = (0..FRAMES)
        .flat_map(|k| p.apply(k, &mid).unwrap().into_raw())
        .collect();
    assert!(lights.iter().all(|&v| (17..=170).contains(&v)));
    assert_eq!(p.apply(0, &mid).unwrap(), mid, "frame 0 is as shot");
}

#[test]
fn stress_occluders_cover_the_share_they_report_and_the_truth_stays_whole() {
    let spec: Pipeline = "occlude".parse().unwrap();
    let occ = Occlude {
        gap_min: 2,
        gap_max: 3,
        stretch_min: 10,
        stretch_max: 10,
        ..Occlude::default()
    };
    let pipeline = Pipeline {
        stages: vec![Transform::Occlude(occ)],
    };
    assert_eq!(spec.name(), "occlude");
    let p = plan(&pipeline, SIZE, &truth(), &donors(), 9).unwrap();
    assert_eq!(p.truth(), truth().as_slice());
    let visible = p.visible().unwrap();
    let mut covered_frames = 0;
    for (k, v) in visible.iter().enumerate() {
        let out = p.apply(k, &frame(k)).unwrap();
        let b = true_box(k);
        // The share of the box's pixels still showing the scene (not the green occluder).
        let (mut all, mut green) = (0.0, 0.0);
        for j in (b.y.ceil() as u32)..((b.y + b.h).ceil() as u32) {
            for i in (b.x.ceil() as u32)..((b.x + b.w).ceil() as u32) {
                all += 1.0;
                if out.get_pixel(i, j).0 == [0, 255, 0] {
                    green += 1.0;
                }
            }
        }
        let v = v.unwrap();
        // Whole pixels against a continuous edge: one row or column of the box, 1/24 at most.
        assert!(
            ((1.0 - green / all) - v).abs() <= 1.0 / 24.0 + 1e-9,
            "frame {k}: seen {}, reported {v}",
            1.0 - green / all
        );
        if (0.3 - 1e-9..=0.7 + 1e-9).contains(&(1.0 - v)) {
            covered_frames += 1;
        }
    }
    assert_eq!(visible[0], Some(1.0), "the first frame is clean");
    assert!(covered_frames >= 10, "{covered_frames}");
    // Without donors there is nothing to cut occluders from.
    let err = plan(&pipeline, SIZE, &truth(), &[], 9).unwrap_err();
    assert!(err.to_string().contains("donor"), "{err}");
}

#[test]
fn stress_occluders_are_never_cut_from_a_donor_s_target() {
    // A donor whose left half is its (red) target, labelled as covering exactly those pixels:
    // every cut must come from the blue right half.
    let donor = Donor {
        frame: RgbImage::from_fn(120, 60, |i, _| {
            if i < 60 {
                Rgb([255, 0, 0])
            } else {
                Rgb([0, 0, 255])
            }
        }),
        target: Some(BoundingBox::new(-0.5, -0.5, 60.0, 60.0)),
    };
    for seed in 0..20 {
        let p = plan(
            &"occlude".parse().unwrap(),
            SIZE,
            &truth(),
            std::slice::from_ref(&donor),
            seed,
        )
        .unwrap();
        for k in 0..FRAMES {
            let out = p.apply(k, &frame(k)).unwrap();
            assert!(
                out.pixels().all(|px| px.0 != [255, 0, 0]),
                "seed {seed}, frame {k}"
            );
        }
    }
}

#[test]
fn stress_composed_transforms_map_the_truth_through_every_stage() {
    assert_truth_matches("grey,shake", 1.5);
    assert_truth_matches("tilt,small", 2.0);
    let p: Pipeline = "grey,shake".parse().unwrap();
    assert_eq!(p.name(), "grey+shake");
    assert!(
        "grey,wobble"
            .parse::<Pipeline>()
            .unwrap_err()
            .to_string()
            .contains("wobble")
    );
}

#[test]
fn stress_every_transform_is_deterministic_for_a_seed() {
    for name in Transform::NAMES {
        let a = planned(name, 11);
        let b = planned(name, 11);
        let c = planned(name, 12);
        let frames_of = |p: &Plan| -> Vec<Vec<u8>> {
            (0..FRAMES)
                .map(|k| p.apply(k, &frame(k)).unwrap().into_raw())
                .collect()
        };
        assert_eq!(frames_of(&a), frames_of(&b), "{name}");
        assert_eq!(a.truth(), b.truth(), "{name}");
        let seeded = !matches!(name, "grey" | "small" | "zoom");
        assert_eq!(frames_of(&a) != frames_of(&c), seeded, "{name}");
    }
}

#[test]
fn stress_settings_are_checked_and_overridden_by_name() {
    let t: Transform = "shake".parse().unwrap();
    let t2 = t.with_setting("zoom", "1.5").unwrap();
    assert!(matches!(t2, Transform::Shake(s) if s.zoom == 1.5));
    assert!(t.with_setting("zoom", "0.5").is_err());
    assert!(
        t.with_setting("nonsense", "1")
            .unwrap_err()
            .to_string()
            .contains("nonsense")
    );
    assert!(Transform::Grey.with_setting("x", "1").is_err());
    assert_ne!(
        derive_seed(1, &["Boy", "shake"]),
        derive_seed(1, &["Boy", "tilt"])
    );
    assert_ne!(derive_seed(1, &["ab", "c"]), derive_seed(1, &["a", "bc"]));
}
