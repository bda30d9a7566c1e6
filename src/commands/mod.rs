//! The subcommands of `h8swarm`, one file each: [`run`] (the swarm experiment), [`fit`],
//! [`cost`], [`learn`], [`emu`] and [`sweep`], with the argument types they share in
//! [`args`]. Each parses nothing itself (clap does, from its `…Args`), does its work through
//! the libraries, and returns its text or a [`Failure`] that carries the exit status.

pub mod args;
pub mod cost;
pub mod emu;
pub mod fit;
pub mod learn;
pub mod run;
pub mod sweep;

use std::io::{self, Write};

use swarm::terminal_text::printable;

/// How a command failed, with its exit status.
#[derive(Debug)]
pub enum Failure {
    /// Bad input: exit status 2.
    Input(anyhow::Error),
    /// The tool failed: exit status 1.
    Tool(anyhow::Error),
    /// An emulated program ended with this exit status (already reported).
    Program(u8),
}

/// Writes a command's report to standard output, each line made [`printable`] (so no name
/// from a file or an argument reaches the terminal as a control or format character), ending
/// quietly when the reader has closed the pipe.
///
/// # Errors
/// The output cannot be written ([`Failure::Tool`]; a closed pipe is no error).
pub fn write_text(text: &str) -> Result<(), Failure> {
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

/// Maps a write error to the right outcome: a closed pipe downstream (`h8swarm … | head`) is a
/// normal end, anything else a tool failure.
///
/// # Errors
/// Any write error but a closed pipe ([`Failure::Tool`]).
pub fn write_failure(e: io::Error) -> Result<(), Failure> {
    if e.kind() == io::ErrorKind::BrokenPipe {
        Ok(())
    } else {
        Err(Failure::Tool(
            anyhow::Error::new(e).context("writing the output"),
        ))
    }
}
