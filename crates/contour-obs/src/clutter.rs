//! Clutter learning (Wu §6.1): random measurement lines over training images, edges per pixel of
//! line, k-means on these densities → a Gaussian per cluster, p(λ | β = k) = G(λ̄_k, σ_λk).

use nalgebra::Vector2;
use rand::Rng;
use serde::{Deserialize, Serialize};
use vision_core::GreyImage;

use crate::{EdgeSettings, Error, LineSettings, MeasurementLines, Result};

/// Settings of clutter learning.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ClutterSettings {
    /// Number of random lines over all images. Default 20,000 (Wu §6.1).
    pub lines: usize,
    /// Number of clusters k. Default 3 (Wu §6.1).
    pub k: usize,
    /// Line length L in pixels (even). Default 20, as the trackers' lines.
    pub length: usize,
    /// The edge detector. Default: the workspace convention.
    pub edge: EdgeSettings,
    /// Maximum Lloyd iterations of k-means. Default 100 (1-D k-means converges in a handful).
    pub max_iterations: usize,
}

impl Default for ClutterSettings {
    fn default() -> Self {
        Self {
            lines: 20_000,
            k: 3,
            length: 20,
            edge: EdgeSettings::default(),
            max_iterations: 100,
        }
    }
}

impl ClutterSettings {
    /// Checks lines ≥ k ≥ 1, max_iterations ≥ 1, and the line geometry.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the field.
    pub fn validate(&self) -> Result<()> {
        if self.k == 0 {
            return Err(Error::InvalidSetting {
                name: "k",
                reason: "must be at least 1".into(),
            });
        }
        if self.lines < self.k {
            return Err(Error::InvalidSetting {
                name: "lines",
                reason: format!("must be at least k = {}, got {}", self.k, self.lines),
            });
        }
        if self.max_iterations == 0 {
            return Err(Error::InvalidSetting {
                name: "max_iterations",
                reason: "must be at least 1".into(),
            });
        }
        self.line_settings().validate()
    }

    fn line_settings(&self) -> LineSettings {
        LineSettings {
            n_lines: 3,
            length: self.length,
            edge: self.edge,
            min_observed_fraction: 1.0,
        }
    }
}

/// One clutter class: λ̄_k, σ_λk and the share of lines in it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Cluster {
    /// Mean edge density λ̄_k, edges per pixel.
    pub mean: f64,
    /// Standard deviation σ_λk of the densities in the cluster (population form).
    pub std: f64,
    /// Fraction of the lines in the cluster.
    pub weight: f64,
}

/// Learnt clutter classes, sorted by increasing mean. Serialises as
/// `{"clusters": [{"mean": …, "std": …, "weight": …}, …]}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClutterModel {
    /// The clusters, by increasing mean.
    pub clusters: Vec<Cluster>,
}

impl ClutterModel {
    /// Pretty JSON.
    ///
    /// # Errors
    /// Never in practice (serde_json on plain numbers); non-finite numbers become `null`.
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string_pretty(self).map_err(|e| Error::Degenerate {
            reason: e.to_string(),
        })
    }

    /// Parses JSON written by [`Self::to_json`].
    ///
    /// # Errors
    /// [`Error::Degenerate`] with the parser's message.
    pub fn from_json(s: &str) -> Result<Self> {
        serde_json::from_str(s).map_err(|e| Error::Degenerate {
            reason: e.to_string(),
        })
    }
}

