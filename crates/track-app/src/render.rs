//! Overlay frames (as in W Fig. 10, 13, 15): the frame with the estimated contour coloured by
//! tracker status or clutter class, the likely particles drawn faintly, and optionally the
//! ground-truth box; PNG files and an animated GIF of them.
//!
//! The drawing is a small antialiased rasteriser of its own: each pixel within reach of a curve is
//! blended with the curve's colour in proportion to how much of a line of the given width covers
//! it, using the pixel centre's distance to the curve (pixel (i, j) has its centre at (i, j)). For
//! an ellipse the distance is the first-order distance |r − 1|/|∇r| of the implicit function
//! r = sqrt((u/a)² + (v/b)²) in the ellipse's own axes: exact on circles and within a fraction of
//! a pixel near the contour for the moderate eccentricities of tracked targets. One pass per shape means no
//! darker dots where polyline segments would overlap, which matters for translucent particles.

use std::path::Path;

use image::codecs::gif::{GifEncoder, Repeat};
use image::codecs::png::PngEncoder;
use image::{Delay, ExtendedColorType, ImageEncoder, RgbImage, RgbaImage};
use vision_core::{BoundingBox, Ellipse, TrackStatus};

use crate::output::write_atomic;
use crate::{AppError, Result};

/// An 8-bit RGB colour.
pub type Colour = [u8; 3];

/// Contour colour while locked.
pub const LOCKED: Colour = [40, 210, 60];
/// Contour colour while partially occluded.
pub const PARTIAL: Colour = [255, 150, 0];
/// Contour colour while lost.
pub const LOST: Colour = [235, 30, 30];
/// Colour of the ground-truth box.
pub const GROUND_TRUTH: Colour = [60, 200, 255];
/// Colours of clutter classes β = 0, 1, 2 (low, medium, high clutter); later classes reuse them.
pub const CLUTTER: [Colour; 3] = [[60, 140, 255], [255, 220, 0], [230, 40, 200]];

/// The contour colour of a tracker status: locked green, partial orange, lost red.
pub fn status_colour(status: TrackStatus) -> Colour {
    match status {
        TrackStatus::Locked => LOCKED,
        TrackStatus::PartiallyOccluded => PARTIAL,
        TrackStatus::Lost => LOST,
    }
}

/// The contour colour of clutter class `beta` (0-based).
pub fn clutter_colour(beta: usize) -> Colour {
    CLUTTER[beta % CLUTTER.len()]
}

/// Line widths and opacities of an overlay.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OverlayStyle {
    /// Width of the estimated contour, pixels (default 2).
    pub contour_width: f64,
    /// Width of particle contours, pixels (default 1).
    pub particle_width: f64,
    /// Width of the ground-truth box outline, pixels (default 1).
    pub groundtruth_width: f64,
}

impl Default for OverlayStyle {
    fn default() -> Self {
        Self {
            contour_width: 2.0,
            particle_width: 1.0,
            groundtruth_width: 1.0,
        }
    }
}

/// What to draw over one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Overlay {
    /// The estimated contour.
    pub contour: Ellipse,
    /// Its colour ([`status_colour`] or [`clutter_colour`]).
    pub colour: Colour,
    /// Likely particles as (contour, opacity in [0, 1]), drawn first and faintly in `colour`.
    pub particles: Vec<(Ellipse, f64)>,
    /// The ground-truth box, if known for this frame.
    pub groundtruth: Option<BoundingBox>,
    /// Widths.
    pub style: OverlayStyle,
}

impl Overlay {
    /// An overlay with the contour only, in the default style.
    pub fn new(contour: Ellipse, colour: Colour) -> Self {
        Self {
            contour,
            colour,
            particles: Vec::new(),
            groundtruth: None,
            style: OverlayStyle::default(),
        }
    }
}

