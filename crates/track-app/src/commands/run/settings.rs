//! `track run`'s settings: the parsers of its options and the tracker configuration they give
//! (shared with the other commands that run trackers).

use std::path::Path;

use trackers::{Preset, TrackerConfig};
use vision_core::{BoundingBox, Ellipse};

use super::{DEFAULT_PARTICLES, DEFAULT_SEED};
use crate::groundtruth::{parse_box_arg, parse_ellipse_arg};
use crate::{AppError, Result};

/// Parses `--init x,y,w,h` for clap.
///
/// # Errors
/// The message of [`parse_box_arg`].
pub fn parse_box(s: &str) -> std::result::Result<BoundingBox, String> {
    parse_box_arg(s, "--init").map_err(|e| e.to_string())
}

/// Largest `--edge-threshold`: a grey-level step of 255 across one pixel, the steepest edge an
/// 8-bit frame can hold, is far below it; a larger threshold finds no edge at all.
pub const MAX_EDGE_THRESHOLD: f64 = 1000.0;

/// Parses `--edge-threshold` for clap: a number in (0, [`MAX_EDGE_THRESHOLD`]], reported as the
/// user typed it when it is out of range.
///
/// # Errors
/// A message that names the value and the range.
pub fn parse_edge_threshold(s: &str) -> std::result::Result<f32, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s} is not a number of grey levels per pixel"))?;
    if !(v.is_finite() && v > 0.0 && v <= MAX_EDGE_THRESHOLD) {
        return Err(format!(
            "{s} is out of range: give a number of grey levels per pixel in (0, {MAX_EDGE_THRESHOLD}]"
        ));
    }
    Ok(v as f32)
}

/// Parses `--init-ellipse cx,cy,a,b,angle` (angle in radians) for clap.
///
/// # Errors
/// The message of [`parse_ellipse_arg`].
pub fn parse_ellipse(s: &str) -> std::result::Result<Ellipse, String> {
    parse_ellipse_arg(s, "--init-ellipse").map_err(|e| e.to_string())
}

/// Command-line settings applied on top of a preset or a configuration file.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Overrides {
    /// `--particles`.
    pub particles: Option<usize>,
    /// `--seed`.
    pub seed: Option<u64>,
    /// `--parallel`.
    pub parallel: bool,
    /// `--edge-threshold`: the 1-D edge detector's threshold in grey levels per pixel, for every
    /// measurement-line term; refused for a tracker without measurement lines.
    pub edge_threshold: Option<f32>,
}

/// The tracker configuration from `--config` or the preset, with the command-line overrides
/// applied, validated.
///
/// Each error names what is at fault: the configuration file (`--config`) or the preset
/// (`--tracker`) for their own values, and the option for an override (`--particles`,
/// `--edge-threshold`), so a bad override is never blamed on the file.
///
/// # Errors
/// [`AppError::InvalidSetting`] (exit 2) for an unknown preset, a configuration file that cannot
/// be read or parsed or holds an invalid value (the file is a setting, like the options that
/// override it), or an invalid override (`--edge-threshold` for a tracker without measurement
/// lines, which would not read it).
pub fn tracker_config(preset: &str, config: Option<&Path>, o: Overrides) -> Result<TrackerConfig> {
    let mut c = match config {
        Some(path) => {
            let c = load_config(path)?;
            c.validate()
                .map_err(|e| config_error(path, e.to_string()))?;
            c
        }
        None => {
            let c = Preset::from_name(preset)
                .map_err(|e| AppError::setting("--tracker", e.to_string()))?
                .config(DEFAULT_PARTICLES, DEFAULT_SEED);
            c.validate()
                .map_err(|e| AppError::setting("--tracker", e.to_string()))?;
            c
        }
    };
    if let Some(s) = o.seed {
        c.seed = s;
    }
    c.filter.parallel |= o.parallel;
    if let Some(n) = o.particles {
        c.particles = n;
        c.validate()
            .map_err(|e| AppError::setting("--particles", e.to_string()))?;
    }
    if let Some(t) = o.edge_threshold {
        if !(t.is_finite() && t > 0.0) {
            return Err(AppError::setting(
                "--edge-threshold",
                format!("{t} is not a finite positive number of grey levels per pixel"),
            ));
        }
        // Refused, not ignored, for a tracker without measurement lines (head).
        c.set_edge_threshold(t).map_err(|e| match e {
            trackers::Error::InvalidSetting { reason, .. } => {
                AppError::setting("--edge-threshold", reason)
            }
            other => AppError::setting("--edge-threshold", other.to_string()),
        })?;
        c.validate()
            .map_err(|e| AppError::setting("--edge-threshold", e.to_string()))?;
    }
    Ok(c)
}

/// An error in the configuration file `path`: exit 2, naming `--config` and the file.
fn config_error(path: &Path, reason: impl std::fmt::Display) -> AppError {
    AppError::setting("--config", format!("{}: {reason}", path.display()))
}

fn load_config(path: &Path) -> Result<TrackerConfig> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| config_error(path, format!("cannot read the configuration: {e}")))?;
    TrackerConfig::parse(&text, trackers::ConfigFormat::of_path(path))
        .map_err(|reason| config_error(path, reason))
}

/// Largest difference, in radians, between an `--init-ellipse` angle and a multiple of π/2 that
/// an axis-aligned tracker accepts as that multiple (the library's constant).
pub use trackers::AXIS_ANGLE_TOLERANCE;

/// The ellipse `e` as the tracker of `config` can start from it, exactly: the library's
/// [`TrackerConfig::initial_ellipse`] (a rotated ellipse is refused by trackers of axis-aligned
/// ellipses), checked here so that the error names the option.
///
/// # Errors
/// [`AppError::InvalidSetting`] naming `--init-ellipse` for a rotated, non-circular ellipse and a
/// tracker that cannot rotate.
pub fn initial_ellipse_for(e: &Ellipse, config: &TrackerConfig) -> Result<Ellipse> {
    config.initial_ellipse(e).map_err(|err| match err {
        trackers::Error::InvalidSetting { reason, .. } => {
            AppError::setting("--init-ellipse", reason)
        }
        other => AppError::setting("--init-ellipse", other.to_string()),
    })
}
