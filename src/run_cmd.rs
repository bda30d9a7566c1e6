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

use crate::experiment::{RunOptions, RunOutput, build_world, run_one};
use crate::plot::{
    ArenaFigure, LearningFigure, Panel, Series, arena_figure_panels, learning_figure,
};
use crate::robot::{Condition, controller_config};
use crate::scenario::Scenario;
use crate::summary::{Claim, ConditionStats, Estimate, claims, conditions};

/// Options of `h8swarm run`.
#[derive(Args, Debug, Default, Clone)]
pub struct RunArgs {
    /// `arena` (default), `corridor`, or a scenario file (.toml).
    pub scenario: Option<String>,
    /// Robots (the square arena is scaled to keep the paper's density).
    #[arg(long)]
    pub robots: Option<usize>,
    /// Steps per run.
    #[arg(long)]
    pub steps: Option<u32>,
    /// Repeats of each condition.
    #[arg(long)]
    pub repeats: Option<u32>,
    /// Master seed.
    #[arg(long)]
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
    /// Capacity of one cell of the paper's pack (ten 1.2 V NiMH cells), mAh, for the battery
    /// life the summary gives (default: 2 000 mAh, a typical AA NiMH cell of 2008).
    #[arg(long, value_name = "MAH")]
    pub capacity_mah: Option<f64>,
    /// What a firmware robot's stack guard does with the first stack access outside the
    /// stack's room (the end of the firmware's data and boot-sized arrays to its stack's
    /// top): `stop` the run with an error, or `warn` after the run and go on.
    #[arg(long, value_enum, value_name = "ACTION")]
    pub stack_guard: Option<StackGuardArg>,
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

impl From<StackGuardArg> for emu::core::cpu::StackGuardMode {
    fn from(g: StackGuardArg) -> Self {
        match g {
            StackGuardArg::Stop => emu::core::cpu::StackGuardMode::Stop,
            StackGuardArg::Warn => emu::core::cpu::StackGuardMode::Warn,
        }
    }
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
    if s.controller.kind != crate::fit::ControllerKind::Firmware {
        bail!(
            "{option} {k}: robot {k} runs the Rust model, which has no firmware to look at (use --controller firmware, or --firmware IMAGE)"
        );
    }
    Ok(k)
}

/// The probes `--vcd` and `--gdb` ask for, checked (a bad value fails before any run); the
/// GDB stub is listening when this returns.
fn probes(a: &RunArgs, s: &Scenario) -> Result<crate::experiment::RobotProbes> {
    let mut p = crate::experiment::RobotProbes::default();
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
        // Fail now, not after the runs, if the file cannot be written.
        std::fs::write(path, b"")
            .map_err(anyhow::Error::new)
            .context(OutputError(format!(
                "--vcd: cannot create `{}`",
                path.display()
            )))?;
        p.vcd = Some(crate::experiment::VcdProbe {
            robot,
            from,
            steps: steps.min(s.steps - from),
            path: path.clone(),
        });
    }
    if let Some(addr) = &a.gdb {
        let robot = probed_robot("--gdb-robot", a.gdb_robot.unwrap_or(0), s)?;
        let listener = emu::chip::gdb::GdbListener::bind(addr).context("--gdb")?;
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
    eeprom_records_written: u64,
    conditions: &'a [ConditionStats],
    claims: &'a [Claim],
    battery: &'a crate::energy::BatteryReport,
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
            crate::fit_cmd::ControllerArg::Firmware => crate::fit::ControllerKind::Firmware,
            crate::fit_cmd::ControllerArg::Model => crate::fit::ControllerKind::Model,
        };
    }
    if let Some(image) = &a.firmware {
        if a.controller == Some(crate::fit_cmd::ControllerArg::Model) {
            bail!("--firmware runs an image on the core: it cannot go with --controller model");
        }
        s.controller.kind = crate::fit::ControllerKind::Firmware;
        s.controller.image = Some(image.display().to_string());
    }
    let s = s.with_overrides(a.robots, a.steps, a.repeats, a.seed)?;
    crate::fit_cmd::parse_capacity(a.capacity_mah)?;
    let images = crate::robot::Images::load(&s)?;
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
    check_memory(&s, threads_or_all(a.threads), a.max_memory)?;
    // Fail now if the robots do not fit the arena, or a probe's option is bad.
    build_world(&s, 0)?;
    let probes = std::sync::Mutex::new(Some(probes(a, &s)?));
    // Every file is written into a staging folder beside `out` and moved into place only
    // when the whole run succeeded; a failure before that leaves `out` as it was.
    let stage = Stage::new(&out)?;
    let result = run_into(
        a,
        &s,
        images.as_ref(),
        &probes,
        &stage,
        threads_or_all(a.threads),
    );
    match result {
        Ok((mut text, names)) => {
            stage.commit(&names)?;
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
            Ok(text)
        }
        Err(e) => {
            let kept = stage.abandon();
            Err(e.context(format!("the run into `{}` failed; {kept}", out.display())))
        }
    }
}

