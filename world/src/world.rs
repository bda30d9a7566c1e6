//! The world: the robots' state and the sub-step that runs the pipeline's stages over it in
//! order (see [`crate::pipeline`]'s module documentation for the stages).

use rayon::prelude::*;
use seeding::Purpose;

use crate::arena::{Arena, ArenaKind};
use crate::body::{BodyConst, BodyPose};
use crate::error::WorldError;
use crate::geometry::{Obb, arc_step_twist, obb_distance, obb_overlap};
use crate::motor::{Direction, LagCoefficients, MODE_BRAKE, MODE_COAST, MODE_DRIVE, WheelCommand};
use crate::params::{MAX_ADVANCE_S, WorldParams};
use crate::pipeline::broad_phase::BroadPhase;
use crate::pipeline::corrections::{Corrections, Scene};
use crate::pipeline::drive::{Drive, Motion};
use crate::pipeline::islands::Islands;
use crate::pipeline::narrow_phase::{NarrowPhase, Probe, speculative_m};
use crate::pipeline::par::{PAR_CHUNK, PAR_STAGE_ROBOTS};
use crate::pipeline::sensing::{Bumpers, MountRays, RayScene};
use crate::pipeline::solver::IslandBody;
use crate::pipeline::warm_start::WarmStart;
use crate::placement::{place_corridor, place_open, stream_rng, unit};

/// Most robots a world may hold (indices are stored as `u32`).
pub const MAX_ROBOTS: usize = 50_000_000;

/// Bumper index of the front switch in [`World::bumpers`] (also the default front sensor).
pub const FRONT: usize = 0;
/// Bumper index of the rear switch (also the default rear sensor).
pub const REAR: usize = 1;
/// Bumper index of the left switch (also the default left sensor).
pub const LEFT: usize = 2;
/// Bumper index of the right switch (also the default right sensor).
pub const RIGHT: usize = 3;

/// A robot's pose: centre in metres, heading in radians counter-clockwise from +x, in (−π, π].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Centre x, metres.
    pub x_m: f64,
    /// Centre y, metres.
    pub y_m: f64,
    /// Heading, radians.
    pub heading_rad: f64,
}

/// What the contact solver did, counted over the world's life (for evaluation: these are
/// not used by the simulation).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolverStats {
    /// Sub-steps taken.
    pub substeps: u64,
    /// Contacts (robot–robot and robot–wall manifolds, speculative ones included) solved.
    pub contacts: u64,
    /// Robot-sub-steps in a contact (solved rather than moved freely).
    pub active_robot_substeps: u64,
    /// Islands (robots joined by contacts) whose velocities were solved, over all sub-steps.
    pub islands: u64,
    /// Gauss–Seidel sweeps of the velocity solver run (over all sub-steps).
    pub solver_sweeps: u64,
    /// Islands whose solve the sweep cap (`WorldParams::solver_iterations`) stopped before a
    /// sweep changed no impulse by more than 1e-6 N·s, or (under `Convergence::Newton`) whose
    /// Newton solve its cap of outer iterations stopped.
    pub capped_islands: u64,
    /// Islands solved by Newton's method (`Convergence::Newton`; the rest by sweeps).
    pub newton_islands: u64,
    /// Newton steps run, over those islands.
    pub newton_steps: u64,
    /// Sub-steps whose velocity solve left an overlap for the position correction.
    pub overlap_substeps: u64,
    /// Position-correction sweeps run.
    pub position_sweeps: u64,
    /// Robot-sub-steps stopped early because the position correction did not clear them.
    pub stopped_robot_substeps: u64,
}

/// The sub-steps of one advance, in clock states (see [`World::substep_plan`]): an iterator
/// of lengths that add up to the advance exactly and differ by at most one state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SubstepPlan {
    /// Sub-steps left.
    left: u64,
    /// Sub-steps still to be one state longer.
    long_left: u64,
    /// The shorter length, states.
    short_states: u64,
}

impl SubstepPlan {
    /// The plan for `dt_states` in sub-steps of at most `max_states` (at least 1).
    pub fn new(dt_states: u64, max_states: u64) -> SubstepPlan {
        let max_states = max_states.max(1);
        let k = dt_states.div_ceil(max_states);
        if k == 0 {
            return SubstepPlan {
                left: 0,
                long_left: 0,
                short_states: 0,
            };
        }
        SubstepPlan {
            left: k,
            long_left: dt_states % k,
            short_states: dt_states / k,
        }
    }

    /// Number of sub-steps.
    pub fn substeps(&self) -> u64 {
        self.left
    }
}

