//! "Does it fit the H8/3052?" (docs/design.md §6), measured by running the controller on the emulated
//! MCU: by default the robot firmware (`firmware/robot.mot`, docs/design.md §8) on the H8/300H core,
//! with the Rust model of the controller (`robot_board::model`) measured beside it.
//!
//! [`measure`] builds an MCU with four modelled IR sensors (`sensors::IrSensor`, datasheet
//! spread and noise, their own seeds) whose true distances follow a seeded random walk between
//! 30 mm and 1 m (so the learner sees rewards, punishments and dead zones, and the readings
//! include the fold-back), and runs the controller on it for `steps` step periods.
//!
//! With the firmware, the settings reach it through its configuration block (written into the
//! flash at load); boot runs from reset until the first step begins (the first entry into the
//! step's first phase, `ad_scan` for the robot firmware); the step periods are counted from
//! there, one window of K ticks each, so each holds one step and the ticks and idle time up to
//! the next. States are attributed to phases by PC through the image's symbol table,
//! each phase a function with its callees ([`robot_board::profile`]); a window's busy states are
//! all but those asleep. RAM is the image's `.data` and `.bss` (every variable, sized from the
//! symbol table), the network's arrays carved at boot (from the firmware's own pointers), and
//! the stack's high-water mark (the lowest SP the run saw). ROM is the image's bytes.
//!
//! With the model, the phases are the model's own accounting; RAM is its placement of the same
//! items and ROM the firmware image's size (the model has no image of its own).
//!
//! The report gives the maximum and mean states per phase (with the other controller's mean
//! and the ratio when both ran), the time at φ against the step period, the RAM items against
//! the 8 192 bytes, the ROM against the 512 KB of flash, the EEPROM traffic and the lifetime the
//! endurance allows, and a one-line verdict with the tightest margin.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use seeding::Purpose;
use serde::Serialize;

use h8_3052f::mcu::Mcu;
use h8_3052f::pins::Board;
use h8300h::bus::Bus;
use h8300h::cpu::{Cpu, CpuError, Event, StackFault, StackGuard};
use h8300h::memmap::{RAM_BYTES, ROM_BYTES};
use robot_board::board::{BoardError, RobotBoard, RobotConfig, robot_mcu};
use robot_board::firmware::{
    BlockError, ConfigBlock, ConfigStatus, Firmware, FirmwareError, RunError, halted,
};
use robot_board::model::{Controller, ControllerConfig, ControllerError, PhaseStates};
use robot_board::profile::{PhaseDef, Profiler, UnknownFunction};

use crate::energy::{
    Charge, DriveMeter, ElectronicsMeter, FreeWheels, PAPER_BATTERY_LIFE_H, Pack, Part,
    mean_current_ma,
};
use crate::scenario::ControllerKind;
use crate::seeds::robot_stream;

/// Endurance of a 24LC256 page: 1 000 000 write cycles (docs/design.md §3.6; Microchip DS21203).
pub const ENDURANCE_CYCLES: f64 = 1_000_000.0;
/// Longest boot the fit waits for before calling the image stuck: 10 s of MCU time.
pub const BOOT_LIMIT_S: f64 = 10.0;

/// A firmware image to measure and its phases.
#[derive(Clone, Debug)]
pub struct FirmwareUnderTest {
    /// The image and its symbols.
    pub firmware: Firmware,
    /// The phases, each a name and its functions (see [`robot_phases`]).
    pub phases: Vec<PhaseDef>,
}

impl FirmwareUnderTest {
    /// The robot firmware with its phases.
    ///
    /// # Errors
    /// Only if the built-in image were damaged.
    pub fn robot() -> Result<Self, FirmwareError> {
        Ok(FirmwareUnderTest {
            firmware: Firmware::robot()?,
            phases: robot_phases(),
        })
    }
}

/// The robot firmware's phases, in report order, and the functions that make them (docs/design.md §8).
#[must_use]
pub fn robot_phases() -> Vec<PhaseDef> {
    vec![
        PhaseDef::new(PHASE_ADC, &["ad_scan"]),
        PhaseDef::new(PHASE_INPUT, &["learner_step"]),
        PhaseDef::new(PHASE_UPDATE, &["learner_update"]),
        PhaseDef::new(PHASE_FORWARD, &["learner_forward"]),
        PhaseDef::new(PHASE_MOTORS, &["motors_set"]),
        PhaseDef::new(PHASE_SAVE, &["record_save"]),
        PhaseDef::new(PHASE_TICKS, &["tick_isr"]),
        PhaseDef::new(PHASE_BOOT, &["boot"]),
    ]
}

/// Phase names shared by the firmware's profile and the model's accounting.
const PHASE_ADC: &str = "A/D";
const PHASE_INPUT: &str = "input";
const PHASE_UPDATE: &str = "update";
const PHASE_FORWARD: &str = "forward";
const PHASE_MOTORS: &str = "motors";
const PHASE_SAVE: &str = "EEPROM save (amortised)";
const PHASE_TICKS: &str = "tick interrupts";
const PHASE_BOOT: &str = "boot";
const PHASE_OTHER: &str = "main loop and the rest";

/// What to measure.
#[derive(Clone, Debug)]
pub struct FitConfig {
    /// The controller's settings (the firmware gets them through its configuration block).
    pub controller: ControllerConfig,
    /// Step periods to run (after boot).
    pub steps: u32,
    /// The master seed: the fit's robot is robot 0 of repeat 0 under it ([`crate::seeds`]), whose
    /// streams give its sensors, their distances and its EEPROMs. (The initial weights come
    /// with [`Self::controller`]; the commands take them from the same robot,
    /// [`fit_weight_seed`].)
    pub seed: u64,
    /// Which controller the verdict is about.
    pub kind: ControllerKind,
    /// The image when `kind` is [`ControllerKind::Firmware`] (and the ROM figure of the model).
    pub firmware: FirmwareUnderTest,
    /// Also run the other controller and put its figures beside each phase.
    pub compare: bool,
    /// Stop the measurement at the image's first access to a register the emulated chip does
    /// not model (or a reserved address) instead of noting it in the verdict.
    pub strict_io: bool,
}

