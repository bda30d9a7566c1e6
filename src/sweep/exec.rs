//! `h8swarm sweep run`: one task's share of the points (or all of them).
//!
//! Each point is run by `h8swarm run`'s own code (the [`RunScenario`] the caller passes:
//! `h8swarm sweep run` passes [`crate::commands::run::run_file`]) into a temporary
//! folder `points/.tmp-ID-HOST-PID`, which gets the point's `scenario.toml` first and its
//! `status.json` last, and is then renamed to `points/ID` in one step: `points/ID` either does
//! not exist or is complete. A point whose folder holds `status.json` with `"status": "ok"`
//! and the planned `scenario.toml` is finished and skipped; anything else (no folder, a failed
//! point, a folder of another scenario, a temporary folder left by a task that was killed) is
//! removed and run again. A task claims a point before it touches anything of it (an exclusive
//! lock on `points/.lock-ID`, which the kernel frees when its holder ends), so two tasks on one
//! plan never work on one point, and a killed task's points are taken over. A point depends only on its scenario, so its files are the same byte
//! for byte whichever task runs it and with how many threads (`run.txt`, the console text with
//! its wall time, is the exception).

use super::plan::{PlanLine, read_plan};
use super::points::{PointState, Status, host_name, is_dead_leftover, point_state};
use super::{SweepError, write_atomic};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How a point is run: its `scenario.toml`, the thread count (as `h8swarm run --threads`) and
/// the output folder in, the console text out. The sweep machinery sits below the commands, so
/// the command that runs a sweep hands it `h8swarm run`'s own code
/// ([`crate::commands::run::run_file`]) rather than the machinery reaching up for it.
pub type RunScenario<'a> = &'a dyn Fn(&Path, Option<usize>, &Path) -> anyhow::Result<String>;

/// What became of a point in a task.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Already finished: skipped.
    Skipped,
    /// Run now, successfully.
    Done,
    /// Run now, and it failed (the reason is in its `status.json`).
    Failed(String),
    /// Another task that is alive holds it (two sweeps on one plan): left to that task.
    Held,
}

fn io_err(what: &str, p: &Path, e: &std::io::Error) -> SweepError {
    SweepError::tool(format!("cannot {what} `{}`: {e}", p.display()))
}

/// Runs one point into `points/ID` (atomically); `threads` as `h8swarm run --threads`.
///
/// # Errors
/// A folder that cannot be written or renamed (tool). A point that fails to run is not an
/// error here: it is recorded in its folder and returned as [`Outcome::Failed`].
pub fn run_point(
    points: &Path,
    line: &PlanLine,
    threads: Option<usize>,
    run: RunScenario<'_>,
) -> Result<Outcome, SweepError> {
    if point_state(points, line) == PointState::Ok {
        return Ok(Outcome::Skipped);
    }
    // The point is claimed before anything of it is touched: an exclusive lock on
    // `points/.lock-ID`, which the kernel releases when the holder ends however it ends (so
    // a killed task's points are taken over by the next). A point another live task holds is
    // left to it.
    let Some(claim) = Claim::take(points, &line.id)? else {
        return Ok(Outcome::Held);
    };
    // Checked again under the claim: the holder before may have finished it.
    let outcome = if point_state(points, line) == PointState::Ok {
        Ok(Outcome::Skipped)
    } else {
        run_claimed(points, line, threads, run)
    };
    claim.release();
    outcome
}

/// An exclusive claim on a point (see [`run_point`]): a lock on `points/.lock-ID`.
struct Claim {
    path: PathBuf,
    file: std::fs::File,
    _registered: crate::cleanup::Staged,
}

/// The prefix of a claim's file under `points/`.
pub const CLAIM_PREFIX: &str = ".lock-";

/// Locks the file at `path` if no one holds it: `Ok(None)` when another process holds its
/// lock. The lock holds only if the file locked is still the one at `path` (a holder may have
/// removed it between the open and the lock): otherwise it is tried again.
fn lock_file(path: &Path) -> Result<Option<std::fs::File>, SweepError> {
    use std::os::unix::fs::MetadataExt;
    loop {
        let file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(path)
            .map_err(|e| io_err("open the claim", path, &e))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => return Ok(None),
            Err(std::fs::TryLockError::Error(e)) => {
                return Err(io_err("lock the claim", path, &e));
            }
        }
        let held = file.metadata().map(|m| (m.dev(), m.ino())).ok();
        let there = std::fs::metadata(path).map(|m| (m.dev(), m.ino())).ok();
        if held.is_some() && held == there {
            return Ok(Some(file));
        }
    }
}

