use super::*;
use crate::experiment::RunOutput;
use crate::experiment::{RunMetrics, StepMetrics};
use crate::motion::RobotTally;
use crate::robot::Condition;

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
        solver: world::SolverStats::default(),
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
