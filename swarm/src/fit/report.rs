//! The fit verdict's report ([`FitReport`]): states per phase, RAM, ROM, stack, EEPROM and
//! energy, each against its limit.

use crate::energy::Pack;
use crate::scenario::ControllerKind;
use serde::Serialize;

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
    /// The part ([`crate::energy::Part::key`]).
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
