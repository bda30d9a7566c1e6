//! The I/O ports of the H8/3052F: ports 1–9, A and B (H8/3052F hardware manual, section 9
//! "I/O Ports"; addresses from appendix B.1). On the robot, port 2 carries the bumpers, port 4
//! the bit-banged I²C bus, port A the ITU outputs TIOCA1/TIOCA2 to the motor drivers and port
//! B the H-bridge direction inputs; a user's image may use any of them.
//!
//! Each port has a data direction register (DDR: 1 = output; port 7, input only, has none), a
//! data register (DR, the output latch) and, for ports 2, 4 and 5, an input pull-up control
//! register (PCR). Ports 5, 6, 8 and 9 have fewer than eight pins ([`PortId::pins`]: P5.0–3,
//! P6.0–6, P8.0–4, P9.0–5); the bits of the pins they lack are reserved and read 1. Behaviour
//! modelled:
//!
//! - **DDRs are write-only.** The manual: a DDR cannot be read; a read returns 1 in every bit.
//!   So reading PnDDR returns [`DDR_READ_VALUE`] (H'FF) whatever was written — firmware keeps a
//!   shadow copy (docs/design.md §3.6).
//! - **DR reads** return the DR latch for output bits (DDR = 1) and the pin level for input
//!   bits (DDR = 0).
//! - **Pull-ups** (P2PCR, P4PCR, P5PCR): an input pin with its PCR bit set is pulled high by
//!   the on-chip MOS pull-up; a pin that nothing drives and nothing pulls up *floats*. A
//!   floating input is undefined on the chip; here it reads 0 (a deterministic stand-in), so
//!   firmware that forgets to enable the pull-ups it needs (bumpers, I²C) misreads as it would
//!   on the robot. The pull-up is off for output bits, as on the chip. The other ports have no
//!   pull-ups.
//! - **What drives an input pin** is the board's: port 2's pins are pulled low or released
//!   ([`Board::port2_pins`]: the bumpers), port 4's lines are the EEPROM bus (below), and every
//!   other port's input pins are driven high or low, or left alone, by
//!   [`Board::port_pins`] ([`ExternalPins`]).
//! - Pins driven by a peripheral (TIOCA outputs of the ITU on ports A and B) read their
//!   peripheral level.
//! - Port 4 is used open-drain (on the robot, P4.7/P4.6 carry its bit-banged I²C bus,
//!   [`P4_SDA`], [`P4_SCL`]): a pin is pulled low while its DDR bit is 1 with DR = 0 and
//!   released otherwise (a 1 in DR with DDR = 1 would drive the line high; it is treated as a
//!   release, since only the port could then pull it). Every write to P4DDR or P4DR tells the
//!   board the new pulls at the instant of the write ([`Board::port4_drive`]); P4DR reads
//!   return the lines as the board leaves them at the instant of the read
//!   ([`Board::port4_pins`]).
//! - P8.0–P8.3 are also the IRQ0–IRQ3 inputs and P9.4–P9.5 IRQ4–IRQ5 ([`IRQ_PINS`]): the
//!   interrupt controller's IRQ logic ([`crate::periph::irq`]) watches their levels.
//!
//! [`Ports`] is the eleven ports as one [`Peripheral`] owning the port block
//! H'FFFFC0–H'FFFFDB; its reserved addresses (H'FFFFCC, D5, D7, D9) read 0 and ignore writes
//! (the chip reports accesses to them, [`crate::iomap`]).

use super::Peripheral;
use super::itu::Itu;
use crate::pins::Board;
// The port identifiers and what the outside drives are the pins' words (`crate::pins`); named here too,
// where the ports are.
pub use crate::pins::{ExternalPins, PortId};

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

/// Address of P1DDR (H8/3052F manual, appendix B.1: H'FFFFC0).
pub const P1DDR: u32 = 0xFF_FFC0;
/// Address of P1DR (H'FFFFC2).
pub const P1DR: u32 = 0xFF_FFC2;
/// Address of P3DDR (H'FFFFC4).
pub const P3DDR: u32 = 0xFF_FFC4;
/// Address of P3DR (H'FFFFC6).
pub const P3DR: u32 = 0xFF_FFC6;
/// Address of P5DDR (H'FFFFC8).
pub const P5DDR: u32 = 0xFF_FFC8;
/// Address of P6DDR (H'FFFFC9).
pub const P6DDR: u32 = 0xFF_FFC9;
/// Address of P5DR (H'FFFFCA).
pub const P5DR: u32 = 0xFF_FFCA;
/// Address of P6DR (H'FFFFCB).
pub const P6DR: u32 = 0xFF_FFCB;
/// Address of P8DDR (H'FFFFCD).
pub const P8DDR: u32 = 0xFF_FFCD;
/// Address of P7DR, port 7's data register (input only: it reads the pins; H'FFFFCE).
pub const P7DR: u32 = 0xFF_FFCE;
/// Address of P8DR (H'FFFFCF).
pub const P8DR: u32 = 0xFF_FFCF;
/// Address of P9DDR (H'FFFFD0).
pub const P9DDR: u32 = 0xFF_FFD0;
/// Address of P9DR (H'FFFFD2).
pub const P9DR: u32 = 0xFF_FFD2;
/// Address of P5PCR, port 5 input pull-up control register (H'FFFFDB).
pub const P5PCR: u32 = 0xFF_FFDB;

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

