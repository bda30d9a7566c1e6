//! One robot: the emulated H8/3052F on the robot's board (its two EEPROMs on the MCU's port 4,
//! `robot_board::board`) with its controller, four IR sensors and, in the world, its body.
//!
//! Every random draw comes from its own stream: the sensors (one each), the EEPROMs, the
//! initial weights and the random-walk control each get a seed from the run's seed, the
//! repeat, the robot and the purpose ([`crate::seeds::robot_stream`], the project's one
//! derivation); adding a robot or a thread changes nobody else's numbers.

use std::sync::Arc;

use anyhow::{Context, Result};
use h8_3052f::gdb::Debugger;
use h8_3052f::mcu::Mcu;
use h8_3052f::pins::Board;
use h8_3052f::trace::CodeNames;
use h8_3052f::vcd::{VcdInfo, VcdStream};
use h8300h::bus::Bus;
use nn_q15::{Behaviour, InputLayout, Params};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robot_board::board::{RobotBoard, RobotConfig, robot_mcu};
use robot_board::firmware::{
    ConfigBlock, ConfigStatus, FLAG_RANDOM_WALK, Firmware, FirmwareController,
};
use robot_board::model::{Controller, ControllerConfig};
use robot_board::wiring::{Bridge, MotorDrive};
use seeding::Purpose;
use sensors::{BumperSet, IrParams, IrSensor, port2_pins};
use world::{Direction, WheelCommand};

use crate::scenario::Scenario;

use crate::seeds::robot_stream;

/// The robot's hardware that the world drives: what the sensors see and the bumpers feel (the
/// analog inputs and port 2; the board's EEPROMs are [`RobotBoard`]'s own).
pub struct Senses {
    sensors: [IrSensor; 4],
    /// The true distance each sensor's ray finds (mm), as of the step being run.
    pub distance_mm: [Option<f64>; 4],
    /// The bumpers (front, rear, left, right; `true` = pressed) as the world's latest sub-step
    /// before the step's sensing left them; port 2 shows them active low.
    pub bumpers: [bool; 4],
    /// The A/D input each sensor is wired to (the scenario's `sensors.channels`).
    channels: [u8; 4],
}

