//! The colour model of the region tracker: HSV bins as in Pérez et al. 2002 (hue × saturation
//! for coloured pixels, value alone for dark or unsaturated ones, where hue means nothing), grey
//! levels for grey frames, normalised histograms, and the per-bin log-ratio of the target's
//! histogram to the background's. Its thresholds and bounds are
//! [`HistogramSettings`](super::HistogramSettings).

use super::HistogramSettings;

/// How pixels map to histogram bins.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColourBins {
    hs: usize,
    value: usize,
    colour: bool,
    /// Saturation below which a pixel's hue is not trusted
    /// ([`HistogramSettings::min_saturation`]).
    min_saturation: f32,
    /// Value below which a pixel's hue is not trusted ([`HistogramSettings::min_value`]).
    min_value: f32,
}

impl ColourBins {
    /// Colour bins: `hs`×`hs` hue–saturation bins and `value` value bins, the hue trusted as
    /// `settings` say.
    pub fn colour(hs: usize, value: usize, settings: &HistogramSettings) -> Self {
        Self {
            hs,
            value,
            colour: true,
            min_saturation: settings.min_saturation as f32,
            min_value: settings.min_value as f32,
        }
    }

    /// Grey bins: `levels` grey-level bins. No hue is trusted: an RGB pixel goes to the bin of
    /// its value.
    pub fn grey(levels: usize) -> Self {
        Self {
            hs: 0,
            value: levels,
            colour: false,
            min_saturation: f32::INFINITY,
            min_value: f32::INFINITY,
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
        if s < self.min_saturation || v < self.min_value {
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
        let sb = (((s - self.min_saturation) / (1.0 - self.min_saturation) * self.hs as f32)
            as usize)
            .min(self.hs - 1);
        (hb * self.hs + sb) as u16
    }

    /// The bin of a grey level (0–255).
    pub fn of_grey(&self, g: f32) -> u16 {
        let v = (g / 256.0).clamp(0.0, 1.0);
        (self.hs * self.hs + ((v * self.value as f32) as usize).min(self.value - 1)) as u16
    }
}

/// Whether an interleaved RGB image (components 0–255) has colour worth histogramming: at least
/// [`HistogramSettings::min_chromatic_share`] of its pixels (read on a sparse lattice) have a
/// trusted hue (see [`ColourBins::of_rgb`]).
pub fn is_chromatic(rgb: &[u8], settings: &HistogramSettings) -> bool {
    // Every 7th pixel in raster order: the share is a proportion, estimated here from a frame's
    // thousands of pixels, and reading all of them would only sharpen the estimate, not change
    // what it estimates. A width that is not a multiple of 7 moves the lattice along from row to
    // row, so it does not keep to a few columns. A bound on the cost of one call at the first
    // frame, not a modelling choice: it stays a constant.
    const STRIDE: usize = 7;
    let (min_saturation, min_value) = (settings.min_saturation as f32, settings.min_value as f32);
    let (mut coloured, mut read) = (0usize, 0usize);
    for px in rgb.chunks_exact(3).step_by(STRIDE) {
        let [r, g, b] = [px[0], px[1], px[2]].map(f32::from);
        let max = r.max(g).max(b);
        let min = r.min(g).min(b);
        read += 1;
        if max / 255.0 >= min_value && (max - min) / max >= min_saturation {
            coloured += 1;
        }
    }
    read > 0 && coloured as f64 >= settings.min_chromatic_share * read as f64
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

/// The log-ratio ln((p_target + ε) / (p_background + ε)) of every bin, bounded by ±M nats: the
/// evidence one pixel of that bin gives for the target against the background (ε
/// [`HistogramSettings::bin_floor`], M [`HistogramSettings::max_log_ratio`]).
pub fn log_ratios(
    target: &Histogram,
    background: &Histogram,
    settings: &HistogramSettings,
    out: &mut Vec<f32>,
) {
    let (floor, bound) = (settings.bin_floor, settings.max_log_ratio);
    out.clear();
    out.extend(
        target
            .mass
            .iter()
            .zip(&background.mass)
            .map(|(t, b)| ((t + floor) / (b + floor)).ln().clamp(-bound, bound) as f32),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hue_saturation_and_value_bins() {
        let bins = ColourBins::colour(8, 8, &HistogramSettings::default());
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
        // Grey bins trust no hue: pure red goes to the bin of its value.
        assert_eq!(grey.of_rgb(255.0, 0.0, 0.0), 15);
    }

    #[test]
    fn the_hue_thresholds_are_read_from_the_settings() {
        let default = HistogramSettings::default();
        // The defaults are Pérez et al.'s, exactly as single-precision numbers.
        let bins = ColourBins::colour(8, 8, &default);
        assert_eq!((bins.min_saturation, bins.min_value), (0.1, 0.2));
        // A dark red (value 0.16) and a pale red (saturation 0.075): no trusted hue by default.
        let dark = [40.0, 0.0, 0.0];
        let pale = [200.0, 185.0, 185.0];
        let hue = |b: &ColourBins, [r, g, bl]: [f32; 3]| usize::from(b.of_rgb(r, g, bl)) < 64;
        assert!(!hue(&bins, dark) && !hue(&bins, pale));
        let darker = ColourBins::colour(
            8,
            8,
            &HistogramSettings {
                min_value: 0.1,
                ..default
            },
        );
        assert!(hue(&darker, dark) && !hue(&darker, pale));
        let paler = ColourBins::colour(
            8,
            8,
            &HistogramSettings {
                min_saturation: 0.05,
                ..default
            },
        );
        assert!(!hue(&paler, dark) && hue(&paler, pale));
        // Saturation bins span the threshold to 1: saturation 0.2 is in the first of 8 from 0.1,
        // in the second from 0.
        assert_eq!(bins.of_rgb(200.0, 160.0, 160.0) % 8, 0);
        let all = HistogramSettings {
            min_saturation: 0.0,
            ..default
        };
        assert_eq!(
            ColourBins::colour(8, 8, &all).of_rgb(200.0, 160.0, 160.0) % 8,
            1
        );
    }

    #[test]
    fn grey_stored_as_rgb_is_not_chromatic() {
        let s = HistogramSettings::default();
        let grey: Vec<u8> = (0..300u32).flat_map(|k| [(k % 256) as u8; 3]).collect();
        assert!(!is_chromatic(&grey, &s));
        let mut tinted = grey.clone();
        for px in tinted.chunks_exact_mut(3).step_by(5) {
            px[0] = 200;
            px[1] = 40;
        }
        assert!(is_chromatic(&tinted, &s));
        assert!(!is_chromatic(&[], &s));
        // A tint on one pixel in 140 (3 of the 43 read) is colour at a share of 2 %, not at 10 %.
        let mut faint = grey.clone();
        for px in faint.chunks_exact_mut(3).step_by(140) {
            px[0] = 200;
            px[1] = 40;
        }
        assert!(is_chromatic(&faint, &s));
        let strict = HistogramSettings {
            min_chromatic_share: 0.1,
            ..s
        };
        assert!(!is_chromatic(&faint, &strict) && is_chromatic(&tinted, &strict));
    }

    #[test]
    fn bhattacharyya_and_log_ratios() {
        let a = Histogram::from_counts(vec![1.0, 1.0, 0.0]).unwrap();
        let b = Histogram::from_counts(vec![0.0, 1.0, 1.0]).unwrap();
        assert!((a.bhattacharyya(&a) - 1.0).abs() < 1e-12);
        assert!((a.bhattacharyya(&b) - 0.5).abs() < 1e-12);
        let s = HistogramSettings::default();
        let mut lr = Vec::new();
        log_ratios(&a, &b, &s, &mut lr);
        assert!(lr[0] > 2.0 && lr[1].abs() < 1e-6 && lr[2] < -2.0);
        assert!(Histogram::from_counts(vec![0.0; 3]).is_none());
    }

    #[test]
    fn the_log_ratio_bound_and_floor_are_read_from_the_settings() {
        // A bin the background never shows: ln((0.5 + 1e-3) / 1e-3) ≈ 6.2 nats, bounded by 3.
        let t = Histogram::from_counts(vec![1.0, 1.0, 0.0]).unwrap();
        let b = Histogram::from_counts(vec![0.0, 1.0, 1.0]).unwrap();
        let s = HistogramSettings::default();
        let mut lr = Vec::new();
        log_ratios(&t, &b, &s, &mut lr);
        assert_eq!((lr[0], lr[2]), (3.0, -3.0));
        let wide = HistogramSettings {
            max_log_ratio: 10.0,
            ..s
        };
        log_ratios(&t, &b, &wide, &mut lr);
        let unbounded = (0.501f64 / 0.001).ln() as f32;
        assert!(lr[0] > 3.0 && (lr[0] - unbounded).abs() < 1e-5, "{}", lr[0]);
        assert!((lr[2] + unbounded).abs() < 1e-5, "{}", lr[2]);
        // A larger floor pulls every log-ratio towards 0: ln(0.6 / 0.1).
        let floored = HistogramSettings {
            bin_floor: 0.1,
            ..wide
        };
        log_ratios(&t, &b, &floored, &mut lr);
        assert!((lr[0] - 6.0f32.ln()).abs() < 1e-6, "{}", lr[0]);
    }
}
