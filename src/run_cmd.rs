//! `h8swarm run [corridor|arena|FILE.toml] [--robots N] [--steps S] [--repeats R] [--seed X]
//! [--threads T] [--out DIR] [--vcd FILE [--vcd-robot K] [--vcd-from S] [--vcd-steps N]]
//! [--gdb ADDR [--gdb-robot K]]`: the paper's experiment with its controls, in parallel, with
//! the metrics, the summary, the figures and the fit verdict written to DIR; `--vcd` traces one
//! firmware robot's pins over a window of steps, `--gdb` puts one under a GDB client's control
//! (both in the learning run's first repeat; the results do not change).

use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;

use crate::plot::{
    ArenaFigure, LearningFigure, Panel, Series, SpaceTimeFigure, arena_figure_panels,
    learning_figure, spacetime_figure,
};
use crate::stage::Stage;
use swarm::experiment::{RunOptions, RunOutput, build_world, run_one};
use swarm::output_error::OutputError;
use swarm::robot::{Condition, controller_config};
use swarm::scenario::Scenario;
use swarm::summary::{Analysis, Claim, ConditionStats, Estimate, Pairing, Quantity, analyse};

/// An option's help with its default, which comes from the scenario (an option given overrides
/// it; not given, the scenario's value stands, so clap must not hold a default of its own):
/// `WHAT [default: the scenario's: arena A, corridor C, a file's own or its base's]`, the values
/// read from the built-ins themselves.
fn scenario_default(what: &str, value: fn(&Scenario) -> String) -> String {
    format!(
        "{what} [default: the scenario's: arena {}, corridor {}, a file's own or its base's]",
        value(&Scenario::arena()),
        value(&Scenario::corridor())
    )
}

/// Options of `h8swarm run`.
#[derive(Args, Debug, Default, Clone)]
pub struct RunArgs {
    /// `arena` (default), `corridor`, or a scenario file (.toml).
    pub scenario: Option<String>,
    /// Robots (the square arena is scaled to keep the paper's density). Default: the
    /// scenario's.
    #[arg(long, help = scenario_default("Robots (the square arena is scaled to keep the paper's density)", |s| s.robots.to_string()))]
    pub robots: Option<usize>,
    /// Steps per run. Default: the scenario's.
    #[arg(long, help = scenario_default("Steps per run", |s| s.steps.to_string()))]
    pub steps: Option<u32>,
    /// Repeats of each condition. Default: the scenario's.
    #[arg(long, help = scenario_default("Repeats of each condition", |s| s.repeats.to_string()))]
    pub repeats: Option<u32>,
    /// Master seed. Default: the scenario's.
    #[arg(long, help = scenario_default("Master seed", |s| s.seed.to_string()))]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores). The output does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Output folder (default `out/<scenario>`, with `-<N>robots` when --robots is given).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// The robots' controller: `firmware` (the robot firmware, machine code on the emulated
    /// H8/300H) or `model` (its Rust model); overrides the scenario's `controller.kind`.
    #[arg(long, value_enum, value_name = "KIND")]
    pub controller: Option<crate::fit_cmd::ControllerArg>,
    /// A firmware image of yours (.mot, with IMAGE.sym beside it when it has a configuration
    /// block) for every robot (or the scenario's `controller.robots`); implies `--controller
    /// firmware`.
    #[arg(long, value_name = "IMAGE")]
    pub firmware: Option<PathBuf>,
    /// When a robot's controller fails (a faulty image: an undefined opcode, a fetch outside
    /// memory, no step for 10 s), mark that robot dead and go on instead of stopping.
    #[arg(long)]
    pub keep_going: bool,
    /// The most memory the run may need, e.g. `8G`, `512M` (default: the memory the machine
    /// has available now). A run estimated to need more is refused before it starts.
    #[arg(long, value_name = "BYTES", value_parser = parse_bytes)]
    pub max_memory: Option<u64>,
    /// Write a pin trace of one firmware robot of the learning run (repeat 0) to FILE as VCD
    /// (PWM, H-bridge, I2C lines, A/D, tick, sleep, the function that runs).
    #[arg(long, value_name = "FILE")]
    pub vcd: Option<PathBuf>,
    /// The robot --vcd traces (default 0).
    #[arg(long, value_name = "K", requires = "vcd")]
    pub vcd_robot: Option<usize>,
    /// The first step --vcd traces (default 0: from reset).
    #[arg(long, value_name = "S", requires = "vcd")]
    pub vcd_from: Option<u32>,
    /// How many steps --vcd traces (default 10, cut at the run's end).
    #[arg(long, value_name = "N", requires = "vcd")]
    pub vcd_steps: Option<u32>,
    /// Wait for a GDB client on this loopback address (127.0.0.1:PORT; port 0 picks a free
    /// one, printed on standard error) and run one firmware robot of the learning run
    /// (repeat 0) under its control; the swarm pauses while the robot is stopped.
    #[arg(long, value_name = "ADDR")]
    pub gdb: Option<String>,
    /// The robot --gdb controls (default 0).
    #[arg(long, value_name = "K", requires = "gdb")]
    pub gdb_robot: Option<usize>,
    /// Record the runs for the browser viewer: writes replay.html (one self-contained page to
    /// open from the file system) with repeat 0 of every condition, every robot.
    #[arg(long)]
    pub replay: bool,
    /// Steps between two recorded frames (default: every step for runs up to 5 000 steps,
    /// else about 5 000 frames a run).
    #[arg(long, value_name = "N", requires = "replay")]
    pub replay_stride: Option<u32>,
    /// The repeats recorded: a list such as `0,2`, or `all` (default 0).
    #[arg(long, value_name = "LIST", requires = "replay")]
    pub replay_repeats: Option<String>,
    /// Record only the first K robots (default: all).
    #[arg(long, value_name = "K", requires = "replay")]
    pub replay_robots: Option<usize>,
    /// Capacity of one cell of the paper's pack (ten 1.2 V NiMH cells), mAh, for the battery
    /// life the summary gives (default: 2 000 mAh, a typical AA NiMH cell of 2008).
    #[arg(long, value_name = "MAH")]
    pub capacity_mah: Option<f64>,
    /// What a firmware robot's stack guard does with the first stack access outside the
    /// stack's room (the end of the firmware's data and boot-sized arrays to its stack's
    /// top): `stop` the run with an error, or `warn` after the run and go on.
    #[arg(long, value_enum, value_name = "ACTION")]
    pub stack_guard: Option<StackGuardArg>,
    /// Write a profile of where one firmware robot's states go by call stack (the learning
    /// run, repeat 0) to FILE as folded stacks, for speedscope, inferno-flamegraph or
    /// flamegraph.pl. The robot then runs instruction by instruction (the same results, more
    /// slowly).
    #[arg(long, value_name = "FILE")]
    pub profile: Option<PathBuf>,
    /// The robot --profile profiles (default 0).
    #[arg(long, value_name = "K", requires = "profile")]
    pub profile_robot: Option<usize>,
    /// Stop a firmware robot (an error, or a dead robot with --keep-going) at its first access
    /// to a register the emulated chip does not model or to a reserved address, instead of
    /// warning about each after the run.
    #[arg(long)]
    pub strict_io: bool,
}

/// What the stack guard does (`--stack-guard`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum StackGuardArg {
    /// Stop at the instruction with a one-line error.
    #[default]
    Stop,
    /// Go on; say which robots' stacks left their room, and where first.
    Warn,
}

impl From<StackGuardArg> for h8300h::cpu::StackGuardMode {
    fn from(g: StackGuardArg) -> Self {
        match g {
            StackGuardArg::Stop => h8300h::cpu::StackGuardMode::Stop,
            StackGuardArg::Warn => h8300h::cpu::StackGuardMode::Warn,
        }
    }
}

/// What `--replay` asks for, checked.
#[derive(Clone, Debug)]
struct ReplayPlan {
    opts: swarm::recording::RecordOptions,
    repeats: Vec<u32>,
    robots: usize,
}

/// Checks the `--replay` options against the scenario.
fn replay_plan(a: &RunArgs, s: &Scenario) -> Result<Option<ReplayPlan>> {
    if !a.replay {
        return Ok(None);
    }
    if a.replay_stride == Some(0) {
        bail!("--replay-stride 0: give at least 1 (record every step)");
    }
    let repeats: Vec<u32> = match a.replay_repeats.as_deref().map(str::trim) {
        None => vec![0],
        Some("all") => (0..s.repeats).collect(),
        Some(list) => {
            let mut v = Vec::new();
            for part in list.split(',') {
                let r: u32 = part.trim().parse().map_err(|_| {
                    anyhow::anyhow!(
                        "--replay-repeats `{}`: `{}` is not a repeat: give repeats 0 to {} separated by commas, or `all`",
                        swarm::text::one_line(list),
                        swarm::text::one_line(part),
                        s.repeats - 1
                    )
                })?;
                if r >= s.repeats {
                    bail!(
                        "--replay-repeats: repeat {r} does not exist: the run has {} repeats (valid: 0 to {})",
                        s.repeats,
                        s.repeats - 1
                    );
                }
                if !v.contains(&r) {
                    v.push(r);
                }
            }
            v.sort_unstable();
            v
        }
    };
    let robots = a.replay_robots.unwrap_or(s.robots);
    if robots == 0 || robots > s.robots {
        bail!(
            "--replay-robots {robots}: the run has {} robots (valid: 1 to {})",
            s.robots,
            s.robots
        );
    }
    Ok(Some(ReplayPlan {
        opts: swarm::recording::RecordOptions::for_steps(s.steps, a.replay_stride),
        repeats,
        robots,
    }))
}

