//! Breakdown point of the robust estimator: a background moving by a known affine
//! motion (2° rotation, 3 % scale, slight shear, translation (3, −2) about the region's centre)
//! with a square block of another texture, or of the same texture, translating on its own, over a
//! grid of block positions (corner, edge, centre of the region), relative motions of the block
//! ((−4, 3), (−1, 1), (4, −3), (8, 6) px added to the background's translation), block textures
//! (different, same) and several texture and noise draws (σ = 2 grey levels, 8-bit rounding).
//!
//! A fit *fails* when the mean corner error of the region against the background's motion is
//! above 0.5 px (failures are typically several pixels: a compromise between the two motions or
//! the block's motion). The bounds: in a 64×64 region no failure up to 39 % of the area
//! and at most 1 in 12 at 47 %; on the full 320×240 frame no failure up to 35 % and at most 1 in 8
//! at 45 %. A flagged estimate (`MotionEstimate::reliable == false`) counts as a failure too:
//! the tracker discards it.
//!
//! `cargo test -p motion-est --release --test integration breakdown:: -- --nocapture` prints the table.
//!
//! The texture is `tests/common`'s; every frame row is evaluated by rotating each sinusoid's
//! phasor along the row (`Texture::row`: the warped coordinates are affine in the column), which
//! makes the exact pairs cheap enough for a grid of several hundred estimates.
#![allow(missing_docs)]

use crate::common;

use common::Texture;
use motion_est::{ModelSpec, MotionEstimate, MotionEstimator, MotionModel, Region};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use vision_core::GreyImage;

/// Sinusoids per texture (wavelengths uniform in 3–40 px).
const COMPONENTS: usize = 120;
/// Standard deviation of a texture, grey levels.
const TEXTURE_STD: f64 = 40.0;
/// Texture draws per configuration of the 64×64 grid (each run has its own noise draw).
const DRAWS: u64 = 2;
/// The relative motions of the block, added to the background's translation.
const RELATIVE: [[f64; 2]; 4] = [[-4.0, 3.0], [-1.0, 1.0], [4.0, -3.0], [8.0, 6.0]];
/// The background's translation.
const T: [f64; 2] = [3.0, -2.0];
/// The failure threshold on the mean corner error, px.
const FAIL: f64 = 0.5;

/// The background's motion about `origin`: d(r) = t + A (r − origin).
#[derive(Clone, Copy)]
struct Affine {
    a: [f64; 6],
    origin: [f64; 2],
}

impl Affine {
    fn issue(origin: [f64; 2]) -> Self {
        let (s, c) = 2.0f64.to_radians().sin_cos();
        let k = 1.03;
        Self {
            a: [T[0], k * c - 1.0, -k * s + 0.005, T[1], k * s, k * c - 1.0],
            origin,
        }
    }

    fn displacement(&self, x: f64, y: f64) -> [f64; 2] {
        let (dx, dy) = (x - self.origin[0], y - self.origin[1]);
        let a = &self.a;
        [a[0] + a[1] * dx + a[2] * dy, a[3] + a[4] * dx + a[5] * dy]
    }

    /// The point r with r + d(r) = q.
    fn inverse(&self, q: [f64; 2]) -> [f64; 2] {
        let a = &self.a;
        let (m11, m12, m21, m22) = (1.0 + a[1], a[2], a[4], 1.0 + a[5]);
        let det = m11 * m22 - m12 * m21;
        let (bx, by) = (q[0] - self.origin[0] - a[0], q[1] - self.origin[1] - a[3]);
        [
            self.origin[0] + (m22 * bx - m12 * by) / det,
            self.origin[1] + (-m21 * bx + m11 * by) / det,
        ]
    }
}

/// Noise-free background frames of size w×h: frame 0 = texture, frame 1 = texture warped.
fn background(tex: &Texture, warp: &Affine, w: usize, h: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut f0, mut f1) = (vec![0.0; w * h], vec![0.0; w * h]);
    let r0 = warp.inverse([0.0, 0.0]);
    let r1 = warp.inverse([1.0, 0.0]);
    let dp = [r1[0] - r0[0], r1[1] - r0[1]];
    for j in 0..h {
        tex.row([0.0, j as f64], [1.0, 0.0], &mut f0[j * w..(j + 1) * w]);
        let p = warp.inverse([0.0, j as f64]);
        tex.row(p, dp, &mut f1[j * w..(j + 1) * w]);
    }
    (f0, f1)
}

