//! The fast extraction paths against a plain reference: edges from per-sample f32 bilinear
//! interpolation and the detector run over the whole line (the implementation before the
//! fixed-point sampler), and Odobez's windowed nearest-edge search against Eq. 19 on all edges.

use contour_obs::{
    Affine2, Bilinear, EdgeDetector, EdgeSettings, LineSettings, LineTerms, OcclusionLikelihood,
    OdobezLikelihood, OdobezSettings, Template, WuLikelihood, WuSettings, occlusion_line_log,
    odobez_line_log_term,
};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use vision_core::GreyImage;

/// The benchmark's scene generator (only its clutter image is used here).
#[path = "../examples/common/frame.rs"]
#[allow(dead_code)]
mod frame;

const W: usize = 120;
const H: usize = 90;

/// Random grey discs (radius 2–7 px) on mid-grey, then a bright ellipse: edges of every
/// strength, including many near the detection threshold.
fn clutter_image(rng: &mut Pcg64Mcg) -> Vec<f32> {
    frame::DiscClutter {
        width: W,
        height: H,
        background: 110.0,
        discs: 120,
        radii: 2.0..7.0,
        ellipse: [60.0, 45.0, 30.0, 20.0],
    }
    .render(rng)
}

/// Poses around the ellipse, some reaching over the border and some far outside.
fn poses(rng: &mut Pcg64Mcg, n: usize) -> Vec<Affine2> {
    (0..n)
        .map(|_| {
            Affine2::from_ellipse(
                rng.random_range(10.0..110.0),
                rng.random_range(5.0..85.0),
                rng.random_range(8.0..45.0),
                rng.random_range(8.0..35.0),
                rng.random_range(-1.5..1.5),
            )
        })
        .collect()
}

/// Reference edges of one line: f32 positions c + k·n, `GreyImage::sample`, the detector over the
/// in-image run of offsets in [−reach, reach]. `None` when the line is unobserved.
fn reference_edges(
    image: &GreyImage<'_>,
    det: &mut EdgeDetector,
    lines: &LineSettings,
    centre: (f64, f64),
    normal: (f64, f64),
) -> Option<Vec<f64>> {
    let half = lines.half_length() as i64;
    let reach = half + 1 + det.radius() as i64;
    let (cx, cy, nx, ny) = (
        centre.0 as f32,
        centre.1 as f32,
        normal.0 as f32,
        normal.1 as f32,
    );
    let mut first = None;
    let mut profile = Vec::new();
    for k in -reach..=reach {
        let kf = k as f32;
        if let Some(v) = image.sample(cx + kf * nx, cy + kf * ny) {
            first.get_or_insert(k);
            profile.push(v);
        }
    }
    let mut out = Vec::new();
    let examined = det.detect(&profile, first?, -half, half, &mut out);
    let needed = lines.min_observed_fraction * (2 * half + 1) as f64;
    (examined > 0 && examined as f64 >= needed).then_some(out)
}

#[test]
fn extracted_edges_match_the_reference_within_1e_4_px() {
    let mut rng = Pcg64Mcg::seed_from_u64(11);
    let data = clutter_image(&mut rng);
    let image = GreyImage::new(W, H, &data).unwrap();
    let settings = OdobezSettings {
        lines: LineSettings {
            n_lines: 40,
            ..Default::default()
        },
        ..Default::default()
    };
    let model = OdobezLikelihood::new(settings, &Template::UnitCircle).unwrap();
    let mut ws = model.workspace().unwrap();
    let mut det = EdgeDetector::new(&EdgeSettings::default()).unwrap();
    let (mut edges, mut lines, mut worst) = (0usize, 0usize, 0.0f64);
    for pose in poses(&mut rng, 150) {
        ws.extract(&image, model.contour(), &pose).unwrap();
        for i in 0..ws.len() {
            let (c, n) = (ws.centre(i), ws.normal(i));
            let want = reference_edges(&image, &mut det, &settings.lines, (c.x, c.y), (n.x, n.y));
            // A line the reference cannot see (its run of in-image samples differs by rounding
            // at the border) is not compared; there are few of them.
            let Some(want) = want else { continue };
            if !ws.is_observed(i) {
                continue;
            }
            lines += 1;
            let got = ws.edges(i);
            assert_eq!(got.len(), want.len(), "line {i}: {got:?} vs {want:?}");
            for (g, w) in got.iter().zip(&want) {
                worst = worst.max((g - w).abs());
                edges += 1;
            }
        }
    }
    // The fixed-point positions differ from f32 ones by ~1e−5 px; 1e−4 px is the bound asked.
    assert!(worst < 1e-4, "worst offset difference {worst}");
    assert!(lines > 3000 && edges > 3000, "{lines} lines, {edges} edges");
    eprintln!("{lines} lines, {edges} edges, worst difference {worst:.2e} px");
}

