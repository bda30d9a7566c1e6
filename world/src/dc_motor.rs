//! The drive motors as electrical loads: what one motor draws at a PWM duty, a speed and a
//! load.
//!
//! The robot is a commercial toy with two DC gear motors (paper §2); the world moves it like a
//! Tamiya 203:1 gearbox with 56 mm wheels (docs/design.md §3.5), and every Tamiya twin-motor and double
//! gearbox of that class is built around the Mabuchi FA-130, so the motor is an FA-130. Its
//! published figures give the permanent-magnet DC motor's two constants:
//! - armature resistance R = nominal voltage / stall current;
//! - back-EMF constant Ke = (nominal voltage − no-load current × R) / no-load speed, which in SI
//!   units is also the torque constant Kt (N·m/A).
//!
//! The bridge's output at full duty is the voltage that makes the motor run free at the
//! world's top speed: V_full = Ke · ω_top + I₀ · R (about 2.2 V at 0.15 m/s, inside the
//! FA-130's 1.5–3 V; the TA7291P's reference input sets it). At duty D the motor sees D · V_full
//! on average.
//!
//! The motor's current is set by its torque: Kt · I = Kt · I₀ (its own friction, the no-load
//! current) + J · α (spinning its rotor up or down) + the load its gearbox passes on from the
//! wheel. Two of the three come from the world:
//! - **the rotor**: the world's wheel speed follows the command with the motor's
//!   electromechanical time constant τ = J · R / (Ke · Kt), so with the motor at the world's
//!   wheel speed ω the first two terms are the voltage equation's current (D · V_full − Ke · ω)
//!   / R ([`DcMotor::speed_current_a`]): I₀ at the commanded speed, up to the stall current
//!   from rest, negative (the back-EMF above the drive) while the wheel slows. The motor's
//!   speed is taken as the fraction ρ of its command's speed that the world's wheel turns at
//!   (duty × top speed × the wheel's gain spread), times the motor's own no-load speed at
//!   D · V_full.
//! - **the load**: the longitudinal force F the wheel transmits between the floor and the body
//!   (the world's `wheel_forces`), a torque τ_w = F · r at the wheel. Driving (F along the
//!   direction the motor drives), the motor supplies it through the gearbox's losses:
//!   τ_w / (G · η · Kt) more current. Braking (F against the drive: the floor turns the wheel
//!   the way the motor drives it, as when a robot decelerates), the gearbox passes on
//!   τ_w · η / G and the motor needs that much less, down to nothing: the bridge's output
//!   stage sources current, it does not take it back.
//!
//! So a free wheel at its commanded speed draws I₀ at any duty; a wheel slipping at the
//! traction limit against a wall (F = μ · m·g/2 = 1.47 N, at 28 mm through 203.7:1 at an
//! efficiency η of 0.656) draws I₀ + 0.165 A = 0.365 A, and its motor turns at
//! (D · V_full − I · R) / (D · V_full − I₀ · R) = 94 % of its free speed at full duty
//! ([`DcMotor::loaded_speed_fraction`]), so the world's wheel speed (the free speed) is nearly
//! the motor's. What the drive voltage allows bounds it all: a motor that turns with its drive
//! can be slowed by its load to a standstill, no further (the floor's friction cannot turn the
//! wheel backwards), so the current is at most the stall current D · V_full / R; a motor turned
//! against its drive (a reversal) already draws more than that and is not bounded by it.
//! [`MotorCurrent::capped`] says when the bound cut the current.
//!
//! With the PWM, the pack supplies the motor's current only while the output is on: D · I.

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
/// instructions; docs/design.md §3.5's "203:1").
pub const GEAR_RATIO: f64 = 203.7;
/// Wheel diameter, 56 mm (docs/design.md §3.5: Tamiya 56 mm wheels).
pub const WHEEL_DIAMETER_M: f64 = 0.056;
/// Wheel radius, 28 mm: half of [`WHEEL_DIAMETER_M`].
pub const WHEEL_RADIUS_M: f64 = WHEEL_DIAMETER_M / 2.0;
/// Efficiency of one reduction stage of the gearbox, 0.9: an assumption (a spur stage of
/// moulded plastic gears, lubricated, at light load; machined steel spur gears reach 0.97–0.99,
/// small plastic ones lose more to friction and backlash). Neither Tamiya nor the paper gives a
/// figure.
pub const GEAR_STAGE_EFFICIENCY: f64 = 0.9;
/// Reduction stages between the motor and the wheel, four: an assumption (203.7:1 at the
/// 3–4:1 a stage of small plastic spur gears gives, 203.7^(1/4) = 3.8).
pub const GEAR_STAGES: i32 = 4;
/// The gearbox's efficiency, 0.9⁴ = 0.6561 ([`GEAR_STAGE_EFFICIENCY`] over [`GEAR_STAGES`]): an
/// assumption. It scales only the current a loaded wheel adds (a robot pushing with its
/// traction draws I₀ + 0.108 A / η a motor); `docs/energy-and-stack.md` gives the battery
/// figures for η from 0.5 to 0.8.
pub const GEARBOX_EFFICIENCY: f64 = 0.6561;

