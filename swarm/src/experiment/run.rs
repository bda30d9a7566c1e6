//! One run (a condition and a repeat) from its scenario to its outputs ([`run_one`]).

use super::output::RunOutput;
use super::probes::{RobotProbes, vcd_info};
use super::swarm_loop::Swarm;
use crate::robot::{Condition, Images, Robot};
use crate::scenario::Scenario;
use anyhow::{Context, Result};

/// How one run goes besides its scenario, condition and repeat: what it records and what looks
/// inside it. The run's results do not depend on any of it but `keep_going`.
#[derive(Debug, Default)]
pub struct RunOptions {
    /// Record the tracked robots' paths and outlines for the arena figure.
    pub record_track: bool,
    /// Go on when a robot's controller fails (see [`Swarm::set_keep_going`]).
    pub keep_going: bool,
    /// A file for the run's rows of `metrics.csv`, written as the steps complete
    /// ([`Swarm::set_rows`]).
    pub rows: Option<std::path::PathBuf>,
    /// Probes on one robot: a pin trace written as VCD, a GDB client's control.
    pub probes: RobotProbes,
    /// Record the run for the viewer: the recorder and how many robots it records.
    pub replay: Option<(crate::recording::Recorder, usize)>,
    /// What the firmware robots' stack guards do ([`Swarm::set_stack_guard_mode`]).
    pub stack_guard: h8300h::cpu::StackGuardMode,
    /// Stop a firmware robot at its first access to what the chip does not model
    /// ([`Swarm::set_strict_io`]).
    pub strict_io: bool,
    /// Keep a second worker spinning through the world's sub-steps
    /// ([`Swarm::set_spinning_helper`]): only when this run is its pool's only work.
    pub spinning_helper: bool,
}

/// Runs one condition of one repeat. `progress` is called with the number of steps done since
/// its last call.
///
/// # Errors
/// A world or controller failure (none is expected once the scenario checks out); a row file
/// that cannot be written; a probed robot that is no firmware robot; a GDB client that cannot
/// be accepted; a VCD file that cannot be written.
pub fn run_one(
    s: &Scenario,
    condition: Condition,
    repeat: u32,
    images: Option<&Images>,
    progress: &(dyn Fn(u64) + Sync),
    opts: RunOptions,
) -> Result<RunOutput> {
    let mut swarm = Swarm::new(s, condition, repeat, opts.record_track, images)?;
    swarm.set_keep_going(opts.keep_going);
    swarm.set_stack_guard_mode(opts.stack_guard);
    swarm.set_strict_io(opts.strict_io);
    swarm.set_spinning_helper(opts.spinning_helper);
    if let Some(path) = &opts.rows {
        swarm.set_rows(path)?;
    }
    if let Some((rec, robots)) = opts.replay {
        swarm.set_recorder(rec, robots);
    }
    let probes = opts.probes;
    let debugged = probes.gdb.as_ref().map(|(k, _)| *k);
    if let Some((k, listener)) = probes.gdb {
        let robot = swarm
            .robot_mut(k)
            .with_context(|| format!("--gdb-robot {k}: the run has {} robots", s.robots))?;
        let debugger = listener
            .accept()
            .with_context(|| format!("--gdb: waiting for a client for robot {k}"))?;
        robot
            .attach_debugger(debugger)
            .with_context(|| format!("--gdb-robot {k}"))?;
    }
    if let Some(k) = probes.profile.as_ref().map(|pr| &pr.robot) {
        swarm
            .robot_mut(*k)
            .with_context(|| format!("--profile-robot {k}: the run has {} robots", s.robots))?
            .start_profile()
            .with_context(|| format!("--profile-robot {k}"))?;
    }
    let mut tracing = false;
    for step in 0..s.steps {
        if let Some(v) = &probes.vcd {
            let robot = swarm.robot_mut(v.robot).with_context(|| {
                format!("--vcd-robot {}: the run has {} robots", v.robot, s.robots)
            })?;
            if step == v.from {
                let names = images
                    .map(|im| std::sync::Arc::new(im.for_robot(v.robot).symbols.clone()))
                    .with_context(|| {
                        format!("--vcd-robot {}: the robots run no firmware", v.robot)
                    })?;
                let file = std::fs::File::create(&v.path)
                    .with_context(|| format!("--vcd: cannot create `{}`", v.shown.display()))?;
                robot
                    .start_pin_trace(names, Box::new(file), &vcd_info(v, s, condition, repeat))
                    .with_context(|| format!("--vcd-robot {}", v.robot))?;
                tracing = true;
            }
            if tracing && step == v.from + v.steps {
                robot.end_pin_trace_at_sensing();
            }
        }
        swarm.step()?;
        if let Some(v) = &probes.vcd
            && let Some(written) = swarm.robot_mut(v.robot).and_then(Robot::take_pin_trace)
        {
            written.with_context(|| format!("--vcd: cannot write `{}`", v.shown.display()))?;
            tracing = false;
        }
        progress(1);
    }
    if let Some(v) = &probes.vcd
        && tracing
        && let Some(written) = swarm.robot_mut(v.robot).and_then(Robot::finish_pin_trace)
    {
        written.with_context(|| format!("--vcd: cannot write `{}`", v.shown.display()))?;
    }
    if let Some(robot) = debugged.and_then(|k| swarm.robot_mut(k)) {
        robot.detach_debugger();
    }
    if let Some(pr) = &probes.profile
        && let Some((folded, _)) = swarm.robot_mut(pr.robot).and_then(Robot::take_profile)
    {
        std::fs::write(&pr.path, folded)
            .map_err(anyhow::Error::new)
            .context(crate::output_error::OutputError::cannot_write(&pr.shown))?;
    }
    swarm.finish()
}
