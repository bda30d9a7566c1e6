//! The files `h8swarm run` writes into its (staging) output folder: metrics.csv, robots.csv,
//! summary.json with its units, fit.json, the figures and the viewer page.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Serialize;

use crate::figures::{self, TrackFigure};
use crate::plot::{LearningFigure, Series, arena_figure_panels, learning_figure, spacetime_figure};
use crate::stage::Stage;
use swarm::experiment::RunOutput;
use swarm::output_error::OutputError;
use swarm::runner::Analysed;
use swarm::scenario::Scenario;
use swarm::summary::{Claim, ConditionStats, Pairing};

/// Writes every file of the run into the staging folder: metrics.csv (from the runs' row
/// files), robots.csv, summary.json, fit.json, the figures and the viewer page when the plan
/// asks for one; returns the files written, in [`OUTPUT_FILES`]' order.
///
/// # Errors
/// A file that cannot be written or drawn ([`OutputError`]).
pub fn write(
    stage: &Stage,
    s: &Scenario,
    r: &Analysed,
    replay: Option<&swarm::recording::ReplayPlan>,
) -> Result<Vec<String>> {
    write_metrics(&stage.path("metrics.csv"), &r.rows)?;
    write_robots(&stage.path("robots.csv"), &r.runs)?;
    let summary = Summary {
        h8swarm_version: env!("CARGO_PKG_VERSION"),
        scenario: s,
        window_steps: s.window,
        units: UNITS,
        eeprom_records_written: r.saves,
        warnings: &r.warnings,
        conditions: &r.analysis.conditions,
        pairings: &r.analysis.pairings,
        claims: &r.analysis.claims,
        dead_robots: r
            .runs
            .iter()
            .flat_map(|run| {
                run.dead.iter().map(|d| DeadEntry {
                    condition: run.condition.name(),
                    repeat: run.repeat,
                    robot: d,
                })
            })
            .collect(),
        image_configured: r.image_configured,
        battery: &r.battery,
    };
    write_json(&stage.path("summary.json"), &summary)?;
    write_json(&stage.path("fit.json"), &r.fit)?;
    write_figures(s, stage, replay, r)
}

/// Moves the staged files into place; returns the line that says where they went.
///
/// # Errors
/// The move failed ([`OutputError`]; the folder is as it was).
pub fn commit(stage: Stage, names: &[String]) -> Result<String> {
    let out = stage.out().to_path_buf();
    let commit = crate::stage::Commit {
        files: names.to_vec(),
        ours: OUTPUT_FILES.iter().map(|n| (*n).to_string()).collect(),
        folders: Vec::new(),
    };
    stage.commit(&commit).map_err(|e| {
        anyhow::Error::new(OutputError(e.0)).context(format!(
            "the run into `{}` could not be moved into place",
            out.display()
        ))
    })?;
    let (files, plots): (Vec<&String>, Vec<&String>) = names
        .iter()
        .partition(|n| !n.ends_with(".png") && !n.ends_with(".svg"));
    let list = |v: &[&String]| v.iter().map(|n| n.as_str()).collect::<Vec<_>>().join(", ");
    let plots: Vec<String> = plots
        .iter()
        .map(|n| out.join(n).display().to_string())
        .collect();
    Ok(format!(
        "wrote {} ({}); plots: {}\n",
        out.display(),
        list(&files),
        plots.join(", ")
    ))
}

/// How many of [`OUTPUT_FILES`], from the first, every run writes (the tables and the learning
/// figure); the rest depend on the arena and the options.
const ALWAYS_WRITTEN: usize = 6;

/// Every file `h8swarm run` writes into its output folder (`arena.png` for the square arena,
/// `spacetime.png` for the corridor; the others always).
pub const OUTPUT_FILES: [&str; 9] = [
    "metrics.csv",
    "robots.csv",
    "summary.json",
    "fit.json",
    "learning.png",
    "learning.svg",
    "arena.png",
    "spacetime.png",
    "replay.html",
];

