//! How the robot's parts are wired to the H8/3052F (docs/design.md §3.2–3.6).
//!
//! | part | pin | register bit |
//! |---|---|---|
//! | IR sensors front, rear, left, right | AN0, AN1, AN2, AN3 | ADDRA–ADDRD |
//! | bumpers front, rear, left, right (active low) | P2.0–P2.3 | P2DR bits 0–3 |
//! | I²C SDA / SCL (24LC256 at 0x50 and 0x51) | P4.7 / P4.6 | P4DDR/P4DR bits 7/6 |
//! | left motor PWM | TIOCA1 (PA4) | ITU1 in PWM mode |
//! | right motor PWM | TIOCA2 (PA6) | ITU2 in PWM mode |
//! | left motor IN1 / IN2 | PB0 / PB1 | PBDR bits 0/1 |
//! | right motor IN1 / IN2 | PB2 / PB3 | PBDR bits 2/3 |
//! | system tick | — | ITU0 compare match A, vector 24 |
//!
//! PB0–PB3 double as TIOCA3/TIOCB3/TIOCA4/TIOCB4 (and TP8–TP11 of the TPC). They are plain
//! port pins as long as ITU3 and ITU4 leave their outputs off (TIOR IOx = 000, not in PWM or
//! complementary mode — the reset state) and the TPC is not enabled on them (NDERB = 0, the
//! reset state), which holds for the robot's firmware: it uses ITU0–2 only. The H-bridges are
//! Toshiba TA7291P-class (docs/design.md §3.5): IN1/IN2 = H/L forward, L/H reverse, H/H brake, L/L
//! coast; the PWM drives the bridge's reference/enable input.
//!
//! Which port bit each TIOCA output shares, and the I²C lines of the EEPROM bus the chip model
//! carries, are the chip's own pin numbering ([`h8_3052f::periph::ports`]); this module says
//! what the robot connects to them and reads the motor pins as H-bridge inputs
//! ([`motor_pins`]).

use h8_3052f::mcu::Mcu;
use h8_3052f::periph::ports::{PA_TIOCA1, PA_TIOCA2};
use h8_3052f::pins::Board;

/// A/D channel of the front IR sensor: AN0 (result in ADDRA).
pub const AN_IR_FRONT: u8 = 0;
/// A/D channel of the rear IR sensor: AN1 (ADDRB).
pub const AN_IR_REAR: u8 = 1;
/// A/D channel of the left IR sensor: AN2 (ADDRC).
pub const AN_IR_LEFT: u8 = 2;
/// A/D channel of the right IR sensor: AN3 (ADDRD).
pub const AN_IR_RIGHT: u8 = 3;
/// The four IR channels in the order front, rear, left, right.
pub const AN_IR: [u8; 4] = [AN_IR_FRONT, AN_IR_REAR, AN_IR_LEFT, AN_IR_RIGHT];

/// The voltage on A/D input `channel` of a board whose sensor k is wired to `channels[k]` and
/// finds its nearest obstacle at `distance_mm[k]` (`None`: nothing in range); 0 V on an input
/// no sensor is wired to. The distances are finite and non-negative and a board's time only
/// moves forward, so a sample cannot fail; if one did, the pin would read 0 V, never panic.
pub fn sensor_volts(
    sensors: &mut [sensors::IrSensor],
    distance_mm: &[Option<f64>],
    channels: &[u8; 4],
    channel: u8,
    now_states: u64,
) -> f64 {
    let Some(k) = channels.iter().position(|&c| c == channel) else {
        return 0.0;
    };
    match (sensors.get_mut(k), distance_mm.get(k)) {
        (Some(s), Some(&d)) => s.sample(now_states, d).unwrap_or(0.0),
        _ => 0.0,
    }
}

/// Port-2 bit of the front bumper (P2.0, active low; `sensors::port2_pins` order).
pub const P2_BUMPER_FRONT: u8 = 0x01;
/// Port-2 bit of the rear bumper (P2.1).
pub const P2_BUMPER_REAR: u8 = 0x02;
/// Port-2 bit of the left bumper (P2.2).
pub const P2_BUMPER_LEFT: u8 = 0x04;
/// Port-2 bit of the right bumper (P2.3).
pub const P2_BUMPER_RIGHT: u8 = 0x08;
/// All four bumper bits of port 2.
pub const P2_BUMPERS: u8 = 0x0F;

