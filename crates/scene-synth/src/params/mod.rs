//! Scenario presets and their (overridable, serialisable) parameters.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

mod checks;

use checks::{bad, finite};

/// The named scenario presets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Scenario {
    /// Static camera; light / medium / heavy clutter regions (W Fig. 3 and 10).
    Mclutter,
    /// The target passes behind an opaque occluder (W Fig. 13 and 15).
    Occlusion,
    /// Moving, zooming camera; a same-shape distractor; abrupt velocity changes (O Fig. 6–7).
    Distractor,
    /// Abrupt scale changes and a "head turn" (O Fig. 8).
    Zoom,
}

impl Scenario {
    /// Every scenario, in a fixed order.
    pub const ALL: [Scenario; 4] = [
        Scenario::Mclutter,
        Scenario::Occlusion,
        Scenario::Distractor,
        Scenario::Zoom,
    ];

    /// The lowercase name used on the command line and as folder name.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::Mclutter => "mclutter",
            Scenario::Occlusion => "occlusion",
            Scenario::Distractor => "distractor",
            Scenario::Zoom => "zoom",
        }
    }
}

impl fmt::Display for Scenario {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Scenario {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Scenario::ALL
            .into_iter()
            .find(|sc| sc.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| Error::UnknownScenario { name: s.to_owned() })
    }
}

/// Clutter class of a background region: Wu's β ∈ {1, 2, 3}.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ClutterClass {
    /// β = 1, λ̄ = 0.01/px.
    Light,
    /// β = 2, λ̄ = 0.0824/px.
    Medium,
    /// β = 3, λ̄ = 0.2144/px.
    Heavy,
}

impl ClutterClass {
    /// Wu's index β (1–3).
    pub fn index(self) -> u8 {
        match self {
            ClutterClass::Light => 1,
            ClutterClass::Medium => 2,
            ClutterClass::Heavy => 3,
        }
    }
}

/// Background clutter: random high-contrast structures (thick segments, small discs, elliptical
/// blobs) drawn over a smooth texture, calibrated so the default edge detector measures the
/// requested density in each region.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClutterParams {
    /// Requested edge densities (edges per pixel of line) for light, medium and heavy clutter.
    /// Default: Wu's learnt λ̄ = 0.01, 0.0824, 0.2144 (W §6.1).
    pub densities: [f64; 3],
    /// Regions as vertical bands of equal width, left to right, in background-texture
    /// coordinates. Default depends on the scenario.
    pub layout: Vec<ClutterClass>,
    /// Length of the measurement segments used for calibration (px). Default 40.
    pub line_length: f64,
    /// Number of calibration segments per region. Default 3000.
    pub calibration_lines: usize,
    /// Range of the grey-level difference between a structure and the local background.
    /// Default [40, 110]: a 40-level step gives a derivative peak ≈ 16 ≥ 8, so most boundaries
    /// are detected.
    pub contrast: [f64; 2],
    /// Size multiplier of the structures per class (light, medium, heavy). Default [1, 1, 0.6]:
    /// smaller structures let heavy clutter reach its density before they cover each other.
    pub size_scale: [f64; 3],
}

impl Default for ClutterParams {
    fn default() -> Self {
        Self {
            densities: [0.01, 0.0824, 0.2144],
            layout: vec![
                ClutterClass::Light,
                ClutterClass::Medium,
                ClutterClass::Heavy,
            ],
            line_length: 40.0,
            calibration_lines: 3000,
            contrast: [40.0, 110.0],
            size_scale: [0.5, 1.0, 0.6],
        }
    }
}

/// The background texture.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BackgroundParams {
    /// Mean grey level. Default 150.
    pub grey: f64,
    /// Amplitude of the smooth texture (grey levels). Default 18: with the default scale its
    /// gradient stays far below the 8 levels/px edge threshold, so it adds texture, not edges.
    pub texture_amplitude: f64,
    /// Correlation length of the smooth texture (px). Default 24.
    pub texture_scale: f64,
    /// Size of the background texture relative to the frame (≥ 1); larger than 1 when the camera
    /// pans and zooms. Default 1 (static camera).
    pub extent: f64,
    /// The clutter.
    pub clutter: ClutterParams,
}

impl Default for BackgroundParams {
    fn default() -> Self {
        Self {
            grey: 150.0,
            texture_amplitude: 18.0,
            texture_scale: 24.0,
            extent: 1.0,
            clutter: ClutterParams::default(),
        }
    }
}

