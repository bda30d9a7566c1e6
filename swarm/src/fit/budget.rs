//! The largest network within a CPU budget ([`largest_fitting`]).

use super::config::{FitConfig, FitError};
use super::measure::measure;
use super::report::FitReport;
use robot_board::model::ControllerError;
use serde::Serialize;

/// Which CPU share a budget limits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Budget {
    /// The mean share over the steps (the CPU load, saves amortised).
    Mean,
    /// The share of the worst step (a step with a save: the step must still end well inside
    /// its period).
    WorstStep,
}

/// The largest network (inputs N, by spare inputs on top of `base`'s layout) that fits the RAM
/// and keeps the `budget` CPU share within `cpu_budget_percent` of the step period, measured by
/// running each candidate (without the other controller beside); None when even `base` does
/// not. The search is a bisection over N up to the learner's bound (256 inputs), each probe a
/// full [`measure`].
///
/// # Errors
/// [`FitError`] for an impossible base configuration.
pub fn largest_fitting(
    base: &FitConfig,
    cpu_budget_percent: f64,
    budget: Budget,
) -> Result<Option<FitReport>, FitError> {
    let fits = |spare: usize| -> Result<Option<FitReport>, FitError> {
        let mut cfg = base.clone();
        cfg.compare = false;
        cfg.controller.layout = base.controller.layout.with_spare(spare as u16);
        let share = |r: &FitReport| match budget {
            Budget::Mean => r.cpu_mean_percent,
            Budget::WorstStep => r.cpu_worst_percent,
        };
        match measure(&cfg) {
            Ok(r) if r.fits && share(&r) <= cpu_budget_percent => Ok(Some(r)),
            Ok(_)
            | Err(FitError::Controller(ControllerError::Ram(_) | ControllerError::Shape(_)))
            | Err(FitError::Rejected { .. }) => Ok(None),
            Err(e) => Err(e),
        }
    };
    let base_n = base.controller.n_inputs();
    let Some(mut best) = fits(0)? else {
        return Ok(None);
    };
    let (mut lo, mut hi) = (0usize, nn_q15::MAX_INPUTS.saturating_sub(base_n));
    if let Some(r) = fits(hi)? {
        return Ok(Some(r));
    }
    // Invariant: lo fits, hi does not.
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        match fits(mid)? {
            Some(r) => {
                lo = mid;
                best = r;
            }
            None => hi = mid,
        }
    }
    Ok(Some(best))
}
