//! Tests of the whole world through its step: kinematics, motors, collisions, bumpers, rays
//! after motion, poses given by the caller, determinism and thread counts, errors. The stages'
//! own tests stand in their files (the broad phase and the rays against brute force,
//! placement; the geometry against `parry2d`).

// A test, example or bench may use the host's f64 functions (clippy.toml): it checks the
// models within tolerances, and its own output is not a promised result.
#![allow(clippy::disallowed_methods)]

use super::*;
use crate::geometry::{ray_obb, ray_walls};
use crate::motor::Behaviour;
use crate::params::{BODY_LENGTH_M, BODY_WIDTH_M, SensorMount};
use core::f64::consts::{FRAC_PI_2, PI};
use proptest::prelude::*;
use rand_pcg::Pcg64;

const HX: f64 = 0.5 * BODY_LENGTH_M;
const HY: f64 = 0.5 * BODY_WIDTH_M;
const V: f64 = 0.15;
const TAU: f64 = 0.060;

/// Default parameters with no motor-gain spread, so wheel speeds are exactly duty × top speed.
fn exact_params() -> WorldParams {
    WorldParams {
        motor_gain_spread: 0.0,
        ..WorldParams::with_clock(crate::params::TEST_CLOCK_HZ)
    }
}

fn pose(x_m: f64, y_m: f64, heading_rad: f64) -> Pose {
    Pose {
        x_m,
        y_m,
        heading_rad,
    }
}

fn world_at(arena: Arena, params: WorldParams, poses: &[Pose]) -> World {
    World::from_poses(arena, params, poses, 7).unwrap()
}

fn set_behaviour(w: &mut World, robot: usize, b: Behaviour) {
    let (l, r) = b.wheels();
    w.set_wheels(robot, l, r).unwrap();
}

fn run(w: &mut World, seconds: f64, dt: f64) {
    let n = (seconds / dt).round() as usize;
    for _ in 0..n {
        w.advance(dt).unwrap();
    }
}

/// Brute-force check that no body penetrates a wall or another body.
fn assert_no_penetration(w: &World) {
    for i in 0..w.robot_count() {
        assert!(
            !w.wall_penetration(i),
            "robot {i} penetrates a wall: {:?}",
            w.pose(i)
        );
        for j in i + 1..w.robot_count() {
            assert!(
                obb_overlap(&w.obb(i), &w.obb(j), 0.0).is_none(),
                "robots {i} and {j} overlap: {:?} {:?}",
                w.pose(i),
                w.pose(j)
            );
        }
    }
}

// ----- motors and kinematics ------------------------------------------------------------------

#[test]
fn straight_line_distance_is_v_t_less_the_lag() {
    let arena = Arena::rectangle(3.0, 1.0).unwrap();
    for (dt, label) in [(0.010, "10 ms"), (0.007, "7 ms"), (0.5, "one call")] {
        let mut w = world_at(arena, exact_params(), &[pose(0.3, 0.5, 0.0)]);
        w.set_wheels(0, WheelCommand::forward(1.0), WheelCommand::forward(1.0))
            .unwrap();
        let t = if dt == 0.007 { 0.497 } else { 0.5 };
        run(&mut w, t, dt);
        // From rest, a first-order lag covers v·(t − τ(1 − e^(−t/τ))).
        let expect = V * (t - TAU * (1.0 - (-t / TAU).exp()));
        let p = w.pose(0).unwrap();
        assert!(
            (p.x_m - 0.3 - expect).abs() < 1e-12,
            "{label}: {} vs {expect}",
            p.x_m - 0.3
        );
        assert!(
            (p.y_m - 0.5).abs() < 1e-15 && p.heading_rad.abs() < 1e-15,
            "{label}"
        );
        assert_eq!(w.bumpers(0).unwrap(), [false; 4]);
    }
}

#[test]
fn motor_lag_reaches_63_percent_after_tau() {
    for tau in [0.020, 0.060, 0.100] {
        let params = WorldParams {
            motor_time_constant_s: tau,
            ..exact_params()
        };
        let mut w = world_at(Arena::square(), params, &[pose(0.9, 0.9, 0.0)]);
        w.set_wheels(0, WheelCommand::forward(1.0), WheelCommand::reverse(0.5))
            .unwrap();
        run(&mut w, tau, tau / 8.0);
        let [l, r] = w.wheel_speeds(0).unwrap();
        let k = 1.0 - (-1.0f64).exp();
        assert!((l - k * V).abs() < 1e-12, "tau {tau}: left {l}");
        assert!((r + 0.5 * k * V).abs() < 1e-12, "tau {tau}: right {r}");
        assert!((l / V - 0.632).abs() < 0.001);
    }
}

#[test]
fn brake_and_coast_decay_with_their_own_time_constants() {
    let params = WorldParams {
        brake_time_constant_s: 0.020,
        coast_time_constant_s: 0.200,
        ..exact_params()
    };
    let mut w = world_at(Arena::square(), params, &[pose(0.3, 0.9, 0.0)]);
    w.set_wheels(0, WheelCommand::forward(1.0), WheelCommand::forward(1.0))
        .unwrap();
    run(&mut w, 0.6, 0.01); // 10 τ: at speed to 5e-5
    let [v0, _] = w.wheel_speeds(0).unwrap();
    w.set_wheels(0, WheelCommand::brake(), WheelCommand::coast())
        .unwrap();
    run(&mut w, 0.02, 0.005);
    let [l, r] = w.wheel_speeds(0).unwrap();
    assert!((l - v0 * (-1.0f64).exp()).abs() < 1e-12, "brake {l}");
    assert!((r - v0 * (-0.1f64).exp()).abs() < 1e-12, "coast {r}");
}

#[test]
fn turning_radius_matches_theory() {
    // Turn-left-forward: 0.3v left, v right; R = track/2 · (vr + vl)/(vr − vl).
    let track = WHEEL_TRACK;
    let (vl, vr) = (0.3 * V, V);
    let radius = 0.5 * track * (vr + vl) / (vr - vl);
    let omega = (vr - vl) / track;
    let mut w = world_at(Arena::square(), exact_params(), &[pose(0.9, 0.9, 0.0)]);
    set_behaviour(&mut w, 0, Behaviour::TurnLeftForward);
    run(&mut w, 2.0, 0.01); // 33 τ: the lag has settled
    let p0 = w.pose(0).unwrap();
    // Centre of the circle: `radius` to the robot's left.
    let (cx, cy) = (
        p0.x_m - radius * p0.heading_rad.sin(),
        p0.y_m + radius * p0.heading_rad.cos(),
    );
    for _ in 0..300 {
        w.advance(0.01).unwrap();
        let p = w.pose(0).unwrap();
        let r = (p.x_m - cx).hypot(p.y_m - cy);
        assert!((r - radius).abs() < 1e-9, "radius {r} vs {radius}");
    }
    let p1 = w.pose(0).unwrap();
    let turned = (p1.heading_rad - p0.heading_rad).rem_euclid(2.0 * PI);
    assert!((turned - (omega * 3.0).rem_euclid(2.0 * PI)).abs() < 1e-9);
    assert!((radius - 0.148_571_428_571).abs() < 1e-9);
}

const WHEEL_TRACK: f64 = crate::params::WHEEL_TRACK_M;

#[test]
fn arc_integration_does_not_depend_on_substep_length() {
    let params = WorldParams {
        max_substep_s: 0.1,
        ..exact_params()
    };
    let mut w = world_at(Arena::square(), params, &[pose(0.9, 0.9, 0.3)]);
    set_behaviour(&mut w, 0, Behaviour::TurnRightForward);
    run(&mut w, 3.0, 0.01); // 50 τ: wheel speeds constant to 1e-21
    let mut reference: Option<Pose> = None;
    // 1.11 s = 27 750 000 states at 25 MHz, in steps of 1 ms, 10 ms, 37 ms and 111 ms (the
    // last split into two 55.5 ms sub-steps).
    for (dt, step_states) in [
        (0.001, 25_000u64),
        (0.01, 250_000),
        (0.037, 925_000),
        (0.111, 2_775_000),
    ] {
        let mut c = w.clone();
        for _ in 0..27_750_000 / step_states {
            c.advance_states(step_states);
        }
        let p = c.pose(0).unwrap();
        if let Some(r) = reference {
            assert!(
                (p.x_m - r.x_m).abs() < 1e-12 && (p.y_m - r.y_m).abs() < 1e-12,
                "dt {dt}: {p:?} {r:?}"
            );
            assert!((p.heading_rad - r.heading_rad).abs() < 1e-12);
        }
        reference = Some(p);
    }
    // One call covering the whole time (split internally into 0.1 s pieces).
    let mut c = w.clone();
    c.advance(1.11).unwrap();
    let p = c.pose(0).unwrap();
    let r = reference.unwrap();
    assert!((p.x_m - r.x_m).abs() < 1e-12 && (p.y_m - r.y_m).abs() < 1e-12);
}

