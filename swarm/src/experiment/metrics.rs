//! The metrics of a run: one row per step (metrics.csv), sums per window and the whole run's
//! ([`RunMetrics`]), and the motion classes' counts.
//!
//! Memory: a run keeps no per-step history. Each step's metrics, complete one step later (its
//! behaviour's collisions are known when the next step begins), go as a row to the run's own
//! CSV file, when it has one ([`super::Swarm::set_rows`]), and into sums per window
//! ([`RunMetrics`]); the arena figure's paths are kept for the first and the last
//! [`super::SNAPSHOT_STEPS`] steps only. A run of 10⁶ steps needs the memory of one of 10³ steps
//! beside its window sums (one [`WindowSums`] per window).

use crate::motion::{MotionClass, MotionStep};
use crate::robot::Condition;

/// Corridor: neighbours closer than this touch, metres (in contact, or a push away); the gap
/// CV is undefined at a step in which any two do (the spacing of a jam means nothing).
pub const GAP_TOUCH_M: f64 = 0.01;

/// The metrics of one step of one run (docs/design.md §5).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepMetrics {
    /// Mean over robots of D(t), du.
    pub mean_d: f64,
    /// Collisions per robot during this step's behaviour.
    pub collisions_per_robot: f64,
    /// Mean over robots of the share of this step's behaviour spent with a bumper pressed
    /// (time in contact, weighted by sub-step length), percent.
    pub contact_percent: f64,
    /// Share of the robots held in place at the end of this step's behaviour, percent (see
    /// [`crate::motion`]).
    pub held_percent: f64,
    /// Share of the robots shuttling, percent.
    pub shuttling_percent: f64,
    /// Share of the robots circling, percent.
    pub circling_percent: f64,
    /// Share of the robots exploring, percent.
    pub exploring_percent: f64,
    /// Share of the robots that moved at least [`crate::collisions::MOVING_MIN_MM`] during
    /// this step's behaviour, percent (a reference: shuttlers move every step).
    pub moving_percent: f64,
    /// Mean over robots of how far the body's centre moved during this step's behaviour
    /// (straight-line distance between the two step instants), millimetres: 0 for a robot held
    /// against a wall or another body, about 67 mm for a free one driving straight in the
    /// arena. Not in the paper; it tells a robot that avoids obstacles from one that is stuck
    /// (both make no new collisions).
    pub moved_mm: f64,
    /// Mean over robots of the net displacement over the last [`crate::motion::LAG_STEPS`]
    /// steps per step ([`MotionStep::net_m`]), millimetres per step: the net progress.
    pub net_mm: f64,
    /// Mean over robots of the squared displacement over each of [`crate::motion::MSD_LAGS`] steps, cm², once
    /// the run is that long: the mean squared displacement.
    pub msd_cm2: [Option<f64>; 3],
    /// Mean over robots of the cells entered in the step that the robot had not been in for
    /// [`crate::motion::FRESH_STEPS`] steps.
    pub fresh_cells: f64,
    /// Mean over robots of the cells entered in the step that the robot had never been in.
    pub new_cells: f64,
    /// Corridor only: coefficient of variation of the gaps between neighbours at the step;
    /// none while two of them touch ([`GAP_TOUCH_M`]).
    pub gap_cv: Option<f64>,
    /// Corridor only: whether two neighbours touch at the step.
    pub touching: Option<bool>,
    /// Mean over robots of their MCU's CPU load over this step's period (percent): busy
    /// states (the step, the tick interrupts, the main loop; not the time asleep) over the
    /// period's states, as the robots' own clocks count them.
    pub cpu_load_percent: f64,
    /// Mean over robots of the energy each drew from its battery pack over this step
    /// (millijoules at the pack's nominal 12 V): the electronics over the step and the motors
    /// and bridges over its behaviour ([`crate::energy`]).
    pub energy_per_robot_mj: f64,
}

