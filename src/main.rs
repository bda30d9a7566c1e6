//! `h8swarm`: the command-line tool of the hardware-faithful H8/3052F swarm emulator.
//!
//! Exit status: 0 on success; 2 for bad input (a malformed replay line, an unreadable input
//! file, an option out of range, a usage error); 1 when the tool itself fails (an output that
//! cannot be written). `h8swarm emu` exits with the program's own status when it halts, 124
//! when `--max-states` runs out, 125 when the core stops on an error (undefined opcode, fetch
//! outside ROM and RAM), 126 when the program sleeps with nothing left to wake it and 137 when
//! a GDB client kills it.
#![forbid(unsafe_code)]

mod emu_cmd;

use h8swarm::{cost_report, fit_cmd, replay, run_cmd};

use std::fs::File;
use std::io::{self, BufRead, BufReader, BufWriter, Write};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use swarm::text::printable;

/// Hardware-faithful, fixed-point emulator of the Hartono–Kakita (2008) swarm of H8/3052F robots
/// that learn obstacle avoidance together.
#[derive(Parser, Debug)]
#[command(name = "h8swarm", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run the swarm experiment (the default job: the arena, with its controls and plots).
    Run(run_cmd::RunArgs),
    /// Feed the learner core from JSON Lines and print one JSON line per step (docs/design.md §2.6).
    Learn(LearnArgs),
    /// Measure the learner's H8/300H states per step and its RAM footprint (the learner alone).
    Cost(CostArgs),
    /// Run an H8/300H program image (.mot) on the emulated H8/3052F, SCI1 as the console.
    Emu(EmuArgs),
    /// Does the learner fit the H8/3052F? RAM, ROM, states per phase, EEPROM, measured on the
    /// emulated MCU (docs/design.md §6).
    Fit(fit_cmd::FitArgs),
    /// Parameter sweeps: plan a grid as a Slurm job array, run its tasks, merge the results.
    Sweep(h8swarm::sweep::SweepArgs),
}

#[derive(Args, Debug)]
struct EmuArgs {
    /// The program: a Motorola S-record image (.mot).
    image: String,
    /// Stop after this many states (exit status 124).
    #[arg(long, value_name = "N")]
    max_states: Option<u64>,
    /// Print every instruction, disassembled, with its address and states, on standard error.
    #[arg(long)]
    trace: bool,
    /// Print instructions, states and emulated time as JSON on standard error at the end.
    #[arg(long)]
    stats: bool,
    /// Write a pin trace of the run (PWM, H-bridge, I2C lines, A/D, tick, sleep, the function
    /// that runs) to FILE as VCD, for GTKWave or sigrok (written as the run goes).
    #[arg(long, value_name = "FILE")]
    vcd: Option<std::path::PathBuf>,
    /// Wait for a GDB client on this loopback address (127.0.0.1:PORT; port 0 picks a free
    /// one, printed on standard error) and run the program under its control.
    #[arg(long, value_name = "ADDR")]
    gdb: Option<String>,
    /// The image's symbol table (`h8300-hms-nm -n` output) for function names in --trace and
    /// --vcd and the stack guard's room (default: IMAGE.sym beside the image, if present).
    #[arg(long, value_name = "FILE")]
    symbols: Option<std::path::PathBuf>,
    /// What the stack guard does with the first stack access outside the stack's room (the
    /// end of the image's data to its stack's top, or the whole RAM without symbols): `stop`
    /// the program with an error (exit status 125), or `warn` at the end and let it run.
    #[arg(long, value_enum, value_name = "ACTION", default_value_t = GuardArg::Stop)]
    stack_guard: GuardArg,
    /// Write a profile of where the states go by call stack to FILE, as folded stacks
    /// (`caller;callee;… states`, one stack a line) for speedscope, inferno-flamegraph or
    /// flamegraph.pl; the lines add up to the run's states.
    #[arg(long, value_name = "FILE")]
    profile: Option<std::path::PathBuf>,
    /// Stop the program (exit status 125) at the first access to a register the chip does
    /// not model or to a reserved address, instead of warning about each at the end.
    #[arg(long)]
    strict_io: bool,
}

/// What the stack guard does (`--stack-guard`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
enum GuardArg {
    /// Stop the program at the instruction, with a one-line error.
    #[default]
    Stop,
    /// Let it run on; print the first fault as a warning.
    Warn,
}

impl From<GuardArg> for h8300h::cpu::StackGuardMode {
    fn from(g: GuardArg) -> Self {
        match g {
            GuardArg::Stop => h8300h::cpu::StackGuardMode::Stop,
            GuardArg::Warn => h8300h::cpu::StackGuardMode::Warn,
        }
    }
}

#[derive(Args, Debug)]
struct LearnArgs {
    /// The replay file (JSON Lines), or `-` for standard input.
    #[arg(long, value_name = "FILE")]
    replay: String,
    /// Add the H8/300H states of each step's forward pass and update to every output line.
    #[arg(long)]
    states: bool,
    /// Run the robot firmware's own learner routines on the emulated H8/300H instead of
    /// nn_q15 (the same lines; with --states, the states the core counts).
    #[arg(long)]
    on_core: bool,
}

