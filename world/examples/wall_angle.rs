//! One differential-drive robot driving into a wall at an angle: does it square up
//! to the wall and stay, or slide along it? Three models of the same robot (0.5 kg box
//! 230 × 180 mm, wheels 160 mm apart on the axle through the centre, μ_floor 0.6, μ_wall 0.3,
//! a 60 ms motor lag, no motor-gain spread):
//!
//! - **own**: the world crate's solver (20 ms sub-steps), as every run uses it by default
//!   (`world.solver = "capped"`: at most 12 sweeps), converged (`"converged"`: until no
//!   velocity changes by more than 2 µm/s in a sweep, at most 256 sweeps) and by Newton's
//!   method (`"newton"`: to the sweeps' fixed point);
//! - **rapier2d**: rapier2d 0.36.1 with the wheel forces applied explicitly before each 20 ms
//!   step (the set-up of `solver_compare`);
//! - **Coulomb**: a reference written for this scene (`world/tests/coulomb_reference`):
//!   explicit integration in 10 µs steps of plain Coulomb friction — each wheel's force is μ_floor·m·g/2 against the slip velocity of
//!   its contact patch (body velocity at the wheel minus the rim speed along the heading),
//!   isotropic, smoothed below 1 mm/s; the wall is a stiff penalty (10⁵ N/m, critically
//!   damped) at the body's corners with Coulomb friction μ_wall against the corner's sliding.
//!
//! The robot starts at rest 30 mm from the wall (x = 3 m, its normal −x), heading θ from the
//! wall's normal (+x), both wheels full forward (or unequal), and runs 8 s. Printed per case:
//! the heading at the end (degrees from the normal), how far the centre slid along the wall
//! after the first touch (at 5 s and at the end), whether it is at the wall at the end and
//! whether it ended stuck (moved < 1 mm in the last second).
//!
//!     cargo run --release -p world --example wall_angle

// A test, example or bench may use the host's f64 functions (clippy.toml): it checks the
// models within tolerances, and its own output is not a promised result.
#![allow(clippy::disallowed_methods)]

#[path = "../tests/coulomb_reference/mod.rs"]
mod coulomb_reference;
mod rapier_scene;

use rapier2d::prelude::*;
use world::{Arena, Pose, World, WorldParams};

/// The robots' MCU clock the world counts in here: the robot's φ, 25 MHz (the world crate has
/// no clock of its own, and does not depend on the emulator that defines the robot's).
const CLOCK_HZ: u64 = 25_000_000;

const HX: f64 = 0.115;
const HY: f64 = 0.09;
const MASS: f64 = 0.5;
const MU_FLOOR: f64 = 0.6;
const MU_WALL: f64 = 0.3;
const TOP: f64 = 0.15;
const TAU: f64 = 0.06;
const HALF_TRACK: f64 = 0.08;
const WALL_X: f64 = 3.0;
const ARENA_H: f64 = 4.0;
const Y0: f64 = 1.0;
const RUN_S: f64 = 8.0;
const H: f64 = 0.02;

/// A trajectory sampled every 20 ms: (t, x, y, heading).
type Track = Vec<(f64, f64, f64, f64)>;

fn start(theta: f64) -> (f64, f64) {
    // The leading front corner 30 mm from the wall.
    let reach = HX * theta.cos() + HY * theta.sin().abs();
    (WALL_X - 0.03 - reach, Y0)
}

fn inertia() -> f64 {
    MASS * (4.0 * HX * HX + 4.0 * HY * HY) / 12.0
}

/// The world crate's solver: capped (`Impulse`: 12 sweeps, stopped on the impulses),
/// converged (`Velocity`: up to 256 sweeps, stopped on the velocities) or `Newton`.
fn own(theta: f64, duty: [f64; 2], until: world::params::Convergence) -> Track {
    let params = WorldParams {
        motor_gain_spread: 0.0,
        ..WorldParams::with_clock(CLOCK_HZ)
    };
    let params = if until == world::params::Convergence::Impulse {
        params
    } else {
        WorldParams {
            solver_iterations: 256,
            solver_convergence: until,
            ..params
        }
    };
    let (x, y) = start(theta);
    let pose = Pose {
        x_m: x,
        y_m: y,
        heading_rad: theta,
    };
    let arena = Arena::rectangle(WALL_X, ARENA_H).unwrap();
    let mut w = World::from_poses(arena, params, &[pose], 1).unwrap();
    w.set_wheels(
        0,
        world::WheelCommand::forward(duty[0]),
        world::WheelCommand::forward(duty[1]),
    )
    .unwrap();
    let mut track = Vec::new();
    let steps = (RUN_S / H).round() as usize;
    for k in 1..=steps {
        w.advance(H).unwrap();
        let p = w.pose(0).unwrap();
        track.push((k as f64 * H, p.x_m, p.y_m, p.heading_rad));
    }
    track
}

