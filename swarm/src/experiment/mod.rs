//! The swarm experiment: robots (emulated MCU, controller, sensors, EEPROMs) in the world, step
//! after step, with the paper's metrics; deterministic.
//!
//! One run is one condition (learning, learning off, random walk) and one repeat ([`run_one`]).
//! Its parts, in the order a run uses them:
//! * [`setup`]: the scenario's world: the arena, the parameters, the robots placed;
//! * [`swarm_loop`]: the [`Swarm`], every robot stepped at the same instants (the steps are
//!   described there); `substeps` advances the world through a step's sub-steps and feeds the
//!   meters, `spin` keeps a second worker spinning through them;
//! * [`metrics`]: each step's metrics ([`StepMetrics`]), written as a CSV row and summed per
//!   window ([`RunMetrics`]);
//! * [`probes`]: a pin trace, a profile or a GDB client on one firmware robot;
//! * [`output`]: what a run gives back ([`RunOutput`]).
//!
//! Determinism: a run depends only on the scenario, the condition and the repeat; every random
//! stream is split per repeat, robot and purpose ([`crate::seeds`]); robots are processed in
//! index order (in parallel for large swarms, with results gathered in index order), so the
//! output is byte-identical for any thread count.

pub mod metrics;
pub mod output;
pub mod probes;
pub mod run;
pub mod setup;
mod spin;
mod substeps;
pub mod swarm_loop;

pub use metrics::{
    GAP_TOUCH_M, METRICS_HEADER, RunMetrics, StepMetrics, WindowSums, metrics_fields, metrics_row,
    motion_metrics,
};
pub use output::{
    DeadRobot, Outline, RunOutput, SNAPSHOT_STEPS, SPACETIME_SAMPLES, TRACKED_ROBOTS, Track,
    spacetime_stride,
};
pub use probes::{ProfileProbe, RobotProbes, VcdProbe};
pub use run::{RunOptions, run_one};
pub use setup::{arena_of, build_world, nominal_substep_states, period_states, world_params};
pub use swarm_loop::{PARALLEL_ROBOTS, Swarm};
