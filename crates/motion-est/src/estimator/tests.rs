//! Unit tests of the estimator on noise-free synthetic pairs.

use vision_core::Ellipse;

use super::*;
use crate::model::MotionModel;
use crate::region::MaskView;
use crate::robust::RobustFunction;

const W: usize = 128;
const H: usize = 96;

fn tex(x: f64, y: f64) -> f64 {
    128.0
        + 30.0 * (0.31 * x + 0.1 * y).sin()
        + 25.0 * (0.23 * y - 0.05 * x + 1.0).cos()
        + 20.0 * (0.45 * x + 0.37 * y + 2.0).sin()
        + 15.0 * (0.6 * x - 0.52 * y).cos()
}

/// Noise-free f32 pair: frame 1(q) = frame 0(q − d) for d = `a` about `origin` (inverted exactly).
fn pair(a: [f64; 6], origin: [f64; 2], offset: f64) -> (Vec<f32>, Vec<f32>) {
    let f0 = (0..W * H)
        .map(|k| tex((k % W) as f64, (k / W) as f64) as f32)
        .collect();
    let (m11, m12, m21, m22) = (1.0 + a[1], a[2], a[4], 1.0 + a[5]);
    let det = m11 * m22 - m12 * m21;
    let f1 = (0..W * H)
        .map(|k| {
            let (bx, by) = (
                (k % W) as f64 - origin[0] - a[0],
                (k / W) as f64 - origin[1] - a[3],
            );
            let x = origin[0] + (m22 * bx - m12 * by) / det;
            let y = origin[1] + (-m21 * bx + m11 * by) / det;
            (tex(x, y) + offset) as f32
        })
        .collect();
    (f0, f1)
}

fn views<'a>(f0: &'a [f32], f1: &'a [f32]) -> (GreyImage<'a>, GreyImage<'a>) {
    (
        GreyImage::new(W, H, f0).unwrap(),
        GreyImage::new(W, H, f1).unwrap(),
    )
}

/// The affine motion, its origin and the tilted ellipse that several tests share: a region
/// small enough to stay on the calling thread.
const SHARED_MOTION: [f64; 6] = [0.8, 0.01, -0.01, 0.5, 0.015, -0.005];
const SHARED_ORIGIN: [f64; 2] = [60.0, 50.0];
fn shared_ellipse() -> Ellipse {
    Ellipse {
        cx: 60.0,
        cy: 50.0,
        a: 30.0,
        b: 20.0,
        angle: 0.4,
    }
}

#[test]
fn scale_model_and_offset_are_recovered() {
    // Noise-free smooth texture: only interpolation error remains, far below 0.01 px at the
    // corners (0.01 / 60 px ≈ 2e-4 on the scale parameter) and 0.05 grey levels on the offset.
    let origin = [63.5, 47.5];
    let (f0, f1) = pair([1.2, 0.02, 0.0, -0.7, 0.0, 0.02], origin, 6.0);
    let (v0, v1) = views(&f0, &f1);
    let est = MotionEstimator::new(Settings::default()).unwrap();
    let r = est
        .estimate_images(
            v0,
            v1,
            &Region::Full,
            ModelSpec::new(MotionModel::Scale, true),
            Some(origin),
        )
        .unwrap();
    assert!(r.converged);
    assert!((r.params[0] - 1.2).abs() < 0.01, "{:?}", r.params);
    assert!((r.params[1] + 0.7).abs() < 0.01, "{:?}", r.params);
    assert!((r.params[2] - 0.02).abs() < 2e-4, "{:?}", r.params);
    assert!((r.params[3] - 6.0).abs() < 0.05, "{:?}", r.params);
    assert_eq!(r.covariance.len(), 16);
    let a = r.affine();
    assert_eq!(a[1], a[5]);
}

#[test]
fn every_instruction_set_gives_the_same_bits() {
    // The dispatched hot loops (this CPU's best instruction set) against the baseline build of
    // the same loops, on a region small enough to stay on this thread: parameters,
    // covariance, scale and inlier fraction bit for bit, with the offset and the tracking
    // preset's first-order path too.
    let origin = SHARED_ORIGIN;
    let (f0, f1) = pair(SHARED_MOTION, origin, 3.0);
    let (v0, v1) = views(&f0, &f1);
    let region = Region::Ellipse(shared_ellipse());
    for settings in [Settings::default(), Settings::tracking()] {
        let est = MotionEstimator::new(settings).unwrap();
        let spec = ModelSpec::new(MotionModel::Affine, true);
        let run = || {
            est.estimate_images(v0, v1, &region, spec, Some(origin))
                .unwrap()
        };
        let best = run();
        let (base, dispatches) = crate::simd::tests::on_baseline(run);
        // Pyramids, evaluations, normal equations, scale, covariance: dozens of loops.
        assert!(dispatches > 20, "{dispatches}");
        let bits = |r: &MotionEstimate| {
            let mut v: Vec<u64> = r.params.iter().map(|x| x.to_bits()).collect();
            v.extend(r.covariance.iter().map(|x| x.to_bits()));
            v.extend([r.scale.to_bits(), r.inlier_fraction.to_bits()]);
            v
        };
        assert_eq!(bits(&best), bits(&base));
        assert!(best.converged);
    }
}