#[derive(Serialize)]
struct Summary<'a> {
    h8swarm_version: &'static str,
    scenario: &'a Scenario,
    window_steps: u32,
    units: Units,
    eeprom_records_written: u64,
    warnings: &'a [String],
    conditions: &'a [ConditionStats],
    pairings: &'a [Pairing],
    claims: &'a [Claim],
    /// The robots that died in each run (`--keep-going`); their repeats are left out of the
    /// claims and the window statistics.
    dead_robots: Vec<DeadEntry<'a>>,
    /// `false` when the user's image has no configuration block (it ran with its own
    /// settings, not the scenario's); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    image_configured: Option<bool>,
    battery: &'a swarm::battery::BatteryReport,
}

/// A dead robot as summary.json lists it.
#[derive(Serialize)]
struct DeadEntry<'a> {
    condition: &'static str,
    repeat: u32,
    #[serde(flatten)]
    robot: &'a swarm::experiment::DeadRobot,
}

/// The unit of every quantity the outputs hold (the same on screen, in the CSV files, in
/// summary.json and in the figures).
#[derive(Serialize)]
struct Units {
    mean_d: &'static str,
    collisions_per_robot: &'static str,
    collisions_per_net_m: &'static str,
    collisions_per_m: &'static str,
    collisions_per_moving_step: &'static str,
    contact_percent: &'static str,
    held_percent: &'static str,
    shuttling_percent: &'static str,
    circling_percent: &'static str,
    exploring_percent: &'static str,
    moving_percent: &'static str,
    moved_mm: &'static str,
    net_mm: &'static str,
    straightness: &'static str,
    msd_cm2: &'static str,
    msd_exponent: &'static str,
    fresh_cells_per_100_steps: &'static str,
    new_cells: &'static str,
    gap_cv: &'static str,
    touching_percent: &'static str,
    distance_m: &'static str,
    net_m: &'static str,
    cells_visited: &'static str,
}

const UNITS: Units = Units {
    mean_d: "du (1 du = 80/255 cm), mean over robots and steps",
    collisions_per_robot: "collisions per robot over the window",
    collisions_per_net_m: "collisions per net metre: the robots' net displacement over 20 steps, per step, summed (none below 1 m)",
    collisions_per_m: "collisions per metre of path the robots' centres moved (none below 1 m); a reference: shuttling adds path",
    collisions_per_moving_step: "collisions per robot-step in which the robot moved at least 5 mm; a reference",
    contact_percent: "% of robot time with a bumper pressed",
    held_percent: "% of robot-steps held in place (positions over 100 steps within 5 cm of their mean, or under 2 cm of path over 20 steps)",
    shuttling_percent: "% of robot-steps shuttling (net displacement over 20 steps under 0.2 of the path, with a reversal)",
    circling_percent: "% of robot-steps circling (net displacement over 20 steps under 0.2 of the path, no reversal)",
    exploring_percent: "% of robot-steps exploring (net displacement over 20 steps at least 0.2 of the path)",
    moving_percent: "% of robot-steps in which the robot moved at least 5 mm; a reference",
    moved_mm: "mm a robot's centre moved per step (path)",
    net_mm: "mm per step of net progress: a robot's net displacement over the last 20 steps over 20",
    straightness: "net progress over path",
    msd_cm2: "cm², mean squared displacement over 1, 10 and 100 steps",
    msd_exponent: "log10(MSD over 100 steps / MSD over 10): 2 straight driving, 1 diffusion, 0 confinement",
    fresh_cells_per_100_steps: "cells (0.2 m) a robot enters per 100 steps that it had not been in for 100 steps",
    new_cells: "cells (0.2 m) per robot entered for the first time in the run, over the window",
    gap_cv: "coefficient of variation of the gaps between neighbours, over the steps in which no two touch (none when they touch in half the window)",
    touching_percent: "% of corridor steps in which two neighbours are closer than 1 cm",
    distance_m: "metres a robot's centre moved over the run (path)",
    net_m: "net metres a robot made over the run",
    cells_visited: "distinct cells (0.2 m) a robot was in over the run",
};