/// Picks the `k` heaviest particles and gives each an opacity proportional to its weight,
/// `max_alpha` for the heaviest. Weights need not be normalised; non-finite or negative weights
/// and non-finite ellipses are skipped.
pub fn likely_particles(
    ellipses: &[Ellipse],
    weights: &[f64],
    k: usize,
    max_alpha: f64,
) -> Vec<(Ellipse, f64)> {
    let mut idx: Vec<usize> = (0..ellipses.len().min(weights.len()))
        .filter(|&i| weights[i].is_finite() && weights[i] > 0.0 && ellipses[i].is_finite())
        .collect();
    idx.sort_by(|&i, &j| weights[j].total_cmp(&weights[i]));
    idx.truncate(k);
    let top = idx.first().map(|&i| weights[i]).unwrap_or(1.0);
    idx.into_iter()
        .map(|i| (ellipses[i], max_alpha.clamp(0.0, 1.0) * weights[i] / top))
        .collect()
}

/// Blends `colour` into the pixel at (x, y) with opacity `a` in [0, 1].
fn blend(img: &mut RgbImage, x: u32, y: u32, colour: Colour, a: f64) {
    let p = img.get_pixel_mut(x, y);
    for (c, &target) in p.0.iter_mut().zip(&colour) {
        let v = f64::from(*c) * (1.0 - a) + f64::from(target) * a;
        *c = v.round().clamp(0.0, 255.0) as u8;
    }
}

/// Calls `cover(x, y)` for each pixel of the image inside the box [x0, x1]×[y0, y1] (clipped) and
/// blends with the coverage it returns.
fn shade(
    img: &mut RgbImage,
    (x0, y0, x1, y1): (f64, f64, f64, f64),
    colour: Colour,
    alpha: f64,
    cover: impl Fn(f64, f64) -> f64,
) {
    let (w, h) = img.dimensions();
    if w == 0 || h == 0 || !(x0.is_finite() && y0.is_finite() && x1.is_finite() && y1.is_finite()) {
        return;
    }
    let lo = |v: f64, n: u32| v.floor().clamp(0.0, f64::from(n - 1)) as u32;
    let (xa, xb) = (lo(x0, w), lo(x1.ceil(), w));
    let (ya, yb) = (lo(y0, h), lo(y1.ceil(), h));
    if x1 < 0.0 || y1 < 0.0 || x0 > f64::from(w - 1) || y0 > f64::from(h - 1) {
        return;
    }
    for y in ya..=yb {
        for x in xa..=xb {
            let c = cover(f64::from(x), f64::from(y));
            if c > 0.0 {
                blend(img, x, y, colour, alpha * c.min(1.0));
            }
        }
    }
}

/// Draws the outline of `e` with line width `width` (pixels) and opacity `alpha`, antialiased.
/// Non-finite ellipses are skipped; semi-axes below half a pixel are drawn as half a pixel.
pub fn draw_ellipse(img: &mut RgbImage, e: &Ellipse, colour: Colour, alpha: f64, width: f64) {
    if !e.is_finite() || alpha.is_nan() || alpha <= 0.0 {
        return;
    }
    let (a, b) = (e.a.abs().max(0.5), e.b.abs().max(0.5));
    let half = 0.5 * width.max(0.5);
    let reach = half + 1.0;
    let bb = Ellipse { a, b, ..*e }.bounding_box();
    let (s, c) = e.angle.sin_cos();
    let (ia2, ib2) = (1.0 / (a * a), 1.0 / (b * b));
    shade(
        img,
        (
            bb.x - reach,
            bb.y - reach,
            bb.x + bb.w + reach,
            bb.y + bb.h + reach,
        ),
        colour,
        alpha,
        |x, y| {
            let (dx, dy) = (x - e.cx, y - e.cy);
            let (u, v) = (dx * c + dy * s, -dx * s + dy * c);
            // r = sqrt((u/a)² + (v/b)²) is 1 on the contour; |r − 1| / |∇r| is the distance
            // to first order, and exact for a circle (where it is |ρ − a| at radius ρ).
            let r = (u * u * ia2 + v * v * ib2).sqrt();
            let grad = (u * u * ia2 * ia2 + v * v * ib2 * ib2).sqrt();
            if r <= 1e-12 || grad <= 1e-12 {
                return 0.0;
            }
            let d = (r - 1.0).abs() * r / grad;
            (half + 0.5 - d).clamp(0.0, 1.0)
        },
    );
}

