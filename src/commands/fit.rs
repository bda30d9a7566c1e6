//! `h8swarm fit`: the verdict of docs/design.md §6 for the paper's network in its two settings
//! (which the built-in runs may not use: each heading says), what-ifs, and the largest network
//! within a CPU budget, all measured by running the
//! controller on the emulated H8/3052F ([`swarm::fit`]): by default the robot firmware on the
//! H8/300H core, with the Rust model's figures beside each phase.

use std::fmt::Write as _;

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use nn_q15::InputLayout;
use robot_board::firmware::Firmware;
use robot_board::model::ControllerConfig;
use robot_board::profile::PhaseDef;
use serde::Serialize;
use swarm::fit::{
    Budget, FirmwareUnderTest, FitConfig, FitReport, fit_weight_seed, largest_fitting, measure,
    robot_phases,
};
use swarm::scenario::ControllerKind;

use super::args::{ControllerArg, parse_capacity};

/// Which of the paper's settings to start from: the paper's network (its own η), which is not
/// always the network the built-in run of the same name uses (the run's network).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Setting {
    /// Paper env. 2: four behaviours, η = 0.001, 0.45 s steps (the paper's network; `run arena`
    /// runs η = 0.03).
    Arena,
    /// Paper env. 1: forward and backward, η = 0.1, 0.60 s steps.
    Corridor,
}

impl Setting {
    /// The name of the setting and of the built-in scenario.
    fn name(self) -> &'static str {
        match self {
            Setting::Arena => "arena",
            Setting::Corridor => "corridor",
        }
    }

    /// The paper's η for this setting, as the paper gives it (the network uses it in Q15).
    fn paper_eta(self) -> f64 {
        match self {
            Setting::Arena => 0.001,
            Setting::Corridor => 0.1,
        }
    }

    /// The built-in scenario of the same name, whose network a run uses.
    fn scenario(self) -> swarm::scenario::Scenario {
        match self {
            Setting::Arena => swarm::scenario::Scenario::arena(),
            Setting::Corridor => swarm::scenario::Scenario::corridor(),
        }
    }

    /// The heading of a report on the paper's network in this setting, naming the run's
    /// network when the built-in run uses another one (and how it differs).
    fn heading(self, seed: u64) -> Result<String> {
        self.heading_against(&self.scenario(), seed)
    }

    /// [`Setting::heading`] with `scenario` standing for the built-in run (the built-ins run
    /// the paper's networks today; a test gives another).
    fn heading_against(self, scenario: &swarm::scenario::Scenario, seed: u64) -> Result<String> {
        let paper = base_config(self, seed);
        let run = swarm::robot::controller_config(scenario, fit_weight_seed(seed))?;
        let (name, env) = (self.name(), if self == Setting::Arena { 2 } else { 1 });
        let head = format!(
            "{name} (paper env. {env}): the paper's network, eta {}",
            self.paper_eta()
        );
        if run == paper {
            return Ok(format!("{head}, which `h8swarm run {name}` runs too"));
        }
        let mut differs = Vec::new();
        if run.params.eta() != paper.params.eta() {
            differs.push(format!("eta {}", scenario.learner.eta));
        }
        if run.params.threshold() != paper.params.threshold() {
            differs.push(format!("T {}", run.params.threshold()));
        }
        if run.behaviours != paper.behaviours {
            differs.push(format!("{} behaviours", run.behaviours));
        }
        if run.layout != paper.layout {
            differs.push(format!(
                "history {}, bias {}",
                run.layout.history(),
                if run.layout.bias() { "on" } else { "off" }
            ));
        }
        if run.save_every_steps != paper.save_every_steps {
            differs.push(format!("a record every {} steps", run.save_every_steps));
        }
        if run.step_period_s != paper.step_period_s {
            differs.push(format!("step {} s", run.step_period_s));
        }
        if run.clock_hz != paper.clock_hz || run.sensor_channels != paper.sensor_channels {
            differs.push("other board settings".to_string());
        }
        Ok(format!(
            "{head}; `h8swarm run {name}` runs the run's network ({}), measured in its fit.json",
            differs.join(", ")
        ))
    }
}

