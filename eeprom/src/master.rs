//! The bit-banging I²C master: the exact pin sequence the H8 firmware uses on port 4.
//!
//! # Pin sequence (SCL = P4.6, SDA = P4.7 on the robot)
//!
//! "Pull" a line = set its DDR bit with DR = 0; "release" = clear the DDR bit, and the pull-up
//! takes the line high. Every pin operation is one [`I2cPins`] call; the edge happens at the end
//! of the call's cost ([`I2cPins::op_states`]). The master counts its own states (operation
//! costs plus waits, as firmware counts instruction states to size its delay loops) and waits
//! only what is still missing to meet each minimum, so a slower pins implementation gives a
//! slower but never a faster bus. With the defaults (400 kHz class, φ = 25 MHz, free pin
//! operations) the waits are: SCL low 48 states (1.92 µs: T_LOW = 1.3 µs, stretched so one bit
//! takes ≥ 2.5 µs = 1/400 kHz), SCL high 15 (T_HIGH 0.6 µs), START setup/hold 15/15, data setup
//! 3 (T_SU:DAT 0.1 µs), STOP setup 15, bus free after STOP 33 (T_BUF 1.3 µs).
//!
//! - idle: both lines released (high).
//! - START (from idle): pull SDA; wait T_HD:STA; pull SCL.
//! - bit out (SCL low): set SDA to the bit right after SCL fell (T_HD:DAT = 0); wait until SCL
//!   has been low T_LOW and SDA stable T_SU:DAT; release SCL; wait T_HIGH; pull SCL.
//! - bit in (SCL low, SDA released): wait T_LOW; release SCL; wait T_HIGH less one operation;
//!   read SDA (the device changed it T_AA ≤ 0.9 µs after SCL fell, well inside T_LOW); pull SCL.
//! - byte out: 8 bits out, MSB first; release SDA; one bit in = the device's ACK (low = ACK).
//! - byte in: release SDA; 8 bits in, MSB first; one bit out = the master's ACK (low) or NACK.
//! - repeated START (SCL low): release SDA; wait T_LOW; release SCL; wait T_SU:STA; pull SDA;
//!   wait T_HD:STA; pull SCL.
//! - STOP (SCL low): pull SDA; wait T_LOW; release SCL; wait T_SU:STO; release SDA; wait T_BUF.
//!
//! Transfers: write = START, control byte (1010 A2 A1 A0 0), address high, address low, data…,
//! STOP. Random read = START, control (W), address high, low, repeated START, control (R),
//! data in with ACK… last with NACK, STOP. Current address read = START, control (R), data…,
//! STOP. ACK polling (DS21203 Figure 7-1) = START, control (W); while NACK: repeated START,
//! control (W); on ACK: STOP. Any NACK in a transfer ends it with a STOP and an error.

use crate::clock::Clock;
use crate::datasheet::{
    self, CONTROL_CODE, FIRST_DEVICE_ADDRESS, LAST_DEVICE_ADDRESS, MAX_MEMORY_ADDRESS, PAGE_BYTES,
};
use crate::error::{EepromError, MasterError, NackStage};

/// The pins the master drives: open-drain SCL and SDA and a way to wait.
///
/// On the robot: `scl_low` sets DDR bit 6 of port 4 (DR bit 6 is kept 0), `scl_release` clears
/// it, the same with bit 7 for SDA (through the firmware's DDR shadow: the DDR is write-only);
/// `sda_is_high` reads DR bit 7, which returns the pin level; `wait_states` is a delay loop.
/// Each call may cost MCU states; the cost of one pin operation is [`I2cPins::op_states`].
pub trait I2cPins {
    /// Pull SCL low.
    fn scl_low(&mut self);
    /// Release SCL (the pull-up takes it high).
    fn scl_release(&mut self);
    /// Pull SDA low.
    fn sda_low(&mut self);
    /// Release SDA.
    fn sda_release(&mut self);
    /// Sample the SDA pin level.
    fn sda_is_high(&mut self) -> bool;
    /// Let `states` MCU states pass with the pins unchanged.
    fn wait_states(&mut self, states: u64);
    /// States one pin operation costs (the edge happens at its end). The master subtracts it
    /// from its waits. Default 0.
    fn op_states(&self) -> u64 {
        0
    }
}

