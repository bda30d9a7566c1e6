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
/// "The robots keep exploring": at most this share of the last window's robot-steps held,
/// percent (the reasoning is in `docs/claims.md`).
pub const KEEP_EXPLORING_MAX_HELD_PERCENT: f64 = 10.0;
/// "The robots keep exploring": the learning robots' net progress in the last window at
/// least this fraction of the random walk's (same repeat, same placement).
pub const KEEP_EXPLORING_FRACTION: f64 = 0.5;
/// "The gaps even out": neighbours touch in under this share of the last window's steps,
/// percent (a jam has no spacing to judge).
pub const GAPS_MAX_TOUCHING_PERCENT: f64 = 50.0;
/// A window's gap CV is the mean over its steps in which no neighbours touch, and has a value
/// only when at least this share of its steps do.
pub const GAP_CV_MIN_DEFINED: f64 = 0.5;
/// Collisions per metre (net or of path) are defined for a window only when its robots made at
/// least this many metres between them: below that a rate per metre is noise, and a swarm that
/// stood still would otherwise earn a perfect score.
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

/// ln C(n, j), from libm's log-gamma (pure Rust: the same bits on every platform,
/// docs/limits-and-failures.md).
fn ln_choose(n: u32, j: u32) -> f64 {
    let ln_gamma = |x: f64| libm::lgamma_r(x).0;
    ln_gamma(f64::from(n) + 1.0) - ln_gamma(f64::from(j) + 1.0) - ln_gamma(f64::from(n - j) + 1.0)
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
    let ln_half_n = f64::from(n) * std::f64::consts::LN_2;
    let p: f64 = (k..=n)
        .map(|j| libm::exp(ln_choose(n, j) - ln_half_n))
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

/// How one repeat went for a claim "a below b".
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// a below b.
    For,
    /// a above b.
    Against,
    /// a equal to b.
    Tied,
    /// a or b has no value.
    Undefined,
}

impl Side {
    /// How `a` and `b` of one repeat compare.
    #[must_use]
    pub fn of(a: Option<f64>, b: Option<f64>) -> Side {
        match (a, b) {
            (Some(x), Some(y)) if x < y => Side::For,
            (Some(x), Some(y)) if x > y => Side::Against,
            (Some(_), Some(_)) => Side::Tied,
            _ => Side::Undefined,
        }
    }

