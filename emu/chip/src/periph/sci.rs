//! SCI1, the serial communication interface channel 1 of the H8/3052F, at register level
//! (H8/3052F hardware manual, section 13 "Serial Communication Interface"), transmit side.
//!
//! Registers at H'FFFFB8–H'FFFFBD (docs/design.md §4.1): SMR, BRR, SCR, TDR, SSR, RDR. The transmitter
//! behaves as on the chip (docs/design.md §7): with SCR.TE = 1, a program writes TDR and clears SSR.TDRE
//! (by writing 0 after reading it as 1); the byte moves to the transmit shift register as soon
//! as that is free, at which moment TDRE is set again and the byte goes to the console sink;
//! TEND is set when the shift register has sent its last bit and TDR is empty. A frame takes
//! `(1 start + 7/8 data + parity + multiprocessor + 1/2 stop) × bit time` states, the bit time
//! following the manual's BRR formula `B = φ / (64 × 2^(2n−1) × (N + 1))`, i.e.
//! `32 × 4^n × (N + 1)` states (asynchronous mode; `4 × 4^n × (N + 1)` with 8-bit frames in
//! clocked synchronous mode). TXI (vector 58) is requested while SCR.TIE = 1 and TDRE = 1, TEI
//! (vector 59) while SCR.TEIE = 1 and TEND = 1.
//!
//! Modelled choices: the receiver is not modelled (RDR reads its reset value, RDRF never sets);
//! clearing TDRE while TE = 0 is ignored (nothing is sent); clearing TE drops a byte still
//! waiting in TDR, as the manual says the transmitter is initialised. Times are evaluated
//! lazily from the clock value of each access, so the SCI needs no stepping.

use super::Peripheral;
use crate::pins::Board;

/// Address of SMR (serial mode register) of SCI1 (docs/design.md §4.1).
pub const SCI1_SMR: u32 = 0xFF_FFB8;
/// Address of BRR (bit rate register) of SCI1.
pub const SCI1_BRR: u32 = 0xFF_FFB9;
/// Address of SCR (serial control register) of SCI1.
pub const SCI1_SCR: u32 = 0xFF_FFBA;
/// Address of TDR (transmit data register) of SCI1.
pub const SCI1_TDR: u32 = 0xFF_FFBB;
/// Address of SSR (serial status register) of SCI1.
pub const SCI1_SSR: u32 = 0xFF_FFBC;
/// Address of RDR (receive data register) of SCI1.
pub const SCI1_RDR: u32 = 0xFF_FFBD;

/// SCI1 ERI (receive error) vector (H8/3052F hardware manual, Table 5-3).
pub const VECTOR_ERI1: u8 = 56;
/// SCI1 RXI (receive data full) vector.
pub const VECTOR_RXI1: u8 = 57;
/// SCI1 TXI (transmit data empty) vector (docs/design.md §4.1: 58).
pub const VECTOR_TXI1: u8 = 58;
/// SCI1 TEI (transmit end) vector.
pub const VECTOR_TEI1: u8 = 59;

/// SSR bit 7: transmit data register empty.
pub const SSR_TDRE: u8 = 0x80;
/// SSR bit 6: receive data register full.
pub const SSR_RDRF: u8 = 0x40;
/// SSR bit 5: overrun error.
pub const SSR_ORER: u8 = 0x20;
/// SSR bit 4: framing error.
pub const SSR_FER: u8 = 0x10;
/// SSR bit 3: parity error.
pub const SSR_PER: u8 = 0x08;
/// SSR bit 2: transmit end.
pub const SSR_TEND: u8 = 0x04;
/// SSR bit 1: multiprocessor bit (receive).
pub const SSR_MPB: u8 = 0x02;
/// SSR bit 0: multiprocessor bit transfer.
pub const SSR_MPBT: u8 = 0x01;

/// SCR bit 7: transmit interrupt enable.
pub const SCR_TIE: u8 = 0x80;
/// SCR bit 5: transmit enable.
pub const SCR_TE: u8 = 0x20;
/// SCR bit 2: transmit end interrupt enable.
pub const SCR_TEIE: u8 = 0x04;