#[test]
fn odobez_window_search_equals_eq19_on_all_edges() {
    let mut rng = Pcg64Mcg::seed_from_u64(12);
    let data = clutter_image(&mut rng);
    let image = GreyImage::new(W, H, &data).unwrap();
    let ps = poses(&mut rng, 200);
    // Floors and σ that put the search radius at 0 (K = 1), 2, 4 (default), 7 and the whole
    // line (K tiny); and a line shorter than the search.
    for (sigma, k_floor, length) in [
        (2.0, 1.0, 20),
        (1.0, (-2.0f64).exp(), 20),
        (2.0, (-2.0f64).exp(), 20),
        (3.0, 0.1, 20),
        (2.0, 1e-12, 20),
        (2.0, 1e-12, 8),
    ] {
        let settings = OdobezSettings {
            lines: LineSettings {
                n_lines: 24,
                length,
                ..Default::default()
            },
            sigma,
            k_floor,
        };
        let model = OdobezLikelihood::new(settings, &Template::UnitCircle).unwrap();
        let mut ws = model.workspace().unwrap();
        let ln_k = k_floor.ln();
        for pose in &ps {
            let fast = model.log_likelihood(&mut ws, &image, pose).unwrap();
            ws.extract(&image, model.contour(), pose).unwrap();
            let full: f64 = (0..ws.len())
                .map(|i| odobez_line_log_term(ws.edges(i), sigma, ln_k))
                .sum();
            // Same samples, same arithmetic: exactly equal.
            assert_eq!(fast, full, "σ {sigma}, K {k_floor}, L {length}");
        }
    }
}

#[test]
fn occlusion_sum_equals_the_mixture_of_line_terms() {
    let mut rng = Pcg64Mcg::seed_from_u64(13);
    let data = clutter_image(&mut rng);
    let image = GreyImage::new(W, H, &data).unwrap();
    let wu = WuLikelihood::new(WuSettings::default(), &Template::UnitCircle).unwrap();
    let occ = OcclusionLikelihood::new(WuSettings::default(), &Template::UnitCircle).unwrap();
    let mut ws = wu.workspace().unwrap();
    let mut terms = vec![LineTerms::default(); 15];
    for pose in poses(&mut rng, 60) {
        for (lambda, gamma) in [(0.02, 0.3), (0.2, 0.75), (1e-6, 0.5)] {
            wu.line_terms(&mut ws, &image, &pose, lambda, &mut terms)
                .unwrap();
            let want: f64 = terms.iter().map(|&t| occlusion_line_log(t, gamma)).sum();
            let got = occ
                .log_likelihood(&mut ws, &image, &pose, lambda, gamma)
                .unwrap();
            // The linear-domain mixture against the log-sum-exp form: rounding only.
            assert!(
                (got - want).abs() <= 1e-11 * want.abs().max(1.0),
                "{got} vs {want}"
            );
        }
    }
}

