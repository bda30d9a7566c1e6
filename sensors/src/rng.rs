//! Seeded generator streams: one per sensor and per purpose, derived from the sensor's seed
//! with the project's one derivation ([`seeding::derive`]).

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use seeding::{GOLDEN_GAMMA, Purpose, mix64};

/// The generator behind every stream (PCG XSL 128/64 MCG: fast, reproducible on every platform).
pub(crate) type StreamRng = Pcg64Mcg;

/// The stream for `purpose` ([`Purpose::SensorSpread`], [`Purpose::SensorTiming`] or
/// [`Purpose::SensorNoise`]) of the sensor seeded with `seed`: `derive(seed, 0, purpose)`.
pub(crate) fn stream(seed: u64, purpose: Purpose) -> StreamRng {
    StreamRng::seed_from_u64(seeding::derive(seed, 0, purpose))
}

/// A uniform draw in `[0, 1)` with 53 random bits.
pub(crate) fn unit_f64<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A draw of the standard normal distribution N(0, 1): the polar method of Marsaglia and Bray
/// ("A convenient method for generating normal variables", SIAM Review 6(3), 1964): a point
/// drawn uniformly in the unit disc (the square's draws outside it, or at its centre, refused),
/// scaled by √(−2 ln s / s). The logarithm is the `libm` crate's, written in Rust, so a draw
/// is the same on every platform and C library (the host's `ln`, which `rand_distr` calls,
/// need not be).
pub(crate) fn standard_normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    loop {
        let u = 2.0 * unit_f64(rng) - 1.0;
        let v = 2.0 * unit_f64(rng) - 1.0;
        let s = u * u + v * v;
        if s > 0.0 && s < 1.0 {
            return u * libm::sqrt(-2.0 * libm::log(s) / s);
        }
    }
}

/// A uniform draw in `[lo, hi)` (`lo` when `hi == lo`).
pub(crate) fn uniform_f64<R: Rng + ?Sized>(rng: &mut R, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * unit_f64(rng)
}

/// A uniform draw in `[0, 1)` that depends only on `key` and `index` (SplitMix64 evaluated at
/// position `index`): lets a schedule jump to any cycle in O(1) and still be the same whatever
/// the pattern of calls that reached it.
pub(crate) fn counter_unit_f64(key: u64, index: u64) -> f64 {
    let z = mix64(key.wrapping_add(index.wrapping_add(1).wrapping_mul(GOLDEN_GAMMA)));
    (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_normal_draws_have_the_moments_and_tails_of_n01() {
        let mut rng = stream(7, Purpose::SensorNoise);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| standard_normal(&mut rng)).collect();
        let mean = xs.iter().sum::<f64>() / f64::from(n);
        let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / f64::from(n - 1);
        // Standard errors: 1/√n = 0.0022 for the mean, √(2/n) = 0.0032 for the variance.
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.015, "{var}");
        // P(|X| > 1.96) = 0.05, P(|X| > 3) = 0.0027.
        let beyond = |t: f64| xs.iter().filter(|x| x.abs() > t).count() as f64 / f64::from(n);
        assert!((beyond(1.96) - 0.05).abs() < 0.003, "{}", beyond(1.96));
        assert!((beyond(3.0) - 0.0027).abs() < 0.0006, "{}", beyond(3.0));
    }
}
