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
