//! The external interrupt inputs IRQ0–IRQ5 of the interrupt controller (H8/3052F hardware
//! manual, section 5 "Interrupt Controller": ISCR, IER and ISR, the IRQ interrupts, vectors
//! 12–17 of Table 5-3).
//!
//! # Pins
//! IRQ0–IRQ3 are the pins P8.0–P8.3, IRQ4 and IRQ5 P9.4 and P9.5
//! ([`crate::periph::ports::IRQ_PINS`]). An IRQ input sees its pin's level: the port's latch
//! when the pin is an output, else what the board drives on it ([`Board::port_pins`]), else 0
//! (ports 8 and 9 have no pull-ups: a pin nothing drives floats, read 0 as everywhere on this
//! chip, [`crate::periph::ports`]).
//!
//! # Registers (5.2)
//! - **ISCR** (H'FFFFF4), IRQ sense control: bit n = 1 senses IRQn's falling edge, 0 its low
//!   level.
//! - **IER** (H'FFFFF5), IRQ enable: bit n = 1 enables IRQn's interrupt.
//! - **ISR** (H'FFFFF6), IRQ status: bit n (IRQnF) is set on a falling edge (edge sensing) or
//!   while the pin is low (level sensing), whatever IER says. It is cleared by reading it as 1
//!   and then writing 0, or when IRQn's exception handling is carried out (edge sensing; with
//!   level sensing only when the pin is high again).
//!
//! Bits 7–6 of all three are reserved: they read 0 and ignore writes. IRQn is requested while
//! IRQnF and IRQnE are both 1; the interrupt controller decides the priority with IPRA
//! ([`crate::periph::intc`]).
//!
//! # When the pins change
//! The board says when what it drives next changes ([`Board::next_pin_change`]); the chip
//! catches the IRQ logic up lazily, walking those instants in order, so an edge between two
//! accesses is never lost. A port write that changes an IRQ pin is seen at its instant. The
//! IRQ state sits in cells so that the interrupt decision (asked through a shared reference)
//! can bring it up to date.

use std::cell::Cell;

use super::ports::{IRQ_PINS, PortId, Ports};
use crate::pins::Board;

/// Address of ISCR, the IRQ sense control register (Table 5-2: H'FFFFF4).
pub const ISCR: u32 = 0xFF_FFF4;
/// Address of IER, the IRQ enable register (H'FFFFF5).
pub const IER: u32 = 0xFF_FFF5;
/// Address of ISR, the IRQ status register (H'FFFFF6).
pub const ISR: u32 = 0xFF_FFF6;

/// The IRQ bits of ISCR, IER and ISR (IRQ0–IRQ5); bits 7–6 are reserved.
pub const IRQ_BITS: u8 = 0x3F;

/// IRQ0's vector; IRQn's is this + n (Table 5-3).
pub const VECTOR_IRQ0: u8 = 12;

/// Whether a port register write at `addr` may change an IRQ pin (the DDR or DR of port 8 or
/// 9).
#[inline]
#[must_use]
pub const fn is_irq_port_register(addr: u32) -> bool {
    use super::ports::{P8DDR, P8DR, P9DDR, P9DR};
    matches!(addr, P8DDR | P8DR | P9DDR | P9DR)
}

/// The IRQ inputs' registers and flags.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Irq {
    iscr: u8,
    ier: u8,
    /// ISR as of `sampled_at`.
    isr: Cell<u8>,
    /// The IRQ pins' levels at `sampled_at` (bit n: IRQn).
    levels: Cell<u8>,
    /// The instant the flags are worked out to.
    sampled_at: Cell<u64>,
    /// The flags read as 1 since they were set: a 0 written clears them.
    armed: u8,
}

/// The IRQ pins' levels (bit n: IRQn) given port 8's and 9's registers and what the board
/// drives on them at `t`.
fn irq_levels<B: Board>(ports: &Ports, board: &B, t: u64) -> u8 {
    let p8 = ports.levels(PortId::P8, board.port_pins(PortId::P8, t));
    let p9 = ports.levels(PortId::P9, board.port_pins(PortId::P9, t));
    let mut v = 0;
    for (n, &(port, bit)) in IRQ_PINS.iter().enumerate() {
        let level = if port == PortId::P8 { p8 } else { p9 };
        if level & bit != 0 {
            v |= 1 << n;
        }
    }
    v
}

impl Irq {
    /// After reset: every IRQ at low-level sensing, disabled, no flag, the pins taken as low
    /// at instant 0 ([`Irq::reset`] takes them as they are).
    #[must_use]
    pub fn new() -> Self {
        Irq::default()
    }

    /// Whether any IRQ interrupt is enabled (IER ≠ 0): only then can the pins raise a request.
    #[inline]
    #[must_use]
    pub const fn enabled(&self) -> bool {
        self.ier != 0
    }

    /// Takes the pins' levels at `t` (not before the last instant taken): a falling edge sets
    /// the flag of an edge-sensed IRQ, a low level that of a level-sensed one.
    fn sample(&self, t: u64, levels: u8) {
        let fell = self.levels.get() & !levels;
        let low = !levels & IRQ_BITS;
        let set = (fell & self.iscr) | (low & !self.iscr);
        self.isr.set(self.isr.get() | (set & IRQ_BITS));
        self.levels.set(levels);
        self.sampled_at.set(t.max(self.sampled_at.get()));
    }

