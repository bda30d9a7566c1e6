//! The text `h8swarm run` prints: what ran and how fast, the warnings, the battery lines, per
//! condition the first and last window, the robot-by-robot pairings, the claims, and the
//! robots that died or strayed.

use std::fmt::Write as _;

use swarm::experiment::RunOutput;
use swarm::scenario::Scenario;
use swarm::summary::{Analysis, Claim, Estimate};

/// The report's first lines: what ran, and how fast.
pub(crate) fn render_header(
    t: &mut String,
    s: &Scenario,
    conditions: usize,
    runs: usize,
    threads: usize,
    wall_s: f64,
) {
    let robot_steps = runs as f64 * f64::from(s.steps) * s.robots as f64;
    let simulated_s = runs as f64 * f64::from(s.steps) * s.timing.step_period_s;
    let _ = writeln!(
        t,
        "h8swarm run {}: {} robots, {} steps of {} s, {} x {} conditions, seed {}",
        s.name,
        s.robots,
        s.steps,
        s.timing.step_period_s,
        plural(s.repeats, "repeat"),
        conditions,
        s.seed
    );
    let _ = writeln!(
        t,
        "wall {:.1} s on {}: {:.0} robot-steps/s, {}x real time per run",
        wall_s,
        plural(u32::try_from(threads).unwrap_or(u32::MAX), "thread"),
        robot_steps / wall_s,
        factor_text(simulated_s / wall_s)
    );
}

/// A real-time factor with two significant digits below 10 (0.28, 3.1), whole above.
pub(crate) fn factor_text(f: f64) -> String {
    if f >= 10.0 {
        format!("{f:.0}")
    } else if f >= 1.0 {
        format!("{f:.1}")
    } else {
        format!("{f:.2}")
    }
}

/// What the run's shape makes unreliable, said on screen and in summary.json.
pub(crate) fn warnings(s: &Scenario) -> Vec<String> {
    let mut w = Vec::new();
    let windows = s.steps / s.window.max(1);
    if windows < 3 {
        w.push(format!(
            "the run has {windows} whole windows of {} steps: the curves' points are marked and are no trend (use more steps or a smaller window)",
            s.window
        ));
    }
    if s.repeats < 2 {
        w.push("one repeat: no intervals and no paired test (use --repeats 5 or more)".into());
    } else if s.repeats < 5 {
        w.push(format!(
            "{} repeats: a one-sided sign test needs at least 5 repeats all going one way to reach p < 0.05, so no claim can hold",
            s.repeats
        ));
    }
    if let Some(sym) = &s.controller.symbols
        && s.controller.image.is_none()
    {
        w.push(format!(
            "`controller.symbols` = {} is not used: it is the symbol table of `controller.image`, and {}",
            swarm::terminal_text::printable(sym),
            if s.controller.kind == swarm::scenario::ControllerKind::Model {
                "the robots run the Rust model (controller.kind = \"model\")"
            } else {
                "the robots run the built-in firmware"
            }
        ));
    }
    w
}

/// The battery lines of the summary: each condition's battery life in its first and last
/// windows, its mean current by part, and what learning costs or saves against the controls.
pub(crate) fn render_battery(t: &mut String, b: &swarm::battery::BatteryReport) {
    let _ = writeln!(t);
    let _ = writeln!(
        t,
        "battery life, {} x {} V NiMH of {:.0} mAh (the paper: up to {} h); a robot's mean current:",
        b.pack.cells, b.pack.cell_volts, b.pack.capacity_mah, b.paper_h
    );
    for (c, parts) in b.conditions.iter().zip(&b.by_part) {
        let _ = writeln!(
            t,
            "{:<14} {} h ({:.0} mA) -> {} h ({:.0} mA)",
            c.condition.name(),
            fmt_est(&c.first_h),
            c.first_current_ma,
            fmt_est(&c.last_h),
            c.last_current_ma
        );
        let list: Vec<String> = parts
            .current_ma
            .iter()
            .map(|(k, ma)| format!("{k} {ma:.1}"))
            .collect();
        let _ = writeln!(t, "{:<14} whole run, mA: {}", "", list.join(", "));
        let cap = parts.motor_cap;
        if cap.capped_wheel_substeps > 0 {
            let _ = writeln!(
                t,
                "{:<14} motor current cut to the drive voltage's bound in {} of {} driven wheel-sub-steps",
                "", cap.capped_wheel_substeps, cap.driven_wheel_substeps
            );
        }
    }
    for cmp in &b.learning_against {
        let _ = writeln!(
            t,
            "learning {} {:.1} % of battery life ({:+.2} h) against {} in the last window ({})",
            if cmp.change_h >= 0.0 {
                "saves"
            } else {
                "costs"
            },
            cmp.change_percent.abs(),
            cmp.change_h,
            cmp.against.name(),
            if cmp.apart {
                "energy intervals apart"
            } else {
                "energy intervals overlap"
            }
        );
    }
}