/// Steps `--vcd` traces unless `--vcd-steps` says otherwise.
pub const DEFAULT_VCD_STEPS: u32 = 10;

/// A robot index given with `option`, checked against the scenario: it exists and runs
/// firmware.
fn probed_robot(option: &str, k: usize, s: &Scenario) -> Result<usize> {
    if k >= s.robots {
        bail!(
            "{option} {k}: the run has {} robots (valid: 0 to {})",
            s.robots,
            s.robots - 1
        );
    }
    if s.controller.kind != swarm::scenario::ControllerKind::Firmware {
        bail!(
            "{option} {k}: robot {k} runs the Rust model, which has no firmware to look at (use --controller firmware, or --firmware IMAGE)"
        );
    }
    Ok(k)
}

/// Whether two paths name one file (the same path, or the same file through links).
fn same_file(a: &std::path::Path, b: &std::path::Path) -> bool {
    if a == b {
        return true;
    }
    let parent_and_name = |p: &std::path::Path| {
        let parent = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => std::path::PathBuf::from("."),
        };
        Some((
            std::fs::canonicalize(parent).ok()?,
            p.file_name()?.to_owned(),
        ))
    };
    matches!((parent_and_name(a), parent_and_name(b)), (Some(x), Some(y)) if x == y)
}

/// The probes `--vcd`, `--profile` and `--gdb` ask for, checked (a bad value fails before any run); the
/// GDB stub is listening when this returns.
fn probes(a: &RunArgs, s: &Scenario, stage: &mut Stage) -> Result<swarm::experiment::RobotProbes> {
    let mut p = swarm::experiment::RobotProbes::default();
    if let Some(path) = &a.vcd {
        let robot = probed_robot("--vcd-robot", a.vcd_robot.unwrap_or(0), s)?;
        let from = a.vcd_from.unwrap_or(0);
        if from >= s.steps {
            bail!(
                "--vcd-from {from}: the run has {} steps (valid: 0 to {})",
                s.steps,
                s.steps - 1
            );
        }
        let steps = a.vcd_steps.unwrap_or(DEFAULT_VCD_STEPS);
        if steps == 0 {
            bail!("--vcd-steps 0: trace at least 1 step");
        }
        // The trace is an output like the others: written beside FILE and moved into place
        // with the run's files, or not at all. Fail now, not after the runs, if it cannot be
        // written.
        let staged = stage
            .stage_outside("--vcd", path)
            .map_err(|e| anyhow::Error::new(OutputError(e.0)))?;
        std::fs::write(&staged, b"")
            .map_err(anyhow::Error::new)
            .context(OutputError(format!(
                "--vcd: cannot create `{}`",
                path.display()
            )))?;
        p.vcd = Some(swarm::experiment::VcdProbe {
            robot,
            from,
            steps: steps.min(s.steps - from),
            path: staged,
            shown: path.clone(),
        });
    }
    if let Some(path) = &a.profile {
        let robot = probed_robot("--profile-robot", a.profile_robot.unwrap_or(0), s)?;
        if a.vcd.as_deref().is_some_and(|v| same_file(v, path)) {
            bail!(
                "--profile `{}` is also the --vcd file: give each its own file",
                path.display()
            );
        }
        // Staged and committed with the run's files like the trace; fail now, not after the
        // runs, if it cannot be written.
        let staged = stage
            .stage_outside("--profile", path)
            .map_err(|e| anyhow::Error::new(OutputError(e.0)))?;
        std::fs::write(&staged, b"")
            .map_err(anyhow::Error::new)
            .context(OutputError(format!(
                "--profile: cannot create `{}`",
                path.display()
            )))?;
        p.profile = Some(swarm::experiment::ProfileProbe {
            robot,
            path: staged,
            shown: path.clone(),
        });
    }
    if let Some(addr) = &a.gdb {
        let robot = probed_robot("--gdb-robot", a.gdb_robot.unwrap_or(0), s)?;
        let listener = h8_3052f::gdb::GdbListener::bind(addr).context("--gdb")?;
        let at = listener.local_addr();
        eprintln!(
            "h8swarm run: GDB stub listening on {at} for robot {robot} of the learning run (repeat 0); waiting for a client (target remote {at})"
        );
        p.gdb = Some((robot, listener));
    }
    Ok(p)
}

#[derive(Serialize)]
struct Summary<'a> {
    h8swarm_version: &'static str,
    scenario: &'a Scenario,
    window_steps: u32,
    units: Units,
    eeprom_records_written: u64,
    warnings: &'a [String],
    conditions: &'a [ConditionStats],
    pairings: &'a [Pairing],
    claims: &'a [Claim],
    /// The robots that died in each run (`--keep-going`); their repeats are left out of the
    /// claims and the window statistics.
    dead_robots: Vec<DeadEntry<'a>>,
    /// `false` when the user's image has no configuration block (it ran with its own
    /// settings, not the scenario's); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    image_configured: Option<bool>,
    battery: &'a swarm::battery::BatteryReport,
}

/// A run that ended and wrote its outputs but failed as a whole (every robot died): its report,
/// to print before the error.
#[derive(Debug, thiserror::Error)]
#[error("{why}")]
pub struct FailedRun {
    /// The run's text, as a successful run prints it.
    pub report: String,
    /// Why the run failed.
    pub why: String,
}

/// A dead robot as summary.json lists it.
#[derive(Serialize)]
struct DeadEntry<'a> {
    condition: &'static str,
    repeat: u32,
    #[serde(flatten)]
    robot: &'a swarm::experiment::DeadRobot,
}