impl<P: I2cPins + ?Sized> I2cPins for &mut P {
    fn scl_low(&mut self) {
        (**self).scl_low();
    }
    fn scl_release(&mut self) {
        (**self).scl_release();
    }
    fn sda_low(&mut self) {
        (**self).sda_low();
    }
    fn sda_release(&mut self) {
        (**self).sda_release();
    }
    fn sda_is_high(&mut self) -> bool {
        (**self).sda_is_high()
    }
    fn wait_states(&mut self, states: u64) {
        (**self).wait_states(states);
    }
    fn op_states(&self) -> u64 {
        (**self).op_states()
    }
}

/// The minimum intervals the master keeps, in MCU states.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MasterTiming {
    /// The MCU clock these states are counted in.
    pub clock: Clock,
    /// SCL low time (T_LOW, stretched so that low + high ≥ 1/F_CLK).
    pub scl_low_states: u64,
    /// SCL high time (T_HIGH).
    pub scl_high_states: u64,
    /// SCL high before a repeated START's SDA fall (T_SU:STA).
    pub start_setup_states: u64,
    /// SDA low before SCL falls after a START (T_HD:STA).
    pub start_hold_states: u64,
    /// SDA stable before SCL rises (T_SU:DAT).
    pub data_setup_states: u64,
    /// SCL high before the STOP's SDA rise (T_SU:STO).
    pub stop_setup_states: u64,
    /// Bus free after a STOP before the next START (T_BUF).
    pub bus_free_states: u64,
    /// After an unanswered ACK poll, SCL low at least this long (from its last fall) before the
    /// next poll's repeated START: a pause in which the master leaves the bus alone while the
    /// chip's write cycle runs. 0 (the default): poll back to back.
    pub poll_gap_states: u64,
}

impl MasterTiming {
    #[allow(clippy::too_many_arguments)]
    fn from_ns(
        clock: Clock,
        f_max_hz: u64,
        high_ns: u64,
        low_ns: u64,
        su_sta_ns: u64,
        hd_sta_ns: u64,
        su_dat_ns: u64,
        su_sto_ns: u64,
        buf_ns: u64,
    ) -> MasterTiming {
        let period_ns = 1_000_000_000_u64.div_ceil(f_max_hz);
        let high = clock.states_at_least(high_ns);
        let low = clock
            .states_at_least(low_ns)
            .max(clock.states_at_least(period_ns).saturating_sub(high));
        MasterTiming {
            clock,
            scl_low_states: low,
            scl_high_states: high,
            start_setup_states: clock.states_at_least(su_sta_ns),
            start_hold_states: clock.states_at_least(hd_sta_ns),
            data_setup_states: clock.states_at_least(su_dat_ns),
            stop_setup_states: clock.states_at_least(su_sto_ns),
            bus_free_states: clock.states_at_least(buf_ns),
            poll_gap_states: 0,
        }
    }

    /// 400 kHz-class timing: the 24LC256's minima at 2.5–5.5 V (DS21203 Table 1-2), at the
    /// MCU's `clock_hz`.
    ///
    /// # Errors
    /// [`EepromError::InvalidClock`] for a zero clock.
    pub fn fast_mode(clock_hz: u32) -> Result<MasterTiming, EepromError> {
        use datasheet as d;
        Ok(MasterTiming::from_ns(
            Clock::new(clock_hz)?,
            d::F_CLK_MAX_HZ,
            d::T_HIGH_MIN_NS,
            d::T_LOW_MIN_NS,
            d::T_SU_STA_MIN_NS,
            d::T_HD_STA_MIN_NS,
            d::T_SU_DAT_MIN_NS,
            d::T_SU_STO_MIN_NS,
            d::T_BUF_MIN_NS,
        ))
    }

    /// 100 kHz timing: the datasheet's low-voltage minima (= I²C standard mode), for slow
    /// pull-ups.
    ///
    /// # Errors
    /// [`EepromError::InvalidClock`] for a zero clock.
    pub fn standard_mode(clock_hz: u32) -> Result<MasterTiming, EepromError> {
        use datasheet::standard as s;
        Ok(MasterTiming::from_ns(
            Clock::new(clock_hz)?,
            s::F_CLK_MAX_HZ,
            s::T_HIGH_MIN_NS,
            s::T_LOW_MIN_NS,
            s::T_SU_STA_MIN_NS,
            s::T_HD_STA_MIN_NS,
            s::T_SU_DAT_MIN_NS,
            s::T_SU_STO_MIN_NS,
            s::T_BUF_MIN_NS,
        ))
    }
}