/// The target: a textured ellipse with an outline of varying contrast.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TargetParams {
    /// Semi-axes (a horizontal, b vertical) at scale 1 (px). Default [22, 28], head-sized.
    pub semi_axes: [f64; 2],
    /// Mean grey level of the interior. Default 80 (dark against the 150 background).
    pub grey: f64,
    /// Amplitude of the interior texture (grey levels). Default 25: with the default scale the
    /// texture's gradient peaks near the 8 levels/px edge threshold, so it is rich enough for
    /// motion estimation without drawing a second outline inside the target.
    pub texture_amplitude: f64,
    /// Correlation length of the interior texture, as a fraction of the unit radius. Default 0.45.
    pub texture_scale: f64,
    /// Outline contrast factor in the low-contrast stretches (0 = invisible outline, 1 = full).
    /// Default 0.15.
    pub contrast_min: f64,
    /// Number of low-contrast stretches along the outline. Default 2.
    pub low_contrast_stretches: usize,
    /// Half-width of one low-contrast stretch (radians of reference angle). Default 0.35.
    pub stretch_half_width: f64,
    /// Width of the rim inside the outline over which the contrast factor fades to full texture
    /// (px). Default 10: wide enough that, in a low-contrast stretch, the fade itself stays a
    /// gentle ramp rather than a second, inner outline.
    pub rim_width: f64,
}

impl Default for TargetParams {
    fn default() -> Self {
        Self {
            semi_axes: [22.0, 28.0],
            grey: 80.0,
            texture_amplitude: 25.0,
            texture_scale: 0.45,
            contrast_min: 0.15,
            low_contrast_stretches: 2,
            stretch_half_width: 0.35,
            rim_width: 10.0,
        }
    }
}

/// The target's own motion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionParams {
    /// Typical speed between jumps (px/frame). Default depends on the scenario.
    pub speed: f64,
    /// Abrupt velocity changes, if any.
    pub jumps: Option<JumpParams>,
    /// Margin kept between the target's box and the frame border (px). Default 4.
    pub margin: f64,
}

/// Abrupt velocity changes: from time to time the target moves fast for a few frames.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JumpParams {
    /// Range of the jump speed (px/frame). Default [8, 15].
    pub speed: [f64; 2],
    /// Range of the number of frames between jumps. Default [8, 20].
    pub interval: [usize; 2],
    /// Range of the jump duration (frames). Default [1, 3].
    pub duration: [usize; 2],
}

impl Default for JumpParams {
    fn default() -> Self {
        Self {
            speed: [8.0, 15.0],
            interval: [8, 20],
            duration: [1, 3],
        }
    }
}

/// An opaque textured rectangle in front of everything.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OccluderParams {
    /// Centre as a fraction of the frame size. Default [0.5, 0.5].
    pub centre: [f64; 2],
    /// Size (px). Default [64, 110]: 20 px wider than the default target, so it hides it
    /// completely for a few frames.
    pub size: [f64; 2],
    /// Mean grey level. Default 200.
    pub grey: f64,
    /// Amplitude of its stripe-and-noise texture. Default 30.
    pub texture_amplitude: f64,
}

impl Default for OccluderParams {
    fn default() -> Self {
        Self {
            centre: [0.5, 0.5],
            size: [64.0, 110.0],
            grey: 200.0,
            texture_amplitude: 30.0,
        }
    }
}

/// A second ellipse of the target's shape that moves differently nearby.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DistractorParams {
    /// Range of the gap between the two outlines along the line of centres (px). Default [3, 50].
    pub gap: [f64; 2],
    /// Angular speed of the distractor around the target (radians/frame). Default 0.05.
    pub angular_speed: f64,
    /// Period of the gap oscillation (frames). Default 40.
    pub gap_period: f64,
    /// Mean grey level of its interior. Default 90, close to the target's.
    pub grey: f64,
}

impl Default for DistractorParams {
    fn default() -> Self {
        Self {
            gap: [3.0, 50.0],
            angular_speed: 0.05,
            gap_period: 40.0,
            grey: 90.0,
        }
    }
}

/// Camera motion: the background translates and zooms; the target's size follows the zoom.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraParams {
    /// Pan amplitude in x and y (background-texture px). Default [60, 30].
    pub pan_amplitude: [f64; 2],
    /// Pan period (frames). Default 90.
    pub pan_period: f64,
    /// Relative zoom amplitude. Default 0.15 (zoom factor 0.85–1.15).
    pub zoom_amplitude: f64,
    /// Zoom period (frames). Default 70.
    pub zoom_period: f64,
}

impl Default for CameraParams {
    fn default() -> Self {
        Self {
            pan_amplitude: [60.0, 30.0],
            pan_period: 90.0,
            zoom_amplitude: 0.15,
            zoom_period: 70.0,
        }
    }
}

