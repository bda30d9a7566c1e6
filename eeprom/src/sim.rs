//! A pins implementation that drives an [`I2cBus`] directly, with a local clock: the chips can
//! be tested without the emulated MCU.

use crate::bus::{EdgeCounts, I2cBus};
use crate::error::EepromError;
use crate::master::I2cPins;

/// Pins wired straight to an [`I2cBus`]. Each pin operation advances the local clock by
/// `op_states` (default 0) and then acts; `wait_states` advances it. The bus follows the
/// local clock, which never runs behind the bus's own time.
#[derive(Clone, Debug)]
pub struct SimPins {
    bus: I2cBus,
    now: u64,
    op_states: u64,
    error: Option<EepromError>,
}

impl SimPins {
    /// Pins on `bus`, starting at the bus's present time.
    #[must_use]
    pub fn new(bus: I2cBus) -> SimPins {
        SimPins {
            now: bus.now(),
            bus,
            op_states: 0,
            error: None,
        }
    }

    /// Sets the cost of each pin operation in states (e.g. what the H8 firmware's DDR update
    /// takes), which the master subtracts from its waits.
    #[must_use]
    pub fn with_op_states(mut self, op_states: u64) -> SimPins {
        self.op_states = op_states;
        self
    }

    /// The local time in states (never behind the bus's time).
    #[must_use]
    pub fn now(&self) -> u64 {
        self.now.max(self.bus.now())
    }

    /// The bus.
    #[must_use]
    pub fn bus(&self) -> &I2cBus {
        &self.bus
    }

    /// The bus, mutable (to cut power, load chips…). Calls there should use times ≥
    /// [`SimPins::now`]; the local clock catches up with the bus if they go further.
    pub fn bus_mut(&mut self) -> &mut I2cBus {
        &mut self.bus
    }

    /// Gives the bus back, brought to the local time.
    ///
    /// # Errors
    /// Never in practice: the local clock is never behind the bus.
    pub fn into_bus(mut self) -> Result<I2cBus, EepromError> {
        self.sync();
        self.bus.advance_to(self.now)?;
        Ok(self.bus)
    }

    /// Line transitions so far.
    #[must_use]
    pub fn edges(&self) -> EdgeCounts {
        self.bus.edges()
    }

    /// The first bus error met, if any (none can occur unless the bus was moved past the local
    /// clock behind the pins' back and back again).
    #[must_use]
    pub fn error(&self) -> Option<&EepromError> {
        self.error.as_ref()
    }

    /// Lets `states` pass and brings the bus up to date.
    ///
    /// # Errors
    /// Never in practice (see [`SimPins::error`]).
    pub fn advance(&mut self, states: u64) -> Result<(), EepromError> {
        self.sync();
        self.now = self.now.saturating_add(states);
        self.bus.advance_to(self.now)
    }

    fn sync(&mut self) {
        self.now = self.now.max(self.bus.now());
    }

    fn record(&mut self, r: Result<(), EepromError>) {
        if let Err(e) = r
            && self.error.is_none()
        {
            self.error = Some(e);
        }
    }

    fn step(&mut self) {
        self.sync();
        self.now = self.now.saturating_add(self.op_states);
    }

    fn set(&mut self, scl: Option<bool>, sda: Option<bool>) {
        self.step();
        let (scl_low, sda_low) = self.bus.master_pulls();
        let r = self
            .bus
            .set_master(self.now, scl.unwrap_or(scl_low), sda.unwrap_or(sda_low));
        self.record(r);
    }
}

impl I2cPins for SimPins {
    fn scl_low(&mut self) {
        self.set(Some(true), None);
    }

    fn scl_release(&mut self) {
        self.set(Some(false), None);
    }

    fn sda_low(&mut self) {
        self.set(None, Some(true));
    }

    fn sda_release(&mut self) {
        self.set(None, Some(false));
    }

    fn sda_is_high(&mut self) -> bool {
        self.step();
        match self.bus.lines(self.now) {
            Ok(l) => l.sda,
            Err(e) => {
                self.record(Err(e));
                true
            }
        }
    }

    fn wait_states(&mut self, states: u64) {
        self.sync();
        self.now = self.now.saturating_add(states);
    }

    fn op_states(&self) -> u64 {
        self.op_states
    }
}
