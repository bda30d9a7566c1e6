//! The I/O ports the robot uses: port 2 (bumpers), port 4 (the bit-banged I²C bus), port A
//! (ITU outputs TIOCA1/TIOCA2 to the motor drivers) and port B (H-bridge direction inputs)
//! (H8/3052F hardware manual, section 9 "I/O Ports"; addresses from appendix B).
//!
//! Each port has a data direction register (DDR: 1 = output), a data register (DR, the output
//! latch) and, for ports 2 and 4, an input pull-up control register (PCR). Behaviour modelled:
//!
//! - **DDRs are write-only.** The manual: a DDR cannot be read; a read returns 1 in every bit.
//!   So reading PnDDR returns [`DDR_READ_VALUE`] (H'FF) whatever was written — firmware keeps a
//!   shadow copy (docs/design.md §3.6).
//! - **DR reads** return the DR latch for output bits (DDR = 1) and the pin level for input
//!   bits (DDR = 0).
//! - **Pull-ups** (P2PCR, P4PCR): an input pin with its PCR bit set is pulled high by the
//!   on-chip MOS pull-up; a pin that nothing drives and nothing pulls up *floats*. A floating
//!   input is undefined on the chip; here it reads 0 (a deterministic stand-in), so firmware
//!   that forgets to enable the pull-ups it needs (bumpers, I²C) misreads as it would on the
//!   robot. The pull-up is off for output bits, as on the chip. Ports A and B have no
//!   pull-ups.
//! - Pins driven by a peripheral (TIOCA outputs of the ITU) read their peripheral level.
//! - Port 4 is used open-drain (on the robot, P4.7/P4.6 carry its bit-banged I²C bus,
//!   [`P4_SDA`], [`P4_SCL`]): a pin is pulled low while its DDR bit is 1 with DR = 0 and
//!   released otherwise (a 1 in DR with DDR = 1 would drive the line high; it is treated as a
//!   release, since only the port could then pull it). Every write to P4DDR or P4DR tells the
//!   board the new pulls at the instant of the write ([`Board::port4_drive`]); P4DR reads
//!   return the lines as the board leaves them at the instant of the read
//!   ([`Board::port4_pins`]).
//!
//! [`Ports`] is the four ports as one [`Peripheral`] owning the port block H'FFFFC0–H'FFFFDB;
//! the registers of the ports not modelled (1, 3, 5, 6, 7, 8, 9) read 0 and ignore writes.

use super::Peripheral;
use super::itu::Itu;
use crate::pins::Board;

/// Address of P2DDR, port 2 data direction register (write-only; docs/design.md §4.1: H'FFFFC1).
pub const P2DDR: u32 = 0xFF_FFC1;
/// Address of P2DR, port 2 data register (docs/design.md §4.1: H'FFFFC3).
pub const P2DR: u32 = 0xFF_FFC3;
/// Address of P2PCR, port 2 input pull-up control register (H'FFFFD8).
pub const P2PCR: u32 = 0xFF_FFD8;
/// Address of P4DDR, port 4 data direction register (write-only; docs/design.md §4.1: H'FFFFC5).
pub const P4DDR: u32 = 0xFF_FFC5;
/// Address of P4DR, port 4 data register (docs/design.md §4.1: H'FFFFC7).
pub const P4DR: u32 = 0xFF_FFC7;
/// Address of P4PCR, port 4 input pull-up control register (docs/design.md §4.1: H'FFFFDA).
pub const P4PCR: u32 = 0xFF_FFDA;
/// Address of PADDR, port A data direction register (write-only; H8/3052F manual appendix B:
/// H'FFFFD1).
pub const PADDR: u32 = 0xFF_FFD1;
/// Address of PADR, port A data register (H'FFFFD3).
pub const PADR: u32 = 0xFF_FFD3;
/// Address of PBDDR, port B data direction register (write-only; H'FFFFD4).
pub const PBDDR: u32 = 0xFF_FFD4;
/// Address of PBDR, port B data register (H'FFFFD6).
pub const PBDR: u32 = 0xFF_FFD6;

/// Port-A bit of TIOCA0 (PA2; H8/3052F manual, port A pin functions).
pub const PA_TIOCA0: u8 = 0x04;
/// Port-A bit of TIOCA1 (PA4).
pub const PA_TIOCA1: u8 = 0x10;
/// Port-A bit of TIOCA2 (PA6).
pub const PA_TIOCA2: u8 = 0x40;
/// Port-B bit of TIOCA3 (PB0; port B pin functions).
pub const PB_TIOCA3: u8 = 0x01;
/// Port-B bit of TIOCA4 (PB2).
pub const PB_TIOCA4: u8 = 0x04;