impl Iterator for SubstepPlan {
    type Item = u64;

    fn next(&mut self) -> Option<u64> {
        if self.left == 0 {
            return None;
        }
        self.left -= 1;
        if self.long_left > 0 {
            self.long_left -= 1;
            Some(self.short_states + 1)
        } else {
            Some(self.short_states)
        }
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = usize::try_from(self.left).unwrap_or(usize::MAX);
        (n, Some(n))
    }
}

/// The physical world of one run: an arena, robots with motors, bumpers and sensors.
///
/// See the crate documentation for the model. All methods that take a robot or a sensor
/// index return an error for an index out of range; nothing panics.
#[derive(Debug, Clone)]
pub struct World {
    arena: Arena,
    params: WorldParams,
    seed: u64,
    /// What every body shares: size, mass, inertia, wheels, friction.
    body: BodyConst,
    gains: Vec<[f64; 2]>,
    pose: Vec<BodyPose>,
    motion: Vec<Motion>,
    /// Pose at the start of the current sub-step.
    prev: Vec<BodyPose>,
    /// World-frame velocity (vx, vy, ω): the wheels' twist for a free robot, the solved one
    /// for a robot in contact (kept as momentum into the next sub-step).
    vel: Vec<[f64; 3]>,
    /// Mean wheel speeds (left, right) over the current sub-step, m/s.
    wmean: Vec<[f64; 2]>,
    /// Accumulated wheel impulses of the latest solve (left along, left across, right …).
    wheel_imp: Vec<[f64; 4]>,
    /// Longitudinal force each drive wheel transmitted to the body over the latest sub-step
    /// (left, right), N, along the heading (see [`World::wheel_forces`]).
    wheel_force: Vec<[f64; 2]>,
    bumpers: Bumpers,
    broad: BroadPhase,
    narrow: NarrowPhase,
    islands: Islands,
    /// The solved robots' motions of the latest sub-step (scratch, in `narrow.active`'s order).
    solved: Vec<SolvedMotion>,
    warm: WarmStart,
    corrections: Corrections,
    /// Lag coefficients for the two sub-step lengths of the latest plan (length in states).
    lag_cache: [(u64, LagCoefficients); 2],
    mounts: Vec<MountRays>,
    max_substep_states: u64,
    elapsed_states: u64,
    substeps: u64,
    stats: SolverStats,
}

impl World {
    /// A world with `n_robots` robots placed at random, non-overlapping poses (seeded):
    /// in the corridor on its centre line facing along it (forward or backward at random)
    /// with random gaps; in an open arena at uniform positions and headings. Every body keeps
    /// `params.placement_clearance_m` from the others and from the walls (in the corridor:
    /// along it; across it the body is centred).
    ///
    /// Errors: bad parameters; more robots than fit (with how many fit at most); or random
    /// placement giving up after its bounded number of attempts.
    pub fn new(
        arena: Arena,
        params: WorldParams,
        n_robots: usize,
        seed: u64,
    ) -> Result<World, WorldError> {
        params.validate()?;
        check_robot_count(n_robots)?;
        let poses = match arena.kind() {
            ArenaKind::Corridor => place_corridor(&arena, &params, n_robots, seed)?,
            ArenaKind::Open => place_open(&arena, &params, n_robots, seed)?,
        };
        World::build(arena, params, poses, seed)
    }

    /// A world with robots at the given poses (checked: inside the walls, no overlaps). The
    /// seed draws the motor gains.
    pub fn from_poses(
        arena: Arena,
        params: WorldParams,
        poses: &[Pose],
        seed: u64,
    ) -> Result<World, WorldError> {
        params.validate()?;
        check_robot_count(poses.len())?;
        let mut body = Vec::with_capacity(poses.len());
        for (i, p) in poses.iter().enumerate() {
            let b = body_pose(p);
            if !p.x_m.is_finite() || !p.y_m.is_finite() || !p.heading_rad.is_finite() {
                return Err(outside(i, p, &arena));
            }
            body.push(b);
        }
        let w = World::build(arena, params, body, seed)?;
        for (i, p) in poses.iter().enumerate() {
            if w.wall_penetration(i) {
                return Err(outside(i, p, &arena));
            }
        }
        if let Some((a, b, depth_m)) = w.first_overlap() {
            return Err(WorldError::PosesOverlap { a, b, depth_m });
        }
        Ok(w)
    }

