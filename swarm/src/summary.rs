//! Windows, estimates over repeats with 95 % intervals that stay in range, paired tests, and
//! the paper's claims checked against them (the reasoning is in `docs/claims.md`).
//!
//! * **Units**, one per quantity everywhere (screen, `metrics.csv`, `summary.json`, figures):
//!   D in du; collisions as counts per robot, per metre moved and per moving robot-step;
//!   contact time, stuck and moving robot-steps in percent; distance moved per step in mm.
//! * **Intervals**: the mean over repeats with the *expanded percentile bootstrap* interval
//!   ([`Estimate::of`]): seeded resamples of the repeats, their means' percentiles at a tail
//!   widened for small samples. Such an interval never leaves the range of the repeats'
//!   values, so a share stays in 0–100 %, a count at or above 0.
//! * **Paired comparisons**: learning, learning off and the random walk of one repeat share
//!   the placement (and learning and learning off the initial weights), so every claim compares
//!   them repeat by repeat with an exact one-sided sign test ([`Paired`]); robot by robot, which
//!   robots end the run stuck under each condition is compared with McNemar's exact test
//!   ([`Pairing`]).
//! * **Claims** are judged on quantities a stopped robot cannot satisfy: collisions per metre
//!   moved (a robot that stands still adds neither collisions nor metres) and the share of
//!   stuck robot-steps; the raw collision count is kept as a reference line.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, Normal, StudentsT};

use crate::experiment::{RunOutput, WindowSums};
use crate::robot::Condition;

/// Resamples of every bootstrap interval.
pub const BOOTSTRAP_RESAMPLES: usize = 10_000;
/// The level of every test: a claim holds when its one-sided p-value is below it.
pub const SIGNIFICANCE: f64 = 0.05;
/// "The robots keep moving": at most this share of the last window's robot-steps stuck,
/// percent (the reasoning is in `docs/claims.md`).
pub const KEEP_MOVING_MAX_STUCK_PERCENT: f64 = 10.0;
/// Collisions per metre are defined for a window only when its robots moved at least this far
/// between them, metres: below that a rate per metre is noise, and a swarm that stood still
/// would otherwise earn a perfect score.
pub const MIN_MOVED_M: f64 = 1.0;
/// Collisions per moving robot-step are defined only over at least this many moving
/// robot-steps.
pub const MIN_MOVING_ROBOT_STEPS: f64 = 20.0;

/// The two-sided 95 % quantile of Student's t with `dof` degrees of freedom (its 97.5 %
/// point), exact for any `dof` ≥ 1 (statrs' inverse CDF).
#[must_use]
pub fn t_975(dof: usize) -> f64 {
    StudentsT::new(0.0, 1.0, dof.max(1) as f64)
        .map(|t| t.inverse_cdf(0.975))
        .unwrap_or(f64::NAN)
}

/// The tail probability each end of the expanded percentile interval takes for a sample of
/// `n` ≥ 2: Φ(−√(n/(n−1)) · t₀.₉₇₅,ₙ₋₁) (Hesterberg, "What Teachers Should Know About the
/// Bootstrap", The American Statistician 69(4), 2015, §5: the percentile interval widened to
/// the t interval's width and for the bootstrap's narrowness with few observations). 0.0010
/// for 5 repeats, 0.0085 for 10, 0.025 in the limit.
#[must_use]
pub fn expanded_tail(n: usize) -> f64 {
    let z = (n as f64 / (n.max(2) - 1) as f64).sqrt() * t_975(n.max(2) - 1);
    Normal::new(0.0, 1.0).map_or(f64::NAN, |d| d.cdf(-z))
}

/// Mean over repeats with its 95 % interval (none with a single repeat).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Estimate {
    /// Mean over the repeats.
    pub mean: f64,
    /// Lower end of the 95 % interval.
    pub lo: Option<f64>,
    /// Upper end of the 95 % interval.
    pub hi: Option<f64>,
    /// Number of repeats with a value.
    pub n: usize,
}

