#![allow(missing_docs)]
use rand::SeedableRng;
use scene_synth::edges::*;
use scene_synth::*;

#[test]
fn sweep() {
    let det = EdgeDetector::default();
    let mut worst = [0.0f64; 3];
    let mut sums = [0.0f64; 3];
    for seed in 100..120u64 {
        let sc = Scene::new(&ScenarioParams::preset(Scenario::Mclutter), seed).unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
        let (w, h) = sc.size();
        for (i, r) in sc.background().regions.iter().enumerate() {
            let (mut edges, mut length) = (0usize, 0.0);
            for k in [0usize, 20, 40, 60, 80, 100] {
                let (img, truth) = sc.render_frame(k).unwrap();
                let data = to_f32(&img);
                let view = GrayView { width: w, height: h, data: &data };
                let e = truth.ellipse;
                let segs = random_segments(&mut rng, [r.x0 as f64, 0.0, r.x1 as f64, h as f64], 5.0, 40.0, 1000, |s| {
                    let len = s.length();
                    let (dx, dy) = ((s.p1[0] - s.p0[0]) / len, (s.p1[1] - s.p0[1]) / len);
                    (-5..=(len.ceil() as i64 + 5)).all(|t| e.signed_distance(s.p0[0] + t as f64 * dx, s.p0[1] + t as f64 * dy) > 4.0)
                });
                let mut s = EdgeScratch::default();
                for seg in &segs {
                    edges += count_edges(&view, seg, &det, &mut s);
                    length += seg.length();
                }
            }
            let l = edges as f64 / length;
            let rel = (l - r.requested) / r.requested;
            worst[i] = f64::max(worst[i], rel.abs());
            sums[i] += l / 20.0;
            println!("seed {seed} class {} calib {:.4} indep {:.4} rel {:+.3} n {}", i + 1, r.measured, l, rel, r.structures);
        }
    }
    println!("worst {worst:?} mean {sums:?}");
}