    /// A repeat of a claim made of parts that must all hold: against when one part is,
    /// else undefined when one part is, else tied when one is, else for.
    #[must_use]
    pub fn all(parts: impl IntoIterator<Item = Side>) -> Side {
        let mut out = Side::For;
        for s in parts {
            out = match (out, s) {
                (Side::Against, _) | (_, Side::Against) => Side::Against,
                (Side::Undefined, _) | (_, Side::Undefined) => Side::Undefined,
                (Side::Tied, _) | (_, Side::Tied) => Side::Tied,
                _ => Side::For,
            };
        }
        out
    }
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
        Self::of_sides(&sides(a, b))
    }

    /// Counts the repeats' sides.
    #[must_use]
    pub fn of_sides(sides: &[Side]) -> Paired {
        let count = |s: Side| sides.iter().filter(|&&x| x == s).count() as u32;
        let (for_, against) = (count(Side::For), count(Side::Against));
        Paired {
            for_,
            against,
            tied: count(Side::Tied),
            undefined: count(Side::Undefined),
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

/// Each repeat's side, pairing `a[r]` with `b[r]`.
#[must_use]
pub fn sides(a: &[Option<f64>], b: &[Option<f64>]) -> Vec<Side> {
    (0..a.len().max(b.len()))
        .map(|r| Side::of(a.get(r).copied().flatten(), b.get(r).copied().flatten()))
        .collect()
}

/// The power a sign test needs for 80 %: the probability of reaching p < [`SIGNIFICANCE`].
pub const POWER: f64 = 0.8;
/// Largest number of untied repeats [`repeats_needed`] computes exactly (beyond it, the normal
/// approximation).
const EXACT_POWER_UP_TO: u32 = 400;
/// Largest number of repeats [`repeats_needed`] reports.
pub const MAX_REPEATS_NEEDED: u32 = 100_000;

/// The fewest untied repeats with which a one-sided sign test reaches p < [`SIGNIFICANCE`]
/// with probability [`POWER`] when each repeat goes the claimed way with probability `q`
/// (above ½); none for `q` ≤ ½ or when more than [`MAX_REPEATS_NEEDED`] would be needed.
/// Exact up to 400 repeats (the smallest n whose critical count k, the least with
/// P(X ≥ k | n, ½) < 0.05, is reached with P(X ≥ k | n, q) ≥ 0.8), the normal approximation
/// beyond.
#[must_use]
pub fn repeats_needed(q: f64) -> Option<u32> {
    if q.is_nan() || q <= 0.5 {
        return None;
    }
    let q = q.min(1.0);
    for n in 1..=EXACT_POWER_UP_TO {
        let Some(k) = (0..=n).find(|&k| sign_test_p(k, n) < SIGNIFICANCE) else {
            continue;
        };
        if binomial_tail(k, n, q) >= POWER {
            return Some(n);
        }
    }
    // Normal approximation: n = ((z_α/2 + z_β √(q(1−q))) / (q − ½))².
    let (za, zb) = (1.644_853_626_951_472, 0.841_621_233_572_914_3);
    let root_n = (za * 0.5 + zb * (q * (1.0 - q)).sqrt()) / (q - 0.5);
    let n = root_n * root_n;
    (n <= f64::from(MAX_REPEATS_NEEDED)).then(|| n.ceil() as u32)
}

/// P(X ≥ k) for X ~ Binomial(n, q).
fn binomial_tail(k: u32, n: u32, q: f64) -> f64 {
    if k == 0 {
        return 1.0;
    }
    if q >= 1.0 {
        return if k <= n { 1.0 } else { 0.0 };
    }
    let (lq, lr) = (libm::log(q), libm::log(1.0 - q));
    (k..=n)
        .map(|j| libm::exp(ln_choose(n, j) + f64::from(j) * lq + f64::from(n - j) * lr))
        .sum::<f64>()
        .min(1.0)
}

/// What a decision on a claim would take at the effect its repeats show.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Power {
    /// The share of the untied repeats with a value that go the claimed way.
    pub observed_share: Option<f64>,
    /// Which way a decision could go at that share: `holds` (more go the claimed way),
    /// `opposite`, or `none` (as many each way, or no repeat untied).
    pub towards: &'static str,
    /// Repeats (all of them, at the observed share of ties and missing values) a sign test
    /// needs to decide that way with 80 % power at that share; none when it cannot.
    pub repeats_needed: Option<u32>,
}

impl Power {
    /// The power of a claim's repeats.
    #[must_use]
    pub fn of(r: &Paired) -> Power {
        let untied = r.for_ + r.against;
        let all = untied + r.tied + r.undefined;
        if untied == 0 {
            return Power {
                observed_share: None,
                towards: "none",
                repeats_needed: None,
            };
        }
        let q = f64::from(r.for_) / f64::from(untied);
        let (towards, needed) = if r.for_ > r.against {
            ("holds", repeats_needed(q))
        } else if r.against > r.for_ {
            ("opposite", repeats_needed(1.0 - q))
        } else {
            ("none", None)
        };
        // Scaled up for the repeats that tie or lack a value.
        let scale = f64::from(all) / f64::from(untied);
        Power {
            observed_share: Some(q),
            towards,
            repeats_needed: needed
                .map(|n| (f64::from(n) * scale).ceil() as u32)
                .filter(|&n| n <= MAX_REPEATS_NEEDED),
        }
    }

    /// In words: "a decision needs about N repeats" or why none can be had.
    #[must_use]
    pub fn words(&self) -> String {
        match (self.towards, self.repeats_needed) {
            ("holds", Some(n)) => format!("to hold at this effect it needs about {n} repeats"),
            ("opposite", Some(n)) => {
                format!("the opposite would need about {n} repeats at this effect")
            }
            ("none", _) if self.observed_share.is_some() => {
                "at an even split no number of repeats decides it".into()
            }
            ("none", _) => "no repeat decides it".into(),
            _ => format!("more than {MAX_REPEATS_NEEDED} repeats would be needed at this effect"),
        }
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

/// A claim checked against the numbers: "a below b", paired by repeat; or several such parts
/// that must all hold in a repeat for it to count.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Claim {
    /// What is claimed.
    pub claim: String,
    /// Whether it is one of the paper's own text claims (the others compare with the controls
    /// the paper lacks, or are kept for reference).
    pub paper: bool,
    /// The quantity compared (its name in the window statistics), or `all of its parts`.
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
    /// The two values compared (means over the repeats that have one) in the order the claim's
    /// words name them ("learning above learning off": learning's first, whichever way the
    /// claim goes); for a claim of parts, the share of repeats against it and for it (percent).
    pub values: [f64; 2],
    /// Their 95 % intervals (none with a single repeat, nor for a claim of parts).
    pub intervals: [[Option<f64>; 2]; 2],
    /// The repeat-by-repeat comparison.
    pub repeats: Paired,
    /// What a decision would take at the observed effect.
    pub power: Power,
    /// A claim of parts: the parts' claims (each also listed among the claims).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub parts: Vec<String>,
    /// Each repeat's side (for a claim made of this one).
    #[serde(skip)]
    pub sides: Vec<Side>,
}

/// The outcome and verdict of repeats `r`.
fn verdict_of(r: &Paired) -> (Outcome, String) {
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
    (outcome, verdict)
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
        let sides = sides(a, b);
        let r = Paired::of_sides(&sides);
        let (outcome, verdict) = verdict_of(&r);
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
            repeats: r,
            power: Power::of(&r),
            parts: Vec::new(),
            sides,
        }
    }

    /// The claim "`subject` above `reference`", each given per repeat: the claim "`reference`
    /// below `subject`" with its values and intervals in the words' order (`subject` first).
    #[must_use]
    pub fn paired_above(
        claim: &str,
        paper: bool,
        quantity: Quantity,
        subject: &[Option<f64>],
        reference: &[Option<f64>],
        seed: u64,
    ) -> Claim {
        let mut c = Claim::paired(claim, paper, quantity, reference, subject, seed);
        c.values.swap(0, 1);
        c.intervals.swap(0, 1);
        c
    }

    /// The claim that every one of `parts` holds, repeat by repeat: a repeat goes for it when
    /// it goes for every part, against it when it goes against one ([`Side::all`]). Its values
    /// are the shares of the repeats against and for it (percent).
    #[must_use]
    pub fn all_of(claim: &str, paper: bool, parts: &[&Claim]) -> Claim {
        let n = parts.iter().map(|p| p.sides.len()).max().unwrap_or(0);
        let sides: Vec<Side> = (0..n)
            .map(|r| {
                Side::all(
                    parts
                        .iter()
                        .map(|p| p.sides.get(r).copied().unwrap_or(Side::Undefined)),
                )
            })
            .collect();
        let r = Paired::of_sides(&sides);
        let (outcome, verdict) = verdict_of(&r);
        let share = |k: u32| {
            if n == 0 {
                f64::NAN
            } else {
                100.0 * f64::from(k) / n as f64
            }
        };
        Claim {
            claim: claim.to_string(),
            paper,
            quantity: "all of its parts".into(),
            unit: "% of repeats".into(),
            outcome,
            means_agree: r.for_ > r.against,
            apart: false,
            verdict,
            values: [share(r.against), share(r.for_)],
            intervals: [[None; 2]; 2],
            repeats: r,
            power: Power::of(&r),
            parts: parts.iter().map(|p| p.claim.clone()).collect(),
            sides,
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
    /// Collisions per net metre (the net displacement over the lag, per step, summed; none
    /// below [`MIN_MOVED_M`]).
    CollisionsPerNetM,
    /// Collisions per metre of path the robots moved (none below [`MIN_MOVED_M`]); a
    /// reference: a shuttler adds metres without getting anywhere.
    CollisionsPerM,
    /// Collisions per moving robot-step (none below [`MIN_MOVING_ROBOT_STEPS`]); a reference.
    CollisionsPerMovingStep,
    /// Time with a bumper pressed, percent.
    ContactPercent,
    /// Held robot-steps, percent.
    HeldPercent,
    /// Shuttling robot-steps, percent.
    ShuttlingPercent,
    /// Circling robot-steps, percent.
    CirclingPercent,
    /// Exploring robot-steps, percent.
    ExploringPercent,
    /// Moving robot-steps (at least 5 mm), percent; a reference.
    MovingPercent,
    /// Distance a robot moved per step (path), mm.
    MovedMm,
    /// Net progress: a robot's net displacement over the lag per step, mm.
    NetMm,
    /// Net progress over path: net over moved.
    Straightness,
    /// Mean squared displacement over [`crate::motion::MSD_LAGS`]`[i]` steps, cm².
    Msd(usize),
    /// The MSD's exponent from the lag of 10 to that of 100 steps: log₁₀(MSD₁₀₀ / MSD₁₀)
    /// (2 straight driving, 1 diffusion, 0 confinement).
    MsdExponent,
    /// Fresh cells a robot enters per 100 steps ([`crate::motion::FRESH_STEPS`]).
    FreshCells,
    /// New cells per robot over the window.
    NewCells,
    /// The corridor's gap CV (none in the square arena, and none when neighbours touch in
    /// half the window's steps or more).
    GapCv,
    /// Corridor steps in which neighbours touch, percent (none in the square arena).
    TouchingPercent,
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
            Quantity::CollisionsPerNetM => "collisions_per_net_m",
            Quantity::CollisionsPerM => "collisions_per_m",
            Quantity::CollisionsPerMovingStep => "collisions_per_moving_step",
            Quantity::ContactPercent => "contact_percent",
            Quantity::HeldPercent => "held_percent",
            Quantity::ShuttlingPercent => "shuttling_percent",
            Quantity::CirclingPercent => "circling_percent",
            Quantity::ExploringPercent => "exploring_percent",
            Quantity::MovingPercent => "moving_percent",
            Quantity::MovedMm => "moved_mm",
            Quantity::NetMm => "net_mm",
            Quantity::Straightness => "straightness",
            Quantity::Msd(0) => "msd_1_cm2",
            Quantity::Msd(1) => "msd_10_cm2",
            Quantity::Msd(_) => "msd_100_cm2",
            Quantity::MsdExponent => "msd_exponent",
            Quantity::FreshCells => "fresh_cells_per_100_steps",
            Quantity::NewCells => "new_cells",
            Quantity::GapCv => "gap_cv",
            Quantity::TouchingPercent => "touching_percent",
            Quantity::EnergyMj => "energy_per_robot_step_mj",
        }
    }

    /// Its unit, short.
    #[must_use]
    pub const fn unit(self) -> &'static str {
        match self {
            Quantity::MeanD => "du",
            Quantity::CollisionsPerRobot => "per robot",
            Quantity::CollisionsPerNetM => "per net m",
            Quantity::CollisionsPerM => "per m",
            Quantity::CollisionsPerMovingStep => "per moving robot-step",
            Quantity::ContactPercent
            | Quantity::HeldPercent
            | Quantity::ShuttlingPercent
            | Quantity::CirclingPercent
            | Quantity::ExploringPercent
            | Quantity::MovingPercent
            | Quantity::TouchingPercent => "%",
            Quantity::MovedMm | Quantity::NetMm => "mm",
            Quantity::Straightness => "net/path",
            Quantity::Msd(_) => "cm²",
            Quantity::MsdExponent => "exponent",
            Quantity::FreshCells => "cells per 100 steps",
            Quantity::NewCells => "cells per robot",
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
        let per =
            |metres: f64| (metres >= MIN_MOVED_M).then(|| w.collisions_per_robot * robots / metres);
        let msd = |l: usize| (w.msd_steps[l] > 0).then(|| w.msd_cm2[l] / f64::from(w.msd_steps[l]));
        match self {
            Quantity::MeanD => Some(w.mean_d / steps),
            Quantity::CollisionsPerRobot => Some(w.collisions_per_robot),
            Quantity::CollisionsPerNetM => per(w.net_mm / 1000.0 * robots),
            Quantity::CollisionsPerM => per(w.moved_mm / 1000.0 * robots),
            Quantity::CollisionsPerMovingStep => {
                let moving = w.moving_percent / 100.0 * robots;
                (moving >= MIN_MOVING_ROBOT_STEPS).then(|| w.collisions_per_robot * robots / moving)
            }
            Quantity::ContactPercent => Some(w.contact_percent / steps),
            Quantity::HeldPercent => Some(w.held_percent / steps),
            Quantity::ShuttlingPercent => Some(w.shuttling_percent / steps),
            Quantity::CirclingPercent => Some(w.circling_percent / steps),
            Quantity::ExploringPercent => Some(w.exploring_percent / steps),
            Quantity::MovingPercent => Some(w.moving_percent / steps),
            Quantity::MovedMm => Some(w.moved_mm / steps),
            Quantity::NetMm => Some(w.net_mm / steps),
            Quantity::Straightness => (w.moved_mm > 0.0).then(|| w.net_mm / w.moved_mm),
            Quantity::Msd(l) => msd(l.min(2)),
            Quantity::MsdExponent => match (msd(1), msd(2)) {
                (Some(a), Some(b)) if a > 0.0 && b > 0.0 => Some(libm::log10(b / a)),
                _ => None,
            },
            Quantity::FreshCells => Some(w.fresh_cells / steps * 100.0),
            Quantity::NewCells => Some(w.new_cells),
            Quantity::GapCv => (w.is_corridor()
                && f64::from(w.gap_cv_steps) >= GAP_CV_MIN_DEFINED * f64::from(w.corridor_steps))
            .then(|| w.gap_cv / f64::from(w.gap_cv_steps)),
            Quantity::TouchingPercent => w
                .is_corridor()
                .then(|| 100.0 * f64::from(w.touching_steps) / f64::from(w.corridor_steps)),
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
    /// Collisions per net metre.
    pub collisions_per_net_m: Estimate,
    /// Collisions per metre of path the robots moved (a reference).
    pub collisions_per_m: Estimate,
    /// Collisions per moving robot-step (a reference).
    pub collisions_per_moving_step: Estimate,
    /// Time a robot spent with a bumper pressed, percent.
    pub contact_percent: Estimate,
    /// Robot-steps held in place, percent.
    pub held_percent: Estimate,
    /// Robot-steps shuttling, percent.
    pub shuttling_percent: Estimate,
    /// Robot-steps circling, percent.
    pub circling_percent: Estimate,
    /// Robot-steps exploring, percent.
    pub exploring_percent: Estimate,
    /// Robot-steps in which the robot moved at least 5 mm, percent (a reference).
    pub moving_percent: Estimate,
    /// Distance a robot's centre moved per step (path), mm.
    pub moved_mm: Estimate,
    /// Net progress: net displacement over the lag per step, mm.
    pub net_mm: Estimate,
    /// Net progress over path.
    pub straightness: Estimate,
    /// Mean squared displacement over 1 step, cm².
    pub msd_1_cm2: Estimate,
    /// Mean squared displacement over 10 steps, cm².
    pub msd_10_cm2: Estimate,
    /// Mean squared displacement over 100 steps, cm².
    pub msd_100_cm2: Estimate,
    /// log₁₀(MSD₁₀₀ / MSD₁₀): 2 straight driving, 1 diffusion, 0 confinement.
    pub msd_exponent: Estimate,
    /// Fresh cells a robot enters per 100 steps.
    pub fresh_cells_per_100_steps: Estimate,
    /// New cells per robot over the window.
    pub new_cells: Estimate,
    /// Corridor: mean gap CV over the window's steps in which no neighbours touch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap_cv: Option<Estimate>,
    /// Corridor: steps in which neighbours touch, percent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub touching_percent: Option<Estimate>,
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
    use Quantity as Q;
    let est = |q: Quantity| Estimate::of_defined(&per_repeat(runs, q, robots, win), seed);
    let corridor = runs.iter().all(|r| win(r).is_corridor());
    WindowStats {
        from_step: from,
        to_step: to,
        mean_d: est(Q::MeanD),
        collisions_per_robot: est(Q::CollisionsPerRobot),
        collisions_per_net_m: est(Q::CollisionsPerNetM),
        collisions_per_m: est(Q::CollisionsPerM),
        collisions_per_moving_step: est(Q::CollisionsPerMovingStep),
        contact_percent: est(Q::ContactPercent),
        held_percent: est(Q::HeldPercent),
        shuttling_percent: est(Q::ShuttlingPercent),
        circling_percent: est(Q::CirclingPercent),
        exploring_percent: est(Q::ExploringPercent),
        moving_percent: est(Q::MovingPercent),
        moved_mm: est(Q::MovedMm),
        net_mm: est(Q::NetMm),
        straightness: est(Q::Straightness),
        msd_1_cm2: est(Q::Msd(0)),
        msd_10_cm2: est(Q::Msd(1)),
        msd_100_cm2: est(Q::Msd(2)),
        msd_exponent: est(Q::MsdExponent),
        fresh_cells_per_100_steps: est(Q::FreshCells),
        new_cells: est(Q::NewCells),
        gap_cv: corridor.then(|| est(Q::GapCv)),
        touching_percent: corridor.then(|| est(Q::TouchingPercent)),
        energy_per_robot_step_mj: est(Q::EnergyMj),
    }
}

/// The robots of one condition over all its repeats: how many end the run held, when their
/// first lasting held spell began, how far they went.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RobotStats {
    /// Robots over all repeats.
    pub robots: u32,
    /// Of them, those held at the run's last step.
    pub ending_held: u32,
    /// The share of a repeat's robots that end it held, percent.
    pub ending_held_percent: Estimate,
    /// Robots that had a lasting held spell (held for at least a window, or to the end).
    pub with_lasting_held_spell: u32,
    /// The median onset step of the first lasting held spell over the robots that had one.
    pub first_lasting_held_step_median: Option<f64>,
    /// Distance (path) a robot moved over the whole run, metres.
    pub distance_m: Estimate,
    /// Net metres a robot made over the whole run.
    pub net_m: Estimate,
    /// Distinct cells a robot was in over the whole run.
    pub cells_visited: Estimate,
}

fn robot_stats(runs: &[&RunOutput], seed: u64) -> RobotStats {
    let all = runs.iter().flat_map(|r| &r.robots);
    let robots = all.clone().count() as u32;
    let ending_held = all.clone().filter(|t| t.ends_held).count() as u32;
    let mut onsets: Vec<f64> = all
        .clone()
        .filter_map(|t| t.first_lasting_held_step.map(f64::from))
        .collect();
    onsets.sort_by(f64::total_cmp);
    let median = match onsets.len() {
        0 => None,
        k if k % 2 == 1 => Some(onsets[k / 2]),
        k => Some(0.5 * (onsets[k / 2 - 1] + onsets[k / 2])),
    };
    let mean_of = |f: &dyn Fn(&crate::motion::RobotTally) -> f64| -> Vec<f64> {
        runs.iter()
            .map(|r| {
                let n = r.robots.len().max(1) as f64;
                r.robots.iter().map(f).sum::<f64>() / n
            })
            .collect()
    };
    let share = mean_of(&|t| if t.ends_held { 100.0 } else { 0.0 });
    RobotStats {
        robots,
        ending_held,
        ending_held_percent: Estimate::of(&share, seed),
        with_lasting_held_spell: onsets.len() as u32,
        first_lasting_held_step_median: median,
        distance_m: Estimate::of(&mean_of(&|t| t.distance_m), seed),
        net_m: Estimate::of(&mean_of(&|t| t.net_m), seed),
        cells_visited: Estimate::of(&mean_of(&|t| f64::from(t.cells_visited)), seed),
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
/// initial weights for learning off): which robots end the run held under each.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Pairing {
    /// The other condition.
    pub other: Condition,
    /// Robot pairs compared (robots × repeats present in both).
    pub robots: u32,
    /// Held at the end under the other condition, not with learning: learning frees them.
    pub frees: u32,
    /// Held at the end with learning, not under the other condition: learning traps them.
    pub traps: u32,
    /// Held at the end under both.
    pub both_held: u32,
    /// Held under neither.
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
        both_held: 0,
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
            match (a.ends_held, b.ends_held) {
                (true, true) => p.both_held += 1,
                (false, false) => p.neither += 1,
                (false, true) => p.frees += 1,
                (true, false) => p.traps += 1,
            }
        }
    }
    p.p = mcnemar_p(p.frees, p.traps);
    Some(p)
}