#[test]
fn arc_with_lag_transient_converges_with_substep_length() {
    // From rest the wheel speeds change within a sub-step; the mean-speed arc is then second
    // order accurate. 1 ms and 20 ms sub-steps agree to well under a millimetre.
    let run_with = |dt: f64| {
        let mut w = world_at(Arena::square(), exact_params(), &[pose(0.9, 0.9, 0.0)]);
        set_behaviour(&mut w, 0, Behaviour::TurnLeftForward);
        run(&mut w, 0.4, dt);
        w.pose(0).unwrap()
    };
    let a = run_with(0.001);
    let b = run_with(0.020);
    let d = (a.x_m - b.x_m).hypot(a.y_m - b.y_m);
    assert!(d < 1e-4, "{d}");
    assert!(
        (a.heading_rad - b.heading_rad).abs() < 1e-12,
        "heading change is exact"
    );
}

#[test]
fn motor_gains_are_seeded_per_robot_and_within_spread() {
    let a = World::new(
        Arena::scaled_square(20).unwrap(),
        WorldParams::with_clock(crate::params::TEST_CLOCK_HZ),
        20,
        99,
    )
    .unwrap();
    let b = World::new(
        Arena::scaled_square(5).unwrap(),
        WorldParams::with_clock(crate::params::TEST_CLOCK_HZ),
        5,
        99,
    )
    .unwrap();
    let c = World::new(
        Arena::scaled_square(5).unwrap(),
        WorldParams::with_clock(crate::params::TEST_CLOCK_HZ),
        5,
        100,
    )
    .unwrap();
    for i in 0..5 {
        assert_eq!(a.motor_gains(i).unwrap(), b.motor_gains(i).unwrap());
        assert_ne!(a.motor_gains(i).unwrap(), c.motor_gains(i).unwrap());
    }
    let mut distinct = std::collections::BTreeSet::new();
    for i in 0..20 {
        for g in a.motor_gains(i).unwrap() {
            assert!((0.95..=1.05).contains(&g), "{g}");
            distinct.insert(g.to_bits());
        }
    }
    assert_eq!(distinct.len(), 40);
    // The gain scales the commanded speed.
    let mut w = a.clone();
    w.set_wheels(3, WheelCommand::forward(0.5), WheelCommand::reverse(1.0))
        .unwrap();
    let g = w.motor_gains(3).unwrap();
    assert_eq!(w.motion[3].target, [0.5 * V * g[0], -V * g[1]]);
}

// ----- collisions and bumpers -----------------------------------------------------------------

#[test]
fn driving_into_a_wall_stops_at_it_and_presses_the_front_bumper() {
    let mut w = world_at(Arena::square(), exact_params(), &[pose(1.2, 0.9, 0.0)]);
    w.set_wheels(0, WheelCommand::forward(1.0), WheelCommand::forward(1.0))
        .unwrap();
    let mut pressed_at = None;
    for k in 0..500 {
        w.advance(0.01).unwrap();
        let p = w.pose(0).unwrap();
        assert!(
            p.x_m + HX <= 1.8,
            "penetrates at step {k}: {}",
            p.x_m + HX - 1.8
        );
        let b = w.bumpers(0).unwrap();
        if b[FRONT] && pressed_at.is_none() {
            pressed_at = Some(k);
        }
        if pressed_at.is_some() {
            assert_eq!(b, [true, false, false, false], "step {k}");
        }
    }
    // 1.8 − 1.2 − 0.115 = 0.485 m at ≤ 0.15 m/s: about 3.3 s.
    let k = pressed_at.expect("front bumper pressed");
    assert!((320..=345).contains(&k), "{k}");
    let p = w.pose(0).unwrap();
    // The speculative contact lets it close the gap to the 10 nm skin, no further (a position
    // correction may leave up to 10 µm).
    assert!(
        (1.8 - (p.x_m + HX)).abs() < 2e-5,
        "stops at the wall: gap {}",
        1.8 - (p.x_m + HX)
    );
    // Straight, to the solver's precision (its sweeps stop once impulses change < 1e-6 N·s).
    assert!(
        (p.y_m - 0.9).abs() < 1e-4 && p.heading_rad.abs() < 1e-5,
        "pushes straight: {p:?}"
    );
    // The wheels keep turning (they slip); the front sensor reads ~0.
    assert!((w.wheel_speeds(0).unwrap()[0] - V).abs() < 1e-9);
    assert!(w.sense(0, FRONT).unwrap().unwrap() < 0.02);
    // Stopping the motors releases the switch once the robot no longer pushes.
    w.set_wheels(0, WheelCommand::brake(), WheelCommand::brake())
        .unwrap();
    run(&mut w, 1.0, 0.01);
    assert_eq!(w.bumpers(0).unwrap(), [false; 4]);
}

#[test]
fn newton_pushes_with_full_traction_at_a_vanishing_slip_where_the_cap_lets_go() {
    // A robot drives into a wall, then brakes. The braked wheels' speed decays exponentially
    // (the motor's lag) and never reaches zero, so they still slip against the blocked body by
    // nanometres a second. Coulomb friction is the full traction at any slip: Newton's method,
    // solving to the fixed point, keeps the robot pressed to the wall with both wheels' traction
    // and the bumper pressed; the capped sweeps add m·slip a sweep, far below the traction in 12
    // sweeps, and let the bumper go.
    let braked = |until: crate::params::Convergence| {
        let params = if until == crate::params::Convergence::Impulse {
            exact_params()
        } else {
            WorldParams {
                solver_iterations: 256,
                solver_convergence: until,
                ..exact_params()
            }
        };
        let mut w = world_at(Arena::square(), params, &[pose(1.2, 0.9, 0.0)]);
        w.set_wheels(0, WheelCommand::forward(1.0), WheelCommand::forward(1.0))
            .unwrap();
        run(&mut w, 5.0, 0.01);
        w.set_wheels(0, WheelCommand::brake(), WheelCommand::brake())
            .unwrap();
        run(&mut w, 1.0, 0.01);
        let rim = w.wheel_speeds(0).unwrap()[0];
        let push: f64 = w.narrow.contacts.iter().map(|c| c.normal_impulse()).sum();
        (
            w.bumpers(0).unwrap()[FRONT],
            rim,
            push,
            w.body.wheel_force_n,
        )
    };
    let (pressed, rim, push, traction) = braked(crate::params::Convergence::Newton);
    assert!(rim > 0.0 && rim < 1e-7, "{rim}");
    assert!(pressed);
    let h = 0.01;
    assert!(
        (push - 2.0 * traction * h).abs() < 1e-6,
        "{push} against {}",
        2.0 * traction * h
    );
    let (pressed, _, push, _) = braked(crate::params::Convergence::Impulse);
    assert!(!pressed && push < 1e-6, "{push}");
}

#[test]
fn reversing_into_a_wall_presses_the_rear_bumper() {
    let mut w = world_at(Arena::square(), exact_params(), &[pose(0.5, 0.9, 0.0)]);
    w.set_wheels(0, WheelCommand::reverse(1.0), WheelCommand::reverse(1.0))
        .unwrap();
    run(&mut w, 4.0, 0.01);
    assert_eq!(w.bumpers(0).unwrap(), [false, true, false, false]);
    let p = w.pose(0).unwrap();
    assert!(p.x_m - HX >= 0.0 && p.x_m - HX < 2e-5, "{p:?}");
}

#[test]
fn head_on_robots_press_both_front_bumpers() {
    let mut w = world_at(
        Arena::square(),
        exact_params(),
        &[pose(0.5, 0.9, 0.0), pose(1.3, 0.9, PI)],
    );
    for r in 0..2 {
        set_behaviour(&mut w, r, Behaviour::Forward);
    }
    let mut both = false;
    for _ in 0..400 {
        w.advance(0.01).unwrap();
        assert_no_penetration(&w);
        let (a, b) = (w.bumpers(0).unwrap(), w.bumpers(1).unwrap());
        if a[FRONT] || b[FRONT] {
            assert_eq!(a, [true, false, false, false]);
            assert_eq!(b, [true, false, false, false]);
            both = true;
        }
    }
    assert!(both);
    let (p, q) = (w.pose(0).unwrap(), w.pose(1).unwrap());
    // They meet in the middle, touching.
    assert!(((p.x_m + q.x_m) / 2.0 - 0.9).abs() < 1e-5);
    assert!((q.x_m - p.x_m - 2.0 * HX).abs() < 2e-5);
}