/// Sums of a run's per-step metrics over a span of steps: the summary's and the figure's
/// window values are these divided by the steps (means) or as they are (totals). The sums run
/// in step order, so they equal the sums of the same steps' metrics taken afterwards.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WindowSums {
    /// Steps summed.
    pub steps: u32,
    /// Sum of [`StepMetrics::mean_d`].
    pub mean_d: f64,
    /// Sum of [`StepMetrics::collisions_per_robot`].
    pub collisions_per_robot: f64,
    /// Sum of [`StepMetrics::contact_percent`].
    pub contact_percent: f64,
    /// Sum of [`StepMetrics::held_percent`].
    pub held_percent: f64,
    /// Sum of [`StepMetrics::shuttling_percent`].
    pub shuttling_percent: f64,
    /// Sum of [`StepMetrics::circling_percent`].
    pub circling_percent: f64,
    /// Sum of [`StepMetrics::exploring_percent`].
    pub exploring_percent: f64,
    /// Sum of [`StepMetrics::moving_percent`].
    pub moving_percent: f64,
    /// Sum of [`StepMetrics::moved_mm`].
    pub moved_mm: f64,
    /// Sum of [`StepMetrics::net_mm`].
    pub net_mm: f64,
    /// Sums of [`StepMetrics::msd_cm2`] over the steps that have them.
    pub msd_cm2: [f64; 3],
    /// Steps that have each of them.
    pub msd_steps: [u32; 3],
    /// Sum of [`StepMetrics::fresh_cells`].
    pub fresh_cells: f64,
    /// Sum of [`StepMetrics::new_cells`].
    pub new_cells: f64,
    /// Sum of [`StepMetrics::gap_cv`] over the steps that have one.
    pub gap_cv: f64,
    /// Steps that have a gap CV (in the corridor, those in which no neighbours touch).
    pub gap_cv_steps: u32,
    /// Corridor steps (none in the square).
    pub corridor_steps: u32,
    /// Corridor steps in which two neighbours touch.
    pub touching_steps: u32,
    /// Sum of [`StepMetrics::cpu_load_percent`].
    pub cpu_load_percent: f64,
    /// Sum of [`StepMetrics::energy_per_robot_mj`].
    pub energy_per_robot_mj: f64,
}

impl WindowSums {
    /// Adds one step's metrics.
    pub fn add(&mut self, m: &StepMetrics) {
        self.steps += 1;
        self.mean_d += m.mean_d;
        self.collisions_per_robot += m.collisions_per_robot;
        self.contact_percent += m.contact_percent;
        self.held_percent += m.held_percent;
        self.shuttling_percent += m.shuttling_percent;
        self.circling_percent += m.circling_percent;
        self.exploring_percent += m.exploring_percent;
        self.moving_percent += m.moving_percent;
        self.moved_mm += m.moved_mm;
        self.net_mm += m.net_mm;
        for (l, v) in m.msd_cm2.iter().enumerate() {
            if let Some(v) = v {
                self.msd_cm2[l] += v;
                self.msd_steps[l] += 1;
            }
        }
        self.fresh_cells += m.fresh_cells;
        self.new_cells += m.new_cells;
        if let Some(g) = m.gap_cv {
            self.gap_cv += g;
            self.gap_cv_steps += 1;
        }
        if let Some(t) = m.touching {
            self.corridor_steps += 1;
            self.touching_steps += u32::from(t);
        }
        self.cpu_load_percent += m.cpu_load_percent;
        self.energy_per_robot_mj += m.energy_per_robot_mj;
    }

    /// Whether the steps summed are a corridor's (they have a gap metric, defined or not).
    #[must_use]
    pub fn is_corridor(&self) -> bool {
        self.corridor_steps > 0
    }
}

/// What a run keeps of its per-step metrics: sums over windows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunMetrics {
    /// The window length, steps.
    pub window: u32,
    /// The run's planned steps.
    pub planned_steps: u32,
    /// One sum per window of `window` steps from step 0 (the last one partial when `window`
    /// does not divide the run); the learning figure's points are the whole ones, the summary's
    /// first window is the first.
    pub windows: Vec<WindowSums>,
    /// The summary's last window: steps `planned_steps - window..planned_steps`.
    pub last: WindowSums,
    /// Every step of the run.
    pub whole: WindowSums,
}

