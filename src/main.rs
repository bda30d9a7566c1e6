//! `h8swarm`: the command-line tool of the hardware-faithful H8/3052F swarm emulator.
//!
//! Exit status: 0 on success; 2 for bad input (a malformed replay line, an unreadable input
//! file, an option out of range, a usage error); 1 when the tool itself fails (an output that
//! cannot be written). `h8swarm emu` exits with the program's own status when it halts, 124
//! when `--max-states` runs out, 125 when the core stops on an error (undefined opcode, fetch
//! outside ROM and RAM), 126 when the program sleeps with nothing left to wake it and 137 when
//! a GDB client kills it.
#![forbid(unsafe_code)]

use std::io::{self, Write};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use h8swarm::commands::{Failure, cost, emu, fit, learn, run, sweep};
use swarm::terminal_text::printable;

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
    Run(run::RunArgs),
    /// Feed the learner core from JSON Lines and print one JSON line per step (docs/design.md §2.6).
    Learn(learn::LearnArgs),
    /// Measure the learner's H8/300H states per step and its RAM footprint (the learner alone).
    Cost(cost::CostArgs),
    /// Run an H8/300H program image (.mot) on the emulated H8/3052F, SCI1 as the console.
    Emu(emu::EmuArgs),
    /// Does the learner fit the H8/3052F? RAM, ROM, states per phase, EEPROM, measured on the
    /// emulated MCU (docs/design.md §6).
    Fit(fit::FitArgs),
    /// Parameter sweeps: plan a grid as a Slurm job array, run its tasks, merge the results.
    Sweep(sweep::SweepArgs),
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
        Some(Command::Learn(args)) => learn::command(&args),
        Some(Command::Cost(args)) => cost::command(&args),
        Some(Command::Emu(args)) => emu::command(&args),
        Some(Command::Fit(args)) => fit::command(&args),
        Some(Command::Run(args)) => run::command(&args),
        Some(Command::Sweep(args)) => sweep::command(&args),
        None => run::command(&run::RunArgs::default()),
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
                printable(&swarm::terminal_text::short_numbers(&format!("{e:#}")))
            );
            ExitCode::from(2)
        }
        Err(Failure::Tool(e)) => {
            eprintln!(
                "error: {}",
                printable(&swarm::terminal_text::short_numbers(&format!("{e:#}")))
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
