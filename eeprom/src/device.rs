//! One Microchip 24LC256 at pin level: what it does with the SDA and SCL levels it sees over
//! time, its array, its write cycle, its wear and what a power cut does to it.

use std::collections::VecDeque;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use seeding::Purpose;

use crate::cells::Cells;
use crate::clock::Clock;
use crate::datasheet::{
    ARRAY_BYTES, CONTROL_CODE, ENDURANCE_CYCLES, F_CLK_MAX_HZ, FIRST_DEVICE_ADDRESS,
    LAST_DEVICE_ADDRESS, MAX_MEMORY_ADDRESS, PAGE_BYTES, PAGES, T_AA_MAX_NS, T_BUF_MIN_NS,
    T_HD_STA_MIN_NS, T_HIGH_MIN_NS, T_LOW_MIN_NS, T_OUTPUT_DELAY_MIN_NS, T_SU_DAT_MIN_NS,
    T_SU_STA_MIN_NS, T_SU_STO_MIN_NS, T_WC_MAX_NS, T_WC_MODEL_MIN_NS,
};
use crate::error::EepromError;

/// Default probability that one bit of a page becomes stuck during one write cycle once the
/// page is past its endurance limit. Not a datasheet figure (DS21203 gives no failure
/// statistics, only the characterised 1 000 000 cycles): 1/1024 makes a worn page show about
/// one new stuck bit every two writes, so wear shows up quickly in a simulation.
pub const DEFAULT_STUCK_BIT_PROBABILITY: f64 = 1.0 / 1024.0;

pub use crate::datasheet::ERASED_BYTE;

/// Most timing violations kept in detail (all are counted).
const VIOLATION_LOG_LEN: usize = 64;

/// Configuration of one 24LC256. Build with [`DeviceConfig::new`], adjust fields, then pass
/// to [`Eeprom24lc256::new`], which validates it.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceConfig {
    /// 7-bit bus address, 0x50..=0x57 (set by the chip's A2..A0 pins).
    pub address: u8,
    /// MCU clock φ the device's times are counted in (default 25 MHz).
    pub clock_hz: u32,
    /// Shortest write cycle time drawn, in ns (3 000 000 ..= 5 000 000).
    pub t_wc_min_ns: u64,
    /// Longest write cycle time drawn, in ns (≥ `t_wc_min_ns`, ≤ 5 000 000, the datasheet T_WC).
    pub t_wc_max_ns: u64,
    /// Delay from SCL falling to the device's SDA output changing, in ns (300 ..= 900; default
    /// 900, the datasheet's worst case T_AA).
    pub output_delay_ns: u64,
    /// Writes a page takes before stuck bits may appear (default 1 000 000; ≥ 1; a small value
    /// makes wear testable).
    pub endurance_cycles: u32,
    /// Probability that a bit of a page past its limit becomes stuck in one write cycle (0..=1).
    pub stuck_bit_probability: f64,
    /// Seed of the device's random streams (write cycle time, power-cut corruption, wear). Each
    /// purpose uses its own ChaCha8 generator seeded with `seeding::derive(seed, address,
    /// purpose)`, so two chips may share a seed.
    pub seed: u64,
}

impl DeviceConfig {
    /// Datasheet defaults for a chip at `address` counting in the MCU's `clock_hz`, random
    /// streams from `seed`.
    #[must_use]
    pub fn new(address: u8, seed: u64, clock_hz: u32) -> DeviceConfig {
        DeviceConfig {
            address,
            clock_hz,
            t_wc_min_ns: T_WC_MODEL_MIN_NS,
            t_wc_max_ns: T_WC_MAX_NS,
            output_delay_ns: T_AA_MAX_NS,
            endurance_cycles: ENDURANCE_CYCLES,
            stuck_bit_probability: DEFAULT_STUCK_BIT_PROBABILITY,
            seed,
        }
    }
}

/// A timing rule of DS21203 Table 1-2 the device watches the master keep.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TimingCheck {
    /// T_HIGH: SCL high at least 600 ns.
    SclHigh,
    /// T_LOW: SCL low at least 1 300 ns.
    SclLow,
    /// F_CLK: SCL rising edges at least 2 500 ns apart (400 kHz).
    ClockPeriod,
    /// T_SU:DAT: SDA stable at least 100 ns before SCL rises.
    DataSetup,
    /// T_HD:STA: SCL stays high at least 600 ns after the START's SDA fall.
    StartHold,
    /// T_SU:STA: SCL high at least 600 ns before a (repeated) START.
    StartSetup,
    /// T_SU:STO: SCL high at least 600 ns before the STOP's SDA rise.
    StopSetup,
    /// T_BUF: bus free at least 1 300 ns between a STOP and the next START.
    BusFree,
}

