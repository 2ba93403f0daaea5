//! Working at a resolution set by the target's size.
//!
//! The papers' measurement lines, edge detector, patch grids and dynamics are all set in pixels
//! (lines of L = 20 px, edges at σ = 1 px, translation noise of 3 px), for a head of about 22×28
//! px semi-axes. On footage where the head is 100×160 px those settings measure texture inside
//! the face rather than its outline, the prior cannot follow its motion, and every motion estimate
//! costs as much as the head has pixels. [`ScaledTracker`] therefore shrinks every frame by one
//! factor, fixed at initialisation, so that the target's mean radius becomes
//! [`TrackerConfig::working_radius`] pixels, runs the particle tracker on the shrunk frames, and
//! maps every estimate back to the frame's pixels. A target no larger than the working radius is
//! tracked at full resolution, unchanged.
//!
//! The shrinking averages the frame over boxes of f×f pixels (fractional at the borders of a box),
//! which is what a camera with larger pixels would have recorded: the noise falls by f and fine
//! texture averages out, while an outline of the target's size is kept.

use nalgebra::{Matrix6, Vector6};
use smc_core::smooth::SmootherSettings;
use vision_core::{BoundingBox, Ellipse, GreyImage};

use crate::Result;
use crate::api::{Estimate, Tracker, WeightedEllipse};
use crate::config::TrackerConfig;
use crate::engine::ParticleTracker;
use crate::frame::Frame;
use crate::smoothing::SmoothedRun;
use crate::space::ShapeSpace;

/// The map between a frame's pixel coordinates and the working frame's: a frame pixel's
/// coordinate x is `(x_w + 0.5)·factor − 0.5` of the working frame's x_w (pixel centres at
/// integer coordinates in both, working pixel i averaging frame pixels [i·f, (i+1)·f) in corner
/// coordinates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorkingScale {
    factor: f64,
}

impl WorkingScale {
    /// No shrinking.
    pub const IDENTITY: WorkingScale = WorkingScale { factor: 1.0 };

    /// The scale that maps `target`'s mean radius √(ab) to `working_radius` pixels, or the
    /// identity for a target no larger than that.
    pub fn for_target(target: &Ellipse, working_radius: f64) -> Self {
        let radius = (target.a * target.b).sqrt();
        let factor = radius / working_radius;
        if factor.is_finite() && factor > 1.0 {
            Self { factor }
        } else {
            Self::IDENTITY
        }
    }

    /// [`WorkingScale::for_target`] with `working_radius`, or the identity without one.
    pub fn for_radius(target: &Ellipse, working_radius: Option<f64>) -> Self {
        working_radius.map_or(Self::IDENTITY, |r| Self::for_target(target, r))
    }

    /// Frame pixels per working pixel (≥ 1).
    pub fn factor(&self) -> f64 {
        self.factor
    }

    /// Whether frames are used as they are.
    pub fn is_identity(&self) -> bool {
        self.factor == 1.0
    }

    fn point_to_frame(&self, x: f64) -> f64 {
        (x + 0.5) * self.factor - 0.5
    }

    fn point_to_working(&self, x: f64) -> f64 {
        (x + 0.5) / self.factor - 0.5
    }

    /// `e` (frame pixels) in working pixels.
    pub fn to_working(&self, e: &Ellipse) -> Ellipse {
        Ellipse {
            cx: self.point_to_working(e.cx),
            cy: self.point_to_working(e.cy),
            a: e.a / self.factor,
            b: e.b / self.factor,
            angle: e.angle,
        }
    }

    /// `e` (working pixels) in frame pixels.
    pub fn to_frame(&self, e: &Ellipse) -> Ellipse {
        Ellipse {
            cx: self.point_to_frame(e.cx),
            cy: self.point_to_frame(e.cy),
            a: e.a * self.factor,
            b: e.b * self.factor,
            angle: e.angle,
        }
    }

    /// An estimate made on the working frame, in frame pixels. The clutter density λ̂ stays in
    /// edges per working pixel: it is measured on the working frame.
    pub fn estimate_to_frame(&self, space: ShapeSpace, mut e: Estimate) -> Estimate {
        e.ellipse = self.to_frame(&e.ellipse);
        let b = e.bbox;
        e.bbox = BoundingBox::new(
            self.point_to_frame(b.x),
            self.point_to_frame(b.y),
            b.w * self.factor,
            b.h * self.factor,
        );
        e.state = space.map_pose(&e.state, self.factor, self.factor * 0.5 - 0.5);
        e
    }

