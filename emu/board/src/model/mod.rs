//! The robot controller: the program the H8/3052F runs, written in Rust, running on the
//! emulated MCU through its registers.
//!
//! # What it does (docs/design.md §3.5)
//! At boot it sets up the ports, the ITU (ITU0 as a 10 ms tick interrupt, ITU1 and ITU2 as the
//! motors' PWM) and the I²C lines, then restores the newest valid record from the two EEPROMs
//! or, if there is none, draws fresh weights with a seeded xorshift32 (uniform in ±0.5). Then it
//! sleeps; every tick interrupt counts a tick, and every `step_period_s / 10 ms` ticks it runs a
//! step:
//! 1. **A/D**: a scan of AN0–AN3 (134 states per conversion, CKS = 1), polling ADF, then the
//!    four 8-bit codes through the du table (docs/design.md §3.3) into the proximities p;
//! 2. **learner**: D and E(t−1), the update, the input vector and the forward pass
//!    (`nn_q15`, charged from its H8 meter, phases `input`, `update`, `forward`);
//! 3. **motors**: the winner's row of the behaviour table into GRB1 and GRB2 (PWM duty) and the
//!    H-bridge direction bits on port B;
//! 4. **save** every `save_every_steps` steps: the weights as an A/B record on the EEPROMs
//!    (`eeprom::persist`), bit-banged on port 4 with ACK polling during each write cycle;
//! 5. back to SLEEP until the next step's tick.
//!
//! Every register access goes through the bus and is charged by area; instruction fetches and
//! register-only code are charged from their instruction sequences ([`charging`]); the learner's
//! arithmetic from `nn_q15`'s H8 meter. The tick interrupt is taken whenever it is pending
//! between two charges (interrupts are enabled after boot), and its states are reported apart.
//!
//! # Choices where the spec is silent
//! - Tick 10 ms (ITU0, φ/8, compare match A clears the counter); the step period must be a
//!   whole number of ticks (0.45 s = 45, 0.60 s = 60). The first step comes with the first tick
//!   after boot.
//! - PWM: ITU1 (left) and ITU2 (right) in PWM mode at φ/8 with GRA = 1249: a 400 µs period
//!   (2.5 kHz at 25 MHz); 0.3 v = 375 counts high (GRB = 374); v = 100 % duty with GRB = 1250,
//!   above GRA, the hardware manual's recipe for a 100 % PWM output (the GRB compare match
//!   never comes, so the pin stays high from the GRA match on). GRB = GRA would not do: with
//!   equal compare values the PWM output does not change at all (it holds its level, low after
//!   reset).
//!   Direction: PB0/PB1 = IN1/IN2 of the left H-bridge, PB2/PB3 of the right (H/L forward,
//!   L/H reverse).
//! - The sample is taken at the step's tick: each sensor's held value dates from its latest
//!   refresh, at most one sensor period (≤ 47.9 ms) earlier, while the robot was still running
//!   the previous behaviour.
//! - The record's payload is the weight matrix as the H8 holds it: row by row, big-endian i16.

pub mod charging;
pub mod regs;
pub mod timeline_save;

use eeprom::persist::{Persistence, Record, RecordLayout};
use eeprom::{I2cMaster, MasterTiming};
use nn_q15::cost::Insn;
use nn_q15::{
    Behaviour, DynLearner, H8Meter, InputLayout, Params, Phase, Q15, ShapeError, StepOut,
    UpdateKind, ram_items,
};

use crate::board::RobotBoard;
use crate::ram::{RamMap, RamOverflow};
use charging::{FETCH_STATES, Fw, FwPins, SLEEP_STATES};
use h8_3052f::mcu::Mcu;
use h8_3052f::pins::Board;
use h8300h::bus::FastPathHints;
use regs::*;
use timeline_save::SaveTimelines;

/// What the model asks of the MCU besides the bus: the EEPROM bus for its transaction-level
/// save ([`ControllerConfig::fast_forward`]), which no program on the chip could reach and
/// the core's [`h8300h::bus::Bus`] therefore does not carry (the ADF poll's shortcut uses
/// [`FastPathHints::reads_stable_until`], as the core's loop fast-forwarding does). Implemented
/// for an [`Mcu`] on the robot's board ([`RobotBoard`], which holds the EEPROMs); a bus that
/// answers neither (the defaults, as a test's wrapper around an MCU may) runs the model
/// register by register and I²C pin by pin, with the same results.
pub trait ModelBus: FastPathHints {
    /// The EEPROM bus behind port 4, for the timeline save that acts on the chips at transaction
    /// level with exactly the pin-level outcome ([`timeline_save`]). `None`: pin-level access only.
    fn eeprom_bus(&mut self) -> Option<&mut eeprom::I2cBus> {
        None
    }
}

impl<W: Board> ModelBus for Mcu<RobotBoard<W>> {
    fn eeprom_bus(&mut self) -> Option<&mut eeprom::I2cBus> {
        Some(self.board_mut().eeproms_mut())
    }
}

/// The tick period: 10 ms.
pub const TICK_S: f64 = 0.010;
/// PWM period in ITU counts at φ/8 (GRA + 1): 1250 counts, 400 µs at 25 MHz.
pub const PWM_PERIOD_COUNTS: u16 = 1250;
/// GRB for 100 % duty: above GRA (= [`PWM_PERIOD_COUNTS`] − 1), so its compare match never
/// comes and the output stays high (the H8/3052 hardware manual's PWM-mode 100 % setting).
pub const PWM_FULL_GRB: u16 = PWM_PERIOD_COUNTS;
/// Lowest φ the H8/3052F runs at (the chip's [`h8_3052f::mcu::MIN_CLOCK_HZ`]).
pub const CLOCK_MIN_HZ: u32 = h8_3052f::mcu::MIN_CLOCK_HZ;
/// Highest φ of the H8/3052F (the chip's [`h8_3052f::mcu::MAX_CLOCK_HZ`]).
pub const CLOCK_MAX_HZ: u32 = h8_3052f::mcu::MAX_CLOCK_HZ;
/// Longest step period accepted (10 minutes).
pub const MAX_STEP_PERIOD_S: f64 = 600.0;

/// What a step period may be, as messages say it ([`step_period_ok`]).
pub const STEP_PERIOD_VALID: &str =
    "a whole number of 10 ms ticks from 0.01 to 600 s (0.45 and 0.60 are the paper's)";

/// The one rule for a step period, wherever it is given (a scenario's
/// `timing.step_period_s`, `fit --step-period-s`, `cost --step-period-s`, the controller's
/// configuration): finite, a whole number of [`TICK_S`] ticks, from one tick to
/// [`MAX_STEP_PERIOD_S`].
#[must_use]
pub fn step_period_ok(step_period_s: f64) -> bool {
    let ticks = step_period_s / TICK_S;
    (TICK_S..=MAX_STEP_PERIOD_S).contains(&step_period_s) && (ticks - ticks.round()).abs() < 1e-9
}
/// Amplitude of the fresh random weights: uniform in ±0.5 (±16384 in Q15).
pub const INITIAL_WEIGHT_AMPLITUDE: i16 = 16384;
/// Most ACK polls per page write before the save gives up (well past a 5 ms write cycle).
pub const MAX_POLLS: u32 = 200;

