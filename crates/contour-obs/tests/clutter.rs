//! Clutter learning on a generated image with three regions of known edge density.

use contour_obs::{ClutterSettings, learn_clutter, line_densities};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use vision_core::GreyImage;

const BAND: usize = 700;
const H: usize = 700;

/// One band of random black and white discs (radius 2–6 px, painted in turn) on mid-grey.
/// Discs are isotropic, so the edge density along a random line does not depend on its direction.
fn band(discs: usize, rng: &mut Pcg64Mcg) -> Vec<f32> {
    let mut img = vec![128.0f32; BAND * H];
    for _ in 0..discs {
        let (cx, cy) = (
            rng.random_range(0.0..BAND as f64),
            rng.random_range(0.0..H as f64),
        );
        let r: f64 = rng.random_range(2.0..6.0);
        let grey = if rng.random::<bool>() { 0.0 } else { 255.0 };
        let (x0, x1) = (
            (cx - r).floor().max(0.0) as usize,
            ((cx + r).ceil() as usize).min(BAND - 1),
        );
        let (y0, y1) = (
            (cy - r).floor().max(0.0) as usize,
            ((cy + r).ceil() as usize).min(H - 1),
        );
        for y in y0..=y1 {
            for x in x0..=x1 {
                if (x as f64 - cx).hypot(y as f64 - cy) <= r {
                    img[y * BAND + x] = grey;
                }
            }
        }
    }
    img
}

#[test]
fn recovers_three_region_densities_within_15_percent() {
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    let bands: Vec<Vec<f32>> = [700, 3500, 20000]
        .iter()
        .map(|&n| band(n, &mut rng))
        .collect();
    // Side by side into one image.
    let w = 3 * BAND;
    let mut whole = vec![0.0f32; w * H];
    for (b, data) in bands.iter().enumerate() {
        for y in 0..H {
            whole[y * w + b * BAND..y * w + (b + 1) * BAND]
                .copy_from_slice(&data[y * BAND..(y + 1) * BAND]);
        }
    }
    // Lines of 100 px: per-line counts then separate the three regions (√count grows with L), so
    // k-means clusters regions rather than cutting one Poisson-like count distribution; with the
    // default 20 px a line in light clutter mostly sees 0 edges and the clusters become counts.
    let settings = ClutterSettings {
        length: 100,
        ..ClutterSettings::default()
    };
    // Reference densities by the definition itself, on 40,000 lines inside each band alone.
    let reference: Vec<f64> = bands
        .iter()
        .map(|d| {
            let v = GreyImage::new(BAND, H, d).unwrap();
            let s = ClutterSettings {
                lines: 40_000,
                ..settings
            };
            let dens = line_densities(&[v], &s, &mut rng).unwrap();
            dens.iter().sum::<f64>() / dens.len() as f64
        })
        .collect();
    let image = GreyImage::new(w, H, &whole).unwrap();
    let model = learn_clutter(&[image], &settings, &mut rng).unwrap();
    eprintln!("reference {reference:?}\nlearnt {:?}", model.clusters);
    assert_eq!(model.clusters.len(), 3);
    for (c, r) in model.clusters.iter().zip(&reference) {
        assert!(
            (c.mean - r).abs() <= 0.15 * r,
            "learnt {} vs reference {r}",
            c.mean
        );
    }
    let wsum: f64 = model.clusters.iter().map(|c| c.weight).sum();
    assert!((wsum - 1.0).abs() < 1e-12);
}
