//! The 16-bit integrated timer unit (ITU) of the H8/3052F, channels 0–4, at register level
//! (H8/3052F hardware manual, section 10 "16-Bit Integrated Timer Unit"; register map in its
//! appendix B, the same as the H8/3048 series').
//!
//! # What is modelled
//! - TSTR (start bits STR0–4), TSNC, TMDR (PWM0–4), TFCR, TOER, TOCR as registers; of them
//!   TSTR and the PWM bits act.
//! - Per channel: TCR (CCLR1–0, CKEG1–0, TPSC2–0), TIOR (IOB2–0, IOA2–0), TIER (OVIE, IMIEB,
//!   IMIEA), TSR (OVF, IMFB, IMFA), TCNT, GRA, GRB and, for channels 3 and 4, BRA/BRB (stored;
//!   buffer operation is not modelled).
//! - Prescaler φ, φ/2, φ/4, φ/8 (TPSC = 0xx). The prescaler runs freely from reset, so TCNT
//!   counts at the states that are multiples of 1, 2, 4 or 8: a channel started at an odd
//!   state with φ/8 counts its first increment less than 8 states later, as on the chip.
//!   External clocks (TPSC = 1xx) are not connected on the robot: the counter does not count.
//! - **Compare match.** The manual: the compare-match signal is generated in the last state
//!   in which TCNT equals GR, i.e. when TCNT leaves the matching value at the next count.
//!   Here the flag (IMFA/IMFB) is set, the counter is cleared (CCLR) and the output changes at
//!   that count edge: with CCLR = 01 the counter shows GRA for one full count and then 0, so
//!   the period is GRA + 1 counts.
//! - Overflow: OVF is set when TCNT goes from H'FFFF to H'0000 (also when that is a clear by
//!   a compare match with GR = H'FFFF).
//! - Flags are cleared by reading them as 1 and then writing 0 (writing 1 has no effect).
//! - IMIA/IMIB/OVI are requested while flag and enable are both 1 (vectors 24–26 for ITU0,
//!   28–30, 32–34, 36–38, 40–42).
//! - A GR whose TIOR bits select input capture (IOx2 = 1) is not compared (no capture signal
//!   is connected, so it never captures either), except in PWM mode where TIOR is ignored.
//! - **PWM mode** (TMDR.PWMn = 1): TIOCAn is set to 1 at compare match A and cleared to 0 at
//!   compare match B; when both happen at once (GRA = GRB) the output does not change. With
//!   the counter cleared by GRA (CCLR = 01) the period is GRA + 1 counts and the high time
//!   GRB + 1 counts (docs/design.md §3.5); GRB > GRA gives 100 % (B never matches), as the manual's
//!   0 %/100 % duty examples say. Cleared by GRB instead, the high time is GRB − GRA counts.
//!   See [`Itu::pwm`] for the steady-state waveform.
//! - Output compare outside PWM mode on TIOCA (IOA = 001 → 0, 010 → 1, 011 → toggle) is
//!   modelled; TIOCB outputs are not (nothing on the robot uses them).
//! - 16-bit registers (TCNT, GRA, GRB, BRA, BRB) sit on an internal 16-bit bus (manual: "the
//!   TCNTs are linked to the CPU by an internal 16-bit bus and can be written or read by either
//!   word access or byte access"): a word access is one bus cycle
//!   ([`ITU_WORD_ACCESS_STATES`]) and needs no temporary register; byte accesses reach either
//!   half directly.
//! - Not modelled: synchronous operation and synchronous clear (CCLR = 11 acts as no clear),
//!   buffer operation, complementary and reset-synchronised PWM, phase counting, input
//!   capture, TIOCB/TOCXA4/TOCXB4 outputs.
//!
//! # Lazy synchronisation
//! Each channel keeps TCNT, the flags and the TIOCA level as of the state it was last brought
//! up to date. Bringing it to a later state counts the prescaler edges in between and works
//! out, in O(1), how many times TCNT passed GRA, GRB and H'FFFF (TCNT runs through a known
//! orbit: up to the clearing value or H'FFFF, then round a cycle of GRA + 1, GRB + 1 or
//! 65 536 counts). Nothing is stepped per state.

use super::Peripheral;
use crate::pins::Board;

/// Address of TSTR, timer start register (docs/design.md §4.1: H'FFFF60).
pub const TSTR: u32 = 0xFF_FF60;
/// Address of TSNC, timer synchro register.
pub const TSNC: u32 = 0xFF_FF61;
/// Address of TMDR, timer mode register (PWM0–4 in bits 0–4).
pub const TMDR: u32 = 0xFF_FF62;
/// Address of TFCR, timer function control register.
pub const TFCR: u32 = 0xFF_FF63;
/// Address of TOER, timer output master enable register (channels 3 and 4).
pub const TOER: u32 = 0xFF_FF90;
/// Address of TOCR, timer output control register.
pub const TOCR: u32 = 0xFF_FF91;
/// First ITU register address (TSTR).
pub const ITU_FIRST: u32 = TSTR;
/// Last ITU register address (BRB4 low byte).
pub const ITU_LAST: u32 = 0xFF_FF9F;

