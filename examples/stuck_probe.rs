//! What a held robot senses, evaluates and chooses: runs the learning and learning-off
//! conditions of a scenario with model robots and, for every robot-step of the last window,
//! records whether the robot is held in place (`swarm::motion`'s class: its positions over 100
//! steps within 5 cm of their mean, or under 2 cm of path over 20 steps), its four proximities p
//! (du), E = D(t) − D(t−1) (the evaluation the learner applies at this step), the winning
//! behaviour, the winner's margin over the runner-up in the outputs O, and which bumper is
//! pressed. Prints the means over held and over free robot-steps, and how held spells end and
//! how long they last over the whole run (a spell counted from the step the class first says
//! held). (The file keeps its name from the earlier "stuck" detector it was written for.)
//!
//!     cargo run --release --example stuck_probe [arena|corridor|FILE.toml] [REPEATS] [SEED]

// A test, example or bench may use the host's f64 functions (clippy.toml): it checks the
// models within tolerances, and its own output is not a promised result.
#![allow(clippy::disallowed_methods)]

use nn_q15::DynLearner;
use swarm::experiment::Swarm;
use swarm::motion::{MotionClass, MotionTracker};
use swarm::robot::{Brain, Condition};
use swarm::scenario::Scenario;

#[derive(Default)]
struct Tally {
    n: u64,
    win: [u64; 4],
    p: [f64; 4],
    e_abs_over_t: u64,
    reward: u64,
    punish: u64,
    margin: f64,
    bumper: [u64; 4],
    any_bumper: u64,
}

impl Tally {
    fn add(&mut self, s: &Sample, threshold: i32) {
        self.n += 1;
        self.win[s.win] += 1;
        for k in 0..4 {
            self.p[k] += f64::from(s.p[k]);
            self.bumper[k] += u64::from(s.bumpers[k]);
        }
        self.any_bumper += u64::from(s.bumpers.iter().any(|&b| b));
        let e = i32::from(s.e);
        self.e_abs_over_t += u64::from(e.abs() > threshold);
        self.reward += u64::from(e > threshold);
        self.punish += u64::from(e < -threshold);
        self.margin += f64::from(s.margin);
    }

    fn print(&self, what: &str) {
        let n = self.n.max(1) as f64;
        let pc = |x: u64| 100.0 * x as f64 / n;
        println!(
            "| {what} | {} | {:.0} / {:.0} / {:.0} / {:.0} % | {:.0} / {:.0} / {:.0} / {:.0} | {:.0} % ({:.0} % reward, {:.0} % punish) | {:.0} | {:.0} % (front {:.0}, rear {:.0}, left {:.0}, right {:.0} %) |",
            self.n,
            pc(self.win[0]),
            pc(self.win[1]),
            pc(self.win[2]),
            pc(self.win[3]),
            self.p[0] / n,
            self.p[1] / n,
            self.p[2] / n,
            self.p[3] / n,
            pc(self.e_abs_over_t),
            pc(self.reward),
            pc(self.punish),
            self.margin / n,
            pc(self.any_bumper),
            pc(self.bumper[0]),
            pc(self.bumper[1]),
            pc(self.bumper[2]),
            pc(self.bumper[3]),
        );
    }
}

struct Sample {
    win: usize,
    p: [i16; 4],
    e: i16,
    margin: i32,
    bumpers: [bool; 4],
}

/// What one condition's runs gathered.
#[derive(Default)]
struct Gathered {
    stuck: Tally,
    moving: Tally,
    /// Stuck spells that ended in the last window.
    spells_ended: u64,
    /// Stuck spells lasting to the end.
    spells_to_end: u64,
    /// The behaviour that ended each of `spells_ended`.
    ended_by: [u64; 4],
    /// Every stuck spell of the whole run: its length in steps (counted from the step the
    /// detector first flags it) and whether it ended before the run did.
    spells: Vec<(u32, bool)>,
}

/// What a learner senses and chooses: its four proximities p (du), the winning behaviour, and
/// the winner's margin over the runner-up in the outputs O.
fn choice(l: &DynLearner) -> ([i16; 4], usize, i32) {
    let x = l.inputs();
    let p: [i16; 4] = std::array::from_fn(|k| i16::from(x[k].to_bits()) + 128);
    let o: Vec<i32> = l.outputs().iter().map(|v| i32::from(v.to_bits())).collect();
    let mut win = 0;
    for (j, &v) in o.iter().enumerate() {
        if v > o[win] {
            win = j;
        }
    }
    let second = o
        .iter()
        .enumerate()
        .filter(|&(j, _)| j != win)
        .map(|(_, &v)| v)
        .max()
        .unwrap_or(o[win]);
    (p, win, o[win] - second)
}

