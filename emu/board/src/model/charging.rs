//! How the Rust controller pays for what it does on the emulated MCU.
//!
//! The controller is a program running on the H8/3052F, written in Rust instead of H8 code. It
//! reaches the hardware only through [`h8300h::bus::Bus`] register reads and writes, each
//! charged by the area it touches (3 states per byte of on-chip I/O, docs/design.md §4.1); the instruction
//! fetches of the instructions that make those accesses are charged as ROM fetch cycles (2 states
//! per word); register-only code is charged from its instruction sequence ([`nn_q15::cost::Insn`]);
//! the learner's arithmetic is charged from `nn_q15`'s H8 meter. Between charges the controller
//! takes the tick interrupt when it is pending, as the chip would with interrupts enabled, and
//! keeps the states spent in it apart so that every phase is measured without it.

use eeprom::I2cPins;
use nn_q15::cost::Insn;

use super::ModelBus;
use super::regs::{IMA, ITU0, P4DDR, P4DR, SCL_BIT, SDA_BIT, TSR, VECTOR_IMIA0};
use h8300h::cpu::timing::{N_INTERRUPT_INTERNAL, N_PRIORITY_DECISION_INTERNAL};
use h8300h::memmap::{RAM_ACCESS_STATES, ROM_ACCESS_STATES};

/// States of one instruction-fetch cycle from the on-chip flash (docs/design.md §4.1: 2 states, 16-bit).
pub const FETCH_STATES: u32 = ROM_ACCESS_STATES;

/// Interrupt entry for an on-chip source, as the H8/300H core charges it (H8/3052F hardware
/// manual Table 5-5): priority decision, the prefetch at the return address, PC and CCR pushed
/// (two word writes to RAM), the vector read (two words from flash), the prefetch of the
/// handler, and the internal states after it.
pub const INTERRUPT_ENTRY_STATES: u32 = N_PRIORITY_DECISION_INTERNAL
    + FETCH_STATES
    + 2 * RAM_ACCESS_STATES
    + 2 * ROM_ACCESS_STATES
    + FETCH_STATES
    + N_INTERRUPT_INTERNAL;

/// States of RTE (docs/design.md §4.2).
pub const RTE_STATES: u32 = 10;
/// States of SLEEP (docs/design.md §4.2).
pub const SLEEP_STATES: u32 = 2;

/// Sum of the states of an instruction sequence (on-chip operands, docs/design.md §4.2).
#[must_use]
#[inline]
pub const fn states_of(insns: &[Insn]) -> u32 {
    let mut total = 0;
    let mut i = 0;
    while i < insns.len() {
        total += insns[i].states();
        i += 1;
    }
    total
}

/// The firmware's tick interrupt handler (`tick_isr`, from the listing) around its two TSR0
/// accesses: `PUSH.L ER2 ; PUSH.L ER3 ; MOV.L #TSR0,ER2 ;` [MOV.B @ER2,R3L] `AND.B #H'FE,R3L ;`
/// [MOV.B R3L,@ER2] `MOV.L @ticks:24,ER2 ; ADDS #1,ER2 ; MOV.L ER2,@ticks:24 ; POP.L ER3 ;
/// POP.L ER2 ;` then RTE.
const ISR_BEFORE_READ: [Insn; 3] = [Insn::PushPopL, Insn::PushPopL, Insn::ImmL];
const ISR_BETWEEN: [Insn; 1] = [Insn::Reg];
const ISR_AFTER_WRITE: [Insn; 5] = [
    Insn::MovLAbs24,
    Insn::Reg,
    Insn::MovLAbs24,
    Insn::PushPopL,
    Insn::PushPopL,
];

/// The firmware's view of the MCU while it runs: the bus, whether interrupts are enabled, the
/// tick counter the interrupt handler keeps, and the states spent in the handler so far.
pub struct Fw<'a, B: ModelBus> {
    /// The MCU.
    pub bus: &'a mut B,
    /// CCR.I = 0: the tick interrupt is taken when pending.
    pub interrupts_enabled: bool,
    /// The tick counter (a 32-bit variable in RAM on the chip).
    pub ticks: &'a mut u64,
    /// States spent in the tick handler (entry to RTE) since the counter was last reset.
    pub isr_states: u64,
    /// When the next tick is due, if known: the interrupt controller is only asked from then
    /// on (an emulation shortcut with identical results: the tick cannot be pending earlier).
    pub next_tick_at: Option<u64>,
    /// The tick period in states (to predict the next tick after one is taken).
    pub tick_period: u64,
}

impl<'a, B: ModelBus> Fw<'a, B> {
    /// A view of `bus` with the tick counter `ticks`.
    pub fn new(bus: &'a mut B, ticks: &'a mut u64, interrupts_enabled: bool) -> Self {
        Self {
            bus,
            interrupts_enabled,
            ticks,
            isr_states: 0,
            next_tick_at: None,
            tick_period: 0,
        }
    }

    /// The MCU clock.
    pub fn now(&self) -> u64 {
        self.bus.now()
    }

    /// Runs register-only code (no I/O access), then takes a pending tick.
    #[inline]
    pub fn code(&mut self, insns: &[Insn]) {
        self.bus.internal(states_of(insns));
        self.service();
    }

