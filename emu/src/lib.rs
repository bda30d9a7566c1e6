//! The emulated H8/3052F and the robot board around it, in three layers, each a crate of its
//! own that knows only the layers below it (Cargo enforces the direction: `h8300h` depends on
//! neither of the others, `h8_3052f` on `h8300h`, `robot_board` on both). This crate re-exports
//! them under one name and holds the tests and benchmarks that run across the layers.
//!
//! 1. [`core`] — the H8/300H core: [`core::memmap`] (the memory map and the access states of
//!    each area, docs/design.md §4.1), [`core::bus`] (the clocked [`core::bus::Bus`] every program talks
//!    through), [`core::cpu`] (decode, execute, timing by the manual's I·S_I + … + N·S_N rule,
//!    an objdump-form disassembler; generic over the bus) and [`core::srec`] (the Motorola
//!    S-record loader for `.mot` images). It knows no chip.
//! 2. [`chip`] — the H8/3052F: [`chip::periph`] (A/D, ITU, ports, interrupt controller with
//!    the IRQ inputs, SCI1, watchdog timer, each synchronised lazily to the clock), [`chip::mcu`] (the chip as one bus: memories,
//!    peripherals, the [`chip::pins::Board`] outside its pins),
//!    [`chip::machine`] (the MCU with nothing connected), [`chip::run`]
//!    (running an image to its halt, with console, trace and statistics) and [`chip::power`]
//!    (what the chip draws from its supply, by state). It knows the core and no robot.
//! 3. [`board`] — the robot around the chip: [`board::board`] (the robot's clock and the
//!    board's own parts, the EEPROMs on port 4: what `h8swarm emu` runs images on),
//!    [`board::wiring`] (which robot part sits on which
//!    pin; the motor pins read as H-bridge inputs), [`board::ram`] (the on-chip RAM as a budget
//!    of placed items), the robot's firmware ([`board::firmware`] with its [`board::symbols`],
//!    [`board::profile`] and [`board::oncore`]) and [`board::model`] (the Rust model of the
//!    controller the robot runs, checked against the firmware). It knows the chip and the core.
//!
//! The arrows point one way by construction: the core reaches everything through
//! [`core::bus::Bus`], which carries no firmware shortcut (its promises are about the chip:
//! which fetches touch no device, until when the interrupt decision and a register's reads
//! stay as they are, which the core's fast path and loop fast-forwarding use; the model's
//! transaction-level save goes through its own [`board::model::ModelBus`], implemented for the
//! chip); the chip numbers its own pins and
//! leaves what they drive to [`board::wiring`]; and every on-chip module is a
//! [`chip::periph::Peripheral`] that declares the I/O block it owns, so the chip dispatches by
//! those blocks.
//!
//! Machine code (`h8swarm emu`) and the Rust model of the controller run on the same
//! [`chip::mcu::Mcu`]: same bus, same peripherals, same timing.
//!
//! # Choices where the spec and the manuals are silent
//! - Timing: every fetch and data access is charged through [`core::bus::Bus`] by the area it
//!   touches (the core's fast path charges a cached ROM instruction's fetches as one lump of
//!   the same states, and its loop fast-forwarding charges skipped iterations in closed form:
//!   the same clock either way, see [`core::cpu`]); internal states and the branch-target prefetch of one-word branches come from
//!   [`core::cpu::timing`] (programming manual Appendix A). Interrupt entry costs the priority
//!   decision (1 state for on-chip sources, 2 for NMI/IRQ) + 16 states; the "wait for the end of
//!   the current instruction" of the hardware manual's Table 5-5 overlaps the instruction,
//!   since interrupts are taken between instructions.
//! - Results the manual leaves open (DIVXU/DIVXS by zero or with overflow, DAA/DAS H and V,
//!   STC to memory, `MOV Rn,@-ERn`, JSR's top stack byte) are listed in [`core::cpu`]'s docs.
//! - CCR.UI is a user bit (SYSCR.UE = 1 after reset): only CCR.I masks interrupts; NMI is never
//!   masked. MOVFPE/MOVTPE stop the program with an error (no E clock on the H8/3052F).
//! - SCI1 transmits as on the chip: a byte is sent when TDRE is cleared with SCR.TE = 1, and
//!   TDRE/TEND return after the frame time the BRR formula gives ([`chip::periph::sci`]).
//! - The [`chip::machine::Machine`] loads S-record data into flash only; data for other
//!   addresses is an error. Registers of modules that are not modelled read 0 and ignore writes,
//!   and the first access to each is reported with its register's name ([`chip::iomap`],
//!   [`chip::mcu::IoReport`]).
//! - The watchdog timer resets the chip at its overflow in watchdog timer mode: 518 states,
//!   every module reset but RSTCSR (WRST set), then the reset vector ([`chip::periph::wdt`]).
//! - Memory is allocated on first use: the flash when an image is loaded (an empty flash
//!   reads H'FF), the RAM on its first write (untouched RAM reads 0) ([`chip::mcu`]).
//! - A/D: the input is sampled at the end of the sampling window, t_D (maximum, 17/9 states)
//!   plus t_SPL (63/31), i.e. 80/40 states after ADST is written; the result and ADF come
//!   266/134 states after it; later conversions of a scan take 256/128 states
//!   ([`chip::periph::adc`]).
//! - ITU: the prescaler runs freely from reset; a compare match sets its flag, clears the
//!   counter and changes the output at the count edge that leaves the matching value, so the
//!   period with CCLR = GRA is GRA + 1 counts and the PWM high time GRB + 1 counts; word
//!   accesses to TCNT/GR/BR take one bus cycle (16-bit internal bus) ([`chip::periph::itu`]).
//! - Ports: DDRs read H'FF; an input pin that nothing drives and whose pull-up is off reads 0
//!   (a floating pin), so firmware must enable P2PCR/P4PCR for the bumpers and the I²C lines
//!   ([`chip::periph::ports`]).
//! - A run ends on SLEEP with CCR.I = 1 and no NMI pending (exit status = R0L), on the state
//!   budget, on a core error, or when SLEEP with interrupts enabled has nothing that could ever
//!   wake it and no budget ([`chip::run::Outcome::SleptForever`]).
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub use h8_3052f as chip;
pub use h8300h as core;
pub use robot_board as board;
