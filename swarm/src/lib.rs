//! # swarm — the swarm experiment of the H8/3052F robots
//!
//! The library under the `h8swarm` tool: what a scenario is ([`scenario`]), a robot with its
//! controller on the emulated MCU ([`robot`]), the swarm that runs them in the world
//! ([`experiment`]), its contacts ([`collisions`]), where its robots go: held, shuttling,
//! circling or exploring, and how far ([`motion`]), the charge meter
//! ([`energy`]) and the battery life ([`battery`]), the window statistics and the paper's
//! claims ([`summary`]), the recording of runs for the viewer ([`recording`]), the seed
//! streams ([`seeds`]) and the fit verdict of docs/design.md §6 ([`fit`]). It writes no
//! command's output: the `h8swarm` package holds the commands, the figures, the sweeps and the
//! viewer page.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod battery;
pub mod collisions;
pub mod energy;
pub mod experiment;
pub mod fit;
pub mod motion;
pub mod output_error;
pub mod recording;
pub mod robot;
pub mod runner;
pub mod scenario;
pub mod seeds;
pub mod summary;
pub mod terminal_text;
