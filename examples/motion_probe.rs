//! Where the robots go, by the new classes and by the old definitions: runs a scenario's
//! three conditions with model robots and, for every robot-step of the last window, tracks each
//! robot with `swarm::motion::MotionTracker` and with the definitions it replaced (*moving*:
//! at least 5 mm in the step; *stuck*: less than 1 mm of path over 100 steps). Prints, per
//! condition, the new classes against the old labels (% of the last window's robot-steps),
//! how the held steps were caught (the disc over 100 steps, the still path over 20, both), the
//! distribution of the straightness (net displacement over 20 steps over the path), and per
//! robot of the last window its class shares, reversals and straightness: the numbers the
//! classifier's thresholds are argued from (docs/claims.md).
//!
//!     cargo run --release --example motion_probe [arena|corridor|FILE.toml] [REPEATS] [SEED]

use std::collections::VecDeque;

use swarm::experiment::Swarm;
use swarm::motion::{
    HELD_RADIUS_M, HELD_STEPS, LAG_STEPS, MotionClass, MotionTracker, REVERSAL_STEP_MIN_M,
    STILL_PATH_M,
};
use swarm::robot::Condition;
use swarm::scenario::Scenario;

/// One robot's recent positions, for the old definitions and the probe's own measures.
#[derive(Default)]
struct Recent {
    pos: VecDeque<(f64, f64)>,
}

impl Recent {
    fn push(&mut self, p: (f64, f64)) {
        self.pos.push_back(p);
        if self.pos.len() > HELD_STEPS + 1 {
            self.pos.pop_front();
        }
    }

    /// Path of the last `n` steps.
    fn path(&self, n: usize) -> f64 {
        let k = self.pos.len();
        (k.saturating_sub(n + 1)..k.saturating_sub(1))
            .map(|i| dist(self.pos[i], self.pos[i + 1]))
            .sum()
    }

    /// Net displacement over the last `n` steps.
    fn net(&self, n: usize) -> f64 {
        let k = self.pos.len();
        dist(self.pos[k - 1], self.pos[k.saturating_sub(n + 1)])
    }

    /// Whether the last 101 positions lie within the held radius of their mean.
    fn in_disc(&self) -> bool {
        if self.pos.len() < HELD_STEPS + 1 {
            return false;
        }
        let n = self.pos.len() as f64;
        let (sx, sy) = self
            .pos
            .iter()
            .fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
        let m = (sx / n, sy / n);
        self.pos.iter().all(|&p| dist(p, m) <= HELD_RADIUS_M)
    }
}

/// Whether the latest step reverses the last one that moved at least
/// [`REVERSAL_STEP_MIN_M`] (as the tracker counts reversals), remembering its direction.
fn reversed(r: &Recent, last: &mut Option<(f64, f64)>) -> bool {
    let k = r.pos.len();
    if k < 2 {
        return false;
    }
    let d = (
        r.pos[k - 1].0 - r.pos[k - 2].0,
        r.pos[k - 1].1 - r.pos[k - 2].1,
    );
    if libm::hypot(d.0, d.1) < REVERSAL_STEP_MIN_M {
        return false;
    }
    let rev = last.is_some_and(|h| h.0 * d.0 + h.1 * d.1 < 0.0);
    *last = Some(d);
    rev
}

fn dist(a: (f64, f64), b: (f64, f64)) -> f64 {
    libm::hypot(a.0 - b.0, a.1 - b.1)
}

/// What one condition's last windows gathered.
#[derive(Default)]
struct Gathered {
    steps: u64,
    /// [old label: stuck, moving, neither][new class code].
    cross: [[u64; 4]; 3],
    /// Held steps caught by the disc only, the still path only, both.
    held_by: [u64; 3],
    /// Straightness over 20 steps in tenths (the last bin: 0.9 and more), of the steps not
    /// held.
    straight: [u64; 10],
    /// Per robot: class steps, reversals between consecutive steps, mean straightness of its
    /// steps not held.
    robots: Vec<([u32; 4], u32, f64)>,
}

