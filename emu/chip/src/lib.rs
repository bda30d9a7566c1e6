//! The H8/3052F as one chip: the [`mcu::Mcu`] (clock, flash, RAM, the on-chip peripherals of
//! [`periph`]) implementing the core's [`h8300h::bus::Bus`],
//! the [`machine::Machine`] with nothing connected, [`run`], which runs an image on it, and
//! [`trace`], the pin traces the MCU records on request, written as VCD files by [`vcd`],
//! [`gdb`], a GDB remote stub, [`profile`], where a program's states go by call stack (folded
//! stacks), and [`iomap`], the table of the chip's I/O registers by which it reports the
//! accesses to what it does not model.
//!
//! The chip knows the core and nothing above it: the robot outside is a [`pins::Board`] that
//! answers for the input pins and holds the parts on port 4's open-drain lines (the robot's
//! EEPROMs), and what the output pins drive is read by the board layer
//! (`robot_board::wiring`). The chip does not depend on any part's model.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod flash;
pub mod gdb;
pub mod iomap;
pub mod machine;
pub mod mcu;
pub mod periph;
pub mod pins;
pub mod power;
pub mod profile;
pub mod run;
pub mod trace;
pub mod vcd;
