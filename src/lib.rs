//! # h8swarm — the command-line tool
//!
//! The root package is the `h8swarm` command-line tool (`src/main.rs`) and this library of its
//! commands, so that benchmarks and tests can drive them directly: the swarm experiment's
//! command with its outputs ([`run_cmd`]), its figures ([`plot`]) and its viewer page
//! ([`viewer`]), the fit verdict's command ([`fit_cmd`]), the learner's cost summary
//! ([`cost_report`]), the replay of docs/design.md §2.6 ([`replay`]), parameter sweeps
//! ([`sweep`]) and the removal of half-written outputs on a signal ([`cleanup`]). What the
//! commands run is the `swarm` crate's (the scenario, the robots, the experiment, its
//! statistics, energy and the fit); the parts of the robot live in the workspace's other
//! crates: `nn_q15`, `sensors`, `eeprom`, `emu` and `world`.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod cleanup;
pub mod cost_report;
pub mod fit_cmd;
pub mod plot;
pub mod replay;
pub mod run_cmd;
pub mod stage;
pub mod sweep;
pub mod viewer;
