//! The working window: the part of a frame around the target, read at the working scale (the
//! scale that maps the target to a fixed size in working pixels), with each working pixel's
//! colour bin, grey level and target-against-background log-ratio, and the integral image of the
//! log-ratios. Its cost depends on the window's size in working pixels only, never on the target's
//! or the frame's size in pixels.

use vision_core::Ellipse;

use super::colour::ColourBins;
use crate::Result;
use crate::frame::Frame;

// The two counts below set how finely an integral the model defines is computed, not the model:
// the colour contrast is the sum of the log-ratios over the ellipse and the contour contrast the
// mean grey contrast around it; more strips or points only come closer to those. Both are counted
// on the target, which the working scale shrinks to a mean radius of 16 working pixels for `head`
// (a smaller target is not enlarged), so their spacing does not grow with the footage's
// resolution: about 3 working pixels between strips and between contour points of a round target
// of that radius. They stay constants, not settings.

/// Strips of the staircase that approximates an ellipse in [`WorkingWindow::ellipse_sums`].
const STRIPS: usize = 10;
/// Points on the contour read by [`WorkingWindow::edge_strength`].
const CONTOUR_POINTS: usize = 32;

/// Where [`WorkingWindow::read`] samples a `width`×`height` frame for a rectangle and a step: the
/// rectangle clipped to the frame, its size in window pixels and the samples' offsets in each.
struct Layout {
    origin: [f64; 2],
    step: f64,
    width: usize,
    height: usize,
    frame: (usize, usize),
}

impl Layout {
    fn new(width: usize, height: usize, rect: [f64; 4], step: f64) -> Self {
        let (fw, fh) = (width as f64, height as f64);
        let x0 = rect[0].clamp(0.0, fw - 1.0).floor();
        let y0 = rect[1].clamp(0.0, fh - 1.0).floor();
        let x1 = rect[2].clamp(x0 + 1.0, fw);
        let y1 = rect[3].clamp(y0 + 1.0, fh);
        let step = step.max(1.0);
        Self {
            origin: [x0, y0],
            step,
            width: (((x1 - x0) / step).ceil() as usize).max(1),
            height: (((y1 - y0) / step).ceil() as usize).max(1),
            frame: (width, height),
        }
    }

    /// Where in a window pixel its samples lie, in steps from its centre: a 2 × 2 grid when a
    /// window pixel spans two frame pixels or more, the centre otherwise.
    fn offsets(&self) -> &'static [f64] {
        if self.step >= 2.0 {
            &[-0.25, 0.25]
        } else {
            &[0.0]
        }
    }

    /// The frame pixels the samples read, `[x0, y0, x1, y1]` (x1 and y1 excluded).
    fn footprint(&self) -> [usize; 4] {
        let offsets = self.offsets();
        let (first, last) = (offsets[0], offsets[offsets.len() - 1]);
        let span = |origin: f64, n: usize, len: usize| {
            let at = |i: usize, d: f64| {
                ((origin + (i as f64 + 0.5) * self.step + d * self.step) as usize).min(len - 1)
            };
            (at(0, first), at(n - 1, last) + 1)
        };
        let (x0, x1) = span(self.origin[0], self.width, self.frame.0);
        let (y0, y1) = span(self.origin[1], self.height, self.frame.1);
        [x0, y0, x1, y1]
    }
}

/// The pixels of a `width`×`height` frame that [`WorkingWindow::read`] of `rect` at `step`
/// reads, `[x0, y0, x1, y1]` (x1 and y1 excluded).
pub fn footprint(width: usize, height: usize, rect: [f64; 4], step: f64) -> [usize; 4] {
    Layout::new(width, height, rect, step).footprint()
}

/// A window of a frame at the working scale. Reused from frame to frame (no allocation once
/// the buffers have grown).
#[derive(Debug, Clone, Default)]
pub struct WorkingWindow {
    /// Full-resolution position of the window's top-left corner.
    origin: [f64; 2],
    /// Full-resolution pixels per working pixel (≥ 1).
    step: f64,
    width: usize,
    height: usize,
    bins: Vec<u16>,
    grey: Vec<f32>,
    /// Integral image of the log-ratios, `(width + 1) × (height + 1)`.
    integral: Vec<f64>,
    /// Integral image of the positive parts of the log-ratios (target-like evidence only).
    integral_positive: Vec<f64>,
    /// Mean gradient magnitude of the grey window (the edge term's unit).
    mean_gradient: f64,
}

