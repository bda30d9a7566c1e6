//! Seeded generator streams: one per sensor and per purpose, derived from the caller's seed.

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// The generator behind every stream (PCG XSL 128/64 MCG: fast, reproducible on every platform).
pub(crate) type StreamRng = Pcg64Mcg;

/// What a stream is used for; each purpose gets its own, independent stream.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Purpose {
    /// Per-sensor spread (gain, offset), drawn once.
    Spread = 1,
    /// Refresh timing: per-sensor period, phase, per-cycle jitter.
    Timing = 2,
    /// Read noise and spikes.
    Noise = 3,
}

/// SplitMix64's finaliser: a bijective mixer, so distinct inputs give distinct seeds.
const fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The stream for `purpose` of the sensor seeded with `seed`.
pub(crate) fn stream(seed: u64, purpose: Purpose) -> StreamRng {
    let tag = (purpose as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    StreamRng::seed_from_u64(mix64(seed ^ mix64(tag)))
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
    let z = mix64(key.wrapping_add(index.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15)));
    (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}
