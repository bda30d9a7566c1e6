//! MCU time: states of φ, and conversions from datasheet nanoseconds.

use crate::error::EepromError;

const NS_PER_S: u128 = 1_000_000_000;

/// The MCU clock φ that every time in this crate is counted in (one state = 1/φ), given by
/// the caller (the robot's is the board's, docs/design.md §4.1: at 25 MHz one state is 40 ns).
/// The crate has no clock of its own.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Clock {
    clock_hz: u32,
}

impl Clock {
    /// A clock of `clock_hz` (at least 1 Hz; the MCU that runs the master checks its own
    /// range).
    ///
    /// # Errors
    /// [`EepromError::InvalidClock`] for a zero clock.
    pub fn new(clock_hz: u32) -> Result<Clock, EepromError> {
        if clock_hz == 0 {
            return Err(EepromError::InvalidClock { clock_hz });
        }
        Ok(Clock { clock_hz })
    }

    /// φ in hertz.
    #[must_use]
    pub const fn hz(self) -> u32 {
        self.clock_hz
    }

    /// The fewest whole states that last at least `ns` nanoseconds (rounds up): what a master
    /// must wait to meet a datasheet minimum.
    #[must_use]
    pub fn states_at_least(self, ns: u64) -> u64 {
        let num = u128::from(ns) * u128::from(self.clock_hz);
        let states = num.div_ceil(NS_PER_S);
        u64::try_from(states).unwrap_or(u64::MAX)
    }

    /// The most whole states that last at most `ns` nanoseconds (rounds down): what a device may
    /// take to meet a datasheet maximum.
    #[must_use]
    pub fn states_at_most(self, ns: u64) -> u64 {
        let num = u128::from(ns) * u128::from(self.clock_hz);
        u64::try_from(num / NS_PER_S).unwrap_or(u64::MAX)
    }

    /// Whether `states` last at least `ns` nanoseconds (exact, no rounding).
    #[must_use]
    pub fn lasts_at_least(self, states: u64, ns: u64) -> bool {
        u128::from(states) * NS_PER_S >= u128::from(ns) * u128::from(self.clock_hz)
    }

    /// `states` in nanoseconds, rounded down.
    #[must_use]
    pub fn ns(self, states: u64) -> u64 {
        let ns = u128::from(states) * NS_PER_S / u128::from(self.clock_hz);
        u64::try_from(ns).unwrap_or(u64::MAX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_at_25_mhz() {
        let c = Clock::new(25_000_000).unwrap();
        assert_eq!(c.hz(), 25_000_000);
        assert_eq!(c.states_at_least(600), 15);
        assert_eq!(c.states_at_least(1_300), 33);
        assert_eq!(c.states_at_most(900), 22);
        assert_eq!(c.states_at_least(5_000_000), 125_000);
        assert!(c.lasts_at_least(15, 600));
        assert!(!c.lasts_at_least(14, 600));
        assert_eq!(c.ns(25), 1_000);
    }

    #[test]
    fn zero_and_too_fast_clocks_are_errors() {
        assert!(matches!(
            Clock::new(0),
            Err(EepromError::InvalidClock { clock_hz: 0 })
        ));
        assert!(Clock::new(u32::MAX).is_ok());
        assert!(Clock::new(1).is_ok());
        let slow = Clock::new(1).unwrap();
        assert_eq!(slow.states_at_least(1), 1);
        assert_eq!(slow.states_at_most(900), 0);
    }
}