/// Port-4 bit of P4.7, the pin the robot's EEPROM bus has its data line SDA on
/// (docs/design.md §3.6). The H8/3052F has no I²C module: firmware bit-bangs the bus through
/// P4DDR; the parts on the lines are the board's ([`Board::port4_pins`]). A pin trace records
/// this pin's line level ([`crate::trace`]).
pub const P4_SDA: u8 = 0x80;
/// Port-4 bit of P4.6, the pin of the EEPROM bus's clock line SCL (docs/design.md §3.6).
pub const P4_SCL: u8 = 0x40;

/// What a read of a write-only DDR returns: every bit 1 (H8/3052F manual, port sections: "DDR
/// is a write-only register ... all bits are read as 1").
pub const DDR_READ_VALUE: u8 = 0xFF;
/// Reset value of DDR, DR and PCR of ports 2, 4, A and B: H'00 (all inputs, latches 0,
/// pull-ups off) in single-chip mode.
pub const PORT_RESET: u8 = 0x00;

/// One 8-bit port: DDR, DR latch and PCR.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Port {
    /// Data direction register (1 = output).
    pub ddr: u8,
    /// Data register (output latch).
    pub dr: u8,
    /// Input pull-up control register (ports 2 and 4; always 0 for the others).
    pub pcr: u8,
}

impl Port {
    /// A port after reset.
    #[must_use]
    pub const fn new() -> Self {
        Port {
            ddr: PORT_RESET,
            dr: PORT_RESET,
            pcr: PORT_RESET,
        }
    }

    /// The input pins whose on-chip pull-up is on (PCR = 1 and DDR = 0).
    #[inline]
    #[must_use]
    pub const fn pulled_up(&self) -> u8 {
        self.pcr & !self.ddr
    }

    /// Levels of input pins that are either pulled low from outside or released: bit = 1
    /// where nothing outside pulls the pin low. A released pin reads high only through its
    /// pull-up; otherwise it floats and reads 0 (see the module docs).
    #[inline]
    #[must_use]
    pub const fn open_drain_levels(&self, released: u8) -> u8 {
        released & self.pulled_up()
    }

    /// What a DR read returns given the levels of the input pins: the latch for output bits,
    /// the pin for input bits.
    #[inline]
    #[must_use]
    pub const fn read_dr(&self, input_levels: u8) -> u8 {
        (self.dr & self.ddr) | (input_levels & !self.ddr)
    }

    /// Pins that drive a low level (output bits whose latch is 0): what pulls an open-drain
    /// line low when DDR is set with DR = 0 (docs/design.md §3.6).
    #[inline]
    #[must_use]
    pub const fn driven_low(&self) -> u8 {
        self.ddr & !self.dr
    }

    /// Levels the port drives on its output pins (input bits read 0 here).
    #[inline]
    #[must_use]
    pub const fn output_levels(&self) -> u8 {
        self.ddr & self.dr
    }
}

/// First address of the port block: P1DDR (H'FFFFC0).
pub const PORTS_FIRST: u32 = 0xFF_FFC0;
/// Last address of the port block: P5PCR (H'FFFFDB).
pub const PORTS_LAST: u32 = 0xFF_FFDB;

/// What the ports see around them during an access.
pub struct PortPins<'a, B: Board> {
    /// The board, for the levels of the port-2 pins ([`Board::port2_pins`]: the bumpers) and
    /// the port-4 lines ([`Board::port4_pins`], [`Board::port4_drive`]: the EEPROM bus).
    pub board: &'a mut B,
    /// The ITU, whose TIOCA outputs share pins with ports A and B.
    pub itu: &'a mut Itu,
}

/// Ports 2, 4, A and B.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ports {
    p2: Port,
    p4: Port,
    pa: Port,
    pb: Port,
}

impl Ports {
    /// The ports after reset.
    #[must_use]
    pub const fn new() -> Self {
        Ports {
            p2: Port::new(),
            p4: Port::new(),
            pa: Port::new(),
            pb: Port::new(),
        }
    }

    /// Port 4's registers (DDR as written, DR, PCR).
    #[must_use]
    pub const fn port4(&self) -> Port {
        self.p4
    }

    /// Port A's registers (DDR as written, DR).
    #[must_use]
    pub const fn port_a(&self) -> Port {
        self.pa
    }

    /// Port B's registers (DDR as written, DR).
    #[must_use]
    pub const fn port_b(&self) -> Port {
        self.pb
    }