/// Base address of each channel's registers (docs/design.md §4.1: ITU0 H'FFFF64, ITU1 H'FFFF6E, ITU2
/// H'FFFF78, ITU3 H'FFFF82, ITU4 H'FFFF92).
pub const CHANNEL_BASE: [u32; 5] = [0xFF_FF64, 0xFF_FF6E, 0xFF_FF78, 0xFF_FF82, 0xFF_FF92];

/// Offset of TCR (timer control register) from a channel's base.
pub const OFF_TCR: u32 = 0;
/// Offset of TIOR (timer I/O control register).
pub const OFF_TIOR: u32 = 1;
/// Offset of TIER (timer interrupt enable register).
pub const OFF_TIER: u32 = 2;
/// Offset of TSR (timer status register).
pub const OFF_TSR: u32 = 3;
/// Offset of TCNT (high byte; low byte at +1).
pub const OFF_TCNT: u32 = 4;
/// Offset of GRA (high byte).
pub const OFF_GRA: u32 = 6;
/// Offset of GRB (high byte).
pub const OFF_GRB: u32 = 8;
/// Offset of BRA (channels 3 and 4 only).
pub const OFF_BRA: u32 = 10;
/// Offset of BRB (channels 3 and 4 only).
pub const OFF_BRB: u32 = 12;

/// TSR/TIER bit 0: IMFA / IMIEA (compare match or capture A).
pub const IMFA: u8 = 0x01;
/// TSR/TIER bit 1: IMFB / IMIEB.
pub const IMFB: u8 = 0x02;
/// TSR/TIER bit 2: OVF / OVIE (overflow).
pub const OVF: u8 = 0x04;
/// The three flag bits of TSR (and enable bits of TIER).
pub const TSR_FLAGS: u8 = IMFA | IMFB | OVF;

/// Reserved bits of TSTR/TSNC read as 1 (bits 7–5); reset value H'E0.
pub const TSTR_RESERVED: u8 = 0xE0;
/// Reserved bit 7 of TMDR reads as 1; reset value H'80.
pub const TMDR_RESERVED: u8 = 0x80;
/// Reserved bits 7–6 of TFCR read as 1; reset value H'C0.
pub const TFCR_RESERVED: u8 = 0xC0;
/// Reset value of TOER and TOCR (H'FF).
pub const TOER_RESET: u8 = 0xFF;
/// Reserved bit 7 of TCR reads as 1; reset value H'80.
pub const TCR_RESERVED: u8 = 0x80;
/// Reserved bits 7 and 3 of TIOR read as 1; reset value H'88.
pub const TIOR_RESERVED: u8 = 0x88;
/// Reserved bits 7–3 of TIER and TSR read as 1; reset value H'F8.
pub const TIER_TSR_RESERVED: u8 = 0xF8;
/// Reset value of GRA, GRB, BRA, BRB: H'FFFF.
pub const GR_RESET: u16 = 0xFFFF;

/// TCR CCLR field value 01: TCNT cleared by GRA compare match.
pub const CCLR_GRA: u8 = 1;
/// TCR CCLR field value 10: TCNT cleared by GRB compare match.
pub const CCLR_GRB: u8 = 2;

/// States of a word access to TCNT/GRA/GRB/BRA/BRB: one 3-state cycle on the ITU's internal
/// 16-bit bus (manual, ITU register descriptions; the 3 states are docs/design.md §4.1's on-chip I/O
/// figure, [`h8300h::memmap::IO_ACCESS_STATES`]).
pub const ITU_WORD_ACCESS_STATES: u32 = h8300h::memmap::IO_ACCESS_STATES;

/// IMIA vector of each channel (H8/3052F manual Table 5-3: 24, 28, 32, 36, 40; IMIB is +1,
/// OVI +2).
pub const VECTOR_IMIA: [u8; 5] = [24, 28, 32, 36, 40];

/// Whether `addr` holds one of the ITU's 16-bit registers (TCNT, GRA, GRB, BRA, BRB), which a
/// word access reaches in one bus cycle.
#[inline]
#[must_use]
pub const fn is_word_register(addr: u32) -> bool {
    match decode(addr) {
        Some((_, off)) => off >= OFF_TCNT,
        None => false,
    }
}

/// Channel and offset of a channel register address.
#[inline]
const fn decode(addr: u32) -> Option<(usize, u32)> {
    match addr {
        0xFF_FF64..=0xFF_FF6D => Some((0, addr - 0xFF_FF64)),
        0xFF_FF6E..=0xFF_FF77 => Some((1, addr - 0xFF_FF6E)),
        0xFF_FF78..=0xFF_FF81 => Some((2, addr - 0xFF_FF78)),
        0xFF_FF82..=0xFF_FF8F => Some((3, addr - 0xFF_FF82)),
        0xFF_FF92..=0xFF_FF9F => Some((4, addr - 0xFF_FF92)),
        _ => None,
    }
}

