//! The battery life of a run's conditions: how long the paper's pack lasts at each condition's
//! energy per step in its first and last windows, what learning costs or saves against the
//! controls, and each condition's mean current by part (from the charge meter of
//! [`crate::energy`] and the window statistics of [`crate::summary`]).

use serde::Serialize;

use crate::energy::{Charge, CurrentCap, PAPER_BATTERY_LIFE_H, Pack, Part, mean_current_ma};
use crate::experiment::RunOutput;
use crate::robot::Condition;
use crate::summary::{ConditionStats, Estimate};

/// The battery life of one condition of a run: its first and last windows.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BatteryLine {
    /// The condition.
    pub condition: Condition,
    /// A robot's mean current over the first window, mA (over the repeats).
    pub first_current_ma: f64,
    /// Over the last window, mA.
    pub last_current_ma: f64,
    /// Hours the pack lasts at the first window's mean energy per step (the interval from the
    /// energy's).
    pub first_h: Estimate,
    /// At the last window's.
    pub last_h: Estimate,
}

/// What learning costs or saves in battery life against a control, in the last window.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BatteryComparison {
    /// The control.
    pub against: Condition,
    /// Learning's battery life less the control's, hours.
    pub change_h: f64,
    /// The same in percent of the control's.
    pub change_percent: f64,
    /// Whether the two energies' 95 % intervals are apart.
    pub apart: bool,
}

/// The battery life of a run's conditions for the paper's pack.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BatteryReport {
    /// The pack.
    pub pack: Pack,
    /// The paper's figure: "up to 3.5 hours".
    pub paper_h: f64,
    /// Per condition.
    pub conditions: Vec<BatteryLine>,
    /// Learning against each control present.
    pub learning_against: Vec<BatteryComparison>,
    /// A robot's mean current by part over each condition's whole runs, mA.
    pub by_part: Vec<ConditionParts>,
}

/// A robot's mean current by part over a condition's whole runs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConditionParts {
    /// The condition.
    pub condition: Condition,
    /// ([`Part::key`], mA) in [`Part::ALL`]'s order.
    pub current_ma: Vec<(&'static str, f64)>,
    /// How often the drive voltage's bound cut a motor's current over the runs.
    pub motor_cap: CurrentCap,
}

impl ConditionParts {
    /// The mean current by part of `runs` (one condition's), each `robot_seconds` long
    /// (robots × steps × step period).
    #[must_use]
    pub fn of(condition: Condition, runs: &[&RunOutput], robot_seconds: f64) -> Self {
        let mut total = Charge::default();
        let mut motor_cap = CurrentCap::default();
        for r in runs {
            total.add(&r.energy);
            motor_cap.add(r.motor_cap);
        }
        let seconds = robot_seconds * runs.len() as f64;
        ConditionParts {
            condition,
            current_ma: Part::ALL
                .iter()
                .map(|&p| (p.key(), mean_current_ma(total.of(p), seconds)))
                .collect(),
            motor_cap,
        }
    }
}

impl BatteryReport {
    /// The battery life of each condition of `stats` for `pack`, steps of `step_period_s`.
    #[must_use]
    pub fn of(stats: &[ConditionStats], pack: Pack, step_period_s: f64) -> Self {
        use Estimate;
        // mJ per step → mA: mJ / V = mC, per second = mA.
        let ma = |mj: f64| mj / pack.volts() / step_period_s;
        let life = |e: &Estimate| -> Estimate {
            let h = |mj: f64| (mj > 0.0).then(|| pack.life_h(ma(mj)));
            Estimate {
                mean: h(e.mean).unwrap_or(f64::INFINITY),
                lo: e.hi.and_then(h),
                hi: e.lo.and_then(h),
                n: e.n,
            }
        };
        let conditions: Vec<BatteryLine> = stats
            .iter()
            .map(|c| BatteryLine {
                condition: c.condition,
                first_current_ma: ma(c.first.energy_per_robot_step_mj.mean),
                last_current_ma: ma(c.last.energy_per_robot_step_mj.mean),
                first_h: life(&c.first.energy_per_robot_step_mj),
                last_h: life(&c.last.energy_per_robot_step_mj),
            })
            .collect();
        let learning = stats.iter().find(|c| c.condition == Condition::Learning);
        let learning_against = match learning {
            None => Vec::new(),
            Some(l) => stats
                .iter()
                .filter(|c| c.condition != Condition::Learning)
                .map(|c| {
                    let (hl, hc) = (
                        life(&l.last.energy_per_robot_step_mj).mean,
                        life(&c.last.energy_per_robot_step_mj).mean,
                    );
                    BatteryComparison {
                        against: c.condition,
                        change_h: hl - hc,
                        change_percent: (hl / hc - 1.0) * 100.0,
                        apart: l
                            .last
                            .energy_per_robot_step_mj
                            .apart_from(&c.last.energy_per_robot_step_mj),
                    }
                })
                .collect(),
        };
        BatteryReport {
            pack,
            paper_h: PAPER_BATTERY_LIFE_H,
            conditions,
            learning_against,
            by_part: Vec::new(),
        }
    }
}
