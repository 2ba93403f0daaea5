//! Pixel resampling shared by the geometric transforms: an affine map from output pixels to
//! source pixels, sampled bilinearly, with the source reflected at its borders, and an optional
//! linear motion blur.
//!
//! Coordinates follow the workspace's convention: pixel (i, j) is centred at (i, j), so a pixel
//! covers [i − ½, i + ½) and the frame [−½, W − ½) × [−½, H − ½).

use image::{Rgb, RgbImage};

/// The affine map from an output pixel (u, v) to the source point
/// (x, y) = (m[0]·u + m[1]·v + m[2], m[3]·u + m[4]·v + m[5]).
pub type Affine = [f64; 6];

/// An index of a row or column of `n` pixels, reflected about the frame's edges (−½ and n − ½):
/// −1 ↦ 0, −2 ↦ 1, n ↦ n − 1, n + 1 ↦ n − 2, and so on, periodically.
fn reflect(i: i64, n: u32) -> u32 {
    let n = i64::from(n);
    let period = 2 * n;
    let r = i.rem_euclid(period);
    // rem_euclid of a positive period lies in [0, 2n), so both branches fit in u32's range of n.
    (if r < n { r } else { period - 1 - r }) as u32
}

/// The bilinear sample of `img` at (x, y), the source reflected beyond its edges.
fn sample(img: &RgbImage, x: f64, y: f64) -> [f32; 3] {
    let (w, h) = img.dimensions();
    let (fx, fy) = (x.floor(), y.floor());
    let (ax, ay) = ((x - fx) as f32, (y - fy) as f32);
    let (i0, j0) = (fx as i64, fy as i64);
    let (x0, x1) = (reflect(i0, w), reflect(i0 + 1, w));
    let (y0, y1) = (reflect(j0, h), reflect(j0 + 1, h));
    let p00 = img.get_pixel(x0, y0).0;
    let p10 = img.get_pixel(x1, y0).0;
    let p01 = img.get_pixel(x0, y1).0;
    let p11 = img.get_pixel(x1, y1).0;
    let mut out = [0.0_f32; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let top = f32::from(p00[c]) * (1.0 - ax) + f32::from(p10[c]) * ax;
        let bottom = f32::from(p01[c]) * (1.0 - ax) + f32::from(p11[c]) * ax;
        *o = top * (1.0 - ay) + bottom * ay;
    }
    out
}

/// The frame of `size` whose pixel (u, v) shows `src` at `map`(u, v), bilinearly. With
/// `blur` = (bx, by), each pixel is the mean of `n` samples along the source displacement
/// t·(bx, by), t evenly spaced over [−½, ½] (a linear motion blur centred on the unblurred
/// picture, so the blurred target's centre is where the map puts it); `n` is one sample per
/// output pixel of the streak's length, at least 1 and at most 24.
pub fn warp(src: &RgbImage, size: (u32, u32), map: &Affine, blur: Option<(f64, f64)>) -> RgbImage {
    let offsets: Vec<(f64, f64)> = match blur {
        Some((bx, by)) if bx.hypot(by) > 0.0 => {
            // The streak's length in output pixels: the source displacement through the map's
            // inverse scale (the maps used here are similarities, so one scale suffices).
            let scale = (map[0] * map[4] - map[1] * map[3]).abs().sqrt().max(1e-9);
            let n = ((bx.hypot(by) / scale).ceil() as usize + 1).clamp(1, 24);
            (0..n)
                .map(|k| {
                    let t = if n == 1 {
                        0.0
                    } else {
                        k as f64 / (n - 1) as f64 - 0.5
                    };
                    (t * bx, t * by)
                })
                .collect()
        }
        _ => vec![(0.0, 0.0)],
    };
    let inv = 1.0 / offsets.len() as f32;
    RgbImage::from_fn(size.0, size.1, |u, v| {
        let (u, v) = (f64::from(u), f64::from(v));
        let x = map[0] * u + map[1] * v + map[2];
        let y = map[3] * u + map[4] * v + map[5];
        let mut acc = [0.0_f32; 3];
        for &(dx, dy) in &offsets {
            let s = sample(src, x + dx, y + dy);
            for c in 0..3 {
                acc[c] += s[c];
            }
        }
        Rgb(acc.map(|a| (a * inv).round().clamp(0.0, 255.0) as u8))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflection_repeats_the_edge_pixel_then_mirrors() {
        let got: Vec<u32> = (-4..8).map(|i| reflect(i, 4)).collect();
        assert_eq!(got, [3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0]);
    }

    #[test]
    fn the_identity_map_returns_the_frame_and_a_shift_moves_it() {
        let src = RgbImage::from_fn(9, 7, |i, j| Rgb([(i * 20) as u8, (j * 30) as u8, 7]));
        let same = warp(&src, (9, 7), &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0], None);
        assert_eq!(same, src);
        let shifted = warp(&src, (9, 7), &[1.0, 0.0, 2.0, 0.0, 1.0, 1.0], None);
        assert_eq!(shifted.get_pixel(3, 3), src.get_pixel(5, 4));
        // A blur along x of a picture constant along x changes nothing.
        let rows = RgbImage::from_fn(9, 7, |_, j| Rgb([(j * 30) as u8; 3]));
        let blurred = warp(
            &rows,
            (9, 7),
            &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            Some((6.0, 0.0)),
        );
        assert_eq!(blurred, rows);
    }
}
