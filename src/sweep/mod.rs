//! `h8swarm sweep`: parameter sweeps split, run and merged on Slurm (or on one machine with
//! the same files).
//!
//! * `h8swarm sweep plan SWEEP.toml --out DIR` ([`plan`]): expands the sweep file ([`spec`]) to
//!   its points, each a full scenario, and writes the run list, the plan and a job-array
//!   script `DIR/sweep.sbatch` whose requests come from the points' robots and steps.
//! * `h8swarm sweep run DIR [--task I]` ([`exec`]): runs task I's points (from
//!   `SLURM_ARRAY_TASK_ID` under Slurm; every point without either), each into its own folder
//!   atomically, skipping those finished before, so a requeued or resubmitted task loses
//!   nothing and redoes only what is missing or broken.
//! * `h8swarm sweep confirm DIR` ([`confirm`]): the cells chosen from a finished map on master
//!   seeds it never used, planned into `DIR/confirm` (run like any sweep folder).
//! * `h8swarm sweep merge DIR` ([`merge`]): one table of every point's claims and first/last
//!   window statistics (CSV and JSON), figures of each claim's effect against the swept keys
//!   ([`figures`]), and the failed and missing points listed; with a confirmation, it too and
//!   the two side by side.
//!
//! A point's results depend only on its scenario (its master seed included: every stream is
//! derived from it by [`swarm::seeds`]), so the merged table is the same byte for byte however
//! the points are split into tasks, in what order they run, and on which machine.
//!
//! Exit status: 2 for bad input (a malformed sweep file, an unknown key, an empty grid, a task
//! out of range, a folder that is not a sweep's, `merge --require-complete` on a sweep with a
//! point that is not ok), 1 when the tool fails (a folder that cannot be
//! written) or, for `run`, when a point failed (it is recorded, and `merge` lists it).

pub mod confirm;
pub mod exec;
pub mod figures;
pub mod merge;
pub mod plan;
pub mod points;
pub mod spec;
pub mod table;

use std::path::Path;

/// Why a sweep command stopped: the two exit statuses.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// Bad input (exit status 2).
    #[error("{0}")]
    Input(String),
    /// The tool failed (exit status 1).
    #[error("{0}")]
    Tool(String),
}

impl SweepError {
    /// Bad input.
    pub fn input(msg: impl Into<String>) -> Self {
        Self::Input(msg.into())
    }

    /// The tool failed.
    pub fn tool(msg: impl Into<String>) -> Self {
        Self::Tool(msg.into())
    }
}

/// Writes `bytes` to `path` through a temporary file beside it and a rename, so a reader
/// never sees half a file.
///
/// # Errors
/// The file cannot be written (tool).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SweepError> {
    let name = path
        .file_name()
        .map_or_else(|| "file".into(), |n| n.to_string_lossy().into_owned());
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    std::fs::write(&tmp, bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            SweepError::tool(format!("cannot write `{}`: {e}", path.display()))
        })
}

/// A name read from a file, as an error message shows it (control and format characters
/// escaped, at most 80 characters).
#[must_use]
pub fn text_of(name: &str) -> String {
    let shown: String = name.chars().take(80).collect();
    swarm::terminal_text::printable(&shown)
}
