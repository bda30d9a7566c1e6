//! Motor commands (PWM duty and H-bridge direction) and the first-order wheel-speed lag.

use crate::error::WorldError;

/// The H-bridge mode of one motor, from its two input pins (TA7291P truth table, docs/design.md §3.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// IN1 = H, IN2 = L: drive forward.
    Forward,
    /// IN1 = L, IN2 = H: drive in reverse.
    Reverse,
    /// IN1 = H, IN2 = H: brake (motor terminals shorted).
    Brake,
    /// IN1 = L, IN2 = L: coast (outputs off, motor terminals open).
    Coast,
}

impl Direction {
    /// The mode for the two H-bridge inputs (`true` = H), per the TA7291P truth table:
    /// H/L forward, L/H reverse, H/H brake, L/L coast.
    pub fn from_pins(in1: bool, in2: bool) -> Direction {
        match (in1, in2) {
            (true, false) => Direction::Forward,
            (false, true) => Direction::Reverse,
            (true, true) => Direction::Brake,
            (false, false) => Direction::Coast,
        }
    }

    /// The two H-bridge inputs that select this mode (`true` = H).
    pub fn pins(self) -> (bool, bool) {
        match self {
            Direction::Forward => (true, false),
            Direction::Reverse => (false, true),
            Direction::Brake => (true, true),
            Direction::Coast => (false, false),
        }
    }
}

/// What one wheel's motor is told: PWM duty in [0, 1] and the H-bridge mode.
/// The duty only matters for [`Direction::Forward`] and [`Direction::Reverse`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelCommand {
    /// PWM high time over period, 0..=1.
    pub duty: f64,
    /// H-bridge mode.
    pub direction: Direction,
}

impl WheelCommand {
    /// Forward at the given duty.
    pub fn forward(duty: f64) -> WheelCommand {
        WheelCommand {
            duty,
            direction: Direction::Forward,
        }
    }
    /// Reverse at the given duty.
    pub fn reverse(duty: f64) -> WheelCommand {
        WheelCommand {
            duty,
            direction: Direction::Reverse,
        }
    }
    /// Brake (H/H).
    pub fn brake() -> WheelCommand {
        WheelCommand {
            duty: 0.0,
            direction: Direction::Brake,
        }
    }
    /// Coast (L/L).
    pub fn coast() -> WheelCommand {
        WheelCommand {
            duty: 0.0,
            direction: Direction::Coast,
        }
    }

    /// Checks the duty is a number in [0, 1]; `wheel` names the wheel in the error.
    pub(crate) fn check(&self, wheel: &'static str) -> Result<(), WorldError> {
        if self.duty.is_nan() || !(0.0..=1.0).contains(&self.duty) {
            Err(WorldError::Duty {
                wheel,
                value: self.duty,
            })
        } else {
            Ok(())
        }
    }
}

/// Speed ratio of the slow wheel in the turning behaviours: 0.3 (docs/design.md §3.5).
pub const TURN_SLOW_WHEEL_RATIO: f64 = 0.3;

/// The paper's four primitive behaviours (docs/design.md §3.5) as wheel commands at full duty.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Behaviour {
    /// (+v, +v).
    Forward,
    /// (−v, −v).
    Backward,
    /// (0.3v left, v right).
    TurnLeftForward,
    /// (v left, 0.3v right).
    TurnRightForward,
}

impl Behaviour {
    /// All four, in the order of the network's outputs.
    pub const ALL: [Behaviour; 4] = [
        Behaviour::Forward,
        Behaviour::Backward,
        Behaviour::TurnLeftForward,
        Behaviour::TurnRightForward,
    ];

    /// Left and right wheel commands (duty 1 for v, 0.3 for 0.3v).
    pub fn wheels(self) -> (WheelCommand, WheelCommand) {
        let full = WheelCommand::forward(1.0);
        let slow = WheelCommand::forward(TURN_SLOW_WHEEL_RATIO);
        match self {
            Behaviour::Forward => (full, full),
            Behaviour::Backward => (WheelCommand::reverse(1.0), WheelCommand::reverse(1.0)),
            Behaviour::TurnLeftForward => (slow, full),
            Behaviour::TurnRightForward => (full, slow),
        }
    }
}

