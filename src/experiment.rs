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

use anyhow::{Context, Result};
use rayon::prelude::*;
use world::{Arena, SensorMount, SubstepPlan, World, WorldParams};

use crate::collisions::{ContactMeter, StuckDetector};

use crate::plot::Outline;
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

/// The metrics of one step of one run (SPEC §5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepMetrics {
    /// Mean over robots of D(t), du.
    pub mean_d: f64,
    /// Collisions per robot during this step's behaviour.
    pub collisions_per_robot: f64,
    /// Mean over robots of the fraction of this step's behaviour spent with a bumper pressed
    /// (time in contact, weighted by sub-step length).
    pub contact_fraction: f64,
    /// Fraction of the robots stuck at the end of this step's behaviour: moved less than 1 mm
    /// over the last 100 steps while their motors drove (see [`crate::collisions`]).
    pub stuck_fraction: f64,
    /// Mean over robots of how far the body's centre moved during this step's behaviour
    /// (straight-line distance between the two step instants), metres: 0 for a robot held
    /// against a wall or another body, about 0.07 m for a free one driving straight in the
    /// arena. Not in the paper; it tells a robot that avoids obstacles from one that is stuck
    /// (both make no new collisions).
    pub moved_m: f64,
    /// Corridor only: coefficient of variation of the gaps between neighbours at the step.
    pub gap_cv: Option<f64>,
    /// Mean over robots of their MCU's CPU load over this step's period (percent): busy
    /// states (the step, the tick interrupts, the main loop; not the time asleep) over the
    /// period's states, as the robots' own clocks count them.
    pub cpu_load_percent: f64,
}

/// Robot paths and outlines for the arena figure.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Track {
    /// Per tracked robot, its centre at every step (metres).
    pub paths: Vec<Vec<(f64, f64)>>,
    /// Outlines of the tracked robots at a few instants.
    pub outlines: Vec<Outline>,
    /// The arena's walls.
    pub walls: Vec<[(f64, f64); 2]>,
}

/// What one run produced.
#[derive(Clone, Debug, PartialEq)]
pub struct RunOutput {
    /// The condition.
    pub condition: Condition,
    /// The repeat index.
    pub repeat: u32,
    /// Per-step metrics.
    pub steps: Vec<StepMetrics>,
    /// Paths and outlines, when asked for.
    pub track: Option<Track>,
    /// EEPROM records written over the run (all robots).
    pub saves: u64,
    /// Robots that died (with `--keep-going`), with why.
    pub dead: Vec<(usize, String)>,
}