#[test]
fn side_hits_press_left_and_right_bumpers() {
    // Robot 0 faces +x; robot 1 below it drives north into its right side, robot 2 above it
    // drives south into its left side.
    let mut w = world_at(
        Arena::square(),
        exact_params(),
        &[
            pose(0.9, 0.9, 0.0),
            pose(0.9, 0.5, FRAC_PI_2),
            pose(0.9, 1.3, -FRAC_PI_2),
        ],
    );
    set_behaviour(&mut w, 1, Behaviour::Forward);
    set_behaviour(&mut w, 2, Behaviour::Forward);
    let mut seen = [false; 3];
    for _ in 0..400 {
        w.advance(0.01).unwrap();
        assert_no_penetration(&w);
        let b0 = w.bumpers(0).unwrap();
        let b1 = w.bumpers(1).unwrap();
        let b2 = w.bumpers(2).unwrap();
        if b1[FRONT] {
            assert!(b0[RIGHT]);
            seen[1] = true;
        }
        if b2[FRONT] {
            assert!(b0[LEFT]);
            seen[2] = true;
        }
        if b0.iter().any(|&x| x) {
            assert!(!b0[FRONT] && !b0[REAR]);
            seen[0] = true;
        }
        assert!(!b1[REAR] && !b1[LEFT] && !b1[RIGHT]);
        assert!(!b2[REAR] && !b2[LEFT] && !b2[RIGHT]);
    }
    assert_eq!(seen, [true; 3]);
}

#[test]
fn corner_contacts_go_to_the_larger_normal_component() {
    // Heading 30° into the east wall: wall normal in the body frame (0.87, −0.5): front.
    let mut w = world_at(Arena::square(), exact_params(), &[pose(1.5, 0.6, PI / 6.0)]);
    set_behaviour(&mut w, 0, Behaviour::Forward);
    let mut hit = None;
    for _ in 0..300 {
        w.advance(0.01).unwrap();
        assert_no_penetration(&w);
        let b = w.bumpers(0).unwrap();
        if b.iter().any(|&x| x) {
            hit = Some(b);
            break;
        }
    }
    assert_eq!(hit, Some([true, false, false, false]));
    // Heading 60° next to the east wall: the right-front corner meets it; normal (0.5, −0.87)
    // in the body frame: right.
    let mut w = world_at(Arena::square(), exact_params(), &[pose(1.6, 0.4, PI / 3.0)]);
    set_behaviour(&mut w, 0, Behaviour::Forward);
    let mut hit = None;
    for _ in 0..300 {
        w.advance(0.01).unwrap();
        assert_no_penetration(&w);
        let b = w.bumpers(0).unwrap();
        if b.iter().any(|&x| x) {
            hit = Some(b);
            break;
        }
    }
    assert_eq!(hit, Some([false, false, false, true]));
}

#[test]
fn a_robot_pushing_another_into_a_wall_is_blocked_without_penetration() {
    let mut w = world_at(
        Arena::square(),
        exact_params(),
        &[pose(1.2, 0.9, 0.0), pose(1.5, 0.9, 0.0)],
    );
    set_behaviour(&mut w, 0, Behaviour::Forward);
    for _ in 0..600 {
        w.advance(0.01).unwrap();
        assert_no_penetration(&w);
    }
    let (p, q) = (w.pose(0).unwrap(), w.pose(1).unwrap());
    // Within the 10 µm a position correction may leave.
    assert!(1.8 - (q.x_m + HX) < 2e-5, "pushed to the wall: {p:?} {q:?}");
    assert!(q.x_m - p.x_m - 2.0 * HX < 2e-5, "touching");
    assert!(w.bumpers(0).unwrap()[FRONT]);
    assert!(w.bumpers(1).unwrap()[REAR]);
}

/// A robot pushing an idle robot (its motors coasting, its wheels held by the 203:1 gearbox)
/// pushes with its traction against the other's equal friction: the bump's momentum carries
/// them a little, then they stand pressed together, without penetrating, and nothing is
/// reset: the pusher's wheels slip.
#[test]
fn equal_traction_stalls_a_push_without_penetration() {
    let gap = 0.001;
    let mut w = world_at(
        Arena::square(),
        exact_params(),
        &[pose(0.5, 0.9, 0.0), pose(0.5 + 2.0 * HX + gap, 0.9, 0.0)],
    );
    set_behaviour(&mut w, 0, Behaviour::Forward);
    let x1 = w.pose(1).unwrap().x_m;
    for _ in 0..100 {
        w.advance(0.02).unwrap();
        assert_no_penetration(&w);
    }
    let pushed = w.pose(1).unwrap().x_m - x1;
    // A free robot would have gone 0.29 m in the 2 s.
    assert!(pushed < 0.05, "the idle robot moved {pushed} m");
    assert!(w.bumpers(0).unwrap()[FRONT] && w.bumpers(1).unwrap()[REAR]);
    assert_eq!(w.solver_stats().stopped_robot_substeps, 0);
}

/// A robot pushing one that drives the same way at 0.3 of its speed: the slower one's wheels
/// hold it at their speed with the same traction the pusher has, so the pair goes on at about
/// the slower speed, the pusher's wheels slipping; the pushed one feels it on its rear bumper.
#[test]
fn a_robot_pushes_a_slower_one_along() {
    let gap = 0.001;
    let mut w = world_at(
        Arena::rectangle(4.0, 1.8).unwrap(),
        exact_params(),
        &[pose(0.5, 0.9, 0.0), pose(0.5 + 2.0 * HX + gap, 0.9, 0.0)],
    );
    set_behaviour(&mut w, 0, Behaviour::Forward);
    w.set_wheels(1, WheelCommand::forward(0.3), WheelCommand::forward(0.3))
        .unwrap();
    let x1 = w.pose(1).unwrap().x_m;
    for _ in 0..200 {
        w.advance(0.02).unwrap();
        assert_no_penetration(&w);
    }
    let v1 = (w.pose(1).unwrap().x_m - x1) / 4.0;
    assert!(
        v1 > 0.3 * V * 0.9 && v1 < 0.3 * V * 1.5,
        "pushed robot at {v1} m/s"
    );
    let v0 = w.vel[0][0];
    assert!(v0 < 0.5 * V, "the pusher is held back: {v0} m/s");
    assert!(w.bumpers(1).unwrap()[REAR]);
}

/// Driving at a wall at an angle, the front corner's contact turns the robot square to the
/// wall (as a differential-drive robot does: its wheels hold it against sliding sideways), and
/// backing off frees it at once.
#[test]
fn a_robot_driving_into_a_wall_at_an_angle_turns_square_and_backs_off_freely() {
    let mut w = world_at(
        Arena::square(),
        exact_params(),
        &[pose(1.5, 0.9, 30f64.to_radians())],
    );
    set_behaviour(&mut w, 0, Behaviour::Forward);
    run(&mut w, 6.0, 0.02);
    let p = w.pose(0).unwrap();
    assert!(p.heading_rad.abs() < 1e-3, "square to the wall: {p:?}");
    assert!((1.8 - (p.x_m + HX)).abs() < 2e-5);
    assert!(w.bumpers(0).unwrap()[FRONT]);
    set_behaviour(&mut w, 0, Behaviour::Backward);
    run(&mut w, 2.0, 0.02);
    let q = w.pose(0).unwrap();
    assert!(p.x_m - q.x_m > 0.2, "backs off: {p:?} -> {q:?}");
    assert_eq!(w.bumpers(0).unwrap(), [false; 4]);
}

/// A robot squeezed from both sides by two robots driving into it, its own wheels driving it
/// sideways out of the squeeze: the friction of the two contacts (0.3 × about 2.9 N each)
/// is less than its traction, so it slides out while they push (the old solver, failing to
/// separate the three, reset them all and the middle one never moved). Nothing overlaps and
/// no robot's motion is cut short.
#[test]
fn a_squeezed_robot_with_open_floor_ahead_slides_out() {
    let gap = 0.002;
    let mut w = world_at(
        Arena::square(),
        exact_params(),
        &[
            pose(0.9 - HY - HX - gap, 0.6, 0.0),
            pose(0.9, 0.6, FRAC_PI_2),
            pose(0.9 + HY + HX + gap, 0.6, PI),
        ],
    );
    for r in 0..3 {
        set_behaviour(&mut w, r, Behaviour::Forward);
    }
    let mut squeezed = false;
    for _ in 0..150 {
        w.advance(0.02).unwrap();
        assert_no_penetration(&w);
        let b = w.bumpers(1).unwrap();
        squeezed |= b[LEFT] && b[RIGHT];
    }
    assert!(squeezed, "both sides pressed at some point");
    let p = w.pose(1).unwrap();
    assert!(p.y_m - 0.6 > 0.15, "the middle robot slid out: {p:?}");
    assert_eq!(w.solver_stats().stopped_robot_substeps, 0);
}

