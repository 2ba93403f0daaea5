//! A stress suite laid over real footage (`cargo xtask stress`): each failure class the
//! development clips show only here and there, laid over every clip, with the ground truth
//! mapped exactly.
//!
//! A [`Transform`] stands for one class:
//! - [`Shake`] (`shake`): abrupt camera motion — jumps of 1–2 target radii every few frames,
//!   with reversals and motion blur, in a crop of a slightly zoomed frame;
//! - [`Occlude`] (`occlude`): textured occluders cut from other clips' frames slide over
//!   30–70 % of the head's box for stretches of 20–100 frames;
//! - [`Tilt`] (`tilt`): in-plane rotation about the target, swinging to ±45°;
//! - `grey`: colour removed (BT.601 luma, Y = 0.299 R + 0.587 G + 0.114 B, in every channel);
//! - [`Small`] (`small`): the frame downscaled until the target is about 20 px wide;
//! - [`Light`] (`light`): gain and gamma ramps and a moving illumination gradient, half to
//!   double brightness;
//! - [`Zoom`] (`zoom`): `camera-zoom`'s zoom ([`crate::camera_zoom`]).
//!
//! A [`Pipeline`] composes transforms in order (`grey,shake`: grey, then shake). [`plan`] lays
//! out a whole clip from its frame size, its ground truth, the donor frames occluders are cut
//! from, and a seed — the truth is mapped by the same geometry as the pixels, with no pixel read
//! — and [`Plan::apply`] then makes any frame from the clip's own frame, independently of every
//! other frame, so frames can be made in any order, on any number of threads, with identical
//! results. Everything is a pure function of the inputs, the settings and the seed.
//!
//! Geometric maps use the workspace's convention (pixel (i, j) centred at (i, j)); a box
//! (x, y, w, h) covers the pixel centres in [x, x + w) × [y, y + h).
//!
//! ```
//! use scene_synth::stress::{Pipeline, plan};
//! use vision_core::BoundingBox;
//! let pipeline: Pipeline = "grey,small".parse()?;
//! let truth = vec![Some(BoundingBox::new(40.0, 30.0, 40.0, 50.0)); 3];
//! let planned = plan(&pipeline, (160, 120), &truth, &[], 7)?;
//! assert_eq!(planned.size(), (80, 60)); // a 40 px wide target is halved to 20 px
//! let b = planned.truth()[0].unwrap();
//! assert!((b.w - 20.0).abs() < 1e-9 && (b.h - 25.0).abs() < 1e-9);
//! let frame = image::RgbImage::new(160, 120);
//! assert_eq!(planned.apply(0, &frame)?.dimensions(), (80, 60));
//! # Ok::<(), scene_synth::Error>(())
//! ```

use std::str::FromStr;

use image::RgbImage;
use image::imageops::{self, FilterType};
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;
use serde::{Deserialize, Serialize};
use vision_core::BoundingBox;

use crate::camera_zoom::{CameraZoom, Crop, Operator};
use crate::error::{Error, Result};

mod light;
mod occlude;
mod shake;
mod tilt;
mod warp;

pub use light::Light;
pub use occlude::Occlude;
pub use shake::Shake;
pub use tilt::{Tilt, rotated_ellipse_box};

/// The settings of `small`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Small {
    /// The target's width after downscaling, in pixels: the frame is scaled by
    /// min(1, target_px / the median labelled width). Default 20.
    pub target_px: f64,
}

impl Default for Small {
    fn default() -> Self {
        Self { target_px: 20.0 }
    }
}

/// The settings of `zoom`: `camera-zoom`'s ([`CameraZoom`]), and the share of the frame the
/// largest labelled box may fill at the zoom's peak.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Zoom {
    /// Z, the largest zoom (≥ 1), lowered per clip by `fill`. Default 2.
    pub max_zoom: f64,
    /// P, frames from one zoom-out to the next. Default 120.
    pub period: f64,
    /// The operator's share of the way to the target each frame. Default 0.1.
    pub follow: f64,
    /// The share of the frame's width and height the largest box may fill zoomed. Default 0.9.
    pub fill: f64,
}

impl Default for Zoom {
    fn default() -> Self {
        Self {
            max_zoom: 2.0,
            period: 120.0,
            follow: CameraZoom::DEFAULT_FOLLOW,
            fill: 0.9,
        }
    }
}

