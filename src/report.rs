//! The text `h8swarm run` prints: what ran and how fast, the warnings, the battery lines, per
//! condition the first and last window, the robot-by-robot pairings, the claims, and the
//! robots that died or strayed.

use std::fmt::Write as _;

use swarm::experiment::RunOutput;
use swarm::runner::Analysed;
use swarm::scenario::Scenario;
use swarm::summary::{Analysis, Claim, Estimate};

/// The report of a run on `threads` threads: what ran and how fast, the warnings, the battery
/// lines, the tables and the claims, the robots that died or strayed, the fit verdict.
#[must_use]
pub fn render(s: &Scenario, r: &Analysed, threads: usize) -> String {
    let mut t = String::new();
    render_header(
        &mut t,
        s,
        r.conditions.len(),
        r.runs.len(),
        threads,
        r.wall_s,
    );
    for w in &r.warnings {
        let _ = writeln!(t, "WARNING {w}");
    }
    render_solver(&mut t, s, &r.runs);
    render_battery(&mut t, &r.battery);
    let _ = writeln!(t);
    report(&mut t, s, &r.analysis);
    render_failures(&mut t, &r.runs);
    let _ = writeln!(t);
    let _ = writeln!(t, "fit: {}", r.fit.verdict);
    t
}

/// The report's first lines: what ran, and how fast.
fn render_header(
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

/// The contact solver's line: the islands solved over every run, their sweeps, and how many
/// the sweep cap (`world.solver`) stopped before they converged.
fn render_solver(t: &mut String, s: &Scenario, runs: &[RunOutput]) {
    let (mut islands, mut sweeps, mut capped) = (0u64, 0u64, 0u64);
    let (mut newton, mut steps) = (0u64, 0u64);
    for r in runs {
        islands += r.solver.islands;
        sweeps += r.solver.solver_sweeps;
        capped += r.solver.capped_islands;
        newton += r.solver.newton_islands;
        steps += r.solver.newton_steps;
    }
    if islands == 0 {
        let _ = writeln!(
            t,
            "contact solver: no robot touched a wall or another robot"
        );
        return;
    }
    if s.world.solver == swarm::scenario::SolverKind::Newton {
        let swept = islands - newton;
        let _ = writeln!(
            t,
            "contact solver (world.solver = \"newton\"): {islands} islands solved, {newton} by Newton's method ({:.1} steps each), {swept} larger by sweeps ({:.1} each); {capped} ({:.2} %) stopped at a cap ({} outer iterations, {} sweeps) before converging",
            steps as f64 / newton.max(1) as f64,
            sweeps as f64 / swept.max(1) as f64,
            100.0 * capped as f64 / islands as f64,
            world::params::NEWTON_MAX_OUTER,
            s.world.solver.params().0
        );
        return;
    }
    let _ = writeln!(
        t,
        "contact solver (world.solver = \"{}\"): {islands} islands solved, {:.1} sweeps each; {capped} ({:.2} %) stopped at the cap of {} sweeps before converging",
        s.world.solver.name(),
        sweeps as f64 / islands as f64,
        100.0 * capped as f64 / islands as f64,
        s.world.solver.params().0
    );
}

/// A real-time factor with two significant digits below 10 (0.28, 3.1), whole above.
fn factor_text(f: f64) -> String {
    if f >= 10.0 {
        format!("{f:.0}")
    } else if f >= 1.0 {
        format!("{f:.1}")
    } else {
        format!("{f:.2}")
    }
}

/// The battery lines of the summary: each condition's battery life in its first and last
/// windows, its mean current by part, and what learning costs or saves against the controls.
fn render_battery(t: &mut String, b: &swarm::battery::BatteryReport) {
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
fn report(t: &mut String, s: &Scenario, a: &Analysis) {
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
fn report_conditions(t: &mut String, a: &Analysis) {
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
fn report_pairings(t: &mut String, a: &Analysis) {
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
fn report_claims(t: &mut String, a: &Analysis) {
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
fn claim_line(t: &mut String, c: &Claim) {
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
fn render_failures(t: &mut String, runs: &[RunOutput]) {
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

fn fmt_value(v: f64) -> String {
    if v.is_nan() {
        "none".to_string()
    } else {
        format!("{v:.2}")
    }
}

fn fmt_mean(e: &Estimate) -> String {
    if e.mean.is_nan() {
        "none".to_string()
    } else {
        format!("{:.2}", e.mean)
    }
}

fn fmt_est(e: &Estimate) -> String {
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
