//! The emulated H8/3052F and the robot board around it, in three layers, each a crate of its
//! own that knows only the layers below it (Cargo enforces the direction). This crate
//! re-exports them under one name and holds the tests and benchmarks that run across the
//! layers.
//!
//! 1. [`core`] (`h8300h`): the H8/300H core: the memory map, the clocked [`core::bus::Bus`]
//!    every program talks through, the CPU, the S-record loader. It knows no chip.
//! 2. [`chip`] (`h8_3052f`): the H8/3052F: its peripherals, the chip as one bus
//!    ([`chip::mcu::Mcu`]), running an image to its halt ([`chip::run`]), pin traces, the GDB
//!    stub. It knows the core and no robot.
//! 3. [`board`] (`robot_board`): the robot around the chip: the board and its EEPROMs, which
//!    part sits on which pin ([`board::wiring`]), the RAM budget, the robot's firmware and the
//!    Rust model of its controller ([`board::model`]). It knows the chip and the core.
//!
//! Machine code (`h8swarm emu`) and the Rust model of the controller run on the same
//! [`chip::mcu::Mcu`]: same bus, same peripherals, same timing. What each layer holds and why
//! the arrows point one way: docs/crates.md; the modelling choices where the manuals are
//! silent: docs/design.md §4.1 and docs/emulator-accuracy.md.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub use h8_3052f as chip;
pub use h8300h as core;
pub use robot_board as board;