/// The firmware's I²C bus timing, from the listing of `firmware/i2c.c` (states between the
/// edges its code makes; every one above DS21203's 400 kHz minima): SCL low 94 (a bit's low
/// half: the return from `clock`, the loop, the SDA write and the call: 92 or 96 by the bit's
/// value), SCL high 34 (`delay(2)`, the SDA sample, the shadow update), START hold 29 and
/// repeated-START setup 31 (`delay(2)` and a pin write), data setup 41 (the SDA write to the
/// SCL rise), STOP setup 29, bus free 90 (`delay(5)`, the return and the next START's first
/// pin write). The model's master keeps these as its minima, so its bus runs at the firmware's
/// pace (about 190 kHz instead of the chip's 400 kHz).
///
/// # Errors
/// [`eeprom::EepromError::InvalidClock`] for a clock the EEPROM model refuses.
pub fn firmware_i2c_timing(clock_hz: u32) -> Result<MasterTiming, eeprom::EepromError> {
    Ok(MasterTiming {
        clock: eeprom::clock::Clock::new(clock_hz)?,
        scl_low_states: 94,
        scl_high_states: 34,
        start_setup_states: 31,
        start_hold_states: 29,
        data_setup_states: 41,
        stop_setup_states: 29,
        bus_free_states: 90,
        poll_gap_states: POLL_GAP_STATES,
    })
}

/// The stack the model places in its RAM map: the firmware's measured high-water mark
/// (`h8swarm fit`: the lowest SP of a run with saves, the tick interrupt on top of the deepest
/// I²C call chain), so that the model's RAM total is the firmware's. The root package's fit
/// tests check that the firmware still measures this.
pub const MODEL_STACK_BYTES: u32 = 160;

/// States from the end of [`Controller::sleep_until_step`] to the end of the ADST write that
/// starts the step's A/D scan (the transcription in [`Controller::step_with`]: main's NEXT
/// update and JSR, robot_step's prologue and JSR, 62; ad_scan's set-up, 16; the write, 5): the
/// instant a firmware robot's step begins in the swarm, so that the world places model and
/// firmware robots at the same instants.
pub const SENSING_OFFSET_STATES: u64 = 62 + 16 + 5;

/// The firmware's pause between ACK polls, from the NACK's SCL fall to the repeated START's
/// first edge (from the listing): the return from `clock` and `write_byte` (54), the tests in
/// `i2c_ack_poll` (14), `delay16(833)` (4 + 833 · 6 = 5 002), the call of `repeated_start` and
/// its first pin write (41) — less the master's own pin operation (7).
pub const POLL_GAP_STATES: u64 = 54 + 14 + 5002 + 41 - 7;

/// main's test after each wake-up (from the listing): MOV.L @ticks:24,ER2 ; SUB.L ER3,ER2 ;
/// MOV.L ER2,ER2 ; BLT back to SLEEP.
const MAIN_TICK_TEST: [Insn; 4] = [Insn::MovLAbs24, Insn::Reg, Insn::Reg, Insn::Bcc8];
/// States of the random walk's draw in the firmware's robot_step (from the listing): JSR
/// @xorshift32 (10) and its 210 states (three shift loops of 13, 1 and 5 places, the loads and
/// stores, RTS), SUB.L, MOV.B @net_n_out:24, MOV.W E0,R0, EXTU.L (14), JSR @__mulsi3 (10) and
/// its 84 states (three MULXU.W), MOV.W E0,R0, EXTU.L (4).
pub const RANDOM_WALK_DRAW_STATES: u64 = 10 + 210 + 14 + 10 + 84 + 4;

/// The default wiring of the four IR sensors (front, rear, left, right): AN0–AN3 (docs/design.md §3.2).
pub const DEFAULT_SENSOR_CHANNELS: [u8; 4] = crate::wiring::AN_IR;

/// How the controller is set up.
#[derive(Clone, Debug, PartialEq)]
pub struct ControllerConfig {
    /// The MCU clock φ in Hz (2–25 MHz).
    pub clock_hz: u32,
    /// Enabled behaviours M (2: forward, backward; 4: all).
    pub behaviours: usize,
    /// History depth, bias and spare inputs.
    pub layout: InputLayout,
    /// η and T.
    pub params: Params,
    /// One record every this many steps (≥ 1).
    pub save_every_steps: u32,
    /// Step period in seconds: a whole number of 10 ms ticks.
    pub step_period_s: f64,
    /// Seed of the fresh random weights (used when no record is restored).
    pub weight_seed: u64,
    /// The A/D input (AN0–AN7) each sensor is wired to, in sensor order front, rear, left,
    /// right; [`DEFAULT_SENSOR_CHANNELS`] by default. The four must be distinct and in one scan
    /// group (AN0–AN3 or AN4–AN7), since the firmware converts them in one scan.
    pub sensor_channels: [u8; 4],
    /// Emulation shortcuts with identical results (tested): while asleep between two steps,
    /// only the first and the last tick interrupt are emulated register by register and the
    /// identical ones in between are charged as such; and the interrupt controller is only
    /// asked once a tick is due.
    pub fast_forward: bool,
}

impl ControllerConfig {
    /// The arena's controller (paper env. 2): four behaviours, η = 0.001, T = 10, 0.45 s,
    /// one record every 20 steps, φ = 25 MHz.
    #[must_use]
    pub fn arena(weight_seed: u64) -> Self {
        Self {
            clock_hz: crate::board::CLOCK_HZ,
            behaviours: 4,
            layout: InputLayout::DEFAULT,
            params: Params::ARENA,
            save_every_steps: eeprom::persist::DEFAULT_SAVE_EVERY_STEPS,
            step_period_s: 0.45,
            weight_seed,
            sensor_channels: DEFAULT_SENSOR_CHANNELS,
            fast_forward: true,
        }
    }

    /// The corridor's controller (paper env. 1): forward and backward, η = 0.1, T = 10, 0.60 s.
    #[must_use]
    pub fn corridor(weight_seed: u64) -> Self {
        Self {
            behaviours: 2,
            params: Params::CORRIDOR,
            step_period_s: 0.60,
            ..Self::arena(weight_seed)
        }
    }

    /// Number of inputs N.
    #[must_use]
    pub fn n_inputs(&self) -> usize {
        self.layout.n_inputs(self.behaviours)
    }
}

