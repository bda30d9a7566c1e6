//! Property tests of h8swarm live in `tests/`; this library is intentionally empty.
