//! Windows, means over repeats with 95 % intervals, and the paper's claims checked against them.

use serde::Serialize;
use statrs::distribution::{ContinuousCDF, StudentsT};

use crate::experiment::{RunOutput, WindowSums};
use crate::robot::Condition;

/// The two-sided 95 % quantile of Student's t with `dof` degrees of freedom (its 97.5 %
/// point), exact for any `dof` ≥ 1 (statrs' inverse CDF), so intervals do not jump at 30
/// degrees of freedom as a printed table's normal 1.960 does.
#[must_use]
pub fn t_975(dof: usize) -> f64 {
    StudentsT::new(0.0, 1.0, dof.max(1) as f64)
        .map(|t| t.inverse_cdf(0.975))
        .unwrap_or(f64::NAN)
}

/// Mean over repeats with its 95 % interval (Student's t; none with a single repeat).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Estimate {
    /// Mean over the repeats.
    pub mean: f64,
    /// Lower end of the 95 % interval.
    pub lo: Option<f64>,
    /// Upper end of the 95 % interval.
    pub hi: Option<f64>,
    /// Number of repeats.
    pub n: usize,
}

impl Estimate {
    /// The estimate of a sample.
    #[must_use]
    pub fn of(values: &[f64]) -> Estimate {
        let n = values.len();
        let mean = if n == 0 {
            f64::NAN
        } else {
            values.iter().sum::<f64>() / n as f64
        };
        if n < 2 {
            return Estimate {
                mean,
                lo: None,
                hi: None,
                n,
            };
        }
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let t = t_975(n - 1);
        let half = t * (var / n as f64).sqrt();
        Estimate {
            mean,
            lo: Some(mean - half),
            hi: Some(mean + half),
            n,
        }
    }

    /// Whether this interval lies wholly below `other`'s.
    #[must_use]
    pub fn clearly_below(&self, other: &Estimate) -> bool {
        matches!((self.hi, other.lo), (Some(h), Some(l)) if h < l)
    }

    /// Whether the two intervals do not overlap (either way round).
    #[must_use]
    pub fn apart_from(&self, other: &Estimate) -> bool {
        self.clearly_below(other) || other.clearly_below(self)
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
    /// Collisions per robot over the window.
    pub collisions_per_robot: Estimate,
    /// Mean distance a robot's centre moved per step over the window, metres.
    pub moved_m: Estimate,
    /// Fraction of the window's time a robot spent with a bumper pressed (contact time).
    pub contact_fraction: Estimate,
    /// Fraction of the window's robot-steps that were stuck (moved < 1 mm over the last 100
    /// steps while driving).
    pub stuck_fraction: Estimate,
    /// Corridor: mean gap CV over the window.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap_cv: Option<Estimate>,
    /// Mean energy a robot drew from its pack per step over the window, mJ at the pack's
    /// nominal 12 V ([`crate::energy`]).
    pub energy_per_robot_step_mj: Estimate,
}

/// First and last window of a condition.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConditionStats {
    /// The condition.
    pub condition: Condition,
    /// The first window.
    pub first: WindowStats,
    /// The last window.
    pub last: WindowStats,
}

/// A claim of the paper checked against the numbers: "a below b".
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Claim {
    /// What is claimed.
    pub claim: String,
    /// Whether the means go the claimed way.
    pub holds: bool,
    /// Whether the two 95 % intervals are apart (do not overlap), whichever way.
    pub apart: bool,
    /// In words: "holds, intervals apart", "holds in the means, intervals overlap", "fails:
    /// the opposite, intervals overlap" or "fails: the opposite, intervals apart".
    pub verdict: String,
    /// The two values compared (means), in the claim's order.
    pub values: [f64; 2],
    /// Their 95 % intervals (none with a single repeat).
    pub intervals: [[Option<f64>; 2]; 2],
}

impl Claim {
    /// The claim "`a` below `b`" checked.
    #[must_use]
    pub fn below(claim: &str, a: &Estimate, b: &Estimate) -> Claim {
        let holds = a.mean < b.mean;
        let apart = a.apart_from(b);
        let verdict = match (holds, apart) {
            (true, true) => "holds, intervals apart",
            (true, false) => "holds in the means, intervals overlap",
            (false, false) => "fails: the opposite in the means, intervals overlap",
            (false, true) => "fails: the opposite, intervals apart",
        };
        Claim {
            claim: claim.to_string(),
            holds,
            apart,
            verdict: verdict.to_string(),
            values: [a.mean, b.mean],
            intervals: [[a.lo, a.hi], [b.lo, b.hi]],
        }
    }
}

/// Window statistics over runs of one condition, from each run's sums over the same window of
/// steps `from..to`.
#[must_use]
pub fn window(sums: &[&WindowSums], from: u32, to: u32) -> WindowStats {
    let per_run = |f: &dyn Fn(&WindowSums) -> f64, mean: bool| -> Vec<f64> {
        sums.iter()
            .map(|w| {
                let total = f(w);
                if mean {
                    total / f64::from(w.steps)
                } else {
                    total
                }
            })
            .collect()
    };
    let gap = sums
        .iter()
        .all(|w| w.all_have_gap_cv())
        .then(|| Estimate::of(&per_run(&|w| w.gap_cv, true)));
    WindowStats {
        from_step: from,
        to_step: to,
        mean_d: Estimate::of(&per_run(&|w| w.mean_d, true)),
        collisions_per_robot: Estimate::of(&per_run(&|w| w.collisions_per_robot, false)),
        moved_m: Estimate::of(&per_run(&|w| w.moved_m, true)),
        contact_fraction: Estimate::of(&per_run(&|w| w.contact_fraction, true)),
        stuck_fraction: Estimate::of(&per_run(&|w| w.stuck_fraction, true)),
        gap_cv: gap,
        energy_per_robot_step_mj: Estimate::of(&per_run(&|w| w.energy_per_robot_mj, true)),
    }
}

