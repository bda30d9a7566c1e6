//! Windows, estimates over repeats with 95 % intervals that stay in range, paired tests, and
//! the paper's claims checked against them (the reasoning is in `docs/claims.md`).
//!
//! * **Units**, one per quantity everywhere (screen, `metrics.csv`, `summary.json`, figures):
//!   D in du; collisions as counts per robot, per net metre, per path metre and per moving
//!   robot-step; contact time and the motion classes' shares in percent; path and net progress
//!   in mm per step; mean squared displacement in cm²; cells per 100 steps and per robot.
//! * **Intervals**: the mean over repeats with the *expanded percentile bootstrap* interval
//!   ([`Estimate::of`]): seeded resamples of the repeats, their means' percentiles at a tail
//!   widened for small samples. Such an interval never leaves the range of the repeats'
//!   values, so a share stays in 0–100 %, a count at or above 0.
//! * **Paired comparisons**: learning, learning off and the random walk of one repeat share
//!   the placement (and learning and learning off the initial weights), so every claim compares
//!   them repeat by repeat with an exact one-sided sign test ([`Paired`]); a claim of parts
//!   counts a repeat for it only when every part goes its way ([`Side::all`]); robot by robot,
//!   which robots end the run held under each condition is compared with McNemar's exact test
//!   ([`Pairing`]).
//! * **Claims** are judged on quantities a robot held in place, shuttling or circling cannot
//!   satisfy ([`crate::motion`]): the held share, net progress against the random walk's, and
//!   collisions per net metre; collisions per path metre and the raw collision count are kept
//!   as references.
//! * **Power**: every claim says how many repeats a decision would need at the effect it shows
//!   ([`Power`], [`repeats_needed`]).

pub mod analysis;
pub mod claims;
pub mod quantities;
pub mod stats;
#[cfg(test)]
mod tests;

pub use analysis::{Analysis, analyse};
pub use claims::{
    Claim, GAPS_MAX_TOUCHING_PERCENT, KEEP_EXPLORING_FRACTION, KEEP_EXPLORING_MAX_HELD_PERCENT,
    Outcome, claims, keep_exploring_text,
};
pub use quantities::{
    ConditionStats, GAP_CV_MIN_DEFINED, MIN_MOVED_M, MIN_MOVING_ROBOT_STEPS, Pairing, Quantity,
    RobotStats, WindowStats, window,
};
pub use stats::{
    BOOTSTRAP_RESAMPLES, Estimate, MAX_REPEATS_NEEDED, POWER, Paired, Power, SIGNIFICANCE, Side,
    expanded_tail, fmt_p, mcnemar_p, repeats_needed, sides, sign_test_p, t_975,
};