/// A controller that cannot be built or cannot run.
#[derive(Debug, thiserror::Error)]
pub enum ControllerError {
    /// A configuration value out of range.
    #[error("{field} = {value}: {valid}")]
    Config {
        /// Which setting.
        field: &'static str,
        /// Its value as given.
        value: String,
        /// What would be valid.
        valid: String,
    },
    /// The controller's state does not fit the on-chip RAM.
    #[error(transparent)]
    Ram(#[from] RamOverflow),
    /// The network shape is outside the learner's bounds.
    #[error("the network cannot be built")]
    Shape(#[from] ShapeError),
    /// The EEPROM record layout or a save failed.
    #[error("EEPROM record")]
    Persist(#[from] eeprom::PersistError),
    /// The I²C master timing could not be set up for this clock.
    #[error("I2C timing")]
    I2c(#[from] eeprom::EepromError),
    /// SLEEP returned without the tick interrupt pending.
    #[error("SLEEP at state {now} woke without the tick interrupt (ITU0 compare match A) pending")]
    NoTick {
        /// The clock when it happened.
        now: u64,
    },
}

/// States of one step by phase, excluding the tick interrupts taken during it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PhaseStates {
    /// A/D scan, du lookup.
    pub adc: u64,
    /// The learner's input phase (D, E, input vector).
    pub input: u64,
    /// The learner's update.
    pub update: u64,
    /// The learner's forward pass.
    pub forward: u64,
    /// Motor set-up.
    pub motors: u64,
    /// The EEPROM save (0 when none was due).
    pub save: u64,
    /// Tick interrupts taken during the step (entry to RTE).
    pub isr: u64,
    /// The main loop's own code in the step (the calls, the behaviour, the save test).
    pub main: u64,
}

impl PhaseStates {
    /// The step's own work: every phase but the interrupts.
    #[must_use]
    pub const fn work(&self) -> u64 {
        self.adc + self.input + self.update + self.forward + self.motors + self.save + self.main
    }
}

/// What one save did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SaveSummary {
    /// The record's sequence number.
    pub sequence: u32,
    /// The chip written (0x50 or 0x51).
    pub chip: u8,
    /// Pages written (body pages, then the commit page).
    pub pages: usize,
    /// ACK polls in total.
    pub polls: u32,
    /// Record bytes sent.
    pub record_bytes: usize,
}

/// What one step did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StepReport {
    /// The step's index from boot (0 = first step).
    pub step: u64,
    /// The clock when the step began.
    pub start_states: u64,
    /// The proximities read (du).
    pub p: [u8; 4],
    /// D(t).
    pub d: i16,
    /// E(t−1).
    pub e: i16,
    /// The update's branch (None at the first step).
    pub update: Option<UpdateKind>,
    /// The behaviour the motors run (the network's choice, or the forced one).
    pub behaviour: Behaviour,
    /// States by phase.
    pub phases: PhaseStates,
    /// The save, when one was due.
    pub saved: Option<SaveSummary>,
}

/// What boot did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BootReport {
    /// The sequence number of the restored record, or None (fresh random weights).
    pub restored: Option<u32>,
    /// States from reset to the end of boot.
    pub states: u64,
}

/// What the sleep between two steps did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SleepReport {
    /// Tick interrupts taken while asleep.
    pub ticks: u64,
    /// States the CPU was busy while "asleep" (SLEEP, interrupt entry, handler, main loop).
    pub busy_states: u64,
    /// States elapsed in all.
    pub elapsed_states: u64,
}

/// The controller: configuration, learner, RAM placement and the firmware's variables.
#[derive(Clone, Debug)]
pub struct Controller {
    cfg: ControllerConfig,
    learner: DynLearner,
    ram: RamMap,
    persistence: Persistence,
    timing: MasterTiming,
    p4_shadow: u8,
    ticks: u64,
    next_step_tick: u64,
    ticks_per_step: u64,
    tick_counts: u16,
    steps: u64,
    next_sequence: u32,
    booted: bool,
    /// The next tick's instant, once known (see [`ControllerConfig::fast_forward`]).
    next_tick_at: Option<u64>,
    /// The timeline save's timelines (with [`ControllerConfig::fast_forward`]).
    timelines: Option<std::sync::Arc<SaveTimelines>>,
    /// States of one tick interrupt (entry to RTE), as measured on this MCU.
    isr_states: Option<u64>,
}

fn config_error(
    field: &'static str,
    value: impl ToString,
    valid: impl Into<String>,
) -> ControllerError {
    ControllerError::Config {
        field,
        value: value.to_string(),
        valid: valid.into(),
    }
}

/// Checks a sensor wiring: the four A/D inputs must exist (AN0–AN7), differ, and share a scan
/// group (what [`Controller::new`] checks of [`ControllerConfig::sensor_channels`]).
///
/// # Errors
/// [`ControllerError::Config`] naming the first sensor whose channel is not valid.
pub fn check_sensor_channels(ch: &[u8; 4]) -> Result<(), ControllerError> {
    const FIELDS: [&str; 4] = [
        "sensor_channels[0] (front)",
        "sensor_channels[1] (rear)",
        "sensor_channels[2] (left)",
        "sensor_channels[3] (right)",
    ];
    for (k, &c) in ch.iter().enumerate() {
        if c > 7 {
            return Err(config_error(
                FIELDS[k],
                c,
                "an analog input the H8/3052F has: 0 to 7 (AN0 to AN7)",
            ));
        }
        if ch[..k].contains(&c) {
            return Err(config_error(
                FIELDS[k],
                c,
                "a channel no other sensor uses (each sensor needs its own A/D input)",
            ));
        }
        if c / 4 != ch[0] / 4 {
            return Err(config_error(
                FIELDS[k],
                c,
                format!(
                    "a channel in the scan group of the front sensor's AN{} (AN{} to AN{}): the firmware converts the four sensors in one scan",
                    ch[0],
                    ch[0] / 4 * 4,
                    ch[0] / 4 * 4 + 3
                ),
            ));
        }
    }
    Ok(())
}

impl Controller {
    /// Checks the configuration, places the controller's state in the on-chip RAM and builds
    /// the learner (its weights are set at boot).
    ///
    /// # Errors
    /// [`ControllerError::Config`] for a value out of range, [`ControllerError::Ram`] naming the
    /// item that overflows the 8 KB, [`ControllerError::Shape`] for a network beyond the
    /// learner's no-overflow bound.
    pub fn new(cfg: ControllerConfig) -> Result<Self, ControllerError> {
        if !(CLOCK_MIN_HZ..=CLOCK_MAX_HZ).contains(&cfg.clock_hz) {
            return Err(config_error(
                "clock_hz",
                cfg.clock_hz,
                format!("the H8/3052F runs at {CLOCK_MIN_HZ} to {CLOCK_MAX_HZ} Hz (2 to 25 MHz)"),
            ));
        }
        if !(2..=4).contains(&cfg.behaviours) {
            return Err(config_error(
                "behaviours",
                cfg.behaviours,
                "2 (forward, backward) to 4 (all four behaviours)",
            ));
        }
        check_sensor_channels(&cfg.sensor_channels)?;
        if cfg.save_every_steps == 0 {
            return Err(config_error(
                "save_every_steps",
                0,
                "at least 1 (one record every S steps)",
            ));
        }
        if !step_period_ok(cfg.step_period_s) {
            return Err(config_error(
                "step_period_s",
                cfg.step_period_s,
                STEP_PERIOD_VALID,
            ));
        }
        let tick_counts = (TICK_S * f64::from(cfg.clock_hz) / PRESCALE as f64).round();
        // 2–25 MHz gives 2 500 to 31 250 counts: always a 16-bit GRA.
        let tick_counts = tick_counts as u16;

        let n_in = cfg.n_inputs();
        let n_out = cfg.behaviours;
        let ram = Self::place_ram(n_in, n_out)?;
        let layout = RecordLayout::new(0, u16::try_from(2 * n_in * n_out).unwrap_or(u16::MAX))?;
        let persistence = Persistence::new(layout, MAX_POLLS)?;
        let learner = DynLearner::new(
            n_out,
            cfg.layout,
            cfg.params,
            &vec![Q15::ZERO; n_in.min(nn_q15::MAX_INPUTS) * n_out],
        )?;
        let timing = firmware_i2c_timing(cfg.clock_hz)?;
        let cfg_fast = cfg.fast_forward;
        Ok(Self {
            ticks_per_step: (cfg.step_period_s / TICK_S).round() as u64,
            tick_counts,
            cfg,
            learner,
            ram,
            persistence,
            timing,
            p4_shadow: 0,
            ticks: 0,
            next_step_tick: 1,
            steps: 0,
            next_sequence: 0,
            booted: false,
            next_tick_at: None,
            timelines: if cfg_fast {
                Some(SaveTimelines::shared(timing)?)
            } else {
                None
            },
            isr_states: None,
        })
    }