impl Claim {
    /// Takes the claim on point `id`, or `None` when another live task holds it.
    fn take(points: &Path, id: &str) -> Result<Option<Claim>, SweepError> {
        let path = points.join(format!("{CLAIM_PREFIX}{id}"));
        // Removed if a signal stops the task (the lock itself goes with the process).
        let registered = crate::cleanup::Staged::register(&path);
        Ok(lock_file(&path)?.map(|file| Claim {
            path,
            file,
            _registered: registered,
        }))
    }

    /// Gives the claim up, removing its file (a task that opened it meanwhile finds it gone
    /// once it holds the lock, and tries again).
    fn release(self) {
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

/// Runs a point this task has claimed.
fn run_claimed(
    points: &Path,
    line: &PlanLine,
    threads: Option<usize>,
    run: RunScenario<'_>,
) -> Result<Outcome, SweepError> {
    let final_dir = points.join(&line.id);
    // Leftovers of this point: a broken or failed folder, temporary folders of killed tasks
    // (`.tmp-ID-…`) and the staging folders of their runs (`..tmp-ID-….partial-PID`).
    let stale_prefix = format!(".tmp-{}-", line.id);
    let stale_stage = format!(".{stale_prefix}");
    if let Ok(entries) = std::fs::read_dir(points) {
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with(&stale_prefix) || name.starts_with(&stale_stage) {
                let p = e.path();
                std::fs::remove_dir_all(&p).map_err(|e| io_err("remove", &p, &e))?;
            }
        }
    }
    if final_dir.exists() {
        std::fs::remove_dir_all(&final_dir).map_err(|e| io_err("remove", &final_dir, &e))?;
    }
    let tmp = points.join(format!(
        "{stale_prefix}{}-{}",
        host_name(),
        std::process::id()
    ));
    // Removed if a signal stops the task (its run's own staging folder is registered too).
    let registered = crate::cleanup::Staged::register(&tmp);
    std::fs::create_dir_all(&tmp).map_err(|e| io_err("create", &tmp, &e))?;
    let scenario_path = tmp.join("scenario.toml");
    write_atomic(&scenario_path, line.point().scenario_toml()?.as_bytes())?;
    let (status, outcome) = match run(&scenario_path, threads, &tmp) {
        Ok(text) => {
            write_atomic(&tmp.join("run.txt"), text.as_bytes())?;
            (
                Status {
                    id: line.id.clone(),
                    status: "ok".into(),
                    error: None,
                },
                Outcome::Done,
            )
        }
        Err(e) => {
            // The temporary folder's name means nothing to a reader: say what was run.
            let why = format!("{e:#}").replace(&tmp.display().to_string(), &line.id);
            (
                Status {
                    id: line.id.clone(),
                    status: "failed".into(),
                    error: Some(why.clone()),
                },
                Outcome::Failed(why),
            )
        }
    };
    let json = serde_json::to_string_pretty(&status)
        .map_err(|e| SweepError::tool(format!("writing status.json: {e}")))?
        + "\n";
    write_atomic(&tmp.join("status.json"), json.as_bytes())?;
    let renamed = crate::cleanup::while_committing(|| std::fs::rename(&tmp, &final_dir));
    if let Err(e) = renamed {
        // Another task finished the same point first: keep its folder if it is complete.
        let _ = std::fs::remove_dir_all(&tmp);
        if point_state(points, line) != PointState::Ok {
            return Err(io_err("rename the finished point into", &final_dir, &e));
        }
    }
    registered.release();
    Ok(outcome)
}

/// Removes the leftovers under `points` of this machine's processes that are gone
/// ([`is_dead_leftover`]); returns their names.
///
/// # Errors
/// A leftover that cannot be removed (tool).
pub fn remove_dead_leftovers(points: &Path) -> Result<Vec<String>, SweepError> {
    let host = host_name();
    let mut removed = Vec::new();
    for e in std::fs::read_dir(points).into_iter().flatten().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        // A claim no one holds (its task was killed): removed under its lock.
        if name.starts_with(CLAIM_PREFIX) {
            let p = e.path();
            if let Some(file) = lock_file(&p)? {
                let _ = std::fs::remove_file(&p);
                drop(file);
            }
            continue;
        }
        if is_dead_leftover(&name, &host) {
            let p = e.path();
            std::fs::remove_dir_all(&p).map_err(|e| io_err("remove", &p, &e))?;
            removed.push(name);
        }
    }
    removed.sort();
    Ok(removed)
}