/// The steady-state PWM waveform of a channel's TIOCA output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PwmWave {
    /// Period in states (counts × prescaler).
    pub period_states: u64,
    /// High time per period in states (0 ..= `period_states`).
    pub high_states: u64,
}

/// The path TCNT runs from a starting value: up to `wrap` (then to 0), then round a cycle of
/// `cycle` counts (0 ..= cycle − 1).
#[derive(Clone, Copy, Debug)]
struct Orbit {
    v0: u64,
    wrap: u64,
    cycle: u64,
}

impl Orbit {
    /// Counts until (and including) the first wrap to 0.
    #[inline]
    fn first_len(&self) -> u64 {
        self.wrap - self.v0 + 1
    }

    /// The count edge (1-based) at which TCNT leaves value `x` for the first time, if ever.
    #[inline]
    fn first_hit(&self, x: u64) -> Option<u64> {
        if self.v0 <= x && x <= self.wrap {
            Some(x - self.v0 + 1)
        } else if x < self.cycle {
            Some(self.first_len() + x + 1)
        } else {
            None
        }
    }

    /// How many times TCNT leaves `x` within edges 1..=n, and the last such edge.
    #[inline]
    fn hits(&self, x: u64, n: u64) -> (u64, u64) {
        match self.first_hit(x) {
            // A value outside the cycle is passed once, on the way to the first wrap.
            Some(f) if f <= n && x >= self.cycle => (1, f),
            Some(f) if f <= n => {
                let count = 1 + (n - f) / self.cycle;
                (count, f + (count - 1) * self.cycle)
            }
            _ => (0, 0),
        }
    }

    /// TCNT after n edges.
    #[inline]
    fn value_after(&self, n: u64) -> u16 {
        let first = self.first_len();
        if n < first {
            (self.v0 + n) as u16
        } else {
            ((n - first) % self.cycle) as u16
        }
    }
}

/// The state of a channel brought to some later instant (computed without changing it).
#[derive(Clone, Copy, Debug)]
struct Advanced {
    flags: u8,
    tcnt: u16,
    tioca: bool,
}

/// One ITU channel.
#[derive(Clone, Debug)]
struct Channel {
    tcr: u8,
    tior: u8,
    tier: u8,
    /// IMFA/IMFB/OVF as of `synced_at`.
    flags: u8,
    /// Flags read as 1 since they were last cleared (the read-1-then-write-0 rule).
    seen: u8,
    tcnt: u16,
    gra: u16,
    grb: u16,
    bra: u16,
    brb: u16,
    /// TIOCA output level as of `synced_at`.
    tioca: bool,
    /// Copy of TSTR.STRn.
    running: bool,
    /// Copy of TMDR.PWMn.
    pwm: bool,
    synced_at: u64,
    /// Count edges after `synced_at` before the first compare match or overflow: within them
    /// TCNT only counts up (the fast path of a catch-up).
    quiet: u64,
}

impl Channel {
    fn new() -> Self {
        Channel {
            tcr: 0,
            tior: 0,
            tier: 0,
            flags: 0,
            seen: 0,
            tcnt: 0,
            gra: GR_RESET,
            grb: GR_RESET,
            bra: GR_RESET,
            brb: GR_RESET,
            tioca: false,
            running: false,
            pwm: false,
            synced_at: 0,
            quiet: 0,
        }
        .with_quiet()
    }

    fn with_quiet(mut self) -> Self {
        self.recompute_quiet();
        self
    }

    /// Recomputes `quiet` from the current configuration (after every register change and
    /// every catch-up that passed an event). The first wrap of TCNT is itself a compare match
    /// (the clearing value) or an overflow, so TCNT + n never wraps within the quiet edges.
    fn recompute_quiet(&mut self) {
        let orbit = self.orbit();
        let mut first = orbit.first_hit(0xFFFF).unwrap_or(u64::MAX);
        if self.compares_a()
            && let Some(k) = orbit.first_hit(u64::from(self.gra))
        {
            first = first.min(k);
        }
        if self.compares_b()
            && let Some(k) = orbit.first_hit(u64::from(self.grb))
        {
            first = first.min(k);
        }
        self.quiet = first.saturating_sub(1);
    }

    /// log2 of the prescaler, or None for an external clock.
    #[inline]
    fn shift(&self) -> Option<u32> {
        if self.tcr & 0x04 != 0 {
            None
        } else {
            Some(u32::from(self.tcr & 0x03))
        }
    }

    #[inline]
    fn compares_a(&self) -> bool {
        self.pwm || self.tior & 0x04 == 0
    }

    #[inline]
    fn compares_b(&self) -> bool {
        self.pwm || self.tior & 0x40 == 0
    }

    /// The value whose compare match clears TCNT, if any.
    #[inline]
    fn clear_at(&self) -> Option<u16> {
        match (self.tcr >> 5) & 3 {
            CCLR_GRA if self.compares_a() => Some(self.gra),
            CCLR_GRB if self.compares_b() => Some(self.grb),
            _ => None,
        }
    }