/// Draws a square block of side `side` at (x, y) in frame 0 and at (x, y) + `shift` in frame 1,
/// showing `tex` in the block's own coordinates (`same`: the background texture itself, so that
/// the block is invisible in frame 0).
#[allow(clippy::too_many_arguments)]
fn draw_block(
    f: (&mut [f64], &mut [f64]),
    w: usize,
    h: usize,
    tex: &Texture,
    xy: [f64; 2],
    side: usize,
    shift: [f64; 2],
) {
    let mut row = vec![0.0; side];
    for (frame, o) in [(f.0, xy), (f.1, [xy[0] + shift[0], xy[1] + shift[1]])] {
        // Integer pixels inside [o, o + side).
        let i0 = o[0].ceil().max(0.0) as usize;
        let j0 = o[1].ceil().max(0.0) as usize;
        let i1 = ((o[0] + side as f64).ceil() as usize).min(w);
        let j1 = ((o[1] + side as f64).ceil() as usize).min(h);
        if i0 >= i1 {
            continue;
        }
        for j in j0..j1 {
            // Texture coordinates: the frame-0 position of the pixel, so the same-texture block
            // matches the background in frame 0.
            let p = [i0 as f64 - o[0] + xy[0], j as f64 - o[1] + xy[1]];
            tex.row(p, [1.0, 0.0], &mut row[..i1 - i0]);
            frame[j * w + i0..j * w + i1].copy_from_slice(&row[..i1 - i0]);
        }
    }
}

/// Adds N(0, 2²) noise and rounds to 8 bits.
fn noisy(clean: &[f64], seed: u64) -> Vec<f32> {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let n = Normal::new(0.0, 2.0).unwrap();
    clean
        .iter()
        .map(|v| (v + n.sample(&mut rng)).round().clamp(0.0, 255.0) as f32)
        .collect()
}

fn mean_corner_error(est: &MotionEstimate, truth: &Affine, b: [f64; 4]) -> f64 {
    [(b[0], b[1]), (b[2], b[1]), (b[0], b[3]), (b[2], b[3])]
        .iter()
        .map(|&(x, y)| {
            let d = est.displacement(x, y);
            let t = truth.displacement(x, y);
            (d[0] - t[0]).hypot(d[1] - t[1])
        })
        .sum::<f64>()
        / 4.0
}

#[derive(Clone, Copy, Debug)]
enum Place {
    Corner,
    Edge,
    Centre,
}

/// The scene: image size, the region (x, y, side w, side h), the block sides to test.
struct Scene {
    w: usize,
    h: usize,
    region: [usize; 4],
}

#[derive(Default, Debug)]
struct Tally {
    runs: usize,
    /// Error above `FAIL`, whatever the flag.
    wrong: usize,
    /// Error above `FAIL` and not flagged: a silent failure.
    silent: usize,
    /// Flagged (whatever the error).
    flagged: usize,
    /// Unflagged and matching neither motion present (the background's nor the block's).
    silent_any: usize,
    /// The largest error among the unflagged estimates.
    worst_unflagged: f64,
    /// Mean error over the accurate, unflagged estimates.
    ok_error: f64,
    ok: usize,
}

impl Tally {
    /// Failures as the tracker sees them: wrong or flagged.
    fn failures(&self) -> usize {
        self.runs - self.ok
    }
}

/// What every run over one scene shares: the region's centre (the warp's origin), the
/// background's warp, the region and its corners.
struct Geometry {
    centre: [f64; 2],
    warp: Affine,
    region: Region<'static>,
    corners: [f64; 4],
}

impl Geometry {
    fn of(scene: &Scene) -> Self {
        let [rx, ry, rw, rh] = scene.region;
        let centre = [
            rx as f64 + (rw as f64 - 1.0) / 2.0,
            ry as f64 + (rh as f64 - 1.0) / 2.0,
        ];
        let warp = Affine::issue(centre);
        let region = if rw == scene.w && rh == scene.h {
            Region::Full
        } else {
            Region::Rect {
                x: rx as f64,
                y: ry as f64,
                width: rw as f64,
                height: rh as f64,
            }
        };
        let corners = [
            rx as f64,
            ry as f64,
            (rx + rw - 1) as f64,
            (ry + rh - 1) as f64,
        ];
        Self {
            centre,
            warp,
            region,
            corners,
        }
    }
}

