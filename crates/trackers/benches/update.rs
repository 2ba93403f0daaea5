//! One tracker update per preset: 200 particles, 320×240 frames, one thread (the paper's setting
//! for its speed figures: M1 real time, M2 ≈ 20 frames/s, M3 ≈ 4 frames/s on a 2.5 GHz P4).

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_main};
use scene_synth::{Scenario, ScenarioParams, Scene};
use trackers::{Frame, Preset, build};
use vision_core::Ellipse;

fn update(c: &mut Criterion) {
    let mut params = ScenarioParams::preset(Scenario::Mclutter);
    params.frames = 40;
    let Ok(scene) = Scene::new(&params, 1) else {
        return;
    };
    let (w, h) = scene.size();
    let mut frames = Vec::new();
    let mut start = None;
    for k in 0..scene.len() {
        let Ok((img, truth)) = scene.render_frame(k) else {
            return;
        };
        frames.push(scene_synth::to_f32(&img));
        if k == 0 {
            let e = truth.ellipse;
            start = Some(Ellipse {
                cx: e.cx,
                cy: e.cy,
                a: e.a,
                b: e.b,
                angle: e.angle,
            });
        }
    }
    let Some(start) = start else {
        return;
    };
    let mut group = c.benchmark_group("tracker_update_200_particles_320x240");
    group.throughput(Throughput::Elements(1));
    group.sample_size(20);
    for preset in Preset::ALL {
        let Ok(mut tracker) = build(preset.config(200, 1)) else {
            continue;
        };
        let Ok(first) = Frame::new(w, h, &frames[0]) else {
            continue;
        };
        if tracker.init(first, start).is_err() {
            continue;
        }
        let mut k = 1;
        group.bench_function(BenchmarkId::from_parameter(preset.name()), |b| {
            b.iter(|| {
                // Walk through the clip; at its end, start again from the first frame.
                if k == frames.len() {
                    k = 1;
                    if let Ok(f) = Frame::new(w, h, &frames[0]) {
                        let _ = tracker.init(f, start);
                    }
                }
                if let Ok(f) = Frame::new(w, h, &frames[k]) {
                    let _ = black_box(tracker.update(f));
                }
                k += 1;
            });
        });
    }
    group.finish();
}

#[allow(missing_docs)]
mod group {
    use criterion::criterion_group;
    criterion_group!(benches, super::update);
}

criterion_main!(group::benches);
