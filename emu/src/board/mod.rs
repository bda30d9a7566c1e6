//! The robot board around the chip: [`wiring`] (which robot part sits on which pin, and what
//! the motor pins mean to the H-bridges), [`ram`] (the on-chip RAM as a budget of placed
//! items), and [`model`], the Rust model of the controller the robot runs.
//!
//! The board knows the chip and the core; neither knows it.

pub mod model;
pub mod ram;
pub mod wiring;
