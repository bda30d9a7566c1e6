//! The whole experiment in one call ([`run`]): every condition's repeats on a pool of worker
//! threads, then their analysis (the window statistics, the pairings, the claims), the battery
//! life and the fit verdict, returned together ([`Analysed`]). The caller checks the scenario
//! and its options first and writes the outputs after; nothing here prints.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{Context, Result};
use rayon::prelude::*;
use robot_board::model::ControllerConfig;
use world::Arena;

use crate::battery::{BatteryReport, ConditionParts};
use crate::energy::Pack;
use crate::experiment::{RobotProbes, RunOptions, RunOutput, arena_of, run_one};
use crate::fit::FitReport;
use crate::recording::{Recorder, ReplayPlan, part_paths};
use crate::robot::{Condition, Images, controller_config};
use crate::scenario::{ControllerKind, Scenario};
use crate::summary::{Analysis, ConditionStats, analyse};

/// How the experiment runs besides its scenario. The results depend on none of it but
/// `keep_going` and `capacity_mah` (the battery life).
#[derive(Debug)]
pub struct Options<'a> {
    /// Worker threads.
    pub threads: usize,
    /// The robots' firmware images (firmware robots), loaded and checked.
    pub images: Option<&'a Images>,
    /// Probes on one robot of the learning run's first repeat.
    pub probes: RobotProbes,
    /// The runs to record for the viewer, if any.
    pub replay: Option<&'a ReplayPlan>,
    /// Mark a robot whose controller fails dead and go on.
    pub keep_going: bool,
    /// What the firmware robots' stack guards do.
    pub stack_guard: h8300h::cpu::StackGuardMode,
    /// Stop a firmware robot at its first access to what the chip does not model.
    pub strict_io: bool,
    /// The capacity of one cell of the robots' pack, mAh.
    pub capacity_mah: f64,
    /// The folder the runs write their rows of metrics ([`Analysed::rows`]) and their
    /// recordings into.
    pub folder: &'a Path,
}

/// The experiment's runs and what they show.
#[derive(Debug)]
pub struct Analysed {
    /// The conditions run: learning, then the controls the scenario asks for.
    pub conditions: Vec<Condition>,
    /// Every run's output, condition after condition, repeat after repeat.
    pub runs: Vec<RunOutput>,
    /// The files holding each run's rows of metrics, in run order (in [`Options::folder`]).
    pub rows: Vec<PathBuf>,
    /// The window statistics, the pairings and the claims.
    pub analysis: Analysis,
    /// Each condition's battery life.
    pub battery: BatteryReport,
    /// The fit verdict of the scenario's learner on the robot firmware.
    pub fit: FitReport,
    /// What the run's shape makes unreliable.
    pub warnings: Vec<String>,
    /// The learner's inputs (the rows of its weights).
    pub n_inputs: usize,
    /// The arena the robots ran in.
    pub arena: Arena,
    /// EEPROM records written over every run.
    pub saves: u64,
    /// `Some(false)` when the user's image has no configuration block (it ran with its own
    /// settings, not the scenario's); `None` otherwise.
    pub image_configured: Option<bool>,
    /// When every robot of every run died: what to say.
    pub all_dead: Option<String>,
    /// Seconds the runs took (the analysis left out).
    pub wall_s: f64,
}

/// The conditions `s` runs (learning, then the controls it asks for) and its runs: every
/// condition's repeats, condition after condition.
#[must_use]
pub fn jobs(s: &Scenario) -> (Vec<Condition>, Vec<(Condition, u32)>) {
    let mut kinds = vec![Condition::Learning];
    if s.controls.learning_off {
        kinds.push(Condition::LearningOff);
    }
    if s.controls.random_walk {
        kinds.push(Condition::RandomWalk);
    }
    let jobs = kinds
        .iter()
        .flat_map(|&c| (0..s.repeats).map(move |r| (c, r)))
        .collect();
    (kinds, jobs)
}

/// Runs the experiment of `s` and analyses it. `progress` is called with the robot-steps done
/// since its last call, from any worker.
///
/// # Errors
/// A run that fails (a controller failure without `keep_going`, a row or recording file that
/// cannot be written, a probe that fails), or the fit's measurement.
pub fn run(s: &Scenario, mut o: Options, progress: &(dyn Fn(u64) + Sync)) -> Result<Analysed> {
    let probes = std::mem::take(&mut o.probes);
    // The scenario's learner, configured once: the fit measures it and the outputs name its
    // shape.
    let controller = controller_config(s, crate::fit::fit_weight_seed(s.seed))?;
    let (conditions, jobs) = jobs(s);
    let arena = arena_of(s)?;
    let rows: Vec<PathBuf> = jobs
        .iter()
        .map(|&(c, r)| rows_path(o.folder, c, r))
        .collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(o.threads)
        .build()
        .context("starting the worker threads")?;
    let started = Instant::now();
    let runs = pool.install(|| run_all(s, &o, probes, &jobs, &arena, progress))?;
    let wall_s = started.elapsed().as_secs_f64();
    let analysis = analyse(
        &runs,
        s.robots,
        s.steps,
        s.window,
        crate::seeds::bootstrap_seed(s.seed),
    );
    let battery = battery_report(s, o.capacity_mah, &analysis.conditions, &runs);
    let warnings = warnings(s);
    let all_dead = all_dead(&runs, s.robots);
    Ok(Analysed {
        conditions,
        rows,
        warnings,
        saves: runs.iter().map(|r| r.saves).sum(),
        image_configured: o
            .images
            .and_then(|i| i.user.as_ref())
            .map(|(fw, _)| fw.has_config_block())
            .filter(|configured| !configured),
        all_dead,
        analysis,
        battery,
        n_inputs: controller.n_inputs(),
        fit: measure_fit(s, controller)?,
        arena,
        runs,
        wall_s,
    })
}

