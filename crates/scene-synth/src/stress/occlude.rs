//! `occlude`: partial occlusion by textured occluders cut from real frames. In seeded stretches
//! of `stretch_min`–`stretch_max` frames, separated by `gap_min`–`gap_max` clean frames, a
//! rectangle slides over the head's box from one side (seeded: left, right, top or bottom),
//! covering a fraction f of the box that sways smoothly between `cover_min` and `cover_max`
//! (period seeded in `sway_min`–`sway_max` frames). It slides in over `slide_frames` frames
//! before the stretch and out over as many after it. The rectangle reaches `overhang` box sizes
//! beyond the box on its side and `margin` box sizes past it across, so the covered share of
//! the box is f exactly; its texture is anchored to its inner edge and slides with it.
//!
//! Each occluder's texture is cut from a donor frame ([`Donor`]), away from the donor's own
//! target (its box grown by a quarter on each side never meets the cut): from other clips'
//! frames when the caller gives them, else from the clip's own frames, and never from a target.
//! The truth stays the whole head's box, as OTB labels it; the visible fraction 1 − f is
//! written beside it.

use image::RgbImage;
use rand::Rng;
use rand_pcg::Pcg64Mcg;
use serde::{Deserialize, Serialize};
use vision_core::BoundingBox;

use super::{Donor, bad};
use crate::error::{Error, Result};

/// The settings of `occlude`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Occlude {
    /// The smallest share of the box covered during a stretch. Default 0.3.
    pub cover_min: f64,
    /// The largest share covered. Default 0.7.
    pub cover_max: f64,
    /// The shortest stretch, in frames (≥ 1). Default 20.
    pub stretch_min: usize,
    /// The longest stretch. Default 100.
    pub stretch_max: usize,
    /// The fewest clean frames before a stretch (the first frame is always clean). Default 20.
    pub gap_min: usize,
    /// The most clean frames before a stretch. Default 60.
    pub gap_max: usize,
    /// Frames of sliding in before a stretch, and out after it. Default 5.
    pub slide_frames: usize,
    /// The shortest period of the sway between the two shares, in frames. Default 20.
    pub sway_min: f64,
    /// The longest period of the sway. Default 60.
    pub sway_max: f64,
    /// How far the occluder reaches beyond the box on its side, in box sizes. Default 0.5.
    pub overhang: f64,
    /// How far the occluder reaches past the box across, in box sizes. Default 0.15.
    pub margin: f64,
}

impl Default for Occlude {
    fn default() -> Self {
        Self {
            cover_min: 0.3,
            cover_max: 0.7,
            stretch_min: 20,
            stretch_max: 100,
            gap_min: 20,
            gap_max: 60,
            slide_frames: 5,
            sway_min: 20.0,
            sway_max: 60.0,
            overhang: 0.5,
            margin: 0.15,
        }
    }
}

/// Which side of the box an occluder comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    Left,
    Right,
    Top,
    Bottom,
}

/// One occlusion stretch.
#[derive(Debug, Clone)]
struct Stretch {
    /// First frame of the slide in.
    enter: usize,
    /// First and last-plus-one frames covered between the two shares.
    start: usize,
    end: usize,
    side: Side,
    sway: f64,
    phase: f64,
    texture: usize,
}

impl Occlude {
    /// Checks every field against its documented range.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] naming the first field out of range.
    pub fn validate(&self) -> Result<()> {
        if !(self.cover_min > 0.0 && self.cover_max >= self.cover_min && self.cover_max < 1.0) {
            return bad("occlude.cover_min", "need 0 < cover_min ≤ cover_max < 1");
        }
        if self.stretch_min == 0 || self.stretch_max < self.stretch_min {
            return bad("occlude.stretch_min", "need 1 ≤ stretch_min ≤ stretch_max");
        }
        if self.gap_min == 0 || self.gap_max < self.gap_min {
            return bad("occlude.gap_min", "need 1 ≤ gap_min ≤ gap_max");
        }
        if !(self.sway_min >= 2.0 && self.sway_max.is_finite() && self.sway_max >= self.sway_min) {
            return bad("occlude.sway_min", "need 2 ≤ sway_min ≤ sway_max, finite");
        }
        if !(self.overhang > 0.0 && self.overhang <= 4.0) {
            return bad("occlude.overhang", "must lie in (0, 4]");
        }
        if !(0.0..=1.0).contains(&self.margin) {
            return bad("occlude.margin", "must lie in [0, 1]");
        }
        Ok(())
    }