    #[inline]
    fn orbit(&self) -> Orbit {
        let v0 = u64::from(self.tcnt);
        match self.clear_at() {
            Some(c) => {
                let c = u64::from(c);
                Orbit {
                    v0,
                    wrap: if v0 <= c { c } else { 0xFFFF },
                    cycle: c + 1,
                }
            }
            None => Orbit {
                v0,
                wrap: 0xFFFF,
                cycle: 0x1_0000,
            },
        }
    }

    /// Count edges in (synced_at, now].
    #[inline]
    fn edges_until(&self, now: u64) -> u64 {
        match self.shift() {
            Some(s) if self.running && now > self.synced_at => (now >> s) - (self.synced_at >> s),
            _ => 0,
        }
    }

    /// The state at `now` (≥ synced_at), without changing the channel.
    fn advanced(&self, now: u64) -> Advanced {
        let n = self.edges_until(now);
        if n <= self.quiet {
            // Only counting in between: TCNT + n cannot wrap here.
            return Advanced {
                flags: self.flags,
                tcnt: self.tcnt.wrapping_add(n as u16),
                tioca: self.tioca,
            };
        }
        let orbit = self.orbit();
        let (ca, la) = if self.compares_a() {
            orbit.hits(u64::from(self.gra), n)
        } else {
            (0, 0)
        };
        let (cb, lb) = if self.compares_b() {
            orbit.hits(u64::from(self.grb), n)
        } else {
            (0, 0)
        };
        let (co, _) = orbit.hits(0xFFFF, n);
        let mut flags = self.flags;
        if ca > 0 {
            flags |= IMFA;
        }
        if cb > 0 {
            flags |= IMFB;
        }
        if co > 0 {
            flags |= OVF;
        }
        let mut tioca = self.tioca;
        if self.pwm {
            // Set at A, cleared at B; simultaneous matches (GRA = GRB) leave it alone.
            if la > lb {
                tioca = true;
            } else if lb > la {
                tioca = false;
            }
        } else if ca > 0 {
            match self.tior & 0x07 {
                1 => tioca = false,
                2 => tioca = true,
                3 => tioca ^= ca % 2 == 1,
                _ => {}
            }
        }
        Advanced {
            flags,
            tcnt: orbit.value_after(n),
            tioca,
        }
    }

    /// Brings the channel to `now`.
    #[inline]
    fn sync(&mut self, now: u64) {
        if now <= self.synced_at {
            return;
        }
        let n = self.edges_until(now);
        if n <= self.quiet {
            self.tcnt = self.tcnt.wrapping_add(n as u16);
            self.quiet -= n;
            self.synced_at = now;
            return;
        }
        let a = self.advanced(now);
        self.flags = a.flags;
        self.tcnt = a.tcnt;
        self.tioca = a.tioca;
        self.synced_at = now;
        self.recompute_quiet();
    }

    /// The state when the first count edge after `synced_at` numbered `k` (1-based) happens.
    #[inline]
    fn edge_time(&self, k: u64) -> Option<u64> {
        let s = self.shift()?;
        ((self.synced_at >> s) + k).checked_shl(s)
    }

    /// Earliest time after the last sync at which an enabled flag that is clear now gets set.
    fn next_irq_time(&self, now: u64) -> Option<u64> {
        if self.tier & TSR_FLAGS == 0 || !self.running || self.shift().is_none() {
            return None;
        }
        let pending = self.advanced(now).flags;
        let want = self.tier & TSR_FLAGS & !pending;
        if want == 0 {
            return None;
        }
        let orbit = self.orbit();
        let mut first: Option<u64> = None;
        let mut consider = |k: Option<u64>| {
            if let Some(k) = k {
                first = Some(first.map_or(k, |f: u64| f.min(k)));
            }
        };
        if want & IMFA != 0 && self.compares_a() {
            consider(orbit.first_hit(u64::from(self.gra)));
        }
        if want & IMFB != 0 && self.compares_b() {
            consider(orbit.first_hit(u64::from(self.grb)));
        }
        if want & OVF != 0 {
            consider(orbit.first_hit(0xFFFF));
        }
        self.edge_time(first?)
    }

    /// Earliest time after `now` at which this channel's flags or TIOCA can change (any
    /// compare match or overflow edge), if it runs.
    fn next_event(&self, now: u64) -> Option<u64> {
        if !self.running {
            return None;
        }
        let s = self.shift()?;
        // Bring a copy to now, then look for the first interesting edge.
        let mut c = self.clone();
        c.sync(now);
        let orbit = c.orbit();
        let mut first: Option<u64> = None;
        for (x, on) in [
            (u64::from(c.gra), c.compares_a()),
            (u64::from(c.grb), c.compares_b()),
            (0xFFFF, true),
        ] {
            if on && let Some(k) = orbit.first_hit(x) {
                first = Some(first.map_or(k, |f| f.min(k)));
            }
        }
        ((c.synced_at >> s) + first?).checked_shl(s)
    }