/// Draws the outline of an axis-aligned box, antialiased.
pub fn draw_box(img: &mut RgbImage, bx: &BoundingBox, colour: Colour, alpha: f64, width: f64) {
    if !bx.is_finite() || alpha.is_nan() || alpha <= 0.0 {
        return;
    }
    let (x0, y0, x1, y1) = (bx.x, bx.y, bx.x + bx.w.max(0.0), bx.y + bx.h.max(0.0));
    let half = 0.5 * width.max(0.5);
    let reach = half + 1.0;
    shade(
        img,
        (x0 - reach, y0 - reach, x1 + reach, y1 + reach),
        colour,
        alpha,
        |x, y| {
            let inside = x >= x0 && x <= x1 && y >= y0 && y <= y1;
            let d = if inside {
                (x - x0).min(x1 - x).min(y - y0).min(y1 - y)
            } else {
                let dx = (x0 - x).max(x - x1).max(0.0);
                let dy = (y0 - y).max(y - y1).max(0.0);
                dx.hypot(dy)
            };
            (half + 0.5 - d).clamp(0.0, 1.0)
        },
    );
}

/// Draws `overlay` on a copy of `frame`: particles first (faint), then the ground-truth box, then
/// the estimated contour on top.
pub fn render_overlay(frame: &RgbImage, overlay: &Overlay) -> RgbImage {
    let mut img = frame.clone();
    let st = &overlay.style;
    for (e, alpha) in &overlay.particles {
        draw_ellipse(&mut img, e, overlay.colour, *alpha, st.particle_width);
    }
    if let Some(gt) = &overlay.groundtruth {
        draw_box(&mut img, gt, GROUND_TRUTH, 1.0, st.groundtruth_width);
    }
    draw_ellipse(
        &mut img,
        &overlay.contour,
        overlay.colour,
        1.0,
        st.contour_width,
    );
    img
}

/// Encodes an RGB image as PNG bytes.
///
/// # Errors
/// [`AppError::Computation`] when encoding fails.
pub fn encode_png(img: &RgbImage) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    PngEncoder::new(&mut bytes)
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            ExtendedColorType::Rgb8,
        )
        .map_err(|e| AppError::computation("PNG encoding", e))?;
    Ok(bytes)
}

/// Writes `img` as a PNG file atomically.
///
/// # Errors
/// [`AppError::Computation`] when encoding fails, [`AppError::Write`] when writing fails.
pub fn write_png(path: &Path, img: &RgbImage) -> Result<()> {
    write_atomic(path, &encode_png(img)?)
}

/// A copy of `img` scaled down (never up) to at most `max_width` pixels wide, keeping its aspect.
pub fn thumbnail(img: &RgbImage, max_width: u32) -> RgbImage {
    let (w, h) = img.dimensions();
    if w <= max_width || w == 0 {
        return img.clone();
    }
    let nh = ((u64::from(h) * u64::from(max_width)) / u64::from(w)).max(1) as u32;
    image::imageops::resize(
        img,
        max_width.max(1),
        nh,
        image::imageops::FilterType::Triangle,
    )
}