impl RunMetrics {
    /// Empty sums for a run of `planned_steps` steps in windows of `window` (at least 1).
    #[must_use]
    pub fn new(planned_steps: u32, window: u32) -> Self {
        Self {
            window: window.max(1),
            planned_steps,
            ..Self::default()
        }
    }

    /// Adds step `k`'s metrics (steps come in order, from 0).
    pub fn add(&mut self, k: u32, m: &StepMetrics) {
        let w = (k / self.window) as usize;
        if k.is_multiple_of(self.window) && w == self.windows.len() {
            self.windows.push(WindowSums::default());
        }
        if let Some(sums) = self.windows.get_mut(w) {
            sums.add(m);
        }
        if k < self.planned_steps && k >= self.planned_steps.saturating_sub(self.window) {
            self.last.add(m);
        }
        self.whole.add(m);
    }

    /// The summary's first window, steps `0..window` (empty before the first step).
    #[must_use]
    pub fn first(&self) -> &WindowSums {
        const NONE: WindowSums = WindowSums {
            steps: 0,
            mean_d: 0.0,
            collisions_per_robot: 0.0,
            contact_percent: 0.0,
            held_percent: 0.0,
            shuttling_percent: 0.0,
            circling_percent: 0.0,
            exploring_percent: 0.0,
            moving_percent: 0.0,
            moved_mm: 0.0,
            net_mm: 0.0,
            msd_cm2: [0.0; 3],
            msd_steps: [0; 3],
            fresh_cells: 0.0,
            new_cells: 0.0,
            gap_cv: 0.0,
            gap_cv_steps: 0,
            corridor_steps: 0,
            touching_steps: 0,
            cpu_load_percent: 0.0,
            energy_per_robot_mj: 0.0,
        };
        self.windows.first().unwrap_or(&NONE)
    }

    /// The whole windows (a trailing partial window left out).
    #[must_use]
    pub fn whole_windows(&self) -> &[WindowSums] {
        let whole = self
            .windows
            .iter()
            .take_while(|w| w.steps == self.window)
            .count();
        &self.windows[..whole]
    }
}

/// The columns of `metrics.csv`, one row per step of every run (the MSD columns' lags are
/// [`crate::motion::MSD_LAGS`]).
pub const METRICS_HEADER: [&str; 23] = [
    "condition",
    "repeat",
    "step",
    "mean_d",
    "collisions_per_robot",
    "contact_percent",
    "held_percent",
    "shuttling_percent",
    "circling_percent",
    "exploring_percent",
    "moving_percent",
    "moved_mm",
    "net_mm",
    "msd_1_cm2",
    "msd_10_cm2",
    "msd_100_cm2",
    "fresh_cells",
    "new_cells",
    "gap_cv",
    "robots_touching",
    "cpu_load_percent",
    "energy_per_robot_mj",
    "dead_robots",
];