    fn build(
        arena: Arena,
        params: WorldParams,
        poses: Vec<BodyPose>,
        seed: u64,
    ) -> Result<World, WorldError> {
        let n = poses.len();
        let body = params.body();
        let spread = params.motor_gain_spread;
        let gains = (0..n)
            .map(|i| {
                let mut rng = stream_rng(seed, Purpose::MotorGain, i as u64);
                let l = 1.0 + spread * (2.0 * unit(&mut rng) - 1.0);
                let r = 1.0 + spread * (2.0 * unit(&mut rng) - 1.0);
                [l, r]
            })
            .collect();
        let max_substep_states = (params.max_substep_s * params.clock_hz as f64).round() as u64;
        let max_h = max_substep_states as f64 / params.clock_hz as f64;
        // The speculative distance of the longest sub-step must fit in the broad phase's
        // margin with room for drift.
        let broad = BroadPhase::new(
            arena.width_m(),
            arena.height_m(),
            body.radius_m,
            speculative_m(&params, body.radius_m, max_h),
            n,
        );
        let lag = LagCoefficients::new(
            max_h,
            params.motor_time_constant_s,
            params.brake_time_constant_s,
            params.coast_time_constant_s,
        );
        let mut w = World {
            arena,
            seed,
            body,
            gains,
            motion: vec![
                Motion {
                    speed: [0.0; 2],
                    target: [0.0; 2],
                    mode: [MODE_COAST; 2]
                };
                n
            ],
            prev: poses.clone(),
            vel: vec![[0.0; 3]; n],
            wmean: vec![[0.0; 2]; n],
            wheel_imp: vec![[0.0; 4]; n],
            wheel_force: vec![[0.0; 2]; n],
            pose: poses,
            bumpers: Bumpers::new(n),
            broad,
            narrow: NarrowPhase::new(n),
            islands: Islands::new(n),
            solved: Vec::new(),
            warm: WarmStart::new(n),
            corrections: Corrections::new(n),
            lag_cache: [(max_substep_states, lag), (0, lag)],
            mounts: MountRays::all(&params),
            params,
            max_substep_states,
            elapsed_states: 0,
            substeps: 0,
            stats: SolverStats::default(),
        };
        w.rebuild_broad_phase(false);
        Ok(w)
    }

    // ----- accessors -------------------------------------------------------------------------

    /// Number of robots.
    pub fn robot_count(&self) -> usize {
        self.pose.len()
    }

    /// The arena.
    pub fn arena(&self) -> &Arena {
        &self.arena
    }

    /// The parameters in use.
    pub fn params(&self) -> &WorldParams {
        &self.params
    }

    /// The seed the world was made with.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Simulated time advanced so far, seconds (from [`World::elapsed_states`]).
    pub fn elapsed_s(&self) -> f64 {
        self.elapsed_states as f64 / self.params.clock_hz as f64
    }

    /// Simulated time advanced so far, in clock states (`params.clock_hz`).
    pub fn elapsed_states(&self) -> u64 {
        self.elapsed_states
    }

    /// What the contact solver has done so far (an evaluation aid).
    pub fn solver_stats(&self) -> SolverStats {
        self.stats
    }

    /// Side of the broad-phase grid cells, metres (diagnostic).
    pub fn grid_cell_m(&self) -> f64 {
        self.broad.grid().cell_m()
    }

    /// Internal sub-steps taken so far.
    pub fn substeps(&self) -> u64 {
        self.substeps
    }

    fn check_robot(&self, robot: usize) -> Result<(), WorldError> {
        if robot < self.pose.len() {
            Ok(())
        } else {
            Err(WorldError::RobotIndex {
                index: robot,
                count: self.pose.len(),
            })
        }
    }
    /// A robot's pose (heading in (−π, π]).
    pub fn pose(&self, robot: usize) -> Result<Pose, WorldError> {
        self.check_robot(robot)?;
        let b = self.pose[robot];
        Ok(Pose {
            x_m: b.x,
            y_m: b.y,
            heading_rad: libm::atan2(b.s, b.c),
        })
    }

    /// A robot's wheel speeds now (left, right), m/s, as driven by its motors. Wheels pushing
    /// against an obstacle keep turning (they slip); see the crate docs.
    pub fn wheel_speeds(&self, robot: usize) -> Result<[f64; 2], WorldError> {
        self.check_robot(robot)?;
        Ok(self.motion[robot].speed)
    }

    /// A robot's mean wheel speeds over the latest sub-step (left, right), m/s: the exact
    /// integral of the motors' lag, the speeds the body followed if it touched nothing. Like
    /// [`World::wheel_speeds`], the motors' speed: a blocked wheel slips at it.
    pub fn wheel_mean_speeds(&self, robot: usize) -> Result<[f64; 2], WorldError> {
        self.check_robot(robot)?;
        Ok(self.wmean[robot])
    }

