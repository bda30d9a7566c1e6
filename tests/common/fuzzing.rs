//! What the fuzz families share (`tests/fuzz.rs`, `tests/fuzz3.rs`): how many cases, the
//! runner, a family's folder, the checks of a message.

use std::path::Path;
use std::time::{Duration, Instant};

use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestRunner};

pub fn cases() -> u32 {
    cases_or(2_000)
}

/// `H8SWARM_FUZZ_CASES`, else `default`.
pub fn cases_or(default: u32) -> u32 {
    std::env::var("H8SWARM_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The same cases on every CI run (a fixed seed); a soak (`H8SWARM_FUZZ_CASES` set) draws new
/// ones each time.
pub fn runner() -> TestRunner {
    runner_of(cases())
}

/// [`runner`] with `cases` cases.
pub fn runner_of(cases: u32) -> TestRunner {
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    if std::env::var_os("H8SWARM_FUZZ_CASES").is_some() {
        TestRunner::new(config)
    } else {
        let rng = proptest::test_runner::TestRng::deterministic_rng(config.rng_algorithm);
        TestRunner::new_with_rng(config, rng)
    }
}

/// An error's first line says what; it must exist and not be empty.
pub fn one_line_first(message: &str) -> Result<(), TestCaseError> {
    let first = message.lines().next().unwrap_or("");
    prop_assert!(!first.trim().is_empty(), "an empty error: {message:?}");
    Ok(())
}

/// A fresh, empty folder for a family's cases.
pub fn family_dir(name: &str) -> std::path::PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("fuzz-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// [`family_dir`] in memory where the system has it (/dev/shm): a family that makes and
/// removes thousands of small files spends most of its time making inodes on a disk.
pub fn family_dir_in_memory(name: &str) -> std::path::PathBuf {
    let shm = Path::new("/dev/shm");
    if !shm.is_dir() {
        return family_dir(name);
    }
    let d = shm.join(format!("h8swarm-fuzz-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// No control character but line ends: what reaches a terminal.
pub fn printable_text(text: &str) -> bool {
    !text
        .chars()
        .any(|c| (c.is_control() && c != '\n') || ('\u{80}'..='\u{9f}').contains(&c))
}

pub fn wait_bounded(child: &mut std::process::Child, what: &str) -> std::process::ExitStatus {
    let started = Instant::now();
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        if started.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("{what} did not end within 120 s");
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}
