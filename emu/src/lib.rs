//! The emulated H8/3052F.
//!
//! - [`memmap`]: the memory map and the access states of each area (SPEC §4.1);
//! - [`bus`]: the clocked bus every program talks through;
//! - [`cpu`]: the H8/300H core (decode, execute, timing by the manual's I·S_I + … + N·S_N rule,
//!   an objdump-form disassembler), generic over [`bus::Bus`];
//! - [`periph`]: on-chip peripherals (A/D, ITU, ports, interrupt controller, SCI1), each
//!   synchronised lazily to the clock;
//! - [`mcu`]: the H8/3052F as one chip (memories, peripherals, the EEPROM bus on port 4, the
//!   board outside) implementing [`bus::Bus`];
//! - [`wiring`]: which robot part sits on which pin;
//! - [`machine`]: the MCU with nothing connected, for `h8swarm emu`;
//! - [`srec`]: the Motorola S-record loader for `.mot` images;
//! - [`run`]: running an image to its halt, with console, trace and statistics.
//!
//! Machine code (`h8swarm emu`) and the Rust controller run on the same [`mcu::Mcu`]: same bus,
//! same peripherals, same timing.
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
//!   an error. Registers of modules that are not modelled read 0 and ignore writes.
//! - Memory is allocated on first use: the flash when an image is loaded (an empty flash
//!   reads H'FF), the RAM on its first write (untouched RAM reads 0) ([`mcu`]).
//! - A/D: the input is sampled at the end of the sampling window, t_D (maximum, 17/9 states)
//!   plus t_SPL (63/31), i.e. 80/40 states after ADST is written; the result and ADF come
//!   266/134 states after it; later conversions of a scan take 256/128 states
//!   ([`periph::adc`]).
//! - ITU: the prescaler runs freely from reset; a compare match sets its flag, clears the
//!   counter and changes the output at the count edge that leaves the matching value, so the
//!   period with CCLR = GRA is GRA + 1 counts and the PWM high time GRB + 1 counts; word
//!   accesses to TCNT/GR/BR take one bus cycle (16-bit internal bus) ([`periph::itu`]).
//! - Ports: DDRs read H'FF; an input pin that nothing drives and whose pull-up is off reads 0
//!   (a floating pin), so firmware must enable P2PCR/P4PCR for the bumpers and the I²C lines
//!   ([`periph::ports`]).
//! - A run ends on SLEEP with CCR.I = 1 and no NMI pending (exit status = R0L), on the state
//!   budget, on a core error, or when SLEEP with interrupts enabled has nothing that could ever
//!   wake it and no budget ([`run::Outcome::SleptForever`]).
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod bus;
pub mod controller;
pub mod cpu;
pub mod fit;
pub mod machine;
pub mod mcu;
pub mod memmap;
pub mod periph;
pub mod ram;
pub mod run;
pub mod srec;
pub mod wiring;
