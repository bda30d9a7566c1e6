//! The watchdog timer (WDT) of the H8/3052F at register level (H8/3052F hardware manual,
//! section 12 "Watchdog Timer"; addresses from appendix B.1).
//!
//! # Registers (12.2)
//! - **TCNT** (read H'FFFFA9): an 8-bit up-counter of the clock CKS2–0 select. It counts while
//!   TCSR.TME = 1; clearing TME stops it and sets it to H'00 (12.2.1).
//! - **TCSR** (read H'FFFFA8): OVF (bit 7), WT/IT (6), TME (5), bits 4–3 reserved (read 1),
//!   CKS2–0 (12.2.2). Reset value H'18. CKS selects φ/2, φ/32, φ/64, φ/128, φ/256, φ/512,
//!   φ/2048 or φ/4096 ([`DIVIDER_SHIFT`]).
//! - **RSTCSR** (read H'FFFFAB): WRST (bit 7: the watchdog reset the chip), RSTOE (6: the
//!   reset is also output on the RESO pin), bits 5–0 reserved (read 1) (12.2.3). Reset value
//!   H'3F, by the RES pin only: the watchdog's own reset leaves it (with WRST set).
//!
//! # Writing: the password (12.2.4, Figures 12-2 and 12-3)
//! The three registers are written only by a **word** write, whose upper byte is a password:
//! at H'FFFFA8, H'5A writes the lower byte to TCNT and H'A5 to TCSR; at H'FFFFAA, H'A5 with a
//! lower byte whose bit 7 is 0 clears WRST, H'5A writes bit 6 of the lower byte to RSTOE. Byte
//! writes and words with another upper byte change nothing. A word access is one bus cycle
//! ([`WDT_WORD_ACCESS_STATES`]: the password and the data must arrive together, so the WDT is
//! taken to sit on the 16-bit internal bus like the ITU's 16-bit registers; not confirmed from
//! the manual's text, and kept in that one constant).
//!
//! # Counting
//! The prescaler runs freely from reset (as the ITU's, [`crate::periph::itu`]): with divider
//! 2^s, TCNT counts at the states that are multiples of 2^s. A write to TCNT takes effect at
//! the end of its bus cycle; the next count is the next multiple after it (a write wins over
//! an increment in the same cycle). Changing CKS while the counter runs counts on at the new
//! rate from the write (the manual says to stop the timer first; 12.5).
//!
//! # Overflow (12.3, Figures 12-4 to 12-7)
//! When TCNT goes from H'FF to H'00, OVF is set.
//! - **Interval timer mode** (WT/IT = 0): an interval interrupt WOVI (vector 20) is requested
//!   while OVF = 1; OVF is cleared by reading TCSR with OVF = 1 and then writing 0 to it (a
//!   TCSR write with bit 7 = 0). TCNT counts on.
//! - **Watchdog timer mode** (WT/IT = 1): the chip is reset internally. WRST is set at the
//!   overflow, and a reset is requested ([`h8300h::bus::RESET_REQUEST`]) from that instant; the
//!   internal reset signal lasts [`RESET_STATES`] = 518 states from the overflow (Figure
//!   12-4), after which the CPU starts from the reset vector. The reset returns every module to
//!   its reset state (TCSR to H'18, TCNT to H'00) but leaves RSTCSR. The RESO output (132
//!   states with RSTOE = 1) goes to a pin nothing is connected to on the robot.
//!
//! Modelled choices: the CPU takes the reset at the first instruction boundary at or after
//! the overflow (the instruction under way finishes; the reset still ends 518 states after the
//! overflow). While TME = 0 a TCNT write is ignored (the counter is held at H'00). A read of
//! H'FFFFAA (the write address of RSTCSR) returns H'FF.
//!
//! The WDT requests nothing and has no event while TME = 0, the state the robot firmware keeps
//! it in, so it costs the robot nothing.

use super::Peripheral;
use crate::pins::Board;
use h8300h::bus::RESET_REQUEST;

