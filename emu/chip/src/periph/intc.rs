//! The interrupt controller of the H8/3052F: priority registers IPRA/IPRB and the choice of the
//! interrupt the CPU is offered (H8/3052F hardware manual, section 5 "Interrupt Controller").
//!
//! Every on-chip source requests its interrupt while its flag and its enable bit are both set
//! (the sources compute that themselves); this module only decides which request wins:
//!
//! 1. the requests whose source group has its IPR bit set (priority level 1) beat the others
//!    (level 0);
//! 2. within a level, the lower vector number wins (the manual's Table 5-3 lists the sources
//!    in their default priority order, which is the vector order).
//!
//! Requests are passed as a bit mask indexed by vector number (bit `v` = vector `v`
//! requested), so choosing is two mask operations and a trailing-zero count. A reset request
//! (bit 0, the watchdog's, [`h8300h::bus::RESET_REQUEST`]) and NMI (vector 7; no NMI pin is
//! wired here) beat every interrupt whatever the IPRs say; the CPU core handles masking by
//! CCR.I. The UI bit as a second mask (SYSCR.UE = 0) is not modelled (the core treats UI as a
//! user bit, SYSCR.UE = 1 after reset).
//!
//! Of the interrupt controller's registers (the manual's Table 5-2: SYSCR, ISCR, IER, ISR,
//! IPRA, IPRB at H'FFFFF2–H'FFFFF9) this module holds SYSCR, which reads back what was written
//! (reset H'0B), and IPRA/IPRB, which act as above; the IRQ registers ISCR, IER and ISR are
//! [`crate::periph::irq`]'s. The chip routes H'FFFFF2, F8 and F9 here; BRCR at H'FFFFF3 is the
//! bus controller's (not modelled) and H'FFFFF7 is reserved.

use super::Peripheral;
use crate::pins::Board;

/// Address of SYSCR, the system control register (docs/design.md §4.1: H'FFFFF2).
pub const SYSCR: u32 = 0xFF_FFF2;
/// Reset value of SYSCR in this model: H'0B (UE = 1, RAME = 1, STS = 000, SSBY = 0).
pub const SYSCR_RESET: u8 = 0x0B;

/// Address of IPRA, interrupt priority register A (H8/3052F hardware manual, appendix B
/// register map: H'FFFFF8).
pub const IPRA: u32 = 0xFF_FFF8;
/// Address of IPRB, interrupt priority register B (H'FFFFF9).
pub const IPRB: u32 = 0xFF_FFF9;

/// Reset value of IPRA and IPRB: every source at priority level 0.
pub const IPR_RESET: u8 = 0x00;

/// IPRA bit 7: IRQ0 (vector 12).
pub const IPRA_IRQ0: u8 = 0x80;
/// IPRA bit 6: IRQ1 (vector 13).
pub const IPRA_IRQ1: u8 = 0x40;
/// IPRA bit 5: IRQ2 and IRQ3 (vectors 14, 15).
pub const IPRA_IRQ23: u8 = 0x20;
/// IPRA bit 4: IRQ4 and IRQ5 (vectors 16, 17).
pub const IPRA_IRQ45: u8 = 0x10;
/// IPRA bit 3: watchdog timer (vector 20; 21 is kept with it).
pub const IPRA_WDT: u8 = 0x08;
/// IPRA bit 2: ITU channel 0 (vectors 24–26).
pub const IPRA_ITU0: u8 = 0x04;
/// IPRA bit 1: ITU channel 1 (vectors 28–30).
pub const IPRA_ITU1: u8 = 0x02;
/// IPRA bit 0: ITU channel 2 (vectors 32–34).
pub const IPRA_ITU2: u8 = 0x01;
/// IPRB bit 7: ITU channel 3 (vectors 36–38).
pub const IPRB_ITU3: u8 = 0x80;
/// IPRB bit 6: ITU channel 4 (vectors 40–42).
pub const IPRB_ITU4: u8 = 0x40;
/// IPRB bit 5: DMA controller (vectors 44–47).
pub const IPRB_DMAC: u8 = 0x20;
/// IPRB bit 3: SCI channel 0 (vectors 52–55).
pub const IPRB_SCI0: u8 = 0x08;
/// IPRB bit 2: SCI channel 1 (vectors 56–59).
pub const IPRB_SCI1: u8 = 0x04;
/// IPRB bit 1: A/D converter (vector 60).
pub const IPRB_AD: u8 = 0x02;

/// The requests that beat every interrupt: the reset request (bit 0) and NMI (vector 7).
const NON_MASKABLE: u64 = 1 | (1 << 7);

/// A mask with bits `first..=last` set (vectors as bit numbers).
const fn vectors(first: u32, last: u32) -> u64 {
    let width = last - first + 1;
    ((1u64 << width) - 1) << first
}

/// The vectors each IPRA bit (7 down to 0) raises to level 1.
const IPRA_GROUPS: [u64; 8] = [
    vectors(12, 12), // bit 7: IRQ0
    vectors(13, 13), // bit 6: IRQ1
    vectors(14, 15), // bit 5: IRQ2, IRQ3
    vectors(16, 17), // bit 4: IRQ4, IRQ5
    vectors(20, 21), // bit 3: WDT
    vectors(24, 27), // bit 2: ITU0
    vectors(28, 31), // bit 1: ITU1
    vectors(32, 35), // bit 0: ITU2
];