/// The arena of a scenario (the square scaled to keep the paper's density for other than 3
/// robots).
///
/// # Errors
/// An arena the world refuses.
pub fn arena_of(s: &Scenario) -> Result<Arena> {
    Ok(match s.arena {
        ArenaKind::Corridor => Arena::paper_corridor(),
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
        clock_hz: u64::from(s.timing.clock_hz),
        sensor_max_range_m: s.world.sensor_range_m,
        sensor_mounts: SensorMount::default_mounts(
            world::params::BODY_LENGTH_M,
            world::params::BODY_WIDTH_M,
        )
        .into_iter()
        .map(|m| {
            let (sin, cos) = m.angle_rad.sin_cos();
            SensorMount {
                x_m: m.x_m - cos * s.world.sensor_setback_m,
                y_m: m.y_m - sin * s.world.sensor_setback_m,
                ..m
            }
        })
        .collect(),
        ..WorldParams::default()
    }
}

/// Places the robots of a run (fails early, before any emulation, if they do not fit).
///
/// # Errors
/// More robots than the arena holds, or a placement that gives up.
pub fn build_world(s: &Scenario, repeat: u32) -> Result<World> {
    let seed = world_seed(s.seed, repeat);
    World::new(arena_of(s)?, world_params(s), s.robots, seed).with_context(|| {
        format!(
            "cannot place {} robots in the {} (robots = {})",
            s.robots,
            arena_of(s).map(|a| a.describe()).unwrap_or_default(),
            s.robots
        )
    })
}

/// One run in progress: the world and its robots, stepped one step at a time.
pub struct Swarm {
    scenario: Scenario,
    condition: Condition,
    repeat: u32,
    world: World,
    robots: Vec<Robot>,
    meters: Vec<ContactMeter>,
    stuck: Vec<StuckDetector>,
    /// Whether each robot's motors drove through the step being run.
    drove: Vec<bool>,
    /// The step period in clock states.
    period_states: u64,
    steps: Vec<StepMetrics>,
    track: Option<Track>,
    tracked: usize,
    snapshots: [u32; 4],
    saves: u64,
    parallel: bool,
    /// Every robot's centre at the latest step instant.
    last_xy: Vec<(f64, f64)>,
    /// Go on when a robot's controller fails: the robot is dead from then on (its motors
    /// coast; it is left out of the means).
    keep_going: bool,
    /// Why each dead robot died.
    dead: Vec<Option<String>>,
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
        let robots: Vec<Robot> = (0..n)
            .map(|i| {
                Robot::new(s, condition, repeat, i as u32, images)
                    .with_context(|| format!("robot {i}"))
            })
            .collect::<Result<_>>()?;
        let tracked = if record_track {
            n.min(TRACKED_ROBOTS)
        } else {
            0
        };
        let track = record_track.then(|| Track {
            paths: vec![Vec::with_capacity(s.steps as usize); tracked],
            outlines: Vec::new(),
            walls: world
                .arena()
                .walls()
                .iter()
                .map(|w| [(w.a.0, w.a.1), (w.b.0, w.b.1)])
                .collect(),
        });
        Ok(Self {
            scenario: s.clone(),
            condition,
            repeat,
            world,
            robots,
            meters: vec![ContactMeter::new(nominal_substep_states(s)); n],
            stuck: vec![StuckDetector::default(); n],
            drove: vec![false; n],
            period_states: period_states(s),
            steps: Vec::with_capacity(s.steps as usize),
            track,
            tracked,
            snapshots: {
                let k = SNAPSHOT_STEPS as u32;
                let last = s.steps.saturating_sub(1);
                [0, k.min(last), s.steps.saturating_sub(k), last]
            },
            saves: 0,
            parallel: n >= PARALLEL_ROBOTS,
            last_xy: Vec::new(),
            keep_going: false,
            dead: vec![None; n],
        })
    }

    /// Whether a robot whose controller fails is marked dead and the run goes on (default:
    /// the run stops with the error).
    pub fn set_keep_going(&mut self, keep_going: bool) {
        self.keep_going = keep_going;
    }

    /// The robots that died, with why.
    #[must_use]
    pub fn dead(&self) -> Vec<(usize, String)> {
        self.dead
            .iter()
            .enumerate()
            .filter_map(|(i, d)| d.clone().map(|d| (i, d)))
            .collect()
    }

    /// A robot's failure: the run's error, or with `keep_going` the robot's death.
    fn fail(&mut self, i: usize, e: anyhow::Error) -> Result<()> {
        let e = e.context(format!("robot {i}"));
        if self.keep_going {
            self.dead[i] = Some(format!("{e:#}"));
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

    /// Runs the next step: every MCU sleeps to the step instant, the world catches up (its
    /// collisions are the previous step's), the robots sense, step and drive.
    ///
    /// # Errors
    /// A world or controller failure (none is expected once the scenario checks out).
    pub fn step(&mut self) -> Result<()> {
        let n = self.robots.len();
        let k = self.steps.len() as u32;
        let par = self.parallel;
        let dead = self.dead.clone();
        let sleep = |(i, r): (usize, &mut Robot)| -> Option<Result<u64>> {
            dead[i].is_none().then(|| r.sleep())
        };
        let times: Vec<Option<Result<u64>>> = if par {
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
        let times = live_times;
        let t_step = match times.iter().copied().min() {
            Some(t) => t,
            // Every robot dead: the world goes on by the step period.
            None => self.world.elapsed_states() + self.period_states,
        };
        let t_step_s = t_step as f64 / f64::from(self.scenario.timing.clock_hz);
        self.close_step(t_step)?;
        if let Some(t) = self.track.as_mut() {
            record(
                &self.world,
                t,
                self.tracked,
                self.snapshots.contains(&k),
                t_step_s,
            )?;
        }
        let world = &self.world;
        let sense = |i: usize| -> Result<[Option<f64>; 4]> {
            let mut d = [None; 4];
            for (k, dk) in d.iter_mut().enumerate() {
                *dk = world.sense(i, k)?;
            }
            Ok(d)
        };
        let distances: Vec<[Option<f64>; 4]> = if par {
            (0..n).into_par_iter().map(sense).collect::<Result<_>>()?
        } else {
            (0..n).map(sense).collect::<Result<_>>()?
        };
        let dead = self.dead.clone();
        let step = |(i, (r, d)): (usize, (&mut Robot, &[Option<f64>; 4]))| {
            dead[i]
                .is_none()
                .then(|| r.step(*d).map(|rep| (rep, r.take_busy_states())))
        };
        let results: Vec<_> = if par {
            self.robots
                .par_iter_mut()
                .zip(distances.par_iter())
                .enumerate()
                .map(step)
                .collect()
        } else {
            self.robots
                .iter_mut()
                .zip(&distances)
                .enumerate()
                .map(step)
                .collect()
        };
        let period_states =
            self.scenario.timing.step_period_s * f64::from(self.scenario.timing.clock_hz);
        let (mut sum_d, mut sum_load, mut live) = (0.0, 0.0, 0usize);
        for (i, res) in results.into_iter().enumerate() {
            match res {
                Some(Ok((rep, busy))) => {
                    self.saves += u64::from(rep.saved);
                    sum_d += f64::from(rep.d);
                    sum_load += busy as f64 / period_states * 100.0;
                    live += 1;
                }
                Some(Err(e)) => self.fail(i, e)?,
                None => {}
            }
        }
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
            let drives = |w: &world::WheelCommand| {
                w.duty > 0.0
                    && matches!(
                        w.direction,
                        world::Direction::Forward | world::Direction::Reverse
                    )
            };
            self.drove[i] = drives(&left) || drives(&right);
            self.world.set_wheels(i, left, right)?;
        }
        let live_f = live.max(1) as f64;
        let mean_d = sum_d / live_f;
        let gap_cv = match self.scenario.arena {
            ArenaKind::Corridor => self.world.corridor_gap_cv()?,
            ArenaKind::Square => None,
        };
        self.steps.push(StepMetrics {
            mean_d,
            collisions_per_robot: 0.0,
            contact_fraction: 0.0,
            stuck_fraction: 0.0,
            moved_m: 0.0,
            gap_cv,
            cpu_load_percent: sum_load / live_f,
        });
        Ok(())
    }

    /// Advances the world to `t_states` (the behaviour of the latest step runs to its end)
    /// and completes that step's metrics: collisions, contact time, distance moved, stuck
    /// robots.
    fn close_step(&mut self, t_states: u64) -> Result<()> {
        let dt = t_states.saturating_sub(self.world.elapsed_states());
        let (collided, contact_states) =
            advance_world(&mut self.world, t_states, &mut self.meters, self.parallel)?;
        let n = self.robots.len();
        let (moved, stuck) = self.moved()?;
        if let Some(last) = self.steps.last_mut() {
            last.collisions_per_robot = collided as f64 / n as f64;
            last.contact_fraction = if dt == 0 {
                0.0
            } else {
                contact_states as f64 / (dt as f64 * n as f64)
            };
            last.moved_m = moved;
            last.stuck_fraction = stuck as f64 / n as f64;
        }
        Ok(())
    }

    /// The mean distance the robots' centres moved since the previous call (0 on the first)
    /// and how many robots are stuck, remembering where they are now.
    fn moved(&mut self) -> Result<(f64, usize)> {
        let n = self.robots.len();
        let mut sum = 0.0;
        let mut stuck = 0;
        let first = self.last_xy.is_empty();
        self.last_xy.resize(n, (0.0, 0.0));
        for (i, xy) in self.last_xy.iter_mut().enumerate() {
            let p = self.world.pose(i)?;
            if !first {
                let d = (p.x_m - xy.0).hypot(p.y_m - xy.1);
                sum += d;
                if self.stuck[i].record(d, self.drove[i] && self.dead[i].is_none()) {
                    stuck += 1;
                }
            }
            *xy = (p.x_m, p.y_m);
        }
        Ok((sum / n as f64, stuck))
    }

    /// Lets the last behaviour run its full period (its collisions counted) and returns the
    /// run's metrics.
    ///
    /// # Errors
    /// A world failure.
    pub fn finish(mut self) -> Result<RunOutput> {
        let end = self.world.elapsed_states() + self.period_states;
        self.close_step(end)?;
        let dead = self.dead();
        Ok(RunOutput {
            condition: self.condition,
            repeat: self.repeat,
            steps: self.steps,
            track: self.track,
            saves: self.saves,
            dead,
        })
    }
}

/// Runs one condition of one repeat. `progress` is called with the number of steps done since
/// its last call.
///
/// # Errors
/// A world or controller failure (none is expected once the scenario checks out).
pub fn run_one(
    s: &Scenario,
    condition: Condition,
    repeat: u32,
    record_track: bool,
    images: Option<&Images>,
    keep_going: bool,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RunOutput> {
    run_one_probed(
        s,
        condition,
        repeat,
        record_track,
        images,
        keep_going,
        progress,
        RobotProbes::default(),
    )
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
    /// The VCD file.
    pub path: std::path::PathBuf,
}

/// What to look at inside one robot of a run: its pins, its firmware under GDB.
#[derive(Debug, Default)]
pub struct RobotProbes {
    /// A pin trace.
    pub vcd: Option<VcdProbe>,
    /// A GDB stub for a robot, waiting for its client: (robot, listener). The run waits for
    /// the client before its first step and pauses while it has the robot stopped.
    pub gdb: Option<(usize, emu::chip::gdb::GdbListener)>,
}

/// [`run_one`] with probes on one robot: a pin trace written as VCD, a GDB client's control.
/// The run's results are the same as without them.
///
/// # Errors
/// As [`run_one`]; a probed robot that is no firmware robot; a GDB client that cannot be
/// accepted; a VCD file that cannot be written.
#[allow(clippy::too_many_arguments)]
pub fn run_one_probed(
    s: &Scenario,
    condition: Condition,
    repeat: u32,
    record_track: bool,
    images: Option<&Images>,
    keep_going: bool,
    progress: &(dyn Fn(u64) + Sync),
    probes: RobotProbes,
) -> Result<RunOutput> {
    let mut swarm = Swarm::new(s, condition, repeat, record_track, images)?;
    swarm.set_keep_going(keep_going);
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
                robot
                    .start_pin_trace(names)
                    .with_context(|| format!("--vcd-robot {}", v.robot))?;
                tracing = true;
            }
            if tracing && step == v.from + v.steps {
                robot.end_pin_trace_at_sensing();
            }
        }
        swarm.step()?;
        if let Some(v) = &probes.vcd
            && let Some(t) = swarm.robot_mut(v.robot).and_then(Robot::take_pin_trace)
        {
            write_robot_vcd(v, s, condition, repeat, &t)?;
            tracing = false;
        }
        progress(1);
    }
    if let Some(v) = &probes.vcd
        && tracing
        && let Some(t) = swarm.robot_mut(v.robot).and_then(Robot::finish_pin_trace)
    {
        write_robot_vcd(v, s, condition, repeat, &t)?;
    }
    if let Some(robot) = debugged.and_then(|k| swarm.robot_mut(k)) {
        robot.detach_debugger();
    }
    swarm.finish()
}