impl Board for Senses {
    fn analog_volts(&mut self, channel: u8, now_states: u64) -> f64 {
        robot_board::wiring::sensor_volts(
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

/// Which run a robot belongs to (docs/design.md §5: learning and the two controls).
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

/// What runs on a robot's MCU.
pub enum Brain {
    /// The Rust model of the controller.
    Model(Box<Controller>),
    /// Machine code on the H8/300H core: the robot firmware or a user's image.
    Firmware(Box<FirmwareController>),
}

/// What one step gave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepResult {
    /// D(t), the summed proximities the robot read (du).
    pub d: i16,
    /// Whether an EEPROM record was written in the step.
    pub saved: bool,
}

/// One robot.
pub struct Robot {
    /// The MCU on its board.
    pub mcu: Mcu<RobotBoard<Senses>>,
    /// The controller running on it.
    pub brain: Brain,
    walk: Option<ChaCha8Rng>,
    behaviours: usize,
    /// Records (commit-page writes) counted so far, for the firmware's saves.
    records: u64,
    /// Busy states of the MCU since the last step began.
    busy_states: u64,
    /// Where the firmware reports what it made of its configuration block (`cfg_status`),
    /// when it got one and has the symbol; checked once it has booted.
    cfg_status: Option<u32>,
    /// A pin trace under way ends when the next step's sensing begins.
    trace_ends_at_sensing: bool,
    /// The pin trace under way, written to its VCD file step by step.
    vcd: Option<VcdStream<'static>>,
    /// A pin trace that ended, not yet taken ([`Robot::take_pin_trace`]): whether its file
    /// was written.
    finished_trace: Option<std::io::Result<()>>,
    /// Where a firmware robot keeps the pointer to its weights (the symbol `net_w`), when its
    /// image has one.
    net_w: Option<u32>,
    /// How many weights the learner has (N × M).
    weights_len: usize,
    /// The charge meter of the electronics (everything but the motors and their bridges).
    electronics: crate::energy::ElectronicsMeter,
    /// The electronics' charge over the latest step ([`Robot::step_charge`]).
    step_charge: crate::energy::Charge,
}

/// Ends the MCU's pin trace and writes the rest of it (and of the phases) into `vcd`.
fn finish_stream(
    mcu: &mut Mcu<RobotBoard<Senses>>,
    c: &mut FirmwareController,
    vcd: Option<VcdStream<'static>>,
) -> Option<std::io::Result<()>> {
    let mut v = vcd?;
    let drained = h8_3052f::run::drain_into(&mut v, mcu, c.phases_mut());
    let rest = mcu.finish_trace()?;
    let phases = c.take_phases();
    Some(drained.and_then(|()| v.finish(&rest.changes, &phases, rest.end)))
}

/// The images a swarm's firmware robots run, loaded once.
#[derive(Clone, Debug)]
pub struct Images {
    /// The robot firmware.
    pub robot: Firmware,
    /// The user's image (`controller.image`) and the robots that run it (None: every one).
    pub user: Option<(Firmware, Option<Vec<usize>>)>,
}

impl Images {
    /// The images a scenario asks for (none for model robots).
    ///
    /// # Errors
    /// An image or symbol file that cannot be read or parsed, naming it.
    pub fn load(s: &Scenario) -> Result<Option<Images>> {
        if s.controller.kind == crate::scenario::ControllerKind::Model {
            return Ok(None);
        }
        let robot = Firmware::robot().context("the built-in robot firmware")?;
        let user = match &s.controller.image {
            None => None,
            Some(image) => {
                let image = std::path::Path::new(image);
                let symbols = s
                    .controller
                    .symbols
                    .as_ref()
                    .map(std::path::PathBuf::from)
                    .or_else(|| {
                        let p = image.with_extension("sym");
                        p.exists().then_some(p)
                    });
                let fw = match symbols {
                    Some(sym) => Firmware::load(image, &sym),
                    None => Firmware::load_without_symbols(image),
                }
                .with_context(|| format!("`controller.image` = {}", image.display()))?;
                Some((fw, s.controller.robots.clone()))
            }
        };
        Ok(Some(Images { robot, user }))
    }

    /// The image robot `index` runs.
    #[must_use]
    pub fn for_robot(&self, index: usize) -> &Firmware {
        match &self.user {
            Some((fw, None)) => fw,
            Some((fw, Some(robots))) if robots.contains(&index) => fw,
            _ => &self.robot,
        }
    }
}

/// The user's image when it has no configuration block (so the scenario cannot configure
/// it); an error when the scenario's controls need it configured.
///
/// The controls differ from learning only through the configuration block: learning off is
/// η = 0 written into it, the random walk a flag in it. An image without one (a `.mot`
/// without its `.sym`, or a program of the user's own) would run the same program in all
/// three conditions and the claims would compare a run with itself, so such a run is refused;
/// with the controls off it runs, warned about and marked in summary.json.
///
/// # Errors
/// An image without a configuration block and a control condition on.
pub fn unconfigured_image(s: &Scenario, images: Option<&Images>) -> Result<Option<String>> {
    let Some((fw, _)) = images.and_then(|i| i.user.as_ref()) else {
        return Ok(None);
    };
    if fw.has_config_block() {
        return Ok(None);
    }
    let image = s.controller.image.clone().unwrap_or_default();
    if s.controls.learning_off || s.controls.random_walk {
        anyhow::bail!(
            "`controller.image` = {image}: the image has no configuration block (no symbol table names `config_block` at H'000400: give IMAGE.sym beside the image, or controller.symbols), so the controls cannot reach it: learning off (eta = 0) and the random walk would run the same program as learning. Give the image's symbol table, or turn the controls off (controls.learning_off = false, controls.random_walk = false) to run the image as it is"
        );
    }
    Ok(Some(image))
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
    /// Robot `index` of `repeat` under `condition`, booted (the model) or reset (firmware:
    /// it boots on its way to its first step).
    ///
    /// # Errors
    /// A configuration the controller or the sensors refuse.
    pub fn new(
        s: &Scenario,
        condition: Condition,
        repeat: u32,
        index: u32,
        images: Option<&Images>,
    ) -> Result<Self> {
        let stream = |k: u64, purpose: Purpose| robot_stream(s.seed, repeat, index, k, purpose);
        let clock_hz = s.timing.clock_hz;
        let ir = IrParams {
            noise_sigma_volts: s.sensors.noise_sigma_v,
            spike_probability: s.sensors.spike_probability,
            ..if s.sensors.spread {
                IrParams::datasheet(clock_hz)
            } else {
                IrParams::ideal(clock_hz)
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
        let senses = Senses {
            sensors,
            distance_mm: [None; 4],
            bumpers: [false; 4],
            channels: s.sensors.channels,
        };
        let mut mcu = robot_mcu(
            senses,
            &RobotConfig {
                clock_hz: s.timing.clock_hz,
                eeprom_seed: stream(0, Purpose::Eeproms),
            },
        )
        .context("timing.clock_hz")?;
        let electronics = crate::energy::ElectronicsMeter::new(&mcu);
        let mut cfg = controller_config(s, stream(0, Purpose::Weights))?;
        let weights_len = cfg.n_inputs() * cfg.behaviours;
        if condition != Condition::Learning {
            cfg.params = Params::new(0, s.learner.threshold).context("learner.threshold")?;
        }
        let mut cfg_status = None;
        let mut net_w = None;
        let (brain, walk) = match images {
            None => {
                let mut controller = Controller::new(cfg)?;
                controller.boot(&mut mcu)?;
                let walk = (condition == Condition::RandomWalk)
                    .then(|| ChaCha8Rng::seed_from_u64(stream(0, Purpose::RandomWalk)));
                (Brain::Model(Box::new(controller)), walk)
            }
            Some(images) => {
                let fw = images.for_robot(index as usize);
                // The random walk is the firmware's own: it draws the behaviour with its
                // xorshift32 (seeded from the weight seed) and obeys it.
                let mut block = ConfigBlock::from_controller(&cfg)?;
                if condition == Condition::RandomWalk {
                    block.flags |= FLAG_RANDOM_WALK;
                }
                let block = fw.has_config_block().then_some(block);
                cfg_status = block.and(fw.symbols.addr("cfg_status"));
                net_w = block.and(fw.symbols.addr("net_w"));
                let controller = FirmwareController::start(fw, &mut mcu, block.as_ref())
                    .with_context(|| format!("robot {index}: {}", fw.name))?;
                (Brain::Firmware(Box::new(controller)), None)
            }
        };
        let mut robot = Self {
            mcu,
            brain,
            walk,
            behaviours: s.learner.behaviours,
            records: 0,
            busy_states: 0,
            cfg_status,
            trace_ends_at_sensing: false,
            vcd: None,
            finished_trace: None,
            net_w,
            weights_len,
            electronics,
            step_charge: crate::energy::Charge::default(),
        };
        robot.records = robot.records_written();
        Ok(robot)
    }

    /// EEPROM records written so far: writes of the record slot's commit page (page 0) on
    /// either chip (docs/design.md §3.6's A/B records).
    fn records_written(&self) -> u64 {
        self.mcu
            .board()
            .eeproms()
            .devices()
            .iter()
            .map(|d| u64::from(d.write_counts().first().copied().unwrap_or(0)))
            .sum()
    }

    /// Sleeps until the next step is due; returns the instant its sensing begins (states: the
    /// write that starts the A/D converter). A firmware robot runs until it starts its A/D
    /// conversion (booting first when it has just been reset); the model's instant is where
    /// its transcription of the firmware makes that write.
    ///
    /// # Errors
    /// The tick did not come (the model); the firmware stopped, halted, or has not started a
    /// step within the watchdog's time (naming the PC); a configuration block the firmware
    /// rejected.
    pub fn sleep(&mut self) -> Result<u64> {
        match &mut self.brain {
            Brain::Model(c) => {
                let r = c.sleep_until_step(&mut self.mcu)?;
                self.busy_states += r.busy_states;
                // The model's step begins sensing this much later (its ADST write), where a
                // firmware robot's run stops.
                return Ok(self.mcu.now() + robot_board::model::SENSING_OFFSET_STATES);
            }
            Brain::Firmware(c) => {
                c.run_to_sensing(&mut self.mcu)?;
                self.busy_states += c.take_busy();
                // The trace's step goes to its file; it is never held longer.
                if let Some(v) = self.vcd.as_mut()
                    && let Err(e) = h8_3052f::run::drain_into(v, &mut self.mcu, c.phases_mut())
                {
                    self.vcd = None;
                    self.finished_trace = Some(Err(e));
                    self.mcu.finish_trace();
                    c.take_phases();
                }
                if std::mem::take(&mut self.trace_ends_at_sensing) {
                    self.finished_trace = finish_stream(&mut self.mcu, c, self.vcd.take())
                        .or(self.finished_trace.take());
                }
                // Booted: a configuration block the firmware rejected is an error.
                if let Some(addr) = self.cfg_status.take()
                    && let ConfigStatus::Rejected { field, code } =
                        ConfigStatus::from_code(self.mcu.peek(addr))
                {
                    anyhow::bail!(
                        "the firmware rejected its configuration block: {field} (cfg_status 0x{code:02X})"
                    );
                }
            }
        }
        Ok(self.mcu.now())
    }

    /// Starts a pin trace of a firmware robot's MCU now, with the phase signal named by
    /// `names` (the image's symbols): it runs until [`Robot::end_pin_trace_at_sensing`] ends
    /// it at the start of a step, or [`Robot::finish_pin_trace`] now. Tracing changes nothing
    /// the robot does.
    ///
    /// # Errors
    /// A robot whose controller is the model (it has no firmware whose pins could be traced).
    pub fn start_pin_trace(
        &mut self,
        names: Arc<dyn CodeNames + Send + Sync>,
        out: Box<dyn std::io::Write + Send>,
        info: &VcdInfo,
    ) -> Result<()> {
        let Brain::Firmware(c) = &mut self.brain else {
            anyhow::bail!(
                "its controller is the Rust model: only firmware robots have pins to trace"
            );
        };
        self.mcu.start_trace(c.cpu().sleeping());
        let now = self.mcu.now();
        c.record_phases(names, now);
        let phase = c
            .phases_mut()
            .and_then(|p| p.drain_before(now + 1).pop())
            .map_or_else(|| h8_3052f::trace::UNNAMED_PHASE.to_string(), |(_, n)| n);
        let (start, initial) = self
            .mcu
            .trace_beginning()
            .unwrap_or((0, [false; h8_3052f::trace::SIGNAL_COUNT]));
        self.vcd = Some(VcdStream::start(
            out,
            self.mcu.clock_hz(),
            start,
            initial,
            Some(&phase),
            info,
        )?);
        self.trace_ends_at_sensing = false;
        Ok(())
    }

    /// Ends the pin trace under way when the next step's sensing begins (the write that starts
    /// the A/D converter), so that the last traced step's behaviour shows to its end; take it
    /// with [`Robot::take_pin_trace`] after that step.
    pub fn end_pin_trace_at_sensing(&mut self) {
        self.trace_ends_at_sensing = self.mcu.tracing();
    }

    /// The pin trace that ended at a step's sensing, if one did and was not taken yet:
    /// whether its VCD file was written whole.
    pub fn take_pin_trace(&mut self) -> Option<std::io::Result<()>> {
        self.finished_trace.take()
    }

    /// Ends the pin trace under way now and finishes its file (`None` when none is).
    pub fn finish_pin_trace(&mut self) -> Option<std::io::Result<()>> {
        self.trace_ends_at_sensing = false;
        match &mut self.brain {
            Brain::Firmware(c) => finish_stream(&mut self.mcu, c, self.vcd.take()),
            Brain::Model(_) => None,
        }
    }

    /// Puts a firmware robot under a GDB client's control (see
    /// [`FirmwareController::attach`]): the swarm waits while the client has it stopped.
    ///
    /// # Errors
    /// A robot whose controller is the model.
    pub fn attach_debugger(&mut self, debugger: Debugger) -> Result<()> {
        let Brain::Firmware(c) = &mut self.brain else {
            anyhow::bail!("its controller is the Rust model: only firmware robots can be debugged");
        };
        c.attach(debugger);
        Ok(())
    }

    /// Ends a GDB session on this robot, if one is attached (the client is told the program
    /// ended).
    pub fn detach_debugger(&mut self) {
        if let Brain::Firmware(c) = &mut self.brain {
            c.detach();
        }
    }

    /// Sets the bumper switches the board shows on port 2 (front, rear, left, right; `true` =
    /// pressed), as they stand for the coming step.
    pub fn set_bumpers(&mut self, bumpers: [bool; 4]) {
        self.mcu.board_mut().world.bumpers = bumpers;
    }

    /// Runs the step with the distances the world's rays found.
    ///
    /// # Errors
    /// A save that failed on the bus (the model); the firmware stopped, halted, or did not go
    /// back to sleep within the watchdog's time.
    pub fn step(&mut self, distance_mm: [Option<f64>; 4]) -> Result<StepResult> {
        let r = self.run_step(distance_mm)?;
        // The electronics since the previous step's work ended: its busy states are those
        // the step's sleep and work counted.
        self.step_charge = self.electronics.take(&self.mcu, self.busy_states);
        Ok(r)
    }

    /// The charge the electronics (the MCU, its A/D converter, the IR sensors, the EEPROMs,
    /// the regulator) drew from the end of the previous step's work to the end of the latest
    /// one's ([`crate::energy`]).
    #[must_use]
    pub fn step_charge(&self) -> crate::energy::Charge {
        self.step_charge
    }

    /// [`Robot::step`] without the charge meter.
    fn run_step(&mut self, distance_mm: [Option<f64>; 4]) -> Result<StepResult> {
        self.mcu.board_mut().world.distance_mm = distance_mm;
        match &mut self.brain {
            Brain::Model(c) => {
                let forced = self
                    .walk
                    .as_mut()
                    .map(|rng| Behaviour::ALL[rng.random_range(0..self.behaviours)]);
                let t0 = self.mcu.now();
                let r = c.step_with(&mut self.mcu, forced)?;
                self.busy_states += self.mcu.now() - t0;
                Ok(StepResult {
                    d: r.d,
                    saved: r.saved.is_some(),
                })
            }
            Brain::Firmware(c) => {
                c.run_to_sleep(&mut self.mcu)?;
                self.busy_states += c.take_busy();
                let records = self.records_written();
                let saved = records != self.records;
                self.records = records;
                Ok(StepResult {
                    d: self.sensed_d(),
                    saved,
                })
            }
        }
    }

    /// D as the firmware computes it from the A/D codes it read: the du table of the upper
    /// byte of each sensor's result register.
    fn sensed_d(&self) -> i16 {
        self.readings_du().iter().map(|&p| i16::from(p)).sum()
    }

    /// The four readings of the latest step (front, rear, left, right) in du, as the
    /// controller made them: the du table of the upper byte of each sensor's A/D result.
    #[must_use]
    pub fn readings_du(&self) -> [u8; 4] {
        self.mcu.board().world.channels.map(|ch| {
            let code8 = (self.mcu.adc().data(usize::from(ch & 3)) >> 8) as usize;
            sensors::DU_TABLE[code8]
        })
    }

    /// The learner's weights (M rows of N, Q15 bits): the model's own, or read from a firmware
    /// robot's RAM through its `net_w` symbol; none for an image without it.
    #[must_use]
    pub fn weights(&self) -> Option<Vec<i16>> {
        match &self.brain {
            Brain::Model(c) => Some(c.learner().weights().iter().map(|q| q.to_bits()).collect()),
            Brain::Firmware(_) => {
                let at = self.net_w?;
                let peek = |a: u32| self.mcu.peek(a);
                let base = (0..4).fold(0u32, |v, i| (v << 8) | u32::from(peek(at + i)));
                let n = self.weights_len;
                Some(
                    (0..n as u32)
                        .map(|k| i16::from_be_bytes([peek(base + 2 * k), peek(base + 2 * k + 1)]))
                        .collect(),
                )
            }
        }
    }

    /// The MCU's busy states since the last call: the step's work, the tick interrupts and
    /// the main loop around them (not the time asleep).
    pub fn take_busy_states(&mut self) -> u64 {
        std::mem::take(&mut self.busy_states)
    }

    /// What a firmware robot's stack guard does when a stack access leaves the stack's room
    /// (see [`FirmwareController::set_stack_guard_mode`]); a model robot has no stack to guard.
    pub fn set_stack_guard_mode(&mut self, mode: h8300h::cpu::StackGuardMode) {
        if let Brain::Firmware(c) = &mut self.brain {
            c.set_stack_guard_mode(mode);
        }
    }

    /// The first stack access of a firmware robot that left the stack's room (under a
    /// warning guard).
    #[must_use]
    pub fn stack_fault(&self) -> Option<h8300h::cpu::StackFault> {
        match &self.brain {
            Brain::Firmware(c) => c.stack_fault(),
            Brain::Model(_) => None,
        }
    }

    /// Whether a firmware robot stops at the first access to what its chip does not model
    /// (see [`FirmwareController::set_strict_io`]).
    pub fn set_strict_io(&mut self, on: bool) {
        if let Brain::Firmware(c) = &mut self.brain {
            c.set_strict_io(on);
        }
    }

    /// The first access to each address the chip does not model, one line each, named from
    /// the firmware's symbols ([`h8_3052f::mcu::IoReport`]).
    #[must_use]
    pub fn io_reports(&self) -> Vec<String> {
        self.mcu
            .io_reports()
            .iter()
            .map(|r| match &self.brain {
                Brain::Firmware(c) => c.describe_io(r),
                Brain::Model(_) => r.describe(None),
            })
            .collect()
    }

    /// Starts a profile of where a firmware robot's states go by call stack
    /// ([`FirmwareController::start_profile`]).
    ///
    /// # Errors
    /// A robot whose controller is the model.
    pub fn start_profile(&mut self) -> Result<()> {
        let Brain::Firmware(c) = &mut self.brain else {
            anyhow::bail!("its controller is the Rust model: only firmware robots can be profiled");
        };
        c.start_profile(self.mcu.now());
        Ok(())
    }

    /// Ends the profile under way and returns it as folded stacks, with the robot's states
    /// (its MCU's clock) they add up to (`None` when none is under way).
    pub fn take_profile(&mut self) -> Option<(String, u64)> {
        let Brain::Firmware(c) = &mut self.brain else {
            return None;
        };
        let now = self.mcu.now();
        c.take_profile(now).map(|p| (p.folded(), now))
    }

    /// The wheel commands the motor pins give now.
    pub fn wheels(&mut self) -> (WheelCommand, WheelCommand) {
        let pins = robot_board::wiring::motor_pins(&mut self.mcu);
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