/// Host memory one robot takes while its run is going (measured: the peak resident size of
/// `h8swarm run --robots 1000` less that of 100 robots, per robot, with model robots 148 KB,
/// with firmware robots 855 KB: the MCU's flash image, RAM and decode cache), with a margin.
pub const MODEL_ROBOT_BYTES: u64 = 192 << 10;
/// See [`MODEL_ROBOT_BYTES`].
pub const FIRMWARE_ROBOT_BYTES: u64 = 1 << 20;
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
        crate::fit::ControllerKind::Firmware => FIRMWARE_ROBOT_BYTES,
        crate::fit::ControllerKind::Model => MODEL_ROBOT_BYTES,
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

/// Whether `e` is an output that could not be written ([`OutputError`] anywhere in its chain
/// of contexts): the tool failed (exit status 1), not the input.
#[must_use]
pub fn is_output_error(e: &anyhow::Error) -> bool {
    e.downcast_ref::<OutputError>().is_some()
}

/// The memory the machine has available now (`MemAvailable` of /proc/meminfo), if known.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb.saturating_mul(1024))
}

/// Refuses a run estimated to need more than `max` (default: the available memory).
fn check_memory(s: &Scenario, threads: usize, max: Option<u64>) -> Result<()> {
    let Some(limit) = max.or_else(available_memory) else {
        return Ok(());
    };
    let need = estimated_memory(s, threads);
    if need > limit {
        let what = if max.is_some() {
            "--max-memory"
        } else {
            "the memory available on this machine"
        };
        let (runs, at_once) = run_counts(s, threads);
        bail!(
            "this run needs about {} of memory ({} robots x {at_once} runs at once, {} steps x {runs} runs of metrics) but {what} is {}: use fewer robots, threads, steps or repeats, or raise --max-memory",
            show_bytes(need),
            s.robots,
            s.steps,
            show_bytes(limit)
        );
    }
    Ok(())
}

