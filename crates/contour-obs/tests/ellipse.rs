//! Ground truth on a synthetic ellipse: edge offsets and the maxima of the three likelihoods.

use contour_obs::{
    Affine2, MeasurementLines, OcclusionLikelihood, OdobezLikelihood, OdobezSettings, Template,
    WuLikelihood, WuSettings,
};
use nalgebra::Vector2;
use vision_core::GreyImage;

const W: usize = 160;
const H: usize = 120;
const TRUTH: (f64, f64, f64, f64, f64) = (80.3, 60.7, 35.0, 22.0, 0.3);

/// The ellipse `TRUTH` at grey 180 on a background of 60, area-sampled (16×16 sub-samples per
/// pixel, pixel (i, j) covering [i − ½, i + ½] × [j − ½, j + ½]) so the boundary is sub-pixel exact.
fn ellipse_image() -> Vec<f32> {
    let (cx, cy, a, b, th) = TRUTH;
    let (s, c) = th.sin_cos();
    let inside = |x: f64, y: f64| {
        let (dx, dy) = (x - cx, y - cy);
        let (u, v) = (c * dx + s * dy, -s * dx + c * dy);
        (u / a).powi(2) + (v / b).powi(2) <= 1.0
    };
    let n = 16;
    (0..W * H)
        .map(|k| {
            let (i, j) = ((k % W) as f64, (k / W) as f64);
            let mut hits = 0;
            for p in 0..n {
                for q in 0..n {
                    let x = i - 0.5 + (p as f64 + 0.5) / n as f64;
                    let y = j - 0.5 + (q as f64 + 0.5) / n as f64;
                    hits += usize::from(inside(x, y));
                }
            }
            (60.0 + 120.0 * hits as f64 / (n * n) as f64) as f32
        })
        .collect()
}

fn truth_pose() -> Affine2 {
    let (cx, cy, a, b, th) = TRUTH;
    Affine2::from_ellipse(cx, cy, a, b, th)
}

/// Offsets s with p + s·n on the true ellipse (roots of a quadratic in s).
fn true_crossings(p: Vector2<f64>, n: Vector2<f64>) -> Vec<f64> {
    let (cx, cy, a, b, th) = TRUTH;
    let (sn, c) = th.sin_cos();
    let rot = |v: Vector2<f64>| Vector2::new((c * v.x + sn * v.y) / a, (-sn * v.x + c * v.y) / b);
    let (q0, q1) = (rot(p - Vector2::new(cx, cy)), rot(n));
    let (qa, qb, qc) = (q1.dot(&q1), 2.0 * q0.dot(&q1), q0.dot(&q0) - 1.0);
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return vec![];
    }
    vec![
        (-qb - disc.sqrt()) / (2.0 * qa),
        (-qb + disc.sqrt()) / (2.0 * qa),
    ]
}

#[test]
fn edge_offsets_within_a_quarter_pixel_of_the_true_boundary() {
    let data = ellipse_image();
    let image = GreyImage::new(W, H, &data).unwrap();
    let model = OdobezLikelihood::new(
        OdobezSettings {
            lines: contour_obs::LineSettings {
                n_lines: 40,
                ..Default::default()
            },
            ..Default::default()
        },
        &Template::UnitCircle,
    )
    .unwrap();
    let mut ws: MeasurementLines = model.workspace().unwrap();
    let (cx, cy, a, b, th) = TRUTH;
    let mut checked = 0;
    let mut worst: f64 = 0.0;
    // The truth and hypotheses off in position, scale, aspect and angle: every crossing of the
    // true boundary inside the line's ±10 px must be found within 0.25 px, and nothing else
    // (the background and the interior are flat).
    for pose in [
        truth_pose(),
        Affine2::from_ellipse(cx + 3.0, cy - 2.0, a, b, th),
        Affine2::from_ellipse(cx, cy, 1.15 * a, 0.9 * b, th),
        Affine2::from_ellipse(cx - 1.5, cy + 1.0, a, b, th + 0.15),
    ] {
        ws.extract(&image, model.contour(), &pose).unwrap();
        for i in 0..ws.len() {
            // Crossings well inside the line (the detector needs the whole peak) and well apart.
            let want: Vec<f64> = true_crossings(ws.centre(i), ws.normal(i))
                .into_iter()
                .filter(|s| s.abs() <= 9.0)
                .collect();
            let got = ws.edges(i);
            assert_eq!(
                got.len(),
                want.len(),
                "line {i}: got {got:?}, want {want:?}"
            );
            for (g, w) in got.iter().zip(&want) {
                worst = worst.max((g - w).abs());
                checked += 1;
            }
        }
    }
    // 0.25 px is the bound; an area-sampled boundary read by bilinear interpolation
    // along oblique lines and a parabola vertex stay well inside it.
    assert!(worst < 0.25, "worst offset error {worst}");
    assert!(checked >= 100, "only {checked} crossings checked");
    eprintln!("edge offsets: {checked} crossings, worst error {worst:.4} px");
}

