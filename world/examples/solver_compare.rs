//! The contact model against `rapier2d` on the same scenes: n robots (3, 100, 1 000,
//! 10 000) in the square arena scaled to the paper's density, every robot drawing a random
//! behaviour every 0.45 s, 0.45 s steps cut into 23 sub-steps of 19.6 ms. Both engines get the
//! same bodies (0.5 kg boxes 230 × 180 mm), the same wheels (a first-order lag of 60 ms to the
//! behaviour's speeds, two wheels holding the body's velocity at the wheel with at most
//! μ·m·g/2 each, μ 0.6), the same friction between bodies and with the walls (0.3), the same
//! placement and the same random behaviours. rapier2d gets the wheel forces explicitly before
//! each of its steps (the usual way to drive it), our solver has them as constraints.
//!
//! Printed per scene and engine: host time per robot per sub-step, the deepest overlap left at a
//! step's end, the robot-steps blocked (a driving robot moving < 1 mm in a step), and whether two
//! runs give bit-identical poses (ours: 1 and 2 threads; rapier2d as built here runs on one
//! thread, so: the same run twice).
//!
//!     cargo run --release -p world --example solver_compare [MAX_ROBOTS]

// A test, example or bench may use the host's f64 functions (clippy.toml): it checks the
// models within tolerances, and its own output is not a promised result.
#![allow(clippy::disallowed_methods)]

use std::time::Instant;

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use rapier2d::prelude::*;

mod rapier_scene;
use world::geometry::{Obb, obb_overlap};
use world::{Arena, Behaviour, World, WorldParams};

const STEP_STATES: u64 = 11_250_000;
/// The robots' MCU clock the world counts in here: the robot's φ, 25 MHz (the world crate has
/// no clock of its own, and does not depend on the emulator that defines the robot's).
const CLOCK_HZ: u64 = 25_000_000;
const SUBSTEPS: u32 = 23;
const HX: f64 = 0.115;
const HY: f64 = 0.09;
const MASS: f64 = 0.5;
const MU_FLOOR: f64 = 0.6;
const MU_CONTACT: f64 = 0.3;
const TOP: f64 = 0.15;
const TAU: f64 = 0.06;
const HALF_TRACK: f64 = 0.08;

struct Outcome {
    ns_per_robot_substep: f64,
    deepest_overlap_m: f64,
    blocked_steps: f64,
    fingerprint: u64,
}

fn behaviours(n: usize, steps: usize) -> Vec<Vec<Behaviour>> {
    let mut rng = Pcg64::seed_from_u64(12);
    (0..steps)
        .map(|_| {
            (0..n)
                .map(|_| Behaviour::ALL[rng.random_range(0..4usize)])
                .collect()
        })
        .collect()
}

fn fingerprint(poses: impl Iterator<Item = (f64, f64, f64)>) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for (x, y, t) in poses {
        for v in [x, y, t] {
            h = (h ^ v.to_bits()).wrapping_mul(0x100_0000_01b3);
        }
    }
    h
}

fn own(n: usize, plan: &[Vec<Behaviour>], parallel: bool) -> Outcome {
    let mut w = World::new(
        Arena::scaled_square(n).unwrap(),
        WorldParams::with_clock(CLOCK_HZ),
        n,
        2008,
    )
    .unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let (mut deepest, mut blocked, mut elapsed) = (0.0f64, 0u64, 0.0);
    for step in plan {
        for (i, b) in step.iter().enumerate() {
            let (l, r) = b.wheels();
            w.set_wheels(i, l, r).unwrap();
        }
        let before: Vec<_> = (0..n).map(|i| w.pose(i).unwrap()).collect();
        let t0 = Instant::now();
        if parallel {
            pool.install(|| w.advance_states_par(STEP_STATES));
        } else {
            w.advance_states(STEP_STATES);
        }
        elapsed += t0.elapsed().as_secs_f64();
        deepest = deepest.max(w.deepest_overlap_m());
        for (i, p) in before.iter().enumerate() {
            let q = w.pose(i).unwrap();
            blocked += u64::from((q.x_m - p.x_m).hypot(q.y_m - p.y_m) < 0.001);
        }
    }
    Outcome {
        ns_per_robot_substep: elapsed * 1e9 / (n * plan.len() * SUBSTEPS as usize) as f64,
        deepest_overlap_m: deepest,
        blocked_steps: blocked as f64 / (n * plan.len()) as f64,
        fingerprint: fingerprint((0..n).map(|i| {
            let p = w.pose(i).unwrap();
            (p.x_m, p.y_m, p.heading_rad)
        })),
    }
}

