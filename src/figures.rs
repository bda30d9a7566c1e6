//! The figures' data, built from the runs: the learning curves ([`LearningFigure`]), the
//! arena's paths ([`ArenaFigure`]) and the corridor's space-time figure ([`SpaceTimeFigure`]).
//! [`crate::plot`] draws them.

use crate::plot::{ArenaFigure, LearningFigure, Panel, Series, SpaceTimeFigure};
use crate::report::plural;
use swarm::experiment::RunOutput;
use swarm::robot::Condition;
use swarm::scenario::Scenario;
use swarm::summary::{Estimate, Quantity};

/// Every figure of a run: the learning curves, and the tracked robots' figure (the corridor's
/// space-time figure, or the arena's paths) when the learning run's first repeat was tracked.
pub struct Figures {
    /// The learning curves.
    pub learning: LearningFigure,
    /// The tracked robots' figure.
    pub track: Option<TrackFigure>,
}

/// The tracked robots' figure.
pub enum TrackFigure {
    /// The corridor's: the robots along it over the run.
    SpaceTime(SpaceTimeFigure),
    /// The arena's: the first and last steps' paths.
    Arena(Vec<ArenaFigure>),
}

/// The figures of `runs`.
#[must_use]
pub fn of(s: &Scenario, runs: &[RunOutput]) -> Figures {
    let track = runs.iter().find_map(|r| r.track.as_ref()).map(|track| {
        if s.arena == swarm::scenario::ArenaKind::Corridor {
            TrackFigure::SpaceTime(spacetime(s, track))
        } else {
            TrackFigure::Arena(arena(s, track))
        }
    });
    Figures {
        learning: learning(s, runs),
        track,
    }
}

/// The learning figure: per condition, mean D and collisions per robot per window (the
/// paper's two panels), then collisions per net metre, net progress, collisions per path metre
/// (a reference), the area covered, contact time, exploring robot-steps and, in the corridor,
/// the gap CV and the steps with neighbours touching; the held robot-steps drawn dotted beside
/// every collision curve. Each curve is the mean over repeats with its 95 % band (the mean
/// alone with one repeat); a window in which no repeat has a value (collisions per net metre of
/// robots that went nowhere) has no point, and one in which only some have a value is drawn
/// as an open circle with their number beside it, without a band.
fn learning(s: &Scenario, runs: &[RunOutput]) -> LearningFigure {
    let win = s.window.max(1);
    let windows = runs
        .iter()
        .map(|r| r.metrics.whole_windows().len())
        .min()
        .unwrap_or(0);
    let seed = swarm::seeds::bootstrap_seed(s.seed);
    let panel = |q: Quantity| -> Vec<Series> {
        let mut out = Vec::new();
        for c in Condition::ALL {
            let mut of_c: Vec<&RunOutput> = runs.iter().filter(|r| r.condition == c).collect();
            if of_c.is_empty() {
                continue;
            }
            of_c.sort_by_key(|r| r.repeat);
            let (mut xs, mut m, mut lo, mut hi, mut n) = (vec![], vec![], vec![], vec![], vec![]);
            for w in 0..windows {
                let vals: Vec<Option<f64>> = of_c
                    .iter()
                    .map(|r| q.of(&r.metrics.windows[w], s.robots))
                    .collect();
                let e = Estimate::of_defined(&vals, seed);
                if e.n == 0 {
                    continue;
                }
                xs.push(f64::from(w as u32 * win + win / 2));
                m.push(e.mean);
                lo.push(e.lo.unwrap_or(e.mean));
                hi.push(e.hi.unwrap_or(e.mean));
                n.push(e.n);
            }
            if xs.is_empty() {
                continue;
            }
            out.push(Series {
                label: match c {
                    Condition::Learning => "learning".to_string(),
                    Condition::LearningOff => "learning off (η = 0)".to_string(),
                    Condition::RandomWalk => "random walk".to_string(),
                },
                dashed: c != Condition::Learning,
                x: xs,
                mean: m,
                lo,
                hi,
                n,
                repeats: of_c.len(),
            });
        }
        out
    };
    let mut more = Vec::new();
    let mut add = |caption: &str, y_label: &str, q: Quantity, held_overlay: bool| {
        let series = panel(q);
        if !series.is_empty() {
            more.push(Panel {
                caption: caption.to_string(),
                y_label: y_label.to_string(),
                series,
                held_overlay,
            });
        }
    };
    add(
        "Collisions per net metre (shuttling and standing earn nothing)",
        "collisions per net metre",
        Quantity::CollisionsPerNetM,
        true,
    );
    add(
        "Net progress (net displacement over 20 steps, per step)",
        "mm per step",
        Quantity::NetMm,
        false,
    );
    add(
        "Collisions per path metre (a reference: shuttling adds path)",
        "collisions per metre of path",
        Quantity::CollisionsPerM,
        true,
    );
    add(
        "Area covered (cells of 0.2 m not visited for 100 steps)",
        "fresh cells per 100 steps",
        Quantity::FreshCells,
        false,
    );
    add(
        "Contact time (a bumper pressed)",
        "% of robot time",
        Quantity::ContactPercent,
        false,
    );
    add(
        "Robot-steps exploring (net at least 0.2 of the path)",
        "% of robot-steps",
        Quantity::ExploringPercent,
        false,
    );
    if runs.iter().all(|r| r.metrics.whole.is_corridor()) {
        add(
            "Gap CV between neighbours (steps none touch; even: low)",
            "coefficient of variation",
            Quantity::GapCv,
            false,
        );
        add(
            "Steps with neighbours touching (closer than 1 cm)",
            "% of steps",
            Quantity::TouchingPercent,
            false,
        );
    }
    LearningFigure {
        title: format!(
            "h8swarm {}: {} robots, {}, windows of {} steps ({} s per step){}",
            s.name,
            s.robots,
            plural(s.repeats, "repeat"),
            s.window,
            s.timing.step_period_s,
            if windows < 3 {
                format!(": only {windows} windows, no trend")
            } else {
                String::new()
            }
        ),
        x_label: "learning step".to_string(),
        d: panel(Quantity::MeanD),
        collisions: panel(Quantity::CollisionsPerRobot),
        more,
        held: panel(Quantity::HeldPercent),
        markers: windows < 3,
    }
}

