//! What one firmware robot of a run can be watched with: a pin trace (VCD), a profile of its
//! states by call stack, a GDB client.

use crate::robot::Condition;
use crate::scenario::Scenario;

/// A pin trace of one firmware robot over a window of steps, written as a VCD file
/// (`h8swarm run --vcd`).
#[derive(Clone, Debug)]
pub struct VcdProbe {
    /// The robot.
    pub robot: usize,
    /// The first traced step: the trace starts where the robot's MCU is before it (asleep
    /// after the previous step's work, or at reset for step 0).
    pub from: u32,
    /// Traced steps: the trace ends when the step after the last one begins sensing (so the
    /// last step's behaviour shows to its end), or with the run.
    pub steps: u32,
    /// The file the trace is written to (a staging file, moved into place by the caller).
    pub path: std::path::PathBuf,
    /// The file as the user named it, for messages.
    pub shown: std::path::PathBuf,
}

/// What to look at inside one robot of a run: its pins, its firmware under GDB.
#[derive(Debug, Default)]
pub struct RobotProbes {
    /// A pin trace.
    pub vcd: Option<VcdProbe>,
    /// A GDB stub for a robot, waiting for its client: (robot, listener). The run waits for
    /// the client before its first step and pauses while it has the robot stopped.
    pub gdb: Option<(usize, h8_3052f::gdb::GdbListener)>,
    /// A profile of where one firmware robot's states go by call stack, written as folded
    /// stacks when the run ends.
    pub profile: Option<ProfileProbe>,
}

/// A profile of one firmware robot's states by call stack ([`RobotProbes::profile`]).
#[derive(Debug)]
pub struct ProfileProbe {
    /// The robot.
    pub robot: usize,
    /// The file the folded stacks are written to (a staging file, moved into place by the
    /// caller).
    pub path: std::path::PathBuf,
    /// The file as the user named it, for messages.
    pub shown: std::path::PathBuf,
}

/// What the VCD file of `v` says of its trace.
pub(super) fn vcd_info(
    v: &VcdProbe,
    s: &Scenario,
    condition: Condition,
    repeat: u32,
) -> h8_3052f::vcd::VcdInfo {
    h8_3052f::vcd::VcdInfo {
        source: format!(
            "robot {} of h8swarm run {} ({} run, repeat {repeat}, seed {}), steps {} to {}",
            v.robot,
            s.name,
            condition.name(),
            s.seed,
            v.from,
            (v.from + v.steps).min(s.steps) - 1
        ),
    }
}