    /// The RAM items of a controller with N inputs and M outputs, placed.
    ///
    /// # Errors
    /// [`RamOverflow`] naming the first item that does not fit.
    pub fn place_ram(n_in: usize, n_out: usize) -> Result<RamMap, RamOverflow> {
        let mut ram = RamMap::new();
        for item in ram_items(n_in, n_out) {
            ram.place(item.name, item.bytes)?;
        }
        ram.place("proximities p (u8 x 4)", 4)?;
        ram.place("tick counter, next step tick, step counter (u32 each)", 12)?;
        ram.place("record sequence (u32), save countdown (u16)", 6)?;
        ram.place("EEPROM page buffer (64 bytes)", 64)?;
        ram.place("EEPROM commit block", eeprom::persist::COMMIT_BYTES as u32)?;
        ram.place("xorshift32 state (u32)", 4)?;
        ram.place(
            "stack (deepest call chain + tick interrupt)",
            MODEL_STACK_BYTES,
        )?;
        Ok(ram)
    }

    /// The configuration.
    #[must_use]
    pub fn config(&self) -> &ControllerConfig {
        &self.cfg
    }

    /// The RAM placement.
    #[must_use]
    pub fn ram(&self) -> &RamMap {
        &self.ram
    }

    /// The learner (its weights, shape and parameters).
    #[must_use]
    pub fn learner(&self) -> &DynLearner {
        &self.learner
    }

    /// Changes the learning parameters (η = 0 freezes learning).
    pub fn set_params(&mut self, params: Params) {
        self.learner.set_params(params);
    }

    /// Ticks per step.
    #[must_use]
    pub const fn ticks_per_step(&self) -> u64 {
        self.ticks_per_step
    }

    /// Steps run since boot.
    #[must_use]
    pub const fn steps(&self) -> u64 {
        self.steps
    }

    /// States of one tick interrupt (entry to RTE) as measured on this MCU, once one was taken.
    #[must_use]
    pub const fn isr_states(&self) -> Option<u64> {
        self.isr_states
    }

    /// EEPROM bytes written per save (record bytes on the wire).
    #[must_use]
    pub fn bytes_per_save(&self) -> usize {
        self.persistence
            .layout()
            .bytes_per_save(self.weight_bytes())
    }

    /// EEPROM pages written per save.
    #[must_use]
    pub fn pages_per_save(&self) -> usize {
        self.persistence
            .layout()
            .pages_per_record(self.weight_bytes())
    }

    fn weight_bytes(&self) -> usize {
        2 * self.learner.weights().len()
    }

    /// Boots on `bus` (the MCU after reset or after a power cut): sets up the hardware,
    /// restores the newest valid record or draws fresh weights, enables interrupts. The first
    /// step comes with the first tick.
    ///
    /// # Errors
    /// None from the hardware model today; kept fallible for the bus errors of later boards.
    pub fn boot<B: ModelBus>(&mut self, bus: &mut B) -> Result<BootReport, ControllerError> {
        let t0 = bus.now();
        self.ticks = 0;
        self.next_step_tick = 1;
        self.steps = 0;
        self.p4_shadow = 0;
        self.next_tick_at = None;
        self.learner.restart();
        let mut ticks = 0u64;
        let restored = {
            let mut fw = Fw::new(bus, &mut ticks, false);
            // Stack pointer, ports: P4DR = 0 and P4DDR = 0 (both I2C lines released, ready to be
            // pulled by DDR) with the SDA/SCL pull-ups on; port B bits 0-3 outputs,
            // H-bridges coasting.
            fw.code(&[Insn::ImmL, Insn::Reg]);
            fw.write8(P4DR, 0);
            fw.write8(P4DDR, 0);
            fw.code(&[Insn::Reg]);
            fw.write8(P4PCR, SDA_BIT | SCL_BIT);
            // The bumpers' pull-ups (P2.0-P2.3), so that a released switch reads high.
            fw.code(&[Insn::Reg]);
            fw.write8(P2PCR, 0x0F);
            fw.write8(PBDR, 0);
            fw.code(&[Insn::Reg]);
            fw.write8(PBDDR, 0x0F);
            // ITU0: 10 ms tick; ITU1/2: PWM at φ/8, coasting duty; start all three.
            fw.code(&[Insn::Reg]);
            fw.write8(ITU0 + TCR, TCR_CLEAR_ON_GRA_PHI8);
            fw.write8(ITU1 + TCR, TCR_CLEAR_ON_GRA_PHI8);
            fw.write8(ITU2 + TCR, TCR_CLEAR_ON_GRA_PHI8);
            fw.code(&[Insn::ImmW]);
            fw.write16(ITU0 + GRA, self.tick_counts - 1);
            fw.code(&[Insn::ImmW]);
            fw.write16(ITU1 + GRA, PWM_PERIOD_COUNTS - 1);
            fw.write16(ITU2 + GRA, PWM_PERIOD_COUNTS - 1);
            fw.write16(ITU1 + GRB, PWM_FULL_GRB);
            fw.write16(ITU2 + GRB, PWM_FULL_GRB);
            fw.code(&[Insn::Reg]);
            fw.write8(ITU0 + TIER, IMA);
            fw.code(&[Insn::Reg]);
            fw.write8(TMDR, 0b0000_0110);
            fw.code(&[Insn::Reg]);
            fw.write8(TSTR, 0b0000_0111);
            fw.code(&[Insn::Reg, Insn::MovLAbs16, Insn::MovLAbs16, Insn::MovLAbs16]);

            // Restore the newest valid record, if its size matches this network.
            let expected = self.weight_bytes();
            let recovery = {
                let mut pins = FwPins {
                    fw: &mut fw,
                    shadow: &mut self.p4_shadow,
                };
                let mut master = I2cMaster::new(&mut pins, self.timing);
                master.init();
                let _ = master.bus_clear();
                self.persistence.recover(&mut master)
            };
            fw.code(&[Insn::JsrAbs24, Insn::Rts]);
            let usable = recovery
                .newest
                .as_ref()
                .filter(|r| r.payload.len() == expected);
            // The firmware checks the commit blocks and the body it read with CRC-16.
            let checked: usize = 2 * eeprom::persist::COMMIT_BYTES
                + recovery.newest.as_ref().map_or(0, |r| r.payload.len());
            fw.lump(crc16_states_estimate(checked));
            match usable {
                Some(record) => {
                    let weights: Vec<Q15> = record
                        .payload
                        .chunks_exact(2)
                        .map(|b| Q15::from_bits(i16::from_be_bytes([b[0], b[1]])))
                        .collect();
                    // Lengths match by the filter above.
                    let _ = self.learner.set_weights(&weights);
                    self.next_sequence = record.sequence.wrapping_add(1);
                    Some(record.sequence)
                }
                None => {
                    let weights = fresh_weights(self.cfg.weight_seed, self.learner.weights().len());
                    fw.lump(XORSHIFT_WEIGHT_STATES * weights.len() as u64);
                    let _ = self.learner.set_weights(&weights);
                    self.next_sequence = recovery.next_sequence();
                    None
                }
            }
        };
        // ANDC #H'7F,CCR: interrupts on.
        bus.internal(FETCH_STATES);
        self.ticks = ticks;
        self.booted = true;
        Ok(BootReport {
            restored,
            states: bus.now() - t0,
        })
    }

