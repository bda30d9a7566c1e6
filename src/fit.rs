//! "Does it fit the H8/3052?" (SPEC §6), measured by running the controller on the emulated
//! MCU.
//!
//! [`measure`] builds an MCU with four modelled IR sensors (`sensors::IrSensor`, datasheet
//! spread and noise, their own seeds) whose true distances follow a seeded random walk between
//! 30 mm and 1 m (so the learner sees rewards, punishments and dead zones, and the readings
//! include the fold-back), boots the controller on it, and runs `steps` steps with the sleep
//! between them, recording every phase of every step. The report gives the maximum and mean
//! states per phase, the time at φ against the step period, the RAM items against the 8 192
//! bytes, the ROM estimate against the 512 KB of flash, the EEPROM traffic and the lifetime the
//! endurance allows, and a one-line verdict with the tightest margin. Nothing in it is computed
//! from a formula alone: the step states are what the emulated MCU counted.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use seeding::Purpose;
use serde::Serialize;

use emu::board::model::code::rom_estimate;
use emu::board::model::{Controller, ControllerConfig, ControllerError, PhaseStates};
use emu::chip::mcu::{Board, Mcu, McuConfig};
use emu::core::memmap::{RAM_BYTES, ROM_BYTES};

use crate::seeds::robot_stream;

/// Endurance of a 24LC256 page: 1 000 000 write cycles (SPEC §3.6; Microchip DS21203).
pub const ENDURANCE_CYCLES: f64 = 1_000_000.0;

/// What to measure.
#[derive(Clone, Debug)]
pub struct FitConfig {
    /// The controller to run.
    pub controller: ControllerConfig,
    /// Steps to run (after boot).
    pub steps: u32,
    /// The master seed: the fit's robot is robot 0 of repeat 0 under it ([`crate::seeds`]), whose
    /// streams give its sensors, their distances and its EEPROMs. (The initial weights come
    /// with [`Self::controller`]; the commands take them from the same robot,
    /// [`fit_weight_seed`].)
    pub seed: u64,
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
    pub phase: &'static str,
    /// States per step (over all steps; for the save, steps without a save count as 0, so the
    /// mean is the amortised cost).
    pub states: Spread,
    /// The maximum in microseconds at φ.
    pub max_us: f64,
}

/// A RAM or ROM item.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MemLine {
    /// What it holds.
    pub item: String,
    /// Where it starts (RAM) or 0 (ROM estimate).
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

/// The verdict of SPEC §6.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FitReport {
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
    /// States of boot (hardware set-up, recovery, weights).
    pub boot_states: u64,
    /// States per phase.
    pub phases: Vec<PhaseLine>,
    /// The CPU's busy states per step: the step's work plus the tick interrupts and the main
    /// loop over one step period.
    pub busy_per_step: Spread,
    /// Busy share of the step period, mean over the steps (percent).
    pub cpu_mean_percent: f64,
    /// Busy share of the step period in the worst step (percent).
    pub cpu_worst_percent: f64,
    /// RAM items.
    pub ram: Vec<MemLine>,
    /// RAM used, bytes.
    pub ram_used: u32,
    /// ROM estimate items.
    pub rom: Vec<MemLine>,
    /// ROM estimate, bytes.
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
}

/// The board of the fit runs: four IR sensors whose distances the driver sets; bumpers open.
pub struct FitBoard {
    sensors: Vec<sensors::IrSensor>,
    distance_mm: [f64; 4],
    /// The A/D input of each sensor (the controller's wiring).
    channels: [u8; 4],
}