impl TimingCheck {
    /// The datasheet minimum this check enforces, in ns.
    #[must_use]
    pub fn min_ns(self) -> u64 {
        match self {
            TimingCheck::SclHigh => T_HIGH_MIN_NS,
            TimingCheck::SclLow => T_LOW_MIN_NS,
            TimingCheck::ClockPeriod => 1_000_000_000_u64.div_ceil(F_CLK_MAX_HZ),
            TimingCheck::DataSetup => T_SU_DAT_MIN_NS,
            TimingCheck::StartHold => T_HD_STA_MIN_NS,
            TimingCheck::StartSetup => T_SU_STA_MIN_NS,
            TimingCheck::StopSetup => T_SU_STO_MIN_NS,
            TimingCheck::BusFree => T_BUF_MIN_NS,
        }
    }
}

/// One broken timing rule, as the device saw it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimingViolation {
    /// The rule.
    pub check: TimingCheck,
    /// When the too-early edge happened, in states.
    pub at_states: u64,
    /// The interval measured, in states.
    pub measured_states: u64,
    /// The datasheet minimum, in ns.
    pub min_ns: u64,
}

/// Watches line transitions for datasheet timing violations. It does not change what the
/// device does (a real chip may misbehave in many ways; this one just reports).
#[derive(Clone, Debug)]
struct TimingMonitor {
    /// Minimum of each check in whole states (`TimingCheck as usize` indexes it).
    min_states: [u64; 8],
    last_rise: Option<u64>,
    last_fall: Option<u64>,
    last_data_change: Option<u64>,
    last_start: Option<u64>,
    last_stop: Option<u64>,
    log: Vec<TimingViolation>,
    count: u64,
}

impl TimingMonitor {
    fn new(clock: Clock) -> Self {
        let checks = [
            TimingCheck::SclHigh,
            TimingCheck::SclLow,
            TimingCheck::ClockPeriod,
            TimingCheck::DataSetup,
            TimingCheck::StartHold,
            TimingCheck::StartSetup,
            TimingCheck::StopSetup,
            TimingCheck::BusFree,
        ];
        // `measured · 1e9 ≥ min_ns · φ` ⇔ `measured ≥ ceil(min_ns · φ / 1e9)`: exact.
        let min_states = checks.map(|c| clock.states_at_least(c.min_ns()));
        TimingMonitor {
            min_states,
            last_rise: None,
            last_fall: None,
            last_data_change: None,
            last_start: None,
            last_stop: None,
            log: Vec::new(),
            count: 0,
        }
    }

    fn forget_edges(&mut self) {
        self.last_rise = None;
        self.last_fall = None;
        self.last_data_change = None;
        self.last_start = None;
        self.last_stop = None;
    }

    fn check(&mut self, check: TimingCheck, from: Option<u64>, now: u64) {
        let Some(from) = from else { return };
        let measured = now.saturating_sub(from);
        if measured < self.min_states[check as usize] {
            let min_ns = check.min_ns();
            self.count += 1;
            if self.log.len() < VIOLATION_LOG_LEN {
                self.log.push(TimingViolation {
                    check,
                    at_states: now,
                    measured_states: measured,
                    min_ns,
                });
            }
        }
    }

    fn scl(&mut self, now: u64, high: bool) {
        if high {
            self.check(TimingCheck::SclLow, self.last_fall, now);
            self.check(TimingCheck::ClockPeriod, self.last_rise, now);
            // Setup counts only for an SDA change made in this low phase.
            if let (Some(d), Some(f)) = (self.last_data_change, self.last_fall)
                && d >= f
            {
                self.check(TimingCheck::DataSetup, Some(d), now);
            }
            self.last_rise = Some(now);
        } else {
            self.check(TimingCheck::SclHigh, self.last_rise, now);
            if let (Some(s), Some(r)) = (self.last_start, self.last_rise)
                && s >= r
            {
                self.check(TimingCheck::StartHold, Some(s), now);
            }
            self.last_fall = Some(now);
        }
    }

    fn sda(&mut self, now: u64, high: bool, scl_high: bool) {
        if !scl_high {
            self.last_data_change = Some(now);
        } else if high {
            self.check(TimingCheck::StopSetup, self.last_rise, now);
            self.last_stop = Some(now);
        } else {
            self.check(TimingCheck::StartSetup, self.last_rise, now);
            if let Some(stop) = self.last_stop
                && self.last_rise.is_none_or(|r| stop >= r)
            {
                self.check(TimingCheck::BusFree, Some(stop), now);
            }
            self.last_start = Some(now);
        }
    }
}

/// What the I²C front end is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    /// Waiting for a START (standby).
    Standby,
    /// Receiving the control byte.
    Control,
    /// Receiving the high address byte.
    AddrHigh,
    /// Receiving the low address byte.
    AddrLow,
    /// Receiving data bytes into the page buffer.
    WriteData,
    /// Sending data bytes.
    Read,
    /// Not addressed, or the master ended a read: ignore clocks until START or STOP.
    Wait,
}

/// One internally timed write cycle, started by a STOP.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WriteCycleInfo {
    /// The page written (0..=511).
    pub page: u16,
    /// Bytes loaded into the page buffer (1..=64).
    pub bytes: u8,
    /// When the cycle started (the STOP), in states.
    pub start_states: u64,
    /// When the cycle ends: from this state on the page holds the new data.
    pub end_states: u64,
}