/// The printed tables: per condition the first and last window, the robots, the pairings and
/// the claims.
pub(crate) fn report(t: &mut String, s: &Scenario, a: &Analysis) {
    report_conditions(t, a);
    if s.repeats < 2 {
        let _ = writeln!(
            t,
            "(windows of {} steps; first -> last window; one repeat, so no intervals)",
            s.window
        );
    } else {
        let _ = writeln!(
            t,
            "(windows of {} steps; first -> last window, mean over repeats; [95 % interval: expanded percentile bootstrap over repeats])",
            s.window
        );
    }
    report_pairings(t, a);
    report_claims(t, a);
}

/// Per condition: the first and last window's measures, and the robots that ended held or
/// had a lasting held spell.
pub(crate) fn report_conditions(t: &mut String, a: &Analysis) {
    let _ = writeln!(
        t,
        "{:<14} {:>26} {:>26} {:>26}",
        "condition", "D (du)", "collisions per robot", "collisions per net metre"
    );
    let arrow = |f: &Estimate, l: &Estimate| format!("{} -> {}", fmt_mean(f), fmt_mean(l));
    for c in &a.conditions {
        let (f, l) = (&c.first, &c.last);
        let _ = writeln!(
            t,
            "{:<14} {:>26} {:>26} {:>26}",
            c.condition.name(),
            arrow(&f.mean_d, &l.mean_d),
            arrow(&f.collisions_per_robot, &l.collisions_per_robot),
            arrow(&f.collisions_per_net_m, &l.collisions_per_net_m),
        );
        let _ = writeln!(
            t,
            "{:<14} last window: D {}, collisions per net metre {} (per path metre {})",
            "",
            fmt_est(&l.mean_d),
            fmt_est(&l.collisions_per_net_m),
            fmt_est(&l.collisions_per_m)
        );
        let _ = writeln!(
            t,
            "{:<14} held {} -> {} %; shuttling {} -> {} %; circling {} -> {} %; exploring {} -> {} %",
            "",
            fmt_mean(&f.held_percent),
            fmt_est(&l.held_percent),
            fmt_mean(&f.shuttling_percent),
            fmt_mean(&l.shuttling_percent),
            fmt_mean(&f.circling_percent),
            fmt_mean(&l.circling_percent),
            fmt_mean(&f.exploring_percent),
            fmt_mean(&l.exploring_percent),
        );
        let _ = writeln!(
            t,
            "{:<14} net progress {} -> {} mm per step of {} -> {} mm path; MSD exponent {} -> {}; fresh cells per 100 steps {} -> {}",
            "",
            fmt_mean(&f.net_mm),
            fmt_est(&l.net_mm),
            fmt_mean(&f.moved_mm),
            fmt_mean(&l.moved_mm),
            fmt_mean(&f.msd_exponent),
            fmt_mean(&l.msd_exponent),
            fmt_mean(&f.fresh_cells_per_100_steps),
            fmt_mean(&l.fresh_cells_per_100_steps),
        );
        let _ = writeln!(
            t,
            "{:<14} contact {} -> {} %; moving (5 mm a step, a reference) {} -> {} %",
            "",
            fmt_mean(&f.contact_percent),
            fmt_est(&l.contact_percent),
            fmt_mean(&f.moving_percent),
            fmt_mean(&l.moving_percent),
        );
        if let (Some(fg), Some(lg)) = (&f.gap_cv, &l.gap_cv) {
            let touching = match (&f.touching_percent, &l.touching_percent) {
                (Some(ft), Some(lt)) => format!(
                    "; neighbours touching {} -> {} % of steps",
                    fmt_mean(ft),
                    fmt_mean(lt)
                ),
                _ => String::new(),
            };
            let _ = writeln!(
                t,
                "{:<14} gap CV {} -> {} (over the steps no neighbours touch){touching}",
                "",
                fmt_mean(fg),
                fmt_est(lg)
            );
        }
        let r = &c.robots;
        let onset = r
            .first_lasting_held_step_median
            .map_or_else(String::new, |m| format!(", median onset step {m:.0}"));
        let _ = writeln!(
            t,
            "{:<14} robots ending the run held {} of {} ({} %); a lasting held spell: {} of {}{onset}",
            "",
            r.ending_held,
            r.robots,
            fmt_est(&r.ending_held_percent),
            r.with_lasting_held_spell,
            r.robots,
        );
    }
}

/// Robot by robot, learning against each control: the robots it frees and traps.
pub(crate) fn report_pairings(t: &mut String, a: &Analysis) {
    for p in &a.pairings {
        let _ = writeln!(
            t,
            "robot by robot against {}: learning frees {} and traps {} of {} robots held at the end, leaves {} alone ({} held under both, {} under neither); McNemar exact p = {}",
            p.other.name(),
            p.frees,
            p.traps,
            p.robots,
            p.both_held + p.neither,
            p.both_held,
            p.neither,
            swarm::summary::fmt_p(p.p)
        );
    }
}