fn run(s: &Scenario, c: Condition, repeat: u32, g: &mut Gathered) -> anyhow::Result<()> {
    let mut sw = Swarm::new(s, c, repeat, false, None)?;
    let n = s.robots;
    let last_from = s.steps.saturating_sub(s.window);
    let mut trackers = vec![MotionTracker::new(); n];
    let mut recent: Vec<Recent> = (0..n).map(|_| Recent::default()).collect();
    let mut per_robot = vec![([0u32; 4], 0u32, 0.0f64); n];
    let mut headings = vec![None; n];
    for (i, t) in trackers.iter_mut().enumerate() {
        let p = sw.world().pose(i)?;
        t.start(p.x_m, p.y_m);
        recent[i].push((p.x_m, p.y_m));
    }
    for k in 0..s.steps {
        sw.step()?;
        for i in 0..n {
            let p = sw.world().pose(i)?;
            let m = trackers[i].record(p.x_m, p.y_m);
            let r = &mut recent[i];
            r.push((p.x_m, p.y_m));
            let rev = reversed(r, &mut headings[i]);
            if k < last_from {
                continue;
            }
            let old_stuck = r.pos.len() > HELD_STEPS && r.path(HELD_STEPS) < 0.001;
            let old = if old_stuck {
                0
            } else if m.step_m * 1000.0 >= swarm::collisions::MOVING_MIN_MM {
                1
            } else {
                2
            };
            g.steps += 1;
            g.cross[old][m.class.code() as usize] += 1;
            if m.class == MotionClass::Held {
                let (disc, still) = (r.in_disc(), r.path(LAG_STEPS) < STILL_PATH_M);
                g.held_by[match (disc, still) {
                    (true, false) => 0,
                    (false, true) => 1,
                    _ => 2,
                }] += 1;
            }
            let pr = &mut per_robot[i];
            pr.0[m.class.code() as usize] += 1;
            pr.1 += u32::from(rev);
            if m.class != MotionClass::Held {
                let straight = r.net(LAG_STEPS) / r.path(LAG_STEPS);
                g.straight[((straight * 10.0) as usize).min(9)] += 1;
                pr.2 += straight;
            }
        }
    }
    for pr in &mut per_robot {
        let moving = pr.0.iter().take(3).sum::<u32>();
        pr.2 = if moving > 0 {
            pr.2 / f64::from(moving)
        } else {
            f64::NAN
        };
    }
    g.robots.extend(per_robot);
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let mut s = Scenario::load(&args.next().unwrap_or_else(|| "arena".into()))?;
    let repeats: u32 = args.next().map_or(Ok(5), |a| a.parse())?;
    if let Some(seed) = args.next() {
        s.seed = seed.parse()?;
    }
    println!(
        "{}: {} robots, {} steps, last window of {} steps, {repeats} repeats, seed {}",
        s.name, s.robots, s.steps, s.window, s.seed
    );
    for c in Condition::ALL {
        let mut g = Gathered::default();
        for r in 0..repeats {
            run(&s, c, r, &mut g)?;
        }
        let pc = |x: u64| 100.0 * x as f64 / g.steps.max(1) as f64;
        println!(
            "\n{} ({} robot-steps of the last windows)",
            c.name(),
            g.steps
        );
        println!("| old label | exploring | shuttling | circling | held |");
        println!("|---|---:|---:|---:|---:|");
        for (o, name) in [
            "stuck (< 1 mm over 100 steps)",
            "moving (>= 5 mm)",
            "neither",
        ]
        .iter()
        .enumerate()
        {
            let row = g.cross[o];
            println!(
                "| {name} | {:.1} % | {:.1} % | {:.1} % | {:.1} % |",
                pc(row[0]),
                pc(row[1]),
                pc(row[2]),
                pc(row[3])
            );
        }
        println!(
            "held caught by the disc only {:.1} %, the still path only {:.1} %, both {:.1} % (of all robot-steps)",
            pc(g.held_by[0]),
            pc(g.held_by[1]),
            pc(g.held_by[2])
        );
        let moving: u64 = g.straight.iter().sum();
        let bins: Vec<String> = g
            .straight
            .iter()
            .map(|&b| format!("{:.0}", 100.0 * b as f64 / moving.max(1) as f64))
            .collect();
        println!(
            "straightness over {LAG_STEPS} steps of the steps not held, % in 0-0.1, 0.1-0.2, ..., 0.9-1: {}",
            bins.join(" / ")
        );
        println!(
            "per robot (last window): exploring / shuttling / circling / held steps, reversals, mean straightness"
        );
        for (i, (cl, rev, st)) in g.robots.iter().enumerate() {
            println!(
                "  repeat {} robot {}: {} / {} / {} / {}, {rev} reversals, {st:.2}",
                i / s.robots,
                i % s.robots,
                cl[0],
                cl[1],
                cl[2],
                cl[3]
            );
        }
    }
    Ok(())
}