/// Grid over translations (±4 px, 1 px steps) and scales (0.85 … 1.15), relative to the truth.
fn grid() -> Vec<(f64, f64, f64, Affine2)> {
    let (cx, cy, a, b, th) = TRUTH;
    let mut g = Vec::new();
    for dx in -4..=4 {
        for dy in -4..=4 {
            for ks in 0..=6 {
                let s = 0.85 + 0.05 * ks as f64;
                let pose = Affine2::from_ellipse(cx + dx as f64, cy + dy as f64, s * a, s * b, th);
                g.push((dx as f64, dy as f64, s, pose));
            }
        }
    }
    g
}

fn assert_argmax_is_truth(name: &str, grid: &[(f64, f64, f64, Affine2)], logl: &[f64]) {
    let best = logl
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, _)| i)
        .unwrap();
    let (dx, dy, s, _) = grid[best];
    assert!(
        dx == 0.0 && dy == 0.0 && (s - 1.0).abs() < 1e-9,
        "{name}: maximum at dx {dx}, dy {dy}, s {s}"
    );
    // And strictly: every other grid point is below.
    let top = logl[best];
    let second = logl
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != best)
        .map(|(_, v)| *v)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(second < top, "{name}: tie at the top");
    assert!(logl.iter().all(|v| v.is_finite()));
}

#[test]
fn each_likelihood_is_maximised_at_the_true_transform() {
    let data = ellipse_image();
    let image = GreyImage::new(W, H, &data).unwrap();
    let g = grid();
    let poses: Vec<Affine2> = g.iter().map(|p| p.3).collect();
    let mut out = vec![0.0; poses.len()];

    let odobez = OdobezLikelihood::new(OdobezSettings::default(), &Template::UnitCircle).unwrap();
    let mut ws = odobez.workspace().unwrap();
    odobez
        .log_likelihood_batch(&mut ws, &image, &poses, &mut out)
        .unwrap();
    assert_argmax_is_truth("odobez", &g, &out);

    let wu = WuLikelihood::new(WuSettings::default(), &Template::UnitCircle).unwrap();
    for lambda in [0.01, 0.0824, 0.2144] {
        wu.log_likelihood_batch(&mut ws, &image, &poses, &[lambda], &mut out)
            .unwrap();
        assert_argmax_is_truth("wu", &g, &out);
    }

    let occ = OcclusionLikelihood::new(WuSettings::default(), &Template::UnitCircle).unwrap();
    for gamma in [0.0, 0.3, 0.8] {
        occ.log_likelihood_batch(&mut ws, &image, &poses, &[0.05], &[gamma], &mut out)
            .unwrap();
        assert_argmax_is_truth("occlusion", &g, &out);
    }
}

#[test]
fn batch_equals_single_and_occlusion_limits() {
    let data = ellipse_image();
    let image = GreyImage::new(W, H, &data).unwrap();
    let g = grid();
    let poses: Vec<Affine2> = g.iter().step_by(37).map(|p| p.3).collect();
    let lambdas: Vec<f64> = (0..poses.len()).map(|i| 0.01 + 0.01 * i as f64).collect();
    let wu = WuLikelihood::new(WuSettings::default(), &Template::UnitCircle).unwrap();
    let occ = OcclusionLikelihood::new(WuSettings::default(), &Template::UnitCircle).unwrap();
    let mut ws = wu.workspace().unwrap();
    let mut batch = vec![0.0; poses.len()];
    wu.log_likelihood_batch(&mut ws, &image, &poses, &lambdas, &mut batch)
        .unwrap();
    let mut terms = vec![Default::default(); 15];
    for (i, p) in poses.iter().enumerate() {
        let single = wu.log_likelihood(&mut ws, &image, p, lambdas[i]).unwrap();
        assert_eq!(single, batch[i]);
        // γ = 0: the target term exactly; γ = 1: the clutter-only term exactly.
        wu.line_terms(&mut ws, &image, p, lambdas[i], &mut terms)
            .unwrap();
        let clutter: f64 = terms.iter().map(|t| t.log_clutter).sum();
        let target: f64 = terms.iter().map(|t| t.log_target).sum();
        assert_eq!(target, single);
        let at0 = occ
            .log_likelihood(&mut ws, &image, p, lambdas[i], 0.0)
            .unwrap();
        let at1 = occ
            .log_likelihood(&mut ws, &image, p, lambdas[i], 1.0)
            .unwrap();
        assert_eq!(at0, target);
        assert_eq!(at1, clutter);
    }
}