/// Address of TCSR (read) and of the password write of TCSR and TCNT (H'FFFFA8; 12.2.4).
pub const TCSR: u32 = 0xFF_FFA8;
/// Address of TCNT (read; H'FFFFA9).
pub const TCNT: u32 = 0xFF_FFA9;
/// Address of the password write of RSTCSR (H'FFFFAA).
pub const RSTCSR_WRITE: u32 = 0xFF_FFAA;
/// Address of RSTCSR (read; H'FFFFAB).
pub const RSTCSR: u32 = 0xFF_FFAB;

/// The password (upper byte of the word) that writes TCNT at [`TCSR`].
pub const PASSWORD_TCNT: u8 = 0x5A;
/// The password that writes TCSR at [`TCSR`], and clears WRST at [`RSTCSR_WRITE`].
pub const PASSWORD_TCSR: u8 = 0xA5;
/// The password that writes RSTOE at [`RSTCSR_WRITE`].
pub const PASSWORD_RSTOE: u8 = 0x5A;

/// TCSR bit 7: overflow flag.
pub const TCSR_OVF: u8 = 0x80;
/// TCSR bit 6: timer mode select (1: watchdog timer mode, 0: interval timer mode).
pub const TCSR_WT: u8 = 0x40;
/// TCSR bit 5: timer enable.
pub const TCSR_TME: u8 = 0x20;
/// TCSR bits 4–3: reserved, read as 1.
pub const TCSR_RESERVED: u8 = 0x18;
/// TCSR bits 2–0: clock select.
pub const TCSR_CKS: u8 = 0x07;
/// TCSR after reset (12.2.2).
pub const TCSR_RESET: u8 = 0x18;

/// RSTCSR bit 7: watchdog timer reset.
pub const RSTCSR_WRST: u8 = 0x80;
/// RSTCSR bit 6: reset output enable.
pub const RSTCSR_RSTOE: u8 = 0x40;
/// RSTCSR bits 5–0: reserved, read as 1.
pub const RSTCSR_RESERVED: u8 = 0x3F;
/// RSTCSR after a reset by the RES pin (12.2.3).
pub const RSTCSR_RESET: u8 = 0x3F;

/// The interval interrupt WOVI's vector (Table 5-3).
pub const VECTOR_WOVI: u8 = 20;

/// How long the watchdog's internal reset lasts, states from the overflow (Figure 12-4).
pub const RESET_STATES: u64 = 518;

/// States of a word access to the WDT: one cycle (see the module docs).
pub const WDT_WORD_ACCESS_STATES: u32 = 3;

/// log2 of the prescaler division CKS2–0 select: φ/2, φ/32, φ/64, φ/128, φ/256, φ/512,
/// φ/2048, φ/4096 (12.2.2).
pub const DIVIDER_SHIFT: [u32; 8] = [1, 5, 6, 7, 8, 9, 11, 12];

/// Whether a word access at `addr` (even) reaches the WDT as one word.
#[inline]
#[must_use]
pub const fn is_word_register(addr: u32) -> bool {
    addr == TCSR || addr == RSTCSR_WRITE
}

/// The watchdog timer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Wdt {
    /// OVF, WT/IT, TME and CKS as of `synced_at` (OVF set there if the counter overflowed).
    tcsr: u8,
    /// TCNT as of `synced_at`.
    tcnt: u8,
    /// The instant TCNT and OVF are worked out to.
    synced_at: u64,
    /// WRST and RSTOE.
    rstcsr: u8,
    /// TCSR was read with OVF = 1 since OVF was last set or cleared: a 0 written clears it.
    ovf_armed: bool,
    /// The overflow in watchdog timer mode that requests the reset, once it happened.
    reset_at: Option<u64>,
}

impl Default for Wdt {
    fn default() -> Self {
        Self::new()
    }
}

impl Wdt {
    /// The WDT after a reset by the RES pin (power-on).
    #[must_use]
    pub const fn new() -> Self {
        Wdt {
            tcsr: TCSR_RESET & !TCSR_RESERVED,
            tcnt: 0,
            synced_at: 0,
            rstcsr: RSTCSR_RESET & !RSTCSR_RESERVED,
            ovf_armed: false,
            reset_at: None,
        }
    }