    /// The longitudinal force each drive wheel transmitted between the floor and the body over
    /// the latest sub-step (left, right), N, signed along the robot's heading (positive: the
    /// floor pushes the robot forward). For a robot solved in contact, the solver's accumulated
    /// rolling impulse of the wheel over the sub-step's length (a blocked robot's slipping
    /// wheels give their traction, `μ_floor · m·g/2` each, against their slip). For a robot
    /// touching nothing, the force that gave its body its change of velocity over the sub-step,
    /// split between the wheels by the rigid body's equations, m·Δv/h = F_l + F_r and
    /// I·Δω/h = (F_r − F_l)·track/2, each at most the wheel's traction (a body that goes from
    /// a solved velocity to its wheels' in one sub-step changes it faster than the floor could
    /// push it): 0 at a steady speed, m·a/2 a wheel while accelerating straight. Reading it
    /// changes nothing; it is zero before the first sub-step.
    pub fn wheel_forces(&self, robot: usize) -> Result<[f64; 2], WorldError> {
        self.check_robot(robot)?;
        Ok(self.wheel_force[robot])
    }

    /// A robot's motor gains (left, right), drawn once from the seed.
    pub fn motor_gains(&self, robot: usize) -> Result<[f64; 2], WorldError> {
        self.check_robot(robot)?;
        Ok(self.gains[robot])
    }

    /// A robot's bumpers as of the latest sub-step: `[front, rear, left, right]`, `true` =
    /// pressed (index with [`FRONT`], [`REAR`], [`LEFT`], [`RIGHT`]).
    pub fn bumpers(&self, robot: usize) -> Result<[bool; 4], WorldError> {
        self.check_robot(robot)?;
        Ok(self.bumpers.of(robot))
    }

    /// A robot's body outline for plotting: front-left, rear-left, rear-right, front-right
    /// corners (x, y), metres.
    pub fn corners(&self, robot: usize) -> Result<[(f64, f64); 4], WorldError> {
        self.check_robot(robot)?;
        Ok(self.obb(robot).corners())
    }

    #[inline]
    fn obb(&self, i: usize) -> Obb {
        self.body.obb(self.pose[i])
    }

    // ----- commands ----------------------------------------------------------------------------

    /// Sets a robot's two motor commands; they hold until changed. The commanded wheel speed
    /// is duty × top speed × the wheel's motor gain, signed by the direction (brake and coast:
    /// 0 with their own time constants).
    pub fn set_wheels(
        &mut self,
        robot: usize,
        left: WheelCommand,
        right: WheelCommand,
    ) -> Result<(), WorldError> {
        self.check_robot(robot)?;
        left.check("left")?;
        right.check("right")?;
        let top = self.params.top_speed_m_per_s;
        let gains = self.gains[robot];
        let m = &mut self.motion[robot];
        for (w, cmd) in [left, right].into_iter().enumerate() {
            let (target, mode) = match cmd.direction {
                Direction::Forward => (cmd.duty * top * gains[w], MODE_DRIVE),
                Direction::Reverse => (-cmd.duty * top * gains[w], MODE_DRIVE),
                Direction::Brake => (0.0, MODE_BRAKE),
                Direction::Coast => (0.0, MODE_COAST),
            };
            m.target[w] = target;
            m.mode[w] = mode;
        }
        Ok(())
    }

    /// Moves a robot to a pose (checked against the walls and the other robots, which stay);
    /// its wheel speeds and commands are kept.
    pub fn set_pose(&mut self, robot: usize, pose: Pose) -> Result<(), WorldError> {
        self.check_robot(robot)?;
        if !pose.x_m.is_finite() || !pose.y_m.is_finite() || !pose.heading_rad.is_finite() {
            return Err(outside(robot, &pose, &self.arena));
        }
        let old = self.pose[robot];
        self.pose[robot] = body_pose(&pose);
        if self.wall_penetration(robot) {
            self.pose[robot] = old;
            return Err(outside(robot, &pose, &self.arena));
        }
        let a = self.obb(robot);
        for j in 0..self.pose.len() {
            if j != robot
                && let Some(o) = obb_overlap(&a, &self.obb(j), 0.0)
            {
                self.pose[robot] = old;
                return Err(WorldError::PosesOverlap {
                    a: robot.min(j),
                    b: robot.max(j),
                    depth_m: o.depth_m,
                });
            }
        }
        self.prev[robot] = self.pose[robot];
        self.rebuild_broad_phase(false);
        Ok(())
    }

