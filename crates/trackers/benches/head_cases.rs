//! `head`'s update on real frames of three kinds, each while the track is locked and while it is
//! lost: 640×360 with a 67 px wide head, 352×288 with a 26 px wide face, 320×240 with a 60 px
//! face. 200 particles, one thread.
//!
//! Each case is built from the first [`FRAMES`] frames of a development clip
//! (`../shared/data/real`): every frame is scaled so that the first frame's labelled box has the
//! case's width, then cropped (or padded, by repeating its border) to the case's size by one
//! window placed around that box. The box keeps the clip's aspect ratio. The clip is played
//! forwards, then backwards, and so on, so that every update sees the clip's own motion.
//!
//! - **locked**: the frames as built; the track holds the head;
//! - **lost**: after initialisation on the first frame, every update sees the frames rolled by
//!   half their width, so that the target sits half a frame away, beyond every search, and the
//!   box where it was shows background. The bench first runs updates until the tracker reports
//!   [`TrackStatus::Lost`] (at most 100), and measures the updates that follow: the steady state
//!   of a lost track searching for its target.
//!
//! The 640×360 case is also run with `filter.parallel` on a pool of two threads
//! (`…_parallel2`): the same updates, the same estimates, spread over two cores.
//!
//! Without the development set beside the checkout the cases are skipped, saying so.

use std::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_main};
use trackers::{Frame, Preset, build};
use vision_core::{Ellipse, TrackStatus};

/// One kind of frame: a clip's first frame and labelled box (x, y, w, h), the frame size and the
/// box's width wanted.
struct Case {
    clip: &'static str,
    label: [f64; 4],
    size: (usize, usize),
    width: f64,
    /// Whether the case is also run on two threads.
    parallel: bool,
}

const CASES: [Case; 3] = [
    Case {
        clip: "DragonBaby",
        label: [160.0, 83.0, 56.0, 65.0],
        size: (640, 360),
        width: 67.0,
        parallel: true,
    },
    Case {
        clip: "Freeman1",
        label: [253.0, 66.0, 23.0, 28.0],
        size: (352, 288),
        width: 26.0,
        parallel: false,
    },
    Case {
        clip: "ytf_Albert_Brooks_0",
        label: [142.5, 67.5, 59.0, 59.0],
        size: (320, 240),
        width: 60.0,
        parallel: false,
    },
];

/// Frames of each clip played.
const FRAMES: usize = 40;

fn clip_frame(clip: &str, k: usize) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/real")
        .join(clip)
        .join(format!("img/{k:04}.jpg"))
}

/// The case's RGB frames and the head's ellipse in the first (the box's inscribed ellipse).
fn case_frames(case: &Case) -> Option<(Vec<Vec<u8>>, Ellipse)> {
    let s = case.width / case.label[2];
    let (w, h) = case.size;
    let [x, y, bw, bh] = case.label.map(|v| v * s);
    let (cx, cy) = (x + bw / 2.0, y + bh / 2.0);
    let mut frames = Vec::with_capacity(FRAMES);
    let mut origin = (0, 0);
    for k in 1..=FRAMES {
        let img = image::open(clip_frame(case.clip, k)).ok()?.to_rgb8();
        let (sw, sh) = (
            (f64::from(img.width()) * s).round() as u32,
            (f64::from(img.height()) * s).round() as u32,
        );
        let scaled = image::imageops::resize(&img, sw, sh, image::imageops::FilterType::Triangle);
        if k == 1 {
            origin = (window_offset(cx, w, sw), window_offset(cy, h, sh));
        }
        let (ox, oy) = origin;
        let mut rgb = Vec::with_capacity(w * h * 3);
        for yy in 0..h as i64 {
            for xx in 0..w as i64 {
                let px = (xx + ox).clamp(0, i64::from(sw) - 1) as u32;
                let py = (yy + oy).clamp(0, i64::from(sh) - 1) as u32;
                rgb.extend(scaled.get_pixel(px, py).0);
            }
        }
        frames.push(rgb);
    }
    let head = Ellipse {
        cx: cx - origin.0 as f64,
        cy: cy - origin.1 as f64,
        a: bw / 2.0,
        b: bh / 2.0,
        angle: 0.0,
    };
    Some((frames, head))
}

