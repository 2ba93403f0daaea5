//! Per-frame poses of the target, the distractor and the camera, drawn once per sequence.

use std::f64::consts::PI;

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use vision_core::Ellipse;

use crate::params::{Scenario, ScenarioParams};

/// The camera: texture point shown at the frame centre and the zoom factor
/// (frame px per texture px). Frame point p shows texture point c + (p − frame centre)/zoom.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Texture x at the frame centre.
    pub cx: f64,
    /// Texture y at the frame centre.
    pub cy: f64,
    /// Zoom factor.
    pub zoom: f64,
}

/// Everything that moves, for one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameState {
    /// The target's outline.
    pub target: Ellipse,
    /// Shift of the interior texture in reference units (the head turn).
    pub texture_offset: [f64; 2],
    /// The distractor, if any.
    pub distractor: Option<Ellipse>,
    /// The camera.
    pub camera: Camera,
}

/// Radius of an axis-aligned ellipse in direction φ.
fn radius(a: f64, b: f64, phi: f64) -> f64 {
    let (s, c) = phi.sin_cos();
    a * b / ((b * c).powi(2) + (a * s).powi(2)).sqrt()
}

fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Draws the whole sequence of states. Deterministic in (params, seed).
///
/// The random draws happen in a fixed order (camera, scale changes, centre path, head turns,
/// distractor), one generator for the whole sequence, so that a seed always gives the same
/// sequence.
pub fn plan(p: &ScenarioParams, tex_size: (usize, usize), seed: u64) -> Vec<FrameState> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let n = p.frames;
    let [a0, b0] = p.target.semi_axes;
    let cameras = camera_path(p, tex_size, &mut rng);
    let scale = scale_profile(p, &mut rng);
    let total_scale: Vec<f64> = (0..n).map(|k| scale[k] * cameras[k].zoom).collect();
    let s_max = total_scale.iter().copied().fold(1.0f64, f64::max);
    let bounds = CentreBounds::new(p, s_max);
    let centres = match p.scenario {
        Scenario::Mclutter => sweep_path(p, &bounds, &mut rng),
        Scenario::Occlusion => occluder_pass(p, &bounds, &mut rng),
        Scenario::Distractor | Scenario::Zoom => wandering_path(p, &bounds, &mut rng),
    };
    let offsets = head_turn_offsets(p, &mut rng);

    // Distractor: circles the target at a varying gap between the outlines.
    let d_phase = rng.random::<f64>() * 2.0 * PI;
    let g_phase = rng.random::<f64>() * 2.0 * PI;
    (0..n)
        .map(|k| {
            let s = total_scale[k];
            let target = Ellipse {
                cx: centres[k].0,
                cy: centres[k].1,
                a: a0 * s,
                b: b0 * s,
                angle: 0.0,
            };
            let distractor = p
                .distractor
                .as_ref()
                .map(|d| place_distractor(p, d, &target, k, d_phase, g_phase));
            FrameState {
                target,
                texture_offset: offsets[k],
                distractor,
                camera: cameras[k],
            }
        })
        .collect()
}

/// The camera of every frame: fixed at the texture centre, or panning and zooming along
/// sinusoids of random phase with the visible window kept inside the texture.
fn camera_path(p: &ScenarioParams, tex_size: (usize, usize), rng: &mut Pcg64Mcg) -> Vec<Camera> {
    let (w, h) = (f64::from(p.width), f64::from(p.height));
    let (tw, th) = (tex_size.0 as f64, tex_size.1 as f64);
    let cam_phase = [
        rng.random::<f64>() * 2.0 * PI,
        rng.random::<f64>() * 2.0 * PI,
        rng.random::<f64>() * 2.0 * PI,
    ];
    (0..p.frames)
        .map(|k| match &p.camera {
            None => Camera {
                cx: (tw - 1.0) / 2.0,
                cy: (th - 1.0) / 2.0,
                zoom: 1.0,
            },
            Some(c) => {
                let t = k as f64;
                let zoom =
                    1.0 + c.zoom_amplitude * (2.0 * PI * t / c.zoom_period + cam_phase[2]).sin();
                // Keep the visible window inside the texture.
                let (hx, hy) = (0.5 * w / zoom, 0.5 * h / zoom);
                let mx = ((tw - 1.0) / 2.0 - hx).max(0.0);
                let my = ((th - 1.0) / 2.0 - hy).max(0.0);
                let px = (c.pan_amplitude[0] * (2.0 * PI * t / c.pan_period + cam_phase[0]).sin())
                    .clamp(-mx, mx);
                let py = (c.pan_amplitude[1]
                    * (2.0 * PI * t / (1.37 * c.pan_period) + cam_phase[1]).sin())
                .clamp(-my, my);
                Camera {
                    cx: (tw - 1.0) / 2.0 + px,
                    cy: (th - 1.0) / 2.0 + py,
                    zoom,
                }
            }
        })
        .collect()
}