    /// Lets `states` states of register and RAM work pass (the learner's metered arithmetic),
    /// then takes a pending tick.
    pub fn lump(&mut self, states: u64) {
        self.idle(states);
        self.service();
    }

    /// Lets `states` states pass without taking the tick (the CPU asleep).
    pub fn idle(&mut self, states: u64) {
        let mut left = states;
        while left > 0 {
            let chunk = u32::try_from(left).unwrap_or(u32::MAX);
            self.bus.internal(chunk);
            left -= u64::from(chunk);
        }
    }

    /// `MOV.B @aa:8,R0L`: one fetch, one byte read.
    pub fn read8(&mut self, addr: u32) -> u8 {
        self.bus.internal(FETCH_STATES);
        let v = self.bus.read8(addr);
        self.service();
        v
    }

    /// `MOV.B R0L,@aa:8`: one fetch, one byte write.
    pub fn write8(&mut self, addr: u32, value: u8) {
        self.bus.internal(FETCH_STATES);
        self.bus.write8(addr, value);
        self.service();
    }

    /// `MOV.W R0,@aa:16`: two fetches, one word write.
    pub fn write16(&mut self, addr: u32, value: u16) {
        self.bus.internal(2 * FETCH_STATES);
        self.bus.write16(addr, value);
        self.service();
    }

    /// Takes the tick interrupt if interrupts are enabled and it is pending.
    pub fn service(&mut self) {
        if !self.interrupts_enabled {
            return;
        }
        if self.next_tick_at.is_some_and(|due| self.bus.now() < due) {
            return;
        }
        if self.bus.pending_irq() == Some(VECTOR_IMIA0) {
            self.tick_handler();
        }
    }

    /// Interrupt entry, the handler and RTE; counts one tick.
    pub fn tick_handler(&mut self) {
        let t0 = self.bus.now();
        self.bus.internal(INTERRUPT_ENTRY_STATES);
        // TSR0 is read with IMFA = 1 and written back with it cleared (the chip's
        // read-1-then-write-0 rule).
        self.bus.internal(states_of(&ISR_BEFORE_READ));
        self.bus.internal(FETCH_STATES);
        let tsr = self.bus.read8(ITU0 + TSR);
        self.bus.internal(states_of(&ISR_BETWEEN));
        self.bus.internal(FETCH_STATES);
        self.bus.write8(ITU0 + TSR, tsr & !IMA);
        self.bus.internal(states_of(&ISR_AFTER_WRITE));
        self.bus.internal(RTE_STATES);
        *self.ticks += 1;
        self.isr_states += self.bus.now() - t0;
        if let Some(due) = self.next_tick_at.as_mut() {
            *due += self.tick_period;
        }
    }
}

/// Port 4 as the I²C pins (docs/design.md §3.6): a line is pulled low by setting its DDR bit (DR bits 7
/// and 6 stay 0) and released by clearing it; the DDR is write-only, so the firmware keeps a
/// shadow in a register and writes it whole. A pin operation is `BSET/BCLR #n,R2L ;
/// MOV.B R2L,@P4DDR:8` (2 + 2 + 3 = 7 states, the edge at the end of the write); reading SDA is
/// `MOV.B @P4DR:8,R0L ; BTST #7,R0L` (2 + 3 + 2 = 7). The master's waits are the firmware's delay
/// loops; the shifts and branches that pick each bit run inside them.
pub struct FwPins<'f, 'a, B: ModelBus> {
    /// The firmware's view of the MCU.
    pub fw: &'f mut Fw<'a, B>,
    /// The P4DDR shadow.
    pub shadow: &'f mut u8,
}

/// States of one I²C pin operation (see [`FwPins`]).
pub const PIN_OP_STATES: u64 = 7;

impl<B: ModelBus> FwPins<'_, '_, B> {
    fn set_ddr(&mut self, bit: u8, pull: bool) {
        if pull {
            *self.shadow |= bit;
        } else {
            *self.shadow &= !bit;
        }
        self.fw.bus.internal(states_of(&[Insn::Reg]));
        self.fw.write8(P4DDR, *self.shadow);
    }
}

impl<B: ModelBus> I2cPins for FwPins<'_, '_, B> {
    fn scl_low(&mut self) {
        self.set_ddr(SCL_BIT, true);
    }
    fn scl_release(&mut self) {
        self.set_ddr(SCL_BIT, false);
    }
    fn sda_low(&mut self) {
        self.set_ddr(SDA_BIT, true);
    }
    fn sda_release(&mut self) {
        self.set_ddr(SDA_BIT, false);
    }
    fn sda_is_high(&mut self) -> bool {
        let v = self.fw.read8(P4DR);
        self.fw.code(&[Insn::Reg]);
        v & SDA_BIT != 0
    }
    fn wait_states(&mut self, states: u64) {
        self.fw.lump(states);
    }
    fn op_states(&self) -> u64 {
        PIN_OP_STATES
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interrupt_entry_is_the_manuals_17_states() {
        assert_eq!(INTERRUPT_ENTRY_STATES, 17);
        assert_eq!(states_of(&[Insn::MulxsW, Insn::Reg]), 26);
    }
}
