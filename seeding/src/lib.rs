//! # seeding — one way to derive every random stream's seed
//!
//! Every random draw in h8swarm comes from a seeded generator of its own (docs/design.md §9: split
//! per robot and per purpose, never a global RNG). This crate is the one rule that names those
//! streams: the seed of a stream is [`derive()`]`(parent, index, purpose)`, where
//! - `parent` is the seed of what the stream belongs to (the run's master seed at the top);
//! - `index` tells apart the members of one family (robot i of a repeat, sensor k of a robot,
//!   the EEPROM chip at address 0x50 or 0x51);
//! - `purpose` says what the stream is for ([`Purpose`], the register of every stream).
//!
//! Seeds form a tree from the master seed down; each crate derives the part below the seed it
//! is handed, with the same function:
//!
//! ```text
//! master seed (h8swarm run --seed, h8swarm fit --seed)
//! ├─ bootstrap           derive(master, 0, Bootstrap)      (the summary's intervals)
//! └─ repeat r            derive(master, r, Repeat)
//!    ├─ world            derive(repeat, 0, World)          → world::World::new
//!    │  ├─ placement     derive(world, 0, Placement)
//!    │  └─ motor gains   derive(world, i, MotorGain)       (robot i)
//!    └─ robot i          derive(repeat, i, Robot)
//!       ├─ IR sensor k   derive(robot, k, IrSensor)        → sensors::IrSensor::new
//!       │  └─ spread, timing, noise: derive(sensor, 0, SensorSpread | SensorTiming | SensorNoise)
//!       ├─ EEPROMs       derive(robot, 0, Eeproms)         → the eeprom crate's chips
//!       │  └─ chip a     derive(eeproms, a, EepromWriteCycle | EepromPowerCut | EepromWear)
//!       ├─ weights       derive(robot, 0, Weights)         → the controller's xorshift32 seed
//!       ├─ random walk   derive(robot, 0, RandomWalk)
//!       ├─ fit distances derive(robot, 0, FitDistances)    (the fit report's one robot)
//!       └─ cost inputs   derive(robot, 0, CostInputs)      (the learner's cost summary)
//! ```
//!
//! Adding a robot, a repeat or a thread therefore changes nobody else's streams (docs/design.md §5), and
//! the fit report's robot for `--seed s` is robot 0 of repeat 0 of a run with master seed `s`.
//!
//! # Why a crate of its own
//! `sensors`, `eeprom` and `world` know nothing of each other (docs/design.md §9), yet each splits the
//! seed it is given into several streams of its own (a sensor's spread, timing and noise; a
//! chip's write-cycle, power-cut and wear streams; the world's placement and per-robot motor
//! gains). Plain `u64` seeds derived at the root alone would leave those splits to each crate's
//! own devising, which is how the project came to have four schemes. A dependency-free leaf
//! crate with one function lets every crate, and the root package, derive the same way
//! without knowing each other.
//!
//! # The mixing
//! [`mix64`] is the finaliser of SplitMix64 (Steele, Lea and Flood, "Fast splittable
//! pseudorandom number generators", OOPSLA 2014; the variant of `java.util.SplittableRandom`),
//! a bijection of `u64` with full avalanche. For a fixed purpose and index, distinct parents
//! give distinct seeds; for a fixed parent and purpose, distinct indices give distinct seeds
//! (robots of one repeat can never share a stream). Seeds of different purposes are unrelated
//! 64-bit values. Generators are seeded from the result with their own `seed_from_u64`.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

/// The golden-ratio increment of SplitMix64 (2^64 / φ, odd).
pub const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// What a random stream is for: the register of every stream in the project (see the crate
/// documentation for the tree they form). The discriminant is the purpose's code in
/// [`derive()`]; codes are never reused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u64)]
pub enum Purpose {
    /// One repeat of a run under the master seed (index: the repeat).
    Repeat = 1,
    /// The world of a repeat (index 0): the seed handed to `world`.
    World = 2,
    /// One robot of a repeat (index: the robot).
    Robot = 3,
    /// One IR sensor of a robot (index: 0 front, 1 rear, 2 left, 3 right): the seed handed to
    /// `sensors`.
    IrSensor = 4,
    /// The robot's EEPROM bus (index 0): the seed handed to `eeprom` for both chips.
    Eeproms = 5,
    /// The controller's fresh initial weights (index 0).
    Weights = 6,
    /// The random-walk control's behaviours (index 0).
    RandomWalk = 7,
    /// The random walk of the distances the fit report's sensors see (index 0).
    FitDistances = 8,
    /// The sensor codes and weights of the learner's cost summary (index 0).
    CostInputs = 9,
    /// The resamples of the summary's bootstrap intervals (index 0), under the master seed.
    Bootstrap = 10,
    /// Placement of the robots in the arena (index 0), under the world's seed.
    Placement = 16,
    /// The motor gain spread of one robot (index: the robot), under the world's seed.
    MotorGain = 17,
    /// A sensor's gain and offset, drawn once (index 0), under the sensor's seed.
    SensorSpread = 32,
    /// A sensor's refresh period, phase and jitter (index 0).
    SensorTiming = 33,
    /// A sensor's read noise and spikes (index 0).
    SensorNoise = 34,
    /// A chip's write-cycle times (index: the chip's I²C address), under the EEPROM bus's seed.
    EepromWriteCycle = 48,
    /// What a power cut leaves in the page being written (index: the chip's address).
    EepromPowerCut = 49,
    /// Bits stuck by wear past the endurance (index: the chip's address).
    EepromWear = 50,
}

/// SplitMix64's finaliser: a bijective mixer of `u64` (distinct inputs give distinct outputs)
/// whose every output bit depends on every input bit.
#[must_use]
pub const fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The seed of stream (`index`, `purpose`) under `parent`: the one derivation of the project.
#[must_use]
pub const fn derive(parent: u64, index: u64, purpose: Purpose) -> u64 {
    let tag = mix64((purpose as u64).wrapping_mul(GOLDEN_GAMMA));
    let keyed = mix64(parent ^ tag);
    mix64(keyed.wrapping_add(index.wrapping_add(1).wrapping_mul(GOLDEN_GAMMA)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mix64_is_splitmix64s_finaliser() {
        // SplitMix64 seeded with 0 outputs mix64(GOLDEN_GAMMA) first: the reference value
        // of the generator's published test vector.
        assert_eq!(mix64(GOLDEN_GAMMA), 0xE220_A839_7B1D_CDAF);
    }

    #[test]
    fn every_part_of_the_name_matters() {
        let base = derive(1, 0, Purpose::Robot);
        assert_ne!(base, derive(2, 0, Purpose::Robot));
        assert_ne!(base, derive(1, 1, Purpose::Robot));
        assert_ne!(base, derive(1, 0, Purpose::World));
        assert_eq!(base, derive(1, 0, Purpose::Robot));
    }

    #[test]
    fn robots_of_one_parent_never_share_a_seed() {
        // Distinct indices under one parent and purpose give distinct seeds (a bijection);
        // checked on a sample, with a sort to find duplicates.
        let mut seeds = [0u64; 4096];
        for (i, s) in seeds.iter_mut().enumerate() {
            *s = derive(7, i as u64, Purpose::Robot);
        }
        seeds.sort_unstable();
        assert!(seeds.windows(2).all(|w| w[0] != w[1]));
    }
}
