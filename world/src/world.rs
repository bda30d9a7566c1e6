//! The world: robots' bodies, motors, kinematics, collisions, bumpers and sensor rays.

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;
use seeding::Purpose;

use crate::arena::{Arena, ArenaKind};
use crate::contact::{Manifold, box_box, box_walls};
use crate::error::WorldError;
use crate::geometry::{
    Obb, arc_step, arc_step_twist, obb_distance, obb_overlap, ray_obb, ray_walls, side_of,
};
use crate::grid::Grid;
use crate::motor::{Direction, LagCoefficients, MODE_BRAKE, MODE_COAST, MODE_DRIVE, WheelCommand};
use crate::params::{MAX_ADVANCE_S, WorldParams};
use crate::solver::{BodyConst, Contact, IslandBody, WALL, solve_island};

/// Overlaps are corrected to this gap (10 nm), so that corrected bodies do not touch even
/// after rounding, and far below anything a sensor or a metric resolves.
pub const CONTACT_SKIN_M: f64 = 1e-8;
/// The gap a position correction opens (10 µm): more than the skin, so that a correction that
/// pushes a body a little into a neighbour (a chain of contacts) still leaves the neighbour's
/// pair clear, and a chain clears in a few sweeps instead of converging on the skin forever.
/// Far below anything a sensor (3 mm per du) or a metric resolves.
const CORRECTION_GAP_M: f64 = 1e-5;
/// Smallest broad-phase margin (a Verlet skin): pairs of bodies whose bounding circles are
/// closer than the margin, and bodies closer than it to a wall, are contact candidates; the
/// grid and the candidate lists are kept until some robot has moved half the margin less the
/// speculative contact distance since they were built (our choice: 200 mm, about 60 sub-steps
/// of 10 ms at 0.15 m/s; larger when fast robots and long sub-steps need it).
pub const BROAD_PHASE_MARGIN_M: f64 = 0.2;
/// Robots per chunk in the parallel phases (fixed, so results never depend on thread count).
const PAR_CHUNK: usize = 512;
/// Solved robots from which [`World::advance_states_par`] solves islands in parallel.
const PAR_ISLAND_ROBOTS: usize = 64;
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

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct BodyPose {
    pub(crate) x: f64,
    pub(crate) y: f64,
    pub(crate) c: f64,
    pub(crate) s: f64,
}

impl BodyPose {
    /// The body's box, half extents `hx` along the heading and `hy` across.
    #[inline]
    fn obb(self, hx: f64, hy: f64) -> Obb {
        Obb {
            x: self.x,
            y: self.y,
            c: self.c,
            s: self.s,
            hx,
            hy,
        }
    }

    /// Whether the body's box reaches past a wall of the `w` × `h` arena.
    #[inline]
    fn crosses_walls(self, hx: f64, hy: f64, w: f64, h: f64) -> bool {
        let (ex, ey) = self.obb(hx, hy).aabb_half_extents();
        self.x - ex < 0.0 || self.x + ex > w || self.y - ey < 0.0 || self.y + ey > h
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Motion {
    /// Wheel speeds now, m/s (left, right).
    speed: [f64; 2],
    /// Commanded wheel speeds, m/s (duty × top speed × gain × sign).
    target: [f64; 2],
    /// Which lag applies: drive, brake or coast.
    mode: [u8; 2],
}

/// A sensor's mount point and ray directions in the body frame.
#[derive(Debug, Clone, PartialEq)]
struct MountRays {
    x: f64,
    y: f64,
    dirs: Vec<(f64, f64)>,
}

#[derive(Debug, Clone, Default)]
struct Candidates {
    pairs: Vec<[u32; 2]>,
    walls: Vec<u32>,
}

/// A solved contact's identity, point count and (normal, friction) impulses per point.
type WarmStart = ((u32, u32, u8), u8, [[f64; 2]; 2]);

/// In a binding contact this sub-step (or in contact with such a robot): solved, not moved
/// freely.
const ACTIVE: u8 = 1;
/// The share of the previous sub-step's impulses a solve starts from: all of them, so that a
/// steady push converges in a sweep or two. (A wheel that is braked or coasting starts from
/// nothing instead: a braked robot held against a wall is statically indeterminate, and a full
/// warm start would keep a push that nothing sustains any more.)
const WARM_START: f64 = 1.0;
/// Listed in `World::active`.
const LISTED: u8 = 2;
/// In some contact (binding or not): checked for overlap after the move.
const CHECK: u8 = 4;
/// A contact binds when the robots' own wheels would bring a point to within this of touching
/// (0.1 mm: the linear estimate misses the chord of a turning corner's arc by at most about
/// R·(ω·h)²/2 ≈ 13 µm at 20 ms).
const BIND_MARGIN_M: f64 = 1e-4;

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
    /// Gauss–Seidel sweeps of the velocity solver run (over all sub-steps).
    pub solver_sweeps: u64,
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
    hx: f64,
    hy: f64,
    /// Bounding-circle radius of a body, metres.
    radius_m: f64,
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
    bumpers: Vec<u8>,
    /// Normal impulse each bumper face took in the current sub-step, from the solver's
    /// contacts and the position corrections (front, rear, left, right), N·s.
    face_impulse: Vec<[f64; 4]>,
    /// The robots with some face impulse in the current sub-step.
    pushed: Vec<u32>,
    /// The bumpers as the previous sub-step left them (a pressed switch releases at a lower
    /// force than it operates).
    held: Vec<u8>,
    grid: Grid,
    cand: Candidates,
    /// Broad-phase margin in use, metres.
    margin_m: f64,
    /// Drift from the filed position that triggers a rebuild, metres.
    drift_limit_m: f64,
    /// The sub-step's contacts, walls first, then pairs, in candidate order.
    contacts: Vec<Contact>,
    chunk_contacts: Vec<Vec<Contact>>,
    /// The robots solved this sub-step, in index order.
    active: Vec<u32>,
    /// Union-find parents of the active robots (scratch, by robot).
    uf: Vec<u32>,
    /// Island number of a union-find root (scratch, by robot; `u32::MAX` when unset).
    root_island: Vec<u32>,
    /// Per active robot (in `active`'s order, which `build_islands` makes island by island),
    /// what the solver needs.
    island_bodies: Vec<IslandBody>,
    /// Per island, its range in `active`/`island_bodies` and in `contacts`.
    islands: Vec<(core::ops::Range<usize>, core::ops::Range<usize>)>,
    /// Island of each active robot (scratch, in `active`'s order before the sort).
    isl_of: Vec<u32>,
    /// First place of each island in `active` (scratch; one more entry than islands).
    isl_start: Vec<usize>,
    /// Next free place of each island (scratch).
    isl_fill: Vec<usize>,
    /// `active` being sorted into islands (scratch).
    active_scratch: Vec<u32>,
    /// `contacts` being sorted into islands (scratch).
    contact_scratch: Vec<Contact>,
    /// The solved contacts' impulses of the previous sub-step, sorted by contact identity
    /// (the warm start of the next solve).
    warm: Vec<WarmStart>,
    /// Per robot, the sub-step in which it was last solved (its wheel impulses warm-start the
    /// next solve only if that was the previous sub-step).
    solved_at: Vec<u64>,
    /// The robots in some contact this sub-step (solved or not), in index order.
    checked: Vec<u32>,
    /// Overlaps found by the latest check.
    overlaps: Candidates,
    /// Correction epoch: one per sweep, counted over the whole run.
    epoch: u64,
    /// Per robot, the epoch in which it last moved in the contact phases.
    last_move: Vec<u64>,
    chunk_cands: Vec<Candidates>,
    flags: Vec<u8>,
    body: BodyConst,
    /// Lag coefficients for the two sub-step lengths of the latest plan (length in states).
    lag_cache: [(u64, LagCoefficients); 2],
    mounts: Vec<MountRays>,
    max_substep_states: u64,
    elapsed_states: u64,
    substeps: u64,
    stats: SolverStats,
}

/// The generator for one purpose and one index (robot index, or 0 for world-wide purposes):
/// the project's one derivation, `seeding::derive(seed, index, purpose)`.
fn stream_rng(seed: u64, purpose: Purpose, index: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seeding::derive(seed, index, purpose))
}

