//! `h8swarm sweep plan`: the run list, the plan and the `sbatch` script.
//!
//! The folder it writes:
//! * `points.jsonl`: the run list, one JSON line per point in order (`index`, `id`, `task`,
//!   `coords`, `seed`, and its full `scenario`);
//! * `plan.json`: the sweep's name, axes, seeds, tasks and the requests per task;
//! * `sweep.sbatch`: the job array (`sbatch DIR/sweep.sbatch`);
//! * `sweep.toml`: a copy of the sweep file; `points/` (results) and `logs/` (Slurm's output).
//!
//! Planning into a folder that holds a plan is allowed only when the run list is the same
//! (then the script is written again, e.g. for another binary); a different plan is refused,
//! so results of one grid never mix with another's.
//!
//! **Requests.** Every task of an array asks for the same resources, so they are computed for
//! the largest point and the fullest task, on the safe side (any of them can be set in
//! `[slurm]`):
//! * CPUs: the point's parallel work, its runs (conditions × repeats, one thread each), times
//!   ⌈robots / 64⌉ for swarms that step their robots in parallel, at most `max_cpus`;
//! * memory: [`BASE_MEM_MB`], plus per concurrent run [`MODEL_ROBOT_MB`] a model robot or
//!   [`FIRMWARE_ROBOT_MB`] a firmware robot, plus 72 bytes a run-step of metrics and 16 bytes a
//!   tracked robot-step of paths, times 1.5, rounded up to 64 MB;
//! * time: 20 s a point (the fit report, the figures) plus its robot-steps at
//!   [`MODEL_ROBOT_STEPS_PER_S`] or [`FIRMWARE_ROBOT_STEPS_PER_S`] a CPU, summed over the
//!   task's points, times 3, plus 5 minutes.
//!
//! What was measured when these were set: docs/performance.md, "A sweep's requests".

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::spec::{Axis, Point, SlurmSpec, Sweep};
use super::{SweepError, write_atomic};
use swarm::scenario::ControllerKind;

/// Default points per array task.
pub const DEFAULT_POINTS_PER_TASK: usize = 1;
/// Default most array tasks at once (`%L`).
pub const DEFAULT_MAX_PARALLEL: usize = 100;
/// Default upper bound of the computed CPUs per task.
pub const DEFAULT_MAX_CPUS: usize = 8;
/// Memory of the process itself, MB.
pub const BASE_MEM_MB: f64 = 64.0;
/// Memory of one model robot, MB.
pub const MODEL_ROBOT_MB: f64 = 0.5;
/// Memory of one firmware robot, MB (flash, RAM, decode caches).
pub const FIRMWARE_ROBOT_MB: f64 = 2.0;
/// Robot-steps a second on one CPU, model robots (well below what a loaded machine runs).
pub const MODEL_ROBOT_STEPS_PER_S: f64 = 3000.0;
/// Robot-steps a second on one CPU, firmware robots (well below what a loaded machine runs).
pub const FIRMWARE_ROBOT_STEPS_PER_S: f64 = 800.0;

/// One line of `points.jsonl`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanLine {
    /// The point's number.
    pub index: usize,
    /// Its id (its folder's name under `points/`).
    pub id: String,
    /// The array task that runs it.
    pub task: usize,
    /// Its position on each axis.
    pub coords: Vec<usize>,
    /// Its master seed.
    pub seed: u64,
    /// Its full scenario.
    pub scenario: toml::Table,
}

impl PlanLine {
    /// The point it describes.
    #[must_use]
    pub fn point(&self) -> Point {
        Point {
            index: self.index,
            id: self.id.clone(),
            coords: self.coords.clone(),
            seed: self.seed,
            scenario: self.scenario.clone(),
        }
    }
}

/// What each array task asks Slurm for.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Requests {
    /// `--cpus-per-task`.
    pub cpus_per_task: usize,
    /// `--mem`, MB.
    pub mem_mb: u64,
    /// `--time`.
    pub time: String,
}