/// Runs the experiment; returns the text to print.
///
/// # Errors
/// A bad scenario or option (naming the key or path), an output folder that cannot be written,
/// more robots than the arena holds.
pub fn run(a: &RunArgs) -> Result<String> {
    let what = a.scenario.as_deref().unwrap_or("arena");
    let mut s = Scenario::load(what)?;
    if let Some(k) = a.controller {
        s.controller.kind = match k {
            crate::fit_cmd::ControllerArg::Firmware => swarm::scenario::ControllerKind::Firmware,
            crate::fit_cmd::ControllerArg::Model => swarm::scenario::ControllerKind::Model,
        };
    }
    if let Some(image) = &a.firmware {
        if a.controller == Some(crate::fit_cmd::ControllerArg::Model) {
            bail!("--firmware runs an image on the core: it cannot go with --controller model");
        }
        s.controller.kind = swarm::scenario::ControllerKind::Firmware;
        s.controller.image = Some(image.display().to_string());
    }
    let s = s.with_overrides(a.robots, a.steps, a.repeats, a.seed)?;
    crate::fit_cmd::parse_capacity(a.capacity_mah)?;
    let images = swarm::robot::Images::load(&s)?;
    let unconfigured = unconfigured_image(&s, images.as_ref())?;
    if let Some(image) = &unconfigured {
        eprintln!(
            "warning: {}: the image has no configuration block, so it runs with its own built-in settings, not the scenario's learner, timing and sensor settings (summary.json says \"image_configured\": false); give its symbol table (IMAGE.sym beside it, or controller.symbols) to configure it",
            swarm::text::printable(image)
        );
    }
    let max_threads = max_threads();
    match a.threads {
        Some(0) => bail!("--threads 0: give at least 1 (or leave it out for all cores)"),
        Some(t) if t > max_threads => bail!(
            "--threads {t}: at most {max_threads} on this machine ({THREADS_PER_CORE} per core; more only wait for each other)"
        ),
        _ => {}
    }
    // The folder's name comes from what the user typed (a built-in's name or the file's
    // stem), never from the scenario's `name`, which is data.
    let out = a.out.clone().unwrap_or_else(|| {
        let mut name = default_out_name(what);
        if let Some(n) = a.robots {
            let _ = write!(name, "-{n}robots");
        }
        Path::new("out").join(name)
    });
    let trace_buffers = if a.vcd.is_some() {
        h8_3052f::vcd::STREAM_BUFFER_BYTES
    } else {
        0
    };
    check_memory(&s, threads_or_all(a.threads), a.max_memory, trace_buffers)?;
    // Fail now if the robots do not fit the arena, or a probe's option is bad.
    build_world(&s, 0)?;
    let replay = replay_plan(a, &s)?;
    // Every file (the trace of --vcd too) is written into a staging folder beside `out` and
    // moved into place only when the whole run succeeded; a failure before that leaves `out`
    // (and the trace's file) as it was.
    let mut stage = Stage::new("--out", &out).map_err(|e| anyhow::Error::new(OutputError(e.0)))?;
    let probes = match probes(a, &s, &mut stage) {
        Ok(p) => std::sync::Mutex::new(Some(p)),
        Err(e) => {
            let _ = stage.abandon();
            return Err(e);
        }
    };
    let result = run_into(&RunContext {
        a,
        s: &s,
        images: images.as_ref(),
        probes: &probes,
        replay: replay.as_ref(),
        stage: &stage,
        threads: threads_or_all(a.threads),
    });
    match result {
        Ok((mut text, names, dead)) => {
            let commit = crate::stage::Commit {
                files: names.clone(),
                ours: OUTPUT_FILES.iter().map(|n| (*n).to_string()).collect(),
                folders: Vec::new(),
            };
            stage.commit(&commit).map_err(|e| {
                anyhow::Error::new(OutputError(e.0)).context(format!(
                    "the run into `{}` could not be moved into place",
                    out.display()
                ))
            })?;
            let (files, plots): (Vec<&String>, Vec<&String>) = names
                .iter()
                .partition(|n| !n.ends_with(".png") && !n.ends_with(".svg"));
            let list = |v: &[&String]| v.iter().map(|n| n.as_str()).collect::<Vec<_>>().join(", ");
            let plots: Vec<String> = plots
                .iter()
                .map(|n| out.join(n).display().to_string())
                .collect();
            let _ = writeln!(
                text,
                "wrote {} ({}); plots: {}",
                out.display(),
                list(&files),
                plots.join(", ")
            );
            match dead {
                // The record is written; the run itself is a failure of the image (bad
                // input: exit status 2), reported after the run's own text.
                Some(why) => Err(anyhow::Error::new(FailedRun { report: text, why })),
                None => Ok(text),
            }
        }
        Err(e) => {
            let kept = stage.abandon();
            Err(e.context(format!("the run into `{}` failed; {kept}", out.display())))
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
fn unconfigured_image(
    s: &Scenario,
    images: Option<&swarm::robot::Images>,
) -> Result<Option<String>> {
    let Some((fw, _)) = images.and_then(|i| i.user.as_ref()) else {
        return Ok(None);
    };
    if fw.has_config_block() {
        return Ok(None);
    }
    let image = s.controller.image.clone().unwrap_or_default();
    if s.controls.learning_off || s.controls.random_walk {
        bail!(
            "`controller.image` = {image}: the image has no configuration block (no symbol table names `config_block` at H'000400: give IMAGE.sym beside the image, or controller.symbols), so the controls cannot reach it: learning off (eta = 0) and the random walk would run the same program as learning. Give the image's symbol table, or turn the controls off (controls.learning_off = false, controls.random_walk = false) to run the image as it is"
        );
    }
    Ok(Some(image))
}

/// Host memory one robot takes while its run is going, with a margin (measured, see
/// docs/performance.md: the peak resident size of `h8swarm run --robots 10000` less that of
/// 1 000 robots, per robot: model robots 16 KB; firmware robots 39 KB, the flash and the
/// CPU's decoded code being shared).
pub const MODEL_ROBOT_BYTES: u64 = 24 << 10;
/// See [`MODEL_ROBOT_BYTES`].
pub const FIRMWARE_ROBOT_BYTES: u64 = 56 << 10;
/// Host memory per window of a run kept for the summary and the plots (the window's sums;
/// the steps themselves are written as they complete and not kept), with a margin.
pub const WINDOW_BYTES: u64 = 128;
/// The tool itself (code, fonts, the fit, the plots), with a margin.
pub const BASE_BYTES: u64 = 64 << 20;

/// The memory a run of `s` on `threads` threads is estimated to need: the runs going at once
/// (one per thread) with their robots, and every run's metrics.
#[must_use]
pub fn estimated_memory(s: &Scenario, threads: usize) -> u64 {
    let (runs, at_once) = run_counts(s, threads);
    let per_robot = match s.controller.kind {
        swarm::scenario::ControllerKind::Firmware => FIRMWARE_ROBOT_BYTES,
        swarm::scenario::ControllerKind::Model => MODEL_ROBOT_BYTES,
    };
    BASE_BYTES
        .saturating_add(
            at_once
                .saturating_mul(s.robots as u64)
                .saturating_mul(per_robot),
        )
        .saturating_add(
            runs.saturating_mul(u64::from(s.steps / s.window.max(1)) + 1)
                .saturating_mul(WINDOW_BYTES),
        )
}

/// The runs of `s` (conditions × repeats) and how many of them go at once on `threads`.
fn run_counts(s: &Scenario, threads: usize) -> (u64, u64) {
    let conditions = 1 + u64::from(s.controls.learning_off) + u64::from(s.controls.random_walk);
    let runs = conditions.saturating_mul(u64::from(s.repeats));
    (runs, runs.min(threads as u64).max(1))
}

/// The memory the machine has available now (`MemAvailable` of /proc/meminfo), if known.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb.saturating_mul(1024))
}

/// Address space a run takes beyond the memory it uses: the program's own mappings and
/// thread stacks, and the allocator's reservations (an arena of 64 MiB a thread at most).
/// Only compared with an address-space limit (`ulimit -v`), which counts reservations too.
pub const ADDRESS_SPACE_BASE_BYTES: u64 = 192 << 20;
/// See [`ADDRESS_SPACE_BASE_BYTES`]: per worker thread.
pub const ADDRESS_SPACE_PER_THREAD_BYTES: u64 = 66 << 20;

/// The limits the kernel holds this process to, besides the machine's memory.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProcessLimits {
    /// The soft address-space limit (`ulimit -v`, RLIMIT_AS), bytes.
    pub address_space: Option<u64>,
    /// What the process's control groups still let it use: the least, over its cgroup and
    /// every cgroup above it, of the limit less the usage (cgroup v2 `memory.max` less
    /// `memory.current`, or v1 `memory.limit_in_bytes` less `memory.usage_in_bytes`). Slurm's
    /// `--mem` is such a limit.
    pub cgroup_room: Option<u64>,
}

impl ProcessLimits {
    /// This process's limits, from /proc/self/limits, /proc/self/cgroup and /sys/fs/cgroup
    /// (none where they cannot be read: another system, or no limit).
    #[must_use]
    pub fn read() -> ProcessLimits {
        let limits = std::fs::read_to_string("/proc/self/limits").unwrap_or_default();
        let cgroups = std::fs::read_to_string("/proc/self/cgroup").unwrap_or_default();
        ProcessLimits {
            address_space: address_space_limit(&limits),
            cgroup_room: cgroup_room(Path::new("/sys/fs/cgroup"), &cgroups),
        }
    }
}

/// The soft "Max address space" of a /proc/PID/limits text (`None`: unlimited or absent).
#[must_use]
pub fn address_space_limit(limits: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// The memory the control groups of a /proc/PID/cgroup text still allow, read under `root`
/// (normally /sys/fs/cgroup): v2 (`0::PATH`, `memory.max` and `memory.current`, also under
/// `unified/` on hybrid systems) and v1 (`N:memory:PATH` or `N:…,memory,…:PATH`,
/// `memory/…/memory.limit_in_bytes` and `memory.usage_in_bytes`), each cgroup from the
/// process's own up to the root; a cgroup path the mount does not show is looked up from the
/// mount's root (a container sees its own cgroup there). `None` when no limit is found.
#[must_use]
pub fn cgroup_room(root: &Path, cgroups: &str) -> Option<u64> {
    let read = |p: PathBuf| -> Option<u64> {
        let t = std::fs::read_to_string(p).ok()?;
        t.trim().parse().ok()
    };
    let mut room: Option<u64> = None;
    let mut consider = |limit: Option<u64>, used: Option<u64>| {
        // v1 writes "no limit" as a huge number near 2^63.
        if let Some(limit) = limit.filter(|&l| l < 1 << 60) {
            let left = limit.saturating_sub(used.unwrap_or(0));
            room = Some(room.map_or(left, |r| r.min(left)));
        }
    };
    for line in cgroups.lines() {
        let mut parts = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(path)) = (parts.next(), parts.next(), parts.next())
        else {
            continue;
        };
        let (bases, max_file, used_file): (Vec<PathBuf>, &str, &str) = if controllers.is_empty() {
            (
                vec![root.to_path_buf(), root.join("unified")],
                "memory.max",
                "memory.current",
            )
        } else if controllers.split(',').any(|c| c == "memory") {
            (
                vec![root.join("memory")],
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
            )
        } else {
            continue;
        };
        for base in bases {
            let own = base.join(path.trim_start_matches('/'));
            let start = if own.is_dir() { own } else { base.clone() };
            let mut dir = Some(start.as_path());
            while let Some(d) = dir {
                if !d.starts_with(&base) {
                    break;
                }
                consider(read(d.join(max_file)), read(d.join(used_file)));
                dir = d.parent();
            }
        }
    }
    room
}

/// Refuses a run estimated to need more than `max` (default: the available memory), or than
/// the process's own limits allow ([`ProcessLimits`]: a cgroup's room, and for the address
/// space the need with [`ADDRESS_SPACE_BASE_BYTES`] and [`ADDRESS_SPACE_PER_THREAD_BYTES`]);
/// `extra` is memory the run holds besides the estimate (a pin trace's buffers).
fn check_memory(s: &Scenario, threads: usize, max: Option<u64>, extra: u64) -> Result<()> {
    check_memory_within(s, threads, max, extra, &ProcessLimits::read())
}

fn check_memory_within(
    s: &Scenario,
    threads: usize,
    max: Option<u64>,
    extra: u64,
    limits: &ProcessLimits,
) -> Result<()> {
    let need = estimated_memory(s, threads).saturating_add(extra);
    let address_space = need
        .saturating_add(ADDRESS_SPACE_BASE_BYTES)
        .saturating_add((threads as u64).saturating_mul(ADDRESS_SPACE_PER_THREAD_BYTES));
    let machine = max.or_else(available_memory);
    let refusal = if let Some(limit) = machine.filter(|&l| need > l) {
        Some((
            need,
            if max.is_some() {
                "--max-memory"
            } else {
                "the memory available on this machine"
            },
            limit,
            "raise --max-memory",
        ))
    } else if let Some(room) = limits.cgroup_room.filter(|&r| need > r) {
        Some((
            need,
            "the memory its control group still allows (cgroup memory.max, as Slurm's --mem sets it)",
            room,
            "ask for more memory (Slurm: --mem)",
        ))
    } else {
        limits
            .address_space
            .filter(|&l| address_space > l)
            .map(|l| {
                (
                    address_space,
                    "the address-space limit of this process (ulimit -v)",
                    l,
                    "raise ulimit -v",
                )
            })
    };
    if let Some((need, what, limit, raise)) = refusal {
        let (runs, at_once) = run_counts(s, threads);
        let with_space = if need == address_space {
            format!(
                " of address space (with {} for the program and {} a thread)",
                show_bytes(ADDRESS_SPACE_BASE_BYTES),
                show_bytes(ADDRESS_SPACE_PER_THREAD_BYTES)
            )
        } else {
            " of memory".to_string()
        };
        bail!(
            "this run needs about {}{with_space} ({} robots x {at_once} runs at once, {} steps x {runs} runs of metrics{}) but {what} is {}: use fewer robots, threads, steps or repeats, or {raise}",
            show_bytes(need),
            s.robots,
            s.steps,
            if extra > 0 {
                format!(", {} of pin-trace buffers", show_bytes(extra))
            } else {
                String::new()
            },
            show_bytes(limit)
        );
    }
    Ok(())
}

/// A size for a message: bytes below 1 KiB, else KiB, MiB or GiB with one decimal (never
/// "0 MiB" for a size that is not 0).
#[must_use]
pub fn show_bytes(b: u64) -> String {
    const UNITS: [(u32, &str); 3] = [(30, "GiB"), (20, "MiB"), (10, "KiB")];
    for (shift, unit) in UNITS {
        if b >= 1 << shift {
            return format!("{:.1} {unit}", b as f64 / (1u64 << shift) as f64);
        }
    }
    format!("{b} bytes")
}

/// `--max-memory`: a whole number of bytes, or with a suffix K, M, G or T (powers of 1024).
///
/// # Errors
/// Anything else, saying what is valid.
pub fn parse_bytes(text: &str) -> std::result::Result<u64, String> {
    let t = text.trim();
    let (digits, shift) = match t.chars().last().map(|c| c.to_ascii_uppercase()) {
        Some('K') => (&t[..t.len() - 1], 10),
        Some('M') => (&t[..t.len() - 1], 20),
        Some('G') => (&t[..t.len() - 1], 30),
        Some('T') => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    let n: u64 = digits.parse().map_err(|_| {
        format!("`{text}` is not a size: give bytes as a whole number, optionally with K, M, G or T (e.g. 8G)")
    })?;
    n.checked_mul(1u64 << shift)
        .filter(|&b| b > 0)
        .ok_or_else(|| format!("`{text}`: give a size from 1 byte to 16 EiB"))
}

/// Worker threads at most: [`THREADS_PER_CORE`] per core the machine has.
#[must_use]
pub fn max_threads() -> usize {
    THREADS_PER_CORE * std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
}

/// `--threads` may be up to this many per core.
pub const THREADS_PER_CORE: usize = 8;

fn threads_or_all(t: Option<usize>) -> usize {
    t.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get))
}

