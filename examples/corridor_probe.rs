//! Why the corridor's robots do not space themselves evenly: runs a corridor scenario's
//! learning and learning-off conditions with model robots and, for every robot-step, reads
//! where the robot is (its gaps to its neighbours and the end walls, its bumpers), the move it
//! made, its readings, E = D(t) − D(t−1) (the evaluation of the behaviour it ran since the
//! previous step) and its outputs. Prints, per condition:
//!
//! * where the robot-steps are: free (everything at least 1 cm away), touching a neighbour,
//!   touching an end wall, pressed against a side wall;
//! * for free moves, whether E rewards moving towards the middle of the robot's free span (the
//!   place that evens its two gaps) and punishes moving away: the pull the rule would need;
//! * E's dead zone (|E| ≤ T), its spikes (|E| > 4 T), and how often the readings are capped at
//!   255 du (nothing within the sensor's range); E split into the change of the front and rear
//!   readings (which carry the spacing) and of the left and right ones (which see the side
//!   walls, at an angle when the robot yaws), and which of the two decided E's sign; the
//!   robots' yaw off the corridor's axis;
//! * jams (a robot touching a neighbour or an end wall for 5 steps or more): how many, how long,
//!   what the robot ran into, and the behaviour and E that started and ended them;
//! * the run's own verdict on the last window (gap CV over the steps no neighbours touch, the
//!   share of steps with neighbours touching).
//!
//!     cargo run --release --example corridor_probe [corridor|FILE.toml] [REPEATS] [SEED]

use nn_q15::DynLearner;
use swarm::experiment::{GAP_TOUCH_M, Swarm};
use swarm::robot::{Brain, Condition};
use swarm::scenario::Scenario;

/// A jam lasts at least this many steps.
const JAM_STEPS: u32 = 5;
/// A move towards or away from the middle of the free span counts from this many metres.
const MOVE_MIN_M: f64 = 0.005;

/// The learner's four readings (du) and its winner.
fn choice(l: &DynLearner) -> ([i16; 4], usize) {
    let x = l.inputs();
    let p: [i16; 4] = std::array::from_fn(|k| i16::from(x[k].to_bits()) + 128);
    let o: Vec<i32> = l.outputs().iter().map(|v| i32::from(v.to_bits())).collect();
    let mut win = 0;
    for (j, &v) in o.iter().enumerate() {
        if v > o[win] {
            win = j;
        }
    }
    (p, win)
}

/// Where a robot stands in the line: its centre, the edges of its free span (the neighbours'
/// near faces or the end walls), and its distances to them (its own faces to theirs).
#[derive(Clone, Copy, Debug)]
struct Place {
    x: f64,
    left_edge: f64,
    right_edge: f64,
    left_gap: f64,
    right_gap: f64,
    left_is_wall: bool,
    right_is_wall: bool,
}

impl Place {
    fn middle(&self) -> f64 {
        0.5 * (self.left_edge + self.right_edge)
    }
}

fn places(xs: &[f64], body: f64, length: f64) -> Vec<Place> {
    let mut order: Vec<usize> = (0..xs.len()).collect();
    order.sort_by(|&a, &b| xs[a].total_cmp(&xs[b]).then(a.cmp(&b)));
    let mut out = vec![
        Place {
            x: 0.0,
            left_edge: 0.0,
            right_edge: 0.0,
            left_gap: 0.0,
            right_gap: 0.0,
            left_is_wall: false,
            right_is_wall: false,
        };
        xs.len()
    ];
    for (k, &i) in order.iter().enumerate() {
        let left_edge = if k == 0 {
            0.0
        } else {
            xs[order[k - 1]] + body / 2.0
        };
        let right_edge = if k + 1 == order.len() {
            length
        } else {
            xs[order[k + 1]] - body / 2.0
        };
        out[i] = Place {
            x: xs[i],
            left_edge,
            right_edge,
            left_gap: xs[i] - body / 2.0 - left_edge,
            right_gap: right_edge - (xs[i] + body / 2.0),
            left_is_wall: k == 0,
            right_is_wall: k + 1 == order.len(),
        };
    }
    out
}