/// One transform of the suite, with its settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "name", content = "settings", rename_all = "lowercase")]
pub enum Transform {
    /// Abrupt camera motion.
    Shake(Shake),
    /// Partial occlusion by textured occluders from other clips.
    Occlude(Occlude),
    /// In-plane rotation about the target.
    Tilt(Tilt),
    /// Colour removed (BT.601 luma).
    Grey,
    /// A small target: the frame downscaled.
    Small(Small),
    /// Lighting changes.
    Light(Light),
    /// `camera-zoom`'s zoom.
    Zoom(Zoom),
}

impl Transform {
    /// Every transform's name, in the suite's order.
    pub const NAMES: [&'static str; 7] =
        ["shake", "occlude", "tilt", "grey", "small", "light", "zoom"];

    /// The transform's name.
    pub fn name(&self) -> &'static str {
        match self {
            Transform::Shake(_) => "shake",
            Transform::Occlude(_) => "occlude",
            Transform::Tilt(_) => "tilt",
            Transform::Grey => "grey",
            Transform::Small(_) => "small",
            Transform::Light(_) => "light",
            Transform::Zoom(_) => "zoom",
        }
    }

    /// The failure class the transform stands for.
    pub fn class(&self) -> &'static str {
        match self {
            Transform::Shake(_) => {
                "abrupt motion: jumps of 1–2 target radii with reversals and blur"
            }
            Transform::Occlude(_) => {
                "partial occlusion: 30–70 % of the head covered for 20–100 frames"
            }
            Transform::Tilt(_) => "in-plane tilt: the picture turned about the head to ±45°",
            Transform::Grey => "grey footage",
            Transform::Small(_) => "small targets: about 20 px wide",
            Transform::Light(_) => "lighting changes: half to double brightness, moving gradient",
            Transform::Zoom(_) => "scale change: a camera zoom to 2× and back",
        }
    }

    /// Checks the settings against their documented ranges.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first field out of range.
    pub fn validate(&self) -> Result<()> {
        match self {
            Transform::Shake(s) => s.validate(),
            Transform::Occlude(s) => s.validate(),
            Transform::Tilt(s) => s.validate(),
            Transform::Grey => Ok(()),
            Transform::Small(s) => {
                if s.target_px.is_finite() && s.target_px >= 2.0 {
                    Ok(())
                } else {
                    bad("small.target_px", "must be a finite number ≥ 2")
                }
            }
            Transform::Light(s) => s.validate(),
            Transform::Zoom(s) => {
                if !(s.fill > 0.0 && s.fill <= 1.0) {
                    return bad("zoom.fill", "must lie in (0, 1]");
                }
                CameraZoom {
                    max_zoom: s.max_zoom,
                    period: s.period,
                    follow: s.follow,
                }
                .validate()
            }
        }
    }

    /// The same transform with one setting replaced: `field` and a JSON value, e.g.
    /// `("zoom", "1.3")` for `shake`.
    ///
    /// # Errors
    /// [`Error::Override`] for an unknown field or a value of the wrong type, and
    /// [`Error::InvalidParameter`] for a value out of range.
    pub fn with_setting(&self, field: &str, value: &str) -> Result<Self> {
        let over = |reason: String| Error::Override { reason };
        let value: serde_json::Value = serde_json::from_str(value).map_err(|e| {
            over(format!(
                "{}.{field}: `{value}` is not JSON: {e}",
                self.name()
            ))
        })?;
        let mut whole = serde_json::to_value(self)?;
        let settings = whole
            .get_mut("settings")
            .and_then(serde_json::Value::as_object_mut)
            .ok_or_else(|| over(format!("{} has no settings", self.name())))?;
        if !settings.contains_key(field) {
            let known: Vec<&String> = settings.keys().collect();
            return Err(over(format!(
                "{} has no setting `{field}` (it has: {known:?})",
                self.name()
            )));
        }
        settings.insert(field.to_owned(), value);
        let t: Transform = serde_json::from_value(whole)
            .map_err(|e| over(format!("{}.{field}: {e}", self.name())))?;
        t.validate()?;
        Ok(t)
    }
}

impl FromStr for Transform {
    type Err = Error;