#[test]
fn ellipse_and_equivalent_mask_give_the_same_estimate() {
    let origin = SHARED_ORIGIN;
    let (f0, f1) = pair(SHARED_MOTION, origin, 0.0);
    let (v0, v1) = views(&f0, &f1);
    let e = shared_ellipse();
    let ell = Region::Ellipse(e);
    let weights: Vec<f32> = (0..W * H)
        .map(|k| ell.weight((k % W) as f64, (k / W) as f64))
        .collect();
    let mask = Region::Mask(MaskView::new(W, H, &weights).unwrap());
    let est = MotionEstimator::new(Settings::default()).unwrap();
    let spec = ModelSpec::new(MotionModel::Affine, false);
    let a = est
        .estimate_images(v0, v1, &ell, spec, Some(origin))
        .unwrap();
    let b = est
        .estimate_images(v0, v1, &mask, spec, Some(origin))
        .unwrap();
    // Same pixels, same weights, same pyramid window: identical arithmetic.
    assert_eq!(a.params, b.params);
    assert!(
        (a.params[0] - 0.8).abs() < 0.01 && (a.params[3] - 0.5).abs() < 0.01,
        "{:?}",
        a.params
    );
}

#[test]
fn shared_full_pyramids_match_region_pyramids() {
    // The region window has a 32 px margin, so the two pyramids agree where the region reads
    // them; the estimates differ only by rounding (< 1e-4 px at the corners).
    let origin = [64.0, 48.0];
    let (f0, f1) = pair([1.5, 0.0, 0.0, -1.0, 0.0, 0.0], origin, 0.0);
    let (v0, v1) = views(&f0, &f1);
    let est = MotionEstimator::new(Settings::default()).unwrap();
    let region = Region::Rect {
        x: 40.0,
        y: 30.0,
        width: 48.0,
        height: 36.0,
    };
    let spec = ModelSpec::new(MotionModel::Affine, false);
    let single = est.estimate_images(v0, v1, &region, spec, None).unwrap();
    let (mut p0, mut p1) = (Pyramid::new(), Pyramid::new());
    est.build_pyramid_into(v0, &mut p0).unwrap();
    est.build_pyramid_into(v1, &mut p1).unwrap();
    let mut ws = Workspace::new();
    let shared = est
        .estimate(&p0, &p1, &region, spec, None, &mut ws)
        .unwrap();
    for (x, y) in [(40.0, 30.0), (87.0, 65.0)] {
        let (a, b) = (single.displacement(x, y), shared.displacement(x, y));
        assert!(
            (a[0] - b[0]).abs() < 1e-4 && (a[1] - b[1]).abs() < 1e-4,
            "{a:?} vs {b:?}"
        );
    }
    assert!((single.params[0] - 1.5).abs() < 0.01);
}

#[test]
fn non_convergence_is_a_status_not_an_error() {
    let origin = [63.5, 47.5];
    let (f0, f1) = pair([2.5, 0.0, 0.0, 1.5, 0.0, 0.0], origin, 0.0);
    let (v0, v1) = views(&f0, &f1);
    let settings = Settings {
        max_iterations: 1,
        levels: 1,
        ..Settings::default()
    };
    let r = MotionEstimator::new(settings)
        .unwrap()
        .estimate_images(
            v0,
            v1,
            &Region::Full,
            ModelSpec::new(MotionModel::Affine, false),
            None,
        )
        .unwrap_err();
    // An estimate that did not converge is an error, never `Ok`; it carries the estimate.
    let message = r.to_string();
    assert!(message.contains("did not converge"), "{message}");
    let r = r.into_unreliable().unwrap();
    assert!(!r.converged && !r.reliable);
    // The starting hypotheses' iterations are counted too.
    assert!(r.iterations.len() == 1 && r.iterations[0] >= 2, "{r:?}");
}

