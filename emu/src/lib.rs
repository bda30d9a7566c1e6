//! The emulated H8/3052F.
//!
//! - [`memmap`]: the memory map and the access states of each area (SPEC §4.1);
//! - [`bus`]: the clocked bus every program talks through;
//! - [`cpu`]: the H8/300H core (decode, execute, timing by the manual's I·S_I + … + N·S_N rule,
//!   an objdump-form disassembler), generic over [`bus::Bus`];
//! - [`periph`]: on-chip peripherals (so far SCI1, the console);
//! - [`machine`]: a simple system (flash, RAM, SCI1) implementing [`bus::Bus`];
//! - [`srec`]: the Motorola S-record loader for `.mot` images;
//! - [`run`]: running an image to its halt, with console, trace and statistics.
//!
//! The remaining peripherals (A/D, ITU, ports, the I²C EEPROMs) and the controller program
//! arrive with their issues.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod bus;
pub mod cpu;
pub mod machine;
pub mod memmap;
pub mod periph;
pub mod run;
pub mod srec;