/// Abrupt changes of the target's scale.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScaleChangeParams {
    /// Number of changes in the sequence. Default 4.
    pub count: usize,
    /// Range of the relative change per event. Default [0.2, 0.3].
    pub magnitude: [f64; 2],
    /// Frames over which one change happens. Default 3.
    pub duration: usize,
    /// Allowed scale range (relative to the preset size). Default [0.7, 1.4].
    pub bounds: [f64; 2],
}

impl Default for ScaleChangeParams {
    fn default() -> Self {
        Self {
            count: 4,
            magnitude: [0.2, 0.3],
            duration: 3,
            bounds: [0.7, 1.4],
        }
    }
}

/// The "head turn": the interior texture translates while the outline stays.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeadTurnParams {
    /// Texture shift at the peak of the turn (fraction of the horizontal semi-axis). Default 0.6.
    pub shift: f64,
    /// Frames to turn away (the same number to turn back). Default 10.
    pub duration: usize,
    /// Number of turns. Default 2.
    pub count: usize,
}

impl Default for HeadTurnParams {
    fn default() -> Self {
        Self {
            shift: 0.6,
            duration: 10,
            count: 2,
        }
    }
}

/// Visible-fraction thresholds of the status label, consistent with Wu's γ ranges (γ ≈ 1 − v;
/// W §6.3 with docs/MODELS.md's fix: locked γ ∈ [0, 0.2], lost γ ∈ [0.8, 1]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StatusThresholds {
    /// Locked when v ≥ this. Default 0.8.
    pub locked_min_visible: f64,
    /// Lost when v ≤ this. Default 0.2.
    pub lost_max_visible: f64,
}

impl Default for StatusThresholds {
    fn default() -> Self {
        Self {
            locked_min_visible: 0.8,
            lost_max_visible: 0.2,
        }
    }
}

/// Every parameter of a scene. Start from [`ScenarioParams::preset`] and override fields.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioParams {
    /// Which preset these parameters started from (decides the trajectory's shape).
    pub scenario: Scenario,
    /// Frame width (px). Default 320.
    pub width: u32,
    /// Frame height (px). Default 240.
    pub height: u32,
    /// Number of frames. Default 120.
    pub frames: usize,
    /// Standard deviation of the per-frame sensor noise (grey levels). Default 2: far below the
    /// edge threshold, but it keeps consecutive frames from being exactly equal.
    pub noise_sigma: f64,
    /// The background.
    pub background: BackgroundParams,
    /// The target.
    pub target: TargetParams,
    /// The target's motion.
    pub motion: MotionParams,
    /// An occluder, if any.
    pub occluder: Option<OccluderParams>,
    /// A distractor, if any.
    pub distractor: Option<DistractorParams>,
    /// Camera motion, if any.
    pub camera: Option<CameraParams>,
    /// Abrupt scale changes, if any.
    pub scale_changes: Option<ScaleChangeParams>,
    /// Head turns, if any.
    pub head_turn: Option<HeadTurnParams>,
    /// Status thresholds.
    pub status: StatusThresholds,
}

impl ScenarioParams {
    /// The preset of a scenario at 320×240, 120 frames.
    pub fn preset(scenario: Scenario) -> Self {
        let mut p = Self {
            scenario,
            width: 320,
            height: 240,
            frames: 120,
            noise_sigma: 2.0,
            background: BackgroundParams::default(),
            target: TargetParams::default(),
            motion: MotionParams {
                speed: 3.0,
                jumps: None,
                margin: 4.0,
            },
            occluder: None,
            distractor: None,
            camera: None,
            scale_changes: None,
            head_turn: None,
            status: StatusThresholds::default(),
        };
        match scenario {
            Scenario::Mclutter => {}
            Scenario::Occlusion => {
                p.background.clutter.layout = vec![ClutterClass::Medium];
                p.motion.speed = 2.0;
                p.occluder = Some(OccluderParams::default());
            }
            Scenario::Distractor => {
                // Edge-rich background moving with the camera (O Fig. 6–7).
                p.background.clutter.layout = vec![ClutterClass::Medium];
                p.background.extent = 1.8;
                p.motion.speed = 2.0;
                p.motion.jumps = Some(JumpParams::default());
                p.distractor = Some(DistractorParams::default());
                p.camera = Some(CameraParams::default());
            }
            Scenario::Zoom => {
                p.background.clutter.layout = vec![ClutterClass::Light, ClutterClass::Medium];
                p.motion.speed = 1.0;
                p.scale_changes = Some(ScaleChangeParams::default());
                p.head_turn = Some(HeadTurnParams::default());
            }
        }
        p
    }

