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
//! the largest point and the fullest task (estimates on the safe side, from measurements on a
//! loaded 2-core machine; any of them can be set in `[slurm]`):
//! * CPUs: the point's parallel work, its runs (conditions × repeats, one thread each), times
//!   ⌈robots / 64⌉ for swarms that step their robots in parallel, at most `max_cpus` (8);
//! * memory: 64 MB for the process, plus per concurrent run 0.5 MB a model robot or 2 MB a
//!   firmware robot (512 KB of flash and its decode caches), plus 72 bytes a run-step of
//!   metrics and 16 bytes a tracked robot-step of paths, times 1.5, rounded up to 64 MB;
//! * time: 20 s a point (the fit report, the figures) plus its robot-steps at 3 000 a second a
//!   CPU for model robots or 800 for firmware robots, summed over the task's points, times 3,
//!   plus 5 minutes.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::spec::{Axis, Point, SlurmSpec, Sweep};
use super::{SweepError, write_atomic};
use crate::fit::ControllerKind;

/// Default points per array task.
pub const DEFAULT_POINTS_PER_TASK: usize = 1;
/// Default most array tasks at once (`%L`).
pub const DEFAULT_MAX_PARALLEL: usize = 100;
/// Default upper bound of the computed CPUs per task.
pub const DEFAULT_MAX_CPUS: usize = 8;
/// Memory of the process itself, MB (measured ≈ 30 MB for 3 robots).
pub const BASE_MEM_MB: f64 = 64.0;
/// Memory of one model robot, MB (measured ≈ 0.2 MB).
pub const MODEL_ROBOT_MB: f64 = 0.5;
/// Memory of one firmware robot, MB (measured ≈ 0.8 MB: flash, RAM, decode caches).
pub const FIRMWARE_ROBOT_MB: f64 = 2.0;
/// Robot-steps a second on one CPU, model robots (measured 9 000-14 000 on a loaded machine).
pub const MODEL_ROBOT_STEPS_PER_S: f64 = 3000.0;
/// Robot-steps a second on one CPU, firmware robots (measured ≈ 3 100).
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
    /// Points per array task.
    pub points_per_task: usize,
    /// Number of array tasks (0 to `tasks` − 1).
    pub tasks: usize,
    /// At most this many tasks at once.
    pub max_parallel: usize,
    /// What each task asks for.
    pub requests: Requests,
}