impl Estimate {
    /// The mean of `values` and its expanded percentile bootstrap interval: the means of
    /// [`BOOTSTRAP_RESAMPLES`] resamples (with replacement, drawn from `seed`) sorted, and the
    /// ones at [`expanded_tail`] from either end. The interval lies within the values' own
    /// range (a resample's mean cannot leave it; the ends are clamped to it against rounding).
    #[must_use]
    pub fn of(values: &[f64], seed: u64) -> Estimate {
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
        let (min, max) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if min == max {
            return Estimate {
                mean,
                lo: Some(min),
                hi: Some(max),
                n,
            };
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut means: Vec<f64> = (0..BOOTSTRAP_RESAMPLES)
            .map(|_| (0..n).map(|_| values[rng.random_range(0..n)]).sum::<f64>() / n as f64)
            .collect();
        means.sort_by(f64::total_cmp);
        let k = ((expanded_tail(n) * BOOTSTRAP_RESAMPLES as f64).floor() as usize)
            .min(BOOTSTRAP_RESAMPLES / 2 - 1);
        Estimate {
            mean,
            lo: Some(means[k].clamp(min, max)),
            hi: Some(means[BOOTSTRAP_RESAMPLES - 1 - k].clamp(min, max)),
            n,
        }
    }

    /// [`Estimate::of`] the values that are defined.
    #[must_use]
    pub fn of_defined(values: &[Option<f64>], seed: u64) -> Estimate {
        let v: Vec<f64> = values.iter().flatten().copied().collect();
        Self::of(&v, seed)
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

    /// The estimate scaled by `k` (a change of unit).
    #[must_use]
    pub fn scaled(&self, k: f64) -> Estimate {
        Estimate {
            mean: self.mean * k,
            lo: self.lo.map(|v| v * k),
            hi: self.hi.map(|v| v * k),
            n: self.n,
        }
    }
}

/// P(X ≥ k) for X ~ Binomial(n, ½): the one-sided p-value of an exact sign test that saw `k`
/// of `n` untied pairs go the claimed way.
#[must_use]
pub fn sign_test_p(k: u32, n: u32) -> f64 {
    if k == 0 {
        return 1.0;
    }
    if k > n {
        return 0.0;
    }
    // ln C(n, j) − n ln 2 from libm's log-gamma and exponential (pure Rust: the same bits on
    // every platform, docs/limits-and-failures.md).
    let ln_gamma = |x: f64| libm::lgamma_r(x).0;
    let ln_n_fact = ln_gamma(f64::from(n) + 1.0);
    let ln_half_n = f64::from(n) * std::f64::consts::LN_2;
    let p: f64 = (k..=n)
        .map(|j| {
            let ln_c = ln_n_fact - ln_gamma(f64::from(j) + 1.0) - ln_gamma(f64::from(n - j) + 1.0);
            libm::exp(ln_c - ln_half_n)
        })
        .sum();
    p.min(1.0)
}

/// McNemar's exact test on the discordant pairs `b` and `c` (two-sided): 2 · P(X ≤ min(b, c))
/// for X ~ Binomial(b + c, ½), at most 1.
#[must_use]
pub fn mcnemar_p(b: u32, c: u32) -> f64 {
    let n = b + c;
    if n == 0 {
        return 1.0;
    }
    // P(X ≤ m) = P(X ≥ n − m) by symmetry.
    (2.0 * sign_test_p(n - b.min(c), n)).min(1.0)
}

/// A paired comparison repeat by repeat: how many repeats go the claimed way (a below b), the
/// other way, tie, or lack a value on either side, with the exact sign test's one-sided
/// p-values (ties and missing values dropped).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Paired {
    /// Repeats with a below b.
    #[serde(rename = "for")]
    pub for_: u32,
    /// Repeats with a above b.
    pub against: u32,
    /// Repeats with a equal to b.
    pub tied: u32,
    /// Repeats where a or b has no value (collisions per metre of robots that did not move).
    pub undefined: u32,
    /// One-sided p-value for "a below b".
    pub p: f64,
    /// One-sided p-value for "a above b".
    pub p_opposite: f64,
}

impl Paired {
    /// Pairs `a[r]` with `b[r]`.
    #[must_use]
    pub fn of(a: &[Option<f64>], b: &[Option<f64>]) -> Paired {
        let (mut for_, mut against, mut tied, mut undefined) = (0, 0, 0, 0);
        for r in 0..a.len().max(b.len()) {
            match (a.get(r).copied().flatten(), b.get(r).copied().flatten()) {
                (Some(x), Some(y)) if x < y => for_ += 1,
                (Some(x), Some(y)) if x > y => against += 1,
                (Some(_), Some(_)) => tied += 1,
                _ => undefined += 1,
            }
        }
        Paired {
            for_,
            against,
            tied,
            undefined,
            p: sign_test_p(for_, for_ + against),
            p_opposite: sign_test_p(against, for_ + against),
        }
    }

    /// Repeats with a value on both sides.
    #[must_use]
    pub fn defined(&self) -> u32 {
        self.for_ + self.against + self.tied
    }
}

/// How a claim came out, from the repeat-by-repeat comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Outcome {
    /// The sign test says so (one-sided p below [`SIGNIFICANCE`]).
    Holds,
    /// More repeats go the claimed way than the other, but not enough to say so.
    Unsure,
    /// As many repeats go each way, or more go the other way.
    Fails,
    /// No repeat has a value on both sides.
    Undecided,
}

impl Outcome {
    /// The word the tables print.
    #[must_use]
    pub const fn word(self) -> &'static str {
        match self {
            Outcome::Holds => "HOLDS",
            Outcome::Unsure => "UNSURE",
            Outcome::Fails => "FAILS",
            Outcome::Undecided => "UNDECIDED",
        }
    }
}

