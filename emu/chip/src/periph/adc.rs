//! The 10-bit A/D converter of the H8/3052F at register level (docs/design.md §3.2; H8/3052F hardware
//! manual, section 15 "A/D Converter").
//!
//! # Registers
//! - ADDRA–ADDRD (H'FFFFE0–E7): 16-bit results, left-justified: the high byte holds result
//!   bits 9..2, bits 7–6 of the low byte hold bits 1..0, the rest read 0. AN0/AN4 → ADDRA,
//!   AN1/AN5 → ADDRB, AN2/AN6 → ADDRC, AN3/AN7 → ADDRD. The converter sits on the 8-bit bus:
//!   reading the high byte passes the low byte into a temporary register, and reading the low
//!   byte returns that register (the manual: read the upper byte first). A word read does
//!   exactly that; a lone low-byte read returns the low byte latched by the last high-byte read.
//! - ADCSR (H'FFFFE8): ADF (bit 7, A/D end flag; cleared by reading it as 1 then writing 0),
//!   ADIE (6), ADST (5), SCAN (4), CKS (3), CH2–0.
//! - ADCR (H'FFFFE9): TRGE (bit 7) is stored; the other bits read 1. The ADTRG pin is not
//!   connected, so external triggering never starts a conversion.
//!
//! # Timing (manual: "Input Sampling and A/D Conversion Time", Table "A/D conversion time")
//! A conversion starts when ADST is written 1 (at the end of that bus cycle). The first
//! conversion takes t_CONV = [`CONV_STATES_CKS0`] = 266 states with CKS = 0 and
//! [`CONV_STATES_CKS1`] = 134 with CKS = 1 (the table's maxima, docs/design.md §3.2): the start delay
//! t_D (10–17 / 6–9 states, used at its maximum 17 / 9), then the input sampling time t_SPL
//! (63 / 31 states), then the successive approximation. The sample-and-hold keeps the input
//! at the **end of the sampling window**, so the analog input is sampled at
//! `start + t_D + t_SPL` = start + [`SAMPLE_OFFSET_CKS0`] (80) or [`SAMPLE_OFFSET_CKS1`] (40)
//! states, and the result is ready (ADDR written, ADF set) at start + t_CONV. In scan mode the
//! second and later conversions take a fixed [`SCAN_CONV_STATES_CKS0`] = 256 /
//! [`SCAN_CONV_STATES_CKS1`] = 128 states (manual, same section); each samples its input the
//! same 186 / 94 states before its end as the first.
//!
//! # Modes
//! - Single mode (SCAN = 0): one conversion of channel CH; at its end the result goes to its
//!   ADDR, ADF is set and ADST is cleared.
//! - Scan mode (SCAN = 1): channels AN0..ANn (CH2 = 0) or AN4..ANn (CH2 = 1) with n = CH, in
//!   order, repeated until ADST is cleared; ADF is set at the end of each round (after the
//!   last channel of the group).
//! - ADI (vector 60) is requested while ADF = 1 and ADIE = 1.
//! - Writing ADST = 0 stops the conversion under way (its result is not stored). Changes of
//!   SCAN, CKS or CH while ADST = 1 take effect at the next start (the manual asks to change
//!   them only with ADST = 0).
//!
//! # Lazy synchronisation
//! The converter keeps the time it was last brought up to date; a later access works out
//! which conversions ended since, in O(1). The board is asked for the input voltage with the
//! **sampling instant** of each conversion whose result lands in a register; a conversion
//! whose result is overwritten before anyone could read it (a channel converted twice between
//! two accesses in scan mode) is not sampled. Volts become codes with [`code10`].
//!
//! # Transfer function
//! The converter is the ideal 10-bit converter of the hardware manual's "A/D conversion
//! accuracy definitions" figure: the code steps from `k − 1` to `k` exactly at
//! `k · AVref / 1024`, i.e. `code10(V) = max { k ∈ 0..=1023 : V ≥ k · AVref / 1024 }`, with NaN
//! and negative volts reading 0 and everything from `1023 · AVref / 1024` up reading 1023. The
//! result sits left-justified in ADDRn: `ADDRn = code10 << 6` (docs/design.md §3.2).

