//! The colour model of the region tracker: HSV bins as in Pérez et al. 2002 (hue × saturation
//! for coloured pixels, value alone for dark or unsaturated ones, where hue means nothing), grey
//! levels for grey frames, normalised histograms, and the per-bin log-ratio of the target's
//! histogram to the background's.

/// Saturation below which a pixel's hue is not trusted (Pérez et al. use 0.1).
const MIN_SATURATION: f32 = 0.1;
/// Value below which a pixel's hue is not trusted (Pérez et al. use 0.2).
const MIN_VALUE: f32 = 0.2;
/// Probability added to every bin before a ratio, so that an empty bin is not ±∞.
const BIN_FLOOR: f64 = 1e-3;
/// Bound of a bin's log-ratio, nats: one bin cannot outvote a region.
const MAX_LOG_RATIO: f64 = 3.0;

/// How pixels map to histogram bins.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ColourBins {
    hs: usize,
    value: usize,
    colour: bool,
}

impl ColourBins {
    /// Colour bins: `hs`×`hs` hue–saturation bins and `value` value bins.
    pub fn colour(hs: usize, value: usize) -> Self {
        Self {
            hs,
            value,
            colour: true,
        }
    }

    /// Grey bins: `levels` grey-level bins.
    pub fn grey(levels: usize) -> Self {
        Self {
            hs: 0,
            value: levels,
            colour: false,
        }
    }

    /// Whether the bins read colour.
    pub fn is_colour(&self) -> bool {
        self.colour
    }

    /// Number of bins.
    pub fn len(&self) -> usize {
        self.hs * self.hs + self.value
    }

    /// The bin of an RGB pixel (components 0–255).
    pub fn of_rgb(&self, r: f32, g: f32, b: f32) -> u16 {
        let max = r.max(g).max(b);
        let min = r.min(g).min(b);
        let v = max / 255.0;
        let s = if max > 0.0 { (max - min) / max } else { 0.0 };
        let value_bin = |v: f32| ((v * self.value as f32) as usize).min(self.value - 1);
        if s < MIN_SATURATION || v < MIN_VALUE {
            return (self.hs * self.hs + value_bin(v)) as u16;
        }
        let delta = max - min;
        // Hue in [0, 6).
        let h = if max == r {
            ((g - b) / delta).rem_euclid(6.0)
        } else if max == g {
            (b - r) / delta + 2.0
        } else {
            (r - g) / delta + 4.0
        };
        let hb = ((h / 6.0 * self.hs as f32) as usize).min(self.hs - 1);
        let sb = (((s - MIN_SATURATION) / (1.0 - MIN_SATURATION) * self.hs as f32) as usize)
            .min(self.hs - 1);
        (hb * self.hs + sb) as u16
    }

    /// The bin of a grey level (0–255).
    pub fn of_grey(&self, g: f32) -> u16 {
        let v = (g / 256.0).clamp(0.0, 1.0);
        (self.hs * self.hs + ((v * self.value as f32) as usize).min(self.value - 1)) as u16
    }
}

/// Share of coloured pixels (hue trusted, see [`ColourBins::of_rgb`]) below which an RGB frame
/// is read as grey: a grey video stored as RGB has no hue to histogram, and its grey levels are
/// binned finer than the value bins of a colour frame.
const MIN_CHROMATIC_SHARE: f64 = 0.02;

/// Whether an interleaved RGB image (components 0–255) has colour worth histogramming: at least
/// [`MIN_CHROMATIC_SHARE`] of its pixels (read on a sparse lattice) have a trusted hue.
pub fn is_chromatic(rgb: &[u8]) -> bool {
    const STRIDE: usize = 7;
    let (mut coloured, mut read) = (0usize, 0usize);
    for px in rgb.chunks_exact(3).step_by(STRIDE) {
        let [r, g, b] = [px[0], px[1], px[2]].map(f32::from);
        let max = r.max(g).max(b);
        let min = r.min(g).min(b);
        read += 1;
        if max / 255.0 >= MIN_VALUE && (max - min) / max >= MIN_SATURATION {
            coloured += 1;
        }
    }
    read > 0 && coloured as f64 >= MIN_CHROMATIC_SHARE * read as f64
}

