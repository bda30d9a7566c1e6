//! The robot board around the chip: [`board`] (the board's clock and its own parts, the
//! EEPROMs on port 4, as the chip's [`h8_3052f::pins::Board`]), [`wiring`] (which robot part
//! sits on which pin, and what the motor pins mean to the H-bridges), [`ram`] (the on-chip RAM as a budget of placed
//! items), the robot's firmware ([`firmware`]: images, their [`symbols`], the configuration
//! block; [`profile`]: states per function from the symbol table; [`firmware_learner`]: the firmware's
//! learner routines called by symbol), and [`model`], the Rust model of the controller the
//! robot runs, checked against the firmware.
//!
//! The board knows the chip and the core; neither knows it.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod board;
pub mod firmware;
pub mod firmware_learner;
pub mod model;
pub mod profile;
pub mod ram;
pub mod symbols;
pub mod wiring;
