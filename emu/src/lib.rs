//! The tests and benchmarks that run across the emulator's three layers, each a crate of its
//! own that knows only the layers below it (Cargo enforces the direction):
//!
//! 1. `h8300h`: the H8/300H core: the memory map, the clocked bus every program talks through,
//!    the CPU, the S-record loader. It knows no chip.
//! 2. `h8_3052f`: the H8/3052F: its peripherals, the chip as one bus (`Mcu`), running an
//!    image to its halt, pin traces, the GDB stub. It knows the core and no robot.
//! 3. `robot_board`: the robot around the chip: the board and its EEPROMs, which part sits on
//!    which pin, the RAM budget, the robot's firmware and the Rust model of its controller. It
//!    knows the chip and the core.
//!
//! This crate exports nothing: the crates above (swarm, the h8swarm tool) depend on the three
//! layers directly, each on what it uses (docs/crates.md, "No
//! facade"). Its tests (`emu/tests`) and benchmarks (`emu/benches`) are the ones that need more
//! than one layer: the firmware on the core on the chip on the board.
#![forbid(unsafe_code)]
#![deny(missing_docs)]
