//! The argument types and checks the commands share: the controller, the stack guard, thread
//! counts, sizes and the battery's capacity.

use anyhow::{Result, bail};
use swarm::scenario::ControllerKind;

/// Which controller the robots run, or `fit` measures (`--controller`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ControllerArg {
    /// The robot firmware (or `--firmware IMAGE`) as machine code on the H8/300H core.
    #[default]
    Firmware,
    /// The Rust model of the controller.
    Model,
}

impl From<ControllerArg> for ControllerKind {
    fn from(c: ControllerArg) -> Self {
        match c {
            ControllerArg::Firmware => ControllerKind::Firmware,
            ControllerArg::Model => ControllerKind::Model,
        }
    }
}

/// `--capacity-mah`: a capacity from 1 mAh to 100 Ah (default
/// [`swarm::energy::DEFAULT_CAPACITY_MAH`]).
///
/// # Errors
/// A value outside that range, or not a number.
pub fn parse_capacity(given: Option<f64>) -> Result<f64> {
    match given {
        None => Ok(swarm::energy::DEFAULT_CAPACITY_MAH),
        Some(c) if c.is_finite() && (1.0..=100_000.0).contains(&c) => Ok(c),
        Some(c) => bail!(
            "--capacity-mah {}: give a cell's capacity from 1 to 100000 mAh (AA NiMH cells hold 1 900-2 700 mAh)",
            swarm::terminal_text::number(c)
        ),
    }
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

/// `--threads`, checked: at least 1 and at most [`max_threads`]; all cores when not given.
///
/// # Errors
/// 0, or more than [`max_threads`].
pub fn threads(given: Option<usize>) -> Result<usize> {
    let max = max_threads();
    match given {
        Some(0) => bail!("--threads 0: give at least 1 (or leave it out for all cores)"),
        Some(t) if t > max => bail!(
            "--threads {t}: at most {max} on this machine ({THREADS_PER_CORE} per core; more only wait for each other)"
        ),
        _ => Ok(threads_or_all(given)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_sizes_parse() {
        assert_eq!(parse_bytes("512M"), Ok(512 << 20));
        assert_eq!(parse_bytes("8g"), Ok(8 << 30));
        assert_eq!(parse_bytes("1000"), Ok(1000));
        for bad in ["", "0", "-1", "8 GB", "1.5G", "99999999999T"] {
            assert!(parse_bytes(bad).is_err(), "{bad}");
        }
    }
}
