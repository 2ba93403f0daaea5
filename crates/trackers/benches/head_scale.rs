//! Cost of one update against the target's and the frame's size: a 640×480 frame with a
//! 150×200 px head against a 320×240 frame with a 50×60 px head, 200 particles, one thread, for
//! `head` and for the presets that estimate motion (`m3`, `full`, whose motion is estimated at a
//! working scale set by the target's size). The frames are real when the development set sits
//! beside the checkout (`../shared/data/real/Boy/img/0001.jpg`, and the same frame halved),
//! synthetic texture otherwise; each update tracks the same frame again, so the cost is the
//! steady state (for `m3` and `full`, of estimating a zero motion). `head`'s abrupt-motion jump
//! searches the window for its detection on every frame; `head_no_jump` is `head` without it
//! (`reacquisition.detection_share` 0).

use std::hint::black_box;
use std::path::Path;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_main};
use trackers::{Frame, Preset, TrackerConfig, build};
use vision_core::Ellipse;

/// RGB bytes of a `w`×`h` frame: the real frame scaled to that size, or a hash texture.
fn rgb_frame(w: u32, h: u32) -> (Vec<u8>, &'static str) {
    let real =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/real/Boy/img/0001.jpg");
    if let Ok(img) = image::open(&real) {
        let img = img.resize_exact(w, h, image::imageops::FilterType::Triangle);
        return (img.to_rgb8().into_raw(), "real");
    }
    let mut out = Vec::with_capacity((w * h * 3) as usize);
    for y in 0..h {
        for x in 0..w {
            let z = (u64::from(x / 8) * 0x9E37_79B9_7F4A_7C15) ^ (u64::from(y / 8) * 0xC2B2_AE3D);
            let v = (z >> 56) as u8;
            out.extend([v, v / 2 + 60, 255 - v]);
        }
    }
    (out, "synthetic")
}

fn update_against_size(c: &mut Criterion, name: &str, config: &TrackerConfig) {
    let mut group = c.benchmark_group(format!("{name}_update_200_particles"));
    group.throughput(Throughput::Elements(1));
    group.sample_size(30);
    for (w, h, head_w, head_h) in [(320u32, 240u32, 50.0, 60.0), (640, 480, 150.0, 200.0)] {
        let (rgb, source) = rgb_frame(w, h);
        let grey: Vec<f32> = rgb
            .chunks(3)
            .map(|p| 0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2]))
            .collect();
        let (w, h) = (w as usize, h as usize);
        let Ok(frame) = Frame::with_rgb(w, h, &grey, &rgb) else {
            continue;
        };
        let start = Ellipse {
            cx: w as f64 / 2.0,
            cy: h as f64 / 2.5,
            a: head_w / 2.0,
            b: head_h / 2.0,
            angle: 0.0,
        };
        let Ok(mut tracker) = build(config.clone()) else {
            continue;
        };
        if tracker.init(frame, start).is_err() {
            continue;
        }
        let id = format!("{w}x{h}_head_{head_w}x{head_h}_{source}");
        group.bench_function(BenchmarkId::from_parameter(id), |b| {
            b.iter(|| black_box(tracker.update(frame).map(|e| e.bbox)));
        });
    }
    group.finish();
}

fn benches() {
    let mut c = Criterion::default().configure_from_args();
    for preset in [Preset::Head, Preset::M3, Preset::Full] {
        update_against_size(&mut c, preset.name(), &preset.config(200, 1));
    }
    let mut no_jump = Preset::Head.config(200, 1);
    if let Some(r) = no_jump.reacquisition.as_mut() {
        r.detection_share = 0.0;
    }
    update_against_size(&mut c, "head_no_jump", &no_jump);
}

criterion_main!(benches);