/// Edge densities (edges per pixel, count/L) of `settings.lines` random lines. Each line picks an
/// image with probability proportional to its usable area, a centre uniformly among positions
/// where the whole line fits in the image at any angle, and a uniform direction.
///
/// # Errors
/// [`Error::NoImages`]; [`Error::ImageTooSmall`] when an image cannot hold a line; invalid
/// settings.
pub fn line_densities<R: Rng + ?Sized>(
    images: &[GreyImage<'_>],
    settings: &ClutterSettings,
    rng: &mut R,
) -> Result<Vec<f64>> {
    settings.validate()?;
    if images.is_empty() {
        return Err(Error::NoImages);
    }
    let mut ws = MeasurementLines::new(&settings.line_settings())?;
    // Sampled offsets reach L/2 + 1 + r; keep that many pixels (plus a guard) from the border.
    let margin = (settings.length / 2 + 2 + settings.edge.radius()) as f64;
    let min = 2 * margin as usize + 2;
    let mut areas = Vec::with_capacity(images.len());
    for im in images {
        if im.width() < min || im.height() < min {
            return Err(Error::ImageTooSmall {
                width: im.width(),
                height: im.height(),
                min,
            });
        }
        areas.push((im.width() as f64 - 2.0 * margin) * (im.height() as f64 - 2.0 * margin));
    }
    let total: f64 = areas.iter().sum();
    let mut out = Vec::with_capacity(settings.lines);
    for _ in 0..settings.lines {
        let mut u = rng.random::<f64>() * total;
        let mut idx = images.len() - 1;
        for (i, a) in areas.iter().enumerate() {
            if u < *a {
                idx = i;
                break;
            }
            u -= a;
        }
        let im = &images[idx];
        let cx = rng.random_range(margin..im.width() as f64 - 1.0 - margin);
        let cy = rng.random_range(margin..im.height() as f64 - 1.0 - margin);
        let angle = rng.random_range(0.0..std::f64::consts::TAU);
        ws.clear();
        ws.push_line(
            im,
            Vector2::new(cx, cy),
            Some(Vector2::new(angle.cos(), angle.sin())),
        );
        out.push(ws.edges(0).len() as f64 / settings.length as f64);
    }
    Ok(out)
}

/// Clutter learning (Wu §6.1): [`line_densities`] then [`kmeans_1d`].
///
/// # Errors
/// As [`line_densities`] and [`kmeans_1d`].
pub fn learn_clutter<R: Rng + ?Sized>(
    images: &[GreyImage<'_>],
    settings: &ClutterSettings,
    rng: &mut R,
) -> Result<ClutterModel> {
    let d = line_densities(images, settings, rng)?;
    let clusters = kmeans_1d(&d, settings.k, settings.max_iterations, rng)?;
    Ok(ClutterModel { clusters })
}

/// k-means on scalars with k-means++ initialisation (seeded through `rng`), Lloyd iterations until
/// no assignment changes or `max_iterations`. Returns the clusters sorted by mean.
///
/// # Errors
/// [`Error::NonFinite`] for a non-finite value; [`Error::TooFewDistinct`] when fewer than k
/// distinct values exist; [`Error::InvalidSetting`] for k = 0.
pub fn kmeans_1d<R: Rng + ?Sized>(
    values: &[f64],
    k: usize,
    max_iterations: usize,
    rng: &mut R,
) -> Result<Vec<Cluster>> {
    if k == 0 {
        return Err(Error::InvalidSetting {
            name: "k",
            reason: "must be at least 1".into(),
        });
    }
    if let Some(index) = values.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "k-means value",
            index,
        });
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    if sorted.len() < k {
        return Err(Error::TooFewDistinct {
            k,
            distinct: sorted.len(),
        });
    }
    // k-means++: first centre uniform, then each with probability ∝ squared distance to the
    // nearest chosen centre. With ≥ k distinct values the total never reaches 0 before k centres.
    let mut centres = Vec::with_capacity(k);
    centres.push(values[rng.random_range(0..values.len())]);
    let mut d2: Vec<f64> = values.iter().map(|v| (v - centres[0]).powi(2)).collect();
    while centres.len() < k {
        let total: f64 = d2.iter().sum();
        let mut u = rng.random::<f64>() * total;
        let mut pick = d2.iter().rposition(|d| *d > 0.0).unwrap_or(0);
        for (i, d) in d2.iter().enumerate() {
            if u < *d {
                pick = i;
                break;
            }
            u -= d;
        }
        let c = values[pick];
        centres.push(c);
        for (d, v) in d2.iter_mut().zip(values) {
            *d = d.min((v - c).powi(2));
        }
    }
    let mut assign = vec![usize::MAX; values.len()];
    for _ in 0..max_iterations {
        let mut changed = false;
        for (a, v) in assign.iter_mut().zip(values) {
            let best = nearest(&centres, *v);
            if *a != best {
                *a = best;
                changed = true;
            }
        }
        let mut sums = vec![(0.0, 0usize); k];
        for (a, v) in assign.iter().zip(values) {
            sums[*a].0 += v;
            sums[*a].1 += 1;
        }
        for (c, (s, n)) in centres.iter_mut().zip(&sums) {
            // An emptied cluster keeps its centre; it can win points back next round.
            if *n > 0 {
                *c = s / *n as f64;
            }
        }
        if !changed {
            break;
        }
    }
    let n = values.len() as f64;
    let mut clusters: Vec<Cluster> = (0..k)
        .map(|j| {
            let members = assign.iter().zip(values).filter(|(a, _)| **a == j);
            let (cnt, sum) = members
                .clone()
                .fold((0usize, 0.0), |(c, s), (_, v)| (c + 1, s + v));
            let mean = if cnt > 0 {
                sum / cnt as f64
            } else {
                centres[j]
            };
            let var = if cnt > 0 {
                members.map(|(_, v)| (v - mean).powi(2)).sum::<f64>() / cnt as f64
            } else {
                0.0
            };
            Cluster {
                mean,
                std: var.sqrt(),
                weight: cnt as f64 / n,
            }
        })
        .collect();
    clusters.sort_by(|a, b| a.mean.total_cmp(&b.mean));
    Ok(clusters)
}