/// `plan.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// The version of h8swarm that planned it.
    pub h8swarm_version: String,
    /// The sweep's name.
    pub sweep: String,
    /// The axes.
    pub axes: Vec<Axis>,
    /// The master seeds.
    pub seeds: Vec<u64>,
    /// Number of points.
    pub points: usize,
    /// The cells of the axes' grid (index, the first axis slowest) the plan runs, in
    /// increasing order, when not all of them: a confirmation ([`super::confirm`]) runs the
    /// map's grid in chosen cells only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cells: Option<Vec<usize>>,
    /// Points per array task.
    pub points_per_task: usize,
    /// Number of array tasks (0 to `tasks` − 1).
    pub tasks: usize,
    /// At most this many tasks at once.
    pub max_parallel: usize,
    /// What each task asks for.
    pub requests: Requests,
}

/// Slurm's default `MaxArraySize`: array indices 0 to 1 000.
pub const DEFAULT_MAX_ARRAY_SIZE: usize = 1001;
/// The largest `MaxArraySize` Slurm accepts.
pub const SLURM_MAX_ARRAY_SIZE: usize = 4_000_001;
/// The most CPUs a task may ask for (`cpus_per_task`, `max_cpus`).
pub const MAX_CPUS_PER_TASK: usize = 4096;
/// The most memory a task may ask for, MB (16 TiB).
pub const MAX_MEM_MB: u64 = 16 << 20;
/// The longest time limit, minutes (365 days; `UNLIMITED` asks for none).
pub const MAX_TIME_MINUTES: u64 = 365 * 24 * 60;

/// The options the plan writes into `sweep.sbatch` itself; `slurm.extra` may not give them
/// again (the `[slurm]` keys set those that may change).
pub const PLAN_OPTIONS: [&str; 14] = [
    "--array",
    "--output",
    "--error",
    "--open-mode",
    "--requeue",
    "--no-requeue",
    "--ntasks",
    "--job-name",
    "--cpus-per-task",
    "--mem",
    "--mem-per-cpu",
    "--time",
    "--partition",
    "--account",
];

/// A count from `[slurm]`: `default` when absent, else 1 to `max`.
fn count_in(v: Option<usize>, default: usize, key: &str, max: usize) -> Result<usize, SweepError> {
    match v {
        None => Ok(default),
        Some(n) if (1..=max).contains(&n) => Ok(n),
        Some(n) => Err(SweepError::input(format!(
            "sweep file: `slurm.{key}` = {n} is out of range: valid is 1 to {max}"
        ))),
    }
}

/// Checks a `--time` value against the formats `sbatch` takes: `MINUTES`, `MINUTES:SECONDS`,
/// `HOURS:MINUTES:SECONDS`, `DAYS-HOURS`, `DAYS-HOURS:MINUTES`, `DAYS-HOURS:MINUTES:SECONDS`
/// (whole numbers; a later field below 60, hours after days below 24), or `UNLIMITED` /
/// `INFINITE`; the limit must be above 0 and at most 365 days. Returns the minutes (rounded
/// up; `None` for no limit).
///
/// # Errors
/// Anything else, saying the formats.
pub fn slurm_time_minutes(text: &str) -> Result<Option<u64>, String> {
    let formats = "give MINUTES, MM:SS, HH:MM:SS, D-HH, D-HH:MM, D-HH:MM:SS or UNLIMITED (e.g. \"90\", \"12:00:00\", \"2-00:00:00\")";
    let bad = || format!("`slurm.time` = {text:?} is not a Slurm time limit: {formats}");
    let t = text.trim();
    if t.eq_ignore_ascii_case("unlimited") || t.eq_ignore_ascii_case("infinite") {
        return Ok(None);
    }
    let num = |f: &str| -> Result<u64, String> {
        if f.is_empty() || f.len() > 9 || !f.bytes().all(|b| b.is_ascii_digit()) {
            return Err(bad());
        }
        f.parse::<u64>().map_err(|_| bad())
    };
    let (days, clock) = match t.split_once('-') {
        Some((d, rest)) => (Some(num(d)?), rest),
        None => (None, t),
    };
    let fields = clock
        .split(':')
        .map(num)
        .collect::<Result<Vec<u64>, String>>()?;
    let below = |v: u64, limit: u64| if v < limit { Ok(v) } else { Err(bad()) };
    let seconds = match (days, fields.as_slice()) {
        (None, [m]) => m * 60,
        (None, [m, s]) => m * 60 + below(*s, 60)?,
        (None, [h, m, s]) => h * 3600 + below(*m, 60)? * 60 + below(*s, 60)?,
        (Some(d), [h]) => d * 86_400 + below(*h, 24)? * 3600,
        (Some(d), [h, m]) => d * 86_400 + below(*h, 24)? * 3600 + below(*m, 60)? * 60,
        (Some(d), [h, m, s]) => {
            d * 86_400 + below(*h, 24)? * 3600 + below(*m, 60)? * 60 + below(*s, 60)?
        }
        _ => return Err(bad()),
    };
    let minutes = seconds.div_ceil(60);
    if minutes == 0 {
        return Err(format!(
            "`slurm.time` = {text:?} is no time at all: give a limit above 0, or UNLIMITED"
        ));
    }
    if minutes > MAX_TIME_MINUTES {
        return Err(format!(
            "`slurm.time` = {text:?} is more than 365 days: give less, or UNLIMITED"
        ));
    }
    Ok(Some(minutes))
}

