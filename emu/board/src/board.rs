//! The robot's board as the chip's pins see it: its clock ([`CLOCK_HZ`]), its own parts on
//! port 4 — the two 24LC256 EEPROMs at 0x50 and 0x51 on the bit-banged I²C bus, SDA on P4.7
//! and SCL on P4.6 (docs/design.md §3.6) — and, for every other pin, what the world drives
//! (the IR sensors' voltages, the bumpers: a [`Board`] of the caller's, [`RobotBoard::world`]).
//!
//! The chip knows pins, not parts ([`h8_3052f::pins`]): [`RobotBoard`] implements the chip's
//! port-4 exchange on the EEPROM bus — the port's pulls become the master's pulls on the bus,
//! P4DR reads the bus's wired-AND line levels — and hands the chip the bus's own events (the
//! end of a write cycle), its line log for pin traces and the power switching. It is built
//! from a plain description of the robot, [`RobotConfig`] (its clock and the EEPROMs' seed);
//! [`robot_mcu`] builds the chip on it.
//!
//! `h8swarm emu` runs images on `RobotBoard<NullBoard>`: the EEPROMs present (seed 0), nothing
//! else connected, so a program that uses the EEPROMs runs as on the robot.

use eeprom::{EepromError, I2cBus, PowerCutOutcome};
use h8_3052f::mcu::{MAX_CLOCK_HZ, Mcu, McuConfig, McuError};
use h8_3052f::periph::ports::{P4_SCL, P4_SDA};
use h8_3052f::pins::Board;

/// The robot's clock φ: the AKI-H8/3052F board runs the chip at its highest φ, 25 MHz
/// ([`MAX_CLOCK_HZ`]), one state = 40 ns (docs/design.md §4.1). The one definition of the
/// robot's clock: the scenarios' default, the model controller's, the cost report's and the
/// parts' clocks (the sensors', the EEPROMs', the world's, which take it as a parameter) all
/// come from here.
pub const CLOCK_HZ: u32 = MAX_CLOCK_HZ;

/// What a robot's board is built from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RobotConfig {
    /// The MCU's clock φ in Hz, which the EEPROMs' timing counts in too ([`CLOCK_HZ`] by
    /// default).
    pub clock_hz: u32,
    /// Seed of the two EEPROMs' random streams (write-cycle times, power-cut corruption,
    /// wear).
    pub eeprom_seed: u64,
}

impl Default for RobotConfig {
    fn default() -> Self {
        RobotConfig {
            clock_hz: CLOCK_HZ,
            eeprom_seed: 0,
        }
    }
}