/// Writes `value` as pretty JSON with a final newline to `path`.
fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    std::fs::write(path, serde_json::to_string_pretty(value)? + "\n")
        .map_err(anyhow::Error::new)
        .context(OutputError::cannot_write(path))
}

/// The columns of `robots.csv`, one row per robot of every run.
pub const ROBOTS_HEADER: [&str; 20] = [
    "condition",
    "repeat",
    "robot",
    "distance_m",
    "net_m",
    "collisions",
    "moving_steps",
    "held_steps",
    "shuttling_steps",
    "circling_steps",
    "exploring_steps",
    "cells_visited",
    "ends_held",
    "first_lasting_held_step",
    "last_window_distance_m",
    "last_window_net_m",
    "last_window_collisions",
    "last_window_cells",
    "last_class",
    "died_at_step",
];

/// Writes every robot's record of every run (in run order, robots in index order).
fn write_robots(path: &Path, runs: &[RunOutput]) -> Result<()> {
    let write = || -> Result<()> {
        let mut w = csv::Writer::from_path(path)?;
        w.write_record(ROBOTS_HEADER)?;
        for r in runs {
            for (i, t) in r.robots.iter().enumerate() {
                use swarm::motion::MotionClass;
                w.write_record([
                    r.condition.name().to_string(),
                    r.repeat.to_string(),
                    i.to_string(),
                    format!("{}", t.distance_m),
                    format!("{}", t.net_m),
                    t.collisions.to_string(),
                    t.moving_steps.to_string(),
                    t.steps_in(MotionClass::Held).to_string(),
                    t.steps_in(MotionClass::Shuttling).to_string(),
                    t.steps_in(MotionClass::Circling).to_string(),
                    t.steps_in(MotionClass::Exploring).to_string(),
                    t.cells_visited.to_string(),
                    u8::from(t.ends_held).to_string(),
                    t.first_lasting_held_step
                        .map(|k| k.to_string())
                        .unwrap_or_default(),
                    format!("{}", t.last_window_distance_m),
                    format!("{}", t.last_window_net_m),
                    t.last_window_collisions.to_string(),
                    t.last_window_cells.to_string(),
                    t.last_class
                        .map(MotionClass::name)
                        .unwrap_or_default()
                        .to_string(),
                    r.dead
                        .iter()
                        .find(|d| d.robot == i)
                        .map(|d| d.step.to_string())
                        .unwrap_or_default(),
                ])?;
            }
        }
        w.flush()?;
        Ok(())
    };
    write().context(OutputError::cannot_write(path))
}

/// Joins the runs' row files (in run order) under the header into `path`, removing them.
fn write_metrics(path: &Path, parts: &[PathBuf]) -> Result<()> {
    write_metrics_csv(path, parts).context(OutputError::cannot_write(path))
}

fn write_metrics_csv(path: &Path, parts: &[PathBuf]) -> Result<()> {
    let mut w = csv::Writer::from_path(path)?;
    w.write_record(swarm::experiment::METRICS_HEADER)?;
    let mut out = w
        .into_inner()
        .map_err(|e| anyhow::anyhow!("{}", e.error()))?;
    for part in parts {
        let mut f = std::fs::File::open(part)
            .with_context(|| format!("reading the run's rows `{}`", part.display()))?;
        std::io::copy(&mut f, &mut out)?;
        std::fs::remove_file(part)?;
    }
    std::io::Write::flush(&mut out)?;
    Ok(())
}

