//! The world: robots' bodies, motors, kinematics, collisions, bumpers and sensor rays.

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;
use seeding::Purpose;

use crate::arena::{Arena, ArenaKind};
use crate::error::WorldError;
use crate::geometry::{Obb, arc_step, obb_distance, obb_overlap, ray_obb, ray_walls, side_of};
use crate::grid::Grid;
use crate::motor::{Direction, LagCoefficients, MODE_BRAKE, MODE_COAST, MODE_DRIVE, WheelCommand};
use crate::params::{MAX_ADVANCE_S, WorldParams};

/// Collisions are resolved to this gap (1 nm) so that resolved bodies do not touch.
pub const CONTACT_SKIN_M: f64 = 1e-9;
/// Broad-phase margin (a Verlet skin): pairs of bodies whose bounding circles are closer than
/// this, and bodies closer than this to a wall, are narrow-phase candidates; the grid and the
/// candidate lists are kept until some robot has moved half of it since they were built
/// (our choice: 200 mm, about 67 sub-steps of 10 ms at 0.15 m/s).
pub const BROAD_PHASE_MARGIN_M: f64 = 0.2;
/// How far a robot may move from where the broad phase filed it before it is rebuilt.
const DRIFT_LIMIT_M: f64 = 0.5 * BROAD_PHASE_MARGIN_M;
/// Robots per chunk in the parallel phases (fixed, so results never depend on thread count).
const PAR_CHUNK: usize = 512;
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
struct BodyPose {
    x: f64,
    y: f64,
    c: f64,
    s: f64,
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

/// The wheel-speed difference below which a wheel is taken to have reached its target speed:
/// 1e-12 m/s, a picometre per second, far below anything the model resolves.
const SPEED_SNAP_M_S: f64 = 1e-12;

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

const TOUCHED: u8 = 1;
const REVERTED: u8 = 2;
const VIOLATOR: u8 = 4;
/// Held by a wall (or by a robot held by a wall) during this sub-step: takes no share of a push.
const PINNED: u8 = 8;

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
    prev: Vec<BodyPose>,
    kin: Vec<[f64; 2]>,
    bumpers: Vec<u8>,
    grid: Grid,
    cand: Candidates,
    /// The candidates that involve a robot moved since the sub-step's first pass.
    hot: Candidates,
    /// Resolution epoch: one per pass or stage, counted over the whole run.
    epoch: u64,
    /// Per robot, the epoch in which it last moved in collision resolution.
    last_move: Vec<u64>,
    /// Whether the next pass must go over all candidates (after the kinematics or a rebuild).
    full_pass_pending: bool,
    chunk_cands: Vec<Candidates>,
    flags: Vec<u8>,
    touched: Vec<u32>,
    violators: Vec<u32>,
    lag: LagCoefficients,
    mounts: Vec<MountRays>,
    elapsed_s: f64,
    substeps: u64,
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
        let grid = Grid::new(
            arena.width_m(),
            arena.height_m(),
            2.0 * radius_m + BROAD_PHASE_MARGIN_M,
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
            params.max_substep_s,
            params.motor_time_constant_s,
            params.brake_time_constant_s,
            params.coast_time_constant_s,
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
            kin: vec![[0.0; 2]; n],
            pose: poses,
            bumpers: vec![0; n],
            grid,
            cand: Candidates::default(),
            hot: Candidates::default(),
            epoch: 1,
            last_move: vec![0; n],
            full_pass_pending: false,
            chunk_cands: vec![Candidates::default(); n_chunks],
            flags: vec![0; n],
            touched: Vec::new(),
            violators: Vec::new(),
            lag,
            mounts,
            params,
            elapsed_s: 0.0,
            substeps: 0,
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

    /// Simulated time advanced so far, seconds.
    pub fn elapsed_s(&self) -> f64 {
        self.elapsed_s
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

    /// Advances every robot by `dt_s` seconds, in sub-steps of at most `max_substep_s`
    /// (equal pieces), on the calling thread.
    pub fn advance(&mut self, dt_s: f64) -> Result<(), WorldError> {
        self.advance_impl(dt_s, false)
    }

    /// As [`World::advance`], with the per-robot phases (motors and kinematics, broad-phase
    /// candidates, the first collision pass's overlap tests) split over rayon's current
    /// thread pool. Results are bit-identical to
    /// [`World::advance`] whatever the number of threads: the parallel work is per robot into
    /// fixed chunks, merged in index order; collision resolution runs in index order on one
    /// thread.
    pub fn advance_par(&mut self, dt_s: f64) -> Result<(), WorldError> {
        self.advance_impl(dt_s, true)
    }

    fn advance_impl(&mut self, dt_s: f64, parallel: bool) -> Result<(), WorldError> {
        if dt_s.is_nan() || dt_s <= 0.0 || dt_s > MAX_ADVANCE_S {
            return Err(WorldError::TimeStep {
                value_s: dt_s,
                max_s: MAX_ADVANCE_S,
            });
        }
        let pieces = (dt_s / self.params.max_substep_s).ceil().max(1.0);
        let sub_s = dt_s / pieces;
        if self.lag.dt_s != sub_s {
            self.lag = LagCoefficients::new(
                sub_s,
                self.params.motor_time_constant_s,
                self.params.brake_time_constant_s,
                self.params.coast_time_constant_s,
            );
        }
        for _ in 0..pieces as u64 {
            self.substep(sub_s, parallel);
        }
        Ok(())
    }

    fn substep(&mut self, dt: f64, parallel: bool) {
        let drive = Drive {
            lag: self.lag,
            inv_track: 1.0 / self.params.wheel_track_m,
            dt,
            drift_limit2: DRIFT_LIMIT_M * DRIFT_LIMIT_M,
        };
        let stale = if parallel && self.pose.len() > PAR_CHUNK {
            self.pose
                .par_chunks_mut(PAR_CHUNK)
                .zip(self.motion.par_chunks_mut(PAR_CHUNK))
                .zip(self.prev.par_chunks_mut(PAR_CHUNK))
                .zip(self.kin.par_chunks_mut(PAR_CHUNK))
                .zip(self.grid.build_xy.par_chunks(PAR_CHUNK))
                .map(|((((p, m), pr), k), b)| drive.chunk(p, m, pr, k, b))
                .reduce(|| false, |a, b| a | b)
        } else {
            drive.chunk(
                &mut self.pose,
                &mut self.motion,
                &mut self.prev,
                &mut self.kin,
                &self.grid.build_xy,
            )
        };
        self.bumpers.fill(0);
        if stale {
            self.rebuild_broad_phase(parallel);
        }
        self.full_pass_pending = true;
        self.resolve_collisions(parallel);
        self.elapsed_s += dt;
        self.substeps += 1;
    }

    // ----- collisions ----------------------------------------------------------------------------

    /// Rebuilds the grid and the candidate lists from the current positions.
    fn rebuild_broad_phase(&mut self, parallel: bool) {
        let pose = &self.pose;
        self.grid.build(pose.iter().map(|b| (b.x, b.y)));
        let reach = 2.0 * self.radius_m + BROAD_PHASE_MARGIN_M;
        let ctx = CandidateCtx {
            pose,
            grid: &self.grid,
            reach2: reach * reach,
            radius_m: self.radius_m,
            w: self.arena.width_m(),
            h: self.arena.height_m(),
        };
        self.cand.pairs.clear();
        self.cand.walls.clear();
        self.full_pass_pending = true;
        if parallel && pose.len() > PAR_CHUNK {
            self.chunk_cands
                .par_iter_mut()
                .enumerate()
                .for_each(|(k, out)| {
                    out.pairs.clear();
                    out.walls.clear();
                    let lo = k * PAR_CHUNK;
                    let hi = (lo + PAR_CHUNK).min(ctx.pose.len());
                    ctx.find(lo, hi, out);
                });
            for c in &self.chunk_cands {
                self.cand.pairs.extend_from_slice(&c.pairs);
                self.cand.walls.extend_from_slice(&c.walls);
            }
        } else {
            ctx.find(0, pose.len(), &mut self.cand);
        }
    }

    /// Pushes overlapping bodies apart (fixed passes, robot index order), then makes sure no
    /// body penetrates: robots still overlapping lose this sub-step's rotation, and if that
    /// does not clear them, their whole move (and so on for robots pushed into them).
    fn resolve_collisions(&mut self, parallel: bool) {
        if self.cand.pairs.is_empty() && self.cand.walls.is_empty() {
            return;
        }
        if !self.settle(parallel) {
            self.find_violators();
        }
        if !self.violators.is_empty() {
            // Stage 2: keep the translation, block the rotation.
            self.epoch += 1;
            for k in 0..self.violators.len() {
                let i = self.violators[k] as usize;
                let p = self.prev[i];
                self.pose[i] = BodyPose {
                    x: self.kin[i][0],
                    y: self.kin[i][1],
                    c: p.c,
                    s: p.s,
                };
                self.touch(i);
            }
            self.refresh_if_drifted(parallel);
            if self.settle(parallel) {
                self.clear_violators();
            } else {
                self.find_violators();
            }
            // Stage 3: undo the move of every robot still overlapping, until none does. The
            // previous state was free of overlaps, so this ends within n rounds.
            while !self.violators.is_empty() {
                self.epoch += 1;
                let mut reverted_any = false;
                for k in 0..self.violators.len() {
                    let i = self.violators[k] as usize;
                    if self.flags[i] & REVERTED == 0 {
                        self.flags[i] |= REVERTED;
                        self.pose[i] = self.prev[i];
                        self.touch(i);
                        reverted_any = true;
                    }
                }
                if !reverted_any {
                    break;
                }
                self.refresh_if_drifted(parallel);
                self.find_violators();
            }
        }
        for &i in &self.touched {
            self.flags[i as usize] = 0;
        }
        self.touched.clear();
        self.violators.clear();
    }

    /// Resolution passes until a clean pass on a current candidate list (at most a few
    /// rebuilds); returns whether the last pass was clean, i.e. nothing overlaps.
    fn settle(&mut self, parallel: bool) -> bool {
        for _ in 0..3 {
            let clean = self.resolve_passes(parallel);
            if !self.refresh_if_drifted(parallel) {
                return clean;
            }
        }
        false
    }

    fn clear_violators(&mut self) {
        for &i in &self.violators {
            self.flags[i as usize] &= !VIOLATOR;
        }
        self.violators.clear();
    }

    /// Records that robot `i` moved (or is about to be moved) in the current epoch.
    #[inline]
    fn touch(&mut self, i: usize) {
        self.last_move[i] = self.epoch;
        if self.flags[i] & TOUCHED == 0 {
            self.flags[i] |= TOUCHED;
            self.touched.push(i as u32);
        }
    }

    /// Presses the bumper of robot `i` that faces the world direction (fx, fy).
    #[inline]
    fn press(&mut self, i: usize, fx: f64, fy: f64) {
        let b = self.pose[i];
        let side = side_of(fx * b.c + fy * b.s, -fx * b.s + fy * b.c);
        self.bumpers[i] |= 1 << side;
    }

    /// Resolves robot `i` against the walls; returns whether it had to move.
    fn resolve_wall(&mut self, i: usize) -> bool {
        let (ex, ey) = self.obb(i).aabb_half_extents();
        let (w, h) = (self.arena.width_m(), self.arena.height_m());
        let mut b = self.pose[i];
        let mut hit = false;
        if b.x - ex < 0.0 {
            b.x = ex + CONTACT_SKIN_M;
            self.press(i, -1.0, 0.0);
            hit = true;
        }
        if b.x + ex > w {
            b.x = w - ex - CONTACT_SKIN_M;
            self.press(i, 1.0, 0.0);
            hit = true;
        }
        if b.y - ey < 0.0 {
            b.y = ey + CONTACT_SKIN_M;
            self.press(i, 0.0, -1.0);
            hit = true;
        }
        if b.y + ey > h {
            b.y = h - ey - CONTACT_SKIN_M;
            self.press(i, 0.0, 1.0);
            hit = true;
        }
        if hit {
            self.pose[i] = b;
            self.touch(i);
            self.flags[i] |= PINNED;
        }
        hit
    }

    fn wall_penetration(&self, i: usize) -> bool {
        self.pose[i].crosses_walls(
            self.hx,
            self.hy,
            self.arena.width_m(),
            self.arena.height_m(),
        )
    }

    /// Resolves the pair (i, j); returns whether they overlapped.
    fn resolve_pair(&mut self, i: usize, j: usize) -> bool {
        let (a, b) = (self.pose[i], self.pose[j]);
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        if dx * dx + dy * dy >= 4.0 * self.radius_m * self.radius_m {
            return false;
        }
        let Some(o) = obb_overlap(&self.obb(i), &self.obb(j), 0.0) else {
            return false;
        };
        // Equal bodies share the push; a body held by a wall (directly or through a chain of
        // bodies) does not give way, so the other takes all of it and is held in turn. The MTV
        // removes the motion into the contact.
        let total = o.depth_m + CONTACT_SKIN_M;
        let pinned_i = self.flags[i] & PINNED != 0;
        let pinned_j = self.flags[j] & PINNED != 0;
        let (push_i, push_j) = match (pinned_i, pinned_j) {
            (true, false) => {
                self.flags[j] |= PINNED;
                (0.0, total)
            }
            (false, true) => {
                self.flags[i] |= PINNED;
                (total, 0.0)
            }
            _ => (0.5 * total, 0.5 * total),
        };
        self.pose[i].x -= o.nx * push_i;
        self.pose[i].y -= o.ny * push_i;
        self.pose[j].x += o.nx * push_j;
        self.pose[j].y += o.ny * push_j;
        self.press(i, o.nx, o.ny);
        self.press(j, -o.nx, -o.ny);
        self.touch(i);
        self.touch(j);
        true
    }

    /// Up to `collision_iterations` passes over the candidates in robot index order (each
    /// robot: walls, then its pairs with higher-index robots); stops early after a clean pass
    /// and returns whether there was one (then nothing overlaps).
    ///
    /// The first pass after the kinematics (or after a broad-phase rebuild) goes over every
    /// candidate; a later pass only over the candidates with a robot moved by the previous
    /// pass (or by a stage of `resolve_collisions`): the others were clean when last checked
    /// and neither robot has moved since.
    fn resolve_passes(&mut self, parallel: bool) -> bool {
        for _ in 0..self.params.collision_iterations {
            if self.full_pass_pending {
                self.full_pass_pending = false;
                self.detect_overlaps(parallel);
            } else {
                self.filter_hot(self.epoch);
            }
            self.epoch += 1;
            let list = core::mem::take(&mut self.hot);
            let any = self.pass(&list);
            self.hot = list;
            if !any {
                return true;
            }
        }
        false
    }

    /// The candidates that overlap now, into `hot` in the candidates' order: the first pass
    /// of a sub-step (or after a rebuild) resolves exactly these, in index order. A pair that
    /// only comes to overlap during that pass has a robot moved by it, so the next pass takes
    /// it. The test only reads the poses, so it runs per chunk of candidates on rayon's pool
    /// when `parallel`, with the same result.
    fn detect_overlaps(&mut self, parallel: bool) {
        let probe = Probe {
            pose: &self.pose,
            hx: self.hx,
            hy: self.hy,
            reach2: 4.0 * self.radius_m * self.radius_m,
            w: self.arena.width_m(),
            h: self.arena.height_m(),
        };
        self.hot.pairs.clear();
        self.hot.walls.clear();
        let n_pairs = self.cand.pairs.len();
        let n_walls = self.cand.walls.len();
        if parallel && n_pairs + n_walls > PAR_CHUNK {
            let chunks = n_pairs.max(n_walls).div_ceil(PAR_CHUNK);
            if self.chunk_cands.len() < chunks {
                self.chunk_cands.resize_with(chunks, Candidates::default);
            }
            let cand = &self.cand;
            self.chunk_cands[..chunks]
                .par_iter_mut()
                .enumerate()
                .for_each(|(k, out)| {
                    out.pairs.clear();
                    out.walls.clear();
                    let lo = k * PAR_CHUNK;
                    let pairs = &cand.pairs[lo.min(n_pairs)..(lo + PAR_CHUNK).min(n_pairs)];
                    let walls = &cand.walls[lo.min(n_walls)..(lo + PAR_CHUNK).min(n_walls)];
                    probe.collect(pairs, walls, out);
                });
            for c in &self.chunk_cands[..chunks] {
                self.hot.pairs.extend_from_slice(&c.pairs);
            }
            for c in &self.chunk_cands[..chunks] {
                self.hot.walls.extend_from_slice(&c.walls);
            }
        } else {
            probe.collect(&self.cand.pairs, &self.cand.walls, &mut self.hot);
        }
    }

    /// One pass over `list` in robot index order; returns whether anything overlapped.
    fn pass(&mut self, list: &Candidates) -> bool {
        let mut any = false;
        let (mut pw, mut pp) = (0, 0);
        loop {
            let wi = list.walls.get(pw).map_or(u32::MAX, |&i| i);
            let pi = list.pairs.get(pp).map_or(u32::MAX, |p| p[0]);
            let i = wi.min(pi);
            if i == u32::MAX {
                break;
            }
            if wi == i {
                any |= self.resolve_wall(i as usize);
                pw += 1;
            }
            while pp < list.pairs.len() && list.pairs[pp][0] == i {
                any |= self.resolve_pair(i as usize, list.pairs[pp][1] as usize);
                pp += 1;
            }
        }
        any
    }

    /// The candidates with a robot moved at or after `since` (all of them if a full pass is
    /// pending), into `hot`, in the candidates' order.
    fn filter_hot(&mut self, since: u64) {
        self.hot.walls.clear();
        self.hot.pairs.clear();
        if self.full_pass_pending {
            self.hot.walls.extend_from_slice(&self.cand.walls);
            self.hot.pairs.extend_from_slice(&self.cand.pairs);
            return;
        }
        let moved = &self.last_move;
        self.hot.walls.extend(
            self.cand
                .walls
                .iter()
                .filter(|&&i| moved[i as usize] >= since),
        );
        self.hot.pairs.extend(
            self.cand
                .pairs
                .iter()
                .filter(|p| moved[p[0] as usize] >= since || moved[p[1] as usize] >= since),
        );
    }

    /// Rebuilds the broad phase if a robot moved more than half the margin since the build;
    /// returns whether it did.
    fn refresh_if_drifted(&mut self, parallel: bool) -> bool {
        let lim2 = DRIFT_LIMIT_M * DRIFT_LIMIT_M;
        let drifted = self.touched.iter().any(|&i| {
            let b = self.pose[i as usize];
            let [x0, y0] = self.grid.build_xy[i as usize];
            (b.x - x0) * (b.x - x0) + (b.y - y0) * (b.y - y0) > lim2
        });
        if drifted {
            self.rebuild_broad_phase(parallel);
        }
        drifted
    }

    /// Lists (in index order) every robot that penetrates a wall or another body, and presses
    /// the bumpers of those contacts.
    fn find_violators(&mut self) {
        self.clear_violators();
        // Only candidates with a robot moved in the latest pass or stage can overlap (see
        // `resolve_passes`).
        self.filter_hot(self.epoch);
        self.full_pass_pending = false;
        for k in 0..self.hot.walls.len() {
            let i = self.hot.walls[k] as usize;
            if self.wall_penetration(i) {
                self.flags[i] |= VIOLATOR;
            }
        }
        for k in 0..self.hot.pairs.len() {
            let [i, j] = self.hot.pairs[k];
            let (i, j) = (i as usize, j as usize);
            if let Some(o) = obb_overlap(&self.obb(i), &self.obb(j), 0.0) {
                self.press(i, o.nx, o.ny);
                self.press(j, -o.nx, -o.ny);
                self.flags[i] |= VIOLATOR;
                self.flags[j] |= VIOLATOR;
            }
        }
        // Collect the flagged robots in index order.
        let mut list = core::mem::take(&mut self.violators);
        for &i in self.hot.walls.iter().chain(self.hot.pairs.iter().flatten()) {
            if self.flags[i as usize] & VIOLATOR != 0 {
                list.push(i);
            }
        }
        list.sort_unstable();
        list.dedup();
        for &i in &list {
            self.touch(i as usize);
        }
        self.violators = list;
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
        let pad = self.radius_m + DRIFT_LIMIT_M;
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

/// What the motor and kinematics phase needs for one sub-step.
#[derive(Clone, Copy)]
struct Drive {
    lag: LagCoefficients,
    inv_track: f64,
    dt: f64,
    drift_limit2: f64,
}

impl Drive {
    /// Motors and kinematics for a slice of robots: wheel speeds follow their targets with the
    /// exact first-order lag, and the body moves along the exact arc of the sub-step's mean
    /// wheel speeds (exact heading change and, for straight motion, exact distance). Returns
    /// whether some robot is now farther than the drift limit from where the broad phase last
    /// filed it.
    fn chunk(
        &self,
        pose: &mut [BodyPose],
        motion: &mut [Motion],
        prev: &mut [BodyPose],
        kin: &mut [[f64; 2]],
        build_xy: &[[f64; 2]],
    ) -> bool {
        let mut stale = false;
        for ((((p, m), pr), k), b) in pose
            .iter_mut()
            .zip(motion.iter_mut())
            .zip(prev.iter_mut())
            .zip(kin.iter_mut())
            .zip(build_xy)
        {
            *pr = *p;
            let mut mean = [0.0; 2];
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
            let v = 0.5 * (mean[0] + mean[1]);
            let omega = (mean[1] - mean[0]) * self.inv_track;
            let (dx, dy, c, s) = arc_step(p.c, p.s, v, omega, self.dt);
            p.x += dx;
            p.y += dy;
            p.c = c;
            p.s = s;
            *k = [p.x, p.y];
            let (ddx, ddy) = (p.x - b[0], p.y - b[1]);
            stale |= ddx * ddx + ddy * ddy > self.drift_limit2;
        }
        stale
    }
}

/// What the overlap detection reads.
struct Probe<'a> {
    pose: &'a [BodyPose],
    hx: f64,
    hy: f64,
    /// Squared distance between centres beyond which bodies cannot touch.
    reach2: f64,
    w: f64,
    h: f64,
}

impl Probe<'_> {
    /// Appends the overlapping pairs and the robots penetrating a wall, in the given order.
    fn collect(&self, pairs: &[[u32; 2]], walls: &[u32], out: &mut Candidates) {
        for &i in walls {
            if self.pose[i as usize].crosses_walls(self.hx, self.hy, self.w, self.h) {
                out.walls.push(i);
            }
        }
        for &[i, j] in pairs {
            let (a, b) = (self.pose[i as usize], self.pose[j as usize]);
            let (dx, dy) = (b.x - a.x, b.y - a.y);
            if dx * dx + dy * dy >= self.reach2 {
                continue;
            }
            let (oa, ob) = (a.obb(self.hx, self.hy), b.obb(self.hx, self.hy));
            if obb_overlap(&oa, &ob, 0.0).is_some() {
                out.pairs.push([i, j]);
            }
        }
    }
}

/// What the candidate search reads.
struct CandidateCtx<'a> {
    pose: &'a [BodyPose],
    grid: &'a Grid,
    reach2: f64,
    radius_m: f64,
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
            let e = self.radius_m + BROAD_PHASE_MARGIN_M;
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