#[derive(Clone, Debug)]
struct WriteCycle {
    info: WriteCycleInfo,
    data: [u8; PAGE_BYTES],
    loaded: u64,
}

/// What a power cut did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct PowerCutOutcome {
    /// The write cycle the cut interrupted, if any: its page is now undefined.
    pub interrupted_write: Option<WriteCycleInfo>,
    /// Whether a page-write transfer was under way (bytes loaded, no STOP yet): nothing of it
    /// is written.
    pub discarded_transfer: bool,
}

/// Counters of bus activity seen by one device.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct DeviceStats {
    /// STARTs (and repeated STARTs) seen while powered.
    pub starts: u64,
    /// STOPs seen while powered.
    pub stops: u64,
    /// Control bytes addressed to this chip and acknowledged.
    pub control_acks: u64,
    /// Control bytes addressed to this chip but not acknowledged because a write cycle was running.
    pub busy_nacks: u64,
    /// Address and data bytes received and acknowledged.
    pub bytes_received: u64,
    /// Data bytes sent.
    pub bytes_sent: u64,
    /// Write cycles started.
    pub write_cycles: u64,
    /// Write cycles cut by a power loss.
    pub write_cycles_interrupted: u64,
    /// States of the write cycles started (each its drawn T_WC, counted at the STOP that
    /// starts it): the time the chip draws its write current.
    pub write_cycle_states: u64,
}

impl DeviceStats {
    /// SCL clocks the chip took part in: nine for every byte it acknowledged, sent or refused
    /// while busy (the control bytes, addresses and data, the ACK polls it did not answer).
    #[must_use]
    pub fn clocks(&self) -> u64 {
        9 * (self.control_acks + self.busy_nacks + self.bytes_received + self.bytes_sent)
    }

    /// The chip's charge over the counters `self` less `earlier` and `interval_states` of its
    /// time at `clock_hz`, µC, from the datasheet's currents: its standby current all the time,
    /// [`crate::datasheet::CHARGE_PER_CLOCK_NC`] for every clock it took part in, its write
    /// current through every write cycle.
    #[must_use]
    pub fn charge_since_uc(
        &self,
        earlier: &DeviceStats,
        interval_states: u64,
        clock_hz: u32,
    ) -> f64 {
        use crate::datasheet::{CHARGE_PER_CLOCK_NC, ICC_WRITE_MAX_MA, ICCS_STANDBY_MAX_UA};
        let s = 1.0 / f64::from(clock_hz.max(1));
        let clocks = self.clocks().saturating_sub(earlier.clocks());
        let write_states = self
            .write_cycle_states
            .saturating_sub(earlier.write_cycle_states);
        interval_states as f64 * s * ICCS_STANDBY_MAX_UA
            + clocks as f64 * CHARGE_PER_CLOCK_NC * 1e-3
            + write_states as f64 * s * ICC_WRITE_MAX_MA * 1e3
    }
}

/// A Microchip 24LC256 (32 KB serial EEPROM) at pin level.
///
/// It sees SDA and SCL transitions through [`crate::I2cBus`] and answers by pulling SDA low or
/// releasing it (`floor(output_delay)` states after SCL falls). See the crate docs for the
/// behaviour and the modelling choices.
#[derive(Clone, Debug)]
pub struct Eeprom24lc256 {
    config: DeviceConfig,
    clock: Clock,
    t_wc_min_states: u64,
    t_wc_max_states: u64,
    output_delay_states: u64,
    cells: Cells,
    writes: Vec<u32>,
    powered: bool,
    now: u64,
    mode: Mode,
    bit: u8,
    shift: u8,
    acking: bool,
    master_ack: bool,
    tx: u8,
    pointer: u16,
    addr_high: u8,
    page_base: u16,
    page_buf: [u8; PAGE_BYTES],
    loaded: u64,
    sda_pull: bool,
    pending: VecDeque<(u64, bool)>,
    cycle: Option<WriteCycle>,
    last_cycle: Option<WriteCycleInfo>,
    rng_t_wc: ChaCha8Rng,
    rng_cut: ChaCha8Rng,
    rng_wear: ChaCha8Rng,
    monitor: TimingMonitor,
    stats: DeviceStats,
}

/// The chip's stream for `purpose`: the project's one derivation, indexed by the address.
fn stream(seed: u64, address: u8, purpose: Purpose) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seeding::derive(seed, u64::from(address), purpose))
}

fn check_range(address: u32, len: usize) -> Result<(), EepromError> {
    let end = u64::from(address) + len as u64;
    if end > ARRAY_BYTES as u64 {
        return Err(EepromError::MemoryAddressOutOfRange { address, len });
    }
    Ok(())
}