/// A setting that goes into an `#SBATCH` line: printable ASCII without spaces or quotes.
fn sbatch_safe(text: &str, key: &str, allowed: &str) -> Result<(), SweepError> {
    let ok = !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || allowed.contains(c));
    if ok {
        Ok(())
    } else {
        Err(SweepError::input(format!(
            "sweep file: `slurm.{key}` = {text:?}: only letters, digits and {allowed:?} are allowed in an #SBATCH line"
        )))
    }
}

/// What a point costs, for the requests: its runs, robots, steps and controller (16 bytes
/// a point, the only thing a plan keeps per point).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PointCost {
    /// Conditions × repeats.
    pub runs: u32,
    /// Robots.
    pub robots: u32,
    /// Steps per run.
    pub steps: u32,
    /// Firmware robots (else model robots).
    pub firmware: bool,
}

impl PointCost {
    /// The cost of a point's scenario.
    #[must_use]
    pub fn of(s: &swarm::scenario::Scenario) -> PointCost {
        let runs = (1 + u32::from(s.controls.learning_off) + u32::from(s.controls.random_walk))
            * s.repeats;
        PointCost {
            runs,
            robots: u32::try_from(s.robots).unwrap_or(u32::MAX),
            steps: s.steps,
            firmware: s.controller.kind == ControllerKind::Firmware,
        }
    }
}

/// The requests of the points (their costs, in order), as the module's docs describe.
///
/// # Errors
/// A bad `[slurm]` value.
pub fn requests(
    costs: &[PointCost],
    slurm: &SlurmSpec,
    per_task: usize,
) -> Result<Requests, SweepError> {
    let max_cpus = count_in(
        slurm.max_cpus,
        DEFAULT_MAX_CPUS,
        "max_cpus",
        MAX_CPUS_PER_TASK,
    )?;
    let mut cpus = 1usize;
    for c in costs {
        let factor = (c.robots as usize)
            .div_ceil(swarm::experiment::PARALLEL_ROBOTS)
            .max(1);
        cpus = cpus.max((c.runs as usize * factor).min(max_cpus));
    }
    let cpus = count_in(
        slurm.cpus_per_task,
        cpus,
        "cpus_per_task",
        MAX_CPUS_PER_TASK,
    )?;
    let mut mem_mb = 0.0f64;
    let mut worst_task_s = 0.0f64;
    let mut task_s = 0.0f64;
    for (i, c) in costs.iter().enumerate() {
        let runs = c.runs as usize;
        let concurrent = cpus.min(runs).max(1) as f64;
        let robots = f64::from(c.robots);
        let steps = f64::from(c.steps);
        let per_robot = if c.firmware {
            FIRMWARE_ROBOT_MB
        } else {
            MODEL_ROBOT_MB
        };
        let tracked = robots.min(swarm::experiment::TRACKED_ROBOTS as f64);
        let mem = BASE_MEM_MB
            + concurrent * robots * per_robot
            + (runs as f64 * steps * 72.0 + steps * tracked * 16.0) / 1_048_576.0;
        mem_mb = mem_mb.max(mem);
        let rate = if c.firmware {
            FIRMWARE_ROBOT_STEPS_PER_S
        } else {
            MODEL_ROBOT_STEPS_PER_S
        };
        if i % per_task == 0 {
            task_s = 0.0;
        }
        task_s += 20.0 + runs as f64 * steps * robots / (rate * concurrent);
        worst_task_s = worst_task_s.max(task_s);
    }
    let mem_mb = match slurm.mem_mb {
        Some(m) if (1..=MAX_MEM_MB).contains(&m) => m,
        Some(m) => {
            return Err(SweepError::input(format!(
                "sweep file: `slurm.mem_mb` = {m} is out of range: valid is 1 to {MAX_MEM_MB} (MB, 16 TiB)"
            )));
        }
        None => ((mem_mb * 1.5 / 64.0).ceil() as u64).clamp(1, MAX_MEM_MB / 64) * 64,
    };
    let time = match &slurm.time {
        Some(t) => {
            slurm_time_minutes(t).map_err(|e| SweepError::input(format!("sweep file: {e}")))?;
            t.trim().to_string()
        }
        None => {
            let minutes = (((worst_task_s * 3.0) / 60.0).ceil() as u64 + 5).min(MAX_TIME_MINUTES);
            format!(
                "{}-{:02}:{:02}:00",
                minutes / 1440,
                (minutes / 60) % 24,
                minutes % 60
            )
        }
    };
    Ok(Requests {
        cpus_per_task: cpus,
        mem_mb,
        time,
    })
}