    /// Whether the counter runs (TME = 1).
    #[inline]
    #[must_use]
    pub const fn running(&self) -> bool {
        self.tcsr & TCSR_TME != 0
    }

    /// Whether overflows reset the chip (WT/IT = 1).
    #[inline]
    #[must_use]
    pub const fn watchdog_mode(&self) -> bool {
        self.tcsr & TCSR_WT != 0
    }

    /// log2 of the counting clock's division.
    #[inline]
    fn shift(&self) -> u32 {
        DIVIDER_SHIFT[usize::from(self.tcsr & TCSR_CKS)]
    }

    /// The instant of the next overflow after `synced_at`, while counting.
    #[inline]
    fn overflow_after_sync(&self) -> Option<u64> {
        if !self.running() {
            return None;
        }
        let s = self.shift();
        let counts = 0x100 - u64::from(self.tcnt);
        Some(((self.synced_at >> s) + counts) << s)
    }

    /// The instant of the next overflow after `now` (at or before which nothing changes), while
    /// counting.
    fn next_overflow(&self, now: u64) -> Option<u64> {
        let first = self.overflow_after_sync()?;
        if first > now {
            return Some(first);
        }
        // Overflows recur every 256 counts after the first.
        let period = 0x100u64 << self.shift();
        Some(first + ((now - first) / period + 1) * period)
    }

    /// Brings TCNT and OVF up to `now`: counts the prescaler's edges since the last update; an
    /// overflow sets OVF, and in watchdog timer mode WRST and the reset request.
    pub fn sync(&mut self, now: u64) {
        if now <= self.synced_at {
            return;
        }
        if self.running() {
            let s = self.shift();
            let edges = (now >> s) - (self.synced_at >> s);
            let total = u64::from(self.tcnt) + edges;
            if total >= 0x100 {
                let first = ((self.synced_at >> s) + (0x100 - u64::from(self.tcnt))) << s;
                if self.tcsr & TCSR_OVF == 0 {
                    self.tcsr |= TCSR_OVF;
                    self.ovf_armed = false;
                }
                if self.watchdog_mode() && self.reset_at.is_none() {
                    self.reset_at = Some(first);
                    self.rstcsr |= RSTCSR_WRST;
                }
            }
            self.tcnt = (total & 0xFF) as u8;
        }
        self.synced_at = now;
    }

    /// Reads the byte at `addr` at `now`.
    pub fn read(&mut self, addr: u32, now: u64) -> u8 {
        self.sync(now);
        match addr {
            TCSR => {
                if self.tcsr & TCSR_OVF != 0 {
                    self.ovf_armed = true;
                }
                self.tcsr | TCSR_RESERVED
            }
            TCNT => self.tcnt,
            RSTCSR => self.rstcsr | RSTCSR_RESERVED,
            _ => 0xFF,
        }
    }

    /// A byte write: the WDT's registers take only password words, so nothing changes.
    pub fn write(&mut self, _addr: u32, _value: u8, now: u64) {
        self.sync(now);
    }

    /// A word write of `value` at `addr` (even) at `now`: the password decides (module docs).
    pub fn write16(&mut self, addr: u32, value: u16, now: u64) {
        self.sync(now);
        let [password, data] = value.to_be_bytes();
        match (addr, password) {
            (TCSR, PASSWORD_TCNT) if self.running() => self.tcnt = data,
            (TCSR, PASSWORD_TCSR) => self.write_tcsr(data),
            (RSTCSR_WRITE, PASSWORD_TCSR) if data & RSTCSR_WRST == 0 => {
                self.rstcsr &= !RSTCSR_WRST;
            }
            (RSTCSR_WRITE, PASSWORD_RSTOE) => {
                self.rstcsr = (self.rstcsr & !RSTCSR_RSTOE) | (data & RSTCSR_RSTOE);
            }
            _ => {}
        }
    }