impl Eeprom24lc256 {
    /// A new chip, powered on at state 0, erased (all 0xFF), no page written yet.
    ///
    /// # Errors
    /// Any field of `config` outside its valid range (see [`DeviceConfig`]).
    pub fn new(config: DeviceConfig) -> Result<Eeprom24lc256, EepromError> {
        if !(FIRST_DEVICE_ADDRESS..=LAST_DEVICE_ADDRESS).contains(&config.address) {
            return Err(EepromError::InvalidDeviceAddress {
                address: config.address,
            });
        }
        let clock = Clock::new(config.clock_hz)?;
        if config.t_wc_min_ns < T_WC_MODEL_MIN_NS
            || config.t_wc_max_ns > T_WC_MAX_NS
            || config.t_wc_min_ns > config.t_wc_max_ns
        {
            return Err(EepromError::InvalidWriteCycleTime {
                min_ns: config.t_wc_min_ns,
                max_ns: config.t_wc_max_ns,
            });
        }
        if !(T_OUTPUT_DELAY_MIN_NS..=T_AA_MAX_NS).contains(&config.output_delay_ns) {
            return Err(EepromError::InvalidOutputDelay {
                ns: config.output_delay_ns,
            });
        }
        let output_delay_states = clock.states_at_most(config.output_delay_ns);
        if output_delay_states == 0 {
            return Err(EepromError::OutputDelayBelowOneState {
                ns: config.output_delay_ns,
                clock_hz: config.clock_hz,
            });
        }
        if config.endurance_cycles == 0 {
            return Err(EepromError::InvalidEndurance {
                cycles: config.endurance_cycles,
            });
        }
        let p = config.stuck_bit_probability;
        if !(0.0..=1.0).contains(&p) {
            return Err(EepromError::InvalidStuckProbability { p });
        }
        // The drawn time must stay inside [min, max] in ns: round the ends inwards.
        let t_wc_min_states = clock.states_at_least(config.t_wc_min_ns);
        let t_wc_max_states = clock
            .states_at_most(config.t_wc_max_ns)
            .max(t_wc_min_states);
        Ok(Eeprom24lc256 {
            rng_t_wc: stream(config.seed, config.address, Purpose::EepromWriteCycle),
            rng_cut: stream(config.seed, config.address, Purpose::EepromPowerCut),
            rng_wear: stream(config.seed, config.address, Purpose::EepromWear),
            clock,
            t_wc_min_states,
            t_wc_max_states,
            output_delay_states,
            cells: Cells::fresh(),
            writes: vec![0; PAGES],
            powered: true,
            now: 0,
            mode: Mode::Standby,
            bit: 0,
            shift: 0,
            acking: false,
            master_ack: false,
            tx: 0,
            pointer: 0,
            addr_high: 0,
            page_base: 0,
            page_buf: [0; PAGE_BYTES],
            loaded: 0,
            sda_pull: false,
            pending: VecDeque::new(),
            cycle: None,
            last_cycle: None,
            monitor: TimingMonitor::new(clock),
            stats: DeviceStats::default(),
            config,
        })
    }

    /// The chip's 7-bit bus address.
    #[must_use]
    pub fn address(&self) -> u8 {
        self.config.address
    }

    /// The MCU clock its times are counted in.
    #[must_use]
    pub fn clock(&self) -> Clock {
        self.clock
    }

    /// The configuration it was built with.
    #[must_use]
    pub fn config(&self) -> &DeviceConfig {
        &self.config
    }

    /// The shortest and longest write cycle it draws, in states.
    #[must_use]
    pub fn t_wc_range_states(&self) -> (u64, u64) {
        (self.t_wc_min_states, self.t_wc_max_states)
    }

    /// States from SCL falling to its SDA output changing.
    #[must_use]
    pub fn output_delay_states(&self) -> u64 {
        self.output_delay_states
    }

    /// The latest time the chip has seen, in states.
    #[must_use]
    pub fn now_states(&self) -> u64 {
        self.now
    }

    /// Whether it has power.
    #[must_use]
    pub fn is_powered(&self) -> bool {
        self.powered
    }

    /// Whether it is pulling SDA low right now.
    #[must_use]
    pub fn pulls_sda(&self) -> bool {
        self.sda_pull
    }

    /// Whether a write cycle is running at `now` (states).
    #[must_use]
    pub fn is_busy_at(&self, now: u64) -> bool {
        self.powered && self.cycle.as_ref().is_some_and(|c| now < c.info.end_states)
    }

    /// The write cycle started and not yet seen to end (it may have ended by now: see
    /// [`Eeprom24lc256::is_busy_at`]).
    #[must_use]
    pub fn current_write_cycle(&self) -> Option<WriteCycleInfo> {
        self.cycle.as_ref().map(|c| c.info)
    }

    /// The last write cycle that ran to its end.
    #[must_use]
    pub fn last_completed_write_cycle(&self) -> Option<WriteCycleInfo> {
        self.last_cycle
    }