    fn read(&mut self, off: u32, now: u64) -> u8 {
        self.sync(now);
        match off {
            OFF_TCR => self.tcr | TCR_RESERVED,
            OFF_TIOR => self.tior | TIOR_RESERVED,
            OFF_TIER => self.tier | TIER_TSR_RESERVED,
            OFF_TSR => {
                self.seen |= self.flags;
                self.flags | TIER_TSR_RESERVED
            }
            4 => (self.tcnt >> 8) as u8,
            5 => self.tcnt as u8,
            6 => (self.gra >> 8) as u8,
            7 => self.gra as u8,
            8 => (self.grb >> 8) as u8,
            9 => self.grb as u8,
            10 => (self.bra >> 8) as u8,
            11 => self.bra as u8,
            12 => (self.brb >> 8) as u8,
            13 => self.brb as u8,
            _ => 0xFF,
        }
    }

    fn write(&mut self, off: u32, v: u8, now: u64) {
        self.sync(now);
        let hi = |r: u16| (r & 0x00FF) | (u16::from(v) << 8);
        let lo = |r: u16| (r & 0xFF00) | u16::from(v);
        match off {
            OFF_TCR => self.tcr = v & !TCR_RESERVED,
            OFF_TIOR => self.tior = v & !TIOR_RESERVED,
            OFF_TIER => self.tier = v & TSR_FLAGS,
            OFF_TSR => {
                let clear = self.seen & self.flags & !v & TSR_FLAGS;
                self.flags &= !clear;
                self.seen &= !clear;
            }
            4 => self.tcnt = hi(self.tcnt),
            5 => self.tcnt = lo(self.tcnt),
            6 => self.gra = hi(self.gra),
            7 => self.gra = lo(self.gra),
            8 => self.grb = hi(self.grb),
            9 => self.grb = lo(self.grb),
            10 => self.bra = hi(self.bra),
            11 => self.bra = lo(self.bra),
            12 => self.brb = hi(self.brb),
            13 => self.brb = lo(self.brb),
            _ => {}
        }
        self.recompute_quiet();
    }
}

/// The five-channel ITU.
#[derive(Clone, Debug)]
pub struct Itu {
    ch: [Channel; 5],
    tstr: u8,
    tsnc: u8,
    tmdr: u8,
    tfcr: u8,
    toer: u8,
    tocr: u8,
}

impl Default for Itu {
    fn default() -> Self {
        Self::new()
    }
}

impl Itu {
    /// The ITU after reset: all channels stopped, TCNT = 0, GRs = H'FFFF.
    #[must_use]
    pub fn new() -> Self {
        Itu {
            ch: [
                Channel::new(),
                Channel::new(),
                Channel::new(),
                Channel::new(),
                Channel::new(),
            ],
            tstr: 0,
            tsnc: 0,
            tmdr: 0,
            tfcr: 0,
            toer: TOER_RESET,
            tocr: TOER_RESET,
        }
    }

    /// Brings every channel to `now`.
    pub fn sync(&mut self, now: u64) {
        for c in &mut self.ch {
            c.sync(now);
        }
    }

    /// Brings the channels with an interrupt enabled to `now`, so the interrupt decision that
    /// follows starts from caught-up channels (cheap between compare matches).
    pub fn sync_irq_sources(&mut self, now: u64) {
        for c in &mut self.ch {
            if c.tier != 0 {
                c.sync(now);
            }
        }
    }

    /// Reads a register at `now` (the instant the bus cycle ends).
    pub fn read(&mut self, addr: u32, now: u64) -> u8 {
        if let Some((n, off)) = decode(addr) {
            return self.ch[n].read(off, now);
        }
        match addr {
            TSTR => self.tstr | TSTR_RESERVED,
            TSNC => self.tsnc | TSTR_RESERVED,
            TMDR => self.tmdr | TMDR_RESERVED,
            TFCR => self.tfcr | TFCR_RESERVED,
            TOER => self.toer,
            TOCR => self.tocr,
            _ => 0xFF,
        }
    }

    /// Writes a register at `now`.
    pub fn write(&mut self, addr: u32, value: u8, now: u64) {
        if let Some((n, off)) = decode(addr) {
            self.ch[n].write(off, value, now);
            return;
        }
        match addr {
            TSTR => {
                self.sync(now);
                self.tstr = value & 0x1F;
                for (i, c) in self.ch.iter_mut().enumerate() {
                    c.running = self.tstr & (1 << i) != 0;
                    c.recompute_quiet();
                }
            }
            TSNC => self.tsnc = value & 0x1F,
            TMDR => {
                self.sync(now);
                self.tmdr = value & 0x7F;
                for (i, c) in self.ch.iter_mut().enumerate() {
                    c.pwm = self.tmdr & (1 << i) != 0;
                    c.recompute_quiet();
                }
            }
            TFCR => self.tfcr = value & 0x3F,
            TOER => self.toer = value | 0xC0,
            TOCR => self.tocr = value | 0xEC,
            _ => {}
        }
    }