#[derive(Args, Debug)]
struct CostArgs {
    /// Enabled behaviours M: 2 (corridor) to 4 (arena).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u8).range(2..=4))]
    outputs: u8,
    /// History depth H: delayed copies of the four proximities (0 to 8).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(0..=8))]
    history: u8,
    /// Add the bias input +127.
    #[arg(long)]
    bias: bool,
    /// Learning rate η: a real number (0.001, as scenarios give it) or a Q15 integer (33);
    /// 0.001 = 33, 0.1 = 3277.
    #[arg(long, default_value_t = 33, value_parser = cost_report::parse_eta)]
    eta: i32,
    /// Dead-zone threshold T in distance units.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(i32).range(0..=32767))]
    threshold: i32,
    /// Steps to measure (at most 10 000 000; the statistics settle long before).
    #[arg(long, default_value_t = 10_000, value_parser = clap::value_parser!(u32).range(1..=i64::from(h8swarm::cost_report::MAX_COST_STEPS)))]
    steps: u32,
    /// Seed of the proximities and initial weights.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Step period in seconds for the CPU share (0.45 s in the arena, 0.60 s in the corridor).
    #[arg(long, default_value_t = 0.45)]
    step_period_s: f64,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
}

impl Default for CostArgs {
    fn default() -> Self {
        Self {
            outputs: 4,
            history: 1,
            bias: false,
            eta: 33,
            threshold: 10,
            steps: 10_000,
            seed: 1,
            step_period_s: 0.45,
            json: false,
        }
    }
}

/// A failure with its exit status.
enum Failure {
    /// Bad input: exit status 2.
    Input(anyhow::Error),
    /// The tool failed: exit status 1.
    Tool(anyhow::Error),
    /// An emulated program ended with this exit status (already reported).
    Program(u8),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage(&with_escaped_values(e)),
    };
    // A run or a sweep's task removes its staging folders when a signal stops it.
    if matches!(
        cli.command,
        None | Some(Command::Run(_)) | Some(Command::Sweep(_))
    ) {
        h8swarm::cleanup::install();
    }
    let result = match cli.command {
        Some(Command::Learn(args)) => learn(&args),
        Some(Command::Cost(args)) => cost(&args),
        Some(Command::Emu(args)) => emu_cmd::run(&emu_cmd::EmuOptions {
            image: &args.image,
            max_states: args.max_states,
            trace: args.trace,
            stats: args.stats,
            vcd: args.vcd.as_deref(),
            gdb: args.gdb.as_deref(),
            symbols: args.symbols.as_deref(),
            stack_guard: args.stack_guard.into(),
            profile: args.profile.as_deref(),
            strict_io: args.strict_io,
        }),
        Some(Command::Fit(args)) => fit(&args),
        Some(Command::Run(args)) => run(&args),
        Some(Command::Sweep(args)) => sweep(&args),
        None => run(&run_cmd::RunArgs::default()),
    };
    // A signal is ending the process: what failed because its cleanup removed the staging
    // folders is not an error to report; the signal says how the process ended.
    h8swarm::cleanup::wait_if_signalled();
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Program(status)) => ExitCode::from(status),
        Err(Failure::Input(e)) => {
            eprintln!(
                "error: {}",
                printable(&swarm::text::short_numbers(&format!("{e:#}")))
            );
            ExitCode::from(2)
        }
        Err(Failure::Tool(e)) => {
            eprintln!(
                "error: {}",
                printable(&swarm::text::short_numbers(&format!("{e:#}")))
            );
            ExitCode::from(1)
        }
    }
}

/// What clap did not parse: help and version text (exit status 0, or 1 when it cannot be
/// written), or a usage error (exit status 2).
fn usage(e: &clap::Error) -> ExitCode {
    if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
        // clap prints the help alone: say first, in one line, what is wrong.
        eprintln!("error: a subcommand or argument is missing: see the usage below");
    }
    let printed = if e.use_stderr() {
        // A usage error echoes what was typed: every value in it escaped first (so a value's
        // newline cannot split the error line and its ESC is shown, not stripped), then each
        // of clap's lines made printable.
        let text: String = e
            .render()
            .to_string()
            .lines()
            .map(|l| printable(l) + "\n")
            .collect();
        io::stderr().lock().write_all(text.as_bytes())
    } else {
        e.print()
    }
    .and_then(|()| io::stdout().flush());
    match printed {
        Err(w) if w.kind() != io::ErrorKind::BrokenPipe => {
            eprintln!("error: writing the output: {w}");
            ExitCode::from(1)
        }
        _ if e.use_stderr() => ExitCode::from(2),
        _ => ExitCode::SUCCESS,
    }
}

