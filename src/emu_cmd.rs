//! `h8swarm emu IMAGE.mot [--max-states N] [--trace] [--stats]`: runs a program on the emulated
//! H8/3052F (SPEC §7). SCI1 is the console (standard output); `--trace` writes one line per
//! instruction (address, disassembly, states) and `--stats` a JSON summary, both on standard
//! error.
//!
//! Exit status: the program's (low byte of R0) when it halts with SLEEP under CCR.I = 1; 124
//! when the state budget runs out; 125 when the core stops on an error (the message names the PC
//! and the bytes); 126 when the program sleeps with interrupts enabled and nothing that could
//! wake it; 2 when the image cannot be read or is not a valid S-record file.

use std::io::{self, BufWriter, Write};

use emu::chip::run::{Outcome, RunOptions, run_image};

use crate::Failure;

/// Exit status when `--max-states` runs out (as `timeout(1)` does).
pub const EXIT_MAX_STATES: u8 = 124;
/// Exit status when the core stops on an error.
pub const EXIT_CORE_ERROR: u8 = 125;
/// Exit status when the program sleeps forever.
pub const EXIT_SLEPT_FOREVER: u8 = 126;
/// Exit status when a GDB client kills the program (128 + SIGKILL, as a shell reports it).
pub const EXIT_KILLED: u8 = 137;

pub fn run(image: &str, max_states: Option<u64>, trace: bool, stats: bool) -> Result<(), Failure> {
    let bytes = std::fs::read(image).map_err(|e| {
        Failure::Input(anyhow::anyhow!(
            "cannot read image `{image}`: {e} (give a Motorola S-record file, .mot)"
        ))
    })?;
    let options = RunOptions { max_states };
    let stdout = io::stdout();
    let mut console = stdout.lock();
    let stderr = io::stderr();
    let mut trace_out = BufWriter::new(stderr.lock());
    let report = run_image(
        &bytes,
        &options,
        &mut console,
        if trace { Some(&mut trace_out) } else { None },
    );
    let _ = trace_out.flush();
    drop(trace_out);
    let report = match report {
        Ok(r) => r,
        Err(emu::chip::run::RunError::Io(e)) if e.kind() == io::ErrorKind::BrokenPipe => {
            return Ok(());
        }
        Err(emu::chip::run::RunError::Io(e)) => {
            return Err(Failure::Tool(
                anyhow::Error::new(e).context("writing the console"),
            ));
        }
        Err(e) => {
            return Err(Failure::Input(
                anyhow::Error::new(e).context(format!("image `{image}`")),
            ));
        }
    };
    if stats {
        eprintln!("{}", report.to_json());
    }
    match report.outcome {
        Outcome::Halted { exit_status: 0 } => Ok(()),
        Outcome::Halted { exit_status } => Err(Failure::Program(exit_status)),
        Outcome::MaxStates => {
            eprintln!(
                "h8swarm emu: stopped after {} states (--max-states)",
                report.stats.states
            );
            Err(Failure::Program(EXIT_MAX_STATES))
        }
        Outcome::Error(e) => {
            eprintln!("error: image `{image}`: the core stopped: {e}");
            Err(Failure::Program(EXIT_CORE_ERROR))
        }
        Outcome::SleptForever { pc } => {
            eprintln!(
                "error: image `{image}`: SLEEP at H'{pc:06X} with interrupts enabled and nothing to wake the CPU"
            );
            Err(Failure::Program(EXIT_SLEPT_FOREVER))
        }
        Outcome::Killed => {
            eprintln!("h8swarm emu: the GDB client killed the program");
            Err(Failure::Program(EXIT_KILLED))
        }
    }
}