#[test]
fn flat_images_and_bad_inputs_are_errors() {
    let flat = vec![100.0f32; W * H];
    let v = GreyImage::new(W, H, &flat).unwrap();
    let est = MotionEstimator::new(Settings::default()).unwrap();
    let r = est.estimate_images(
        v,
        v,
        &Region::Full,
        ModelSpec::new(MotionModel::Affine, false),
        None,
    );
    assert!(matches!(r, Err(Error::Degenerate { .. })), "{r:?}");

    let small = vec![0.0f32; 16];
    let s = GreyImage::new(4, 4, &small).unwrap();
    let r = est.estimate_images(
        v,
        s,
        &Region::Full,
        ModelSpec::new(MotionModel::Affine, false),
        None,
    );
    assert!(matches!(r, Err(Error::DimensionMismatch { .. })));
    let outside = Region::Rect {
        x: 500.0,
        y: 0.0,
        width: 10.0,
        height: 10.0,
    };
    let r = est.estimate_images(
        v,
        v,
        &outside,
        ModelSpec::new(MotionModel::Affine, false),
        None,
    );
    assert!(matches!(r, Err(Error::RegionTooSmall { .. })));
    let r = est.estimate_images(
        v,
        v,
        &Region::Full,
        ModelSpec::new(MotionModel::Affine, false),
        Some([f64::NAN, 0.0]),
    );
    assert!(matches!(r, Err(Error::NonFinite { what: "origin", .. })));
    let bad = Settings {
        tolerance: 0.0,
        ..Settings::default()
    };
    assert!(MotionEstimator::new(bad).is_err());
}

#[test]
fn lane_normal_equations_match_a_scalar_f64_reference() {
    // The f32 lane accumulation over row spans against a direct f64 sum with
    // `MotionModel::gradient_row`, for every model, with an offset and a redescending ρ
    // rejecting some pixels. f32 products summed in f64 every 64 groups: relative agreement
    // to 1e-4 of the largest entry (f32 epsilon 6e-8 × a few hundred terms per flush, with
    // margin).
    let origin = SHARED_ORIGIN;
    let (f0, f1) = pair(SHARED_MOTION, origin, 3.0);
    let (v0, v1) = views(&f0, &f1);
    let settings = Settings::default();
    let est = MotionEstimator::new(settings).unwrap();
    let (mut p0, mut p1) = (Pyramid::new(), Pyramid::new());
    est.build_pyramid_into(v0, &mut p0).unwrap();
    est.build_pyramid_into(v1, &mut p1).unwrap();
    let region = Region::Ellipse(shared_ellipse());
    let (l0, l1) = (p0.level(0).unwrap(), p1.level(0).unwrap());
    let bbox = region.pixel_box(W, H).unwrap();
    let robust = RobustFunction::default();
    for spec in [
        ModelSpec::new(MotionModel::Translation, false),
        ModelSpec::new(MotionModel::Scale, true),
        ModelSpec::new(MotionModel::Affine, false),
        ModelSpec::new(MotionModel::Affine, true),
    ] {
        let mut ws = Workspace::new();
        ws.collect(l0, 0, &region, bbox);
        // A rough Θ so that residuals are large and Tukey rejects some pixels.
        let theta = [0.5, 0.0, 0.0, 0.3, 0.0, 0.0, 0.0];
        ws.evaluate(l0, l1, spec, &theta, origin, true);
        let s = 2.0;
        let rejected = (0..ws.idx.len())
            .filter(|&k| ws.valid[k] != 0 && f64::from(ws.res[k]).abs() >= robust.c() * s)
            .count();
        assert!(rejected > 0, "{spec:?}: no pixel rejected");
        let (h, b, hp) = ws.normal_equations(spec, robust, s, origin, true);
        let (n, ng) = (spec.len(), spec.model.geometric_len());
        let (mut hr, mut br, mut hpr) = (Mat7::zeros(), Vec7::zeros(), Mat7::zeros());
        let mut j = [0.0f64; 7];
        let pixels = ws
            .spans
            .iter()
            .flat_map(|sp| (0..sp.len).map(move |t| (sp.k0 + t, sp.i0 + t, sp.j)));
        for (k, i, jj) in pixels {
            if ws.valid[k] == 0 {
                continue;
            }
            let r = f64::from(ws.res[k]);
            let (x, y) = (i as f64 - origin[0], jj as f64 - origin[1]);
            spec.model
                .gradient_row(f64::from(ws.gx[k]), f64::from(ws.gy[k]), x, y, &mut j);
            if spec.offset {
                j[ng] = -1.0;
            }
            let (w, wp) = (robust.weight(r / s), robust.psi_prime(r / s));
            for a in 0..n {
                br[a] += w * j[a] * r;
                for c in 0..n {
                    hr[(a, c)] += w * j[a] * j[c];
                    hpr[(a, c)] += wp * j[a] * j[c];
                }
            }
        }
        for (got, want) in [(h, hr), (hp, hpr)] {
            let scale = want.abs().max();
            assert!(scale > 0.0);
            assert!((got - want).abs().max() < 1e-4 * scale, "{spec:?}");
        }
        assert!((b - br).abs().max() < 1e-4 * br.abs().max(), "{spec:?}");
    }
}

