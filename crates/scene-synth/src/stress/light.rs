//! `light`: lighting changes, as from a dark room into a lit hall. Each frame's pixels v (in
//! [0, 1]) become min(1, 2^e · v^γ), with a global gain of g stops and a gamma γ ramped smoothly
//! between seeded key frames, and a moving illumination gradient: e = clamp(g + G·d, −M, M),
//! where d ∈ [−1, 1] is the pixel's position along a direction that turns a little every frame
//! (−1 and 1 at the frame's half-diagonal from its centre).
//!
//! The key frames alternate dark and bright: key 0 (frame 0) is the footage as shot (the
//! gradient fades in over the first ramp), odd keys
//! darken by `gain_min`–`gain_max` stops, even keys brighten by as much. With the defaults and
//! M = 1 the brightness goes from half to double.

use rand::Rng;
use rand_pcg::Pcg64Mcg;
use serde::{Deserialize, Serialize};

use super::bad;
use crate::error::Result;

/// The settings of `light`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Light {
    /// Frames between key frames (≥ 2). Default 50.
    pub ramp_frames: usize,
    /// The smallest gain of a key frame, in stops (its sign alternates). Default 0.5.
    pub gain_min: f64,
    /// The largest gain of a key frame, in stops. Default 0.8.
    pub gain_max: f64,
    /// The smallest gamma of a key frame (after the first, which is 1). Default 0.8.
    pub gamma_min: f64,
    /// The largest gamma of a key frame. Default 1.25.
    pub gamma_max: f64,
    /// G, the gradient's strength: stops gained at one end of the frame's half-diagonal and lost
    /// at the other. Default 0.3.
    pub gradient: f64,
    /// The fastest turn of the gradient's direction, radians per frame (seeded in [½, 1] of
    /// this, either way). Default 0.03.
    pub turn: f64,
    /// M, the bound of the total exposure change, in stops: 1 is half to double. Default 1.
    pub max_stops: f64,
}

impl Default for Light {
    fn default() -> Self {
        Self {
            ramp_frames: 50,
            gain_min: 0.5,
            gain_max: 0.8,
            gamma_min: 0.8,
            gamma_max: 1.25,
            gradient: 0.3,
            turn: 0.03,
            max_stops: 1.0,
        }
    }
}

impl Light {
    /// Checks every field against its documented range.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] naming the first field out of range.
    pub fn validate(&self) -> Result<()> {
        if self.ramp_frames < 2 {
            return bad("light.ramp_frames", "must be ≥ 2");
        }
        if !(self.gain_min >= 0.0 && self.gain_max >= self.gain_min && self.gain_max <= 4.0) {
            return bad("light.gain_min", "need 0 ≤ gain_min ≤ gain_max ≤ 4 stops");
        }
        if !(self.gamma_min > 0.0 && self.gamma_max >= self.gamma_min && self.gamma_max <= 4.0) {
            return bad("light.gamma_min", "need 0 < gamma_min ≤ gamma_max ≤ 4");
        }
        if !(0.0..=4.0).contains(&self.gradient) {
            return bad("light.gradient", "must lie in [0, 4] stops");
        }
        if !(0.0..=1.0).contains(&self.turn) {
            return bad("light.turn", "must lie in [0, 1] radians per frame");
        }
        if !(self.max_stops > 0.0 && self.max_stops <= 4.0) {
            return bad("light.max_stops", "must lie in (0, 4]");
        }
        Ok(())
    }

    pub(crate) fn plan(&self, frames: usize, rng: &mut Pcg64Mcg) -> LightPlan {
        let keys = frames / self.ramp_frames + 2;
        let mut gains = vec![0.0];
        let mut gammas = vec![1.0];
        for j in 1..keys {
            let g = rng.random_range(self.gain_min..=self.gain_max);
            gains.push(if j % 2 == 1 { -g } else { g });
            gammas.push(rng.random_range(self.gamma_min..=self.gamma_max));
        }
        let start = rng.random_range(0.0..std::f64::consts::TAU);
        let turn =
            self.turn * rng.random_range(0.5..=1.0) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let step = self.ramp_frames as f64;
        let frames = (0..frames)
            .map(|k| {
                let u = k as f64 / step;
                let j = u.floor() as usize;
                let t = u - j as f64;
                let s = t * t * (3.0 - 2.0 * t);
                LightFrame {
                    gain: gains[j] + s * (gains[j + 1] - gains[j]),
                    // The gradient fades in over the first ramp, so frame 0 is as shot.
                    gradient: self.gradient * u.min(1.0),
                    gamma: gammas[j] + s * (gammas[j + 1] - gammas[j]),
                    direction: start + turn * k as f64,
                }
            })
            .collect();
        LightPlan {
            max_stops: self.max_stops,
            frames,
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct LightFrame {
    gain: f64,
    gradient: f64,
    gamma: f64,
    direction: f64,
}

/// The planned exposure of every frame.
#[derive(Debug, Clone)]
pub(crate) struct LightPlan {
    max_stops: f64,
    frames: Vec<LightFrame>,
}

impl LightPlan {
    /// The exposure change in stops at pixel (x, y) of frame `k` of a `size` frame.
    pub(crate) fn stops(&self, k: usize, size: (u32, u32), x: f64, y: f64) -> f64 {
        let f = self.frames[k];
        let (w, h) = (f64::from(size.0), f64::from(size.1));
        let half_diag = 0.5 * w.hypot(h);
        let (dx, dy) = (f.direction.cos(), f.direction.sin());
        let d = ((x - 0.5 * (w - 1.0)) * dx + (y - 0.5 * (h - 1.0)) * dy) / half_diag;
        (f.gain + f.gradient * d).clamp(-self.max_stops, self.max_stops)
    }

    pub(crate) fn apply(&self, k: usize, frame: &mut image::RgbImage) {
        let gamma = self.frames[k].gamma;
        let lut: Vec<f32> = (0..256)
            .map(|v| (255.0 * (f64::from(v) / 255.0).powf(gamma)) as f32)
            .collect();
        let size = frame.dimensions();
        for (x, y, p) in frame.enumerate_pixels_mut() {
            let gain = self.stops(k, size, f64::from(x), f64::from(y)).exp2() as f32;
            for c in &mut p.0 {
                *c = (lut[usize::from(*c)] * gain).round().clamp(0.0, 255.0) as u8;
            }
        }
    }

    pub(crate) fn describe(&self) -> serde_json::Value {
        let lo = self.frames.iter().map(|f| f.gain).fold(0.0, f64::min);
        let hi = self.frames.iter().map(|f| f.gain).fold(0.0, f64::max);
        serde_json::json!({ "darkest_gain_stops": lo, "brightest_gain_stops": hi })
    }
}