/// The default output folder's name for the scenario argument: a built-in's name, or the
/// file's stem reduced to letters, digits, `-`, `_` and `.` (at most 64, never starting with
/// `.`), `scenario` when nothing is left.
#[must_use]
pub fn default_out_name(what: &str) -> String {
    let stem = Path::new(what)
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let clean: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .take(64)
        .collect();
    let clean = clean.trim_start_matches('.').to_string();
    if clean.is_empty() {
        "scenario".to_string()
    } else {
        clean
    }
}

/// Every file `h8swarm run` writes into its output folder (`arena.png` for the square arena,
/// `spacetime.png` for the corridor; the others always).
pub const OUTPUT_FILES: [&str; 9] = [
    "metrics.csv",
    "robots.csv",
    "summary.json",
    "fit.json",
    "learning.png",
    "learning.svg",
    "arena.png",
    "spacetime.png",
    "replay.html",
];

/// The probes of one robot, taken by the first run that asks for them.
type SharedProbes = std::sync::Mutex<Option<swarm::experiment::RobotProbes>>;

/// What one `run` works with: its options, its scenario, the robots' images, the probes and
/// the replay plan, the staging folder its files go into, and its worker threads.
struct RunContext<'r> {
    a: &'r RunArgs,
    s: &'r Scenario,
    images: Option<&'r swarm::robot::Images>,
    probes: &'r SharedProbes,
    replay: Option<&'r ReplayPlan>,
    stage: &'r Stage,
    threads: usize,
}

/// Runs the experiment, writing its files into the staging folder; returns the text to print
/// and the files written.
fn run_into(cx: &RunContext) -> Result<(String, Vec<String>, Option<String>)> {
    let RunContext {
        a,
        s,
        images,
        replay,
        stage,
        threads,
        ..
    } = *cx;
    let (kinds, jobs) = run_jobs(s);
    let floor = swarm::experiment::arena_of(s)?;
    let started = Instant::now();
    let runs = run_all(cx, &jobs, &floor)?;
    let wall_s = started.elapsed().as_secs_f64();

    let parts: Vec<PathBuf> = jobs.iter().map(|&(c, r)| rows_path(stage, c, r)).collect();
    write_metrics(&stage.path("metrics.csv"), &parts)?;
    write_robots(&stage.path("robots.csv"), &runs)?;
    let analysis = analyse(
        &runs,
        s.robots,
        s.steps,
        s.window,
        swarm::seeds::bootstrap_seed(s.seed),
    );
    let warnings = warnings(s);
    let saves: u64 = runs.iter().map(|r| r.saves).sum();
    let battery = battery_report(a, s, &analysis.conditions, &runs)?;
    let summary = Summary {
        h8swarm_version: env!("CARGO_PKG_VERSION"),
        scenario: s,
        window_steps: s.window,
        units: UNITS,
        eeprom_records_written: saves,
        warnings: &warnings,
        conditions: &analysis.conditions,
        pairings: &analysis.pairings,
        claims: &analysis.claims,
        dead_robots: runs
            .iter()
            .flat_map(|r| {
                r.dead.iter().map(|d| DeadEntry {
                    condition: r.condition.name(),
                    repeat: r.repeat,
                    robot: d,
                })
            })
            .collect(),
        image_configured: images
            .and_then(|i| i.user.as_ref())
            .map(|(fw, _)| fw.has_config_block())
            .filter(|configured| !configured),
        battery: &battery,
    };
    write_json(&stage.path("summary.json"), &summary)?;
    let fit = measure_fit(s)?;
    write_json(&stage.path("fit.json"), &fit)?;
    let names = write_figures(s, stage, replay, &floor, &runs)?;

    let mut t = String::new();
    render_header(&mut t, s, kinds.len(), jobs.len(), threads, wall_s);
    for w in &warnings {
        let _ = writeln!(t, "WARNING {w}");
    }
    render_battery(&mut t, &battery);
    let _ = writeln!(t);
    report(&mut t, s, &analysis);
    render_failures(&mut t, &runs);
    let _ = writeln!(t);
    let _ = writeln!(t, "fit: {}", fit.verdict);
    Ok((t, names, all_dead(&runs, s.robots)))
}

/// When every robot of every run died (`--keep-going`): what to say, with the first
/// robot's reason.
fn all_dead(runs: &[RunOutput], robots: usize) -> Option<String> {
    let every = !runs.is_empty() && runs.iter().all(|r| r.dead.len() >= robots);
    every.then(|| {
        let why = runs
            .iter()
            .flat_map(|r| &r.dead)
            .next()
            .map_or_else(String::new, |d| format!(" (the first: {})", d.why));
        format!(
            "every robot of every run died{why}: nothing could be judged (every claim is undecided); the outputs name the dead robots"
        )
    })
}

/// The conditions `s` runs (learning, then the controls it asks for) and its runs: every
/// condition's repeats, condition after condition.
fn run_jobs(s: &Scenario) -> (Vec<Condition>, Vec<(Condition, u32)>) {
    let mut kinds = vec![Condition::Learning];
    if s.controls.learning_off {
        kinds.push(Condition::LearningOff);
    }
    if s.controls.random_walk {
        kinds.push(Condition::RandomWalk);
    }
    let jobs = kinds
        .iter()
        .flat_map(|&c| (0..s.repeats).map(move |r| (c, r)))
        .collect();
    (kinds, jobs)
}

/// The file a run writes its rows of metrics.csv into as its steps complete (they are joined
/// in run order into metrics.csv at the end).
fn rows_path(stage: &Stage, c: Condition, r: u32) -> PathBuf {
    stage.path(&format!(".rows-{}-{r}.csv", c.name()))
}

/// The progress bar of `runs` runs on a terminal (hidden otherwise), counting robot-steps.
fn progress_bar(s: &Scenario, runs: usize, threads: usize) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let b = ProgressBar::new(runs as u64 * u64::from(s.steps));
    b.set_style(
        ProgressStyle::with_template(
            "{spinner} {elapsed_precise} [{bar:40}] {pos}/{len} robot-steps {msg} (eta {eta})",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    b.set_message(format!(
        "x {} robots, {runs} runs on {threads} threads",
        s.robots
    ));
    b
}

/// Runs every job on the context's workers, each run writing its rows into the staging folder
/// (and its frames, when the plan records it); the runs' outputs in job order.
fn run_all(
    cx: &RunContext,
    jobs: &[(Condition, u32)],
    floor: &world::Arena,
) -> Result<Vec<RunOutput>> {
    let RunContext {
        a,
        s,
        images,
        probes,
        replay,
        stage,
        threads,
    } = *cx;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("starting the worker threads")?;
    let bar = progress_bar(s, jobs.len(), threads);
    // Every condition's runs are recorded in the repeats the plan names.
    let recorded = |r: u32| replay.is_some_and(|p| p.repeats.contains(&r));
    let runs = pool.install(|| {
        jobs.par_iter()
            .map(|&(c, r)| {
                let track = c == Condition::Learning && r == 0;
                // The probes go to the learning run's first repeat.
                let probes = if track {
                    probes.lock().ok().and_then(|mut p| p.take())
                } else {
                    None
                };
                let replay = match replay.filter(|_| recorded(r)) {
                    Some(p) => Some((
                        swarm::recording::Recorder::new(
                            p.opts.clone(),
                            (floor.width_m(), floor.height_m()),
                            swarm::recording::part_paths(stage.dir(), c, r),
                        )?,
                        p.robots,
                    )),
                    None => None,
                };
                run_one(
                    s,
                    c,
                    r,
                    images,
                    &|k| bar.inc(k),
                    RunOptions {
                        record_track: track,
                        keep_going: a.keep_going,
                        rows: Some(rows_path(stage, c, r)),
                        probes: probes.unwrap_or_default(),
                        replay,
                        stack_guard: a.stack_guard.unwrap_or_default().into(),
                        strict_io: a.strict_io,
                    },
                )
            })
            .collect::<Result<_>>()
    })?;
    bar.finish_and_clear();
    Ok(runs)
}

/// Writes `value` as pretty JSON with a final newline to `path`.
fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    std::fs::write(path, serde_json::to_string_pretty(value)? + "\n")
        .map_err(anyhow::Error::new)
        .context(OutputError::cannot_write(path))
}