impl PortId {
    /// Every port, in the order of [`PortId::index`].
    pub const ALL: [PortId; 11] = [
        PortId::P1,
        PortId::P2,
        PortId::P3,
        PortId::P4,
        PortId::P5,
        PortId::P6,
        PortId::P7,
        PortId::P8,
        PortId::P9,
        PortId::PA,
        PortId::PB,
    ];

    /// 0–10, in the order of [`PortId::ALL`].
    #[inline]
    #[must_use]
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The port's name: `P1`–`P9`, `PA`, `PB`.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            PortId::P1 => "P1",
            PortId::P2 => "P2",
            PortId::P3 => "P3",
            PortId::P4 => "P4",
            PortId::P5 => "P5",
            PortId::P6 => "P6",
            PortId::P7 => "P7",
            PortId::P8 => "P8",
            PortId::P9 => "P9",
            PortId::PA => "PA",
            PortId::PB => "PB",
        }
    }

    /// The bits of the pins the port has (section 9: port 5 has four pins, port 6 seven,
    /// port 8 five, port 9 six); the other bits are reserved and read 1.
    #[must_use]
    pub const fn pins(self) -> u8 {
        match self {
            PortId::P5 => 0x0F,
            PortId::P6 => 0x7F,
            PortId::P8 => 0x1F,
            PortId::P9 => 0x3F,
            _ => 0xFF,
        }
    }

    /// The port whose DDR, DR or PCR is at `addr`, and which of the three it is.
    #[must_use]
    pub const fn of_register(addr: u32) -> Option<(PortId, PortReg)> {
        use PortReg::{Ddr, Dr, Pcr};
        Some(match addr {
            P1DDR => (PortId::P1, Ddr),
            P2DDR => (PortId::P2, Ddr),
            P1DR => (PortId::P1, Dr),
            P2DR => (PortId::P2, Dr),
            P3DDR => (PortId::P3, Ddr),
            P4DDR => (PortId::P4, Ddr),
            P3DR => (PortId::P3, Dr),
            P4DR => (PortId::P4, Dr),
            P5DDR => (PortId::P5, Ddr),
            P6DDR => (PortId::P6, Ddr),
            P5DR => (PortId::P5, Dr),
            P6DR => (PortId::P6, Dr),
            P8DDR => (PortId::P8, Ddr),
            P7DR => (PortId::P7, Dr),
            P8DR => (PortId::P8, Dr),
            P9DDR => (PortId::P9, Ddr),
            PADDR => (PortId::PA, Ddr),
            P9DR => (PortId::P9, Dr),
            PADR => (PortId::PA, Dr),
            PBDDR => (PortId::PB, Ddr),
            PBDR => (PortId::PB, Dr),
            P2PCR => (PortId::P2, Pcr),
            P4PCR => (PortId::P4, Pcr),
            P5PCR => (PortId::P5, Pcr),
            _ => return None,
        })
    }
}

/// Which register of a port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PortReg {
    /// The data direction register.
    Ddr,
    /// The data register.
    Dr,
    /// The input pull-up control register.
    Pcr,
}

/// The IRQ inputs' pins: (port, bit) of IRQ0–IRQ5 (section 5, IRQ pins; section 9: P8.0–P8.3
/// are IRQ0–IRQ3, P9.4 and P9.5 IRQ4 and IRQ5).
pub const IRQ_PINS: [(PortId, u8); 6] = [
    (PortId::P8, 0x01),
    (PortId::P8, 0x02),
    (PortId::P8, 0x04),
    (PortId::P8, 0x08),
    (PortId::P9, 0x10),
    (PortId::P9, 0x20),
];

/// What the ports see around them during an access.
pub struct PortPins<'a, B: Board> {
    /// The board, for the levels of the port-2 pins ([`Board::port2_pins`]: the bumpers), the
    /// port-4 lines ([`Board::port4_pins`], [`Board::port4_drive`]: the EEPROM bus) and the
    /// other ports' input pins ([`Board::port_pins`]).
    pub board: &'a mut B,
    /// The ITU, whose TIOCA outputs share pins with ports A and B.
    pub itu: &'a mut Itu,
}