/// Why a robot's MCU and board cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BoardError {
    /// The chip refuses the configuration (φ outside its range).
    #[error(transparent)]
    Mcu(#[from] McuError),
    /// The EEPROM model refuses the configuration.
    #[error("EEPROM bus on port 4")]
    Eeprom(#[from] EepromError),
}

/// The robot's board: the EEPROM bus on port 4 and `world` on every other pin.
#[derive(Clone, Debug)]
pub struct RobotBoard<W> {
    /// What the world drives on the chip's other pins: the analog inputs and port 2
    /// ([`Board::analog_volts`], [`Board::port2_pins`]; its port-4 methods are not asked).
    pub world: W,
    eeproms: I2cBus,
    last_power_cut: Vec<PowerCutOutcome>,
}

impl<W> RobotBoard<W> {
    /// The board with `world` outside and the robot's two 24LC256 (0x50, 0x51) on port 4,
    /// counting in `config.clock_hz`, their streams seeded from `config.eeprom_seed`.
    ///
    /// # Errors
    /// [`EepromError`] if the EEPROM model refuses the clock.
    pub fn new(world: W, config: &RobotConfig) -> Result<Self, EepromError> {
        let eeproms = I2cBus::robot(config.eeprom_seed, config.clock_hz)?;
        Ok(RobotBoard {
            world,
            eeproms,
            last_power_cut: Vec::new(),
        })
    }

    /// The I²C bus with the two EEPROMs.
    #[must_use]
    pub fn eeproms(&self) -> &I2cBus {
        &self.eeproms
    }

    /// The I²C bus, mutably (back-door loads and reads of the chips, the model controller's
    /// transaction-level save). Keep its time calls at or after the MCU's clock.
    pub fn eeproms_mut(&mut self) -> &mut I2cBus {
        &mut self.eeproms
    }

    /// Each chip's outcome of the latest power cut (0x50, then 0x51); empty before the first.
    #[must_use]
    pub fn last_power_cut(&self) -> &[PowerCutOutcome] {
        &self.last_power_cut
    }

    /// The bus's time for an operation at `now`: never before the bus's own clock, so that
    /// the bus cannot refuse it (time never goes back).
    fn at(&self, now: u64) -> u64 {
        now.max(self.eeproms.now())
    }
}

/// Port-4 levels (bit n = P4.n) of the bus's lines: SDA on P4.7, SCL on P4.6; nothing else on
/// port 4, so the other lines read released.
fn port4_levels(scl: bool, sda: bool) -> u8 {
    !(P4_SDA | P4_SCL) | if sda { P4_SDA } else { 0 } | if scl { P4_SCL } else { 0 }
}

impl<W: Board> Board for RobotBoard<W> {
    fn analog_volts(&mut self, channel: u8, now_states: u64) -> f64 {
        self.world.analog_volts(channel, now_states)
    }

    fn port2_pins(&mut self, now_states: u64) -> u8 {
        self.world.port2_pins(now_states)
    }

    /// The port's pulls on P4.6/P4.7 become the master's pulls on SCL/SDA.
    fn port4_drive(&mut self, pulled_low: u8, now_states: u64) {
        let scl_low = pulled_low & P4_SCL != 0;
        let sda_low = pulled_low & P4_SDA != 0;
        if self.eeproms.master_pulls() != (scl_low, sda_low) {
            let t = self.at(now_states);
            // Cannot fail: time never goes back here.
            let _ = self.eeproms.set_master(t, scl_low, sda_low);
        }
    }

    /// The bus's line levels on P4.7/P4.6 (the wired AND of the port's pulls and the chips').
    fn port4_pins(&mut self, now_states: u64) -> u8 {
        let t = self.at(now_states);
        match self.eeproms.lines(t) {
            Ok(l) => port4_levels(l.scl, l.sda),
            // Cannot happen (time never goes back here); read the lines as released.
            Err(_) => 0xFF,
        }
    }

    /// The end of a chip's write cycle (a chip's scheduled output change).
    fn next_event_states(&self, now_states: u64) -> Option<u64> {
        self.eeproms.next_event_states().filter(|&t| t > now_states)
    }

    fn sync(&mut self, now_states: u64) {
        let t = self.at(now_states);
        // Time never goes back here (max), so the bus cannot refuse.
        let _ = self.eeproms.advance_to(t);
    }

    fn now_states(&self) -> u64 {
        self.eeproms.now()
    }

    fn set_pin_log(&mut self, on: bool) {
        self.eeproms.set_line_log(on);
    }

    fn take_pin_log(&mut self) -> Vec<(u64, u8)> {
        self.eeproms
            .take_line_log()
            .into_iter()
            .map(|(t, l)| (t, port4_levels(l.scl, l.sda)))
            .collect()
    }

    /// Both chips lose power (a write cycle under way is corrupted as the `eeprom` crate
    /// models it) and the master's lines are released; the outcomes are kept
    /// ([`RobotBoard::last_power_cut`]).
    fn power_cut(&mut self, now_states: u64) {
        let t = self.at(now_states);
        // Cannot fail: time never goes back here.
        self.last_power_cut = self.eeproms.power_cut(t).unwrap_or_default();
    }

    fn power_on(&mut self, now_states: u64) {
        let t = self.at(now_states);
        // Cannot fail: time never goes back here.
        let _ = self.eeproms.power_on(t);
    }
}

/// The H8/3052F on the robot's board: φ = `config.clock_hz`, `world` on the analog inputs and
/// port 2, the EEPROMs on port 4.
///
/// # Errors
/// [`BoardError::Mcu`] if the chip refuses the clock (checked first);
/// [`BoardError::Eeprom`] if the EEPROM model refuses it.
pub fn robot_mcu<W: Board>(
    world: W,
    config: &RobotConfig,
) -> Result<Mcu<RobotBoard<W>>, BoardError> {
    let mcu_config = McuConfig {
        clock_hz: config.clock_hz,
    };
    mcu_config.validate()?;
    Ok(Mcu::new(mcu_config, RobotBoard::new(world, config)?)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use h8_3052f::pins::NullBoard;

    #[test]
    fn the_eeproms_count_in_the_mcus_clock() {
        let cfg = RobotConfig {
            clock_hz: 16_000_000,
            eeprom_seed: 1,
        };
        let m = robot_mcu(NullBoard, &cfg).unwrap();
        assert_eq!(m.clock_hz(), 16_000_000);
        let d = m.board().eeproms().devices();
        assert_eq!(d.len(), 2);
        assert_eq!(d[0].clock().hz(), 16_000_000);
        assert_eq!(d[1].clock().hz(), 16_000_000);
    }

    #[test]
    fn a_clock_the_chip_refuses_is_the_chips_error() {
        for hz in [0, 1_000_000, CLOCK_HZ + 1] {
            let e = robot_mcu(
                NullBoard,
                &RobotConfig {
                    clock_hz: hz,
                    eeprom_seed: 0,
                },
            )
            .unwrap_err();
            assert_eq!(e, BoardError::Mcu(McuError::InvalidClock { clock_hz: hz }));
        }
    }

    #[test]
    fn the_default_robot_runs_at_the_chips_highest_clock() {
        let m = robot_mcu(NullBoard, &RobotConfig::default()).unwrap();
        assert_eq!(m.clock_hz(), CLOCK_HZ);
        assert_eq!(CLOCK_HZ, 25_000_000);
    }
}
