//! Figures from the Microchip 24AA256/24LC256/24FC256 datasheet (DS21203, revisions T–X), and
//! the few modelling bounds this crate adds to them.
//!
//! The robot runs its chips at 5 V, so every timing figure is the datasheet's
//! "2.5 V ≤ VCC ≤ 5.5 V" column of Table 1-2 (AC characteristics) unless it says otherwise. The
//! 100 kHz figures of [`standard`] are the "1.7 V ≤ VCC < 2.5 V" column, which equal the I²C
//! standard-mode limits; a master that meets them also meets the 5 V ones.

/// Size of the array: 256 Kbit = 32 768 bytes (DS21203, "Description").
pub const ARRAY_BYTES: usize = 32_768;
/// Highest memory address, H'7FFF; address bit 15 is "don't care" (DS21203 §5.1, Figure 5-2).
pub const MAX_MEMORY_ADDRESS: u16 = 0x7FFF;
/// Page-write buffer size: 64 bytes (DS21203 §6.2 "Page Write").
pub const PAGE_BYTES: usize = 64;
/// Number of 64-byte pages in the array (32 768 / 64).
pub const PAGES: usize = ARRAY_BYTES / PAGE_BYTES;
/// Value of an erased EEPROM byte; a new chip reads all 0xFF (DS21203: "erased" state).
pub const ERASED_BYTE: u8 = 0xFF;
/// Control code in the four high bits of the control byte: `1010` (DS21203 §5.0, Figure 5-1).
pub const CONTROL_CODE: u8 = 0b1010;
/// Lowest 7-bit bus address a 24LC256 can take: control code 1010 with A2..A0 = 000.
pub const FIRST_DEVICE_ADDRESS: u8 = 0x50;
/// Highest 7-bit bus address a 24LC256 can take: control code 1010 with A2..A0 = 111.
pub const LAST_DEVICE_ADDRESS: u8 = 0x57;

/// F_CLK: maximum SCL clock frequency, 400 kHz (DS21203 Table 1-2, param. 1).
pub const F_CLK_MAX_HZ: u64 = 400_000;
/// T_HIGH: minimum SCL high time, 600 ns (DS21203 Table 1-2, param. 2).
pub const T_HIGH_MIN_NS: u64 = 600;
/// T_LOW: minimum SCL low time, 1 300 ns (DS21203 Table 1-2, param. 3).
pub const T_LOW_MIN_NS: u64 = 1_300;
/// T_R: maximum SDA/SCL rise time, 300 ns (DS21203 Table 1-2, param. 4). Not modelled: the lines
/// here switch instantly; see the crate docs.
pub const T_R_MAX_NS: u64 = 300;
/// T_F: maximum SDA/SCL fall time, 300 ns (DS21203 Table 1-2, param. 5). Not modelled.
pub const T_F_MAX_NS: u64 = 300;
/// T_HD:STA: minimum START hold time (SDA fall to SCL fall), 600 ns (DS21203 Table 1-2, param. 6).
pub const T_HD_STA_MIN_NS: u64 = 600;
/// T_SU:STA: minimum (repeated) START setup time (SCL rise to SDA fall), 600 ns (DS21203
/// Table 1-2, param. 7).
pub const T_SU_STA_MIN_NS: u64 = 600;
/// T_HD:DAT: minimum data input hold time, 0 ns (DS21203 Table 1-2, param. 8).
pub const T_HD_DAT_MIN_NS: u64 = 0;
/// T_SU:DAT: minimum data input setup time (SDA change to SCL rise), 100 ns (DS21203 Table 1-2,
/// param. 9).
pub const T_SU_DAT_MIN_NS: u64 = 100;
/// T_SU:STO: minimum STOP setup time (SCL rise to SDA rise), 600 ns (DS21203 Table 1-2, param. 10).
pub const T_SU_STO_MIN_NS: u64 = 600;
/// T_AA: maximum delay from SCL falling to valid data out, 900 ns (DS21203 Table 1-2, param. 13).
pub const T_AA_MAX_NS: u64 = 900;
/// Minimum internal delay of the device's SDA output after SCL falls, 300 ns, which bridges the
/// undefined region of the SCL falling edge (DS21203 Table 1-2, Note 2).
pub const T_OUTPUT_DELAY_MIN_NS: u64 = 300;
/// T_BUF: minimum bus free time between a STOP and the next START, 1 300 ns (DS21203 Table 1-2,
/// param. 14).
pub const T_BUF_MIN_NS: u64 = 1_300;
/// T_SP: input spike suppression, 50 ns (DS21203 Table 1-2, param. 16). Not modelled: lines here
/// have no glitches shorter than one MCU state unless the master makes them.
pub const T_SP_MAX_NS: u64 = 50;
/// T_WC: maximum write cycle time (byte or page), 5 ms (DS21203 Table 1-2, param. 17).
pub const T_WC_MAX_NS: u64 = 5_000_000;
/// Lower bound of the modelled write cycle time, 3 ms. Not a datasheet figure (it gives only the
/// 5 ms maximum): docs/design.md §3.6 says "model 3–5 ms".
pub const T_WC_MODEL_MIN_NS: u64 = 3_000_000;
/// Endurance: 1 000 000 write cycles per page at 25 °C, 5.5 V, page mode; "not tested but
/// ensured by characterization" (DS21203 Table 1-2, param. 18 and Note 4).
pub const ENDURANCE_CYCLES: u32 = 1_000_000;

