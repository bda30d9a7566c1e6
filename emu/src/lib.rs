//! The emulated H8/3052F.
//!
//! The memory map and its access states ([`memmap`]) and the clocked bus every program talks
//! through ([`bus`]); the peripherals, the controller program and the H8/300H core arrive
//! with their issues.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod bus;
pub mod memmap;