/// A normalised histogram over [`ColourBins`].
#[derive(Debug, Clone, PartialEq)]
pub struct Histogram {
    mass: Vec<f64>,
}

impl Histogram {
    /// A histogram from weighted bin counts; `None` when the counts are empty.
    pub fn from_counts(mut counts: Vec<f64>) -> Option<Self> {
        let total: f64 = counts.iter().sum();
        if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || !total.is_finite() {
            return None;
        }
        for c in &mut counts {
            *c /= total;
        }
        Some(Self { mass: counts })
    }

    /// Moves this histogram towards `other` by `rate` (exponential forgetting).
    pub fn blend(&mut self, other: &Histogram, rate: f64) {
        for (m, o) in self.mass.iter_mut().zip(&other.mass) {
            *m = (1.0 - rate) * *m + rate * o;
        }
    }

    /// The Bhattacharyya coefficient Σ √(p q) ∈ [0, 1] (1: identical).
    pub fn bhattacharyya(&self, other: &Histogram) -> f64 {
        self.mass
            .iter()
            .zip(&other.mass)
            .map(|(p, q)| (p * q).sqrt())
            .sum::<f64>()
            .min(1.0)
    }
}

/// The log-ratio ln((p_target + ε) / (p_background + ε)) of every bin, bounded by ±3 nats: the
/// evidence one pixel of that bin gives for the target against the background.
pub fn log_ratios(target: &Histogram, background: &Histogram, out: &mut Vec<f32>) {
    out.clear();
    out.extend(target.mass.iter().zip(&background.mass).map(|(t, b)| {
        ((t + BIN_FLOOR) / (b + BIN_FLOOR))
            .ln()
            .clamp(-MAX_LOG_RATIO, MAX_LOG_RATIO) as f32
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hue_saturation_and_value_bins() {
        let bins = ColourBins::colour(8, 8);
        assert_eq!(bins.len(), 72);
        // Pure red: hue 0, full saturation.
        assert_eq!(bins.of_rgb(255.0, 0.0, 0.0), 7);
        // Pure blue: hue 4/6 of the circle.
        assert_eq!(bins.of_rgb(0.0, 0.0, 255.0) as usize / 8, 5);
        // Grey and black go to the value bins.
        assert_eq!(bins.of_rgb(128.0, 128.0, 128.0), 64 + 4);
        assert_eq!(bins.of_rgb(10.0, 0.0, 0.0), 64);
        let grey = ColourBins::grey(16);
        assert_eq!(grey.of_grey(0.0), 0);
        assert_eq!(grey.of_grey(255.0), 15);
    }

    #[test]
    fn grey_stored_as_rgb_is_not_chromatic() {
        let grey: Vec<u8> = (0..300u32).flat_map(|k| [(k % 256) as u8; 3]).collect();
        assert!(!is_chromatic(&grey));
        let mut tinted = grey.clone();
        for px in tinted.chunks_exact_mut(3).step_by(5) {
            px[0] = 200;
            px[1] = 40;
        }
        assert!(is_chromatic(&tinted));
        assert!(!is_chromatic(&[]));
    }

    #[test]
    fn bhattacharyya_and_log_ratios() {
        let a = Histogram::from_counts(vec![1.0, 1.0, 0.0]).unwrap();
        let b = Histogram::from_counts(vec![0.0, 1.0, 1.0]).unwrap();
        assert!((a.bhattacharyya(&a) - 1.0).abs() < 1e-12);
        assert!((a.bhattacharyya(&b) - 0.5).abs() < 1e-12);
        let mut lr = Vec::new();
        log_ratios(&a, &b, &mut lr);
        assert!(lr[0] > 2.0 && lr[1].abs() < 1e-6 && lr[2] < -2.0);
        assert!(Histogram::from_counts(vec![0.0; 3]).is_none());
    }
}