    /// Write cycles started on `page` since the chip was built (counted at the STOP that starts
    /// them, whether or not they complete).
    ///
    /// # Errors
    /// [`EepromError::PageOutOfRange`] for a page beyond 511.
    pub fn write_count(&self, page: usize) -> Result<u32, EepromError> {
        self.writes
            .get(page)
            .copied()
            .ok_or(EepromError::PageOutOfRange { page })
    }

    /// Write cycles started on every page, indexed by page number.
    #[must_use]
    pub fn write_counts(&self) -> &[u32] {
        &self.writes
    }

    /// Number of bits that wear has stuck, over the whole array.
    #[must_use]
    pub fn stuck_bit_count(&self) -> u64 {
        self.cells.stuck_bit_count()
    }

    /// Timing violations seen (the first 64 in detail).
    #[must_use]
    pub fn timing_violations(&self) -> &[TimingViolation] {
        &self.monitor.log
    }

    /// Number of timing violations seen.
    #[must_use]
    pub fn timing_violation_count(&self) -> u64 {
        self.monitor.count
    }

    /// Bus activity counters.
    #[must_use]
    pub fn stats(&self) -> DeviceStats {
        self.stats
    }

    /// The internal address pointer (the next address a current address read returns).
    #[must_use]
    pub fn address_pointer(&self) -> u16 {
        self.pointer
    }

    /// Brings the chip's internal time to `now`: ends a write cycle whose time is up.
    ///
    /// # Errors
    /// [`EepromError::TimeWentBackwards`] if `now` is before a time already seen.
    pub fn advance_to(&mut self, now: u64) -> Result<(), EepromError> {
        if now < self.now {
            return Err(EepromError::TimeWentBackwards {
                now,
                last: self.now,
            });
        }
        self.catch_up(now);
        Ok(())
    }

    /// Reads the array directly (a test/debug back door, no bus traffic, no time cost) as it is
    /// at `now`: a running write cycle's page still shows its old data.
    ///
    /// # Errors
    /// Powered off, range beyond 0x7FFF, or `now` earlier than a time already seen.
    pub fn read(&mut self, now: u64, address: u16, buf: &mut [u8]) -> Result<(), EepromError> {
        self.advance_to(now)?;
        if !self.powered {
            return Err(EepromError::PoweredOff {
                address: self.config.address,
            });
        }
        check_range(u32::from(address), buf.len())?;
        let a = usize::from(address);
        self.cells.read(a, buf);
        Ok(())
    }

    /// Writes the array directly, as a device programmer would before assembly: no bus
    /// traffic, no write cycle, no wear count. Stuck bits keep their value.
    ///
    /// # Errors
    /// Powered off, or range beyond 0x7FFF.
    pub fn load(&mut self, address: u16, data: &[u8]) -> Result<(), EepromError> {
        if !self.powered {
            return Err(EepromError::PoweredOff {
                address: self.config.address,
            });
        }
        check_range(u32::from(address), data.len())?;
        let a = usize::from(address);
        for (i, &d) in data.iter().enumerate() {
            self.cells.write(a + i, d);
        }
        Ok(())
    }

    /// Cuts the power at `now`. A write cycle still running is cut: every byte of its page
    /// becomes undefined (see the crate docs for the model); a page-write transfer without its
    /// STOP is lost; SDA is released. Cutting a chip already off does nothing.
    ///
    /// # Errors
    /// [`EepromError::TimeWentBackwards`] if `now` is before a time already seen.
    pub fn power_off(&mut self, now: u64) -> Result<PowerCutOutcome, EepromError> {
        self.advance_to(now)?;
        let mut outcome = PowerCutOutcome::default();
        if !self.powered {
            return Ok(outcome);
        }
        if let Some(cycle) = self.cycle.take() {
            self.corrupt_page(&cycle);
            self.stats.write_cycles_interrupted += 1;
            outcome.interrupted_write = Some(cycle.info);
        }
        outcome.discarded_transfer = self.mode == Mode::WriteData && self.loaded != 0;
        self.powered = false;
        self.reset_front_end();
        self.sda_pull = false;
        self.pending.clear();
        Ok(outcome)
    }

    /// Powers the chip on at `now`: standby, address pointer 0, waiting for a START. Powering
    /// on a chip already on does nothing.
    ///
    /// # Errors
    /// [`EepromError::TimeWentBackwards`] if `now` is before a time already seen.
    pub fn power_on(&mut self, now: u64) -> Result<(), EepromError> {
        self.advance_to(now)?;
        if self.powered {
            return Ok(());
        }
        self.powered = true;
        self.reset_front_end();
        self.pointer = 0;
        self.monitor.forget_edges();
        Ok(())
    }

    fn reset_front_end(&mut self) {
        self.mode = Mode::Standby;
        self.bit = 0;
        self.shift = 0;
        self.acking = false;
        self.master_ack = false;
        self.loaded = 0;
    }

    /// Ends the write cycle if its time is up.
    ///
    /// Called at every bus edge: the test is inlined into the callers, the end of a write
    /// cycle (rare) is [`Self::end_write_cycle`], out of line.
    #[inline]
    fn catch_up(&mut self, now: u64) {
        self.now = self.now.max(now);
        if self
            .cycle
            .as_ref()
            .is_some_and(|c| self.now >= c.info.end_states)
        {
            self.end_write_cycle();
        }
    }

