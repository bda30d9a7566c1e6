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
    ("metrics.csv", "c4ddb953faefd6448b34ffea19ea8139d1d92457"),
    ("robots.csv", "16d63739ced6c4eeeeb648a1401d51618787ff85"),
    ("summary.json", "b6610437634594fc7efb461e2da2eb58a4b1bb33"),
    ("fit.json", "4d6fcd4b0dfd524e8797fde3d3362ca33d1ab479"),
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
