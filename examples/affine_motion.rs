//! Robust affine motion, with its covariance, between two grey images (motion-est).
//!
//! ```text
//! cargo run --release --example affine_motion -- first.png second.png
//! cargo run --release --example affine_motion          # a synthetic pair with known motion
//! ```
//!
//! The estimator finds the dominant affine motion d(x, y) = (a1 + a2 x + a3 y, a4 + a5 x + a6 y)
//! (Odobez et al. 2003, Eq. 13) such that the second image at (x, y) + d matches the first at
//! (x, y), with (x, y) measured from the origin it reports. Pixels that do not follow that motion
//! are down-weighted by a robust (Tukey) function rather than spoiling the fit. The covariance
//! predicts the error of each parameter; with no file given, the example warps a synthetic
//! texture by a known motion so that the error can be compared with it.
//!
//! This example lives in the root package because reading PNG files needs the `image` crate,
//! which is not a dependency of motion-est.
#![allow(clippy::print_stdout)]

use motion_est::{ModelSpec, MotionEstimator, MotionModel, Region, Settings};
use vision_core::{GreyImage, ToGreyBuffer};

/// The motion of the synthetic pair, about a 2° rotation, a 3 % zoom and a shift of
/// (1.5, −0.7) px, as [a1 … a6] about the image centre.
const SYNTHETIC_MOTION: [f64; 6] = [1.5, 0.03, -0.0349, -0.7, 0.0349, 0.03];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    let (width, height, first, second, truth) = match paths.as_slice() {
        [a, b] => {
            let (w, h, first) = read_grey(a)?;
            let (w2, h2, second) = read_grey(b)?;
            if (w, h) != (w2, h2) {
                return Err(format!("{a} is {w}×{h} but {b} is {w2}×{h2}").into());
            }
            (w, h, first, second, None)
        }
        [] => {
            let (w, h) = (160, 120);
            let (first, second) = synthetic_pair(w, h, &SYNTHETIC_MOTION);
            (w, h, first, second, Some(SYNTHETIC_MOTION))
        }
        _ => return Err("give two PNG files, or none for a synthetic pair".into()),
    };

    let estimator = MotionEstimator::new(Settings::default())?;
    let estimate = estimator.estimate_images(
        GreyImage::new(width, height, &first)?,
        GreyImage::new(width, height, &second)?,
        &Region::Full,
        ModelSpec::new(MotionModel::Affine, false),
        None,
    )?;

    let [ox, oy] = estimate.origin;
    println!("origin of (x, y): ({ox:.1}, {oy:.1})");
    // An estimate that did not converge, or that no dominant motion explains, is an error
    // (`motion_est::Error::Unreliable`) that `?` above reports: this one is reliable.
    println!(
        "inliers {:.0} %, noise σ {:.2} grey levels",
        100.0 * estimate.inlier_fraction,
        estimate.noise_sigma
    );
    // The synthetic motion is given about the image centre; re-express it about the origin the
    // estimator used: d(r) = b + B (r − c) = (b + B (o − c)) + B (r − o).
    let expected = truth.map(|t| {
        let (dx, dy) = (
            ox - (width as f64 - 1.0) / 2.0,
            oy - (height as f64 - 1.0) / 2.0,
        );
        [
            t[0] + t[1] * dx + t[2] * dy,
            t[1],
            t[2],
            t[3] + t[4] * dx + t[5] * dy,
            t[4],
            t[5],
        ]
    });
    let n = estimate.params.len();
    for (i, value) in estimate.params.iter().enumerate() {
        // The predicted standard deviation of each parameter is the root of its variance.
        let sd = estimate.covariance[i * n + i].sqrt();
        match expected {
            Some(e) => println!(
                "a{} = {value:9.5} ± {sd:.5}   (true {:9.5}, error {:+.5})",
                i + 1,
                e[i],
                value - e[i]
            ),
            None => println!("a{} = {value:9.5} ± {sd:.5}", i + 1),
        }
    }
    Ok(())
}

/// Reads an image file as grey levels 0–255, row-major.
fn read_grey(path: &str) -> Result<(usize, usize, Vec<f32>), Box<dyn std::error::Error>> {
    let grey = image::open(path)
        .map_err(|e| format!("{path}: {e}"))?
        .to_grey_buffer();
    let (w, h) = (grey.width() as usize, grey.height() as usize);
    Ok((w, h, grey.into_raw()))
}

/// A smooth texture, and the same texture moved by the affine `motion` about the image centre:
/// the second image at r + d(r) shows what the first shows at r.
fn synthetic_pair(w: usize, h: usize, motion: &[f64; 6]) -> (Vec<f32>, Vec<f32>) {
    let texture = |x: f64, y: f64| {
        128.0
            + 45.0 * (0.21 * x + 0.05 * y).sin() * (0.17 * y - 0.03 * x).cos()
            + 25.0 * (0.43 * x - 0.29 * y).sin()
    };
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    // p − c = (I + B)(r − c) + b, so r − c = (I + B)⁻¹ (p − c − b).
    let [b1, m11, m12, b2, m21, m22] = *motion;
    let (a, b, c, d) = (1.0 + m11, m12, m21, 1.0 + m22);
    let det = a * d - b * c;
    let mut first = Vec::with_capacity(w * h);
    let mut second = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let (px, py) = (x as f64 - cx - b1, y as f64 - cy - b2);
            let (rx, ry) = ((d * px - b * py) / det, (a * py - c * px) / det);
            first.push(texture(x as f64, y as f64) as f32);
            second.push(texture(rx + cx, ry + cy) as f32);
        }
    }
    (first, second)
}
