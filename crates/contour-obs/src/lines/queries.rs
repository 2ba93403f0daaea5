//! What the likelihoods ask of one line without storing it: its edge count and the edges near
//! the contour point (Wu's Poisson-clutter likelihood), and the nearest edge (Odobez's shape
//! likelihood).

use nalgebra::Vector2;
use vision_core::GreyImage;

use super::MeasurementLines;
use super::scan_plan::{Planned, inside_interval};

impl MeasurementLines {
    /// Line `i` of the last [`Self::scan_lines`] (candidates −L/2 ..= L/2) without storing it:
    /// returns (observed length, number of edges m(L)) as [`Self::push_line`] would record
    /// them, and leaves in [`Self::candidates`] the edge offsets, increasing, of at least every
    /// edge within `near` px of the contour point (on the fast path only those at integer
    /// offsets |k| ≤ ⌊`near` + ½⌋, which are all that can lie within `near`; on the general
    /// path all). Wu's likelihoods need no more.
    #[cfg(test)]
    pub(crate) fn count_edges(
        &mut self,
        image: &GreyImage<'_>,
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
            // Lines longer than the fast scan's 64 samples take the general path, which does not
            // read the window; their bits would fall off the word (a shift overflow, found with
            // 1000 px lines), so they get none.
            u32::try_from(half - kn)
                .ok()
                .and_then(|shift| ones.checked_shl(shift))
                .unwrap_or(0)
        }
    }

    /// [`Self::count_edges`] with the window as [`Self::window_bits`] of `near`, computed once
    /// per hypothesis.
    #[inline]
    pub(crate) fn count_edges_in(
        &mut self,
        image: &GreyImage<'_>,
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

    /// The squared offset of the nearest edge to the contour point on the line at `centre`
    /// along `normal`, considering only edges at integer offsets |k| ≤ `search`; +∞ when there
    /// is none there or the line is unobserved. The result equals the minimum of z² over the
    /// edges z with |k| ≤ `search` that [`Self::push_line`] finds (same samples, same
    /// arithmetic, same observed-line rule), but only the part of the line that can matter is
    /// sampled: at most 2·(`search` + 1 + r) + 1 samples instead of L + 3 + 2r. Nothing is
    /// stored in the line list.
    pub fn nearest_edge_sq(
        &mut self,
        image: &GreyImage<'_>,
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
    pub(crate) fn nearest_planned(&mut self, image: &GreyImage<'_>, i: usize, search: i64) -> f64 {
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
    pub(super) fn nearest_general(
        &mut self,
        image: &GreyImage<'_>,
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
        crate::image::sample_line(
            image,
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
}
