//! The H8/3052F's on-chip I/O area as a table: every address from H'FFFF1C to H'FFFFFF, the
//! register there and the module it belongs to, or *reserved* (H8/3052F hardware manual,
//! Appendix B.1 "Addresses": the register list in address order, which leaves the addresses
//! it does not list reserved; section 3, the memory map of mode 7: flash H'000000–H'07FFFF,
//! RAM H'FFDF10–H'FFFF0F, on-chip I/O H'FFFF1C–H'FFFFFF, nothing else).
//!
//! The chip ([`crate::mcu`]) models some modules and not others. Every access to an address
//! the chip does not model — a register of a module it does not model, a register it does not
//! model in a module it does, a reserved I/O address, an address outside the memory map — is
//! *reported*: the first access to each address, with the instant and, when the CPU tells the
//! chip (a break request, [`h8300h::bus::BREAK_REQUEST`]), the instruction that made it
//! ([`crate::mcu::IoReport`]). Such an access still behaves as before: an I/O read returns 0,
//! a read outside the map H'FF, writes are ignored.
//!
//! The table is transcribed from the manual's register list; the names are the manual's (a
//! word register's bytes by their byte names, MAR0AR–MAR0AL, ETCR0AH/ETCR0AL). The flash
//! memory's control registers (H'FFFF40–H'FFFF47) are named as the F-ZTAT single-power flash
//! documents them (FLMCR1, FLMCR2, EBR1, EBR2, RAMER); only their names in a report depend on
//! that.

use h8300h::memmap::{IO_END, IO_START};

/// An on-chip module of the H8/3052F that owns registers in the I/O area.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Unit {
    /// The DMA controller (section 8).
    Dmac,
    /// The flash memory's program/erase control (the ROM section).
    Flash,
    /// The clock pulse generator's division control (DIVCR).
    Clock,
    /// The power-down modes' module standby control (MSTCR).
    PowerDown,
    /// The bus controller (section 6: ABWCR, ASTCR, WCR, WCER, BRCR, CSCR).
    BusController,
    /// The operating modes (section 3: MDCR).
    Modes,
    /// The 16-bit integrated timer unit (section 10).
    Itu,
    /// The programmable timing pattern controller (section 11).
    Tpc,
    /// The watchdog timer (section 12).
    Wdt,
    /// The refresh controller (section 7).
    Refresh,
    /// Serial communication interface channel 0 (section 13).
    Sci0,
    /// Serial communication interface channel 1 (section 13): the console.
    Sci1,
    /// The I/O ports (section 9).
    Ports,
    /// The D/A converter.
    Da,
    /// The A/D converter.
    Ad,
    /// The interrupt controller (section 5) with the system control register.
    Intc,
}

impl Unit {
    /// The module's short name, as the manual abbreviates it.
    #[must_use]
    pub const fn short(self) -> &'static str {
        match self {
            Unit::Dmac => "DMAC",
            Unit::Flash => "flash",
            Unit::Clock => "CPG",
            Unit::PowerDown => "power-down",
            Unit::BusController => "BSC",
            Unit::Modes => "modes",
            Unit::Itu => "ITU",
            Unit::Tpc => "TPC",
            Unit::Wdt => "WDT",
            Unit::Refresh => "refresh",
            Unit::Sci0 => "SCI0",
            Unit::Sci1 => "SCI1",
            Unit::Ports => "ports",
            Unit::Da => "D/A",
            Unit::Ad => "A/D",
            Unit::Intc => "INTC",
        }
    }

    /// The module's name in words.
    #[must_use]
    pub const fn title(self) -> &'static str {
        match self {
            Unit::Dmac => "the DMA controller",
            Unit::Flash => "the flash memory's program/erase control",
            Unit::Clock => "the clock pulse generator",
            Unit::PowerDown => "the power-down modes (module standby)",
            Unit::BusController => "the bus controller",
            Unit::Modes => "the operating modes",
            Unit::Itu => "the 16-bit integrated timer unit",
            Unit::Tpc => "the programmable timing pattern controller",
            Unit::Wdt => "the watchdog timer",
            Unit::Refresh => "the refresh controller",
            Unit::Sci0 => "serial channel 0",
            Unit::Sci1 => "serial channel 1",
            Unit::Ports => "the I/O ports",
            Unit::Da => "the D/A converter",
            Unit::Ad => "the A/D converter",
            Unit::Intc => "the interrupt controller",
        }
    }
}

/// One register of the I/O area.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Register {
    /// Its address (24 bits).
    pub addr: u32,
    /// Its name in the manual.
    pub name: &'static str,
    /// The module it belongs to.
    pub unit: Unit,
}

/// Shorthand for the table.
const fn r(low: u32, name: &'static str, unit: Unit) -> Register {
    Register {
        addr: 0xFF_FF00 | low,
        name,
        unit,
    }
}