/// The eleven ports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Ports {
    ports: [Port; 11],
}

impl Ports {
    /// The ports after reset.
    #[must_use]
    pub const fn new() -> Self {
        Ports {
            ports: [Port::new(); 11],
        }
    }

    /// Port `id`'s registers (DDR as written, DR, PCR).
    #[inline]
    #[must_use]
    pub const fn port(&self, id: PortId) -> Port {
        self.ports[id.index()]
    }

    /// Port 4's registers (DDR as written, DR, PCR).
    #[must_use]
    pub const fn port4(&self) -> Port {
        self.port(PortId::P4)
    }

    /// Port A's registers (DDR as written, DR).
    #[must_use]
    pub const fn port_a(&self) -> Port {
        self.port(PortId::PA)
    }

    /// Port B's registers (DDR as written, DR).
    #[must_use]
    pub const fn port_b(&self) -> Port {
        self.port(PortId::PB)
    }

    /// Pin levels of port A at `now`: ITU-driven TIOCA0–2 (PA2, PA4, PA6), else the output
    /// latch; input pins with nothing connected float and read 0 (port A has no pull-ups).
    pub fn pa_pins(&self, itu: &mut Itu, now: u64) -> u8 {
        let mut pins = self.port_a().output_levels();
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
        let mut pins = self.port_b().output_levels();
        for (ch, bit) in [(3, PB_TIOCA3), (4, PB_TIOCA4)] {
            let (level, drives) = itu.tioca(ch, now);
            if drives {
                pins = (pins & !bit) | if level { bit } else { 0 };
            }
        }
        pins
    }

    /// The levels of a port's pins given what the outside drives: output pins at their latch,
    /// input pins at the outside's level, else high through a pull-up, else 0 (floating); the
    /// pins the port lacks read 1. Not for port 2 and 4, whose pins the board reports apart,
    /// nor for the ITU's pins on ports A and B ([`Ports::pa_pins`], [`Ports::pb_pins`]).
    #[must_use]
    pub fn levels(&self, id: PortId, outside: ExternalPins) -> u8 {
        let p = self.port(id);
        let input = !p.ddr;
        let external = (outside.levels & outside.driven) | (p.pulled_up() & !outside.driven);
        (p.output_levels() | (external & input)) | !id.pins()
    }

    /// Levels of port 4's input pins as the board leaves the lines; a released pin reads high
    /// only through its pull-up.
    fn p4_inputs<B: Board>(&self, board: &mut B, now: u64) -> u8 {
        self.port4().open_drain_levels(board.port4_pins(now))
    }

    /// What a read of port `id`'s DR returns at `now`.
    fn read_dr<B: Board>(&self, id: PortId, now: u64, pins: PortPins<'_, B>) -> u8 {
        let p = self.port(id);
        match id {
            PortId::P2 => {
                let released = pins.board.port2_pins(now);
                p.read_dr(p.open_drain_levels(released))
            }
            PortId::P4 => {
                let inputs = self.p4_inputs(pins.board, now);
                p.read_dr(inputs)
            }
            PortId::PA | PortId::PB => {
                let own = if id == PortId::PA {
                    self.pa_pins(pins.itu, now)
                } else {
                    self.pb_pins(pins.itu, now)
                };
                let outside = pins.board.port_pins(id, now);
                p.read_dr(own | (outside.levels & outside.driven))
            }
            // Input only: the pins as the outside leaves them.
            PortId::P7 => {
                let outside = pins.board.port_pins(id, now);
                outside.levels & outside.driven
            }
            _ => {
                let outside = pins.board.port_pins(id, now);
                p.read_dr(self.levels(id, outside)) | !id.pins()
            }
        }
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
        match PortId::of_register(addr) {
            Some((_, PortReg::Ddr)) => DDR_READ_VALUE,
            Some((id, PortReg::Dr)) => self.read_dr(id, now, pins),
            Some((id, PortReg::Pcr)) => self.port(id).pcr | !id.pins(),
            None => 0,
        }
    }

    #[inline]
    fn write<B: Board>(&mut self, addr: u32, value: u8, now: u64, pins: PortPins<'_, B>) {
        let Some((id, reg)) = PortId::of_register(addr) else {
            return;
        };
        let p = &mut self.ports[id.index()];
        match reg {
            PortReg::Ddr => p.ddr = value,
            PortReg::Dr => p.dr = value,
            PortReg::Pcr => p.pcr = value,
        }
        if id == PortId::P4 && reg != PortReg::Pcr {
            pins.board.port4_drive(p.driven_low(), now);
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
