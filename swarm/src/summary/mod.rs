//! Windows, estimates over repeats with 95 % intervals that stay in range, paired tests, and
//! the paper's claims checked against them (the reasoning is in `docs/claims.md`).
//!
//! Its parts: [`stats`] (estimates, their intervals, the paired tests, the power),
//! [`quantities`] (the quantities per window and their statistics per condition), [`mod@claims`]
//! (the paper's claims judged on them) and [`analysis`] (all of it from an experiment's runs).

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