#[derive(Default)]
struct Gathered {
    steps: u64,
    free: u64,
    touch_neighbour: u64,
    touch_wall: u64,
    side_pressed: u64,
    /// Free moves: [towards, away, neither][reward, dead zone, punish].
    pull: [[u64; 3]; 3],
    /// All steps: E in the dead zone, spikes.
    dead: u64,
    spikes: u64,
    /// Readings capped at 255 du (front or rear).
    capped: u64,
    /// Readings front + rear, free steps, and their count.
    front_rear_sum: f64,
    /// Free steps: summed |Δ(front + rear)| and |Δ(left + right)|; steps with |E| > T whose
    /// sign the side readings decided (|Δ sides| > |Δ front-rear|, same sign as E); steps with
    /// |E| > T; spikes decided by the sides.
    d_fr: f64,
    d_side: f64,
    decided_by_sides: u64,
    decisive: u64,
    spikes_by_sides: u64,
    /// Free moves judged by the front and rear readings alone: [towards, away][reward, dead,
    /// punish].
    pull_fr: [[u64; 3]; 2],
    /// Yaw off the corridor's axis: summed degrees, steps above 5°.
    yaw_sum: f64,
    yawed: u64,
    /// Jams: count, steps, into a wall, into a neighbour; started by forward/backward; ended by
    /// forward/backward; E at the start (sum).
    jams: u32,
    jam_steps: u64,
    jam_wall: u32,
    jam_neighbour: u32,
    jam_started_by: [u32; 2],
    jams_ended: u32,
    jam_ended_by: [u32; 2],
    /// Steps with E > T, dead, E < −T inside jams.
    jam_e: [u64; 3],
    /// Behaviours in jams: forward, backward.
    jam_behaviour: [u64; 2],
    /// For the jams, the run of the same behaviour that led into them: summed length, summed
    /// punishments (E < −T) and rewards (E > T) received on the way without a change of
    /// behaviour, and jams whose run held through at least one punishment.
    run_into_jam: u64,
    run_punished: u64,
    run_rewarded: u64,
    jams_after_punishment: u32,
    /// The last window's gap CV (mean over repeats of the run's own) and touching share.
    last_touching: f64,
    last_cv: Vec<f64>,
    repeats: u32,
}

