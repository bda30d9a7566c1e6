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

use super::Failure;
use super::args::{ControllerArg, StackGuardArg, parse_bytes, parse_capacity};
use crate::outputs::{OUTPUT_FILES, Summary};
use crate::stage::Stage;
use swarm::experiment::{RunOptions, RunOutput, build_world, run_one};
use swarm::output_error::OutputError;
use swarm::robot::{Condition, controller_config};
use swarm::scenario::Scenario;
use swarm::summary::{ConditionStats, analyse};

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
    pub controller: Option<ControllerArg>,
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

/// Checks the `--replay` options against the scenario.
fn replay_plan(a: &RunArgs, s: &Scenario) -> Result<Option<swarm::recording::ReplayPlan>> {
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
                        swarm::terminal_text::one_line(list),
                        swarm::terminal_text::one_line(part),
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
    Ok(Some(swarm::recording::ReplayPlan {
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
        let staged = stage.create_outside("--vcd", path)?;
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
        let staged = stage.create_outside("--profile", path)?;
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

/// Runs the experiment; returns the text to print.
///
/// # Errors
/// A bad scenario or option (naming the key or path), an output folder that cannot be written,
/// more robots than the arena holds.
pub fn run(a: &RunArgs) -> Result<String> {
    let what = a.scenario.as_deref().unwrap_or("arena");
    let mut s = Scenario::load(what)?;
    if let Some(k) = a.controller {
        s.controller.kind = k.into();
    }
    if let Some(image) = &a.firmware {
        if a.controller == Some(ControllerArg::Model) {
            bail!("--firmware runs an image on the core: it cannot go with --controller model");
        }
        s.controller.kind = swarm::scenario::ControllerKind::Firmware;
        s.controller.image = Some(image.display().to_string());
    }
    let s = s.with_overrides(a.robots, a.steps, a.repeats, a.seed)?;
    parse_capacity(a.capacity_mah)?;
    let images = swarm::robot::Images::load(&s)?;
    let unconfigured = unconfigured_image(&s, images.as_ref())?;
    if let Some(image) = &unconfigured {
        eprintln!(
            "warning: {}: the image has no configuration block, so it runs with its own built-in settings, not the scenario's learner, timing and sensor settings (summary.json says \"image_configured\": false); give its symbol table (IMAGE.sym beside it, or controller.symbols) to configure it",
            swarm::terminal_text::printable(image)
        );
    }
    let threads = super::args::threads(a.threads)?;
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
    crate::resources::check_memory(&s, threads, a.max_memory, trace_buffers)?;
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
        threads,
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

/// The probes of one robot, taken by the first run that asks for them.
type SharedProbes = std::sync::Mutex<Option<swarm::experiment::RobotProbes>>;

/// What one `run` works with: its options, its scenario, the robots' images, the probes and
/// the replay plan, the staging folder its files go into, and its worker threads.
struct RunContext<'r> {
    a: &'r RunArgs,
    s: &'r Scenario,
    images: Option<&'r swarm::robot::Images>,
    probes: &'r SharedProbes,
    replay: Option<&'r swarm::recording::ReplayPlan>,
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
    crate::outputs::write_metrics(&stage.path("metrics.csv"), &parts)?;
    crate::outputs::write_robots(&stage.path("robots.csv"), &runs)?;
    let analysis = analyse(
        &runs,
        s.robots,
        s.steps,
        s.window,
        swarm::seeds::bootstrap_seed(s.seed),
    );
    let warnings = crate::report::warnings(s);
    let saves: u64 = runs.iter().map(|r| r.saves).sum();
    let battery = battery_report(a, s, &analysis.conditions, &runs)?;
    let summary = Summary {
        h8swarm_version: env!("CARGO_PKG_VERSION"),
        scenario: s,
        window_steps: s.window,
        units: crate::outputs::UNITS,
        eeprom_records_written: saves,
        warnings: &warnings,
        conditions: &analysis.conditions,
        pairings: &analysis.pairings,
        claims: &analysis.claims,
        dead_robots: runs
            .iter()
            .flat_map(|r| {
                r.dead.iter().map(|d| crate::outputs::DeadEntry {
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
    crate::outputs::write_json(&stage.path("summary.json"), &summary)?;
    let fit = measure_fit(s)?;
    crate::outputs::write_json(&stage.path("fit.json"), &fit)?;
    let names = crate::outputs::write_figures(s, stage, replay, &floor, &runs)?;

    let mut t = String::new();
    crate::report::render_header(&mut t, s, kinds.len(), jobs.len(), threads, wall_s);
    for w in &warnings {
        let _ = writeln!(t, "WARNING {w}");
    }
    crate::report::render_battery(&mut t, &battery);
    let _ = writeln!(t);
    crate::report::report(&mut t, s, &analysis);
    crate::report::render_failures(&mut t, &runs);
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

/// The battery life of each condition ([`swarm::battery::BatteryReport`]) for the pack
/// `--capacity-mah` gives.
fn battery_report(
    a: &RunArgs,
    s: &Scenario,
    stats: &[ConditionStats],
    runs: &[RunOutput],
) -> Result<swarm::battery::BatteryReport> {
    let pack = swarm::energy::Pack::paper(parse_capacity(a.capacity_mah)?);
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

/// An error of `run`: a tool failure when some output could not be written
/// ([`swarm::output_error::OutputError`] in its chain), else bad input.
fn run_failure(e: anyhow::Error) -> Failure {
    if swarm::output_error::is_output_error(&e) {
        Failure::Tool(e)
    } else {
        Failure::Input(e)
    }
}

/// `h8swarm run`: runs the experiment and prints its report (also when the run failed as a
/// whole after writing its outputs: [`FailedRun`]).
///
/// # Errors
/// Bad input ([`Failure::Input`]), an output that cannot be written ([`Failure::Tool`]).
pub fn command(args: &RunArgs) -> Result<(), Failure> {
    let text = match run(args) {
        Ok(text) => text,
        Err(e) => {
            // A run that wrote its outputs but failed as a whole: its report first.
            if let Some(f) = e.downcast_ref::<FailedRun>() {
                super::write_text(&f.report)?;
            }
            return Err(run_failure(e));
        }
    };
    super::write_text(&text)
}

#[cfg(test)]
mod tests {
    use super::*;

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
