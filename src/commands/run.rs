//! `h8swarm run [corridor|arena|FILE.toml] [--robots N] [--steps S] [--repeats R] [--seed X]
//! [--threads T] [--out DIR] [--vcd FILE [--vcd-robot K] [--vcd-from S] [--vcd-steps N]]
//! [--gdb ADDR [--gdb-robot K]]`: the paper's experiment with its controls, in parallel, with
//! the metrics, the summary, the figures and the fit verdict written to DIR; `--vcd` traces one
//! firmware robot's pins over a window of steps, `--gdb` puts one under a GDB client's control
//! (both in the learning run's first repeat; the results do not change).

use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use super::Failure;
use super::args::{ControllerArg, StackGuardArg, parse_bytes, parse_capacity};
use crate::stage::Stage;
use swarm::experiment::build_world;
use swarm::output_error::OutputError;
use swarm::runner;
use swarm::scenario::Scenario;

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
    let s = scenario(a, what)?;
    let capacity_mah = parse_capacity(a.capacity_mah)?;
    let threads = super::args::threads(a.threads)?;
    let images = swarm::robot::Images::load(&s)?;
    let unconfigured = swarm::robot::unconfigured_image(&s, images.as_ref())?;
    if let Some(image) = &unconfigured {
        eprintln!(
            "warning: {}: the image has no configuration block, so it runs with its own built-in settings, not the scenario's learner, timing and sensor settings (summary.json says \"image_configured\": false); give its symbol table (IMAGE.sym beside it, or controller.symbols) to configure it",
            swarm::terminal_text::printable(image)
        );
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
    crate::resources::check_memory(&s, threads, a.max_memory, trace_buffers)?;
    // Fail now if the robots do not fit the arena, or a probe's option is bad.
    build_world(&s, 0)?;
    let replay = replay_plan(a, &s)?;
    // Every file (the trace of --vcd too) is written into a staging folder beside `out` and
    // moved into place only when the whole run succeeded; a failure before that leaves `out`
    // (and the trace's file) as it was.
    let mut stage = Stage::new("--out", &out).map_err(|e| anyhow::Error::new(OutputError(e.0)))?;
    let probes = match probes(a, &s, &mut stage) {
        Ok(p) => p,
        Err(e) => {
            let _ = stage.abandon();
            return Err(e);
        }
    };
    let options = runner::Options {
        threads,
        images: images.as_ref(),
        probes,
        replay: replay.as_ref(),
        keep_going: a.keep_going,
        stack_guard: a.stack_guard.unwrap_or_default().into(),
        strict_io: a.strict_io,
        capacity_mah,
        folder: stage.dir(),
    };
    let bar = progress_bar(&s, runner::jobs(&s).1.len(), threads);
    let analysed = runner::run(&s, options, &|k| bar.inc(k));
    bar.finish_and_clear();
    let written = analysed.and_then(|r| {
        let names = crate::outputs::write(&stage, &s, &r, replay.as_ref())?;
        Ok((crate::report::render(&s, &r, threads), names, r.all_dead))
    });
    match written {
        Ok((text, names, dead)) => {
            let text = text + &crate::outputs::commit(stage, &names)?;
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

/// Runs the scenario file `scenario` into the folder `out` with `threads` threads (as `h8swarm
/// run SCENARIO --out OUT --threads T`, every other option at its default); returns the text to
/// print. A sweep's points are run by it ([`crate::sweep::exec::RunScenario`]).
///
/// # Errors
/// As [`run`].
pub fn run_file(scenario: &Path, threads: Option<usize>, out: &Path) -> Result<String> {
    run(&RunArgs {
        scenario: Some(scenario.display().to_string()),
        threads,
        out: Some(out.to_path_buf()),
        ..RunArgs::default()
    })
}

/// The scenario the arguments name, with the options that override it.
///
/// # Errors
/// A scenario that cannot be read or checks out wrong; `--firmware` with `--controller model`.
fn scenario(a: &RunArgs, what: &str) -> Result<Scenario> {
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
    s.with_overrides(a.robots, a.steps, a.repeats, a.seed)
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
