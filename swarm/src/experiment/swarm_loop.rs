//! The swarm loop: every robot's MCU, sensors and body stepped together in the world, step
//! after step, with the metrics gathered as the steps complete.
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

use super::metrics::{GAP_TOUCH_M, Rows, RunMetrics, StepMetrics, metrics_fields, motion_metrics};
use super::output::{
    DeadRobot, Outline, RunOutput, SNAPSHOT_STEPS, TRACKED_ROBOTS, Track, spacetime_stride,
};
use super::setup::{build_world, nominal_substep_states, period_states};
use super::substeps::{Readings, advance_world};
use crate::collisions::ContactMeter;
use crate::motion::{MotionStep, MotionTracker, RobotTally};
use crate::robot::{Condition, Images, Robot};
use crate::scenario::{ArenaKind, Scenario};
use anyhow::{Context, Result};
use rayon::prelude::*;
use world::World;

/// Swarms at least this large step their robots in parallel inside a run.
pub const PARALLEL_ROBOTS: usize = 64;

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
    /// Keep a second worker spinning through the world's sub-steps ([`Swarm::set_spinning_helper`]).
    spinning_helper: bool,
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
            spinning_helper: false,
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

    /// Writes every step's row of `metrics.csv` (no header; [`super::metrics_row`]) to a new file at
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

    /// Whether a second worker of rayon's pool spins through the world's sub-steps, taking
    /// their parallel jobs as they come, instead of sleeping between them (off by default;
    /// used from 512 robots, `PIPELINE_ROBOTS`, when the meters are fed beside each sub-step).
    /// Only for a swarm that is its pool's only work: two swarms stepped side by side on one
    /// pool with it could each hold the other's helper and never finish. The results do not
    /// depend on it.
    pub fn set_spinning_helper(&mut self, on: bool) {
        self.spinning_helper = on;
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

    /// [`advance_world`] on the pool with a second worker spinning through the sub-steps
    /// ([`Swarm::set_spinning_helper`]); out of line, so that the path without it stays as it
    /// was (inlined, it moved the wall time of small swarms: docs/performance.md).
    #[inline(never)]
    fn advance_helped(&mut self, t_states: u64) -> Result<(u64, u64)> {
        super::spin::with_spinning_helper(|| {
            advance_world(
                &mut self.world,
                t_states,
                (&mut self.meters, &mut self.collided),
                true,
                &mut self.drives,
                &mut self.readings,
            )
        })
    }

    /// Advances the world to `t_states` (the behaviour of the latest step runs to its end)
    /// and completes that step's metrics: collisions, contact time, where the robots went.
    fn close_step(&mut self, t_states: u64) -> Result<()> {
        let dt = t_states.saturating_sub(self.world.elapsed_states());
        let par = self.par();
        // The helper pays where the meters are fed beside each sub-step (it has a job every
        // sub-step); in a smaller swarm it would spin through one-thread stages for nothing.
        let spin = self.spinning_helper && self.readings.pipelined(par, self.meters.len());
        let (collided, contact_states) = if spin {
            self.advance_helped(t_states)?
        } else {
            advance_world(
                &mut self.world,
                t_states,
                (&mut self.meters, &mut self.collided),
                par,
                &mut self.drives,
                &mut self.readings,
            )?
        };
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
            solver: self.world.solver_stats(),
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

/// What a robot's board shows its MCU for a step: each sensor's true distance (mm, `None`
/// beyond range) and the bumper switches (front, rear, left, right).
type Senses = ([Option<f64>; 4], [bool; 4]);

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
mod tests;
