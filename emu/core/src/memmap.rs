//! The H8/3052F memory map in advanced mode (docs/design.md §4.1) and the access states of each area.
//!
//! Every bus access is charged by the area it touches: the H8/300H manual's rule
//! `states = I·S_I + J·S_J + K·S_K + L·S_L + M·S_M + N·S_N` multiplies each access count by
//! the states of one access *to the area it goes to*. This module is the single place that
//! says what those per-area figures are.

/// Address bus width in advanced mode: 24 bits (H8/3052F hardware manual, §2 "Address space").
pub const ADDRESS_MASK: u32 = 0x00FF_FFFF;

/// First address of the exception vector table (reset = vector 0, 4 bytes per vector).
pub const VECTORS_START: u32 = 0x00_0000;
/// Number of vectors of the H8/3052F (docs/design.md §4.1: 61 × 4 bytes, H'000000–H'0000F3).
pub const VECTOR_COUNT: u32 = 61;

/// First byte of the 512 KB on-chip flash (docs/design.md §4.1).
pub const ROM_START: u32 = 0x00_0000;
/// Last byte of the on-chip flash (docs/design.md §4.1).
pub const ROM_END: u32 = 0x07_FFFF;
/// Size of the on-chip flash in bytes.
pub const ROM_BYTES: u32 = ROM_END - ROM_START + 1;

/// First byte of the 8 KB on-chip RAM (docs/design.md §4.1).
pub const RAM_START: u32 = 0xFF_DF10;
/// Last byte of the on-chip RAM (docs/design.md §4.1).
pub const RAM_END: u32 = 0xFF_FF0F;
/// Size of the on-chip RAM in bytes (8 192).
pub const RAM_BYTES: u32 = RAM_END - RAM_START + 1;

/// First byte of the on-chip I/O registers (docs/design.md §4.1).
pub const IO_START: u32 = 0xFF_FF1C;
/// Last byte of the on-chip I/O registers (docs/design.md §4.1).
pub const IO_END: u32 = 0xFF_FFFF;

/// States of one access to on-chip flash: 2, over a 16-bit bus (docs/design.md §4.1).
pub const ROM_ACCESS_STATES: u32 = 2;
/// States of one access to on-chip RAM: 2, over a 16-bit bus (docs/design.md §4.1).
pub const RAM_ACCESS_STATES: u32 = 2;
/// States of one access to on-chip I/O: 3, over an 8-bit bus. docs/design.md §4.1 marks this figure as an
/// assumption not confirmed from the manual; it is kept in this one constant on purpose.
pub const IO_ACCESS_STATES: u32 = 3;

/// The areas of the address space.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Area {
    /// On-chip flash (program, constants, vectors).
    Rom,
    /// On-chip RAM.
    Ram,
    /// On-chip I/O registers.
    Io,
    /// Nothing is there in single-chip advanced mode.
    Unmapped,
}

impl Area {
    /// The area that holds `addr` (only the low 24 bits count).
    ///
    /// ```
    /// use h8300h::memmap::Area;
    /// assert_eq!(Area::of(0x00_0100), Area::Rom);
    /// assert_eq!(Area::of(0xFF_E000), Area::Ram);
    /// assert_eq!(Area::of(0xFF_FFB8), Area::Io);
    /// assert_eq!(Area::of(0x10_0000), Area::Unmapped);
    /// // An access's states: a word from RAM one 2-state cycle, from I/O two 3-state ones.
    /// assert_eq!((Area::Ram.word_states(), Area::Io.word_states()), (2, 6));
    /// ```
    #[must_use]
    pub const fn of(addr: u32) -> Area {
        let a = addr & ADDRESS_MASK;
        if a <= ROM_END {
            Area::Rom
        } else if a >= RAM_START && a <= RAM_END {
            Area::Ram
        } else if a >= IO_START {
            Area::Io
        } else {
            Area::Unmapped
        }
    }

    /// Width of the area's data bus in bits.
    #[must_use]
    pub const fn bus_bits(self) -> u32 {
        match self {
            Area::Rom | Area::Ram => 16,
            Area::Io | Area::Unmapped => 8,
        }
    }

    /// States of one bus cycle to this area. Unmapped addresses are charged like I/O (an
    /// 8-bit, 3-state cycle): the chip still runs a bus cycle even though nothing answers.
    #[must_use]
    pub const fn cycle_states(self) -> u32 {
        match self {
            Area::Rom => ROM_ACCESS_STATES,
            Area::Ram => RAM_ACCESS_STATES,
            Area::Io | Area::Unmapped => IO_ACCESS_STATES,
        }
    }

    /// States of one byte access to this area.
    #[must_use]
    pub const fn byte_states(self) -> u32 {
        self.cycle_states()
    }

    /// States of one word access to this area: one cycle on a 16-bit bus, two on an 8-bit bus.
    #[must_use]
    pub const fn word_states(self) -> u32 {
        if self.bus_bits() == 16 {
            self.cycle_states()
        } else {
            2 * self.cycle_states()
        }
    }

    /// Whether instructions may be fetched from this area (docs/design.md §7: only ROM and RAM).
    #[must_use]
    pub const fn executable(self) -> bool {
        matches!(self, Area::Rom | Area::Ram)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn areas_match_the_spec_table() {
        assert_eq!(Area::of(0x00_0000), Area::Rom);
        assert_eq!(Area::of(0x07_FFFF), Area::Rom);
        assert_eq!(Area::of(0x08_0000), Area::Unmapped);
        assert_eq!(Area::of(0xFF_DF0F), Area::Unmapped);
        assert_eq!(Area::of(0xFF_DF10), Area::Ram);
        assert_eq!(Area::of(0xFF_FF0F), Area::Ram);
        assert_eq!(Area::of(0xFF_FF10), Area::Unmapped);
        assert_eq!(Area::of(0xFF_FF1C), Area::Io);
        assert_eq!(Area::of(0xFF_FFFF), Area::Io);
        // Only 24 address lines: the top byte of a 32-bit pointer is ignored.
        assert_eq!(Area::of(0xABFF_DF10), Area::Ram);
        assert_eq!(RAM_BYTES, 8192);
        assert_eq!(ROM_BYTES, 512 * 1024);
    }

    #[test]
    fn word_access_to_the_8_bit_io_bus_takes_two_cycles() {
        assert_eq!(Area::Ram.word_states(), 2);
        assert_eq!(Area::Rom.word_states(), 2);
        assert_eq!(Area::Io.byte_states(), 3);
        assert_eq!(Area::Io.word_states(), 6);
    }
}
