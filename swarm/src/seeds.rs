//! The run's seeds: every random stream of a repeat, of its world and of each of its robots
//! comes from the master seed by the project's one derivation (`seeding::derive`, whose crate
//! documentation draws the whole tree of streams). The fit report's one robot is robot 0 of
//! repeat 0, so `h8swarm fit --seed s` measures the robot `h8swarm run --seed s` starts with.

use seeding::{Purpose, derive};

/// The seed of repeat `repeat` under the master seed.
#[must_use]
pub const fn repeat_seed(master: u64, repeat: u32) -> u64 {
    derive(master, repeat as u64, Purpose::Repeat)
}

/// The seed of the world of repeat `repeat` (placement and motor gains, split by `world`).
#[must_use]
pub const fn world_seed(master: u64, repeat: u32) -> u64 {
    derive(repeat_seed(master, repeat), 0, Purpose::World)
}

/// The seed of the summary's bootstrap resamples (the same resamples for every estimate of a
/// run, so two quantities' intervals come from the same draws).
#[must_use]
pub const fn bootstrap_seed(master: u64) -> u64 {
    derive(master, 0, Purpose::Bootstrap)
}

/// The seed of robot `robot` of repeat `repeat`.
#[must_use]
pub const fn robot_seed(master: u64, repeat: u32, robot: u32) -> u64 {
    derive(repeat_seed(master, repeat), robot as u64, Purpose::Robot)
}

/// Stream (`index`, `purpose`) of robot `robot` of repeat `repeat`: its IR sensor k
/// (`index` k, [`Purpose::IrSensor`]), its EEPROMs, its initial weights, its random walk.
#[must_use]
pub const fn robot_stream(
    master: u64,
    repeat: u32,
    robot: u32,
    index: u64,
    purpose: Purpose,
) -> u64 {
    derive(robot_seed(master, repeat, robot), index, purpose)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn robots_repeats_and_purposes_have_their_own_streams() {
        let a = robot_stream(1, 0, 0, 0, Purpose::Weights);
        assert_ne!(a, robot_stream(1, 0, 1, 0, Purpose::Weights));
        assert_ne!(a, robot_stream(1, 1, 0, 0, Purpose::Weights));
        assert_ne!(a, robot_stream(1, 0, 0, 0, Purpose::RandomWalk));
        assert_ne!(a, robot_stream(2, 0, 0, 0, Purpose::Weights));
        assert_ne!(world_seed(1, 0), world_seed(1, 1));
    }
}
