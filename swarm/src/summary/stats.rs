//! The statistics under every claim: estimates over repeats with their bootstrap intervals,
//! the exact sign and McNemar tests, and the repeats a decision would need (power).
//!
//! * **Intervals**: the mean over repeats with the *expanded percentile bootstrap* interval
//!   ([`Estimate::of`]): seeded resamples of the repeats, their means' percentiles at a tail
//!   widened for small samples. Such an interval never leaves the range of the repeats'
//!   values, so a share stays in 0–100 %, a count at or above 0.
//! * **Paired comparisons**: learning, learning off and the random walk of one repeat share
//!   the placement (and learning and learning off the initial weights), so every claim compares
//!   them repeat by repeat with an exact one-sided sign test ([`Paired`]); a claim of parts
//!   counts a repeat for it only when every part goes its way ([`Side::all`]); robot by robot,
//!   which robots end the run held under each condition is compared with McNemar's exact test
//!   ([`super::Pairing`]).
//! * **Power**: every claim says how many repeats a decision would need at the effect it shows
//!   ([`Power`], [`repeats_needed`]).

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, Normal, StudentsT};

/// Resamples of every bootstrap interval.
pub const BOOTSTRAP_RESAMPLES: usize = 10_000;

/// The level of every test: a claim holds when its one-sided p-value is below it.
pub const SIGNIFICANCE: f64 = 0.05;

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
pub(super) fn ln_choose(n: u32, j: u32) -> f64 {
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
pub(super) const EXACT_POWER_UP_TO: u32 = 400;

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
pub(super) fn binomial_tail(k: u32, n: u32, q: f64) -> f64 {
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

/// A p-value with three significant digits (`< 0.001` below that).
#[must_use]
pub fn fmt_p(p: f64) -> String {
    if p < 0.001 {
        "< 0.001".to_string()
    } else {
        format!("{p:.3}")
    }
}