#[test]
fn wu_counting_path_equals_the_sum_of_line_terms_bit_for_bit() {
    // Wu's likelihood counts each line's edges without storing the line and forms only the
    // window's Gaussians; line_terms extracts and stores every edge. Same edges, same
    // arithmetic in the same order: the same bits, also for lines over the border.
    let mut rng = Pcg64Mcg::seed_from_u64(15);
    let data = clutter_image(&mut rng);
    let image = GreyImage::new(W, H, &data).unwrap();
    for window in [8.0, 3.0, 20.0] {
        let settings = WuSettings {
            lines: LineSettings {
                n_lines: 30,
                ..Default::default()
            },
            window,
            ..Default::default()
        };
        let wu = WuLikelihood::new(settings, &Template::UnitCircle).unwrap();
        let occ = OcclusionLikelihood::new(settings, &Template::UnitCircle).unwrap();
        let mut ws = wu.workspace().unwrap();
        let mut terms = vec![LineTerms::default(); 30];
        for pose in poses(&mut rng, 80) {
            let lambda = 0.07;
            wu.line_terms(&mut ws, &image, &pose, lambda, &mut terms)
                .unwrap();
            let want: f64 = terms.iter().map(|t| t.log_target).sum();
            let got = wu.log_likelihood(&mut ws, &image, &pose, lambda).unwrap();
            assert_eq!(got.to_bits(), want.to_bits(), "W = {window}");
            // γ = 0: the occlusion mixture is the target term, exactly.
            let occ0 = occ
                .log_likelihood(&mut ws, &image, &pose, lambda, 0.0)
                .unwrap();
            assert_eq!(occ0.to_bits(), want.to_bits());
        }
    }
}

#[test]
fn parallel_batches_are_bit_identical_to_sequential() {
    let mut rng = Pcg64Mcg::seed_from_u64(14);
    let data = clutter_image(&mut rng);
    let image = GreyImage::new(W, H, &data).unwrap();
    // 75 poses: several rayon chunks and a partial last one.
    let ps = poses(&mut rng, 75);
    let lambdas: Vec<f64> = (0..ps.len()).map(|i| 0.005 * (i + 1) as f64).collect();
    let gammas: Vec<f64> = (0..ps.len()).map(|i| i as f64 / ps.len() as f64).collect();
    let od = OdobezLikelihood::new(OdobezSettings::default(), &Template::UnitCircle).unwrap();
    let wu = WuLikelihood::new(WuSettings::default(), &Template::UnitCircle).unwrap();
    let occ = OcclusionLikelihood::new(WuSettings::default(), &Template::UnitCircle).unwrap();
    let mut ws = od.workspace().unwrap();
    let (mut seq, mut par) = (vec![0.0; ps.len()], vec![1.0; ps.len()]);
    od.log_likelihood_batch(&mut ws, &image, &ps, &mut seq)
        .unwrap();
    od.log_likelihood_batch_par(&image, &ps, &mut par).unwrap();
    assert_eq!(seq, par);
    wu.log_likelihood_batch(&mut ws, &image, &ps, &lambdas, &mut seq)
        .unwrap();
    wu.log_likelihood_batch_par(&image, &ps, &lambdas, &mut par)
        .unwrap();
    assert_eq!(seq, par);
    occ.log_likelihood_batch(&mut ws, &image, &ps, &lambdas, &gammas, &mut seq)
        .unwrap();
    occ.log_likelihood_batch_par(&image, &ps, &lambdas, &gammas, &mut par)
        .unwrap();
    assert_eq!(seq, par);
    // The error is that of the lowest bad index, as sequentially.
    let mut bad = ps.clone();
    bad[70].t.y = f64::NAN;
    bad[40].t.x = f64::INFINITY;
    let e = od
        .log_likelihood_batch_par(&image, &bad, &mut par)
        .unwrap_err();
    assert_eq!(
        e,
        contour_obs::Error::NonFinite {
            what: "pose",
            index: 40
        }
    );
}