/// Options of `h8swarm fit`.
#[derive(Args, Debug, Default)]
pub struct FitArgs {
    /// The controller the verdict is about; the other one is measured beside it.
    #[arg(long, value_enum, default_value_t = ControllerArg::Firmware)]
    pub controller: ControllerArg,
    /// Measure this firmware image (Motorola S-records) instead of the robot firmware.
    #[arg(long, value_name = "IMAGE")]
    pub firmware: Option<PathBuf>,
    /// The image's symbol table as `h8300-hms-nm -n` prints it (default: IMAGE with the
    /// extension `.sym`).
    #[arg(long, value_name = "FILE", requires = "firmware")]
    pub symbols: Option<PathBuf>,
    /// A phase of the image: NAME=FUNCTION[,FUNCTION…] (repeatable). Default: the robot
    /// firmware's phases whose functions the image has.
    #[arg(long = "phase", value_name = "NAME=SYMBOL")]
    pub phases: Vec<String>,
    /// Do not measure the other controller beside.
    #[arg(long)]
    pub alone: bool,
    /// Start from this setting (default: report both, arena first; with a what-if, arena).
    #[arg(long, value_enum)]
    pub setting: Option<Setting>,
    /// What-if: the network has N inputs (the layout's own inputs plus spare inputs held at 0).
    #[arg(long, value_name = "N")]
    pub inputs: Option<usize>,
    /// What-if: history depth H (0 to 8).
    #[arg(long, value_name = "H")]
    pub history: Option<usize>,
    /// What-if: enabled behaviours M (2 to 4).
    #[arg(long, value_name = "M")]
    pub outputs: Option<usize>,
    /// What-if: one EEPROM record every S steps.
    #[arg(long, value_name = "S")]
    pub save_every: Option<u32>,
    /// What-if: add the bias input.
    #[arg(long)]
    pub bias: bool,
    /// What-if: the step period in seconds (a whole number of 10 ms ticks).
    #[arg(long, value_name = "SECONDS")]
    pub step_period_s: Option<f64>,
    /// What-if: the MCU clock φ in Hz (2 000 000 to 25 000 000).
    #[arg(long, value_name = "HZ")]
    pub clock_hz: Option<u32>,
    /// Also find the largest network (by inputs) whose CPU share stays within this share of
    /// the step period, e.g. `5%` or `5`: once for the mean share (the load) and once for the
    /// worst step.
    #[arg(long, value_name = "PERCENT")]
    pub cpu_budget: Option<String>,
    /// Steps to run for each measurement.
    #[arg(long, default_value_t = 400)]
    pub steps: u32,
    /// Master seed: the measured robot is robot 0 of repeat 0 of `h8swarm run` with this seed
    /// (its sensors, their distances, its EEPROMs and its initial weights).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print the reports as JSON.
    #[arg(long)]
    pub json: bool,
    /// Capacity of one cell of the paper's pack (ten 1.2 V NiMH cells), mAh, for the battery
    /// life (default: 2 000 mAh, a typical AA NiMH cell of 2008).
    #[arg(long, value_name = "MAH")]
    pub capacity_mah: Option<f64>,
    /// Stop with an error at the image's first access to a register the emulated chip does
    /// not model or to a reserved address, instead of naming them in the verdict.
    #[arg(long)]
    pub strict_io: bool,
}

impl FitArgs {
    fn what_if(&self) -> bool {
        self.inputs.is_some()
            || self.history.is_some()
            || self.outputs.is_some()
            || self.save_every.is_some()
            || self.bias
            || self.step_period_s.is_some()
            || self.clock_hz.is_some()
    }
}

#[derive(Serialize)]
struct JsonOut<'a> {
    reports: &'a [(String, FitReport)],
    #[serde(skip_serializing_if = "Option::is_none")]
    largest: Option<&'a LargestOut>,
}

#[derive(Serialize)]
struct LargestOut {
    cpu_budget_percent: f64,
    by_mean: Option<FitReport>,
    by_worst_step: Option<FitReport>,
}

fn base_config(setting: Setting, seed: u64) -> ControllerConfig {
    let weights = fit_weight_seed(seed);
    match setting {
        Setting::Arena => ControllerConfig::arena(weights),
        Setting::Corridor => ControllerConfig::corridor(weights),
    }
}