/// The file a run writes its rows of metrics.csv into as its steps complete.
fn rows_path(folder: &Path, c: Condition, r: u32) -> PathBuf {
    folder.join(format!(".rows-{}-{r}.csv", c.name()))
}

/// Runs every job on the current pool's workers, each run writing its rows (and its frames, when the
/// plan records it); the runs' outputs in job order.
fn run_all(
    s: &Scenario,
    o: &Options,
    probes: RobotProbes,
    jobs: &[(Condition, u32)],
    arena: &Arena,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<RunOutput>> {
    // The probes go to the learning run's first repeat, whichever worker takes it.
    let probes = Mutex::new(Some(probes));
    // Every condition's runs are recorded in the repeats the plan names.
    let recorded = |r: u32| o.replay.is_some_and(|p| p.repeats.contains(&r));
    jobs.par_iter()
        .map(|&(c, r)| {
            let track = c == Condition::Learning && r == 0;
            let probes = if track {
                probes.lock().ok().and_then(|mut p| p.take())
            } else {
                None
            };
            let replay = match o.replay.filter(|_| recorded(r)) {
                Some(p) => Some((
                    Recorder::new(
                        p.opts.clone(),
                        (arena.width_m(), arena.height_m()),
                        part_paths(o.folder, c, r),
                    )?,
                    p.robots,
                )),
                None => None,
            };
            run_one(
                s,
                c,
                r,
                o.images,
                progress,
                RunOptions {
                    record_track: track,
                    keep_going: o.keep_going,
                    rows: Some(rows_path(o.folder, c, r)),
                    probes: probes.unwrap_or_default(),
                    replay,
                    stack_guard: o.stack_guard,
                    strict_io: o.strict_io,
                    // A run alone on its pool keeps the pool's other worker spinning through
                    // its world's sub-steps; beside other runs the workers have runs to do.
                    spinning_helper: jobs.len() == 1,
                },
            )
        })
        .collect::<Result<_>>()
}

/// The battery life of each condition for a pack of cells of `capacity_mah`.
fn battery_report(
    s: &Scenario,
    capacity_mah: f64,
    stats: &[ConditionStats],
    runs: &[RunOutput],
) -> BatteryReport {
    let mut b = BatteryReport::of(stats, Pack::paper(capacity_mah), s.timing.step_period_s);
    let robot_seconds = s.robots as f64 * f64::from(s.steps) * s.timing.step_period_s;
    for c in stats {
        let of_c: Vec<&RunOutput> = runs.iter().filter(|r| r.condition == c.condition).collect();
        b.by_part
            .push(ConditionParts::of(c.condition, &of_c, robot_seconds));
    }
    b
}

/// The fit verdict of the scenario's learner (`controller`) on the robot firmware (400 steps,
/// compared with the model).
fn measure_fit(s: &Scenario, controller: ControllerConfig) -> Result<FitReport> {
    Ok(crate::fit::measure(&crate::fit::FitConfig {
        controller,
        steps: 400,
        seed: s.seed,
        kind: ControllerKind::Firmware,
        firmware: crate::fit::FirmwareUnderTest::robot()?,
        compare: true,
        strict_io: false,
    })?)
}

/// When every robot of every run died (`keep_going`): what to say, with the first robot's
/// reason.
fn all_dead(runs: &[RunOutput], robots: usize) -> Option<String> {
    let every = !runs.is_empty() && runs.iter().all(|r| r.dead.len() >= robots);
    every.then(|| {
        let why = runs
            .iter()
            .flat_map(|r| &r.dead)
            .next()
            .map_or_else(String::new, |d| format!(" (the first: {})", d.why));
        format!(
            "every robot of every run died{why}: nothing could be judged (every claim is undecided); the outputs name the dead robots"
        )
    })
}

/// What the run's shape makes unreliable (too few windows or repeats, a symbol table that is
/// not used).
#[must_use]
pub fn warnings(s: &Scenario) -> Vec<String> {
    let mut w = Vec::new();
    let windows = s.steps / s.window.max(1);
    if windows < 3 {
        w.push(format!(
            "the run has {windows} whole windows of {} steps: the curves' points are marked and are no trend (use more steps or a smaller window)",
            s.window
        ));
    }
    if s.repeats < 2 {
        w.push("one repeat: no intervals and no paired test (use --repeats 5 or more)".into());
    } else if s.repeats < 5 {
        w.push(format!(
            "{} repeats: a one-sided sign test needs at least 5 repeats all going one way to reach p < 0.05, so no claim can hold",
            s.repeats
        ));
    }
    if let Some(sym) = &s.controller.symbols
        && s.controller.image.is_none()
    {
        w.push(format!(
            "`controller.symbols` = {} is not used: it is the symbol table of `controller.image`, and {}",
            crate::terminal_text::printable(sym),
            if s.controller.kind == ControllerKind::Model {
                "the robots run the Rust model (controller.kind = \"model\")"
            } else {
                "the robots run the built-in firmware"
            }
        ));
    }
    w
}