    /// Sleeps until the next step is due: SLEEP, the tick interrupt, the main loop's check,
    /// again and again.
    ///
    /// # Errors
    /// [`ControllerError::NoTick`] when SLEEP wakes without the tick pending (the ITU was
    /// stopped or reprogrammed behind the controller's back).
    pub fn sleep_until_step<B: ModelBus>(
        &mut self,
        bus: &mut B,
    ) -> Result<SleepReport, ControllerError> {
        let t0 = bus.now();
        let mut report = SleepReport::default();
        let period = u64::from(self.tick_counts) * PRESCALE;
        let mut ticks = self.ticks;
        let fast = self.cfg.fast_forward;
        let mut next_tick_at = self.next_tick_at;
        {
            let mut fw = Fw::new(bus, &mut ticks, true);
            fw.tick_period = period;
            while *fw.ticks < self.next_step_tick {
                fw.bus.internal(SLEEP_STATES);
                let asleep_from = fw.bus.now();
                let deadline = asleep_from + 2 * period;
                if !fw.bus.sleep_until_irq(deadline) || fw.bus.pending_irq() != Some(VECTOR_IMIA0) {
                    return Err(ControllerError::NoTick { now: fw.bus.now() });
                }
                // Woken at the tick's instant: from here on its successors' are known.
                let tick_at = fw.bus.now();
                let slept = tick_at - asleep_from;
                fw.next_tick_at = fast.then_some(tick_at);
                let isr_from = fw.isr_states;
                fw.tick_handler();
                self.isr_states = Some(fw.isr_states - isr_from);
                report.ticks += 1;
                // main after SLEEP: MOV.L @ticks:24,ER2 ; SUB.L ER3,ER2 ; MOV.L ER2,ER2 ; BLT
                // (ER3 holds next_step across the loop).
                fw.code(&MAIN_TICK_TEST);
                let busy = fw.bus.now() - asleep_from - slept + u64::from(SLEEP_STATES);
                report.busy_states += busy;
                let left = self.next_step_tick.saturating_sub(*fw.ticks);
                if fast && left >= 2 {
                    // The ticks between this one and the last are identical: SLEEP, entry,
                    // handler (TSR0 read with IMFA = 1 and cleared), RTE, the main loop. Charge
                    // them as such and wake for real at the last one, whose IMFA is pending.
                    let skipped = left - 1;
                    let last_at = tick_at + left * period;
                    *fw.ticks += skipped;
                    report.ticks += skipped;
                    report.busy_states += skipped * busy;
                    fw.bus.internal(SLEEP_STATES);
                    fw.idle(last_at - fw.bus.now());
                    fw.next_tick_at = Some(last_at);
                    fw.tick_handler();
                    report.ticks += 1;
                    fw.code(&MAIN_TICK_TEST);
                    report.busy_states += busy;
                }
            }
            next_tick_at = fw.next_tick_at.or(next_tick_at);
        }
        self.next_tick_at = if fast { next_tick_at } else { None };
        self.ticks = ticks;
        self.next_step_tick += self.ticks_per_step;
        report.elapsed_states = bus.now() - t0;
        Ok(report)
    }

    /// Runs one step now (call it after [`Self::sleep_until_step`]).
    ///
    /// # Errors
    /// [`ControllerError::Persist`] when a due save fails on the bus (a chip that never
    /// answers, say).
    pub fn step<B: ModelBus>(&mut self, bus: &mut B) -> Result<StepReport, ControllerError> {
        self.step_with(bus, None)
    }

    /// [`Self::step`], but the motors run `forced` instead of the network's choice when it is
    /// given (the random-walk control of docs/design.md §5: the learner still runs and costs what it
    /// costs, only its choice is not obeyed).
    ///
    /// # Errors
    /// As [`Self::step`].
    pub fn step_with<B: ModelBus>(
        &mut self,
        bus: &mut B,
        forced: Option<Behaviour>,
    ) -> Result<StepReport, ControllerError> {
        let start_states = bus.now();
        let mut ticks = self.ticks;
        let mut phases = PhaseStates::default();
        let step = self.steps;
        let due = (step + 1).is_multiple_of(u64::from(self.cfg.save_every_steps));
        let tick_period = u64::from(self.tick_counts) * PRESCALE;
        let mut next_tick_at = self.next_tick_at;
        let (p, out, behaviour, saved) = {
            let mut fw = Fw::new(bus, &mut ticks, true);
            fw.tick_period = tick_period;
            fw.next_tick_at = next_tick_at;
            // The steps below follow the firmware's listing (`firmware/build.sh --listing`):
            // main's loop after its due test fell through, robot_step, ad_scan and motors_set,
            // instruction by instruction, each I/O access at its place. Phases are counted as
            // the firmware's profile counts them: a routine from its first instruction to its
            // RTS; the calls belong to the caller (the main loop).
            let ((), mut main_states) = timed(&mut fw, main_calls_ad_scan);
            let (p, adc) = timed(&mut fw, |fw| self.ad_scan(fw));
            phases.adc = adc;
            main_states += timed(&mut fw, robot_step_calls_learner).1;
            let out = self.learn(&mut fw, &p, &mut phases);
            main_states += timed(&mut fw, |fw| robot_step_calls_motors_set(fw, forced)).1;
            let behaviour = forced.unwrap_or(out.behaviour);
            phases.motors = timed(&mut fw, |fw| motors_set(fw, behaviour)).1;
            let saved = self.save_when_due(&mut fw, due, &mut main_states, &mut phases)?;
            main_states += timed(&mut fw, robot_step_returns_to_main).1;
            phases.main = main_states;
            phases.isr = fw.isr_states;
            next_tick_at = fw.next_tick_at;
            (p, out, behaviour, saved)
        };
        self.next_tick_at = next_tick_at;
        self.ticks = ticks;
        self.steps += 1;
        Ok(StepReport {
            step,
            start_states,
            p,
            d: out.d,
            e: out.e,
            update: out.update,
            behaviour,
            phases,
            saved,
        })
    }

