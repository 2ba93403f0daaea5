//! A profiling driver, not an example of use (for that, see the crate's README): the
//! benchmark's frame and 200 hypotheses
//! (`cargo run --release -p contour-obs --example obs_profile -- ARGS`):
//!
//! - `hash`: every batch value (Odobez, Wu, occlusion × 15 and 40 lines, sequential and rayon)
//!   as one FNV-1a hash of their bits, per set and in total, to check that a change keeps the
//!   results bit for bit;
//! - `CASE LINES N [par]` with CASE `odobez`, `wu` or `occlusion`: N batches, then the fastest
//!   and the median time per batch (the fastest is the figure least affected by other
//!   processes on a shared machine); under `perf record` or `callgrind` use N of 1 or more.
#![allow(missing_docs, clippy::unwrap_used, clippy::print_stdout)]

use std::hint::black_box;
use std::time::Instant;

use contour_obs::{
    LineSettings, OcclusionLikelihood, OdobezLikelihood, OdobezSettings, Template, WuLikelihood,
    WuSettings,
};
use vision_core::GreyImage;

#[path = "common/frame.rs"]
mod frame;
use frame::{H, N, W, scene};

/// The three likelihoods for `n_lines` lines.
fn likelihoods(n_lines: usize) -> (OdobezLikelihood, WuLikelihood, OcclusionLikelihood) {
    let lines = LineSettings {
        n_lines,
        ..LineSettings::default()
    };
    let od = OdobezSettings {
        lines,
        ..Default::default()
    };
    let wu = WuSettings {
        lines,
        ..Default::default()
    };
    (
        OdobezLikelihood::new(od, &Template::UnitCircle).unwrap(),
        WuLikelihood::new(wu, &Template::UnitCircle).unwrap(),
        OcclusionLikelihood::new(wu, &Template::UnitCircle).unwrap(),
    )
}

fn fnv(values: &[f64], mut h: u64) -> u64 {
    for v in values {
        for b in v.to_bits().to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
        }
    }
    h
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let s = scene();
    let image = GreyImage::new(W, H, &s.data).unwrap();
    let mut out = vec![0.0; N];
    if args.first().map(String::as_str) == Some("hash") {
        let mut total = 0xcbf2_9ce4_8422_2325u64;
        for n_lines in [15, 40] {
            let (od, wu, occ) = likelihoods(n_lines);
            let mut ws = od.workspace().unwrap();
            let mut sets: Vec<(&str, Vec<f64>)> = Vec::new();
            od.log_likelihood_batch(&mut ws, &image, &s.poses, &mut out)
                .unwrap();
            sets.push(("odobez", out.clone()));
            wu.log_likelihood_batch(&mut ws, &image, &s.poses, &s.lambdas, &mut out)
                .unwrap();
            sets.push(("wu", out.clone()));
            occ.log_likelihood_batch(&mut ws, &image, &s.poses, &s.lambdas, &s.gammas, &mut out)
                .unwrap();
            sets.push(("occlusion", out.clone()));
            od.log_likelihood_batch_par(&image, &s.poses, &mut out)
                .unwrap();
            sets.push(("odobez par", out.clone()));
            wu.log_likelihood_batch_par(&image, &s.poses, &s.lambdas, &mut out)
                .unwrap();
            sets.push(("wu par", out.clone()));
            occ.log_likelihood_batch_par(&image, &s.poses, &s.lambdas, &s.gammas, &mut out)
                .unwrap();
            sets.push(("occlusion par", out.clone()));
            for (name, values) in &sets {
                println!(
                    "{n_lines:>2} lines {name:<14} {:016x}",
                    fnv(values, 0xcbf2_9ce4_8422_2325)
                );
                total = fnv(values, total);
            }
        }
        println!("all {total:016x}");
        return;
    }
    let case = args.first().map_or("odobez", String::as_str);
    let n_lines: usize = args.get(1).map_or(40, |a| a.parse().unwrap());
    let runs: usize = args.get(2).map_or(500, |a| a.parse().unwrap());
    let par = args.get(3).is_some_and(|a| a == "par");
    let (od, wu, occ) = likelihoods(n_lines);
    let mut ws = od.workspace().unwrap();
    let (poses, lambdas, gammas) = (&s.poses, &s.lambdas, &s.gammas);
    let mut batch = || match (case, par) {
        ("odobez", false) => od.log_likelihood_batch(&mut ws, &image, poses, &mut out),
        ("odobez", true) => od.log_likelihood_batch_par(&image, poses, &mut out),
        ("wu", false) => wu.log_likelihood_batch(&mut ws, &image, poses, lambdas, &mut out),
        ("wu", true) => wu.log_likelihood_batch_par(&image, poses, lambdas, &mut out),
        ("occlusion", false) => {
            occ.log_likelihood_batch(&mut ws, &image, poses, lambdas, gammas, &mut out)
        }
        ("occlusion", true) => {
            occ.log_likelihood_batch_par(&image, poses, lambdas, gammas, &mut out)
        }
        _ => panic!("unknown case {case}"),
    };
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let t = Instant::now();
            black_box(batch()).unwrap();
            t.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    times.sort_by(f64::total_cmp);
    println!(
        "{case} {n_lines} lines{}: fastest {:.1} µs, median {:.1} µs ({runs} batches)",
        if par { " (rayon)" } else { "" },
        times[0],
        times[runs / 2]
    );
}
