//! What a run gives back: its metrics, each robot's record, the dead robots, the tracked
//! paths for the figures, the warnings and the charge drawn.

use super::metrics::RunMetrics;
use crate::motion::RobotTally;
use crate::robot::Condition;

/// What one run produced.
#[derive(Clone, Debug, PartialEq)]
pub struct RunOutput {
    /// The condition.
    pub condition: Condition,
    /// The repeat index.
    pub repeat: u32,
    /// Per-window sums of the per-step metrics (the steps themselves went to the run's CSV
    /// rows, when it had a file for them).
    pub metrics: RunMetrics,
    /// Paths and outlines, when asked for.
    pub track: Option<Track>,
    /// EEPROM records written over the run (all robots).
    pub saves: u64,
    /// Robots that died (with `--keep-going`): which, in which step, why.
    pub dead: Vec<DeadRobot>,
    /// Each robot's record over the run (distance, collisions, stuck spells), by index.
    pub robots: Vec<RobotTally>,
    /// With a recorder: the frames recorded and the frames with weights.
    pub recorded: Option<(u32, Vec<u32>)>,
    /// Firmware robots whose stack left its room under a warning guard, with the first fault.
    pub stack_warnings: Vec<(usize, String)>,
    /// The first access of each robot to each address its chip does not model, one line each.
    pub io_warnings: Vec<(usize, String)>,
    /// The charge every robot drew from its pack over the run, summed, by part.
    pub energy: crate::energy::Charge,
    /// How often the drive voltage's bound cut a motor's current, summed over the robots.
    pub motor_cap: crate::energy::CurrentCap,
    /// What the world's contact solver did over the run (islands solved, sweeps, islands the
    /// sweep cap stopped).
    pub solver: world::SolverStats,
}

/// A robot whose controller failed in a run with `--keep-going`: it is dead from then on (its
/// motors coast), and the run's claims leave its repeat out.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct DeadRobot {
    /// Its index.
    pub robot: usize,
    /// The step in which it died.
    pub step: u32,
    /// Why.
    pub why: String,
}

/// The arena figure shows the paths of the first and the last this many steps (the outlines
/// are recorded at the start and the end of each).
pub const SNAPSHOT_STEPS: usize = 200;

/// At most this many robots' paths are recorded for the arena figure.
pub const TRACKED_ROBOTS: usize = 40;

/// Robot paths and outlines for the arena figure.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Track {
    /// Per tracked robot, its centre at each of the first [`SNAPSHOT_STEPS`] steps (metres).
    pub early: Vec<Vec<(f64, f64)>>,
    /// Per tracked robot, its centre at each of the last [`SNAPSHOT_STEPS`] steps of the run
    /// (metres; the same steps as `early` in a run of fewer than twice as many steps).
    pub late: Vec<Vec<(f64, f64)>>,
    /// Outlines of the tracked robots at a few instants.
    pub outlines: Vec<Outline>,
    /// The arena's walls.
    pub walls: Vec<[(f64, f64); 2]>,
    /// Corridor only: per tracked robot, (step, position along the corridor in metres) every
    /// [`spacetime_stride`] steps and at the last step, for the space-time figure.
    pub spacetime: Vec<Vec<(f64, f64)>>,
}

/// A robot's outline at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outline {
    /// Robot number (the index of its path in a figure's paths).
    pub robot: usize,
    /// Time of the snapshot in seconds; outlines with equal times share a legend entry.
    pub time_s: f64,
    /// Corners of the body in metres, in order around it.
    pub corners: [(f64, f64); 4],
    /// Heading as a unit vector (any non-zero length is accepted and normalised).
    pub heading: (f64, f64),
}

/// The space-time figure's most samples per robot.
pub const SPACETIME_SAMPLES: u32 = 2000;

/// Steps between two samples of the space-time figure in a run of `steps` steps (every step
/// up to [`SPACETIME_SAMPLES`] steps).
#[must_use]
pub fn spacetime_stride(steps: u32) -> u32 {
    steps.div_ceil(SPACETIME_SAMPLES).max(1)
}