/// A uniform draw in [0, 1).
fn unit(rng: &mut Pcg64) -> f64 {
    rng.random::<f64>()
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
        let hx = 0.5 * params.body_length_m;
        let hy = 0.5 * params.body_width_m;
        let radius_m = hx.hypot(hy);
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
        // The speculative distance of the longest sub-step (see `speculative_m`) must fit in
        // the margin with room for drift.
        let vmax = params.top_speed_m_per_s * (1.0 + params.motor_gain_spread);
        let spec_max = 2.5
            * vmax
            * (1.0 + 2.0 * radius_m / params.wheel_track_m)
            * (max_substep_states as f64 / params.clock_hz as f64);
        let margin_m = BROAD_PHASE_MARGIN_M.max(4.0 * spec_max);
        let drift_limit_m = 0.5 * (margin_m - spec_max);
        let grid = Grid::new(
            arena.width_m(),
            arena.height_m(),
            2.0 * radius_m + margin_m,
            n,
        );
        let mounts = params
            .sensor_mounts
            .iter()
            .map(|m| {
                let k = params.rays_per_sensor;
                let dirs = (0..k)
                    .map(|r| {
                        let off = if k == 1 {
                            0.0
                        } else {
                            params.cone_half_angle_rad
                                * (2.0 * f64::from(r) / f64::from(k - 1) - 1.0)
                        };
                        let (s, c) = (m.angle_rad + off).sin_cos();
                        (c, s)
                    })
                    .collect();
                MountRays {
                    x: m.x_m,
                    y: m.y_m,
                    dirs,
                }
            })
            .collect();
        let lag = LagCoefficients::new(
            max_substep_states as f64 / params.clock_hz as f64,
            params.motor_time_constant_s,
            params.brake_time_constant_s,
            params.coast_time_constant_s,
        );
        let body = BodyConst::new(
            params.mass_kg,
            params.body_length_m,
            params.body_width_m,
            params.wheel_track_m,
            params.mu_floor,
            params.mu_robot,
            params.mu_wall,
        );
        let n_chunks = n.div_ceil(PAR_CHUNK);
        let mut w = World {
            arena,
            seed,
            hx,
            hy,
            radius_m,
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
            bumpers: vec![0; n],
            face_impulse: vec![[0.0; 4]; n],
            pushed: Vec::new(),
            held: vec![0; n],
            grid,
            cand: Candidates::default(),
            margin_m,
            drift_limit_m,
            contacts: Vec::new(),
            chunk_contacts: Vec::new(),
            active: Vec::new(),
            warm: Vec::new(),
            uf: vec![0; n],
            root_island: vec![u32::MAX; n],
            island_bodies: Vec::new(),
            islands: Vec::new(),
            isl_of: Vec::new(),
            isl_start: Vec::new(),
            isl_fill: Vec::new(),
            active_scratch: Vec::new(),
            contact_scratch: Vec::new(),
            solved_at: vec![u64::MAX; n],
            checked: Vec::new(),
            overlaps: Candidates::default(),
            epoch: 1,
            last_move: vec![0; n],
            chunk_cands: vec![Candidates::default(); n_chunks],
            flags: vec![0; n],
            body,
            lag_cache: [(max_substep_states, lag), (0, lag)],
            mounts,
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
        self.grid.cell_m()
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
            heading_rad: b.s.atan2(b.c),
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
        let b = self.bumpers[robot];
        Ok([b & 1 != 0, b & 2 != 0, b & 4 != 0, b & 8 != 0])
    }

    /// A robot's body outline for plotting: front-left, rear-left, rear-right, front-right
    /// corners (x, y), metres.
    pub fn corners(&self, robot: usize) -> Result<[(f64, f64); 4], WorldError> {
        self.check_robot(robot)?;
        Ok(self.obb(robot).corners())
    }

    #[inline]
    fn obb(&self, i: usize) -> Obb {
        self.pose[i].obb(self.hx, self.hy)
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

    /// The largest distance two bodies' points can close in a sub-step of `h` seconds under
    /// their own wheels (each point of a body moves at most `v_max·(1 + 2R/track)`), with a
    /// margin of 25 % for pushes: contacts nearer than this are handed to the solver.
    fn speculative_m(&self, h: f64) -> f64 {
        let vmax = self.params.top_speed_m_per_s * (1.0 + self.params.motor_gain_spread);
        2.5 * vmax * (1.0 + 2.0 * self.radius_m / self.params.wheel_track_m) * h
    }

    fn substep(&mut self, len: u64, parallel: bool) {
        let h = len as f64 / self.params.clock_hz as f64;
        let drive = Drive {
            lag: self.lag_for(len),
            inv_track: 1.0 / self.params.wheel_track_m,
            h,
            inv_h: 1.0 / h,
            body: self.body,
        };
        // 1. Motors: the wheel speeds over the sub-step.
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
        core::mem::swap(&mut self.bumpers, &mut self.held);
        self.bumpers.fill(0);
        // 2. Contacts at the start of the sub-step, gaps up to the speculative distance.
        let spec = self.speculative_m(h);
        self.find_contacts(spec, h, parallel);
        // 3. Robots touching nothing follow their wheels exactly; the others are solved.
        let flags = &self.flags;
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
        if !self.active.is_empty() {
            // Warm start from the previous sub-step's impulses of the same contacts and wheels.
            let motion = &self.motion;
            let driven = |i: u32| {
                i != WALL
                    && motion[i as usize]
                        .mode
                        .iter()
                        .zip(motion[i as usize].target)
                        .any(|(&m, t)| m == MODE_DRIVE && t != 0.0)
            };
            for ct in self.contacts.iter_mut() {
                // A contact between robots whose motors do not drive starts from nothing (a
                // braked robot against a wall is statically indeterminate, see WARM_START).
                if !driven(ct.a) && !driven(ct.b) {
                    continue;
                }
                if let Ok(k) = self.warm.binary_search_by(|w| w.0.cmp(&ct.id()))
                    && self.warm[k].1 == ct.count
                {
                    for (p, [ln, lt]) in ct.pts.iter_mut().zip(self.warm[k].2) {
                        p.ln = WARM_START * ln;
                        p.lt = WARM_START * lt;
                    }
                }
            }
            for &i in &self.active {
                let i = i as usize;
                if self.solved_at[i] == self.substeps.wrapping_sub(1) {
                    for (w, x) in self.wheel_imp[i].iter_mut().enumerate() {
                        let driven = self.motion[i].mode[w / 2] == MODE_DRIVE
                            && self.motion[i].target[w / 2] != 0.0;
                        *x *= if driven { WARM_START } else { 0.0 };
                    }
                } else {
                    self.wheel_imp[i] = [0.0; 4];
                }
                self.solved_at[i] = self.substeps;
            }
            self.build_islands();
            let (body, iterations) = (&self.body, self.params.solver_iterations);
            if parallel && self.active.len() > PAR_ISLAND_ROBOTS && self.islands.len() > 1 {
                // Islands share nothing: each is solved on whichever thread, with the same
                // result as in order.
                let mut jobs = Vec::with_capacity(self.islands.len());
                let (mut bodies, mut contacts) =
                    (&mut self.island_bodies[..], &mut self.contacts[..]);
                for (b, c) in &self.islands {
                    let (bi, rest) = core::mem::take(&mut bodies).split_at_mut(b.len());
                    bodies = rest;
                    let (ci, rest) = core::mem::take(&mut contacts).split_at_mut(c.len());
                    contacts = rest;
                    jobs.push((bi, ci));
                }
                self.stats.solver_sweeps += jobs
                    .par_iter_mut()
                    .with_min_len(16)
                    .map(|(b, c)| u64::from(solve_island(b, c, body, h, iterations)))
                    .sum::<u64>();
            } else {
                for (b, c) in &self.islands {
                    self.stats.solver_sweeps += u64::from(solve_island(
                        &mut self.island_bodies[b.clone()],
                        &mut self.contacts[c.clone()],
                        body,
                        h,
                        iterations,
                    ));
                }
            }
            let inv_h = 1.0 / h;
            for (k, &i) in self.active.iter().enumerate() {
                let b = &self.island_bodies[k];
                self.vel[i as usize] = b.vel;
                self.wheel_imp[i as usize] = b.wheel_imp;
                // The wheels' rolling impulses over the sub-step, as mean forces.
                self.wheel_force[i as usize] = [b.wheel_imp[0] * inv_h, b.wheel_imp[2] * inv_h];
            }
            for k in 0..self.active.len() {
                let i = self.active[k] as usize;
                let p = &mut self.pose[i];
                let v = &mut self.vel[i];
                let along = v[0] * p.c + v[1] * p.s;
                let across = -v[0] * p.s + v[1] * p.c;
                let (dx, dy, c, s) = arc_step_twist(p.c, p.s, along, across, v[2], h);
                p.x += dx;
                p.y += dy;
                p.c = c;
                p.s = s;
                v[0] = along * c - across * s;
                v[1] = along * s + across * c;
            }
        }
        self.warm.clear();
        self.warm.extend(self.contacts.iter().map(|ct| {
            (
                ct.id(),
                ct.count,
                [[ct.pts[0].ln, ct.pts[0].lt], [ct.pts[1].ln, ct.pts[1].lt]],
            )
        }));
        self.warm.sort_unstable_by_key(|w| w.0);
        if !self.checked.is_empty() {
            // 4. What the linearised solve left of an overlap is corrected.
            self.clear_overlaps(h);
            // 5. A bumper is pressed when the contacts on its face carried force: the solver's
            // impulses and the corrections' pushes (as impulses) summed over the sub-step.
            for k in 0..self.contacts.len() {
                let ct = self.contacts[k];
                let j = ct.normal_impulse();
                self.push_face(ct.a as usize, ct.nx, ct.ny, j);
                if ct.b != WALL {
                    self.push_face(ct.b as usize, -ct.nx, -ct.ny, j);
                }
            }
            // A switch operates at `bumper_force_n` and, once pressed, releases only below
            // `bumper_release_force_n` (a snap-action switch's hysteresis).
            let operate = self.params.bumper_force_n * h;
            let release = self.params.bumper_release_force_n * h;
            for &i in &self.pushed {
                let i = i as usize;
                let held = self.held[i];
                for (side, j) in self.face_impulse[i].iter_mut().enumerate() {
                    let threshold = if held & (1 << side) != 0 {
                        release
                    } else {
                        operate
                    };
                    if *j > threshold {
                        self.bumpers[i] |= 1 << side;
                    }
                    *j = 0.0;
                }
            }
            self.pushed.clear();
            self.stats.active_robot_substeps += self.active.len() as u64;
            self.stats.contacts += self.contacts.len() as u64;
            for &i in &self.checked {
                self.flags[i as usize] = 0;
            }
        }
        // 6. The broad phase is rebuilt once some robot has drifted too far.
        let lim2 = self.drift_limit_m * self.drift_limit_m;
        let stale = self
            .pose
            .iter()
            .zip(&self.grid.build_xy)
            .any(|(b, [x0, y0])| (b.x - x0) * (b.x - x0) + (b.y - y0) * (b.y - y0) > lim2);
        if stale {
            self.rebuild_broad_phase(parallel);
        }
        self.elapsed_states += len;
        self.substeps += 1;
        self.stats.substeps += 1;
    }

    // ----- collisions ----------------------------------------------------------------------------

    /// Rebuilds the grid and the candidate lists from the current positions.
    fn rebuild_broad_phase(&mut self, parallel: bool) {
        let pose = &self.pose;
        self.grid.build(pose.iter().map(|b| (b.x, b.y)));
        let reach = 2.0 * self.radius_m + self.margin_m;
        let ctx = CandidateCtx {
            pose,
            grid: &self.grid,
            reach2: reach * reach,
            wall_reach: self.radius_m + self.margin_m,
            w: self.arena.width_m(),
            h: self.arena.height_m(),
        };
        self.cand.pairs.clear();
        self.cand.walls.clear();
        if parallel && pose.len() > PAR_CHUNK {
            let n_chunks = pose.len().div_ceil(PAR_CHUNK);
            if self.chunk_cands.len() < n_chunks {
                self.chunk_cands.resize_with(n_chunks, Candidates::default);
            }
            self.chunk_cands[..n_chunks]
                .par_iter_mut()
                .enumerate()
                .for_each(|(k, out)| {
                    out.pairs.clear();
                    out.walls.clear();
                    let lo = k * PAR_CHUNK;
                    let hi = (lo + PAR_CHUNK).min(ctx.pose.len());
                    ctx.find(lo, hi, out);
                });
            for c in &self.chunk_cands[..n_chunks] {
                self.cand.pairs.extend_from_slice(&c.pairs);
                self.cand.walls.extend_from_slice(&c.walls);
            }
        } else {
            ctx.find(0, pose.len(), &mut self.cand);
        }
    }

    /// The contacts of the sub-step: every candidate wall or pair whose manifold has a point
    /// within `spec` metres, in the candidates' order (walls first, then pairs); marks the
    /// robots in them active and lists those in index order.
    fn find_contacts(&mut self, spec: f64, h: f64, parallel: bool) {
        let probe = Probe {
            pose: &self.pose,
            hx: self.hx,
            hy: self.hy,
            reach2: (2.0 * self.radius_m + spec) * (2.0 * self.radius_m + spec),
            w: self.arena.width_m(),
            h: self.arena.height_m(),
            spec,
            body: &self.body,
        };
        self.contacts.clear();
        let n_pairs = self.cand.pairs.len();
        let n_walls = self.cand.walls.len();
        if parallel && n_pairs + n_walls > PAR_CHUNK {
            let chunks = n_pairs.max(n_walls).div_ceil(PAR_CHUNK);
            if self.chunk_contacts.len() < 2 * chunks {
                self.chunk_contacts.resize_with(2 * chunks, Vec::new);
            }
            let cand = &self.cand;
            self.chunk_contacts[..2 * chunks]
                .par_iter_mut()
                .enumerate()
                .for_each(|(k, out)| {
                    out.clear();
                    let lo = (k / 2) * PAR_CHUNK;
                    if k % 2 == 0 {
                        probe.walls(
                            &cand.walls[lo.min(n_walls)..(lo + PAR_CHUNK).min(n_walls)],
                            out,
                        );
                    } else {
                        probe.pairs(
                            &cand.pairs[lo.min(n_pairs)..(lo + PAR_CHUNK).min(n_pairs)],
                            out,
                        );
                    }
                });
            for c in self.chunk_contacts[..2 * chunks].iter().step_by(2) {
                self.contacts.extend_from_slice(c);
            }
            for c in self.chunk_contacts[1..2 * chunks].iter().step_by(2) {
                self.contacts.extend_from_slice(c);
            }
        } else {
            probe.walls(&self.cand.walls, &mut self.contacts);
            probe.pairs(&self.cand.pairs, &mut self.contacts);
        }
        // Which contacts bind: those that the robots' own wheels would close (to within
        // BIND_MARGIN_M, which covers the chord of a turning corner's arc). A robot in a binding
        // contact is solved, and so, in turn, is every robot in a contact with a solved one
        // (its motion is no longer its wheels'); the rest follow their wheels exactly, and
        // their contacts are checked for overlap after the move.
        self.active.clear();
        self.checked.clear();
        let inv_track = 1.0 / self.params.wheel_track_m;
        let twist = |i: usize| -> [f64; 3] {
            let w = self.wmean[i];
            let v = 0.5 * (w[0] + w[1]);
            let p = self.pose[i];
            [v * p.c, v * p.s, (w[1] - w[0]) * inv_track]
        };
        for ct in &self.contacts {
            let a = ct.a as usize;
            let wall = ct.b == WALL;
            let ua = twist(a);
            let ub = if wall { [0.0; 3] } else { twist(ct.b as usize) };
            let (ca, cb) = (
                self.pose[a],
                if wall {
                    self.pose[a]
                } else {
                    self.pose[ct.b as usize]
                },
            );
            let binds = ct.pts[..usize::from(ct.count)].iter().any(|p| {
                let _ = (ca, cb);
                let rvx = (ub[0] - ub[2] * p.rb[1]) - (ua[0] - ua[2] * p.ra[1]);
                let rvy = (ub[1] + ub[2] * p.rb[0]) - (ua[1] + ua[2] * p.ra[0]);
                p.sep + (rvx * ct.nx + rvy * ct.ny) * h < BIND_MARGIN_M
            });
            for i in [ct.a, ct.b] {
                if i != WALL && self.flags[i as usize] & CHECK == 0 {
                    self.flags[i as usize] |= CHECK;
                    self.checked.push(i);
                }
            }
            if binds {
                for i in [ct.a, ct.b] {
                    if i != WALL {
                        self.flags[i as usize] |= ACTIVE;
                    }
                }
            }
        }
        loop {
            let mut grew = false;
            for ct in &self.contacts {
                if ct.b == WALL {
                    continue;
                }
                let (fa, fb) = (self.flags[ct.a as usize], self.flags[ct.b as usize]);
                if (fa ^ fb) & ACTIVE != 0 {
                    self.flags[ct.a as usize] |= ACTIVE;
                    self.flags[ct.b as usize] |= ACTIVE;
                    grew = true;
                }
            }
            if !grew {
                break;
            }
        }
        let flags = &self.flags;
        self.contacts
            .retain(|ct| flags[ct.a as usize] & ACTIVE != 0);
        for ct in &self.contacts {
            for i in [ct.a, ct.b] {
                if i != WALL && self.flags[i as usize] & LISTED == 0 {
                    self.flags[i as usize] |= LISTED;
                    self.active.push(i);
                }
            }
        }
        self.active.sort_unstable();
        self.checked.sort_unstable();
    }

    /// Splits the solved robots into islands (connected by robot–robot contacts), numbered in
    /// order of their lowest robot: `active` is reordered island by island (index order within
    /// each), `contacts` likewise (their order kept within each island), every contact gets
    /// its robots' places in the island, and `island_bodies` the solver's view of each robot.
    fn build_islands(&mut self) {
        fn find(uf: &mut [u32], mut i: u32) -> u32 {
            while uf[i as usize] != i {
                let p = uf[uf[i as usize] as usize];
                uf[i as usize] = p;
                i = p;
            }
            i
        }
        for &i in &self.active {
            self.uf[i as usize] = i;
        }
        for ct in &self.contacts {
            if ct.b != WALL {
                let (ra, rb) = (find(&mut self.uf, ct.a), find(&mut self.uf, ct.b));
                if ra != rb {
                    // The lower root wins, so the result does not depend on contact order.
                    let (lo, hi) = (ra.min(rb), ra.max(rb));
                    self.uf[hi as usize] = lo;
                }
            }
        }
        // Island numbers in order of each island's lowest robot (`active` is in index order).
        let mut count = 0u32;
        self.isl_of.clear();
        for k in 0..self.active.len() {
            let r = find(&mut self.uf, self.active[k]) as usize;
            if self.root_island[r] == u32::MAX {
                self.root_island[r] = count;
                count += 1;
            }
            self.isl_of.push(self.root_island[r]);
        }
        for &i in &self.active {
            let r = find(&mut self.uf, i) as usize;
            self.root_island[r] = u32::MAX;
        }
        // Members island by island, index order within each (a stable counting sort).
        let islands = count as usize;
        self.isl_start.clear();
        self.isl_start.resize(islands + 1, 0);
        for &k in &self.isl_of {
            self.isl_start[k as usize + 1] += 1;
        }
        for k in 0..islands {
            self.isl_start[k + 1] += self.isl_start[k];
        }
        self.isl_fill.clear();
        self.isl_fill.extend_from_slice(&self.isl_start[..islands]);
        self.active_scratch.clear();
        self.active_scratch.resize(self.active.len(), 0);
        for (k, &i) in self.active.iter().enumerate() {
            let isl = self.isl_of[k] as usize;
            self.active_scratch[self.isl_fill[isl]] = i;
            self.isl_fill[isl] += 1;
        }
        core::mem::swap(&mut self.active, &mut self.active_scratch);
        // Each robot's island and place in it, through the `uf` scratch (no longer needed).
        self.islands.clear();
        for isl in 0..islands {
            let range = self.isl_start[isl]..self.isl_start[isl + 1];
            for (local, &i) in self.active[range.clone()].iter().enumerate() {
                self.uf[i as usize] = local as u32;
                self.root_island[i as usize] = isl as u32;
            }
            self.islands.push((range, 0..0));
        }
        // Contacts island by island, their order kept within each (a stable counting sort).
        self.isl_fill.clear();
        self.isl_fill.resize(islands + 1, 0);
        for ct in &self.contacts {
            self.isl_fill[self.root_island[ct.a as usize] as usize + 1] += 1;
        }
        for k in 0..islands {
            self.isl_fill[k + 1] += self.isl_fill[k];
        }
        for (isl, range) in self.islands.iter_mut().enumerate() {
            range.1 = self.isl_fill[isl]..self.isl_fill[isl + 1];
        }
        self.contact_scratch.clear();
        self.contact_scratch
            .resize(self.contacts.len(), Contact::default());
        for ct in &self.contacts {
            let isl = self.root_island[ct.a as usize] as usize;
            let mut c = *ct;
            c.la = self.uf[ct.a as usize];
            c.lb = if ct.b == WALL {
                WALL
            } else {
                self.uf[ct.b as usize]
            };
            self.contact_scratch[self.isl_fill[isl]] = c;
            self.isl_fill[isl] += 1;
        }
        core::mem::swap(&mut self.contacts, &mut self.contact_scratch);
        for &i in &self.active {
            self.root_island[i as usize] = u32::MAX;
        }
        self.island_bodies.clear();
        for &i in &self.active {
            let i = i as usize;
            self.island_bodies.push(IslandBody {
                c: self.pose[i].c,
                s: self.pose[i].s,
                vel: self.vel[i],
                wheel_speed: self.wmean[i],
                wheel_imp: self.wheel_imp[i],
            });
        }
    }

    /// Removes the overlaps the velocity solve left (a rotation is linearised in it; a cluster
    /// may not have converged): position sweeps over the overlapping pairs and walls, each
    /// pushing the bodies apart along the contact normal with rotation, weighted by mass and
    /// inertia, to [`CONTACT_SKIN_M`]; after every sweep the candidates of the robots it moved
    /// are tested again. What is still overlapping after `position_iterations` sweeps stops
    /// early: its robots move only the largest fraction (1/2, 1/4, …, 0) of this sub-step's
    /// motion at which nothing overlaps (a time of impact: no body jumps anywhere, it is only
    /// kept from going on), and so do robots whose motion ends in those robots.
    fn clear_overlaps(&mut self, h: f64) {
        self.epoch += 1;
        let mut since = self.epoch;
        for k in 0..self.checked.len() {
            let i = self.checked[k] as usize;
            self.last_move[i] = self.epoch;
        }
        let mut first = true;
        for _ in 0..self.params.position_iterations {
            self.collect_overlaps(since);
            if self.overlaps.pairs.is_empty() && self.overlaps.walls.is_empty() {
                return;
            }
            if first {
                self.stats.overlap_substeps += 1;
                first = false;
            }
            self.stats.position_sweeps += 1;
            self.epoch += 1;
            since = self.epoch;
            let list = core::mem::take(&mut self.overlaps);
            for &i in &list.walls {
                self.correct_wall(i as usize, h);
            }
            for &[i, j] in &list.pairs {
                self.correct_pair(i as usize, j as usize, h);
            }
            self.overlaps = list;
        }
        self.collect_overlaps(since);
        if !self.overlaps.pairs.is_empty() || !self.overlaps.walls.is_empty() {
            self.stop_early();
        }
    }

    /// The candidates with a robot moved at or after epoch `since` that overlap now, into
    /// `overlaps`.
    fn collect_overlaps(&mut self, since: u64) {
        self.overlaps.pairs.clear();
        self.overlaps.walls.clear();
        let moved = &self.last_move;
        let (w, h) = (self.arena.width_m(), self.arena.height_m());
        for &i in &self.cand.walls {
            if moved[i as usize] >= since
                && self.pose[i as usize].crosses_walls(self.hx, self.hy, w, h)
            {
                self.overlaps.walls.push(i);
            }
        }
        let reach2 = 4.0 * self.radius_m * self.radius_m;
        for &[i, j] in &self.cand.pairs {
            if moved[i as usize] < since && moved[j as usize] < since {
                continue;
            }
            let (a, b) = (self.pose[i as usize], self.pose[j as usize]);
            if (b.x - a.x) * (b.x - a.x) + (b.y - a.y) * (b.y - a.y) >= reach2 {
                continue;
            }
            if obb_overlap(&self.obb(i as usize), &self.obb(j as usize), 0.0).is_some() {
                self.overlaps.pairs.push([i, j]);
            }
        }
    }

    /// Moves and turns robot `i` by a position impulse (px, py) applied at lever arm r.
    #[inline]
    fn nudge(&mut self, i: usize, px: f64, py: f64, r: [f64; 2]) {
        let b = &mut self.pose[i];
        b.x += px * self.body.inv_m;
        b.y += py * self.body.inv_m;
        let dtheta = (r[0] * py - r[1] * px) * self.body.inv_i;
        if dtheta != 0.0 {
            let (sn, cs) = dtheta.sin_cos();
            let (c, s) = (b.c * cs - b.s * sn, b.s * cs + b.c * sn);
            let k = 1.5 - 0.5 * (c * c + s * s);
            b.c = c * k;
            b.s = s * k;
        }
        self.last_move[i] = self.epoch;
    }

    /// One position correction of robot `i` against the walls: per wall in contact, the
    /// deepest point is pushed out to the skin, then the manifold is taken again (a corner
    /// pushed out turns the body, which moves the other corner). A push of `λ` (kg·m) in a
    /// sub-step of `h` seconds is the impulse λ / h on the bumper face it acts on.
    fn correct_wall(&mut self, i: usize, h: f64) {
        let skin = CORRECTION_GAP_M;
        for _ in 0..4 {
            let mut deepest: Option<(Manifold, usize)> = None;
            box_walls(
                &self.obb(i),
                self.arena.width_m(),
                self.arena.height_m(),
                skin,
                |m| {
                    for k in 0..m.count {
                        if deepest.is_none_or(|(d, dk)| m.points[k].sep < d.points[dk].sep) {
                            deepest = Some((m, k));
                        }
                    }
                },
            );
            let Some((m, k)) = deepest else {
                return;
            };
            let p = m.points[k];
            let c = p.sep - skin;
            if c >= 0.0 {
                return;
            }
            let b = self.pose[i];
            let r = [p.x - b.x, p.y - b.y];
            let rn = r[0] * m.ny - r[1] * m.nx;
            let kn = self.body.inv_m + self.body.inv_i * rn * rn;
            // The wall does not give way: the body takes the whole push, into the arena.
            let lambda = -c / kn;
            self.push_face(i, m.nx, m.ny, lambda / h);
            self.nudge(i, -lambda * m.nx, -lambda * m.ny, r);
        }
    }

    /// One position correction of the pair (i, j): the deepest point of their manifold is
    /// pushed apart to the skin, shared by mass and inertia, then the manifold is taken again
    /// for the other point. The push is an impulse on both robots' faces, as in
    /// [`World::correct_wall`].
    fn correct_pair(&mut self, i: usize, j: usize, h: f64) {
        let skin = CORRECTION_GAP_M;
        for _ in 0..2 {
            let Some(m) = box_box(&self.obb(i), &self.obb(j), skin) else {
                return;
            };
            let k = if m.count == 2 && m.points[1].sep < m.points[0].sep {
                1
            } else {
                0
            };
            let p = m.points[k];
            let c = p.sep - skin;
            if c >= 0.0 {
                return;
            }
            let (a, b) = (self.pose[i], self.pose[j]);
            let ra = [p.x - a.x, p.y - a.y];
            let rb = [p.x - b.x, p.y - b.y];
            let rna = ra[0] * m.ny - ra[1] * m.nx;
            let rnb = rb[0] * m.ny - rb[1] * m.nx;
            let kn = 2.0 * self.body.inv_m + self.body.inv_i * (rna * rna + rnb * rnb);
            let lambda = -c / kn;
            self.push_face(i, m.nx, m.ny, lambda / h);
            self.push_face(j, -m.nx, -m.ny, lambda / h);
            self.nudge(i, -lambda * m.nx, -lambda * m.ny, ra);
            self.nudge(j, lambda * m.nx, lambda * m.ny, rb);
        }
    }

    /// The last resort when position sweeps leave an overlap: the robots involved (and, in
    /// turn, any robot whose end pose overlaps their stopped poses) move only a fraction of
    /// this sub-step's motion, the largest of 1, 1/2, …, 1/1024, 0 at which nothing they touch
    /// overlaps. Their start poses were free of overlaps, so this ends.
    fn stop_early(&mut self) {
        let mut group: Vec<u32> = Vec::new();
        let mut ends: Vec<BodyPose> = Vec::new();
        let add = |i: u32, group: &mut Vec<u32>, ends: &mut Vec<BodyPose>, pose: &[BodyPose]| {
            if !group.contains(&i) {
                group.push(i);
                ends.push(pose[i as usize]);
            }
        };
        for &i in &self.overlaps.walls {
            add(i, &mut group, &mut ends, &self.pose);
        }
        for &[i, j] in &self.overlaps.pairs {
            add(i, &mut group, &mut ends, &self.pose);
            add(j, &mut group, &mut ends, &self.pose);
        }
        loop {
            let mut fraction = 1.0;
            let mut clear = false;
            for _ in 0..=11 {
                fraction = if fraction > 1.0 / 1024.0 {
                    fraction * 0.5
                } else {
                    0.0
                };
                self.epoch += 1;
                for (k, &i) in group.iter().enumerate() {
                    let i = i as usize;
                    self.pose[i] = interpolate(self.prev[i], ends[k], fraction);
                    self.last_move[i] = self.epoch;
                }
                self.collect_overlaps(self.epoch);
                if self.overlaps.pairs.is_empty() && self.overlaps.walls.is_empty() {
                    clear = true;
                    break;
                }
                if fraction == 0.0 {
                    break;
                }
            }
            if clear {
                break;
            }
            // At fraction 0 the group is where it started, free of overlaps among itself: what
            // still overlaps is a robot outside the group ending in it, which joins the group.
            let before = group.len();
            for &i in &self.overlaps.walls {
                add(i, &mut group, &mut ends, &self.pose);
            }
            for k in 0..self.overlaps.pairs.len() {
                let [i, j] = self.overlaps.pairs[k];
                add(i, &mut group, &mut ends, &self.pose);
                add(j, &mut group, &mut ends, &self.pose);
            }
            if group.len() == before {
                break;
            }
        }
        for &i in &group {
            self.vel[i as usize] = [0.0; 3];
        }
        self.stats.stopped_robot_substeps += group.len() as u64;
    }

    /// Adds a normal impulse (N·s, > 0 to count) to the bumper face of robot `i` that faces
    /// the world direction (fx, fy).
    #[inline]
    fn push_face(&mut self, i: usize, fx: f64, fy: f64, impulse: f64) {
        if impulse <= 0.0 {
            return;
        }
        let b = self.pose[i];
        let side = side_of(fx * b.c + fy * b.s, -fx * b.s + fy * b.c);
        let f = &mut self.face_impulse[i];
        if f.iter().all(|&x| x == 0.0) {
            self.pushed.push(i as u32);
        }
        f[side] += impulse;
    }

    fn wall_penetration(&self, i: usize) -> bool {
        self.pose[i].crosses_walls(
            self.hx,
            self.hy,
            self.arena.width_m(),
            self.arena.height_m(),
        )
    }

    /// The first overlapping pair (lower index first) with its depth, by brute force over the
    /// broad-phase candidates.
    fn first_overlap(&self) -> Option<(usize, usize, f64)> {
        let mut best: Option<(usize, usize, f64)> = None;
        for &[i, j] in &self.cand.pairs {
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
        for &[i, j] in &self.cand.pairs {
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
        let b = self.pose[robot];
        let ox = b.x + b.c * m.x - b.s * m.y;
        let oy = b.y + b.s * m.x + b.c * m.y;
        let mut best: Option<f64> = None;
        for &(dc, ds) in &m.dirs {
            let dx = b.c * dc - b.s * ds;
            let dy = b.s * dc + b.c * ds;
            if let Some(t) = self.cast(robot, ox, oy, dx, dy)
                && best.is_none_or(|bt| t < bt)
            {
                best = Some(t);
            }
        }
        Ok(best.map(|t| t * 1000.0))
    }

    /// Casts one ray (unit direction) and returns the nearest hit in metres within range.
    fn cast(&self, own: usize, ox: f64, oy: f64, dx: f64, dy: f64) -> Option<f64> {
        let range = self.params.sensor_max_range_m;
        let t_wall = ray_walls(ox, oy, dx, dy, self.arena.width_m(), self.arena.height_m());
        let (mut t_max, mut hit) = if t_wall <= range {
            (t_wall, true)
        } else {
            (range, false)
        };
        // Cells whose robots (filed by their centre at the last build, which may have moved
        // up to half the margin since) can reach the segment.
        let pad = self.radius_m + self.drift_limit_m;
        let (ex, ey) = (ox + dx * t_max, oy + dy * t_max);
        let c0 = self.grid.col(ox.min(ex) - pad);
        let c1 = self.grid.col(ox.max(ex) + pad);
        let r0 = self.grid.row(oy.min(ey) - pad);
        let r1 = self.grid.row(oy.max(ey) + pad);
        let r = self.radius_m;
        for row in r0..=r1 {
            for col in c0..=c1 {
                for &j in self.grid.cell(col, row) {
                    let j = j as usize;
                    if j == own {
                        continue;
                    }
                    let b = self.pose[j];
                    let (rx, ry) = (b.x - ox, b.y - oy);
                    let tc = rx * dx + ry * dy;
                    if tc < -r || tc > t_max + r {
                        continue;
                    }
                    let perp2 = rx * rx + ry * ry - tc * tc;
                    if perp2 > r * r {
                        continue;
                    }
                    if let Some(t) = ray_obb(ox, oy, dx, dy, &self.obb(j), t_max)
                        && (t < t_max || !hit)
                    {
                        t_max = t;
                        hit = true;
                    }
                }
            }
        }
        hit.then_some(t_max)
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
    let (s, c) = p.heading_rad.sin_cos();
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

/// What the motor and free-motion phases need for one sub-step.
#[derive(Clone, Copy)]
struct Drive {
    lag: LagCoefficients,
    inv_track: f64,
    h: f64,
    /// 1 / h.
    inv_h: f64,
    /// The bodies' mass, inertia, wheel geometry and traction (for the free robots' wheel
    /// forces).
    body: BodyConst,
}

/// The wheel-speed difference below which a wheel is taken to have reached its target speed:
/// 1e-12 m/s, a picometre per second, far below anything the model resolves.
const SPEED_SNAP_M_S: f64 = 1e-12;

impl Drive {
    /// Motors for a slice of robots: wheel speeds follow their targets with the exact
    /// first-order lag; `wmean` gets each wheel's mean speed over the sub-step (the exact
    /// integral of the lag) and `prev` the pose at its start.
    fn motors(
        &self,
        motion: &mut [Motion],
        wmean: &mut [[f64; 2]],
        prev: &mut [BodyPose],
        pose: &[BodyPose],
    ) {
        for (((m, mean), pr), p) in motion.iter_mut().zip(wmean).zip(prev).zip(pose) {
            *pr = *p;
            for (w, mean_w) in mean.iter_mut().enumerate() {
                let l = self.lag.by_mode[usize::from(m.mode[w]).min(2)];
                let mut diff = m.speed[w] - m.target[w];
                // A speed within SPEED_SNAP_M_S of its target has arrived: without the snap, a
                // wheel decaying to a zero target keeps shrinking through subnormal floats,
                // which cost x86 cores about a hundred cycles per operation.
                if diff.abs() < SPEED_SNAP_M_S {
                    diff = 0.0;
                }
                *mean_w = m.target[w] + diff * l.mean_factor;
                m.speed[w] = m.target[w] + diff * l.decay;
            }
        }
    }

    /// Robots touching nothing (no `ACTIVE` flag) follow their wheels: the exact arc of the
    /// sub-step's mean wheel speeds (exact heading change and, for straight motion, exact
    /// distance); their velocity becomes the wheels' twist, and their wheel forces those that
    /// changed the velocity they had along their heading (see [`World::wheel_forces`]).
    fn free(
        &self,
        pose: &mut [BodyPose],
        vel: &mut [[f64; 3]],
        force: &mut [[f64; 2]],
        wmean: &[[f64; 2]],
        flags: &[u8],
    ) {
        for ((((p, v), fw), w), &f) in pose.iter_mut().zip(vel).zip(force).zip(wmean).zip(flags) {
            if f & ACTIVE != 0 {
                continue;
            }
            let along = 0.5 * (w[0] + w[1]);
            let omega = (w[1] - w[0]) * self.inv_track;
            let along0 = v[0] * p.c + v[1] * p.s;
            *fw = self
                .body
                .wheel_forces(along - along0, omega - v[2], self.inv_h);
            let (dx, dy, c, s) = arc_step(p.c, p.s, along, omega, self.h);
            p.x += dx;
            p.y += dy;
            p.c = c;
            p.s = s;
            *v = [along * c, along * s, omega];
        }
    }
}

/// What the contact search reads.
struct Probe<'a> {
    pose: &'a [BodyPose],
    hx: f64,
    hy: f64,
    /// Squared distance between centres beyond which bodies cannot come within `spec`.
    reach2: f64,
    w: f64,
    h: f64,
    spec: f64,
    body: &'a BodyConst,
}

impl Probe<'_> {
    /// Appends the wall contacts of the robots `walls`, in order.
    fn walls(&self, walls: &[u32], out: &mut Vec<Contact>) {
        for &i in walls {
            let b = self.pose[i as usize];
            let (ex, ey) = b.obb(self.hx, self.hy).aabb_half_extents();
            let near = b.x - ex <= self.spec
                || b.x + ex >= self.w - self.spec
                || b.y - ey <= self.spec
                || b.y + ey >= self.h - self.spec;
            if !near {
                continue;
            }
            box_walls(&b.obb(self.hx, self.hy), self.w, self.h, self.spec, |m| {
                out.push(Contact::new(i, WALL, &m, (b.x, b.y), (0.0, 0.0), self.body));
            });
        }
    }

    /// Appends the contacts of the candidate pairs, in order.
    fn pairs(&self, pairs: &[[u32; 2]], out: &mut Vec<Contact>) {
        for &[i, j] in pairs {
            let (a, b) = (self.pose[i as usize], self.pose[j as usize]);
            let (dx, dy) = (b.x - a.x, b.y - a.y);
            if dx * dx + dy * dy >= self.reach2 {
                continue;
            }
            if let Some(m) = box_box(
                &a.obb(self.hx, self.hy),
                &b.obb(self.hx, self.hy),
                self.spec,
            ) {
                out.push(Contact::new(i, j, &m, (a.x, a.y), (b.x, b.y), self.body));
            }
        }
    }
}

/// The pose a fraction `f` of the way from `a` to `b` (position linearly, heading by the
/// shorter rotation).
fn interpolate(a: BodyPose, b: BodyPose, f: f64) -> BodyPose {
    let dtheta = (a.c * b.s - a.s * b.c).atan2(a.c * b.c + a.s * b.s);
    let (sn, cs) = (f * dtheta).sin_cos();
    BodyPose {
        x: a.x + f * (b.x - a.x),
        y: a.y + f * (b.y - a.y),
        c: a.c * cs - a.s * sn,
        s: a.s * cs + a.c * sn,
    }
}

/// What the candidate search reads.
struct CandidateCtx<'a> {
    pose: &'a [BodyPose],
    grid: &'a Grid,
    reach2: f64,
    /// A robot whose centre is nearer a wall than this is a wall candidate.
    wall_reach: f64,
    w: f64,
    h: f64,
}

impl CandidateCtx<'_> {
    /// Candidates for robots `lo..hi`: those whose bounding circle is within the margin of a
    /// wall, and pairs (i, j > i) whose centres are within two bounding radii plus the margin.
    fn find(&self, lo: usize, hi: usize, out: &mut Candidates) {
        let nx = self.grid.nx();
        let ny = self.grid.ny();
        for i in lo..hi {
            let b = self.pose[i];
            // By the bounding circle, so that turning cannot bring a body to a wall unseen.
            let e = self.wall_reach;
            if b.x - e < 0.0 || b.x + e > self.w || b.y - e < 0.0 || b.y + e > self.h {
                out.walls.push(i as u32);
            }
            let (cx, cy) = self.grid.cell_of(i);
            let (c0, c1) = (cx.saturating_sub(1), (cx + 1).min(nx - 1));
            let (r0, r1) = (cy.saturating_sub(1), (cy + 1).min(ny - 1));
            for row in r0..=r1 {
                for col in c0..=c1 {
                    for &j in self.grid.cell(col, row) {
                        if (j as usize) <= i {
                            continue;
                        }
                        let q = self.pose[j as usize];
                        let (dx, dy) = (q.x - b.x, q.y - b.y);
                        if dx * dx + dy * dy < self.reach2 {
                            out.pairs.push([i as u32, j]);
                        }
                    }
                }
            }
        }
    }
}

/// Corridor placement: bodies on the centre line facing +x or −x at random, separated by the
/// clearance plus a uniformly random share of the free length (uniform spacings).
fn place_corridor(
    arena: &Arena,
    params: &WorldParams,
    n: usize,
    seed: u64,
) -> Result<Vec<BodyPose>, WorldError> {
    let len = params.body_length_m;
    let clr = params.placement_clearance_m;
    let (w, h) = (arena.width_m(), arena.height_m());
    if params.body_width_m > h {
        return Err(WorldError::Parameter {
            name: "body_width_m",
            value: params.body_width_m,
            valid: "a body no wider than the corridor",
        });
    }
    let free = w - n as f64 * len - (n as f64 + 1.0) * clr;
    if free < 0.0 {
        let max_fit = ((w - clr) / (len + clr)).floor().max(0.0) as usize;
        return Err(WorldError::TooManyRobots {
            requested: n,
            max_fit,
            arena: arena.describe(),
            clearance_m: clr,
        });
    }
    let mut rng = stream_rng(seed, Purpose::Placement, 0);
    let mut cuts: Vec<f64> = (0..n).map(|_| unit(&mut rng) * free).collect();
    cuts.sort_by(f64::total_cmp);
    let mut poses = Vec::with_capacity(n);
    let mut edge = 0.0; // right edge of the previous body (or the wall)
    let mut last_cut = 0.0;
    for &cut in &cuts {
        let gap = clr + (cut - last_cut);
        last_cut = cut;
        let x = edge + gap + 0.5 * len;
        edge = x + 0.5 * len;
        let backward = unit(&mut rng) < 0.5;
        let (c, s) = if backward { (-1.0, 0.0) } else { (1.0, 0.0) };
        poses.push(BodyPose {
            x,
            y: 0.5 * h,
            c,
            s,
        });
    }
    Ok(poses)
}

/// Open-arena placement: rejection sampling of uniform headings and positions with the
/// clearance to walls and bodies; a bounded number of attempts.
fn place_open(
    arena: &Arena,
    params: &WorldParams,
    n: usize,
    seed: u64,
) -> Result<Vec<BodyPose>, WorldError> {
    let (w, h) = (arena.width_m(), arena.height_m());
    let (hx, hy) = (0.5 * params.body_length_m, 0.5 * params.body_width_m);
    let clr = params.placement_clearance_m;
    // Bodies inflated by half the clearance are disjoint and lie inside the arena shrunk by
    // half the clearance on each side: an upper bound on how many fit.
    let usable = ((w - clr).max(0.0)) * ((h - clr).max(0.0));
    let cell_area = (params.body_length_m + clr) * (params.body_width_m + clr);
    let max_fit = (usable / cell_area).floor() as usize;
    if n > max_fit {
        return Err(WorldError::TooManyRobots {
            requested: n,
            max_fit,
            arena: arena.describe(),
            clearance_m: clr,
        });
    }
    let reach = 2.0 * hx.hypot(hy) + clr;
    let mut grid_cells: Vec<Vec<u32>>;
    let cell_m = reach.max((w * h / (n.max(1) as f64)).sqrt());
    let nx = ((w / cell_m).ceil() as usize).max(1);
    let ny = ((h / cell_m).ceil() as usize).max(1);
    grid_cells = vec![Vec::new(); nx * ny];
    let cell_ix = |x: f64, y: f64| -> (usize, usize) {
        let cx = ((x / cell_m).floor().max(0.0) as usize).min(nx - 1);
        let cy = ((y / cell_m).floor().max(0.0) as usize).min(ny - 1);
        (cx, cy)
    };
    let max_attempts: u64 = 1000 * n as u64 + 10_000;
    let mut attempts: u64 = 0;
    let mut rng = stream_rng(seed, Purpose::Placement, 0);
    let mut poses: Vec<BodyPose> = Vec::with_capacity(n);
    while poses.len() < n {
        if attempts >= max_attempts {
            return Err(WorldError::PlacementFailed {
                placed: poses.len(),
                requested: n,
                attempts,
                max_fit,
                arena: arena.describe(),
                clearance_m: clr,
            });
        }
        attempts += 1;
        let theta = core::f64::consts::PI * (2.0 * unit(&mut rng) - 1.0);
        let (s, c) = theta.sin_cos();
        let ex = hx * c.abs() + hy * s.abs() + clr;
        let ey = hx * s.abs() + hy * c.abs() + clr;
        let ux = unit(&mut rng);
        let uy = unit(&mut rng);
        if 2.0 * ex > w || 2.0 * ey > h {
            continue;
        }
        let x = ex + ux * (w - 2.0 * ex);
        let y = ey + uy * (h - 2.0 * ey);
        let a = Obb { x, y, c, s, hx, hy };
        let (cx, cy) = cell_ix(x, y);
        let mut free = true;
        'scan: for row in cy.saturating_sub(1)..=(cy + 1).min(ny - 1) {
            for col in cx.saturating_sub(1)..=(cx + 1).min(nx - 1) {
                for &j in &grid_cells[row * nx + col] {
                    let b = poses[j as usize].obb(hx, hy);
                    if obb_overlap(&a, &b, -clr).is_some() {
                        free = false;
                        break 'scan;
                    }
                }
            }
        }
        if free {
            grid_cells[cy * nx + cx].push(poses.len() as u32);
            poses.push(BodyPose { x, y, c, s });
        }
    }
    Ok(poses)
}

#[cfg(test)]
mod tests;
