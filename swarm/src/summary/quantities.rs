//! The quantities measured per window ([`Quantity`]), their statistics per condition over
//! the repeats, and the robots compared robot by robot ([`Pairing`]).
//!
//! * **Units**, one per quantity everywhere (screen, `metrics.csv`, `summary.json`, figures):
//!   D in du; collisions as counts per robot, per net metre, per path metre and per moving
//!   robot-step; contact time and the motion classes' shares in percent; path and net progress
//!   in mm per step; mean squared displacement in cm²; cells per 100 steps and per robot.

use super::stats::{Estimate, mcnemar_p};
use crate::experiment::{RunOutput, WindowSums};
use crate::robot::Condition;
use serde::Serialize;

/// A window's gap CV is the mean over its steps in which no neighbours touch, and has a value
/// only when at least this share of its steps do.
pub const GAP_CV_MIN_DEFINED: f64 = 0.5;

/// Collisions per metre (net or of path) are defined for a window only when its robots made at
/// least this many metres between them: below that a rate per metre is noise, and a swarm that
/// stood still would otherwise earn a perfect score.
pub const MIN_MOVED_M: f64 = 1.0;

/// Collisions per moving robot-step are defined only over at least this many moving
/// robot-steps.
pub const MIN_MOVING_ROBOT_STEPS: f64 = 20.0;

/// A quantity of a window, computed from one run's sums over it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// Mean summed sensor distance D, du.
    MeanD,
    /// Collisions per robot over the window.
    CollisionsPerRobot,
    /// Collisions per net metre (the net displacement over the lag, per step, summed; none
    /// below [`MIN_MOVED_M`]).
    CollisionsPerNetM,
    /// Collisions per metre of path the robots moved (none below [`MIN_MOVED_M`]); a
    /// reference: a shuttler adds metres without getting anywhere.
    CollisionsPerM,
    /// Collisions per moving robot-step (none below [`MIN_MOVING_ROBOT_STEPS`]); a reference.
    CollisionsPerMovingStep,
    /// Time with a bumper pressed, percent.
    ContactPercent,
    /// Held robot-steps, percent.
    HeldPercent,
    /// Shuttling robot-steps, percent.
    ShuttlingPercent,
    /// Circling robot-steps, percent.
    CirclingPercent,
    /// Exploring robot-steps, percent.
    ExploringPercent,
    /// Moving robot-steps (at least 5 mm), percent; a reference.
    MovingPercent,
    /// Distance a robot moved per step (path), mm.
    MovedMm,
    /// Net progress: a robot's net displacement over the lag per step, mm.
    NetMm,
    /// Net progress over path: net over moved.
    Straightness,
    /// Mean squared displacement over [`crate::motion::MSD_LAGS`]`[i]` steps, cm².
    Msd(usize),
    /// The MSD's exponent from the lag of 10 to that of 100 steps: log₁₀(MSD₁₀₀ / MSD₁₀)
    /// (2 straight driving, 1 diffusion, 0 confinement).
    MsdExponent,
    /// Fresh cells a robot enters per 100 steps ([`crate::motion::FRESH_STEPS`]).
    FreshCells,
    /// New cells per robot over the window.
    NewCells,
    /// The corridor's gap CV (none in the square arena, and none when neighbours touch in
    /// half the window's steps or more).
    GapCv,
    /// Corridor steps in which neighbours touch, percent (none in the square arena).
    TouchingPercent,
    /// Energy a robot draws from its pack per step, mJ.
    EnergyMj,
}