use super::Peripheral;
use crate::pins::Board;

/// AVref, the converter's full scale: 5.0 V (the AKI-H8/3052F board ties AVref to Vcc,
/// docs/design.md §3.2).
pub const AVREF_VOLTS: f64 = 5.0;
/// Number of 10-bit codes, 1024.
const CODES10: u16 = 1024;
/// Largest 10-bit code, 1023.
pub const CODE10_MAX: u16 = CODES10 - 1;
/// One 10-bit step, AVref / 1024 (exact in `f64`).
const LSB_VOLTS: f64 = AVREF_VOLTS / CODES10 as f64;
/// Left shift of the 10-bit result in ADDRn (bits 15–6 hold the code, bits 5–0 read 0).
const ADDR_SHIFT: u32 = 6;

/// The transition voltage into code `k`: `k · AVref / 1024` (exact in `f64`; `k` above 1024
/// taken as 1024).
fn threshold_volts(k: u16) -> f64 {
    f64::from(k.min(CODES10)) * LSB_VOLTS
}

/// The 10-bit conversion result of `volts` on an analog pin (see the module docs), exact at
/// every code boundary.
#[must_use]
pub fn code10(volts: f64) -> u16 {
    // NaN and everything below the first transition read 0.
    if volts.is_nan() || volts < LSB_VOLTS {
        return 0;
    }
    if volts >= threshold_volts(CODE10_MAX) {
        return CODE10_MAX;
    }
    // The step is exact in f64 and division is correctly rounded, so the quotient is never
    // below the true code k and at most rounds up onto k + 1; the exact threshold check then
    // steps back once.
    let k = (volts / LSB_VOLTS) as u16; // in 1..=1023 here
    if volts < threshold_volts(k) { k - 1 } else { k }
}

/// The 16-bit contents of ADDRn for a 10-bit result (bits above 10 ignored).
#[must_use]
pub fn addr_register(code10: u16) -> u16 {
    (code10 & CODE10_MAX) << ADDR_SHIFT
}

/// Address of ADDRA (high byte; low byte at +1) (docs/design.md §3.2: H'FFFFE0).
pub const ADDRA: u32 = 0xFF_FFE0;
/// Address of ADDRB.
pub const ADDRB: u32 = 0xFF_FFE2;
/// Address of ADDRC.
pub const ADDRC: u32 = 0xFF_FFE4;
/// Address of ADDRD (low byte at H'FFFFE7).
pub const ADDRD: u32 = 0xFF_FFE6;
/// Address of ADCSR, A/D control/status register (docs/design.md §3.2: H'FFFFE8).
pub const ADCSR: u32 = 0xFF_FFE8;
/// Address of ADCR, A/D control register (H'FFFFE9).
pub const ADCR: u32 = 0xFF_FFE9;

/// ADCSR bit 7: A/D end flag.
pub const ADCSR_ADF: u8 = 0x80;
/// ADCSR bit 6: A/D interrupt enable.
pub const ADCSR_ADIE: u8 = 0x40;
/// ADCSR bit 5: A/D start.
pub const ADCSR_ADST: u8 = 0x20;
/// ADCSR bit 4: scan mode.
pub const ADCSR_SCAN: u8 = 0x10;
/// ADCSR bit 3: clock select (1 = 134 states per conversion).
pub const ADCSR_CKS: u8 = 0x08;
/// ADCSR bits 2–0: channel select.
pub const ADCSR_CH: u8 = 0x07;
/// ADCR bit 7: external trigger enable.
pub const ADCR_TRGE: u8 = 0x80;
/// ADCR bits 6–0 are reserved and read 1 (reset value H'7F).
pub const ADCR_RESERVED: u8 = 0x7F;

