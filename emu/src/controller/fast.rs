//! The fast save: the same master, the same pin sequence, the same states — on a virtual bus.
//!
//! [`FastPins`] is an `I2cPins` that charges every pin operation exactly what [`super::fw::FwPins`]
//! charges, at the same points (so the tick interrupt is taken at the same instants), but does
//! not write P4DDR: it decodes the master's bytes from its own pin operations, answers the ACK
//! bits as the chips would (a chip in its write cycle does not acknowledge its control byte,
//! decided at the fall of SCL after the byte's eighth bit, as the pin-level chip decides), and
//! hands each completed write transfer to the chip at transaction level at the instant of its
//! STOP ([`eeprom::I2cBus::write_transaction`]). During ACK polling it lets the master skip the
//! polls that are certain to go unacknowledged. The outcome — the chips' memory, write counters
//! and seeded write-cycle times, the states of the save, the MCU clock — is the pin-level one;
//! the controller's tests compare the two run for run. Only the bus's edge counter differs (it
//! counts pin-level traffic).

use eeprom::I2cPins;

use super::fw::{Fw, PIN_OP_STATES};
use crate::bus::Bus;

/// Of a pin operation's 7 states, those before its bus access ends (`MOV.B @P4DR:8` = 2 + 3).
const READ_ACCESS_STATES: u64 = 5;
/// An upper bound of the tick interrupt's states (entry to RTE), for the poll-skipping margin.
const ISR_STATES_BOUND: u64 = 200;

/// The virtual I²C pins of the fast save.
pub struct FastPins<'f, 'a, B: Bus> {
    fw: &'f mut Fw<'a, B>,
    scl_high: bool,
    sda_high: bool,
    /// Bits clocked in the current byte (SCL rises since the byte began).
    bit: u32,
    shift: u8,
    /// Bytes of the current transfer (control byte first).
    bytes: Vec<u8>,
    /// Whether the transfer's control byte was acknowledged.
    acked: bool,
    /// The answer for the ninth clock of the current byte.
    ack_now: bool,
    /// The instant the last START completed (its SCL fall) and when the next control byte was
    /// decided, for the poll-skipping estimate.
    start_at: u64,
    decision_offset: Option<u64>,
    /// The chip the last control byte addressed.
    last_device: Option<u8>,
    tick_period: u64,
    /// The first error the chips reported, if any (a chip off or missing): the transfer then
    /// goes unacknowledged, as on the wire.
    pub failure: Option<eeprom::EepromError>,
}

impl<'f, 'a, B: Bus> FastPins<'f, 'a, B> {
    /// Virtual pins on `fw`'s MCU; both lines released.
    pub fn new(fw: &'f mut Fw<'a, B>, tick_period: u64) -> Self {
        Self {
            fw,
            scl_high: true,
            sda_high: true,
            bit: 0,
            shift: 0,
            bytes: Vec::with_capacity(80),
            acked: false,
            ack_now: false,
            start_at: 0,
            decision_offset: None,
            last_device: None,
            tick_period,
            failure: None,
        }
    }

    /// A pin operation: 7 states, the tick taken at its end if due (as `FwPins` does).
    fn op(&mut self) {
        self.fw.idle(PIN_OP_STATES);
        self.fw.service();
    }

    fn device(&self) -> Option<u8> {
        self.bytes.first().map(|c| 0x50 | ((c >> 1) & 0b111))
    }

    /// Whether the chip addressed by the control byte answers at `now`.
    fn chip_ready(&mut self, now: u64, control: u8) -> bool {
        if control >> 4 != 0b1010 || control & 1 != 0 {
            // Only write control bytes are sent by the save; anything else is not for us.
            return false;
        }
        let device = 0x50 | ((control >> 1) & 0b111);
        match self.fw.bus.eeprom_bus().map(|b| b.busy_until(now, device)) {
            Some(Ok(None)) => b_powered(self.fw.bus, device),
            Some(Ok(Some(_))) => false,
            Some(Err(e)) => {
                self.failure.get_or_insert(e);
                false
            }
            None => false,
        }
    }