/// The words of the claim "the robots keep exploring".
#[must_use]
pub fn keep_exploring_text() -> String {
    format!(
        "the robots keep exploring: held robot-steps in the last window below {KEEP_EXPLORING_MAX_HELD_PERCENT} % and net progress at least {KEEP_EXPLORING_FRACTION} of the random walk's (learning)"
    )
}

/// The claims, learning's quantities paired by repeat with its own first window or with the
/// controls' last window:
/// * the paper's text claims: D rises; collisions per net metre fall; the robots keep
///   exploring (at most [`KEEP_EXPLORING_MAX_HELD_PERCENT`] of the last window's robot-steps
///   held, and net progress at least [`KEEP_EXPLORING_FRACTION`] of the random walk's, same
///   repeat, both in the same repeat); in the corridor, the gaps even out (gap CV falls, with
///   neighbours touching in under [`GAPS_MAX_TOUCHING_PERCENT`] of the last window's steps);
///   the parts of the two claims of parts are listed after them;
/// * against the controls: collisions per net metre below learning off's and the random
///   walk's, D and net progress above learning off's, held robot-steps below learning off's,
///   contact time below the random walk's, energy below both, in the corridor the gap CV
///   below learning off's;
/// * for reference, collisions per path metre (which shuttling lowers) beside each collision
///   claim, and the raw collision count falling (which robots that stop satisfy).
#[must_use]
pub fn claims(runs: &[RunOutput], robots: usize, seed: u64) -> Vec<Claim> {
    let learn = runs_of(runs, Condition::Learning);
    if learn.is_empty() {
        return Vec::new();
    }
    let n = learn.len();
    let of = |rs: &[&RunOutput], q: Quantity, w: fn(&RunOutput) -> &WindowSums| {
        // Paired by repeat: the control's run of each learning repeat (none if it has none).
        learn
            .iter()
            .map(|l| {
                rs.iter()
                    .find(|r| r.repeat == l.repeat)
                    .and_then(|r| q.of(w(r), robots))
            })
            .collect::<Vec<_>>()
    };
    let first = |q| per_repeat(&learn, q, robots, first_window);
    let last = |q| per_repeat(&learn, q, robots, last_window);
    let corridor = learn.iter().all(|r| r.metrics.whole.is_corridor());
    let off = runs_of(runs, Condition::LearningOff);
    let walk = runs_of(runs, Condition::RandomWalk);
    let claim = |text: &str, paper: bool, q: Quantity, a: Vec<Option<f64>>, b: Vec<Option<f64>>| {
        Claim::paired(text, paper, q, &a, &b, seed)
    };
    let above = |text: &str, paper: bool, q: Quantity, a: Vec<Option<f64>>, b: Vec<Option<f64>>| {
        Claim::paired_above(text, paper, q, &a, &b, seed)
    };
    use Quantity as Q;
    let d_rises = above(
        "D rises: mean D in the last window above the first (learning)",
        true,
        Q::MeanD,
        last(Q::MeanD),
        first(Q::MeanD),
    );
    let collisions_fall = claim(
        "collisions fall: collisions per net metre in the last window below the first (learning)",
        true,
        Q::CollisionsPerNetM,
        last(Q::CollisionsPerNetM),
        first(Q::CollisionsPerNetM),
    );
    let held_part = claim(
        &format!(
            "part of keep exploring: held robot-steps in the last window below {KEEP_EXPLORING_MAX_HELD_PERCENT} % (learning)"
        ),
        false,
        Q::HeldPercent,
        last(Q::HeldPercent),
        vec![Some(KEEP_EXPLORING_MAX_HELD_PERCENT); n],
    );
    let walk_net = of(&walk, Q::NetMm, last_window);
    let explore_part = above(
        &format!(
            "part of keep exploring: net progress in the last window at least {KEEP_EXPLORING_FRACTION} of the random walk's (learning; below: {KEEP_EXPLORING_FRACTION} x the random walk's)"
        ),
        false,
        Q::NetMm,
        last(Q::NetMm),
        walk_net
            .iter()
            .map(|v| v.map(|v| KEEP_EXPLORING_FRACTION * v))
            .collect(),
    );
    let keep_exploring = Claim::all_of(&keep_exploring_text(), true, &[&held_part, &explore_part]);
    let mut out = vec![d_rises, collisions_fall, keep_exploring];
    let mut gap_parts = Vec::new();
    if corridor {
        let cv_part = claim(
            "part of the gaps even out: gap CV in the last window below the first (learning)",
            false,
            Q::GapCv,
            last(Q::GapCv),
            first(Q::GapCv),
        );
        let touch_part = claim(
            &format!(
                "part of the gaps even out: neighbours touch in under {GAPS_MAX_TOUCHING_PERCENT} % of the last window's steps (learning)"
            ),
            false,
            Q::TouchingPercent,
            last(Q::TouchingPercent),
            vec![Some(GAPS_MAX_TOUCHING_PERCENT); n],
        );
        out.push(Claim::all_of(
            &format!(
                "the gaps even out: gap CV in the last window below the first, neighbours touching in under {GAPS_MAX_TOUCHING_PERCENT} % of its steps (learning)"
            ),
            true,
            &[&cv_part, &touch_part],
        ));
        gap_parts = vec![cv_part, touch_part];
    }
    out.push(held_part);
    out.push(explore_part);
    out.extend(gap_parts);
    out.push(claim(
        "for reference: collisions per path metre in the last window below the first (learning; shuttling adds path)",
        false,
        Q::CollisionsPerM,
        last(Q::CollisionsPerM),
        first(Q::CollisionsPerM),
    ));
    for (others, name) in [(&off, "learning off"), (&walk, "the random walk")] {
        if others.is_empty() {
            continue;
        }
        out.push(claim(
            &format!("collisions per net metre in the last window: learning below {name}"),
            false,
            Q::CollisionsPerNetM,
            last(Q::CollisionsPerNetM),
            of(others, Q::CollisionsPerNetM, last_window),
        ));
        out.push(claim(
            &format!(
                "for reference: collisions per path metre in the last window: learning below {name}"
            ),
            false,
            Q::CollisionsPerM,
            last(Q::CollisionsPerM),
            of(others, Q::CollisionsPerM, last_window),
        ));
    }
    if !off.is_empty() {
        out.push(above(
            "mean D in the last window: learning above learning off",
            false,
            Q::MeanD,
            last(Q::MeanD),
            of(&off, Q::MeanD, last_window),
        ));
        out.push(above(
            "net progress in the last window: learning above learning off",
            false,
            Q::NetMm,
            last(Q::NetMm),
            of(&off, Q::NetMm, last_window),
        ));
        out.push(claim(
            "held robot-steps in the last window: learning below learning off",
            false,
            Q::HeldPercent,
            last(Q::HeldPercent),
            of(&off, Q::HeldPercent, last_window),
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
    use crate::experiment::{RunMetrics, StepMetrics};
    use crate::motion::RobotTally;

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

    #[test]
    fn a_claim_lists_its_values_in_the_order_its_words_name_them() {
        let q = Quantity::MeanD;
        let (hi, lo) = (constant(800.0, 5), constant(600.0, 5));
        // "hi above lo": the subject's value first, and it holds.
        let above = Claim::paired_above("x above y", true, q, &hi, &lo, 1);
        assert_eq!(above.values, [800.0, 600.0]);
        assert_eq!(above.intervals[0][0], Some(800.0));
        assert_eq!(above.outcome, Outcome::Holds);
        // The same comparison stated as "lo below hi" holds with lo's value first.
        let below = Claim::paired("y below x", true, q, &lo, &hi, 1);
        assert_eq!(below.values, [600.0, 800.0]);
        assert_eq!(below.outcome, Outcome::Holds);
        assert_eq!(above.repeats.for_, below.repeats.for_);
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

    /// Trajectory makers for three robots: where robot `i` is after step `k`.
    type Paths = dyn Fn(usize, u32) -> (f64, f64);

    /// A run of three robots whose centres follow `paths`, their steps classified by their
    /// trackers and summed as a swarm sums them; `collided(i, k)` says whether robot i collided
    /// in step k.
    fn run_along(
        c: Condition,
        repeat: u32,
        steps: u32,
        win: u32,
        paths: &Paths,
        collided: &dyn Fn(usize, u32) -> bool,
    ) -> RunOutput {
        use crate::motion::MotionTracker;
        let mut trackers = vec![MotionTracker::new(); 3];
        for (i, t) in trackers.iter_mut().enumerate() {
            let (x, y) = paths(i, 0);
            t.start(x, y);
        }
        let mut tallies = vec![RobotTally::new(win); 3];
        let mut m = RunMetrics::new(steps, win);
        for k in 0..steps {
            let moved: Vec<_> = trackers
                .iter_mut()
                .enumerate()
                .map(|(i, t)| {
                    let (x, y) = paths(i, k + 1);
                    t.record(x, y)
                })
                .collect();
            let mut step = StepMetrics {
                mean_d: 700.0,
                collisions_per_robot: (0..3).filter(|&i| collided(i, k)).count() as f64 / 3.0,
                energy_per_robot_mj: 3000.0,
                ..StepMetrics::default()
            };
            crate::experiment::motion_metrics(&mut step, &moved);
            for (i, s) in moved.iter().enumerate() {
                tallies[i].record(k, s, u64::from(collided(i, k)), k >= steps - win);
            }
            m.add(k, &step);
        }
        for (t, tr) in tallies.iter_mut().zip(&trackers) {
            t.finish(tr, steps - win);
        }
        RunOutput {
            robots: tallies,
            ..run_of(c, repeat, steps, win, |_| StepMetrics::default(), vec![])
        }
        .with_metrics(m)
    }

    impl RunOutput {
        fn with_metrics(mut self, m: RunMetrics) -> Self {
            self.metrics = m;
            self
        }
    }

    /// A robot driving round the 1.8 m arena's inside at 6 cm a step (a square of side 1.2 m
    /// from (0.3, 0.3)), started `phase` steps along it: it explores.
    fn patrol(phase: u32, k: u32) -> (f64, f64) {
        let s = (0.06 * f64::from(k + phase)) % 4.8;
        match s {
            s if s < 1.2 => (0.3 + s, 0.3),
            s if s < 2.4 => (1.5, 0.3 + s - 1.2),
            s if s < 3.6 => (1.5 - (s - 2.4), 1.5),
            s => (0.3, 1.5 - (s - 3.6)),
        }
    }

    /// A shuttler: two steps of 5 cm forward and two back, near (x, y).
    fn shuttle(x: f64, y: f64, k: u32) -> (f64, f64) {
        let along = [0.0, 1.0, 2.0, 1.0][(k % 4) as usize];
        (x + 0.05 * along, y)
    }

    /// Rocking 0.2–0.5 mm to either side of (x, y): steps of 0.4–1 mm, wedged in place.
    fn jitter(x: f64, y: f64, k: u32) -> (f64, f64) {
        let side = if k.is_multiple_of(2) { 1.0 } else { -1.0 };
        let off = side * (0.0002 + 0.0003 * f64::from((k * 7919) % 101) / 100.0);
        (x + off, y)
    }

    /// The robots that would cheat the old claims, run through the trackers. In the first
    /// window all three patrol the arena, colliding every 20th step; in the last, robot 0
    /// still patrols, colliding every 15th step (it learnt nothing), and the other two cheat:
    /// * jittering in place against a wall, they are never "stuck" (the old detector needs less
    ///   than 1 mm of path over 100 steps), so the old "keep moving" claim held at 0 % stuck;
    ///   the new claim sees 2/3 of the robot-steps held and fails;
    /// * shuttling without a collision, they are "moving" every step and add path, so collisions
    ///   per path metre fall (the old claim held); per net metre they rise, and the robots do not
    ///   keep exploring.
    #[test]
    fn the_robots_that_cheat_the_old_claims_fail_the_new_ones() {
        let (steps, win) = (1000u32, 300u32);
        let collided = |i: usize, k: u32| {
            if k < 500 {
                k.is_multiple_of(20)
            } else {
                i == 0 && k.is_multiple_of(15)
            }
        };
        let find = |cs: &[Claim], start: &str| -> Claim {
            cs.iter()
                .find(|c| c.claim.starts_with(start))
                .cloned()
                .unwrap()
        };
        for cheat in ["jitter", "shuttle"] {
            let paths = move |i: usize, k: u32| -> (f64, f64) {
                if i == 0 || k < 500 {
                    patrol(400 * i as u32, k)
                } else if cheat == "jitter" {
                    jitter(0.12, 0.3 + 0.6 * i as f64, k)
                } else {
                    shuttle(0.3, 0.3 + 0.6 * i as f64, k)
                }
            };
            let mut runs = Vec::new();
            for r in 0..5 {
                runs.push(run_along(
                    Condition::Learning,
                    r,
                    steps,
                    win,
                    &paths,
                    &collided,
                ));
                // The random walk's net progress: robots patrolling as robot 0 does.
                let walk = |i: usize, k: u32| patrol(100 + 400 * i as u32, k);
                runs.push(run_along(
                    Condition::RandomWalk,
                    r,
                    steps,
                    win,
                    &walk,
                    &|_, _| false,
                ));
            }
            let a = analyse(&runs, 3, steps, win, 1);
            let last = &a.conditions[0].last;
            let keep = find(&a.claims, "the robots keep exploring");
            assert_eq!(keep.outcome, Outcome::Fails, "{cheat}: {}", keep.verdict);
            if cheat == "jitter" {
                // The old definitions: no robot-step stuck, so "keep moving" held.
                let moved_per_step = last.moved_mm.mean;
                assert!(moved_per_step > 0.0);
                assert!(
                    (last.held_percent.mean - 200.0 / 3.0).abs() < 1.0,
                    "{last:?}"
                );
                let held = find(&a.claims, "part of keep exploring: held");
                assert_eq!(held.outcome, Outcome::Fails, "{}", held.verdict);
            } else {
                assert!(last.shuttling_percent.mean > 60.0, "{last:?}");
                // The old measure: collisions per path metre fall.
                let per_path = find(
                    &a.claims,
                    "for reference: collisions per path metre in the last window below the first",
                );
                assert_eq!(per_path.outcome, Outcome::Holds, "{}", per_path.verdict);
                // Per net metre they rise.
                let per_net = find(&a.claims, "collisions fall");
                assert_eq!(per_net.outcome, Outcome::Fails, "{}", per_net.verdict);
                assert!(
                    per_net.values[0] > per_net.values[1],
                    "{:?}",
                    per_net.values
                );
                let explore = find(&a.claims, "part of keep exploring: net progress");
                assert_eq!(explore.outcome, Outcome::Fails, "{}", explore.verdict);
            }
            // Robot by robot, the two cheaters end the run held (jitter) or not (shuttling);
            // either way the run's class shares add up.
            let l = &a.conditions[0].last;
            let sum = l.held_percent.mean
                + l.shuttling_percent.mean
                + l.circling_percent.mean
                + l.exploring_percent.mean;
            assert!((sum - 100.0).abs() < 1e-9);
            assert_eq!(
                a.conditions[0].robots.ending_held,
                if cheat == "jitter" { 10 } else { 0 }
            );
        }
        // Honest robots that keep patrolling hold both parts.
        let paths = |i: usize, k: u32| patrol(400 * i as u32, k);
        let mut runs = Vec::new();
        for r in 0..5 {
            runs.push(run_along(
                Condition::Learning,
                r,
                steps,
                win,
                &paths,
                &|_, _| false,
            ));
            let walk = |i: usize, k: u32| patrol(100 + 400 * i as u32, k);
            runs.push(run_along(
                Condition::RandomWalk,
                r,
                steps,
                win,
                &walk,
                &|_, _| false,
            ));
        }
        let keep = find(&claims(&runs, 3, 1), "the robots keep exploring");
        assert_eq!(keep.outcome, Outcome::Holds, "{}", keep.verdict);
        // Without a random walk it cannot be judged.
        let learning_only: Vec<RunOutput> = runs
            .into_iter()
            .filter(|r| r.condition == Condition::Learning)
            .collect();
        let keep = find(&claims(&learning_only, 3, 1), "the robots keep exploring");
        assert_eq!(keep.outcome, Outcome::Undecided, "{}", keep.verdict);
    }

    #[test]
    fn a_claim_of_parts_needs_every_part_in_the_same_repeat() {
        use Side::{Against, For, Tied, Undefined};
        assert_eq!(Side::all([For, For]), For);
        assert_eq!(Side::all([For, Against]), Against);
        assert_eq!(Side::all([Undefined, Against]), Against);
        assert_eq!(Side::all([For, Undefined]), Undefined);
        assert_eq!(Side::all([Tied, For]), Tied);
        let q = Quantity::MeanD;
        let some = |v: [f64; 5]| v.map(Some).to_vec();
        // Part a holds in repeats 0-3, part b in repeats 1-4: both in 1-3 only.
        let a = Claim::paired(
            "a",
            false,
            q,
            &some([1.0, 1.0, 1.0, 1.0, 9.0]),
            &some([5.0; 5]),
            1,
        );
        let b = Claim::paired(
            "b",
            false,
            q,
            &some([9.0, 1.0, 1.0, 1.0, 1.0]),
            &some([5.0; 5]),
            1,
        );
        let both = Claim::all_of("both", true, &[&a, &b]);
        assert_eq!((both.repeats.for_, both.repeats.against), (3, 2));
        assert_eq!(both.outcome, Outcome::Unsure);
        assert_eq!(both.values, [40.0, 60.0]);
        assert_eq!(both.parts, ["a", "b"]);
    }

    #[test]
    fn the_repeats_a_decision_needs_give_the_power_asked_for() {
        // Direct: P(X ≥ k | n, q) by the pmf's recursion, the critical k from sign_test_p.
        let power = |n: u32, q: f64| {
            let k = (0..=n)
                .find(|&k| sign_test_p(k, n) < SIGNIFICANCE)
                .unwrap_or(n + 1);
            let mut pmf = libm::pow(1.0 - q, f64::from(n));
            let mut tail = 0.0;
            for j in 0..=n {
                if j >= k {
                    tail += pmf;
                }
                pmf *= f64::from(n - j) / f64::from(j + 1) * q / (1.0 - q);
            }
            tail
        };
        for q in [0.6, 0.7, 0.8, 0.9, 0.95] {
            let n = repeats_needed(q).unwrap();
            assert!(power(n, q) >= POWER, "{q}: {n}");
            assert!(n == 1 || power(n - 1, q) < POWER, "{q}: {n}");
        }
        // All repeats one way: five decide (1/32 < 0.05).
        assert_eq!(repeats_needed(1.0), Some(5));
        assert_eq!(repeats_needed(0.5), None);
        assert_eq!(repeats_needed(0.3), None);
        // Past the exact range the normal approximation: q = 0.55 needs about 620.
        let n = repeats_needed(0.55).unwrap();
        assert!((560..700).contains(&n), "{n}");
        assert_eq!(repeats_needed(0.5001), None, "more than the most reported");
        // A claim's power: 32 of 50 for, 18 against (the default cell): about 100.
        let r = Paired {
            for_: 32,
            against: 18,
            tied: 0,
            undefined: 0,
            p: sign_test_p(32, 50),
            p_opposite: sign_test_p(18, 50),
        };
        let p = Power::of(&r);
        assert_eq!(p.towards, "holds");
        assert!((p.observed_share.unwrap() - 0.64).abs() < 1e-12);
        let n = p.repeats_needed.unwrap();
        assert_eq!(n, 80, "32 of 50: exact binomial sums give 80");
        // Ties and missing values scale it up.
        let p2 = Power::of(&Paired {
            tied: 25,
            undefined: 25,
            ..r
        });
        assert_eq!(p2.repeats_needed, Some((f64::from(n) * 2.0).ceil() as u32));
        // More against: the opposite's.
        let p3 = Power::of(&Paired {
            for_: 18,
            against: 32,
            ..r
        });
        assert_eq!((p3.towards, p3.repeats_needed), ("opposite", Some(n)));
    }

    fn ended(held: bool) -> RobotTally {
        use crate::motion::{MotionClass, MotionStep};
        let mut t = RobotTally::new(10);
        for k in 0..200 {
            let class = if held && k >= 100 {
                MotionClass::Held
            } else {
                MotionClass::Exploring
            };
            let m = MotionStep {
                class,
                step_m: 0.05,
                net_m: 0.05,
                sq_disp_m2: [None; 3],
                fresh_cells: 0,
                new_cells: 0,
            };
            t.record(k, &m, 0, false);
        }
        t.finish(&crate::motion::MotionTracker::new(), 100);
        t
    }

    /// Robot by robot: learning frees the robots held only with learning off, traps those
    /// held only with learning; McNemar on the two counts.
    #[test]
    fn pairings_count_freed_and_trapped_robots() {
        let step = |_| StepMetrics {
            moved_mm: 50.0,
            net_mm: 50.0,
            ..StepMetrics::default()
        };
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
            (p.robots, p.frees, p.traps, p.both_held, p.neither),
            (6, 3, 1, 1, 1)
        );
        assert!((p.p - mcnemar_p(3, 1)).abs() < 1e-15);
        let learning = &a.conditions[0].robots;
        assert_eq!((learning.robots, learning.ending_held), (6, 2));
        assert_eq!(learning.with_lasting_held_spell, 2);
        assert_eq!(learning.first_lasting_held_step_median, Some(100.0));
    }
}