/// Why the fit could not be measured.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// The model controller refused the settings.
    #[error(transparent)]
    Controller(#[from] ControllerError),
    /// The configuration block cannot carry a setting.
    #[error(transparent)]
    Block(#[from] BlockError),
    /// The image could not be used.
    #[error(transparent)]
    Firmware(#[from] FirmwareError),
    /// A phase names a function the image lacks.
    #[error(transparent)]
    Phase(#[from] UnknownFunction),
    /// The firmware rejected its configuration block.
    #[error("the firmware rejected its configuration block: {field} (cfg_status 0x{code:02X})")]
    Rejected {
        /// The field, as the firmware names it.
        field: &'static str,
        /// The status byte.
        code: u8,
    },
    /// The firmware stopped.
    #[error("the firmware stopped at state {at}")]
    Run {
        /// When.
        at: u64,
        /// Why.
        #[source]
        source: RunError,
    },
    /// The firmware never went to sleep after reset.
    #[error(
        "the firmware did not reach SLEEP within {BOOT_LIMIT_S} s of reset (PC H'{pc:06X}): the fit counts boot up to the first SLEEP"
    )]
    BootTimeout {
        /// Where it was.
        pc: u32,
    },
    /// The step's first phase did not come again.
    #[error(
        "the next step's `{phase}` did not begin within two step periods and {BOOT_LIMIT_S} s (PC H'{pc:06X})"
    )]
    StepTimeout {
        /// The phase the step periods start with.
        phase: String,
        /// Where the CPU was.
        pc: u32,
    },
    /// The MCU could not be built.
    #[error("building the MCU")]
    Mcu(#[from] BoardError),
    /// A what-if on an image without a configuration block.
    #[error(
        "`{image}` has no configuration block (symbol config_block at H'000400), so the settings cannot reach it; measure it without what-ifs"
    )]
    NoBlock {
        /// The image.
        image: String,
    },
    /// A sensor model refused the clock.
    #[error("clock_hz = {clock_hz}: {why}")]
    Sensor {
        /// The clock.
        clock_hz: u32,
        /// The sensor model's reason.
        why: String,
    },
}

/// Maximum and mean of a per-step quantity in states.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Spread {
    /// Largest value over the steps.
    pub max: u64,
    /// Mean over the steps.
    pub mean: f64,
}

/// One phase of the step.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PhaseLine {
    /// The phase.
    pub phase: String,
    /// States per step period (over all periods; for the save, periods without a save count
    /// as 0, so the mean is the amortised cost).
    pub states: Spread,
    /// The maximum in microseconds at φ.
    pub max_us: f64,
    /// The other controller's figures for the same phase, when it ran.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub other: Option<Spread>,
    /// This controller's mean over the other's, when both are non-zero.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ratio: Option<f64>,
}

/// A RAM or ROM item.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MemLine {
    /// What it holds.
    pub item: String,
    /// Where it starts.
    pub addr: u32,
    /// Its size.
    pub bytes: u32,
}

/// The EEPROM side.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EepromLine {
    /// Record bytes sent per save.
    pub bytes_per_save: usize,
    /// Pages written per save (body and commit).
    pub pages_per_save: usize,
    /// Saves per hour at this step period.
    pub saves_per_hour: f64,
    /// Writes per hour on each record page of one chip (A/B: every other save).
    pub page_writes_per_hour: f64,
    /// Hours until a page reaches its endurance.
    pub lifetime_hours: f64,
    /// States of the slowest save (mostly ACK polling through the write cycles).
    pub save_max_states: u64,
}

/// The stack's room and what the firmware left of it ([`h8300h::cpu::stack`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StackLine {
    /// The room's low end: the end of the firmware's data and of the arrays it carves at
    /// boot.
    pub room_low: u32,
    /// The stack's top (the initial SP).
    pub room_top: u32,
    /// Bytes in the room.
    pub room_bytes: u32,
    /// The lowest SP the run saw.
    pub lowest_sp: u32,
    /// Bytes between the lowest SP and the room's low end (negative past it).
    pub left_bytes: i64,
    /// The first stack access outside the room, if one stopped the measurement.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub overflow: Option<String>,
    /// Its bytes outside the room.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub overflow_bytes: Option<u32>,
}

/// One part's draw from the pack.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PartLine {
    /// The part ([`Part::key`]).
    pub part: &'static str,
    /// The part in words.
    pub name: &'static str,
    /// Its mean current, mA.
    pub mean_current_ma: f64,
    /// Its energy per step period at the pack's voltage, mJ.
    pub energy_per_step_mj: f64,
}

/// What the robot draws from its pack with the measured controller, and how long the pack
/// lasts ([`crate::energy`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EnergyReport {
    /// The pack.
    pub pack: Pack,
    /// The step period, s.
    pub step_period_s: f64,
    /// By part, the wheels free (no obstacle: each follows its command with the world's lag).
    pub parts: Vec<PartLine>,
    /// The robot's mean current, mA.
    pub mean_current_ma: f64,
    /// Its energy per step period, mJ.
    pub energy_per_step_mj: f64,
    /// Hours the pack lasts.
    pub battery_life_h: f64,
    /// The motors' mean current pressed against a wall the whole time, still driving (the
    /// body still, each turning wheel slipping at its traction), mA.
    pub held_motors_current_ma: f64,
    /// The robot's mean current so, mA.
    pub held_mean_current_ma: f64,
    /// Hours the pack lasts so.
    pub held_battery_life_h: f64,
    /// The paper's figure: "up to 3.5 hours".
    pub paper_battery_life_h: f64,
    /// The capacity a cell would need for the paper's 3.5 h at the free-running current, mAh.
    pub capacity_for_paper_mah: f64,
    /// How often the drive voltage's bound cut a motor's current, the wheels free.
    pub motor_cap: crate::energy::CurrentCap,
    /// The same pressed against a wall.
    pub held_motor_cap: crate::energy::CurrentCap,
}