/// Which task `sweep run` serves: `--task`, else `SLURM_ARRAY_TASK_ID`, else every task.
///
/// # Errors
/// A `SLURM_ARRAY_TASK_ID` that is not a whole number.
pub fn task_from(task: Option<usize>) -> Result<Option<usize>, SweepError> {
    if task.is_some() {
        return Ok(task);
    }
    match std::env::var("SLURM_ARRAY_TASK_ID") {
        Ok(v) => v.trim().parse::<usize>().map(Some).map_err(|_| {
            SweepError::input(format!(
                "SLURM_ARRAY_TASK_ID = {v:?} is not a task number: submit sweep.sbatch as a job array, or give --task"
            ))
        }),
        Err(_) => Ok(None),
    }
}

/// Threads: `--threads`, else `SLURM_CPUS_PER_TASK`, else all cores.
#[must_use]
pub fn threads_from(threads: Option<usize>) -> Option<usize> {
    threads.or_else(|| {
        std::env::var("SLURM_CPUS_PER_TASK")
            .ok()
            .and_then(|v| v.trim().parse::<usize>().ok())
            .filter(|&n| n > 0)
    })
}

/// Runs task `task`'s points (every point when `None`) of the sweep in `dir`; returns what to
/// print and whether every point is finished.
///
/// # Errors
/// Not a sweep folder, a task out of range, `--threads 0` (input); a folder that cannot be
/// written (tool).
pub fn run_task(
    dir: &Path,
    task: Option<usize>,
    threads: Option<usize>,
    run: RunScenario<'_>,
) -> Result<(String, bool), SweepError> {
    let (plan, lines) = read_plan(dir)?;
    if threads == Some(0) {
        return Err(SweepError::input(
            "--threads 0: give at least 1 (or leave it out for SLURM_CPUS_PER_TASK or all cores)",
        ));
    }
    let task = task_from(task)?;
    if let Some(t) = task
        && t >= plan.tasks
    {
        return Err(SweepError::input(format!(
            "task {t} is out of range: the plan in `{}` has tasks 0 to {}",
            dir.display(),
            plan.tasks.saturating_sub(1)
        )));
    }
    let threads = threads_from(threads);
    let points: PathBuf = dir.join("points");
    std::fs::create_dir_all(&points).map_err(|e| io_err("create", &points, &e))?;
    // What killed tasks of this machine left (of any point) goes first.
    for name in remove_dead_leftovers(&points)? {
        eprintln!(
            "removed points/{}: left by a task that was killed",
            swarm::terminal_text::printable(&name)
        );
    }
    let share: Vec<&PlanLine> = lines
        .iter()
        .filter(|l| task.is_none_or(|t| l.task == t))
        .collect();
    let mut t = String::new();
    let _ = writeln!(
        t,
        "h8swarm sweep run `{}`: {}, {} points",
        plan.sweep,
        task.map_or_else(
            || format!("all {} tasks", plan.tasks),
            |k| format!("task {k} of 0-{}", plan.tasks.saturating_sub(1))
        ),
        share.len()
    );
    let (mut done, mut skipped, mut failed, mut held) = (0, 0, 0, 0);
    for line in share {
        let started = Instant::now();
        let outcome = run_point(&points, line, threads, run)?;
        let line_text = match &outcome {
            Outcome::Skipped => {
                skipped += 1;
                format!("{} finished before: skipped", line.id)
            }
            Outcome::Done => {
                done += 1;
                format!(
                    "{} done in {:.1} s",
                    line.id,
                    started.elapsed().as_secs_f64()
                )
            }
            Outcome::Failed(why) => {
                failed += 1;
                format!("{} FAILED: {why}", line.id)
            }
            Outcome::Held => {
                held += 1;
                format!("{} is being run by another task: left to it", line.id)
            }
        };
        // One line per point as it ends, for Slurm's log (standard output holds the totals).
        eprintln!("{}", swarm::terminal_text::printable(&line_text));
    }
    let _ = writeln!(
        t,
        "{done} run, {skipped} skipped (finished before), {failed} failed{}",
        if held > 0 {
            format!(", {held} left to another task running them now")
        } else {
            String::new()
        }
    );
    Ok((t, failed == 0))
}