/// Single-quotes `text` for the shell.
fn shell_quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', r"'\''"))
}

/// The `sbatch` script of a plan.
///
/// # Errors
/// A folder path an `#SBATCH` line cannot carry, or a bad `[slurm]` value.
pub fn sbatch_script(
    plan: &Plan,
    slurm: &SlurmSpec,
    dir: &Path,
    bin: &Path,
) -> Result<String, SweepError> {
    let dir_text = dir.display().to_string();
    if !dir_text
        .chars()
        .all(|c| c.is_ascii_graphic() && !matches!(c, '%' | '"' | '\'' | '\\' | '#'))
    {
        return Err(SweepError::input(format!(
            "sweep folder `{dir_text}`: Slurm's #SBATCH lines cannot carry spaces, %, quotes, # or backslashes in a path: give --out a plainer folder"
        )));
    }
    let mut t = String::new();
    let _ = writeln!(t, "#!/bin/bash");
    let _ = writeln!(
        t,
        "# h8swarm sweep `{}`: {} points in {} array tasks of up to {} points.",
        plan.sweep, plan.points, plan.tasks, plan.points_per_task
    );
    let _ = writeln!(
        t,
        "# Written by `h8swarm sweep plan`; submit with `sbatch {dir_text}/sweep.sbatch`, then"
    );
    let _ = writeln!(
        t,
        "# `h8swarm sweep merge {dir_text}`. A task skips the points already finished, so"
    );
    let _ = writeln!(
        t,
        "# resubmitting (or a requeue after preemption) redoes only what is missing."
    );
    let _ = writeln!(t, "#SBATCH --job-name=h8swarm-{}", plan.sweep);
    let _ = writeln!(
        t,
        "#SBATCH --array=0-{}%{}",
        plan.tasks.saturating_sub(1),
        plan.max_parallel
    );
    let _ = writeln!(t, "#SBATCH --ntasks=1");
    let _ = writeln!(t, "#SBATCH --cpus-per-task={}", plan.requests.cpus_per_task);
    let _ = writeln!(t, "#SBATCH --mem={}M", plan.requests.mem_mb);
    let _ = writeln!(t, "#SBATCH --time={}", plan.requests.time);
    let _ = writeln!(t, "#SBATCH --output={dir_text}/logs/%A_%a.out");
    let _ = writeln!(t, "#SBATCH --open-mode=append");
    let _ = writeln!(t, "#SBATCH --requeue");
    if let Some(p) = &slurm.partition {
        sbatch_safe(p, "partition", "_.,-")?;
        let _ = writeln!(t, "#SBATCH --partition={p}");
    }
    if let Some(a) = &slurm.account {
        sbatch_safe(a, "account", "_.-")?;
        let _ = writeln!(t, "#SBATCH --account={a}");
    }
    for e in slurm.extra.iter().flatten() {
        sbatch_safe(e, "extra", "-_.,:=@/+")?;
        if !e.starts_with("--") {
            return Err(SweepError::input(format!(
                "sweep file: `slurm.extra` entry {e:?}: give long options, like \"--qos=long\""
            )));
        }
        let option = e.split('=').next().unwrap_or(e);
        if PLAN_OPTIONS.contains(&option) {
            return Err(SweepError::input(format!(
                "sweep file: `slurm.extra` entry {e:?}: the plan writes {option} itself (set it with the [slurm] keys cpus_per_task, mem_mb, time, partition, account, points_per_task and max_parallel)"
            )));
        }
        let _ = writeln!(t, "#SBATCH {e}");
    }
    let _ = writeln!(t, "set -euo pipefail");
    let _ = writeln!(
        t,
        "# The task's share is SLURM_ARRAY_TASK_ID's, its threads SLURM_CPUS_PER_TASK."
    );
    let _ = writeln!(
        t,
        "exec {} sweep run {}",
        shell_quote(&bin.display().to_string()),
        shell_quote(&dir_text)
    );
    Ok(t)
}