fn apply_what_ifs(mut cfg: ControllerConfig, a: &FitArgs) -> Result<ControllerConfig> {
    if let Some(m) = a.outputs {
        if !(2..=4).contains(&m) {
            bail!("--outputs {m}: valid is 2 (forward, backward) to 4 (all four behaviours)");
        }
        cfg.behaviours = m;
    }
    let history = a.history.unwrap_or(cfg.layout.history());
    let mut layout = InputLayout::new(history, a.bias || cfg.layout.bias())
        .with_context(|| format!("--history {history}"))?;
    if let Some(n) = a.inputs {
        let own = layout.n_inputs(cfg.behaviours);
        if n < own {
            bail!(
                "--inputs {n}: this layout already has {own} inputs (4 proximities x (1 + history), the outputs, E{}); give at least {own}",
                if layout.bias() { ", bias" } else { "" }
            );
        }
        let spare =
            u16::try_from(n - own).with_context(|| format!("--inputs {n}: far too many inputs"))?;
        layout = layout.with_spare(spare);
    }
    cfg.layout = layout;
    if let Some(s) = a.save_every {
        cfg.save_every_steps = s;
    }
    if let Some(p) = a.step_period_s {
        if !robot_board::model::step_period_ok(p) {
            bail!(
                "--step-period-s {}: valid is {}",
                swarm::terminal_text::number(p),
                robot_board::model::STEP_PERIOD_VALID
            );
        }
        cfg.step_period_s = p;
    }
    if let Some(hz) = a.clock_hz {
        cfg.clock_hz = hz;
    }
    Ok(cfg)
}

/// Parses `--phase NAME=SYMBOL[,SYMBOL…]`.
fn parse_phase(text: &str) -> Result<PhaseDef> {
    let Some((name, functions)) = text.split_once('=') else {
        bail!(
            "--phase {text}: give NAME=FUNCTION (several functions separated by commas), e.g. forward=learner_forward"
        );
    };
    let functions: Vec<&str> = functions.split(',').map(str::trim).collect();
    if name.trim().is_empty() || functions.iter().any(|f| f.is_empty()) {
        bail!(
            "--phase {text}: the name and every function must be non-empty (NAME=FUNCTION[,FUNCTION…])"
        );
    }
    Ok(PhaseDef::new(name.trim(), &functions))
}

/// The image to measure and its phases.
fn firmware_under_test(a: &FitArgs) -> Result<FirmwareUnderTest> {
    let Some(image) = &a.firmware else {
        let mut fut = FirmwareUnderTest::robot().context("the built-in robot firmware")?;
        if !a.phases.is_empty() {
            fut.phases = a
                .phases
                .iter()
                .map(|p| parse_phase(p))
                .collect::<Result<_>>()?;
        }
        return Ok(fut);
    };
    let symbols = a
        .symbols
        .clone()
        .unwrap_or_else(|| image.with_extension("sym"));
    let firmware = Firmware::load(image, &symbols).with_context(|| {
        format!(
            "--firmware {}: the image and its symbol table (`{}`; give another with --symbols)",
            image.display(),
            symbols.display()
        )
    })?;
    let phases = if a.phases.is_empty() {
        robot_phases()
            .into_iter()
            .filter(|p| {
                p.functions
                    .iter()
                    .all(|f| firmware.symbols.get(f).is_some_and(|s| s.is_function()))
            })
            .collect()
    } else {
        a.phases
            .iter()
            .map(|p| parse_phase(p))
            .collect::<Result<_>>()?
    };
    Ok(FirmwareUnderTest { firmware, phases })
}

fn parse_budget(text: &str) -> Result<f64> {
    let t = text.trim().trim_end_matches('%').trim();
    let v: f64 = t
        .parse()
        .with_context(|| format!("--cpu-budget {text}: give a percentage such as 5% or 5"))?;
    if !(v > 0.0 && v <= 100.0) {
        bail!("--cpu-budget {text}: valid is more than 0 and at most 100 percent");
    }
    Ok(v)
}

/// The most steps `fit` measures (1 million: under 100 MB of per-step states; the time it
/// takes: docs/limits-and-failures.md).
pub const MAX_FIT_STEPS: u32 = 1_000_000;

