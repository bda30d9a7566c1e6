//! The analysis of an experiment's runs: the window statistics, the pairings and the claims.

use super::claims::{Claim, claims};
use super::quantities::{
    ConditionStats, Pairing, first_window, last_window, pairing, robot_stats, runs_of, window,
};
use crate::experiment::RunOutput;
use crate::robot::Condition;
use serde::Serialize;

/// Everything the summary says about a set of runs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Analysis {
    /// Per condition, in condition order.
    pub conditions: Vec<ConditionStats>,
    /// Learning against each control, robot by robot.
    pub pairings: Vec<Pairing>,
    /// The claims.
    pub claims: Vec<Claim>,
}

/// Analyses runs of `robots` robots and `steps` steps in windows of `win` steps; `seed` seeds
/// the bootstrap.
#[must_use]
pub fn analyse(runs: &[RunOutput], robots: usize, steps: u32, win: u32, seed: u64) -> Analysis {
    let mut conditions = Vec::new();
    for c in Condition::ALL {
        let of_c = runs_of(runs, c);
        if of_c.is_empty() {
            continue;
        }
        conditions.push(ConditionStats {
            condition: c,
            first: window(&of_c, robots, (0, win), first_window, seed),
            last: window(&of_c, robots, (steps - win, steps), last_window, seed),
            robots: robot_stats(&of_c, seed),
        });
    }
    let learning = runs_of(runs, Condition::Learning);
    let pairings = [Condition::LearningOff, Condition::RandomWalk]
        .into_iter()
        .filter_map(|c| pairing(&learning, &runs_of(runs, c), c))
        .collect();
    Analysis {
        conditions,
        pairings,
        claims: claims(runs, robots, seed),
    }
}