    /// TCSR's new value (after [`Wdt::sync`]): OVF only cleared (by a 0 after reading it as
    /// 1), the rest as written; clearing TME clears and stops TCNT.
    fn write_tcsr(&mut self, data: u8) {
        let mut ovf = self.tcsr & TCSR_OVF;
        if data & TCSR_OVF == 0 && self.ovf_armed {
            ovf = 0;
            self.ovf_armed = false;
        }
        self.tcsr = ovf | (data & (TCSR_WT | TCSR_TME | TCSR_CKS));
        if !self.running() {
            self.tcnt = 0;
        }
    }

    /// The reset request's overflow instant, while one stands (watchdog timer mode).
    #[must_use]
    pub const fn reset_requested_at(&self) -> Option<u64> {
        self.reset_at
    }

    /// When the internal reset ends: [`RESET_STATES`] after the overflow that requested it.
    #[must_use]
    pub fn reset_end(&self) -> Option<u64> {
        self.reset_at.map(|t| t + RESET_STATES)
    }

    /// The watchdog's own reset of the chip: TCSR and TCNT to their reset values, RSTCSR kept
    /// (WRST stays set), the request withdrawn.
    pub fn internal_reset(&mut self, now: u64) {
        let rstcsr = self.rstcsr;
        *self = Wdt::new();
        self.rstcsr = rstcsr;
        self.synced_at = now;
    }

    /// TCSR as a read would return it at `now`, without arming OVF's clearing (for tests and
    /// inspection).
    #[must_use]
    pub fn tcsr_at(&self, now: u64) -> u8 {
        let mut w = self.clone();
        w.sync(now);
        w.tcsr | TCSR_RESERVED
    }

    /// TCNT at `now` (for tests and inspection).
    #[must_use]
    pub fn tcnt_at(&self, now: u64) -> u8 {
        let mut w = self.clone();
        w.sync(now);
        w.tcnt
    }

    /// RSTCSR as a read returns it.
    #[must_use]
    pub const fn rstcsr(&self) -> u8 {
        self.rstcsr | RSTCSR_RESERVED
    }

    /// The first instant after `now` at which the WDT raises a request it does not raise at
    /// `now`: the next overflow, unless its request already stands (OVF set in interval timer
    /// mode, a reset requested in watchdog timer mode), in which case none.
    #[must_use]
    pub fn next_request_after(&self, now: u64) -> Option<u64> {
        if self.requests_at(now) != 0 {
            return None;
        }
        self.next_overflow(now)
    }

    /// The requests at `now` as a vector mask: WOVI (bit 20) while OVF = 1 in interval timer
    /// mode; the reset request (bit 0) from the overflow in watchdog timer mode.
    #[must_use]
    pub fn requests_at(&self, now: u64) -> u64 {
        if let Some(t) = self.reset_at {
            return if t <= now { 1 << RESET_REQUEST } else { 0 };
        }
        let ovf = self.tcsr & TCSR_OVF != 0
            || self
                .overflow_after_sync()
                .is_some_and(|t| t <= now && now > self.synced_at);
        if !ovf {
            return 0;
        }
        if self.watchdog_mode() {
            1 << RESET_REQUEST
        } else {
            1 << VECTOR_WOVI
        }
    }
}

impl Peripheral for Wdt {
    type Outside<'a, B: Board + 'a> = ();
    const FIRST: u32 = TCSR;
    const LAST: u32 = RSTCSR;
    const AFFECTS_IRQ: bool = true;

    #[inline]
    fn read<B: Board>(&mut self, addr: u32, now: u64, (): ()) -> u8 {
        Wdt::read(self, addr, now)
    }

    #[inline]
    fn write<B: Board>(&mut self, addr: u32, value: u8, now: u64, (): ()) {
        Wdt::write(self, addr, value, now);
    }

    #[inline]
    fn sync<B: Board>(&mut self, now: u64, (): ()) {
        Wdt::sync(self, now);
    }