    /// A transform by name, with its default settings.
    fn from_str(s: &str) -> Result<Self> {
        Ok(match s.trim() {
            "shake" => Transform::Shake(Shake::default()),
            "occlude" => Transform::Occlude(Occlude::default()),
            "tilt" => Transform::Tilt(Tilt::default()),
            "grey" | "gray" => Transform::Grey,
            "small" => Transform::Small(Small::default()),
            "light" => Transform::Light(Light::default()),
            "zoom" => Transform::Zoom(Zoom::default()),
            other => {
                return Err(Error::InvalidParameter {
                    name: "transform",
                    reason: format!(
                        "unknown transform `{other}` (expected one of: {})",
                        Transform::NAMES.join(", ")
                    ),
                });
            }
        })
    }
}

/// Transforms applied in order, each to the previous one's frames and truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Pipeline {
    /// The transforms, first applied first.
    pub stages: Vec<Transform>,
}

impl Pipeline {
    /// The pipeline's name: its transforms' names joined by `+` (`grey+shake`), the name of its
    /// folder in a suite.
    pub fn name(&self) -> String {
        self.stages
            .iter()
            .map(Transform::name)
            .collect::<Vec<_>>()
            .join("+")
    }

    /// Whether a stage needs donor frames (`occlude`).
    pub fn needs_donors(&self) -> bool {
        self.stages
            .iter()
            .any(|t| matches!(t, Transform::Occlude(_)))
    }
}

impl FromStr for Pipeline {
    type Err = Error;

    /// Transform names separated by commas or `+`: `grey,shake`.
    fn from_str(s: &str) -> Result<Self> {
        let stages = s
            .split([',', '+'])
            .map(str::parse)
            .collect::<Result<Vec<Transform>>>()?;
        if stages.is_empty() {
            return bad("transform", "no transform named");
        }
        Ok(Self { stages })
    }
}

/// A frame occluders may be cut from, with its target's box (kept clear of every cut).
#[derive(Debug, Clone)]
pub struct Donor {
    /// The frame.
    pub frame: RgbImage,
    /// Its labelled target, `None` when unlabelled (then any region may be cut).
    pub target: Option<BoundingBox>,
}

/// One stage laid out over a clip.
#[derive(Debug, Clone)]
enum StagePlan {
    Shake(shake::ShakePlan),
    Occlude(occlude::OccludePlan),
    Tilt(tilt::TiltPlan),
    Grey,
    Small {
        size: (u32, u32),
        scale: (f64, f64),
    },
    Light(light::LightPlan),
    Zoom {
        crops: Vec<Crop>,
        fitted: CameraZoom,
    },
}

impl StagePlan {
    fn map_box(&self, k: usize, b: &BoundingBox) -> BoundingBox {
        match self {
            StagePlan::Shake(p) => p.map_box(k, b),
            StagePlan::Tilt(p) => p.map_box(k, b),
            StagePlan::Small { scale, .. } => BoundingBox::new(
                (b.x + 0.5) * scale.0 - 0.5,
                (b.y + 0.5) * scale.1 - 0.5,
                b.w * scale.0,
                b.h * scale.1,
            ),
            StagePlan::Zoom { crops, .. } => crops[k].map_box(b),
            StagePlan::Occlude(_) | StagePlan::Grey | StagePlan::Light(_) => *b,
        }
    }

    fn apply(&self, k: usize, mut frame: RgbImage) -> Result<RgbImage> {
        Ok(match self {
            StagePlan::Shake(p) => p.apply(k, &frame),
            StagePlan::Tilt(p) => p.apply(k, &frame),
            StagePlan::Small { size, .. } => {
                imageops::resize(&frame, size.0, size.1, FilterType::Triangle)
            }
            StagePlan::Zoom { crops, .. } => crops[k].apply(&frame)?,
            StagePlan::Occlude(p) => {
                p.apply(k, &mut frame);
                frame
            }
            StagePlan::Light(p) => {
                p.apply(k, &mut frame);
                frame
            }
            StagePlan::Grey => {
                for p in frame.pixels_mut() {
                    let [r, g, b] = p.0.map(u32::from);
                    let y = ((299 * r + 587 * g + 114 * b + 500) / 1000) as u8;
                    p.0 = [y; 3];
                }
                frame
            }
        })
    }