/// The offset, along one axis, of a window of `want` pixels in a scaled frame of `have`: centred
/// on `c`, inside the frame when it fits; the frame centred in the window when it does not.
fn window_offset(c: f64, want: usize, have: u32) -> i64 {
    let (want, have) = (want as f64, f64::from(have));
    if have >= want {
        (c - want / 2.0).clamp(0.0, have - want).round() as i64
    } else {
        -((want - have) / 2.0).round() as i64
    }
}

/// `rgb` (`w`×`h`) rolled left by half its width.
fn rolled(rgb: &[u8], w: usize) -> Vec<u8> {
    let row = 3 * w;
    let half = 3 * (w / 2);
    rgb.chunks(row)
        .flat_map(|r| r[half..].iter().chain(&r[..half]).copied())
        .collect()
}

fn grey_of(rgb: &[u8]) -> Vec<f32> {
    rgb.chunks(3)
        .map(|p| 0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2]))
        .collect()
}

/// Indices 1, 2, …, n − 1, n − 2, …, 0, 1, … : the clip forwards, backwards, and again.
fn ping_pong(n: usize) -> impl Iterator<Item = usize> {
    (1..n).chain((0..n - 1).rev()).cycle()
}

fn head_cases(c: &mut Criterion) {
    let mut group = c.benchmark_group("head_update_real_frames");
    group.throughput(Throughput::Elements(1));
    group.sample_size(30);
    for case in &CASES {
        let Some((rgb, head)) = case_frames(case) else {
            eprintln!(
                "head_cases: frames of {} not found, case skipped",
                case.clip
            );
            continue;
        };
        let (w, h) = case.size;
        let away_rgb: Vec<Vec<u8>> = rgb.iter().map(|f| rolled(f, w)).collect();
        let grey: Vec<Vec<f32>> = rgb.iter().map(|f| grey_of(f)).collect();
        let away_grey: Vec<Vec<f32>> = away_rgb.iter().map(|f| grey_of(f)).collect();
        let frame = |k: usize, lost: bool| {
            if lost {
                Frame::with_rgb(w, h, &away_grey[k], &away_rgb[k])
            } else {
                Frame::with_rgb(w, h, &grey[k], &rgb[k])
            }
        };
        let size = format!("{w}x{h}_target_{:.0}x{:.0}", 2.0 * head.a, 2.0 * head.b);
        let variants = [(false, false), (true, false)].into_iter().chain(
            case.parallel
                .then_some([(false, true), (true, true)])
                .into_iter()
                .flatten(),
        );
        for (lost, parallel) in variants {
            let mut config = Preset::Head.config(200, 1);
            config.filter.parallel = parallel;
            let threads = if parallel { 2 } else { 1 };
            let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(threads).build() else {
                continue;
            };
            let Ok(mut tracker) = build(config) else {
                continue;
            };
            let Ok(first) = frame(0, false) else {
                continue;
            };
            if tracker.init(first, head).is_err() {
                continue;
            }
            let mut order = ping_pong(FRAMES);
            if lost {
                let reached = (0..100).any(|_| {
                    let k = order.next().unwrap_or(0);
                    frame(k, true)
                        .and_then(|f| tracker.update(f))
                        .is_ok_and(|e| e.track_status() == TrackStatus::Lost)
                });
                if !reached {
                    eprintln!("head_cases: {size} never reported lost; case skipped");
                    continue;
                }
            }
            let id = format!(
                "{size}_{}{}",
                if lost { "lost" } else { "locked" },
                if parallel { "_parallel2" } else { "" }
            );
            group.bench_function(BenchmarkId::from_parameter(id), |b| {
                pool.install(|| {
                    b.iter(|| {
                        let k = order.next().unwrap_or(0);
                        black_box(
                            frame(k, lost)
                                .and_then(|f| tracker.update(f))
                                .map(|e| e.bbox),
                        )
                    });
                });
            });
        }
    }
    group.finish();
}

#[allow(missing_docs)]
mod group {
    use criterion::criterion_group;
    criterion_group!(benches, super::head_cases);
}

criterion_main!(group::benches);
