//! A step's sub-steps: the world advanced through them and every robot's contact and drive
//! meters fed with what each sub-step did ([`advance_world`]), the readings gathered after each
//! sub-step and fed in batches ([`Readings`]), beside the world's next sub-step on two or more
//! threads.

use crate::collisions::ContactMeter;
use anyhow::Result;
use rayon::prelude::*;
use world::World;

/// Sub-steps whose readings are gathered before the meters take them, robot by robot, in one
/// pass: one pass a step at the arena's 23 sub-steps (a pass on the pool is dear:
/// docs/performance.md), and a bound on the readings kept (32 × 41 bytes a robot) whatever
/// the sub-step.
pub(super) const METER_BATCH: usize = 32;

/// Robots from which the meters are fed beside the world's next sub-step on two or more
/// threads: below it a join a sub-step costs more than the meters it overlaps (measured in
/// docs/performance.md, beside the pipelined meters).
pub(super) const PIPELINE_ROBOTS: usize = 512;

/// Robots from which a sub-step's readings are gathered on the pool: the world's own threshold
/// for its per-robot stages (below it a parallel region costs more than the copying).
pub(super) const GATHER_PAR_ROBOTS: usize = world::PAR_STAGE_ROBOTS;

/// Robots per chunk of the parallel gathering.
pub(super) const GATHER_CHUNK: usize = 1024;

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
pub(super) struct Readings {
    lens: Vec<u64>,
    of: Vec<Reading>,
    /// Robots from which the meters are fed beside the world's next sub-step
    /// ([`PIPELINE_ROBOTS`]; tests lower it).
    pub(super) pipeline_from: usize,
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
    /// Whether `robots` robots' meters are fed beside the world's next sub-step: with `par` on
    /// a pool of more than one thread, from `pipeline_from` ([`PIPELINE_ROBOTS`]) robots.
    pub(super) fn pipelined(&self, par: bool, robots: usize) -> bool {
        par && robots >= self.pipeline_from && rayon::current_num_threads() > 1
    }

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
pub(super) fn add(a: (u64, u64), b: (u64, u64)) -> (u64, u64) {
    (a.0 + b.0, a.1 + b.1)
}

/// Advances the world to `target_states` in its sub-steps, feeding every robot's bumpers
/// after each to its meter and its wheels' mean speeds and the forces they transmitted to its
/// drive meter (when `drives` has one per robot); adds each robot's collisions to `per_robot`
/// and returns the collisions counted and the robot-states in contact. The readings are
/// gathered after each sub-step and fed to the meters in batches ([`Readings`]): each meter
/// sees its robot's sub-steps in order, as if fed after each.
pub(super) fn advance_world(
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
    let pipelined = readings.pipelined(par, meters.len());
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::setup::{nominal_substep_states, world_params};
    use crate::scenario::Scenario;
    use world::{Arena, Behaviour};

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
}
