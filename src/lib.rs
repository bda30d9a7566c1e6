//! # h8swarm — the command-line tool
//!
//! The root package is the `h8swarm` command-line tool (`src/main.rs`, the arguments and the
//! dispatch) and this library of its commands, so that benchmarks and tests can drive them
//! directly: one module per subcommand in [`commands`], the memory check before a run
//! ([`resources`]), its staging folder ([`stage`]), its files ([`outputs`]), its printed
//! report ([`report`]), its figures' data ([`figures`]) and drawing ([`plot`]), the viewer
//! page ([`viewer`]), parameter sweeps ([`sweep`]) and the removal of half-written outputs on
//! a signal ([`cleanup`]). What the commands run is the `swarm` crate's; the parts of the
//! robot live in the workspace's other crates.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod cleanup;
pub mod commands;
pub mod figures;
pub mod outputs;
pub mod plot;
pub mod report;
pub mod resources;
pub mod stage;
pub mod sweep;
pub mod viewer;