fn rapier(theta: f64, duty: [f64; 2]) -> Track {
    let mut pw = rapier_scene::walled_world(WALL_X, ARENA_H, MU_WALL, H);
    let (x0, y0) = start(theta);
    let hd = pw.bodies.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(x0 as Real, y0 as Real))
            .rotation(theta as Real)
            .can_sleep(false)
            .build(),
    );
    let col = ColliderBuilder::cuboid(HX as Real, HY as Real)
        .mass(MASS as Real)
        .friction(MU_WALL as Real)
        .restitution(0.0)
        .build();
    pw.colliders.insert_with_parent(col, hd, &mut pw.bodies);
    let wheels = rapier_scene::Wheels::new(MASS, inertia(), HALF_TRACK, MU_FLOOR);
    let decay = (-H / TAU).exp();
    let mean_factor = TAU / H * (1.0 - decay);
    let mut speed = [0.0f64; 2];
    let mut track = Vec::new();
    let steps = (RUN_S / H).round() as usize;
    for k in 1..=steps {
        let mut mean = [0.0; 2];
        for wh in 0..2 {
            let target = duty[wh] * TOP;
            let diff = speed[wh] - target;
            mean[wh] = target + diff * mean_factor;
            speed[wh] = target + diff * decay;
        }
        wheels.apply(&mut pw.bodies[hd], mean, H);
        pw.step();
        let b = &pw.bodies[hd];
        let tr = b.translation();
        track.push((
            k as f64 * H,
            f64::from(tr.x),
            f64::from(tr.y),
            f64::from(b.rotation().angle()),
        ));
    }
    track
}

/// The reference (plain Coulomb, explicit in 10 µs steps; `world/tests/coulomb_reference`).
fn coulomb(theta: f64, duty: [f64; 2]) -> Track {
    let (x, y) = start(theta);
    coulomb_reference::run(&coulomb_reference::Scene {
        x,
        y,
        heading: theta,
        duty,
        wall_x: WALL_X,
        mu_wall: MU_WALL,
        every_s: H,
        run_s: RUN_S,
    })
}

/// Does the body reach within 1 mm of the wall at this pose?
fn at_wall(x: f64, phi: f64) -> bool {
    x + HX * phi.cos().abs() + HY * phi.sin().abs() > WALL_X - 1e-3
}

struct Summary {
    heading_deg: f64,
    slid_5s_mm: f64,
    slid_end_mm: f64,
    at_wall: bool,
    stuck: bool,
    square_s: Option<f64>,
}

fn summarise(track: &Track) -> Summary {
    let touch = track
        .iter()
        .position(|&(_, x, _, p)| at_wall(x, p))
        .unwrap_or(track.len() - 1);
    let y_touch = track[touch].2;
    let at = |t: f64| {
        track
            .iter()
            .find(|s| s.0 >= t - 1e-9)
            .copied()
            .unwrap_or(*track.last().unwrap())
    };
    let end = *track.last().unwrap();
    let last_s = at(RUN_S - 1.0);
    let square_s = track[touch..]
        .iter()
        .find(|s| s.3.to_degrees().abs() < 1.0)
        .map(|s| s.0);
    Summary {
        heading_deg: end.3.to_degrees(),
        slid_5s_mm: 1e3 * (at(5.0).2 - y_touch),
        slid_end_mm: 1e3 * (end.2 - y_touch),
        at_wall: at_wall(end.1, end.3),
        stuck: (end.1 - last_s.1).hypot(end.2 - last_s.2) < 1e-3,
        square_s,
    }
}

fn main() {
    println!(
        "| θ from normal | wheels (L, R) | model | heading at end | slid along wall 5 s / 8 s | at wall at end | stuck (< 1 mm in last s) | square (< 1°) at | farthest from Coulomb |"
    );
    println!("|---:|---|---|---:|---:|---|---|---:|---:|");
    let mut cases: Vec<(f64, [f64; 2])> = [10.0, 30.0, 45.0, 50.0, 55.0, 60.0, 80.0]
        .iter()
        .map(|&d| (d, [1.0, 1.0]))
        .collect();
    cases.push((30.0, [1.0, 0.3]));
    cases.push((30.0, [0.3, 1.0]));
    cases.push((60.0, [1.0, 0.3]));
    for (deg, duty) in cases {
        let theta = f64::to_radians(deg);
        let reference = coulomb(theta, duty);
        for (name, track) in [
            ("own", own(theta, duty, world::params::Convergence::Impulse)),
            (
                "own, converged",
                own(theta, duty, world::params::Convergence::Velocity),
            ),
            (
                "own, newton",
                own(theta, duty, world::params::Convergence::Newton),
            ),
            ("rapier2d", rapier(theta, duty)),
            ("Coulomb", reference.clone()),
        ] {
            let s = summarise(&track);
            let apart = track
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a.1 - b.1).hypot(a.2 - b.2))
                .fold(0.0f64, f64::max);
            println!(
                "| {deg}° | {:.1}, {:.1} | {name} | {:.1}° | {:.0} / {:.0} mm | {} | {} | {} | {:.0} mm |",
                duty[0],
                duty[1],
                s.heading_deg,
                s.slid_5s_mm,
                s.slid_end_mm,
                if s.at_wall { "yes" } else { "no" },
                if s.stuck { "yes" } else { "no" },
                s.square_s
                    .map_or_else(|| "never".to_string(), |t| format!("{t:.2} s")),
                1e3 * apart,
            );
        }
    }
}
