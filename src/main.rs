//! h8swarm command-line tool (work in progress).
fn main() {}
