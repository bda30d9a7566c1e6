//! The H8/300H core and what it needs to run: the clocked [`bus::Bus`] it talks through, the
//! memory map that says what each access costs, the CPU (decode, execute, timing,
//! disassembly) and the S-record loader for `.mot` images.
//!
//! The core knows nothing of the chip around it: it reaches memory and peripherals only
//! through [`bus::Bus`], so any implementation of the bus (the H8/3052F of the chip layer, a
//! test's probe) can run it.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod bus;
pub mod cpu;
pub mod memmap;
pub mod srec;

/// The crate's README, whose example runs as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
