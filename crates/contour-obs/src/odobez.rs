//! Odobez Eq. 19: the CONDENSATION shape likelihood, Π_l max(K, exp(−d_l²/2σ²)), d_l the offset
//! of the nearest edge on line l.

use serde::{Deserialize, Serialize};

use crate::{Affine2, Contour, Error, GreyView, LineSettings, MeasurementLines, Result, Template};

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
}

impl OdobezLikelihood {
    /// The likelihood for `template` sampled at `settings.lines.n_lines` points.
    ///
    /// # Errors
    /// Invalid settings or a degenerate template.
    pub fn new(settings: OdobezSettings, template: &Template) -> Result<Self> {
        settings.validate()?;
        let contour = Contour::new(template, settings.lines.n_lines)?;
        Ok(Self {
            ln_k: settings.k_floor.ln(),
            settings,
            contour,
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
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite pose.
    pub fn log_likelihood(
        &self,
        ws: &mut MeasurementLines,
        image: &GreyView<'_>,
        pose: &Affine2,
    ) -> Result<f64> {
        ensure_workspace(ws, &self.settings.lines)?;
        ws.extract(image, &self.contour, pose)?;
        Ok((0..ws.len())
            .map(|i| odobez_line_log_term(ws.edges(i), self.settings.sigma, self.ln_k))
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
        image: &GreyView<'_>,
        poses: &[Affine2],
        out: &mut [f64],
    ) -> Result<()> {
        check_len("out", poses.len(), out.len())?;
        for (index, (pose, o)) in poses.iter().zip(out.iter_mut()).enumerate() {
            *o = self
                .log_likelihood(ws, image, pose)
                .map_err(|e| with_index(e, index))?;
        }
        Ok(())
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
pub(crate) fn with_index(e: Error, index: usize) -> Error {
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
