//! Measurement lines: length L, centred on each contour point along its outward normal, sampled
//! every pixel by bilinear interpolation, with their detected edges. [`MeasurementLines`] is the
//! reusable workspace of every likelihood: after the first use it allocates nothing.
//!
//! Sample positions c + k·n are stepped in fixed point (`GreyView::sample_line`): within
//! ~1e−6 px of the exact positions, so edge offsets agree with per-sample f32 interpolation to
//! well under 1e−4 px (measured worst 5.5e−5 px, `tests/fast_paths.rs`).
//!
//! Lines wholly inside the image go through the batched fast scan ([`crate::scan`]); the
//! others through the general path (the in-image interval, clamped sampling, the detector).
//! Both compute the same positions and arithmetic, so they give the same edges to the bit
//! (`fast_scan_equals_the_general_path_bit_for_bit`).

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::scan::LineScan;
use crate::{Affine2, Contour, EdgeDetector, EdgeSettings, Error, GreyView, Result};

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

/// Whether a line lies wholly inside the image: both end points c ± reach·n in
/// [0, w − 1] × [0, h − 1], the test `inside_interval` starts with (so that the fast and the
/// general path agree on which lines are wholly inside; a segment is inside when its end points
/// are). False for non-finite centres or normals.
#[derive(Debug, Clone, Copy)]
struct LineBounds {
    reach: f64,
    xmax: f64,
    ymax: f64,
}

impl LineBounds {
    /// Branch-free, so that a pass over many lines vectorises.
    #[inline(always)]
    fn holds(&self, c: Vector2<f64>, n: Vector2<f64>) -> bool {
        let r = self.reach;
        let (x0, y0, x1, y1) = (c.x - r * n.x, c.y - r * n.y, c.x + r * n.x, c.y + r * n.y);
        (x0 >= 0.0)
            & (x0 <= self.xmax)
            & (y0 >= 0.0)
            & (y0 <= self.ymax)
            & (x1 >= 0.0)
            & (x1 <= self.xmax)
            & (y1 >= 0.0)
            & (y1 <= self.ymax)
    }
}

/// [`MeasurementLines::scan_lines`] as an operation that [`pulp::Arch::dispatch`] compiles once
/// per instruction set and runs under the best one of the processor.
struct ScanLines<'a, 'b> {
    lines: &'a mut MeasurementLines,
    image: &'a GreyView<'b>,
    contour: &'a Contour,
    pose: &'a Affine2,
    klo: i64,
    khi: i64,
}

impl pulp::WithSimd for ScanLines<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let Self {
            lines,
            image,
            contour,
            pose,
            klo,
            khi,
        } = self;
        lines.scan_lines_with(image, contour, pose, klo, khi);
    }
}