fn positive(v: Option<usize>, default: usize, key: &str) -> Result<usize, SweepError> {
    match v {
        None => Ok(default),
        Some(0) => Err(SweepError::input(format!(
            "sweep file: `slurm.{key}` = 0: give 1 or more"
        ))),
        Some(n) => Ok(n),
    }
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

/// The requests of the points, as the module's docs describe.
///
/// # Errors
/// A bad `[slurm]` value or a point whose scenario does not resolve.
pub fn requests(
    points: &[Point],
    slurm: &SlurmSpec,
    per_task: usize,
) -> Result<Requests, SweepError> {
    let max_cpus = positive(slurm.max_cpus, DEFAULT_MAX_CPUS, "max_cpus")?;
    let mut cpus = 1usize;
    let mut scenarios = Vec::with_capacity(points.len());
    for p in points {
        let s = p.resolve()?;
        let runs = (1 + usize::from(s.controls.learning_off) + usize::from(s.controls.random_walk))
            * s.repeats as usize;
        let factor = s.robots.div_ceil(crate::experiment::PARALLEL_ROBOTS).max(1);
        cpus = cpus.max((runs * factor).min(max_cpus));
        scenarios.push((s, runs));
    }
    let cpus = match slurm.cpus_per_task {
        Some(n) => positive(Some(n), 1, "cpus_per_task")?,
        None => cpus,
    };
    let mut mem_mb = 0.0f64;
    let mut task_s = Vec::new();
    for (i, (s, runs)) in scenarios.iter().enumerate() {
        let firmware = s.controller.kind == ControllerKind::Firmware;
        let concurrent = cpus.min(*runs).max(1) as f64;
        let robots = s.robots as f64;
        let steps = f64::from(s.steps);
        let per_robot = if firmware {
            FIRMWARE_ROBOT_MB
        } else {
            MODEL_ROBOT_MB
        };
        let tracked = robots.min(crate::experiment::TRACKED_ROBOTS as f64);
        let mem = BASE_MEM_MB
            + concurrent * robots * per_robot
            + (*runs as f64 * steps * 72.0 + steps * tracked * 16.0) / 1_048_576.0;
        mem_mb = mem_mb.max(mem);
        let rate = if firmware {
            FIRMWARE_ROBOT_STEPS_PER_S
        } else {
            MODEL_ROBOT_STEPS_PER_S
        };
        let secs = 20.0 + *runs as f64 * steps * robots / (rate * concurrent);
        let task = i / per_task;
        if task_s.len() <= task {
            task_s.push(0.0);
        }
        task_s[task] += secs;
    }
    let mem_mb = match slurm.mem_mb {
        Some(0) => {
            return Err(SweepError::input(
                "sweep file: `slurm.mem_mb` = 0: give 1 or more (MB)",
            ));
        }
        Some(m) => m,
        None => ((mem_mb * 1.5 / 64.0).ceil() as u64).max(1) * 64,
    };
    let time = match &slurm.time {
        Some(t) => {
            sbatch_safe(t, "time", ":-")?;
            t.clone()
        }
        None => {
            let worst = task_s.iter().copied().fold(0.0f64, f64::max);
            let minutes = ((worst * 3.0) / 60.0).ceil() as u64 + 5;
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
    let slurm = &sweep.slurm;
    let per_task = positive(
        slurm.points_per_task,
        DEFAULT_POINTS_PER_TASK,
        "points_per_task",
    )?;
    let max_parallel = positive(slurm.max_parallel, DEFAULT_MAX_PARALLEL, "max_parallel")?;
    let tasks = sweep.points.len().div_ceil(per_task);
    let requests = requests(&sweep.points, slurm, per_task)?;
    let plan = Plan {
        h8swarm_version: env!("CARGO_PKG_VERSION").to_string(),
        sweep: sweep.name.clone(),
        axes: sweep.axes.clone(),
        seeds: sweep.seeds.clone(),
        points: sweep.points.len(),
        points_per_task: per_task,
        tasks,
        max_parallel,
        requests,
    };
    let mut lines = String::new();
    for p in &sweep.points {
        let line = PlanLine {
            index: p.index,
            id: p.id.clone(),
            task: p.index / per_task,
            coords: p.coords.clone(),
            seed: p.seed,
            scenario: p.scenario.clone(),
        };
        let json = serde_json::to_string(&line)
            .map_err(|e| SweepError::tool(format!("writing point {}: {e}", p.id)))?;
        lines.push_str(&json);
        lines.push('\n');
    }

    std::fs::create_dir_all(dir).map_err(|e| {
        SweepError::tool(format!(
            "cannot create the sweep folder `{}`: {e}",
            dir.display()
        ))
    })?;
    let dir = dir
        .canonicalize()
        .map_err(|e| SweepError::tool(format!("cannot resolve `{}`: {e}", dir.display())))?;
    let list_path = dir.join("points.jsonl");
    if let Ok(old) = std::fs::read_to_string(&list_path)
        && old != lines
    {
        return Err(SweepError::input(format!(
            "`{}` already holds a different sweep plan (its points.jsonl differs): give --out a new folder, or remove the old one",
            dir.display()
        )));
    }
    let bin: PathBuf = match bin {
        Some(b) => b.to_path_buf(),
        None => std::env::current_exe()
            .map_err(|e| SweepError::tool(format!("cannot find this program's path: {e}")))?,
    };
    let script = sbatch_script(&plan, slurm, &dir, &bin)?;
    for sub in ["points", "logs"] {
        let p = dir.join(sub);
        std::fs::create_dir_all(&p)
            .map_err(|e| SweepError::tool(format!("cannot create `{}`: {e}", p.display())))?;
    }
    let plan_json = serde_json::to_string_pretty(&plan)
        .map_err(|e| SweepError::tool(format!("writing plan.json: {e}")))?
        + "\n";
    write_atomic(&dir.join("sweep.toml"), sweep_text.as_bytes())?;
    write_atomic(&list_path, lines.as_bytes())?;
    write_atomic(&dir.join("plan.json"), plan_json.as_bytes())?;
    write_atomic(&dir.join("sweep.sbatch"), script.as_bytes())?;

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
        "wrote {} (plan.json, points.jsonl, sweep.sbatch)",
        dir.display()
    );
    let _ = writeln!(t, "on a cluster: sbatch {}/sweep.sbatch", dir.display());
    let _ = writeln!(t, "on this machine: h8swarm sweep run {}", dir.display());
    let _ = writeln!(t, "then: h8swarm sweep merge {}", dir.display());
    Ok(t)
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
    let list =
        std::fs::read_to_string(dir.join("points.jsonl")).map_err(|e| not("points.jsonl", &e))?;
    let mut lines = Vec::new();
    for (n, l) in list.lines().enumerate() {
        let line: PlanLine = serde_json::from_str(l)
            .map_err(|e| not(&format!("points.jsonl line {}", n + 1), &e))?;
        if line.index != n
            || line.id != super::spec::sanitize(&line.id, super::spec::MAX_ID_CHARS)
            || line.task >= plan.tasks.max(1)
        {
            return Err(not(
                &format!("points.jsonl line {}", n + 1),
                &"its index, id or task does not fit the plan",
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