    fn describe(&self) -> serde_json::Value {
        match self {
            StagePlan::Shake(p) => p.describe(),
            StagePlan::Occlude(p) => p.describe(),
            StagePlan::Tilt(p) => p.describe(),
            StagePlan::Grey => serde_json::json!({}),
            StagePlan::Small { size, scale } => {
                serde_json::json!({ "size": [size.0, size.1], "scale": [scale.0, scale.1] })
            }
            StagePlan::Light(p) => p.describe(),
            StagePlan::Zoom { fitted, .. } => {
                serde_json::json!({ "fitted_max_zoom": fitted.max_zoom })
            }
        }
    }
}

/// A pipeline laid out over one clip: the mapped truth, and what each frame needs.
#[derive(Debug, Clone)]
pub struct Plan {
    stages: Vec<StagePlan>,
    seeds: Vec<u64>,
    input: (u32, u32),
    size: (u32, u32),
    truth: Vec<Option<BoundingBox>>,
    visible: Option<Vec<Option<f64>>>,
}

/// Lays `pipeline` out over a clip of `frames` = truth.len() frames of `size` pixels with ground
/// truth `truth` (`None` for unlabelled frames), occluders cut from `donors`, seeded by `seed`.
/// Stage `i` draws from its own generator, seeded by [`derive_seed`]`(seed, [i, name])`.
///
/// # Errors
/// [`Error::InvalidParameter`] for settings out of range, an empty frame or clip, or an
/// `occlude` stage without donor frames (or without room in them).
pub fn plan(
    pipeline: &Pipeline,
    size: (u32, u32),
    truth: &[Option<BoundingBox>],
    donors: &[Donor],
    seed: u64,
) -> Result<Plan> {
    if size.0 == 0 || size.1 == 0 {
        return bad("frame", format!("an empty frame ({} × {})", size.0, size.1));
    }
    if truth.is_empty() {
        return bad("truth", "a clip without frames");
    }
    let input = size;
    let mut size = size;
    let mut truth = truth.to_vec();
    let mut visible: Option<Vec<Option<f64>>> = None;
    let mut stages = Vec::new();
    let mut seeds = Vec::new();
    for (i, t) in pipeline.stages.iter().enumerate() {
        t.validate()?;
        let stage_seed = derive_seed(seed, &[&i.to_string(), t.name()]);
        let mut rng = Pcg64Mcg::seed_from_u64(stage_seed);
        let stage = match t {
            Transform::Shake(s) => StagePlan::Shake(s.plan(size, &truth, &mut rng)),
            Transform::Occlude(s) => {
                let p = s.plan(&truth, donors, &mut rng)?;
                let v = p.visible();
                visible = Some(match visible {
                    None => v.to_vec(),
                    Some(old) => old
                        .iter()
                        .zip(v)
                        .map(|(a, b)| a.zip(*b).map(|(a, b)| a * b))
                        .collect(),
                });
                StagePlan::Occlude(p)
            }
            Transform::Tilt(s) => StagePlan::Tilt(s.plan(size, &truth, &mut rng)),
            Transform::Grey => StagePlan::Grey,
            Transform::Small(s) => {
                let width = median(truth.iter().flatten().map(|b| b.w));
                let s = width.map_or(1.0, |w| (s.target_px / w).min(1.0));
                let out = (
                    ((f64::from(size.0) * s).round() as u32).max(1),
                    ((f64::from(size.1) * s).round() as u32).max(1),
                );
                let scale = (
                    f64::from(out.0) / f64::from(size.0),
                    f64::from(out.1) / f64::from(size.1),
                );
                StagePlan::Small { size: out, scale }
            }
            Transform::Light(s) => StagePlan::Light(s.plan(truth.len(), &mut rng)),
            Transform::Zoom(z) => {
                let largest = truth
                    .iter()
                    .flatten()
                    .fold((0.0_f64, 0.0_f64), |(w, h), b| (w.max(b.w), h.max(b.h)));
                let zoom = CameraZoom {
                    max_zoom: z.max_zoom,
                    period: z.period,
                    follow: z.follow,
                };
                let fitted = zoom.fitted(largest, size, z.fill);
                let mut operator = Operator::new(fitted, size)?;
                let crops = truth
                    .iter()
                    .map(|b| operator.next_crop(b.as_ref()))
                    .collect();
                StagePlan::Zoom { crops, fitted }
            }
        };
        for (k, b) in truth.iter_mut().enumerate() {
            if let Some(b) = b {
                *b = stage.map_box(k, b);
            }
        }
        size = match &stage {
            StagePlan::Small { size, .. } => *size,
            _ => size,
        };
        stages.push(stage);
        seeds.push(stage_seed);
    }
    Ok(Plan {
        stages,
        seeds,
        input,
        size,
        truth,
        visible,
    })
}