/// The top-left corner of a block of `side` at `place` in the scene's region.
fn block_origin(scene: &Scene, place: Place, side: usize) -> [f64; 2] {
    let [rx, ry, rw, rh] = scene.region;
    let (dx, dy) = match place {
        Place::Corner => (0, 0),
        Place::Edge => (0, (rh - side) / 2),
        Place::Centre => ((rw - side) / 2, (rh - side) / 2),
    };
    [(rx + dx) as f64, (ry + dy) as f64]
}

/// One block of texture `btex` at `xy` moving by `shift` over the warped background `b`, with
/// noise from `nseed`: the estimate over the region, and its mean corner errors against the
/// background's warp and against the block's shift.
#[allow(clippy::too_many_arguments)]
fn estimate_block(
    scene: &Scene,
    g: &Geometry,
    est: &MotionEstimator,
    b: (&[f64], &[f64]),
    btex: &Texture,
    xy: [f64; 2],
    side: usize,
    shift: [f64; 2],
    nseed: u64,
) -> (MotionEstimate, f64, f64) {
    let (mut c0, mut c1) = (b.0.to_vec(), b.1.to_vec());
    draw_block((&mut c0, &mut c1), scene.w, scene.h, btex, xy, side, shift);
    let f0 = noisy(&c0, nseed);
    let f1 = noisy(&c1, nseed + 1);
    let r = est
        .estimate_images(
            GreyImage::new(scene.w, scene.h, &f0).unwrap(),
            GreyImage::new(scene.w, scene.h, &f1).unwrap(),
            &g.region,
            ModelSpec::new(MotionModel::Affine, false),
            Some(g.centre),
        )
        // A flagged (unreliable) estimate is an error that carries it; the tally counts both.
        .or_else(motion_est::Error::into_unreliable)
        .unwrap();
    let e = mean_corner_error(&r, &g.warp, g.corners);
    let eb = mean_corner_error(
        &r,
        &Affine {
            a: [shift[0], 0.0, 0.0, shift[1], 0.0, 0.0],
            origin: g.centre,
        },
        g.corners,
    );
    (r, e, eb)
}

impl Tally {
    /// Counts one run of error `e` against the background's warp and `eb` against the block's
    /// shift; `case` names it in the report of a silent failure.
    fn count(&mut self, r: &MotionEstimate, e: f64, eb: f64, flagged: bool, case: &str) {
        self.runs += 1;
        if !flagged && e > FAIL && eb > FAIL {
            self.silent_any += 1;
        }
        if e > FAIL {
            self.wrong += 1;
            if !flagged {
                self.silent += 1;
                eprintln!(
                    "  silent failure: {case}: \
                     error {e:.3} px, scale {:.2}, inliers {:.2}, iterations {:?}",
                    r.scale, r.inlier_fraction, r.iterations
                );
            }
        }
        if flagged {
            self.flagged += 1;
        } else {
            self.worst_unflagged = self.worst_unflagged.max(e);
            if e <= FAIL {
                self.ok += 1;
                self.ok_error += e;
            }
        }
    }
}

/// Runs the grid for one block side: 3 places × 4 motions × 2 textures × `draws`.
fn grid(scene: &Scene, side: usize, est: &MotionEstimator, seed: u64, draws: u64) -> Tally {
    let g = Geometry::of(scene);
    let mut tally = Tally::default();
    for d in 0..draws {
        let tseed = seed + 100 * d;
        let tex = Texture::new(tseed, COMPONENTS, TEXTURE_STD);
        let other = Texture::new(tseed + 1, COMPONENTS, TEXTURE_STD);
        let (b0, b1) = background(&tex, &g.warp, scene.w, scene.h);
        for place in [Place::Corner, Place::Edge, Place::Centre] {
            let xy = block_origin(scene, place, side);
            for (m, rel) in RELATIVE.iter().enumerate() {
                for same in [false, true] {
                    let shift = [T[0] + rel[0], T[1] + rel[1]];
                    let btex = if same { &tex } else { &other };
                    let nseed = 1_000_000 * seed + 10_000 * d + 100 * m as u64 + 10 * same as u64;
                    let (r, e, eb) =
                        estimate_block(scene, &g, est, (&b0, &b1), btex, xy, side, shift, nseed);
                    let flagged = flagged(&r);
                    let case = format!("side {side} {place:?} rel {rel:?} same {same} draw {d}");
                    if std::env::var_os("BREAKDOWN_VERBOSE").is_some() && (e > FAIL || flagged) {
                        eprintln!(
                            "  {case}: e {e:.3} eb {eb:.3} \
                             reliable {} conv {} scale {:.2} inl {:.2} it {:?}",
                            r.reliable, r.converged, r.scale, r.inlier_fraction, r.iterations
                        );
                    }
                    tally.count(&r, e, eb, flagged, &case);
                }
            }
        }
    }
    if tally.ok > 0 {
        tally.ok_error /= tally.ok as f64;
    }
    tally
}