/// One line of [`MeasurementLines::scan_lines`]: where it is, and its index in the fast scan
/// (`None`: the general path takes it).
#[derive(Debug, Clone, Copy)]
struct Planned {
    centre: Vector2<f64>,
    normal: Option<Vector2<f64>>,
    fast: Option<usize>,
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
    /// [`Error::LengthMismatch`] when the contour does not have `n_lines` points.
    pub fn extract(
        &mut self,
        image: &GreyView<'_>,
        contour: &Contour,
        pose: &Affine2,
    ) -> Result<()> {
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
        image: &GreyView<'_>,
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

    /// Scans the candidates `klo ..= khi` of every line of `contour` under `pose`: the lines
    /// wholly inside the image in one [`LineScan`], the others marked for the general path.
    /// Each line's plan is then in `plan`. The pose must be finite.
    pub(crate) fn scan_lines(
        &mut self,
        image: &GreyView<'_>,
        contour: &Contour,
        pose: &Affine2,
        klo: i64,
        khi: i64,
    ) {
        let arch = self.arch;
        arch.dispatch(ScanLines {
            lines: self,
            image,
            contour,
            pose,
            klo,
            khi,
        });
    }

    /// [`Self::scan_lines`], inlined into the dispatched (feature-enabled) operation.
    #[inline(always)]
    fn scan_lines_with(
        &mut self,
        image: &GreyView<'_>,
        contour: &Contour,
        pose: &Affine2,
        klo: i64,
        khi: i64,
    ) {
        self.plan.clear();
        let fits = self.scan.begin(&self.detector, klo, khi, contour.len());
        contour.pose_all(pose, &mut self.posed);
        // The end-point test and the fixed-point set-up of every line in branch-free passes,
        // then the lines.
        let bounds = self.bounds(image);
        if fits {
            self.scan
                .place(image, &self.posed, |c, n| bounds.holds(c, n));
        }
        for (i, &(centre, normal)) in self.posed.iter().enumerate() {
            self.plan.push(Planned {
                centre,
                normal: (!normal.x.is_nan()).then_some(normal),
                fast: self.scan.scanned(i).then_some(i),
            });
        }
        self.scan.finish(image, &self.detector);
    }

    /// One line through the fast scan alone: its index there, or `None` for the general path.
    fn scan_one(
        &mut self,
        image: &GreyView<'_>,
        centre: Vector2<f64>,
        normal: Option<Vector2<f64>>,
        klo: i64,
        khi: i64,
    ) -> Option<usize> {
        let n = normal?;
        if !self.scan.begin(&self.detector, klo, khi, 1) {
            return None;
        }
        let bounds = self.bounds(image);
        self.scan
            .place(image, &[(centre, n)], |c, n| bounds.holds(c, n));
        if !self.scan.scanned(0) {
            return None;
        }
        self.scan.finish(image, &self.detector);
        Some(0)
    }

    /// The end-point test of lines on `image`.
    #[inline]
    fn bounds(&self, image: &GreyView<'_>) -> LineBounds {
        LineBounds {
            reach: self.reach as f64,
            xmax: (image.width() - 1) as f64,
            ymax: (image.height() - 1) as f64,
        }
    }

    /// Appends the edges of fast line `line` (candidates −L/2 ..= L/2) and returns the offsets
    /// examined: all L + 1 of a line wholly inside.
    fn append_fast(&mut self, line: usize) -> usize {
        let examined = self.settings.length + 1;
        if !self.whole_observed {
            return 0;
        }
        self.edges
            .extend(self.scan.offsets(line, self.scan.mask(line)));
        examined
    }

    /// The general path: appends the edges of one line to `edges` (none for an unobserved line)
    /// and returns how many offsets were examined (0: unobserved).
    fn append_general(
        &mut self,
        image: &GreyView<'_>,
        centre: Vector2<f64>,
        normal: Option<Vector2<f64>>,
    ) -> usize {
        let Some(n) = normal.filter(|_| centre.x.is_finite() && centre.y.is_finite()) else {
            return 0;
        };
        let Some((lo, hi)) = inside_interval(image, centre, n, self.reach) else {
            return 0;
        };
        let half = self.settings.half_length() as i64;
        let len = (hi - lo + 1) as usize;
        self.samples.resize(len, 0.0);
        image.sample_line((centre.x, centre.y), (n.x, n.y), lo, hi, &mut self.samples);
        let before = self.edges.len();
        let examined = self
            .detector
            .detect(&self.samples, lo, -half, half, &mut self.edges);
        if self.enough(examined) {
            examined
        } else {
            self.edges.truncate(before);
            0
        }
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

    /// Line `i` of the last [`Self::scan_lines`] (candidates −L/2 ..= L/2) without storing it:
    /// returns (observed length, number of edges m(L)) as [`Self::push_line`] would record
    /// them, and leaves in [`Self::candidates`] the edge offsets, increasing, of at least every
    /// edge within `near` px of the contour point (on the fast path only those at integer
    /// offsets |k| ≤ ⌊`near` + ½⌋, which are all that can lie within `near`; on the general
    /// path all). Wu's likelihoods need no more.
    #[cfg(test)]
    pub(crate) fn count_edges(
        &mut self,
        image: &GreyView<'_>,
        i: usize,
        near: f64,
    ) -> (f64, usize) {
        let window = self.window_bits(near);
        self.count_edges_in(image, i, window)
    }

    /// The candidate bits of a fast line ([`LineScan::mask`], bit j ↔ offset j − L/2) at
    /// integer offsets |k| ≤ ⌊`near` + ½⌋, for [`Self::count_edges_in`].
    pub(crate) fn window_bits(&self, near: f64) -> u64 {
        let half = self.settings.half_length() as i64;
        // |k| ≤ kn ↔ j ∈ [half − kn, half + kn]. ⌊near + ½⌋ by truncation (a libm call
        // otherwise on baseline x86-64).
        let kn = if near + 0.5 >= 0.0 {
            ((near + 0.5) as i64).min(half)
        } else {
            -1
        };
        if kn < 0 {
            0
        } else {
            let width = 2 * kn + 1;
            let ones = if width >= 64 {
                u64::MAX
            } else {
                (1u64 << width) - 1
            };
            ones << (half - kn)
        }
    }

    /// [`Self::count_edges`] with the window as [`Self::window_bits`] of `near`, computed once
    /// per hypothesis.
    #[inline]
    pub(crate) fn count_edges_in(
        &mut self,
        image: &GreyView<'_>,
        i: usize,
        window: u64,
    ) -> (f64, usize) {
        self.edges.clear();
        let Some(&planned) = self.plan.get(i) else {
            return (self.length_of(0), 0);
        };
        let Some(line) = planned.fast else {
            let examined = self.append_general(image, planned.centre, planned.normal);
            return (self.length_of(examined), self.edges.len());
        };
        if !self.whole_observed {
            return (self.length_of(0), 0);
        }
        let mask = self.scan.mask(line);
        // Pushed one by one: `extend` from the bit iterator (no size hint) stays an
        // out-of-line generic loop, a call per line.
        for z in self.scan.offsets(line, window & mask) {
            self.edges.push(z);
        }
        // All L + 1 offsets examined.
        (self.whole_length, mask.count_ones() as usize)
    }

    /// The edge offsets left by [`Self::count_edges_in`].
    #[inline]
    pub(crate) fn candidates(&self) -> &[f64] {
        &self.edges
    }

    /// Whether `examined` offsets make a line observed.
    #[inline]
    fn enough(&self, examined: usize) -> bool {
        let needed =
            self.settings.min_observed_fraction * self.settings.length.saturating_add(1) as f64;
        examined > 0 && examined as f64 >= needed
    }

    /// The squared offset of the nearest edge to the contour point on the line at `centre`
    /// along `normal`, considering only edges at integer offsets |k| ≤ `search`; +∞ when there
    /// is none there or the line is unobserved. The result equals the minimum of z² over the
    /// edges z with |k| ≤ `search` that [`Self::push_line`] finds (same samples, same
    /// arithmetic, same observed-line rule), but only the part of the line that can matter is
    /// sampled: at most 2·(`search` + 1 + r) + 1 samples instead of L + 3 + 2r. Nothing is
    /// stored in the line list.
    pub fn nearest_edge_sq(
        &mut self,
        image: &GreyView<'_>,
        centre: Vector2<f64>,
        normal: Option<Vector2<f64>>,
        search: usize,
    ) -> f64 {
        let search = search.min(self.settings.half_length()) as i64;
        match self.scan_one(image, centre, normal, -search, search) {
            Some(line) => self.nearest_fast(line),
            None => self.nearest_general(image, centre, normal, search),
        }
    }

    /// [`Self::nearest_edge_sq`] of line `i` of the last [`Self::scan_lines`], which must have
    /// scanned the candidates −`search` ..= `search` (`search` ≤ L/2).
    #[inline]
    pub(crate) fn nearest_planned(&mut self, image: &GreyView<'_>, i: usize, search: i64) -> f64 {
        match self.plan.get(i) {
            Some(&Planned {
                fast: Some(line), ..
            }) => self.nearest_fast(line),
            Some(&Planned { centre, normal, .. }) => {
                self.nearest_general(image, centre, normal, search)
            }
            None => f64::INFINITY,
        }
    }

    /// The nearest edge of a fast line: min z² over its mask.
    #[inline]
    fn nearest_fast(&self, line: usize) -> f64 {
        if !self.whole_observed {
            return f64::INFINITY;
        }
        self.scan
            .offsets(line, self.scan.mask(line))
            .fold(f64::INFINITY, |best, z| best.min(z * z))
    }

    /// [`Self::nearest_edge_sq`] on the general path (`search` ≤ L/2).
    fn nearest_general(
        &mut self,
        image: &GreyView<'_>,
        centre: Vector2<f64>,
        normal: Option<Vector2<f64>>,
        search: i64,
    ) -> f64 {
        let Some(n) = normal.filter(|_| centre.x.is_finite() && centre.y.is_finite()) else {
            return f64::INFINITY;
        };
        let Some((lo, hi)) = inside_interval(image, centre, n, self.reach) else {
            return f64::INFINITY;
        };
        let half = self.settings.half_length() as i64;
        let r = self.detector.radius() as i64;
        // The offsets EdgeDetector::detect would examine on the in-image part [lo, hi].
        let (klo, khi) = ((lo + r + 1).max(-half), (hi - r - 1).min(half));
        let examined = if khi >= klo {
            (khi - klo + 1) as usize
        } else {
            0
        };
        if !self.enough(examined) {
            return f64::INFINITY;
        }
        let (clo, chi) = (klo.max(-search), khi.min(search));
        if chi < clo {
            return f64::INFINITY;
        }
        // Samples at clo − 1 − r ..= chi + 1 + r (samples[k − s_lo]), derivatives at
        // clo − 1 ..= chi + 1, in one run.
        let (s_lo, s_hi) = (clo - 1 - r, chi + 1 + r);
        self.samples.resize((s_hi - s_lo + 1) as usize, 0.0);
        image.sample_line(
            (centre.x, centre.y),
            (n.x, n.y),
            s_lo,
            s_hi,
            &mut self.samples,
        );
        self.nearest_in(clo, chi, s_lo)
    }

    /// min z² over the edges at integer offsets `a` ..= `b`, from `samples[k − s_lo]`, which
    /// must hold offsets a − 1 − r ..= b + 1 + r.
    fn nearest_in(&mut self, a: i64, b: i64, s_lo: i64) -> f64 {
        self.detector.fill_derivatives(
            &self.samples,
            (a - 1 - s_lo) as usize,
            (b + 1 - s_lo) as usize,
        );
        let mut best = f64::INFINITY;
        for (i, w) in self.detector.responses().windows(3).enumerate() {
            if let Some(delta) = self.detector.peak(w[0], w[1], w[2]) {
                let z = (a + i as i64) as f64 + f64::from(delta);
                best = best.min(z * z);
            }
        }
        best
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

/// The integer offsets k in [−reach, reach] for which centre + k·n lies inside the image, or
/// `None` if there are none. A segment meets a rectangle in one interval, so this is exact.
fn inside_interval(
    image: &GreyView<'_>,
    c: Vector2<f64>,
    n: Vector2<f64>,
    reach: i64,
) -> Option<(i64, i64)> {
    let r = reach as f64;
    let (xmax, ymax) = ((image.width() - 1) as f64, (image.height() - 1) as f64);
    // Most lines lie wholly inside: both end points inside means the whole segment is.
    let inside = |k: f64| {
        let (x, y) = (c.x + k * n.x, c.y + k * n.y);
        (0.0..=xmax).contains(&x) && (0.0..=ymax).contains(&y)
    };
    if inside(-r) && inside(r) {
        return Some((-reach, reach));
    }
    let mut lo = -r;
    let mut hi = r;
    for (ci, ni, max) in [
        (c.x, n.x, (image.width() - 1) as f64),
        (c.y, n.y, (image.height() - 1) as f64),
    ] {
        if ni.abs() < 1e-12 {
            if !(0.0..=max).contains(&ci) {
                return None;
            }
        } else {
            let (a, b) = ((0.0 - ci) / ni, (max - ci) / ni);
            lo = lo.max(a.min(b));
            hi = hi.min(a.max(b));
        }
    }
    // A hair of tolerance: sampling clamps indices, so rounding at the border is harmless.
    let (lo, hi) = ((lo - 1e-9).ceil(), (hi + 1e-9).floor());
    (lo <= hi).then_some((lo as i64, hi as i64))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Polarity, Template};
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    /// Random grey discs on mid-grey: edges of every strength, many near the threshold.
    fn cluttered(rng: &mut Pcg64Mcg, w: usize, h: usize) -> Vec<f32> {
        let mut img = vec![110.0f32; w * h];
        for _ in 0..w * h / 60 {
            let (cx, cy, r): (f64, f64, f64) = (
                rng.random_range(0.0..w as f64),
                rng.random_range(0.0..h as f64),
                rng.random_range(1.5..7.0),
            );
            let g = rng.random_range(0.0..255.0) as f32;
            for y in 0..h {
                for x in 0..w {
                    let (dx, dy) = (x as f64 - cx, y as f64 - cy);
                    if dx * dx + dy * dy <= r * r {
                        img[y * w + x] = g;
                    }
                }
            }
        }
        img
    }

    /// The line settings the fast scan is checked under: the default, a wider filter (σ = 1.7,
    /// radius 6, the general tap loop), long lines (L = 50: 61 samples, near the scan's cap),
    /// lines too long for the scan (L = 60: the general path only), each polarity, a low
    /// threshold, and a strict observed fraction.
    fn settings_under_test() -> Vec<LineSettings> {
        let d = LineSettings::default();
        let edge = |sigma, threshold, polarity| EdgeSettings {
            sigma,
            threshold,
            polarity,
        };
        vec![
            d,
            LineSettings {
                edge: edge(1.7, 8.0, Polarity::Any),
                ..d
            },
            LineSettings { length: 50, ..d },
            LineSettings { length: 60, ..d },
            LineSettings {
                edge: edge(1.0, 8.0, Polarity::Rising),
                ..d
            },
            LineSettings {
                edge: edge(1.0, 3.0, Polarity::Falling),
                min_observed_fraction: 1.0,
                ..d
            },
        ]
    }

    #[test]
    fn fast_scan_equals_the_general_path_bit_for_bit() {
        // Every line of random poses (many reaching over the border or wholly outside) through
        // extract (the batched fast scan where a line is wholly inside), push_line (the scan
        // of one line), nearest_edge_sq and count_edges, against the general path
        // (inside_interval, sample_line, EdgeDetector) on the same line: the same samples and
        // arithmetic, so the same edges to the bit and the same observed length.
        let mut rng = Pcg64Mcg::seed_from_u64(21);
        let (w, h) = (150, 110);
        let data = cluttered(&mut rng, w, h);
        let image = GreyView::new(w, h, &data).unwrap();
        let (mut fast_lines, mut edges) = (0usize, 0usize);
        for settings in settings_under_test() {
            let settings = LineSettings {
                n_lines: 24,
                ..settings
            };
            let contour = Contour::new(&Template::UnitCircle, settings.n_lines).unwrap();
            let mut ws = MeasurementLines::new(&settings).unwrap();
            let mut single = MeasurementLines::new(&settings).unwrap();
            let mut general = MeasurementLines::new(&settings).unwrap();
            let half = settings.half_length();
            for _ in 0..150 {
                let pose = Affine2::from_ellipse(
                    rng.random_range(-10.0..160.0),
                    rng.random_range(-10.0..120.0),
                    rng.random_range(5.0..45.0),
                    rng.random_range(5.0..45.0),
                    rng.random_range(-3.2..3.2),
                );
                ws.extract(&image, &contour, &pose).unwrap();
                fast_lines += ws.plan.iter().filter(|p| p.fast.is_some()).count();
                single.clear();
                for i in 0..contour.len() {
                    let (c, n) = (ws.plan[i].centre, ws.plan[i].normal);
                    general.clear();
                    let examined = general.append_general(&image, c, n);
                    let want = &general.edges[..];
                    assert_eq!(ws.edges(i), want, "extract, line {i}");
                    assert_eq!(ws.observed_length(i), general.length_of(examined));
                    single.push_line(&image, c, n);
                    assert_eq!(single.edges(i), want, "push_line, line {i}");
                    assert_eq!(single.observed_length(i), ws.observed_length(i));
                    edges += want.len();
                    for search in [0, 2, 4, half] {
                        let want = general.nearest_general(&image, c, n, search as i64);
                        let got = general.nearest_edge_sq(&image, c, n, search);
                        assert_eq!(got.to_bits(), want.to_bits(), "nearest, search {search}");
                    }
                }
                // Wu's counting path: the count and, in the window, the same offsets.
                let near = 4.0;
                ws.scan_lines(&image, &contour, &pose, -(half as i64), half as i64);
                for i in 0..contour.len() {
                    let (c, n) = (ws.plan[i].centre, ws.plan[i].normal);
                    general.clear();
                    let examined = general.append_general(&image, c, n);
                    let (length, m) = ws.count_edges(&image, i, near);
                    assert_eq!(
                        (length, m),
                        (general.length_of(examined), general.edges.len())
                    );
                    let in_window = |e: &&f64| e.abs() <= near;
                    assert!(
                        ws.candidates()
                            .iter()
                            .filter(in_window)
                            .eq(general.edges.iter().filter(in_window))
                    );
                }
            }
        }
        // The comparison covers many lines on the fast path, and enough edges.
        assert!(
            fast_lines > 5_000 && edges > 20_000,
            "{fast_lines} fast lines, {edges} edges"
        );
    }

    /// Every instruction set the scan can run under on this processor: baseline x86-64, AVX2
    /// and AVX-512 where available.
    fn instruction_sets() -> Vec<pulp::Arch> {
        let mut sets = vec![pulp::Arch::Scalar];
        if let Some(v3) = pulp::x86::V3::try_new() {
            sets.push(pulp::Arch::V3(v3));
        }
        if let Some(v4) = pulp::x86::V4::try_new() {
            sets.push(pulp::Arch::V4(v4));
        }
        sets
    }

    #[test]
    fn every_instruction_set_gives_the_same_bits() {
        // The scan compiled for each instruction set (pulp's run-time dispatch) against the
        // baseline one on the same lines: the same edges, observed lengths, nearest edges and
        // counts to the bit (no fused multiply-add: Rust never contracts).
        let mut rng = Pcg64Mcg::seed_from_u64(22);
        let (w, h) = (150, 110);
        let data = cluttered(&mut rng, w, h);
        let image = GreyView::new(w, h, &data).unwrap();
        let sets = instruction_sets();
        let mut lines = 0usize;
        for settings in settings_under_test() {
            let settings = LineSettings {
                n_lines: 24,
                ..settings
            };
            let contour = Contour::new(&Template::UnitCircle, settings.n_lines).unwrap();
            let mut workspaces: Vec<MeasurementLines> = sets
                .iter()
                .map(|&arch| MeasurementLines::new(&settings).unwrap().with_arch(arch))
                .collect();
            let half = settings.half_length() as i64;
            for _ in 0..60 {
                let pose = Affine2::from_ellipse(
                    rng.random_range(-10.0..160.0),
                    rng.random_range(-10.0..120.0),
                    rng.random_range(5.0..45.0),
                    rng.random_range(5.0..45.0),
                    rng.random_range(-3.2..3.2),
                );
                let (base, others) = workspaces.split_first_mut().unwrap();
                base.extract(&image, &contour, &pose).unwrap();
                for ws in others.iter_mut() {
                    ws.extract(&image, &contour, &pose).unwrap();
                    for i in 0..contour.len() {
                        assert_eq!(ws.edges(i), base.edges(i), "line {i}");
                        assert_eq!(ws.observed_length(i), base.observed_length(i));
                    }
                }
                for search in [2, half] {
                    let mut want = Vec::new();
                    base.scan_lines(&image, &contour, &pose, -search, search);
                    for i in 0..contour.len() {
                        want.push(base.nearest_planned(&image, i, search).to_bits());
                    }
                    for ws in others.iter_mut() {
                        ws.scan_lines(&image, &contour, &pose, -search, search);
                        for (i, want) in want.iter().enumerate() {
                            assert_eq!(ws.nearest_planned(&image, i, search).to_bits(), *want);
                        }
                    }
                }
                base.scan_lines(&image, &contour, &pose, -half, half);
                for ws in others.iter_mut() {
                    ws.scan_lines(&image, &contour, &pose, -half, half);
                    for i in 0..contour.len() {
                        let want = base.count_edges(&image, i, 4.0);
                        assert_eq!(ws.count_edges(&image, i, 4.0), want);
                        assert_eq!(ws.candidates(), base.candidates());
                        lines += usize::from(base.plan[i].fast.is_some());
                    }
                }
            }
        }
        // Many lines through the fast scan under every other instruction set.
        assert!(lines > 1_000 * (sets.len() - 1), "{lines} fast lines");
    }

    #[test]
    fn vertical_step_seen_by_horizontal_lines() {
        // Dark left half, bright from x = 20.3 on (area sampled).
        let (w, h) = (40, 10);
        let data: Vec<f32> = (0..w * h)
            .map(|k| 200.0 * ((k % w) as f32 + 0.5 - 20.3).clamp(0.0, 1.0))
            .collect();
        let img = GreyView::new(w, h, &data).unwrap();
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
        let img = GreyView::new(10, 10, &data).unwrap();
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
        let img = GreyView::new(30, 30, &data).unwrap();
        let mut ml = MeasurementLines::new(&LineSettings::default()).unwrap();
        ml.push_line(&img, Vector2::new(2.0, 15.0), Some(Vector2::new(1.0, 0.0)));
        ml.push_line(&img, Vector2::new(8.0, 15.0), Some(Vector2::new(1.0, 0.0)));
        assert!(!ml.is_observed(0));
        assert!((ml.observed_length(1) - 20.0 * 15.0 / 21.0).abs() < 1e-12);
    }
}