/// Which time constant a wheel follows: index into [`LagCoefficients`].
pub(crate) const MODE_DRIVE: u8 = 0;
/// Braking time constant.
pub(crate) const MODE_BRAKE: u8 = 1;
/// Coasting time constant.
pub(crate) const MODE_COAST: u8 = 2;

/// Exact first-order-lag update for one sub-step of length `dt` with time constant `tau`:
/// `v(dt) = target + (v0 − target)·decay` and the mean speed over the sub-step
/// `target + (v0 − target)·mean_factor`, where `decay = exp(−dt/τ)` and
/// `mean_factor = τ/dt · (1 − decay)` (the integral of the exponential, so positions are
/// exact for straight motion whatever the sub-step length).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Lag {
    pub decay: f64,
    pub mean_factor: f64,
}

impl Lag {
    pub(crate) fn new(dt_s: f64, tau_s: f64) -> Lag {
        let x = dt_s / tau_s;
        let decay = libm::exp(-x);
        // (1 − e^−x)/x = −expm1(−x)/x, accurate for small x too; its series below 1e-8
        // (where the next term, x²/6, is below rounding), which also covers x = 0.
        let mean_factor = if x < 1e-8 {
            1.0 - 0.5 * x
        } else {
            -libm::expm1(-x) / x
        };
        Lag { decay, mean_factor }
    }
}

/// The lag coefficients for the three modes at one sub-step length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LagCoefficients {
    pub dt_s: f64,
    pub by_mode: [Lag; 3],
}

impl LagCoefficients {
    pub(crate) fn new(dt_s: f64, drive_tau_s: f64, brake_tau_s: f64, coast_tau_s: f64) -> Self {
        LagCoefficients {
            dt_s,
            by_mode: [
                Lag::new(dt_s, drive_tau_s),
                Lag::new(dt_s, brake_tau_s),
                Lag::new(dt_s, coast_tau_s),
            ],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truth_table_round_trips() {
        for d in [
            Direction::Forward,
            Direction::Reverse,
            Direction::Brake,
            Direction::Coast,
        ] {
            let (a, b) = d.pins();
            assert_eq!(Direction::from_pins(a, b), d);
        }
        assert_eq!(Direction::from_pins(true, false), Direction::Forward);
        assert_eq!(Direction::from_pins(false, true), Direction::Reverse);
        assert_eq!(Direction::from_pins(true, true), Direction::Brake);
        assert_eq!(Direction::from_pins(false, false), Direction::Coast);
    }

    #[test]
    fn duty_checks() {
        assert!(WheelCommand::forward(0.0).check("left").is_ok());
        assert!(WheelCommand::forward(1.0).check("left").is_ok());
        assert!(WheelCommand::forward(1.0 + 1e-12).check("left").is_err());
        assert!(WheelCommand::forward(-0.0001).check("left").is_err());
        assert!(WheelCommand::reverse(f64::NAN).check("right").is_err());
        let e = WheelCommand::reverse(f64::NAN).check("right").unwrap_err();
        assert!(e.to_string().contains("right wheel duty NaN"), "{e}");
    }

    #[test]
    fn lag_coefficients_match_closed_form() {
        let l = Lag::new(0.01, 0.06);
        assert!((l.decay - libm::exp(-1.0f64 / 6.0)).abs() < 1e-15);
        assert!((l.mean_factor - 6.0 * (1.0 - libm::exp(-1.0f64 / 6.0))).abs() < 1e-14);
        // Tiny steps: the mean factor tends to 1 without cancellation.
        let t = Lag::new(1e-12, 0.06);
        assert!((t.mean_factor - 1.0).abs() < 1e-10);
        let z = Lag::new(5e-324, 0.06);
        assert_eq!((z.decay, z.mean_factor), (1.0, 1.0));
        let x: f64 = 1e-8 * 1.000001;
        assert!((Lag::new(x * 0.06, 0.06).mean_factor - (1.0 - 0.5 * x)).abs() < 1e-16);
    }

    #[test]
    fn behaviours_match_spec() {
        let (l, r) = Behaviour::TurnLeftForward.wheels();
        assert_eq!((l.duty, r.duty), (0.3, 1.0));
        let (l, r) = Behaviour::Backward.wheels();
        assert_eq!(
            (l.direction, r.direction),
            (Direction::Reverse, Direction::Reverse)
        );
    }
}