    pub(crate) fn plan(
        &self,
        truth: &[Option<BoundingBox>],
        donors: &[Donor],
        rng: &mut Pcg64Mcg,
    ) -> Result<OccludePlan> {
        if donors.is_empty() {
            return bad(
                "occlude",
                "needs donor frames to cut its occluders from (none given)",
            );
        }
        let boxes = held_boxes(truth);
        let n = truth.len();
        let mut stretches = Vec::new();
        let mut textures = Vec::new();
        let mut k = 0;
        loop {
            let enter = k + rng.random_range(self.gap_min..=self.gap_max);
            let start = enter + self.slide_frames;
            if start >= n {
                break;
            }
            let len = rng.random_range(self.stretch_min..=self.stretch_max);
            let end = (start + len).min(n);
            let side = [Side::Left, Side::Right, Side::Top, Side::Bottom][rng.random_range(0..4)];
            let sway = if self.sway_max > self.sway_min {
                rng.random_range(self.sway_min..=self.sway_max)
            } else {
                self.sway_min
            };
            let phase = rng.random_range(0.0..std::f64::consts::TAU);
            let Some(b) = boxes[start] else {
                k = end + self.slide_frames;
                continue;
            };
            // The texture's aspect: its length from the inner edge outward over its breadth.
            let (along, across) = match side {
                Side::Left | Side::Right => (b.w, b.h),
                Side::Top | Side::Bottom => (b.h, b.w),
            };
            let aspect =
                (self.cover_max + self.overhang) * along / ((1.0 + 2.0 * self.margin) * across);
            let aspect = match side {
                Side::Left | Side::Right => aspect,
                Side::Top | Side::Bottom => 1.0 / aspect,
            };
            textures.push(cut_texture(donors, aspect, rng)?);
            stretches.push(Stretch {
                enter,
                start,
                end,
                side,
                sway,
                phase,
                texture: textures.len() - 1,
            });
            k = end + self.slide_frames;
        }
        let mut plan = OccludePlan {
            settings: *self,
            stretches,
            textures,
            boxes,
            visible: Vec::new(),
        };
        plan.visible = (0..n)
            .map(|k| truth[k].map(|_| 1.0 - plan.cover(k).map_or(0.0, |(_, f)| f)))
            .collect();
        Ok(plan)
    }
}

/// Each frame's labelled box, or the last one before it (the first one before any).
fn held_boxes(truth: &[Option<BoundingBox>]) -> Vec<Option<BoundingBox>> {
    let first = truth.iter().flatten().next().copied();
    let mut last = first;
    truth
        .iter()
        .map(|b| {
            if let Some(b) = b {
                last = Some(*b);
            }
            last
        })
        .collect()
}

/// A texture of `aspect` (width over height) cut from a seeded donor frame, away from its target.
fn cut_texture(donors: &[Donor], aspect: f64, rng: &mut Pcg64Mcg) -> Result<RgbImage> {
    let first = rng.random_range(0..donors.len());
    for d in 0..donors.len() {
        let donor = &donors[(first + d) % donors.len()];
        let (w, h) = (
            f64::from(donor.frame.width()),
            f64::from(donor.frame.height()),
        );
        let keep_out = donor
            .target
            .map(|t| BoundingBox::new(t.x - 0.25 * t.w, t.y - 0.25 * t.h, 1.5 * t.w, 1.5 * t.h));
        let mut share = rng.random_range(0.3..=0.6);
        for _ in 0..6 {
            let mut rh = share * h;
            let mut rw = aspect * rh;
            if rw > 0.95 * w {
                rh *= 0.95 * w / rw;
                rw = 0.95 * w;
            }
            let (rw, rh) = (rw.round().max(2.0), rh.round().max(2.0));
            if rw <= w && rh <= h {
                for _ in 0..48 {
                    let x = rng.random_range(0.0..=(w - rw)).floor();
                    let y = rng.random_range(0.0..=(h - rh)).floor();
                    let region = BoundingBox::new(x - 0.5, y - 0.5, rw, rh);
                    let clear = keep_out.is_none_or(|k| {
                        region.x >= k.x + k.w
                            || k.x >= region.x + region.w
                            || region.y >= k.y + k.h
                            || k.y >= region.y + region.h
                    });
                    if clear {
                        return Ok(image::imageops::crop_imm(
                            &donor.frame,
                            x as u32,
                            y as u32,
                            rw as u32,
                            rh as u32,
                        )
                        .to_image());
                    }
                }
            }
            share *= 0.7;
        }
    }
    Err(Error::InvalidParameter {
        name: "occlude",
        reason: "no donor frame has room for an occluder away from its target".to_owned(),
    })
}