impl Quantity {
    /// Its name in `summary.json` and the sweep table.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Quantity::MeanD => "mean_d",
            Quantity::CollisionsPerRobot => "collisions_per_robot",
            Quantity::CollisionsPerNetM => "collisions_per_net_m",
            Quantity::CollisionsPerM => "collisions_per_m",
            Quantity::CollisionsPerMovingStep => "collisions_per_moving_step",
            Quantity::ContactPercent => "contact_percent",
            Quantity::HeldPercent => "held_percent",
            Quantity::ShuttlingPercent => "shuttling_percent",
            Quantity::CirclingPercent => "circling_percent",
            Quantity::ExploringPercent => "exploring_percent",
            Quantity::MovingPercent => "moving_percent",
            Quantity::MovedMm => "moved_mm",
            Quantity::NetMm => "net_mm",
            Quantity::Straightness => "straightness",
            Quantity::Msd(0) => "msd_1_cm2",
            Quantity::Msd(1) => "msd_10_cm2",
            Quantity::Msd(_) => "msd_100_cm2",
            Quantity::MsdExponent => "msd_exponent",
            Quantity::FreshCells => "fresh_cells_per_100_steps",
            Quantity::NewCells => "new_cells",
            Quantity::GapCv => "gap_cv",
            Quantity::TouchingPercent => "touching_percent",
            Quantity::EnergyMj => "energy_per_robot_step_mj",
        }
    }

    /// Its unit, short.
    #[must_use]
    pub const fn unit(self) -> &'static str {
        match self {
            Quantity::MeanD => "du",
            Quantity::CollisionsPerRobot => "per robot",
            Quantity::CollisionsPerNetM => "per net m",
            Quantity::CollisionsPerM => "per m",
            Quantity::CollisionsPerMovingStep => "per moving robot-step",
            Quantity::ContactPercent
            | Quantity::HeldPercent
            | Quantity::ShuttlingPercent
            | Quantity::CirclingPercent
            | Quantity::ExploringPercent
            | Quantity::MovingPercent
            | Quantity::TouchingPercent => "%",
            Quantity::MovedMm | Quantity::NetMm => "mm",
            Quantity::Straightness => "net/path",
            Quantity::Msd(_) => "cm²",
            Quantity::MsdExponent => "exponent",
            Quantity::FreshCells => "cells per 100 steps",
            Quantity::NewCells => "cells per robot",
            Quantity::GapCv => "CV",
            Quantity::EnergyMj => "mJ",
        }
    }

    /// Its value for one run's sums `w` over a window of a run with `robots` robots.
    #[must_use]
    pub fn of(self, w: &WindowSums, robots: usize) -> Option<f64> {
        if w.steps == 0 {
            return None;
        }
        let steps = f64::from(w.steps);
        let robots = robots.max(1) as f64;
        let per =
            |metres: f64| (metres >= MIN_MOVED_M).then(|| w.collisions_per_robot * robots / metres);
        let msd = |l: usize| (w.msd_steps[l] > 0).then(|| w.msd_cm2[l] / f64::from(w.msd_steps[l]));
        match self {
            Quantity::MeanD => Some(w.mean_d / steps),
            Quantity::CollisionsPerRobot => Some(w.collisions_per_robot),
            Quantity::CollisionsPerNetM => per(w.net_mm / 1000.0 * robots),
            Quantity::CollisionsPerM => per(w.moved_mm / 1000.0 * robots),
            Quantity::CollisionsPerMovingStep => {
                let moving = w.moving_percent / 100.0 * robots;
                (moving >= MIN_MOVING_ROBOT_STEPS).then(|| w.collisions_per_robot * robots / moving)
            }
            Quantity::ContactPercent => Some(w.contact_percent / steps),
            Quantity::HeldPercent => Some(w.held_percent / steps),
            Quantity::ShuttlingPercent => Some(w.shuttling_percent / steps),
            Quantity::CirclingPercent => Some(w.circling_percent / steps),
            Quantity::ExploringPercent => Some(w.exploring_percent / steps),
            Quantity::MovingPercent => Some(w.moving_percent / steps),
            Quantity::MovedMm => Some(w.moved_mm / steps),
            Quantity::NetMm => Some(w.net_mm / steps),
            Quantity::Straightness => (w.moved_mm > 0.0).then(|| w.net_mm / w.moved_mm),
            Quantity::Msd(l) => msd(l.min(2)),
            Quantity::MsdExponent => match (msd(1), msd(2)) {
                (Some(a), Some(b)) if a > 0.0 && b > 0.0 => Some(libm::log10(b / a)),
                _ => None,
            },
            Quantity::FreshCells => Some(w.fresh_cells / steps * 100.0),
            Quantity::NewCells => Some(w.new_cells),
            Quantity::GapCv => (w.is_corridor()
                && f64::from(w.gap_cv_steps) >= GAP_CV_MIN_DEFINED * f64::from(w.corridor_steps))
            .then(|| w.gap_cv / f64::from(w.gap_cv_steps)),
            Quantity::TouchingPercent => w
                .is_corridor()
                .then(|| 100.0 * f64::from(w.touching_steps) / f64::from(w.corridor_steps)),
            Quantity::EnergyMj => Some(w.energy_per_robot_mj / steps),
        }
    }
}