    // ----- time ----------------------------------------------------------------------------------

    /// Advances every robot by `dt_s` seconds, rounded to whole clock states (see
    /// [`World::advance_states`]), on the calling thread. A convenience for tests and tools:
    /// the experiment counts its time in states and calls [`World::advance_states`].
    ///
    /// Errors: `dt_s` not positive, less than one state, or beyond an hour.
    pub fn advance(&mut self, dt_s: f64) -> Result<(), WorldError> {
        let states = self.states_of(dt_s)?;
        self.advance_states_impl(states, false);
        Ok(())
    }

    /// As [`World::advance`], with the per-robot phases on rayon's current pool (see
    /// [`World::advance_states_par`]).
    pub fn advance_par(&mut self, dt_s: f64) -> Result<(), WorldError> {
        let states = self.states_of(dt_s)?;
        self.advance_states_impl(states, true);
        Ok(())
    }

    fn states_of(&self, dt_s: f64) -> Result<u64, WorldError> {
        let states = (dt_s * self.params.clock_hz as f64).round();
        if dt_s.is_nan() || states < 1.0 || dt_s > MAX_ADVANCE_S {
            return Err(WorldError::TimeStep {
                value_s: dt_s,
                max_s: MAX_ADVANCE_S,
            });
        }
        Ok(states as u64)
    }

    /// Advances every robot by `dt_states` clock states (one clock rules it all: the world
    /// counts the time the robots' MCUs count). The interval is split into
    /// [`World::substep_plan`]'s equal sub-steps; time is kept as an integer, so no drift and no
    /// sliver of a sub-step can arise. Zero states do nothing.
    pub fn advance_states(&mut self, dt_states: u64) {
        self.advance_states_impl(dt_states, false);
    }

    /// As [`World::advance_states`], with the per-robot phases (motors, free robots' motion,
    /// broad-phase candidates, contact search) split over rayon's current thread pool in fixed
    /// chunks merged in index order; the contact solve runs island by island, islands in
    /// parallel (each island's solve is the same on any thread).
    /// Results are bit-identical to [`World::advance_states`] whatever the number of threads.
    pub fn advance_states_par(&mut self, dt_states: u64) {
        self.advance_states_impl(dt_states, true);
    }

    /// How an advance of `dt_states` is cut into sub-steps: `k = ⌈dt / max⌉` pieces (max =
    /// `max_substep_s` in states), the first `dt mod k` of them one state longer than the rest,
    /// so they add up to `dt` exactly and differ by at most one state.
    pub fn substep_plan(&self, dt_states: u64) -> SubstepPlan {
        SubstepPlan::new(dt_states, self.max_substep_states)
    }

    /// The longest sub-step, in clock states (`max_substep_s` rounded).
    pub fn max_substep_states(&self) -> u64 {
        self.max_substep_states
    }

    fn advance_states_impl(&mut self, dt_states: u64, parallel: bool) {
        for len in self.substep_plan(dt_states) {
            self.substep(len, parallel);
        }
    }

    /// The lag coefficients for a sub-step of `len` states (the two lengths of a plan cached).
    fn lag_for(&mut self, len: u64) -> LagCoefficients {
        if let Some(&(_, l)) = self.lag_cache.iter().find(|(k, _)| *k == len) {
            return l;
        }
        let l = LagCoefficients::new(
            len as f64 / self.params.clock_hz as f64,
            self.params.motor_time_constant_s,
            self.params.brake_time_constant_s,
            self.params.coast_time_constant_s,
        );
        self.lag_cache.swap(0, 1);
        self.lag_cache[0] = (len, l);
        l
    }

