//! Measurement lines: length L, centred on each contour point along its outward normal, sampled
//! every pixel by bilinear interpolation, with their detected edges. [`MeasurementLines`] is the
//! reusable workspace of every likelihood: after the first use it allocates nothing.
//!
//! Sample positions c + k·n are stepped in fixed point (`image::sample_line`): within
//! ~1e−6 px of the exact positions, so edge offsets agree with per-sample f32 interpolation to
//! within 1e−4 px (asserted by `tests/fast_paths.rs`).
//!
//! Lines wholly inside the image go through the batched fast scan ([`crate::scan`]); the
//! others through the general path (the in-image interval, clamped sampling, the detector).
//! Both compute the same positions and arithmetic, so they give the same edges to the bit
//! (`fast_scan_equals_the_general_path_bit_for_bit`).
//!
//! The code is split by concern: this file holds the settings, the workspace and what it
//! records; `scan_plan.rs` decides which lines go through the fast scan and which through the
//! general path, and appends their edges; `queries.rs` answers the likelihoods' questions about
//! a line (Wu's edge counts, the nearest edge) without storing it.

mod queries;
mod scan_plan;

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};
use vision_core::GreyImage;

use crate::image::check_samplable;
use crate::scan::LineScan;
use crate::{Affine2, Contour, EdgeDetector, EdgeSettings, Error, Result};
use scan_plan::Planned;

/// Most measurement lines a contour may have (a contour is sampled, not rasterised: more lines
/// than this add cost without information).
pub const MAX_LINES: usize = 1_000;

/// Geometry of the measurement lines and the edge detector used on them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LineSettings {
    /// Number of lines n, one per contour point. Default 15 (Wu §6).
    pub n_lines: usize,
    /// Line length L in pixels, even: edges are searched at offsets −L/2 … L/2 from the contour
    /// point. Default 20 (Wu §6).
    pub length: usize,
    /// The 1-D edge detector. Default: the workspace convention (σ = 1 px, threshold 8).
    pub edge: EdgeSettings,
    /// A line whose in-image part covers less than this fraction of its L + 1 offsets is
    /// "unobserved" and is treated as a line with no edges over its full length. Default 0.5.
    pub min_observed_fraction: f64,
}

impl Default for LineSettings {
    fn default() -> Self {
        Self {
            n_lines: 15,
            length: 20,
            edge: EdgeSettings::default(),
            min_observed_fraction: 0.5,
        }
    }
}

impl LineSettings {
    /// Checks the ranges: n ≥ 3, L even in [2, 1000], fraction in [0, 1], edge settings.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the field.
    pub fn validate(&self) -> Result<()> {
        if self.n_lines > MAX_LINES {
            return Err(Error::InvalidSetting {
                name: "n_lines",
                reason: format!("must be at most {MAX_LINES}, got {}", self.n_lines),
            });
        }
        if self.n_lines < 3 {
            return Err(Error::InvalidSetting {
                name: "n_lines",
                reason: format!("must be at least 3, got {}", self.n_lines),
            });
        }
        if !(2..=1000).contains(&self.length) || !self.length.is_multiple_of(2) {
            return Err(Error::InvalidSetting {
                name: "length",
                reason: format!("must be even and in [2, 1000] px, got {}", self.length),
            });
        }
        if !(0.0..=1.0).contains(&self.min_observed_fraction) {
            return Err(Error::InvalidSetting {
                name: "min_observed_fraction",
                reason: format!("must be in [0, 1], got {}", self.min_observed_fraction),
            });
        }
        self.edge.validate()
    }

    /// Half length L/2 in pixels.
    pub fn half_length(&self) -> usize {
        self.length / 2
    }
}

/// The measurement lines of one contour hypothesis on one image, with their edges; reused from
/// hypothesis to hypothesis.
///
/// What happens at the image border: samples outside [0, w − 1] × [0, h − 1] are missing. The
/// in-image part of a line is one interval; edges are detected on it only where the filter has
/// full support, and the line's observed length is L · (examined offsets)/(L + 1). A line with
/// less than [`LineSettings::min_observed_fraction`] observed, or whose normal is undefined
/// (singular pose), is unobserved: it has no edges and its observed length is the full L, so every
/// likelihood gives it its "no edge" value — a hypothesis gains nothing by leaving the image.
#[derive(Debug, Clone)]
pub struct MeasurementLines {
    settings: LineSettings,
    detector: EdgeDetector,
    /// Sample offsets reach ±(L/2 + 1 + r) so that the filter and the non-maximum suppression
    /// are defined over the whole line.
    reach: i64,
    samples: Vec<f32>,
    centres: Vec<Vector2<f64>>,
    normals: Vec<Vector2<f64>>,
    observed: Vec<bool>,
    observed_len: Vec<f64>,
    /// Line i's edges are `edges[starts[i]..starts[i + 1]]`.
    starts: Vec<usize>,
    edges: Vec<f64>,
    /// The fast scan of the lines wholly inside the image ([`LineScan`]), and each line's place
    /// in it after [`Self::scan_lines`].
    scan: LineScan,
    plan: Vec<Planned>,
    /// Whether a line examined over all its L + 1 offsets is observed (always, unless the
    /// observed fraction exceeds 1, which validation rejects): `enough(L + 1)`, once.
    whole_observed: bool,
    /// The observed length of a line examined over all its L + 1 offsets, `length_of(L + 1)`.
    whole_length: f64,
    /// The posed contour points and normals ((NaN, NaN): undefined), [`Contour::pose_all`].
    posed: Vec<(Vector2<f64>, Vector2<f64>)>,
    /// The best instruction set of this processor (run-time detection), under which the line
    /// scan is compiled.
    arch: pulp::Arch,
}