/// The paper's claims, then those against the controls it lacks, and how many of its text
/// claims hold together.
pub(crate) fn report_claims(t: &mut String, a: &Analysis) {
    let _ = writeln!(t);
    let _ = writeln!(
        t,
        "The paper's claims (learning, paired by repeat, one-sided sign test at p < 0.05):"
    );
    for c in a.claims.iter().filter(|c| c.paper) {
        claim_line(t, c);
    }
    let _ = writeln!(
        t,
        "Their parts, against the controls the paper lacks, and for reference:"
    );
    for c in a.claims.iter().filter(|c| !c.paper) {
        claim_line(t, c);
    }
    let paper: Vec<&Claim> = a.claims.iter().filter(|c| c.paper).collect();
    let held = paper
        .iter()
        .filter(|c| c.outcome == swarm::summary::Outcome::Holds)
        .count();
    let _ = writeln!(
        t,
        "{held} of the paper's {} text claims hold together here{}",
        paper.len(),
        if held == paper.len() {
            ""
        } else {
            " (see docs/claims.md for where they do)"
        }
    );
    // The repeats that would decide every text claim at the effects seen here: what the
    // default run's repeat count is chosen from (docs/claims.md).
    let undecidable: Vec<&str> = paper
        .iter()
        .filter(|c| c.power.repeats_needed.is_none())
        .map(|c| c.claim.split(':').next().unwrap_or(&c.claim))
        .collect();
    let most = paper.iter().filter_map(|c| c.power.repeats_needed).max();
    match (most, undecidable.is_empty()) {
        (Some(n), true) => {
            let _ = writeln!(
                t,
                "at the effects seen here, about {n} repeats would decide every text claim (80 % power each)"
            );
        }
        (_, false) => {
            let _ = writeln!(
                t,
                "no number of repeats decides {} at the effect seen here{}",
                undecidable.join(", "),
                most.map_or_else(String::new, |n| format!(
                    "; the others need about {n} repeats"
                ))
            );
        }
        (None, true) => {}
    }
}

/// One claim's line: its outcome, its words, the values compared (or, for a claim of parts,
/// the repeats that meet all of them), the verdict and what a decision would take.
pub(crate) fn claim_line(t: &mut String, c: &Claim) {
    let values = if c.parts.is_empty() {
        format!(
            "{} vs {} {}",
            fmt_value(c.values[0]),
            fmt_value(c.values[1]),
            c.unit
        )
    } else {
        let r = &c.repeats;
        format!(
            "{} of {} meet all its parts",
            r.for_,
            plural(r.for_ + r.against + r.tied + r.undefined, "repeat")
        )
    };
    let _ = writeln!(
        t,
        "{:<9} {} ({values}: {}; {})",
        c.outcome.word(),
        c.claim,
        c.verdict,
        c.power.words()
    );
}

/// One line per robot that died and per stack warning, run by run; one per robot and
/// address its chip does not model, for the first run that touched it.
pub(crate) fn render_failures(t: &mut String, runs: &[RunOutput]) {
    let mut io_seen = std::collections::BTreeSet::new();
    for r in runs {
        for (i, what) in &r.io_warnings {
            if io_seen.insert((*i, what.clone())) {
                let _ = writeln!(
                    t,
                    "IO    robot {i} in {} repeat {}: {what}",
                    r.condition.name(),
                    r.repeat
                );
            }
        }
        for d in &r.dead {
            let _ = writeln!(
                t,
                "DEAD  robot {} in {} repeat {} (from step {}): {}",
                d.robot,
                r.condition.name(),
                r.repeat,
                d.step,
                d.why
            );
        }
        for (i, fault) in &r.stack_warnings {
            let _ = writeln!(
                t,
                "STACK robot {i} in {} repeat {}: {fault}",
                r.condition.name(),
                r.repeat
            );
        }
    }
}

pub(crate) fn fmt_value(v: f64) -> String {
    if v.is_nan() {
        "none".to_string()
    } else {
        format!("{v:.2}")
    }
}

pub(crate) fn fmt_mean(e: &Estimate) -> String {
    if e.mean.is_nan() {
        "none".to_string()
    } else {
        format!("{:.2}", e.mean)
    }
}

pub(crate) fn fmt_est(e: &Estimate) -> String {
    match (e.lo, e.hi) {
        _ if e.mean.is_nan() => "none".to_string(),
        (Some(lo), Some(hi)) => format!("{:.2} [{:.2}, {:.2}]", e.mean, lo, hi),
        _ => format!("{:.2}", e.mean),
    }
}

/// `n` and the noun, plural when `n` is not 1.
pub(crate) fn plural(n: u32, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}
