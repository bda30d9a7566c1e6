//! The rig a controller is measured on: the MCU with four modelled IR sensors whose distances
//! follow a seeded random walk, and the meter that attributes its states to phases.
//!
//! [`super::measure()`] builds an MCU with four modelled IR sensors (`sensors::IrSensor`, datasheet
//! spread and noise, their own seeds) whose true distances follow a seeded random walk between
//! 30 mm and 1 m (so the learner sees rewards, punishments and dead zones, and the readings
//! include the fold-back), and runs the controller on it for `steps` step periods.

use super::config::{FitConfig, FitError};
use super::report::{MemLine, StackLine};
use crate::energy::{Charge, DriveMeter, ElectronicsMeter, FreeWheels};
use crate::seeds::robot_stream;
use h8_3052f::mcu::Mcu;
use h8_3052f::pins::Board;
use h8300h::bus::Bus;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robot_board::board::{RobotBoard, RobotConfig, robot_mcu};
use seeding::Purpose;

/// What the fit's world drives on the robot's board: four IR sensors whose distances the driver
/// sets; bumpers open.
pub struct FitBoard {
    pub(super) sensors: Vec<sensors::IrSensor>,
    pub(super) distance_mm: [f64; 4],
    /// The A/D input of each sensor (the controller's wiring).
    pub(super) channels: [u8; 4],
}

impl Board for FitBoard {
    fn analog_volts(&mut self, channel: u8, now_states: u64) -> f64 {
        let d = self.distance_mm.map(Some);
        robot_board::wiring::sensor_volts(
            &mut self.sensors,
            &d,
            &self.channels,
            channel,
            now_states,
        )
    }

    fn port2_pins(&mut self, _now_states: u64) -> u8 {
        // Pull-ups: no bumper pressed.
        0xFF
    }
}

/// The fit's robot: its MCU (sensors, EEPROMs) and the walk of its sensors' distances.
pub(super) struct Rig {
    pub(super) mcu: Mcu<RobotBoard<FitBoard>>,
    pub(super) walk: ChaCha8Rng,
}

impl Rig {
    pub(super) fn new(cfg: &FitConfig) -> Result<Rig, FitError> {
        let clock_hz = cfg.controller.clock_hz;
        let stream = |k: u64, purpose: Purpose| robot_stream(cfg.seed, 0, 0, k, purpose);
        let mut sensors_v = Vec::with_capacity(4);
        for k in 0..4 {
            let params = sensors::IrParams::datasheet(clock_hz);
            sensors_v.push(
                sensors::IrSensor::new(params, stream(k, Purpose::IrSensor)).map_err(|e| {
                    FitError::Sensor {
                        clock_hz,
                        why: e.to_string(),
                    }
                })?,
            );
        }
        let board = FitBoard {
            sensors: sensors_v,
            distance_mm: [300.0, 500.0, 150.0, 800.0],
            channels: cfg.controller.sensor_channels,
        };
        let mcu = robot_mcu(
            board,
            &RobotConfig {
                clock_hz,
                eeprom_seed: stream(0, Purpose::Eeproms),
            },
        )?;
        Ok(Rig {
            mcu,
            walk: ChaCha8Rng::seed_from_u64(stream(0, Purpose::FitDistances)),
        })
    }

    /// The world moves before each step: each distance takes a bounded random step.
    pub(super) fn move_world(&mut self) {
        for d in &mut self.mcu.board_mut().world.distance_mm {
            let delta: f64 = self.walk.random_range(-60.0..60.0);
            *d = (*d + delta).clamp(30.0, 1000.0);
        }
    }
}

/// One controller's measurement before it becomes a report.
pub(super) struct Measured {
    pub(super) source: String,
    pub(super) boot_states: u64,
    /// (phase, states in each step period).
    pub(super) phases: Vec<(String, Vec<u64>)>,
    pub(super) busy: Vec<u64>,
    pub(super) ram: Vec<MemLine>,
    pub(super) stack_high_water: Option<u32>,
    /// The stack's room and what the firmware left of it (machine code only).
    pub(super) stack: Option<StackLine>,
    /// The charge over the measured step periods.
    pub(super) energy: Option<Metered>,
    /// The first access to each address the chip does not model: (what, in a few words; the
    /// whole line).
    pub(super) unmodelled: Vec<(String, String)>,
}

/// What the charge meter saw over the measured step periods.
pub(super) struct Metered {
    /// The electronics (MCU, A/D converter, sensors, EEPROMs, regulator).
    pub(super) electronics: Charge,
    /// The motors and bridges with the wheels free.
    pub(super) free: Charge,
    /// The motors and bridges pressed against a wall.
    pub(super) held: Charge,
    /// How often the drive voltage's bound cut a motor's current, free.
    pub(super) free_cap: crate::energy::CurrentCap,
    /// The same, pressed against a wall.
    pub(super) held_cap: crate::energy::CurrentCap,
    /// The measured time, s.
    pub(super) seconds: f64,
}

/// The fit's energy meter: the electronics from the MCU's counters, and the motors under the
/// controller's commands twice over, once with the wheels free and once pressed against a wall
/// (the body still, the wheels slipping).
pub(super) struct FitMeter {
    pub(super) electronics: ElectronicsMeter,
    pub(super) free: (DriveMeter, FreeWheels),
    pub(super) held: (DriveMeter, FreeWheels),
    pub(super) start: u64,
}

impl FitMeter {
    pub(super) fn new<W: Board>(mcu: &Mcu<RobotBoard<W>>) -> FitMeter {
        let params = world::WorldParams::with_clock(u64::from(robot_board::board::CLOCK_HZ));
        let top = params.top_speed_m_per_s;
        let wheels = || FreeWheels::new(&params);
        FitMeter {
            electronics: ElectronicsMeter::new(mcu),
            free: (DriveMeter::new(top, [1.0; 2]), wheels()),
            held: (DriveMeter::new(top, [1.0; 2]), wheels()),
            start: mcu.now(),
        }
    }

    /// A step period of `seconds` has run under the motor commands its step set (the motor
    /// pins now, before the next step sets them).
    pub(super) fn period<B: Board>(&mut self, mcu: &mut Mcu<B>, seconds: f64) {
        let pins = robot_board::wiring::motor_pins(mcu);
        let (l, r) = (
            crate::robot::wheel(&pins.left),
            crate::robot::wheel(&pins.right),
        );
        for (meter, wheels, held) in [
            (&mut self.free.0, &mut self.free.1, false),
            (&mut self.held.0, &mut self.held.1, true),
        ] {
            meter.set_commands(l, r);
            wheels.run(meter, seconds, world::params::MAX_SUBSTEP_S, held);
        }
    }

    pub(super) fn finish<W: Board>(
        mut self,
        mcu: &Mcu<RobotBoard<W>>,
        busy_states: u64,
    ) -> Metered {
        Metered {
            electronics: self.electronics.take(mcu, busy_states),
            free: self.free.0.take(),
            held: self.held.0.take(),
            free_cap: self.free.0.cap(),
            held_cap: self.held.0.cap(),
            seconds: (mcu.now() - self.start) as f64 / f64::from(mcu.clock_hz()),
        }
    }
}

impl Measured {
    pub(super) fn phase(&self, name: &str) -> Option<&[u64]> {
        self.phases
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}