/// One drive motor's electrical model (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DcMotor {
    /// Armature resistance, Ω.
    pub resistance_ohm: f64,
    /// Back-EMF constant, V per rad/s of the motor shaft; in SI units also the torque
    /// constant, N·m/A.
    pub ke_v_s_per_rad: f64,
    /// No-load current, A (the motor's own friction).
    pub no_load_current_a: f64,
    /// The bridge's mean output at full duty, V.
    pub full_duty_volts: f64,
    /// Gear ratio, motor turns per wheel turn.
    pub gear_ratio: f64,
    /// Wheel radius, m.
    pub wheel_radius_m: f64,
    /// Efficiency of the gearbox, 0–1.
    pub gearbox_efficiency: f64,
}

/// A motor's current in a sub-step and whether the drive voltage's bound cut it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorCurrent {
    /// The motor's current, A (≥ 0).
    pub motor_a: f64,
    /// Whether the torque asked for needed more than the drive voltage allows (the stall
    /// current of a motor turning with its drive) and the current was cut to it.
    pub capped: bool,
}

impl DcMotor {
    /// The FA-130 behind the gearbox ([`GEARBOX_EFFICIENCY`]), its full-duty voltage set for
    /// `top_speed_m_per_s` at the wheel.
    #[must_use]
    pub fn fa130(top_speed_m_per_s: f64) -> DcMotor {
        let r = FA130_NOMINAL_VOLTS / FA130_STALL_CURRENT_A;
        let no_load_rad_s = FA130_NO_LOAD_RPM * std::f64::consts::TAU / 60.0;
        let ke = (FA130_NOMINAL_VOLTS - FA130_NO_LOAD_CURRENT_A * r) / no_load_rad_s;
        let top_rad_s = top_speed_m_per_s / WHEEL_RADIUS_M * GEAR_RATIO;
        DcMotor {
            resistance_ohm: r,
            ke_v_s_per_rad: ke,
            no_load_current_a: FA130_NO_LOAD_CURRENT_A,
            full_duty_volts: ke * top_rad_s + FA130_NO_LOAD_CURRENT_A * r,
            gear_ratio: GEAR_RATIO,
            wheel_radius_m: WHEEL_RADIUS_M,
            gearbox_efficiency: GEARBOX_EFFICIENCY,
        }
    }

    /// The same motor behind a gearbox of efficiency `eta` (0–1].
    #[must_use]
    pub fn with_gearbox_efficiency(self, eta: f64) -> DcMotor {
        DcMotor {
            gearbox_efficiency: eta,
            ..self
        }
    }

    /// The motor's speed, rad/s, at PWM duty `duty` with its wheel at `speed_ratio` of the
    /// speed its command asks for: that fraction of its no-load speed at `duty` · V_full.
    fn speed_rad_s(&self, duty: f64, speed_ratio: f64) -> f64 {
        let v = duty * self.full_duty_volts;
        let no_load_rad_s =
            ((v - self.no_load_current_a * self.resistance_ohm) / self.ke_v_s_per_rad).max(0.0);
        speed_ratio * no_load_rad_s
    }

