//! What the bumpers read inside a step: runs a scenario's learning condition with
//! model robots to step STEP, then replays the next STEPS steps' world sub-step by sub-step on
//! a copy of it (the commands the robots set, which do not change within a step) and prints,
//! per robot, its pose and wheel speeds at the step's start and its four switches (front,
//! rear, left, right; 1 = pressed) after every sub-step. It found the light rub along a wall
//! that read pressed and released in alternate sub-steps (docs/testing.md, "The soak").
//!
//!     cargo run --release --example chatter_probe FILE.toml ROBOTS SEED STEP [STEPS]
//!
//! e.g. `scenarios/arena-learning-only.toml 10 2 50790 1`.

use anyhow::{Context, bail};
use swarm::experiment::{Swarm, period_states};
use swarm::robot::Condition;
use swarm::scenario::Scenario;

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.len() < 4 {
        bail!("usage: chatter_probe FILE.toml ROBOTS SEED STEP [STEPS]");
    }
    let mut s = Scenario::load(&a[0])?;
    s.robots = a[1].parse().context("ROBOTS: a whole number")?;
    s.seed = a[2].parse().context("SEED: a whole number")?;
    let at: u32 = a[3].parse().context("STEP: a whole number")?;
    let show: u32 = a
        .get(4)
        .map_or(Ok(1), |x| x.parse())
        .context("STEPS: a whole number")?;
    s.steps = at
        .checked_add(show)
        .and_then(|n| n.checked_add(1))
        .context("STEP + STEPS too large")?;
    let mut sw = Swarm::new(&s, Condition::Learning, 0, false, None)?;
    for _ in 0..at {
        sw.step()?;
    }
    let period = period_states(&s);
    for k in 0..show {
        sw.step()?;
        let mut w = sw.world().clone();
        let plan = w.substep_plan(period);
        println!("step {} ({} sub-steps)", at + k, plan.substeps());
        for i in 0..s.robots {
            let p = w.pose(i)?;
            let v = w.wheel_speeds(i)?;
            println!(
                "  robot {i}: x {:.4} m, y {:.4} m, heading {:.3} deg, wheels {:.4} / {:.4} m/s",
                p.x_m,
                p.y_m,
                p.heading_rad.to_degrees(),
                v[0],
                v[1]
            );
        }
        let mut rows = vec![String::new(); s.robots];
        for len in plan {
            w.advance_states(len);
            for (i, row) in rows.iter_mut().enumerate() {
                let b = w.bumpers(i)?;
                row.push(' ');
                row.extend(b.iter().map(|&x| if x { '1' } else { '0' }));
            }
        }
        for (i, row) in rows.iter().enumerate() {
            println!("  robot {i} switches by sub-step:{row}");
        }
    }
    Ok(())
}
