//! The emulated H8/3052F.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod bus;
pub mod cpu;
pub mod memmap;
