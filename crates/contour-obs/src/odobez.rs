//! Odobez Eq. 19: the CONDENSATION shape likelihood, Π_l max(K, exp(−d_l²/2σ²)), d_l the offset
//! of the nearest edge on line l.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use vision_core::GreyImage;

use crate::{Affine2, Contour, Error, LineSettings, MeasurementLines, Result, Template};

/// Settings of Odobez's shape likelihood.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OdobezSettings {
    /// Measurement lines. Default: n = 15, L = 20 px.
    pub lines: LineSettings,
    /// σ of Eq. 19 in pixels. Default 2 px (the papers' shared setting).
    pub sigma: f64,
    /// The floor K of Eq. 19 for a line with no (near) edge. Default e⁻² ≈ 0.135: an edge
    /// farther than 2σ = 4 px scores the same as no edge. Beyond 2σ an edge is more likely clutter
    /// than the target, and a floor this high keeps one occluded or edgeless line from vetoing a
    /// hypothesis (a tiny K would make the product a count of missing lines).
    pub k_floor: f64,
}

impl Default for OdobezSettings {
    fn default() -> Self {
        Self {
            lines: LineSettings::default(),
            sigma: 2.0,
            k_floor: (-2.0f64).exp(),
        }
    }
}

impl OdobezSettings {
    /// Checks σ > 0 finite, K in (0, 1], and the line settings.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the field.
    pub fn validate(&self) -> Result<()> {
        self.lines.validate()?;
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            return Err(Error::InvalidSetting {
                name: "sigma",
                reason: format!("must be finite and positive, got {}", self.sigma),
            });
        }
        if !(self.k_floor > 0.0 && self.k_floor <= 1.0) {
            return Err(Error::InvalidSetting {
                name: "k_floor",
                reason: format!("must be in (0, 1], got {}", self.k_floor),
            });
        }
        Ok(())
    }
}

/// Log of one line's factor in Eq. 19: max(ln K, −d²/2σ²) with d the smallest |offset|; ln K when
/// there is no edge.
pub fn odobez_line_log_term(edges: &[f64], sigma: f64, ln_k: f64) -> f64 {
    let d2 = edges.iter().fold(f64::INFINITY, |m, z| m.min(z * z));
    (-d2 / (2.0 * sigma * sigma)).max(ln_k)
}

/// Odobez's shape likelihood for one contour template (immutable; the caller owns the
/// [`MeasurementLines`] workspace, one per thread).
#[derive(Debug, Clone)]
pub struct OdobezLikelihood {
    settings: OdobezSettings,
    contour: Contour,
    ln_k: f64,
    /// Edges at integer offsets |k| > `search` cannot beat the floor K (see [`Self::new`]).
    search: usize,
}

