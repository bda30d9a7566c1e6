//! The default run's results, pinned by their SHA-1 (issue 34, "results that travel between
//! machines"): `h8swarm run` with no options writes the same metrics.csv, robots.csv,
//! summary.json and fit.json, byte for byte, on every machine and platform, because every
//! model computes with IEEE arithmetic and libm's pure-Rust functions (clippy.toml forbids
//! the host's), and every random draw comes from the seeded generators.
//!
//! A change that alters the results on purpose (a model, a metric, a column) updates these pins
//! in the same commit, and says so in its message; the failure prints the new ones.

mod common;

use common::{fresh, ok, s};
use sha1::{Digest, Sha1};

/// The files and their SHA-1, as `h8swarm run` writes them.
const PINS: [(&str, &str); 4] = [
    ("metrics.csv", "f646aa02e11acf31d21ceeea66b662c89d7d8038"),
    ("robots.csv", "53f634bf64190e9a45d8cccb158c0e0a1d85d6f1"),
    ("summary.json", "85cd37f906f080a4386f461cab1aacd0dde94788"),
    ("fit.json", "0172f8332da3660f07c700771f93d0946ece65f9"),
];

fn sha1_hex(bytes: &[u8]) -> String {
    Sha1::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

#[test]
fn the_default_run_writes_the_pinned_bytes() {
    let dir = fresh("pinned-default");
    let out = dir.join("out");
    ok(&["run", "--out", s(&out)]);
    let got: Vec<(&str, String)> = PINS
        .iter()
        .map(|(f, _)| {
            (
                *f,
                sha1_hex(&std::fs::read(out.join(f)).expect("an output")),
            )
        })
        .collect();
    let changed: Vec<String> = PINS
        .iter()
        .zip(&got)
        .filter(|((_, want), (_, have))| want != have)
        .map(|((f, want), (_, have))| format!("{f}: pinned {want}, now {have}"))
        .collect();
    assert!(
        changed.is_empty(),
        "the default run's results changed (if on purpose, update PINS):\n{}",
        changed.join("\n")
    );
    let _ = std::fs::remove_dir_all(&dir);
}
