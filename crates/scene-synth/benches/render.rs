//! Rendering speed: frames per second at 320×240 for every scenario (the target is ≥ 200).
//! Scene construction (calibration, textures, trajectory) happens once, outside the timing.
// `criterion_group!` generates an undocumented public function.
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use scene_synth::{Scenario, ScenarioParams, Scene};

fn render(c: &mut Criterion) {
    let mut group = c.benchmark_group("render_frame_320x240");
    group.throughput(Throughput::Elements(1));
    for sc in Scenario::ALL {
        let p = ScenarioParams::preset(sc);
        let Ok(scene) = Scene::new(&p, 1) else {
            continue;
        };
        let (w, h) = scene.size();
        let mut out = vec![0u8; w * h];
        let mut scratch = Vec::with_capacity(w * h);
        let mut k = 0usize;
        group.bench_with_input(
            BenchmarkId::from_parameter(sc.name()),
            &scene,
            |b, scene| {
                b.iter(|| {
                    k = (k + 1) % scene.len();
                    black_box(
                        scene
                            .render_frame_into(black_box(k), &mut out, &mut scratch)
                            .ok(),
                    );
                });
            },
        );
    }
    group.finish();
    let mut g = c.benchmark_group("scene_new_320x240");
    g.sample_size(10);
    for sc in Scenario::ALL {
        let p = ScenarioParams::preset(sc);
        g.bench_with_input(BenchmarkId::from_parameter(sc.name()), &p, |b, p| {
            b.iter(|| black_box(Scene::new(black_box(p), 1).ok()));
        });
    }
    g.finish();
}

criterion_group!(benches, render);
criterion_main!(benches);
