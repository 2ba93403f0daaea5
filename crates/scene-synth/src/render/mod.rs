//! The scene: precomputed layers composited frame by frame.
//!
//! Everything expensive (the calibrated background, the textures, the whole trajectory) is built
//! once in [`Scene::new`]; [`Scene::render_frame_into`] only composites: background (copied, or
//! warped by the camera), distractor, target, occluder, sensor noise, quantisation.

use image::GrayImage;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use vision_core::Ellipse;

mod layers;

use layers::{Appearance, Occluder, Stream, mix};

use crate::background::Background;
use crate::edges::bilinear_raw;
use crate::error::{Error, Result};
use crate::geometry::{OdobezState, WuAffine};
use crate::params::{Scenario, ScenarioParams};
use crate::trajectory::{FrameState, plan};
use crate::truth::FrameTruth;

/// A deterministic synthetic sequence: build once, render any frame in any order.
#[derive(Debug, Clone)]
pub struct Scene {
    params: ScenarioParams,
    seed: u64,
    background: Background,
    target: Appearance,
    distractor: Option<Appearance>,
    occluder: Option<Occluder>,
    states: Vec<FrameState>,
}

impl Scene {
    /// Builds the scene: validates the parameters, calibrates the background clutter, draws the
    /// textures and the trajectory. Deterministic in (params, seed).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for bad parameters, [`Error::Calibration`] when the clutter
    /// density cannot be reached.
    ///
    /// # Examples
    /// ```
    /// use scene_synth::{Scenario, ScenarioParams, Scene};
    /// let p = ScenarioParams::preset(Scenario::Occlusion);
    /// let scene = Scene::new(&p, 7)?;
    /// // The first frame shows the target free of the occluder.
    /// let (img, truth) = scene.render_frame(0)?;
    /// assert_eq!((img.width(), img.height()), (320, 240));
    /// assert!(truth.visible_fraction > 0.99);
    /// # Ok::<(), scene_synth::Error>(())
    /// ```
    pub fn new(params: &ScenarioParams, seed: u64) -> Result<Self> {
        params.validate()?;
        let (w, h) = (params.width as usize, params.height as usize);
        let ext = params.background.extent;
        let (tw, th) = (
            (w as f64 * ext).ceil() as usize,
            (h as f64 * ext).ceil() as usize,
        );
        let background =
            Background::generate(&params.background, tw, th, mix(seed, Stream::Background, 0))?;
        let t = &params.target;
        let mut rng = Pcg64Mcg::seed_from_u64(mix(seed, Stream::Target, 0));
        let target = Appearance::new(
            &mut rng,
            t.grey,
            t.texture_amplitude,
            t.texture_scale,
            t.contrast_min,
            t.low_contrast_stretches,
            t.stretch_half_width,
        );
        let distractor = params.distractor.as_ref().map(|d| {
            let mut rng = Pcg64Mcg::seed_from_u64(mix(seed, Stream::Distractor, 0));
            Appearance::new(
                &mut rng,
                d.grey,
                t.texture_amplitude,
                t.texture_scale,
                t.contrast_min,
                t.low_contrast_stretches,
                t.stretch_half_width,
            )
        });
        let occluder = params.occluder.as_ref().map(|o| {
            let mut rng = Pcg64Mcg::seed_from_u64(mix(seed, Stream::Occluder, 0));
            Occluder::new(o, w, h, &mut rng)
        });
        let states = plan(params, (tw, th), mix(seed, Stream::Trajectory, 0));
        Ok(Self {
            params: params.clone(),
            seed,
            background,
            target,
            distractor,
            occluder,
            states,
        })
    }

    /// The scene of a preset.
    ///
    /// # Errors
    /// As [`Scene::new`].
    pub fn preset(scenario: Scenario, seed: u64) -> Result<Self> {
        Self::new(&ScenarioParams::preset(scenario), seed)
    }