/// Encodes `frames` as a looping animated GIF, `delay_ms` per frame.
///
/// # Errors
/// [`AppError::Computation`] when there is no frame, the frames differ in size, or encoding
/// fails.
pub fn encode_gif(frames: &[RgbImage], delay_ms: u32) -> Result<Vec<u8>> {
    let ctx = "GIF encoding";
    let Some(first) = frames.first() else {
        return Err(AppError::computation(ctx, "no frame to encode"));
    };
    if let Some((i, f)) = frames
        .iter()
        .enumerate()
        .find(|(_, f)| f.dimensions() != first.dimensions())
    {
        return Err(AppError::computation(
            ctx,
            format!(
                "frame {} is {}×{} but the first is {}×{}",
                i + 1,
                f.width(),
                f.height(),
                first.width(),
                first.height()
            ),
        ));
    }
    let mut bytes = Vec::new();
    {
        // Speed 10 of 1–30: quantisation quality matters less than time for hundreds of frames.
        let mut enc = GifEncoder::new_with_speed(&mut bytes, 10);
        enc.set_repeat(Repeat::Infinite)
            .map_err(|e| AppError::computation(ctx, e))?;
        for f in frames {
            let rgba: RgbaImage = image::DynamicImage::ImageRgb8(f.clone()).to_rgba8();
            let frame =
                image::Frame::from_parts(rgba, 0, 0, Delay::from_numer_denom_ms(delay_ms, 1));
            enc.encode_frame(frame)
                .map_err(|e| AppError::computation(ctx, e))?;
        }
    }
    Ok(bytes)
}