/// A/D interrupt ADI vector (docs/design.md §4.1: 60).
pub const VECTOR_ADI: u8 = 60;

/// Total conversion time with CKS = 0, in states (docs/design.md §3.2; manual Table "A/D conversion
/// time", t_CONV max).
pub const CONV_STATES_CKS0: u64 = 266;
/// Total conversion time with CKS = 1, in states (docs/design.md §3.2; t_CONV max).
pub const CONV_STATES_CKS1: u64 = 134;
/// A/D conversion start delay t_D with CKS = 0, at its maximum (manual: 10–17 states).
pub const START_DELAY_STATES_CKS0: u64 = 17;
/// A/D conversion start delay t_D with CKS = 1, at its maximum (manual: 6–9 states).
pub const START_DELAY_STATES_CKS1: u64 = 9;
/// Input sampling time t_SPL with CKS = 0 (manual: 63 states).
pub const SAMPLING_STATES_CKS0: u64 = 63;
/// Input sampling time t_SPL with CKS = 1 (manual: 31 states).
pub const SAMPLING_STATES_CKS1: u64 = 31;
/// Sampling instant after the start with CKS = 0: the end of the sampling window, t_D + t_SPL.
pub const SAMPLE_OFFSET_CKS0: u64 = START_DELAY_STATES_CKS0 + SAMPLING_STATES_CKS0;
/// Sampling instant after the start with CKS = 1: t_D + t_SPL.
pub const SAMPLE_OFFSET_CKS1: u64 = START_DELAY_STATES_CKS1 + SAMPLING_STATES_CKS1;
/// Second and later conversions of a scan with CKS = 0, in states (manual: 256, fixed).
pub const SCAN_CONV_STATES_CKS0: u64 = 256;
/// Second and later conversions of a scan with CKS = 1, in states (manual: 128, fixed).
pub const SCAN_CONV_STATES_CKS1: u64 = 128;

/// Timing of one configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Timing {
    first: u64,
    next: u64,
    /// States from the sampling instant to the end of a conversion.
    sample_to_end: u64,
}

const fn timing(cks: bool) -> Timing {
    if cks {
        Timing {
            first: CONV_STATES_CKS1,
            next: SCAN_CONV_STATES_CKS1,
            sample_to_end: CONV_STATES_CKS1 - SAMPLE_OFFSET_CKS1,
        }
    } else {
        Timing {
            first: CONV_STATES_CKS0,
            next: SCAN_CONV_STATES_CKS0,
            sample_to_end: CONV_STATES_CKS0 - SAMPLE_OFFSET_CKS0,
        }
    }
}

/// A run of conversions started by one ADST write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Run {
    /// When ADST was written 1.
    start: u64,
    scan: bool,
    timing: Timing,
    /// First channel (0 or 4 in scan mode; CH in single mode).
    first_channel: u8,
    /// Channels per round (1 in single mode).
    channels: u64,
    /// Conversions already completed and stored.
    done: u64,
}

impl Run {
    /// End time of conversion k (0-based).
    #[inline]
    fn end(&self, k: u64) -> u64 {
        self.start + self.timing.first + k * self.timing.next
    }

    /// How long the run converts: one conversion in single mode, until stopped in scan mode.
    #[inline]
    fn length(&self) -> u64 {
        if self.scan {
            u64::MAX
        } else {
            self.timing.first
        }
    }

    /// Conversions completed by `now` (capped at 1 in single mode).
    #[inline]
    fn completed_by(&self, now: u64) -> u64 {
        let first_end = self.start + self.timing.first;
        if now < first_end {
            0
        } else if !self.scan {
            1
        } else {
            1 + (now - first_end) / self.timing.next
        }
    }

    /// The first conversion index ≥ k that ends a round (sets ADF).
    #[inline]
    fn round_end_from(&self, k: u64) -> u64 {
        let n = self.channels;
        k + (n - 1 - k % n)
    }

    #[inline]
    fn channel(&self, k: u64) -> u8 {
        // channels ≤ 4, so the remainder fits.
        self.first_channel + (k % self.channels) as u8
    }
}

