//! The two-wire bus: open-drain SDA and SCL with pull-ups, one master and several 24LC256s.

use crate::datasheet::{FIRST_DEVICE_ADDRESS, LAST_DEVICE_ADDRESS};
use crate::device::{DeviceConfig, Eeprom24lc256, PowerCutOutcome};
use crate::error::EepromError;

/// Levels of the two lines (true = high).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LineLevels {
    /// SCL level.
    pub scl: bool,
    /// SDA level.
    pub sda: bool,
}

/// Transitions of the lines counted since the bus was built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct EdgeCounts {
    /// SCL low → high.
    pub scl_rising: u64,
    /// SCL high → low.
    pub scl_falling: u64,
    /// SDA low → high.
    pub sda_rising: u64,
    /// SDA high → low.
    pub sda_falling: u64,
}

impl EdgeCounts {
    /// All transitions of both lines.
    #[must_use]
    pub fn total(&self) -> u64 {
        self.scl_rising + self.scl_falling + self.sda_rising + self.sda_falling
    }

    /// Transitions since `earlier` (a count taken before).
    #[must_use]
    pub fn since(&self, earlier: &EdgeCounts) -> EdgeCounts {
        EdgeCounts {
            scl_rising: self.scl_rising.saturating_sub(earlier.scl_rising),
            scl_falling: self.scl_falling.saturating_sub(earlier.scl_falling),
            sda_rising: self.sda_rising.saturating_sub(earlier.sda_rising),
            sda_falling: self.sda_falling.saturating_sub(earlier.sda_falling),
        }
    }
}

/// An I²C bus with wired-AND lines: each party either pulls a line low or releases it, and a
/// line is high only when nobody pulls it (the pull-ups — on the robot, port 4's on-chip MOS
/// pull-ups).
///
/// Only the master drives SCL (a 24LC256 never stretches the clock). Every call takes the
/// present time in states and time must not go back. Device output changes scheduled in the
/// past of `now` are applied, in time order, before the call acts. When one call changes both
/// lines, the devices see SCL's transition first, then SDA's.
#[derive(Clone, Debug)]
pub struct I2cBus {
    devices: Vec<Eeprom24lc256>,
    master_scl_low: bool,
    master_sda_low: bool,
    scl_high: bool,
    sda_high: bool,
    now: u64,
    edges: EdgeCounts,
    /// Every change of the line levels with its instant, while a log is kept
    /// ([`I2cBus::set_line_log`]): for pin traces.
    line_log: Option<Vec<(u64, LineLevels)>>,
}

impl I2cBus {
    /// A bus with these devices, both lines released and high, at the latest time any of the
    /// devices has seen (0 for new chips).
    ///
    /// # Errors
    /// Two devices with one address, or more than eight devices.
    pub fn new(devices: Vec<Eeprom24lc256>) -> Result<I2cBus, EepromError> {
        let max = usize::from(LAST_DEVICE_ADDRESS - FIRST_DEVICE_ADDRESS) + 1;
        if devices.len() > max {
            return Err(EepromError::TooManyDevices {
                count: devices.len(),
            });
        }
        for (i, d) in devices.iter().enumerate() {
            if devices[..i].iter().any(|o| o.address() == d.address()) {
                return Err(EepromError::DuplicateDeviceAddress {
                    address: d.address(),
                });
            }
        }
        let now = devices
            .iter()
            .map(Eeprom24lc256::now_states)
            .max()
            .unwrap_or(0);
        Ok(I2cBus {
            devices,
            master_scl_low: false,
            master_sda_low: false,
            scl_high: true,
            sda_high: true,
            now,
            edges: EdgeCounts::default(),
            line_log: None,
        })
    }