#[test]
fn finite_everywhere_and_errors_carry_the_index() {
    let data = ellipse_image();
    let image = GreyImage::new(W, H, &data).unwrap();
    let flat = vec![90.0f32; W * H];
    let flat = GreyImage::new(W, H, &flat).unwrap();
    let odobez = OdobezLikelihood::new(OdobezSettings::default(), &Template::UnitCircle).unwrap();
    let wu = WuLikelihood::new(WuSettings::default(), &Template::UnitCircle).unwrap();
    let occ = OcclusionLikelihood::new(WuSettings::default(), &Template::UnitCircle).unwrap();
    let mut ws = wu.workspace().unwrap();
    let poses = [
        Affine2::from_ellipse(5.0, 5.0, 30.0, 20.0, 0.0), // partly outside
        Affine2::from_ellipse(-500.0, 900.0, 30.0, 20.0, 0.0), // wholly outside
        Affine2::from_wu([1.0, 2.0, 2.0, 4.0, 80.0, 60.0]), // singular
        Affine2::from_ellipse(80.0, 60.0, 0.0, 0.0, 0.0), // collapsed to a point
        Affine2::from_ellipse(80.0, 60.0, 1e6, 1e6, 0.0), // huge
    ];
    let mut out = [0.0; 5];
    for img in [&image, &flat] {
        odobez
            .log_likelihood_batch(&mut ws, img, &poses, &mut out)
            .unwrap();
        assert!(out.iter().all(|v| v.is_finite()), "{out:?}");
        for lambda in [0.0, 1e-300, 0.2, 50.0] {
            wu.log_likelihood_batch(&mut ws, img, &poses, &[lambda], &mut out)
                .unwrap();
            assert!(out.iter().all(|v| v.is_finite()), "{lambda}: {out:?}");
            for gamma in [0.0, 0.5, 1.0] {
                occ.log_likelihood_batch(&mut ws, img, &poses, &[lambda], &[gamma], &mut out)
                    .unwrap();
                assert!(
                    out.iter().all(|v| v.is_finite()),
                    "{lambda} {gamma}: {out:?}"
                );
            }
        }
    }
    // An unobserved line scores exactly as an observed line without edges: the wholly-outside
    // contour and a contour on the flat image are equal.
    let mut a = [0.0; 1];
    let mut b = [0.0; 1];
    wu.log_likelihood_batch(&mut ws, &image, &poses[1..2], &[0.05], &mut a)
        .unwrap();
    wu.log_likelihood_batch(&mut ws, &flat, &[truth_pose()], &[0.05], &mut b)
        .unwrap();
    assert_eq!(a, b);

    let mut bad = poses;
    bad[3].t.x = f64::NAN;
    let e = odobez
        .log_likelihood_batch(&mut ws, &image, &bad, &mut out)
        .unwrap_err();
    assert_eq!(
        e,
        contour_obs::Error::NonFinite {
            what: "pose",
            index: 3
        }
    );
    let e = wu
        .log_likelihood_batch(
            &mut ws,
            &image,
            &poses,
            &[0.1, 0.1, f64::NAN, 0.1, 0.1],
            &mut out,
        )
        .unwrap_err();
    assert_eq!(
        e,
        contour_obs::Error::NonFinite {
            what: "lambda",
            index: 2
        }
    );
    assert!(
        occ.log_likelihood_batch(
            &mut ws,
            &image,
            &poses,
            &[0.1],
            &[0.5, 0.5, 0.5, 0.5, 1.5],
            &mut out
        )
        .is_err()
    );
    assert!(
        wu.log_likelihood_batch(&mut ws, &image, &poses, &[0.1, 0.1], &mut out)
            .is_err()
    );
}

#[test]
fn bspline_template_of_a_circle_finds_the_disc() {
    // A closed uniform cubic B-spline through 12 control points on a circle of radius ρ is a
    // near-circle: at a knot it is (P_{j−1} + 4P_j + P_{j+1})/6, at radius ρ(4 + 2cos(2π/12))/6.
    // Choosing ρ to put the knots at radius 1 (the curve between knots deviates by < 0.03 %),
    // the template must behave as the unit circle: the maximum is at the disc's true pose.
    let m = 12;
    let rho = 6.0 / (4.0 + 2.0 * (std::f64::consts::TAU / m as f64).cos());
    let ctrl: Vec<[f64; 2]> = (0..m)
        .map(|k| {
            let u = std::f64::consts::TAU * k as f64 / m as f64;
            [rho * u.cos(), rho * u.sin()]
        })
        .collect();
    let (w, h) = (100usize, 80usize);
    let data: Vec<f32> = (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f64 - 50.0, (k / w) as f64 - 40.0);
            if x.hypot(y) <= 25.0 { 200.0 } else { 40.0 }
        })
        .collect();
    let image = GreyImage::new(w, h, &data).unwrap();
    let model = WuLikelihood::new(WuSettings::default(), &Template::ClosedBSpline(ctrl)).unwrap();
    let mut ws = model.workspace().unwrap();
    let mut best = (f64::NEG_INFINITY, 0.0, 0.0);
    for dx in -3..=3 {
        for ks in 0..=4 {
            let s = 25.0 * (0.9 + 0.05 * ks as f64);
            let pose = Affine2::from_ellipse(50.0 + dx as f64, 40.0, s, s, 0.0);
            let l = model.log_likelihood(&mut ws, &image, &pose, 0.05).unwrap();
            if l > best.0 {
                best = (l, dx as f64, s);
            }
        }
    }
    assert_eq!((best.1, best.2), (0.0, 25.0), "{best:?}");
}