impl WorkingWindow {
    /// Reads the full-resolution rectangle `[x0, x1) × [y0, y1)` of `frame` (clipped to the
    /// frame) at `step` full-resolution pixels per working pixel. Each working pixel averages
    /// a 2 × 2 grid of samples in its footprint when `step` ≥ 2, one sample otherwise.
    pub fn read(&mut self, frame: &Frame<'_>, bins: &ColourBins, rect: [f64; 4], step: f64) {
        let layout = Layout::new(frame.width(), frame.height(), rect, step);
        let [x0, y0] = layout.origin;
        let step = layout.step;
        self.origin = layout.origin;
        self.step = step;
        self.width = layout.width;
        self.height = layout.height;
        let n = self.width * self.height;
        self.bins.clear();
        self.grey.clear();
        self.bins.reserve(n);
        self.grey.reserve(n);
        let offsets = layout.offsets();
        let inv = 1.0 / (offsets.len() * offsets.len()) as f32;
        let (w, h) = (frame.width(), frame.height());
        let grey = frame.data();
        let rgb = frame.colour().filter(|_| bins.is_colour());
        for j in 0..self.height {
            for i in 0..self.width {
                let cx = x0 + (i as f64 + 0.5) * step;
                let cy = y0 + (j as f64 + 0.5) * step;
                let (mut r, mut g, mut b, mut l) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
                for dy in offsets {
                    let y = ((cy + dy * step) as usize).min(h - 1);
                    for dx in offsets {
                        let x = ((cx + dx * step) as usize).min(w - 1);
                        let k = y * w + x;
                        l += grey[k];
                        if let Some((pixels, [ro, go, bo])) = rgb {
                            r += f32::from(pixels[3 * k + ro]);
                            g += f32::from(pixels[3 * k + go]);
                            b += f32::from(pixels[3 * k + bo]);
                        }
                    }
                }
                l *= inv;
                self.grey.push(l);
                self.bins.push(if rgb.is_some() {
                    bins.of_rgb(r * inv, g * inv, b * inv)
                } else {
                    bins.of_grey(l)
                });
            }
        }
        self.mean_gradient = self.gradient_mean();
    }

    fn gradient_mean(&self) -> f64 {
        let (w, h) = (self.width, self.height);
        if w < 3 || h < 3 {
            return 0.0;
        }
        let mut sum = 0.0f64;
        for j in 1..h - 1 {
            let row = &self.grey[j * w..(j + 1) * w];
            let up = &self.grey[(j - 1) * w..j * w];
            let down = &self.grey[(j + 1) * w..(j + 2) * w];
            for i in 1..w - 1 {
                let gx = row[i + 1] - row[i - 1];
                let gy = down[i] - up[i];
                sum += f64::from((gx * gx + gy * gy).sqrt() * 0.5);
            }
        }
        sum / ((w - 2) * (h - 2)) as f64
    }

    /// Fills the integral image of the per-bin log-ratios `ratios`.
    pub fn integrate(&mut self, ratios: &[f32]) {
        let (w, h) = (self.width, self.height);
        self.integral.clear();
        self.integral.resize((w + 1) * (h + 1), 0.0);
        self.integral_positive.clear();
        self.integral_positive.resize((w + 1) * (h + 1), 0.0);
        for j in 0..h {
            let mut row = 0.0f64;
            let mut row_positive = 0.0f64;
            for i in 0..w {
                let r = f64::from(
                    ratios
                        .get(self.bins[j * w + i] as usize)
                        .copied()
                        .unwrap_or(0.0),
                );
                row += r;
                row_positive += r.max(0.0);
                let (at, above) = ((j + 1) * (w + 1) + i + 1, j * (w + 1) + i + 1);
                self.integral[at] = self.integral[above] + row;
                self.integral_positive[at] = self.integral_positive[above] + row_positive;
            }
        }
    }