    /// A bus with one chip per address in `addresses`, each configured as `base` but for its
    /// address (each chip's random streams are keyed by its address, so they differ).
    ///
    /// # Errors
    /// As [`Eeprom24lc256::new`] and [`I2cBus::new`].
    pub fn with_chips(addresses: &[u8], base: &DeviceConfig) -> Result<I2cBus, EepromError> {
        let devices = addresses
            .iter()
            .map(|&address| {
                Eeprom24lc256::new(DeviceConfig {
                    address,
                    ..base.clone()
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        I2cBus::new(devices)
    }

    /// The robot's bus: chips at 0x50 and 0x51 with datasheet defaults, counting in the MCU's
    /// `clock_hz`, streams from `seed`.
    ///
    /// # Errors
    /// [`EepromError::InvalidClock`] for a zero clock.
    pub fn robot(seed: u64, clock_hz: u32) -> Result<I2cBus, EepromError> {
        I2cBus::with_chips(
            &[crate::persist::CHIP_A, crate::persist::CHIP_B],
            &DeviceConfig::new(crate::persist::CHIP_A, seed, clock_hz),
        )
    }

    /// The latest time the bus has seen, in states.
    #[must_use]
    pub fn now(&self) -> u64 {
        self.now
    }

    /// Line transitions so far.
    #[must_use]
    pub fn edges(&self) -> EdgeCounts {
        self.edges
    }

    /// The devices, in the order given.
    #[must_use]
    pub fn devices(&self) -> &[Eeprom24lc256] {
        &self.devices
    }

    fn index_of(&self, address: u8) -> Result<usize, EepromError> {
        self.devices
            .iter()
            .position(|d| d.address() == address)
            .ok_or_else(|| EepromError::NoSuchDevice {
                address,
                present: self
                    .devices
                    .iter()
                    .map(|d| format!("0x{:02X}", d.address()))
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// The device at `address`.
    ///
    /// # Errors
    /// [`EepromError::NoSuchDevice`] if none is there.
    pub fn device(&self, address: u8) -> Result<&Eeprom24lc256, EepromError> {
        Ok(&self.devices[self.index_of(address)?])
    }

    /// The device at `address`, mutable (for back-door loads and reads). A device's own
    /// time-taking calls should get a time ≥ [`I2cBus::now`] and not later than the bus's next
    /// call; switch a chip's power through [`I2cBus::power_off_device`] /
    /// [`I2cBus::power_on_device`] so the lines settle.
    ///
    /// # Errors
    /// [`EepromError::NoSuchDevice`] if none is there.
    pub fn device_mut(&mut self, address: u8) -> Result<&mut Eeprom24lc256, EepromError> {
        let i = self.index_of(address)?;
        Ok(&mut self.devices[i])
    }

    /// The earliest scheduled device output change, if any (a hook for event-driven callers).
    #[must_use]
    pub fn next_event_states(&self) -> Option<u64> {
        self.devices
            .iter()
            .filter_map(Eeprom24lc256::next_event)
            .min()
    }

    /// Brings the bus to `now`, applying scheduled device output changes in time order.
    ///
    /// # Errors
    /// [`EepromError::TimeWentBackwards`] if `now` is before [`I2cBus::now`].
    pub fn advance_to(&mut self, now: u64) -> Result<(), EepromError> {
        if now < self.now {
            return Err(EepromError::TimeWentBackwards {
                now,
                last: self.now,
            });
        }
        // Devices end their write cycles lazily, whenever they are next touched.
        loop {
            let next = self
                .devices
                .iter()
                .enumerate()
                .filter_map(|(i, d)| d.next_event().map(|t| (t, i)))
                .min();
            match next {
                Some((t, i)) if t <= now => {
                    self.now = self.now.max(t);
                    let at = self.now;
                    self.devices[i].apply_event(at);
                    self.settle(at);
                }
                _ => break,
            }
        }
        self.now = now;
        Ok(())
    }

    /// A whole write transfer to the chip at `device`, at transaction level (see
    /// [`Eeprom24lc256::write_transaction`]): the bus lines do not move and no edges are
    /// counted. Returns when the chip's write cycle ends.
    ///
    /// # Errors
    /// No such chip, time going backwards, a chip that is off or busy.
    pub fn write_transaction(
        &mut self,
        stop_states: u64,
        device: u8,
        address: u16,
        data: &[u8],
    ) -> Result<u64, EepromError> {
        self.advance_to(stop_states)?;
        let i = self.index_of(device)?;
        self.devices[i].write_transaction(stop_states, address, data)
    }

    /// The instant the write cycle of the chip at `device` ends, if one runs at `now`.
    ///
    /// # Errors
    /// No such chip.
    pub fn busy_until(&self, now: u64, device: u8) -> Result<Option<u64>, EepromError> {
        let d = self.device(device)?;
        Ok(d.is_busy_at(now)
            .then(|| d.current_write_cycle().map(|c| c.end_states))
            .flatten())
    }

    /// Starts (`true`) or stops (`false`) keeping a log of the line levels: every change of
    /// SCL or SDA with the instant it happens (a master's pull, a chip's scheduled output
    /// change, a power cut), for pin traces. Stopping discards what was not taken.
    pub fn set_line_log(&mut self, on: bool) {
        self.line_log = on.then(Vec::new);
    }

    /// The line changes logged since the last call, in time order: (instant, the levels from
    /// then on). Empty when no log is kept.
    pub fn take_line_log(&mut self) -> Vec<(u64, LineLevels)> {
        self.line_log
            .as_mut()
            .map(std::mem::take)
            .unwrap_or_default()
    }

    /// Appends the present levels to the line log, if one is kept.
    #[inline]
    fn log_lines(&mut self, now: u64) {
        if let Some(log) = self.line_log.as_mut() {
            log.push((
                now,
                LineLevels {
                    scl: self.scl_high,
                    sda: self.sda_high,
                },
            ));
        }
    }

    /// Recomputes the wired-AND levels and tells every device about each transition.
    fn settle(&mut self, now: u64) {
        let scl = !self.master_scl_low;
        if scl != self.scl_high {
            self.scl_high = scl;
            if scl {
                self.edges.scl_rising += 1;
            } else {
                self.edges.scl_falling += 1;
            }
            let sda = self.sda_high;
            for d in &mut self.devices {
                d.on_scl(now, scl, sda);
            }
            self.log_lines(now);
        }
        let sda = !(self.master_sda_low || self.devices.iter().any(Eeprom24lc256::pulls_sda));
        if sda != self.sda_high {
            self.sda_high = sda;
            if sda {
                self.edges.sda_rising += 1;
            } else {
                self.edges.sda_falling += 1;
            }
            let scl = self.scl_high;
            for d in &mut self.devices {
                d.on_sda(now, sda, scl);
            }
            self.log_lines(now);
        }
    }

    /// Sets what the master does with both lines at `now` (`true` = pull low, `false` =
    /// release). This is what a write to port 4's DDR amounts to on the robot.
    ///
    /// # Errors
    /// [`EepromError::TimeWentBackwards`] if `now` is before [`I2cBus::now`].
    pub fn set_master(
        &mut self,
        now: u64,
        scl_low: bool,
        sda_low: bool,
    ) -> Result<(), EepromError> {
        self.advance_to(now)?;
        self.master_scl_low = scl_low;
        self.master_sda_low = sda_low;
        self.settle(now);
        Ok(())
    }

    /// Sets the master's SCL at `now` (`true` = pull low, `false` = release).
    ///
    /// # Errors
    /// [`EepromError::TimeWentBackwards`] if `now` is before [`I2cBus::now`].
    pub fn set_master_scl(&mut self, now: u64, low: bool) -> Result<(), EepromError> {
        let sda = self.master_sda_low;
        self.set_master(now, low, sda)
    }

    /// Sets the master's SDA at `now` (`true` = pull low, `false` = release).
    ///
    /// # Errors
    /// [`EepromError::TimeWentBackwards`] if `now` is before [`I2cBus::now`].
    pub fn set_master_sda(&mut self, now: u64, low: bool) -> Result<(), EepromError> {
        let scl = self.master_scl_low;
        self.set_master(now, scl, low)
    }

    /// What the master pulls: (SCL low, SDA low).
    #[must_use]
    pub fn master_pulls(&self) -> (bool, bool) {
        (self.master_scl_low, self.master_sda_low)
    }

    /// The line levels at `now` (what reading port 4's DR returns for P4.6/P4.7).
    ///
    /// # Errors
    /// [`EepromError::TimeWentBackwards`] if `now` is before [`I2cBus::now`].
    pub fn lines(&mut self, now: u64) -> Result<LineLevels, EepromError> {
        self.advance_to(now)?;
        Ok(LineLevels {
            scl: self.scl_high,
            sda: self.sda_high,
        })
    }

    /// Cuts the power of the whole robot at `now`: every chip loses power (see
    /// [`Eeprom24lc256::power_off`]) and the master releases both lines (an unpowered port is
    /// an input). Returns each chip's outcome, in device order.
    ///
    /// # Errors
    /// [`EepromError::TimeWentBackwards`] if `now` is before [`I2cBus::now`].
    pub fn power_cut(&mut self, now: u64) -> Result<Vec<PowerCutOutcome>, EepromError> {
        self.advance_to(now)?;
        let mut outcomes = Vec::with_capacity(self.devices.len());
        for d in &mut self.devices {
            outcomes.push(d.power_off(now)?);
        }
        self.master_scl_low = false;
        self.master_sda_low = false;
        self.settle(now);
        Ok(outcomes)
    }

    /// Powers every chip on at `now` (the master's lines stay released).
    ///
    /// # Errors
    /// [`EepromError::TimeWentBackwards`] if `now` is before [`I2cBus::now`].
    pub fn power_on(&mut self, now: u64) -> Result<(), EepromError> {
        self.advance_to(now)?;
        for d in &mut self.devices {
            d.power_on(now)?;
        }
        self.settle(now);
        Ok(())
    }

    /// Cuts the power of one chip at `now` and lets the lines settle.
    ///
    /// # Errors
    /// No such device, or time going back.
    pub fn power_off_device(
        &mut self,
        now: u64,
        address: u8,
    ) -> Result<PowerCutOutcome, EepromError> {
        self.advance_to(now)?;
        let i = self.index_of(address)?;
        let outcome = self.devices[i].power_off(now)?;
        self.settle(now);
        Ok(outcome)
    }

    /// Powers one chip on at `now`.
    ///
    /// # Errors
    /// No such device, or time going back.
    pub fn power_on_device(&mut self, now: u64, address: u8) -> Result<(), EepromError> {
        self.advance_to(now)?;
        let i = self.index_of(address)?;
        self.devices[i].power_on(now)?;
        self.settle(now);
        Ok(())
    }

    /// Timing violations seen by all devices together.
    #[must_use]
    pub fn timing_violation_count(&self) -> u64 {
        self.devices
            .iter()
            .map(Eeprom24lc256::timing_violation_count)
            .sum()
    }
}

#[cfg(test)]
mod line_log_tests {
    use super::*;

    #[test]
    fn the_line_log_holds_every_change_with_its_instant() {
        let mut bus = I2cBus::robot(7, 25_000_000).unwrap();
        // No log yet: nothing is kept.
        bus.set_master(10, false, true).unwrap();
        assert!(bus.take_line_log().is_empty());
        bus.set_line_log(true);
        bus.set_master(20, false, false).unwrap(); // SDA released: rises
        bus.set_master(30, true, false).unwrap(); // SCL pulled: falls
        bus.set_master(30, true, false).unwrap(); // no change, no entry
        let log = bus.take_line_log();
        assert_eq!(
            log,
            vec![
                (
                    20,
                    LineLevels {
                        scl: true,
                        sda: true
                    }
                ),
                (
                    30,
                    LineLevels {
                        scl: false,
                        sda: true
                    }
                ),
            ]
        );
        // Taken: the next call starts afresh; stopping discards.
        bus.set_master(40, false, false).unwrap();
        assert_eq!(bus.take_line_log().len(), 1);
        bus.set_master(50, true, false).unwrap();
        bus.set_line_log(false);
        assert!(bus.take_line_log().is_empty());
    }
}