    /// The voltage equation's current, A, at PWM duty `duty` (0–1) with the wheel at
    /// `speed_ratio` of the speed its command asks for (1 at that speed, 0 still):
    /// (D · V_full − Ke · ω) / R, signed (negative when the back-EMF exceeds the drive). With
    /// the world's wheel speed, the current that holds the motor's friction and spins its rotor
    /// along the world's lag.
    #[must_use]
    #[inline]
    pub fn speed_current_a(&self, duty: f64, speed_ratio: f64) -> f64 {
        let duty = duty.clamp(0.0, 1.0);
        if duty == 0.0 || !speed_ratio.is_finite() {
            return 0.0;
        }
        let v = duty * self.full_duty_volts;
        (v - self.ke_v_s_per_rad * self.speed_rad_s(duty, speed_ratio)) / self.resistance_ohm
    }

    /// The extra current, A, the wheel's load asks of the motor: a longitudinal force
    /// `drive_force_n` between the floor and the body, positive along the direction the motor
    /// drives. Driving: τ_w / (G · η · Kt); braking (negative): −|τ_w| · η / (G · Kt).
    #[must_use]
    #[inline]
    pub fn load_current_a(&self, drive_force_n: f64) -> f64 {
        let tau_wheel = drive_force_n * self.wheel_radius_m;
        let per_motor_torque = 1.0 / (self.gear_ratio * self.ke_v_s_per_rad);
        if tau_wheel >= 0.0 {
            tau_wheel * per_motor_torque / self.gearbox_efficiency
        } else {
            tau_wheel * per_motor_torque * self.gearbox_efficiency
        }
    }

    /// The motor's current at PWM duty `duty` (0–1), with the wheel at `speed_ratio` of the
    /// speed its command asks for and carrying `drive_force_n` (N, positive along the direction
    /// the motor drives): [`Self::speed_current_a`] plus [`Self::load_current_a`], bounded by
    /// the stall current D · V_full / R while the motor turns with its drive, and never below
    /// zero (see the module docs).
    #[must_use]
    #[inline]
    pub fn current(&self, duty: f64, speed_ratio: f64, drive_force_n: f64) -> MotorCurrent {
        let duty = duty.clamp(0.0, 1.0);
        if duty == 0.0 || !speed_ratio.is_finite() || !drive_force_n.is_finite() {
            return MotorCurrent {
                motor_a: 0.0,
                capped: false,
            };
        }
        let demand = self.speed_current_a(duty, speed_ratio) + self.load_current_a(drive_force_n);
        let cap = if speed_ratio >= 0.0 {
            duty * self.full_duty_volts / self.resistance_ohm
        } else {
            f64::INFINITY
        };
        MotorCurrent {
            motor_a: demand.min(cap).max(0.0),
            capped: demand > cap,
        }
    }

    /// The current the pack supplies to the motor's bridge output, A: the motor's current
    /// while the PWM output is on, `duty` × [`Self::current`].
    #[must_use]
    pub fn pack_current_a(&self, duty: f64, speed_ratio: f64, drive_force_n: f64) -> f64 {
        duty.clamp(0.0, 1.0) * self.current(duty, speed_ratio, drive_force_n).motor_a
    }