impl OdobezLikelihood {
    /// The likelihood for `template` sampled at `settings.lines.n_lines` points.
    ///
    /// # Errors
    /// Invalid settings or a degenerate template.
    pub fn new(settings: OdobezSettings, template: &Template) -> Result<Self> {
        settings.validate()?;
        let contour = Contour::new(template, settings.lines.n_lines)?;
        let ln_k = settings.k_floor.ln();
        // An edge scores above the floor only when −d²/2σ² > ln K, i.e. |d| < σ√(−2 ln K). A
        // detected edge lies within ½ px of its integer offset k, so |k| > σ√(−2 ln K) − ½ can
        // be skipped; the 1e−9 makes rounding err on the side of searching one ring more.
        let d_max = settings.sigma * (-2.0 * ln_k).sqrt();
        let search = (d_max - 0.5 + 1e-9)
            .ceil()
            .clamp(0.0, settings.lines.half_length() as f64) as usize;
        Ok(Self {
            ln_k,
            settings,
            contour,
            search,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &OdobezSettings {
        &self.settings
    }

    /// The sampled contour.
    pub fn contour(&self) -> &Contour {
        &self.contour
    }

    /// A fresh workspace for this likelihood.
    ///
    /// # Errors
    /// Never for validated settings.
    pub fn workspace(&self) -> Result<MeasurementLines> {
        MeasurementLines::new(&self.settings.lines)
    }

    /// log p_sh(z | pose) up to its constant: Σ_l max(ln K, −d_l²/2σ²) (Odobez Eq. 19). At most 0,
    /// at least n·ln K.
    ///
    /// Only the part of each line where an edge can score above the floor K is examined
    /// ([`MeasurementLines::nearest_edge_sq`]): the value is the one [`odobez_line_log_term`]
    /// gives on the edges of [`MeasurementLines::extract`], bit for bit, at a fraction of the
    /// cost. The workspace is left with no lines.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite pose; [`Error::ImageTooSmall`] for an image below
    /// 2×2 pixels.
    pub fn log_likelihood(
        &self,
        ws: &mut MeasurementLines,
        image: &GreyImage<'_>,
        pose: &Affine2,
    ) -> Result<f64> {
        ensure_workspace(ws, &self.settings.lines)?;
        crate::image::check_samplable(image)?;
        if !pose.is_finite() {
            return Err(Error::NonFinite {
                what: "pose",
                index: 0,
            });
        }
        ws.clear();
        let (sigma, ln_k) = (self.settings.sigma, self.ln_k);
        let search = self.search as i64;
        ws.scan_lines(image, &self.contour, pose, -search, search);
        Ok((0..self.contour.len())
            .map(|i| {
                let d2 = ws.nearest_planned(image, i, search);
                // As odobez_line_log_term on the nearest edge. Without one (d2 = +∞) that is
                // max(−∞, ln K) = ln K: the division is skipped.
                if d2 == f64::INFINITY {
                    ln_k
                } else {
                    (-d2 / (2.0 * sigma * sigma)).max(ln_k)
                }
            })
            .sum())
    }

    /// [`Self::log_likelihood`] for every pose, into `out`.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] when `out.len() != poses.len()`; [`Error::NonFinite`] with the
    /// index of the first non-finite pose.
    pub fn log_likelihood_batch(
        &self,
        ws: &mut MeasurementLines,
        image: &GreyImage<'_>,
        poses: &[Affine2],
        out: &mut [f64],
    ) -> Result<()> {
        let mode = Batch::Sequential(ws);
        run_batch(mode, poses, [], out, |ws, pose, []| {
            self.log_likelihood(ws, image, pose)
        })
    }

    /// [`Self::log_likelihood_batch`] on the rayon thread pool, one workspace per task
    /// (allocated per call). Results are bit-identical to the sequential batch, and so is the
    /// error (that of the lowest failing index). Worth it when cores are free; on a busy machine
    /// the sequential batch with a reused workspace can be as fast.
    ///
    /// # Errors
    /// As [`Self::log_likelihood_batch`].
    pub fn log_likelihood_batch_par(
        &self,
        image: &GreyImage<'_>,
        poses: &[Affine2],
        out: &mut [f64],
    ) -> Result<()> {
        let mode = Batch::Parallel(&self.settings.lines);
        run_batch(mode, poses, [], out, |ws, pose, []| {
            self.log_likelihood(ws, image, pose)
        })
    }
}

/// The most hypotheses per rayon task in the parallel batches.
const PAR_CHUNK: usize = 16;

/// Rayon tasks per thread that a parallel batch aims at: enough that a thread slowed down by
/// other work leaves little for the others to wait on at the end.
const PAR_TASKS_PER_THREAD: usize = 16;

/// Hypotheses per rayon task for a batch of `n`: `n` spread over [`PAR_TASKS_PER_THREAD`] tasks
/// per thread, between 2 (a task must outweigh its scheduling) and [`PAR_CHUNK`].
fn par_chunk(n: usize) -> usize {
    let tasks = rayon::current_num_threads().max(1) * PAR_TASKS_PER_THREAD;
    n.div_ceil(tasks).clamp(2, PAR_CHUNK)
}

/// How [`run_batch`] evaluates its hypotheses.
pub(crate) enum Batch<'a> {
    /// In order, on the caller's workspace, stopping at the first error.
    Sequential(&'a mut MeasurementLines),
    /// On the rayon thread pool over chunks of [`par_chunk`] hypotheses, each chunk sequential
    /// inside and with its own workspace for these line settings.
    Parallel(&'a LineSettings),
}

/// The batch driver behind every likelihood's `log_likelihood_batch` and
/// `log_likelihood_batch_par`: `out[i] = eval(ws, &poses[i], [p[i] for each parameter p])`.
///
/// `params` are named per-hypothesis parameters, each holding one value shared by every pose or
/// one value per pose. Lengths are checked first (`out`, then each parameter in order), and a
/// per-pose error gets the index of its hypothesis. Both modes compute each value the same way,
/// so their results are bit-identical, and both return the error of the lowest failing index.
pub(crate) fn run_batch<const P: usize, F>(
    mode: Batch<'_>,
    poses: &[Affine2],
    params: [(&'static str, &[f64]); P],
    out: &mut [f64],
    eval: F,
) -> Result<()>
where
    F: Fn(&mut MeasurementLines, &Affine2, [f64; P]) -> Result<f64> + Sync,
{
    let n = poses.len();
    check_len("out", n, out.len())?;
    for (what, values) in params {
        if values.len() != 1 {
            check_len(what, n, values.len())?;
        }
    }
    let one = |ws: &mut MeasurementLines, index: usize| {
        let picked = params.map(|(_, values)| values[if values.len() == 1 { 0 } else { index }]);
        eval(ws, &poses[index], picked).map_err(|e| with_index(e, index))
    };
    match mode {
        Batch::Sequential(ws) => {
            for (index, o) in out.iter_mut().enumerate() {
                *o = one(ws, index)?;
            }
            Ok(())
        }
        Batch::Parallel(lines) => {
            // One workspace per rayon job (a few per thread, not one per chunk): its scan
            // buffers are allocated on first use.
            let size = par_chunk(n);
            let results: Vec<Result<()>> = out
                .par_chunks_mut(size)
                .enumerate()
                .map_init(
                    || MeasurementLines::new(lines),
                    |ws, (chunk, o)| {
                        let ws = ws.as_mut().map_err(|e| e.clone())?;
                        for (j, v) in o.iter_mut().enumerate() {
                            *v = one(ws, chunk * size + j)?;
                        }
                        Ok(())
                    },
                )
                .collect();
            results.into_iter().collect()
        }
    }
}

/// Re-creates the workspace if it was built for other line settings (allocates only then).
pub(crate) fn ensure_workspace(ws: &mut MeasurementLines, lines: &LineSettings) -> Result<()> {
    if ws.settings() != lines {
        *ws = MeasurementLines::new(lines)?;
    }
    Ok(())
}

pub(crate) fn check_len(what: &'static str, expected: usize, got: usize) -> Result<()> {
    if expected != got {
        return Err(Error::LengthMismatch {
            what,
            expected,
            got,
        });
    }
    Ok(())
}

/// Puts the hypothesis index into a per-pose error.
fn with_index(e: Error, index: usize) -> Error {
    match e {
        Error::NonFinite { what, .. } => Error::NonFinite { what, index },
        Error::OutOfRange {
            what, value, range, ..
        } => Error::OutOfRange {
            what,
            index,
            value,
            range,
        },
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_term() {
        let ln_k = -2.0;
        assert_eq!(odobez_line_log_term(&[], 2.0, ln_k), ln_k);
        // Nearest edge 1 px: −1/8.
        assert_eq!(odobez_line_log_term(&[-6.0, 1.0, 3.0], 2.0, -2.0), -0.125);
        assert_eq!(odobez_line_log_term(&[9.0], 2.0, -2.0), -2.0);
    }

    #[test]
    fn settings_validate() {
        assert!(OdobezSettings::default().validate().is_ok());
        let bad = OdobezSettings {
            k_floor: 0.0,
            ..Default::default()
        };
        assert!(bad.validate().is_err());
    }
}