    /// Step 1, `ad_scan`: one scan of the sensors' group (AN0-AN3 by default), ADF polled, the
    /// scan stopped, the four codes through the du table. Returns the four sensor values.
    fn ad_scan<B: ModelBus>(&self, fw: &mut Fw<'_, B>) -> [u8; 4] {
        let group_ch = (self.cfg.sensor_channels[0] & 4) | 3;
        // MOV.B @cfg.channels:24,R2L ; AND.B #4 ; MOV.B R2L,R3L ; OR.B #3,R3L ; OR.B #H'3B,R2L ;
        // MOV.B R2L,@ADCSR:8.
        fw.code(&[Insn::MovBwAbs24, Insn::Reg, Insn::Reg, Insn::Reg, Insn::Reg]);
        fw.write8(ADCSR, ADCSR_ADST | ADCSR_SCAN | ADCSR_CKS | group_ch);
        self.poll_adf(fw);
        // OR.B #H'18,R3L ; MOV.B R3L,@ADCSR:8 (ADF read as 1, written 0; ADST off) ; SUB.B.
        fw.code(&[Insn::Reg]);
        fw.write8(ADCSR, ADCSR_SCAN | ADCSR_CKS | group_ch);
        fw.code(&[Insn::Reg]);
        let mut p = [0u8; 4];
        for (pk, &ch) in p.iter_mut().zip(&self.cfg.sensor_channels) {
            // SUB.L ; MOV.B ; MOV.L ; ADD.L ; MOV.B @(cfg.channels:24,ER2),R2L ; AND.L #3 ;
            // SHLL.L ; ADD.L #ADDRAH ; MOV.B @ER2,R2L (AN0/AN4 in ADDRA, AN1/AN5 in ADDRB …).
            fw.code(&[
                Insn::Reg,
                Insn::Reg,
                Insn::Reg,
                Insn::Reg,
                Insn::MovBwDisp24,
                Insn::ImmL,
                Insn::Reg,
                Insn::ImmL,
            ]);
            let code8 = fw.read8(ADDRAH + 2 * u32::from(ch & 3));
            // EXTU.W ; EXTU.L ; MOV.B @(du_table:24,ER2),R2L ; MOV.B R2L,@ER3 ; ADD.B ;
            // CMP.B #3 ; BLS.
            fw.code(&[
                Insn::Reg,
                Insn::Reg,
                Insn::MovBwDisp24,
                Insn::MovBwInd,
                Insn::Reg,
                Insn::Reg,
                Insn::Bcc8,
            ]);
            *pk = sensors::DU_TABLE[usize::from(code8)];
        }
        fw.code(&[Insn::Rts]);
        p
    }

    /// `ad_scan`'s wait for the scan's end: `1: MOV.B @ADCSR:8,R2L ; BGE 1b` until ADF reads 1.
    fn poll_adf<B: ModelBus>(&self, fw: &mut Fw<'_, B>) {
        // 2 + 3 + 4 states a poll, the read ending 5 states in.
        const POLL_STATES: u64 = 9;
        const POLL_READ_END: u64 = 5;
        loop {
            let v = fw.read8(ADCSR);
            fw.code(&[Insn::Bcc8]);
            if v & ADCSR_ADF != 0 {
                break;
            }
            // Shortcut: every poll whose read ends before the next peripheral event reads
            // the same; let them pass unread, unless the tick could come meanwhile.
            if self.cfg.fast_forward
                && v & ADCSR_ADF == 0
                && let (Some(event), Some(tick)) = (
                    fw.bus.reads_stable_until(ADCSR).filter(|&e| e != u64::MAX),
                    fw.next_tick_at,
                )
            {
                let now = fw.now();
                let skip = event
                    .saturating_sub(now + POLL_READ_END)
                    .div_ceil(POLL_STATES);
                if skip > 0 && now + skip * POLL_STATES < tick {
                    fw.idle(skip * POLL_STATES);
                }
            }
        }
    }

    /// Step 2, the learner on the sensor values `p`, charged phase by phase (input, update,
    /// forward) from its meter, re-derived from the firmware's learner routines, calls and
    /// returns included.
    fn learn<B: ModelBus>(
        &mut self,
        fw: &mut Fw<'_, B>,
        p: &[u8; 4],
        phases: &mut PhaseStates,
    ) -> StepOut {
        let mut meter = H8Meter::new();
        let out = self.learner.step(p, &mut meter);
        for (phase, slot) in [
            (Phase::Input, &mut phases.input),
            (Phase::Update, &mut phases.update),
            (Phase::Forward, &mut phases.forward),
        ] {
            *slot = timed(fw, |fw| fw.lump(meter.states(phase))).1;
        }
        out
    }

    /// Step 4, robot_step's save test (MOV.W @cfg.save_every:24 ; BEQ ; MOV.W @save_count:24 ;
    /// ADDS ; CMP.W ; BCS), and when `due` the record written: SUB.W ;
    /// MOV.W R2,@save_count:24 ; JSR @record_save ; BRA — else MOV.W R2,@save_count:24.
    /// robot_step's instructions go to `main_states`, record_save's to `phases.save`.
    fn save_when_due<B: ModelBus>(
        &mut self,
        fw: &mut Fw<'_, B>,
        due: bool,
        main_states: &mut u64,
        phases: &mut PhaseStates,
    ) -> Result<Option<SaveSummary>, ControllerError> {
        let m = Mark::new(fw);
        fw.code(&[
            Insn::MovBwAbs24,
            Insn::Bcc8,
            Insn::MovBwAbs24,
            Insn::Reg,
            Insn::Reg,
            Insn::Bcc8,
        ]);
        if !due {
            fw.code(&[Insn::MovBwAbs24]);
            *main_states += m.done(fw);
            return Ok(None);
        }
        fw.code(&[Insn::Reg, Insn::MovBwAbs24, Insn::JsrAbs24]);
        *main_states += m.done(fw);
        let (summary, save_states) = timed(fw, |fw| self.save(fw));
        let summary = summary?;
        phases.save = save_states;
        *main_states += timed(fw, |fw| fw.code(&[Insn::Bcc8])).1;
        Ok(Some(summary))
    }

    /// Writes the weights as the next A/B record.
    fn save<B: ModelBus>(&mut self, fw: &mut Fw<'_, B>) -> Result<SaveSummary, ControllerError> {
        let payload: Vec<u8> = self
            .learner
            .weights()
            .iter()
            .flat_map(|w| w.to_bits().to_be_bytes())
            .collect();
        let record = Record {
            sequence: self.next_sequence,
            payload,
        };
        // record_save's own code (from the listing; the I²C routines run as the master below):
        // the entry with the body CRC (two calls of crc16), each page gathered byte by byte
        // into the page buffer and written, then the commit block with its CRC.
        let (commit, body) = self.persistence.layout().encode(&record)?;
        fw.lump(SAVE_ENTRY_STATES + crc16_states(&body[..body.len() - 2], 2));
        fw.lump(page_gather_states(body.len()));
        fw.lump(SAVE_COMMIT_STATES + crc16_states(&commit[..commit.len() - 2], 1));
        let report = if let (Some(timelines), Some(isr), true) = (
            self.timelines.as_deref(),
            self.isr_states,
            fw.bus.eeprom_bus().is_some(),
        ) {
            timeline_save::save(fw, &self.persistence, timelines, isr, &record)?
        } else {
            let mut pins = FwPins {
                fw,
                shadow: &mut self.p4_shadow,
            };
            let mut master = I2cMaster::new(&mut pins, self.timing);
            self.persistence.save(&mut master, &record)?
        };
        self.next_sequence = self.next_sequence.wrapping_add(1);
        Ok(SaveSummary {
            sequence: report.sequence,
            chip: report.chip,
            pages: report.pages_written,
            polls: report.polls_per_page.iter().sum(),
            record_bytes: report.record_bytes,
        })
    }
}