    /// The next overflow while the counter runs.
    #[inline]
    fn next_event(&self, now: u64) -> Option<u64> {
        if self.running() {
            self.next_overflow(now)
        } else {
            None
        }
    }

    #[inline]
    fn requests(&self, now: u64) -> u64 {
        if self.running() || self.tcsr & TCSR_OVF != 0 || self.reset_at.is_some() {
            self.requests_at(now)
        } else {
            0
        }
    }

    #[inline]
    fn next_request(&self, now: u64) -> Option<u64> {
        if self.running() {
            self.next_request_after(now)
        } else {
            None
        }
    }

    #[inline]
    fn reset(&mut self) {
        *self = Wdt::new();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wdt_at(now: u64, tcsr: u8) -> Wdt {
        let mut w = Wdt::new();
        w.write16(TCSR, u16::from_be_bytes([PASSWORD_TCSR, tcsr]), now);
        w
    }

    #[test]
    fn reset_values_and_reserved_bits() {
        let mut w = Wdt::new();
        assert_eq!(w.read(TCSR, 0), TCSR_RESET);
        assert_eq!(w.read(TCNT, 0), 0);
        assert_eq!(w.read(RSTCSR, 0), RSTCSR_RESET);
        assert_eq!(w.read(RSTCSR_WRITE, 0), 0xFF);
        // Stopped: nothing counts, nothing is requested.
        assert_eq!(w.tcnt_at(1_000_000), 0);
        assert_eq!(Peripheral::next_event(&w, 0), None);
        assert_eq!(Peripheral::requests(&w, 1_000_000), 0);
    }

    #[test]
    fn only_password_words_write() {
        let mut w = Wdt::new();
        // Byte writes and wrong passwords: nothing.
        w.write(TCSR, TCSR_TME, 10);
        w.write16(TCSR, 0x1234, 10);
        w.write16(TCSR, u16::from_be_bytes([PASSWORD_TCNT, 0x40]), 10);
        assert_eq!(w.read(TCSR, 10), TCSR_RESET);
        assert_eq!(w.read(TCNT, 10), 0, "TCNT is held at 0 while TME = 0");
        w.write16(
            TCSR,
            u16::from_be_bytes([PASSWORD_TCSR, TCSR_TME | 0x07]),
            10,
        );
        assert_eq!(w.read(TCSR, 10), TCSR_RESET | TCSR_TME | 0x07);
        w.write16(TCSR, u16::from_be_bytes([PASSWORD_TCNT, 0x40]), 10);
        assert_eq!(w.read(TCNT, 10), 0x40);
    }

    #[test]
    fn tcnt_counts_at_the_multiples_of_the_divider() {
        // φ/32 (CKS = 1): counts at multiples of 32.
        let w = wdt_at(5, TCSR_TME | 1);
        assert_eq!(w.tcnt_at(31), 0);
        assert_eq!(w.tcnt_at(32), 1);
        assert_eq!(w.tcnt_at(63), 1);
        assert_eq!(w.tcnt_at(64 * 32), 64);
        // φ/4096 (CKS = 7).
        let w = wdt_at(0, TCSR_TME | 7);
        assert_eq!(w.tcnt_at(4095), 0);
        assert_eq!(w.tcnt_at(4096 * 3), 3);
    }

    #[test]
    fn interval_mode_sets_ovf_requests_wovi_and_clears_by_read_then_write() {
        // φ/2 from 0: overflow after 256 counts, at state 512.
        let mut w = wdt_at(0, TCSR_TME);
        assert_eq!(Peripheral::next_request(&w, 0), Some(512));
        assert_eq!(Peripheral::requests(&w, 511), 0);
        assert_eq!(Peripheral::requests(&w, 512), 1 << VECTOR_WOVI);
        assert_eq!(w.tcnt_at(512), 0, "TCNT wraps and counts on");
        assert_eq!(w.tcnt_at(514), 1);
        // Writing 0 before reading OVF as 1 does not clear it.
        w.write16(TCSR, u16::from_be_bytes([PASSWORD_TCSR, TCSR_TME]), 520);
        assert_eq!(w.tcsr_at(520) & TCSR_OVF, TCSR_OVF);
        assert_eq!(w.read(TCSR, 521) & TCSR_OVF, TCSR_OVF);
        w.write16(TCSR, u16::from_be_bytes([PASSWORD_TCSR, TCSR_TME]), 524);
        assert_eq!(w.tcsr_at(524) & TCSR_OVF, 0);
        assert_eq!(Peripheral::requests(&w, 524), 0);
        // The next overflow: 256 counts after the first.
        assert_eq!(Peripheral::next_request(&w, 524), Some(1024));
        // No reset in interval mode.
        assert_eq!(w.rstcsr() & RSTCSR_WRST, 0);
    }

    #[test]
    fn watchdog_mode_requests_a_reset_and_sets_wrst() {
        let mut w = wdt_at(0, TCSR_WT | TCSR_TME | 1);
        // Kicked at 1000 (TCNT = 0): the next overflow is 256 counts of 32 after the last
        // multiple of 32 before 1000 (992).
        w.write16(TCSR, u16::from_be_bytes([PASSWORD_TCNT, 0]), 1000);
        let t = 992 + 256 * 32;
        assert_eq!(Peripheral::next_request(&w, 1000), Some(t));
        assert_eq!(Peripheral::requests(&w, t - 1), 0);
        assert_eq!(Peripheral::requests(&w, t), 1 << RESET_REQUEST);
        w.sync(t + 5);
        assert_eq!(w.reset_requested_at(), Some(t));
        assert_eq!(w.reset_end(), Some(t + RESET_STATES));
        assert_eq!(w.rstcsr() & RSTCSR_WRST, RSTCSR_WRST);
        // The reset: TCSR and TCNT to their reset values, WRST kept until written 0.
        w.internal_reset(t + RESET_STATES);
        assert_eq!(w.read(TCSR, t + RESET_STATES), TCSR_RESET);
        assert_eq!(w.read(RSTCSR, t + RESET_STATES), RSTCSR_RESET | RSTCSR_WRST);
        assert_eq!(Peripheral::requests(&w, t + RESET_STATES), 0);
        w.write16(
            RSTCSR_WRITE,
            u16::from_be_bytes([PASSWORD_TCSR, 0x00]),
            t + 600,
        );
        assert_eq!(w.read(RSTCSR, t + 600), RSTCSR_RESET);
        // RSTOE by the other password.
        w.write16(
            RSTCSR_WRITE,
            u16::from_be_bytes([PASSWORD_RSTOE, 0xFF]),
            t + 610,
        );
        assert_eq!(w.read(RSTCSR, t + 610), RSTCSR_RESET | RSTCSR_RSTOE);
        // A RES-pin reset (power-on) clears it.
        Peripheral::reset(&mut w);
        assert_eq!(w.read(RSTCSR, 0), RSTCSR_RESET);
    }

    #[test]
    fn kicking_in_time_prevents_the_reset() {
        let mut w = wdt_at(0, TCSR_WT | TCSR_TME);
        for k in 1..100u64 {
            w.write16(TCSR, u16::from_be_bytes([PASSWORD_TCNT, 0]), k * 400);
        }
        assert_eq!(Peripheral::requests(&w, 99 * 400 + 1), 0);
        assert_eq!(w.reset_requested_at(), None);
        assert_eq!(w.rstcsr() & RSTCSR_WRST, 0);
    }

    #[test]
    fn clearing_tme_stops_and_clears_the_counter() {
        let mut w = wdt_at(0, TCSR_TME);
        assert_eq!(w.tcnt_at(100), 50);
        w.write16(TCSR, u16::from_be_bytes([PASSWORD_TCSR, 0]), 100);
        assert_eq!(w.read(TCNT, 100), 0);
        assert_eq!(w.tcnt_at(100_000), 0);
        assert_eq!(Peripheral::next_event(&w, 100), None);
    }
}