/// A claim checked against the numbers: "a below b", paired by repeat.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Claim {
    /// What is claimed.
    pub claim: String,
    /// Whether it is one of the paper's own text claims (the others compare with the controls
    /// the paper lacks, or are kept for reference).
    pub paper: bool,
    /// The quantity compared (its name in the window statistics).
    pub quantity: String,
    /// The values' unit.
    pub unit: String,
    /// How it came out.
    pub outcome: Outcome,
    /// Whether the means go the claimed way (strictly): a description; the outcome follows
    /// the repeats.
    pub means_agree: bool,
    /// Whether the two 95 % intervals are apart (do not overlap), whichever way.
    pub apart: bool,
    /// In words, with the repeats and the p-value.
    pub verdict: String,
    /// The two values compared (means over the repeats that have one), in the claim's order.
    pub values: [f64; 2],
    /// Their 95 % intervals (none with a single repeat).
    pub intervals: [[Option<f64>; 2]; 2],
    /// The repeat-by-repeat comparison.
    pub repeats: Paired,
}

impl Claim {
    /// The claim "`a` below `b`", each given per repeat (the same repeat at the same index).
    #[must_use]
    pub fn paired(
        claim: &str,
        paper: bool,
        quantity: Quantity,
        a: &[Option<f64>],
        b: &[Option<f64>],
        seed: u64,
    ) -> Claim {
        let (ea, eb) = (Estimate::of_defined(a, seed), Estimate::of_defined(b, seed));
        let r = Paired::of(a, b);
        let n = r.defined();
        // "k of n repeats go" / "1 of 1 repeat goes".
        let (of_n, go) = if n == 1 {
            ("of 1 repeat".to_string(), "goes")
        } else {
            (format!("of {n} repeats"), "go")
        };
        let (outcome, mut verdict) = if n == 0 {
            (
                Outcome::Undecided,
                "undecided: no repeat has a value on both sides".to_string(),
            )
        } else if r.p < SIGNIFICANCE {
            (
                Outcome::Holds,
                format!("holds: {} {of_n}, sign test p = {}", r.for_, fmt_p(r.p)),
            )
        } else if r.p_opposite < SIGNIFICANCE {
            (
                Outcome::Fails,
                format!(
                    "fails: the opposite, {} {of_n}, sign test p = {}",
                    r.against,
                    fmt_p(r.p_opposite)
                ),
            )
        } else if r.for_ > r.against {
            (
                Outcome::Unsure,
                format!(
                    "unsure: {} {of_n} {go} this way, {} the other (sign test p = {})",
                    r.for_,
                    r.against,
                    fmt_p(r.p)
                ),
            )
        } else if r.for_ == r.against {
            (
                Outcome::Fails,
                format!(
                    "fails: as many repeats go each way ({} and {}, {} tied)",
                    r.for_, r.against, r.tied
                ),
            )
        } else {
            (
                Outcome::Fails,
                format!(
                    "fails: {} {of_n} {go} the other way, {} this way (sign test p = {})",
                    r.against,
                    r.for_,
                    fmt_p(r.p_opposite)
                ),
            )
        };
        if r.undefined > 0 {
            let s = if r.undefined == 1 { "" } else { "s" };
            verdict.push_str(&format!("; {} repeat{s} without a value", r.undefined));
        }
        let repeats = r;
        Claim {
            claim: claim.to_string(),
            paper,
            quantity: quantity.name().to_string(),
            unit: quantity.unit().to_string(),
            outcome,
            means_agree: ea.mean < eb.mean,
            apart: ea.apart_from(&eb),
            verdict,
            values: [ea.mean, eb.mean],
            intervals: [[ea.lo, ea.hi], [eb.lo, eb.hi]],
            repeats,
        }
    }
}

/// A p-value with three significant digits (`< 0.001` below that).
#[must_use]
pub fn fmt_p(p: f64) -> String {
    if p < 0.001 {
        "< 0.001".to_string()
    } else {
        format!("{p:.3}")
    }
}