    /// Applies one override written `dotted.path=VALUE` (VALUE is JSON, or a bare string when it
    /// does not parse as JSON), e.g. `target.contrast_min=0.05` or `occluder=null`.
    ///
    /// # Errors
    /// [`Error::Override`] for a spec without `=` or a value of the wrong type.
    pub fn with_override(&self, spec: &str) -> Result<Self> {
        let (path, value) = spec.split_once('=').ok_or_else(|| Error::Override {
            reason: format!("expected PATH=JSON, got `{spec}`"),
        })?;
        let mut v: serde_json::Value = serde_json::from_str(value)
            .unwrap_or_else(|_| serde_json::Value::String(value.to_owned()));
        for key in path.rsplit('.') {
            let mut m = serde_json::Map::new();
            m.insert(key.trim().to_owned(), v);
            v = serde_json::Value::Object(m);
        }
        self.with_overrides(&v)
    }

    /// Applies a JSON merge patch (RFC 7386: objects merge, `null` deletes, anything else
    /// replaces) to these parameters, then validates the result.
    ///
    /// # Errors
    /// [`Error::Override`] if the patched document no longer describes valid parameters.
    pub fn with_overrides(&self, patch: &serde_json::Value) -> Result<Self> {
        let mut doc = serde_json::to_value(self)?;
        merge_patch(&mut doc, patch);
        let p: Self = serde_json::from_value(doc).map_err(|e| Error::Override {
            reason: e.to_string(),
        })?;
        p.validate()?;
        Ok(p)
    }

    /// Checks every parameter against its documented range.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first offending field.
    pub fn validate(&self) -> Result<()> {
        if self.width < 32 || self.height < 32 || self.width > 8192 || self.height > 8192 {
            return Err(bad(
                "width/height",
                "frame size must be within 32..=8192 px",
            ));
        }
        if self.frames == 0 {
            return Err(bad("frames", "at least one frame"));
        }
        finite("noise_sigma", &[self.noise_sigma])?;
        if self.noise_sigma < 0.0 {
            return Err(bad("noise_sigma", "negative"));
        }
        self.background.check()?;
        self.target.check(f64::from(self.width.min(self.height)))?;
        self.motion.check()?;
        if let Some(o) = &self.occluder {
            o.check()?;
        }
        if let Some(d) = &self.distractor {
            d.check()?;
        }
        if let Some(cam) = &self.camera {
            cam.check()?;
        }
        if let Some(s) = &self.scale_changes {
            s.check()?;
        }
        if let Some(h) = &self.head_turn {
            h.check()?;
        }
        self.status.check()
    }
}

/// RFC 7386 JSON merge patch.
fn merge_patch(target: &mut serde_json::Value, patch: &serde_json::Value) {
    use serde_json::Value;
    match patch {
        Value::Object(p) => {
            if !target.is_object() {
                *target = Value::Object(serde_json::Map::new());
            }
            if let Value::Object(t) = target {
                for (k, v) in p {
                    if v.is_null() {
                        t.remove(k);
                    } else {
                        merge_patch(t.entry(k.clone()).or_insert(Value::Null), v);
                    }
                }
            }
        }
        other => *target = other.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate_and_round_trip_through_json() {
        for sc in Scenario::ALL {
            let p = ScenarioParams::preset(sc);
            p.validate().unwrap();
            let json = serde_json::to_string(&p).unwrap();
            let back: ScenarioParams = serde_json::from_str(&json).unwrap();
            assert_eq!(back, p);
            assert_eq!(sc.name().parse::<Scenario>().unwrap(), sc);
        }
        assert!("nope".parse::<Scenario>().is_err());
    }

    #[test]
    fn overrides_merge_into_the_preset_and_are_validated() {
        let p = ScenarioParams::preset(Scenario::Distractor);
        let q = p
            .with_overrides(&serde_json::json!({"frames": 30, "motion": {"jumps": {"speed": [5.0, 6.0]}}, "camera": null}))
            .unwrap();
        assert_eq!(q.frames, 30);
        assert_eq!(q.motion.jumps.as_ref().unwrap().speed, [5.0, 6.0]);
        assert_eq!(q.motion.jumps.as_ref().unwrap().interval, [8, 20]);
        assert!(q.camera.is_none());
        assert!(
            p.with_overrides(&serde_json::json!({"target": {"contrast_min": 2.0}}))
                .is_err()
        );
        assert!(
            p.with_overrides(&serde_json::json!({"target": {"colour": 2.0}}))
                .is_err()
        );
    }
}