/// ITU channel whose TIOCA drives the left motor's PWM (ITU1, pin TIOCA1 = PA4).
pub const ITU_MOTOR_LEFT: usize = 1;
/// ITU channel whose TIOCA drives the right motor's PWM (ITU2, pin TIOCA2 = PA6).
pub const ITU_MOTOR_RIGHT: usize = 2;
/// ITU channel of the system tick (ITU0, compare match A).
pub const ITU_TICK: usize = 0;
/// Interrupt vector of the system tick: ITU0 IMIA0 (docs/design.md §4.1: 24).
pub const VECTOR_TICK: u8 = 24;

/// Port-B bit of the left H-bridge's IN1 (PB0).
pub const PB_LEFT_IN1: u8 = 0x01;
/// Port-B bit of the left H-bridge's IN2 (PB1).
pub const PB_LEFT_IN2: u8 = 0x02;
/// Port-B bit of the right H-bridge's IN1 (PB2).
pub const PB_RIGHT_IN1: u8 = 0x04;
/// Port-B bit of the right H-bridge's IN2 (PB3).
pub const PB_RIGHT_IN2: u8 = 0x08;

/// A TA7291P's supply current in forward or reverse mode, outputs open: 8.0 mA typical, 13 mA
/// maximum (Toshiba TA7291P data sheet, electrical characteristics, I_CC1 "output off, CW/CCW
/// mode", VCC = 12 V).
pub const BRIDGE_ICC_DRIVE_MA: f64 = 8.0;
/// A TA7291P's supply current in brake mode: 6.5 mA typical, 10 mA maximum (the same table,
/// I_CC3 "output off, brake mode").
pub const BRIDGE_ICC_BRAKE_MA: f64 = 6.5;
/// A TA7291P's supply current in stop (coast) mode: 0 typical, 50 µA maximum (the same table,
/// I_CC2 "output off, stop mode").
pub const BRIDGE_ICC_STOP_MA: f64 = 0.0;
/// A TA7291P's saturation voltage, upper plus lower side, at 1.0 A: 1.3 V + 1.2 V typical (the
/// same table, V_SAT U-3 and L-3). What the bridge can give a motor from a 12 V pack is far
/// above the 2.2 V the FA-130 runs at; the rest of the pack's voltage drops in the bridge.
pub const BRIDGE_SATURATION_1A_V: f64 = 2.5;

impl Bridge {
    /// The bridge's own supply current in this mode, mA ([`BRIDGE_ICC_DRIVE_MA`] and the
    /// others).
    #[must_use]
    pub const fn supply_current_ma(self) -> f64 {
        match self {
            Bridge::Forward | Bridge::Reverse => BRIDGE_ICC_DRIVE_MA,
            Bridge::Brake => BRIDGE_ICC_BRAKE_MA,
            Bridge::Coast => BRIDGE_ICC_STOP_MA,
        }
    }
}

/// What a TA7291P-class H-bridge does with its two logic inputs (docs/design.md §3.5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Bridge {
    /// IN1 = H, IN2 = L: forward.
    Forward,
    /// IN1 = L, IN2 = H: reverse.
    Reverse,
    /// IN1 = H, IN2 = H: brake (both low-side switches on).
    Brake,
    /// IN1 = L, IN2 = L: coast (outputs off).
    Coast,
}

impl Bridge {
    /// The bridge state for logic levels `in1`, `in2` (true = H).
    #[must_use]
    pub const fn from_inputs(in1: bool, in2: bool) -> Bridge {
        match (in1, in2) {
            (true, false) => Bridge::Forward,
            (false, true) => Bridge::Reverse,
            (true, true) => Bridge::Brake,
            (false, false) => Bridge::Coast,
        }
    }
}

/// The PWM output to one motor, synchronised to the MCU clock.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PwmOutput {
    /// The ITU channel counts in PWM mode (TSTR.STRn = 1, TMDR.PWMn = 1, internal clock).
    pub running: bool,
    /// The level of the pin now.
    pub level: bool,
    /// PWM period in states when running (GRA + 1 counts × prescaler with CCLR = GRA), else 0.
    pub period_states: u64,
    /// High time per period in states when running (GRB + 1 counts × prescaler with
    /// CCLR = GRA; 0 or the whole period for a constant output), else 0.
    pub high_states: u64,
}