impl Board for FitBoard {
    fn analog_volts(&mut self, channel: u8, now_states: u64) -> f64 {
        let d = self.distance_mm.map(Some);
        emu::board::wiring::sensor_volts(&mut self.sensors, &d, &self.channels, channel, now_states)
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

/// Runs the controller as [`FitConfig`] says and reports.
///
/// # Errors
/// [`ControllerError`] when the configuration is impossible (clock, save period, step period,
/// a network too large for the RAM (naming the item) or beyond the learner's bound).
pub fn measure(cfg: &FitConfig) -> Result<FitReport, ControllerError> {
    let mut controller = Controller::new(cfg.controller.clone())?;
    let clock_hz = cfg.controller.clock_hz;
    // The fit's robot is robot 0 of repeat 0 under the seed (crate::seeds).
    let stream = |k: u64, purpose: Purpose| robot_stream(cfg.seed, 0, 0, k, purpose);
    let mut sensors_v = Vec::with_capacity(4);
    for k in 0..4 {
        let params = sensors::IrParams {
            clock_hz,
            ..sensors::IrParams::default()
        };
        sensors_v.push(
            sensors::IrSensor::new(params, stream(k, Purpose::IrSensor)).map_err(|e| {
                ControllerError::Config {
                    field: "clock_hz",
                    value: clock_hz.to_string(),
                    valid: e.to_string(),
                }
            })?,
        );
    }
    let mut walk = ChaCha8Rng::seed_from_u64(stream(0, Purpose::FitDistances));
    let board = FitBoard {
        sensors: sensors_v,
        distance_mm: [300.0, 500.0, 150.0, 800.0],
        channels: cfg.controller.sensor_channels,
    };
    let mut mcu = Mcu::new(
        McuConfig {
            clock_hz,
            eeprom_seed: stream(0, Purpose::Eeproms),
        },
        board,
    )
    .map_err(|e| ControllerError::Config {
        field: "clock_hz",
        value: clock_hz.to_string(),
        valid: e.to_string(),
    })?;

    let boot = controller.boot(&mut mcu)?;
    let mut per_step: Vec<PhaseStates> = Vec::with_capacity(cfg.steps as usize);
    let mut busy: Vec<u64> = Vec::with_capacity(cfg.steps as usize);
    let mut save_max = 0u64;
    for _ in 0..cfg.steps {
        let sleep = controller.sleep_until_step(&mut mcu)?;
        // The world moves: each distance takes a bounded random step.
        for d in &mut mcu.board_mut().distance_mm {
            let delta: f64 = walk.random_range(-60.0..60.0);
            *d = (*d + delta).clamp(30.0, 1000.0);
        }
        let step = controller.step(&mut mcu)?;
        save_max = save_max.max(step.phases.save);
        busy.push(step.phases.work() + step.phases.isr + sleep.busy_states);
        per_step.push(step.phases);
    }

    let spread = |f: &dyn Fn(&PhaseStates) -> u64| -> Spread {
        let values: Vec<u64> = per_step.iter().map(f).collect();
        spread_of(&values)
    };
    let us = |states: u64| states as f64 / f64::from(clock_hz) * 1e6;
    let mut phases = Vec::new();
    for (name, s) in [
        ("A/D", spread(&|p| p.adc)),
        ("input", spread(&|p| p.input)),
        ("update", spread(&|p| p.update)),
        ("forward", spread(&|p| p.forward)),
        ("motors", spread(&|p| p.motors)),
        ("EEPROM save (amortised)", spread(&|p| p.save)),
        ("tick interrupts in the step", spread(&|p| p.isr)),
    ] {
        phases.push(PhaseLine {
            phase: name,
            states: s,
            max_us: us(s.max),
        });
    }
    let busy_per_step = spread_of(&busy);
    let period_states = cfg.controller.step_period_s * f64::from(clock_hz);
    let cpu_mean_percent = busy_per_step.mean / period_states * 100.0;
    let cpu_worst_percent = busy_per_step.max as f64 / period_states * 100.0;

    let ram: Vec<MemLine> = controller
        .ram()
        .items()
        .iter()
        .map(|p| MemLine {
            item: p.name.clone(),
            addr: p.addr,
            bytes: p.bytes,
        })
        .collect();
    let ram_used = controller.ram().used();
    let rom: Vec<MemLine> = rom_estimate()
        .into_iter()
        .map(|l| MemLine {
            item: l.name.to_string(),
            addr: 0,
            bytes: l.bytes,
        })
        .collect();
    let rom_used: u32 = rom.iter().map(|l| l.bytes).sum();

    let saves_per_hour =
        3600.0 / (cfg.controller.step_period_s * f64::from(cfg.controller.save_every_steps));
    let page_writes_per_hour = saves_per_hour / 2.0;
    let eeprom = EepromLine {
        bytes_per_save: controller.bytes_per_save(),
        pages_per_save: controller.pages_per_save(),
        saves_per_hour,
        page_writes_per_hour,
        lifetime_hours: ENDURANCE_CYCLES / page_writes_per_hour,
        save_max_states: save_max,
    };

    let margins = [
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
    let (tightest, tightest_margin_percent) = margins
        .iter()
        .copied()
        .fold(("RAM", f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
    let fits = margins.iter().all(|m| m.1 >= 0.0);
    let layout = cfg.controller.layout;
    let n_in = cfg.controller.n_inputs();
    let verdict = format!(
        "{}: {} x {} network, RAM {} of {} B, ROM ≈ {} B of {} KB, worst step {:.2} % of the {} s period (mean {:.3} %); tightest margin: {} with {:.1} % left",
        if fits { "FITS" } else { "DOES NOT FIT" },
        n_in,
        cfg.controller.behaviours,
        ram_used,
        RAM_BYTES,
        rom_used,
        ROM_BYTES / 1024,
        cpu_worst_percent,
        cfg.controller.step_period_s,
        cpu_mean_percent,
        tightest,
        tightest_margin_percent
    );
    let _ = boot;
    Ok(FitReport {
        n_in,
        n_out: cfg.controller.behaviours,
        history: layout.history(),
        bias: layout.bias(),
        spare: layout.spare(),
        eta: cfg.controller.params.eta().to_bits(),
        threshold: cfg.controller.params.threshold(),
        save_every_steps: cfg.controller.save_every_steps,
        step_period_s: cfg.controller.step_period_s,
        clock_hz,
        steps: cfg.steps,
        seed: cfg.seed,
        boot_states: boot.states,
        phases,
        busy_per_step,
        cpu_mean_percent,
        cpu_worst_percent,
        ram,
        ram_used,
        rom,
        rom_used,
        eeprom,
        fits,
        tightest,
        tightest_margin_percent,
        verdict,
    })
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
/// running each candidate; None when even `base` does not. The search is a bisection over N up
/// to the learner's bound (256 inputs), each probe a full [`measure`].
///
/// # Errors
/// [`ControllerError`] for an impossible base configuration.
pub fn largest_fitting(
    base: &FitConfig,
    cpu_budget_percent: f64,
    budget: Budget,
) -> Result<Option<FitReport>, ControllerError> {
    let fits = |spare: usize| -> Result<Option<FitReport>, ControllerError> {
        let mut cfg = base.clone();
        cfg.controller.layout = base.controller.layout.with_spare(spare as u16);
        let share = |r: &FitReport| match budget {
            Budget::Mean => r.cpu_mean_percent,
            Budget::WorstStep => r.cpu_worst_percent,
        };
        match measure(&cfg) {
            Ok(r) if r.fits && share(&r) <= cpu_budget_percent => Ok(Some(r)),
            Ok(_) | Err(ControllerError::Ram(_)) | Err(ControllerError::Shape(_)) => Ok(None),
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