#[test]
fn veering_robot_in_the_corridor_slides_along_without_penetrating() {
    // A strong gain mismatch turns the robot into the corridor wall; it must not pass through
    // or stick, and it reaches the far end.
    let params = WorldParams {
        motor_gain_spread: 0.0,
        ..WorldParams::with_clock(crate::params::TEST_CLOCK_HZ)
    };
    let arena = Arena::paper_corridor();
    let mut w = world_at(arena, params, &[pose(0.3, 0.11, 0.0)]);
    w.set_wheels(0, WheelCommand::forward(0.8), WheelCommand::forward(1.0))
        .unwrap();
    let mut side = false;
    for _ in 0..3000 {
        w.advance(0.01).unwrap();
        assert_no_penetration(&w);
        let b = w.bumpers(0).unwrap();
        side |= b[LEFT] || b[FRONT];
    }
    assert!(side);
    let p = w.pose(0).unwrap();
    assert!(p.x_m > 2.5, "got stuck at {p:?}");
}

/// A test's random behaviours: stream `k` of the random-walk purpose under `seed`.
fn walk_rng(seed: u64, k: u64) -> Pcg64 {
    stream_rng(seed, Purpose::RandomWalk, k)
}

fn dense_swarm(seed: u64, n: usize, params: WorldParams) -> World {
    let params = WorldParams {
        placement_clearance_m: 0.01,
        ..params
    };
    let mut w = World::new(Arena::square(), params, n, seed).unwrap();
    let mut rng = walk_rng(seed, 1);
    for r in 0..n {
        set_behaviour(&mut w, r, Behaviour::ALL[(unit(&mut rng) * 4.0) as usize]);
    }
    w
}