    /// Ends the write cycle running: its loaded bytes go into the array.
    #[cold]
    #[inline(never)]
    fn end_write_cycle(&mut self) {
        if let Some(cycle) = self.cycle.take() {
            let base = usize::from(cycle.info.page) * PAGE_BYTES;
            for (i, &d) in cycle.data.iter().enumerate() {
                if cycle.loaded & (1 << i) != 0 {
                    self.cells.write(base + i, d);
                }
            }
            self.last_cycle = Some(cycle.info);
        }
    }

    /// The model of a write cycle cut by a power loss: each byte of the page independently
    /// ends up old, new, erased (0xFF) or a bitwise mix where each bit is the old bit, the new
    /// bit or erased (1), with equal odds. Stuck bits keep their value.
    fn corrupt_page(&mut self, cycle: &WriteCycle) {
        let base = usize::from(cycle.info.page) * PAGE_BYTES;
        for i in 0..PAGE_BYTES {
            let old = self.cells.byte(base + i);
            let new = if cycle.loaded & (1 << i) != 0 {
                cycle.data[i]
            } else {
                old
            };
            let value = match self.rng_cut.random_range(0..4u8) {
                0 => old,
                1 => new,
                2 => ERASED_BYTE,
                _ => {
                    let mut v = 0u8;
                    for b in 0..8 {
                        let bit = match self.rng_cut.random_range(0..3u8) {
                            0 => old >> b & 1,
                            1 => new >> b & 1,
                            _ => 1,
                        };
                        v |= bit << b;
                    }
                    v
                }
            };
            self.cells.write(base + i, value);
        }
    }

    /// Wear past the endurance limit: each bit of the page independently sticks at its
    /// present value with the configured probability.
    fn wear(&mut self, page: usize) {
        let p = self.config.stuck_bit_probability;
        if p <= 0.0 {
            return;
        }
        let base = page * PAGE_BYTES;
        for i in 0..PAGE_BYTES {
            for b in 0..8 {
                if self.rng_wear.random_bool(p) {
                    self.cells.stick(base + i, b);
                }
            }
        }
    }

    fn start_write_cycle(&mut self, now: u64) {
        let t_wc = self
            .rng_t_wc
            .random_range(self.t_wc_min_states..=self.t_wc_max_states);
        let page = usize::from(self.page_base) / PAGE_BYTES;
        self.writes[page] = self.writes[page].saturating_add(1);
        if self.writes[page] > self.config.endurance_cycles {
            self.wear(page);
        }
        let bytes = u8::try_from(self.loaded.count_ones()).unwrap_or(u8::MAX);
        self.cycle = Some(WriteCycle {
            info: WriteCycleInfo {
                page: u16::try_from(page).unwrap_or(u16::MAX),
                bytes,
                start_states: now,
                end_states: now.saturating_add(t_wc),
            },
            data: self.page_buf,
            loaded: self.loaded,
        });
        self.loaded = 0;
        self.stats.write_cycles += 1;
        self.stats.write_cycle_states += t_wc;
    }

    /// The time of the next scheduled SDA output change, if any.
    pub(crate) fn next_event(&self) -> Option<u64> {
        self.pending.front().map(|e| e.0)
    }

    /// Applies the next scheduled SDA output change (the bus calls this at its time).
    pub(crate) fn apply_event(&mut self, now: u64) {
        self.catch_up(now);
        if let Some((_, pull)) = self.pending.pop_front() {
            self.sda_pull = pull;
        }
    }

    fn drive(&mut self, now: u64, pull_low: bool) {
        self.pending
            .push_back((now.saturating_add(self.output_delay_states), pull_low));
    }

    fn drive_bit(&mut self, now: u64, bit_index: u8) {
        let one = self.tx >> bit_index & 1 == 1;
        self.drive(now, !one);
    }

    fn load_tx(&mut self) {
        self.tx = self.cells.byte(usize::from(self.pointer));
        self.pointer = (self.pointer + 1) & MAX_MEMORY_ADDRESS;
        self.stats.bytes_sent += 1;
    }

    /// SCL changed to `scl_high` at `now`; SDA is `sda_high`.
    pub(crate) fn on_scl(&mut self, now: u64, scl_high: bool, sda_high: bool) {
        self.catch_up(now);
        if !self.powered {
            return;
        }
        self.monitor.scl(now, scl_high);
        if scl_high {
            self.scl_rise(sda_high);
        } else {
            self.scl_fall(now);
        }
    }