/// Step `k`'s row of `metrics.csv` (see [`METRICS_HEADER`]) written into `buf` (cleared
/// first), field after field; `dead` robots had died by its end (`--keep-going`). Returns where
/// each field ends. A run writes its rows this way,
/// through one buffer, rather than a string per field.
pub fn metrics_fields(
    condition: Condition,
    repeat: u32,
    k: u32,
    m: &StepMetrics,
    dead: usize,
    buf: &mut String,
) -> [usize; 23] {
    use std::fmt::Write as _;
    buf.clear();
    let mut ends = [0usize; 23];
    let mut field = 0;
    let mut end = |buf: &String| {
        ends[field] = buf.len();
        field += 1;
    };
    buf.push_str(condition.name());
    end(buf);
    let _ = write!(buf, "{repeat}");
    end(buf);
    let _ = write!(buf, "{k}");
    end(buf);
    let opt = |buf: &mut String, v: Option<f64>| {
        if let Some(v) = v {
            let _ = write!(buf, "{v}");
        }
    };
    for v in [
        m.mean_d,
        m.collisions_per_robot,
        m.contact_percent,
        m.held_percent,
        m.shuttling_percent,
        m.circling_percent,
        m.exploring_percent,
        m.moving_percent,
        m.moved_mm,
        m.net_mm,
    ] {
        let _ = write!(buf, "{v}");
        end(buf);
    }
    for v in m.msd_cm2 {
        opt(buf, v);
        end(buf);
    }
    for v in [m.fresh_cells, m.new_cells] {
        let _ = write!(buf, "{v}");
        end(buf);
    }
    opt(buf, m.gap_cv);
    end(buf);
    if let Some(t) = m.touching {
        buf.push(if t { '1' } else { '0' });
    }
    end(buf);
    for v in [m.cpu_load_percent, m.energy_per_robot_mj] {
        let _ = write!(buf, "{v}");
        end(buf);
    }
    let _ = write!(buf, "{dead}");
    end(buf);
    ends
}

/// Step `k`'s row of `metrics.csv` (see [`METRICS_HEADER`]); `dead` robots had died by its
/// end (`--keep-going`).
#[must_use]
pub fn metrics_row(
    condition: Condition,
    repeat: u32,
    k: u32,
    m: &StepMetrics,
    dead: usize,
) -> [String; 23] {
    let mut buf = String::new();
    let ends = metrics_fields(condition, repeat, k, m, dead, &mut buf);
    std::array::from_fn(|i| buf[if i == 0 { 0 } else { ends[i - 1] }..ends[i]].to_string())
}

/// A run's rows of `metrics.csv`, written as the steps complete.
pub(super) struct Rows {
    pub(super) path: std::path::PathBuf,
    pub(super) w: csv::Writer<std::io::BufWriter<std::fs::File>>,
    /// The row being written, field after field.
    pub(super) buf: String,
}

/// Fills the motion part of a step's metrics from every robot's step as its tracker saw it:
/// the class shares, the moving share, the path and net progress, the mean squared
/// displacements (once every robot has one) and the cells.
pub fn motion_metrics(m: &mut StepMetrics, steps: &[MotionStep]) {
    let n = steps.len().max(1) as f64;
    let mut classes = [0u32; 4];
    let (mut step_m, mut net_m, mut moving) = (0.0, 0.0, 0u32);
    let (mut msd, mut msd_robots) = ([0.0; 3], [0usize; 3]);
    let (mut fresh, mut new) = (0u32, 0u32);
    for s in steps {
        step_m += s.step_m;
        net_m += s.net_m;
        classes[s.class.code() as usize] += 1;
        moving += u32::from(s.step_m * 1000.0 >= crate::collisions::MOVING_MIN_MM);
        for (l, v) in s.sq_disp_m2.iter().enumerate() {
            if let Some(v) = v {
                msd[l] += v;
                msd_robots[l] += 1;
            }
        }
        fresh += s.fresh_cells;
        new += s.new_cells;
    }
    let share = |c: MotionClass| 100.0 * f64::from(classes[c.code() as usize]) / n;
    m.held_percent = share(MotionClass::Held);
    m.shuttling_percent = share(MotionClass::Shuttling);
    m.circling_percent = share(MotionClass::Circling);
    m.exploring_percent = share(MotionClass::Exploring);
    m.moving_percent = 100.0 * f64::from(moving) / n;
    m.moved_mm = 1000.0 * step_m / n;
    m.net_mm = 1000.0 * net_m / n;
    m.msd_cm2 = std::array::from_fn(|l| {
        (!steps.is_empty() && msd_robots[l] == steps.len()).then(|| 1e4 * msd[l] / n)
    });
    m.fresh_cells = f64::from(fresh) / n;
    m.new_cells = f64::from(new) / n;
}