/// Every register of the I/O area, in address order (Appendix B.1). The addresses between
/// them are reserved.
pub const REGISTERS: &[Register] = &[
    // DMAC, channel 0A/0B and 1A/1B (short and full address modes share the registers).
    r(0x20, "MAR0AR", Unit::Dmac),
    r(0x21, "MAR0AE", Unit::Dmac),
    r(0x22, "MAR0AH", Unit::Dmac),
    r(0x23, "MAR0AL", Unit::Dmac),
    r(0x24, "ETCR0AH", Unit::Dmac),
    r(0x25, "ETCR0AL", Unit::Dmac),
    r(0x26, "IOAR0A", Unit::Dmac),
    r(0x27, "DTCR0A", Unit::Dmac),
    r(0x28, "MAR0BR", Unit::Dmac),
    r(0x29, "MAR0BE", Unit::Dmac),
    r(0x2A, "MAR0BH", Unit::Dmac),
    r(0x2B, "MAR0BL", Unit::Dmac),
    r(0x2C, "ETCR0BH", Unit::Dmac),
    r(0x2D, "ETCR0BL", Unit::Dmac),
    r(0x2E, "IOAR0B", Unit::Dmac),
    r(0x2F, "DTCR0B", Unit::Dmac),
    r(0x30, "MAR1AR", Unit::Dmac),
    r(0x31, "MAR1AE", Unit::Dmac),
    r(0x32, "MAR1AH", Unit::Dmac),
    r(0x33, "MAR1AL", Unit::Dmac),
    r(0x34, "ETCR1AH", Unit::Dmac),
    r(0x35, "ETCR1AL", Unit::Dmac),
    r(0x36, "IOAR1A", Unit::Dmac),
    r(0x37, "DTCR1A", Unit::Dmac),
    r(0x38, "MAR1BR", Unit::Dmac),
    r(0x39, "MAR1BE", Unit::Dmac),
    r(0x3A, "MAR1BH", Unit::Dmac),
    r(0x3B, "MAR1BL", Unit::Dmac),
    r(0x3C, "ETCR1BH", Unit::Dmac),
    r(0x3D, "ETCR1BL", Unit::Dmac),
    r(0x3E, "IOAR1B", Unit::Dmac),
    r(0x3F, "DTCR1B", Unit::Dmac),
    // Flash memory control.
    r(0x40, "FLMCR1", Unit::Flash),
    r(0x41, "FLMCR2", Unit::Flash),
    r(0x42, "EBR1", Unit::Flash),
    r(0x43, "EBR2", Unit::Flash),
    r(0x47, "RAMER", Unit::Flash),
    // D/A standby, division, module standby, chip select.
    r(0x5C, "DASTCR", Unit::Da),
    r(0x5D, "DIVCR", Unit::Clock),
    r(0x5E, "MSTCR", Unit::PowerDown),
    r(0x5F, "CSCR", Unit::BusController),
    // ITU: shared registers, channels 0–4.
    r(0x60, "TSTR", Unit::Itu),
    r(0x61, "TSNC", Unit::Itu),
    r(0x62, "TMDR", Unit::Itu),
    r(0x63, "TFCR", Unit::Itu),
    r(0x64, "TCR0", Unit::Itu),
    r(0x65, "TIOR0", Unit::Itu),
    r(0x66, "TIER0", Unit::Itu),
    r(0x67, "TSR0", Unit::Itu),
    r(0x68, "TCNT0H", Unit::Itu),
    r(0x69, "TCNT0L", Unit::Itu),
    r(0x6A, "GRA0H", Unit::Itu),
    r(0x6B, "GRA0L", Unit::Itu),
    r(0x6C, "GRB0H", Unit::Itu),
    r(0x6D, "GRB0L", Unit::Itu),
    r(0x6E, "TCR1", Unit::Itu),
    r(0x6F, "TIOR1", Unit::Itu),
    r(0x70, "TIER1", Unit::Itu),
    r(0x71, "TSR1", Unit::Itu),
    r(0x72, "TCNT1H", Unit::Itu),
    r(0x73, "TCNT1L", Unit::Itu),
    r(0x74, "GRA1H", Unit::Itu),
    r(0x75, "GRA1L", Unit::Itu),
    r(0x76, "GRB1H", Unit::Itu),
    r(0x77, "GRB1L", Unit::Itu),
    r(0x78, "TCR2", Unit::Itu),
    r(0x79, "TIOR2", Unit::Itu),
    r(0x7A, "TIER2", Unit::Itu),
    r(0x7B, "TSR2", Unit::Itu),
    r(0x7C, "TCNT2H", Unit::Itu),
    r(0x7D, "TCNT2L", Unit::Itu),
    r(0x7E, "GRA2H", Unit::Itu),
    r(0x7F, "GRA2L", Unit::Itu),
    r(0x80, "GRB2H", Unit::Itu),
    r(0x81, "GRB2L", Unit::Itu),
    r(0x82, "TCR3", Unit::Itu),
    r(0x83, "TIOR3", Unit::Itu),
    r(0x84, "TIER3", Unit::Itu),
    r(0x85, "TSR3", Unit::Itu),
    r(0x86, "TCNT3H", Unit::Itu),
    r(0x87, "TCNT3L", Unit::Itu),
    r(0x88, "GRA3H", Unit::Itu),
    r(0x89, "GRA3L", Unit::Itu),
    r(0x8A, "GRB3H", Unit::Itu),
    r(0x8B, "GRB3L", Unit::Itu),
    r(0x8C, "BRA3H", Unit::Itu),
    r(0x8D, "BRA3L", Unit::Itu),
    r(0x8E, "BRB3H", Unit::Itu),
    r(0x8F, "BRB3L", Unit::Itu),
    r(0x90, "TOER", Unit::Itu),
    r(0x91, "TOCR", Unit::Itu),
    r(0x92, "TCR4", Unit::Itu),
    r(0x93, "TIOR4", Unit::Itu),
    r(0x94, "TIER4", Unit::Itu),
    r(0x95, "TSR4", Unit::Itu),
    r(0x96, "TCNT4H", Unit::Itu),
    r(0x97, "TCNT4L", Unit::Itu),
    r(0x98, "GRA4H", Unit::Itu),
    r(0x99, "GRA4L", Unit::Itu),
    r(0x9A, "GRB4H", Unit::Itu),
    r(0x9B, "GRB4L", Unit::Itu),
    r(0x9C, "BRA4H", Unit::Itu),
    r(0x9D, "BRA4L", Unit::Itu),
    r(0x9E, "BRB4H", Unit::Itu),
    r(0x9F, "BRB4L", Unit::Itu),
    // TPC (NDRA/NDRB have two addresses each, by the output groups' triggers).
    r(0xA0, "TPMR", Unit::Tpc),
    r(0xA1, "TPCR", Unit::Tpc),
    r(0xA2, "NDERB", Unit::Tpc),
    r(0xA3, "NDERA", Unit::Tpc),
    r(0xA4, "NDRB", Unit::Tpc),
    r(0xA5, "NDRA", Unit::Tpc),
    r(0xA6, "NDRB", Unit::Tpc),
    r(0xA7, "NDRA", Unit::Tpc),
    // WDT (write addresses H'FFA8 for TCSR/TCNT and H'FFAA for RSTCSR; read addresses
    // H'FFA8 TCSR, H'FFA9 TCNT, H'FFAB RSTCSR).
    r(0xA8, "TCSR", Unit::Wdt),
    r(0xA9, "TCNT", Unit::Wdt),
    r(0xAA, "RSTCSR (write)", Unit::Wdt),
    r(0xAB, "RSTCSR", Unit::Wdt),
    // Refresh controller.
    r(0xAC, "RFSHCR", Unit::Refresh),
    r(0xAD, "RTMCSR", Unit::Refresh),
    r(0xAE, "RTCNT", Unit::Refresh),
    r(0xAF, "RTCOR", Unit::Refresh),
    // SCI0 and SCI1 (SCMR: the smart card mode register).
    r(0xB0, "SMR0", Unit::Sci0),
    r(0xB1, "BRR0", Unit::Sci0),
    r(0xB2, "SCR0", Unit::Sci0),
    r(0xB3, "TDR0", Unit::Sci0),
    r(0xB4, "SSR0", Unit::Sci0),
    r(0xB5, "RDR0", Unit::Sci0),
    r(0xB6, "SCMR0", Unit::Sci0),
    r(0xB8, "SMR1", Unit::Sci1),
    r(0xB9, "BRR1", Unit::Sci1),
    r(0xBA, "SCR1", Unit::Sci1),
    r(0xBB, "TDR1", Unit::Sci1),
    r(0xBC, "SSR1", Unit::Sci1),
    r(0xBD, "RDR1", Unit::Sci1),
    r(0xBE, "SCMR1", Unit::Sci1),
    // Ports 1–9, A, B.
    r(0xC0, "P1DDR", Unit::Ports),
    r(0xC1, "P2DDR", Unit::Ports),
    r(0xC2, "P1DR", Unit::Ports),
    r(0xC3, "P2DR", Unit::Ports),
    r(0xC4, "P3DDR", Unit::Ports),
    r(0xC5, "P4DDR", Unit::Ports),
    r(0xC6, "P3DR", Unit::Ports),
    r(0xC7, "P4DR", Unit::Ports),
    r(0xC8, "P5DDR", Unit::Ports),
    r(0xC9, "P6DDR", Unit::Ports),
    r(0xCA, "P5DR", Unit::Ports),
    r(0xCB, "P6DR", Unit::Ports),
    r(0xCD, "P8DDR", Unit::Ports),
    r(0xCE, "P7DR", Unit::Ports),
    r(0xCF, "P8DR", Unit::Ports),
    r(0xD0, "P9DDR", Unit::Ports),
    r(0xD1, "PADDR", Unit::Ports),
    r(0xD2, "P9DR", Unit::Ports),
    r(0xD3, "PADR", Unit::Ports),
    r(0xD4, "PBDDR", Unit::Ports),
    r(0xD6, "PBDR", Unit::Ports),
    r(0xD8, "P2PCR", Unit::Ports),
    r(0xDA, "P4PCR", Unit::Ports),
    r(0xDB, "P5PCR", Unit::Ports),
    // D/A.
    r(0xDC, "DADR0", Unit::Da),
    r(0xDD, "DADR1", Unit::Da),
    r(0xDE, "DACR", Unit::Da),
    // A/D.
    r(0xE0, "ADDRAH", Unit::Ad),
    r(0xE1, "ADDRAL", Unit::Ad),
    r(0xE2, "ADDRBH", Unit::Ad),
    r(0xE3, "ADDRBL", Unit::Ad),
    r(0xE4, "ADDRCH", Unit::Ad),
    r(0xE5, "ADDRCL", Unit::Ad),
    r(0xE6, "ADDRDH", Unit::Ad),
    r(0xE7, "ADDRDL", Unit::Ad),
    r(0xE8, "ADCSR", Unit::Ad),
    r(0xE9, "ADCR", Unit::Ad),
    // Bus controller, mode control, system control, interrupt controller.
    r(0xEC, "ABWCR", Unit::BusController),
    r(0xED, "ASTCR", Unit::BusController),
    r(0xEE, "WCR", Unit::BusController),
    r(0xEF, "WCER", Unit::BusController),
    r(0xF1, "MDCR", Unit::Modes),
    r(0xF2, "SYSCR", Unit::Intc),
    r(0xF3, "BRCR", Unit::BusController),
    r(0xF4, "ISCR", Unit::Intc),
    r(0xF5, "IER", Unit::Intc),
    r(0xF6, "ISR", Unit::Intc),
    r(0xF8, "IPRA", Unit::Intc),
    r(0xF9, "IPRB", Unit::Intc),
];