/// The A/D converter.
#[derive(Clone, Debug)]
pub struct Adc {
    /// ADDRA–ADDRD, left-justified.
    data: [u16; 4],
    /// Low byte latched by the last high-byte read.
    temp: u8,
    /// ADIE, SCAN, CKS, CH as written.
    control: u8,
    adf: bool,
    adf_seen: bool,
    adcr: u8,
    run: Option<Run>,
    /// Conversions stored since reset (statistics).
    conversions: u64,
    /// Runs started (ADST written 1 while idle) since reset.
    starts: u64,
    /// States of the runs that have ended (the converter busy: its analog supply draws its
    /// conversion current), since reset.
    converting_states: u64,
}

impl Default for Adc {
    fn default() -> Self {
        Self::new()
    }
}

impl Adc {
    /// The converter after reset: idle, results 0.
    #[must_use]
    pub const fn new() -> Self {
        Adc {
            data: [0; 4],
            temp: 0,
            control: 0,
            adf: false,
            adf_seen: false,
            adcr: 0,
            run: None,
            conversions: 0,
            starts: 0,
            converting_states: 0,
        }
    }

    /// Whether a conversion run is under way (ADST = 1), as of the last synchronisation.
    #[must_use]
    pub const fn busy(&self) -> bool {
        self.run.is_some()
    }

    /// Runs started since reset (each write of ADST = 1 to an idle converter): how an observer
    /// outside the chip sees a program begin to sample its inputs.
    #[must_use]
    pub const fn starts(&self) -> u64 {
        self.starts
    }

    /// ADDRA–ADDRD as the converter holds them (left-justified, register `n` = 0–3), without
    /// the register read's side effects. Call after the MCU was synchronised.
    #[must_use]
    pub const fn data(&self, n: usize) -> u16 {
        self.data[n & 3]
    }

    /// Conversions stored in ADDRA–D since reset.
    #[must_use]
    pub const fn conversions(&self) -> u64 {
        self.conversions
    }

    /// States the converter has spent converting since reset, up to `now`: from each run's
    /// ADST = 1 to its end (a single conversion's end, or ADST cleared in scan mode). While it
    /// converts its analog supply draws the conversion current ([`crate::power`]).
    /// Call after the MCU was synchronised.
    #[must_use]
    pub fn converting_states(&self, now: u64) -> u64 {
        self.converting_states
            + self
                .run
                .map_or(0, |r| now.saturating_sub(r.start).min(r.length()))
    }

    /// Brings the converter to `now`: stores the results of the conversions that ended by
    /// then, asking `volts(channel, sampling_instant)` for each stored one, in time order.
    pub fn sync(&mut self, now: u64, volts: &mut impl FnMut(u8, u64) -> f64) {
        let Some(mut run) = self.run else {
            return;
        };
        if now < run.end(run.done) {
            return;
        }
        let completed = run.completed_by(now);
        if completed <= run.done {
            return;
        }
        // Only the last conversion of each channel can still be read: sample those.
        let from = run.done.max(completed.saturating_sub(run.channels));
        for k in from..completed {
            let ch = run.channel(k);
            let t_sample = run.end(k) - run.timing.sample_to_end;
            let code = code10(volts(ch, t_sample));
            self.data[usize::from(ch & 3)] = addr_register(code);
        }
        self.conversions += completed - run.done;
        if run.round_end_from(run.done) < completed {
            self.adf = true;
        }
        run.done = completed;
        self.run = if run.scan {
            Some(run)
        } else {
            self.converting_states += run.timing.first;
            None
        };
    }

    /// ADF at `now` without changing anything.
    #[inline]
    fn adf_at(&self, now: u64) -> bool {
        self.adf
            || self
                .run
                .is_some_and(|r| r.completed_by(now) > r.round_end_from(r.done))
    }