#[test]
fn pixels_leaving_the_image_are_dropped() {
    // A 4 px shift to the right: the last 4 columns of frame 0 have no match in frame 1 and
    // count neither as inliers nor in the total (the fraction is over the pixels
    // that stay in the image), so a pure shift reads close to 1. Noise-free, the robust scale
    // is tiny, so a few columns next to the clamped image border fall outside c·σ̂: allow up
    // to 8 columns.
    let origin = [63.5, 47.5];
    let (f0, f1) = pair([4.0, 0.0, 0.0, 0.0, 0.0, 0.0], origin, 0.0);
    let (v0, v1) = views(&f0, &f1);
    let r = MotionEstimator::new(Settings::default())
        .unwrap()
        .estimate_images(
            v0,
            v1,
            &Region::Full,
            ModelSpec::new(MotionModel::Translation, false),
            None,
        )
        .unwrap();
    assert!(r.converged && (r.params[0] - 4.0).abs() < 0.01, "{r:?}");
    let f = r.inlier_fraction;
    assert!((1.0 - 8.0 / 124.0..=1.0).contains(&f), "{f}");
    assert!(r.reliable);
}

#[test]
fn whole_pixel_translations_give_evaluate_s_residuals_bit_for_bit() {
    // The cold start's search reads residuals at whole-pixel shifts without interpolating: they
    // must be `evaluate`'s to the bit, with the same validity, at full resolution (bicubic
    // interior, bilinear border) and at a coarse level (bilinear), for shifts that carry the
    // region across the frame's border (clamped last row and column included); any other Θ is
    // evaluated in full.
    let origin = SHARED_ORIGIN;
    let (f0, f1) = pair(SHARED_MOTION, origin, 3.0);
    let (v0, v1) = views(&f0, &f1);
    let est = MotionEstimator::new(Settings::default()).unwrap();
    let (mut p0, mut p1) = (Pyramid::new(), Pyramid::new());
    est.build_pyramid_into(v0, &mut p0).unwrap();
    est.build_pyramid_into(v1, &mut p1).unwrap();
    let region = Region::Ellipse(Ellipse {
        cx: 64.0,
        cy: 48.0,
        a: 60.0,
        b: 44.0,
        angle: 0.0,
    });
    let bbox = region.pixel_box(W, H).unwrap();
    for (level, full_res) in [(0, true), (1, false)] {
        let (l0, l1) = (p0.level(level).unwrap(), p1.level(level).unwrap());
        let f = 0.5f64.powi(level as i32);
        let o = [origin[0] * f, origin[1] * f];
        for spec in [
            ModelSpec::new(MotionModel::Translation, false),
            ModelSpec::new(MotionModel::Affine, true),
        ] {
            let (tx, ty) = (0, spec.model.geometric_len() / 2);
            let mut thetas = Vec::new();
            for (dx, dy) in [
                (0.0, 0.0),
                (2.0, -1.0),
                (-5.0, 3.0),
                (7.0, 6.0),
                (-9.0, -8.0),
            ] {
                let mut t = [0.0f64; 7];
                (t[tx], t[ty]) = (dx, dy);
                thetas.push(t);
            }
            // Not whole pixels, or not a translation: the full evaluation.
            let mut frac = [0.0f64; 7];
            frac[tx] = 0.5;
            thetas.push(frac);
            if spec.model == MotionModel::Affine {
                let mut lin = [0.0f64; 7];
                lin[1] = 0.01;
                thetas.push(lin);
            }
            for theta in thetas {
                let mut a = Workspace::new();
                a.collect(l0, level, &region, bbox);
                let mut b = a.clone();
                let na = a.evaluate(l0, l1, spec, &theta, o, full_res);
                let nb = b.residuals_at_shift(l0, l1, spec, &theta, o, full_res);
                assert_eq!(na, nb, "level {level}, {spec:?}, {theta:?}");
                assert!(na > 0);
                assert_eq!(a.valid, b.valid, "level {level}, {spec:?}, {theta:?}");
                for k in (0..a.idx.len()).filter(|&k| a.valid[k] != 0) {
                    assert_eq!(
                        a.res[k].to_bits(),
                        b.res[k].to_bits(),
                        "level {level}, {spec:?}, {theta:?}, pixel {k}"
                    );
                }
            }
        }
    }
}
