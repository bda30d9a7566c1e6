//! A differential-drive robot driving into a wall at an angle. With both wheels
//! slipping (the wall blocks them) each wheel pushes with μ_floor·m·g/2 along the heading and
//! the pair has no moment about the axle's centre, so only the wall's force turns the body: at
//! the leading front corner, inside its friction cone. The corner sticks, and the robot pivots
//! square to the wall, while the line from the corner to the centre lies inside the cone, i.e.
//! while θ < atan(half width / half length) + atan(μ_wall) (54.7° by default); past that the
//! corner slides and the wall's force turns the robot parallel to the wall (docs/physics.md).

// A test, example or bench may use the host's f64 functions (clippy.toml): it checks the
// models within tolerances, and its own output is not a promised result.
#![allow(clippy::disallowed_methods)]

mod coulomb_reference;

use coulomb_reference::{Sample, Scene};
use world::params::{BODY_LENGTH_M, BODY_WIDTH_M, Convergence};
use world::{Arena, Pose, WheelCommand, World, WorldParams};

/// The robots' MCU clock the world counts in here: the robot's φ, 25 MHz (the world crate has
/// no clock of its own, and does not depend on the emulator that defines the robot's).
const CLOCK_HZ: u64 = 25_000_000;

const WALL_X: f64 = 3.0;
const EVERY_S: f64 = 0.02;

/// The scene at heading `deg` from the wall's normal, the leading corner 30 mm from the wall.
fn scene(deg: f64, duty: [f64; 2], mu_wall: f64, run_s: f64) -> Scene {
    let theta = deg.to_radians();
    let reach = BODY_LENGTH_M / 2.0 * theta.cos() + BODY_WIDTH_M / 2.0 * theta.sin().abs();
    Scene {
        x: WALL_X - 0.03 - reach,
        y: 1.0,
        heading: theta,
        duty,
        wall_x: WALL_X,
        mu_wall,
        every_s: EVERY_S,
        run_s,
    }
}

/// Each solver a scenario can choose: the one every run uses by default (`Impulse`, at most 12
/// sweeps), the one that sweeps until no velocity changes by more than 2 µm/s (`Velocity`,
/// at most 256 sweeps) and Newton's method (`Newton`).
const SOLVERS: [Convergence; 3] = [
    Convergence::Impulse,
    Convergence::Velocity,
    Convergence::Newton,
];

/// The same scene in the world (no motor-gain spread), with the solver `until`.
fn own(s: &Scene, until: Convergence) -> Vec<Sample> {
    let params = WorldParams {
        motor_gain_spread: 0.0,
        mu_wall: s.mu_wall,
        ..WorldParams::with_clock(CLOCK_HZ)
    };
    let params = if until == Convergence::Impulse {
        params
    } else {
        WorldParams {
            solver_iterations: 256,
            solver_convergence: until,
            ..params
        }
    };
    let pose = Pose {
        x_m: s.x,
        y_m: s.y,
        heading_rad: s.heading,
    };
    let arena = Arena::rectangle(WALL_X, 4.0).unwrap();
    let mut w = World::from_poses(arena, params, &[pose], 1).unwrap();
    w.set_wheels(
        0,
        WheelCommand::forward(s.duty[0]),
        WheelCommand::forward(s.duty[1]),
    )
    .unwrap();
    let n = (s.run_s / s.every_s).round() as usize;
    (1..=n)
        .map(|k| {
            w.advance(s.every_s).unwrap();
            let p = w.pose(0).unwrap();
            (k as f64 * s.every_s, p.x_m, p.y_m, p.heading_rad)
        })
        .collect()
}

#[test]
fn squares_up_below_the_critical_angle_and_turns_along_the_wall_above_it() {
    for (mu_wall, solver) in [0.3f64, 0.6]
        .into_iter()
        .flat_map(|mu| SOLVERS.map(|s| (mu, s)))
    {
        let critical =
            (BODY_WIDTH_M / BODY_LENGTH_M).atan().to_degrees() + mu_wall.atan().to_degrees();
        for (deg, squares) in [(critical - 5.0, true), (critical + 5.0, false)] {
            let track = own(&scene(deg, [1.0, 1.0], mu_wall, 6.0), solver);
            let end = *track.last().unwrap();
            let second_before = track[track.len() - 1 - (1.0 / EVERY_S) as usize];
            let moved = (end.1 - second_before.1).hypot(end.2 - second_before.2);
            let heading = end.3.to_degrees();
            let what = format!(
                "{solver:?}, μ_wall {mu_wall}, {deg:.1}° (critical {critical:.1}°): heading {heading:.2}°, moved {:.1} mm in the last s, y {:.3} m",
                1e3 * moved,
                end.2
            );
            if squares {
                assert!(heading.abs() < 0.5, "should square up: {what}");
                assert!(moved < 1e-3, "should stay: {what}");
            } else {
                assert!(
                    (heading - 90.0).abs() < 0.5,
                    "should turn along the wall: {what}"
                );
                assert!(moved > 0.1 && end.2 > 1.5, "should slide along: {what}");
            }
        }
    }
}

#[test]
fn follows_plain_coulomb_friction_at_the_wheels_and_the_wall() {
    // The sliding wheels' friction points against their slip (isotropic Coulomb): a solver
    // that resisted sideways slip harder (the projection weighted by the rows' masses) pivots
    // 20 % slower and is 25 mm off at 45° and 20 mm off with unequal wheels.
    for (deg, duty) in [(45.0, [1.0, 1.0]), (30.0, [0.3, 1.0]), (60.0, [1.0, 0.3])] {
        let s = scene(deg, duty, world::params::MU_WALL, 3.0);
        let reference = coulomb_reference::run(&s);
        for solver in SOLVERS {
            let ours = own(&s, solver);
            let (mut worst, mut at) = (0.0f64, 0.0);
            for (a, b) in ours.iter().zip(&reference) {
                let d = (a.1 - b.1).hypot(a.2 - b.2);
                if d > worst {
                    (worst, at) = (d, a.0);
                }
            }
            assert!(
                worst < 5e-3,
                "{deg}° wheels {duty:?}, {solver:?}: {:.1} mm from the Coulomb reference at {at:.2} s",
                1e3 * worst
            );
        }
    }
}
