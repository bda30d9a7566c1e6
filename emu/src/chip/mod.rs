//! The H8/3052F as one chip: the [`mcu::Mcu`] (clock, flash, RAM, the on-chip peripherals of
//! [`periph`] and the EEPROM bus on port 4) implementing the core's [`crate::core::bus::Bus`],
//! the [`machine::Machine`] with nothing connected, and [`run`], which runs an image on it.
//!
//! The chip knows the core and nothing above it: the robot outside is a [`mcu::Board`] that
//! answers for the input pins, and what the output pins drive is read by the board layer
//! (`emu::board::wiring`).

pub mod machine;
pub mod mcu;
pub mod periph;
pub mod run;