/// The vectors each IPRB bit (7 down to 0) raises to level 1 (bits 4 and 0 are reserved).
const IPRB_GROUPS: [u64; 8] = [
    vectors(36, 39), // bit 7: ITU3
    vectors(40, 43), // bit 6: ITU4
    vectors(44, 47), // bit 5: DMAC
    0,               // bit 4: reserved
    vectors(52, 55), // bit 3: SCI0
    vectors(56, 59), // bit 2: SCI1
    vectors(60, 60), // bit 1: A/D
    0,               // bit 0: reserved
];

/// SYSCR, IPRA/IPRB and the priority decision.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Intc {
    syscr: u8,
    ipra: u8,
    iprb: u8,
    /// Vectors at priority level 1, derived from IPRA/IPRB on every write.
    level1: u64,
}

impl Default for Intc {
    fn default() -> Self {
        Self::new()
    }
}

impl Intc {
    /// The controller after reset: every source at level 0, SYSCR = [`SYSCR_RESET`].
    #[must_use]
    pub const fn new() -> Self {
        Intc {
            syscr: SYSCR_RESET,
            ipra: IPR_RESET,
            iprb: IPR_RESET,
            level1: 0,
        }
    }

    /// Reads SYSCR, IPRA or IPRB (other addresses read 0). Every bit reads back as written.
    #[must_use]
    pub fn read(&self, addr: u32) -> u8 {
        match addr {
            SYSCR => self.syscr,
            IPRA => self.ipra,
            IPRB => self.iprb,
            _ => 0,
        }
    }

    /// Writes SYSCR, IPRA or IPRB (other addresses are ignored).
    pub fn write(&mut self, addr: u32, value: u8) {
        match addr {
            SYSCR => {
                self.syscr = value;
                return;
            }
            IPRA => self.ipra = value,
            IPRB => self.iprb = value,
            _ => return,
        }
        let mut level1 = 0;
        for bit in 0..8 {
            let m = 0x80u8 >> bit;
            if self.ipra & m != 0 {
                level1 |= IPRA_GROUPS[bit];
            }
            if self.iprb & m != 0 {
                level1 |= IPRB_GROUPS[bit];
            }
        }
        self.level1 = level1;
    }

    /// The priority level (0 or 1) of vector `vector`.
    #[must_use]
    pub fn level(&self, vector: u8) -> u8 {
        u8::from(vector < 64 && self.level1 & (1u64 << vector) != 0)
    }

    /// The winning vector among `requests` (bit `v` = vector `v` requested): a reset request
    /// (0) or NMI (7) if any, else the lowest vector at level 1 if any, else the lowest vector
    /// at level 0.
    #[inline]
    #[must_use]
    pub fn choose(&self, requests: u64) -> Option<u8> {
        let top = requests & NON_MASKABLE;
        let high = requests & self.level1;
        let pick = if top != 0 {
            top
        } else if high != 0 {
            high
        } else {
            requests
        };
        if pick == 0 {
            None
        } else {
            // trailing_zeros of a non-zero u64 is at most 63.
            Some(pick.trailing_zeros() as u8)
        }
    }
}

impl Peripheral for Intc {
    type Outside<'a, B: Board + 'a> = ();
    const FIRST: u32 = SYSCR;
    const LAST: u32 = IPRB;
    const AFFECTS_IRQ: bool = true;

    #[inline]
    fn read<B: Board>(&mut self, addr: u32, _now: u64, (): ()) -> u8 {
        Intc::read(self, addr)
    }

    #[inline]
    fn write<B: Board>(&mut self, addr: u32, value: u8, _now: u64, (): ()) {
        Intc::write(self, addr, value);
    }

    #[inline]
    fn sync<B: Board>(&mut self, _now: u64, (): ()) {}

    #[inline]
    fn next_event(&self, _now: u64) -> Option<u64> {
        None
    }

    /// The controller requests nothing itself: it chooses among the sources' requests
    /// ([`Intc::choose`]).
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
        *self = Intc::new();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lower_vector_wins_within_a_level() {
        let intc = Intc::new();
        let req = (1 << 60) | (1 << 28) | (1 << 58);
        assert_eq!(intc.choose(req), Some(28));
        assert_eq!(intc.choose(0), None);
    }

    #[test]
    fn level_one_beats_level_zero() {
        let mut intc = Intc::new();
        intc.write(IPRB, IPRB_AD);
        assert_eq!(intc.read(IPRB), IPRB_AD);
        let req = (1 << 60) | (1 << 24);
        assert_eq!(intc.choose(req), Some(60));
        assert_eq!(intc.level(60), 1);
        assert_eq!(intc.level(24), 0);
        intc.write(IPRA, IPRA_ITU0);
        assert_eq!(intc.choose(req), Some(24));
    }

    #[test]
    fn every_ipr_bit_maps_its_vectors() {
        let mut intc = Intc::new();
        intc.write(IPRA, IPRA_ITU1 | IPRA_IRQ23);
        for v in [14, 15, 28, 29, 30] {
            assert_eq!(intc.level(v), 1, "vector {v}");
        }
        for v in [12, 13, 16, 24, 32, 58, 60] {
            assert_eq!(intc.level(v), 0, "vector {v}");
        }
        intc.write(IPRB, IPRB_SCI1 | IPRB_ITU4);
        for v in [40, 41, 42, 56, 57, 58, 59] {
            assert_eq!(intc.level(v), 1, "vector {v}");
        }
        assert_eq!(intc.level(200), 0);
    }
}