    /// ADST and ADF as ADCSR shows them at `now`, without changing anything: ADST is 1 from
    /// the start of a run until its conversion ends (single mode) or until software clears it
    /// (scan mode); ADF is set at the end of each round. Valid for any `now` not before the
    /// converter was last brought up to date (a copy taken after a register write answers for
    /// every later instant until the next write: pin traces).
    #[must_use]
    pub fn status_at(&self, now: u64) -> (bool, bool) {
        let adst = self
            .run
            .is_some_and(|r| r.scan || r.completed_by(now) <= r.done);
        (adst, self.adf_at(now))
    }

    /// The ADI request at `now` as a vector bit mask.
    #[inline]
    #[must_use]
    pub fn requests(&self, now: u64) -> u64 {
        if self.control & ADCSR_ADIE != 0 && self.adf_at(now) {
            1u64 << VECTOR_ADI
        } else {
            0
        }
    }

    /// When ADF will next be set (the end of the current round), if a run is under way and
    /// ADF is clear at `now`.
    #[must_use]
    pub fn next_adf_time(&self, now: u64) -> Option<u64> {
        let r = self.run?;
        if self.adf_at(now) {
            return None;
        }
        // ADF clear at `now` means the round under way has not ended yet.
        Some(r.end(r.round_end_from(r.done)))
    }

    /// The earliest state after `now` at which ADI becomes requested, if it will.
    #[must_use]
    pub fn next_irq_time(&self, now: u64) -> Option<u64> {
        if self.control & ADCSR_ADIE == 0 {
            return None;
        }
        self.next_adf_time(now)
    }

    /// The earliest state after `now` at which the converter next needs attention: the next
    /// sampling instant or conversion end.
    #[must_use]
    pub fn next_event(&self, now: u64) -> Option<u64> {
        let r = self.run?;
        let k = r.done.max(r.completed_by(now));
        if !r.scan && k >= 1 {
            return None;
        }
        let end = r.end(k);
        let sample = end - r.timing.sample_to_end;
        Some(if sample > now { sample } else { end })
    }

    /// Reads a register at `now` (call [`Adc::sync`] first).
    pub fn read(&mut self, addr: u32) -> u8 {
        match addr {
            ADDRA..=0xFF_FFE7 => {
                let i = ((addr - ADDRA) / 2) as usize;
                if addr & 1 == 0 {
                    let [hi, lo] = self.data[i].to_be_bytes();
                    self.temp = lo;
                    hi
                } else {
                    self.temp
                }
            }
            ADCSR => {
                if self.adf {
                    self.adf_seen = true;
                }
                let mut v = self.control;
                if self.adf {
                    v |= ADCSR_ADF;
                }
                if self.run.is_some() {
                    v |= ADCSR_ADST;
                }
                v
            }
            ADCR => self.adcr | ADCR_RESERVED,
            _ => 0xFF,
        }
    }

    /// Writes a register at `now` (call [`Adc::sync`] first). ADDRA–D are read-only.
    pub fn write(&mut self, addr: u32, value: u8, now: u64) {
        match addr {
            ADCSR => {
                if value & ADCSR_ADF == 0 && self.adf && self.adf_seen {
                    self.adf = false;
                    self.adf_seen = false;
                }
                self.control = value & (ADCSR_ADIE | ADCSR_SCAN | ADCSR_CKS | ADCSR_CH);
                let start = value & ADCSR_ADST != 0;
                match (self.run.is_some(), start) {
                    (false, true) => {
                        self.starts += 1;
                        let scan = value & ADCSR_SCAN != 0;
                        let ch = value & ADCSR_CH;
                        self.run = Some(Run {
                            start: now,
                            scan,
                            timing: timing(value & ADCSR_CKS != 0),
                            first_channel: if scan { ch & 4 } else { ch },
                            channels: if scan { u64::from(ch & 3) + 1 } else { 1 },
                            done: 0,
                        });
                    }
                    (true, false) => {
                        if let Some(r) = self.run.take() {
                            self.converting_states += now.saturating_sub(r.start).min(r.length());
                        }
                    }
                    _ => {}
                }
            }
            ADCR => self.adcr = value & ADCR_TRGE,
            _ => {}
        }
    }
}

