//! `h8swarm sweep plan|run|confirm|merge`: the sweep subcommands' arguments and dispatch; the
//! sweep machinery is [`crate::sweep`].

use std::path::PathBuf;

use clap::{Args, Subcommand};

use super::Failure;
use crate::sweep::{SweepError, confirm, exec, merge, plan, spec};

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
pub fn outcome(args: &SweepArgs) -> (String, Result<(), SweepError>) {
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
        SweepCommand::Run { dir, task, threads } => {
            match exec::run_task(dir, *task, *threads, &super::run::run_file) {
                Ok((text, true)) => (text, Ok(())),
                Ok((text, false)) => (
                    text,
                    Err(SweepError::tool(
                        "some points failed (each says why in its status.json; `h8swarm sweep merge` lists them)",
                    )),
                ),
                Err(e) => (String::new(), Err(e)),
            }
        }
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

/// `h8swarm sweep`: runs the sweep command and prints what it found, also when it ends in an
/// error (the points a run did, a merge's table of an incomplete sweep); the error line
/// follows on standard error.
///
/// # Errors
/// As [`outcome`]: [`Failure::Input`] or [`Failure::Tool`].
pub fn command(args: &SweepArgs) -> Result<(), Failure> {
    let (text, result) = outcome(args);
    super::write_text(&text)?;
    result.map_err(|e| match e {
        SweepError::Input(m) => Failure::Input(anyhow::anyhow!(m)),
        SweepError::Tool(m) => Failure::Tool(anyhow::anyhow!(m)),
    })
}