    /// Odobez's affine displacement parameters `[a1..a6]` (Eq. 13) and their covariance, estimated
    /// on the working frame about a point, in frame pixels about the same point: the
    /// displacement is `factor` times longer while the coordinates relative to the point are too,
    /// so the translations a1, a4 scale by `factor` and the linear part is unchanged.
    pub fn affine_to_frame(
        &self,
        affine: [f64; 6],
        covariance: &Matrix6<f64>,
    ) -> ([f64; 6], Matrix6<f64>) {
        let f = self.factor;
        let d = Vector6::new(f, 1.0, 1.0, f, 1.0, 1.0);
        let mut a = affine;
        for (v, s) in a.iter_mut().zip(d.iter()) {
            *v *= s;
        }
        let cov = Matrix6::from_fn(|i, j| covariance[(i, j)] * d[i] * d[j]);
        (a, cov)
    }

    /// The size of the working frame of a `width`×`height` frame (at least 1×1).
    pub fn working_size(&self, width: usize, height: usize) -> (usize, usize) {
        let shrink = |n: usize| ((n as f64 / self.factor).floor() as usize).max(1);
        (shrink(width), shrink(height))
    }
}

/// Box-average resampling of one axis at a fixed width: output i averages the inputs
/// `first[i]..first[i] + width` with `weights[i * width..(i + 1) * width]`. The inputs its box
/// covers are weighted by their share of the box, in order; the others, before or after them,
/// are weighted zero (a box narrower than the widest, or one moved back from the last input).
#[derive(Debug, Clone, Default)]
struct AxisBoxes {
    width: usize,
    first: Vec<usize>,
    weights: Vec<f32>,
}

impl AxisBoxes {
    /// Output pixel i averages input [i f, (i + 1) f) (corner coordinates), clipped to `n`.
    fn new(n: usize, out: usize, factor: f64) -> Self {
        let boxes: Vec<Vec<(usize, f32)>> = (0..out)
            .map(|i| {
                let (lo, hi) = (i as f64 * factor, ((i + 1) as f64 * factor).min(n as f64));
                let width = hi - lo;
                (lo.floor() as usize..(hi.ceil() as usize).min(n))
                    .filter_map(|j| {
                        let cover = (hi.min((j + 1) as f64) - lo.max(j as f64)).max(0.0);
                        (cover > 0.0).then_some((j, (cover / width) as f32))
                    })
                    .collect()
            })
            .collect();
        let width = boxes.iter().map(Vec::len).max().unwrap_or(0).min(n);
        let mut first = Vec::with_capacity(out);
        let mut weights = vec![0.0; out * width];
        for (i, own) in boxes.iter().enumerate() {
            let start = own.first().map_or(0, |t| t.0).min(n - width);
            first.push(start);
            for &(j, t) in own {
                weights[i * width + j - start] = t;
            }
        }
        Self {
            width,
            first,
            weights,
        }
    }

    /// The inputs output `i` averages and their weights, in order (its box's own taps).
    fn taps(&self, i: usize) -> impl DoubleEndedIterator<Item = (usize, f32)> + '_ {
        let weights = &self.weights[i * self.width..(i + 1) * self.width];
        (self.first[i]..self.first[i] + self.width)
            .zip(weights.iter().copied())
            .filter(|&(_, t)| t != 0.0)
    }
}

/// Shrinks frames of one size by a [`WorkingScale`], reusing its buffers.
#[derive(Debug, Clone, Default)]
pub(crate) struct Shrinker {
    size: (usize, usize),
    out: (usize, usize),
    columns: AxisBoxes,
    rows: AxisBoxes,
    /// The frame averaged along x: `out.0` × `size.1`.
    half: Vec<f32>,
    pixels: Vec<f32>,
    /// The colour frame averaged along x (`out.0` × `size.1`, interleaved RGB), one output row
    /// of it averaged along y, and the shrunk colour frame (interleaved RGB).
    half_rgb: Vec<f32>,
    row_rgb: Vec<f32>,
    rgb: Vec<u8>,
}

