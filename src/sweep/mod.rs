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

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};

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
    swarm::text::printable(&shown)
}

/// Options of `h8swarm sweep`.
#[derive(Args, Debug, Clone)]
pub struct SweepArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: SweepCommand,
}

/// The sweep's three steps.
#[derive(Subcommand, Debug, Clone)]
pub enum SweepCommand {
    /// Expand a sweep file into DIR: the run list (points.jsonl), plan.json and sweep.sbatch,
    /// a Slurm job array that runs it.
    Plan {
        /// The sweep file (.toml): base scenario, grid, seeds, Slurm settings.
        sweep: PathBuf,
        /// The sweep folder.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// The h8swarm binary the job runs (default: this one).
        #[arg(long, value_name = "PATH")]
        bin: Option<PathBuf>,
    },
    /// Run one array task's points (--task, else SLURM_ARRAY_TASK_ID), or every point;
    /// finished points are skipped.
    Run {
        /// The sweep folder.
        dir: PathBuf,
        /// The task (0 to tasks − 1; see plan.json).
        #[arg(long, value_name = "I")]
        task: Option<usize>,
        /// Worker threads per point (default: SLURM_CPUS_PER_TASK, else all cores). The
        /// results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Plan the confirmation of a finished map: the cells its [confirm] section chooses, on
    /// seeds the map never used, into DIR/confirm (run it like any sweep folder).
    Confirm {
        /// The map's sweep folder.
        dir: PathBuf,
        /// The h8swarm binary the job runs (default: this one).
        #[arg(long, value_name = "PATH")]
        bin: Option<PathBuf>,
    },
    /// Merge every point's claims and window statistics into DIR/merged (sweep.csv,
    /// sweep.json, plots/), listing failed and missing points; with a confirmation in
    /// DIR/confirm, it too and the two side by side (confirmation.csv).
    Merge {
        /// The sweep folder.
        dir: PathBuf,
        /// Output folder (default DIR/merged).
        #[arg(long, value_name = "OUT")]
        out: Option<PathBuf>,
        /// Exit with status 2 unless every point finished (the table is written all the same).
        #[arg(long)]
        require_complete: bool,
    },
}

/// Runs a sweep command; returns the text to print on standard output and how it ended.
/// The text is printed whatever the outcome: a run's points and a merge's summary come
/// before the error that follows them.
///
/// # Errors
/// [`SweepError::Input`] for bad input (and `merge --require-complete` on an incomplete
/// sweep), [`SweepError::Tool`] when the tool fails (and, for `run`, when a point failed).
pub fn command(args: &SweepArgs) -> (String, Result<(), SweepError>) {
    match &args.command {
        SweepCommand::Plan { sweep, out, bin } => {
            let planned = (|| {
                let max = swarm::scenario::MAX_FILE_BYTES;
                let text = swarm::scenario::read_text(sweep, max).map_err(|e| {
                    SweepError::input(format!(
                        "cannot read sweep file `{}`: {e} (give a .toml sweep file)",
                        sweep.display()
                    ))
                })?;
                let s = spec::parse(&text, sweep)?;
                plan::write_plan(&s, &text, out, bin.as_deref())
            })();
            match planned {
                Ok(text) => (text, Ok(())),
                Err(e) => (String::new(), Err(e)),
            }
        }
        SweepCommand::Run { dir, task, threads } => match exec::run_task(dir, *task, *threads) {
            Ok((text, true)) => (text, Ok(())),
            Ok((text, false)) => (
                text,
                Err(SweepError::tool(
                    "some points failed (each says why in its status.json; `h8swarm sweep merge` lists them)",
                )),
            ),
            Err(e) => (String::new(), Err(e)),
        },
        SweepCommand::Confirm { dir, bin } => match confirm::plan_confirmation(dir, bin.as_deref())
        {
            Ok(text) => (text, Ok(())),
            Err(e) => (String::new(), Err(e)),
        },
        SweepCommand::Merge {
            dir,
            out,
            require_complete,
        } => match merge::merge(dir, out.as_deref()) {
            Ok((text, complete)) if *require_complete && !complete => (
                text,
                Err(SweepError::input(
                    "the sweep is not complete (--require-complete): every point above that is not ok must be run again",
                )),
            ),
            Ok((text, _)) => (text, Ok(())),
            Err(e) => (String::new(), Err(e)),
        },
    }
}