    /// The speed at which the motor turns while it draws `current_a` steadily at PWM duty
    /// `duty`, as a fraction of its no-load speed at that duty: the voltage equation solved
    /// for ω, (D · V_full − I · R) / (D · V_full − I₀ · R). For a wheel slipping at its
    /// traction, how far the motor falls below the free speed the world gives its wheel.
    #[must_use]
    pub fn loaded_speed_fraction(&self, duty: f64, current_a: f64) -> f64 {
        let v = duty.clamp(0.0, 1.0) * self.full_duty_volts;
        (v - current_a * self.resistance_ohm) / (v - self.no_load_current_a * self.resistance_ohm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default traction of one drive wheel, μ_floor · m·g/2 (the world's defaults).
    fn traction_n() -> f64 {
        crate::params::MU_FLOOR * crate::params::MASS_KG * crate::params::GRAVITY_M_PER_S2 / 2.0
    }

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
        assert!(
            (GEARBOX_EFFICIENCY - libm::pow(GEAR_STAGE_EFFICIENCY, f64::from(GEAR_STAGES))).abs()
                < 1e-12,
            "0.9^4"
        );
        assert_eq!(m.gearbox_efficiency, GEARBOX_EFFICIENCY);
    }

    #[test]
    fn free_running_draws_the_no_load_current_at_any_duty() {
        let m = DcMotor::fa130(0.15);
        for duty in [0.3, 0.7, 1.0] {
            let c = m.current(duty, 1.0, 0.0);
            assert!((c.motor_a - 0.20).abs() < 1e-12, "{duty}");
            assert!(!c.capped);
            assert!((m.speed_current_a(duty, 1.0) - 0.20).abs() < 1e-12);
        }
        // No duty: nothing.
        assert_eq!(m.pack_current_a(0.0, 0.0, 1.0), 0.0);
    }

    #[test]
    fn a_wheel_slipping_at_its_traction_draws_the_friction_torque_s_current() {
        let m = DcMotor::fa130(0.15);
        let f = traction_n();
        assert!((f - 1.4710).abs() < 1e-4, "{f}");
        // By hand: 1.4710 N × 0.028 m = 41.19 mN·m at the wheel; through 203.7:1 at 0.6561,
        // 0.3082 mN·m at the motor; over Kt = 1.8629 mN·m/A, 0.1654 A. Plus I₀: 0.3654 A.
        let c = m.current(1.0, 1.0, f);
        assert!((c.motor_a - 0.3654).abs() < 2e-4, "{}", c.motor_a);
        assert!(!c.capped);
        // Not the stall current (3.18 A) the wheel's speed over the ground would suggest.
        assert!(c.motor_a < 0.12 * m.full_duty_volts / m.resistance_ohm);
        // The motor then turns at (2.169 − 0.3654 · 0.6818) / (2.169 − 0.2 · 0.6818) = 94.4 %
        // of its free speed.
        let k = m.loaded_speed_fraction(1.0, c.motor_a);
        assert!((k - 0.944).abs() < 0.002, "{k}");
        // At 30 % duty the same torque, the same current; the pack gives 30 % of it.
        let c30 = m.current(0.3, 1.0, f);
        assert!((c30.motor_a - c.motor_a).abs() < 1e-12 && !c30.capped);
        assert!((m.pack_current_a(0.3, 1.0, f) - 0.3 * c.motor_a).abs() < 1e-12);
        // The gearbox's efficiency scales only the load's share: η 0.5 → 0.2 + 0.2170 A.
        let lossy = m.with_gearbox_efficiency(0.5).current(1.0, 1.0, f).motor_a;
        assert!(
            (lossy - (0.2 + 0.1654 * 0.6561 / 0.5)).abs() < 2e-4,
            "{lossy}"
        );
    }

    #[test]
    fn braking_loads_give_nothing_back() {
        let m = DcMotor::fa130(0.15);
        // The floor pushes against the drive (a decelerating robot): the motor needs less,
        // 0.2 A − 0.3 N × 0.028 m × 0.6561 / (203.7 × 1.8629e-3) = 0.2 − 0.01452 A.
        let c = m.current(1.0, 1.0, -0.3);
        assert!((c.motor_a - (0.2 - 0.014_52)).abs() < 1e-4, "{}", c.motor_a);
        // A wheel faster than its new command (full to 30 %): the back-EMF exceeds the
        // drive, and with a braking load the motor draws nothing.
        assert_eq!(m.current(0.3, 3.0, -0.5).motor_a, 0.0);
        assert!(m.speed_current_a(0.3, 3.0) < 0.0);
    }

    #[test]
    fn spinning_up_and_the_drive_voltage_s_bound() {
        let m = DcMotor::fa130(0.15);
        let stall = m.full_duty_volts / m.resistance_ohm;
        // From rest, the voltage equation: the stall current, 3.18 A at full duty.
        assert!((m.speed_current_a(1.0, 0.0) - stall).abs() < 1e-12);
        assert!((stall - 3.18).abs() < 0.01, "{stall}");
        // Half-way up: between.
        let half = m.current(1.0, 0.5, 0.0).motor_a;
        assert!(half > 0.2 && half < stall);
        // From rest with a load on top: cut to the stall current, and said so.
        let c = m.current(1.0, 0.0, 1.0);
        assert_eq!(c.motor_a, stall);
        assert!(c.capped);
        // At 10 % duty, 0.318 A at stall cannot hold a slipping wheel's 0.365 A: cut.
        let c = m.current(0.1, 1.0, traction_n());
        assert!(c.capped && (c.motor_a - 0.1 * stall).abs() < 1e-12);
        // A reversal (the wheel still turning the other way): more than the stall current,
        // not bounded by it.
        let c = m.current(1.0, -1.0, 0.3);
        assert!(!c.capped && c.motor_a > stall, "{c:?}");
    }
}