fn rapier(n: usize, plan: &[Vec<Behaviour>]) -> Outcome {
    // The same placement and motor gains as ours.
    let start = World::new(
        Arena::scaled_square(n).unwrap(),
        WorldParams::with_clock(CLOCK_HZ),
        n,
        2008,
    )
    .unwrap();
    let side = start.arena().width_m();
    let h = STEP_STATES as f64 / CLOCK_HZ as f64 / f64::from(SUBSTEPS);
    let mut pw = rapier_scene::walled_world(side, side, MU_CONTACT, h);
    let mut handles = Vec::with_capacity(n);
    let mut gains = Vec::with_capacity(n);
    for i in 0..n {
        let p = start.pose(i).unwrap();
        let rb = RigidBodyBuilder::dynamic()
            .translation(Vector::new(p.x_m as Real, p.y_m as Real))
            .rotation(p.heading_rad as Real)
            .can_sleep(false)
            .build();
        let hd = pw.bodies.insert(rb);
        let col = ColliderBuilder::cuboid(HX as Real, HY as Real)
            .mass(MASS as Real)
            .friction(MU_CONTACT as Real)
            .restitution(0.0)
            .build();
        pw.colliders.insert_with_parent(col, hd, &mut pw.bodies);
        handles.push(hd);
        gains.push(start.motor_gains(i).unwrap());
    }
    let inertia = MASS * (0.23 * 0.23 + 0.18 * 0.18) / 12.0;
    let wheels = rapier_scene::Wheels::new(MASS, inertia, HALF_TRACK, MU_FLOOR);
    let decay = (-h / TAU).exp();
    let mean_factor = TAU / h * (1.0 - decay);
    let mut speed = vec![[0.0f64; 2]; n];
    let (mut deepest, mut blocked, mut elapsed) = (0.0f64, 0u64, 0.0);
    let pose_of = |pw: &PhysicsWorld, hd: RigidBodyHandle| {
        let b = &pw.bodies[hd];
        let tr = b.translation();
        (
            f64::from(tr.x),
            f64::from(tr.y),
            f64::from(b.rotation().angle()),
        )
    };
    for step in plan {
        let before: Vec<_> = handles.iter().map(|&hd| pose_of(&pw, hd)).collect();
        let t0 = Instant::now();
        for _ in 0..SUBSTEPS {
            for (i, &hd) in handles.iter().enumerate() {
                let (l, r) = step[i].wheels();
                let targets = [l, r].map(|c| {
                    let s = match c.direction {
                        world::Direction::Reverse => -1.0,
                        _ => 1.0,
                    };
                    s * c.duty * TOP
                });
                let mut mean = [0.0; 2];
                for w in 0..2 {
                    let target = targets[w] * gains[i][w];
                    let diff = speed[i][w] - target;
                    mean[w] = target + diff * mean_factor;
                    speed[i][w] = target + diff * decay;
                }
                wheels.apply(&mut pw.bodies[hd], mean, h);
            }
            pw.step();
        }
        elapsed += t0.elapsed().as_secs_f64();
        // The deepest overlap left, measured with our own separating-axis test (f64).
        let obbs: Vec<Obb> = handles
            .iter()
            .map(|&hd| {
                let (x, y, t) = pose_of(&pw, hd);
                Obb::new(x, y, t, HX, HY)
            })
            .collect();
        for pair in pw.narrow_phase.contact_pairs() {
            let (Some(a), Some(b)) = (
                pw.colliders[pair.collider1].parent(),
                pw.colliders[pair.collider2].parent(),
            ) else {
                for m in pair.manifolds() {
                    for p in &m.points {
                        deepest = deepest.max(-f64::from(p.dist));
                    }
                }
                continue;
            };
            let ia = handles.iter().position(|&x| x == a);
            let ib = handles.iter().position(|&x| x == b);
            if let (Some(ia), Some(ib)) = (ia, ib)
                && let Some(o) = obb_overlap(&obbs[ia], &obbs[ib], 0.0)
            {
                deepest = deepest.max(o.depth_m);
            }
        }
        for (i, &hd) in handles.iter().enumerate() {
            let (x, y, _) = pose_of(&pw, hd);
            let p = before[i];
            blocked += u64::from((x - p.0).hypot(y - p.1) < 0.001);
        }
    }
    Outcome {
        ns_per_robot_substep: elapsed * 1e9 / (n * plan.len() * SUBSTEPS as usize) as f64,
        deepest_overlap_m: deepest,
        blocked_steps: blocked as f64 / (n * plan.len()) as f64,
        fingerprint: fingerprint(handles.iter().map(|&hd| pose_of(&pw, hd))),
    }
}

fn main() {
    let max: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(10_000);
    println!(
        "| robots | steps | engine | ns / robot / sub-step | deepest overlap left | blocked robot-steps | deterministic |"
    );
    println!("|---:|---:|---|---:|---:|---:|---|");
    for n in [3usize, 100, 1_000, 10_000] {
        if n > max {
            break;
        }
        let steps = match n {
            3 => 400,
            100 => 200,
            1_000 => 60,
            _ => 12,
        };
        let plan = behaviours(n, steps);
        let a = own(n, &plan, false);
        let b = own(n, &plan, true);
        let r1 = rapier(n, &plan);
        let r2 = rapier(n, &plan);
        let row = |name: &str, o: &Outcome, same: bool, how: &str| {
            println!(
                "| {n} | {steps} | {name} | {:.0} | {:.2e} m | {:.2} % | {} ({how}) |",
                o.ns_per_robot_substep,
                o.deepest_overlap_m,
                100.0 * o.blocked_steps,
                if same { "yes" } else { "NO" }
            );
        };
        row(
            "own solver",
            &a,
            a.fingerprint == b.fingerprint,
            "1 vs 2 threads",
        );
        row(
            "rapier2d 0.36.1",
            &r1,
            r1.fingerprint == r2.fingerprint,
            "twice, 1 thread",
        );
    }
}