/// Maps a write error to the right outcome: a closed pipe downstream (`h8swarm … | head`) is a
/// normal end, anything else a tool failure.
/// Writes a command's report to standard output, each line made [`printable`] (so no name
/// from a file or an argument reaches the terminal as a control or format character), ending
/// quietly when the reader has closed the pipe.
fn write_text(text: &str) -> Result<(), Failure> {
    let mut shown = String::with_capacity(text.len());
    for line in text.lines() {
        shown.push_str(&printable(line));
        shown.push('\n');
    }
    let mut out = io::stdout().lock();
    out.write_all(shown.as_bytes())
        .and_then(|()| out.flush())
        .or_else(write_failure)
}

/// The usage error to show for `e`: the same error found again with every argument made
/// [`printable`], so that the values it quotes are escaped (a value's newline cannot split
/// the error line, and its ESC is shown rather than stripped); `e` itself when the escaped
/// arguments do not give an error of the same kind.
fn with_escaped_values(e: clap::Error) -> clap::Error {
    let escaped: Vec<String> = std::env::args_os()
        .map(|a| printable(&a.to_string_lossy()))
        .collect();
    match Cli::try_parse_from(escaped) {
        Err(again) if again.kind() == e.kind() => again,
        _ => e,
    }
}

fn write_failure(e: io::Error) -> Result<(), Failure> {
    if e.kind() == io::ErrorKind::BrokenPipe {
        Ok(())
    } else {
        Err(Failure::Tool(
            anyhow::Error::new(e).context("writing the output"),
        ))
    }
}

fn learn(args: &LearnArgs) -> Result<(), Failure> {
    let stdin = io::stdin();
    let mut input: Box<dyn BufRead> = if args.replay == "-" {
        Box::new(stdin.lock())
    } else {
        let file = File::open(&args.replay).map_err(|e| {
            Failure::Input(anyhow::anyhow!(
                "cannot open replay file `{}`: {e} (give a JSON Lines file, or - for standard input)",
                args.replay
            ))
        })?;
        Box::new(BufReader::new(file))
    };
    let stdout = io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let engine = if args.on_core {
        let fw = robot_board::firmware::Firmware::robot()
            .map_err(|e| Failure::Tool(anyhow::Error::new(e).context("the built-in firmware")))?;
        replay::Engine::OnCore(Box::new(fw))
    } else {
        replay::Engine::Model
    };
    let result = replay::run(&mut input, &mut out, args.states, &engine);
    // Whatever happened, the lines already produced are delivered.
    let flushed = out.flush();
    match result {
        Ok(_) => flushed.or_else(write_failure),
        Err(replay::ReplayFailure::Input(e)) => Err(Failure::Input(
            anyhow::Error::new(e).context(format!("replay `{}`", args.replay)),
        )),
        Err(replay::ReplayFailure::Core(e)) => Err(Failure::Tool(
            anyhow::Error::new(e).context(format!("replay `{}` on the core", args.replay)),
        )),
        Err(replay::ReplayFailure::Output(e)) => write_failure(e),
        Err(replay::ReplayFailure::Io(e)) => Err(Failure::Input(
            anyhow::Error::new(e).context(format!("reading replay `{}`", args.replay)),
        )),
    }
}

fn cost(args: &CostArgs) -> Result<(), Failure> {
    let cfg = cost_report::CostConfig {
        outputs: usize::from(args.outputs),
        history: usize::from(args.history),
        bias: args.bias,
        eta: args.eta,
        threshold: args.threshold,
        steps: args.steps,
        seed: args.seed,
        step_period_s: args.step_period_s,
    };
    let report = cost_report::measure(&cfg).map_err(Failure::Input)?;
    let text = if args.json {
        serde_json::to_string_pretty(&report).map_err(|e| Failure::Tool(e.into()))? + "\n"
    } else {
        cost_report::render(&report)
    };
    write_text(&text)
}

fn fit(args: &fit_cmd::FitArgs) -> Result<(), Failure> {
    let text = fit_cmd::run(args).map_err(Failure::Input)?;
    write_text(&text)
}

fn sweep(args: &h8swarm::sweep::SweepArgs) -> Result<(), Failure> {
    use h8swarm::sweep::SweepError;
    // What the command found is printed even when it ends in an error (the points a run
    // did, a merge's table of an incomplete sweep); the error line follows on stderr.
    let (text, result) = h8swarm::sweep::command(args);
    write_text(&text)?;
    result.map_err(|e| match e {
        SweepError::Input(m) => Failure::Input(anyhow::anyhow!(m)),
        SweepError::Tool(m) => Failure::Tool(anyhow::anyhow!(m)),
    })
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

fn run(args: &run_cmd::RunArgs) -> Result<(), Failure> {
    let text = match run_cmd::run(args) {
        Ok(text) => text,
        Err(e) => {
            // A run that wrote its outputs but failed as a whole: its report first.
            if let Some(f) = e.downcast_ref::<run_cmd::FailedRun>() {
                write_text(&f.report)?;
            }
            return Err(run_failure(e));
        }
    };
    write_text(&text)
}