fn show_bytes(b: u64) -> String {
    if b >= 1 << 30 {
        format!("{:.1} GiB", b as f64 / f64::from(1u32 << 30))
    } else {
        format!("{:.0} MiB", b as f64 / f64::from(1u32 << 20))
    }
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

/// An output that cannot be written (the tool failed: exit status 1), as the context of the
/// error that says why.
#[derive(Debug)]
pub struct OutputError(pub String);

impl std::fmt::Display for OutputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for OutputError {}

/// A staging folder beside the output folder: `<parent>/.<name>.partial-<pid>`.
struct Stage {
    out: PathBuf,
    dir: PathBuf,
}

impl Stage {
    fn new(out: &Path) -> Result<Stage> {
        let name = out
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .filter(|n| n != "." && n != "..")
            .ok_or_else(|| {
                anyhow::Error::new(OutputError(format!(
                    "--out `{}`: give a folder name (e.g. out/run1), not a root or `..`",
                    out.display()
                )))
            })?;
        if out.exists() && !out.is_dir() {
            return Err(anyhow::Error::new(OutputError(format!(
                "--out `{}` is a file: give a folder (new or holding earlier results)",
                out.display()
            ))));
        }
        let parent = match out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let dir = parent.join(format!(".{name}.partial-{}", std::process::id()));
        std::fs::create_dir_all(&dir)
            .map_err(anyhow::Error::new)
            .context(OutputError(format!(
                "cannot create the staging folder `{}` beside the output folder",
                dir.display()
            )))?;
        Ok(Stage {
            out: out.to_path_buf(),
            dir,
        })
    }

    fn path(&self, file: &str) -> PathBuf {
        self.dir.join(file)
    }

    /// Moves the staged files into `out` (replacing earlier ones of the same names, removing
    /// this tool's files the run did not write) and removes the staging folder.
    fn commit(&self, names: &[String]) -> Result<()> {
        let fail =
            |what: String, e: std::io::Error| anyhow::Error::new(e).context(OutputError(what));
        std::fs::create_dir_all(&self.out).map_err(|e| {
            fail(
                format!("cannot create the output folder `{}`", self.out.display()),
                e,
            )
        })?;
        for name in names {
            let to = self.out.join(name);
            std::fs::rename(self.dir.join(name), &to).map_err(|e| {
                fail(
                    format!("cannot move `{name}` into `{}`", self.out.display()),
                    e,
                )
            })?;
        }
        for old in OUTPUT_FILES {
            if !names.iter().any(|n| n == old) {
                let stale = self.out.join(old);
                if stale.is_file() {
                    std::fs::remove_file(&stale).map_err(|e| {
                        fail(
                            format!("cannot remove the earlier `{}`", stale.display()),
                            e,
                        )
                    })?;
                }
            }
        }
        let _ = std::fs::remove_dir_all(&self.dir);
        Ok(())
    }

    /// Removes the staging folder after a failure; says what became of `out`.
    fn abandon(&self) -> String {
        let _ = std::fs::remove_dir_all(&self.dir);
        if self.out.is_dir() {
            "the earlier results there are untouched".to_string()
        } else {
            "nothing was written".to_string()
        }
    }
}

/// Every file `h8swarm run` writes into its output folder.
pub const OUTPUT_FILES: [&str; 6] = [
    "metrics.csv",
    "summary.json",
    "fit.json",
    "learning.png",
    "learning.svg",
    "arena.png",
];

/// Runs the experiment, writing its files into `stage`; returns the text to print and the
/// files written.
fn run_into(
    a: &RunArgs,
    s: &Scenario,
    images: Option<&crate::robot::Images>,
    probes: &std::sync::Mutex<Option<crate::experiment::RobotProbes>>,
    stage: &Stage,
    threads: usize,
) -> Result<(String, Vec<String>)> {
    let metrics_path = stage.path("metrics.csv");

    let mut jobs: Vec<(Condition, u32)> = Vec::new();
    let mut kinds = vec![Condition::Learning];
    if s.controls.learning_off {
        kinds.push(Condition::LearningOff);
    }
    if s.controls.random_walk {
        kinds.push(Condition::RandomWalk);
    }
    for c in &kinds {
        for r in 0..s.repeats {
            jobs.push((*c, r));
        }
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("starting the worker threads")?;
    let total = jobs.len() as u64 * u64::from(s.steps);
    let bar = if std::io::stderr().is_terminal() {
        let b = ProgressBar::new(total);
        b.set_style(
            ProgressStyle::with_template(
                "{spinner} {elapsed_precise} [{bar:40}] {pos}/{len} robot-steps {msg} (eta {eta})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        b.set_message(format!(
            "x {} robots, {} runs on {threads} threads",
            s.robots,
            jobs.len()
        ));
        b
    } else {
        ProgressBar::hidden()
    };
    let started = Instant::now();
    // Each run writes its rows as its steps complete into a file of its own in the staging
    // folder; they are joined in run order into metrics.csv at the end.
    let rows_path = |c: Condition, r: u32| stage.path(&format!(".rows-{}-{r}.csv", c.name()));
    let runs: Vec<RunOutput> = pool.install(|| {
        jobs.par_iter()
            .map(|&(c, r)| {
                let track = c == Condition::Learning && r == 0;
                // The probes go to the learning run's first repeat.
                let probes = if track {
                    probes.lock().ok().and_then(|mut p| p.take())
                } else {
                    None
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
                        rows: Some(rows_path(c, r)),
                        probes: probes.unwrap_or_default(),
                        stack_guard: a.stack_guard.unwrap_or_default().into(),
                    },
                )
            })
            .collect::<Result<_>>()
    })?;
    bar.finish_and_clear();
    let wall_s = started.elapsed().as_secs_f64();

    let parts: Vec<PathBuf> = jobs.iter().map(|&(c, r)| rows_path(c, r)).collect();
    write_metrics(&metrics_path, &parts)?;
    let stats = conditions(&runs, s.steps, s.window);
    let checked = claims(&stats);
    let saves: u64 = runs.iter().map(|r| r.saves).sum();
    let battery = battery_report(a, s, &stats, &runs)?;
    let summary = Summary {
        h8swarm_version: env!("CARGO_PKG_VERSION"),
        scenario: s,
        window_steps: s.window,
        eeprom_records_written: saves,
        conditions: &stats,
        claims: &checked,
        battery: &battery,
    };
    let summary_path = stage.path("summary.json");
    std::fs::write(
        &summary_path,
        serde_json::to_string_pretty(&summary)? + "\n",
    )
    .map_err(anyhow::Error::new)
    .context(OutputError(format!(
        "cannot write `{}`",
        summary_path.display()
    )))?;

    let fit = crate::fit::measure(&crate::fit::FitConfig {
        controller: controller_config(s, crate::fit::fit_weight_seed(s.seed))?,
        steps: 400,
        seed: s.seed,
        kind: crate::fit::ControllerKind::Firmware,
        firmware: crate::fit::FirmwareUnderTest::robot()?,
        compare: true,
    })?;
    let fit_path = stage.path("fit.json");
    std::fs::write(&fit_path, serde_json::to_string_pretty(&fit)? + "\n")
        .map_err(anyhow::Error::new)
        .context(OutputError(format!(
            "cannot write `{}`",
            fit_path.display()
        )))?;

    let (png, svg, arena_png) = (
        stage.path("learning.png"),
        stage.path("learning.svg"),
        stage.path("arena.png"),
    );
    let drawn = |e: crate::plot::PlotError| {
        anyhow::Error::new(e).context(OutputError("cannot draw the figures".into()))
    };
    learning_figure(&learning(s, &runs), &png, &svg).map_err(drawn)?;
    let mut names: Vec<String> = [
        "metrics.csv",
        "summary.json",
        "fit.json",
        "learning.png",
        "learning.svg",
    ]
    .map(String::from)
    .to_vec();
    if let Some(track) = runs.iter().find_map(|r| r.track.as_ref()) {
        arena_figure_panels(&arena(s, track), &arena_png).map_err(drawn)?;
        names.push("arena.png".into());
    }

    let robot_steps = jobs.len() as f64 * f64::from(s.steps) * s.robots as f64;
    let simulated_s = jobs.len() as f64 * f64::from(s.steps) * s.timing.step_period_s;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "h8swarm run {}: {} robots, {} steps of {} s, {} repeats x {} conditions, seed {}",
        s.name,
        s.robots,
        s.steps,
        s.timing.step_period_s,
        s.repeats,
        kinds.len(),
        s.seed
    );
    let _ = writeln!(
        t,
        "wall {:.1} s on {threads} threads: {:.0} robot-steps/s, {:.0}x real time per run",
        wall_s,
        robot_steps / wall_s,
        simulated_s / wall_s
    );
    let _ = writeln!(t);
    let _ = writeln!(
        t,
        "{:<14} {:>22} {:>22} {:>22} {:>22}",
        "condition", "D first window", "D last window", "coll./robot first", "coll./robot last"
    );
    for c in &stats {
        let _ = writeln!(
            t,
            "{:<14} {:>22} {:>22} {:>22} {:>22}",
            c.condition.name(),
            fmt_est(&c.first.mean_d),
            fmt_est(&c.last.mean_d),
            fmt_est(&c.first.collisions_per_robot),
            fmt_est(&c.last.collisions_per_robot)
        );
        let mm = |e: &Estimate| Estimate {
            mean: e.mean * 1e3,
            lo: e.lo.map(|v| v * 1e3),
            hi: e.hi.map(|v| v * 1e3),
            n: e.n,
        };
        let _ = writeln!(
            t,
            "{:<14} moved per step {} -> {} mm",
            "",
            fmt_est(&mm(&c.first.moved_m)),
            fmt_est(&mm(&c.last.moved_m))
        );
        let pct = |e: &Estimate| Estimate {
            mean: e.mean * 100.0,
            lo: e.lo.map(|v| v * 100.0),
            hi: e.hi.map(|v| v * 100.0),
            n: e.n,
        };
        let _ = writeln!(
            t,
            "{:<14} contact time {} -> {} %; stuck robot-steps {} -> {} %",
            "",
            fmt_est(&pct(&c.first.contact_fraction)),
            fmt_est(&pct(&c.last.contact_fraction)),
            fmt_est(&pct(&c.first.stuck_fraction)),
            fmt_est(&pct(&c.last.stuck_fraction))
        );
        if let (Some(f), Some(l)) = (&c.first.gap_cv, &c.last.gap_cv) {
            let _ = writeln!(t, "{:<14} gap CV {} -> {}", "", fmt_est(f), fmt_est(l));
        }
    }
    let _ = writeln!(
        t,
        "(windows of {} steps; mean over repeats [95 % interval])",
        s.window
    );
    render_battery(&mut t, &battery);
    let _ = writeln!(t);
    for c in &checked {
        let _ = writeln!(
            t,
            "{} {} ({:.3} vs {:.3}: {})",
            if c.holds { "HOLDS " } else { "FAILS " },
            c.claim,
            c.values[0],
            c.values[1],
            c.verdict
        );
    }
    for r in &runs {
        for (i, why) in &r.dead {
            let _ = writeln!(
                t,
                "DEAD  robot {i} in {} repeat {}: {why}",
                r.condition.name(),
                r.repeat
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
    let _ = writeln!(t);
    let _ = writeln!(t, "fit: {}", fit.verdict);
    Ok((t, names))
}

/// The battery life of each condition ([`crate::energy::BatteryReport`]) for the pack
/// `--capacity-mah` gives.
fn battery_report(
    a: &RunArgs,
    s: &Scenario,
    stats: &[ConditionStats],
    runs: &[RunOutput],
) -> Result<crate::energy::BatteryReport> {
    let pack = crate::energy::Pack::paper(crate::fit_cmd::parse_capacity(a.capacity_mah)?);
    let mut b = crate::energy::BatteryReport::of(stats, pack, s.timing.step_period_s);
    let robot_seconds = s.robots as f64 * f64::from(s.steps) * s.timing.step_period_s;
    for c in stats {
        let of_c: Vec<&RunOutput> = runs.iter().filter(|r| r.condition == c.condition).collect();
        b.by_part.push(crate::energy::ConditionParts::of(
            c.condition,
            &of_c,
            robot_seconds,
        ));
    }
    Ok(b)
}

/// The battery lines of the summary: each condition's battery life in its first and last
/// windows, its mean current by part, and what learning costs or saves against the controls.
fn render_battery(t: &mut String, b: &crate::energy::BatteryReport) {
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
        (Some(lo), Some(hi)) => format!("{:.2} [{:.2}, {:.2}]", e.mean, lo, hi),
        _ => format!("{:.2}", e.mean),
    }
}

/// Joins the runs' row files (in run order) under the header into `path`, removing them.
fn write_metrics(path: &Path, parts: &[PathBuf]) -> Result<()> {
    write_metrics_csv(path, parts)
        .context(OutputError(format!("cannot write `{}`", path.display())))
}

fn write_metrics_csv(path: &Path, parts: &[PathBuf]) -> Result<()> {
    let mut w = csv::Writer::from_path(path)?;
    w.write_record(crate::experiment::METRICS_HEADER)?;
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

/// The learning figure: per condition, mean D per window and collisions per robot per window
/// (the paper's two panels), then contact time (percent of the window) and, in the corridor,
/// the gap CV (elsewhere the stuck robot-steps, percent): mean over repeats with its 95 % band
/// (or the mean alone with fewer than two repeats).
fn learning(s: &Scenario, runs: &[RunOutput]) -> LearningFigure {
    use crate::experiment::WindowSums;
    let win = s.window.max(1) as usize;
    let windows = runs
        .iter()
        .map(|r| r.metrics.whole_windows().len())
        .min()
        .unwrap_or(0);
    let of =
        |c: Condition| -> Vec<&RunOutput> { runs.iter().filter(|r| r.condition == c).collect() };
    // One series per condition of a per-step metric, summed or averaged over each window.
    let panel =
        |f: &dyn Fn(&WindowSums) -> f64, sum: bool, scale: f64, floor0: bool| -> Vec<Series> {
            let mut out = Vec::new();
            for c in Condition::ALL {
                let of_c = of(c);
                if of_c.is_empty() {
                    continue;
                }
                let (mut xs, mut m, mut lo, mut hi) = (vec![], vec![], vec![], vec![]);
                for w in 0..windows {
                    let vals: Vec<f64> = of_c
                        .iter()
                        .map(|r| {
                            let t = f(&r.metrics.windows[w]);
                            scale * if sum { t } else { t / win as f64 }
                        })
                        .collect();
                    let e = Estimate::of(&vals);
                    xs.push((w * win + win / 2) as f64);
                    m.push(e.mean);
                    let l = e.lo.unwrap_or(e.mean);
                    lo.push(if floor0 { l.max(0.0) } else { l });
                    hi.push(e.hi.unwrap_or(e.mean));
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
                });
            }
            out
        };
    let mut more = vec![Panel {
        caption: "Contact time (a bumper pressed)".to_string(),
        y_label: "% of the window".to_string(),
        series: panel(&|m| m.contact_fraction, false, 100.0, true),
    }];
    let corridor = runs.iter().all(|r| r.metrics.whole.all_have_gap_cv());
    more.push(if corridor {
        Panel {
            caption: "Gap CV between neighbours (evenly spaced: low)".to_string(),
            y_label: "coefficient of variation".to_string(),
            series: panel(&|m| m.gap_cv, false, 1.0, true),
        }
    } else {
        Panel {
            caption: "Stuck robots (< 1 mm in 100 steps, driving)".to_string(),
            y_label: "% of robot-steps".to_string(),
            series: panel(&|m| m.stuck_fraction, false, 100.0, true),
        }
    });
    LearningFigure {
        title: format!(
            "h8swarm {}: {} robots, {} repeats, windows of {} steps ({} s per step)",
            s.name, s.robots, s.repeats, s.window, s.timing.step_period_s
        ),
        x_label: "learning step".to_string(),
        d: panel(&|m| m.mean_d, false, 1.0, false),
        collisions: panel(&|m| m.collisions_per_robot, true, 1.0, true),
        more,
    }
}

/// The arena figure as the paper's Fig. 8 shows learning: the first and the last
/// [`crate::experiment::SNAPSHOT_STEPS`] steps' paths in two panels, with the outlines at the
/// start and the end of each.
fn arena(s: &Scenario, t: &crate::experiment::Track) -> Vec<ArenaFigure> {
    let k = crate::experiment::SNAPSHOT_STEPS.min(s.steps as usize);
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
                "{} {} steps ({:.0}-{:.0} s), {} robots{}",
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
        // 100 000 model robots on one thread: over 15 GiB.
        assert!(estimated_memory(&big, 1) > 15 << 30);
        assert!(check_memory(&big, 1, Some(8 << 30)).is_err());
        assert!(check_memory(&s, 1, Some(8 << 30)).is_ok());
    }

    #[test]
    fn output_errors_are_found_under_any_context() {
        let direct = anyhow::Error::new(OutputError("cannot write".into()));
        assert!(is_output_error(&direct));
        let wrapped = anyhow::Error::new(std::io::Error::other("disk full"))
            .context(OutputError("cannot write `metrics.csv`".into()))
            .context("the run into `out` failed; nothing was written");
        assert!(is_output_error(&wrapped));
        let input = anyhow::anyhow!("`steps` = 0 is out of range").context("scenario file");
        assert!(!is_output_error(&input));
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