impl Shrinker {
    /// A shrinker of `width`×`height` frames by `scale`; an empty one (no buffers) for the
    /// identity, which never shrinks.
    pub(crate) fn for_frames(scale: WorkingScale, width: usize, height: usize) -> Self {
        if scale.is_identity() {
            Self::default()
        } else {
            Self::new(scale, width, height)
        }
    }

    fn new(scale: WorkingScale, width: usize, height: usize) -> Self {
        let out = scale.working_size(width, height);
        Self {
            size: (width, height),
            out,
            columns: AxisBoxes::new(width, out.0, scale.factor()),
            rows: AxisBoxes::new(height, out.1, scale.factor()),
            half: vec![0.0; out.0 * height],
            pixels: vec![0.0; out.0 * out.1],
            half_rgb: Vec::new(),
            row_rgb: Vec::new(),
            rgb: Vec::new(),
        }
    }

    /// Shrinks a grey frame into `pixels`.
    fn shrink(&mut self, data: &[f32]) {
        let mut pixels = std::mem::take(&mut self.pixels);
        self.shrink_into(data, &mut pixels);
        self.pixels = pixels;
    }

    /// Shrinks a grey frame of this shrinker's size (checked by the caller) and returns the
    /// working frame.
    pub(crate) fn shrink_grey(&mut self, frame: &Frame<'_>) -> Result<GreyImage<'_>> {
        debug_assert_eq!((frame.width(), frame.height()), self.size);
        self.shrink(frame.data());
        Ok(GreyImage::new(self.out.0, self.out.1, &self.pixels)?)
    }

    /// Shrinks the colour of a frame (`order`: where R, G and B sit in each pixel) into
    /// interleaved RGB (`rgb`), each channel averaged as the grey levels are
    /// ([`Shrinker::shrink_into`]) and rounded to the nearest level; only the working pixels of
    /// `region` (`[x0, y0, x1, y1]`, x1 and y1 excluded, clipped to the working frame; `None`:
    /// all), the others black. The three channels go through each pass together, reading the
    /// frame once; every channel's sums are taken in the same order as one channel's alone, so
    /// the levels are the same to the bit, whatever the region.
    fn shrink_colour(&mut self, rgb: &[u8], order: [usize; 3], region: Option<[usize; 4]>) {
        let (w, _) = self.size;
        let (ow, oh) = self.out;
        let [x0, y0, x1, y1] = region.unwrap_or([0, 0, ow, oh]);
        let (xs, ys) = (x0.min(ow)..x1.min(ow), y0.min(oh)..y1.min(oh));
        self.rgb.clear();
        self.rgb.resize(3 * ow * oh, 0);
        if xs.is_empty() || ys.is_empty() {
            return;
        }
        // The frame's rows the region's output rows average.
        let first = self.rows.taps(ys.start).next().map_or(0, |t| t.0);
        let last = self.rows.taps(ys.end - 1).next_back().map_or(0, |t| t.0);
        self.half_rgb.resize(3 * ow * self.size.1, 0.0);
        for y in first..=last {
            let row = &rgb[3 * y * w..3 * (y + 1) * w];
            let half = &mut self.half_rgb[3 * y * ow..3 * (y + 1) * ow];
            for x in xs.clone() {
                // -0.0, the neutral element `Iterator::sum` starts from. Each box's own taps
                // only: three channels a tap, the zero-weighted inputs would cost more here than
                // the fixed width saves.
                let mut sums = [-0.0f32; 3];
                for (j, t) in self.columns.taps(x) {
                    let pixel = &row[3 * j..3 * j + 3];
                    for (sum, &offset) in sums.iter_mut().zip(&order) {
                        *sum += t * f32::from(pixel[offset]);
                    }
                }
                half[3 * x..3 * x + 3].copy_from_slice(&sums);
            }
        }
        let (x0, x1) = (3 * xs.start, 3 * xs.end);
        self.row_rgb.resize(3 * ow, 0.0);
        for y in ys {
            let acc = &mut self.row_rgb[x0..x1];
            acc.fill(0.0);
            for (j, t) in self.rows.taps(y) {
                let src = &self.half_rgb[3 * j * ow + x0..3 * j * ow + x1];
                for (o, s) in acc.iter_mut().zip(src) {
                    *o += t * s;
                }
            }
            let out = &mut self.rgb[3 * y * ow + x0..3 * y * ow + x1];
            for (o, &v) in out.iter_mut().zip(acc.iter()) {
                *o = round_level(v);
            }
        }
    }

    /// The box averages of `plane` (row-major, the frame's size).
    fn shrink_into(&mut self, plane: &[f32], out: &mut Vec<f32>) {
        let (w, h) = self.size;
        let ow = self.out.0;
        let columns = &self.columns;
        for (row, half) in plane
            .chunks_exact(w)
            .zip(self.half.chunks_exact_mut(ow))
            .take(h)
        {
            // The common widths with their loops unrolled; the sums are the same to the bit.
            match columns.width {
                2 => average_row::<2>(row, columns, half),
                3 => average_row::<3>(row, columns, half),
                4 => average_row::<4>(row, columns, half),
                5 => average_row::<5>(row, columns, half),
                6 => average_row::<6>(row, columns, half),
                _ => average_row_any(row, columns, half),
            }
        }
        out.resize(ow * self.out.1, 0.0);
        for (y, out_row) in out.chunks_exact_mut(ow).enumerate() {
            out_row.fill(0.0);
            for (j, t) in self.rows.taps(y) {
                let src = &self.half[j * ow..(j + 1) * ow];
                for (o, s) in out_row.iter_mut().zip(src) {
                    *o += t * s;
                }
            }
        }
    }
}

/// One row averaged along x by boxes `W` inputs wide ([`AxisBoxes::width`]). Each sum starts
/// from −0.0 and adds the weighted inputs in order, as `Iterator::sum` over the box's own taps
/// does; the zero-weighted inputs add ±0.0, which leaves every sum of frame levels unchanged.
fn average_row<const W: usize>(row: &[f32], boxes: &AxisBoxes, out: &mut [f32]) {
    for ((o, &start), weights) in out
        .iter_mut()
        .zip(&boxes.first)
        .zip(boxes.weights.chunks_exact(W))
    {
        let inputs = &row[start..start + W];
        let mut sum = -0.0f32;
        for k in 0..W {
            sum += weights[k] * inputs[k];
        }
        *o = sum;
    }
}

/// [`average_row`] for any width.
fn average_row_any(row: &[f32], boxes: &AxisBoxes, out: &mut [f32]) {
    let width = boxes.width;
    for ((o, &start), weights) in out
        .iter_mut()
        .zip(&boxes.first)
        .zip(boxes.weights.chunks_exact(width.max(1)))
    {
        let mut sum = -0.0f32;
        for (t, v) in weights.iter().zip(&row[start..start + width]) {
            sum += t * v;
        }
        *o = sum;
    }
}

/// `v.round().clamp(0.0, 255.0) as u8` for the non-negative averages of levels, without the
/// library call `f32::round` is on targets without SSE4.1: v − ⌊v⌋ is exact for v < 2²³, so
/// comparing it with ½ rounds half away from zero as `round` does.
fn round_level(v: f32) -> u8 {
    let whole = v.clamp(0.0, 255.0) as u32;
    let up = u32::from(v - whole as f32 >= 0.5);
    (whole + up).min(255) as u8
}

/// A particle tracker run on frames shrunk so that the target has a set size (see the module
/// docs); reports in the frame's pixels.
#[derive(Debug)]
pub struct ScaledTracker {
    inner: ParticleTracker,
    scale: WorkingScale,
    shrinker: Shrinker,
}

impl ScaledTracker {
    /// A tracker for `config`, shrinking frames to its [`TrackerConfig::working_radius`].
    ///
    /// # Errors
    /// An invalid configuration.
    pub fn new(config: TrackerConfig) -> Result<Self> {
        Ok(Self::from_tracker(ParticleTracker::new(config)?))
    }