/// The target's own scale in every frame: 1, or abrupt changes (O Fig. 8) evenly spread over
/// the sequence, each a geometric ramp over `duration` frames that stays within `bounds`.
fn scale_profile(p: &ScenarioParams, rng: &mut Pcg64Mcg) -> Vec<f64> {
    let n = p.frames;
    let mut scale = vec![1.0f64; n];
    let Some(sc) = &p.scale_changes else {
        return scale;
    };
    let mut s = 1.0f64;
    let mut k_prev = 0usize;
    for i in 0..sc.count {
        let k0 = ((i + 1) * n / (sc.count + 1)).clamp(k_prev, n);
        for v in &mut scale[k_prev..k0] {
            *v = s;
        }
        let mag = rng.random_range(sc.magnitude[0]..=sc.magnitude[1]);
        let up = if s * (1.0 + mag) > sc.bounds[1] {
            false
        } else if s * (1.0 - mag) < sc.bounds[0] {
            true
        } else {
            rng.random::<bool>()
        };
        let s1 = if up { s * (1.0 + mag) } else { s * (1.0 - mag) };
        let k1 = (k0 + sc.duration).min(n);
        for (j, v) in scale[k0..k1].iter_mut().enumerate() {
            // Geometric interpolation, reaching s1 at the last frame of the change.
            let f = (j + 1) as f64 / sc.duration as f64;
            *v = s * (s1 / s).powf(f);
        }
        s = s1;
        k_prev = k1;
    }
    for v in &mut scale[k_prev..] {
        *v = s;
    }
    scale
}

/// The rectangle the target's centre stays in: the largest target (scale `s_max`) keeps the
/// margin to every border; a frame too small for that pins the centre to the middle.
#[derive(Debug, Clone, Copy)]
struct CentreBounds {
    xl: f64,
    xr: f64,
    yt: f64,
    yb: f64,
}

impl CentreBounds {
    fn new(p: &ScenarioParams, s_max: f64) -> Self {
        let (w, h) = (f64::from(p.width), f64::from(p.height));
        let [a0, b0] = p.target.semi_axes;
        let m = p.motion.margin;
        let (xl, xr) = (m + a0 * s_max, w - 1.0 - m - a0 * s_max);
        let (yt, yb) = (m + b0 * s_max, h - 1.0 - m - b0 * s_max);
        let (xl, xr) = if xl < xr {
            (xl, xr)
        } else {
            (w / 2.0, w / 2.0)
        };
        let (yt, yb) = if yt < yb {
            (yt, yb)
        } else {
            (h / 2.0, h / 2.0)
        };
        Self { xl, xr, yt, yb }
    }
}

/// `mclutter`: left to right and back (light → medium → heavy → …), wavering vertically.
fn sweep_path(p: &ScenarioParams, b: &CentreBounds, rng: &mut Pcg64Mcg) -> Vec<(f64, f64)> {
    let n = p.frames;
    let span = (b.xr - b.xl).max(1.0);
    let cycles = ((n as f64 * p.motion.speed) / (2.0 * span)).max(1.0);
    let ph = rng.random::<f64>() * 2.0 * PI;
    let amp = 0.35 * (b.yb - b.yt);
    (0..n)
        .map(|k| {
            let tau = k as f64 / (n.max(2) - 1) as f64;
            let x = b.xl + span * (0.5 - 0.5 * (2.0 * PI * cycles * tau).cos());
            let y = 0.5 * (b.yt + b.yb) + amp * (2.0 * PI * 1.5 * cycles * tau + ph).sin();
            (x, y)
        })
        .collect()
}

/// `occlusion`: a straight pass behind the occluder: free, partial, full, partial, free.
/// The pass is centred on the occluder and `speed`·(N − 1) px long (clamped to the frame), so
/// the speed sets how many frames each phase lasts.
fn occluder_pass(p: &ScenarioParams, b: &CentreBounds, rng: &mut Pcg64Mcg) -> Vec<(f64, f64)> {
    let n = p.frames;
    let (w, h) = (f64::from(p.width), f64::from(p.height));
    let ox = p.occluder.as_ref().map_or(0.5, |o| o.centre[0]) * (w - 1.0);
    let oy = p.occluder.as_ref().map_or(0.5, |o| o.centre[1]) * (h - 1.0);
    let half = 0.5 * p.motion.speed * (n.max(2) - 1) as f64;
    let (x_start, x_end) = ((ox - half).max(b.xl), (ox + half).min(b.xr));
    let reverse = rng.random::<bool>();
    let ph = rng.random::<f64>() * 2.0 * PI;
    (0..n)
        .map(|k| {
            let tau = k as f64 / (n.max(2) - 1) as f64;
            let tau = if reverse { 1.0 - tau } else { tau };
            let x = x_start + (x_end - x_start) * tau;
            let y = (oy + 4.0 * (2.0 * PI * tau + ph).sin()).clamp(b.yt, b.yb);
            (x, y)
        })
        .collect()
}