fn report(name: &str, side: usize, area: usize, t: &Tally) {
    eprintln!(
        "{name}: block {side}×{side} ({:.0} %): {} runs, wrong {}, flagged {}, silent {}, \
         failures {}, matching neither and unflagged {}, mean error of the rest {:.4} px, worst unflagged {:.3} px",
        100.0 * (side * side) as f64 / area as f64,
        t.runs,
        t.wrong,
        t.flagged,
        t.silent,
        t.failures(),
        t.silent_any,
        t.ok_error,
        t.worst_unflagged
    );
}

/// Whether the estimate says it failed.
fn flagged(r: &MotionEstimate) -> bool {
    !r.reliable
}

fn estimator() -> MotionEstimator {
    MotionEstimator::new(motion_est::Settings::default()).unwrap()
}

/// A 64×64 region at (32, 32) of a 128×128 image (the region's 32 px margin, as
/// `estimate_images` would use on a larger frame).
const REGION: Scene = Scene {
    w: 128,
    h: 128,
    region: [32, 32, 64, 64],
};

/// Runs the grid for each `(block side, allowed share of failures)` and checks that every
/// unflagged estimate describes one of the two motions present (never a compromise) and that
/// the failures stay within the allowed share.
fn check_grid(scene: &Scene, label: &str, cases: &[(usize, f64)], seed: u64, draws: u64) {
    let est = estimator();
    let pixels = scene.region[2] * scene.region[3];
    for (k, &(side, allowed)) in cases.iter().enumerate() {
        // Each block size on its own texture draws.
        let t = grid(scene, side, &est, seed + 1000 * k as u64, draws);
        report(label, side, pixels, &t);
        assert_eq!(t.silent_any, 0, "silent compromises: {t:?}");
        assert!(t.failures() as f64 <= allowed * t.runs as f64, "{t:?}");
    }
}

#[test]
fn region_64_breakdown_grid() {
    // 25, 32 and 39 % of the 4096 pixels: no failure; 47 %: at most 1 in 12 (the bounds).
    // At 47 % a different texture moving by 5–10 px relative to the background explains more
    // pixels than the background, whose pixels that the block covers in the second frame fit no
    // motion; the estimator counts those for the background, the surface behind (see
    // `src/occlusion.rs`). `BREAKDOWN_SEED=N` runs the grid on other texture and noise draws.
    let seed = std::env::var("BREAKDOWN_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(16);
    check_grid(
        &REGION,
        "64×64",
        &[(32, 0.0), (36, 0.0), (40, 0.0), (44, 1.0 / 12.0)],
        seed,
        DRAWS,
    );
}

#[test]
fn full_frame_breakdown_grid() {
    let scene = Scene {
        w: 320,
        h: 240,
        region: [0, 0, 320, 240],
    };
    // 35 and 45 % of the 76 800 pixels: no failure up to 35 %, at most 1 in 8 at 45 % (the
    // bounds). Full-frame estimates that need a re-start take ~0.1 s in the test
    // profile: by default one texture draw per block size (each size its own, each run its own
    // noise); `BREAKDOWN_FULL=1` runs two per size and adds 25 % (0 failures measured).
    let full = std::env::var_os("BREAKDOWN_FULL").is_some();
    let mut cases = vec![(164, 0.0), (186, 1.0 / 8.0)];
    if full {
        cases.insert(0, (139, 0.0));
    }
    check_grid(&scene, "320×240", &cases, 17, if full { 2 } else { 1 });
}

#[test]
fn a_failure_is_flagged() {
    // 60 % of the region moves on its own: the estimate must either describe one of the two
    // motions present (the background's, or the block's, which is then the dominant one) or be
    // flagged; never a compromise reported as reliable.
    let est = estimator();
    let side = 50; // 2500 / 4096 = 61 %.
    let t = grid(&REGION, side, &est, 18, DRAWS);
    report("64×64", side, 64 * 64, &t);
    // The grid above counts as silent only errors against the background; here an unflagged
    // estimate must match the background or the block.
    assert_eq!(t.silent_any, 0, "{t:?}");
}