/// Writes the plan of `sweep` into `dir`; returns what to print.
///
/// # Errors
/// A bad `[slurm]` value, a folder holding another plan (input); a folder that cannot be
/// written (tool).
pub fn write_plan(
    sweep: &Sweep,
    sweep_text: &str,
    dir: &Path,
    bin: Option<&Path>,
) -> Result<String, SweepError> {
    let plan = plan_of(sweep)?;
    let dir = plan_folder(dir)?;
    let bin: PathBuf = match bin {
        Some(b) => b.to_path_buf(),
        None => std::env::current_exe()
            .map_err(|e| SweepError::tool(format!("cannot find this program's path: {e}")))?,
    };
    let script = sbatch_script(&plan, &sweep.slurm, &dir, &bin)?;
    // Second pass: the run list, a point at a time, into a temporary file beside it.
    let list_path = dir.join("points.jsonl");
    let tmp = dir.join(format!(".points.jsonl.tmp-{}", std::process::id()));
    if let Err(e) = write_new_list(sweep, plan.points_per_task, &tmp, &list_path, &dir) {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    for sub in ["points", "logs"] {
        let p = dir.join(sub);
        std::fs::create_dir_all(&p)
            .map_err(|e| SweepError::tool(format!("cannot create `{}`: {e}", p.display())))?;
    }
    let plan_json = serde_json::to_string_pretty(&plan)
        .map_err(|e| SweepError::tool(format!("writing plan.json: {e}")))?
        + "\n";
    write_atomic(&dir.join("sweep.toml"), sweep_text.as_bytes())?;
    std::fs::rename(&tmp, &list_path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        SweepError::tool(format!("cannot write `{}`: {e}", list_path.display()))
    })?;
    write_atomic(&dir.join("plan.json"), plan_json.as_bytes())?;
    write_atomic(&dir.join("sweep.sbatch"), script.as_bytes())?;
    let dir_text = swarm::terminal_text::printable(&dir.display().to_string());
    Ok(plan_summary(&plan, &dir_text))
}

/// The plan of `sweep`: its points shared into array tasks within Slurm's limits, every point
/// checked, and what each task asks for.
fn plan_of(sweep: &Sweep) -> Result<Plan, SweepError> {
    let slurm = &sweep.slurm;
    let per_task = count_in(
        slurm.points_per_task,
        DEFAULT_POINTS_PER_TASK,
        "points_per_task",
        super::spec::MAX_POINTS,
    )?;
    let max_array = count_in(
        slurm.max_array_size,
        DEFAULT_MAX_ARRAY_SIZE,
        "max_array_size",
        SLURM_MAX_ARRAY_SIZE,
    )?;
    let max_parallel = count_in(
        slurm.max_parallel,
        DEFAULT_MAX_PARALLEL.min(max_array),
        "max_parallel",
        max_array,
    )?;
    let tasks = sweep.count.div_ceil(per_task);
    if tasks > max_array {
        let need = sweep.count.div_ceil(max_array);
        return Err(SweepError::input(format!(
            "sweep file: {} points at {per_task} a task make {tasks} array tasks (indices 0 to {}), but Slurm's MaxArraySize of {max_array} allows indices 0 to {} only: set `slurm.points_per_task` to {need} or more, or `slurm.max_array_size` to your cluster's MaxArraySize (`scontrol show config | grep MaxArraySize`)",
            sweep.count,
            tasks - 1,
            max_array - 1
        )));
    }
    // First pass: every point checked, and its cost kept (16 bytes a point) for the requests.
    let mut costs = Vec::with_capacity(sweep.count);
    sweep.check_points(|_, s| {
        costs.push(PointCost::of(s));
        Ok(())
    })?;
    let requests = requests(&costs, slurm, per_task)?;
    drop(costs);
    Ok(Plan {
        h8swarm_version: env!("CARGO_PKG_VERSION").to_string(),
        sweep: sweep.name.clone(),
        axes: sweep.axes.clone(),
        seeds: sweep.seeds.clone(),
        points: sweep.count,
        cells: None,
        points_per_task: per_task,
        tasks,
        max_parallel,
        requests,
    })
}