/// `distractor` and `zoom`: a slowly turning walk, bouncing off the bounds, with abrupt jumps
/// (O Table 1).
fn wandering_path(p: &ScenarioParams, b: &CentreBounds, rng: &mut Pcg64Mcg) -> Vec<(f64, f64)> {
    let n = p.frames;
    let CentreBounds { xl, xr, yt, yb } = *b;
    let mut x = 0.5 * (xl + xr) + 0.2 * (xr - xl) * (rng.random::<f64>() - 0.5);
    let mut y = 0.5 * (yt + yb) + 0.2 * (yb - yt) * (rng.random::<f64>() - 0.5);
    let mut dir = rng.random::<f64>() * 2.0 * PI;
    let mut next_jump = p
        .motion
        .jumps
        .as_ref()
        .map(|j| rng.random_range(j.interval[0]..=j.interval[1]));
    let mut jump_left = 0usize;
    let mut jump_v = (0.0, 0.0);
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        out.push((x, y));
        dir += 0.15 * (rng.random::<f64>() * 2.0 - 1.0);
        let (mut vx, mut vy) = (p.motion.speed * dir.cos(), p.motion.speed * dir.sin());
        if let (Some(j), Some(nj)) = (&p.motion.jumps, next_jump)
            && k + 1 == nj
        {
            jump_left = rng.random_range(j.duration[0]..=j.duration[1]);
            let sp = rng.random_range(j.speed[0]..=j.speed[1]);
            // Half the jumps head for the frame centre, so that the bounce off the frame
            // border does not undo them; the rest go anywhere.
            let toward = (0.5 * (yt + yb) - y).atan2(0.5 * (xl + xr) - x);
            let ang = if rng.random::<f64>() < 0.5 {
                rng.random::<f64>() * 2.0 * PI
            } else {
                toward
            };
            jump_v = (sp * ang.cos(), sp * ang.sin());
            next_jump = Some(k + 1 + jump_left + rng.random_range(j.interval[0]..=j.interval[1]));
        }
        if jump_left > 0 {
            (vx, vy) = jump_v;
            jump_left -= 1;
        }
        x += vx;
        y += vy;
        if x < xl || x > xr {
            x = x.clamp(xl, xr);
            dir = PI - dir;
            jump_v.0 = -jump_v.0;
        }
        if y < yt || y > yb {
            y = y.clamp(yt, yb);
            dir = -dir;
            jump_v.1 = -jump_v.1;
        }
    }
    out
}

/// Head turns: the texture slides sideways and back while the outline stays (O Fig. 8).
fn head_turn_offsets(p: &ScenarioParams, rng: &mut Pcg64Mcg) -> Vec<[f64; 2]> {
    let n = p.frames;
    let mut offsets = vec![[0.0f64, 0.0]; n];
    let Some(ht) = &p.head_turn else {
        return offsets;
    };
    for i in 0..ht.count {
        let mid = ((2 * i + 1) * n) / (2 * ht.count.max(1));
        let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
        let start = mid.saturating_sub(ht.duration);
        for (k, off) in offsets
            .iter_mut()
            .enumerate()
            .take((mid + ht.duration).min(n))
            .skip(start)
        {
            let t = if k <= mid {
                (k - start) as f64
            } else {
                (mid + ht.duration - k) as f64
            };
            off[0] += sign * ht.shift * smoothstep(t / ht.duration as f64);
        }
    }
    offsets
}

/// The distractor in frame `k`: beside the target at the gap of that frame, on the far side
/// when the near side would leave the frame.
fn place_distractor(
    p: &ScenarioParams,
    d: &crate::params::DistractorParams,
    target: &Ellipse,
    k: usize,
    d_phase: f64,
    g_phase: f64,
) -> Ellipse {
    let (w, h) = (f64::from(p.width), f64::from(p.height));
    let gap = d.gap[0]
        + (d.gap[1] - d.gap[0])
            * (0.5 + 0.5 * (2.0 * PI * k as f64 / d.gap_period + g_phase).cos());
    let mut phi = d_phase + d.angular_speed * k as f64;
    let place = |phi: f64| {
        // Identical symmetric convex shapes touch when the centres are 2·ρ(φ) apart.
        let dist = 2.0 * radius(target.a, target.b, phi) + gap;
        (target.cx + dist * phi.cos(), target.cy + dist * phi.sin())
    };
    let (mut x, mut y) = place(phi);
    if x < 0.0 || x > w - 1.0 || y < 0.0 || y > h - 1.0 {
        phi += PI;
        (x, y) = place(phi);
    }
    Ellipse {
        cx: x,
        cy: y,
        ..*target
    }
}