/// First and last window of every condition present in `runs`, in condition order.
#[must_use]
pub fn conditions(runs: &[RunOutput], steps: u32, win: u32) -> Vec<ConditionStats> {
    let mut out = Vec::new();
    for c in Condition::ALL {
        let of_c: Vec<&RunOutput> = runs.iter().filter(|r| r.condition == c).collect();
        if of_c.is_empty() {
            continue;
        }
        let first: Vec<&WindowSums> = of_c.iter().map(|r| r.metrics.first()).collect();
        let last: Vec<&WindowSums> = of_c.iter().map(|r| &r.metrics.last).collect();
        out.push(ConditionStats {
            condition: c,
            first: window(&first, 0, win),
            last: window(&last, steps - win, steps),
        });
    }
    out
}

/// The paper's claims (SPEC §5 and issue 5): collisions in the last window below the first and
/// below the controls' last; the same for contact time (which no sub-step length can fake);
/// mean D higher at the end and above learning off's; in the corridor the gap CV falling and
/// below learning off's.
#[must_use]
pub fn claims(stats: &[ConditionStats]) -> Vec<Claim> {
    let find = |c: Condition| stats.iter().find(|s| s.condition == c);
    let mut out = Vec::new();
    let Some(learn) = find(Condition::Learning) else {
        return out;
    };
    let below = Claim::below;
    out.push(below(
        "collisions per robot: last window below the first (learning)",
        &learn.last.collisions_per_robot,
        &learn.first.collisions_per_robot,
    ));
    if let Some(off) = find(Condition::LearningOff) {
        out.push(below(
            "collisions per robot in the last window: learning below learning off",
            &learn.last.collisions_per_robot,
            &off.last.collisions_per_robot,
        ));
    }
    if let Some(walk) = find(Condition::RandomWalk) {
        out.push(below(
            "collisions per robot in the last window: learning below the random walk",
            &learn.last.collisions_per_robot,
            &walk.last.collisions_per_robot,
        ));
    }
    out.push(below(
        "contact time: last window below the first (learning)",
        &learn.last.contact_fraction,
        &learn.first.contact_fraction,
    ));
    if let Some(off) = find(Condition::LearningOff) {
        out.push(below(
            "contact time in the last window: learning below learning off",
            &learn.last.contact_fraction,
            &off.last.contact_fraction,
        ));
    }
    if let Some(walk) = find(Condition::RandomWalk) {
        out.push(below(
            "contact time in the last window: learning below the random walk",
            &learn.last.contact_fraction,
            &walk.last.contact_fraction,
        ));
    }
    out.push(below(
        "mean D: first window below the last (learning: the robots keep farther from obstacles)",
        &learn.first.mean_d,
        &learn.last.mean_d,
    ));
    if let Some(off) = find(Condition::LearningOff) {
        out.push(below(
            "mean D in the last window: learning off below learning",
            &off.last.mean_d,
            &learn.last.mean_d,
        ));
    }
    if let (Some(first), Some(last)) = (&learn.first.gap_cv, &learn.last.gap_cv) {
        out.push(below(
            "corridor gap CV: last window below the first (the robots space themselves evenly)",
            last,
            first,
        ));
        if let Some(off_cv) = find(Condition::LearningOff).and_then(|o| o.last.gap_cv.as_ref()) {
            out.push(below(
                "corridor gap CV in the last window: learning below learning off",
                last,
                off_cv,
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_quantiles_are_exact_past_thirty_degrees_of_freedom() {
        // Reference values (NIST/SEMATECH e-Handbook, Table 1.3.6.7.2).
        for (dof, t) in [
            (1, 12.706),
            (4, 2.776),
            (19, 2.093),
            (30, 2.042),
            (40, 2.021),
            (100, 1.984),
        ] {
            assert!((t_975(dof) - t).abs() < 5e-4, "{dof}: {}", t_975(dof));
        }
        // No jump to 1.960 past 30: monotone towards it.
        assert!(t_975(31) < t_975(30) && t_975(31) > t_975(32) && t_975(1000) > 1.96);
    }

    #[test]
    fn claims_say_which_way_they_fail() {
        let lo = Estimate::of(&[1.0, 1.1, 0.9]);
        let hi = Estimate::of(&[5.0, 5.1, 4.9]);
        let c = Claim::below("x", &hi, &lo);
        assert!(!c.holds && c.apart);
        assert_eq!(c.verdict, "fails: the opposite, intervals apart");
        let c = Claim::below("x", &lo, &hi);
        assert_eq!(c.verdict, "holds, intervals apart");
        let wide = Estimate::of(&[0.0, 10.0, 3.0]);
        assert_eq!(
            Claim::below("x", &lo, &wide).verdict,
            "holds in the means, intervals overlap"
        );
    }

    #[test]
    fn intervals_use_students_t() {
        let e = Estimate::of(&[1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(e.mean, 3.0);
        // s = sqrt(2.5), t(4) = 2.776: half width 2.776 · sqrt(2.5 / 5) = 1.963.
        let half = e.hi.unwrap() - 3.0;
        assert!((half - t_975(4) * 0.5f64.sqrt()).abs() < 1e-12);
        assert!((t_975(4) - 2.776).abs() < 5e-4);
        assert_eq!(Estimate::of(&[7.0]).lo, None);
        assert!(Estimate::of(&[1.0, 1.01]).clearly_below(&Estimate::of(&[2.0, 2.01])));
        // Two repeats leave t = 12.706: these overlap.
        assert!(!Estimate::of(&[1.0, 1.1]).clearly_below(&Estimate::of(&[2.0, 2.1])));
    }
}