fn shuffle_behaviours(w: &mut World, rng: &mut Pcg64) {
    for r in 0..w.robot_count() {
        set_behaviour(w, r, Behaviour::ALL[(unit(rng) * 4.0) as usize]);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// A crowded arena (20 robots in 1.8 m × 1.8 m, about 7 × the paper's density) with random
    /// behaviours: no body ever penetrates a wall or another body after a sub-step.
    #[test]
    fn crowded_swarm_never_penetrates(seed in any::<u64>(), dt in 0.002f64..0.1) {
        let params = WorldParams { max_substep_s: 0.1, ..WorldParams::with_clock(crate::params::TEST_CLOCK_HZ) };
        let mut w = dense_swarm(seed, 20, params);
        let mut rng = walk_rng(seed, 2);
        let steps = (12.0 / dt) as usize;
        let per_behaviour = (0.45 / dt).ceil() as usize;
        let mut contacts = 0;
        for k in 0..steps {
            if k % per_behaviour == 0 {
                shuffle_behaviours(&mut w, &mut rng);
            }
            w.advance(dt).unwrap();
            assert_no_penetration(&w);
            contacts += (0..20).filter(|&r| w.bumpers(r).unwrap().iter().any(|&b| b)).count();
        }
        prop_assert!(contacts > 0);
    }

    /// Fast robots (1 m/s) with long sub-steps still never penetrate.
    #[test]
    fn fast_robots_never_penetrate(seed in any::<u64>()) {
        let params = WorldParams {
            top_speed_m_per_s: 1.0,
            max_substep_s: 0.1,
            motor_time_constant_s: 0.02,
            ..WorldParams::with_clock(crate::params::TEST_CLOCK_HZ)
        };
        let mut w = dense_swarm(seed, 20, params);
        let mut rng = walk_rng(seed, 2);
        for k in 0..200 {
            if k % 5 == 0 {
                shuffle_behaviours(&mut w, &mut rng);
            }
            w.advance(0.1).unwrap();
            assert_no_penetration(&w);
        }
    }
}

// ----- wheel forces ---------------------------------------------------------------------------

/// The traction of one drive wheel with the default parameters: μ_floor · m·g/2, N.
fn traction_n() -> f64 {
    crate::params::MU_FLOOR * crate::params::MASS_KG * crate::params::GRAVITY_M_PER_S2 / 2.0
}

#[test]
fn a_robot_pushing_a_wall_at_full_duty_slips_at_its_traction() {
    // 0.485 m from the wall at 0.15 m/s: there in about 3.3 s, then pushing it.
    let mut w = world_at(Arena::square(), exact_params(), &[pose(1.2, 0.9, 0.0)]);
    w.set_wheels(0, WheelCommand::forward(1.0), WheelCommand::forward(1.0))
        .unwrap();
    run(&mut w, 4.0, 0.01);
    assert!(w.bumpers(0).unwrap()[FRONT], "pushing the wall");
    let f = traction_n();
    assert!((f - 1.471).abs() < 1e-3, "{f}");
    assert!((w.params().wheel_traction_n() - f).abs() < 1e-12);
    for k in 0..100 {
        w.advance(0.01).unwrap();
        let [l, r] = w.wheel_forces(0).unwrap();
        // Forward (the floor pushes the robot into the wall), each wheel at its traction.
        assert!(
            (l - f).abs() / f < 0.01,
            "step {k}: left {l} N against {f} N"
        );
        assert!(
            (r - f).abs() / f < 0.01,
            "step {k}: right {r} N against {f} N"
        );
        // The motors still turn the wheels at their commanded speed: they slip.
        assert_eq!(w.wheel_mean_speeds(0).unwrap(), [V, V]);
    }
    // Reversing into the opposite wall: the forces point backward.
    let mut w = world_at(Arena::square(), exact_params(), &[pose(0.5, 0.9, 0.0)]);
    w.set_wheels(0, WheelCommand::reverse(1.0), WheelCommand::reverse(1.0))
        .unwrap();
    run(&mut w, 4.0, 0.01);
    let [l, r] = w.wheel_forces(0).unwrap();
    assert!(
        (l + f).abs() / f < 0.01 && (r + f).abs() / f < 0.01,
        "{l} {r}"
    );
}

#[test]
fn a_free_robot_at_a_steady_speed_takes_no_force_from_the_floor() {
    let arena = Arena::rectangle(10.0, 10.0).unwrap();
    for b in [Behaviour::Forward, Behaviour::TurnLeftForward] {
        let mut w = world_at(arena, exact_params(), &[pose(5.0, 5.0, 0.3)]);
        set_behaviour(&mut w, 0, b);
        // Before the first sub-step: nothing.
        assert_eq!(w.wheel_forces(0).unwrap(), [0.0; 2]);
        // 1.2 s = 20 τ: the lag has settled (to 2e-9 of the speed).
        run(&mut w, 1.2, 0.01);
        let [l, r] = w.wheel_forces(0).unwrap();
        assert!(l.abs() < 1e-6 && r.abs() < 1e-6, "{b:?}: {l} {r}");
    }
}

#[test]
fn a_robot_accelerating_from_rest_takes_m_a_from_its_wheels() {
    let arena = Arena::rectangle(10.0, 10.0).unwrap();
    let params = exact_params();
    let (m, ht) = (params.mass_kg, 0.5 * params.wheel_track_m);
    let inertia = m * (BODY_LENGTH_M * BODY_LENGTH_M + BODY_WIDTH_M * BODY_WIDTH_M) / 12.0;
    let h = 0.01;
    // Straight ahead, then turning left from rest: both wheels accelerate, the right faster.
    for b in [Behaviour::Forward, Behaviour::TurnLeftForward] {
        let mut w = world_at(arena, params.clone(), &[pose(5.0, 5.0, 0.0)]);
        set_behaviour(&mut w, 0, b);
        let (mut along0, mut omega0) = (0.0, 0.0);
        let mut before = w.pose(0).unwrap();
        for k in 0..20 {
            w.advance(h).unwrap();
            let after = w.pose(0).unwrap();
            // The body's mean speeds over the sub-step, from its poses (the exact arc).
            let turn = after.heading_rad - before.heading_rad;
            let chord = (after.x_m - before.x_m).hypot(after.y_m - before.y_m);
            let along = if turn.abs() < 1e-15 {
                chord / h
            } else {
                chord / (2.0 * (turn / 2.0).sin()) * turn / h
            };
            let omega = turn / h;
            let (a, alpha) = ((along - along0) / h, (omega - omega0) / h);
            let [l, r] = w.wheel_forces(0).unwrap();
            // m·a = F_l + F_r, I·α = (F_r − F_l)·track/2.
            assert!(
                (l + r - m * a).abs() < 1e-6,
                "{b:?} step {k}: {l} + {r} vs {}",
                m * a
            );
            assert!(
                ((r - l) * ht - inertia * alpha).abs() < 1e-7,
                "{b:?} step {k}: {l}, {r} vs I·α {}",
                inertia * alpha
            );
            if b == Behaviour::Forward {
                // Straight: m·a/2 a wheel, the first 10 ms 0.296 N (the lag's mean speed over
                // the first sub-step is v·(1 − τ/h·(1 − e^(−h/τ))) = 11.8 mm/s).
                assert!((l - r).abs() < 1e-12 && (l - m * a / 2.0).abs() < 1e-6);
                if k == 0 {
                    let v1 = V * (1.0 - TAU / h * (1.0 - (-h / TAU).exp()));
                    assert!((l - m * v1 / h / 2.0).abs() < 1e-9, "{l}");
                    assert!((l - 0.296).abs() < 1e-3, "{l}");
                }
            }
            assert!(l > 0.0 && r > 0.0, "accelerating forward");
            (along0, omega0, before) = (along, omega, after);
        }
    }
}

#[test]
fn wheel_forces_never_exceed_the_traction_in_a_crowd() {
    let mut w = dense_swarm(5, 20, WorldParams::with_clock(crate::params::TEST_CLOCK_HZ));
    let mut rng = walk_rng(5, 2);
    let f = traction_n();
    let mut at_traction = 0;
    for k in 0..1200 {
        if k % 45 == 0 {
            shuffle_behaviours(&mut w, &mut rng);
        }
        w.advance(0.01).unwrap();
        for r in 0..20 {
            for x in w.wheel_forces(r).unwrap() {
                assert!(x.is_finite() && x.abs() <= f * (1.0 + 1e-12), "{x}");
                at_traction += usize::from(x.abs() > 0.99 * f);
            }
        }
    }
    assert!(at_traction > 0, "some wheels slipped");
}

// ----- sensor rays --------------------------------------------------------------------------

fn mm(w: &World, robot: usize, sensor: usize) -> f64 {
    w.sense(robot, sensor).unwrap().expect("a hit")
}

#[test]
fn rays_measure_known_wall_distances() {
    let w = world_at(Arena::square(), exact_params(), &[pose(0.9, 0.5, 0.0)]);
    assert!((mm(&w, 0, FRONT) - 785.0).abs() < 1e-9);
    assert!((mm(&w, 0, REAR) - 785.0).abs() < 1e-9);
    assert!((mm(&w, 0, LEFT) - 1210.0).abs() < 1e-9);
    assert!((mm(&w, 0, RIGHT) - 410.0).abs() < 1e-9);
    let w = world_at(
        Arena::square(),
        exact_params(),
        &[pose(0.9, 0.5, FRAC_PI_2)],
    );
    assert!((mm(&w, 0, FRONT) - 1185.0).abs() < 1e-9);
    assert!((mm(&w, 0, REAR) - 385.0).abs() < 1e-9);
    assert!((mm(&w, 0, LEFT) - 810.0).abs() < 1e-9);
    assert!((mm(&w, 0, RIGHT) - 810.0).abs() < 1e-9);
    // 45°: the front ray from (0.9 + 0.115/√2, 0.5 + 0.115/√2) meets x = 1.8 first.
    let w = world_at(Arena::square(), exact_params(), &[pose(0.9, 0.5, PI / 4.0)]);
    let ox = 0.9 + HX / 2f64.sqrt();
    assert!((mm(&w, 0, FRONT) - 1000.0 * (1.8 - ox) * 2f64.sqrt()).abs() < 1e-9);
}

#[test]
fn a_robot_in_front_is_hit_at_the_right_distance() {
    // Robot 1 turned 90° presents its side (half extent 0.09) to robot 0's front sensor.
    let w = world_at(
        Arena::square(),
        exact_params(),
        &[pose(0.5, 0.9, 0.0), pose(1.0, 0.9, FRAC_PI_2)],
    );
    assert!((mm(&w, 0, FRONT) - 1000.0 * (1.0 - HY - 0.5 - HX)).abs() < 1e-9);
    // And robot 1's left sensor (facing −x) sees robot 0's front face.
    assert!((mm(&w, 1, LEFT) - 1000.0 * (1.0 - HY - 0.5 - HX)).abs() < 1e-9);
    // A robot just off the ray is missed.
    let w = world_at(
        Arena::square(),
        exact_params(),
        &[pose(0.5, 0.9, 0.0), pose(1.0, 0.9 + HX + 1e-6, FRAC_PI_2)],
    );
    assert!((mm(&w, 0, FRONT) - 1000.0 * (1.8 - 0.5 - HX)).abs() < 1e-9);
}

#[test]
fn the_own_body_is_not_hit() {
    // A sensor at the body centre looking forward passes through its own body.
    let mut params = exact_params();
    params.sensor_mounts.push(SensorMount {
        x_m: 0.0,
        y_m: 0.0,
        angle_rad: 0.0,
    });
    let w = world_at(Arena::square(), params, &[pose(0.9, 0.9, 0.0)]);
    assert!((mm(&w, 0, 4) - 900.0).abs() < 1e-9);
}

#[test]
fn beyond_max_range_is_none() {
    let w = world_at(
        Arena::paper_corridor(),
        exact_params(),
        &[pose(0.3, 0.11, 0.0)],
    );
    assert_eq!(
        w.sense(0, FRONT).unwrap(),
        None,
        "2.585 m of empty corridor"
    );
    assert!((mm(&w, 0, REAR) - 185.0).abs() < 1e-9);
    assert!((mm(&w, 0, LEFT) - 20.0).abs() < 1e-9);
    assert!((mm(&w, 0, RIGHT) - 20.0).abs() < 1e-9);
    let params = WorldParams {
        sensor_max_range_m: 0.1,
        ..exact_params()
    };
    let w = world_at(Arena::paper_corridor(), params, &[pose(0.3, 0.11, 0.0)]);
    assert_eq!(w.sense(0, REAR).unwrap(), None);
    // A hit exactly at the range counts.
    let params = WorldParams {
        sensor_max_range_m: 0.185,
        ..exact_params()
    };
    let w = world_at(Arena::paper_corridor(), params, &[pose(0.3, 0.11, 0.0)]);
    assert!(w.sense(0, REAR).unwrap().is_some());
}

#[test]
fn a_cone_sees_what_the_axis_ray_misses() {
    let poses = [pose(0.5, 0.9, 0.0), pose(1.0, 0.9 + HX + 0.02, FRAC_PI_2)];
    let single = world_at(Arena::square(), exact_params(), &poses);
    let params = WorldParams {
        rays_per_sensor: 5,
        cone_half_angle_rad: 0.1,
        ..exact_params()
    };
    let cone = world_at(Arena::square(), params, &poses);
    let far = mm(&single, 0, FRONT);
    let near = mm(&cone, 0, FRONT);
    assert!((far - 1185.0).abs() < 1e-9);
    assert!(near < 500.0, "{near}");
}

// ----- rays against brute force after motion ----------------------------------------------------

/// The nearest hit by brute force over every wall and robot.
fn brute_sense(w: &World, robot: usize, sensor: usize) -> Option<f64> {
    let m = &w.mounts[sensor];
    let b = w.pose[robot];
    let ox = b.x + b.c * m.x - b.s * m.y;
    let oy = b.y + b.s * m.x + b.c * m.y;
    let range = w.params.sensor_max_range_m;
    let mut best: Option<f64> = None;
    for &(dc, ds) in &m.dirs {
        let dx = b.c * dc - b.s * ds;
        let dy = b.s * dc + b.c * ds;
        let mut t = ray_walls(ox, oy, dx, dy, w.arena.width_m(), w.arena.height_m());
        for j in 0..w.robot_count() {
            if j != robot
                && let Some(tj) = ray_obb(ox, oy, dx, dy, &w.obb(j), f64::INFINITY)
            {
                t = t.min(tj);
            }
        }
        if t <= range && best.is_none_or(|bt| t < bt) {
            best = Some(t);
        }
    }
    best.map(|t| t * 1000.0)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// After real motion (the grid is a sub-step old and robots moved since), rays still equal
    /// brute force.
    #[test]
    fn rays_equal_brute_force_after_motion(seed in any::<u64>(), n in 1usize..60, steps in 0usize..200) {
        let params = WorldParams { rays_per_sensor: 2, cone_half_angle_rad: 0.03, ..WorldParams::with_clock(crate::params::TEST_CLOCK_HZ) };
        let mut w = World::new(Arena::scaled_square(n).unwrap(), params, n, seed).unwrap();
        let mut rng = walk_rng(seed, 3);
        for k in 0..steps {
            if k % 45 == 0 {
                shuffle_behaviours(&mut w, &mut rng);
            }
            w.advance(0.01).unwrap();
        }
        for r in 0..n {
            for s in 0..4 {
                prop_assert_eq!(w.sense(r, s).unwrap(), brute_sense(&w, r, s));
            }
        }
    }
}

// ----- placement and poses given by the caller ----------------------------------------------------

/// A world of no robots is a world, and advances.
#[test]
fn an_empty_world_advances() {
    let mut w = World::new(
        Arena::square(),
        WorldParams::with_clock(crate::params::TEST_CLOCK_HZ),
        0,
        1,
    )
    .unwrap();
    assert_eq!(w.robot_count(), 0);
    w.advance(0.01).unwrap();
}

#[test]
fn from_poses_rejects_overlaps_and_bodies_outside() {
    let e = World::from_poses(
        Arena::square(),
        WorldParams::with_clock(crate::params::TEST_CLOCK_HZ),
        &[pose(0.1, 0.9, 0.0)],
        1,
    )
    .unwrap_err();
    assert!(
        matches!(e, WorldError::PoseOutsideArena { robot: 0, .. }),
        "{e}"
    );
    let e = World::from_poses(
        Arena::square(),
        WorldParams::with_clock(crate::params::TEST_CLOCK_HZ),
        &[
            pose(0.9, 0.9, 0.0),
            pose(0.5, 0.9, 0.0),
            pose(1.1, 0.9, 0.0),
        ],
        1,
    )
    .unwrap_err();
    assert!(
        matches!(e, WorldError::PosesOverlap { a: 0, b: 2, .. }),
        "{e}"
    );
    let e = World::from_poses(
        Arena::square(),
        WorldParams::with_clock(crate::params::TEST_CLOCK_HZ),
        &[pose(f64::NAN, 0.9, 0.0)],
        1,
    )
    .unwrap_err();
    assert!(matches!(e, WorldError::PoseOutsideArena { .. }));
    let mut w = World::from_poses(
        Arena::square(),
        WorldParams::with_clock(crate::params::TEST_CLOCK_HZ),
        &[pose(0.5, 0.9, 0.0), pose(1.2, 0.9, 0.0)],
        1,
    )
    .unwrap();
    assert!(w.set_pose(1, pose(0.6, 0.9, 1.0)).is_err());
    assert_eq!(w.pose(1).unwrap().x_m, 1.2);
    assert!(w.set_pose(1, pose(1.79, 0.9, 1.0)).is_err());
    w.set_pose(1, pose(0.9, 0.5, 1.0)).unwrap();
    assert!((w.sense(0, FRONT).unwrap().unwrap() - 1000.0 * (1.8 - 0.5 - HX)).abs() < 1e-9);
}

// ----- determinism ----------------------------------------------------------------------------

fn state_bits(w: &World) -> Vec<u64> {
    let mut v = Vec::new();
    for i in 0..w.robot_count() {
        let b = w.pose[i];
        v.extend([b.x, b.y, b.c, b.s].map(f64::to_bits));
        v.extend(w.motion[i].speed.map(f64::to_bits));
        v.extend(w.wheel_force[i].map(f64::to_bits));
        v.push(u64::from(w.bumpers.bits(i)));
    }
    v
}

fn drive_run(w: &mut World, steps: usize, seed: u64, parallel: bool) {
    let mut rng = walk_rng(seed, 4);
    for k in 0..steps {
        if k % 45 == 0 {
            shuffle_behaviours(w, &mut rng);
        }
        if parallel {
            w.advance_par(0.01).unwrap();
        } else {
            w.advance(0.01).unwrap();
        }
    }
}

#[test]
fn same_seed_gives_identical_state_after_10000_substeps() {
    let n = 30;
    let mk = || {
        World::new(
            Arena::scaled_square(n).unwrap(),
            WorldParams::with_clock(crate::params::TEST_CLOCK_HZ),
            n,
            2024,
        )
        .unwrap()
    };
    let (mut a, mut b) = (mk(), mk());
    drive_run(&mut a, 10_000, 1, false);
    drive_run(&mut b, 10_000, 1, false);
    assert_eq!(state_bits(&a), state_bits(&b));
    assert_eq!(a.substeps(), 10_000);
    assert!((a.elapsed_s() - 100.0).abs() < 1e-9);
    // And the robots did move and collide.
    let c = mk();
    assert_ne!(state_bits(&a), state_bits(&c));
    assert_no_penetration(&a);
}

#[test]
fn thread_count_does_not_change_the_result() {
    // 4 500 robots: the per-robot stages on the pool too (from PAR_STAGE_ROBOTS), nine
    // parallel chunks; dense enough (6× paper density) for contacts in chunks too.
    let n = 4500;
    assert!(n >= crate::pipeline::par::PAR_STAGE_ROBOTS);
    let side = Arena::scaled_square(n).unwrap().width_m() / 6f64.sqrt();
    let arena = Arena::rectangle(side, side).unwrap();
    let mk = || {
        World::new(
            arena,
            WorldParams::with_clock(crate::params::TEST_CLOCK_HZ),
            n,
            77,
        )
        .unwrap()
    };
    let mut seq = mk();
    drive_run(&mut seq, 300, 9, false);
    let reference = state_bits(&seq);
    assert!(
        (0..seq.robot_count()).any(|i| seq.bumpers.bits(i) != 0),
        "some contacts happened"
    );
    // Enough robots in contact that the solved robots' stages run in parallel chunks.
    let st = seq.solver_stats();
    assert!(
        st.active_robot_substeps > st.substeps * PAR_CHUNK as u64,
        "{} solved robot-sub-steps in {} sub-steps",
        st.active_robot_substeps,
        st.substeps
    );
    // The position corrections ran, so their statistics below are compared where they count.
    assert!(st.overlap_substeps > 0 && st.position_sweeps > 0, "{st:?}");
    for threads in [1, 2, 3, 4] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut w = mk();
        pool.install(|| drive_run(&mut w, 300, 9, true));
        assert_eq!(state_bits(&w), reference, "{threads} threads");
        assert_eq!(w.solver_stats(), st, "{threads} threads");
    }
}