/// A quantity of a window, computed from one run's sums over it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// Mean summed sensor distance D, du.
    MeanD,
    /// Collisions per robot over the window.
    CollisionsPerRobot,
    /// Collisions per metre the robots moved (none below [`MIN_MOVED_M`]).
    CollisionsPerM,
    /// Collisions per moving robot-step (none below [`MIN_MOVING_ROBOT_STEPS`]).
    CollisionsPerMovingStep,
    /// Time with a bumper pressed, percent.
    ContactPercent,
    /// Stuck robot-steps, percent.
    StuckPercent,
    /// Moving robot-steps, percent.
    MovingPercent,
    /// Distance a robot moved per step, mm.
    MovedMm,
    /// The corridor's gap CV (none in the square arena).
    GapCv,
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
            Quantity::CollisionsPerM => "collisions_per_m",
            Quantity::CollisionsPerMovingStep => "collisions_per_moving_step",
            Quantity::ContactPercent => "contact_percent",
            Quantity::StuckPercent => "stuck_percent",
            Quantity::MovingPercent => "moving_percent",
            Quantity::MovedMm => "moved_mm",
            Quantity::GapCv => "gap_cv",
            Quantity::EnergyMj => "energy_per_robot_step_mj",
        }
    }

    /// Its unit, short.
    #[must_use]
    pub const fn unit(self) -> &'static str {
        match self {
            Quantity::MeanD => "du",
            Quantity::CollisionsPerRobot => "per robot",
            Quantity::CollisionsPerM => "per m",
            Quantity::CollisionsPerMovingStep => "per moving robot-step",
            Quantity::ContactPercent | Quantity::StuckPercent | Quantity::MovingPercent => "%",
            Quantity::MovedMm => "mm",
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
        match self {
            Quantity::MeanD => Some(w.mean_d / steps),
            Quantity::CollisionsPerRobot => Some(w.collisions_per_robot),
            Quantity::CollisionsPerM => {
                let moved_m = w.moved_mm / 1000.0 * robots;
                (moved_m >= MIN_MOVED_M).then(|| w.collisions_per_robot * robots / moved_m)
            }
            Quantity::CollisionsPerMovingStep => {
                let moving = w.moving_percent / 100.0 * robots;
                (moving >= MIN_MOVING_ROBOT_STEPS).then(|| w.collisions_per_robot * robots / moving)
            }
            Quantity::ContactPercent => Some(w.contact_percent / steps),
            Quantity::StuckPercent => Some(w.stuck_percent / steps),
            Quantity::MovingPercent => Some(w.moving_percent / steps),
            Quantity::MovedMm => Some(w.moved_mm / steps),
            Quantity::GapCv => w.all_have_gap_cv().then(|| w.gap_cv / steps),
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
    /// Collisions per metre the robots moved.
    pub collisions_per_m: Estimate,
    /// Collisions per moving robot-step.
    pub collisions_per_moving_step: Estimate,
    /// Time a robot spent with a bumper pressed, percent.
    pub contact_percent: Estimate,
    /// Robot-steps that were stuck (moved < 1 mm over the last 100 steps while driving),
    /// percent.
    pub stuck_percent: Estimate,
    /// Robot-steps in which the robot moved at least 5 mm, percent.
    pub moving_percent: Estimate,
    /// Distance a robot's centre moved per step, mm.
    pub moved_mm: Estimate,
    /// Corridor: mean gap CV over the window.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap_cv: Option<Estimate>,
    /// Mean energy a robot drew from its pack per step over the window, mJ at the pack's
    /// nominal 12 V ([`crate::energy`]).
    pub energy_per_robot_step_mj: Estimate,
}

/// Each run's value of `q` over the window `win` picks, in repeat order.
fn per_repeat(
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
    let est = |q: Quantity| Estimate::of_defined(&per_repeat(runs, q, robots, win), seed);
    let gap = runs
        .iter()
        .all(|r| win(r).all_have_gap_cv())
        .then(|| est(Quantity::GapCv));
    WindowStats {
        from_step: from,
        to_step: to,
        mean_d: est(Quantity::MeanD),
        collisions_per_robot: est(Quantity::CollisionsPerRobot),
        collisions_per_m: est(Quantity::CollisionsPerM),
        collisions_per_moving_step: est(Quantity::CollisionsPerMovingStep),
        contact_percent: est(Quantity::ContactPercent),
        stuck_percent: est(Quantity::StuckPercent),
        moving_percent: est(Quantity::MovingPercent),
        moved_mm: est(Quantity::MovedMm),
        gap_cv: gap,
        energy_per_robot_step_mj: est(Quantity::EnergyMj),
    }
}

/// The robots of one condition over all its repeats: how many end the run stuck, when their
/// first lasting stuck spell began, how far they went.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RobotStats {
    /// Robots over all repeats.
    pub robots: u32,
    /// Of them, those stuck at the run's last step.
    pub ending_stuck: u32,
    /// The share of a repeat's robots that end it stuck, percent.
    pub ending_stuck_percent: Estimate,
    /// Robots that had a lasting stuck spell (stuck for at least a window, or to the end).
    pub with_lasting_spell: u32,
    /// The median onset step of the first lasting spell over the robots that had one.
    pub first_lasting_stuck_step_median: Option<f64>,
    /// Distance a robot moved over the whole run, metres.
    pub distance_m: Estimate,
}