/// Runs repeat `repeat` of `condition` and adds its robot-steps to `g`.
fn run_repeat(
    s: &Scenario,
    condition: Condition,
    repeat: u32,
    last_from: u32,
    g: &mut Gathered,
) -> anyhow::Result<()> {
    let threshold = s.learner.threshold;
    let mut sw = Swarm::new(s, condition, repeat, false, None)?;
    let n = s.robots;
    let mut det = vec![MotionTracker::new(); n];
    let mut was_stuck = vec![false; n];
    for (i, d) in det.iter_mut().enumerate() {
        let p = sw.world().pose(i)?;
        d.start(p.x_m, p.y_m);
    }
    let mut d_prev = vec![None::<i16>; n];
    let mut prev_win = vec![0usize; n];
    let mut since = vec![0u32; n];
    for step in 0..s.steps {
        sw.step()?;
        for i in 0..n {
            let pose = sw.world().pose(i)?;
            let is_stuck = det[i].record(pose.x_m, pose.y_m).class == MotionClass::Held;
            let bumpers = sw.world().bumpers(i)?;
            let Some(robot) = sw.robot_mut(i) else {
                continue;
            };
            let Brain::Model(c) = &robot.brain else {
                anyhow::bail!("the probe reads model robots only");
            };
            let (p, win, margin) = choice(c.learner());
            let d: i16 = p.iter().sum();
            let e = d_prev[i].map_or(0, |dp| d - dp);
            d_prev[i] = Some(d);
            if step >= last_from {
                let sample = Sample {
                    win,
                    p,
                    e,
                    margin,
                    bumpers,
                };
                if is_stuck {
                    g.stuck.add(&sample, threshold);
                } else {
                    g.moving.add(&sample, threshold);
                }
                if was_stuck[i] && !is_stuck {
                    // The move that ended it ran the behaviour chosen a step ago.
                    g.spells_ended += 1;
                    g.ended_by[prev_win[i]] += 1;
                }
            }
            if is_stuck && !was_stuck[i] {
                since[i] = step;
            }
            if was_stuck[i] && !is_stuck {
                g.spells.push((step - since[i], true));
            }
            was_stuck[i] = is_stuck;
            prev_win[i] = win;
        }
    }
    g.spells_to_end += was_stuck.iter().filter(|&&b| b).count() as u64;
    for i in 0..n {
        if was_stuck[i] {
            g.spells.push((s.steps - since[i], false));
        }
    }
    Ok(())
}

/// Prints what `condition`'s runs gathered, `runs` the robot-runs (repeats × robots).
fn print_gathered(condition: Condition, runs: usize, g: &Gathered) {
    g.stuck.print(&format!("{}, held", condition.name()));
    g.moving.print(&format!("{}, not held", condition.name()));
    println!(
        "|  {}: held spells ended in the last window {} (the behaviour then: fwd {}, back {}, left {}, right {}); robots held at the end {} of {} |",
        condition.name(),
        g.spells_ended,
        g.ended_by[0],
        g.ended_by[1],
        g.ended_by[2],
        g.ended_by[3],
        g.spells_to_end,
        runs
    );
    let spells = &g.spells;
    let mut ended: Vec<u32> = spells.iter().filter(|x| x.1).map(|x| x.0).collect();
    ended.sort_unstable();
    let total: u64 = spells.iter().map(|x| u64::from(x.0)).sum();
    let long: u64 = spells
        .iter()
        .filter(|x| x.0 >= 1000)
        .map(|x| u64::from(x.0))
        .sum();
    println!(
        "|  {}: whole run: {} held spells, {} ended (median length {} steps, 90th percentile {}), {} lasted to the end; spells of 1 000 steps or more hold {:.0} % of the held robot-steps |",
        condition.name(),
        spells.len(),
        ended.len(),
        ended.get(ended.len() / 2).copied().unwrap_or(0),
        ended.get(ended.len() * 9 / 10).copied().unwrap_or(0),
        spells.len() - ended.len(),
        100.0 * long as f64 / total.max(1) as f64
    );
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let mut s = Scenario::load(&args.next().unwrap_or_else(|| "arena".into()))?;
    let repeats: u32 = args.next().map_or(Ok(5), |a| a.parse())?;
    if let Some(seed) = args.next() {
        s.seed = seed.parse()?;
    }
    let threshold = s.learner.threshold;
    let last_from = s.steps.saturating_sub(s.window);
    println!(
        "{}: {} robots, {} steps, last window from step {last_from}, {repeats} repeats, seed {}, T = {threshold} du",
        s.name, s.robots, s.steps, s.seed
    );
    println!(
        "| condition, robot-steps | n | winner fwd / back / left / right | p front / rear / left / right (du) | abs(E) > T | margin O_win − O_2nd (Q15) | bumper pressed |"
    );
    println!("|---|---:|---|---|---|---:|---|");
    for condition in [Condition::Learning, Condition::LearningOff] {
        let mut g = Gathered::default();
        for repeat in 0..repeats {
            run_repeat(&s, condition, repeat, last_from, &mut g)?;
        }
        print_gathered(condition, repeats as usize * s.robots, &g);
    }
    Ok(())
}
