//! Windows, means over repeats with 95 % intervals, and the paper's claims checked against them.

use serde::Serialize;

use crate::experiment::RunOutput;
use crate::robot::Condition;

/// Two-sided 95 % quantiles of Student's t for 1 … 30 degrees of freedom (the standard table,
/// e.g. NIST/SEMATECH e-Handbook of Statistical Methods, Table 1.3.6.7.2); beyond 30 the normal
/// 1.960 is used.
const T_975: [f64; 30] = [
    12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
    2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
    2.052, 2.048, 2.045, 2.042,
];

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
        let t = T_975.get(n - 2).copied().unwrap_or(1.960);
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
    /// Corridor: mean gap CV over the window.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap_cv: Option<Estimate>,
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

/// A claim of the paper checked against the numbers.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Claim {
    /// What is claimed.
    pub claim: String,
    /// Whether the means go the claimed way.
    pub holds: bool,
    /// Whether the 95 % intervals separate as well.
    pub clear: bool,
    /// The two values compared (means).
    pub values: [f64; 2],
}

/// Window statistics of the runs of one condition over steps `from..to`.
#[must_use]
pub fn window(runs: &[&RunOutput], from: u32, to: u32) -> WindowStats {
    let per_run = |f: &dyn Fn(&crate::experiment::StepMetrics) -> f64, mean: bool| -> Vec<f64> {
        runs.iter()
            .map(|r| {
                let s = &r.steps[from as usize..to as usize];
                let total: f64 = s.iter().map(f).sum();
                if mean { total / s.len() as f64 } else { total }
            })
            .collect()
    };
    let gap = runs
        .iter()
        .all(|r| {
            r.steps[from as usize..to as usize]
                .iter()
                .all(|m| m.gap_cv.is_some())
        })
        .then(|| Estimate::of(&per_run(&|m| m.gap_cv.unwrap_or(0.0), true)));
    WindowStats {
        from_step: from,
        to_step: to,
        mean_d: Estimate::of(&per_run(&|m| m.mean_d, true)),
        collisions_per_robot: Estimate::of(&per_run(&|m| m.collisions_per_robot, false)),
        moved_m: Estimate::of(&per_run(&|m| m.moved_m, true)),
        gap_cv: gap,
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
        out.push(ConditionStats {
            condition: c,
            first: window(&of_c, 0, win),
            last: window(&of_c, steps - win, steps),
        });
    }
    out
}

/// The paper's claims (SPEC §5 and issue 5): collisions in the last window below the first and
/// below the learning-off control's last; mean D higher at the end; in the corridor the gap CV
/// falling.
#[must_use]
pub fn claims(stats: &[ConditionStats]) -> Vec<Claim> {
    let find = |c: Condition| stats.iter().find(|s| s.condition == c);
    let mut out = Vec::new();
    let Some(learn) = find(Condition::Learning) else {
        return out;
    };
    let below = |claim: &str, a: &Estimate, b: &Estimate| Claim {
        claim: claim.to_string(),
        holds: a.mean < b.mean,
        clear: a.clearly_below(b),
        values: [a.mean, b.mean],
    };
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
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_use_students_t() {
        let e = Estimate::of(&[1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(e.mean, 3.0);
        // s = sqrt(2.5), t(4) = 2.776: half width 2.776 · sqrt(2.5 / 5) = 1.963.
        let half = e.hi.unwrap() - 3.0;
        assert!((half - 2.776 * 0.5f64.sqrt()).abs() < 1e-12);
        assert_eq!(Estimate::of(&[7.0]).lo, None);
        assert!(Estimate::of(&[1.0, 1.01]).clearly_below(&Estimate::of(&[2.0, 2.01])));
        // Two repeats leave t = 12.706: these overlap.
        assert!(!Estimate::of(&[1.0, 1.1]).clearly_below(&Estimate::of(&[2.0, 2.1])));
    }
}