/// Runs `h8swarm fit`; returns the text to print.
///
/// # Errors
/// Bad options or an impossible configuration, with what would be valid.
pub fn run(a: &FitArgs) -> Result<String> {
    if a.steps == 0 || a.steps > MAX_FIT_STEPS {
        bail!(
            "--steps {}: valid is 1 to {MAX_FIT_STEPS} (each measured step keeps its states per phase; the default 400 already holds many saves)",
            a.steps
        );
    }
    let budget = a.cpu_budget.as_deref().map(parse_budget).transpose()?;
    let pack = swarm::energy::Pack::paper(parse_capacity(a.capacity_mah)?);
    let settings: Vec<Setting> = match (a.setting, a.what_if()) {
        (Some(s), _) => vec![s],
        (None, true) => vec![Setting::Arena],
        (None, false) => vec![Setting::Arena, Setting::Corridor],
    };
    let firmware = firmware_under_test(a)?;
    let kind = ControllerKind::from(a.controller);
    // A user's image is measured alone: the model is a model of the robot firmware.
    let compare = !a.alone && a.firmware.is_none();
    let config = |controller: ControllerConfig| FitConfig {
        controller,
        steps: a.steps,
        seed: a.seed,
        kind,
        firmware: firmware.clone(),
        compare,
        strict_io: a.strict_io,
    };
    let mut reports = Vec::new();
    for setting in &settings {
        let fit = config(apply_what_ifs(base_config(*setting, a.seed), a)?);
        let mut report = measure(&fit).map_err(anyhow::Error::new)?;
        if let Some(e) = report.energy.as_mut() {
            *e = e.with_pack(pack);
        }
        let name = if a.what_if() {
            format!(
                "what-if, from the paper's network in the {}",
                setting.name()
            )
        } else {
            setting.heading(a.seed)?
        };
        reports.push((name, report));
    }
    let largest = match budget {
        Some(pct) => {
            let fit = config(apply_what_ifs(base_config(settings[0], a.seed), a)?);
            Some(LargestOut {
                cpu_budget_percent: pct,
                by_mean: largest_fitting(&fit, pct, Budget::Mean).map_err(anyhow::Error::new)?,
                by_worst_step: largest_fitting(&fit, pct, Budget::WorstStep)
                    .map_err(anyhow::Error::new)?,
            })
        }
        None => None,
    };
    if a.json {
        let out = JsonOut {
            reports: &reports,
            largest: largest.as_ref(),
        };
        return Ok(serde_json::to_string_pretty(&out)? + "\n");
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "h8swarm fit: does the learner fit the H8/3052F? Measured on the emulated MCU over {} steps (seed {}).",
        a.steps, a.seed
    );
    for (name, r) in &reports {
        let _ = writeln!(s);
        render(&mut s, name, r);
    }
    if let Some(l) = &largest {
        let _ = writeln!(s);
        for (what, found) in [
            ("mean CPU share (the load)", &l.by_mean),
            ("worst-step CPU share", &l.by_worst_step),
        ] {
            match found {
                Some(r) => {
                    let _ = writeln!(
                        s,
                        "largest network within a {} % {what}: {} inputs x {} outputs ({} spare inputs); mean {:.3} %, worst step {:.2} %, RAM {} B{}",
                        l.cpu_budget_percent,
                        r.n_in,
                        r.n_out,
                        r.spare,
                        r.cpu_mean_percent,
                        r.cpu_worst_percent,
                        r.ram_used,
                        if r.n_in == nn_q15::MAX_INPUTS {
                            " (the learner's no-overflow bound: the budget would allow more)"
                        } else {
                            ""
                        }
                    );
                }
                None => {
                    let _ = writeln!(
                        s,
                        "no network fits a {} % {what}: even the base network exceeds it",
                        l.cpu_budget_percent
                    );
                }
            }
        }
    }
    Ok(s)
}

/// One controller's report as `fit` prints it, headed `name`.
fn render(s: &mut String, name: &str, r: &FitReport) {
    render_settings(s, name, r);
    render_states(s, r);
    render_ram(s, r);
    render_rom_and_eeprom(s, r);
    if let Some(en) = &r.energy {
        render_energy(s, en);
    }
    for line in &r.unmodelled {
        let _ = writeln!(s, "not modelled: {line}");
    }
    let _ = writeln!(s, "verdict: {}", r.verdict);
}