/// A square arena at 6× the paper's density for `n` robots.
fn crowded_arena(n: usize) -> Arena {
    let side = Arena::scaled_square(n).unwrap().width_m() / 6f64.sqrt();
    Arena::rectangle(side, side).unwrap()
}

/// `n` robots placed in `arena` (seed 31) under the given solver.
fn solver_world(
    arena: Arena,
    n: usize,
    iterations: u32,
    until: crate::params::Convergence,
) -> World {
    let params = WorldParams {
        solver_iterations: iterations,
        solver_convergence: until,
        ..WorldParams::with_clock(crate::params::TEST_CLOCK_HZ)
    };
    World::new(arena, params, n, 31).unwrap()
}

/// `n` robots in an arena at 6× the paper's density, driven for 250 sub-steps of 10 ms under
/// the given solver (on `threads` of a pool, or in order): their state and what the solver did.
fn crowded_run(
    n: usize,
    iterations: u32,
    until: crate::params::Convergence,
    threads: Option<usize>,
) -> (Vec<u64>, SolverStats) {
    let mut w = solver_world(crowded_arena(n), n, iterations, until);
    match threads {
        None => drive_run(&mut w, 250, 5, false),
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
            .install(|| drive_run(&mut w, 250, 5, true)),
    }
    assert_no_penetration(&w);
    (state_bits(&w), w.solver_stats())
}

#[test]
fn the_capped_solver_depends_on_its_cap_and_the_converged_one_does_not() {
    use crate::params::Convergence::{Impulse, Velocity};
    // Stopped on the impulses, 12 sweeps are not enough for many islands (counted), and one
    // sweep more changes the answer.
    let (capped12, st12) = crowded_run(300, 12, Impulse, None);
    let (capped13, _) = crowded_run(300, 13, Impulse, None);
    assert!(st12.capped_islands * 20 > st12.islands, "{st12:?}");
    assert_ne!(capped12, capped13);
    // Stopped on the velocities, every island of this run converges before 200 sweeps, so
    // the answer is the same under any cap it does not reach.
    let (conv256, st256) = crowded_run(300, 256, Velocity, None);
    let (conv200, st200) = crowded_run(300, 200, Velocity, None);
    assert_eq!(st256.capped_islands, 0, "{st256:?}");
    assert_eq!(st200, st256);
    assert_eq!(conv200, conv256);
}

/// Over 40 sub-steps of a crowded arena after 100 of driving, each solved with
/// `iterations`/`until` and, from the same state, with the `reference` solver: the largest and
/// the mean difference of a solved robot's velocity (turn rate at the half-diagonal), m/s.
fn apart_from(
    iterations: u32,
    until: crate::params::Convergence,
    reference: crate::params::Convergence,
) -> (f64, f64) {
    let n = 300;
    let mut w = solver_world(crowded_arena(n), n, iterations, until);
    drive_run(&mut w, 100, 5, false);
    let radius = w.body.radius_m;
    let (mut worst, mut sum, mut count) = (0.0f64, 0.0, 0u32);
    for _ in 0..40 {
        let mut other = w.clone();
        other.params.solver_convergence = reference;
        other.params.solver_iterations = 256;
        w.advance(0.01).unwrap();
        other.advance(0.01).unwrap();
        for (a, b) in w.vel.iter().zip(&other.vel) {
            let d = (a[0] - b[0])
                .abs()
                .max((a[1] - b[1]).abs())
                .max((a[2] - b[2]).abs() * radius);
            if d > 0.0 {
                worst = worst.max(d);
                sum += d;
                count += 1;
            }
        }
    }
    (worst, sum / f64::from(count.max(1)))
}