/// I_CC read: operating current while the chip is clocked for a read, 400 µA maximum at
/// VCC = 5.5 V, SCL = 400 kHz (DS21203 Table 1-1, DC characteristics, "I_CC Read"). The
/// datasheet gives no typical value.
pub const ICC_READ_MAX_UA: f64 = 400.0;
/// I_CC write: operating current during a write (the internally timed write cycle), 3 mA
/// maximum at VCC = 5.5 V (DS21203 Table 1-1, DC characteristics, "I_CC Write").
pub const ICC_WRITE_MAX_MA: f64 = 3.0;
/// I_CCS: standby current, 1 µA maximum at VCC = 5.5 V, SCL = SDA = VCC, industrial
/// temperature range (DS21203 Table 1-1, DC characteristics, "I_CCS").
pub const ICCS_STANDBY_MAX_UA: f64 = 1.0;
/// Charge the chip draws per SCL clock it takes part in, nC: I_CC read over the 400 kHz clock
/// it is specified at (400 µA × 2.5 µs). A CMOS chip's operating current grows with its clock,
/// so a slower master takes longer per clock at a proportionally smaller current: the charge
/// per clock stays.
pub const CHARGE_PER_CLOCK_NC: f64 = ICC_READ_MAX_UA / (F_CLK_MAX_HZ as f64) * 1e3;

/// The 100 kHz (I²C standard-mode) figures: DS21203 Table 1-2, "1.7 V ≤ VCC < 2.5 V" column.
pub mod standard {
    /// F_CLK: 100 kHz (DS21203 Table 1-2, param. 1, low-voltage column).
    pub const F_CLK_MAX_HZ: u64 = 100_000;
    /// T_HIGH: 4 000 ns (DS21203 Table 1-2, param. 2, low-voltage column).
    pub const T_HIGH_MIN_NS: u64 = 4_000;
    /// T_LOW: 4 700 ns (DS21203 Table 1-2, param. 3, low-voltage column).
    pub const T_LOW_MIN_NS: u64 = 4_700;
    /// T_HD:STA: 4 000 ns (DS21203 Table 1-2, param. 6, low-voltage column).
    pub const T_HD_STA_MIN_NS: u64 = 4_000;
    /// T_SU:STA: 4 700 ns (DS21203 Table 1-2, param. 7, low-voltage column).
    pub const T_SU_STA_MIN_NS: u64 = 4_700;
    /// T_SU:DAT: 250 ns (DS21203 Table 1-2, param. 9, low-voltage column).
    pub const T_SU_DAT_MIN_NS: u64 = 250;
    /// T_SU:STO: 4 000 ns (DS21203 Table 1-2, param. 10, low-voltage column).
    pub const T_SU_STO_MIN_NS: u64 = 4_000;
    /// T_BUF: 4 700 ns (DS21203 Table 1-2, param. 14, low-voltage column).
    pub const T_BUF_MIN_NS: u64 = 4_700;
}