    fn scl_rise(&mut self, sda_high: bool) {
        if self.acking {
            self.bit = 9;
            return;
        }
        match self.mode {
            Mode::Standby | Mode::Wait => {}
            Mode::Control | Mode::AddrHigh | Mode::AddrLow | Mode::WriteData => {
                if self.bit < 8 {
                    self.shift = (self.shift << 1) | u8::from(sda_high);
                    self.bit += 1;
                }
            }
            Mode::Read => {
                if self.bit < 8 {
                    self.bit += 1;
                } else if self.bit == 8 {
                    self.bit = 9;
                    self.master_ack = !sda_high;
                }
            }
        }
    }

    fn scl_fall(&mut self, now: u64) {
        if self.acking {
            if self.bit == 9 {
                self.acking = false;
                self.bit = 0;
                self.shift = 0;
                if self.mode == Mode::Read {
                    // Release the ACK and put the first data bit out in one change.
                    self.load_tx();
                    self.drive_bit(now, 7);
                } else {
                    self.drive(now, false);
                }
            }
            return;
        }
        match self.mode {
            Mode::Control | Mode::AddrHigh | Mode::AddrLow | Mode::WriteData if self.bit == 8 => {
                if self.accept_byte(self.shift) {
                    self.acking = true;
                    self.drive(now, true);
                } else {
                    self.mode = Mode::Wait;
                }
            }
            Mode::Read => match self.bit {
                1..=7 => self.drive_bit(now, 7 - self.bit),
                8 => self.drive(now, false),
                9 => {
                    if self.master_ack {
                        self.bit = 0;
                        self.load_tx();
                        self.drive_bit(now, 7);
                    } else {
                        self.mode = Mode::Wait;
                    }
                }
                _ => {}
            },
            _ => {}
        }
    }

    /// A whole byte came in; returns whether to acknowledge it.
    fn accept_byte(&mut self, byte: u8) -> bool {
        match self.mode {
            Mode::Control => {
                let code = byte >> 4;
                let chip_select = (byte >> 1) & 0b111;
                if code != CONTROL_CODE || chip_select != self.config.address & 0b111 {
                    return false;
                }
                if self.cycle.is_some() {
                    // Busy in a write cycle: inputs disabled, no ACK (DS21203 §7.0).
                    self.stats.busy_nacks += 1;
                    return false;
                }
                self.stats.control_acks += 1;
                self.mode = if byte & 1 == 1 {
                    Mode::Read
                } else {
                    Mode::AddrHigh
                };
                true
            }
            Mode::AddrHigh => {
                // Address bit 15 is "don't care" (DS21203 Figure 5-2).
                self.addr_high = byte & 0x7F;
                self.mode = Mode::AddrLow;
                self.stats.bytes_received += 1;
                true
            }
            Mode::AddrLow => {
                self.pointer = (u16::from(self.addr_high) << 8) | u16::from(byte);
                self.page_base = self.pointer & !(PAGE_BYTES as u16 - 1);
                self.loaded = 0;
                self.mode = Mode::WriteData;
                self.stats.bytes_received += 1;
                true
            }
            Mode::WriteData => {
                // Only the six low pointer bits count up: the page wraps (DS21203 §6.2).
                let offset = usize::from(self.pointer) % PAGE_BYTES;
                self.page_buf[offset] = byte;
                self.loaded |= 1 << offset;
                let next = (offset + 1) % PAGE_BYTES;
                self.pointer = self.page_base | u16::try_from(next).unwrap_or(0);
                self.stats.bytes_received += 1;
                true
            }
            Mode::Standby | Mode::Read | Mode::Wait => false,
        }
    }

    /// SDA changed to `sda_high` at `now`; SCL is `scl_high`.
    pub(crate) fn on_sda(&mut self, now: u64, sda_high: bool, scl_high: bool) {
        self.catch_up(now);
        if !self.powered {
            return;
        }
        self.monitor.sda(now, sda_high, scl_high);
        if !scl_high {
            return;
        }
        // Any scheduled output is void after a START or STOP; SDA could only change because
        // this chip was not pulling it.
        self.pending.clear();
        self.sda_pull = false;
        if sda_high {
            self.stop_condition(now);
        } else {
            self.start_condition();
        }
    }

    /// A STOP: a page write with data begins its write cycle; the front end returns to standby.
    fn stop_condition(&mut self, now: u64) {
        self.stats.stops += 1;
        if self.mode == Mode::WriteData && self.loaded != 0 && !self.acking {
            self.start_write_cycle(now);
        }
        self.reset_front_end();
    }

    /// A (repeated) START ends any transfer; a page write without its STOP writes nothing.
    fn start_condition(&mut self) {
        self.stats.starts += 1;
        self.reset_front_end();
        self.mode = Mode::Control;
    }