/// Writes `frames` as an animated GIF atomically (see [`encode_gif`]).
///
/// # Errors
/// As [`encode_gif`], and [`AppError::Write`].
pub fn write_gif(path: &Path, frames: &[RgbImage], delay_ms: u32) -> Result<()> {
    write_atomic(path, &encode_gif(frames, delay_ms)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn black(w: u32, h: u32) -> RgbImage {
        RgbImage::new(w, h)
    }

    #[test]
    fn circle_outline_lies_on_the_radius() {
        let mut img = black(41, 41);
        let e = Ellipse::new(20.0, 20.0, 10.0, 10.0, 0.3);
        draw_ellipse(&mut img, &e, LOCKED, 1.0, 2.0);
        // On the circle: fully covered. Far from it (3 px outside, 7 px inside, the centre): no
        // paint at all.
        assert_eq!(img.get_pixel(30, 20).0, LOCKED);
        assert_eq!(img.get_pixel(20, 10).0, LOCKED);
        assert_eq!(img.get_pixel(20, 20).0, [0, 0, 0]);
        assert_eq!(img.get_pixel(33, 20).0, [0, 0, 0]);
        assert_eq!(img.get_pixel(20, 17).0, [0, 0, 0]);
        // Coverage is (half width + 0.5 − distance) clamped to [0, 1]; check one partial pixel.
        let mut img2 = black(41, 41);
        draw_ellipse(
            &mut img2,
            &Ellipse::new(20.0, 20.25, 10.0, 10.0, 0.0),
            [200, 200, 200],
            1.0,
            2.0,
        );
        // Pixel (20, 31) is 0.75 px outside the circle's bottom: coverage 1 + 0.5 − 0.75 = 0.75,
        // so 0.75 · 200 = 150 exactly (the distance is exact on a circle).
        assert_eq!(img2.get_pixel(20, 31).0, [150, 150, 150]);
    }

    #[test]
    fn rotated_ellipse_axis_end_is_painted() {
        let mut img = black(60, 60);
        let e = Ellipse::new(30.0, 30.0, 20.0, 5.0, std::f64::consts::FRAC_PI_2);
        draw_ellipse(&mut img, &e, LOST, 1.0, 1.0);
        // a is along +y after a 90° turn: (30, 50) and (30, 10) are on the contour, (50, 30) is not.
        assert_eq!(img.get_pixel(30, 50).0, LOST);
        assert_eq!(img.get_pixel(35, 30).0, LOST);
        assert_eq!(img.get_pixel(50, 30).0, [0, 0, 0]);
    }

    #[test]
    fn faint_particles_and_box() {
        let frame = black(30, 30);
        let mut ov = Overlay::new(Ellipse::new(15.0, 15.0, 5.0, 5.0, 0.0), PARTIAL);
        ov.particles = vec![(Ellipse::new(15.0, 15.0, 10.0, 10.0, 0.0), 0.2)];
        ov.groundtruth = Some(BoundingBox::new(2.0, 2.0, 26.0, 26.0));
        let out = render_overlay(&frame, &ov);
        assert_eq!(out.get_pixel(20, 15).0, PARTIAL);
        // Particle at 20 % of PARTIAL: round(0.2·255) = 51, round(0.2·150) = 30.
        assert_eq!(out.get_pixel(25, 15).0, [51, 30, 0]);
        assert_eq!(out.get_pixel(2, 15).0, GROUND_TRUTH);
        assert_eq!(out.get_pixel(28, 28).0, GROUND_TRUTH);
        assert_eq!(out.get_pixel(15, 15).0, [0, 0, 0]);
        // The input frame is not modified.
        assert_eq!(frame.get_pixel(20, 15).0, [0, 0, 0]);
    }

    #[test]
    fn degenerate_shapes_do_not_panic() {
        let mut img = black(10, 10);
        for e in [
            Ellipse::new(f64::NAN, 1.0, 1.0, 1.0, 0.0),
            Ellipse::new(-1e12, 5.0, 1e13, 3.0, 0.1),
            Ellipse::new(5.0, 5.0, 0.0, 0.0, 0.0),
            Ellipse::new(500.0, 500.0, 3.0, 3.0, 0.0),
        ] {
            draw_ellipse(&mut img, &e, LOST, 1.0, 2.0);
        }
        draw_box(
            &mut img,
            &BoundingBox::new(-5.0, -5.0, 100.0, f64::INFINITY),
            LOST,
            1.0,
            1.0,
        );
        draw_box(
            &mut img,
            &BoundingBox::new(20.0, 20.0, 5.0, 5.0),
            LOST,
            1.0,
            1.0,
        );
        draw_ellipse(
            &mut black(0, 0),
            &Ellipse::new(0.0, 0.0, 1.0, 1.0, 0.0),
            LOST,
            1.0,
            1.0,
        );
    }

    #[test]
    fn likely_particles_are_the_heaviest_with_scaled_alpha() {
        let es: Vec<Ellipse> = (0..5)
            .map(|i| Ellipse::new(f64::from(i), 0.0, 1.0, 1.0, 0.0))
            .collect();
        let w = [0.1, 0.4, f64::NAN, 0.2, 0.3];
        let top = likely_particles(&es, &w, 3, 0.5);
        let xs: Vec<f64> = top.iter().map(|(e, _)| e.cx).collect();
        assert_eq!(xs, vec![1.0, 4.0, 3.0]);
        assert_eq!(top[0].1, 0.5);
        assert!((top[2].1 - 0.25).abs() < 1e-12);
        assert!(likely_particles(&es, &[0.0; 5], 3, 0.5).is_empty());
    }

    #[test]
    fn png_and_gif_files() {
        let dir = tempfile::tempdir().unwrap();
        let mut a = black(16, 12);
        draw_ellipse(
            &mut a,
            &Ellipse::new(8.0, 6.0, 4.0, 3.0, 0.0),
            LOCKED,
            1.0,
            1.0,
        );
        let png = dir.path().join("f.png");
        write_png(&png, &a).unwrap();
        let back = image::open(&png).unwrap().to_rgb8();
        assert_eq!(back, a);
        let gif = dir.path().join("a.gif");
        write_gif(&gif, &[a.clone(), black(16, 12)], 100).unwrap();
        let bytes = std::fs::read(&gif).unwrap();
        assert!(bytes.starts_with(b"GIF89a"));
        let decoder = image::codecs::gif::GifDecoder::new(std::io::Cursor::new(bytes)).unwrap();
        let frames = image::AnimationDecoder::into_frames(decoder)
            .collect_frames()
            .unwrap();
        assert_eq!(frames.len(), 2);
        assert!(encode_gif(&[], 100).is_err());
        let msg = encode_gif(&[a, black(3, 3)], 100).unwrap_err().to_string();
        assert!(msg.contains("frame 2 is 3×3"), "{msg}");
        assert_eq!(thumbnail(&black(320, 240), 160).dimensions(), (160, 120));
        assert_eq!(thumbnail(&black(100, 50), 160).dimensions(), (100, 50));
    }
}