/// Writes a robot's pin trace as the VCD file of `v`.
fn write_robot_vcd(
    v: &VcdProbe,
    s: &Scenario,
    condition: Condition,
    repeat: u32,
    t: &crate::robot::RobotTrace,
) -> Result<()> {
    let file = std::fs::File::create(&v.path)
        .with_context(|| format!("--vcd: cannot create `{}`", v.path.display()))?;
    let info = emu::chip::vcd::VcdInfo {
        source: format!(
            "robot {} of h8swarm run {} ({} run, repeat {repeat}, seed {}), steps {} to {}",
            v.robot,
            s.name,
            condition.name(),
            s.seed,
            v.from,
            (v.from + v.steps).min(s.steps) - 1
        ),
    };
    emu::chip::vcd::write_vcd(file, &t.pins, Some(&t.phases), &info)
        .with_context(|| format!("--vcd: cannot write `{}`", v.path.display()))
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

/// Advances the world to `target_states` in its sub-steps, feeding every robot's bumpers
/// after each to its meter; returns the collisions counted and the robot-states in contact.
fn advance_world(
    world: &mut World,
    target_states: u64,
    meters: &mut [ContactMeter],
    par: bool,
) -> Result<(u64, u64)> {
    let (mut collisions, mut contact) = (0u64, 0u64);
    let dt = target_states.saturating_sub(world.elapsed_states());
    for len in world.substep_plan(dt) {
        if par {
            world.advance_states_par(len);
        } else {
            world.advance_states(len);
        }
        for (i, m) in meters.iter_mut().enumerate() {
            let pressed = world.bumpers(i)?.iter().any(|&b| b);
            m.sample(pressed, len);
            let (c, t) = m.take();
            collisions += c;
            contact += t;
        }
    }
    Ok((collisions, contact))
}

fn record(world: &World, t: &mut Track, tracked: usize, snapshot: bool, time_s: f64) -> Result<()> {
    for i in 0..tracked {
        let p = world.pose(i)?;
        t.paths[i].push((p.x_m, p.y_m));
        if snapshot {
            t.outlines.push(Outline {
                robot: i,
                time_s,
                corners: world.corners(i)?,
                heading: (p.heading_rad.cos(), p.heading_rad.sin()),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
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
        let mut collisions = Vec::new();
        let mut t = 0u64;
        for _ in 0..500 {
            t += period;
            for len in w.substep_plan(t - w.elapsed_states()) {
                assert_eq!(len, nominal, "no sliver of a sub-step");
            }
            let (c, contact) = advance_world(&mut w, t, &mut meters, false).unwrap();
            collisions.push((c, contact));
        }
        assert_eq!(w.elapsed_states(), 500 * period, "no drift");
        let total: u64 = collisions.iter().map(|c| c.0).sum();
        assert_eq!(total, 1, "one push, one collision");
        // From the step it arrives (2.5 m → 2.885 m at 0.15 m/s: about 4 steps) it is in
        // contact the whole step.
        assert!(collisions[10..].iter().all(|&(_, c)| c == period));
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
}