impl EnergyReport {
    fn new(m: &Metered, pack: Pack, step_period_s: f64) -> EnergyReport {
        let mut free = m.electronics;
        free.add(&m.free);
        let parts = Part::ALL
            .iter()
            .map(|&p| PartLine {
                part: p.key(),
                name: p.name(),
                mean_current_ma: mean_current_ma(free.of(p), m.seconds),
                energy_per_step_mj: 0.0,
            })
            .collect();
        let held_motors = mean_current_ma(m.held.of(Part::Motors), m.seconds);
        let held_rest = mean_current_ma(
            free.total_uc() - free.of(Part::Motors) - free.of(Part::Bridges)
                + m.held.of(Part::Bridges),
            m.seconds,
        );
        EnergyReport {
            pack,
            step_period_s,
            parts,
            mean_current_ma: 0.0,
            energy_per_step_mj: 0.0,
            battery_life_h: 0.0,
            held_motors_current_ma: held_motors,
            held_mean_current_ma: held_rest + held_motors,
            held_battery_life_h: 0.0,
            paper_battery_life_h: PAPER_BATTERY_LIFE_H,
            capacity_for_paper_mah: 0.0,
            motor_cap: m.free_cap,
            held_motor_cap: m.held_cap,
        }
        .with_pack(pack)
    }

    /// The same draw from another pack (a different capacity).
    #[must_use]
    pub fn with_pack(&self, pack: Pack) -> EnergyReport {
        let mut r = self.clone();
        r.pack = pack;
        // mA × s = mC; at the pack's volts, mJ.
        let per_step = |ma: f64| ma * self.step_period_s * pack.volts();
        for p in &mut r.parts {
            p.energy_per_step_mj = per_step(p.mean_current_ma);
        }
        r.mean_current_ma = r.parts.iter().map(|p| p.mean_current_ma).sum();
        r.energy_per_step_mj = per_step(r.mean_current_ma);
        r.battery_life_h = pack.life_h(r.mean_current_ma);
        r.held_battery_life_h = pack.life_h(r.held_mean_current_ma);
        r.capacity_for_paper_mah = Pack::capacity_for_h(r.mean_current_ma, PAPER_BATTERY_LIFE_H);
        r
    }
}

/// The verdict of docs/design.md §6.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FitReport {
    /// The controller measured.
    pub controller: ControllerKind,
    /// The image (firmware) or `"model"`.
    pub source: String,
    /// The other controller's source, when it ran beside.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub compared_with: Option<String>,
    /// Inputs N.
    pub n_in: usize,
    /// Outputs M.
    pub n_out: usize,
    /// History depth H.
    pub history: usize,
    /// Bias input on.
    pub bias: bool,
    /// Spare inputs.
    pub spare: usize,
    /// η (Q15 integer).
    pub eta: i16,
    /// T (du).
    pub threshold: i16,
    /// Save every S steps.
    pub save_every_steps: u32,
    /// Step period (s).
    pub step_period_s: f64,
    /// φ (Hz).
    pub clock_hz: u32,
    /// Steps measured.
    pub steps: u32,
    /// Seed.
    pub seed: u64,
    /// States of boot (reset until the first step begins: hardware set-up, recovery, weights,
    /// the first tick).
    pub boot_states: u64,
    /// States per phase.
    pub phases: Vec<PhaseLine>,
    /// The CPU's busy states per step period.
    pub busy_per_step: Spread,
    /// Busy share of the step period, mean over the steps (percent).
    pub cpu_mean_percent: f64,
    /// Busy share of the step period in the worst step (percent).
    pub cpu_worst_percent: f64,
    /// RAM items.
    pub ram: Vec<MemLine>,
    /// RAM used, bytes.
    pub ram_used: u32,
    /// The stack's high-water mark (bytes below the top of RAM), when measured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stack_high_water: Option<u32>,
    /// The stack's room and what was left of it (machine code), when measured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stack: Option<StackLine>,
    /// What the robot draws from its pack and how long the pack lasts (the paper's pack, with
    /// cells of [`crate::energy::DEFAULT_CAPACITY_MAH`] unless the command says otherwise),
    /// when the measurement ran to its end.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy: Option<EnergyReport>,
    /// ROM items.
    pub rom: Vec<MemLine>,
    /// ROM used, bytes.
    pub rom_used: u32,
    /// EEPROM traffic and lifetime.
    pub eeprom: EepromLine,
    /// Whether RAM, ROM and CPU all fit.
    pub fits: bool,
    /// The resource with the least room left.
    pub tightest: &'static str,
    /// Its room left, percent.
    pub tightest_margin_percent: f64,
    /// The one-line verdict.
    pub verdict: String,
    /// The image's first access to each address the emulated chip does not model (a register
    /// of a module it does not model, a reserved address), one line each; empty for the robot
    /// firmware. Their effect on the chip is not in the figures.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub unmodelled: Vec<String>,
}