impl Peripheral for Adc {
    /// The board, for the volts on a channel at a sampling instant (its sensors).
    type Outside<'a, B: Board + 'a> = &'a mut B;
    const FIRST: u32 = ADDRA;
    const LAST: u32 = ADCR;
    const AFFECTS_IRQ: bool = true;

    /// Catches up (sampling the conversions that ended), then reads.
    fn read<B: Board>(&mut self, addr: u32, now: u64, board: &mut B) -> u8 {
        Adc::sync(self, now, &mut |ch, t| board.analog_volts(ch, t));
        Adc::read(self, addr)
    }

    /// Catches up, then writes.
    fn write<B: Board>(&mut self, addr: u32, value: u8, now: u64, board: &mut B) {
        Adc::sync(self, now, &mut |ch, t| board.analog_volts(ch, t));
        Adc::write(self, addr, value, now);
    }

    fn sync<B: Board>(&mut self, now: u64, board: &mut B) {
        Adc::sync(self, now, &mut |ch, t| board.analog_volts(ch, t));
    }

    #[inline]
    fn next_event(&self, now: u64) -> Option<u64> {
        Adc::next_event(self, now)
    }

    #[inline]
    fn requests(&self, now: u64) -> u64 {
        Adc::requests(self, now)
    }

    #[inline]
    fn next_request(&self, now: u64) -> Option<u64> {
        self.next_irq_time(now)
    }

    #[inline]
    fn reset(&mut self) {
        *self = Adc::new();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constant(v: f64) -> impl FnMut(u8, u64) -> f64 {
        move |_, _| v
    }

    #[test]
    fn single_conversion_takes_266_states() {
        let mut adc = Adc::new();
        let mut f = constant(2.5);
        adc.write(ADCSR, ADCSR_ADST | 2, 100);
        adc.sync(365, &mut f);
        assert_eq!(adc.read(ADCSR) & (ADCSR_ADF | ADCSR_ADST), ADCSR_ADST);
        adc.sync(366, &mut f);
        assert_eq!(adc.read(ADCSR) & (ADCSR_ADF | ADCSR_ADST), ADCSR_ADF);
        // 2.5 V = code 512: ADDRC = H'8000.
        assert_eq!(adc.read(ADDRC), 0x80);
        assert_eq!(adc.read(ADDRC + 1), 0x00);
        assert_eq!(adc.conversions(), 1);
    }

    #[test]
    fn cks1_conversion_takes_134_states_and_samples_at_40() {
        let mut adc = Adc::new();
        let mut asked = Vec::new();
        let mut f = |ch: u8, t: u64| {
            asked.push((ch, t));
            1.0
        };
        adc.write(ADCSR, ADCSR_ADST | ADCSR_CKS | 1, 0);
        adc.sync(133, &mut f);
        assert!(adc.busy());
        adc.sync(134, &mut f);
        assert!(!adc.busy());
        assert_eq!(asked, vec![(1, 40)]);
    }

    #[test]
    fn scan_repeats_in_order_with_256_state_conversions() {
        let mut adc = Adc::new();
        let mut asked = Vec::new();
        let mut f = |ch: u8, t: u64| {
            asked.push((ch, t));
            f64::from(ch)
        };
        adc.write(ADCSR, ADCSR_ADST | ADCSR_SCAN | 2, 0); // AN0..AN2
        for t in [266, 266 + 256, 266 + 512, 266 + 768] {
            adc.sync(t, &mut f);
        }
        let samples: Vec<(u8, u64)> = vec![(0, 80), (1, 80 + 256), (2, 80 + 512), (0, 80 + 768)];
        assert_eq!(asked, samples);
        assert_eq!(
            adc.read(ADCSR) & (ADCSR_ADF | ADCSR_ADST),
            ADCSR_ADF | ADCSR_ADST
        );
    }
}
