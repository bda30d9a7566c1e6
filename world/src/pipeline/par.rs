//! How the per-robot stages are cut for threads: into fixed chunks of robots (or candidates)
//! whose results are merged in index order, so that no result depends on the thread count.

/// Robots (or candidates) per chunk in the parallel stages.
pub(crate) const PAR_CHUNK: usize = 512;
/// Solved robots from which the islands are solved in parallel.
pub(crate) const PAR_ISLAND_ROBOTS: usize = 64;
/// Robots from which the per-robot stages of a sub-step (motors, contact search, free motion,
/// warm start, solved motion, broad phase) run on the pool. A sub-step's stage is short (about
/// 2 µs for 100 robots' motors), and a parallel region costs about 10-15 µs of waking and
/// joining on this machine: at 1 000 robots on two threads the motors took 120-159 ms on the
/// pool against 21 ms on one thread over a 400-step run (docs/performance.md). The islands'
/// solve, about 127 µs a sub-step at 1 000 robots, goes on the pool from 64 solved robots.
pub const PAR_STAGE_ROBOTS: usize = 4096;
