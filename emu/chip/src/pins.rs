//! The pins of the H8/3052F as the world outside the chip drives them: the [`Board`] trait,
//! which answers for the input pins the chip samples, and [`NullBoard`], nothing connected.
//!
//! The chip knows its pins, not the parts on them: what sits on a pin (a sensor, a bumper) is
//! the board layer's business (`robot_board::wiring`).

/// The robot outside the chip, as the MCU's input pins see it.
pub trait Board {
    /// Volts on analog input ANn at `now_states` (called at each conversion's sampling instant).
    fn analog_volts(&mut self, channel: u8, now_states: u64) -> f64;
    /// Levels of the port-2 input pins (bit n = P2.n) at `now_states`: 0 where something pulls
    /// the pin low (a pressed bumper), 1 where nothing does — such a pin reads high only with
    /// its on-chip pull-up enabled (P2PCR), as the robot's bumpers are wired (`robot_board::wiring`).
    fn port2_pins(&mut self, now_states: u64) -> u8;
}

/// A board with nothing connected: every analog input at 0 V, every port-2 pin released
/// (high with its pull-up). What `h8swarm emu` runs machine code with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NullBoard;

impl Board for NullBoard {
    fn analog_volts(&mut self, _channel: u8, _now_states: u64) -> f64 {
        0.0
    }

    fn port2_pins(&mut self, _now_states: u64) -> u8 {
        0xFF
    }
}