    fn scl_fall(&mut self) {
        self.scl_high = false;
        let now = self.fw.now();
        if self.bit == 8 {
            // The chips decide on the byte at this fall (the ninth clock follows).
            let byte = self.shift;
            self.ack_now = if self.bytes.is_empty() {
                self.decision_offset = Some(now.saturating_sub(self.start_at));
                self.last_device = Some(0x50 | ((byte >> 1) & 0b111));
                self.acked = self.chip_ready(now, byte);
                self.acked
            } else {
                self.acked
            };
        } else if self.bit == 9 {
            self.bytes.push(self.shift);
            self.bit = 0;
            self.shift = 0;
        } else if self.bit == 0 && self.bytes.is_empty() {
            // The fall that completes a START.
            self.start_at = now;
        }
    }

    fn scl_rise(&mut self) {
        self.scl_high = true;
        if self.bit < 8 {
            self.shift = (self.shift << 1) | u8::from(self.sda_high);
        }
        self.bit += 1;
    }

    fn start_condition(&mut self) {
        self.bytes.clear();
        self.bit = 0;
        self.shift = 0;
        self.acked = false;
    }

    fn stop_condition(&mut self) {
        let now = self.fw.now();
        if self.acked
            && self.bytes.len() >= 4
            && let Some(device) = self.device()
        {
            let address = u16::from_be_bytes([self.bytes[1], self.bytes[2]]);
            let data = self.bytes[3..].to_vec();
            if let Some(bus) = self.fw.bus.eeprom_bus()
                && let Err(e) = bus.write_transaction(now, device, address, &data)
            {
                self.failure.get_or_insert(e);
            }
        }
        self.start_condition();
    }
}

fn b_powered<B: Bus>(bus: &mut B, device: u8) -> bool {
    bus.eeprom_bus()
        .and_then(|b| b.device(device).ok())
        .is_some_and(eeprom::Eeprom24lc256::is_powered)
}

impl<B: Bus> I2cPins for FastPins<'_, '_, B> {
    fn scl_low(&mut self) {
        self.op();
        self.scl_fall();
    }

    fn scl_release(&mut self) {
        self.op();
        self.scl_rise();
    }

    fn sda_low(&mut self) {
        self.op();
        if self.sda_high && self.scl_high {
            self.start_condition();
        }
        self.sda_high = false;
    }

    fn sda_release(&mut self) {
        self.op();
        let stop = !self.sda_high && self.scl_high;
        self.sda_high = true;
        if stop {
            self.stop_condition();
        }
    }

    fn sda_is_high(&mut self) -> bool {
        // MOV.B @P4DR:8,R0L (the tick may come after it) ; BTST #7,R0L.
        self.fw.idle(READ_ACCESS_STATES);
        self.fw.service();
        self.fw.idle(PIN_OP_STATES - READ_ACCESS_STATES);
        self.fw.service();
        if self.bit == 9 {
            // The ninth clock: low is an ACK.
            !self.ack_now
        } else {
            // The save only reads ACK bits; a released line reads high.
            self.sda_high
        }
    }

    fn wait_states(&mut self, states: u64) {
        self.fw.lump(states);
    }

    fn op_states(&self) -> u64 {
        PIN_OP_STATES
    }

    fn skip_polls(&mut self, poll_states: u64, max: u32) -> u32 {
        // Right after a repeated START: the next control byte is decided `offset` later.
        let (Some(offset), Some(device)) = (self.decision_offset, self.last_device) else {
            return 0;
        };
        let now = self.fw.now();
        let end = match self.fw.bus.eeprom_bus().map(|b| b.busy_until(now, device)) {
            Some(Ok(Some(end))) => end,
            _ => return 0,
        };
        // Skip poll j only if its decision, delayed by every tick that could come first,
        // is still before the end of the write cycle.
        let mut k = 0u32;
        while k < max {
            let decide = now + u64::from(k) * poll_states + offset;
            let ticks = (decide - now) / self.tick_period.max(1) + 1;
            if decide + ticks * ISR_STATES_BOUND >= end {
                break;
            }
            k += 1;
        }
        if k > 0 {
            self.fw.idle(u64::from(k) * poll_states);
            self.fw.service();
        }
        k
    }
}