fn robot_stats(runs: &[&RunOutput], seed: u64) -> RobotStats {
    let all = runs.iter().flat_map(|r| &r.robots);
    let robots = all.clone().count() as u32;
    let ending_stuck = all.clone().filter(|t| t.ends_stuck).count() as u32;
    let mut onsets: Vec<f64> = all
        .clone()
        .filter_map(|t| t.first_lasting_stuck_step.map(f64::from))
        .collect();
    onsets.sort_by(f64::total_cmp);
    let median = match onsets.len() {
        0 => None,
        k if k % 2 == 1 => Some(onsets[k / 2]),
        k => Some(0.5 * (onsets[k / 2 - 1] + onsets[k / 2])),
    };
    let share: Vec<f64> = runs
        .iter()
        .map(|r| {
            let n = r.robots.len().max(1) as f64;
            100.0 * r.robots.iter().filter(|t| t.ends_stuck).count() as f64 / n
        })
        .collect();
    let distance: Vec<f64> = runs
        .iter()
        .map(|r| {
            let n = r.robots.len().max(1) as f64;
            r.robots.iter().map(|t| t.distance_m).sum::<f64>() / n
        })
        .collect();
    RobotStats {
        robots,
        ending_stuck,
        ending_stuck_percent: Estimate::of(&share, seed),
        with_lasting_spell: onsets.len() as u32,
        first_lasting_stuck_step_median: median,
        distance_m: Estimate::of(&distance, seed),
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
/// initial weights for learning off): which robots end the run stuck under each.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Pairing {
    /// The other condition.
    pub other: Condition,
    /// Robot pairs compared (robots × repeats present in both).
    pub robots: u32,
    /// Stuck at the end under the other condition, not with learning: learning frees them.
    pub frees: u32,
    /// Stuck at the end with learning, not under the other condition: learning traps them.
    pub traps: u32,
    /// Stuck at the end under both.
    pub both_stuck: u32,
    /// Stuck under neither.
    pub neither: u32,
    /// McNemar's exact two-sided p-value on `frees` against `traps`.
    pub p: f64,
}

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

/// The runs of condition `c`, in repeat order.
fn runs_of(runs: &[RunOutput], c: Condition) -> Vec<&RunOutput> {
    let mut v: Vec<&RunOutput> = runs.iter().filter(|r| r.condition == c).collect();
    v.sort_by_key(|r| r.repeat);
    v
}

fn first_window(r: &RunOutput) -> &WindowSums {
    r.metrics.first()
}

fn last_window(r: &RunOutput) -> &WindowSums {
    &r.metrics.last
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

fn pairing(learning: &[&RunOutput], other: &[&RunOutput], c: Condition) -> Option<Pairing> {
    if learning.is_empty() || other.is_empty() {
        return None;
    }
    let mut p = Pairing {
        other: c,
        robots: 0,
        frees: 0,
        traps: 0,
        both_stuck: 0,
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
            match (a.ends_stuck, b.ends_stuck) {
                (true, true) => p.both_stuck += 1,
                (false, false) => p.neither += 1,
                (false, true) => p.frees += 1,
                (true, false) => p.traps += 1,
            }
        }
    }
    p.p = mcnemar_p(p.frees, p.traps);
    Some(p)
}

/// The claims, learning's quantities paired by repeat with its own first window or with the
/// controls' last window:
/// * the paper's text claims: D rises, collisions per metre fall, the robots keep moving (at
///   most [`KEEP_MOVING_MAX_STUCK_PERCENT`] of the last window's robot-steps stuck) and, in the
///   corridor, the gaps even out (gap CV falls);
/// * against the controls: collisions per metre below learning off's and the random walk's,
///   D above learning off's, contact time below the random walk's, in the corridor the gap CV
///   below learning off's;
/// * for reference, the raw collision count falling (which robots that stop also satisfy).
#[must_use]
pub fn claims(runs: &[RunOutput], robots: usize, seed: u64) -> Vec<Claim> {
    let learn = runs_of(runs, Condition::Learning);
    if learn.is_empty() {
        return Vec::new();
    }
    let of = |rs: &[&RunOutput], q: Quantity, w: fn(&RunOutput) -> &WindowSums| {
        per_repeat(rs, q, robots, w)
    };
    let first = |q| of(&learn, q, first_window);
    let last = |q| of(&learn, q, last_window);
    let corridor = learn.iter().all(|r| r.metrics.whole.all_have_gap_cv());
    let off = runs_of(runs, Condition::LearningOff);
    let walk = runs_of(runs, Condition::RandomWalk);
    let claim = |text: &str, paper: bool, q: Quantity, a: Vec<Option<f64>>, b: Vec<Option<f64>>| {
        Claim::paired(text, paper, q, &a, &b, seed)
    };
    use Quantity as Q;
    let mut out = vec![
        claim(
            "D rises: mean D in the last window above the first (learning)",
            true,
            Q::MeanD,
            first(Q::MeanD),
            last(Q::MeanD),
        ),
        claim(
            "collisions fall: collisions per metre moved in the last window below the first (learning)",
            true,
            Q::CollisionsPerM,
            last(Q::CollisionsPerM),
            first(Q::CollisionsPerM),
        ),
        claim(
            &format!(
                "the robots keep moving: stuck robot-steps in the last window below {KEEP_MOVING_MAX_STUCK_PERCENT} % (learning)"
            ),
            true,
            Q::StuckPercent,
            last(Q::StuckPercent),
            vec![Some(KEEP_MOVING_MAX_STUCK_PERCENT); learn.len()],
        ),
    ];
    if corridor {
        out.push(claim(
            "the gaps even out: gap CV in the last window below the first (learning)",
            true,
            Q::GapCv,
            last(Q::GapCv),
            first(Q::GapCv),
        ));
    }
    if !off.is_empty() {
        out.push(claim(
            "collisions per metre moved in the last window: learning below learning off",
            false,
            Q::CollisionsPerM,
            last(Q::CollisionsPerM),
            of(&off, Q::CollisionsPerM, last_window),
        ));
    }
    if !walk.is_empty() {
        out.push(claim(
            "collisions per metre moved in the last window: learning below the random walk",
            false,
            Q::CollisionsPerM,
            last(Q::CollisionsPerM),
            of(&walk, Q::CollisionsPerM, last_window),
        ));
    }
    if !off.is_empty() {
        out.push(claim(
            "mean D in the last window: learning above learning off",
            false,
            Q::MeanD,
            of(&off, Q::MeanD, last_window),
            last(Q::MeanD),
        ));
    }
    if !walk.is_empty() {
        out.push(claim(
            "contact time in the last window: learning below the random walk",
            false,
            Q::ContactPercent,
            last(Q::ContactPercent),
            of(&walk, Q::ContactPercent, last_window),
        ));
    }
    for (others, name) in [(&off, "learning off"), (&walk, "the random walk")] {
        if !others.is_empty() {
            out.push(claim(
                &format!("energy per robot-step in the last window: learning below {name} (battery life longer)"),
                false,
                Q::EnergyMj,
                last(Q::EnergyMj),
                of(others, Q::EnergyMj, last_window),
            ));
        }
    }
    if corridor && !off.is_empty() {
        out.push(claim(
            "gap CV in the last window: learning below learning off",
            false,
            Q::GapCv,
            last(Q::GapCv),
            of(&off, Q::GapCv, last_window),
        ));
    }
    out.push(claim(
        "raw count, for reference: collisions per robot in the last window below the first (learning; robots that stop satisfy it too)",
        false,
        Q::CollisionsPerRobot,
        last(Q::CollisionsPerRobot),
        first(Q::CollisionsPerRobot),
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collisions::RobotTally;
    use crate::experiment::{RunMetrics, StepMetrics};

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
        assert!(t_975(31) < t_975(30) && t_975(31) > t_975(32) && t_975(1000) > 1.96);
    }

    #[test]
    fn the_bootstrap_order_statistic_is_far_from_a_rounding_edge_for_every_repeat_count() {
        // The interval's ends are the resampled means at floor(tail · 10 000) from either end;
        // the tail comes through statrs, which calls the host's exp and ln, so it may differ by
        // a few ulps from one platform or C library to another. For every repeat count a
        // scenario allows, tail · 10 000 lies at least 1e-6 from a whole number, far more than
        // ulps can move it: the same order statistic everywhere.
        // (Below 1 the floor is 0 whatever the ulps: a probability is never negative.)
        let mut nearest = f64::INFINITY;
        for n in 2..=1000 {
            let x = expanded_tail(n) * BOOTSTRAP_RESAMPLES as f64;
            if x >= 0.5 {
                nearest = nearest.min((x - x.round()).abs());
            }
        }
        assert!(nearest > 1e-6, "{nearest}");
    }

    #[test]
    fn the_expanded_tail_widens_small_samples_and_tends_to_2_5_percent() {
        // n = 5: sqrt(5/4) · 2.776 = 3.104, Φ(−3.104) = 0.000955.
        assert!(
            (expanded_tail(5) - 0.000_955).abs() < 2e-5,
            "{}",
            expanded_tail(5)
        );
        assert!(expanded_tail(10) < expanded_tail(30));
        assert!((expanded_tail(100_000) - 0.025).abs() < 1e-4);
    }

    #[test]
    fn sign_and_mcnemar_tests_are_exact() {
        assert_eq!(sign_test_p(5, 5), 1.0 / 32.0);
        assert_eq!(sign_test_p(0, 5), 1.0);
        assert!((sign_test_p(4, 5) - 6.0 / 32.0).abs() < 1e-12);
        assert!((sign_test_p(8, 10) - 56.0 / 1024.0).abs() < 1e-12);
        assert_eq!(sign_test_p(1, 0), 0.0);
        // McNemar: 6 freed, 1 trapped: 2 · P(X ≤ 1 | 7) = 2 · 8 / 128.
        assert!((mcnemar_p(6, 1) - 16.0 / 128.0).abs() < 1e-12);
        assert!((mcnemar_p(1, 6) - 16.0 / 128.0).abs() < 1e-12);
        assert_eq!(mcnemar_p(0, 0), 1.0);
        assert_eq!(mcnemar_p(3, 3), 1.0);
    }

    #[test]
    fn paired_counts_ties_and_missing_values() {
        let a = [Some(1.0), Some(2.0), Some(3.0), None, Some(5.0)];
        let b = [Some(2.0), Some(1.0), Some(3.0), Some(4.0), Some(6.0)];
        let p = Paired::of(&a, &b);
        assert_eq!((p.for_, p.against, p.tied, p.undefined), (2, 1, 1, 1));
        assert_eq!(p.defined(), 4);
        assert!((p.p - sign_test_p(2, 3)).abs() < 1e-15);
    }

    fn constant(v: f64, n: usize) -> Vec<Option<f64>> {
        vec![Some(v); n]
    }

    #[test]
    fn claims_say_how_they_came_out_and_never_the_opposite_for_equal_values() {
        let q = Quantity::MeanD;
        let lo: Vec<Option<f64>> = [1.0, 1.1, 0.9, 1.0, 1.05].map(Some).to_vec();
        let hi: Vec<Option<f64>> = [5.0, 5.1, 4.9, 5.2, 5.3].map(Some).to_vec();
        let c = Claim::paired("x", true, q, &lo, &hi, 1);
        assert_eq!(c.outcome, Outcome::Holds);
        assert!(
            c.verdict.starts_with("holds: 5 of 5 repeats"),
            "{}",
            c.verdict
        );
        let c = Claim::paired("x", true, q, &hi, &lo, 1);
        assert_eq!(c.outcome, Outcome::Fails);
        assert!(
            c.verdict.starts_with("fails: the opposite, 5 of 5"),
            "{}",
            c.verdict
        );
        // Means apart but only 4 of 5 repeats: not significant with 5 repeats.
        let mixed: Vec<Option<f64>> = [5.0, 5.1, 4.9, 5.2, 0.5].map(Some).to_vec();
        let c = Claim::paired("x", true, q, &lo, &mixed, 1);
        assert_eq!(c.outcome, Outcome::Unsure, "{}", c.verdict);
        assert!(c.means_agree);
        // The means agree, the repeats mostly do not: the repeats decide.
        let skew: Vec<Option<f64>> = [0.9, 1.0, 0.8, 0.9, 90.0].map(Some).to_vec();
        let c = Claim::paired("x", true, q, &lo, &skew, 1);
        assert!(c.means_agree);
        assert_eq!(c.outcome, Outcome::Fails, "{}", c.verdict);
        assert!(
            c.verdict
                .starts_with("fails: 4 of 5 repeats go the other way"),
            "{}",
            c.verdict
        );
        // Equal values: fails, and never "the opposite".
        let c = Claim::paired("x", true, q, &constant(600.67, 5), &constant(600.67, 5), 1);
        assert_eq!(c.outcome, Outcome::Fails);
        assert_eq!(
            c.verdict,
            "fails: as many repeats go each way (0 and 0, 5 tied)"
        );
        assert!(!c.verdict.contains("opposite"));
        assert!(!c.means_agree);
        let c = Claim::paired("x", true, q, &[None, None], &constant(1.0, 2), 1);
        assert_eq!(c.outcome, Outcome::Undecided);
    }

    #[test]
    fn intervals_stay_within_the_values() {
        let e = Estimate::of(&[0.0, 0.0, 0.0, 0.0, 100.0], 7);
        assert_eq!(e.mean, 20.0);
        let (lo, hi) = (e.lo.unwrap(), e.hi.unwrap());
        assert!((0.0..=100.0).contains(&lo) && (0.0..=100.0).contains(&hi));
        assert!(lo <= 20.0 && hi >= 20.0);
        assert_eq!(Estimate::of(&[7.0], 1).lo, None);
        assert_eq!(Estimate::of(&[3.0, 3.0, 3.0], 1).lo, Some(3.0));
        // The same values and seed give the same interval.
        assert_eq!(
            Estimate::of(&[1.0, 4.0, 2.0], 5),
            Estimate::of(&[1.0, 4.0, 2.0], 5)
        );
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]
        /// Bounded quantities keep bounded intervals: a share in 0–100 %, a count at or above
        /// 0, D in 0–1020 du; the interval holds the mean and stays within the repeats' range.
        #[test]
        fn intervals_stay_in_the_quantity_s_range(
            values in proptest::collection::vec(
                proptest::prop_oneof![
                    0.0..=100.0f64,
                    proptest::strategy::Just(0.0),
                    proptest::strategy::Just(100.0)
                ],
                1..40,
            ),
            upper in proptest::prop_oneof![
                proptest::strategy::Just(100.0f64),
                proptest::strategy::Just(1020.0),
                proptest::strategy::Just(1.0)
            ],
            seed in proptest::prelude::any::<u64>(),
        ) {
            let v: Vec<f64> = values.iter().map(|x| x / 100.0 * upper).collect();
            let e = Estimate::of(&v, seed);
            let (min, max) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
            proptest::prop_assert_eq!(e.n, v.len());
            match (e.lo, e.hi) {
                (Some(lo), Some(hi)) => {
                    proptest::prop_assert!(v.len() >= 2);
                    proptest::prop_assert!(0.0 <= lo && hi <= upper, "{lo}..{hi} out of 0..{upper}");
                    proptest::prop_assert!(min <= lo && hi <= max, "{lo}..{hi} out of {min}..{max}");
                    proptest::prop_assert!(lo <= e.mean + 1e-9 && e.mean <= hi + 1e-9);
                }
                (None, None) => proptest::prop_assert_eq!(v.len(), 1),
                _ => proptest::prop_assert!(false, "half an interval"),
            }
        }
    }

    /// A run whose every step has the given metrics (`robots` robots, `steps` steps, windows of
    /// `win`), with its robots' tallies.
    fn run_of(
        c: Condition,
        repeat: u32,
        steps: u32,
        win: u32,
        step: impl Fn(u32) -> StepMetrics,
        robots: Vec<RobotTally>,
    ) -> RunOutput {
        let mut m = RunMetrics::new(steps, win);
        for k in 0..steps {
            m.add(k, &step(k));
        }
        RunOutput {
            condition: c,
            repeat,
            metrics: m,
            track: None,
            saves: 0,
            dead: Vec::new(),
            robots,
            recorded: None,
            stack_warnings: Vec::new(),
            io_warnings: Vec::new(),
            energy: crate::energy::Charge::default(),
            motor_cap: crate::energy::CurrentCap::default(),
        }
    }

    fn moving(coll: f64, moved_mm: f64, stuck: f64) -> StepMetrics {
        StepMetrics {
            mean_d: 700.0,
            collisions_per_robot: coll,
            contact_percent: 10.0,
            stuck_percent: stuck,
            moving_percent: if moved_mm > 0.0 { 100.0 - stuck } else { 0.0 },
            moved_mm,
            gap_cv: None,
            cpu_load_percent: 0.3,
            energy_per_robot_mj: 3000.0,
        }
    }

    /// Robots that stop earn nothing: the raw count falls, but collisions per metre of the
    /// robots still moving do not, and the robots-keep-moving claim fails.
    #[test]
    fn a_stopped_robot_earns_no_credit_in_the_movement_aware_claims() {
        let (steps, win) = (400, 100);
        // 3 robots. First half: all move 50 mm a step and collide 0.03 per robot-step (0.6
        // per metre). Second half: two of the three stand stuck against a wall; the third
        // moves and collides a little more often per metre (0.72).
        let step = |k: u32| {
            if k < 200 {
                moving(0.03, 50.0, 0.0)
            } else {
                moving(0.012, 50.0 / 3.0, 200.0 / 3.0)
            }
        };
        let runs: Vec<RunOutput> = (0..5)
            .map(|r| run_of(Condition::Learning, r, steps, win, step, vec![]))
            .collect();
        let checked = claims(&runs, 3, 1);
        let find = |start: &str| checked.iter().find(|c| c.claim.starts_with(start)).unwrap();
        let raw = find("raw count");
        assert_eq!(
            raw.outcome,
            Outcome::Holds,
            "the raw count falls: {}",
            raw.verdict
        );
        let per_m = find("collisions fall");
        assert!((per_m.values[0] - 0.72).abs() < 1e-9 && (per_m.values[1] - 0.6).abs() < 1e-9);
        assert_eq!(per_m.outcome, Outcome::Fails, "{}", per_m.verdict);
        let keep_moving = find("the robots keep moving");
        assert_eq!(
            keep_moving.outcome,
            Outcome::Fails,
            "{}",
            keep_moving.verdict
        );
        // All three stopped: collisions per metre are undefined, not zero.
        let stopped = |k: u32| {
            if k < 200 {
                moving(0.03, 50.0, 0.0)
            } else {
                moving(0.0, 0.0, 100.0)
            }
        };
        let runs: Vec<RunOutput> = (0..5)
            .map(|r| run_of(Condition::Learning, r, steps, win, stopped, vec![]))
            .collect();
        let per_m = claims(&runs, 3, 1)
            .into_iter()
            .find(|c| c.claim.starts_with("collisions fall"))
            .unwrap();
        assert_eq!(per_m.outcome, Outcome::Undecided, "{}", per_m.verdict);
        assert!(per_m.values[0].is_nan());
    }

    fn ended(stuck: bool) -> RobotTally {
        let mut t = RobotTally::new(10);
        for k in 0..200 {
            t.record(
                k,
                if stuck { 0.0 } else { 0.05 },
                0,
                stuck && k >= 100,
                false,
            );
        }
        t.finish();
        t
    }

    /// Robot by robot: learning frees the robots stuck only with learning off, traps those
    /// stuck only with learning; McNemar on the two counts.
    #[test]
    fn pairings_count_freed_and_trapped_robots() {
        let step = |_| moving(0.0, 50.0, 0.0);
        let pattern = [
            // (learning, learning off) per robot, two repeats of three robots.
            [(false, true), (false, true), (true, true)],
            [(false, true), (true, false), (false, false)],
        ];
        let mut runs = Vec::new();
        for (r, robots) in pattern.iter().enumerate() {
            let r = r as u32;
            runs.push(run_of(
                Condition::Learning,
                r,
                200,
                100,
                step,
                robots.iter().map(|&(l, _)| ended(l)).collect(),
            ));
            runs.push(run_of(
                Condition::LearningOff,
                r,
                200,
                100,
                step,
                robots.iter().map(|&(_, o)| ended(o)).collect(),
            ));
        }
        let a = analyse(&runs, 3, 200, 100, 1);
        assert_eq!(a.pairings.len(), 1);
        let p = &a.pairings[0];
        assert_eq!(
            (p.robots, p.frees, p.traps, p.both_stuck, p.neither),
            (6, 3, 1, 1, 1)
        );
        assert!((p.p - mcnemar_p(3, 1)).abs() < 1e-15);
        let learning = &a.conditions[0].robots;
        assert_eq!((learning.robots, learning.ending_stuck), (6, 2));
        assert_eq!(learning.with_lasting_spell, 2);
        assert_eq!(learning.first_lasting_stuck_step_median, Some(1.0));
    }
}