fn nearest(centres: &[f64], v: f64) -> usize {
    let mut best = 0;
    for (j, c) in centres.iter().enumerate() {
        if (v - c).abs() < (v - centres[best]).abs() {
            best = j;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_pcg::Pcg64Mcg;

    #[test]
    fn kmeans_separates_three_groups() {
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        let mut v = Vec::new();
        for (c, n) in [(0.0, 50), (10.0, 30), (25.0, 20)] {
            for i in 0..n {
                v.push(c + (i % 5) as f64 - 2.0);
            }
        }
        let cl = kmeans_1d(&v, 3, 100, &mut rng).unwrap();
        // Each group is symmetric about its centre: exact means, weights, and std √2.
        for (got, (c, w)) in cl.iter().zip([(0.0, 0.5), (10.0, 0.3), (25.0, 0.2)]) {
            assert!((got.mean - c).abs() < 1e-12, "{cl:?}");
            assert!((got.weight - w).abs() < 1e-12);
            assert!((got.std - 2f64.sqrt()).abs() < 1e-12);
        }
    }

    #[test]
    fn kmeans_errors() {
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        assert!(matches!(
            kmeans_1d(&[1.0, 1.0, 2.0], 3, 10, &mut rng),
            Err(Error::TooFewDistinct { k: 3, distinct: 2 })
        ));
        assert!(kmeans_1d(&[1.0, f64::NAN], 1, 10, &mut rng).is_err());
    }

    #[test]
    fn json_shape() {
        let m = ClutterModel {
            clusters: vec![Cluster {
                mean: 0.5,
                std: 0.25,
                weight: 1.0,
            }],
        };
        let v: serde_json::Value = serde_json::from_str(&m.to_json().unwrap()).unwrap();
        assert_eq!(v["clusters"][0]["mean"], 0.5);
        assert_eq!(v["clusters"][0]["std"], 0.25);
        assert_eq!(v["clusters"][0]["weight"], 1.0);
        assert_eq!(ClutterModel::from_json(&m.to_json().unwrap()).unwrap(), m);
    }

    #[test]
    fn too_small_or_no_images() {
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        let s = ClutterSettings::default();
        assert!(matches!(
            line_densities(&[], &s, &mut rng),
            Err(Error::NoImages)
        ));
        let d = vec![0.0f32; 400];
        let im = GreyImage::new(20, 20, &d).unwrap();
        assert!(matches!(
            line_densities(&[im], &s, &mut rng),
            Err(Error::ImageTooSmall { .. })
        ));
    }
}