impl MeasurementLines {
    /// An empty workspace for these settings.
    ///
    /// # Errors
    /// As [`LineSettings::validate`].
    pub fn new(settings: &LineSettings) -> Result<Self> {
        settings.validate()?;
        let detector = EdgeDetector::new(&settings.edge)?;
        let reach = (settings.half_length() + 1 + detector.radius()) as i64;
        let n = settings.n_lines;
        let mut starts = Vec::with_capacity(n + 1);
        starts.push(0);
        let needed = settings.min_observed_fraction * settings.length.saturating_add(1) as f64;
        let whole_observed = (settings.length + 1) as f64 >= needed;
        let full = settings.length as f64;
        let whole_length =
            full * (settings.length + 1) as f64 / (2 * settings.half_length() + 1) as f64;
        Ok(Self {
            whole_observed,
            whole_length,
            settings: *settings,
            detector,
            reach,
            samples: Vec::with_capacity(2 * reach as usize + 1),
            centres: Vec::with_capacity(n),
            normals: Vec::with_capacity(n),
            observed: Vec::with_capacity(n),
            observed_len: Vec::with_capacity(n),
            starts,
            edges: Vec::with_capacity(4 * n),
            scan: LineScan::default(),
            plan: Vec::with_capacity(n),
            posed: Vec::with_capacity(n),
            arch: pulp::Arch::new(),
        })
    }

    /// The settings.
    pub fn settings(&self) -> &LineSettings {
        &self.settings
    }

    /// The same workspace with the line scan run under `arch` instead of the best instruction
    /// set of the processor (tests).
    #[cfg(test)]
    fn with_arch(mut self, arch: pulp::Arch) -> Self {
        self.arch = arch;
        self
    }

    /// Forgets all lines (keeps the buffers).
    pub fn clear(&mut self) {
        self.centres.clear();
        self.normals.clear();
        self.observed.clear();
        self.observed_len.clear();
        self.starts.truncate(1);
        self.edges.clear();
    }

    /// Replaces the lines by those of `contour` under `pose` on `image`.
    ///
    /// # Errors
    /// [`Error::NonFinite`] (index 0) when the pose is not finite;
    /// [`Error::LengthMismatch`] when the contour does not have `n_lines` points;
    /// [`Error::ImageTooSmall`] for an image below 2×2 pixels.
    pub fn extract(
        &mut self,
        image: &GreyImage<'_>,
        contour: &Contour,
        pose: &Affine2,
    ) -> Result<()> {
        check_samplable(image)?;
        if !pose.is_finite() {
            return Err(Error::NonFinite {
                what: "pose",
                index: 0,
            });
        }
        if contour.len() != self.settings.n_lines {
            return Err(Error::LengthMismatch {
                what: "contour points",
                expected: self.settings.n_lines,
                got: contour.len(),
            });
        }
        let half = self.settings.half_length() as i64;
        self.scan_lines(image, contour, pose, -half, half);
        self.clear();
        for i in 0..contour.len() {
            let planned = self.plan[i];
            let examined = match planned.fast {
                Some(line) => self.append_fast(line),
                None => self.append_general(image, planned.centre, planned.normal),
            };
            self.record(planned.centre, planned.normal, examined);
        }
        Ok(())
    }

    /// Appends one line centred at `centre` along the unit direction `normal` (`None`: an
    /// unobserved line). Used directly by clutter learning.
    pub fn push_line(
        &mut self,
        image: &GreyImage<'_>,
        centre: Vector2<f64>,
        normal: Option<Vector2<f64>>,
    ) {
        let half = self.settings.half_length() as i64;
        let examined = match self.scan_one(image, centre, normal, -half, half) {
            Some(line) => self.append_fast(line),
            None => self.append_general(image, centre, normal),
        };
        self.record(centre, normal, examined);
    }

    /// Records a line whose edges were just appended.
    fn record(&mut self, centre: Vector2<f64>, normal: Option<Vector2<f64>>, examined: usize) {
        self.centres.push(centre);
        self.normals.push(normal.unwrap_or_else(Vector2::zeros));
        self.observed.push(examined > 0);
        self.observed_len.push(self.length_of(examined));
        self.starts.push(self.edges.len());
    }

    /// The observed length of a line with `examined` offsets examined (0: unobserved, full L).
    #[inline]
    fn length_of(&self, examined: usize) -> f64 {
        let full = self.settings.length as f64;
        if examined > 0 {
            full * examined as f64 / (2 * self.settings.half_length() + 1) as f64
        } else {
            full
        }
    }