    /// A whole write transfer at transaction level: what the chip does when it sees START,
    /// its write control byte, `address` and `data`, each acknowledged, and a STOP whose SDA
    /// rise is at `stop_states` — the same state changes, through the same code, as the
    /// pin-level path (the page buffer with its wrap, the pointer, the write cycle and its
    /// seeded duration, the write counter, wear), without the edges. Returns the instant the
    /// write cycle ends (or `stop_states` when `data` is empty: no cycle).
    ///
    /// An emulator shortcut for callers that know the transfer's timing (the robot controller
    /// runs the master's pin sequence on a virtual clock); the timing monitor sees nothing.
    ///
    /// # Errors
    /// [`EepromError::PoweredOff`] when the chip has no power, [`EepromError::Busy`] when its
    /// write cycle runs at `stop_states` (it would not acknowledge its control byte).
    pub fn write_transaction(
        &mut self,
        stop_states: u64,
        address: u16,
        data: &[u8],
    ) -> Result<u64, EepromError> {
        self.catch_up(stop_states);
        if !self.powered {
            return Err(EepromError::PoweredOff {
                address: self.config.address,
            });
        }
        if self.cycle.is_some() {
            return Err(EepromError::Busy {
                address: self.config.address,
            });
        }
        self.pending.clear();
        self.sda_pull = false;
        self.start_condition();
        let control = (CONTROL_CODE << 4) | ((self.config.address & 0b111) << 1);
        let [high, low] = address.to_be_bytes();
        for byte in [control, high, low].into_iter().chain(data.iter().copied()) {
            // The control byte matches this chip and it is idle, so every byte is accepted.
            let _ = self.accept_byte(byte);
        }
        self.stop_condition(stop_states);
        Ok(self
            .cycle
            .as_ref()
            .map_or(stop_states, |c| c.info.end_states))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_configs_are_errors_not_panics() {
        let ok = DeviceConfig::new(0x50, 1, 25_000_000);
        assert!(Eeprom24lc256::new(ok.clone()).is_ok());
        let bad = |f: fn(&mut DeviceConfig)| {
            let mut c = ok.clone();
            f(&mut c);
            Eeprom24lc256::new(c)
        };
        assert!(matches!(
            bad(|c| c.address = 0x58),
            Err(EepromError::InvalidDeviceAddress { address: 0x58 })
        ));
        assert!(matches!(
            bad(|c| c.address = 0x4F),
            Err(EepromError::InvalidDeviceAddress { .. })
        ));
        assert!(matches!(
            bad(|c| c.clock_hz = 0),
            Err(EepromError::InvalidClock { .. })
        ));
        assert!(matches!(
            bad(|c| c.t_wc_min_ns = 2_999_999),
            Err(EepromError::InvalidWriteCycleTime { .. })
        ));
        assert!(matches!(
            bad(|c| c.t_wc_max_ns = 5_000_001),
            Err(EepromError::InvalidWriteCycleTime { .. })
        ));
        assert!(matches!(
            bad(|c| {
                c.t_wc_min_ns = 4_000_000;
                c.t_wc_max_ns = 3_500_000;
            }),
            Err(EepromError::InvalidWriteCycleTime { .. })
        ));
        assert!(matches!(
            bad(|c| c.endurance_cycles = 0),
            Err(EepromError::InvalidEndurance { cycles: 0 })
        ));
        assert!(matches!(
            bad(|c| c.stuck_bit_probability = 1.5),
            Err(EepromError::InvalidStuckProbability { .. })
        ));
        assert!(matches!(
            bad(|c| c.stuck_bit_probability = f64::NAN),
            Err(EepromError::InvalidStuckProbability { .. })
        ));
        assert!(matches!(
            bad(|c| c.output_delay_ns = 1_000),
            Err(EepromError::InvalidOutputDelay { .. })
        ));
        assert!(matches!(
            bad(|c| c.clock_hz = 1_000_000),
            Err(EepromError::OutputDelayBelowOneState { .. })
        ));
        let msg = bad(|c| c.address = 0x60).unwrap_err().to_string();
        assert!(msg.contains("0x60") && msg.contains("0x50..=0x57"), "{msg}");
    }

    #[test]
    fn back_door_reads_check_range_and_power() {
        let mut d = Eeprom24lc256::new(DeviceConfig::new(0x51, 1, 25_000_000)).unwrap();
        let mut b = [0u8; 4];
        d.read(0, 0x7FFC, &mut b).unwrap();
        assert_eq!(b, [0xFF; 4]);
        assert!(matches!(
            d.read(0, 0x7FFD, &mut b),
            Err(EepromError::MemoryAddressOutOfRange { .. })
        ));
        assert!(d.load(0x7FFF, &[1, 2]).is_err());
        d.power_off(10).unwrap();
        assert!(matches!(
            d.read(10, 0, &mut b),
            Err(EepromError::PoweredOff { address: 0x51 })
        ));
        assert!(matches!(
            d.read(5, 0, &mut b),
            Err(EepromError::TimeWentBackwards { .. })
        ));
        assert!(d.write_count(512).is_err());
        assert_eq!(d.write_count(511).unwrap(), 0);
    }

    #[test]
    fn write_cycle_time_bounds_in_states() {
        let d = Eeprom24lc256::new(DeviceConfig::new(0x50, 1, 25_000_000)).unwrap();
        assert_eq!(d.t_wc_range_states(), (75_000, 125_000));
        assert_eq!(d.output_delay_states(), 22);
    }
}
