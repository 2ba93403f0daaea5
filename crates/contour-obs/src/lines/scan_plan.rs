//! Planning a contour's measurement lines: the lines wholly inside the image go through the
//! batched fast scan ([`crate::scan`]), compiled per instruction set; the others take the
//! general path (the in-image interval, clamped sampling, the detector). Both append the same
//! edges.

use nalgebra::Vector2;
use vision_core::GreyImage;

use super::MeasurementLines;
use crate::image::samplable;
use crate::{Affine2, Contour};

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
    image: &'a GreyImage<'b>,
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
pub(super) struct Planned {
    pub(super) centre: Vector2<f64>,
    pub(super) normal: Option<Vector2<f64>>,
    pub(super) fast: Option<usize>,
}

impl MeasurementLines {
    /// Scans the candidates `klo ..= khi` of every line of `contour` under `pose`: the lines
    /// wholly inside the image in one [`LineScan`], the others marked for the general path.
    /// Each line's plan is then in `plan`. The pose must be finite.
    pub(crate) fn scan_lines(
        &mut self,
        image: &GreyImage<'_>,
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
        image: &GreyImage<'_>,
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
    pub(super) fn scan_one(
        &mut self,
        image: &GreyImage<'_>,
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
    fn bounds(&self, image: &GreyImage<'_>) -> LineBounds {
        // An image without an interpolation cell holds no line (every end point fails).
        let side = |n: usize| {
            if samplable(image) {
                (n - 1) as f64
            } else {
                -1.0
            }
        };
        LineBounds {
            reach: self.reach as f64,
            xmax: side(image.width()),
            ymax: side(image.height()),
        }
    }

    /// Appends the edges of fast line `line` (candidates −L/2 ..= L/2) and returns the offsets
    /// examined: all L + 1 of a line wholly inside.
    pub(super) fn append_fast(&mut self, line: usize) -> usize {
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
    pub(super) fn append_general(
        &mut self,
        image: &GreyImage<'_>,
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
        crate::image::sample_line(
            image,
            (centre.x, centre.y),
            (n.x, n.y),
            lo,
            hi,
            &mut self.samples,
        );
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
}

/// The integer offsets k in [−reach, reach] for which centre + k·n lies inside the image, or
/// `None` if there are none. A segment meets a rectangle in one interval, so this is exact.
pub(super) fn inside_interval(
    image: &GreyImage<'_>,
    c: Vector2<f64>,
    n: Vector2<f64>,
    reach: i64,
) -> Option<(i64, i64)> {
    if !samplable(image) {
        return None;
    }
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
    use crate::{EdgeSettings, LineSettings, Polarity, Template};
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
        let image = GreyImage::new(w, h, &data).unwrap();
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
        let image = GreyImage::new(w, h, &data).unwrap();
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
}