/// Draws the figures and writes the viewer page when the plan asks for one; returns every file
/// written so far, in [`OUTPUT_FILES`]' order up to the figures.
fn write_figures(
    s: &Scenario,
    stage: &Stage,
    replay: Option<&swarm::recording::ReplayPlan>,
    r: &Analysed,
) -> Result<Vec<String>> {
    let figs = figures::of(s, &r.runs);
    let (png, svg) = (stage.path("learning.png"), stage.path("learning.svg"));
    let drawn = |e: crate::plot::PlotError| {
        anyhow::Error::new(e).context(OutputError("cannot draw the figures".into()))
    };
    learning_figure(&figs.learning, &png, &svg).map_err(drawn)?;
    let mut names: Vec<String> = OUTPUT_FILES[..ALWAYS_WRITTEN]
        .iter()
        .map(|n| (*n).to_string())
        .collect();
    if let Some(plan) = replay {
        write_replay(s, stage, plan, r, &figs.learning)?;
        names.push("replay.html".into());
    }
    match &figs.track {
        Some(TrackFigure::SpaceTime(fig)) => {
            spacetime_figure(fig, &stage.path("spacetime.png")).map_err(drawn)?;
            names.push("spacetime.png".into());
        }
        Some(TrackFigure::Arena(panels)) => {
            arena_figure_panels(panels, &stage.path("arena.png")).map_err(drawn)?;
            names.push("arena.png".into());
        }
        None => {}
    }
    Ok(names)
}

/// Writes the viewer page with the recorded runs (in run order).
fn write_replay(
    s: &Scenario,
    stage: &Stage,
    plan: &swarm::recording::ReplayPlan,
    r: &Analysed,
    fig: &LearningFigure,
) -> Result<()> {
    use crate::viewer::{CurveHeader, Header, MountHeader, RunHeader};
    use swarm::recording::part_paths;
    let (html, arena, runs) = (stage.path("replay.html"), &r.arena, &r.runs);
    let mut headers = Vec::new();
    let mut parts = Vec::new();
    for r in runs {
        if let Some((frames, weight_frames)) = &r.recorded {
            headers.push(RunHeader {
                condition: r.condition.name().to_string(),
                repeat: r.repeat,
                frames: *frames,
                weight_frames: weight_frames.clone(),
            });
            parts.push(part_paths(stage.dir(), r.condition, r.repeat));
        }
    }
    let find = |panel: &[Series], label: &str| -> Vec<f64> {
        panel
            .iter()
            .find(|x| x.label == label)
            .map(|x| x.mean.clone())
            .unwrap_or_default()
    };
    let curves = fig
        .d
        .iter()
        .map(|d| CurveHeader {
            condition: d.label.clone(),
            x: d.x.clone(),
            mean_d: d.mean.clone(),
            collisions_per_robot: find(&fig.collisions, &d.label),
            held_percent: find(&fig.held, &d.label),
            net_mm: fig
                .more
                .iter()
                .find(|p| p.caption.starts_with("Net progress"))
                .map(|p| find(&p.series, &d.label))
                .unwrap_or_default(),
        })
        .collect();
    let params = swarm::experiment::world_params(s);
    let header = Header {
        version: swarm::recording::VERSION,
        name: s.name.clone(),
        arena: match s.arena {
            swarm::scenario::ArenaKind::Corridor => "corridor".into(),
            swarm::scenario::ArenaKind::Square => "square".into(),
        },
        width_m: arena.width_m(),
        height_m: arena.height_m(),
        quantum_m: swarm::recording::quantum_m(arena.width_m(), arena.height_m()),
        walls: arena
            .walls()
            .iter()
            .map(|w| [w.a.0, w.a.1, w.b.0, w.b.1])
            .collect(),
        body_m: [params.body_length_m, params.body_width_m],
        sensors: params
            .sensor_mounts
            .iter()
            .map(|m| MountHeader {
                x_m: m.x_m,
                y_m: m.y_m,
                angle_rad: m.angle_rad,
            })
            .collect(),
        du_m: sensors::du::MM_PER_DU / 1000.0,
        robots: plan.robots,
        run_robots: s.robots,
        steps: s.steps,
        stride: plan.opts.stride,
        step_period_s: s.timing.step_period_s,
        controller: match s.controller.kind {
            swarm::scenario::ControllerKind::Firmware => "firmware".into(),
            swarm::scenario::ControllerKind::Model => "model".into(),
        },
        seed: s.seed,
        weights_shape: [r.n_inputs, s.learner.behaviours],
        behaviours: s.learner.behaviours,
        threshold: s.learner.threshold,
        runs: headers,
        curves,
    };
    crate::viewer::write_viewer(&html, &header, &parts)
}
