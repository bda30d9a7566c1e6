//! # h8swarm — the tool's library
//!
//! The root package is both the `h8swarm` command-line tool (`src/main.rs`) and this library,
//! which holds what the commands do, so that benchmarks and tests can drive it directly:
//! the swarm experiment ([`scenario`], [`robot`], [`experiment`], [`summary`], [`plot`],
//! [`run_cmd`]), the fit verdict of docs/design.md §6 ([`fit`], measured on the emulated MCU, and its
//! command [`fit_cmd`]), the learner's cost summary ([`cost_report`]) and the replay of docs/design.md §2.6
//! ([`replay`]). The parts of the robot live in the workspace's other
//! crates: `nn_q15`, `sensors`, `eeprom`, `emu` and `world`.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod battery;
pub mod cleanup;
pub mod collisions;
pub mod cost_report;
pub mod energy;
pub mod experiment;
pub mod fit;
pub mod fit_cmd;
pub mod output_error;
pub mod plot;
pub mod recording;
pub mod replay;
pub mod robot;
pub mod run_cmd;
pub mod scenario;
pub mod seeds;
pub mod summary;
pub mod sweep;
pub mod text;
pub mod viewer;
