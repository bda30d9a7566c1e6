//! Boards shared by the tests that run the robot firmware on the chip.

use h8_3052f::pins::Board;

/// A board whose four IR voltages wander (a different slow triangle per channel, 0.4-2.6 V), so
/// that the learner sees rewards and punishments; the bumpers (port 2) read released.
pub struct Wandering;

impl Board for Wandering {
    fn analog_volts(&mut self, channel: u8, now_states: u64) -> f64 {
        let period = 40_000_000 + 7_000_000 * u64::from(channel);
        let phase = (now_states % period) as f64 / period as f64;
        let tri = if phase < 0.5 {
            phase * 2.0
        } else {
            2.0 - phase * 2.0
        };
        0.4 + 2.2 * tri
    }
    fn port2_pins(&mut self, _now_states: u64) -> u8 {
        0xFF
    }
}
