//! Clustering particles for the motion proposal (Odobez §5): motion is estimated once per cluster,
//! on the support region of the cluster's mean, and used for every particle of the cluster.
//!
//! Odobez uses K = max(20, N/10) clusters but does not say how they are formed; here it is a few
//! Lloyd (k-means) iterations on the centre and scale of the current state, seeded
//! deterministically with evenly spaced particles, so that the result depends on nothing but the
//! particles.

use crate::particle::Particle;
use crate::space::{STATE_SLOTS, ShapeSpace, StateVector};

/// Reusable buffers of [`cluster_particles`].
#[derive(Debug, Clone, Default)]
pub struct Clustering {
    /// Mean state (`now`) of each cluster.
    pub means: Vec<StateVector>,
    /// Number of particles in each cluster.
    pub sizes: Vec<usize>,
    features: Vec<[f64; 3]>,
}

/// Assigns every particle to one of `k` clusters (written to `Particle::cluster`) and computes the
/// cluster means into `out`. Features are the centre and the scale of `now`, the scale weighted by
/// 2 so that a 10 % size difference counts like a shift of a fifth of the radius.
pub fn cluster_particles(
    space: ShapeSpace,
    particles: &mut [Particle],
    k: usize,
    iterations: usize,
    out: &mut Clustering,
) {
    let n = particles.len();
    let k = k.clamp(1, n.max(1));
    out.features.clear();
    out.features.extend(particles.iter().map(|p| {
        let c = space.centre(&p.now);
        [c[0], c[1], 2.0 * space.scale(&p.now)]
    }));
    let mut centres: Vec<[f64; 3]> = (0..k).map(|c| out.features[c * n / k]).collect();
    let assign = |f: &[f64; 3], centres: &[[f64; 3]]| -> u32 {
        let mut best = (0u32, f64::INFINITY);
        for (c, m) in centres.iter().enumerate() {
            let d = (f[0] - m[0]).powi(2) + (f[1] - m[1]).powi(2) + (f[2] - m[2]).powi(2);
            if d < best.1 {
                best = (c as u32, d);
            }
        }
        best.0
    };
    for _ in 0..iterations.max(1) {
        for (p, f) in particles.iter_mut().zip(&out.features) {
            p.cluster = assign(f, &centres);
        }
        let mut sums = vec![[0.0; 3]; k];
        let mut counts = vec![0usize; k];
        for (p, f) in particles.iter().zip(&out.features) {
            let c = p.cluster as usize;
            counts[c] += 1;
            for d in 0..3 {
                sums[c][d] += f[d];
            }
        }
        for c in 0..k {
            if counts[c] > 0 {
                for d in 0..3 {
                    centres[c][d] = sums[c][d] / counts[c] as f64;
                }
            }
        }
    }
    for (p, f) in particles.iter_mut().zip(&out.features) {
        p.cluster = assign(f, &centres);
    }
    out.means.clear();
    out.means.resize(k, [0.0; STATE_SLOTS]);
    out.sizes.clear();
    out.sizes.resize(k, 0);
    for p in particles.iter() {
        let c = p.cluster as usize;
        out.sizes[c] += 1;
        for j in 0..STATE_SLOTS {
            out.means[c][j] += p.now[j];
        }
    }
    for (m, &s) in out.means.iter_mut().zip(&out.sizes) {
        if s > 0 {
            for v in m.iter_mut() {
                *v /= s as f64;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particle::default_status;

    #[test]
    fn two_separated_groups_are_never_mixed() {
        let clutter = dbn_switch::ClutterState {
            beta: 0,
            lambda: 0.05,
        };
        let mut ps: Vec<Particle> = (0..100)
            .map(|i| {
                let x = if i % 2 == 0 { 50.0 } else { 200.0 } + (i % 7) as f64;
                Particle::at_rest([x, 100.0, 20.0, 1.0, 0.0, 0.0], clutter, default_status())
            })
            .collect();
        let mut c = Clustering::default();
        cluster_particles(ShapeSpace::Odobez, &mut ps, 20, 3, &mut c);
        assert_eq!(c.sizes.iter().sum::<usize>(), 100);
        for p in &ps {
            let m = c.means[p.cluster as usize];
            // Every member is within the spread of its own group (7 px), far from the other (150 px).
            assert!((m[0] - p.now[0]).abs() < 8.0, "{} vs {}", m[0], p.now[0]);
        }
    }
}
