//! One robot: the emulated H8/3052F with its controller, four IR sensors, two EEPROMs (on the
//! MCU's port 4) and, in the world, its body.
//!
//! Every random draw comes from its own stream: the sensors (one each), the EEPROMs, the
//! initial weights and the random-walk control each get a seed from the run's seed, the
//! repeat, the robot and the purpose ([`crate::seeds::robot_stream`], the project's one
//! derivation); adding a robot or a thread changes nobody else's numbers.

use anyhow::{Context, Result};
use emu::board::model::{Controller, ControllerConfig, StepReport};
use emu::board::wiring::{Bridge, MotorDrive};
use emu::chip::mcu::{Board, Mcu, McuConfig};
use emu::core::bus::Bus;
use nn_q15::{Behaviour, InputLayout, Params};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use seeding::Purpose;
use sensors::{BumperSet, IrParams, IrSensor, port2_pins};
use world::{Direction, WheelCommand};

use crate::scenario::Scenario;
use crate::seeds::robot_stream;

/// The robot's hardware outside the chip: what the sensors see and the bumpers feel.
pub struct RobotBoard {
    sensors: [IrSensor; 4],
    /// The true distance each sensor's ray finds (mm), as of the step being run.
    pub distance_mm: [Option<f64>; 4],
    /// The bumpers, as of the latest world sub-step.
    pub bumpers: [bool; 4],
    /// The A/D input each sensor is wired to (the scenario's `sensors.channels`).
    channels: [u8; 4],
}

impl Board for RobotBoard {
    fn analog_volts(&mut self, channel: u8, now_states: u64) -> f64 {
        emu::board::wiring::sensor_volts(
            &mut self.sensors,
            &self.distance_mm,
            &self.channels,
            channel,
            now_states,
        )
    }

    fn port2_pins(&mut self, _now_states: u64) -> u8 {
        let [front, rear, left, right] = self.bumpers;
        port2_pins(BumperSet::from_flags(front, rear, left, right))
    }
}

/// Which run a robot belongs to (SPEC §5: learning and the two controls).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Condition {
    /// The paper's learning run.
    Learning,
    /// Learning off: η = 0, the initial weights frozen.
    LearningOff,
    /// A random walk: uniformly random behaviours.
    RandomWalk,
}

impl Condition {
    /// Every condition, in the order runs, tables and figures list them.
    pub const ALL: [Condition; 3] = [
        Condition::Learning,
        Condition::LearningOff,
        Condition::RandomWalk,
    ];

    /// The name used in files.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Condition::Learning => "learning",
            Condition::LearningOff => "learning-off",
            Condition::RandomWalk => "random-walk",
        }
    }
}

/// One robot.
pub struct Robot {
    /// The MCU with its board.
    pub mcu: Mcu<RobotBoard>,
    /// The controller running on it.
    pub controller: Controller,
    walk: Option<ChaCha8Rng>,
    behaviours: usize,
}

/// The controller configuration a scenario asks for.
///
/// # Errors
/// Values the learner refuses (η, T, history).
pub fn controller_config(s: &Scenario, weight_seed: u64) -> Result<ControllerConfig> {
    Ok(ControllerConfig {
        clock_hz: s.timing.clock_hz,
        behaviours: s.learner.behaviours,
        layout: InputLayout::new(s.learner.history, s.learner.bias).context("learner.history")?,
        params: Params::new(s.eta_q15(), s.learner.threshold).context("learner.eta")?,
        save_every_steps: s.learner.save_every,
        step_period_s: s.timing.step_period_s,
        weight_seed,
        sensor_channels: s.sensors.channels,
        fast_forward: true,
    })
}

impl Robot {
    /// Robot `index` of `repeat` under `condition`, booted.
    ///
    /// # Errors
    /// A configuration the controller or the sensors refuse.
    pub fn new(s: &Scenario, condition: Condition, repeat: u32, index: u32) -> Result<Self> {
        let stream = |k: u64, purpose: Purpose| robot_stream(s.seed, repeat, index, k, purpose);
        let ir = IrParams {
            clock_hz: s.timing.clock_hz,
            noise_sigma_volts: s.sensors.noise_sigma_v,
            spike_probability: s.sensors.spike_probability,
            ..if s.sensors.spread {
                IrParams::default()
            } else {
                IrParams {
                    clock_hz: s.timing.clock_hz,
                    ..IrParams::ideal()
                }
            }
        };
        let mut sensors_v = Vec::with_capacity(4);
        for k in 0..4 {
            sensors_v
                .push(IrSensor::new(ir.clone(), stream(k, Purpose::IrSensor)).context("sensors")?);
        }
        let sensors: [IrSensor; 4] = sensors_v
            .try_into()
            .map_err(|_| anyhow::anyhow!("four sensors"))?;
        let board = RobotBoard {
            sensors,
            distance_mm: [None; 4],
            bumpers: [false; 4],
            channels: s.sensors.channels,
        };
        let mut mcu = Mcu::new(
            McuConfig {
                clock_hz: s.timing.clock_hz,
                eeprom_seed: stream(0, Purpose::Eeproms),
            },
            board,
        )
        .context("timing.clock_hz")?;
        let mut cfg = controller_config(s, stream(0, Purpose::Weights))?;
        if condition != Condition::Learning {
            cfg.params = Params::new(0, s.learner.threshold).context("learner.threshold")?;
        }
        let mut controller = Controller::new(cfg)?;
        controller.boot(&mut mcu)?;
        let walk = (condition == Condition::RandomWalk)
            .then(|| ChaCha8Rng::seed_from_u64(stream(0, Purpose::RandomWalk)));
        Ok(Self {
            mcu,
            controller,
            walk,
            behaviours: s.learner.behaviours,
        })
    }

    /// Sleeps until the next step is due; returns the MCU clock then (states).
    ///
    /// # Errors
    /// The tick did not come (cannot happen with this controller).
    pub fn sleep(&mut self) -> Result<u64> {
        self.controller.sleep_until_step(&mut self.mcu)?;
        Ok(self.mcu.now())
    }

    /// Runs the step with the distances the world's rays found.
    ///
    /// # Errors
    /// A save that failed on the bus.
    pub fn step(&mut self, distance_mm: [Option<f64>; 4]) -> Result<StepReport> {
        self.mcu.board_mut().distance_mm = distance_mm;
        let forced = self
            .walk
            .as_mut()
            .map(|rng| Behaviour::ALL[rng.random_range(0..self.behaviours)]);
        Ok(self.controller.step_with(&mut self.mcu, forced)?)
    }

    /// The wheel commands the motor pins give now.
    pub fn wheels(&mut self) -> (WheelCommand, WheelCommand) {
        let pins = emu::board::wiring::motor_pins(&mut self.mcu);
        (wheel(&pins.left), wheel(&pins.right))
    }
}

/// A motor's driver inputs as a wheel command: the PWM duty and the H-bridge mode.
#[must_use]
pub fn wheel(m: &MotorDrive) -> WheelCommand {
    WheelCommand {
        duty: m.pwm.duty().clamp(0.0, 1.0),
        direction: match m.bridge() {
            Bridge::Forward => Direction::Forward,
            Bridge::Reverse => Direction::Reverse,
            Bridge::Brake => Direction::Brake,
            Bridge::Coast => Direction::Coast,
        },
    }
}