/// The heading: the controller's settings and what was measured (and beside what).
fn render_settings(s: &mut String, name: &str, r: &FitReport) {
    let _ = writeln!(s, "== {name}");
    let _ = writeln!(
        s,
        "network {} inputs x {} outputs (history {}, bias {}, {} spare), eta {} (Q15), T {}, a record every {} steps, step {} s, phi {} MHz",
        r.n_in,
        r.n_out,
        r.history,
        if r.bias { "on" } else { "off" },
        r.spare,
        r.eta,
        r.threshold,
        r.save_every_steps,
        r.step_period_s,
        f64::from(r.clock_hz) / 1e6
    );
    let _ = writeln!(
        s,
        "measured: {}{}",
        match r.controller {
            swarm::scenario::ControllerKind::Firmware =>
                format!("{} on the H8/300H core", r.source),
            swarm::scenario::ControllerKind::Model =>
                "the Rust model of the controller".to_string(),
        },
        match &r.compared_with {
            Some(o) => format!("; beside it: {o}"),
            None => String::new(),
        }
    );
}

/// The states per step period, phase by phase (with the other controller's mean and the
/// ratio when both ran), the busy states and the CPU's share.
fn render_states(s: &mut String, r: &FitReport) {
    let us = |states: f64| states / f64::from(r.clock_hz) * 1e6;
    let other = if r.compared_with.is_some() {
        format!(
            " {:>12} {:>7}",
            match r.controller {
                swarm::scenario::ControllerKind::Firmware => "model mean",
                swarm::scenario::ControllerKind::Model => "fw mean",
            },
            "ratio"
        )
    } else {
        String::new()
    };
    let _ = writeln!(
        s,
        "{:<30} {:>12} {:>12} {:>10}{other}",
        "states per step period", "max", "mean", "max µs"
    );
    for p in &r.phases {
        let beside = match (&r.compared_with, p.other) {
            (Some(_), Some(o)) => format!(
                " {:>12.1} {:>7}",
                o.mean,
                p.ratio.map_or("-".to_string(), |x| format!("{x:.3}"))
            ),
            (Some(_), None) => format!(" {:>12} {:>7}", "-", "-"),
            _ => String::new(),
        };
        let _ = writeln!(
            s,
            "{:<30} {:>12} {:>12.1} {:>10.1}{beside}",
            p.phase, p.states.max, p.states.mean, p.max_us
        );
    }
    let _ = writeln!(
        s,
        "{:<30} {:>12} {:>12.1} {:>10.1}",
        "busy per step period",
        r.busy_per_step.max,
        r.busy_per_step.mean,
        us(r.busy_per_step.max as f64)
    );
    let _ = writeln!(
        s,
        "CPU: {:.3} % of the step period on average, {:.2} % in the worst step (a save); boot {} states",
        r.cpu_mean_percent, r.cpu_worst_percent, r.boot_states
    );
}

/// The RAM, item by item, and the stack's room and what the firmware left of it.
fn render_ram(s: &mut String, r: &FitReport) {
    let _ = writeln!(s, "RAM (bytes):");
    for m in &r.ram {
        let _ = writeln!(s, "  H'{:06X} {:>6}  {}", m.addr, m.bytes, m.item);
    }
    let _ = writeln!(
        s,
        "  total {} of 8192 ({:.1} %){}",
        r.ram_used,
        f64::from(r.ram_used) / 8192.0 * 100.0,
        r.stack_high_water
            .map_or(String::new(), |h| format!("; stack high-water {h} B"))
    );
    if let Some(st) = &r.stack {
        match &st.overflow {
            Some(text) => {
                let _ = writeln!(s, "stack: OVERFLOW: {text}");
            }
            None => {
                let _ = writeln!(
                    s,
                    "stack: room H'{:06X}-H'{:06X} ({} B, the end of the data and the boot-sized arrays to the initial SP); lowest SP H'{:06X}: {} B left ({:.1} %)",
                    st.room_low,
                    st.room_top.saturating_sub(1),
                    st.room_bytes,
                    st.lowest_sp,
                    st.left_bytes,
                    st.left_bytes as f64 / f64::from(st.room_bytes.max(1)) * 100.0
                );
            }
        }
    }
}

