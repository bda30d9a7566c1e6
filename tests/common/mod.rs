//! Helpers shared by the tests that drive the real binary with hostile input
//! (`tests/hostile.rs`, `tests/hostile3.rs`).
#![allow(dead_code)]

pub mod fuzzing;
pub mod tmpfs;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// The binary under test: this build's, or `H8SWARM_BIN` (to see the tests fail on another
/// build, e.g. one from before a fix).
pub fn bin() -> String {
    std::env::var("H8SWARM_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_h8swarm").to_string())
}

pub fn h8swarm(args: &[&str]) -> Output {
    Command::new(bin())
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_CPUS_PER_TASK")
        .stdin(Stdio::null())
        .output()
        .expect("the binary runs")
}

pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

pub fn ok(args: &[&str]) -> String {
    let o = h8swarm(args);
    assert!(
        o.status.success(),
        "h8swarm {args:?}: {}\n{}",
        text(&o.stdout),
        text(&o.stderr)
    );
    text(&o.stdout)
}

/// Exit status, standard output and standard error.
pub fn status(args: &[&str]) -> (i32, String, String) {
    let o = h8swarm(args);
    (
        o.status.code().unwrap_or(-1),
        text(&o.stdout),
        text(&o.stderr),
    )
}

pub fn fresh(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("hostile-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Every file under `dir` with its bytes, sorted by path (folders as empty entries).
pub fn tree(dir: &Path) -> Vec<(String, Option<Vec<u8>>)> {
    fn walk(root: &Path, d: &Path, out: &mut Vec<(String, Option<Vec<u8>>)>) {
        let Ok(entries) = std::fs::read_dir(d) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            let name = p.strip_prefix(root).unwrap().display().to_string();
            if p.is_dir() {
                out.push((name + "/", None));
                walk(root, &p, out);
            } else {
                out.push((name, std::fs::read(&p).ok()));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// A sweep of two points on one axis (so merge draws a figure per claim), 20-step arena runs.
pub fn small_sweep(root: &Path) -> PathBuf {
    let dir = root.join("d");
    let file = root.join("s.toml");
    std::fs::write(
        &file,
        "[set]\nsteps = 20\nwindow = 10\nrepeats = 1\nrobots = 2\ncontrols.random_walk = false\n[grid]\n\"learner.threshold\" = [10, 20]\n",
    )
    .unwrap();
    ok(&["sweep", "plan", s(&file), "--out", s(&dir)]);
    ok(&["sweep", "run", s(&dir), "--threads", "1"]);
    dir
}

/// The entries in which two trees of [`tree`] differ, by name (for a readable failure).
pub fn tree_diff(a: &[(String, Option<Vec<u8>>)], b: &[(String, Option<Vec<u8>>)]) -> Vec<String> {
    let mut names: Vec<&String> = a.iter().chain(b).map(|(n, _)| n).collect();
    names.sort();
    names.dedup();
    let find = |t: &[(String, Option<Vec<u8>>)], n: &str| {
        t.iter().find(|(m, _)| m == n).map(|(_, b)| b.clone())
    };
    names
        .into_iter()
        .filter(|n| find(a, n) != find(b, n))
        .cloned()
        .collect()
}

/// Exit status, standard output and standard error of the binary run in the folder `dir`.
pub fn status_in(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let o = Command::new(bin())
        .args(args)
        .current_dir(dir)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_CPUS_PER_TASK")
        .stdin(Stdio::null())
        .output()
        .expect("the binary runs");
    (
        o.status.code().unwrap_or(-1),
        text(&o.stdout),
        text(&o.stderr),
    )
}