    /// Brings the flags up to `now`: the board's pin changes since the last instant taken, in
    /// order, then `now`.
    pub fn catch_up<B: Board>(&self, now: u64, ports: &Ports, board: &B) {
        let mut t = self.sampled_at.get();
        while let Some(c) = board.next_pin_change(t)
            && c <= now
            && c > t
        {
            self.sample(c, irq_levels(ports, board, c));
            t = c;
        }
        self.sample(now, irq_levels(ports, board, now));
    }

    /// After a write to port 8's or 9's registers at `now` (the flags caught up to just before
    /// it): the pins' new levels.
    pub fn after_port_write<B: Board>(&self, now: u64, ports: &Ports, board: &B) {
        self.sample(now, irq_levels(ports, board, now));
    }

    /// Reads ISCR, IER or ISR (caught up to now by the caller).
    pub fn read(&mut self, addr: u32) -> u8 {
        match addr {
            ISCR => self.iscr,
            IER => self.ier,
            ISR => {
                let isr = self.isr.get();
                self.armed |= isr;
                isr
            }
            _ => 0,
        }
    }

    /// Writes ISCR, IER or ISR (caught up to now by the caller). A 0 written to a flag read
    /// as 1 clears it; a level-sensed flag whose pin is still low is set again at once.
    pub fn write(&mut self, addr: u32, value: u8) {
        let value = value & IRQ_BITS;
        match addr {
            ISCR => self.iscr = value,
            IER => self.ier = value,
            ISR => {
                let clear = self.armed & !value;
                self.isr.set(self.isr.get() & !clear);
                self.armed &= !clear;
                let low = !self.levels.get() & IRQ_BITS & !self.iscr;
                self.isr.set(self.isr.get() | low);
            }
            _ => {}
        }
    }

    /// IRQn's exception handling was carried out (vector `vector`): its flag is cleared when
    /// edge-sensed, or level-sensed with the pin high.
    pub fn accepted(&mut self, vector: u8) {
        let Some(n) = vector.checked_sub(VECTOR_IRQ0).filter(|&n| n < 6) else {
            return;
        };
        let bit = 1u8 << n;
        if self.iscr & bit != 0 || self.levels.get() & bit != 0 {
            self.isr.set(self.isr.get() & !bit);
            self.armed &= !bit;
        }
    }

    /// The requests (vector mask) as of the last catch-up: IRQn while IRQnF and IRQnE.
    #[inline]
    #[must_use]
    pub fn requests(&self) -> u64 {
        u64::from(self.isr.get() & self.ier) << VECTOR_IRQ0
    }

    /// ISR as last caught up (for inspection).
    #[must_use]
    pub fn isr(&self) -> u8 {
        self.isr.get()
    }

    /// Returns to the reset state; the pins as they are at `now`.
    pub fn reset<B: Board>(&mut self, now: u64, ports: &Ports, board: &B) {
        *self = Irq::new();
        self.levels.set(irq_levels(ports, board, now));
        self.sampled_at.set(now);
    }
}

/// What the IRQ logic sees outside itself: ports 8 and 9 and the board.
pub struct IrqView<'a, B: Board> {
    /// The ports (the IRQ pins' DDR and DR).
    pub ports: &'a Ports,
    /// The board (what it drives on the pins).
    pub board: &'a B,
}

impl super::Peripheral for Irq {
    type Outside<'a, B: Board + 'a> = IrqView<'a, B>;
    const FIRST: u32 = ISCR;
    const LAST: u32 = ISR;
    const AFFECTS_IRQ: bool = true;

    fn read<B: Board>(&mut self, addr: u32, now: u64, v: IrqView<'_, B>) -> u8 {
        self.catch_up(now, v.ports, v.board);
        Irq::read(self, addr)
    }

    fn write<B: Board>(&mut self, addr: u32, value: u8, now: u64, v: IrqView<'_, B>) {
        self.catch_up(now, v.ports, v.board);
        Irq::write(self, addr, value);
    }

    /// Nothing to do: the flags are caught up whenever they are looked at.
    #[inline]
    fn sync<B: Board>(&mut self, _now: u64, _v: IrqView<'_, B>) {}

    /// None of its own: the pins change when the board says ([`Board::next_pin_change`]).
    #[inline]
    fn next_event(&self, _now: u64) -> Option<u64> {
        None
    }

    /// As of the last catch-up (the chip catches up before it decides).
    #[inline]
    fn requests(&self, _now: u64) -> u64 {
        Irq::requests(self)
    }

    /// None of its own: the chip counts the board's next pin change while an IRQ is enabled.
    #[inline]
    fn next_request(&self, _now: u64) -> Option<u64> {
        None
    }

    /// The registers' reset state; the chip then takes the pins' levels ([`Irq::reset`]).
    fn reset(&mut self) {
        *self = Irq::new();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pins::NullBoard;

    #[test]
    fn edges_and_levels_set_the_flags() {
        let ports = Ports::new();
        let mut irq = Irq::new();
        // Floating pins read 0: level sensing (the reset state) flags them at once.
        irq.catch_up(10, &ports, &NullBoard);
        assert_eq!(irq.isr(), IRQ_BITS);
        // Edge sensing: no edge, no new flag after clearing.
        irq.write(ISCR, IRQ_BITS);
        let _ = irq.read(ISR);
        irq.write(ISR, 0);
        irq.catch_up(20, &ports, &NullBoard);
        assert_eq!(irq.isr(), 0);
        assert_eq!(irq.requests(), 0);
    }
}