/// The planned occluders of a clip.
#[derive(Debug, Clone)]
pub(crate) struct OccludePlan {
    settings: Occlude,
    stretches: Vec<Stretch>,
    textures: Vec<RgbImage>,
    boxes: Vec<Option<BoundingBox>>,
    visible: Vec<Option<f64>>,
}

impl OccludePlan {
    /// The stretch over frame `k` and the share of the box it covers there.
    fn cover(&self, k: usize) -> Option<(&Stretch, f64)> {
        let s = self
            .stretches
            .iter()
            .find(|s| k >= s.enter && k < s.end + self.settings.slide_frames)?;
        let (lo, hi) = (self.settings.cover_min, self.settings.cover_max);
        let at = |t: usize| {
            let t = t as f64 - s.start as f64;
            lo + (hi - lo) * 0.5 * (1.0 - (std::f64::consts::TAU * t / s.sway + s.phase).cos())
        };
        let slide = (self.settings.slide_frames + 1) as f64;
        let f = if k < s.start {
            at(s.start) * (k + 1 - s.enter) as f64 / slide
        } else if k < s.end {
            at(k)
        } else {
            at(s.end - 1) * (s.end + self.settings.slide_frames - k) as f64 / slide
        };
        Some((s, f))
    }

    /// The visible share of each frame's box (`None` on unlabelled frames).
    pub(crate) fn visible(&self) -> &[Option<f64>] {
        &self.visible
    }

    pub(crate) fn apply(&self, k: usize, frame: &mut RgbImage) {
        let (Some((s, f)), Some(b)) = (self.cover(k), self.boxes[k]) else {
            return;
        };
        let Occlude {
            overhang,
            margin,
            cover_max,
            ..
        } = self.settings;
        // The rectangle [x0, x1) × [y0, y1), and the texture coordinates (along from the inner
        // edge, across) in [0, 1] of a point inside it.
        let reach = cover_max + overhang;
        let (x0, x1, y0, y1) = match s.side {
            Side::Left => (
                b.x - overhang * b.w,
                b.x + f * b.w,
                b.y - margin * b.h,
                b.y + (1.0 + margin) * b.h,
            ),
            Side::Right => (
                b.x + (1.0 - f) * b.w,
                b.x + (1.0 + overhang) * b.w,
                b.y - margin * b.h,
                b.y + (1.0 + margin) * b.h,
            ),
            Side::Top => (
                b.x - margin * b.w,
                b.x + (1.0 + margin) * b.w,
                b.y - overhang * b.h,
                b.y + f * b.h,
            ),
            Side::Bottom => (
                b.x - margin * b.w,
                b.x + (1.0 + margin) * b.w,
                b.y + (1.0 - f) * b.h,
                b.y + (1.0 + overhang) * b.h,
            ),
        };
        let tex = &self.textures[s.texture];
        let (tw, th) = (f64::from(tex.width()), f64::from(tex.height()));
        let (fw, fh) = frame.dimensions();
        let cols = (x0.ceil().max(0.0) as u32)..(x1.ceil().clamp(0.0, f64::from(fw)) as u32);
        let rows = (y0.ceil().max(0.0) as u32)..(y1.ceil().clamp(0.0, f64::from(fh)) as u32);
        for j in rows {
            for i in cols.clone() {
                let (x, y) = (f64::from(i), f64::from(j));
                // (u, v): u across the texture's width, v down its height.
                let (u, v) = match s.side {
                    Side::Left => ((x1 - x) / (reach * b.w), (y - y0) / (y1 - y0)),
                    Side::Right => ((x - x0) / (reach * b.w), (y - y0) / (y1 - y0)),
                    Side::Top => ((x - x0) / (x1 - x0), (y1 - y) / (reach * b.h)),
                    Side::Bottom => ((x - x0) / (x1 - x0), (y - y0) / (reach * b.h)),
                };
                let ti = (u * tw).floor().clamp(0.0, tw - 1.0) as u32;
                let tj = (v * th).floor().clamp(0.0, th - 1.0) as u32;
                frame.put_pixel(i, j, *tex.get_pixel(ti, tj));
            }
        }
    }

    pub(crate) fn describe(&self) -> serde_json::Value {
        let covered = self.visible.iter().flatten().filter(|&&v| v < 1.0).count();
        serde_json::json!({
            "stretches": self.stretches.iter().map(|s| [s.start + 1, s.end]).collect::<Vec<_>>(),
            "occluded_frames": covered,
        })
    }
}
