//! From a scenario to its world: the arena, the world's parameters, the robots placed, and
//! the clock states of a step and of a nominal sub-step.

use crate::scenario::{ArenaKind, Scenario};
use crate::seeds::world_seed;
use anyhow::{Context, Result};
use world::{Arena, SensorMount, SubstepPlan, World, WorldParams};

/// The arena of a scenario (the square scaled to keep the paper's density for other than 3
/// robots).
///
/// # Errors
/// An arena the world refuses.
pub fn arena_of(s: &Scenario) -> Result<Arena> {
    Ok(match s.arena {
        ArenaKind::Corridor => Arena::corridor_with_clearance(
            world::params::BODY_WIDTH_M,
            s.world.corridor_clearance_m,
        )
        .context("arena")?,
        ArenaKind::Square if s.robots == world::arena::PAPER_ROBOTS => Arena::square(),
        ArenaKind::Square => Arena::scaled_square(s.robots).context("arena")?,
    })
}

/// The world parameters of a scenario.
#[must_use]
pub fn world_params(s: &Scenario) -> WorldParams {
    let (solver_iterations, solver_convergence) = s.world.solver.params();
    WorldParams {
        top_speed_m_per_s: s.world.top_speed_m_per_s,
        motor_time_constant_s: s.world.motor_time_constant_s,
        motor_gain_spread: s.world.motor_gain_spread,
        wheel_track_m: s.world.wheel_track_m,
        max_substep_s: s.world.substep_s,
        sensor_max_range_m: s.world.sensor_range_m,
        mu_wall: s.world.mu_wall,
        solver_iterations,
        solver_convergence,
        sensor_mounts: SensorMount::default_mounts(
            world::params::BODY_LENGTH_M,
            world::params::BODY_WIDTH_M,
        )
        .into_iter()
        .map(|m| {
            let (sin, cos) = libm::sincos(m.angle_rad);
            SensorMount {
                x_m: m.x_m - cos * s.world.sensor_setback_m,
                y_m: m.y_m - sin * s.world.sensor_setback_m,
                ..m
            }
        })
        .collect(),
        ..WorldParams::with_clock(u64::from(s.timing.clock_hz))
    }
}

/// Places the robots of a run (fails early, before any emulation, if they do not fit).
///
/// # Errors
/// More robots than the arena holds, or a placement that gives up.
pub fn build_world(s: &Scenario, repeat: u32) -> Result<World> {
    let seed = world_seed(s.seed, repeat);
    // The world's error names the robots, the arena and how many fit.
    World::new(arena_of(s)?, world_params(s), s.robots, seed).context("placing the robots")
}

/// The step period in clock states.
#[must_use]
pub fn period_states(s: &Scenario) -> u64 {
    (s.timing.step_period_s * f64::from(s.timing.clock_hz)).round() as u64
}

/// The nominal sub-step of a scenario, in clock states: the step period cut into the fewest
/// equal sub-steps of at most `world.substep_s` (the shorter length when they differ by one
/// state). A collision must last this long to count.
#[must_use]
pub fn nominal_substep_states(s: &Scenario) -> u64 {
    let max = (s.world.substep_s * f64::from(s.timing.clock_hz)).round() as u64;
    let period = period_states(s);
    let plan = SubstepPlan::new(period, max);
    period / plan.substeps().max(1)
}