    /// One sub-step of `len` clock states: the pipeline's stages in order (see
    /// [`crate::pipeline`]); with `parallel`, the islands on rayon's pool, and the per-robot
    /// stages too from [`PAR_STAGE_ROBOTS`] robots, with the same result.
    fn substep(&mut self, len: u64, parallel: bool) {
        // The islands' solve on the pool with `parallel`; the short per-robot stages only in
        // large swarms.
        let stages = parallel && self.pose.len() >= PAR_STAGE_ROBOTS;
        let h = len as f64 / self.params.clock_hz as f64;
        let drive = Drive {
            lag: self.lag_for(len),
            inv_track: 1.0 / self.params.wheel_track_m,
            h,
            inv_h: 1.0 / h,
            body: self.body,
        };
        // 1. Motors: the wheel speeds over the sub-step.
        self.run_motors(&drive, stages);
        self.bumpers.begin_substep();
        // 2. Contacts at the start of the sub-step, gaps up to the speculative distance.
        let spec = speculative_m(&self.params, self.body.radius_m, h);
        let probe = Probe::new(
            &self.pose,
            &self.body,
            self.arena.width_m(),
            self.arena.height_m(),
            spec,
        );
        self.narrow.find(
            &probe,
            self.broad.candidates(),
            &self.wmean,
            drive.inv_track,
            h,
            stages,
        );
        // 3. Robots touching nothing follow their wheels exactly; the others are solved.
        self.move_free(&drive, stages);
        if !self.narrow.active.is_empty() {
            self.solve(h, (parallel, stages));
        }
        self.warm.keep(&self.narrow.contacts);
        if !self.narrow.checked.is_empty() {
            // 4. What the linearised solve left of an overlap is corrected.
            self.correct(h);
            // 5. A bumper is pressed when the contacts on its face carried force: the solver's
            // impulses and the corrections' pushes (as impulses) summed over the sub-step.
            // A switch operates at `bumper_force_n` and, once pressed, releases only below
            // `bumper_release_force_n` (a snap-action switch's hysteresis).
            self.bumpers
                .push_contacts(&self.narrow.contacts, &self.pose);
            self.bumpers.press(
                self.params.bumper_force_n * h,
                self.params.bumper_release_force_n * h,
            );
            self.stats.active_robot_substeps += self.narrow.active.len() as u64;
            self.stats.contacts += self.narrow.contacts.len() as u64;
            self.narrow.clear_flags();
        }
        // 6. The broad phase is rebuilt once some robot has drifted too far.
        if self.broad.is_stale(&self.pose) {
            self.rebuild_broad_phase(stages);
        }
        self.elapsed_states += len;
        self.substeps += 1;
        self.stats.substeps += 1;
    }

    /// The motors of every robot, in chunks on rayon's pool with `parallel`.
    fn run_motors(&mut self, drive: &Drive, parallel: bool) {
        if parallel && self.pose.len() > PAR_CHUNK {
            self.motion
                .par_chunks_mut(PAR_CHUNK)
                .zip(self.wmean.par_chunks_mut(PAR_CHUNK))
                .zip(self.prev.par_chunks_mut(PAR_CHUNK))
                .zip(self.pose.par_chunks(PAR_CHUNK))
                .for_each(|(((m, w), pr), p)| drive.motors(m, w, pr, p));
        } else {
            drive.motors(
                &mut self.motion,
                &mut self.wmean,
                &mut self.prev,
                &self.pose,
            );
        }
    }

    /// The robots that touch nothing follow their wheels, in chunks on rayon's pool with
    /// `parallel`.
    fn move_free(&mut self, drive: &Drive, parallel: bool) {
        let flags = &self.narrow.flags;
        if parallel && self.pose.len() > PAR_CHUNK {
            self.pose
                .par_chunks_mut(PAR_CHUNK)
                .zip(self.vel.par_chunks_mut(PAR_CHUNK))
                .zip(self.wheel_force.par_chunks_mut(PAR_CHUNK))
                .zip(self.wmean.par_chunks(PAR_CHUNK))
                .zip(flags.par_chunks(PAR_CHUNK))
                .for_each(|((((p, v), fw), w), f)| drive.free(p, v, fw, w, f));
        } else {
            drive.free(
                &mut self.pose,
                &mut self.vel,
                &mut self.wheel_force,
                &self.wmean,
                flags,
            );
        }
    }

