//! Overlay frames (as in W Fig. 10, 13, 15): the frame with the estimated contour coloured by
//! tracker status or clutter class, the likely particles drawn faintly, optionally the
//! ground-truth box, and a label with the frame number and the tracker's status; PNG or JPEG
//! files and an animated GIF of them.
//!
//! What an overlay shows (the report's legend, [`LEGEND`], says the same):
//! - the estimate: a thick contour in the status colour (locked green, partial orange, lost red)
//!   or the clutter-class colour (light blue, yellow, magenta), over a dark halo so that it stands
//!   out from the particles and from the frame;
//! - the particles: the heaviest few as thin contours in the same colour, at most
//!   [`PARTICLE_MAX_ALPHA`] opaque and in proportion to their weight (fewer while lost);
//! - the ground truth: a white dashed box over a dark halo (no status or clutter colour is white);
//! - frame 1, the initialisation: the initial contour (from `--init` or the first labelled box)
//!   in white, without particles — the tracker has estimated nothing yet;
//! - top left: the frame number and the status (`init` on frame 1).
//!
//! The drawing is a small antialiased rasteriser of its own: each pixel within reach of a curve is
//! blended with the curve's colour in proportion to how much of a line of the given width covers
//! it, using the pixel centre's distance to the curve (pixel (i, j) has its centre at (i, j)). For
//! an ellipse the distance is the first-order distance |r − 1|/|∇r| of the implicit function
//! r = sqrt((u/a)² + (v/b)²) in the ellipse's own axes: exact on circles and within a fraction of
//! a pixel near the contour for the moderate eccentricities of tracked targets. One pass per shape means no
//! darker dots where polyline segments would overlap, which matters for translucent particles.
//! Text is drawn with the public-domain 8×8 bitmap font of the `font8x8` crate.

use std::path::Path;

use font8x8::UnicodeFonts as _;
use image::codecs::gif::{GifEncoder, Repeat};
use image::codecs::jpeg::JpegEncoder;
use image::codecs::png::{CompressionType, FilterType, PngEncoder};
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
/// Colour of the ground-truth box (dashed, over a dark halo): white, which no status or clutter
/// class uses.
pub const GROUND_TRUTH: Colour = [255, 255, 255];
/// Colour of the initial contour on frame 1 (not an estimate: the box the tracker starts from).
pub const INIT: Colour = [255, 255, 255];
/// Colour of the halo under the estimate and the ground truth, and of the label's background.
pub const HALO: Colour = [0, 0, 0];
/// Colours of clutter classes β = 0, 1, 2 (low, medium, high clutter); later classes reuse them.
pub const CLUTTER: [Colour; 3] = [[60, 140, 255], [255, 220, 0], [230, 40, 200]];
/// Largest opacity of a particle contour (the heaviest particle's); lighter particles are fainter
/// in proportion to their weight.
pub const PARTICLE_MAX_ALPHA: f64 = 0.35;
/// Opacity of the dark halo under the estimate and the ground-truth box.
pub const HALO_ALPHA: f64 = 0.7;
/// Length of the dashes (and gaps) of the ground-truth box, pixels.
pub const DASH: f64 = 4.0;

/// What the colours and marks of an overlay mean, one line each, for the report's legend and the
/// documentation.
pub const LEGEND: [&str; 7] = [
    "Estimate: thick contour over a dark halo, coloured by tracker status (locked green, \
     partial orange, lost red) or, with --colour-by clutter, by clutter class β̂ (0 light blue, \
     1 yellow, 2 magenta).",
    "Particles: the heaviest ones as thin contours in the estimate's colour, at most 35 % opaque \
     and fainter in proportion to their weight; at most 10 while the tracker is lost.",
    "Ground truth (when known): white dashed box over a dark halo.",
    "Frame 1 is the initialisation: the initial contour (--init, or the first labelled box) in \
     white, without particles; the tracker has no estimate or status of its own there.",
    "Top left: the frame number (1-based) and the tracker status (init on frame 1; with \
     --colour-by clutter also the clutter class).",
    "Trackers without a status process (m1, m2, m3, w-fixed, w-switch, w-hmm) show no status \
     and draw in green; w-occ's status is read from γ̂ (locked ≤ 0.2, lost ≥ 0.8).",
    "The head tracker has two states only, locked and lost (P(lost) > 0.5).",
];

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
    /// Width of the estimated contour, pixels (default 3); its halo is 2 pixels wider.
    pub contour_width: f64,
    /// Width of particle contours, pixels (default 1).
    pub particle_width: f64,
    /// Width of the ground-truth box outline, pixels (default 1).
    pub groundtruth_width: f64,
}