/// The ROM, and the EEPROM's traffic and lifetime.
fn render_rom_and_eeprom(s: &mut String, r: &FitReport) {
    let us = |states: f64| states / f64::from(r.clock_hz) * 1e6;
    let _ = writeln!(s, "ROM (bytes):");
    for m in &r.rom {
        let _ = writeln!(s, "  {:>6}  {}", m.bytes, m.item);
    }
    let _ = writeln!(
        s,
        "  total {} of 524288 ({:.2} %)",
        r.rom_used,
        f64::from(r.rom_used) / 524_288.0 * 100.0
    );
    let e = &r.eeprom;
    let _ = writeln!(
        s,
        "EEPROM: {} bytes on {} pages per save, {:.0} saves/h, {:.0} writes/h on each record page, endurance lifetime {:.0} h; slowest save {} states ({:.1} ms)",
        e.bytes_per_save,
        e.pages_per_save,
        e.saves_per_hour,
        e.page_writes_per_hour,
        e.lifetime_hours,
        e.save_max_states,
        us(e.save_max_states as f64) / 1000.0
    );
}

fn render_energy(s: &mut String, e: &swarm::fit::EnergyReport) {
    let _ = writeln!(
        s,
        "energy from the pack ({} x {} V NiMH, {} V, {:.0} mAh), wheels free (each at its command's speed):",
        e.pack.cells,
        e.pack.cell_volts,
        e.pack.volts(),
        e.pack.capacity_mah
    );
    let _ = writeln!(
        s,
        "  {:<32} {:>10} {:>14}",
        "part",
        "mean mA",
        format!("mJ per {} s", e.step_period_s)
    );
    for p in &e.parts {
        let _ = writeln!(
            s,
            "  {:<32} {:>10.3} {:>14.2}",
            p.name, p.mean_current_ma, p.energy_per_step_mj
        );
    }
    let _ = writeln!(
        s,
        "  {:<32} {:>10.3} {:>14.2}",
        "total", e.mean_current_ma, e.energy_per_step_mj
    );
    let _ = writeln!(
        s,
        "battery life: {:.2} h with the wheels free (the paper: up to {} h, which {:.0} mAh cells would give at this current); {:.2} h pressed against a wall the whole time, its wheels slipping (motors {:.0} mA, total {:.0} mA)",
        e.battery_life_h,
        e.paper_battery_life_h,
        e.capacity_for_paper_mah,
        e.held_battery_life_h,
        e.held_motors_current_ma,
        e.held_mean_current_ma
    );
    for (cap, how) in [
        (e.motor_cap, "with the wheels free"),
        (e.held_motor_cap, "pressed against a wall"),
    ] {
        if cap.capped_wheel_substeps > 0 {
            let _ = writeln!(
                s,
                "motor current cut to the drive voltage's bound {how} in {} of {} driven wheel-sub-steps",
                cap.capped_wheel_substeps, cap.driven_wheel_substeps
            );
        }
    }
}

/// `h8swarm fit`: measures and prints the verdict.
///
/// # Errors
/// Bad options or images ([`super::Failure::Input`]), an output that cannot be written
/// ([`super::Failure::Tool`]).
pub fn command(args: &FitArgs) -> Result<(), super::Failure> {
    let text = run(args).map_err(super::Failure::Input)?;
    super::write_text(&text)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The η the headings give for the paper's network is the one it runs, in Q15.
    #[test]
    fn the_paper_eta_named_is_the_one_measured() {
        for setting in [Setting::Arena, Setting::Corridor] {
            let mut s = setting.scenario();
            s.learner.eta = setting.paper_eta();
            assert_eq!(
                Some(base_config(setting, 1).params.eta().to_bits()),
                i16::try_from(s.eta_q15()).ok(),
                "{setting:?}"
            );
        }
    }

    /// A built-in run on another network than the paper's is named with how it differs; on
    /// the paper's, the heading says the run runs it too.
    #[test]
    fn the_heading_names_how_the_run_differs() {
        let same = Setting::Arena.heading(1).unwrap();
        assert!(
            same.ends_with("which `h8swarm run arena` runs too"),
            "{same}"
        );
        let mut other = Setting::Arena.scenario();
        other.learner.eta = 0.03;
        other.learner.threshold = 32;
        let differs = Setting::Arena.heading_against(&other, 1).unwrap();
        assert_eq!(
            differs,
            "arena (paper env. 2): the paper's network, eta 0.001; `h8swarm run arena` runs the run's network (eta 0.03, T 32), measured in its fit.json"
        );
    }
}