#[test]
fn the_sweeps_stop_short_of_the_fixed_point_newton_reaches() {
    use crate::params::Convergence::{Impulse, Newton, Velocity};
    // Measured (docs/physics.md), each from the same state as Newton's answer: 256 sweeps under
    // the impulse test (a fixed point of the sweeps for all but a few islands) are 1.3 µm/s
    // from it on average and 0.10 mm/s at worst, so the two solvers agree; the velocity test
    // stops 0.11 and 10.8 mm/s from it, the 12-sweep cap 0.05 and 3.8 mm/s, one sweep 2.7 and
    // 43 mm/s.
    let long = apart_from(256, Impulse, Newton);
    assert!(long.1 < 1e-5 && long.0 < 1e-3, "{long:?}");
    let velocity = apart_from(256, Velocity, Newton);
    let capped = apart_from(12, Impulse, Newton);
    let one_sweep = apart_from(1, Impulse, Newton);
    assert!(velocity.0 > 1e-3 && velocity.1 < 5e-4, "{velocity:?}");
    assert!(capped.0 > 1e-3 && capped.1 < 5e-4, "{capped:?}");
    assert!(one_sweep.1 > 1e-3, "{one_sweep:?}");
}

#[test]
fn the_converged_solver_gives_the_same_answer_on_any_thread_count() {
    use crate::params::Convergence::Velocity;
    // Enough robots in contact that the islands are solved on the pool, each with its share
    // of the sweep-start velocities.
    let (conv256, st256) = crowded_run(600, 256, Velocity, None);
    assert!(
        st256.active_robot_substeps
            > st256.substeps * crate::pipeline::par::PAR_ISLAND_ROBOTS as u64
    );
    for threads in [1, 2, 3] {
        let (par, st) = crowded_run(600, 256, Velocity, Some(threads));
        assert_eq!(par, conv256, "{threads} threads");
        assert_eq!(st, st256, "{threads} threads");
    }
}

// ----- errors ---------------------------------------------------------------------------------

