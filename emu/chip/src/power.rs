//! What the H8/3052F draws from its supply, by state: the figures an energy meter weights with
//! the states the chip spends running, asleep and converting.
//!
//! The chip's own supply current depends on the clock and on what runs, not on the program's
//! instructions one by one: the hardware manual gives it per operating mode (Electrical
//! Characteristics, DC characteristics, "current dissipation", at VCC = 5 V and φ = 25 MHz),
//! and the A/D converter's analog supply and reference currents while it converts. All
//! figures are typical values; the maxima are one and a half to twice as large. The SLEEP
//! instruction stops only the CPU's clock: the oscillator, the ITU and the other modules run
//! on, which is why sleep mode saves only about a third (the manual's software standby mode
//! would stop them all, but then the 10 ms tick could not wake the robot).

/// Supply current while the CPU runs (normal operation), mA: H8/3052F hardware manual,
/// Electrical Characteristics, DC characteristics, current dissipation I_CC, normal
/// operation, typical at VCC = 5.0 V, φ = 25 MHz.
pub const ICC_ACTIVE_MA: f64 = 50.0;

/// Supply current in sleep mode (after SLEEP, the modules running), mA: the same table,
/// current dissipation I_CC, sleep mode, typical at VCC = 5.0 V, φ = 25 MHz.
pub const ICC_SLEEP_MA: f64 = 35.0;

/// Analog supply current (AVCC) while the A/D converter converts, mA: the same table, analog
/// power supply current AI_CC during A/D conversion, typical (0.01 µA idle).
pub const AICC_CONVERTING_MA: f64 = 1.0;

/// Reference supply current (VREF) while the A/D converter converts, mA: the same table,
/// reference current AI_CC during A/D conversion, typical (0.01 µA idle).
pub const AIREF_CONVERTING_MA: f64 = 0.45;

/// The chip's charge over an interval, µC: `busy_states` running, the rest of
/// `interval_states` asleep, `converting_states` with the A/D converter converting, at
/// `clock_hz`.
#[must_use]
pub fn mcu_charge_uc(
    interval_states: u64,
    busy_states: u64,
    converting_states: u64,
    clock_hz: u32,
) -> McuCharge {
    let s = 1e6 / f64::from(clock_hz.max(1));
    let busy = busy_states.min(interval_states);
    McuCharge {
        core_uc: (busy as f64 * ICC_ACTIVE_MA + (interval_states - busy) as f64 * ICC_SLEEP_MA)
            * s
            * 1e-3,
        adc_uc: converting_states as f64 * (AICC_CONVERTING_MA + AIREF_CONVERTING_MA) * s * 1e-3,
    }
}

/// The H8/3052F's charge over an interval, split as the supply pins draw it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct McuCharge {
    /// VCC: the CPU running or asleep with its modules, µC.
    pub core_uc: f64,
    /// AVCC and VREF while the A/D converter converts, µC.
    pub adc_uc: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mcu::MAX_CLOCK_HZ;

    /// One second of states at the chip's highest clock, the robot's (25 MHz).
    const SECOND: u64 = MAX_CLOCK_HZ as u64;

    #[test]
    fn a_sleeping_chip_draws_its_sleep_current() {
        // One second at 25 MHz, never awake: 35 mA for 1 s is 35 000 µC.
        let q = mcu_charge_uc(SECOND, 0, 0, MAX_CLOCK_HZ);
        assert!((q.core_uc - 35_000.0).abs() < 1e-6, "{q:?}");
        assert_eq!(q.adc_uc, 0.0);
        // Busy all the time: the active current.
        let q = mcu_charge_uc(SECOND, SECOND, 0, MAX_CLOCK_HZ);
        assert!((q.core_uc - 50_000.0).abs() < 1e-6, "{q:?}");
        // A scan of four conversions (266 + 3 × 256 states = 41.36 µs) at 1.45 mA: 0.06 µC.
        let q = mcu_charge_uc(1034, 1034, 1034, MAX_CLOCK_HZ);
        assert!(
            (q.adc_uc - 1034.0 / f64::from(MAX_CLOCK_HZ) * 1.45e3).abs() < 1e-9,
            "{q:?}"
        );
    }
}