    /// Pin levels of port A at `now`: ITU-driven TIOCA0–2 (PA2, PA4, PA6), else the output
    /// latch; input pins with nothing connected float and read 0 (port A has no pull-ups).
    pub fn pa_pins(&self, itu: &mut Itu, now: u64) -> u8 {
        let mut pins = self.pa.output_levels();
        for (ch, bit) in [(0, PA_TIOCA0), (1, PA_TIOCA1), (2, PA_TIOCA2)] {
            let (level, drives) = itu.tioca(ch, now);
            if drives {
                pins = (pins & !bit) | if level { bit } else { 0 };
            }
        }
        pins
    }

    /// Pin levels of port B at `now`: ITU-driven TIOCA3/TIOCA4 (PB0, PB2), else the output
    /// latch.
    pub fn pb_pins(&self, itu: &mut Itu, now: u64) -> u8 {
        let mut pins = self.pb.output_levels();
        for (ch, bit) in [(3, PB_TIOCA3), (4, PB_TIOCA4)] {
            let (level, drives) = itu.tioca(ch, now);
            if drives {
                pins = (pins & !bit) | if level { bit } else { 0 };
            }
        }
        pins
    }

    /// Levels of port 4's input pins as the board leaves the lines; a released pin reads high
    /// only through its pull-up.
    fn p4_inputs<B: Board>(&self, board: &mut B, now: u64) -> u8 {
        self.p4.open_drain_levels(board.port4_pins(now))
    }
}

impl Peripheral for Ports {
    type Outside<'a, B: Board + 'a> = PortPins<'a, B>;
    const FIRST: u32 = PORTS_FIRST;
    const LAST: u32 = PORTS_LAST;
    /// Port writes (I²C bit-banging, motor direction) request no interrupt.
    const AFFECTS_IRQ: bool = false;

    #[inline]
    fn read<B: Board>(&mut self, addr: u32, now: u64, pins: PortPins<'_, B>) -> u8 {
        match addr {
            P2DDR | P4DDR | PADDR | PBDDR => DDR_READ_VALUE,
            P2DR => {
                let released = pins.board.port2_pins(now);
                self.p2.read_dr(self.p2.open_drain_levels(released))
            }
            P4DR => {
                let inputs = self.p4_inputs(pins.board, now);
                self.p4.read_dr(inputs)
            }
            PADR => {
                let levels = self.pa_pins(pins.itu, now);
                self.pa.read_dr(levels)
            }
            PBDR => {
                let levels = self.pb_pins(pins.itu, now);
                self.pb.read_dr(levels)
            }
            P2PCR => self.p2.pcr,
            P4PCR => self.p4.pcr,
            _ => 0,
        }
    }

    #[inline]
    fn write<B: Board>(&mut self, addr: u32, value: u8, now: u64, pins: PortPins<'_, B>) {
        match addr {
            P2DDR => self.p2.ddr = value,
            P2DR => self.p2.dr = value,
            P2PCR => self.p2.pcr = value,
            P4DDR => {
                self.p4.ddr = value;
                pins.board.port4_drive(self.p4.driven_low(), now);
            }
            P4DR => {
                self.p4.dr = value;
                pins.board.port4_drive(self.p4.driven_low(), now);
            }
            P4PCR => self.p4.pcr = value,
            PADDR => self.pa.ddr = value,
            PADR => self.pa.dr = value,
            PBDDR => self.pb.ddr = value,
            PBDR => self.pb.dr = value,
            _ => {}
        }
    }

    /// Nothing to catch up: the ports hold latches; what they read is asked at the read.
    #[inline]
    fn sync<B: Board>(&mut self, _now: u64, _pins: PortPins<'_, B>) {}

    #[inline]
    fn next_event(&self, _now: u64) -> Option<u64> {
        None
    }

    #[inline]
    fn requests(&self, _now: u64) -> u64 {
        0
    }

    #[inline]
    fn next_request(&self, _now: u64) -> Option<u64> {
        None
    }

    #[inline]
    fn reset(&mut self) {
        *self = Ports::new();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dr_reads_latch_for_outputs_and_pins_for_inputs() {
        let p = Port {
            ddr: 0xF0,
            dr: 0xA5,
            pcr: 0,
        };
        assert_eq!(p.read_dr(0x0F), 0xAF);
        assert_eq!(p.read_dr(0x00), 0xA0);
        assert_eq!(p.output_levels(), 0xA0);
        assert_eq!(p.driven_low(), 0x50);
    }

    #[test]
    fn released_inputs_need_their_pull_up() {
        let p = Port {
            ddr: 0x01,
            dr: 0,
            pcr: 0x0F,
        };
        // Bit 0 is an output (pull-up off), bits 1–3 pulled up, bits 4–7 float.
        assert_eq!(p.pulled_up(), 0x0E);
        assert_eq!(p.open_drain_levels(0xFF), 0x0E);
        // Bit 2 pulled low from outside.
        assert_eq!(p.open_drain_levels(0xFB), 0x0A);
    }
}