/// SMR bit 7: clocked synchronous mode.
pub const SMR_CA: u8 = 0x80;
/// SMR bit 6: 7-bit characters.
pub const SMR_CHR: u8 = 0x40;
/// SMR bit 5: parity enable.
pub const SMR_PE: u8 = 0x20;
/// SMR bit 3: two stop bits.
pub const SMR_STOP: u8 = 0x08;
/// SMR bit 2: multiprocessor mode.
pub const SMR_MP: u8 = 0x04;

/// Reset value of BRR (H8/3052F hardware manual, Table 13-2: H'FF).
pub const BRR_RESET: u8 = 0xFF;
/// Reset value of TDR (H'FF).
pub const TDR_RESET: u8 = 0xFF;
/// Reset value of SSR (H'84: TDRE and TEND set).
pub const SSR_RESET: u8 = 0x84;

/// States per bit in asynchronous mode for n = 0, N = 0 (BRR formula: 64 × 2^(2n−1)).
pub const ASYNC_STATES_PER_BIT_BASE: u64 = 32;
/// States per bit in clocked synchronous mode for n = 0, N = 0 (BRR formula: 8 × 2^(2n−1)).
pub const SYNC_STATES_PER_BIT_BASE: u64 = 4;

/// SCI1 transmit side with a console sink.
#[derive(Clone, Debug)]
pub struct Sci {
    smr: u8,
    brr: u8,
    scr: u8,
    tdr: u8,
    /// SSR bits other than TDRE/TEND (MPBT is the only one that changes here).
    ssr_low: u8,
    /// A byte is in TDR waiting for the shift register.
    tdr_full: bool,
    /// When the waiting byte moves into the shift register.
    taken_at: u64,
    /// When the shift register finishes its current frame.
    tsr_free_at: u64,
    /// TDRE was read as 1 since the last clear (the manual's condition for clearing it).
    tdre_seen: bool,
    /// Transmitted bytes not yet collected.
    out: Vec<u8>,
    /// Bytes transmitted since power-on.
    sent: u64,
}

impl Default for Sci {
    fn default() -> Self {
        Self::new()
    }
}

impl Sci {
    /// SCI1 after reset.
    #[must_use]
    pub fn new() -> Self {
        Sci {
            smr: 0,
            brr: BRR_RESET,
            scr: 0,
            tdr: TDR_RESET,
            ssr_low: 0,
            tdr_full: false,
            taken_at: 0,
            tsr_free_at: 0,
            tdre_seen: false,
            out: Vec::new(),
            sent: 0,
        }
    }

    /// States of one frame with the current SMR and BRR.
    #[must_use]
    pub fn frame_states(&self) -> u64 {
        let n = u32::from(self.smr & 3);
        let per_bit_base = if self.smr & SMR_CA != 0 {
            SYNC_STATES_PER_BIT_BASE
        } else {
            ASYNC_STATES_PER_BIT_BASE
        };
        let bit = per_bit_base * 4u64.pow(n) * (u64::from(self.brr) + 1);
        let bits = if self.smr & SMR_CA != 0 {
            8
        } else {
            1 + if self.smr & SMR_CHR != 0 { 7 } else { 8 }
                + u64::from(self.smr & SMR_PE != 0)
                + u64::from(self.smr & SMR_MP != 0)
                + if self.smr & SMR_STOP != 0 { 2 } else { 1 }
        };
        bits * bit
    }

    /// Moves a waiting byte into the shift register if its time has come.
    fn settle(&mut self, now: u64) {
        if self.tdr_full && now >= self.taken_at {
            self.tdr_full = false;
            self.tsr_free_at = self.taken_at + self.frame_states();
            self.out.push(self.tdr);
            self.sent += 1;
        }
    }

    fn tdre(&self, now: u64) -> bool {
        !(self.tdr_full && now < self.taken_at)
    }

    fn tend(&self, now: u64) -> bool {
        self.tdre(now) && now >= self.tsr_free_at.max(self.pending_free_at())
    }

    /// When the shift register will be free after sending a waiting byte.
    fn pending_free_at(&self) -> u64 {
        if self.tdr_full {
            self.taken_at + self.frame_states()
        } else {
            self.tsr_free_at
        }
    }

    /// Brings the transmitter up to time `now` (a waiting byte whose time has come moves to
    /// the shift register and the console). Register accesses do this themselves; call it
    /// when time jumps without an access (sleep).
    pub fn sync(&mut self, now: u64) {
        self.settle(now);
    }