/// The fit verdict of the scenario's learner on the robot firmware (400 steps, compared with
/// the model), for fit.json.
fn measure_fit(s: &Scenario) -> Result<swarm::fit::FitReport> {
    Ok(swarm::fit::measure(&swarm::fit::FitConfig {
        controller: controller_config(s, swarm::fit::fit_weight_seed(s.seed))?,
        steps: 400,
        seed: s.seed,
        kind: swarm::scenario::ControllerKind::Firmware,
        firmware: swarm::fit::FirmwareUnderTest::robot()?,
        compare: true,
        strict_io: false,
    })?)
}

/// Draws the figures (the learning curves; the arena's paths or the corridor's space-time
/// figure) and writes the viewer page when the plan asks for one; returns every file written
/// so far, in [`OUTPUT_FILES`]' order up to the figures.
fn write_figures(
    s: &Scenario,
    stage: &Stage,
    replay: Option<&ReplayPlan>,
    floor: &world::Arena,
    runs: &[RunOutput],
) -> Result<Vec<String>> {
    let (png, svg) = (stage.path("learning.png"), stage.path("learning.svg"));
    let drawn = |e: crate::plot::PlotError| {
        anyhow::Error::new(e).context(OutputError("cannot draw the figures".into()))
    };
    learning_figure(&learning(s, runs), &png, &svg).map_err(drawn)?;
    let mut names: Vec<String> = [
        "metrics.csv",
        "robots.csv",
        "summary.json",
        "fit.json",
        "learning.png",
        "learning.svg",
    ]
    .map(String::from)
    .to_vec();
    if let Some(plan) = replay {
        write_replay(
            s,
            &stage.path("replay.html"),
            stage.dir(),
            plan,
            floor,
            runs,
        )?;
        names.push("replay.html".into());
    }
    if let Some(track) = runs.iter().find_map(|r| r.track.as_ref()) {
        if s.arena == swarm::scenario::ArenaKind::Corridor {
            spacetime_figure(&spacetime(s, track), &stage.path("spacetime.png")).map_err(drawn)?;
            names.push("spacetime.png".into());
        } else {
            arena_figure_panels(&arena(s, track), &stage.path("arena.png")).map_err(drawn)?;
            names.push("arena.png".into());
        }
    }
    Ok(names)
}

/// The report's first lines: what ran, and how fast.
fn render_header(
    t: &mut String,
    s: &Scenario,
    conditions: usize,
    runs: usize,
    threads: usize,
    wall_s: f64,
) {
    let robot_steps = runs as f64 * f64::from(s.steps) * s.robots as f64;
    let simulated_s = runs as f64 * f64::from(s.steps) * s.timing.step_period_s;
    let _ = writeln!(
        t,
        "h8swarm run {}: {} robots, {} steps of {} s, {} x {} conditions, seed {}",
        s.name,
        s.robots,
        s.steps,
        s.timing.step_period_s,
        plural(s.repeats, "repeat"),
        conditions,
        s.seed
    );
    let _ = writeln!(
        t,
        "wall {:.1} s on {}: {:.0} robot-steps/s, {}x real time per run",
        wall_s,
        plural(u32::try_from(threads).unwrap_or(u32::MAX), "thread"),
        robot_steps / wall_s,
        factor_text(simulated_s / wall_s)
    );
}

/// A real-time factor with two significant digits below 10 (0.28, 3.1), whole above.
fn factor_text(f: f64) -> String {
    if f >= 10.0 {
        format!("{f:.0}")
    } else if f >= 1.0 {
        format!("{f:.1}")
    } else {
        format!("{f:.2}")
    }
}

/// One line per robot that died and per stack warning, run by run; one per robot and
/// address its chip does not model, for the first run that touched it.
fn render_failures(t: &mut String, runs: &[RunOutput]) {
    let mut io_seen = std::collections::BTreeSet::new();
    for r in runs {
        for (i, what) in &r.io_warnings {
            if io_seen.insert((*i, what.clone())) {
                let _ = writeln!(
                    t,
                    "IO    robot {i} in {} repeat {}: {what}",
                    r.condition.name(),
                    r.repeat
                );
            }
        }
        for d in &r.dead {
            let _ = writeln!(
                t,
                "DEAD  robot {} in {} repeat {} (from step {}): {}",
                d.robot,
                r.condition.name(),
                r.repeat,
                d.step,
                d.why
            );
        }
        for (i, fault) in &r.stack_warnings {
            let _ = writeln!(
                t,
                "STACK robot {i} in {} repeat {}: {fault}",
                r.condition.name(),
                r.repeat
            );
        }
    }
}

/// Writes the viewer page with the recorded runs (in run order).
fn write_replay(
    s: &Scenario,
    html: &Path,
    stage: &Path,
    plan: &ReplayPlan,
    arena: &world::Arena,
    runs: &[RunOutput],
) -> Result<()> {
    use crate::viewer::{CurveHeader, Header, MountHeader, RunHeader};
    use swarm::recording::part_paths;
    let mut headers = Vec::new();
    let mut parts = Vec::new();
    for r in runs {
        if let Some((frames, weight_frames)) = &r.recorded {
            headers.push(RunHeader {
                condition: r.condition.name().to_string(),
                repeat: r.repeat,
                frames: *frames,
                weight_frames: weight_frames.clone(),
            });
            parts.push(part_paths(stage, r.condition, r.repeat));
        }
    }
    let fig = learning(s, runs);
    let find = |panel: &[Series], label: &str| -> Vec<f64> {
        panel
            .iter()
            .find(|x| x.label == label)
            .map(|x| x.mean.clone())
            .unwrap_or_default()
    };
    let curves = fig
        .d
        .iter()
        .map(|d| CurveHeader {
            condition: d.label.clone(),
            x: d.x.clone(),
            mean_d: d.mean.clone(),
            collisions_per_robot: find(&fig.collisions, &d.label),
            held_percent: find(&fig.held, &d.label),
            net_mm: fig
                .more
                .iter()
                .find(|p| p.caption.starts_with("Net progress"))
                .map(|p| find(&p.series, &d.label))
                .unwrap_or_default(),
        })
        .collect();
    let params = swarm::experiment::world_params(s);
    let n_in = swarm::robot::controller_config(s, 0)?.n_inputs();
    let header = Header {
        version: swarm::recording::VERSION,
        name: s.name.clone(),
        arena: match s.arena {
            swarm::scenario::ArenaKind::Corridor => "corridor".into(),
            swarm::scenario::ArenaKind::Square => "square".into(),
        },
        width_m: arena.width_m(),
        height_m: arena.height_m(),
        quantum_m: swarm::recording::quantum_m(arena.width_m(), arena.height_m()),
        walls: arena
            .walls()
            .iter()
            .map(|w| [w.a.0, w.a.1, w.b.0, w.b.1])
            .collect(),
        body_m: [params.body_length_m, params.body_width_m],
        sensors: params
            .sensor_mounts
            .iter()
            .map(|m| MountHeader {
                x_m: m.x_m,
                y_m: m.y_m,
                angle_rad: m.angle_rad,
            })
            .collect(),
        du_m: sensors::du::MM_PER_DU / 1000.0,
        robots: plan.robots,
        run_robots: s.robots,
        steps: s.steps,
        stride: plan.opts.stride,
        step_period_s: s.timing.step_period_s,
        controller: match s.controller.kind {
            swarm::scenario::ControllerKind::Firmware => "firmware".into(),
            swarm::scenario::ControllerKind::Model => "model".into(),
        },
        seed: s.seed,
        weights_shape: [n_in, s.learner.behaviours],
        behaviours: s.learner.behaviours,
        threshold: s.learner.threshold,
        runs: headers,
        curves,
    };
    crate::viewer::write_viewer(html, &header, &parts)
}