/// The sweep folder `dir`, created if need be, as an absolute path.
pub(super) fn plan_folder(dir: &Path) -> Result<PathBuf, SweepError> {
    // One rule for output folders (as `run`'s and `merge`'s): a folder with a name of its own.
    crate::stage::check_out_folder("--out", dir).map_err(|e| SweepError::tool(e.0))?;
    std::fs::create_dir_all(dir).map_err(|e| {
        SweepError::tool(format!(
            "cannot create the sweep folder `{}`: {e}",
            dir.display()
        ))
    })?;
    dir.canonicalize()
        .map_err(|e| SweepError::tool(format!("cannot resolve `{}`: {e}", dir.display())))
}

/// Writes the run list into `tmp`; a run list already at `list_path` must be the same (the
/// folder `dir` holds no other plan).
fn write_new_list(
    sweep: &Sweep,
    per_task: usize,
    tmp: &Path,
    list_path: &Path,
    dir: &Path,
) -> Result<(), SweepError> {
    write_list(sweep, per_task, tmp)?;
    if list_path.exists() && !same_file_bytes(list_path, tmp)? {
        return Err(SweepError::input(format!(
            "`{}` already holds a different sweep plan (its points.jsonl differs): give --out a new folder, or remove the old one",
            dir.display()
        )));
    }
    Ok(())
}

/// What `sweep plan` prints: the plan in a line, the requests, and what to run next.
fn plan_summary(plan: &Plan, dir_text: &str) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "h8swarm sweep plan `{}`: {} points ({} axes{}, {} seeds) in {} tasks of up to {} points",
        plan.sweep,
        plan.points,
        plan.axes.len(),
        if plan.axes.is_empty() {
            String::new()
        } else {
            format!(
                ": {}",
                plan.axes
                    .iter()
                    .map(|a| format!("{} x{}", a.name(), a.values.len()))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        },
        plan.seeds.len(),
        plan.tasks,
        plan.points_per_task
    );
    let _ = writeln!(
        t,
        "each task asks for {} CPUs, {} MB, {}",
        plan.requests.cpus_per_task, plan.requests.mem_mb, plan.requests.time
    );
    let _ = writeln!(
        t,
        "wrote {dir_text} (plan.json, points.jsonl, sweep.sbatch)"
    );
    let _ = writeln!(t, "on a cluster: sbatch {dir_text}/sweep.sbatch");
    let _ = writeln!(t, "on this machine: h8swarm sweep run {dir_text}");
    let _ = writeln!(t, "then: h8swarm sweep merge {dir_text}");
    t
}

/// Writes the run list of `sweep` to `path`, one point at a time.
fn write_list(sweep: &Sweep, per_task: usize, path: &Path) -> Result<(), SweepError> {
    use std::io::Write as _;
    let fail = |e: &dyn std::fmt::Display| {
        SweepError::tool(format!("cannot write `{}`: {e}", path.display()))
    };
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).map_err(|e| fail(&e))?);
    for p in sweep.points() {
        let p = p?;
        let line = PlanLine {
            index: p.index,
            id: p.id,
            task: p.index / per_task,
            coords: p.coords,
            seed: p.seed,
            scenario: p.scenario,
        };
        serde_json::to_writer(&mut w, &line).map_err(|e| fail(&e))?;
        w.write_all(b"\n").map_err(|e| fail(&e))?;
    }
    w.flush().map_err(|e| fail(&e))
}