    /// The window in full-resolution pixels, `[x0, y0, x1, y1]`.
    pub fn bounds(&self) -> [f64; 4] {
        [
            self.origin[0],
            self.origin[1],
            self.origin[0] + self.width as f64 * self.step,
            self.origin[1] + self.height as f64 * self.step,
        ]
    }

    /// A full-resolution ellipse in working coordinates, as the axis-aligned ellipse of the same
    /// half-extents along x and y ([`Ellipse::half_extents`]). That is the ellipse itself for
    /// every pose of an axis-aligned tracker, whose ellipses come back from the pose with a ≥ b
    /// and θ = π/2 when the target is taller than wide: read as (a, b) the window would see
    /// such a target lying on its side.
    fn to_working(&self, e: &Ellipse) -> (f64, f64, f64, f64) {
        let (hw, hh) = e.half_extents();
        (
            (e.cx - self.origin[0]) / self.step,
            (e.cy - self.origin[1]) / self.step,
            hw / self.step,
            hh / self.step,
        )
    }

    /// The integral image at a fractional corner, bilinearly interpolated, the corner clamped
    /// to the window (outside the window the log-ratio is taken as 0: no evidence).
    fn integral_at(integral: &[f64], (w, h): (usize, usize), x: f64, y: f64) -> f64 {
        let x = x.clamp(0.0, w as f64);
        let y = y.clamp(0.0, h as f64);
        let (i, j) = ((x as usize).min(w - 1), (y as usize).min(h - 1));
        let (fx, fy) = (x - i as f64, y - j as f64);
        let stride = w + 1;
        let at = |i: usize, j: usize| integral[j * stride + i];
        let top = at(i, j) * (1.0 - fx) + at(i + 1, j) * fx;
        let bottom = at(i, j + 1) * (1.0 - fx) + at(i + 1, j + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    fn box_sum(&self, integral: &[f64], x0: f64, y0: f64, x1: f64, y1: f64) -> f64 {
        let size = (self.width, self.height);
        let at = |x, y| Self::integral_at(integral, size, x, y);
        at(x1, y1) - at(x0, y1) - at(x1, y0) + at(x0, y0)
    }

    /// The sums of each of `integrals`' values (the log-ratios, their positive parts) over the
    /// ellipse, in working pixels, approximated by one staircase of horizontal strips (exact for
    /// the strips, each as wide as the ellipse at its middle row), and the area of the ellipse
    /// that was read, in working pixels: its area times the share of the staircase inside the
    /// window (all of it for an ellipse inside the window).
    fn ellipse_sums<const K: usize>(&self, integrals: [&[f64]; K], e: &Ellipse) -> ([f64; K], f64) {
        let (cx, cy, a, b) = self.to_working(e);
        let (w, h) = (self.width as f64, self.height as f64);
        let dy = 2.0 * b / STRIPS as f64;
        let mut sums = [0.0; K];
        let (mut staircase, mut read) = (0.0, 0.0);
        for k in 0..STRIPS {
            let y0 = cy - b + k as f64 * dy;
            let mid = (y0 + 0.5 * dy - cy) / b;
            let half = a * (1.0 - mid * mid).max(0.0).sqrt();
            for (sum, integral) in sums.iter_mut().zip(integrals) {
                *sum += self.box_sum(integral, cx - half, y0, cx + half, y0 + dy);
            }
            // The strip's part inside the window; exactly the strip when none is cut off.
            let width = if cx - half >= 0.0 && cx + half <= w {
                2.0 * half
            } else {
                ((cx + half).min(w) - (cx - half).max(0.0)).max(0.0)
            };
            let height = if y0 >= 0.0 && y0 + dy <= h {
                dy
            } else {
                ((y0 + dy).min(h) - y0.max(0.0)).max(0.0)
            };
            staircase += 2.0 * half * dy;
            read += width * height;
        }
        let share = if staircase > 0.0 {
            read / staircase
        } else {
            0.0
        };
        (sums, std::f64::consts::PI * a * b * share)
    }

    /// The colour contrast of the ellipse `e`, in nats per pixel of the reference area:
    ///
    /// - the sum of the log-ratios inside `e`, divided by `reference` (the current estimate's
    ///   area, [`WorkingWindow::area`]): the log-likelihood ratio of "these pixels are the target's,
    ///   the rest the background's", as the pixel-wise posteriors of Bibby & Reid (2008). A sum, not
    ///   a mean: a hypothesis grows while the pixels it takes in look more like the target than
    ///   the background, and no further;
    /// - less the mean of the positive log-ratios in the ring between `e` and the ellipse `ring`
    ///   times larger: target-like pixels just outside the contour say the hypothesis is too small
    ///   or off-centre. Only the positive part counts, so that pushing the ring from hair onto
    ///   an even more background-like wall earns nothing (the mean of the signed log-ratios
    ///   there made every estimate grow over hair and neck). The mean is over the part of the
    ///   ring that was read: pixels beyond the window (or the frame) give no evidence, and
    ///   counted as zeros they would dilute the mean, so that a hypothesis at the frame's edge,
    ///   with half its ring unread, would outscore the target.
    pub fn contrast(&self, e: &Ellipse, ring: f64, reference: f64) -> f64 {
        let ([inner, inner_positive], area) =
            self.ellipse_sums([&self.integral, &self.integral_positive], e);
        let outer = Ellipse {
            a: e.a * ring,
            b: e.b * ring,
            ..*e
        };
        let ([outer_positive], outer_area) = self.ellipse_sums([&self.integral_positive], &outer);
        let ring_area = outer_area - area;
        if reference < 1e-9 || ring_area < 1e-9 {
            return 0.0;
        }
        inner / reference - (outer_positive - inner_positive) / ring_area
    }

    /// The area of `e` in working pixels.
    pub fn area(&self, e: &Ellipse) -> f64 {
        let (_, _, a, b) = self.to_working(e);
        std::f64::consts::PI * a * b
    }

    /// Samples the grey window at `grid` (points of the unit disc) mapped onto the ellipse `e`
    /// (full-resolution), bilinearly; samples outside the window are NaN. Returns how many are
    /// valid.
    ///
    /// # Errors
    /// A non-finite ellipse or a buffer whose length differs from the grid's.
    pub fn patch(&self, e: &Ellipse, grid: &[[f64; 2]], out: &mut [f32]) -> Result<usize> {
        self.patch_from(self.grey()?, e, grid, out)
    }

    /// The grey window as an image, its pixels checked once, for [`Self::patch_from`].
    ///
    /// # Errors
    /// A non-finite grey level.
    pub fn grey(&self) -> Result<vision_core::GreyImage<'_>> {
        Ok(vision_core::GreyImage::new(
            self.width,
            self.height,
            &self.grey,
        )?)
    }

    /// [`Self::patch`] from the window's grey image `view` ([`Self::grey`]), which many patches
    /// share: the image's check runs once, not once a patch.
    ///
    /// # Errors
    /// As [`Self::patch`].
    pub fn patch_from(
        &self,
        view: vision_core::GreyImage<'_>,
        e: &Ellipse,
        grid: &[[f64; 2]],
        out: &mut [f32],
    ) -> Result<usize> {
        let (cx, cy, a, b) = self.to_working(e);
        let axes = nalgebra::Matrix2::new(a, 0.0, 0.0, b);
        // Working pixel (i, j) covers [i, i + 1): its sample sits at i + 0.5.
        Ok(motion_est::sample_patch_into(
            view,
            grid,
            &axes,
            [cx - 0.5, cy - 0.5],
            out,
        )?)
    }

    /// Contrast across the contour: the mean, over [`CONTOUR_POINTS`] points of the ellipse
    /// (axis-aligned), of half the absolute grey difference one working pixel inside and outside
    /// along the normal ([`Ellipse::contrast_across`], read bilinearly), in units of the window's
    /// mean gradient magnitude (Birchfield 1998's perimeter gradient, normalised).
    pub fn edge_strength(&self, e: &Ellipse) -> f64 {
        let (cx, cy, a, b) = self.to_working(e);
        if a <= 0.0 || b <= 0.0 {
            return 0.0;
        }
        let working = Ellipse::new(cx, cy, a, b, 0.0);
        let (mean, _) = working.contrast_across(CONTOUR_POINTS, 1.0, |x, y| {
            Some(f64::from(self.grey_at(x, y)))
        });
        0.5 * mean / (self.mean_gradient + 1.0)
    }

    fn grey_at(&self, x: f64, y: f64) -> f32 {
        let (w, h) = (self.width, self.height);
        let x = (x - 0.5).clamp(0.0, (w - 1) as f64);
        let y = (y - 0.5).clamp(0.0, (h - 1) as f64);
        let (i, j) = (x as usize, y as usize);
        let (i1, j1) = ((i + 1).min(w - 1), (j + 1).min(h - 1));
        let (fx, fy) = ((x - i as f64) as f32, (y - j as f64) as f32);
        let g = |i: usize, j: usize| self.grey[j * w + i];
        let top = g(i, j) * (1.0 - fx) + g(i1, j) * fx;
        let bottom = g(i, j1) * (1.0 - fx) + g(i1, j1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The colour bin counts of the ellipse `e` (working pixels whose centre lies inside it,
    /// weighted by the Epanechnikov profile 1 − r², as Pérez et al.) and of the ring between
    /// `e` scaled by `ring.0` and by `ring.1` (unweighted), in one pass over the ring's box.
    pub fn target_and_ring_counts(
        &self,
        bins: usize,
        e: &Ellipse,
        ring: (f64, f64),
    ) -> (Vec<f64>, Vec<f64>) {
        let (mut inside, mut around) = (vec![0.0; bins], vec![0.0; bins]);
        let (cx, cy, a, b) = self.to_working(e);
        let (a, b) = (a.max(1e-9), b.max(1e-9));
        let (inner2, outer2) = (ring.0 * ring.0, ring.1 * ring.1);
        let reach = ring.1.max(1.0);
        let span = |c: f64, r: f64, n: usize| {
            let lo = (c - r * reach).floor().max(0.0) as usize;
            let hi = ((c + r * reach).ceil().max(0.0) as usize).min(n);
            lo..hi
        };
        for j in span(cy, b, self.height) {
            let v = (j as f64 + 0.5 - cy) / b;
            for i in span(cx, a, self.width) {
                let u = (i as f64 + 0.5 - cx) / a;
                let r2 = u * u + v * v;
                let bin = self.bins[j * self.width + i] as usize;
                if r2 <= 1.0
                    && let Some(c) = inside.get_mut(bin)
                {
                    *c += 1.0 - r2;
                }
                if r2 > inner2
                    && r2 <= outer2
                    && let Some(c) = around.get_mut(bin)
                {
                    *c += 1.0;
                }
            }
        }
        (inside, around)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_read_sees_nothing_outside_its_footprint() {
        // Whatever the frame holds outside the footprint, a read gives the same grey levels and
        // bins: at one sample a window pixel and at four, inside the frame and cut by its edges.
        let (w, h) = (97, 71);
        let texture = |k: usize| ((k * 2_654_435_761) >> 11) as u8;
        let rgb: Vec<u8> = (0..3 * w * h).map(texture).collect();
        let bins = ColourBins::colour(8, 8, &crate::HistogramSettings::default());
        for (rect, step) in [
            ([20.3, 11.7, 61.2, 50.4], 1.0),
            ([20.3, 11.7, 61.2, 50.4], 2.6),
            ([-9.0, -4.0, 30.0, 25.0], 3.4),
            ([70.5, 40.2, 130.0, 90.0], 1.7),
        ] {
            let [x0, y0, x1, y1] = footprint(w, h, rect, step);
            assert!(x0 < x1 && x1 <= w && y0 < y1 && y1 <= h, "{rect:?}");
            let mut masked = rgb.clone();
            for (k, px) in masked.chunks_exact_mut(3).enumerate() {
                if !((x0..x1).contains(&(k % w)) && (y0..y1).contains(&(k / w))) {
                    px.copy_from_slice(&[255, 0, 255]);
                }
            }
            let read = |rgb: &[u8]| {
                let grey: Vec<f32> = rgb.chunks(3).map(|p| f32::from(p[1])).collect();
                let frame = Frame::with_rgb(w, h, &grey, rgb).unwrap();
                let mut window = WorkingWindow::default();
                window.read(&frame, &bins, rect, step);
                (window.grey, window.bins)
            };
            assert_eq!(read(&rgb), read(&masked), "{rect:?} at step {step}");
        }
    }

    #[test]
    fn a_tall_pose_is_read_standing_up() {
        // A dark ellipse 8 px wide and 14 px tall (half-axes) on a bright frame. Its pose in
        // Odobez's space comes back as an ellipse with a ≥ b and θ = π/2 (a = 14 along y); the
        // window must read it as the tall region it is, not as an ellipse lying on its side,
        // which would score the wrong shape as the best and pull every tall target round.
        let (w, h) = (64, 64);
        let (cx, cy, hw, hh) = (32.0, 32.0, 8.0, 14.0);
        let pixels: Vec<f32> = (0..w * h)
            .map(|k| {
                let (x, y) = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
                let r2 = ((x - cx) / hw).powi(2) + ((y - cy) / hh).powi(2);
                if r2 <= 1.0 { 40.0 } else { 200.0 }
            })
            .collect();
        let frame = Frame::new(w, h, &pixels).unwrap();
        let bins = ColourBins::grey(16);
        let mut window = WorkingWindow::default();
        window.read(&frame, &bins, [0.0, 0.0, w as f64, h as f64], 1.0);
        let dark = bins.of_grey(40.0) as usize;
        let ratios: Vec<f32> = (0..16)
            .map(|b| if b == dark { 1.0 } else { -1.0 })
            .collect();
        window.integrate(&ratios);

        let space = crate::space::ShapeSpace::Odobez;
        let standing = Ellipse::new(cx, cy, hw, hh, 0.0);
        let pose = space
            .pose(&space.from_ellipse(&standing))
            .to_ellipse()
            .unwrap();
        assert!(pose.a > pose.b && (pose.angle.abs() - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        let lying = Ellipse::new(cx, cy, hh, hw, 0.0);

        let contrast = |e: &Ellipse| window.contrast(e, 1.5, window.area(e));
        assert!((contrast(&pose) - contrast(&standing)).abs() < 1e-9);
        assert!(
            contrast(&pose) > contrast(&lying) + 0.5,
            "{} against {}",
            contrast(&pose),
            contrast(&lying)
        );
        let grid = motion_est::unit_disc_grid(8);
        let (mut a, mut b) = (vec![0.0; grid.len()], vec![0.0; grid.len()]);
        window.patch(&pose, &grid, &mut a).unwrap();
        window.patch(&standing, &grid, &mut b).unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn the_ring_mean_is_taken_over_the_part_of_the_ring_that_was_read() {
        // Every pixel of a 64×48 frame gives the same evidence, 0.5 nats. The ring's mean must
        // be 0.5 wherever the hypothesis sits: in the middle, and at the frame's left edge, where
        // a third of the ring lies beyond the frame. Counted as zeros, the unread part would pull
        // the mean down (to about 0.3 here) and favour hypotheses at the edge.
        let (w, h) = (64, 48);
        let pixels = vec![128.0f32; w * h];
        let frame = Frame::new(w, h, &pixels).unwrap();
        let bins = ColourBins::grey(16);
        let mut window = WorkingWindow::default();
        window.read(&frame, &bins, [0.0, 0.0, w as f64, h as f64], 1.0);
        window.integrate(&[0.5; 16]);
        let ring_mean = |cx: f64| {
            let e = Ellipse::new(cx, 24.0, 8.0, 8.0, 0.0);
            let reference = window.area(&e);
            let ([inner, _], _) = window.ellipse_sums([&window.integral, &window.integral], &e);
            inner / reference - window.contrast(&e, 1.5, reference)
        };
        for cx in [32.0, 4.0] {
            let mean = ring_mean(cx);
            assert!((mean - 0.5).abs() < 0.03, "at x = {cx}: {mean}");
        }
    }
}