    /// Whether `examined` offsets make a line observed.
    #[inline]
    fn enough(&self, examined: usize) -> bool {
        let needed =
            self.settings.min_observed_fraction * self.settings.length.saturating_add(1) as f64;
        examined > 0 && examined as f64 >= needed
    }

    /// Number of lines.
    pub fn len(&self) -> usize {
        self.centres.len()
    }

    /// Whether there are no lines.
    pub fn is_empty(&self) -> bool {
        self.centres.is_empty()
    }

    /// Sub-pixel edge offsets on line `i`, in pixels along the outward normal from the contour
    /// point, increasing.
    ///
    /// # Panics
    /// If `i ≥ len()`.
    pub fn edges(&self, i: usize) -> &[f64] {
        &self.edges[self.starts[i]..self.starts[i + 1]]
    }

    /// The length over which line `i` was observed (L for an unobserved line, see the type docs).
    ///
    /// # Panics
    /// If `i ≥ len()`.
    pub fn observed_length(&self, i: usize) -> f64 {
        self.observed_len[i]
    }

    /// Whether line `i` was observed.
    ///
    /// # Panics
    /// If `i ≥ len()`.
    pub fn is_observed(&self, i: usize) -> bool {
        self.observed[i]
    }

    /// Centre (contour point) of line `i`, image coordinates.
    ///
    /// # Panics
    /// If `i ≥ len()`.
    pub fn centre(&self, i: usize) -> Vector2<f64> {
        self.centres[i]
    }

    /// Unit direction of line `i` (zero when undefined).
    ///
    /// # Panics
    /// If `i ≥ len()`.
    pub fn normal(&self, i: usize) -> Vector2<f64> {
        self.normals[i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertical_step_seen_by_horizontal_lines() {
        // Dark left half, bright from x = 20.3 on (area sampled).
        let (w, h) = (40, 10);
        let data: Vec<f32> = (0..w * h)
            .map(|k| 200.0 * ((k % w) as f32 + 0.5 - 20.3).clamp(0.0, 1.0))
            .collect();
        let img = GreyImage::new(w, h, &data).unwrap();
        let mut ml = MeasurementLines::new(&LineSettings::default()).unwrap();
        ml.push_line(&img, Vector2::new(18.0, 5.0), Some(Vector2::new(1.0, 0.0)));
        ml.push_line(&img, Vector2::new(18.0, 5.0), Some(Vector2::new(-1.0, 0.0)));
        ml.push_line(&img, Vector2::new(18.0, 5.0), Some(Vector2::new(0.0, 1.0)));
        assert_eq!(ml.edges(0).len(), 1);
        // Tolerance 0.1 px: the detector's sub-pixel bias on a clean step (see edges.rs).
        assert!((ml.edges(0)[0] - 2.3).abs() < 0.1, "{:?}", ml.edges(0));
        assert!((ml.edges(1)[0] + 2.3).abs() < 0.1, "{:?}", ml.edges(1));
        // The vertical line sees a constant column (and is half outside the image: y from −5).
        assert!(ml.edges(2).is_empty());
        assert!(ml.is_observed(0));
    }

    #[test]
    fn lines_outside_are_unobserved_with_full_length() {
        let data = vec![0.0f32; 100];
        let img = GreyImage::new(10, 10, &data).unwrap();
        let mut ml = MeasurementLines::new(&LineSettings::default()).unwrap();
        ml.push_line(&img, Vector2::new(-50.0, 5.0), Some(Vector2::new(0.0, 1.0)));
        ml.push_line(&img, Vector2::new(5.0, 5.0), None);
        ml.push_line(
            &img,
            Vector2::new(f64::NAN, 5.0),
            Some(Vector2::new(0.0, 1.0)),
        );
        for i in 0..3 {
            assert!(!ml.is_observed(i));
            assert_eq!(ml.observed_length(i), 20.0);
            assert!(ml.edges(i).is_empty());
        }
    }

    #[test]
    fn partial_line_length() {
        // A 30×30 flat image: a horizontal line centred at x = 2 sees offsets −2 … 10 in the image,
        // of which the filter (r = 3) plus suppression (1) leave −2 + 4 = 2 … 10: 9 of 21 offsets
        // examined, below half, so the line is unobserved; centred at x = 8 it sees 4 … 10 of 21
        // with the left limit at −8 + 4 = −4: offsets −4 … 10, 15 of 21.
        let data = vec![0.0f32; 900];
        let img = GreyImage::new(30, 30, &data).unwrap();
        let mut ml = MeasurementLines::new(&LineSettings::default()).unwrap();
        ml.push_line(&img, Vector2::new(2.0, 15.0), Some(Vector2::new(1.0, 0.0)));
        ml.push_line(&img, Vector2::new(8.0, 15.0), Some(Vector2::new(1.0, 0.0)));
        assert!(!ml.is_observed(0));
        assert!((ml.observed_length(1) - 20.0 * 15.0 / 21.0).abs() < 1e-12);
    }
}