/// Whether two files hold the same bytes (read a block at a time).
pub(super) fn same_file_bytes(a: &Path, b: &Path) -> Result<bool, SweepError> {
    let open = |p: &Path| {
        std::fs::File::open(p)
            .map(std::io::BufReader::new)
            .map_err(|e| SweepError::tool(format!("cannot read `{}`: {e}", p.display())))
    };
    let (mut x, mut y) = (open(a)?, open(b)?);
    let (mut bx, mut by) = (vec![0u8; 1 << 16], vec![0u8; 1 << 16]);
    loop {
        let n = read_full(&mut x, &mut bx)
            .map_err(|e| SweepError::tool(format!("cannot read `{}`: {e}", a.display())))?;
        let m = read_full(&mut y, &mut by)
            .map_err(|e| SweepError::tool(format!("cannot read `{}`: {e}", b.display())))?;
        if n != m || bx[..n] != by[..m] {
            return Ok(false);
        }
        if n == 0 {
            return Ok(true);
        }
    }
}

/// Reads until `buf` is full or the end.
fn read_full(r: &mut impl std::io::Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}

/// Reads a sweep folder's plan and run list.
///
/// # Errors
/// Not a sweep folder, or a damaged plan (input).
pub fn read_plan(dir: &Path) -> Result<(Plan, Vec<PlanLine>), SweepError> {
    let not = |what: &str, e: &dyn std::fmt::Display| {
        SweepError::input(format!(
            "`{}` is not a sweep folder ({what}: {e}): make one with `h8swarm sweep plan SWEEP.toml --out {}`",
            dir.display(),
            dir.display()
        ))
    };
    let plan_text =
        std::fs::read_to_string(dir.join("plan.json")).map_err(|e| not("plan.json", &e))?;
    let plan: Plan = serde_json::from_str(&plan_text).map_err(|e| not("plan.json", &e))?;
    // A plan edited by hand: its sizes are checked before anything is sized by them.
    check_plan_sizes(&plan).map_err(|e| not("plan.json", &e))?;
    let list =
        std::fs::read_to_string(dir.join("points.jsonl")).map_err(|e| not("points.jsonl", &e))?;
    let mut lines = Vec::new();
    let mut ids = std::collections::BTreeSet::new();
    for (n, l) in list.lines().enumerate() {
        let at = format!("points.jsonl line {}", n + 1);
        if n >= plan.points {
            return Err(not(
                "points.jsonl",
                &format!("more lines than the plan's {} points", plan.points),
            ));
        }
        let line: PlanLine = serde_json::from_str(l).map_err(|e| not(&at, &e))?;
        if line.index != n
            || line.id != super::spec::sanitize(&line.id, super::spec::MAX_ID_CHARS)
            || line.task >= plan.tasks.max(1)
        {
            return Err(not(&at, &"its index, id or task does not fit the plan"));
        }
        let fits = line.coords.len() == plan.axes.len()
            && line
                .coords
                .iter()
                .zip(&plan.axes)
                .all(|(&c, a)| c < a.values.len());
        if !fits {
            return Err(not(
                &at,
                &format!(
                    "its coords {:?} lie outside the plan's axes (sizes {:?})",
                    line.coords,
                    plan.axes.iter().map(|a| a.values.len()).collect::<Vec<_>>()
                ),
            ));
        }
        if let Some(list) = &plan.cells
            && list
                .binary_search(&super::figures::cell_index(&plan.axes, &line.coords))
                .is_err()
        {
            return Err(not(
                &at,
                &format!("its coords {:?} lie outside the plan's cells", line.coords),
            ));
        }
        if !ids.insert(line.id.clone()) {
            return Err(not(
                &at,
                &format!("its id `{}` is another point's too", line.id),
            ));
        }
        lines.push(line);
    }
    if lines.len() != plan.points {
        return Err(not(
            "points.jsonl",
            &format!(
                "{} lines for the plan's {} points",
                lines.len(),
                plan.points
            ),
        ));
    }
    Ok((plan, lines))
}