/// What the master has done, as it counts it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct MasterStats {
    /// Pin operations (each an [`I2cPins`] call other than `wait_states`).
    pub pin_ops: u64,
    /// States spent in `wait_states`.
    pub wait_states: u64,
    /// States elapsed by the master's own count (pin operations × their cost + waits).
    pub elapsed_states: u64,
    /// STARTs and repeated STARTs sent.
    pub starts: u64,
    /// STOPs sent.
    pub stops: u64,
    /// Bytes sent (control, address, data).
    pub bytes_sent: u64,
    /// Bytes received.
    pub bytes_received: u64,
    /// NACKs received where an ACK was wanted (busy polls included).
    pub nacks: u64,
    /// ACK polls sent.
    pub polls: u64,
}

/// A bit-banging I²C master for 24LC256s, generic over its pins.
#[derive(Debug)]
pub struct I2cMaster<P: I2cPins> {
    pins: P,
    timing: MasterTiming,
    t: u64,
    last_fall: u64,
    last_rise: u64,
    last_sda: u64,
    stats: MasterStats,
}

fn check_device(device: u8) -> Result<(), MasterError> {
    if (FIRST_DEVICE_ADDRESS..=LAST_DEVICE_ADDRESS).contains(&device) {
        Ok(())
    } else {
        Err(MasterError::InvalidDeviceAddress { address: device })
    }
}

fn check_address(address: u16) -> Result<(), MasterError> {
    if address <= MAX_MEMORY_ADDRESS {
        Ok(())
    } else {
        Err(MasterError::MemoryAddressOutOfRange {
            address: u32::from(address),
        })
    }
}

fn control_byte(device: u8, read: bool) -> u8 {
    (CONTROL_CODE << 4) | ((device & 0b111) << 1) | u8::from(read)
}

impl<P: I2cPins> I2cMaster<P> {
    /// A master on `pins` keeping `timing`. It assumes the bus idle (both lines released);
    /// call [`I2cMaster::init`] or [`I2cMaster::bus_clear`] after a reset to make sure.
    pub fn new(pins: P, timing: MasterTiming) -> I2cMaster<P> {
        I2cMaster {
            pins,
            timing,
            t: 0,
            last_fall: 0,
            last_rise: 0,
            last_sda: 0,
            stats: MasterStats::default(),
        }
    }

    /// The pins.
    pub fn pins(&self) -> &P {
        &self.pins
    }

    /// The pins, mutable.
    pub fn pins_mut(&mut self) -> &mut P {
        &mut self.pins
    }

    /// Gives the pins back.
    pub fn into_pins(self) -> P {
        self.pins
    }

    /// The timing kept.
    pub fn timing(&self) -> &MasterTiming {
        &self.timing
    }

    /// What the master has done so far.
    pub fn stats(&self) -> MasterStats {
        MasterStats {
            elapsed_states: self.t,
            ..self.stats
        }
    }

    // ---- pin level -------------------------------------------------------------------

    fn op_done(&mut self) {
        self.t += self.pins.op_states();
        self.stats.pin_ops += 1;
    }

    fn scl_low(&mut self) {
        self.pins.scl_low();
        self.op_done();
        self.last_fall = self.t;
    }

    fn scl_release(&mut self) {
        self.pins.scl_release();
        self.op_done();
        self.last_rise = self.t;
    }

    fn sda(&mut self, low: bool) {
        if low {
            self.pins.sda_low();
        } else {
            self.pins.sda_release();
        }
        self.op_done();
        self.last_sda = self.t;
    }

    fn sda_read(&mut self) -> bool {
        let v = self.pins.sda_is_high();
        self.op_done();
        v
    }

    /// Waits so that the next pin operation ends no earlier than `target`.
    fn settle_until(&mut self, target: u64) {
        let earliest = self.t + self.pins.op_states();
        if target > earliest {
            let w = target - earliest;
            self.pins.wait_states(w);
            self.t += w;
            self.stats.wait_states += w;
        }
    }

    fn data_ready_for_rise(&self) -> u64 {
        (self.last_fall + self.timing.scl_low_states)
            .max(self.last_sda + self.timing.data_setup_states)
    }

    fn start(&mut self) {
        self.stats.starts += 1;
        self.sda(true);
        self.settle_until(self.last_sda + self.timing.start_hold_states);
        self.scl_low();
    }

    fn repeated_start(&mut self) {
        self.stats.starts += 1;
        self.sda(false);
        self.settle_until(self.data_ready_for_rise());
        self.scl_release();
        self.settle_until(self.last_rise + self.timing.start_setup_states);
        self.sda(true);
        self.settle_until(self.last_sda + self.timing.start_hold_states);
        self.scl_low();
    }

