//! The drive motors as electrical loads: what one motor draws at a PWM duty and a speed.
//!
//! The robot is a commercial toy with two DC gear motors (paper §2); the world moves it like a
//! Tamiya 203:1 gearbox with 56 mm wheels (SPEC §3.5), and every Tamiya twin-motor and double
//! gearbox of that class is built around the Mabuchi FA-130, so the motor is an FA-130. Its
//! published figures give the permanent-magnet DC motor's two constants:
//! - armature resistance R = nominal voltage / stall current;
//! - back-EMF constant Ke = (nominal voltage − no-load current × R) / no-load speed.
//!
//! The bridge's output at full duty is the voltage that makes the motor run free at the
//! world's top speed: V_full = Ke · ω_top + I₀ · R (about 2.2 V at 0.15 m/s, inside the
//! FA-130's 1.5–3 V; the TA7291P's reference input sets it). At duty D the motor sees D · V_full
//! on average.
//!
//! Current: I = (D · V_full − Ke · ω) / R, and none when the back-EMF exceeds the drive (the
//! bridge's output stage sources current but does not take it back). The speed ω is the
//! motor's own: the world gives each wheel's speed over the ground as a fraction ρ of the speed
//! its command asks for (duty × top speed × the wheel's gain), and the motor turns at ρ times
//! its own no-load speed at D · V_full, (D · V_full − I₀ · R) / Ke. So a free wheel at its
//! commanded speed draws the no-load current I₀ whatever the duty; a wheel held still (a robot
//! pressed against a wall) draws the stall current D · V_full / R; an accelerating wheel draws
//! between the two; a wheel that runs faster than its new command (slowing from full to 30 %
//! duty) draws nothing until it has slowed. With the PWM, the pack supplies the motor's current
//! only while the output is on: D · I.

/// Nominal voltage of the FA-130, 1.5 V (Mabuchi FA-130RA-2270 data sheet, "voltage:
/// nominal"; operating range 1.5–3.0 V).
pub const FA130_NOMINAL_VOLTS: f64 = 1.5;
/// No-load speed at the nominal voltage, 6 990 r/min (Mabuchi FA-130RA-2270 data sheet, "no
/// load: speed").
pub const FA130_NO_LOAD_RPM: f64 = 6_990.0;
/// No-load current at the nominal voltage, 0.20 A (Mabuchi FA-130RA-2270 data sheet, "no
/// load: current").
pub const FA130_NO_LOAD_CURRENT_A: f64 = 0.20;
/// Stall current at the nominal voltage, 2.20 A (Mabuchi FA-130RA-2270 data sheet, "stall:
/// current").
pub const FA130_STALL_CURRENT_A: f64 = 2.20;
/// Gear ratio of the Tamiya twin-motor gearbox in its slow setting, 203.7:1 (Tamiya 70097
/// instructions; SPEC §3.5's "203:1").
pub const GEAR_RATIO: f64 = 203.7;
/// Wheel diameter, 56 mm (SPEC §3.5: Tamiya 56 mm wheels).
pub const WHEEL_DIAMETER_M: f64 = 0.056;

/// One drive motor's electrical model (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DcMotor {
    /// Armature resistance, Ω.
    pub resistance_ohm: f64,
    /// Back-EMF constant, V per rad/s of the motor shaft.
    pub ke_v_s_per_rad: f64,
    /// No-load current, A (the motor's own friction).
    pub no_load_current_a: f64,
    /// The bridge's mean output at full duty, V.
    pub full_duty_volts: f64,
}

impl DcMotor {
    /// The FA-130 behind the gearbox, its full-duty voltage set for `top_speed_m_per_s` at the
    /// wheel.
    #[must_use]
    pub fn fa130(top_speed_m_per_s: f64) -> DcMotor {
        let r = FA130_NOMINAL_VOLTS / FA130_STALL_CURRENT_A;
        let no_load_rad_s = FA130_NO_LOAD_RPM * std::f64::consts::TAU / 60.0;
        let ke = (FA130_NOMINAL_VOLTS - FA130_NO_LOAD_CURRENT_A * r) / no_load_rad_s;
        let top_rad_s = top_speed_m_per_s / (WHEEL_DIAMETER_M / 2.0) * GEAR_RATIO;
        DcMotor {
            resistance_ohm: r,
            ke_v_s_per_rad: ke,
            no_load_current_a: FA130_NO_LOAD_CURRENT_A,
            full_duty_volts: ke * top_rad_s + FA130_NO_LOAD_CURRENT_A * r,
        }
    }

    /// The motor's current, A, at PWM duty `duty` (0–1) with the wheel at `speed_ratio` of
    /// the speed its command asks for (1 free-running, 0 held still).
    #[must_use]
    pub fn motor_current_a(&self, duty: f64, speed_ratio: f64) -> f64 {
        let duty = duty.clamp(0.0, 1.0);
        if duty == 0.0 || !speed_ratio.is_finite() {
            return 0.0;
        }
        let v = duty * self.full_duty_volts;
        let no_load_rad_s =
            ((v - self.no_load_current_a * self.resistance_ohm) / self.ke_v_s_per_rad).max(0.0);
        let omega = speed_ratio * no_load_rad_s;
        ((v - self.ke_v_s_per_rad * omega) / self.resistance_ohm).max(0.0)
    }

    /// The current the pack supplies to the motor's bridge output, A: the motor's current
    /// while the PWM output is on, `duty` × [`Self::motor_current_a`].
    #[must_use]
    pub fn pack_current_a(&self, duty: f64, speed_ratio: f64) -> f64 {
        duty.clamp(0.0, 1.0) * self.motor_current_a(duty, speed_ratio)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fa130_s_constants_and_the_full_duty_voltage() {
        let m = DcMotor::fa130(0.15);
        assert!((m.resistance_ohm - 0.681_818).abs() < 1e-5);
        // (1.5 − 0.2 · 0.6818) V / 732.0 rad/s.
        assert!((m.ke_v_s_per_rad - 1.862_9e-3).abs() < 1e-6);
        // 0.15 m/s at a 28 mm radius through 203.7:1 is 1 091 rad/s (10 420 r/min).
        assert!(
            (m.full_duty_volts - 2.169).abs() < 0.01,
            "{}",
            m.full_duty_volts
        );
    }

    #[test]
    fn free_running_draws_the_no_load_current_and_held_still_the_stall_current() {
        let m = DcMotor::fa130(0.15);
        for duty in [0.3, 0.7, 1.0] {
            assert!(
                (m.motor_current_a(duty, 1.0) - 0.20).abs() < 1e-12,
                "{duty}"
            );
        }
        // A full-duty stall: 2.169 V over 0.682 Ω, about 3.18 A from the pack.
        let stall = m.pack_current_a(1.0, 0.0);
        assert!((stall - m.full_duty_volts / m.resistance_ohm).abs() < 1e-12);
        assert!((stall - 3.18).abs() < 0.01, "{stall}");
        // At 30 % duty held still: 0.3 · (0.3 · V_full / R) from the pack.
        let s30 = m.pack_current_a(0.3, 0.0);
        assert!((s30 - 0.09 * m.full_duty_volts / m.resistance_ohm).abs() < 1e-12);
        // Faster than asked: nothing; no duty: nothing.
        assert_eq!(m.motor_current_a(0.3, 3.0), 0.0);
        assert_eq!(m.pack_current_a(0.0, 0.0), 0.0);
        // Accelerating: between the two.
        let half = m.motor_current_a(1.0, 0.5);
        assert!(half > 0.2 && half < stall);
    }
}