/// Checks the sizes a plan.json gives before anything is allocated by them: every axis has
/// values, one per key; the grid's cells times the seeds is the plan's number of points,
/// computed without overflow, and at most [`super::spec::MAX_POINTS`]; the tasks fit the
/// points.
fn check_plan_sizes(plan: &Plan) -> Result<(), String> {
    if plan.points > super::spec::MAX_POINTS {
        return Err(format!(
            "{} points: at most {} are allowed",
            plan.points,
            super::spec::MAX_POINTS
        ));
    }
    let mut cells: usize = 1;
    for a in &plan.axes {
        if a.keys.is_empty()
            || a.values.is_empty()
            || a.values.iter().any(|v| v.len() != a.keys.len())
        {
            return Err(format!(
                "the axis `{}` needs values, one per key",
                super::text_of(&a.name())
            ));
        }
        cells = cells
            .checked_mul(a.values.len())
            .filter(|&c| c <= super::spec::MAX_POINTS)
            .ok_or_else(|| format!("its axes make more than {} cells", super::spec::MAX_POINTS))?;
    }
    if let Some(list) = &plan.cells {
        if list.windows(2).any(|w| w[0] >= w[1]) || list.last().is_some_and(|&c| c >= cells) {
            return Err(format!(
                "its cells must be distinct, in increasing order and below the grid's {cells}"
            ));
        }
        cells = list.len();
    }
    let want = cells.checked_mul(plan.seeds.len());
    if want != Some(plan.points) {
        return Err(format!(
            "{} points, but its axes and seeds make {}",
            plan.points,
            want.map_or_else(|| "too many".to_string(), |w| w.to_string())
        ));
    }
    if plan.tasks > plan.points.max(1) {
        return Err(format!("{} tasks for {} points", plan.tasks, plan.points));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_limits_take_slurms_formats_only() {
        for (t, minutes) in [
            ("90", Some(90)),
            ("1:30", Some(2)),
            ("12:00:00", Some(720)),
            ("2-00", Some(2880)),
            ("1-02:03", Some(1563)),
            ("0-00:00:30", Some(1)),
            ("UNLIMITED", None),
            ("infinite", None),
            ("365-00:00:00", Some(MAX_TIME_MINUTES)),
        ] {
            assert_eq!(slurm_time_minutes(t), Ok(minutes), "{t}");
        }
        for bad in [
            "-x",
            "short",
            "",
            "0",
            "00:00:00",
            "1:60",
            "1:00:60",
            "1-24",
            "-1",
            "1--2",
            "1:2:3:4",
            "1-2-3",
            " 5 0",
            "1e3",
            "366-00",
            "99999999999",
        ] {
            let e = slurm_time_minutes(bad).unwrap_err();
            assert!(e.contains("slurm.time"), "{bad}: {e}");
        }
    }

    #[test]
    fn requests_refuse_values_slurm_cannot_take() {
        let cost = PointCost {
            runs: 3,
            robots: 3,
            steps: 100,
            firmware: false,
        };
        let with = |f: &dyn Fn(&mut SlurmSpec)| {
            let mut s = SlurmSpec::default();
            f(&mut s);
            requests(&[cost], &s, 1).map_err(|e| e.to_string())
        };
        assert!(with(&|_| {}).is_ok());
        let e = with(&|s| s.cpus_per_task = Some(usize::MAX)).unwrap_err();
        assert!(
            e.contains("cpus_per_task") && e.contains("1 to 4096"),
            "{e}"
        );
        let e = with(&|s| s.mem_mb = Some(u64::MAX)).unwrap_err();
        assert!(e.contains("mem_mb"), "{e}");
        let e = with(&|s| s.mem_mb = Some(0)).unwrap_err();
        assert!(e.contains("mem_mb"), "{e}");
        let e = with(&|s| s.time = Some("short".into())).unwrap_err();
        assert!(e.contains("HH:MM:SS"), "{e}");
        let e = with(&|s| s.max_cpus = Some(0)).unwrap_err();
        assert!(e.contains("max_cpus"), "{e}");
        assert_eq!(
            with(&|s| s.time = Some("2-00:00:00".into())).unwrap().time,
            "2-00:00:00"
        );
    }
}