/// One window's metrics for one condition.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WindowStats {
    /// First step of the window.
    pub from_step: u32,
    /// One past its last step.
    pub to_step: u32,
    /// Mean D over the window's steps and the robots, du.
    pub mean_d: Estimate,
    /// Collisions per robot over the window (the paper's count).
    pub collisions_per_robot: Estimate,
    /// Collisions per net metre.
    pub collisions_per_net_m: Estimate,
    /// Collisions per metre of path the robots moved (a reference).
    pub collisions_per_m: Estimate,
    /// Collisions per moving robot-step (a reference).
    pub collisions_per_moving_step: Estimate,
    /// Time a robot spent with a bumper pressed, percent.
    pub contact_percent: Estimate,
    /// Robot-steps held in place, percent.
    pub held_percent: Estimate,
    /// Robot-steps shuttling, percent.
    pub shuttling_percent: Estimate,
    /// Robot-steps circling, percent.
    pub circling_percent: Estimate,
    /// Robot-steps exploring, percent.
    pub exploring_percent: Estimate,
    /// Robot-steps in which the robot moved at least 5 mm, percent (a reference).
    pub moving_percent: Estimate,
    /// Distance a robot's centre moved per step (path), mm.
    pub moved_mm: Estimate,
    /// Net progress: net displacement over the lag per step, mm.
    pub net_mm: Estimate,
    /// Net progress over path.
    pub straightness: Estimate,
    /// Mean squared displacement over 1 step, cm².
    pub msd_1_cm2: Estimate,
    /// Mean squared displacement over 10 steps, cm².
    pub msd_10_cm2: Estimate,
    /// Mean squared displacement over 100 steps, cm².
    pub msd_100_cm2: Estimate,
    /// log₁₀(MSD₁₀₀ / MSD₁₀): 2 straight driving, 1 diffusion, 0 confinement.
    pub msd_exponent: Estimate,
    /// Fresh cells a robot enters per 100 steps.
    pub fresh_cells_per_100_steps: Estimate,
    /// New cells per robot over the window.
    pub new_cells: Estimate,
    /// Corridor: mean gap CV over the window's steps in which no neighbours touch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap_cv: Option<Estimate>,
    /// Corridor: steps in which neighbours touch, percent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub touching_percent: Option<Estimate>,
    /// Mean energy a robot drew from its pack per step over the window, mJ at the pack's
    /// nominal 12 V ([`crate::energy`]).
    pub energy_per_robot_step_mj: Estimate,
}

/// Each run's value of `q` over the window `win` picks, in repeat order.
pub(super) fn per_repeat(
    runs: &[&RunOutput],
    q: Quantity,
    robots: usize,
    win: fn(&RunOutput) -> &WindowSums,
) -> Vec<Option<f64>> {
    // A run in which a robot died (`--keep-going`) has no value: its dead robots would count
    // as robots that neither collide nor get stuck.
    runs.iter()
        .map(|r| {
            if r.dead.is_empty() {
                q.of(win(r), robots)
            } else {
                None
            }
        })
        .collect()
}

/// Window statistics over runs of one condition (in repeat order), from each run's sums over
/// the window `win` picks, steps `from..to`.
#[must_use]
pub fn window(
    runs: &[&RunOutput],
    robots: usize,
    (from, to): (u32, u32),
    win: fn(&RunOutput) -> &WindowSums,
    seed: u64,
) -> WindowStats {
    use Quantity as Q;
    let est = |q: Quantity| Estimate::of_defined(&per_repeat(runs, q, robots, win), seed);
    let corridor = runs.iter().all(|r| win(r).is_corridor());
    WindowStats {
        from_step: from,
        to_step: to,
        mean_d: est(Q::MeanD),
        collisions_per_robot: est(Q::CollisionsPerRobot),
        collisions_per_net_m: est(Q::CollisionsPerNetM),
        collisions_per_m: est(Q::CollisionsPerM),
        collisions_per_moving_step: est(Q::CollisionsPerMovingStep),
        contact_percent: est(Q::ContactPercent),
        held_percent: est(Q::HeldPercent),
        shuttling_percent: est(Q::ShuttlingPercent),
        circling_percent: est(Q::CirclingPercent),
        exploring_percent: est(Q::ExploringPercent),
        moving_percent: est(Q::MovingPercent),
        moved_mm: est(Q::MovedMm),
        net_mm: est(Q::NetMm),
        straightness: est(Q::Straightness),
        msd_1_cm2: est(Q::Msd(0)),
        msd_10_cm2: est(Q::Msd(1)),
        msd_100_cm2: est(Q::Msd(2)),
        msd_exponent: est(Q::MsdExponent),
        fresh_cells_per_100_steps: est(Q::FreshCells),
        new_cells: est(Q::NewCells),
        gap_cv: corridor.then(|| est(Q::GapCv)),
        touching_percent: corridor.then(|| est(Q::TouchingPercent)),
        energy_per_robot_step_mj: est(Q::EnergyMj),
    }
}

