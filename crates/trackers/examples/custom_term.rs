//! An observation term of your own, added to a preset's likelihood.
//!
//! ```sh
//! cargo run --release -p trackers --example custom_term
//! ```
//!
//! A term implements [`ObservationTerm`]: for a batch of particles it adds each one's
//! log-likelihood to `out` (the engine adds the terms together, so the weight is their product).
//! Here the term says what the user knows of the target: it is brighter than its surroundings.
//! Its log-likelihood is `weight` times the mean grey level inside the particle's ellipse minus
//! the mean in a ring around it, in units of 100 grey levels. It joins `m1`'s shape likelihood
//! through [`build_with_terms`]; the example tracks a bright disc that passes over the outline of
//! a circle of its size and prints the mean centre error of `m1` with and without the term, for
//! a few seeds.

use trackers::observation::{FrameContext, ObservationTerm};
use trackers::{Ellipse, Frame, Particle, Preset, build, build_with_terms};

/// The brightness contrast of the ellipse against a ring of 1.5 times its size.
#[derive(Debug)]
struct Brighter {
    /// Nats per 100 grey levels of contrast.
    weight: f64,
}

impl ObservationTerm for Brighter {
    fn name(&self) -> &'static str {
        "brighter than its surroundings"
    }

    fn add_log_likelihoods(
        &self,
        frame: &FrameContext<'_>,
        particles: &[Particle],
        out: &mut [f64],
    ) {
        let image = frame.current();
        for (p, o) in particles.iter().zip(out) {
            // A particle whose contour is not finite cannot be scored: −∞, never NaN.
            let Some(e) = frame.ellipse(p) else {
                *o = f64::NEG_INFINITY;
                continue;
            };
            let (mut inside, mut ring) = ((0.0, 0.0), (0.0, 0.0));
            let reach = 1.5 * e.a.max(e.b);
            let (x0, x1) = (
                (e.cx - reach).max(0.0) as usize,
                (e.cx + reach).max(0.0) as usize,
            );
            let (y0, y1) = (
                (e.cy - reach).max(0.0) as usize,
                (e.cy + reach).max(0.0) as usize,
            );
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let Some(v) = image.get(x, y) else { continue };
                    let (u, w) = ((x as f64 - e.cx) / e.a, (y as f64 - e.cy) / e.b);
                    let r2 = u * u + w * w;
                    let bucket = if r2 <= 1.0 {
                        &mut inside
                    } else if r2 <= 2.25 {
                        &mut ring
                    } else {
                        continue;
                    };
                    bucket.0 += f64::from(v);
                    bucket.1 += 1.0;
                }
            }
            let mean = |(sum, n): (f64, f64)| if n > 0.0 { sum / n } else { 0.0 };
            *o += self.weight * (mean(inside) - mean(ring)) / 100.0;
        }
    }
}

/// A dark frame with the bright outline of a circle of radius 12 at (80, 60) and a bright disc
/// of radius 12 at `centre`.
fn frame_at(centre: [f64; 2]) -> Vec<f32> {
    let (w, h) = (160, 120);
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64, (i / w) as f64);
            let disc = (x - centre[0]).hypot(y - centre[1]) < 12.0;
            let outline = ((x - 80.0).hypot(y - 60.0) - 12.0).abs() < 1.5;
            if disc || outline { 200.0 } else { 40.0 }
        })
        .collect()
}

fn run(mut tracker: Box<dyn trackers::Tracker>) -> Result<f64, trackers::Error> {
    let path = |k: usize| [30.0 + 3.0 * k as f64, 62.0];
    let first = frame_at(path(0));
    let start = Ellipse::new(30.0, 62.0, 12.0, 12.0, 0.0);
    tracker.init(Frame::new(160, 120, &first)?, start)?;
    let mut error = 0.0;
    for k in 1..35 {
        let pixels = frame_at(path(k));
        let e = tracker.update(Frame::new(160, 120, &pixels)?)?.ellipse;
        error += (e.cx - path(k)[0]).hypot(e.cy - path(k)[1]);
    }
    Ok(error / 34.0)
}

fn main() -> Result<(), trackers::Error> {
    for seed in 1..=4 {
        let plain = run(build(Preset::M1.config(200, seed))?)?;
        let with_term = run(build_with_terms(
            Preset::M1.config(200, seed),
            vec![Box::new(Brighter { weight: 20.0 })],
        )?)?;
        println!(
            "seed {seed}: mean centre error {plain:5.1} px for m1, {with_term:5.1} px with the term"
        );
    }
    Ok(())
}