/// What lies at an I/O address.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IoSlot {
    /// A register.
    Register(&'static Register),
    /// A reserved address of the I/O area.
    Reserved,
}

/// The register at `addr` (24 bits) of the I/O area, or `None` for a reserved address or one
/// outside the I/O area.
#[must_use]
pub fn register_at(addr: u32) -> Option<&'static Register> {
    if !(IO_START..=IO_END).contains(&addr) {
        return None;
    }
    REGISTERS
        .binary_search_by_key(&addr, |r| r.addr)
        .ok()
        .map(|i| &REGISTERS[i])
}

/// The register called `name` (the manual's name, case-insensitive), if the I/O area has one
/// (the first of NDRA's/NDRB's two addresses).
#[must_use]
pub fn register_named(name: &str) -> Option<&'static Register> {
    REGISTERS.iter().find(|r| r.name.eq_ignore_ascii_case(name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_in_address_order_inside_the_io_area() {
        for w in REGISTERS.windows(2) {
            assert!(w[0].addr < w[1].addr, "{} before {}", w[0].name, w[1].name);
        }
        assert!(
            REGISTERS
                .iter()
                .all(|r| (IO_START..=IO_END).contains(&r.addr))
        );
    }

    #[test]
    fn registers_and_reserved_addresses_are_found() {
        assert_eq!(register_at(0xFF_FF20).map(|r| r.name), Some("MAR0AR"));
        assert_eq!(register_at(0xFF_FF20).map(|r| r.unit), Some(Unit::Dmac));
        assert_eq!(register_at(0xFF_FFA8).map(|r| r.unit), Some(Unit::Wdt));
        assert_eq!(register_at(0xFF_FFF9).map(|r| r.name), Some("IPRB"));
        // Reserved: before the DMAC, between blocks, after IPRB; outside the I/O area.
        for a in [
            0xFF_FF1C, 0xFF_FF44, 0xFF_FF50, 0xFF_FFCC, 0xFF_FFF7, 0xFF_FFFF, 0xFF_FF10,
        ] {
            assert_eq!(register_at(a), None, "H'{a:06X}");
        }
        assert_eq!(register_named("p9dr").map(|r| r.addr), Some(0xFF_FFD2));
        assert_eq!(register_named("nope"), None);
    }
}