    /// Writes a 16-bit register (TCNT, GRA, GRB, BRA, BRB; `addr` even) in one bus cycle at
    /// `now`: both bytes change at the same instant. Other addresses are written byte by byte.
    pub fn write16(&mut self, addr: u32, value: u16, now: u64) {
        match decode(addr) {
            Some((n, off)) if off >= OFF_TCNT && off & 1 == 0 => {
                let c = &mut self.ch[n];
                c.sync(now);
                match off {
                    OFF_TCNT => c.tcnt = value,
                    OFF_GRA => c.gra = value,
                    OFF_GRB => c.grb = value,
                    OFF_BRA => c.bra = value,
                    OFF_BRB => c.brb = value,
                    _ => {}
                }
                c.recompute_quiet();
            }
            _ => {
                let [hi, lo] = value.to_be_bytes();
                self.write(addr, hi, now);
                self.write(addr + 1, lo, now);
            }
        }
    }

    /// Appends the ITU's state at `now` (every channel brought to it) relative to `now`: the
    /// registers, flags, counters and outputs, and the prescaler phase (`now` modulo 8, the
    /// largest internal prescaler). Two equal signatures `P` states apart mean the ITU's
    /// future is the same function of time from either instant, shifted by `P`.
    pub fn idle_signature(&mut self, now: u64, out: &mut Vec<u64>) {
        self.sync(now);
        out.extend([
            now & 7,
            u64::from(self.tstr),
            u64::from(self.tsnc),
            u64::from(self.tmdr),
            u64::from(self.tfcr),
            u64::from(self.toer),
            u64::from(self.tocr),
        ]);
        for c in &self.ch {
            out.extend([
                u64::from(c.tcr),
                u64::from(c.tior),
                u64::from(c.tier),
                u64::from(c.flags),
                u64::from(c.seen),
                u64::from(c.tcnt),
                u64::from(c.gra),
                u64::from(c.grb),
                u64::from(c.bra),
                u64::from(c.brb),
                u64::from(c.tioca),
                u64::from(c.running),
                u64::from(c.pwm),
            ]);
        }
    }

    /// Moves every channel `states` later in time without changing its state: right when the
    /// ITU's evolution repeats with a period that divides `states` (see
    /// [`Itu::idle_signature`]).
    pub fn shift(&mut self, states: u64) {
        for c in &mut self.ch {
            c.synced_at += states;
        }
    }

    /// Interrupt requests at `now` as a vector bit mask (bit v = vector v).
    #[must_use]
    pub fn requests(&self, now: u64) -> u64 {
        let mut req = 0u64;
        for (i, c) in self.ch.iter().enumerate() {
            if c.tier == 0 {
                continue;
            }
            let active = c.advanced(now.max(c.synced_at)).flags & c.tier;
            req |= u64::from(active) << VECTOR_IMIA[i];
        }
        req
    }

    /// The earliest state after `now` at which an enabled interrupt that is not requested at
    /// `now` becomes requested (if none will without register accesses: `None`).
    #[must_use]
    pub fn next_irq_time(&self, now: u64) -> Option<u64> {
        self.ch
            .iter()
            .filter_map(|c| c.next_irq_time(now.max(c.synced_at)))
            .min()
    }

    /// The earliest state after `now` at which any channel's flags or TIOCA output change
    /// (compare matches and overflows, enabled or not).
    #[must_use]
    pub fn next_event(&self, now: u64) -> Option<u64> {
        self.ch
            .iter()
            .filter_map(|c| c.next_event(now.max(c.synced_at)))
            .min()
    }

    /// The TIOCA output level of channel `n` (0–4) at `now`, and whether the ITU drives the
    /// pin (PWM mode, or an output-compare setting of IOA). Channels out of range: (false,
    /// false).
    pub fn tioca(&mut self, n: usize, now: u64) -> (bool, bool) {
        let Some(c) = self.ch.get_mut(n) else {
            return (false, false);
        };
        c.sync(now);
        let drives = c.pwm || matches!(c.tior & 0x07, 1..=3);
        (c.tioca, drives)
    }

    /// What channel `n`'s TIOCA does at `now` without changing anything: (level, whether the
    /// ITU drives the pin). Valid for any `now` not before the channel was last brought up to
    /// date (a copy of the ITU taken after a register write answers for every later instant
    /// until the next write: pin traces). Channels out of range: (false, false).
    #[must_use]
    pub fn output_at(&self, n: usize, now: u64) -> (bool, bool) {
        let Some(c) = self.ch.get(n) else {
            return (false, false);
        };
        let drives = c.pwm || matches!(c.tior & 0x07, 1..=3);
        (c.advanced(now.max(c.synced_at)).tioca, drives)
    }