/// The robots of one condition over all its repeats: how many end the run held, when their
/// first lasting held spell began, how far they went.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RobotStats {
    /// Robots over all repeats.
    pub robots: u32,
    /// Of them, those held at the run's last step.
    pub ending_held: u32,
    /// The share of a repeat's robots that end it held, percent.
    pub ending_held_percent: Estimate,
    /// Robots that had a lasting held spell (held for at least a window, or to the end).
    pub with_lasting_held_spell: u32,
    /// The median onset step of the first lasting held spell over the robots that had one.
    pub first_lasting_held_step_median: Option<f64>,
    /// Distance (path) a robot moved over the whole run, metres.
    pub distance_m: Estimate,
    /// Net metres a robot made over the whole run.
    pub net_m: Estimate,
    /// Distinct cells a robot was in over the whole run.
    pub cells_visited: Estimate,
}

pub(super) fn robot_stats(runs: &[&RunOutput], seed: u64) -> RobotStats {
    let all = runs.iter().flat_map(|r| &r.robots);
    let robots = all.clone().count() as u32;
    let ending_held = all.clone().filter(|t| t.ends_held).count() as u32;
    let mut onsets: Vec<f64> = all
        .clone()
        .filter_map(|t| t.first_lasting_held_step.map(f64::from))
        .collect();
    onsets.sort_by(f64::total_cmp);
    let median = match onsets.len() {
        0 => None,
        k if k % 2 == 1 => Some(onsets[k / 2]),
        k => Some(0.5 * (onsets[k / 2 - 1] + onsets[k / 2])),
    };
    let mean_of = |f: &dyn Fn(&crate::motion::RobotTally) -> f64| -> Vec<f64> {
        runs.iter()
            .map(|r| {
                let n = r.robots.len().max(1) as f64;
                r.robots.iter().map(f).sum::<f64>() / n
            })
            .collect()
    };
    let share = mean_of(&|t| if t.ends_held { 100.0 } else { 0.0 });
    RobotStats {
        robots,
        ending_held,
        ending_held_percent: Estimate::of(&share, seed),
        with_lasting_held_spell: onsets.len() as u32,
        first_lasting_held_step_median: median,
        distance_m: Estimate::of(&mean_of(&|t| t.distance_m), seed),
        net_m: Estimate::of(&mean_of(&|t| t.net_m), seed),
        cells_visited: Estimate::of(&mean_of(&|t| f64::from(t.cells_visited)), seed),
    }
}

/// First and last window of a condition, and its robots.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConditionStats {
    /// The condition.
    pub condition: Condition,
    /// The first window.
    pub first: WindowStats,
    /// The last window.
    pub last: WindowStats,
    /// The robots over the whole run.
    pub robots: RobotStats,
}

/// Robot by robot, learning against another condition (same placement, same robot index, same
/// initial weights for learning off): which robots end the run held under each.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Pairing {
    /// The other condition.
    pub other: Condition,
    /// Robot pairs compared (robots × repeats present in both).
    pub robots: u32,
    /// Held at the end under the other condition, not with learning: learning frees them.
    pub frees: u32,
    /// Held at the end with learning, not under the other condition: learning traps them.
    pub traps: u32,
    /// Held at the end under both.
    pub both_held: u32,
    /// Held under neither.
    pub neither: u32,
    /// McNemar's exact two-sided p-value on `frees` against `traps`.
    pub p: f64,
}

pub(super) fn pairing(
    learning: &[&RunOutput],
    other: &[&RunOutput],
    c: Condition,
) -> Option<Pairing> {
    if learning.is_empty() || other.is_empty() {
        return None;
    }
    let mut p = Pairing {
        other: c,
        robots: 0,
        frees: 0,
        traps: 0,
        both_held: 0,
        neither: 0,
        p: 1.0,
    };
    for l in learning {
        let Some(o) = other.iter().find(|o| o.repeat == l.repeat) else {
            continue;
        };
        let dead = |r: &RunOutput, i: usize| r.dead.iter().any(|d| d.robot == i);
        for (i, (a, b)) in l.robots.iter().zip(&o.robots).enumerate() {
            // A robot dead in either run is compared with nothing.
            if dead(l, i) || dead(o, i) {
                continue;
            }
            p.robots += 1;
            match (a.ends_held, b.ends_held) {
                (true, true) => p.both_held += 1,
                (false, false) => p.neither += 1,
                (false, true) => p.frees += 1,
                (true, false) => p.traps += 1,
            }
        }
    }
    p.p = mcnemar_p(p.frees, p.traps);
    Some(p)
}

/// The runs of condition `c`, in repeat order.
pub(super) fn runs_of(runs: &[RunOutput], c: Condition) -> Vec<&RunOutput> {
    let mut v: Vec<&RunOutput> = runs.iter().filter(|r| r.condition == c).collect();
    v.sort_by_key(|r| r.repeat);
    v
}

pub(super) fn first_window(r: &RunOutput) -> &WindowSums {
    r.metrics.first()
}

pub(super) fn last_window(r: &RunOutput) -> &WindowSums {
    &r.metrics.last
}
