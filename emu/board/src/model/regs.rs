//! The H8/3052F registers the controller programs (docs/design.md §3.2, §4.1; H8/3052F hardware manual,
//! register tables of the A/D converter, the ITU and the I/O ports) and the bit patterns it
//! writes.

/// A/D data register A, high byte (bits 9..2 of AN0's result; docs/design.md §3.2: H'FFFFE0).
pub const ADDRAH: u32 = 0xFF_FFE0;
/// A/D control/status register (docs/design.md §3.2: H'FFFFE8).
pub const ADCSR: u32 = 0xFF_FFE8;
/// ADCSR bit 7: A/D end flag.
pub const ADCSR_ADF: u8 = 0x80;
/// ADCSR bit 5: A/D start.
pub const ADCSR_ADST: u8 = 0x20;
/// ADCSR bit 4: scan mode.
pub const ADCSR_SCAN: u8 = 0x10;
/// ADCSR bit 3: clock select, 1 = 134 states per conversion.
pub const ADCSR_CKS: u8 = 0x08;

/// Timer start register (docs/design.md §4.1: H'FFFF60).
pub const TSTR: u32 = 0xFF_FF60;
/// Timer mode register (PWM mode bits of the channels).
pub const TMDR: u32 = 0xFF_FF62;
/// ITU0 base (docs/design.md §4.1: H'FFFF64).
pub const ITU0: u32 = 0xFF_FF64;
/// ITU1 base (docs/design.md §4.1: H'FFFF6E).
pub const ITU1: u32 = 0xFF_FF6E;
/// ITU2 base (docs/design.md §4.1: H'FFFF78).
pub const ITU2: u32 = 0xFF_FF78;
/// Offset of TCR from a channel's base.
pub const TCR: u32 = 0;
/// Offset of TIER.
pub const TIER: u32 = 2;
/// Offset of TSR.
pub const TSR: u32 = 3;
/// Offset of GRA (word).
pub const GRA: u32 = 6;
/// Offset of GRB (word).
pub const GRB: u32 = 8;
/// TCR: counter cleared by GRA compare match (CCLR = 01), rising edge, φ/8 (TPSC = 011).
pub const TCR_CLEAR_ON_GRA_PHI8: u8 = 0b0010_0011;
/// TIER / TSR bit 0: compare match A (IMIEA / IMFA).
pub const IMA: u8 = 0x01;
/// The prescaler the controller uses for every channel: φ/8 (0.32 µs per count at 25 MHz,
/// docs/design.md §3.5).
pub const PRESCALE: u64 = 8;
/// ITU0 compare-match A interrupt vector (docs/design.md §4.1: vector 24).
pub const VECTOR_IMIA0: u8 = 24;

/// Port 4 data direction register (write-only; docs/design.md §4.1: H'FFFFC5).
pub const P4DDR: u32 = 0xFF_FFC5;
/// Port 4 data register (docs/design.md §4.1: H'FFFFC7).
pub const P4DR: u32 = 0xFF_FFC7;
/// Port 2 input pull-up control register (H'FFFFD8): bits 0-3 turn on the bumpers' pull-ups.
pub const P2PCR: u32 = 0xFF_FFD8;
/// Port 4 input pull-up control register (docs/design.md §4.1: H'FFFFDA); bits 7 and 6 turn on the
/// pull-ups of SDA and SCL, which are the only thing that takes a released line high.
pub const P4PCR: u32 = 0xFF_FFDA;
/// Port B data direction register (write-only).
pub const PBDDR: u32 = 0xFF_FFD4;
/// Port B data register.
pub const PBDR: u32 = 0xFF_FFD6;
/// P4.7: SDA (docs/design.md §3.6).
pub const SDA_BIT: u8 = 0x80;
/// P4.6: SCL (docs/design.md §3.6).
pub const SCL_BIT: u8 = 0x40;