    /// Reads a register at time `now` (the instant the bus cycle ends).
    pub fn read(&mut self, addr: u32, now: u64) -> u8 {
        self.settle(now);
        match addr {
            SCI1_SMR => self.smr,
            SCI1_BRR => self.brr,
            SCI1_SCR => self.scr,
            SCI1_TDR => self.tdr,
            SCI1_SSR => {
                let tdre = self.tdre(now);
                if tdre {
                    self.tdre_seen = true;
                }
                let mut v = self.ssr_low;
                if tdre {
                    v |= SSR_TDRE;
                }
                if self.tend(now) {
                    v |= SSR_TEND;
                }
                v
            }
            _ => 0, // RDR: the receiver is not modelled.
        }
    }

    /// Writes a register at time `now`.
    pub fn write(&mut self, addr: u32, value: u8, now: u64) {
        self.settle(now);
        match addr {
            SCI1_SMR => self.smr = value,
            SCI1_BRR => self.brr = value,
            SCI1_SCR => {
                let was_te = self.scr & SCR_TE != 0;
                self.scr = value;
                if was_te && value & SCR_TE == 0 {
                    // Transmitter initialised: a byte still in TDR is not sent.
                    self.tdr_full = false;
                }
            }
            SCI1_TDR => self.tdr = value,
            SCI1_SSR => {
                self.ssr_low = (self.ssr_low & !SSR_MPBT) | (value & SSR_MPBT);
                let clear_tdre = value & SSR_TDRE == 0 && self.tdre_seen && self.tdre(now);
                if clear_tdre && self.scr & SCR_TE != 0 {
                    self.tdre_seen = false;
                    self.tdr_full = true;
                    self.taken_at = now.max(self.tsr_free_at);
                    self.settle(now);
                }
            }
            _ => {}
        }
    }

    /// The highest-priority SCI1 interrupt requested and enabled at time `now`.
    #[must_use]
    pub fn pending_irq(&self, now: u64) -> Option<u8> {
        if self.scr & SCR_TIE != 0 && self.scr & SCR_TE != 0 && self.tdre(now) {
            return Some(VECTOR_TXI1);
        }
        if self.scr & SCR_TEIE != 0 && self.scr & SCR_TE != 0 && self.tend(now) {
            return Some(VECTOR_TEI1);
        }
        None
    }

    /// The earliest time after `now` at which an enabled SCI1 interrupt becomes requested, if
    /// any will without further register accesses.
    #[must_use]
    pub fn next_irq_time(&self, now: u64) -> Option<u64> {
        if self.scr & SCR_TE == 0 {
            return None;
        }
        let mut t: Option<u64> = None;
        if self.scr & SCR_TIE != 0 && !self.tdre(now) {
            t = Some(self.taken_at);
        }
        if self.scr & SCR_TEIE != 0 && !self.tend(now) {
            let at = self
                .pending_free_at()
                .max(if self.tdr_full { self.taken_at } else { 0 });
            t = Some(t.map_or(at, |x| x.min(at)));
        }
        t
    }

    /// Takes the bytes transmitted so far (the console sink).
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.out)
    }

    /// Whether transmitted bytes are waiting to be collected.
    #[must_use]
    pub fn has_output(&self) -> bool {
        !self.out.is_empty()
    }

    /// The bytes transmitted and not yet collected.
    #[must_use]
    pub fn output(&self) -> &[u8] {
        &self.out
    }

    /// Forgets the collected bytes (keeps the buffer's capacity).
    pub fn clear_output(&mut self) {
        self.out.clear();
    }

    /// Ends transmission at time `now`: a byte still waiting in TDR is sent (the chip keeps
    /// transmitting after the program stops).
    pub fn flush(&mut self, now: u64) {
        if self.tdr_full {
            self.settle(now.max(self.taken_at));
        }
    }

    /// Bytes transmitted since the MCU was built (resets do not clear the count).
    #[must_use]
    pub const fn bytes_sent(&self) -> u64 {
        self.sent
    }
}

impl Peripheral for Sci {
    type Outside<'a, B: Board + 'a> = ();
    const FIRST: u32 = SCI1_SMR;
    const LAST: u32 = SCI1_RDR;
    const AFFECTS_IRQ: bool = true;

    #[inline]
    fn read<B: Board>(&mut self, addr: u32, now: u64, (): ()) -> u8 {
        Sci::read(self, addr, now)
    }