impl PwmOutput {
    /// The fraction of time the pin is high: `high / period` when running, else 1 or 0 from
    /// the pin's level (a stopped timer holds its output).
    #[must_use]
    pub fn duty(&self) -> f64 {
        if self.running && self.period_states > 0 {
            self.high_states as f64 / self.period_states as f64
        } else if self.level {
            1.0
        } else {
            0.0
        }
    }
}

/// One motor's driver inputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MotorDrive {
    /// The PWM (speed) input.
    pub pwm: PwmOutput,
    /// IN1 level (a port pin that is not an output reads as low: the firmware must drive it).
    pub in1: bool,
    /// IN2 level.
    pub in2: bool,
}

impl MotorDrive {
    /// What the H-bridge does with IN1/IN2.
    #[must_use]
    pub const fn bridge(&self) -> Bridge {
        Bridge::from_inputs(self.in1, self.in2)
    }
}

/// Both motors' driver inputs at one instant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MotorPins {
    /// The left motor (ITU1 TIOCA1, PB0/PB1).
    pub left: MotorDrive,
    /// The right motor (ITU2 TIOCA2, PB2/PB3).
    pub right: MotorDrive,
}

/// Both motors' driver inputs now, read from the chip's pins: the PWM of ITU1/ITU2 on TIOCA1
/// (PA4) and TIOCA2 (PA6), IN1/IN2 on PB0–PB3.
pub fn motor_pins<B: Board>(mcu: &mut Mcu<B>) -> MotorPins {
    let pb = mcu.port_b_pins();
    MotorPins {
        left: motor_drive(mcu, ITU_MOTOR_LEFT, PA_TIOCA1, pb, PB_LEFT_IN1, PB_LEFT_IN2),
        right: motor_drive(
            mcu,
            ITU_MOTOR_RIGHT,
            PA_TIOCA2,
            pb,
            PB_RIGHT_IN1,
            PB_RIGHT_IN2,
        ),
    }
}

/// One H-bridge's inputs: the PWM from ITU channel `ch` (its TIOCA on port-A bit `pa_bit`,
/// which holds the port's latch when the ITU does not drive it) and IN1/IN2 from port B.
fn motor_drive<B: Board>(
    mcu: &mut Mcu<B>,
    ch: usize,
    pa_bit: u8,
    pb: u8,
    in1: u8,
    in2: u8,
) -> MotorDrive {
    let out = mcu.tioca(ch);
    let level = if out.drives {
        out.level
    } else {
        mcu.port_a_pins() & pa_bit != 0
    };
    MotorDrive {
        pwm: PwmOutput {
            running: out.wave.is_some(),
            level,
            period_states: out.wave.map_or(0, |w| w.period_states),
            high_states: out.wave.map_or(0, |w| w.high_states),
        },
        in1: pb & in1 != 0,
        in2: pb & in2 != 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ta7291p_truth_table() {
        assert_eq!(Bridge::from_inputs(true, false), Bridge::Forward);
        assert_eq!(Bridge::from_inputs(false, true), Bridge::Reverse);
        assert_eq!(Bridge::from_inputs(true, true), Bridge::Brake);
        assert_eq!(Bridge::from_inputs(false, false), Bridge::Coast);
    }

    #[test]
    fn duty_of_running_and_stopped_outputs() {
        let run = PwmOutput {
            running: true,
            level: false,
            period_states: 8000,
            high_states: 2000,
        };
        assert!((run.duty() - 0.25).abs() < 1e-12);
        let held_high = PwmOutput {
            running: false,
            level: true,
            period_states: 0,
            high_states: 0,
        };
        assert!((held_high.duty() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn bumper_bits_follow_the_sensors_crate() {
        use sensors::{Bumper, BumperSet, port2_pins};
        assert_eq!(
            !port2_pins(BumperSet::EMPTY.with(Bumper::Front)),
            P2_BUMPER_FRONT
        );
        assert_eq!(
            !port2_pins(BumperSet::EMPTY.with(Bumper::Rear)),
            P2_BUMPER_REAR
        );
        assert_eq!(
            !port2_pins(BumperSet::EMPTY.with(Bumper::Left)),
            P2_BUMPER_LEFT
        );
        assert_eq!(
            !port2_pins(BumperSet::EMPTY.with(Bumper::Right)),
            P2_BUMPER_RIGHT
        );
    }
}