/// `n` and the noun, plural when `n` is not 1.
fn plural(n: u32, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// What the run's shape makes unreliable, said on screen and in summary.json.
fn warnings(s: &Scenario) -> Vec<String> {
    let mut w = Vec::new();
    let windows = s.steps / s.window.max(1);
    if windows < 3 {
        w.push(format!(
            "the run has {windows} whole windows of {} steps: the curves' points are marked and are no trend (use more steps or a smaller window)",
            s.window
        ));
    }
    if s.repeats < 2 {
        w.push("one repeat: no intervals and no paired test (use --repeats 5 or more)".into());
    } else if s.repeats < 5 {
        w.push(format!(
            "{} repeats: a one-sided sign test needs at least 5 repeats all going one way to reach p < 0.05, so no claim can hold",
            s.repeats
        ));
    }
    if let Some(sym) = &s.controller.symbols
        && s.controller.image.is_none()
    {
        w.push(format!(
            "`controller.symbols` = {} is not used: it is the symbol table of `controller.image`, and {}",
            swarm::text::printable(sym),
            if s.controller.kind == swarm::scenario::ControllerKind::Model {
                "the robots run the Rust model (controller.kind = \"model\")"
            } else {
                "the robots run the built-in firmware"
            }
        ));
    }
    w
}

/// The unit of every quantity the outputs hold (the same on screen, in the CSV files, in
/// summary.json and in the figures).
#[derive(Serialize)]
struct Units {
    mean_d: &'static str,
    collisions_per_robot: &'static str,
    collisions_per_net_m: &'static str,
    collisions_per_m: &'static str,
    collisions_per_moving_step: &'static str,
    contact_percent: &'static str,
    held_percent: &'static str,
    shuttling_percent: &'static str,
    circling_percent: &'static str,
    exploring_percent: &'static str,
    moving_percent: &'static str,
    moved_mm: &'static str,
    net_mm: &'static str,
    straightness: &'static str,
    msd_cm2: &'static str,
    msd_exponent: &'static str,
    fresh_cells_per_100_steps: &'static str,
    new_cells: &'static str,
    gap_cv: &'static str,
    touching_percent: &'static str,
    distance_m: &'static str,
    net_m: &'static str,
    cells_visited: &'static str,
}

const UNITS: Units = Units {
    mean_d: "du (1 du = 80/255 cm), mean over robots and steps",
    collisions_per_robot: "collisions per robot over the window",
    collisions_per_net_m: "collisions per net metre: the robots' net displacement over 20 steps, per step, summed (none below 1 m)",
    collisions_per_m: "collisions per metre of path the robots' centres moved (none below 1 m); a reference: shuttling adds path",
    collisions_per_moving_step: "collisions per robot-step in which the robot moved at least 5 mm; a reference",
    contact_percent: "% of robot time with a bumper pressed",
    held_percent: "% of robot-steps held in place (positions over 100 steps within 5 cm of their mean, or under 2 cm of path over 20 steps)",
    shuttling_percent: "% of robot-steps shuttling (net displacement over 20 steps under 0.2 of the path, with a reversal)",
    circling_percent: "% of robot-steps circling (net displacement over 20 steps under 0.2 of the path, no reversal)",
    exploring_percent: "% of robot-steps exploring (net displacement over 20 steps at least 0.2 of the path)",
    moving_percent: "% of robot-steps in which the robot moved at least 5 mm; a reference",
    moved_mm: "mm a robot's centre moved per step (path)",
    net_mm: "mm per step of net progress: a robot's net displacement over the last 20 steps over 20",
    straightness: "net progress over path",
    msd_cm2: "cm², mean squared displacement over 1, 10 and 100 steps",
    msd_exponent: "log10(MSD over 100 steps / MSD over 10): 2 straight driving, 1 diffusion, 0 confinement",
    fresh_cells_per_100_steps: "cells (0.2 m) a robot enters per 100 steps that it had not been in for 100 steps",
    new_cells: "cells (0.2 m) per robot entered for the first time in the run, over the window",
    gap_cv: "coefficient of variation of the gaps between neighbours, over the steps in which no two touch (none when they touch in half the window)",
    touching_percent: "% of corridor steps in which two neighbours are closer than 1 cm",
    distance_m: "metres a robot's centre moved over the run (path)",
    net_m: "net metres a robot made over the run",
    cells_visited: "distinct cells (0.2 m) a robot was in over the run",
};

/// The printed tables: per condition the first and last window, the robots, the pairings and
/// the claims.
fn report(t: &mut String, s: &Scenario, a: &Analysis) {
    report_conditions(t, a);
    if s.repeats < 2 {
        let _ = writeln!(
            t,
            "(windows of {} steps; first -> last window; one repeat, so no intervals)",
            s.window
        );
    } else {
        let _ = writeln!(
            t,
            "(windows of {} steps; first -> last window, mean over repeats; [95 % interval: expanded percentile bootstrap over repeats])",
            s.window
        );
    }
    report_pairings(t, a);
    report_claims(t, a);
}

/// Per condition: the first and last window's measures, and the robots that ended held or
/// had a lasting held spell.
fn report_conditions(t: &mut String, a: &Analysis) {
    let _ = writeln!(
        t,
        "{:<14} {:>26} {:>26} {:>26}",
        "condition", "D (du)", "collisions per robot", "collisions per net metre"
    );
    let arrow = |f: &Estimate, l: &Estimate| format!("{} -> {}", fmt_mean(f), fmt_mean(l));
    for c in &a.conditions {
        let (f, l) = (&c.first, &c.last);
        let _ = writeln!(
            t,
            "{:<14} {:>26} {:>26} {:>26}",
            c.condition.name(),
            arrow(&f.mean_d, &l.mean_d),
            arrow(&f.collisions_per_robot, &l.collisions_per_robot),
            arrow(&f.collisions_per_net_m, &l.collisions_per_net_m),
        );
        let _ = writeln!(
            t,
            "{:<14} last window: D {}, collisions per net metre {} (per path metre {})",
            "",
            fmt_est(&l.mean_d),
            fmt_est(&l.collisions_per_net_m),
            fmt_est(&l.collisions_per_m)
        );
        let _ = writeln!(
            t,
            "{:<14} held {} -> {} %; shuttling {} -> {} %; circling {} -> {} %; exploring {} -> {} %",
            "",
            fmt_mean(&f.held_percent),
            fmt_est(&l.held_percent),
            fmt_mean(&f.shuttling_percent),
            fmt_mean(&l.shuttling_percent),
            fmt_mean(&f.circling_percent),
            fmt_mean(&l.circling_percent),
            fmt_mean(&f.exploring_percent),
            fmt_mean(&l.exploring_percent),
        );
        let _ = writeln!(
            t,
            "{:<14} net progress {} -> {} mm per step of {} -> {} mm path; MSD exponent {} -> {}; fresh cells per 100 steps {} -> {}",
            "",
            fmt_mean(&f.net_mm),
            fmt_est(&l.net_mm),
            fmt_mean(&f.moved_mm),
            fmt_mean(&l.moved_mm),
            fmt_mean(&f.msd_exponent),
            fmt_mean(&l.msd_exponent),
            fmt_mean(&f.fresh_cells_per_100_steps),
            fmt_mean(&l.fresh_cells_per_100_steps),
        );
        let _ = writeln!(
            t,
            "{:<14} contact {} -> {} %; moving (5 mm a step, a reference) {} -> {} %",
            "",
            fmt_mean(&f.contact_percent),
            fmt_est(&l.contact_percent),
            fmt_mean(&f.moving_percent),
            fmt_mean(&l.moving_percent),
        );
        if let (Some(fg), Some(lg)) = (&f.gap_cv, &l.gap_cv) {
            let touching = match (&f.touching_percent, &l.touching_percent) {
                (Some(ft), Some(lt)) => format!(
                    "; neighbours touching {} -> {} % of steps",
                    fmt_mean(ft),
                    fmt_mean(lt)
                ),
                _ => String::new(),
            };
            let _ = writeln!(
                t,
                "{:<14} gap CV {} -> {} (over the steps no neighbours touch){touching}",
                "",
                fmt_mean(fg),
                fmt_est(lg)
            );
        }
        let r = &c.robots;
        let onset = r
            .first_lasting_held_step_median
            .map_or_else(String::new, |m| format!(", median onset step {m:.0}"));
        let _ = writeln!(
            t,
            "{:<14} robots ending the run held {} of {} ({} %); a lasting held spell: {} of {}{onset}",
            "",
            r.ending_held,
            r.robots,
            fmt_est(&r.ending_held_percent),
            r.with_lasting_held_spell,
            r.robots,
        );
    }
}

/// Robot by robot, learning against each control: the robots it frees and traps.
fn report_pairings(t: &mut String, a: &Analysis) {
    for p in &a.pairings {
        let _ = writeln!(
            t,
            "robot by robot against {}: learning frees {} and traps {} of {} robots held at the end, leaves {} alone ({} held under both, {} under neither); McNemar exact p = {}",
            p.other.name(),
            p.frees,
            p.traps,
            p.robots,
            p.both_held + p.neither,
            p.both_held,
            p.neither,
            swarm::summary::fmt_p(p.p)
        );
    }
}

/// One claim's line: its outcome, its words, the values compared (or, for a claim of parts,
/// the repeats that meet all of them), the verdict and what a decision would take.
fn claim_line(t: &mut String, c: &Claim) {
    let values = if c.parts.is_empty() {
        format!(
            "{} vs {} {}",
            fmt_value(c.values[0]),
            fmt_value(c.values[1]),
            c.unit
        )
    } else {
        let r = &c.repeats;
        format!(
            "{} of {} meet all its parts",
            r.for_,
            plural(r.for_ + r.against + r.tied + r.undefined, "repeat")
        )
    };
    let _ = writeln!(
        t,
        "{:<9} {} ({values}: {}; {})",
        c.outcome.word(),
        c.claim,
        c.verdict,
        c.power.words()
    );
}

/// The paper's claims, then those against the controls it lacks, and how many of its text
/// claims hold together.
fn report_claims(t: &mut String, a: &Analysis) {
    let _ = writeln!(t);
    let _ = writeln!(
        t,
        "The paper's claims (learning, paired by repeat, one-sided sign test at p < 0.05):"
    );
    for c in a.claims.iter().filter(|c| c.paper) {
        claim_line(t, c);
    }
    let _ = writeln!(
        t,
        "Their parts, against the controls the paper lacks, and for reference:"
    );
    for c in a.claims.iter().filter(|c| !c.paper) {
        claim_line(t, c);
    }
    let paper: Vec<&Claim> = a.claims.iter().filter(|c| c.paper).collect();
    let held = paper
        .iter()
        .filter(|c| c.outcome == swarm::summary::Outcome::Holds)
        .count();
    let _ = writeln!(
        t,
        "{held} of the paper's {} text claims hold together here{}",
        paper.len(),
        if held == paper.len() {
            ""
        } else {
            " (see docs/claims.md for where they do)"
        }
    );
    // The repeats that would decide every text claim at the effects seen here: what the
    // default run's repeat count is chosen from (docs/claims.md).
    let undecidable: Vec<&str> = paper
        .iter()
        .filter(|c| c.power.repeats_needed.is_none())
        .map(|c| c.claim.split(':').next().unwrap_or(&c.claim))
        .collect();
    let most = paper.iter().filter_map(|c| c.power.repeats_needed).max();
    match (most, undecidable.is_empty()) {
        (Some(n), true) => {
            let _ = writeln!(
                t,
                "at the effects seen here, about {n} repeats would decide every text claim (80 % power each)"
            );
        }
        (_, false) => {
            let _ = writeln!(
                t,
                "no number of repeats decides {} at the effect seen here{}",
                undecidable.join(", "),
                most.map_or_else(String::new, |n| format!(
                    "; the others need about {n} repeats"
                ))
            );
        }
        (None, true) => {}
    }
}

fn fmt_value(v: f64) -> String {
    if v.is_nan() {
        "none".to_string()
    } else {
        format!("{v:.2}")
    }
}

fn fmt_mean(e: &Estimate) -> String {
    if e.mean.is_nan() {
        "none".to_string()
    } else {
        format!("{:.2}", e.mean)
    }
}

/// The battery life of each condition ([`swarm::battery::BatteryReport`]) for the pack
/// `--capacity-mah` gives.
fn battery_report(
    a: &RunArgs,
    s: &Scenario,
    stats: &[ConditionStats],
    runs: &[RunOutput],
) -> Result<swarm::battery::BatteryReport> {
    let pack = swarm::energy::Pack::paper(crate::fit_cmd::parse_capacity(a.capacity_mah)?);
    let mut b = swarm::battery::BatteryReport::of(stats, pack, s.timing.step_period_s);
    let robot_seconds = s.robots as f64 * f64::from(s.steps) * s.timing.step_period_s;
    for c in stats {
        let of_c: Vec<&RunOutput> = runs.iter().filter(|r| r.condition == c.condition).collect();
        b.by_part.push(swarm::battery::ConditionParts::of(
            c.condition,
            &of_c,
            robot_seconds,
        ));
    }
    Ok(b)
}

/// The battery lines of the summary: each condition's battery life in its first and last
/// windows, its mean current by part, and what learning costs or saves against the controls.
fn render_battery(t: &mut String, b: &swarm::battery::BatteryReport) {
    let _ = writeln!(t);
    let _ = writeln!(
        t,
        "battery life, {} x {} V NiMH of {:.0} mAh (the paper: up to {} h); a robot's mean current:",
        b.pack.cells, b.pack.cell_volts, b.pack.capacity_mah, b.paper_h
    );
    for (c, parts) in b.conditions.iter().zip(&b.by_part) {
        let _ = writeln!(
            t,
            "{:<14} {} h ({:.0} mA) -> {} h ({:.0} mA)",
            c.condition.name(),
            fmt_est(&c.first_h),
            c.first_current_ma,
            fmt_est(&c.last_h),
            c.last_current_ma
        );
        let list: Vec<String> = parts
            .current_ma
            .iter()
            .map(|(k, ma)| format!("{k} {ma:.1}"))
            .collect();
        let _ = writeln!(t, "{:<14} whole run, mA: {}", "", list.join(", "));
        let cap = parts.motor_cap;
        if cap.capped_wheel_substeps > 0 {
            let _ = writeln!(
                t,
                "{:<14} motor current cut to the drive voltage's bound in {} of {} driven wheel-sub-steps",
                "", cap.capped_wheel_substeps, cap.driven_wheel_substeps
            );
        }
    }
    for cmp in &b.learning_against {
        let _ = writeln!(
            t,
            "learning {} {:.1} % of battery life ({:+.2} h) against {} in the last window ({})",
            if cmp.change_h >= 0.0 {
                "saves"
            } else {
                "costs"
            },
            cmp.change_percent.abs(),
            cmp.change_h,
            cmp.against.name(),
            if cmp.apart {
                "energy intervals apart"
            } else {
                "energy intervals overlap"
            }
        );
    }
}

fn fmt_est(e: &Estimate) -> String {
    match (e.lo, e.hi) {
        _ if e.mean.is_nan() => "none".to_string(),
        (Some(lo), Some(hi)) => format!("{:.2} [{:.2}, {:.2}]", e.mean, lo, hi),
        _ => format!("{:.2}", e.mean),
    }
}

/// The columns of `robots.csv`, one row per robot of every run.
pub const ROBOTS_HEADER: [&str; 20] = [
    "condition",
    "repeat",
    "robot",
    "distance_m",
    "net_m",
    "collisions",
    "moving_steps",
    "held_steps",
    "shuttling_steps",
    "circling_steps",
    "exploring_steps",
    "cells_visited",
    "ends_held",
    "first_lasting_held_step",
    "last_window_distance_m",
    "last_window_net_m",
    "last_window_collisions",
    "last_window_cells",
    "last_class",
    "died_at_step",
];

/// Writes every robot's record of every run (in run order, robots in index order).
fn write_robots(path: &Path, runs: &[RunOutput]) -> Result<()> {
    let write = || -> Result<()> {
        let mut w = csv::Writer::from_path(path)?;
        w.write_record(ROBOTS_HEADER)?;
        for r in runs {
            for (i, t) in r.robots.iter().enumerate() {
                use swarm::motion::MotionClass;
                w.write_record([
                    r.condition.name().to_string(),
                    r.repeat.to_string(),
                    i.to_string(),
                    format!("{}", t.distance_m),
                    format!("{}", t.net_m),
                    t.collisions.to_string(),
                    t.moving_steps.to_string(),
                    t.steps_in(MotionClass::Held).to_string(),
                    t.steps_in(MotionClass::Shuttling).to_string(),
                    t.steps_in(MotionClass::Circling).to_string(),
                    t.steps_in(MotionClass::Exploring).to_string(),
                    t.cells_visited.to_string(),
                    u8::from(t.ends_held).to_string(),
                    t.first_lasting_held_step
                        .map(|k| k.to_string())
                        .unwrap_or_default(),
                    format!("{}", t.last_window_distance_m),
                    format!("{}", t.last_window_net_m),
                    t.last_window_collisions.to_string(),
                    t.last_window_cells.to_string(),
                    t.last_class
                        .map(MotionClass::name)
                        .unwrap_or_default()
                        .to_string(),
                    r.dead
                        .iter()
                        .find(|d| d.robot == i)
                        .map(|d| d.step.to_string())
                        .unwrap_or_default(),
                ])?;
            }
        }
        w.flush()?;
        Ok(())
    };
    write().context(OutputError::cannot_write(path))
}

/// Joins the runs' row files (in run order) under the header into `path`, removing them.
fn write_metrics(path: &Path, parts: &[PathBuf]) -> Result<()> {
    write_metrics_csv(path, parts).context(OutputError::cannot_write(path))
}

fn write_metrics_csv(path: &Path, parts: &[PathBuf]) -> Result<()> {
    let mut w = csv::Writer::from_path(path)?;
    w.write_record(swarm::experiment::METRICS_HEADER)?;
    let mut out = w
        .into_inner()
        .map_err(|e| anyhow::anyhow!("{}", e.error()))?;
    for part in parts {
        let mut f = std::fs::File::open(part)
            .with_context(|| format!("reading the run's rows `{}`", part.display()))?;
        std::io::copy(&mut f, &mut out)?;
        std::fs::remove_file(part)?;
    }
    std::io::Write::flush(&mut out)?;
    Ok(())
}

/// The learning figure: per condition, mean D and collisions per robot per window (the
/// paper's two panels), then collisions per net metre, net progress, collisions per path metre
/// (a reference), the area covered, contact time, exploring robot-steps and, in the corridor,
/// the gap CV and the steps with neighbours touching; the held robot-steps drawn dotted beside
/// every collision curve. Each curve is the mean over repeats with its 95 % band (the mean
/// alone with one repeat); a window in which no repeat has a value (collisions per net metre of
/// robots that went nowhere) has no point, and one in which only some have a value is drawn
/// as an open circle with their number beside it, without a band.
fn learning(s: &Scenario, runs: &[RunOutput]) -> LearningFigure {
    let win = s.window.max(1);
    let windows = runs
        .iter()
        .map(|r| r.metrics.whole_windows().len())
        .min()
        .unwrap_or(0);
    let seed = swarm::seeds::bootstrap_seed(s.seed);
    let panel = |q: Quantity| -> Vec<Series> {
        let mut out = Vec::new();
        for c in Condition::ALL {
            let mut of_c: Vec<&RunOutput> = runs.iter().filter(|r| r.condition == c).collect();
            if of_c.is_empty() {
                continue;
            }
            of_c.sort_by_key(|r| r.repeat);
            let (mut xs, mut m, mut lo, mut hi, mut n) = (vec![], vec![], vec![], vec![], vec![]);
            for w in 0..windows {
                let vals: Vec<Option<f64>> = of_c
                    .iter()
                    .map(|r| q.of(&r.metrics.windows[w], s.robots))
                    .collect();
                let e = Estimate::of_defined(&vals, seed);
                if e.n == 0 {
                    continue;
                }
                xs.push(f64::from(w as u32 * win + win / 2));
                m.push(e.mean);
                lo.push(e.lo.unwrap_or(e.mean));
                hi.push(e.hi.unwrap_or(e.mean));
                n.push(e.n);
            }
            if xs.is_empty() {
                continue;
            }
            out.push(Series {
                label: match c {
                    Condition::Learning => "learning".to_string(),
                    Condition::LearningOff => "learning off (η = 0)".to_string(),
                    Condition::RandomWalk => "random walk".to_string(),
                },
                dashed: c != Condition::Learning,
                x: xs,
                mean: m,
                lo,
                hi,
                n,
                repeats: of_c.len(),
            });
        }
        out
    };
    let mut more = Vec::new();
    let mut add = |caption: &str, y_label: &str, q: Quantity, held_overlay: bool| {
        let series = panel(q);
        if !series.is_empty() {
            more.push(Panel {
                caption: caption.to_string(),
                y_label: y_label.to_string(),
                series,
                held_overlay,
            });
        }
    };
    add(
        "Collisions per net metre (shuttling and standing earn nothing)",
        "collisions per net metre",
        Quantity::CollisionsPerNetM,
        true,
    );
    add(
        "Net progress (net displacement over 20 steps, per step)",
        "mm per step",
        Quantity::NetMm,
        false,
    );
    add(
        "Collisions per path metre (a reference: shuttling adds path)",
        "collisions per metre of path",
        Quantity::CollisionsPerM,
        true,
    );
    add(
        "Area covered (cells of 0.2 m not visited for 100 steps)",
        "fresh cells per 100 steps",
        Quantity::FreshCells,
        false,
    );
    add(
        "Contact time (a bumper pressed)",
        "% of robot time",
        Quantity::ContactPercent,
        false,
    );
    add(
        "Robot-steps exploring (net at least 0.2 of the path)",
        "% of robot-steps",
        Quantity::ExploringPercent,
        false,
    );
    if runs.iter().all(|r| r.metrics.whole.is_corridor()) {
        add(
            "Gap CV between neighbours (steps none touch; even: low)",
            "coefficient of variation",
            Quantity::GapCv,
            false,
        );
        add(
            "Steps with neighbours touching (closer than 1 cm)",
            "% of steps",
            Quantity::TouchingPercent,
            false,
        );
    }
    LearningFigure {
        title: format!(
            "h8swarm {}: {} robots, {}, windows of {} steps ({} s per step){}",
            s.name,
            s.robots,
            plural(s.repeats, "repeat"),
            s.window,
            s.timing.step_period_s,
            if windows < 3 {
                format!(": only {windows} windows, no trend")
            } else {
                String::new()
            }
        ),
        x_label: "learning step".to_string(),
        d: panel(Quantity::MeanD),
        collisions: panel(Quantity::CollisionsPerRobot),
        more,
        held: panel(Quantity::HeldPercent),
        markers: windows < 3,
    }
}

/// The corridor's space-time figure: each tracked robot's position along the corridor over
/// the run (learning, repeat 0).
fn spacetime(s: &Scenario, t: &swarm::experiment::Track) -> SpaceTimeFigure {
    let length_m = t
        .walls
        .iter()
        .flat_map(|w| [w[0].0, w[1].0])
        .fold(0.0, f64::max);
    SpaceTimeFigure {
        title: format!(
            "{}: the robots along the corridor (learning, repeat 0, seed {}); bands = bodies, white = gaps",
            s.name, s.seed
        ),
        length_m,
        body_m: world::params::BODY_LENGTH_M,
        paths: t.spacetime.clone(),
    }
}

/// The arena figure as the paper's Fig. 8 shows learning: the first and the last
/// [`swarm::experiment::SNAPSHOT_STEPS`] steps' paths in two panels, with the outlines at the
/// start and the end of each.
fn arena(s: &Scenario, t: &swarm::experiment::Track) -> Vec<ArenaFigure> {
    let k = swarm::experiment::SNAPSHOT_STEPS.min(s.steps as usize);
    let n = s.steps as usize;
    let first_of = |from: usize, to: usize| -> ArenaFigure {
        let paths = if from == 0 { &t.early } else { &t.late }.clone();
        let t0 = from as f64 * s.timing.step_period_s;
        let t1 = to as f64 * s.timing.step_period_s;
        let outlines = t
            .outlines
            .iter()
            .filter(|o| o.time_s >= t0 - 1.0 && o.time_s <= t1 + 1.0)
            .cloned()
            .collect();
        ArenaFigure {
            title: format!(
                "learning, repeat 0, seed {}: {} {} steps ({:.0}-{:.0} s), {} robots{}",
                s.seed,
                if from == 0 { "first" } else { "last" },
                to - from,
                t0,
                t1,
                s.robots,
                if t.early.len() < s.robots {
                    format!(", paths of the first {}", t.early.len())
                } else {
                    String::new()
                }
            ),
            walls: t.walls.clone(),
            paths,
            outlines,
        }
    };
    vec![first_of(0, k), first_of(n - k, n)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_sizes_parse_and_estimates_grow_with_the_run() {
        assert_eq!(parse_bytes("512M"), Ok(512 << 20));
        assert_eq!(parse_bytes("8g"), Ok(8 << 30));
        assert_eq!(parse_bytes("1000"), Ok(1000));
        for bad in ["", "0", "-1", "8 GB", "1.5G", "99999999999T"] {
            assert!(parse_bytes(bad).is_err(), "{bad}");
        }
        let s = Scenario::arena();
        let one = estimated_memory(&s, 1);
        assert!(estimated_memory(&s, 2) > one);
        let big = s
            .clone()
            .with_overrides(Some(100_000), None, None, None)
            .unwrap();
        // 100 000 model robots on one thread: about 2.3 GiB (24 KiB a robot), under 4 GiB.
        let e = estimated_memory(&big, 1);
        assert!(e > 2 << 30 && e < 3 << 30, "{e}");
        assert!(check_memory(&big, 1, Some(2 << 30), 0).is_err());
        assert!(check_memory(&big, 1, Some(4 << 30), 0).is_ok());
        assert!(check_memory(&s, 1, Some(8 << 30), 0).is_ok());
    }

    #[test]
    fn sizes_in_messages_are_never_rounded_to_nothing() {
        assert_eq!(show_bytes(1), "1 bytes");
        assert_eq!(show_bytes(1023), "1023 bytes");
        assert_eq!(show_bytes(1024), "1.0 KiB");
        assert_eq!(show_bytes(1536), "1.5 KiB");
        assert_eq!(show_bytes(64 << 20), "64.0 MiB");
        assert_eq!(show_bytes(22 << 30), "22.0 GiB");
        let e = check_memory(&Scenario::arena(), 1, Some(1024), 0).unwrap_err();
        assert!(e.to_string().contains("--max-memory is 1.0 KiB"), "{e}");
    }

    #[test]
    fn the_process_limits_are_read_and_checked() {
        let limits = "Limit                     Soft Limit           Hard Limit           Units\nMax data size             unlimited            unlimited            bytes\nMax address space         4096000000           unlimited            bytes\n";
        assert_eq!(address_space_limit(limits), Some(4_096_000_000));
        assert_eq!(
            address_space_limit("Max address space  unlimited  unlimited  bytes\n"),
            None
        );
        // A fake cgroup tree: v2 with a limit on a parent, v1 with its own.
        let root = std::env::temp_dir().join(format!("h8swarm-cgroups-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let job = root.join("slurm/job_7/step_0");
        std::fs::create_dir_all(&job).unwrap();
        std::fs::write(root.join("slurm/job_7/memory.max"), "1073741824\n").unwrap();
        std::fs::write(root.join("slurm/job_7/memory.current"), "73741824\n").unwrap();
        std::fs::write(job.join("memory.max"), "max\n").unwrap();
        assert_eq!(
            cgroup_room(&root, "0::/slurm/job_7/step_0\n"),
            Some(1_000_000_000)
        );
        assert_eq!(cgroup_room(&root, "0::/elsewhere\n"), None);
        let v1 = root.join("memory/job");
        std::fs::create_dir_all(&v1).unwrap();
        std::fs::write(v1.join("memory.limit_in_bytes"), "536870912\n").unwrap();
        std::fs::write(v1.join("memory.usage_in_bytes"), "36870912\n").unwrap();
        std::fs::write(
            root.join("memory/memory.limit_in_bytes"),
            "9223372036854771712\n",
        )
        .unwrap();
        assert_eq!(cgroup_room(&root, "4:memory:/job\n"), Some(500_000_000));
        let _ = std::fs::remove_dir_all(&root);
        // The checks: a cgroup's room, then the address space.
        let s = Scenario::arena();
        let roomy = ProcessLimits::default();
        assert!(check_memory_within(&s, 2, Some(1 << 40), 0, &roomy).is_ok());
        let tight = ProcessLimits {
            cgroup_room: Some(10 << 20),
            address_space: None,
        };
        let e = check_memory_within(&s, 2, Some(1 << 40), 0, &tight).unwrap_err();
        assert!(e.to_string().contains("control group"), "{e}");
        let small_as = ProcessLimits {
            cgroup_room: None,
            address_space: Some(200 << 20),
        };
        let e = check_memory_within(&s, 2, Some(1 << 40), 0, &small_as).unwrap_err();
        assert!(e.to_string().contains("ulimit -v"), "{e}");
    }

    #[test]
    fn output_names_come_from_the_argument_not_the_data() {
        assert_eq!(default_out_name("arena"), "arena");
        assert_eq!(
            default_out_name("scenarios/arena-surface.toml"),
            "arena-surface"
        );
        assert_eq!(default_out_name("/etc/../x y$z.toml"), "x_y_z");
        assert_eq!(default_out_name("..toml"), "scenario");
        assert_eq!(default_out_name("dir/.hidden.toml"), "hidden");
        assert_eq!(default_out_name(&"a".repeat(300)).len(), 64);
    }
}