impl Default for OverlayStyle {
    fn default() -> Self {
        Self {
            contour_width: 3.0,
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
    /// Text drawn at the top left (the frame number and status), after a swatch of `colour`.
    pub label: Option<String>,
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
            label: None,
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
    draw_box_dashed(img, bx, colour, alpha, width, None);
}

/// Draws the outline of an axis-aligned box, antialiased, solid or in dashes of `dash` pixels
/// (and gaps of the same length) measured along each side from its top or left end.
pub fn draw_box_dashed(
    img: &mut RgbImage,
    bx: &BoundingBox,
    colour: Colour,
    alpha: f64,
    width: f64,
    dash: Option<f64>,
) {
    if !bx.is_finite() || alpha.is_nan() || alpha <= 0.0 {
        return;
    }
    let (x0, y0, x1, y1) = (bx.x, bx.y, bx.x + bx.w.max(0.0), bx.y + bx.h.max(0.0));
    let half = 0.5 * width.max(0.5);
    let reach = half + 1.0;
    let dash = dash.filter(|d| d.is_finite() && *d >= 1.0);
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
            if let Some(dash) = dash {
                // The position along the nearest side: x on the top and bottom, y on the left and
                // right.
                let horizontal =
                    (y - y0).abs().min((y - y1).abs()) <= (x - x0).abs().min((x - x1).abs());
                let along = if horizontal { x - x0 } else { y - y0 };
                if (along / dash).floor().rem_euclid(2.0) != 0.0 {
                    return 0.0;
                }
            }
            (half + 0.5 - d).clamp(0.0, 1.0)
        },
    );
}

/// The scale of the label's 8×8 font on an image of height `h`: 1 below 480 rows, 2 from 480, 3
/// from 720, 4 from 960, so that the label stays legible on large frames and small on small ones.
pub fn label_scale(h: u32) -> u32 {
    (h / 240).clamp(1, 4)
}

/// Margin between the label's box and the image corner, and padding inside it, in font pixels.
const LABEL_PAD: u32 = 2;

/// Draws `text` at the top left of `img`, white in the 8×8 font, after a square swatch of
/// `swatch`, on a dark box. Characters the font lacks are drawn as `?`; what does not fit in the
/// image is clipped.
pub fn draw_label(img: &mut RgbImage, text: &str, swatch: Colour) {
    let (w, h) = img.dimensions();
    if w == 0 || h == 0 {
        return;
    }
    let s = label_scale(h);
    let glyphs: Vec<[u8; 8]> = text
        .chars()
        .map(|c| {
            font8x8::BASIC_FONTS
                .get(c)
                .or_else(|| font8x8::GREEK_FONTS.get(c))
                .or_else(|| font8x8::BASIC_FONTS.get('?'))
                .unwrap_or([0; 8])
        })
        .collect();
    // Box: pad, swatch (8), pad, text (8 per glyph), pad; in font pixels, times the scale.
    let inner = 8 + LABEL_PAD + 8 * glyphs.len() as u32;
    let (bx, by) = (LABEL_PAD * s, LABEL_PAD * s);
    let (bw, bh) = ((inner + 2 * LABEL_PAD) * s, (8 + 2 * LABEL_PAD) * s);
    for y in by..(by + bh).min(h) {
        for x in bx..(bx + bw).min(w) {
            blend(img, x, y, HALO, 0.6);
        }
    }
    let (ox, oy) = (bx + LABEL_PAD * s, by + LABEL_PAD * s);
    let mut put = |gx: u32, gy: u32, colour: Colour| {
        for dy in 0..s {
            for dx in 0..s {
                let (x, y) = (ox + gx * s + dx, oy + gy * s + dy);
                if x < w && y < h {
                    img.put_pixel(x, y, image::Rgb(colour));
                }
            }
        }
    };
    for gy in 1..7 {
        for gx in 1..7 {
            put(gx, gy, swatch);
        }
    }
    for (i, rows) in glyphs.iter().enumerate() {
        let left = 8 + LABEL_PAD + 8 * i as u32;
        for (gy, row) in rows.iter().enumerate() {
            for bit in 0..8u32 {
                // font8x8: one byte per row, top to bottom; bit 0 is the leftmost pixel.
                if row & (1 << bit) != 0 {
                    put(left + bit, gy as u32, [255, 255, 255]);
                }
            }
        }
    }
}

