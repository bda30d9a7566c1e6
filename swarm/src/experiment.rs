//! The swarm experiment: robots (emulated MCU, controller, sensors, EEPROMs) in the world, step
//! after step, with the paper's metrics; repeats and controls in parallel; deterministic.
//!
//! One run is one condition (learning, learning off, random walk) and one repeat. Every robot's
//! MCU boots at time 0 and its controller ticks every 10 ms, so all robots step at the same
//! instants. At each step instant:
//! 1. every MCU sleeps up to the instant (ticks emulated);
//! 2. the world catches up under the motor commands of the previous step, in clock states (one
//!    clock rules it all: the world counts the states the MCUs count): the interval is cut
//!    into the fewest equal sub-steps of at most `world.substep_s` (lengths differing by at most
//!    one state, so no sliver of a sub-step arises), and every sub-step's bumpers feed each
//!    robot's [`ContactMeter`]: a collision is the start of a bumper contact that lasts at least
//!    one sub-step of the nominal length, counted for the behaviour that was running, and the
//!    time in contact is summed (see [`crate::collisions`]);
//! 3. every robot's four rays are cast, its controller runs the step on its MCU (the A/D
//!    samples the sensor models at the rays' distances), and its motor pins become the wheel
//!    commands of its body.
//!
//! The new behaviour's wheel commands apply from the step instant, not the ≈ 0.2 ms later the
//! controller writes GRB1/GRB2 (the world does not move during a step's computation). D is the
//! controller's own D(t) (summed du of its four readings), as the paper plots it.
//!
//! Determinism: a run depends only on the scenario, the condition and the repeat; every random
//! stream is split per repeat, robot and purpose ([`crate::seeds`]); robots are processed
//! in index order (in parallel for large swarms, with results gathered in index order), so the
//! output is byte-identical for any thread count.
//!
//! Memory: a run keeps no per-step history. Each step's metrics, complete one step later (its
//! behaviour's collisions are known when the next step begins), go as a row to the run's own
//! CSV file, when it has one ([`Swarm::set_rows`]), and into sums per window
//! ([`RunMetrics`]); the arena figure's paths are kept for the first and the last
//! [`SNAPSHOT_STEPS`] steps only. A run of 10⁶ steps needs the memory of one of 10³ steps
//! beside its window sums (one [`WindowSums`] per window).

use anyhow::{Context, Result};
use rayon::prelude::*;
use world::{Arena, SensorMount, SubstepPlan, World, WorldParams};

use crate::collisions::ContactMeter;
use crate::motion::{MotionClass, MotionStep, MotionTracker, RobotTally};

use crate::robot::{Condition, Images, Robot};
use crate::scenario::{ArenaKind, Scenario};
use crate::seeds::world_seed;

/// Swarms at least this large step their robots in parallel inside a run.
pub const PARALLEL_ROBOTS: usize = 64;
/// The arena figure shows the paths of the first and the last this many steps (the outlines
/// are recorded at the start and the end of each).
pub const SNAPSHOT_STEPS: usize = 200;
/// At most this many robots' paths are recorded for the arena figure.
pub const TRACKED_ROBOTS: usize = 40;
/// Corridor: neighbours closer than this touch, metres (in contact, or a push away); the gap
/// CV is undefined at a step in which any two do (the spacing of a jam means nothing).
pub const GAP_TOUCH_M: f64 = 0.01;

/// The metrics of one step of one run (docs/design.md §5).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepMetrics {
    /// Mean over robots of D(t), du.
    pub mean_d: f64,
    /// Collisions per robot during this step's behaviour.
    pub collisions_per_robot: f64,
    /// Mean over robots of the share of this step's behaviour spent with a bumper pressed
    /// (time in contact, weighted by sub-step length), percent.
    pub contact_percent: f64,
    /// Share of the robots held in place at the end of this step's behaviour, percent (see
    /// [`crate::motion`]).
    pub held_percent: f64,
    /// Share of the robots shuttling, percent.
    pub shuttling_percent: f64,
    /// Share of the robots circling, percent.
    pub circling_percent: f64,
    /// Share of the robots exploring, percent.
    pub exploring_percent: f64,
    /// Share of the robots that moved at least [`crate::collisions::MOVING_MIN_MM`] during
    /// this step's behaviour, percent (a reference: shuttlers move every step).
    pub moving_percent: f64,
    /// Mean over robots of how far the body's centre moved during this step's behaviour
    /// (straight-line distance between the two step instants), millimetres: 0 for a robot held
    /// against a wall or another body, about 67 mm for a free one driving straight in the
    /// arena. Not in the paper; it tells a robot that avoids obstacles from one that is stuck
    /// (both make no new collisions).
    pub moved_mm: f64,
    /// Mean over robots of the net displacement over the last [`crate::motion::LAG_STEPS`]
    /// steps per step ([`MotionStep::net_m`]), millimetres per step: the net progress.
    pub net_mm: f64,
    /// Mean over robots of the squared displacement over each of [`crate::motion::MSD_LAGS`] steps, cm², once
    /// the run is that long: the mean squared displacement.
    pub msd_cm2: [Option<f64>; 3],
    /// Mean over robots of the cells entered in the step that the robot had not been in for
    /// [`crate::motion::FRESH_STEPS`] steps.
    pub fresh_cells: f64,
    /// Mean over robots of the cells entered in the step that the robot had never been in.
    pub new_cells: f64,
    /// Corridor only: coefficient of variation of the gaps between neighbours at the step;
    /// none while two of them touch ([`GAP_TOUCH_M`]).
    pub gap_cv: Option<f64>,
    /// Corridor only: whether two neighbours touch at the step.
    pub touching: Option<bool>,
    /// Mean over robots of their MCU's CPU load over this step's period (percent): busy
    /// states (the step, the tick interrupts, the main loop; not the time asleep) over the
    /// period's states, as the robots' own clocks count them.
    pub cpu_load_percent: f64,
    /// Mean over robots of the energy each drew from its battery pack over this step
    /// (millijoules at the pack's nominal 12 V): the electronics over the step and the motors
    /// and bridges over its behaviour ([`crate::energy`]).
    pub energy_per_robot_mj: f64,
}

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

/// Sums of a run's per-step metrics over a span of steps: the summary's and the figure's
/// window values are these divided by the steps (means) or as they are (totals). The sums run
/// in step order, so they equal the sums of the same steps' metrics taken afterwards.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WindowSums {
    /// Steps summed.
    pub steps: u32,
    /// Sum of [`StepMetrics::mean_d`].
    pub mean_d: f64,
    /// Sum of [`StepMetrics::collisions_per_robot`].
    pub collisions_per_robot: f64,
    /// Sum of [`StepMetrics::contact_percent`].
    pub contact_percent: f64,
    /// Sum of [`StepMetrics::held_percent`].
    pub held_percent: f64,
    /// Sum of [`StepMetrics::shuttling_percent`].
    pub shuttling_percent: f64,
    /// Sum of [`StepMetrics::circling_percent`].
    pub circling_percent: f64,
    /// Sum of [`StepMetrics::exploring_percent`].
    pub exploring_percent: f64,
    /// Sum of [`StepMetrics::moving_percent`].
    pub moving_percent: f64,
    /// Sum of [`StepMetrics::moved_mm`].
    pub moved_mm: f64,
    /// Sum of [`StepMetrics::net_mm`].
    pub net_mm: f64,
    /// Sums of [`StepMetrics::msd_cm2`] over the steps that have them.
    pub msd_cm2: [f64; 3],
    /// Steps that have each of them.
    pub msd_steps: [u32; 3],
    /// Sum of [`StepMetrics::fresh_cells`].
    pub fresh_cells: f64,
    /// Sum of [`StepMetrics::new_cells`].
    pub new_cells: f64,
    /// Sum of [`StepMetrics::gap_cv`] over the steps that have one.
    pub gap_cv: f64,
    /// Steps that have a gap CV (in the corridor, those in which no neighbours touch).
    pub gap_cv_steps: u32,
    /// Corridor steps (none in the square).
    pub corridor_steps: u32,
    /// Corridor steps in which two neighbours touch.
    pub touching_steps: u32,
    /// Sum of [`StepMetrics::cpu_load_percent`].
    pub cpu_load_percent: f64,
    /// Sum of [`StepMetrics::energy_per_robot_mj`].
    pub energy_per_robot_mj: f64,
}