/// Measures a phase: the clock and the interrupt states at its start.
struct Mark {
    t0: u64,
    isr0: u64,
}

impl Mark {
    fn new<B: ModelBus>(fw: &Fw<'_, B>) -> Self {
        Self {
            t0: fw.now(),
            isr0: fw.isr_states,
        }
    }

    /// States of the phase, interrupts excluded.
    fn done<B: ModelBus>(&self, fw: &Fw<'_, B>) -> u64 {
        (fw.now() - self.t0) - (fw.isr_states - self.isr0)
    }
}

/// Runs `phase` on `fw` and returns its result with its states, interrupts excluded (see
/// [`Mark`]).
fn timed<'a, B: ModelBus, R>(
    fw: &mut Fw<'a, B>,
    phase: impl FnOnce(&mut Fw<'a, B>) -> R,
) -> (R, u64) {
    let m = Mark::new(fw);
    let r = phase(fw);
    (r, m.done(fw))
}

/// main: NEXT += K (MOV.W @cfg.ticks_per_step:24 ; EXTU.L ; ADD.L ; MOV.L ER2,@next:24) ;
/// JSR @robot_step. robot_step: SUBS ; PUSH.L ER4 ; MOV.L ER7,ER4 ; ADDS ; MOV.L ER4,ER0 ;
/// JSR @ad_scan.
fn main_calls_ad_scan<B: ModelBus>(fw: &mut Fw<'_, B>) {
    fw.code(&[
        Insn::MovBwAbs24,
        Insn::Reg,
        Insn::Reg,
        Insn::MovLAbs24,
        Insn::JsrAbs24,
        Insn::Reg,
        Insn::PushPopL,
        Insn::Reg,
        Insn::Reg,
        Insn::Reg,
        Insn::JsrAbs24,
    ]);
}

/// robot_step after ad_scan: MOV.L ER4,ER0 ; JSR @learner_step.
fn robot_step_calls_learner<B: ModelBus>(fw: &mut Fw<'_, B>) {
    fw.code(&[Insn::Reg, Insn::JsrAbs24]);
}

/// robot_step after the learner: MOV.B @cfg.flags:24,R2L ; BTST #1 ; BEQ — and in the random
/// walk (a `forced` behaviour) the draw (JSR @xorshift32 … JSR @__mulsi3 …, 332 states from the
/// listing) — then MOV.B R0L,@behaviour:24 ; JSR @motors_set.
fn robot_step_calls_motors_set<B: ModelBus>(fw: &mut Fw<'_, B>, forced: Option<Behaviour>) {
    fw.code(&[Insn::MovBwAbs24, Insn::Reg, Insn::Bcc8]);
    if forced.is_some() {
        fw.lump(RANDOM_WALK_DRAW_STATES);
    }
    fw.code(&[Insn::MovBwAbs24, Insn::JsrAbs24]);
}

/// Step 3, `motors_set`: the behaviour table's row into GRB1, GRB2 and port B.
fn motors_set<B: ModelBus>(fw: &mut Fw<'_, B>, behaviour: Behaviour) {
    // EXTU.W ; EXTU.L ; MOV.L ; SHLL.L ; ADD.L ; SHLL.L ; ADD.L #motor_table ;
    // MOV.W @ER2,R3 ; MOV.W R3,@GRB1:16 ; MOV.W @(2,ER2),R3 ; MOV.W R3,@GRB2:16 ;
    // MOV.B @(4,ER2),R2L ; MOV.B R2L,@PBDR:8 ; RTS.
    fw.code(&[
        Insn::Reg,
        Insn::Reg,
        Insn::Reg,
        Insn::Reg,
        Insn::Reg,
        Insn::Reg,
        Insn::ImmL,
        Insn::MovBwInd,
    ]);
    let (left, right, dir) = motor_row(behaviour);
    fw.write16(ITU1 + GRB, left);
    fw.code(&[Insn::MovBwAbs16]);
    fw.write16(ITU2 + GRB, right);
    fw.code(&[Insn::MovBwAbs16]);
    fw.write8(PBDR, dir);
    fw.code(&[Insn::Rts]);
}

/// robot_step's end: steps++ (MOV.L @steps:24 ; ADDS ; MOV.L) ; POP.L ER4 ; ADDS ; RTS.
/// Then main: BRA ; MOV.L @ticks:24 ; MOV.L @next:24 ; SUB.L ; MOV.L ; BGE (not taken).
fn robot_step_returns_to_main<B: ModelBus>(fw: &mut Fw<'_, B>) {
    fw.code(&[
        Insn::MovLAbs24,
        Insn::Reg,
        Insn::MovLAbs24,
        Insn::PushPopL,
        Insn::Reg,
        Insn::Rts,
        Insn::Bcc8,
        Insn::MovLAbs24,
        Insn::MovLAbs24,
        Insn::Reg,
        Insn::Reg,
        Insn::Bcc8,
    ]);
}

/// GRB1, GRB2 and the port-B direction bits for a behaviour (docs/design.md §3.5: forward (v, v),
/// backward (−v, −v), turn-left-forward (0.3 v, v), turn-right-forward (v, 0.3 v)).
#[must_use]
pub fn motor_row(b: Behaviour) -> (u16, u16, u8) {
    const FULL: u16 = PWM_FULL_GRB;
    // 0.3 v: 375 of 1250 counts high.
    const SLOW: u16 = (PWM_PERIOD_COUNTS * 3).div_ceil(10) - 1;
    const LEFT_FWD: u8 = 0b0001;
    const LEFT_REV: u8 = 0b0010;
    const RIGHT_FWD: u8 = 0b0100;
    const RIGHT_REV: u8 = 0b1000;
    match b {
        Behaviour::Forward => (FULL, FULL, LEFT_FWD | RIGHT_FWD),
        Behaviour::Backward => (FULL, FULL, LEFT_REV | RIGHT_REV),
        Behaviour::TurnLeftForward => (SLOW, FULL, LEFT_FWD | RIGHT_FWD),
        Behaviour::TurnRightForward => (FULL, SLOW, LEFT_FWD | RIGHT_FWD),
    }
}

/// States of one fresh weight from xorshift32 (an estimate of `fresh_weights` in the firmware's
/// `robot.c`; the boot is not calibrated against the firmware): three shift-and-XOR
/// rounds (13, 17 and 5 one-bit shifts of a long), the 15-bit extraction (17 shifts), the
/// offset, the store and the loop: (13 + 17 + 5 + 17) · 2 + 3 · (2 + 2) + 2 + 2 + 4 + 4 + 2 + 6.
pub const XORSHIFT_WEIGHT_STATES: u64 =
    (13 + 17 + 5 + 17) * 2 + 3 * (2 + 2) + 2 + 2 + 4 + 4 + 2 + 6;