    fn stop(&mut self) {
        self.stats.stops += 1;
        self.sda(true);
        self.settle_until(self.data_ready_for_rise());
        self.scl_release();
        self.settle_until(self.last_rise + self.timing.stop_setup_states);
        self.sda(false);
        self.settle_until(self.last_sda + self.timing.bus_free_states);
    }

    fn clock_out(&mut self, one: bool) {
        self.sda(!one);
        self.settle_until(self.data_ready_for_rise());
        self.scl_release();
        self.settle_until(self.last_rise + self.timing.scl_high_states);
        self.scl_low();
    }

    fn clock_in(&mut self) -> bool {
        self.settle_until(self.last_fall + self.timing.scl_low_states);
        self.scl_release();
        let sample_at = self.last_rise
            + self
                .timing
                .scl_high_states
                .saturating_sub(self.pins.op_states());
        self.settle_until(sample_at);
        let v = self.sda_read();
        self.settle_until(self.last_rise + self.timing.scl_high_states);
        self.scl_low();
        v
    }

    /// Sends a byte; returns whether the device acknowledged it.
    fn write_byte(&mut self, byte: u8) -> bool {
        for i in (0..8).rev() {
            self.clock_out(byte >> i & 1 == 1);
        }
        self.sda(false);
        let ack = !self.clock_in();
        self.stats.bytes_sent += 1;
        if !ack {
            self.stats.nacks += 1;
        }
        ack
    }

    fn read_byte(&mut self, ack: bool) -> u8 {
        self.sda(false);
        let mut v = 0u8;
        for _ in 0..8 {
            v = (v << 1) | u8::from(self.clock_in());
        }
        self.clock_out(!ack);
        self.stats.bytes_received += 1;
        v
    }

    fn fail(&mut self, device: u8, stage: NackStage) -> MasterError {
        self.stop();
        MasterError::Nack { device, stage }
    }

    // ---- operations ------------------------------------------------------------------

    /// Releases both lines (SCL first, so a low SDA makes a STOP) and waits T_BUF: the
    /// firmware's start-up state of the bus.
    pub fn init(&mut self) {
        self.scl_release();
        self.sda(false);
        self.settle_until(self.last_sda + self.timing.bus_free_states);
    }

    /// Frees a bus a device may hold (e.g. the MCU was reset mid-read while the chip kept
    /// power): releases both lines, clocks SCL until SDA reads high (at most 9 clocks), then
    /// sends a STOP. Returns the clocks sent.
    ///
    /// # Errors
    /// [`MasterError::BusStuck`] if SDA is still low after 9 clocks.
    pub fn bus_clear(&mut self) -> Result<u32, MasterError> {
        self.init();
        let mut clocks = 0u32;
        while !self.sda_read() {
            if clocks == 9 {
                return Err(MasterError::BusStuck { clocks });
            }
            self.scl_low();
            self.settle_until(self.last_fall + self.timing.scl_low_states);
            self.scl_release();
            self.settle_until(self.last_rise + self.timing.scl_high_states);
            clocks += 1;
        }
        self.settle_until(self.last_rise + self.timing.scl_high_states);
        self.scl_low();
        self.stop();
        Ok(clocks)
    }

    fn write_transfer(&mut self, device: u8, address: u16, data: &[u8]) -> Result<(), MasterError> {
        check_device(device)?;
        check_address(address)?;
        self.start();
        if !self.write_byte(control_byte(device, false)) {
            return Err(self.fail(device, NackStage::Control));
        }
        if !self.write_byte((address >> 8) as u8) {
            return Err(self.fail(device, NackStage::AddressHigh));
        }
        if !self.write_byte((address & 0xFF) as u8) {
            return Err(self.fail(device, NackStage::AddressLow));
        }
        for (index, &b) in data.iter().enumerate() {
            if !self.write_byte(b) {
                return Err(self.fail(device, NackStage::Data { index }));
            }
        }
        self.stop();
        Ok(())
    }

    /// Byte write (DS21203 §6.1): one byte at `address`. The chip then runs its write cycle;
    /// poll with [`I2cMaster::ack_poll`] before the next access.
    ///
    /// # Errors
    /// Bad device or memory address; a NACK.
    pub fn byte_write(&mut self, device: u8, address: u16, byte: u8) -> Result<(), MasterError> {
        self.write_transfer(device, address, &[byte])
    }