impl WindowSums {
    /// Adds one step's metrics.
    pub fn add(&mut self, m: &StepMetrics) {
        self.steps += 1;
        self.mean_d += m.mean_d;
        self.collisions_per_robot += m.collisions_per_robot;
        self.contact_percent += m.contact_percent;
        self.held_percent += m.held_percent;
        self.shuttling_percent += m.shuttling_percent;
        self.circling_percent += m.circling_percent;
        self.exploring_percent += m.exploring_percent;
        self.moving_percent += m.moving_percent;
        self.moved_mm += m.moved_mm;
        self.net_mm += m.net_mm;
        for (l, v) in m.msd_cm2.iter().enumerate() {
            if let Some(v) = v {
                self.msd_cm2[l] += v;
                self.msd_steps[l] += 1;
            }
        }
        self.fresh_cells += m.fresh_cells;
        self.new_cells += m.new_cells;
        if let Some(g) = m.gap_cv {
            self.gap_cv += g;
            self.gap_cv_steps += 1;
        }
        if let Some(t) = m.touching {
            self.corridor_steps += 1;
            self.touching_steps += u32::from(t);
        }
        self.cpu_load_percent += m.cpu_load_percent;
        self.energy_per_robot_mj += m.energy_per_robot_mj;
    }

    /// Whether the steps summed are a corridor's (they have a gap metric, defined or not).
    #[must_use]
    pub fn is_corridor(&self) -> bool {
        self.corridor_steps > 0
    }
}

/// What a run keeps of its per-step metrics: sums over windows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunMetrics {
    /// The window length, steps.
    pub window: u32,
    /// The run's planned steps.
    pub planned_steps: u32,
    /// One sum per window of `window` steps from step 0 (the last one partial when `window`
    /// does not divide the run); the learning figure's points are the whole ones, the summary's
    /// first window is the first.
    pub windows: Vec<WindowSums>,
    /// The summary's last window: steps `planned_steps - window..planned_steps`.
    pub last: WindowSums,
    /// Every step of the run.
    pub whole: WindowSums,
}

impl RunMetrics {
    /// Empty sums for a run of `planned_steps` steps in windows of `window` (at least 1).
    #[must_use]
    pub fn new(planned_steps: u32, window: u32) -> Self {
        Self {
            window: window.max(1),
            planned_steps,
            ..Self::default()
        }
    }

    /// Adds step `k`'s metrics (steps come in order, from 0).
    pub fn add(&mut self, k: u32, m: &StepMetrics) {
        let w = (k / self.window) as usize;
        if k.is_multiple_of(self.window) && w == self.windows.len() {
            self.windows.push(WindowSums::default());
        }
        if let Some(sums) = self.windows.get_mut(w) {
            sums.add(m);
        }
        if k < self.planned_steps && k >= self.planned_steps.saturating_sub(self.window) {
            self.last.add(m);
        }
        self.whole.add(m);
    }

    /// The summary's first window, steps `0..window` (empty before the first step).
    #[must_use]
    pub fn first(&self) -> &WindowSums {
        const NONE: WindowSums = WindowSums {
            steps: 0,
            mean_d: 0.0,
            collisions_per_robot: 0.0,
            contact_percent: 0.0,
            held_percent: 0.0,
            shuttling_percent: 0.0,
            circling_percent: 0.0,
            exploring_percent: 0.0,
            moving_percent: 0.0,
            moved_mm: 0.0,
            net_mm: 0.0,
            msd_cm2: [0.0; 3],
            msd_steps: [0; 3],
            fresh_cells: 0.0,
            new_cells: 0.0,
            gap_cv: 0.0,
            gap_cv_steps: 0,
            corridor_steps: 0,
            touching_steps: 0,
            cpu_load_percent: 0.0,
            energy_per_robot_mj: 0.0,
        };
        self.windows.first().unwrap_or(&NONE)
    }

    /// The whole windows (a trailing partial window left out).
    #[must_use]
    pub fn whole_windows(&self) -> &[WindowSums] {
        let whole = self
            .windows
            .iter()
            .take_while(|w| w.steps == self.window)
            .count();
        &self.windows[..whole]
    }
}

/// The columns of `metrics.csv`, one row per step of every run (the MSD columns' lags are
/// [`crate::motion::MSD_LAGS`]).
pub const METRICS_HEADER: [&str; 23] = [
    "condition",
    "repeat",
    "step",
    "mean_d",
    "collisions_per_robot",
    "contact_percent",
    "held_percent",
    "shuttling_percent",
    "circling_percent",
    "exploring_percent",
    "moving_percent",
    "moved_mm",
    "net_mm",
    "msd_1_cm2",
    "msd_10_cm2",
    "msd_100_cm2",
    "fresh_cells",
    "new_cells",
    "gap_cv",
    "robots_touching",
    "cpu_load_percent",
    "energy_per_robot_mj",
    "dead_robots",
];

/// Step `k`'s row of `metrics.csv` (see [`METRICS_HEADER`]) written into `buf` (cleared
/// first), field after field; `dead` robots had died by its end (`--keep-going`). Returns where
/// each field ends. A run writes its rows this way,
/// through one buffer, rather than a string per field.
pub fn metrics_fields(
    condition: Condition,
    repeat: u32,
    k: u32,
    m: &StepMetrics,
    dead: usize,
    buf: &mut String,
) -> [usize; 23] {
    use std::fmt::Write as _;
    buf.clear();
    let mut ends = [0usize; 23];
    let mut field = 0;
    let mut end = |buf: &String| {
        ends[field] = buf.len();
        field += 1;
    };
    buf.push_str(condition.name());
    end(buf);
    let _ = write!(buf, "{repeat}");
    end(buf);
    let _ = write!(buf, "{k}");
    end(buf);
    let opt = |buf: &mut String, v: Option<f64>| {
        if let Some(v) = v {
            let _ = write!(buf, "{v}");
        }
    };
    for v in [
        m.mean_d,
        m.collisions_per_robot,
        m.contact_percent,
        m.held_percent,
        m.shuttling_percent,
        m.circling_percent,
        m.exploring_percent,
        m.moving_percent,
        m.moved_mm,
        m.net_mm,
    ] {
        let _ = write!(buf, "{v}");
        end(buf);
    }
    for v in m.msd_cm2 {
        opt(buf, v);
        end(buf);
    }
    for v in [m.fresh_cells, m.new_cells] {
        let _ = write!(buf, "{v}");
        end(buf);
    }
    opt(buf, m.gap_cv);
    end(buf);
    if let Some(t) = m.touching {
        buf.push(if t { '1' } else { '0' });
    }
    end(buf);
    for v in [m.cpu_load_percent, m.energy_per_robot_mj] {
        let _ = write!(buf, "{v}");
        end(buf);
    }
    let _ = write!(buf, "{dead}");
    end(buf);
    ends
}

/// Step `k`'s row of `metrics.csv` (see [`METRICS_HEADER`]); `dead` robots had died by its
/// end (`--keep-going`).
#[must_use]
pub fn metrics_row(
    condition: Condition,
    repeat: u32,
    k: u32,
    m: &StepMetrics,
    dead: usize,
) -> [String; 23] {
    let mut buf = String::new();
    let ends = metrics_fields(condition, repeat, k, m, dead, &mut buf);
    std::array::from_fn(|i| buf[if i == 0 { 0 } else { ends[i - 1] }..ends[i]].to_string())
}