#[test]
fn bad_parameters_and_indices_are_errors() {
    let bad = |f: fn(&mut WorldParams)| {
        let mut p = WorldParams::with_clock(crate::params::TEST_CLOCK_HZ);
        f(&mut p);
        World::new(Arena::square(), p, 3, 1).unwrap_err()
    };
    let e = bad(|p| p.motor_time_constant_s = 0.019);
    assert!(
        matches!(
            e,
            WorldError::TimeConstant {
                name: "motor_time_constant_s",
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("0.02..=0.1 s"), "{e}");
    assert!(matches!(
        bad(|p| p.motor_time_constant_s = 0.101),
        WorldError::TimeConstant { .. }
    ));
    assert!(matches!(
        bad(|p| p.motor_time_constant_s = f64::NAN),
        WorldError::TimeConstant { .. }
    ));
    assert!(matches!(
        bad(|p| p.brake_time_constant_s = 0.0),
        WorldError::TimeConstant { .. }
    ));
    assert!(matches!(
        bad(|p| p.top_speed_m_per_s = 0.0),
        WorldError::TopSpeed { .. }
    ));
    assert!(matches!(
        bad(|p| p.top_speed_m_per_s = -1.0),
        WorldError::TopSpeed { .. }
    ));
    assert!(matches!(
        bad(|p| p.top_speed_m_per_s = f64::NAN),
        WorldError::TopSpeed { .. }
    ));
    assert!(matches!(
        bad(|p| p.top_speed_m_per_s = 5.0),
        WorldError::TopSpeed { .. }
    ));
    assert!(matches!(
        bad(|p| p.wheel_track_m = f64::NAN),
        WorldError::Parameter {
            name: "wheel_track_m",
            ..
        }
    ));
    assert!(matches!(
        bad(|p| p.max_substep_s = 0.0),
        WorldError::Parameter {
            name: "max_substep_s",
            ..
        }
    ));
    assert!(matches!(
        bad(|p| p.rays_per_sensor = 0),
        WorldError::Parameter { .. }
    ));
    assert!(matches!(
        bad(|p| p.sensor_mounts[0].x_m = 0.2),
        WorldError::Parameter { .. }
    ));
    assert!(matches!(
        bad(|p| p.motor_gain_spread = -0.1),
        WorldError::Parameter { .. }
    ));

    let mut w = World::new(
        Arena::square(),
        WorldParams::with_clock(crate::params::TEST_CLOCK_HZ),
        3,
        1,
    )
    .unwrap();
    for dt in [0.0, -0.01, f64::NAN, f64::INFINITY, 1e9] {
        let e = w.advance(dt).unwrap_err();
        assert!(matches!(e, WorldError::TimeStep { .. }), "{e}");
    }
    let e = w.pose(3).unwrap_err();
    assert_eq!(e, WorldError::RobotIndex { index: 3, count: 3 });
    assert!(
        e.to_string().contains("robot index 3 is out of range"),
        "{e}"
    );
    assert!(w.bumpers(usize::MAX).is_err());
    assert!(w.wheel_speeds(9).is_err());
    assert!(w.corners(9).is_err());
    assert!(
        w.set_wheels(9, WheelCommand::coast(), WheelCommand::coast())
            .is_err()
    );
    let e = w
        .set_wheels(0, WheelCommand::forward(1.5), WheelCommand::coast())
        .unwrap_err();
    assert!(matches!(e, WorldError::Duty { wheel: "left", .. }), "{e}");
    let e = w
        .set_wheels(0, WheelCommand::coast(), WheelCommand::forward(f64::NAN))
        .unwrap_err();
    assert!(matches!(e, WorldError::Duty { wheel: "right", .. }), "{e}");
    let e = w.sense(0, 4).unwrap_err();
    assert_eq!(e, WorldError::UnknownSensor { index: 4, count: 4 });
    assert!(w.sense(5, 0).is_err());
    let e = w.corridor_gap_cv().unwrap_err();
    assert!(matches!(e, WorldError::NotACorridor { .. }), "{e}");
}

// ----- corridor metric and outlines -------------------------------------------------------------

#[test]
fn corridor_gaps_and_their_coefficient_of_variation() {
    let w = world_at(
        Arena::paper_corridor(),
        exact_params(),
        &[
            pose(2.0, 0.11, PI),
            pose(0.5, 0.11, 0.0),
            pose(1.0, 0.11, 0.0),
        ],
    );
    let mut g = Vec::new();
    w.corridor_gaps_m(&mut g).unwrap();
    assert_eq!(g.len(), 2);
    assert!((g[0] - (0.5 - 2.0 * HX)).abs() < 1e-12);
    assert!((g[1] - (1.0 - 2.0 * HX)).abs() < 1e-12);
    let (a, b) = (g[0], g[1]);
    let mean = 0.5 * (a + b);
    let cv = (0.5 * ((a - mean).powi(2) + (b - mean).powi(2))).sqrt() / mean;
    assert!((w.corridor_gap_cv().unwrap().unwrap() - cv).abs() < 1e-12);
    assert!(coefficient_of_variation(&[0.2, 0.2, 0.2]).unwrap() < 1e-15);
    assert_eq!(coefficient_of_variation(&[]), None);
    let one = world_at(
        Arena::paper_corridor(),
        exact_params(),
        &[pose(1.0, 0.11, 0.0)],
    );
    assert_eq!(one.corridor_gap_cv().unwrap(), None);
}

#[test]
fn corners_outline_the_body() {
    let w = world_at(
        Arena::square(),
        exact_params(),
        &[pose(0.9, 0.9, FRAC_PI_2)],
    );
    let c = w.corners(0).unwrap();
    let expect = [
        (0.9 - HY, 0.9 + HX),
        (0.9 - HY, 0.9 - HX),
        (0.9 + HY, 0.9 - HX),
        (0.9 + HY, 0.9 + HX),
    ];
    for (a, b) in c.iter().zip(expect) {
        assert!(
            (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12,
            "{a:?} {b:?}"
        );
    }
}

// ----- nothing a caller passes panics -----------------------------------------------------------

fn wild() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(0.0),
        Just(-0.0),
        Just(-1.0),
        Just(5e-324),
        Just(1e-300),
        Just(1e300),
        Just(f64::MAX),
        -10.0f64..10.0,
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Wild parameters, poses, commands, time steps and indices give errors, never panics.
    #[test]
    fn wild_inputs_never_panic(
        field in 0usize..12,
        value in wild(),
        poses in proptest::collection::vec((wild(), wild(), wild()), 0..4),
        duty in wild(),
        dt in prop_oneof![wild(), Just(0.01), Just(0.5)],
        robot in 0usize..6,
        sensor in 0usize..6,
        arena_w in wild(),
        arena_h in wild(),
        n in 0usize..60,
        seed in any::<u64>(),
    ) {
        let mut p = WorldParams::with_clock(crate::params::TEST_CLOCK_HZ);
        match field {
            0 => p.body_length_m = value,
            1 => p.body_width_m = value,
            2 => p.top_speed_m_per_s = value,
            3 => p.motor_time_constant_s = value,
            4 => p.brake_time_constant_s = value,
            5 => p.coast_time_constant_s = value,
            6 => p.motor_gain_spread = value,
            7 => p.wheel_track_m = value,
            8 => p.max_substep_s = value,
            9 => p.cone_half_angle_rad = value,
            10 => p.sensor_max_range_m = value,
            _ => p.placement_clearance_m = value,
        }
        let arenas = [
            Arena::rectangle(arena_w, arena_h),
            Arena::corridor(arena_w),
            Ok(Arena::square()),
            Arena::scaled_square(n),
        ];
        for arena in arenas.into_iter().flatten() {
            let _ = World::new(arena, p.clone(), n, seed);
            let ps: Vec<Pose> = poses.iter().map(|&(x, y, h)| pose(x, y, h)).collect();
            let _ = World::from_poses(arena, p.clone(), &ps, seed);
        }
        let mut w = World::new(Arena::square(), WorldParams::with_clock(crate::params::TEST_CLOCK_HZ), 3, seed).unwrap();
        let _ = w.set_wheels(robot, WheelCommand::forward(duty), WheelCommand::reverse(duty));
        let _ = w.set_wheels(robot, WheelCommand::brake(), WheelCommand::coast());
        let _ = w.advance(dt);
        let _ = w.advance_par(dt);
        let _ = w.sense(robot, sensor);
        let _ = w.bumpers(robot);
        let _ = w.pose(robot);
        let _ = w.corners(robot);
        if let Some(&(x, y, h)) = poses.first() {
            let _ = w.set_pose(robot, pose(x, y, h));
        }
        assert_no_penetration(&w);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// In the corridor (paper env. 1: forward and backward only, 0.60 s steps) robots never
    /// penetrate, and never pass each other: two 180 mm bodies do not fit side by side in
    /// 220 mm, so the order along the corridor is kept.
    #[test]
    fn corridor_robots_keep_their_order(seed in any::<u64>(), n in 2usize..9) {
        let mut w = World::new(Arena::paper_corridor(), WorldParams::with_clock(crate::params::TEST_CLOCK_HZ), n, seed).unwrap();
        let order = |w: &World| {
            let mut o: Vec<usize> = (0..w.robot_count()).collect();
            o.sort_by(|&a, &b| w.pose[a].x.total_cmp(&w.pose[b].x));
            o
        };
        let start = order(&w);
        let mut rng = walk_rng(seed, 5);
        for k in 0..6000 {
            if k % 60 == 0 {
                for r in 0..n {
                    let b = if unit(&mut rng) < 0.5 { Behaviour::Forward } else { Behaviour::Backward };
                    set_behaviour(&mut w, r, b);
                }
            }
            w.advance(0.01).unwrap();
            assert_no_penetration(&w);
        }
        prop_assert_eq!(order(&w), start);
        let mut gaps = Vec::new();
        w.corridor_gaps_m(&mut gaps).unwrap();
        prop_assert_eq!(gaps.len(), n - 1);
        prop_assert!(gaps.iter().all(|&g| g >= 0.0));
    }
}

/// Each island's size and distance from the fixed point (m/s, the largest natural residual of
/// its rows after the solve) over 40 sub-steps of a crowded arena after 100 of driving, solved
/// with `iterations`/`until` (Newton's method stopped after `newton_outer` outer iterations).
fn fixed_point_residuals(
    iterations: u32,
    until: crate::params::Convergence,
    newton_outer: u32,
) -> (Vec<(usize, f64)>, SolverStats) {
    residuals_in(crowded_arena(300), 300, iterations, until, newton_outer)
}

/// [`fixed_point_residuals`] in any arena, `n` robots.
fn residuals_in(
    arena: Arena,
    n: usize,
    iterations: u32,
    until: crate::params::Convergence,
    newton_outer: u32,
) -> (Vec<(usize, f64)>, SolverStats) {
    let mut w = solver_world(arena, n, iterations, until);
    drive_run(&mut w, 100, 5, false);
    w.islands.newton_limits.max_outer = newton_outer;
    w.islands.residuals = Some(Vec::new());
    for _ in 0..40 {
        w.advance(0.01).unwrap();
    }
    (w.islands.residuals.take().unwrap(), w.solver_stats())
}

#[test]
fn newton_reaches_the_fixed_point_where_the_sweeps_do_not() {
    use crate::params::Convergence::{Impulse, Newton, Velocity};
    use crate::params::NEWTON_MAX_OUTER;
    // Measured (docs/physics.md): Newton's solve leaves every island within 0.1 µm/s of its
    // fixed point (its stop); the 12-sweep capped solve and the velocity test leave about half
    // the islands more than 1 µm/s from it, the worst 10 mm/s.
    let apart = |r: &[(usize, f64)], by: f64| r.iter().filter(|x| x.1 > by || x.1.is_nan()).count();
    let (newton, st) = fixed_point_residuals(256, Newton, NEWTON_MAX_OUTER);
    assert!(newton.len() > 1000, "{st:?}");
    assert_eq!(st.newton_islands, st.islands, "{st:?}");
    assert_eq!(apart(&newton, 2e-7), 0, "{st:?}");
    assert!(st.capped_islands * 200 < st.islands, "{st:?}");
    for until in [Impulse, Velocity] {
        let (r, _) = fixed_point_residuals(if until == Impulse { 12 } else { 256 }, until, 0);
        assert!(apart(&r, 1e-6) * 4 > r.len(), "{until:?}");
        assert!(apart(&r, 1e-3) > 0, "{until:?}");
    }
    // The corridor: ten robots in a line between two walls 4 cm wider than a robot, pressed
    // against walls and each other (measured: Newton's worst 0.10 µm/s over 207 islands; the
    // capped solve leaves 120 of 208 more than 1 µm/s from the fixed point, the worst 5.7
    // mm/s).
    let corridor = Arena::corridor_with_clearance(BODY_WIDTH_M, 0.04).unwrap();
    let (r, st) = residuals_in(corridor, 10, 256, Newton, NEWTON_MAX_OUTER);
    assert!(r.len() > 100, "{st:?}");
    assert_eq!(apart(&r, 2e-7), 0, "{st:?}");
    let (r, _) = residuals_in(corridor, 10, 12, Impulse, 0);
    assert!(apart(&r, 1e-6) * 10 > r.len());
    // A Newton solve stopped after one outer iteration and called converged: the measure
    // finds it.
    let (early, _) = fixed_point_residuals(256, Newton, 1);
    assert!(apart(&early, 1e-6) * 10 > early.len());
}

#[test]
fn islands_too_large_for_newton_are_swept_and_counted() {
    use crate::params::Convergence::{Impulse, Newton};
    // With Newton's largest island lowered to one robot, every island of two or more is swept
    // under the impulse test, counted apart, and gives the answer the sweeps give.
    let run = |until, limit: Option<usize>| {
        let n = 300;
        let mut w = solver_world(crowded_arena(n), n, 256, until);
        if let Some(k) = limit {
            w.islands.newton_limits.max_robots = k;
        }
        drive_run(&mut w, 60, 5, false);
        (state_bits(&w), w.solver_stats())
    };
    let (_, all) = run(Newton, None);
    let (_, some) = run(Newton, Some(1));
    assert_eq!(all.newton_islands, all.islands);
    assert_eq!(all.solver_sweeps, 0);
    assert!(
        some.newton_islands > 0 && some.newton_islands < some.islands,
        "{some:?}"
    );
    assert!(
        some.solver_sweeps > some.islands - some.newton_islands,
        "{some:?}"
    );
    // Nothing but sweeps: the same as the impulse test under the same cap.
    assert_eq!(run(Newton, Some(0)).0, run(Impulse, None).0);
}

#[test]
fn newtons_answer_is_the_same_on_any_thread_count() {
    use crate::params::Convergence::Newton;
    let (reference, st) = crowded_run(600, 256, Newton, None);
    assert!(
        st.active_robot_substeps > st.substeps * crate::pipeline::par::PAR_ISLAND_ROBOTS as u64
    );
    assert_eq!(st.newton_islands, st.islands);
    // No island is large enough for the sweeps, so their cap does not enter the answer.
    assert_eq!(crowded_run(600, 12, Newton, None), (reference.clone(), st));
    for threads in [1, 2, 3] {
        let (par, st_par) = crowded_run(600, 256, Newton, Some(threads));
        assert_eq!(par, reference, "{threads} threads");
        assert_eq!(st_par, st, "{threads} threads");
    }
}