    /// The solved robots of a sub-step of `h` seconds: warm-started from the previous
    /// sub-step's impulses of the same contacts and wheels, split into islands and solved;
    /// they then move by the exact motion of their solved velocities.
    fn solve(&mut self, h: f64, (parallel, stages): (bool, bool)) {
        self.warm.apply(
            &mut self.narrow.contacts,
            &self.narrow.active,
            &self.motion,
            &mut self.wheel_imp,
            self.substeps,
            stages,
        );
        self.islands.build(
            &mut self.narrow.active,
            &mut self.narrow.contacts,
            &self.pose,
            &self.vel,
            &self.wmean,
            &self.wheel_imp,
        );
        let done = self.islands.solve(
            &mut self.narrow.contacts,
            &self.body,
            h,
            self.params.solver_iterations,
            self.params.solver_convergence,
            parallel,
        );
        self.stats.islands += self.islands.len() as u64;
        self.stats.solver_sweeps += done.sweeps;
        self.stats.capped_islands += done.capped;
        self.stats.newton_islands += done.newton_islands;
        self.stats.newton_steps += done.newton_steps;
        // Each solved robot's motion over the sub-step (per robot, so on any thread), then
        // written back in order.
        let pose = &self.pose;
        let moved = |(&i, b): (&u32, &IslandBody)| solved_motion(pose[i as usize], b, h);
        self.solved.clear();
        if stages && self.narrow.active.len() > PAR_CHUNK {
            self.narrow
                .active
                .par_iter()
                .zip(self.islands.bodies.par_iter())
                .map(moved)
                .collect_into_vec(&mut self.solved);
        } else {
            self.solved.extend(
                self.narrow
                    .active
                    .iter()
                    .zip(self.islands.bodies.iter())
                    .map(moved),
            );
        }
        for (&i, m) in self.narrow.active.iter().zip(&self.solved) {
            let i = i as usize;
            self.pose[i] = m.pose;
            self.vel[i] = m.vel;
            self.wheel_imp[i] = m.wheel_imp;
            self.wheel_force[i] = m.wheel_force;
        }
    }

    /// The position corrections of a sub-step of `h` seconds, counted in the statistics.
    fn correct(&mut self, h: f64) {
        let mut scene = Scene {
            pose: &mut self.pose,
            prev: &self.prev,
            vel: &mut self.vel,
            bumpers: &mut self.bumpers,
            cand: self.broad.candidates(),
            body: &self.body,
            w: self.arena.width_m(),
            h: self.arena.height_m(),
        };
        let done = self.corrections.clear_overlaps(
            &mut scene,
            &self.narrow.checked,
            self.params.position_iterations,
            h,
        );
        self.stats.overlap_substeps += u64::from(done.overlapped);
        self.stats.position_sweeps += done.sweeps;
        self.stats.stopped_robot_substeps += done.stopped;
    }

    // ----- collisions ----------------------------------------------------------------------------

    /// Rebuilds the grid and the candidate lists from the current positions.
    fn rebuild_broad_phase(&mut self, parallel: bool) {
        self.broad.rebuild(
            &self.pose,
            self.body.radius_m,
            self.arena.width_m(),
            self.arena.height_m(),
            parallel,
        );
    }

    fn wall_penetration(&self, i: usize) -> bool {
        self.pose[i].crosses_walls(
            self.body.hx,
            self.body.hy,
            self.arena.width_m(),
            self.arena.height_m(),
        )
    }

    /// The first overlapping pair (lower index first) with its depth, by brute force over the
    /// broad-phase candidates.
    fn first_overlap(&self) -> Option<(usize, usize, f64)> {
        let mut best: Option<(usize, usize, f64)> = None;
        for &[i, j] in &self.broad.candidates().pairs {
            let (i, j) = (i as usize, j as usize);
            if let Some(o) = obb_overlap(&self.obb(i), &self.obb(j), 0.0)
                && best.is_none_or(|(a, b, _)| (i, j) < (a, b))
            {
                best = Some((i, j, o.depth_m));
            }
        }
        best
    }

    /// The deepest overlap between any two bodies or a body and a wall now, metres (0 when
    /// nothing overlaps), by brute force over the broad-phase candidates: a check, not used by
    /// the simulation.
    pub fn deepest_overlap_m(&self) -> f64 {
        let mut deepest: f64 = 0.0;
        for &[i, j] in &self.broad.candidates().pairs {
            if let Some(o) = obb_overlap(&self.obb(i as usize), &self.obb(j as usize), 0.0) {
                deepest = deepest.max(o.depth_m);
            }
        }
        let (w, h) = (self.arena.width_m(), self.arena.height_m());
        for i in 0..self.pose.len() {
            let b = self.pose[i];
            let (ex, ey) = self.obb(i).aabb_half_extents();
            for d in [ex - b.x, b.x + ex - w, ey - b.y, b.y + ey - h] {
                deepest = deepest.max(d);
            }
        }
        deepest
    }

    // ----- sensing -------------------------------------------------------------------------------

    /// Distance in millimetres from a sensor's mount to the nearest wall or other robot's body
    /// along its ray (the nearest over its cone rays), or `None` if nothing is within
    /// `sensor_max_range_m`. The robot's own body is never hit.
    pub fn sense(&self, robot: usize, sensor: usize) -> Result<Option<f64>, WorldError> {
        self.check_robot(robot)?;
        let Some(m) = self.mounts.get(sensor) else {
            return Err(WorldError::UnknownSensor {
                index: sensor,
                count: self.mounts.len(),
            });
        };
        Ok(self.rays().sense(robot, m))
    }