/// Fresh weights: xorshift32 (13, 17, 5) seeded from `seed`, each weight the top 15 bits less
/// 2^14, so uniform in [−16384, 16383] (±0.5).
#[must_use]
pub fn fresh_weights(seed: u64, n: usize) -> Vec<Q15> {
    // Fold the 64-bit seed and keep the state non-zero (xorshift's one forbidden state).
    let mut x = ((seed ^ (seed >> 32)) as u32) | 1;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            Q15::from_bits(((x >> 17) as i32 - i32::from(INITIAL_WEIGHT_AMPLITUDE)) as i16)
        })
        .collect()
}

/// States of the firmware's `crc16` over `bytes` in `calls` calls (from the listing): 42 per
/// call (PUSH.L, two moves; the final test, EXTU.L, POP.L, RTS), 148 per byte (the loop test,
/// the load and the XOR into the high byte, the bit counter, eight bits of MOV.W, BGE, SHLL.W,
/// ADD.B, BNE at 14 states, the byte loop's SUBS and BRA) and 14 more for each bit that XORs
/// the polynomial (MOV.W, EXTU.L, SHLL.L, MOV.W, XOR.W #H'1021, BRA instead of SHLL.W). The
/// XORs are counted by `eeprom`'s CRC, the one the records are checked with
/// ([`eeprom::crc::crc16_update_counting`]).
#[must_use]
pub fn crc16_states(bytes: &[u8], calls: u64) -> u64 {
    let mut crc = eeprom::crc::CRC16_INIT;
    let mut xors = 0u64;
    for &b in bytes {
        let (next, n) = eeprom::crc::crc16_update_counting(crc, b);
        crc = next;
        xors += u64::from(n);
    }
    42 * calls + bytes.len() as u64 * 148 + 14 * xors
}

/// record_save's entry up to the body's first page (from the listing): frame and registers
/// (36), the chip from the sequence (24), `payload_bytes` with its `__mulsi3` (138), the
/// header via `put_u32` (62), the length bytes (18), the two calls of `crc16` and their set-up
/// (66, the routine itself in [`crc16_states`]), the CRC bytes and the body's length (30), the
/// loop's first test (30).
const SAVE_ENTRY_STATES: u64 = 404;
/// record_save's commit block (from the listing): the magic, version and reserved byte (40),
/// the sequence via `put_u32` (64), length and body CRC (44), the CRC call's set-up (24), its
/// bytes (16), `write_page`'s call and its own code around the I²C routines (144), the
/// sequence's increment (28) and the return (46).
const SAVE_COMMIT_STATES: u64 = 420;

/// record_save gathering a body of `body_len` bytes into pages and writing each (from the
/// listing; the I²C routines apart): per page 50 to set up and 174 to call `write_page` and
/// test its result; per byte 42 (the store, the counters, the loop tests) and 16 for a header
/// byte, 36 for a weight byte, 56 for a CRC byte to fetch it; 12 fewer for the byte that
/// fills a page (the loop leaves at its first test).
#[must_use]
pub fn page_gather_states(body_len: usize) -> u64 {
    let len = body_len as u64;
    let pages = len.div_ceil(64);
    let full_pages = len / 64;
    let payload = len - 8;
    pages * (50 + 174) + len * 42 + 6 * 16 + payload * 36 + 2 * 56 - 12 * full_pages
}

/// The CRC routine's states for `n` bytes whose contents are not at hand (half the bits XOR the
/// polynomial on average): used for what recovery reads.
#[must_use]
pub fn crc16_states_estimate(n: usize) -> u64 {
    n as u64 * (10 + 8 * 12 + 6 + 4 * 4) + 4
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sensor_channels_must_exist_differ_and_share_a_scan_group() {
        for (ch, field, why) in [
            (
                [0, 1, 2, 8],
                "sensor_channels[3] (right) = 8",
                "0 to 7 (AN0 to AN7)",
            ),
            (
                [0, 1, 1, 3],
                "sensor_channels[2] (left) = 1",
                "no other sensor uses",
            ),
            ([4, 5, 6, 3], "sensor_channels[3] (right) = 3", "AN4 to AN7"),
        ] {
            let mut cfg = ControllerConfig::arena(1);
            cfg.sensor_channels = ch;
            let e = Controller::new(cfg).unwrap_err().to_string();
            assert!(e.starts_with(field) && e.contains(why), "{ch:?}: {e}");
        }
        let mut cfg = ControllerConfig::arena(1);
        cfg.sensor_channels = [7, 4, 5, 6];
        assert!(Controller::new(cfg).is_ok());
    }

    #[test]
    fn config_errors_name_the_setting() {
        let mut cfg = ControllerConfig::arena(1);
        cfg.clock_hz = 0;
        let e = Controller::new(cfg).unwrap_err().to_string();
        assert!(e.starts_with("clock_hz = 0"), "{e}");
        let mut cfg = ControllerConfig::arena(1);
        cfg.save_every_steps = 0;
        assert!(
            Controller::new(cfg)
                .unwrap_err()
                .to_string()
                .contains("save_every_steps")
        );
        let mut cfg = ControllerConfig::arena(1);
        cfg.step_period_s = 0.455;
        assert!(
            Controller::new(cfg)
                .unwrap_err()
                .to_string()
                .contains("whole number of 10 ms")
        );
        let mut cfg = ControllerConfig::arena(1);
        cfg.behaviours = 5;
        assert!(
            Controller::new(cfg)
                .unwrap_err()
                .to_string()
                .contains("behaviours = 5")
        );
    }

    #[test]
    fn a_network_too_large_for_the_ram_names_the_item() {
        let mut cfg = ControllerConfig::arena(1);
        cfg.layout = InputLayout::DEFAULT.with_spare(1200);
        match Controller::new(cfg) {
            Err(ControllerError::Ram(o)) => {
                assert_eq!(o.item, "weights w (i16, N x M)");
                assert!(o.over_by > 0);
            }
            other => panic!("expected a RAM overflow, got {other:?}"),
        }
        // Fits the RAM but not the learner's no-overflow bound.
        let mut cfg = ControllerConfig::arena(1);
        cfg.layout = InputLayout::DEFAULT.with_spare(300);
        assert!(matches!(
            Controller::new(cfg),
            Err(ControllerError::Shape(_))
        ));
    }

    #[test]
    fn motor_rows_follow_the_behaviours() {
        assert_eq!(motor_row(Behaviour::Forward), (1250, 1250, 0b0101));
        assert_eq!(motor_row(Behaviour::Backward), (1250, 1250, 0b1010));
        assert_eq!(motor_row(Behaviour::TurnLeftForward), (374, 1250, 0b0101));
        assert_eq!(motor_row(Behaviour::TurnRightForward), (1250, 374, 0b0101));
    }

    #[test]
    fn fresh_weights_are_seeded_and_within_half() {
        let a = fresh_weights(7, 52);
        assert_eq!(a, fresh_weights(7, 52));
        assert_ne!(a, fresh_weights(8, 52));
        assert!(a.iter().all(|w| (-16384..16384).contains(&w.to_bits())));
    }
}
