//! How the per-robot stages are cut for threads: into fixed chunks of robots (or candidates)
//! whose results are merged in index order, so that no result depends on the thread count.

/// Robots (or candidates) per chunk in the parallel stages.
pub(crate) const PAR_CHUNK: usize = 512;
/// Solved robots from which the islands are solved in parallel.
pub(crate) const PAR_ISLAND_ROBOTS: usize = 64;