    /// Channel `n`'s interrupt requests at `now` (TSR flags that are set and enabled in TIER,
    /// IMFA/IMFB/OVF bits), without changing anything; valid as [`Itu::output_at`].
    #[must_use]
    pub fn requests_of(&self, n: usize, now: u64) -> u8 {
        self.ch
            .get(n)
            .map_or(0, |c| c.advanced(now.max(c.synced_at)).flags & c.tier)
    }

    /// Whether channel `n` is counting (TSTR.STRn = 1 with an internal clock).
    #[must_use]
    pub fn running(&self, n: usize) -> bool {
        self.ch
            .get(n)
            .is_some_and(|c| c.running && c.shift().is_some())
    }

    /// Whether channel `n` is in PWM mode (TMDR.PWMn).
    #[must_use]
    pub fn pwm_mode(&self, n: usize) -> bool {
        self.ch.get(n).is_some_and(|c| c.pwm)
    }

    /// The steady-state waveform of channel `n`'s TIOCA in PWM mode, from TCR, GRA and GRB:
    /// `None` unless the channel is in PWM mode with an internal clock. A constant output
    /// (only one of the compare matches happens, or both at once) has `high_states` 0 or
    /// `period_states`; for GRA = GRB the level is the one the pin holds (`level`).
    #[must_use]
    pub fn pwm(&self, n: usize, level: bool) -> Option<PwmWave> {
        let c = self.ch.get(n)?;
        if !c.pwm {
            return None;
        }
        let s = c.shift()?;
        let (cycle, top) = match c.clear_at() {
            Some(t) => (u64::from(t) + 1, u64::from(t)),
            None => (0x1_0000, 0xFFFF),
        };
        let period_states = cycle << s;
        let a = u64::from(c.gra);
        let b = u64::from(c.grb);
        // Offset within the cycle (from the clearing edge) of each compare edge.
        let off = |x: u64| (x + 1) % cycle;
        let high_counts = match (a <= top, b <= top) {
            (true, true) if a == b => {
                if level {
                    cycle
                } else {
                    0
                }
            }
            (true, true) => (off(b) + cycle - off(a)) % cycle,
            (true, false) => cycle,
            (false, true) => 0,
            (false, false) => {
                if level {
                    cycle
                } else {
                    0
                }
            }
        };
        Some(PwmWave {
            period_states,
            high_states: high_counts << s,
        })
    }

    /// TCNT of channel `n` at `now` (test and debugging helper; no bus cycle).
    pub fn tcnt(&mut self, n: usize, now: u64) -> u16 {
        self.ch.get_mut(n).map_or(0, |c| {
            c.sync(now);
            c.tcnt
        })
    }
}

impl Peripheral for Itu {
    type Outside<'a, B: Board + 'a> = ();
    const FIRST: u32 = ITU_FIRST;
    const LAST: u32 = ITU_LAST;
    const AFFECTS_IRQ: bool = true;

    #[inline]
    fn read<B: Board>(&mut self, addr: u32, now: u64, (): ()) -> u8 {
        Itu::read(self, addr, now)
    }

    #[inline]
    fn write<B: Board>(&mut self, addr: u32, value: u8, now: u64, (): ()) {
        Itu::write(self, addr, value, now);
    }

    #[inline]
    fn sync<B: Board>(&mut self, now: u64, (): ()) {
        Itu::sync(self, now);
    }

    #[inline]
    fn next_event(&self, now: u64) -> Option<u64> {
        Itu::next_event(self, now)
    }

    #[inline]
    fn requests(&self, now: u64) -> u64 {
        Itu::requests(self, now)
    }

    #[inline]
    fn next_request(&self, now: u64) -> Option<u64> {
        self.next_irq_time(now)
    }