    /// `inner` run at the working scale of its configuration.
    pub fn from_tracker(inner: ParticleTracker) -> Self {
        Self {
            inner,
            scale: WorkingScale::IDENTITY,
            shrinker: Shrinker::default(),
        }
    }

    /// The scale chosen at initialisation (the identity before it).
    pub fn scale(&self) -> WorkingScale {
        self.scale
    }

    /// Runs `step` on the working frame of `frame` and maps its estimate back.
    fn on_working_frame(
        &mut self,
        frame: Frame<'_>,
        initialising: bool,
        step: impl FnOnce(&mut ParticleTracker, Frame<'_>) -> Result<Estimate>,
    ) -> Result<Estimate> {
        if self.scale.is_identity() {
            return step(&mut self.inner, frame);
        }
        // The update's wall time includes the shrinking, part of the tracker's work.
        let start = std::time::Instant::now();
        // Only updates can meet a frame of another size (init sets the size).
        frame.check_size(self.shrinker.size, self.inner.frames_done() + 1)?;
        let (ow, oh) = self.shrinker.out;
        // Colour is shrunk only for a tracker that reads it (the appearance terms).
        let colour = frame
            .colour()
            .filter(|_| self.inner.config().appearance.is_some());
        if let Some((rgb, order)) = colour {
            // After the first frame the colour terms read their window only: the rest of the
            // working frame's colour is left black.
            let footprint = match initialising {
                true => None,
                false => self.inner.next_colour_footprint(),
            };
            self.shrinker.shrink_colour(rgb, order, footprint);
        }
        self.shrinker.shrink(frame.data());
        let pixels = &self.shrinker.pixels;
        let working = match colour {
            Some(_) => Frame::with_rgb(ow, oh, pixels, &self.shrinker.rgb)?,
            None => Frame::new(ow, oh, pixels)?,
        };
        self.inner.offer_source_frame(&frame, self.scale);
        let mut estimate = step(&mut self.inner, working)?;
        estimate.millis = start.elapsed().as_secs_f64() * 1e3;
        Ok(self
            .scale
            .estimate_to_frame(self.inner.config().space, estimate))
    }
}

impl Tracker for ScaledTracker {
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn config(&self) -> &TrackerConfig {
        self.inner.config()
    }