/// The corridor's space-time figure: each tracked robot's position along the corridor over
/// the run (learning, repeat 0).
fn spacetime(s: &Scenario, t: &swarm::experiment::Track) -> SpaceTimeFigure {
    let length_m = t
        .walls
        .iter()
        .flat_map(|w| [w[0].0, w[1].0])
        .fold(0.0, f64::max);
    SpaceTimeFigure {
        title: format!(
            "{}: the robots along the corridor (learning, repeat 0, seed {}); bands = bodies, white = gaps",
            s.name, s.seed
        ),
        length_m,
        body_m: world::params::BODY_LENGTH_M,
        paths: t.spacetime.clone(),
    }
}

/// The arena figure as the paper's Fig. 8 shows learning: the first and the last
/// [`swarm::experiment::SNAPSHOT_STEPS`] steps' paths in two panels, with the outlines at the
/// start and the end of each.
fn arena(s: &Scenario, t: &swarm::experiment::Track) -> Vec<ArenaFigure> {
    let k = swarm::experiment::SNAPSHOT_STEPS.min(s.steps as usize);
    let n = s.steps as usize;
    let first_of = |from: usize, to: usize| -> ArenaFigure {
        let paths = if from == 0 { &t.early } else { &t.late }.clone();
        let t0 = from as f64 * s.timing.step_period_s;
        let t1 = to as f64 * s.timing.step_period_s;
        let outlines = t
            .outlines
            .iter()
            .filter(|o| o.time_s >= t0 - 1.0 && o.time_s <= t1 + 1.0)
            .cloned()
            .collect();
        ArenaFigure {
            title: format!(
                "learning, repeat 0, seed {}: {} {} steps ({:.0}-{:.0} s), {} robots{}",
                s.seed,
                if from == 0 { "first" } else { "last" },
                to - from,
                t0,
                t1,
                s.robots,
                if t.early.len() < s.robots {
                    format!(", paths of the first {}", t.early.len())
                } else {
                    String::new()
                }
            ),
            walls: t.walls.clone(),
            paths,
            outlines,
        }
    };
    vec![first_of(0, k), first_of(n - k, n)]
}