    /// Page write (DS21203 §6.2): 1..=64 bytes from `address`, all inside one 64-byte page.
    ///
    /// # Errors
    /// Bad device or memory address, no data, data crossing the page end (the chip would wrap
    /// to the page start; use [`I2cMaster::write_raw`] to do that on purpose); a NACK.
    pub fn page_write(&mut self, device: u8, address: u16, data: &[u8]) -> Result<(), MasterError> {
        check_device(device)?;
        check_address(address)?;
        if data.is_empty() {
            return Err(MasterError::EmptyTransfer {
                operation: "page write",
            });
        }
        let offset = usize::from(address) % PAGE_BYTES;
        let room = PAGE_BYTES - offset;
        if data.len() > room {
            return Err(MasterError::CrossesPage {
                address,
                len: data.len(),
                boundary: u32::from(address) + room as u32,
                room,
            });
        }
        self.write_transfer(device, address, data)
    }

    /// A write transfer of any length, unchecked against the page: the chip wraps inside the
    /// page and keeps the last 64 bytes. With no data it only sets the chip's address pointer
    /// (no write cycle).
    ///
    /// # Errors
    /// Bad device or memory address; a NACK.
    pub fn write_raw(&mut self, device: u8, address: u16, data: &[u8]) -> Result<(), MasterError> {
        self.write_transfer(device, address, data)
    }

    /// Random read (DS21203 §8.2), sequential when `buf` holds more than one byte (§8.3; the
    /// address rolls over from 0x7FFF to 0x0000).
    ///
    /// # Errors
    /// Bad device or memory address, empty buffer; a NACK.
    pub fn random_read(
        &mut self,
        device: u8,
        address: u16,
        buf: &mut [u8],
    ) -> Result<(), MasterError> {
        check_device(device)?;
        check_address(address)?;
        if buf.is_empty() {
            return Err(MasterError::EmptyTransfer {
                operation: "random read",
            });
        }
        self.start();
        if !self.write_byte(control_byte(device, false)) {
            return Err(self.fail(device, NackStage::Control));
        }
        if !self.write_byte((address >> 8) as u8) {
            return Err(self.fail(device, NackStage::AddressHigh));
        }
        if !self.write_byte((address & 0xFF) as u8) {
            return Err(self.fail(device, NackStage::AddressLow));
        }
        self.repeated_start();
        if !self.write_byte(control_byte(device, true)) {
            return Err(self.fail(device, NackStage::ReadControl));
        }
        self.read_into(buf);
        Ok(())
    }

    /// Current address read (DS21203 §8.1), sequential when `buf` holds more than one byte.
    ///
    /// # Errors
    /// Bad device address, empty buffer; a NACK.
    pub fn current_address_read(&mut self, device: u8, buf: &mut [u8]) -> Result<(), MasterError> {
        check_device(device)?;
        if buf.is_empty() {
            return Err(MasterError::EmptyTransfer {
                operation: "current address read",
            });
        }
        self.start();
        if !self.write_byte(control_byte(device, true)) {
            return Err(self.fail(device, NackStage::Control));
        }
        self.read_into(buf);
        Ok(())
    }

    fn read_into(&mut self, buf: &mut [u8]) {
        let n = buf.len();
        for (i, b) in buf.iter_mut().enumerate() {
            *b = self.read_byte(i + 1 < n);
        }
        self.stop();
    }

    /// ACK polling (DS21203 §7.0, Figure 7-1): START and the write control byte, repeated
    /// (through repeated STARTs) until the chip acknowledges, then STOP. Returns the number of
    /// control bytes sent (1 = the chip was ready at once).
    ///
    /// # Errors
    /// Bad device address or a zero bound; [`MasterError::PollTimeout`] after `max_polls`
    /// unacknowledged tries.
    pub fn ack_poll(&mut self, device: u8, max_polls: u32) -> Result<u32, MasterError> {
        check_device(device)?;
        if max_polls == 0 {
            return Err(MasterError::InvalidPollBound);
        }
        let t0 = self.t;
        self.start();
        for poll in 1..=max_polls {
            self.stats.polls += 1;
            if self.write_byte(control_byte(device, false)) {
                self.stop();
                return Ok(poll);
            }
            if poll < max_polls {
                self.settle_until(self.last_fall + self.timing.poll_gap_states);
                self.repeated_start();
            }
        }
        self.stop();
        Err(MasterError::PollTimeout {
            device,
            polls: max_polls,
            waited_states: self.t - t0,
        })
    }
}