/// Draws `overlay` on a copy of `frame`: particles first (faint), then the ground-truth box
/// (white dashes over a dark halo), then the estimated contour over its dark halo, then the
/// label.
pub fn render_overlay(frame: &RgbImage, overlay: &Overlay) -> RgbImage {
    let mut img = frame.clone();
    let st = &overlay.style;
    for (e, alpha) in &overlay.particles {
        draw_ellipse(&mut img, e, overlay.colour, *alpha, st.particle_width);
    }
    if let Some(gt) = &overlay.groundtruth {
        draw_box(&mut img, gt, HALO, HALO_ALPHA, st.groundtruth_width + 2.0);
        draw_box_dashed(
            &mut img,
            gt,
            GROUND_TRUTH,
            1.0,
            st.groundtruth_width,
            Some(DASH),
        );
    }
    draw_ellipse(
        &mut img,
        &overlay.contour,
        HALO,
        HALO_ALPHA,
        st.contour_width + 2.0,
    );
    draw_ellipse(
        &mut img,
        &overlay.contour,
        overlay.colour,
        1.0,
        st.contour_width,
    );
    if let Some(text) = &overlay.label {
        draw_label(&mut img, text, overlay.colour);
    }
    img
}

/// Encodes an RGB image as PNG bytes at the fast compression level, adaptive filtering.
///
/// # Errors
/// [`AppError::Computation`] when encoding fails.
pub fn encode_png(img: &RgbImage) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    PngEncoder::new_with_quality(&mut bytes, CompressionType::Fast, FilterType::Adaptive)
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            ExtendedColorType::Rgb8,
        )
        .map_err(|e| AppError::computation("PNG encoding", e))?;
    Ok(bytes)
}

/// Encodes an RGB image as JPEG bytes at `quality` (1–100).
///
/// # Errors
/// [`AppError::Computation`] when encoding fails.
pub fn encode_jpeg(img: &RgbImage, quality: u8) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    JpegEncoder::new_with_quality(&mut bytes, quality)
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            ExtendedColorType::Rgb8,
        )
        .map_err(|e| AppError::computation("JPEG encoding", e))?;
    Ok(bytes)
}

/// Writes `img` as a PNG file atomically.
///
/// # Errors
/// [`AppError::Computation`] when encoding fails, [`AppError::Write`] when writing fails.
pub fn write_png(path: &Path, img: &RgbImage) -> Result<()> {
    write_atomic(path, &encode_png(img)?)
}

/// The file format of overlay frames (`--overlay-format`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum OverlayFormat {
    /// Lossless PNG at the `image` crate's fast compression level: the stronger levels make
    /// overlays of footage only a few percent smaller for many times the time
    /// (docs/RESULTS.md, "Input and output").
    #[default]
    Png,
    /// JPEG at quality [`JPEG_QUALITY`]: several times smaller, lossy.
    Jpeg,
}

/// Quality of JPEG overlays (1–100).
pub const JPEG_QUALITY: u8 = 90;