    fn init(&mut self, frame: Frame<'_>, ellipse: Ellipse) -> Result<Estimate> {
        let ellipse = self.inner.config().initial_ellipse(&ellipse)?;
        self.scale = WorkingScale::for_radius(&ellipse, self.inner.config().working_radius);
        self.shrinker = Shrinker::for_frames(self.scale, frame.width(), frame.height());
        let working = self.scale.to_working(&ellipse);
        self.on_working_frame(frame, true, |inner, f| inner.init(f, working))
    }

    fn update(&mut self, frame: Frame<'_>) -> Result<Estimate> {
        self.on_working_frame(frame, false, |inner, f| inner.update(f))
    }

    fn smoothed(&mut self, settings: &SmootherSettings) -> Result<SmoothedRun> {
        let space = self.inner.config().space;
        let mut run = self.inner.smoothed(settings)?;
        for e in &mut run.estimates {
            *e = self.scale.estimate_to_frame(space, e.clone());
        }
        Ok(run)
    }

    fn particles(&self, max: usize) -> Vec<WeightedEllipse> {
        self.inner
            .particles(max)
            .into_iter()
            .map(|p| WeightedEllipse {
                ellipse: self.scale.to_frame(&p.ellipse),
                weight: p.weight,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Preset;

    /// Interleaved RGB of a `w`×`h` frame of hashed levels (`shift` picks the hash's bits).
    fn texture_rgb(w: usize, h: usize, shift: u32) -> Vec<u8> {
        (0..3 * w * h)
            .map(|i| ((i * 2_654_435_761usize) >> shift) as u8)
            .collect()
    }

    #[test]
    fn rows_average_to_the_bit_as_the_boxes_own_taps() {
        // The fixed-width pass along rows gives, to the bit, each box's own taps summed in order
        // (`Iterator::sum`), at whole and fractional factors, boxes clipped at the frame's edge
        // included.
        let (w, h) = (97, 5);
        let plane: Vec<f32> = texture_rgb(w, h, 5)
            .iter()
            .take(w * h)
            .map(|&v| f32::from(v) * 0.73)
            .collect();
        for radius in [17.0, 24.0, 33.7, 50.0, 61.3, 99.0, 140.0] {
            let target = Ellipse::new(48.0, 2.0, radius, radius, 0.0);
            let scale = WorkingScale::for_target(&target, 16.0);
            let mut shrinker = Shrinker::new(scale, w, h);
            let mut out = Vec::new();
            shrinker.shrink_into(&plane, &mut out);
            let ow = shrinker.out.0;
            for y in 0..h {
                for x in 0..ow {
                    let reference: f32 = shrinker
                        .columns
                        .taps(x)
                        .map(|(j, t)| t * plane[y * w + j])
                        .sum();
                    assert_eq!(
                        shrinker.half[y * ow + x].to_bits(),
                        reference.to_bits(),
                        "radius {radius}, ({x}, {y})"
                    );
                }
            }
        }
    }

    #[test]
    fn colour_shrinks_to_the_levels_of_each_channel_shrunk_alone() {
        // The three channels averaged together give, to the bit, what each gives through
        // `shrink_into` alone, rounded: on a textured frame, at whole and fractional factors.
        let (w, h) = (97, 61);
        let rgb = texture_rgb(w, h, 7);
        for radius in [24.0, 33.7, 50.0, 61.3] {
            let target = Ellipse::new(48.0, 30.0, radius, radius, 0.0);
            let scale = WorkingScale::for_target(&target, 16.0);
            let mut shrinker = Shrinker::new(scale, w, h);
            let order = [2, 0, 1];
            shrinker.shrink_colour(&rgb, order, None);
            let fused = shrinker.rgb.clone();
            let mut plane = Vec::new();
            for (c, &offset) in order.iter().enumerate() {
                let channel: Vec<f32> =
                    (0..w * h).map(|k| f32::from(rgb[3 * k + offset])).collect();
                shrinker.shrink_into(&channel, &mut plane);
                for (i, v) in plane.iter().enumerate() {
                    let level = v.round().clamp(0.0, 255.0) as u8;
                    assert_eq!(fused[3 * i + c], level, "factor {}", scale.factor());
                }
            }
        }
    }

    #[test]
    fn a_region_of_the_colour_is_shrunk_as_the_whole_frame_is() {
        // Inside the region, the same levels to the bit as the whole frame's; black outside;
        // a region that reaches past the frame is clipped.
        let (w, h) = (131, 89);
        let rgb = texture_rgb(w, h, 9);
        let scale = WorkingScale::for_target(&Ellipse::new(60.0, 40.0, 29.0, 29.0, 0.0), 16.0);
        let mut shrinker = Shrinker::new(scale, w, h);
        let (ow, oh) = shrinker.out;
        shrinker.shrink_colour(&rgb, [0, 1, 2], None);
        let whole = shrinker.rgb.clone();
        for region in [
            [10, 7, 31, 23],
            [0, 0, 12, 10],
            [50, 30, 400, 300],
            [0, 0, ow, oh],
        ] {
            shrinker.shrink_colour(&rgb, [0, 1, 2], Some(region));
            for y in 0..oh {
                for x in 0..ow {
                    let k = 3 * (y * ow + x);
                    let got = &shrinker.rgb[k..k + 3];
                    let inside =
                        (region[0]..region[2]).contains(&x) && (region[1]..region[3]).contains(&y);
                    let expected = if inside {
                        &whole[k..k + 3]
                    } else {
                        &[0, 0, 0][..]
                    };
                    assert_eq!(got, expected, "{region:?} at {x},{y}");
                }
            }
        }
    }

    #[test]
    fn levels_round_half_away_from_zero() {
        let mut v = -0.0f32;
        while v < 256.5 {
            assert_eq!(round_level(v), v.round().clamp(0.0, 255.0) as u8, "{v}");
            for near in [v.next_down().max(0.0), v.next_up()] {
                assert_eq!(
                    round_level(near),
                    near.round().clamp(0.0, 255.0) as u8,
                    "{near}"
                );
            }
            v += 0.25;
        }
    }

    #[test]
    fn a_ramp_shrinks_to_the_frame_coordinates_of_the_working_pixels() {
        // f(x, y) = x + 2y: a box average of a plane is the plane at the box's centre, which is
        // the working pixel's position in frame coordinates.
        let (w, h) = (101, 77);
        let data: Vec<f32> = (0..w * h).map(|i| ((i % w) + 2 * (i / w)) as f32).collect();
        let scale = WorkingScale::for_target(
            &Ellipse {
                cx: 50.0,
                cy: 40.0,
                a: 40.0,
                b: 40.0,
                angle: 0.0,
            },
            10.0,
        );
        assert!((scale.factor() - 4.0).abs() < 1e-12);
        let mut shrinker = Shrinker::new(scale, w, h);
        let (ow, oh) = shrinker.out;
        assert_eq!((ow, oh), (25, 19));
        shrinker.shrink(&data);
        let small = shrinker.pixels.clone();
        for y in 0..oh {
            for x in 0..ow {
                let expected =
                    scale.point_to_frame(x as f64) + 2.0 * scale.point_to_frame(y as f64);
                assert!(
                    (small[y * ow + x] as f64 - expected).abs() < 1e-3,
                    "{x},{y}"
                );
            }
        }
        // Colour is averaged channel by channel, whatever the order of the components: a
        // frame stored BGR with B = x, G = y, R = 200 − x comes out RGB.
        let bgr: Vec<u8> = (0..w * h)
            .flat_map(|k| {
                let (x, y) = ((k % w) as u8, (k / w) as u8);
                [x, y, 200 - x]
            })
            .collect();
        shrinker.shrink_colour(&bgr, [2, 1, 0], None);
        for y in 0..oh {
            for x in 0..ow {
                let (fx, fy) = (
                    scale.point_to_frame(x as f64),
                    scale.point_to_frame(y as f64),
                );
                let px = &shrinker.rgb[3 * (y * ow + x)..3 * (y * ow + x) + 3];
                let expected = [200.0 - fx, fy, fx];
                for (c, e) in expected.iter().enumerate() {
                    assert!((f64::from(px[c]) - e).abs() <= 0.51, "{x},{y} channel {c}");
                }
            }
        }
        let e = Ellipse {
            cx: 31.3,
            cy: 12.9,
            a: 20.0,
            b: 8.0,
            angle: 0.4,
        };
        let back = scale.to_frame(&scale.to_working(&e));
        assert!((back.cx - e.cx).abs() < 1e-12 && (back.b - e.b).abs() < 1e-12);
    }

    #[test]
    fn a_large_target_is_tracked_on_the_shrunk_frames_and_reported_in_frame_pixels() {
        // A bright disc of radius 75 px moving 6 px right per frame on a 400×300 frame.
        let (w, h) = (400, 300);
        let frame_at = |k: usize| -> Vec<f32> {
            (0..w * h)
                .map(|i| {
                    let (x, y) = ((i % w) as f64, (i / w) as f64);
                    let d = ((x - 150.0 - 6.0 * k as f64).powi(2) + (y - 150.0).powi(2)).sqrt();
                    if d < 75.0 { 200.0 } else { 40.0 }
                })
                .collect()
        };
        for seed in 1..=3 {
            let config = crate::TrackerConfig {
                working_radius: Some(25.0),
                ..Preset::M1.config(100, seed)
            };
            let mut tracker = ScaledTracker::new(config).unwrap();
            let start = Ellipse {
                cx: 150.0,
                cy: 150.0,
                a: 75.0,
                b: 75.0,
                angle: 0.0,
            };
            let first = tracker
                .init(Frame::new(w, h, &frame_at(0)).unwrap(), start)
                .unwrap();
            assert!((tracker.scale().factor() - 3.0).abs() < 1e-12);
            assert!(
                (first.ellipse.cx - 150.0).abs() < 1e-9 && (first.ellipse.a - 75.0).abs() < 1e-9
            );
            let mut last = first;
            for k in 1..=8 {
                last = tracker
                    .update(Frame::new(w, h, &frame_at(k)).unwrap())
                    .unwrap();
            }
            let e = last.ellipse;
            assert!(
                (e.cx - 198.0).abs() < 6.0 && (e.cy - 150.0).abs() < 6.0,
                "{seed}: {e:?}"
            );
            assert!((e.a / 75.0 - 1.0).abs() < 0.15, "{seed}: {e:?}");
            let (x, bw) = (last.bbox.x, last.bbox.w);
            assert!((x + 0.5 * bw - e.cx).abs() < 1e-6);
            let p = tracker.particles(1);
            assert!((p[0].ellipse.cx - 198.0).abs() < 10.0);
            // A frame of another size is refused.
            assert!(
                tracker
                    .update(Frame::new(w - 1, h, &vec![0.0; (w - 1) * h]).unwrap())
                    .is_err()
            );
        }
    }
}