    /// What the sensors' rays are cast against now.
    fn rays(&self) -> RayScene<'_> {
        RayScene {
            pose: &self.pose,
            body: &self.body,
            grid: self.broad.grid(),
            drift_limit_m: self.broad.drift_limit_m(),
            w: self.arena.width_m(),
            h: self.arena.height_m(),
            range: self.params.sensor_max_range_m,
        }
    }

    // ----- corridor metric -----------------------------------------------------------------------

    /// The free gaps between neighbouring robots along the corridor, metres, in order along it:
    /// robots sorted by centre x (robots cannot pass each other in the corridor), gap k = the
    /// shortest distance between the outlines of robots k and k+1 (0 when touching; for robots
    /// facing along the corridor it is the distance between rear and front faces). The gaps
    /// to the end walls are not included, so n robots give n − 1 gaps. Errors outside the
    /// corridor.
    pub fn corridor_gaps_m(&self, out: &mut Vec<f64>) -> Result<(), WorldError> {
        if self.arena.kind() != ArenaKind::Corridor {
            return Err(WorldError::NotACorridor {
                what: "the gap metric",
                arena: self.arena.describe(),
            });
        }
        out.clear();
        let mut order: Vec<usize> = (0..self.pose.len()).collect();
        order.sort_by(|&a, &b| self.pose[a].x.total_cmp(&self.pose[b].x).then(a.cmp(&b)));
        for w in order.windows(2) {
            out.push(obb_distance(&self.obb(w[0]), &self.obb(w[1])));
        }
        Ok(())
    }

    /// The paper's "evenly spaced" metric: coefficient of variation (population standard
    /// deviation over mean) of [`World::corridor_gaps_m`]; `None` with fewer than two robots or
    /// a mean gap of zero or less.
    pub fn corridor_gap_cv(&self) -> Result<Option<f64>, WorldError> {
        let mut gaps = Vec::new();
        self.corridor_gaps_m(&mut gaps)?;
        Ok(coefficient_of_variation(&gaps))
    }
}

/// Coefficient of variation of `values`: population standard deviation divided by the mean;
/// `None` for an empty slice or a mean of zero or less.
pub fn coefficient_of_variation(values: &[f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    if mean.is_nan() || mean <= 0.0 {
        return None;
    }
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    Some(var.sqrt() / mean)
}

/// A solved robot after its sub-step: pose, velocity, wheel impulses and the wheels' mean
/// forces.
#[derive(Debug, Clone, Copy)]
struct SolvedMotion {
    pose: BodyPose,
    vel: [f64; 3],
    wheel_imp: [f64; 4],
    wheel_force: [f64; 2],
}

/// Where a robot that started the sub-step of `h` seconds at `p` ends with its solved
/// velocity (the exact motion of a constant twist), and what its wheels did.
fn solved_motion(mut p: BodyPose, b: &IslandBody, h: f64) -> SolvedMotion {
    let inv_h = 1.0 / h;
    let mut v = b.vel;
    let along = v[0] * p.c + v[1] * p.s;
    let across = -v[0] * p.s + v[1] * p.c;
    let (dx, dy, c, s) = arc_step_twist(p.c, p.s, along, across, v[2], h);
    p.x += dx;
    p.y += dy;
    p.c = c;
    p.s = s;
    v[0] = along * c - across * s;
    v[1] = along * s + across * c;
    SolvedMotion {
        pose: p,
        vel: v,
        wheel_imp: b.wheel_imp,
        // The wheels' rolling impulses over the sub-step, as mean forces.
        wheel_force: [b.wheel_imp[0] * inv_h, b.wheel_imp[2] * inv_h],
    }
}

fn check_robot_count(n: usize) -> Result<(), WorldError> {
    if n > MAX_ROBOTS {
        Err(WorldError::Parameter {
            name: "n_robots",
            value: n as f64,
            valid: "at most 50 000 000 robots",
        })
    } else {
        Ok(())
    }
}

fn body_pose(p: &Pose) -> BodyPose {
    let (s, c) = libm::sincos(p.heading_rad);
    BodyPose {
        x: p.x_m,
        y: p.y_m,
        c,
        s,
    }
}

fn outside(robot: usize, p: &Pose, arena: &Arena) -> WorldError {
    WorldError::PoseOutsideArena {
        robot,
        x_m: p.x_m,
        y_m: p.y_m,
        heading_rad: p.heading_rad,
        width_m: arena.width_m(),
        height_m: arena.height_m(),
    }
}

#[cfg(test)]
mod tests;
