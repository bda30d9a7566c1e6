//! The paper's claims and their parts, judged repeat by repeat on the window statistics
//! (the reasoning is in `docs/claims.md`).
//!
//! * **Claims** are judged on quantities a robot held in place, shuttling or circling cannot
//!   satisfy ([`crate::motion`]): the held share, net progress against the random walk's, and
//!   collisions per net metre; collisions per path metre and the raw collision count are kept
//!   as references.

use super::quantities::{Quantity, first_window, last_window, per_repeat, runs_of};
use super::stats::{Estimate, Paired, Power, SIGNIFICANCE, Side, fmt_p, sides};
use crate::experiment::{RunOutput, WindowSums};
use crate::robot::Condition;
use serde::Serialize;

/// "The robots keep exploring": at most this share of the last window's robot-steps held,
/// percent (the reasoning is in `docs/claims.md`).
pub const KEEP_EXPLORING_MAX_HELD_PERCENT: f64 = 10.0;

/// "The robots keep exploring": the learning robots' net progress in the last window at
/// least this fraction of the random walk's (same repeat, same placement).
pub const KEEP_EXPLORING_FRACTION: f64 = 0.5;

/// "The gaps even out": neighbours touch in under this share of the last window's steps,
/// percent (a jam has no spacing to judge).
pub const GAPS_MAX_TOUCHING_PERCENT: f64 = 50.0;

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
pub(super) fn verdict_of(r: &Paired) -> (Outcome, String) {
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