fn run(s: &Scenario, c: Condition, repeat: u32, g: &mut Gathered) -> anyhow::Result<()> {
    let mut sw = Swarm::new(s, c, repeat, false, None)?;
    let n = s.robots;
    let t = s.learner.threshold;
    let body = world::params::BODY_LENGTH_M;
    let length = swarm::experiment::arena_of(s)?.width_m();
    let last_from = s.steps.saturating_sub(s.window);
    let xs = |sw: &Swarm| -> anyhow::Result<Vec<f64>> {
        (0..n).map(|i| Ok(sw.world().pose(i)?.x_m)).collect()
    };
    let mut before = places(&xs(&sw)?, body, length);
    let mut d_prev = vec![None::<i32>; n];
    let mut p_prev = vec![None::<[i16; 4]>; n];
    // Per robot: the current run of one behaviour (steps, punishments, rewards).
    let mut runs = vec![(0u32, 0u32, 0u32); n];
    let mut prev_win = vec![0usize; n];
    // Per robot: the jam it is in (start step, into a wall, counted).
    let mut jam: Vec<Option<(u32, bool, bool)>> = vec![None; n];
    let mut touching_steps = 0u32;
    let mut cv_sum = 0.0;
    let mut cv_n = 0u32;
    for step in 0..s.steps {
        sw.step()?;
        let now = places(&xs(&sw)?, body, length);
        let touching_now = now.iter().any(|p| {
            (!p.left_is_wall && p.left_gap < GAP_TOUCH_M)
                || (!p.right_is_wall && p.right_gap < GAP_TOUCH_M)
        });
        if step >= last_from {
            touching_steps += u32::from(touching_now);
            if !touching_now && let Some(cv) = sw.world().corridor_gap_cv()? {
                cv_sum += cv;
                cv_n += 1;
            }
        }
        for i in 0..n {
            let bumpers = sw.world().bumpers(i)?;
            let Some(robot) = sw.robot_mut(i) else {
                continue;
            };
            let Brain::Model(ctl) = &robot.brain else {
                anyhow::bail!("the probe reads model robots only");
            };
            let (p, win) = choice(ctl.learner());
            let d: i32 = p.iter().map(|&v| i32::from(v)).sum();
            let e = d_prev[i].map(|dp| d - dp);
            d_prev[i] = Some(d);
            // E's two parts: the front and rear readings, the side ones.
            let parts = p_prev[i].map(|q| {
                (
                    i32::from(p[0] - q[0]) + i32::from(p[1] - q[1]),
                    i32::from(p[2] - q[2]) + i32::from(p[3] - q[3]),
                )
            });
            p_prev[i] = Some(p);
            let (a, b) = (before[i], now[i]);
            let touch_n = (!b.left_is_wall && b.left_gap < GAP_TOUCH_M)
                || (!b.right_is_wall && b.right_gap < GAP_TOUCH_M);
            let touch_w = (b.left_is_wall && b.left_gap < GAP_TOUCH_M)
                || (b.right_is_wall && b.right_gap < GAP_TOUCH_M);
            let side = bumpers[2] || bumpers[3];
            let heading = sw.world().pose(i)?.heading_rad;
            let yaw = libm::asin(libm::sin(heading).abs()).to_degrees();
            g.yaw_sum += yaw;
            g.yawed += u64::from(yaw > 5.0);
            g.steps += 1;
            g.touch_neighbour += u64::from(touch_n);
            g.touch_wall += u64::from(touch_w);
            g.side_pressed += u64::from(side);
            g.capped += u64::from(p[0] >= 255) + u64::from(p[1] >= 255);
            // The run of the behaviour that ran since the previous step (E evaluates it).
            if let Some(e) = e {
                let r = &mut runs[i];
                r.0 += 1;
                r.1 += u32::from(e < -t);
                r.2 += u32::from(e > t);
            }
            if let Some(e) = e {
                let kind = if e > t {
                    0
                } else if e < -t {
                    2
                } else {
                    1
                };
                g.dead += u64::from(kind == 1);
                g.spikes += u64::from(e.abs() > 4 * t);
                if let Some((fr, sd)) = parts {
                    let by_sides = sd.abs() > fr.abs() && sd.signum() == e.signum();
                    if kind != 1 {
                        g.decisive += 1;
                        g.decided_by_sides += u64::from(by_sides);
                    }
                    g.spikes_by_sides += u64::from(e.abs() > 4 * t && by_sides);
                }
                let free = |q: &Place| q.left_gap >= GAP_TOUCH_M && q.right_gap >= GAP_TOUCH_M;
                if free(&a) && free(&b) && !side {
                    g.free += 1;
                    g.front_rear_sum += f64::from(p[0] + p[1]);
                    // The move since the previous step, against the middle of the span then.
                    let (d0, d1) = ((a.x - a.middle()).abs(), (b.x - a.middle()).abs());
                    let way = if d1 < d0 - MOVE_MIN_M {
                        0
                    } else if d1 > d0 + MOVE_MIN_M {
                        1
                    } else {
                        2
                    };
                    g.pull[way][kind] += 1;
                    if let Some((fr, sd)) = parts {
                        g.d_fr += f64::from(fr.abs());
                        g.d_side += f64::from(sd.abs());
                        let k2 = if fr > t {
                            0
                        } else if fr < -t {
                            2
                        } else {
                            1
                        };
                        if way < 2 {
                            g.pull_fr[way][k2] += 1;
                        }
                    }
                }
                if jam[i].is_some() {
                    g.jam_e[kind] += 1;
                }
            }
            // Jams: touching a neighbour or an end wall.
            let touching = touch_n || touch_w;
            match (&mut jam[i], touching) {
                (None, true) => jam[i] = Some((step, touch_w, false)),
                (Some((start, into_wall, counted)), true) => {
                    if !*counted && step - *start + 1 >= JAM_STEPS {
                        *counted = true;
                        g.jams += 1;
                        if *into_wall {
                            g.jam_wall += 1;
                        } else {
                            g.jam_neighbour += 1;
                        }
                        g.jam_started_by[prev_win[i].min(1)] += 1;
                        g.jam_steps += u64::from(JAM_STEPS);
                        let r = runs[i];
                        g.run_into_jam += u64::from(r.0);
                        g.run_punished += u64::from(r.1);
                        g.run_rewarded += u64::from(r.2);
                        g.jams_after_punishment += u32::from(r.1 > 0);
                    } else if *counted {
                        g.jam_steps += 1;
                        g.jam_behaviour[win.min(1)] += 1;
                    }
                }
                (Some((_, _, counted)), false) => {
                    if *counted {
                        g.jams_ended += 1;
                        g.jam_ended_by[prev_win[i].min(1)] += 1;
                    }
                    jam[i] = None;
                }
                (None, false) => {}
            }
            if win != prev_win[i] {
                runs[i] = (0, 0, 0);
            }
            prev_win[i] = win;
        }
        before = now;
    }
    g.repeats += 1;
    g.last_touching += 100.0 * f64::from(touching_steps) / f64::from(s.window.max(1));
    if cv_n > 0 {
        g.last_cv.push(cv_sum / f64::from(cv_n));
    }
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let mut s = Scenario::load(&args.next().unwrap_or_else(|| "corridor".into()))?;
    let repeats: u32 = args.next().map_or(Ok(10), |a| a.parse())?;
    if let Some(seed) = args.next() {
        s.seed = seed.parse()?;
    }
    println!(
        "{}: {} robots, {} steps, {repeats} repeats, seed {}, eta {}, T = {} du, clearance {} m",
        s.name,
        s.robots,
        s.steps,
        s.seed,
        s.learner.eta,
        s.learner.threshold,
        s.world.corridor_clearance_m
    );
    for c in [Condition::Learning, Condition::LearningOff] {
        let mut g = Gathered::default();
        for r in 0..repeats {
            run(&s, c, r, &mut g)?;
        }
        let pc = |x: u64| 100.0 * x as f64 / g.steps.max(1) as f64;
        println!("\n{} ({} robot-steps)", c.name(), g.steps);
        println!(
            "where: free {:.1} %, touching a neighbour {:.1} %, touching an end wall {:.1} %, a side bumper pressed {:.1} %",
            pc(g.free),
            pc(g.touch_neighbour),
            pc(g.touch_wall),
            pc(g.side_pressed)
        );
        println!(
            "E: dead zone {:.1} % of steps, spikes (|E| > 4 T) {:.1} %; front or rear capped at 255 du in {:.1} % of readings; free steps' front + rear {:.0} du on average",
            pc(g.dead),
            pc(g.spikes),
            50.0 * g.capped as f64 / g.steps.max(1) as f64,
            g.front_rear_sum / g.free.max(1) as f64
        );
        println!(
            "free moves against the middle of the robot's span | E > T (reward) | dead zone | E < -T (punish) | moves"
        );
        for (w, name) in ["towards the middle", "away from it", "neither (< 5 mm)"]
            .iter()
            .enumerate()
        {
            let row = g.pull[w];
            let tot = row.iter().sum::<u64>().max(1) as f64;
            println!(
                "  {name:<22} | {:.1} % | {:.1} % | {:.1} % | {}",
                100.0 * row[0] as f64 / tot,
                100.0 * row[1] as f64 / tot,
                100.0 * row[2] as f64 / tot,
                row.iter().sum::<u64>()
            );
        }
        println!(
            "E's parts on free steps: |change of front + rear| {:.1} du, |change of left + right| {:.1} du on average; the side readings decide the sign of {:.1} % of the steps with |E| > T and of {:.1} % of the spikes; yaw off the axis {:.1} degrees on average, above 5 degrees in {:.1} % of steps",
            g.d_fr / g.free.max(1) as f64,
            g.d_side / g.free.max(1) as f64,
            100.0 * g.decided_by_sides as f64 / g.decisive.max(1) as f64,
            100.0 * g.spikes_by_sides as f64 / g.spikes.max(1) as f64,
            g.yaw_sum / g.steps.max(1) as f64,
            pc(g.yawed)
        );
        println!(
            "free moves judged by the front and rear readings alone | reward | dead zone | punish"
        );
        for (w, name) in ["towards the middle", "away from it"].iter().enumerate() {
            let row = g.pull_fr[w];
            let tot = row.iter().sum::<u64>().max(1) as f64;
            println!(
                "  {name:<22} | {:.1} % | {:.1} % | {:.1} %",
                100.0 * row[0] as f64 / tot,
                100.0 * row[1] as f64 / tot,
                100.0 * row[2] as f64 / tot
            );
        }
        let jam_e: u64 = g.jam_e.iter().sum::<u64>().max(1);
        println!(
            "jams (touching for {JAM_STEPS}+ steps): {} ({} into an end wall, {} into a neighbour), {:.1} % of robot-steps, {} ended; started by forward {} / backward {}, ended by forward {} / backward {}; in jams the robot runs forward {} / backward {} steps, E > T {:.1} %, dead {:.1} %, E < -T {:.1} %",
            g.jams,
            g.jam_wall,
            g.jam_neighbour,
            pc(g.jam_steps),
            g.jams_ended,
            g.jam_started_by[0],
            g.jam_started_by[1],
            g.jam_ended_by[0],
            g.jam_ended_by[1],
            g.jam_behaviour[0],
            g.jam_behaviour[1],
            100.0 * g.jam_e[0] as f64 / jam_e as f64,
            100.0 * g.jam_e[1] as f64 / jam_e as f64,
            100.0 * g.jam_e[2] as f64 / jam_e as f64
        );
        let jams = f64::from(g.jams.max(1));
        println!(
            "the runs of one behaviour that led into the jams: {:.1} steps long on average (counted to the jam's 5th step), with {:.1} rewards and {:.1} punishments received on the way; {} of {} jams came after a run that held through a punishment",
            g.run_into_jam as f64 / jams,
            g.run_rewarded as f64 / jams,
            g.run_punished as f64 / jams,
            g.jams_after_punishment,
            g.jams
        );
        let cv = if g.last_cv.is_empty() {
            "none".to_string()
        } else {
            format!(
                "{:.2}",
                g.last_cv.iter().sum::<f64>() / g.last_cv.len() as f64
            )
        };
        println!(
            "last window: neighbours touching in {:.0} % of steps (mean over repeats); gap CV over the steps none touch {cv} ({} of {} repeats have such steps)",
            g.last_touching / f64::from(g.repeats.max(1)),
            g.last_cv.len(),
            g.repeats
        );
    }
    Ok(())
}