/// What the fit's world drives on the robot's board: four IR sensors whose distances the driver
/// sets; bumpers open.
pub struct FitBoard {
    sensors: Vec<sensors::IrSensor>,
    distance_mm: [f64; 4],
    /// The A/D input of each sensor (the controller's wiring).
    channels: [u8; 4],
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

/// The initial-weight seed of the fit's robot under master seed `seed`: robot 0 of repeat 0's
/// weight stream, as in a run.
#[must_use]
pub const fn fit_weight_seed(seed: u64) -> u64 {
    robot_stream(seed, 0, 0, 0, Purpose::Weights)
}

/// The fit's robot: its MCU (sensors, EEPROMs) and the walk of its sensors' distances.
struct Rig {
    mcu: Mcu<RobotBoard<FitBoard>>,
    walk: ChaCha8Rng,
}

impl Rig {
    fn new(cfg: &FitConfig) -> Result<Rig, FitError> {
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
    fn move_world(&mut self) {
        for d in &mut self.mcu.board_mut().world.distance_mm {
            let delta: f64 = self.walk.random_range(-60.0..60.0);
            *d = (*d + delta).clamp(30.0, 1000.0);
        }
    }
}

/// One controller's measurement before it becomes a report.
struct Measured {
    source: String,
    boot_states: u64,
    /// (phase, states in each step period).
    phases: Vec<(String, Vec<u64>)>,
    busy: Vec<u64>,
    ram: Vec<MemLine>,
    stack_high_water: Option<u32>,
    /// The stack's room and what the firmware left of it (machine code only).
    stack: Option<StackLine>,
    /// The charge over the measured step periods.
    energy: Option<Metered>,
    /// The first access to each address the chip does not model: (what, in a few words; the
    /// whole line).
    unmodelled: Vec<(String, String)>,
}

/// What the charge meter saw over the measured step periods.
struct Metered {
    /// The electronics (MCU, A/D converter, sensors, EEPROMs, regulator).
    electronics: Charge,
    /// The motors and bridges with the wheels free.
    free: Charge,
    /// The motors and bridges pressed against a wall.
    held: Charge,
    /// How often the drive voltage's bound cut a motor's current, free.
    free_cap: crate::energy::CurrentCap,
    /// The same, pressed against a wall.
    held_cap: crate::energy::CurrentCap,
    /// The measured time, s.
    seconds: f64,
}

/// The fit's energy meter: the electronics from the MCU's counters, and the motors under the
/// controller's commands twice over, once with the wheels free and once pressed against a wall
/// (the body still, the wheels slipping).
struct FitMeter {
    electronics: ElectronicsMeter,
    free: (DriveMeter, FreeWheels),
    held: (DriveMeter, FreeWheels),
    start: u64,
}

impl FitMeter {
    fn new<W: Board>(mcu: &Mcu<RobotBoard<W>>) -> FitMeter {
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
    fn period<B: Board>(&mut self, mcu: &mut Mcu<B>, seconds: f64) {
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

    fn finish<W: Board>(mut self, mcu: &Mcu<RobotBoard<W>>, busy_states: u64) -> Metered {
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
    fn phase(&self, name: &str) -> Option<&[u64]> {
        self.phases
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

/// Runs the firmware for `cfg.steps` step periods.
fn measure_firmware(cfg: &FitConfig) -> Result<Measured, FitError> {
    let fw = &cfg.firmware.firmware;
    let block = config_block(cfg)?;
    let mut run = FirmwareRun::start(cfg, block)?;
    let mut periods = StepPeriods::new(run.profiler.names().len(), cfg.steps);
    let mut boot_states = 0;
    let mut meter = None;
    // The measurement, up to a stack overflow if there is one.
    let fault: Option<Box<StackFault>> = 'run: {
        if let Some(f) = run.boot()? {
            break 'run Some(f);
        }
        boot_states = run.profiler.states().iter().sum();
        // Booted: what the firmware carved above its data is not the stack's.
        fw.raise_stack_low(&mut run.cpu, &run.rig.mcu);
        run.check_config_status(fw, block.as_ref())?;
        let m = meter.insert(FitMeter::new(&run.rig.mcu));
        run.step_periods(cfg.steps, &mut periods, m)?
    };
    let energy = match (fault.is_none(), meter) {
        (true, Some(m)) => Some(m.finish(&run.rig.mcu, periods.busy.iter().sum())),
        _ => None,
    };
    let fault = fault.map(|mut f| {
        f.function = fw.symbols.function_at(f.pc).map(|s| s.c_name().to_string());
        *f
    });
    let phases: Vec<(String, Vec<u64>)> = run
        .profiler
        .names()
        .iter()
        .cloned()
        .zip(periods.per_phase)
        .filter(|(n, _)| n != PHASE_BOOT)
        .collect();
    let stack_top = fw
        .symbols
        .addr("_stack_top")
        .unwrap_or(h8300h::memmap::RAM_END + 1);
    let stack_high_water = stack_top.saturating_sub(run.profiler.min_sp());
    let stack = run.stack_line(fw, fault.as_ref());
    let unmodelled = run
        .rig
        .mcu
        .io_reports()
        .iter()
        .map(|r| (r.short(), fw.describe_io(r)))
        .collect();
    Ok(Measured {
        source: fw.name.clone(),
        boot_states,
        phases,
        busy: periods.busy,
        ram: firmware_ram(fw, &run.rig.mcu, stack_high_water),
        stack_high_water: Some(stack_high_water),
        stack: Some(stack),
        energy,
        unmodelled,
    })
}

/// The configuration block to install in the firmware: the controller's, or none for an image
/// without one when the controller is the arena's (the image's own constants are then the
/// arena's).
fn config_block(cfg: &FitConfig) -> Result<Option<ConfigBlock>, FitError> {
    let fw = &cfg.firmware.firmware;
    let block = ConfigBlock::from_controller(&cfg.controller)?;
    if fw.has_config_block() {
        Ok(Some(block))
    } else if block == ConfigBlock::ARENA {
        Ok(None)
    } else {
        Err(FitError::NoBlock {
            image: fw.name.clone(),
        })
    }
}

/// The states of each measured step period: per phase, and all of them (the busy states).
struct StepPeriods {
    per_phase: Vec<Vec<u64>>,
    busy: Vec<u64>,
}

impl StepPeriods {
    fn new(n_phases: usize, steps: u32) -> StepPeriods {
        StepPeriods {
            per_phase: vec![Vec::with_capacity(steps as usize); n_phases],
            busy: Vec::with_capacity(steps as usize),
        }
    }

    /// A step period ended with the profiler's counts at `now`, from `before` at its start.
    fn push(&mut self, before: &[u64], now: &[u64]) {
        for (i, v) in self.per_phase.iter_mut().enumerate() {
            v.push(now[i] - before[i]);
        }
        self.busy
            .push(now.iter().sum::<u64>() - before.iter().sum::<u64>());
    }
}

/// The firmware under measurement: its robot, CPU and phase profiler, and the limits of the run.
struct FirmwareRun {
    rig: Rig,
    cpu: Cpu,
    profiler: Profiler,
    /// The step's first phase (A/D for the robot firmware), or `usize::MAX` without phases
    /// (the step periods are then fixed windows from the first SLEEP).
    step_phase: usize,
    /// The most states boot may take, and the slack of a step period beyond two periods.
    boot_limit: u64,
    /// A step period, states.
    period: u64,
    /// The MCU's clock, Hz.
    clock: f64,
    /// Stop at the first access to what the chip does not model ([`FitConfig::strict_io`]).
    strict_io: bool,
    /// The image's symbols, to name that access's function.
    symbols: robot_board::symbols::SymbolTable,
}

impl FirmwareRun {
    /// The firmware installed (with `block`) on a fresh robot, at reset.
    fn start(cfg: &FitConfig, block: Option<ConfigBlock>) -> Result<FirmwareRun, FitError> {
        let fw = &cfg.firmware.firmware;
        let mut rig = Rig::new(cfg)?;
        let mut cpu = Cpu::new();
        // The stack guard stops the measurement at a stack access outside the room: the verdict
        // is then that it does not fit, with how far it went.
        cpu.set_stack_guard(Some(StackGuard::stop(fw.stack_room())));
        fw.install(&mut rig.mcu, &mut cpu, block.as_ref())?;
        let profiler = Profiler::new(&fw.symbols, &cfg.firmware.phases, PHASE_OTHER)?;
        let clock = f64::from(cfg.controller.clock_hz);
        let step_phase = profiler
            .names()
            .iter()
            .position(|n| n != PHASE_BOOT && n != PHASE_OTHER)
            .unwrap_or(usize::MAX);
        let period = match block {
            Some(b) => b.step_period_states(),
            None => ConfigBlock::ARENA.step_period_states(),
        };
        Ok(FirmwareRun {
            rig,
            cpu,
            profiler,
            step_phase,
            boot_limit: (BOOT_LIMIT_S * clock) as u64,
            period,
            clock,
            strict_io: cfg.strict_io,
            symbols: fw.symbols.clone(),
        })
    }

    /// Runs the CPU up to one event, before `deadline`; a halt is an error.
    fn step(&mut self, deadline: u64) -> Result<Event, FitError> {
        let at = self.rig.mcu.now();
        match self
            .profiler
            .run_one(&mut self.cpu, &mut self.rig.mcu, deadline)
        {
            Ok(Event::Halted) => Err(FitError::Run {
                at,
                source: halted(&self.cpu),
            }),
            Ok(Event::Break) if self.strict_io => {
                let what = self
                    .rig
                    .mcu
                    .io_reports()
                    .last()
                    .map_or_else(String::new, |r| {
                        robot_board::firmware::describe_io(&self.symbols, r)
                    });
                Err(FitError::Run {
                    at,
                    source: RunError::Unmodelled(what),
                })
            }
            Ok(e) => Ok(e),
            Err(e) => Err(FitError::Run {
                at,
                source: RunError::Cpu(e),
            }),
        }
    }

    /// Boot: from reset until the first step begins (the first entry into the step's first
    /// phase, A/D for the robot firmware; without phases, the first SLEEP). The step periods
    /// are counted from there. A stack overflow on the way is returned.
    fn boot(&mut self) -> Result<Option<Box<StackFault>>, FitError> {
        let booted = |run: &FirmwareRun| {
            if run.step_phase == usize::MAX {
                run.cpu.sleeping()
            } else {
                run.profiler.first_entry(run.step_phase).is_some()
            }
        };
        while !booted(self) {
            if self.rig.mcu.now() >= self.boot_limit {
                return Err(FitError::BootTimeout { pc: self.cpu.pc() });
            }
            if let Err(e) = self.step(self.boot_limit) {
                return Ok(Some(overflow(e)?));
            }
        }
        Ok(None)
    }

    /// A firmware that checks its configuration block and rejected it is an error.
    fn check_config_status(
        &self,
        fw: &Firmware,
        block: Option<&ConfigBlock>,
    ) -> Result<(), FitError> {
        if let Some(addr) = fw.symbols.addr("cfg_status")
            && block.is_some()
            && let ConfigStatus::Rejected { field, code } =
                ConfigStatus::from_code(self.rig.mcu.peek(addr))
        {
            return Err(FitError::Rejected { field, code });
        }
        Ok(())
    }

    /// Runs `steps` step periods after boot, counting their states into `periods` and their
    /// charge into `meter`. A stack overflow on the way ends them and is returned.
    fn step_periods(
        &mut self,
        steps: u32,
        periods: &mut StepPeriods,
        meter: &mut FitMeter,
    ) -> Result<Option<Box<StackFault>>, FitError> {
        let mut before: Vec<u64> = self.profiler.states().to_vec();
        // A step period runs from one step's start (the entry into its first phase) to the next
        // one's: one step, its ticks and the idle time up to the next (K ticks in steady state;
        // the first may be shorter when boot outlasted the first tick). Without phases, fixed
        // windows of K ticks from the first SLEEP.
        let mut window_end = self.rig.mcu.now();
        for k in 0..u64::from(steps) {
            // The world moves before each step's A/D scan.
            self.rig.move_world();
            let fault = if self.step_phase == usize::MAX {
                window_end += self.period;
                self.run_window(window_end)?
            } else {
                self.run_step(k)?
            };
            if fault.is_some() {
                return Ok(fault);
            }
            let now = self.profiler.states();
            periods.push(&before, now);
            before = now.to_vec();
            let seconds = self.period as f64 / self.clock;
            meter.period(&mut self.rig.mcu, seconds);
        }
        Ok(None)
    }

    /// Runs up to `window_end` or the next SLEEP, whichever comes first. A stack overflow on
    /// the way is returned.
    fn run_window(&mut self, window_end: u64) -> Result<Option<Box<StackFault>>, FitError> {
        while self.rig.mcu.now() < window_end {
            match self.step(window_end) {
                Ok(Event::Asleep) => break,
                Ok(_) => {}
                Err(e) => return Ok(Some(overflow(e)?)),
            }
        }
        Ok(None)
    }

    /// Runs until step `k + 1` begins (the `k + 2`th entry into the step's first phase); taking
    /// too long is an error. A stack overflow on the way is returned.
    fn run_step(&mut self, k: u64) -> Result<Option<Box<StackFault>>, FitError> {
        let limit = self.rig.mcu.now() + 2 * self.period + self.boot_limit;
        while self.profiler.entries(self.step_phase) < k + 2 {
            if self.rig.mcu.now() >= limit {
                return Err(FitError::StepTimeout {
                    phase: self.profiler.names()[self.step_phase].clone(),
                    pc: self.cpu.pc(),
                });
            }
            if let Err(e) = self.step(limit) {
                return Ok(Some(overflow(e)?));
            }
        }
        Ok(None)
    }

    /// The stack's room and what the firmware left of it, with the overflow if there was one.
    fn stack_line(&self, fw: &Firmware, fault: Option<&StackFault>) -> StackLine {
        let room = self
            .cpu
            .stack_guard()
            .map_or_else(|| fw.stack_room(), |g| g.room);
        let lowest_sp = self.profiler.min_sp().min(room.top);
        StackLine {
            room_low: room.low,
            room_top: room.top,
            room_bytes: room.bytes(),
            lowest_sp,
            left_bytes: i64::from(lowest_sp) - i64::from(room.low),
            overflow: fault.map(ToString::to_string),
            overflow_bytes: fault.map(StackFault::bytes_over),
        }
    }
}

/// The stack fault an error of the measurement is, or the error itself.
fn overflow(e: FitError) -> Result<Box<StackFault>, FitError> {
    match e {
        FitError::Run {
            source: RunError::Cpu(CpuError::StackOverflow(f)),
            ..
        } => Ok(f),
        e => Err(e),
    }
}

/// A big-endian u32 in RAM.
fn peek_u32<B: Board>(mcu: &Mcu<B>, addr: u32) -> u32 {
    (0..4).fold(0, |v, i| (v << 8) | u32::from(mcu.peek(addr + i)))
}

/// The image's RAM: every variable of `.data` and `.bss` (sized by the next symbol), the
/// network's arrays (from the firmware's pointers, when it has them), the stack's high-water.
fn firmware_ram<B: Board>(fw: &Firmware, mcu: &Mcu<B>, stack: u32) -> Vec<MemLine> {
    let sym = |n: &str| fw.symbols.addr(n);
    let mut lines = Vec::new();
    if let (Some(start), Some(end)) = (
        sym("_data_start").or(sym("_bss_start")),
        sym("_bss_end").or(sym("_heap_start")),
    ) {
        let vars: Vec<&robot_board::symbols::Symbol> = fw
            .symbols
            .symbols()
            .iter()
            .filter(|s| {
                matches!(s.kind, 'b' | 'B' | 'd' | 'D')
                    && !s.name.starts_with('.')
                    && !s.name.starts_with("__")
                    && s.addr >= start
                    && s.addr < end
            })
            .collect();
        for (i, v) in vars.iter().enumerate() {
            let next = vars.get(i + 1).map_or(end, |n| n.addr);
            lines.push(MemLine {
                item: format!("{} (variable)", v.c_name()),
                addr: v.addr,
                bytes: next - v.addr,
            });
        }
    }
    let net = ["net_w", "net_delta", "net_y", "net_o", "net_x"].map(&sym);
    if let (Some(heap_end), [Some(w), Some(d), Some(y), Some(o), Some(x)]) = (sym("heap_end"), net)
    {
        let end = peek_u32(mcu, heap_end);
        let p = [w, d, y, o, x].map(|a| peek_u32(mcu, a));
        let names = [
            "weights w (i16, N x M)",
            "update deltas (i16, N)",
            "sums y (i32, M)",
            "outputs O (i16, M)",
            "input vector x (i8, N, word-aligned)",
        ];
        for k in 0..5 {
            let next = if k + 1 < 5 { p[k + 1] } else { end };
            lines.push(MemLine {
                item: format!("{} [carved at boot]", names[k]),
                addr: p[k],
                bytes: next.saturating_sub(p[k]),
            });
        }
    }
    let top = sym("_stack_top").unwrap_or(h8300h::memmap::RAM_END + 1);
    lines.push(MemLine {
        item: "stack (high-water mark measured)".to_string(),
        addr: top - stack,
        bytes: stack,
    });
    lines
}

/// Runs the model controller for `cfg.steps` step periods.
fn measure_model(cfg: &FitConfig) -> Result<Measured, FitError> {
    let mut controller = Controller::new(cfg.controller.clone())?;
    let mut rig = Rig::new(cfg)?;
    let boot = controller.boot(&mut rig.mcu)?;
    // (the step's phases, the sleep's busy states, the sleep's ticks) for each step period:
    // the step and the sleep after it, up to the next step (the firmware's periods, too, run
    // from one step's tick to the next).
    let mut per_step: Vec<(PhaseStates, u64, u64)> = Vec::with_capacity(cfg.steps as usize);
    controller.sleep_until_step(&mut rig.mcu)?;
    let mut meter = FitMeter::new(&rig.mcu);
    let period_s = cfg.controller.step_period_s;
    for _ in 0..cfg.steps {
        rig.move_world();
        let step = controller.step(&mut rig.mcu)?;
        let sleep = controller.sleep_until_step(&mut rig.mcu)?;
        per_step.push((step.phases, sleep.busy_states, sleep.ticks));
        meter.period(&mut rig.mcu, period_s);
    }
    let isr = controller.isr_states().unwrap_or(0);
    let col = |f: &dyn Fn(&(PhaseStates, u64, u64)) -> u64| -> Vec<u64> {
        per_step.iter().map(f).collect()
    };
    // A step period: the step (with the ticks taken during it) and the sleep after it (its
    // ticks, SLEEP and main's test after each).
    let phases = vec![
        (PHASE_ADC.to_string(), col(&|s| s.0.adc)),
        (PHASE_INPUT.to_string(), col(&|s| s.0.input)),
        (PHASE_UPDATE.to_string(), col(&|s| s.0.update)),
        (PHASE_FORWARD.to_string(), col(&|s| s.0.forward)),
        (PHASE_MOTORS.to_string(), col(&|s| s.0.motors)),
        (PHASE_SAVE.to_string(), col(&|s| s.0.save)),
        (PHASE_TICKS.to_string(), col(&|s| s.2 * isr + s.0.isr)),
        (
            PHASE_OTHER.to_string(),
            col(&|s| s.0.main + s.1.saturating_sub(s.2 * isr)),
        ),
    ];
    let ram = controller
        .ram()
        .items()
        .iter()
        .map(|p| MemLine {
            item: p.name.clone(),
            addr: p.addr,
            bytes: p.bytes,
        })
        .collect();
    let busy = col(&|s| s.0.work() + s.0.isr + s.1);
    let energy = Some(meter.finish(&rig.mcu, busy.iter().sum()));
    Ok(Measured {
        source: "model".to_string(),
        boot_states: boot.states,
        phases,
        busy,
        ram,
        stack_high_water: None,
        stack: None,
        energy,
        unmodelled: Vec::new(),
    })
}

/// Runs the controller as [`FitConfig`] says and reports.
///
/// # Errors
/// [`FitError`] when the configuration is impossible, the image unusable or it stops.
pub fn measure(cfg: &FitConfig) -> Result<FitReport, FitError> {
    let run = |kind| match kind {
        ControllerKind::Firmware => measure_firmware(cfg),
        ControllerKind::Model => measure_model(cfg),
    };
    let main = run(cfg.kind)?;
    let other = if cfg.compare {
        Some(run(match cfg.kind {
            ControllerKind::Firmware => ControllerKind::Model,
            ControllerKind::Model => ControllerKind::Firmware,
        })?)
    } else {
        None
    };
    Ok(report(cfg, &main, other.as_ref()))
}

fn spread_of(values: &[u64]) -> Spread {
    if values.is_empty() {
        return Spread::default();
    }
    Spread {
        max: values.iter().copied().max().unwrap_or(0),
        mean: values.iter().sum::<u64>() as f64 / values.len() as f64,
    }
}

fn report(cfg: &FitConfig, m: &Measured, other: Option<&Measured>) -> FitReport {
    let c = &cfg.controller;
    let clock_hz = c.clock_hz;
    let phases = phase_lines(clock_hz, m, other);
    let save_max = m
        .phase(PHASE_SAVE)
        .map_or(0, |v| v.iter().copied().max().unwrap_or(0));
    let busy_per_step = spread_of(&m.busy);
    let period_states = c.step_period_s * f64::from(clock_hz);
    let cpu_mean_percent = busy_per_step.mean / period_states * 100.0;
    let cpu_worst_percent = busy_per_step.max as f64 / period_states * 100.0;
    let ram_used: u32 = m.ram.iter().map(|l| l.bytes).sum();
    let fw = &cfg.firmware.firmware;
    let rom = rom_lines(fw);
    let rom_used = fw.rom_bytes() as u32;
    let n_in = c.n_inputs();
    let eeprom = eeprom_line(c, save_max);
    let margins = Margins::new(ram_used, rom_used, cpu_worst_percent, m.stack.as_ref());
    let verdict = format!(
        "{}: {}{}{} x {} network, RAM {} of {} B, ROM {} B of {} KB, worst step {:.2} % of the {} s period (mean {:.3} %); tightest margin: {} with {:.1} % left",
        if margins.fits { "FITS" } else { "DOES NOT FIT" },
        margins.stack_note,
        unmodelled_note(&m.unmodelled),
        n_in,
        c.behaviours,
        ram_used,
        RAM_BYTES,
        rom_used,
        ROM_BYTES / 1024,
        cpu_worst_percent,
        c.step_period_s,
        cpu_mean_percent,
        margins.tightest,
        margins.tightest_percent
    );
    FitReport {
        controller: cfg.kind,
        source: m.source.clone(),
        compared_with: other.map(|o| o.source.clone()),
        n_in,
        n_out: c.behaviours,
        history: c.layout.history(),
        bias: c.layout.bias(),
        spare: c.layout.spare(),
        eta: c.params.eta().to_bits(),
        threshold: c.params.threshold(),
        save_every_steps: c.save_every_steps,
        step_period_s: c.step_period_s,
        clock_hz,
        steps: cfg.steps,
        seed: cfg.seed,
        boot_states: m.boot_states,
        phases,
        busy_per_step,
        cpu_mean_percent,
        cpu_worst_percent,
        ram: m.ram.clone(),
        ram_used,
        stack_high_water: m.stack_high_water,
        stack: m.stack.clone(),
        energy: m
            .energy
            .as_ref()
            .map(|e| EnergyReport::new(e, Pack::default(), c.step_period_s)),
        rom,
        rom_used,
        eeprom,
        fits: margins.fits,
        tightest: margins.tightest,
        tightest_margin_percent: margins.tightest_percent,
        verdict,
        unmodelled: m.unmodelled.iter().map(|(_, line)| line.clone()).collect(),
    }
}

/// The verdict's note on what the image uses that the chip does not model (empty when
/// nothing): `uses MAR0AR of the DMAC and FLMCR1 of the flash, not modelled; `.
fn unmodelled_note(unmodelled: &[(String, String)]) -> String {
    let what: Vec<&str> = unmodelled.iter().map(|(w, _)| w.as_str()).collect();
    match what.as_slice() {
        [] => String::new(),
        [one] => format!("uses {one}, not modelled; "),
        [first @ .., last] => format!("uses {} and {last}, not modelled; ", first.join(", ")),
    }
}

/// Each phase's states per step period (the maximum in µs at `clock_hz`), with the other
/// controller's and the ratio of the means when both ran.
fn phase_lines(clock_hz: u32, m: &Measured, other: Option<&Measured>) -> Vec<PhaseLine> {
    let us = |states: u64| states as f64 / f64::from(clock_hz) * 1e6;
    m.phases
        .iter()
        .map(|(name, v)| {
            let s = spread_of(v);
            let o = other.and_then(|o| o.phase(name)).map(spread_of);
            PhaseLine {
                phase: name.clone(),
                states: s,
                max_us: us(s.max),
                other: o,
                ratio: o
                    .filter(|o| o.mean > 0.0 && s.mean > 0.0)
                    .map(|o| s.mean / o.mean),
            }
        })
        .collect()
}

/// The image's ROM: its S-record data, and the configuration block within it when it has one.
fn rom_lines(fw: &Firmware) -> Vec<MemLine> {
    let mut rom = vec![MemLine {
        item: format!("{} (S-record data)", fw.name),
        addr: 0,
        bytes: fw.rom_bytes() as u32,
    }];
    if fw.has_config_block() {
        rom.push(MemLine {
            item: "of which the configuration block".to_string(),
            addr: robot_board::firmware::CONFIG_BLOCK_ADDR,
            bytes: robot_board::firmware::CONFIG_BLOCK_BYTES as u32,
        });
    }
    rom
}

/// The EEPROM traffic of the controller's saves and the lifetime the endurance allows (the
/// longest save, `save_max` states, measured).
fn eeprom_line(c: &ControllerConfig, save_max: u64) -> EepromLine {
    let payload = 2 * c.n_inputs() * c.behaviours;
    let record = eeprom::persist::RecordLayout::default();
    let saves_per_hour = 3600.0 / (c.step_period_s * f64::from(c.save_every_steps));
    let page_writes_per_hour = saves_per_hour / 2.0;
    EepromLine {
        bytes_per_save: record.bytes_per_save(payload),
        pages_per_save: record.pages_per_record(payload),
        saves_per_hour,
        page_writes_per_hour,
        lifetime_hours: ENDURANCE_CYCLES / page_writes_per_hour,
        save_max_states: save_max,
    }
}

/// The margins left in RAM, ROM, the CPU's worst step and the stack's room: the tightest, and
/// whether all are left.
struct Margins {
    fits: bool,
    tightest: &'static str,
    tightest_percent: f64,
    /// The verdict's note on a stack that left its room (empty when it did not).
    stack_note: String,
}

impl Margins {
    fn new(
        ram_used: u32,
        rom_used: u32,
        cpu_worst_percent: f64,
        stack: Option<&StackLine>,
    ) -> Margins {
        let mut margins = vec![
            (
                "RAM",
                100.0 * (1.0 - f64::from(ram_used) / f64::from(RAM_BYTES)),
            ),
            (
                "ROM",
                100.0 * (1.0 - f64::from(rom_used) / f64::from(ROM_BYTES)),
            ),
            ("CPU (worst step)", 100.0 - cpu_worst_percent),
        ];
        // The stack's room: what the lowest SP left of it, or how far past it the first access
        // outside went (then it does not fit, whatever the RAM total says).
        let mut stack_note = String::new();
        if let Some(st) = stack {
            let room = f64::from(st.room_bytes.max(1));
            let left = match st.overflow_bytes {
                Some(over) => -f64::from(over),
                None => st.left_bytes as f64,
            };
            margins.push(("stack", 100.0 * left / room));
            if let Some(text) = &st.overflow {
                stack_note = format!(
                    "the stack leaves its room by {} B ({text}); ",
                    st.overflow_bytes.unwrap_or(0)
                );
            }
        }
        let (tightest, tightest_percent) = margins
            .iter()
            .copied()
            .fold(("RAM", f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        Margins {
            fits: margins.iter().all(|m| m.1 >= 0.0),
            tightest,
            tightest_percent,
            stack_note,
        }
    }
}

/// Which CPU share a budget limits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Budget {
    /// The mean share over the steps (the CPU load, saves amortised).
    Mean,
    /// The share of the worst step (a step with a save: the step must still end well inside
    /// its period).
    WorstStep,
}

/// The largest network (inputs N, by spare inputs on top of `base`'s layout) that fits the RAM
/// and keeps the `budget` CPU share within `cpu_budget_percent` of the step period, measured by
/// running each candidate (without the other controller beside); None when even `base` does
/// not. The search is a bisection over N up to the learner's bound (256 inputs), each probe a
/// full [`measure`].
///
/// # Errors
/// [`FitError`] for an impossible base configuration.
pub fn largest_fitting(
    base: &FitConfig,
    cpu_budget_percent: f64,
    budget: Budget,
) -> Result<Option<FitReport>, FitError> {
    let fits = |spare: usize| -> Result<Option<FitReport>, FitError> {
        let mut cfg = base.clone();
        cfg.compare = false;
        cfg.controller.layout = base.controller.layout.with_spare(spare as u16);
        let share = |r: &FitReport| match budget {
            Budget::Mean => r.cpu_mean_percent,
            Budget::WorstStep => r.cpu_worst_percent,
        };
        match measure(&cfg) {
            Ok(r) if r.fits && share(&r) <= cpu_budget_percent => Ok(Some(r)),
            Ok(_)
            | Err(FitError::Controller(ControllerError::Ram(_) | ControllerError::Shape(_)))
            | Err(FitError::Rejected { .. }) => Ok(None),
            Err(e) => Err(e),
        }
    };
    let base_n = base.controller.n_inputs();
    let Some(mut best) = fits(0)? else {
        return Ok(None);
    };
    let (mut lo, mut hi) = (0usize, nn_q15::MAX_INPUTS.saturating_sub(base_n));
    if let Some(r) = fits(hi)? {
        return Ok(Some(r));
    }
    // Invariant: lo fits, hi does not.
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        match fits(mid)? {
            Some(r) => {
                lo = mid;
                best = r;
            }
            None => hi = mid,
        }
    }
    Ok(Some(best))
}