impl OverlayFormat {
    /// The file extension, without the dot: `png` or `jpg`.
    pub fn extension(self) -> &'static str {
        match self {
            OverlayFormat::Png => "png",
            OverlayFormat::Jpeg => "jpg",
        }
    }

    /// Encodes `img` in this format.
    ///
    /// # Errors
    /// [`AppError::Computation`] when encoding fails.
    pub fn encode(self, img: &RgbImage) -> Result<Vec<u8>> {
        match self {
            OverlayFormat::Png => encode_png(img),
            OverlayFormat::Jpeg => encode_jpeg(img, JPEG_QUALITY),
        }
    }

    /// Writes `img` in this format, atomically.
    ///
    /// # Errors
    /// As [`OverlayFormat::encode`], and [`AppError::Write`].
    pub fn write(self, path: &Path, img: &RgbImage) -> Result<()> {
        write_atomic(path, &self.encode(img)?)
    }
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
        // Dashes of 4 px from the top-left corner: x in [2, 6) on the top side is a dash,
        // [6, 10) a gap; the same down the left side.
        assert_eq!(out.get_pixel(4, 2).0, GROUND_TRUTH);
        assert_eq!(out.get_pixel(2, 4).0, GROUND_TRUTH);
        assert_eq!(out.get_pixel(8, 2).0, [0, 0, 0]);
        assert_eq!(out.get_pixel(2, 8).0, [0, 0, 0]);
        assert_eq!(out.get_pixel(15, 15).0, [0, 0, 0]);
        // The input frame is not modified.
        assert_eq!(frame.get_pixel(20, 15).0, [0, 0, 0]);
    }

    /// The largest difference of one channel between two colours.
    fn channel_distance(a: Colour, b: Colour) -> u8 {
        a.iter()
            .zip(&b)
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap_or(0)
    }

    #[test]
    fn ground_truth_has_a_colour_no_status_or_clutter_class_uses() {
        for c in CLUTTER.iter().chain(&[LOCKED, PARTIAL, LOST]) {
            assert!(channel_distance(GROUND_TRUTH, *c) >= 100, "{c:?}");
        }
    }

    #[test]
    fn the_estimate_stands_out_from_the_particles_when_lost() {
        // A grey frame, the lost estimate and ten heavy particles crossing it at every size.
        let frame = RgbImage::from_pixel(80, 80, image::Rgb([128, 128, 128]));
        let mut ov = Overlay::new(Ellipse::new(40.0, 40.0, 15.0, 15.0, 0.0), LOST);
        let heaviest = likely_particles(
            &(0..10)
                .map(|i| Ellipse::new(40.0, 40.0, 5.0 + 3.0 * f64::from(i), 12.0, 0.0))
                .collect::<Vec<_>>(),
            &[1.0; 10],
            10,
            PARTICLE_MAX_ALPHA,
        );
        ov.particles = heaviest;
        let out = render_overlay(&frame, &ov);
        // On the estimate's contour: its own colour, whatever crosses it.
        assert_eq!(out.get_pixel(55, 40).0, LOST);
        assert_eq!(out.get_pixel(40, 25).0, LOST);
        // Its halo, 2 px outside the 3-px line: darker than the frame on every channel.
        let halo = out.get_pixel(57, 40).0;
        assert!(halo.iter().all(|&c| c < 60), "{halo:?}");
        // A particle alone (a = 32 crosses y = 40 at x = 72): at most 35 % of the way to red.
        let p = out.get_pixel(72, 40).0;
        // 128 + 0.35 · (235 − 128) = 165.45, 128 − 0.35 · (128 − 30) = 93.7.
        assert_eq!(p, [165, 94, 94], "{p:?}");
        let max_shift = (PARTICLE_MAX_ALPHA * 128.0).ceil() as u8;
        for (x, y) in [(72, 40), (68, 40), (40, 68)] {
            let q = out.get_pixel(x, y).0;
            assert!(
                q.iter().all(|&c| c.abs_diff(128) <= max_shift),
                "{x},{y}: {q:?}"
            );
        }
    }

    #[test]
    fn label_draws_white_text_after_a_swatch_on_a_dark_box() {
        let mut a = RgbImage::from_pixel(120, 40, image::Rgb([200, 200, 200]));
        draw_label(&mut a, "frame 12  lost", LOST);
        // Scale 1 below 480 rows: the box starts at (2, 2); the swatch at (4 + 1, 4 + 1).
        assert_eq!(a.get_pixel(5, 5).0, LOST);
        assert_eq!(a.get_pixel(10, 10).0, LOST);
        // The box darkens the frame: 200 · 0.4 = 80.
        assert_eq!(a.get_pixel(2, 2).0, [80, 80, 80]);
        // Below the box (its height is 8 + 2 · 2 = 12 rows from row 2) the frame is untouched.
        assert_eq!(a.get_pixel(5, 14).0, [200, 200, 200]);
        // The text is white, and another frame number draws other pixels.
        let white = |img: &RgbImage| -> Vec<(u32, u32)> {
            img.enumerate_pixels()
                .filter(|(_, _, p)| p.0 == [255, 255, 255])
                .map(|(x, y, _)| (x, y))
                .collect()
        };
        let text = white(&a);
        assert!(text.len() > 50, "{}", text.len());
        assert!(text.iter().all(|&(x, y)| x >= 14 && (4..12).contains(&y)));
        let mut b = RgbImage::from_pixel(120, 40, image::Rgb([200, 200, 200]));
        draw_label(&mut b, "frame 13  lost", LOST);
        assert_ne!(white(&b), text);
        // Large frames get a larger font, and a label wider than the frame is clipped.
        assert_eq!(
            (label_scale(240), label_scale(480), label_scale(1080)),
            (1, 2, 4)
        );
        draw_label(&mut black(5, 5), "frame 1000  partial", PARTIAL);
    }

    #[test]
    fn overlay_formats_encode_png_losslessly_and_jpeg_smaller() {
        // A textured frame, as footage is: JPEG is far smaller than lossless PNG.
        // A smooth gradient with a little random grain on every pixel, as footage has.
        use rand::{Rng as _, SeedableRng as _};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let img = RgbImage::from_fn(160, 120, |x, y| {
            let v = (x + y) as u8 / 2 + rng.random_range(0..24u8);
            image::Rgb([v, v / 2 + 60, 200 - v / 2])
        });
        let png = OverlayFormat::Png.encode(&img).unwrap();
        let jpg = OverlayFormat::Jpeg.encode(&img).unwrap();
        assert!(png.starts_with(b"\x89PNG"));
        assert!(jpg.starts_with(&[0xFF, 0xD8]));
        assert_eq!(image::load_from_memory(&png).unwrap().to_rgb8(), img);
        let back = image::load_from_memory(&jpg).unwrap().to_rgb8();
        assert_eq!(back.dimensions(), img.dimensions());
        assert!(jpg.len() < png.len(), "{} vs {}", jpg.len(), png.len());
        assert_eq!(OverlayFormat::Jpeg.extension(), "jpg");
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