    /// The parameters.
    pub fn params(&self) -> &ScenarioParams {
        &self.params
    }

    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.states.len()
    }

    /// Whether the sequence has no frames (never, for validated parameters).
    pub fn is_empty(&self) -> bool {
        self.states.is_empty()
    }

    /// Frame width and height (px).
    pub fn size(&self) -> (usize, usize) {
        (self.params.width as usize, self.params.height as usize)
    }

    /// The calibrated background texture and its regions.
    pub fn background(&self) -> &Background {
        &self.background
    }

    /// The occluder rectangle [x0, y0, x1, y1] in frame coordinates, if any.
    pub fn occluder_rect(&self) -> Option<[f64; 4]> {
        self.occluder.as_ref().map(|o| o.rect)
    }

    fn state(&self, k: usize) -> Result<&FrameState> {
        self.states.get(k).ok_or(Error::FrameOutOfRange {
            index: k,
            frames: self.states.len(),
        })
    }

    /// Ground truth of frame `k` without rendering it.
    ///
    /// # Errors
    /// [`Error::FrameOutOfRange`].
    pub fn truth(&self, k: usize) -> Result<FrameTruth> {
        let st = self.state(k)?;
        let visible = self.visible_coverage(&st.target);
        Ok(self.make_truth(k, st, visible))
    }

    fn make_truth(&self, k: usize, st: &FrameState, visible: f64) -> FrameTruth {
        let e = st.target;
        let (w, _) = self.size();
        let cam = st.camera;
        let qx = cam.cx + (e.cx - (w as f64 - 1.0) / 2.0) / cam.zoom;
        let (class, density) = self
            .background
            .region_at(qx)
            .map_or((0, 0.0), |r| (r.class.index(), r.measured));
        let v = (visible / e.area()).clamp(0.0, 1.0);
        FrameTruth {
            frame: k,
            ellipse: e,
            odobez: OdobezState::from_ellipse(&e),
            affine: WuAffine::from_ellipse(&e),
            bbox: e.bounding_box(),
            clutter_class: class,
            edge_density: density / cam.zoom,
            visible_fraction: v,
            status: self.params.status.status(v),
            distractor: st.distractor,
        }
    }

    /// Renders frame `k` into caller-owned buffers: `out` holds `width * height` grey levels
    /// (row-major), `scratch` is resized as needed.
    ///
    /// # Errors
    /// [`Error::FrameOutOfRange`], [`Error::DimensionMismatch`] if `out` has the wrong length.
    pub fn render_frame_into(
        &self,
        k: usize,
        out: &mut [u8],
        scratch: &mut Vec<f32>,
    ) -> Result<FrameTruth> {
        let st = self.state(k)?;
        let (w, h) = self.size();
        if out.len() != w * h {
            return Err(Error::DimensionMismatch {
                expected: w * h,
                got: out.len(),
            });
        }
        scratch.resize(w * h, 0.0);
        let buf = scratch.as_mut_slice();
        self.paint_background(st, buf);
        if let (Some(app), Some(d)) = (&self.distractor, &st.distractor) {
            self.paint_object(buf, d, app, [0.0, 0.0]);
        }
        let visible = self.paint_object(buf, &st.target, &self.target, st.texture_offset);
        if let Some(o) = &self.occluder {
            self.paint_occluder(buf, o);
        }
        let sigma = self.params.noise_sigma;
        if sigma > 0.0 {
            let mut rng = Pcg64Mcg::seed_from_u64(mix(self.seed, Stream::Noise, k as u64));
            // Irwin–Hall(4) noise from one 64-bit draw per pixel: unit variance after the
            // √3 · 2 scaling, cheap enough to keep rendering far above 200 frames/s.
            let gain = (sigma * 3.0f64.sqrt()) as f32;
            for (o, &v) in out.iter_mut().zip(buf.iter()) {
                let r: u64 = rng.random();
                let s = (r & 0xFFFF) + ((r >> 16) & 0xFFFF) + ((r >> 32) & 0xFFFF) + (r >> 48);
                let n = (s as f32 / 65536.0 - 2.0) * gain;
                *o = (v + n).round().clamp(0.0, 255.0) as u8;
            }
        } else {
            for (o, &v) in out.iter_mut().zip(buf.iter()) {
                *o = v.round().clamp(0.0, 255.0) as u8;
            }
        }
        Ok(self.make_truth(k, st, visible))
    }

    /// Renders frame `k` (allocating convenience twin of [`Scene::render_frame_into`]).
    ///
    /// # Errors
    /// [`Error::FrameOutOfRange`].
    pub fn render_frame(&self, k: usize) -> Result<(GrayImage, FrameTruth)> {
        let (w, h) = self.size();
        let mut out = vec![0u8; w * h];
        let mut scratch = Vec::new();
        let truth = self.render_frame_into(k, &mut out, &mut scratch)?;
        let img = GrayImage::from_raw(w as u32, h as u32, out).ok_or(Error::DimensionMismatch {
            expected: w * h,
            got: 0,
        })?;
        Ok((img, truth))
    }

    fn paint_background(&self, st: &FrameState, buf: &mut [f32]) {
        let (w, h) = self.size();
        let bg = &self.background;
        let cam = st.camera;
        if bg.width == w && bg.height == h && cam.zoom == 1.0 && self.params.camera.is_none() {
            buf.copy_from_slice(&bg.data);
            return;
        }
        let (fcx, fcy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
        let inv = 1.0 / cam.zoom;
        for y in 0..h {
            let qy = cam.cy + (y as f64 - fcy) * inv;
            for x in 0..w {
                let qx = cam.cx + (x as f64 - fcx) * inv;
                buf[y * w + x] = bilinear_raw(bg.width, bg.height, &bg.data, qx, qy) as f32;
            }
        }
    }

    /// Composites an object over `buf`; returns its visible coverage (px²), i.e. the summed
    /// anti-aliased coverage inside the frame and not behind the occluder.
    fn paint_object(
        &self,
        buf: &mut [f32],
        e: &Ellipse,
        app: &Appearance,
        offset: [f64; 2],
    ) -> f64 {
        let (w, _) = self.size();
        let rim = self.params.target.rim_width;
        let mut visible = 0.0;
        self.for_each_covered(e, |x, y, u, v, sd, alpha| {
            let kappa = app.kappa(u, v);
            let t = (-sd / rim).clamp(0.0, 1.0);
            let beta = kappa + (1.0 - kappa) * t * t * (3.0 - 2.0 * t);
            let tex = app.texture(u - offset[0], v - offset[1]);
            let p = &mut buf[y * w + x];
            let bg = f64::from(*p);
            *p = (bg + alpha * beta * (tex - bg)) as f32;
            let occ = self
                .occluder
                .as_ref()
                .map_or(0.0, |o| o.alpha(x as f64, y as f64));
            visible += alpha * (1.0 - occ);
        });
        visible
    }

    fn visible_coverage(&self, e: &Ellipse) -> f64 {
        let mut visible = 0.0;
        self.for_each_covered(e, |x, y, _, _, _, alpha| {
            let occ = self
                .occluder
                .as_ref()
                .map_or(0.0, |o| o.alpha(x as f64, y as f64));
            visible += alpha * (1.0 - occ);
        });
        visible
    }

    /// Calls `f(x, y, u, v, signed_distance, coverage)` for every frame pixel the ellipse covers.
    fn for_each_covered<F: FnMut(usize, usize, f64, f64, f64, f64)>(&self, e: &Ellipse, mut f: F) {
        let (w, h) = self.size();
        let (hw, hh) = e.half_extents();
        let x0 = (e.cx - hw - 1.0).floor().max(0.0) as usize;
        let y0 = (e.cy - hh - 1.0).floor().max(0.0) as usize;
        let x1 = ((e.cx + hw + 2.0).ceil().max(0.0) as usize).min(w);
        let y1 = ((e.cy + hh + 2.0).ceil().max(0.0) as usize).min(h);
        let (sn, cs) = e.angle.sin_cos();
        let (ia, ib) = (1.0 / e.a, 1.0 / e.b);
        for y in y0..y1 {
            let dy = y as f64 - e.cy;
            for x in x0..x1 {
                let dx = x as f64 - e.cx;
                let u = (cs * dx + sn * dy) * ia;
                let v = (-sn * dx + cs * dy) * ib;
                let rho = u.hypot(v);
                // First-order signed distance (ρ − 1)/|∇ρ|; see `Ellipse::signed_distance`.
                let sd = if rho > 1e-9 {
                    (rho - 1.0) * rho / ((u * ia).powi(2) + (v * ib).powi(2)).sqrt()
                } else {
                    -e.a.min(e.b)
                };
                let alpha = (0.5 - sd).clamp(0.0, 1.0);
                if alpha > 0.0 {
                    f(x, y, u, v, sd, alpha);
                }
            }
        }
    }

    fn paint_occluder(&self, buf: &mut [f32], o: &Occluder) {
        let (w, h) = self.size();
        let tex_h = o.tex.len() / o.tex_w;
        for ty in 0..tex_h {
            let y = o.oy + ty;
            if y >= h {
                break;
            }
            for tx in 0..o.tex_w {
                let x = o.ox + tx;
                if x >= w {
                    break;
                }
                let a = o.alpha(x as f64, y as f64) as f32;
                if a > 0.0 {
                    let p = &mut buf[y * w + x];
                    *p += a * (o.tex[ty * o.tex_w + tx] - *p);
                }
            }
        }
    }
}

/// Converts an 8-bit frame to the workspace's f32 grey convention (row-major, 0–255).
pub fn to_f32(img: &GrayImage) -> Vec<f32> {
    img.as_raw().iter().map(|&v| f32::from(v)).collect()
}

#[cfg(test)]
mod tests;