impl Plan {
    /// The size of the frames made.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The mapped ground truth, one entry per frame.
    pub fn truth(&self) -> &[Option<BoundingBox>] {
        &self.truth
    }

    /// The visible share of each frame's box when a stage occludes (the product over `occlude`
    /// stages, each measured in its own stage's frame), `None` otherwise; entries are `None` on
    /// unlabelled frames.
    pub fn visible(&self) -> Option<&[Option<f64>]> {
        self.visible.as_deref()
    }

    /// The seed each stage drew from.
    pub fn seeds(&self) -> &[u64] {
        &self.seeds
    }

    /// What each stage derived from the clip (the fitted zoom, the scale, the realised jumps,
    /// the occlusion stretches, …), for the record written beside the frames.
    pub fn describe(&self) -> Vec<serde_json::Value> {
        self.stages.iter().map(StagePlan::describe).collect()
    }

    /// The in-plane angle of frame `k` in radians, when a stage tilts (the sum over stages).
    pub fn angle(&self, k: usize) -> Option<f64> {
        let mut any = false;
        let mut sum = 0.0;
        for s in &self.stages {
            if let StagePlan::Tilt(p) = s {
                any = true;
                sum += p.angle(k);
            }
        }
        any.then_some(sum)
    }

    /// Frame `k` (0-based) of the transformed clip, made from the clip's frame `k`.
    ///
    /// # Errors
    /// [`Error::FrameOutOfRange`] beyond the clip; [`Error::DimensionMismatch`] when `frame` is
    /// not the size the plan was laid out for.
    pub fn apply(&self, k: usize, frame: &RgbImage) -> Result<RgbImage> {
        if k >= self.truth.len() {
            return Err(Error::FrameOutOfRange {
                index: k,
                frames: self.truth.len(),
            });
        }
        if frame.dimensions() != self.input {
            return Err(Error::DimensionMismatch {
                expected: self.input.0 as usize * self.input.1 as usize,
                got: frame.width() as usize * frame.height() as usize,
            });
        }
        let mut out = frame.clone();
        for s in &self.stages {
            out = s.apply(k, out)?;
        }
        Ok(out)
    }
}

/// A seed derived from `seed` and some names (a clip, a stage): FNV-1a over the names, mixed
/// with the seed by SplitMix64. Results are independent of thread order by construction.
pub fn derive_seed(seed: u64, parts: &[&str]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in parts {
        for &b in p.as_bytes().iter().chain(&[0xff]) {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    let mut z = seed ^ h;
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

pub(crate) fn bad<T>(name: &'static str, reason: impl Into<String>) -> Result<T> {
    Err(Error::InvalidParameter {
        name,
        reason: reason.into(),
    })
}

/// The median of some numbers (the lower middle one of an even count), `None` for none.
fn median(values: impl Iterator<Item = f64>) -> Option<f64> {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[(v.len() - 1) / 2])
}

/// The target's radius: the median over labelled boxes of (w + h)/4.
pub(crate) fn median_radius(truth: &[Option<BoundingBox>]) -> Option<f64> {
    median(truth.iter().flatten().map(|b| 0.25 * (b.w + b.h)))
}

/// Each frame's labelled centre, held over unlabelled frames (the first labelled one before
/// it; the frame's centre when nothing is labelled).
pub(crate) fn held_centres(truth: &[Option<BoundingBox>], size: (u32, u32)) -> Vec<(f64, f64)> {
    let mut last = truth.iter().flatten().next().map_or(
        (
            0.5 * (f64::from(size.0) - 1.0),
            0.5 * (f64::from(size.1) - 1.0),
        ),
        BoundingBox::centre,
    );
    truth
        .iter()
        .map(|b| {
            if let Some(b) = b {
                last = b.centre();
            }
            last
        })
        .collect()
}

#[cfg(test)]
mod tests;
