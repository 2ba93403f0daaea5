//! Reproducibility: large regions are processed in bands that may run concurrently (feature
//! `parallel`); the result must be bit-identical whatever the number of threads.
#![allow(missing_docs)]

use crate::common;

use common::*;
use motion_est::{ModelSpec, MotionEstimate, MotionEstimator, MotionModel, Region, Settings};
use vision_core::{Ellipse, GreyImage};

const W: usize = 320;
const H: usize = 240;

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

fn bits(r: &MotionEstimate) -> Vec<u64> {
    r.params
        .iter()
        .chain(&r.covariance)
        .chain([&r.scale, &r.noise_sigma, &r.inlier_fraction])
        .map(|v| v.to_bits())
        .collect()
}

#[test]
fn full_frame_estimate_is_bit_identical_with_one_or_two_threads() {
    let origin = [159.5, 119.5];
    let tex = Texture::new(11, 300, 40.0);
    let warp = Affine::issue(origin, [3.0, -2.0]);
    let (c0, c1) = clean_pair(W, H, &tex, &warp, 0.0, None);
    let (f0, f1) = (noisy(&c0, 2.0, 1), noisy(&c1, 2.0, 2));
    let est = MotionEstimator::new(Settings::default()).unwrap();
    let ellipse = Region::Ellipse(Ellipse {
        cx: 150.0,
        cy: 110.0,
        a: 90.0,
        b: 70.0,
        angle: 0.3,
    });
    for (region, spec) in [
        (Region::Full, ModelSpec::new(MotionModel::Affine, false)),
        (Region::Full, ModelSpec::new(MotionModel::Scale, true)),
        (ellipse, ModelSpec::new(MotionModel::Affine, true)),
    ] {
        let run = || {
            est.estimate_images(
                GreyImage::new(W, H, &f0).unwrap(),
                GreyImage::new(W, H, &f1).unwrap(),
                &region,
                spec,
                Some(origin),
            )
            // The scale model's estimate may be unreliable (below): an error carrying it.
            .or_else(motion_est::Error::into_unreliable)
            .unwrap()
        };
        let one = in_pool(1, run);
        let two = in_pool(2, run);
        let four = in_pool(4, run);
        // The scale model cannot represent the pair's 2° rotation: its misfit exceeds the weights'
        // scale ceiling and IRLS need not converge; only the bits matter here.
        if spec.model == MotionModel::Affine {
            assert!(one.converged, "{spec:?}: {one:?}");
        }
        assert_eq!(bits(&one), bits(&two), "{spec:?}: 1 vs 2 threads");
        assert_eq!(bits(&one), bits(&four), "{spec:?}: 1 vs 4 threads");
        assert_eq!(one.iterations, two.iterations);
    }
}
