//! Counter-based derivation of random streams.
//!
//! A run must be a pure function of its inputs and one `seed`, also when rayon spreads particles
//! over any number of threads. So no generator is shared between particles: each particle's
//! generator is built afresh from the triple (seed, step, particle index), and the resampler's from
//! (seed, step, [`RESAMPLER_STREAM`]). The triple is hashed with the SplitMix64 finaliser (a
//! bijective avalanche mix), so neighbouring indices give unrelated 128-bit PCG states.

use rand_pcg::Pcg64Mcg;

/// The stream index reserved for the resampler; particle indices never reach it.
pub const RESAMPLER_STREAM: u64 = u64::MAX;

/// The SplitMix64 output function: a bijection on `u64` with full avalanche.
#[inline]
#[must_use]
pub fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The generator of stream `stream` at step `step` of a run seeded with `seed`.
///
/// # Examples
/// ```
/// use rand::Rng;
/// let mut a = smc_core::rng::stream_rng(7, 3, 11);
/// let mut b = smc_core::rng::stream_rng(7, 3, 11);
/// assert_eq!(a.random::<u64>(), b.random::<u64>());
/// ```
#[inline]
#[must_use]
pub fn stream_rng(seed: u64, step: u64, stream: u64) -> Pcg64Mcg {
    // Chain the three words through the mix, so that (seed, step, stream) and any permutation of
    // it land in different places.
    let h = splitmix64(splitmix64(splitmix64(seed) ^ step) ^ stream);
    let hi = splitmix64(h ^ 0xD1B5_4A32_D192_ED03);
    let lo = splitmix64(h);
    Pcg64Mcg::new((u128::from(hi) << 64) | u128::from(lo))
}

/// The generator of particle `index` at step `step`.
#[inline]
#[must_use]
pub fn particle_rng(seed: u64, step: u64, index: usize) -> Pcg64Mcg {
    stream_rng(seed, step, index as u64)
}

/// The resampler's generator at step `step`.
#[inline]
#[must_use]
pub fn resampler_rng(seed: u64, step: u64) -> Pcg64Mcg {
    stream_rng(seed, step, RESAMPLER_STREAM)
}

/// Mixed into the seed of the backward smoothers, so that a smoother given the filter's seed
/// does not replay the filter's particle streams.
pub const BACKWARD_SALT: u64 = 0x6261_636B_7761_7264;

/// The generator of backward trajectory `trajectory` at history frame `frame` (see
/// [`crate::smooth`]).
#[inline]
#[must_use]
pub fn backward_rng(seed: u64, frame: usize, trajectory: usize) -> Pcg64Mcg {
    stream_rng(seed ^ BACKWARD_SALT, frame as u64, trajectory as u64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    #[test]
    fn streams_differ_between_particles_steps_and_seeds() {
        let first = |s: u64, k: u64, i: u64| stream_rng(s, k, i).random::<u64>();
        let base = first(1, 2, 3);
        assert_ne!(base, first(1, 2, 4));
        assert_ne!(base, first(1, 3, 3));
        assert_ne!(base, first(2, 2, 3));
        // A permuted triple is a different stream.
        assert_ne!(base, first(3, 2, 1));
        assert_ne!(first(0, 0, 0), first(0, 0, RESAMPLER_STREAM));
    }

    #[test]
    fn neighbouring_streams_look_independent() {
        // The first uniforms of 20,000 consecutive particle streams should be uniform on [0, 1):
        // mean 1/2 with standard error sqrt(1/12/20000) ≈ 0.002, so 0.01 is a 5-sigma bound;
        // the lag-one correlation has standard error 1/sqrt(20000) ≈ 0.007, bound 0.035.
        let n = 20_000;
        let u: Vec<f64> = (0..n)
            .map(|i| particle_rng(42, 5, i).random::<f64>())
            .collect();
        let mean = u.iter().sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 0.01, "mean {mean}");
        let var = u.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        let lag1 = u
            .windows(2)
            .map(|w| (w[0] - mean) * (w[1] - mean))
            .sum::<f64>()
            / ((n - 1) as f64 * var);
        assert!(lag1.abs() < 0.035, "lag-one correlation {lag1}");
    }
}
