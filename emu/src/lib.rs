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
//!
//! # Choices where the spec and the manuals are silent
//! - Timing: every fetch and data access goes through [`bus::Bus`] and is charged by the area
//!   it touches; internal states and the branch-target prefetch of one-word branches come from
//!   [`cpu::timing`] (programming manual Appendix A). Interrupt entry costs the priority
//!   decision (1 state for on-chip sources, 2 for NMI/IRQ) + 16 states; the "wait for the end of
//!   the current instruction" of the hardware manual's Table 5-5 overlaps the instruction,
//!   since interrupts are taken between instructions.
//! - Results the manual leaves open (DIVXU/DIVXS by zero or with overflow, DAA/DAS H and V,
//!   STC to memory, `MOV Rn,@-ERn`, JSR's top stack byte) are listed in [`cpu`]'s docs.
//! - CCR.UI is a user bit (SYSCR.UE = 1 after reset): only CCR.I masks interrupts; NMI is never
//!   masked. MOVFPE/MOVTPE stop the program with an error (no E clock on the H8/3052F).
//! - SCI1 transmits as on the chip: a byte is sent when TDRE is cleared with SCR.TE = 1, and
//!   TDRE/TEND return after the frame time the BRR formula gives ([`periph::sci`]).
//! - The [`machine::Machine`] loads S-record data into flash only; data for other addresses is
//!   an error. Its other I/O registers read 0 and ignore writes.
//! - A run ends on SLEEP with CCR.I = 1 and no NMI pending (exit status = R0L), on the state
//!   budget, on a core error, or when SLEEP with interrupts enabled has nothing that could ever
//!   wake it and no budget ([`run::Outcome::SleptForever`]).
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod bus;
pub mod cpu;
pub mod machine;
pub mod memmap;
pub mod periph;
pub mod run;
pub mod srec;