    #[inline]
    fn write<B: Board>(&mut self, addr: u32, value: u8, now: u64, (): ()) {
        Sci::write(self, addr, value, now);
    }

    #[inline]
    fn sync<B: Board>(&mut self, now: u64, (): ()) {
        Sci::sync(self, now);
    }

    /// The next frame edge that changes TDRE or TEND.
    #[inline]
    fn next_event(&self, now: u64) -> Option<u64> {
        self.next_irq_time(now)
    }

    #[inline]
    fn requests(&self, now: u64) -> u64 {
        self.pending_irq(now).map_or(0, |v| 1u64 << v)
    }

    /// [`Sci::next_irq_time`] while nothing is requested; once TXI or TEI is requested, SCI1
    /// raises nothing new before a register access.
    #[inline]
    fn next_request(&self, now: u64) -> Option<u64> {
        if Peripheral::requests(self, now) == 0 {
            self.next_irq_time(now)
        } else {
            None
        }
    }

    #[inline]
    /// The registers to their reset values and a frame under way dropped; the bytes already
    /// sent stay the console's (they are on the wire), and so does their count.
    fn reset(&mut self) {
        let out = std::mem::take(&mut self.out);
        let sent = self.sent;
        *self = Sci::new();
        self.out = out;
        self.sent = sent;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The polling sequence of a real program: wait TDRE, write TDR, clear TDRE.
    fn put(sci: &mut Sci, now: &mut u64, c: u8) {
        loop {
            *now += 3;
            if sci.read(SCI1_SSR, *now) & SSR_TDRE != 0 {
                break;
            }
        }
        *now += 3;
        sci.write(SCI1_TDR, c, *now);
        *now += 3;
        let ssr = sci.read(SCI1_SSR, *now);
        *now += 3;
        sci.write(SCI1_SSR, ssr & !SSR_TDRE, *now);
    }

    #[test]
    fn polled_bytes_reach_the_console_in_order_at_the_bit_rate() {
        let mut sci = Sci::new();
        let mut now = 0;
        sci.write(SCI1_SMR, 0, now);
        sci.write(SCI1_BRR, 19, now);
        sci.write(SCI1_SCR, SCR_TE, now);
        for &c in b"hello" {
            put(&mut sci, &mut now, c);
        }
        sci.flush(now);
        assert_eq!(sci.take_output(), b"hello");
        // 8N1 at BRR 19: 10 bits × 32 × 20 states = 6400 states per frame; the fifth byte can
        // only move into the shift register after four frames.
        assert_eq!(sci.frame_states(), 6400);
        assert!(now >= 3 * 6400, "now = {now}");
    }

    #[test]
    fn nothing_is_sent_without_te_or_without_clearing_tdre() {
        let mut sci = Sci::new();
        sci.write(SCI1_TDR, b'x', 1);
        let ssr = sci.read(SCI1_SSR, 2);
        assert_eq!(ssr, SSR_RESET);
        sci.write(SCI1_SSR, ssr & !SSR_TDRE, 3);
        sci.flush(10);
        assert!(sci.take_output().is_empty());
        sci.write(SCI1_SCR, SCR_TE, 4);
        sci.write(SCI1_TDR, b'y', 5);
        sci.flush(10);
        assert!(sci.take_output().is_empty());
    }

    #[test]
    fn txi_is_requested_while_tdre_and_tie() {
        let mut sci = Sci::new();
        sci.write(SCI1_SCR, SCR_TE | SCR_TIE, 0);
        assert_eq!(sci.pending_irq(0), Some(VECTOR_TXI1));
        // Two bytes back to back: the second waits for the first frame.
        let ssr = sci.read(SCI1_SSR, 1);
        sci.write(SCI1_TDR, 1, 2);
        sci.write(SCI1_SSR, ssr & !SSR_TDRE, 3);
        let ssr = sci.read(SCI1_SSR, 4);
        assert_ne!(ssr & SSR_TDRE, 0);
        sci.write(SCI1_TDR, 2, 5);
        sci.write(SCI1_SSR, ssr & !SSR_TDRE, 6);
        assert_eq!(sci.pending_irq(7), None);
        let t = sci.next_irq_time(7).unwrap();
        assert_eq!(t, 3 + sci.frame_states());
        assert_eq!(sci.pending_irq(t), Some(VECTOR_TXI1));
    }
}