/// A run's rows of `metrics.csv`, written as the steps complete.
struct Rows {
    path: std::path::PathBuf,
    w: csv::Writer<std::io::BufWriter<std::fs::File>>,
    /// The row being written, field after field.
    buf: String,
}

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
    WorldParams {
        top_speed_m_per_s: s.world.top_speed_m_per_s,
        motor_time_constant_s: s.world.motor_time_constant_s,
        motor_gain_spread: s.world.motor_gain_spread,
        wheel_track_m: s.world.wheel_track_m,
        max_substep_s: s.world.substep_s,
        sensor_max_range_m: s.world.sensor_range_m,
        mu_wall: s.world.mu_wall,
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

/// One run in progress: the world and its robots, stepped one step at a time.
pub struct Swarm {
    scenario: Scenario,
    condition: Condition,
    repeat: u32,
    world: World,
    robots: Vec<Robot>,
    meters: Vec<ContactMeter>,
    /// Each robot's recent positions and cells.
    motion: Vec<MotionTracker>,
    /// Each robot's record over the run.
    tallies: Vec<RobotTally>,
    /// Collisions counted for each robot since its last tally.
    collided: Vec<u64>,
    /// The step period in clock states.
    period_states: u64,
    /// Steps begun.
    started: u32,
    /// The latest step's metrics, complete once the world has run its behaviour.
    pending: Option<StepMetrics>,
    /// Window sums of the completed steps.
    metrics: RunMetrics,
    /// Where the completed steps' rows go, if anywhere.
    rows: Option<Rows>,
    track: Option<Track>,
    tracked: usize,
    snapshots: [u32; 4],
    saves: u64,
    parallel: bool,
    /// The corridor's gaps, reused step to step.
    gaps: Vec<f64>,
    /// Go on when a robot's controller fails: the robot is dead from then on (its motors
    /// coast; it is left out of the means).
    keep_going: bool,
    /// The step in which each dead robot died, and why.
    dead: Vec<Option<(u32, String)>>,
    /// The replay recorder and how many robots it records, when the run is recorded.
    recorder: Option<(crate::recording::Recorder, usize)>,
    /// Each robot's motors and bridges, metered over the world's sub-steps.
    drives: Vec<crate::energy::DriveMeter>,
    /// The sub-steps' readings gathered for the meters.
    readings: Readings,
    /// The electronics' charge of the step being completed, summed over the live robots, and
    /// how many robots were live.
    pending_charge: (f64, usize),
    /// The charge of the whole run, by part.
    energy: crate::energy::Charge,
}

impl Swarm {
    /// Places the robots and boots every robot's MCU.
    ///
    /// # Errors
    /// Robots that do not fit the arena; a configuration the controller refuses.
    pub fn new(
        s: &Scenario,
        condition: Condition,
        repeat: u32,
        record_track: bool,
        images: Option<&Images>,
    ) -> Result<Self> {
        let n = s.robots;
        let world = build_world(s, repeat)?;
        // Each robot is built from its own seeds: on the pool for a large swarm, the first
        // failure in index order reported whatever the threads.
        let build = |i: usize| {
            Robot::new(s, condition, repeat, i as u32, images).with_context(|| format!("robot {i}"))
        };
        let built: Vec<Result<Robot>> = if n >= PARALLEL_ROBOTS {
            (0..n).into_par_iter().map(build).collect()
        } else {
            (0..n).map(build).collect()
        };
        let robots: Vec<Robot> = built.into_iter().collect::<Result<_>>()?;
        let tracked = if record_track {
            n.min(TRACKED_ROBOTS)
        } else {
            0
        };
        let k = SNAPSHOT_STEPS.min(s.steps as usize);
        let track = record_track.then(|| Track {
            early: vec![Vec::with_capacity(k); tracked],
            late: vec![Vec::with_capacity(k); tracked],
            outlines: Vec::new(),
            walls: world
                .arena()
                .walls()
                .iter()
                .map(|w| [(w.a.0, w.a.1), (w.b.0, w.b.1)])
                .collect(),
            spacetime: vec![Vec::new(); tracked],
        });
        let drives = (0..n)
            .map(|i| {
                world
                    .motor_gains(i)
                    .map(|g| crate::energy::DriveMeter::new(s.world.top_speed_m_per_s, g))
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            scenario: s.clone(),
            condition,
            repeat,
            world,
            robots,
            meters: vec![ContactMeter::new(nominal_substep_states(s)); n],
            motion: vec![MotionTracker::new(); n],
            tallies: vec![RobotTally::new(s.window); n],
            collided: vec![0; n],
            period_states: period_states(s),
            started: 0,
            pending: None,
            metrics: RunMetrics::new(s.steps, s.window),
            rows: None,
            track,
            tracked,
            snapshots: {
                let k = SNAPSHOT_STEPS as u32;
                let last = s.steps.saturating_sub(1);
                [0, k.min(last), s.steps.saturating_sub(k), last]
            },
            saves: 0,
            parallel: n >= PARALLEL_ROBOTS,
            gaps: Vec::new(),
            keep_going: false,
            dead: vec![None; n],
            recorder: None,
            drives,
            readings: Readings::default(),
            pending_charge: (0.0, 0),
            energy: crate::energy::Charge::default(),
        })
    }

    /// Writes every step's row of `metrics.csv` (no header; [`metrics_row`]) to a new file at
    /// `path` as the step completes.
    ///
    /// # Errors
    /// The file cannot be created (an [`crate::output_error::OutputError`]).
    pub fn set_rows(&mut self, path: &std::path::Path) -> Result<()> {
        let file = std::fs::File::create(path)
            .map_err(anyhow::Error::new)
            .context(crate::output_error::OutputError(format!(
                "cannot create `{}`",
                path.display()
            )))?;
        self.rows = Some(Rows {
            buf: String::with_capacity(256),
            path: path.to_path_buf(),
            w: csv::WriterBuilder::new()
                .has_headers(false)
                .from_writer(std::io::BufWriter::new(file)),
        });
        Ok(())
    }

    /// Records the run for the viewer: the first `robots` robots, into `recorder`.
    pub fn set_recorder(&mut self, recorder: crate::recording::Recorder, robots: usize) {
        self.recorder = Some((recorder, robots.min(self.robots.len())));
    }

    /// What the firmware robots' stack guards do when a stack access leaves the stack's room:
    /// stop the robot with an error (the default) or warn ([`RunOutput::stack_warnings`]).
    pub fn set_stack_guard_mode(&mut self, mode: h8300h::cpu::StackGuardMode) {
        for r in &mut self.robots {
            r.set_stack_guard_mode(mode);
        }
    }

    /// Whether the firmware robots stop at their first access to what the chip does not
    /// model (`--strict-io`) instead of reporting it ([`RunOutput::io_warnings`]).
    pub fn set_strict_io(&mut self, on: bool) {
        for r in &mut self.robots {
            r.set_strict_io(on);
        }
    }

    /// Whether a robot whose controller fails is marked dead and the run goes on (default:
    /// the run stops with the error).
    pub fn set_keep_going(&mut self, keep_going: bool) {
        self.keep_going = keep_going;
    }

    /// The robots that died, with the step and why.
    #[must_use]
    pub fn dead(&self) -> Vec<DeadRobot> {
        self.dead
            .iter()
            .enumerate()
            .filter_map(|(i, d)| {
                d.clone().map(|(step, why)| DeadRobot {
                    robot: i,
                    step,
                    why,
                })
            })
            .collect()
    }

    /// A robot's failure: the run's error, or with `keep_going` the robot's death.
    fn fail(&mut self, i: usize, e: anyhow::Error) -> Result<()> {
        let e = e.context(format!("robot {i}"));
        if self.keep_going {
            self.dead[i] = Some((self.started, format!("{e:#}")));
            Ok(())
        } else {
            Err(e)
        }
    }

    /// Robot `i` (its MCU, its controller), between steps; `None` past the last robot.
    pub fn robot_mut(&mut self, i: usize) -> Option<&mut Robot> {
        self.robots.get_mut(i)
    }

    /// The world the robots are in (poses, bumpers, wheel speeds), as of the latest step.
    #[must_use]
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Whether the robots are stepped in parallel (on rayon's current pool); by default from
    /// [`PARALLEL_ROBOTS`] robots on. The results do not depend on it.
    pub fn set_parallel(&mut self, parallel: bool) {
        self.parallel = parallel;
    }

    /// Whether this step's per-robot work goes on rayon's pool: [`Swarm::set_parallel`], on a
    /// pool of more than one thread (on one thread the parallel paths would only cost their
    /// chunking; the results are the same either way).
    fn par(&self) -> bool {
        self.parallel && rayon::current_num_threads() > 1
    }

    /// Runs the next step: every MCU sleeps to the step instant, the world catches up (its
    /// collisions are the previous step's), the robots sense, step and drive.
    ///
    /// # Errors
    /// A world or controller failure (none is expected once the scenario checks out).
    pub fn step(&mut self) -> Result<()> {
        let k = self.started;
        let t_step = self.sleep_all()?;
        let t_step_s = t_step as f64 / f64::from(self.scenario.timing.clock_hz);
        self.close_step(t_step)?;
        self.track_step(k, t_step_s)?;
        let senses = self.sense_all()?;
        let tally = self.step_robots(&senses)?;
        let behaviours = self.drive()?;
        self.record_frame(k, &tally.stepped, &behaviours, &senses)?;
        self.pending_charge = (tally.charge_uc, tally.live);
        let live_f = tally.live.max(1) as f64;
        let mean_d = tally.sum_d / live_f;
        let (gap_cv, touching) = match self.scenario.arena {
            ArenaKind::Corridor => {
                self.world.corridor_gaps_m(&mut self.gaps)?;
                let touching = self.gaps.iter().any(|&g| g < GAP_TOUCH_M);
                let cv = if touching {
                    None
                } else {
                    world::coefficient_of_variation(&self.gaps)
                };
                (cv, Some(touching))
            }
            ArenaKind::Square => (None, None),
        };
        self.started += 1;
        self.pending = Some(StepMetrics {
            mean_d,
            gap_cv,
            touching,
            cpu_load_percent: tally.sum_load / live_f,
            ..StepMetrics::default()
        });
        Ok(())
    }

    /// Every live MCU sleeps to its next step instant; returns the step's instant, the
    /// earliest of theirs (with every robot dead, one step period after the world's time).
    fn sleep_all(&mut self) -> Result<u64> {
        let n = self.robots.len();
        let dead = self.dead.clone();
        let sleep = |(i, r): (usize, &mut Robot)| -> Option<Result<u64>> {
            dead[i].is_none().then(|| r.sleep())
        };
        let times: Vec<Option<Result<u64>>> = if self.par() {
            self.robots.par_iter_mut().enumerate().map(sleep).collect()
        } else {
            self.robots.iter_mut().enumerate().map(sleep).collect()
        };
        let mut live_times = Vec::with_capacity(n);
        for (i, t) in times.into_iter().enumerate() {
            match t {
                Some(Ok(t)) => live_times.push(t),
                Some(Err(e)) => self.fail(i, e)?,
                None => {}
            }
        }
        Ok(match live_times.iter().copied().min() {
            Some(t) => t,
            // Every robot dead: the world goes on by the step period.
            None => self.world.elapsed_states() + self.period_states,
        })
    }

    /// Step `k`'s share of the track, when one is kept: the paths of the first and last
    /// steps, the outlines at the snapshot steps, the corridor's space-time samples.
    fn track_step(&mut self, k: u32, t_step_s: f64) -> Result<()> {
        let Some(t) = self.track.as_mut() else {
            return Ok(());
        };
        let (early, late) = (
            (k as usize) < SNAPSHOT_STEPS,
            k as usize + SNAPSHOT_STEPS >= self.scenario.steps as usize && k < self.scenario.steps,
        );
        record(
            &self.world,
            t,
            self.tracked,
            (early, late),
            self.snapshots.contains(&k),
            t_step_s,
        )?;
        let steps = self.scenario.steps;
        if self.scenario.arena == ArenaKind::Corridor
            && (k.is_multiple_of(spacetime_stride(steps)) || k + 1 == steps)
        {
            for (i, path) in t.spacetime.iter_mut().enumerate() {
                path.push((f64::from(k), self.world.pose(i)?.x_m));
            }
        }
        Ok(())
    }

    /// What each robot's board shows its MCU for the step: the sensors' true distances and
    /// the bumper switches as the latest sub-step left them (port 2's pins).
    fn sense_all(&self) -> Result<Vec<Senses>> {
        let world = &self.world;
        let sense = |i: usize| -> Result<Senses> {
            let mut d = [None; 4];
            for (k, dk) in d.iter_mut().enumerate() {
                *dk = world.sense(i, k)?;
            }
            Ok((d, world.bumpers(i)?))
        };
        let n = self.robots.len();
        if self.par() {
            (0..n).into_par_iter().map(sense).collect()
        } else {
            (0..n).map(sense).collect()
        }
    }

    /// Every live robot steps on its senses; their charge, saves, D and CPU load are summed
    /// (and kept per robot when the run is recorded).
    fn step_robots(&mut self, senses: &[Senses]) -> Result<StepTally> {
        let dead = self.dead.clone();
        let step = |(i, (r, (d, b))): (usize, (&mut Robot, &Senses))| {
            dead[i].is_none().then(|| {
                r.set_bumpers(*b);
                r.step(*d).map(|rep| (rep, r.take_busy_states()))
            })
        };
        let results: Vec<_> = if self.par() {
            self.robots
                .par_iter_mut()
                .zip(senses.par_iter())
                .enumerate()
                .map(step)
                .collect()
        } else {
            self.robots
                .iter_mut()
                .zip(senses)
                .enumerate()
                .map(step)
                .collect()
        };
        let period_states =
            self.scenario.timing.step_period_s * f64::from(self.scenario.timing.clock_hz);
        let recording = self.recorder.is_some();
        let mut tally = StepTally::default();
        for (i, res) in results.into_iter().enumerate() {
            let mut this = (0, false, 0.0);
            match res {
                Some(Ok((rep, busy))) => {
                    let q = self.robots[i].step_charge();
                    tally.charge_uc += q.total_uc();
                    self.energy.add(&q);
                    self.saves += u64::from(rep.saved);
                    tally.sum_d += f64::from(rep.d);
                    let load = busy as f64 / period_states * 100.0;
                    tally.sum_load += load;
                    tally.live += 1;
                    this = (rep.d, rep.saved, load);
                }
                Some(Err(e)) => self.fail(i, e)?,
                None => {}
            }
            if recording {
                tally.stepped.push(this);
            }
        }
        Ok(tally)
    }

    /// Hands every robot's wheel commands to the world and its drive meter (a dead robot
    /// coasts); returns the behaviours they run when the run is recorded.
    fn drive(&mut self) -> Result<Vec<u8>> {
        let recording = self.recorder.is_some();
        let mut behaviours: Vec<u8> = Vec::new();
        for (i, r) in self.robots.iter_mut().enumerate() {
            let (left, right) = if self.dead[i].is_some() {
                let coast = world::WheelCommand {
                    duty: 0.0,
                    direction: world::Direction::Coast,
                };
                (coast, coast)
            } else {
                r.wheels()
            };
            if recording {
                behaviours.push(crate::recording::behaviour_of(&left, &right));
            }
            self.world.set_wheels(i, left, right)?;
            self.drives[i].set_commands(left, right);
        }
        Ok(behaviours)
    }

    /// Step `k`'s frame for the recorder, when the run is recorded: the recorded robots'
    /// poses, behaviours, bumpers, readings, D, flags and load.
    fn record_frame(
        &mut self,
        k: u32,
        stepped: &[(i16, bool, f64)],
        behaviours: &[u8],
        senses: &[Senses],
    ) -> Result<()> {
        let Some((rec, count)) = self.recorder.as_mut() else {
            return Ok(());
        };
        let mut frame = Vec::with_capacity(*count);
        for (i, &(d, saved, load)) in stepped.iter().enumerate().take(*count) {
            let p = self.world.pose(i)?;
            frame.push(crate::recording::RobotStep {
                x_m: p.x_m,
                y_m: p.y_m,
                heading_rad: p.heading_rad,
                behaviour: behaviours[i],
                bumpers: senses[i].1,
                p: self.robots[i].readings_du(),
                d,
                held: self.tallies[i].held_now(),
                motion: self.tallies[i].last_class,
                saved,
                dead: self.dead[i].is_some(),
                load_percent: load,
            });
        }
        let robots = &self.robots;
        rec.step(k, &frame, &mut |i| robots[i].weights())
    }

    /// Advances the world to `t_states` (the behaviour of the latest step runs to its end)
    /// and completes that step's metrics: collisions, contact time, where the robots went.
    fn close_step(&mut self, t_states: u64) -> Result<()> {
        let dt = t_states.saturating_sub(self.world.elapsed_states());
        let par = self.par();
        let (collided, contact_states) = advance_world(
            &mut self.world,
            t_states,
            (&mut self.meters, &mut self.collided),
            par,
            &mut self.drives,
            &mut self.readings,
        )?;
        let mut drive_uc = 0.0;
        for d in &mut self.drives {
            let q = d.take();
            drive_uc += q.total_uc();
            self.energy.add(&q);
        }
        let n = self.robots.len();
        let steps = self.motion_steps()?;
        if let Some(mut last) = self.pending.take() {
            let k = self.started - 1;
            let in_last = k >= self.scenario.steps.saturating_sub(self.scenario.window);
            for (i, m) in steps.iter().enumerate() {
                let c = std::mem::take(&mut self.collided[i]);
                self.tallies[i].record(k, m, c, in_last);
            }
            last.collisions_per_robot = collided as f64 / n as f64;
            last.contact_percent = if dt == 0 {
                0.0
            } else {
                100.0 * contact_states as f64 / (dt as f64 * n as f64)
            };
            motion_metrics(&mut last, &steps);
            let (electronics_uc, live) = std::mem::take(&mut self.pending_charge);
            last.energy_per_robot_mj = if live == 0 {
                0.0
            } else {
                crate::energy::Pack::default().energy_mj(electronics_uc + drive_uc) / live as f64
            };
            self.metrics.add(k, &last);
            if let Some(rows) = self.rows.as_mut() {
                let dead = self.dead.iter().flatten().filter(|d| d.0 <= k).count();
                let ends =
                    metrics_fields(self.condition, self.repeat, k, &last, dead, &mut rows.buf);
                let buf = &rows.buf;
                rows.w
                    .write_record(
                        (0..ends.len())
                            .map(|i| &buf[if i == 0 { 0 } else { ends[i - 1] }..ends[i]]),
                    )
                    .map_err(anyhow::Error::new)
                    .with_context(|| {
                        crate::output_error::OutputError(format!(
                            "cannot write `{}`",
                            rows.path.display()
                        ))
                    })?;
            }
        }
        Ok(())
    }

    /// The window sums of the steps completed so far (a step completes when the next one
    /// begins, or at [`Swarm::finish`]).
    #[must_use]
    pub fn metrics(&self) -> &RunMetrics {
        &self.metrics
    }

    /// Each robot's step since the previous call as its tracker sees it (where it is now
    /// recorded); none on the first call, which records where the robots start.
    fn motion_steps(&mut self) -> Result<Vec<MotionStep>> {
        let mut out = Vec::with_capacity(self.robots.len());
        for (i, t) in self.motion.iter_mut().enumerate() {
            let p = self.world.pose(i)?;
            if t.started() {
                out.push(t.record(p.x_m, p.y_m));
            } else {
                t.start(p.x_m, p.y_m);
            }
        }
        Ok(out)
    }

    /// Lets the last behaviour run its full period (its collisions counted) and returns the
    /// run's metrics.
    ///
    /// # Errors
    /// A world failure.
    pub fn finish(mut self) -> Result<RunOutput> {
        let end = self.world.elapsed_states() + self.period_states;
        self.close_step(end)?;
        if let Some(mut rows) = self.rows.take() {
            rows.w
                .flush()
                .map_err(anyhow::Error::new)
                .context(crate::output_error::OutputError::cannot_write(&rows.path))?;
        }
        let dead = self.dead();
        let last_from = self.scenario.steps.saturating_sub(self.scenario.window);
        for (t, m) in self.tallies.iter_mut().zip(&self.motion) {
            t.finish(m, last_from);
        }
        let recorded = match self.recorder.take() {
            Some((rec, _)) => Some(rec.finish()?),
            None => None,
        };
        let stack_warnings = self
            .robots
            .iter()
            .enumerate()
            .filter_map(|(i, r)| r.stack_fault().map(|f| (i, f.to_string())))
            .collect();
        let io_warnings = self
            .robots
            .iter()
            .enumerate()
            .flat_map(|(i, r)| r.io_reports().into_iter().map(move |w| (i, w)))
            .collect();
        let mut motor_cap = crate::energy::CurrentCap::default();
        for d in &self.drives {
            motor_cap.add(d.cap());
        }
        Ok(RunOutput {
            stack_warnings,
            io_warnings,
            energy: self.energy,
            motor_cap,
            condition: self.condition,
            repeat: self.repeat,
            metrics: self.metrics,
            track: self.track,
            saves: self.saves,
            dead,
            robots: self.tallies,
            recorded,
        })
    }
}

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

/// What the VCD file of `v` says of its trace.
fn vcd_info(
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

/// What a robot's board shows its MCU for a step: each sensor's true distance (mm, `None`
/// beyond range) and the bumper switches (front, rear, left, right).
type Senses = ([Option<f64>; 4], [bool; 4]);

/// Fills the motion part of a step's metrics from every robot's step as its tracker saw it:
/// the class shares, the moving share, the path and net progress, the mean squared
/// displacements (once every robot has one) and the cells.
pub fn motion_metrics(m: &mut StepMetrics, steps: &[MotionStep]) {
    let n = steps.len().max(1) as f64;
    let mut classes = [0u32; 4];
    let (mut step_m, mut net_m, mut moving) = (0.0, 0.0, 0u32);
    let (mut msd, mut msd_robots) = ([0.0; 3], [0usize; 3]);
    let (mut fresh, mut new) = (0u32, 0u32);
    for s in steps {
        step_m += s.step_m;
        net_m += s.net_m;
        classes[s.class.code() as usize] += 1;
        moving += u32::from(s.step_m * 1000.0 >= crate::collisions::MOVING_MIN_MM);
        for (l, v) in s.sq_disp_m2.iter().enumerate() {
            if let Some(v) = v {
                msd[l] += v;
                msd_robots[l] += 1;
            }
        }
        fresh += s.fresh_cells;
        new += s.new_cells;
    }
    let share = |c: MotionClass| 100.0 * f64::from(classes[c.code() as usize]) / n;
    m.held_percent = share(MotionClass::Held);
    m.shuttling_percent = share(MotionClass::Shuttling);
    m.circling_percent = share(MotionClass::Circling);
    m.exploring_percent = share(MotionClass::Exploring);
    m.moving_percent = 100.0 * f64::from(moving) / n;
    m.moved_mm = 1000.0 * step_m / n;
    m.net_mm = 1000.0 * net_m / n;
    m.msd_cm2 = std::array::from_fn(|l| {
        (!steps.is_empty() && msd_robots[l] == steps.len()).then(|| 1e4 * msd[l] / n)
    });
    m.fresh_cells = f64::from(fresh) / n;
    m.new_cells = f64::from(new) / n;
}

/// What the live robots' steps add up to in one swarm step.
#[derive(Default)]
struct StepTally {
    /// Sum of their D, du.
    sum_d: f64,
    /// Sum of their CPU loads, percent.
    sum_load: f64,
    /// Robots that stepped.
    live: usize,
    /// Their charge over the step, µC.
    charge_uc: f64,
    /// Per robot (when the run is recorded): D, whether it saved, CPU load (zeros for a dead
    /// robot).
    stepped: Vec<(i16, bool, f64)>,
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

/// Sub-steps whose readings are gathered before the meters take them, robot by robot, in one
/// pass: one pass a step at the arena's 23 sub-steps (a pass on the pool costs about as much
/// as 1 000 robots' meters of one sub-step; docs/performance.md), and a bound on the readings
/// kept (32 × 41 bytes a robot) whatever the sub-step.
const METER_BATCH: usize = 32;

/// Robots from which the meters are fed beside the world's next sub-step on two or more
/// threads: a join a sub-step costs about 10 µs here, the meters of 100 robots about 3 µs
/// (100 robots × 200 steps on two threads: 0.29–0.30 s pipelined against 0.26–0.29 s
/// batched; 1 000 robots × 600 steps: 3.28–4.07 s against 3.55–4.29 s).
const PIPELINE_ROBOTS: usize = 512;

/// Robots from which a sub-step's readings are gathered on the pool: the world's own threshold
/// for its per-robot stages (below it a parallel region costs more than the copying).
const GATHER_PAR_ROBOTS: usize = world::PAR_STAGE_ROBOTS;
/// Robots per chunk of the parallel gathering.
const GATHER_CHUNK: usize = 1024;

/// What a robot's meters take from one sub-step: its wheels' mean speeds and transmitted
/// forces, and whether a bumper was pressed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Reading {
    speeds: [f64; 2],
    forces: [f64; 2],
    pressed: bool,
}

/// The readings of up to [`METER_BATCH`] sub-steps, every robot's (sub-step major), and the
/// sub-steps' lengths.
#[derive(Clone, Debug)]
struct Readings {
    lens: Vec<u64>,
    of: Vec<Reading>,
    /// Robots from which the meters are fed beside the world's next sub-step
    /// ([`PIPELINE_ROBOTS`]; tests lower it).
    pipeline_from: usize,
}

impl Default for Readings {
    fn default() -> Self {
        Readings {
            lens: Vec::new(),
            of: Vec::new(),
            pipeline_from: PIPELINE_ROBOTS,
        }
    }
}

impl Readings {
    /// Appends every robot's reading of the sub-step of `len` states the world just made, in
    /// chunks on the pool with `par` from [`GATHER_PAR_ROBOTS`] robots.
    fn gather(&mut self, world: &World, len: u64, par: bool) -> Result<()> {
        self.lens.push(len);
        let n = world.robot_count();
        let start = self.of.len();
        self.of.resize(start + n, Reading::default());
        let fill = |first: usize, out: &mut [Reading]| -> Result<()> {
            for (k, r) in out.iter_mut().enumerate() {
                let i = first + k;
                *r = Reading {
                    speeds: world.wheel_mean_speeds(i)?,
                    forces: world.wheel_forces(i)?,
                    pressed: world.bumpers(i)?.iter().any(|&b| b),
                };
            }
            Ok(())
        };
        if par && n >= GATHER_PAR_ROBOTS {
            self.of[start..]
                .par_chunks_mut(GATHER_CHUNK)
                .enumerate()
                .try_for_each(|(k, out)| fill(k * GATHER_CHUNK, out))
        } else {
            fill(0, &mut self.of[start..])
        }
    }

    /// Feeds the gathered sub-steps to every robot's meters, sub-step by sub-step in order for
    /// each robot (robots in any order, on the pool with `par`: the sums are of integers), and
    /// empties the batch; returns the collisions counted and the robot-states in contact.
    fn feed(
        &mut self,
        meters: &mut [ContactMeter],
        per_robot: &mut [u64],
        par: bool,
        drives: &mut [crate::energy::DriveMeter],
        clock_hz: f64,
    ) -> (u64, u64) {
        let n = meters.len();
        let (lens, of) = (&self.lens, &self.of);
        debug_assert_eq!(of.len(), lens.len() * n, "a reading per robot per sub-step");
        let metered = drives.len() == n;
        let meter = |i: usize,
                     m: &mut ContactMeter,
                     c: &mut u64,
                     mut d: Option<&mut crate::energy::DriveMeter>|
         -> (u64, u64) {
            let mut sum = (0, 0);
            for (k, &len) in lens.iter().enumerate() {
                let r = of[k * n + i];
                if let Some(d) = d.as_deref_mut() {
                    d.add_substep(len as f64 / clock_hz, r.speeds, r.forces);
                }
                m.sample(r.pressed, len);
                let (collided, touching) = m.take();
                *c += collided;
                sum = add(sum, (collided, touching));
            }
            sum
        };
        let sum = if par {
            let it = meters
                .par_iter_mut()
                .zip(per_robot.par_iter_mut())
                .enumerate();
            if metered {
                it.zip(drives.par_iter_mut())
                    .map(|((i, (m, c)), d)| meter(i, m, c, Some(d)))
                    .reduce(|| (0, 0), add)
            } else {
                it.map(|(i, (m, c))| meter(i, m, c, None))
                    .reduce(|| (0, 0), add)
            }
        } else {
            let mut drives = drives.iter_mut();
            let mut sum = (0, 0);
            for (i, (m, c)) in meters.iter_mut().zip(per_robot.iter_mut()).enumerate() {
                let d = if metered { drives.next() } else { None };
                sum = add(sum, meter(i, m, c, d));
            }
            sum
        };
        self.lens.clear();
        self.of.clear();
        sum
    }
}

/// Two (collisions, robot-states in contact) sums added.
fn add(a: (u64, u64), b: (u64, u64)) -> (u64, u64) {
    (a.0 + b.0, a.1 + b.1)
}

/// Advances the world to `target_states` in its sub-steps, feeding every robot's bumpers
/// after each to its meter and its wheels' mean speeds and the forces they transmitted to its
/// drive meter (when `drives` has one per robot); adds each robot's collisions to `per_robot`
/// and returns the collisions counted and the robot-states in contact. The readings are
/// gathered after each sub-step and fed to the meters in batches ([`Readings`]): each meter
/// sees its robot's sub-steps in order, as if fed after each.
fn advance_world(
    world: &mut World,
    target_states: u64,
    (meters, per_robot): (&mut [ContactMeter], &mut [u64]),
    par: bool,
    drives: &mut [crate::energy::DriveMeter],
    readings: &mut Readings,
) -> Result<(u64, u64)> {
    let mut sum = (0u64, 0u64);
    let dt = target_states.saturating_sub(world.elapsed_states());
    let clock_hz = world.params().clock_hz as f64;
    // With more than one thread and enough robots, each sub-step's readings are fed while the
    // world makes the next sub-step (the other thread has the meters to do during the world's
    // one-thread stages); otherwise they wait for a batch, which keeps each robot's meters in
    // cache and costs one parallel region a step rather than one a sub-step.
    let pipelined =
        par && meters.len() >= readings.pipeline_from && rayon::current_num_threads() > 1;
    let advance = |world: &mut World, len: u64| {
        if par {
            world.advance_states_par(len);
        } else {
            world.advance_states(len);
        }
    };
    for len in world.substep_plan(dt) {
        if pipelined && !readings.lens.is_empty() {
            let ((), fed) = rayon::join(
                || advance(world, len),
                || readings.feed(meters, per_robot, par, drives, clock_hz),
            );
            sum = add(sum, fed);
        } else {
            advance(world, len);
        }
        readings.gather(world, len, par)?;
        if readings.lens.len() == METER_BATCH {
            sum = add(sum, readings.feed(meters, per_robot, par, drives, clock_hz));
        }
    }
    if !readings.lens.is_empty() {
        sum = add(sum, readings.feed(meters, per_robot, par, drives, clock_hz));
    }
    Ok(sum)
}

/// Records the tracked robots' centres in the early and/or late paths, and their outlines at a
/// snapshot instant.
fn record(
    world: &World,
    t: &mut Track,
    tracked: usize,
    (early, late): (bool, bool),
    snapshot: bool,
    time_s: f64,
) -> Result<()> {
    for i in 0..tracked {
        let p = world.pose(i)?;
        if early {
            t.early[i].push((p.x_m, p.y_m));
        }
        if late {
            t.late[i].push((p.x_m, p.y_m));
        }
        if snapshot {
            t.outlines.push(Outline {
                robot: i,
                time_s,
                corners: world.corners(i)?,
                heading: (libm::cos(p.heading_rad), libm::sin(p.heading_rad)),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::MSD_LAGS;
    use world::{Behaviour, Pose};

    /// The picosecond case: a robot pushing the end wall of the corridor for 500 steps of
    /// 0.6 s. Time is whole states, the sub-steps cut every step exactly, and the push is one
    /// collision, not one every other step (with float time, a final sub-step of ~1 ps
    /// released the bumper and every step from about 429 on counted a new collision).
    #[test]
    fn a_robot_held_against_a_wall_counts_one_collision_over_500_steps() {
        let s = Scenario::corridor();
        let mut w = World::from_poses(
            Arena::paper_corridor(),
            world_params(&s),
            &[Pose {
                x_m: 2.5,
                y_m: 0.11,
                heading_rad: 0.0,
            }],
            1,
        )
        .unwrap();
        let (l, r) = Behaviour::Forward.wheels();
        w.set_wheels(0, l, r).unwrap();
        let period = period_states(&s);
        assert_eq!(period, 15_000_000);
        let nominal = nominal_substep_states(&s);
        assert_eq!(nominal, 500_000, "0.6 s in 30 sub-steps of 20 ms");
        let mut meters = vec![ContactMeter::new(nominal)];
        let mut per_robot = vec![0];
        let mut collisions = Vec::new();
        let mut t = 0u64;
        for _ in 0..500 {
            t += period;
            for len in w.substep_plan(t - w.elapsed_states()) {
                assert_eq!(len, nominal, "no sliver of a sub-step");
            }
            let (c, contact) = advance_world(
                &mut w,
                t,
                (&mut meters, &mut per_robot),
                false,
                &mut [],
                &mut Readings::default(),
            )
            .unwrap();
            collisions.push((c, contact));
        }
        assert_eq!(w.elapsed_states(), 500 * period, "no drift");
        let total: u64 = collisions.iter().map(|c| c.0).sum();
        assert_eq!(total, 1, "one push, one collision");
        assert_eq!(per_robot, [1], "counted for the robot");
        // From the step it arrives (2.5 m → 2.885 m at 0.15 m/s: about 4 steps) it is in
        // contact the whole step.
        assert!(collisions[10..].iter().all(|&(_, c)| c == period));
    }

    /// The meters fed in batches (more than [`METER_BATCH`] sub-steps a step, so full batches
    /// and a remainder) or pipelined with the world's sub-steps (two threads) count what they
    /// count fed after every sub-step: three robots in the corridor, one pushing the end wall,
    /// two meeting head on.
    #[test]
    fn meters_fed_in_batches_count_as_fed_after_every_substep() {
        let mut s = Scenario::corridor();
        s.world.substep_s = 0.008;
        let poses = [
            (2.7, 0.11, 0.0),
            (1.0, 0.11, 0.0),
            (1.3, 0.12, std::f64::consts::PI),
        ];
        let poses: Vec<Pose> = poses
            .iter()
            .map(|&(x_m, y_m, heading_rad)| Pose {
                x_m,
                y_m,
                heading_rad,
            })
            .collect();
        let mut w =
            World::from_poses(Arena::paper_corridor(), world_params(&s), &poses, 1).unwrap();
        let (l, r) = Behaviour::Forward.wheels();
        let mut drive = crate::energy::DriveMeter::new(s.world.top_speed_m_per_s, [1.0, 1.0]);
        drive.set_commands(l, r);
        for i in 0..poses.len() {
            w.set_wheels(i, l, r).unwrap();
        }
        let period = period_states(&s);
        assert!(w.substep_plan(period).substeps() > 2 * METER_BATCH as u64);
        let nominal = nominal_substep_states(&s);
        let fresh = || {
            (
                vec![ContactMeter::new(nominal); 3],
                vec![0u64; 3],
                vec![drive.clone(); 3],
            )
        };
        // The reference: every meter fed after every sub-step.
        let mut plain = w.clone();
        let (mut m0, mut c0, mut d0) = fresh();
        let mut sums0 = Vec::new();
        for k in 1..=40u64 {
            let mut sum = (0, 0);
            for len in plain.substep_plan(k * period - plain.elapsed_states()) {
                plain.advance_states(len);
                for i in 0..3 {
                    d0[i].add_substep(
                        len as f64 / f64::from(s.timing.clock_hz),
                        plain.wheel_mean_speeds(i).unwrap(),
                        plain.wheel_forces(i).unwrap(),
                    );
                    m0[i].sample(plain.bumpers(i).unwrap().iter().any(|&b| b), len);
                    let (n, t) = m0[i].take();
                    c0[i] += n;
                    sum = add(sum, (n, t));
                }
            }
            sums0.push(sum);
        }
        assert!(c0.iter().all(|&c| c >= 1), "every robot collided: {c0:?}");
        // One thread in order, one thread with the pool's stages (batched), two threads
        // batched (three robots are below PIPELINE_ROBOTS) and pipelined (each sub-step fed
        // while the world makes the next).
        for (par, threads, pipeline_from) in [
            (false, 1, PIPELINE_ROBOTS),
            (true, 1, PIPELINE_ROBOTS),
            (true, 2, PIPELINE_ROBOTS),
            (true, 2, 1),
        ] {
            let mut w = w.clone();
            let (mut m, mut c, mut d) = fresh();
            let mut readings = Readings {
                pipeline_from,
                ..Readings::default()
            };
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let sums: Vec<_> = pool.install(|| {
                (1..=40u64)
                    .map(|k| {
                        advance_world(
                            &mut w,
                            k * period,
                            (&mut m, &mut c),
                            par,
                            &mut d,
                            &mut readings,
                        )
                        .unwrap()
                    })
                    .collect()
            });
            assert_eq!(
                sums, sums0,
                "par {par}, {threads} threads, from {pipeline_from}"
            );
            assert_eq!(c, c0);
            assert_eq!(m, m0);
            for (a, b) in d.iter_mut().zip(d0.iter_mut()) {
                assert_eq!(a.take(), b.clone().take());
                assert_eq!(a.cap(), b.cap());
            }
        }
    }

    /// A large swarm's readings gathered on the pool are the ones gathered in order.
    #[test]
    fn readings_gathered_on_the_pool_are_those_gathered_in_order() {
        let s = Scenario::arena();
        let n = GATHER_PAR_ROBOTS + GATHER_CHUNK / 2;
        let arena = Arena::scaled_square(n).unwrap();
        let mut w = World::new(arena, world_params(&s), n, 5).unwrap();
        for i in 0..n {
            let (l, r) = Behaviour::TurnLeftForward.wheels();
            w.set_wheels(i, l, r).unwrap();
        }
        w.advance_states(50 * nominal_substep_states(&s));
        let (mut plain, mut pooled) = (Readings::default(), Readings::default());
        for len in [7, 9] {
            plain.gather(&w, len, false).unwrap();
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(3)
                .build()
                .unwrap();
            pool.install(|| pooled.gather(&w, len, true)).unwrap();
        }
        assert_eq!(plain.lens, pooled.lens);
        assert_eq!(plain.of.len(), 2 * n);
        assert!(plain.of.iter().any(|r| r.pressed), "some bumper pressed");
        assert_eq!(plain.of, pooled.of);
    }

    #[test]
    fn the_arena_step_is_cut_into_23_substeps_a_state_apart() {
        let s = Scenario::arena();
        assert_eq!(period_states(&s), 11_250_000);
        assert_eq!(nominal_substep_states(&s), 489_130);
        let plan: Vec<u64> = SubstepPlan::new(11_250_000, 500_000).collect();
        assert_eq!(plan.len(), 23);
        assert_eq!(plan.iter().sum::<u64>(), 11_250_000);
        assert!(plan.iter().all(|&l| l == 489_130 || l == 489_131));
    }

    /// Step metrics that differ every step (so a sum over the wrong steps shows).
    fn metrics_of(k: u32, gap: bool) -> StepMetrics {
        let x = f64::from(k);
        StepMetrics {
            mean_d: 700.0 + libm::sin(x * 0.37) * 50.0,
            collisions_per_robot: f64::from(k % 7) / 3.0,
            contact_percent: 100.0 * libm::cos(x * 0.11).abs(),
            held_percent: f64::from(k % 5) * 20.0,
            shuttling_percent: f64::from(k % 4) * 10.0,
            circling_percent: f64::from(k % 2) * 5.0,
            exploring_percent: 30.0 + f64::from(k % 7),
            moving_percent: f64::from(k % 3) * 50.0,
            moved_mm: 70.0 / (1.0 + x),
            net_mm: 30.0 / (1.0 + x),
            msd_cm2: [
                Some(x),
                (k >= 10).then_some(2.0 * x),
                (k >= 100).then_some(3.0 * x),
            ],
            fresh_cells: f64::from(k % 11) / 3.0,
            new_cells: f64::from(k % 13) / 7.0,
            gap_cv: (gap && !k.is_multiple_of(9)).then_some(0.1 + x * 1e-4),
            touching: gap.then_some(k.is_multiple_of(9)),
            cpu_load_percent: 0.3 + x * 1e-6,
            energy_per_robot_mj: 3500.0 + libm::cos(x),
        }
    }

    /// The kept sums equal the sums of the same steps taken afterwards (as the summary and the
    /// figure took them when every step was kept), for windows that do and do not divide the
    /// run.
    #[test]
    fn window_sums_equal_the_sums_of_the_kept_steps() {
        for (steps, win, gap) in [
            (1000, 250, false),
            (1234, 500, true),
            (150, 150, true),
            (7, 3, false),
        ] {
            let all: Vec<StepMetrics> = (0..steps).map(|k| metrics_of(k, gap)).collect();
            let mut m = RunMetrics::new(steps, win);
            for (k, s) in all.iter().enumerate() {
                m.add(k as u32, s);
            }
            let sum = |r: std::ops::Range<u32>| {
                let mut w = WindowSums::default();
                for s in &all[r.start as usize..r.end as usize] {
                    w.add(s);
                }
                w
            };
            // Spot-check one field the direct way too (not through WindowSums::add).
            let d: f64 = all[(steps - win) as usize..].iter().map(|s| s.mean_d).sum();
            assert_eq!(m.last.mean_d, d);
            assert_eq!(*m.first(), sum(0..win));
            assert_eq!(m.last, sum(steps - win..steps));
            assert_eq!(m.whole, sum(0..steps));
            assert_eq!(m.whole_windows().len() as u32, steps / win);
            for (w, got) in m.whole_windows().iter().enumerate() {
                let w = w as u32;
                assert_eq!(*got, sum(w * win..(w + 1) * win));
            }
            assert_eq!(m.whole.is_corridor(), gap);
            if gap {
                assert_eq!(m.whole.touching_steps, steps.div_ceil(9));
                assert_eq!(m.whole.gap_cv_steps + m.whole.touching_steps, steps);
            }
            assert_eq!(
                m.whole.msd_steps,
                [steps, steps.saturating_sub(10), steps.saturating_sub(100)]
            );
        }
    }

    /// Port 2 shows each robot's MCU the bumpers the world pressed (a user image may read
    /// them; before, the pins read released whatever the world did).
    #[test]
    fn the_board_shows_the_world_s_bumpers_on_port_2() {
        use h8_3052f::pins::Board;
        let mut s = Scenario::arena();
        s.robots = 10;
        s.steps = 300;
        let mut swarm = Swarm::new(&s, Condition::Learning, 0, false, None).unwrap();
        let mut pressed = 0;
        for _ in 0..s.steps {
            swarm.step().unwrap();
            for i in 0..s.robots {
                let b = swarm.world().bumpers(i).unwrap();
                pressed += usize::from(b.iter().any(|&x| x));
                let board = &mut swarm.robot_mut(i).unwrap().mcu.board_mut().world;
                assert_eq!(board.bumpers, b);
                let [front, rear, left, right] = b;
                let want =
                    sensors::port2_pins(sensors::BumperSet::from_flags(front, rear, left, right));
                assert_eq!(board.port2_pins(0), want);
            }
        }
        assert!(
            pressed > 50,
            "only {pressed} pressed robot-steps: the test saw too few"
        );
    }

    /// A run keeps sums per window, not its steps: the rows go to the file as the steps
    /// complete, and the kept sums are the sums of those rows; the arena paths are kept for
    /// the first and last snapshot steps only.
    #[test]
    fn a_run_streams_its_rows_and_keeps_window_sums() {
        let mut s = Scenario::arena();
        s.steps = 450;
        s.window = 100;
        let dir = std::env::temp_dir().join(format!("h8swarm-rows-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rows = dir.join("rows.csv");
        let mut swarm = Swarm::new(&s, Condition::Learning, 0, true, None).unwrap();
        swarm.set_rows(&rows).unwrap();
        for k in 0..s.steps {
            swarm.step().unwrap();
            // Step k completes when step k + 1 begins.
            assert_eq!(swarm.metrics().whole.steps, k);
        }
        let out = swarm.finish().unwrap();
        let text = std::fs::read_to_string(&rows).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        let parsed: Vec<Vec<String>> = text
            .lines()
            .map(|l| l.split(',').map(String::from).collect())
            .collect();
        assert_eq!(parsed.len(), 450);
        let mut again = RunMetrics::new(s.steps, s.window);
        for (k, r) in parsed.iter().enumerate() {
            assert_eq!(r[0], "learning");
            assert_eq!(r[2], k.to_string());
            let f = |i: usize| r[i].parse::<f64>().unwrap();
            let opt = |i: usize| (!r[i].is_empty()).then(|| f(i));
            assert_eq!(r.len(), METRICS_HEADER.len());
            again.add(
                k as u32,
                &StepMetrics {
                    mean_d: f(3),
                    collisions_per_robot: f(4),
                    contact_percent: f(5),
                    held_percent: f(6),
                    shuttling_percent: f(7),
                    circling_percent: f(8),
                    exploring_percent: f(9),
                    moving_percent: f(10),
                    moved_mm: f(11),
                    net_mm: f(12),
                    msd_cm2: [opt(13), opt(14), opt(15)],
                    fresh_cells: f(16),
                    new_cells: f(17),
                    gap_cv: opt(18),
                    touching: opt(19).map(|t| t != 0.0),
                    cpu_load_percent: f(20),
                    energy_per_robot_mj: f(21),
                },
            );
            let classes = f(6) + f(7) + f(8) + f(9);
            assert!(
                (classes - 100.0).abs() < 1e-9,
                "step {k}: classes sum to {classes}"
            );
        }
        assert_eq!(out.metrics, again);
        assert_eq!(
            out.metrics.windows.len(),
            5,
            "four whole windows and a partial one"
        );
        assert_eq!(out.metrics.whole_windows().len(), 4);
        assert!(
            out.metrics.whole.collisions_per_robot > 0.0,
            "something happened"
        );
        assert_eq!(
            METRICS_HEADER[13..16],
            MSD_LAGS.map(|l| format!("msd_{l}_cm2"))[..],
            "the MSD columns name their lags"
        );
        assert_eq!(
            out.metrics.whole.msd_steps,
            MSD_LAGS.map(|l| 451 - l as u32)
        );
        // Every robot's tally adds up to its steps, and it was somewhere.
        for t in &out.robots {
            assert_eq!(t.class_steps.iter().sum::<u32>(), 450);
            assert!(t.cells_visited >= 1 && t.last_window_cells >= 1);
            assert!(t.net_m <= t.distance_m + 1e-9);
        }
        let t = out.track.unwrap();
        assert!(t.early.iter().all(|p| p.len() == SNAPSHOT_STEPS));
        assert!(t.late.iter().all(|p| p.len() == SNAPSHOT_STEPS));
        assert_ne!(t.early, t.late);
    }
}