    #[inline]
    fn reset(&mut self) {
        *self = Itu::new();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CH0: u32 = 0xFF_FF64;

    fn setup_ch0(itu: &mut Itu, tcr: u8, gra: u16, grb: u16, now: u64) {
        itu.write(CH0 + OFF_TCR, tcr, now);
        itu.write(CH0 + OFF_GRA, (gra >> 8) as u8, now);
        itu.write(CH0 + OFF_GRA + 1, gra as u8, now);
        itu.write(CH0 + OFF_GRB, (grb >> 8) as u8, now);
        itu.write(CH0 + OFF_GRB + 1, grb as u8, now);
    }

    #[test]
    fn counts_at_the_prescaler_edges() {
        let mut itu = Itu::new();
        setup_ch0(&mut itu, 0x03, 0xFFFF, 0xFFFF, 0); // φ/8, no clear
        itu.write(TSTR, 0x01, 5);
        // Edges at 8, 16, 24, ...
        assert_eq!(itu.tcnt(0, 7), 0);
        assert_eq!(itu.tcnt(0, 8), 1);
        assert_eq!(itu.tcnt(0, 15), 1);
        assert_eq!(itu.tcnt(0, 8 * 1000), 1000);
        itu.write(TSTR, 0x00, 8 * 1000 + 3);
        assert_eq!(itu.tcnt(0, 8 * 5000), 1000);
    }

    #[test]
    fn compare_match_sets_flag_and_clears_counter_one_count_later() {
        let mut itu = Itu::new();
        setup_ch0(&mut itu, 0x20 | 0x03, 99, 0xFFFF, 0); // clear on GRA, φ/8
        itu.write(TSTR, 0x01, 0);
        // TCNT reaches 99 at state 792 and leaves it at 800: flag set at 800.
        assert_eq!(itu.tcnt(0, 799), 99);
        assert_eq!(itu.read(CH0 + OFF_TSR, 799) & IMFA, 0);
        assert_ne!(itu.read(CH0 + OFF_TSR, 800) & IMFA, 0);
        assert_eq!(itu.tcnt(0, 800), 0);
        assert_eq!(itu.tcnt(0, 808), 1);
        // Period 100 counts: 10 periods later the counter is at the same phase.
        assert_eq!(itu.tcnt(0, 800 + 10 * 800 + 16), 2);
    }

    #[test]
    fn flag_clears_only_after_being_read_as_one() {
        let mut itu = Itu::new();
        setup_ch0(&mut itu, 0x20, 9, 0xFFFF, 0); // φ, clear on GRA: match every 10 states
        itu.write(TSTR, 0x01, 0);
        itu.write(CH0 + OFF_TSR, 0xF8, 20); // not read yet: no effect
        assert_ne!(itu.read(CH0 + OFF_TSR, 21) & IMFA, 0);
        itu.write(CH0 + OFF_TSR, !IMFA, 22);
        assert_eq!(itu.read(CH0 + OFF_TSR, 23) & IMFA, 0);
        // Set again at the next match (state 30).
        assert_ne!(itu.read(CH0 + OFF_TSR, 30) & IMFA, 0);
    }

    #[test]
    fn interrupt_request_and_next_time() {
        let mut itu = Itu::new();
        setup_ch0(&mut itu, 0x23, 3124, 0xFFFF, 0); // 1 kHz tick at 25 MHz
        itu.write(CH0 + OFF_TIER, IMFA, 0);
        itu.write(TSTR, 0x01, 0);
        assert_eq!(itu.requests(1000), 0);
        assert_eq!(itu.next_irq_time(1000), Some(25_000));
        assert_eq!(itu.requests(24_999), 0);
        assert_eq!(itu.requests(25_000), 1 << 24);
        assert_eq!(itu.next_event(0), Some(25_000));
    }

    #[test]
    fn overflow_sets_ovf() {
        let mut itu = Itu::new();
        setup_ch0(&mut itu, 0x00, 0x1234, 0x1234, 0);
        itu.write(CH0 + OFF_TCNT, 0xFF, 0);
        itu.write(CH0 + OFF_TCNT + 1, 0xF0, 0);
        itu.write(CH0 + OFF_TIER, OVF, 0);
        itu.write(TSTR, 0x01, 0);
        assert_eq!(itu.next_irq_time(0), Some(16));
        assert_eq!(itu.read(CH0 + OFF_TSR, 15) & OVF, 0);
        assert_ne!(itu.read(CH0 + OFF_TSR, 16) & OVF, 0);
        assert_eq!(itu.tcnt(0, 16), 0);
    }

    #[test]
    fn pwm_waveform_from_gra_and_grb() {
        let mut itu = Itu::new();
        setup_ch0(&mut itu, 0x23, 999, 249, 0);
        itu.write(TMDR, 0x01, 0);
        itu.write(TSTR, 0x01, 0);
        let w = itu.pwm(0, false).unwrap();
        assert_eq!(w.period_states, 1000 * 8);
        assert_eq!(w.high_states, 250 * 8);
        // The pin: first compare A at 8000 sets it, compare B 250 counts later clears it.
        assert_eq!(itu.tioca(0, 7999), (false, true));
        assert_eq!(itu.tioca(0, 8000), (true, true));
        assert_eq!(itu.tioca(0, 8000 + 2000 - 1), (true, true));
        assert_eq!(itu.tioca(0, 8000 + 2000), (false, true));
        // Far ahead, computed in one jump: same phase rule.
        let t = 8000 + 1_000_000 * 8000;
        assert_eq!(itu.tioca(0, t + 1999), (true, true));
        assert_eq!(itu.tioca(0, t + 2000), (false, true));
    }

    #[test]
    fn orbit_from_above_the_clearing_value_overflows_first() {
        let o = Orbit {
            v0: 0xFFF0,
            wrap: 0xFFFF,
            cycle: 100,
        };
        assert_eq!(o.first_hit(0xFFFF), Some(16));
        assert_eq!(o.first_hit(99), Some(16 + 100));
        assert_eq!(o.first_hit(0xFFF5), Some(6));
        assert_eq!(o.first_hit(200), None);
        assert_eq!(o.value_after(16), 0);
        assert_eq!(o.value_after(16 + 250), 50);
        assert_eq!(o.hits(99, 16 + 100 + 300), (4, 16 + 100 + 300));
    }
}
