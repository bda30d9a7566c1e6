//! A robot rubbing along a wall: its motors differ a little, so it keeps turning
//! into the wall and slides along it with a light, steady push. The switch on that face must
//! read one steady state, not chatter: the 10^6-step soak found such a robot pressed in every
//! second sub-step (the position correction of the turning corner's micro-overlap pressed the
//! bumper whatever its force) and counted 11 collisions per 0.45 s step; and, once corrections
//! counted as the impulses they are, robots whose face force alternated around the operating
//! force between sub-steps, which a switch's release hysteresis absorbs.

use world::params::{BODY_WIDTH_M, BUMPER_FORCE_N, BUMPER_RELEASE_FORCE_N};
use world::{Arena, Pose, WheelCommand, World, WorldParams};

/// The robots' MCU clock the world counts in here: the robot's φ, 25 MHz (the world crate has
/// no clock of its own, and does not depend on the emulator that defines the robot's).
const CLOCK_HZ: u64 = 25_000_000;

/// Runs the robot along the wall y = 0 for `n` sub-steps of 20 ms with the left wheel at full
/// duty and the right at `right_duty` (turning it into the wall), and returns per sub-step
/// whether any switch was pressed and the body's distance from the wall.
fn rub(right_duty: f64, n: usize, release_n: f64) -> Vec<(bool, f64)> {
    let params = WorldParams {
        motor_gain_spread: 0.0,
        bumper_release_force_n: release_n,
        ..WorldParams::with_clock(CLOCK_HZ)
    };
    let pose = Pose {
        x_m: 0.4,
        y_m: BODY_WIDTH_M / 2.0 + 1e-4,
        heading_rad: (-0.035f64).to_radians(),
    };
    let arena = Arena::rectangle(4.0, 2.0).unwrap();
    let mut w = World::from_poses(arena, params, &[pose], 1).unwrap();
    w.set_wheels(
        0,
        WheelCommand::forward(1.0),
        WheelCommand::forward(right_duty),
    )
    .unwrap();
    (0..n)
        .map(|_| {
            w.advance(0.02).unwrap();
            let pressed = w.bumpers(0).unwrap().iter().any(|&b| b);
            // The lowest corner's height above the wall.
            let low = w
                .corners(0)
                .unwrap()
                .iter()
                .map(|&(_, y)| y)
                .fold(f64::INFINITY, f64::min);
            (pressed, low)
        })
        .collect()
}

fn press_starts(h: &[(bool, f64)]) -> usize {
    h.windows(2).filter(|w| !w[0].0 && w[1].0).count() + usize::from(h[0].0)
}

#[test]
fn a_light_steady_rub_along_a_wall_does_not_chatter() {
    for k in 0..=40 {
        let right = 1.0 - 0.0005 * f64::from(k);
        let h = rub(right, 300, BUMPER_RELEASE_FORCE_N);
        // It does rub: after the first second the lowest corner stays on the wall.
        let max_gap = h[50..].iter().map(|&(_, g)| g).fold(0.0, f64::max);
        assert!(max_gap < 5e-5, "right duty {right}: gap up to {max_gap} m");
        let starts = press_starts(&h);
        assert!(
            starts <= 1,
            "right duty {right}: {starts} separate presses in {} sub-steps: {:?}",
            h.len(),
            h.iter().map(|&(p, _)| u8::from(p)).collect::<Vec<_>>()
        );
    }
}

#[test]
fn a_robot_driven_into_the_wall_holds_its_switch() {
    // The same robot turning hard into the wall pushes with much of its traction: pressed
    // from first touch on, once.
    let h = rub(0.5, 150, BUMPER_RELEASE_FORCE_N);
    let first = h.iter().position(|&(p, _)| p).expect("never pressed");
    assert!(
        h[first..].iter().all(|&(p, _)| p),
        "released after first touch"
    );
    assert_eq!(press_starts(&h), 1);
}

#[test]
fn without_hysteresis_some_rub_chatters() {
    // What the hysteresis is for: a switch that released at its operating force would chatter
    // for some rub, its face force alternating around 0.1 N from one sub-step to the next.
    let chattering: Vec<f64> = (0..=40)
        .map(|k| 1.0 - 0.0005 * f64::from(k))
        .filter(|&right| press_starts(&rub(right, 300, BUMPER_FORCE_N)) > 1)
        .collect();
    eprintln!("chatter without hysteresis at right duty {chattering:?}");
    assert!(!chattering.is_empty());
}
