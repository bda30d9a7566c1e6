//! On-chip peripherals of the H8/3052F, one file per module (as in simavr). Each is
//! synchronised lazily to the MCU clock: it keeps the state it was last brought up to date and
//! works out counters and flags from the elapsed states when accessed, and can say when it next
//! needs attention (for SLEEP fast-forward).
//!
//! - [`adc`]: the 10-bit A/D converter (ADDRA–D, ADCSR, ADCR; single and scan mode);
//! - [`itu`]: the 16-bit integrated timer unit, channels 0–4 (compare match, PWM mode);
//! - [`ports`]: ports 1–9, A and B (write-only DDRs, pull-ups, the pins they share with the
//!   ITU, the EEPROM bus on port 4, what the board drives on the others);
//! - [`intc`]: the interrupt controller (SYSCR, IPRA/IPRB and the priority decision);
//! - [`irq`]: the IRQ0–IRQ5 inputs (ISCR, IER, ISR) on ports 8 and 9;
//! - [`sci`]: SCI1, the console;
//! - [`wdt`]: the watchdog timer (interval interrupt, internal reset).
//!
//! Every module implements [`Peripheral`]: it owns one block of I/O addresses, answers reads
//! and writes in it, catches up with the clock, says when it next needs attention and which
//! interrupts it requests, and returns to its reset state. The MCU routes each access by
//! those blocks ([`crate::mcu`]) and asks every module the same questions.

pub mod adc;
pub mod intc;
pub mod irq;
pub mod itu;
pub mod ports;
pub mod sci;
pub mod wdt;

use crate::pins::Board;

/// One on-chip module as the MCU sees it.
///
/// Times are MCU states since reset; `now` is the instant the bus cycle ends (or the instant
/// the clock was brought to). A module never needs to be stepped: it works out what happened
/// since it was last brought up to date when it is accessed or synchronised.
pub trait Peripheral {
    /// What the module sees outside itself during an access or a catch-up, for a chip on board
    /// `B`: `()` for a module that sees nothing but the clock; the board (its analog inputs)
    /// for the A/D converter; the board's port-2 pins, the EEPROM bus and the ITU for the
    /// ports. Generic over the board so that the board's answers are static calls.
    type Outside<'a, B: Board + 'a>;
    /// First address of the module's register block: every access from here to [`Self::LAST`]
    /// is routed to it (addresses of the block it does not model read 0 or its own fill value
    /// and ignore writes).
    const FIRST: u32;
    /// Last address of the block.
    const LAST: u32;
    /// Whether a write to the block can change an interrupt request or the priority decision,
    /// so that the MCU must forget its cached decision.
    const AFFECTS_IRQ: bool;

    /// Whether `addr` (24-bit) lies in the module's block.
    #[inline]
    #[must_use]
    fn owns(addr: u32) -> bool {
        (Self::FIRST..=Self::LAST).contains(&addr)
    }

    /// Reads the register at `addr` at `now`.
    fn read<B: Board>(&mut self, addr: u32, now: u64, outside: Self::Outside<'_, B>) -> u8;
    /// Writes `value` to the register at `addr` at `now`.
    fn write<B: Board>(&mut self, addr: u32, value: u8, now: u64, outside: Self::Outside<'_, B>);
    /// Brings the module up to `now` (the clock jumped without an access to it).
    fn sync<B: Board>(&mut self, now: u64, outside: Self::Outside<'_, B>);
    /// The earliest state after `now` at which the module next needs attention (a counter
    /// event, a sampling instant, the end of a frame), if any.
    fn next_event(&self, now: u64) -> Option<u64>;
    /// The interrupts it requests at `now`, enabled at the source, as a vector bit mask (bit v =
    /// vector v).
    fn requests(&self, now: u64) -> u64;
    /// The earliest state after `now` at which it raises a request it does not raise at
    /// `now`, if it will without register accesses.
    fn next_request(&self, now: u64) -> Option<u64>;
    /// Returns to the reset state.
    fn reset(&mut self);
}
