//! The charge meter in the world and in the swarm: a robot pressed against a wall draws the
//! current that holds its slipping wheels' friction (the world's wheel forces at its traction),
//! not its stall current; a free one its no-load current; the swarm's `energy_per_robot_mj`
//! adds up to the robots' charge; the fit's energy report by part.

use robot_board::model::ControllerConfig;
use swarm::energy::{DriveMeter, Pack, Part};
use swarm::experiment::{Swarm, world_params};
use swarm::fit::{FirmwareUnderTest, FitConfig, fit_weight_seed, measure};
use swarm::robot::Condition;
use swarm::scenario::ControllerKind;
use swarm::scenario::Scenario;
use world::dc_motor::DcMotor;
use world::{Arena, Behaviour, Pose, World};

/// The motors' mean current, A, of a robot at `pose` in `arena` driving `behaviour`, over
/// `steps` step periods of 0.45 s after `settle` periods, metered sub-step by sub-step from the
/// world's wheel speeds and forces as the swarm meters them.
fn motors_current_a(
    arena: Arena,
    pose: Pose,
    behaviour: Behaviour,
    settle: u32,
    steps: u32,
) -> f64 {
    let s = Scenario::arena();
    let params = world_params(&s);
    let mut w = World::from_poses(arena, params.clone(), &[pose], 1).unwrap();
    let (l, r) = behaviour.wheels();
    w.set_wheels(0, l, r).unwrap();
    let mut meter = DriveMeter::new(params.top_speed_m_per_s, w.motor_gains(0).unwrap());
    meter.set_commands(l, r);
    let period = 11_250_000u64;
    let mut charge = 0.0;
    for k in 0..settle + steps {
        for len in w.substep_plan(period) {
            w.advance_states(len);
            let dt = len as f64 / 25e6;
            meter.add_substep(
                dt,
                w.wheel_mean_speeds(0).unwrap(),
                w.wheel_forces(0).unwrap(),
            );
        }
        assert_eq!(meter.cap().capped_wheel_substeps, 0, "never at the bound");
        let q = meter.take();
        if k >= settle {
            charge += q.of(Part::Motors);
        }
    }
    charge / 1e6 / (f64::from(steps) * 0.45)
}

#[test]
fn a_robot_pressed_against_a_wall_draws_its_slipping_wheels_friction_current() {
    // The corridor's end wall 0.385 m ahead: there within three steps, then pushing it.
    let pose = Pose {
        x_m: 2.5,
        y_m: 0.11,
        heading_rad: 0.0,
    };
    let a = motors_current_a(Arena::paper_corridor(), pose, Behaviour::Forward, 10, 20);
    // Each wheel slips at its traction, μ_floor · m·g/2 = 1.471 N: a torque of 41.2 mN·m at
    // the 28 mm wheel, 0.308 mN·m at the motor through 203.7:1 at 65.6 %, 0.165 A over Kt, on
    // top of the no-load 0.2 A: two motors at full duty, 0.731 A.
    let params = world_params(&Scenario::arena());
    let m = DcMotor::fa130(0.15);
    let per_motor = m.no_load_current_a
        + params.wheel_traction_n() * m.wheel_radius_m
            / (m.gear_ratio * m.gearbox_efficiency * m.ke_v_s_per_rad);
    assert!((per_motor - 0.3654).abs() < 2e-4, "{per_motor}");
    assert!(
        (a - 2.0 * per_motor).abs() / (2.0 * per_motor) < 0.01,
        "{a} A against 2 x {per_motor} A"
    );
    // Not the stall current (2 x 3.18 A) its standstill over the ground would suggest.
    let stall = 2.0 * m.full_duty_volts / m.resistance_ohm;
    assert!(a < 0.15 * stall, "{a} A");
}

#[test]
fn a_free_robot_draws_its_no_load_current() {
    // The middle of the square arena, heading along it: 0.9 m of room, 6 steps of 68 mm.
    let pose = Pose {
        x_m: 0.3,
        y_m: 0.9,
        heading_rad: 0.0,
    };
    let a = motors_current_a(Arena::square(), pose, Behaviour::Forward, 1, 5);
    assert!((a - 0.4).abs() < 0.004, "{a} A against 2 x 0.2 A");
    // Turning: 0.2 A at full duty, 30 % of 0.2 A at 30 %.
    let a = motors_current_a(Arena::square(), pose, Behaviour::TurnLeftForward, 1, 3);
    assert!((a - 0.26).abs() < 0.005, "{a} A against 0.2 + 0.06 A");
}

#[test]
fn the_swarm_s_energy_per_robot_step_adds_up_to_its_robots_charge() {
    let mut s = Scenario::arena();
    s.steps = 120;
    s.window = 60;
    let mut swarm = Swarm::new(&s, Condition::Learning, 0, false, None).unwrap();
    for _ in 0..s.steps {
        swarm.step().unwrap();
    }
    let out = swarm.finish().unwrap();
    let pack = Pack::default();
    let rows_mj = out.metrics.whole.energy_per_robot_mj * s.robots as f64;
    let total_mj = pack.energy_mj(out.energy.total_uc());
    assert!(
        (rows_mj - total_mj).abs() / total_mj < 1e-9,
        "{rows_mj} vs {total_mj}"
    );
    // Every robot-step lies between the electronics alone (the sensors, the sleeping chip,
    // the regulator: about 172 mA) and every motor stalled (two stalls, about 6.4 A).
    assert_eq!(
        out.motor_cap.capped_wheel_substeps, 0,
        "{:?}",
        out.motor_cap
    );
    assert!(out.motor_cap.driven_wheel_substeps > 0);
    let per_step_mj = out.metrics.whole.energy_per_robot_mj / f64::from(s.steps);
    let mj = |ma: f64| ma * 0.45 * 12.0;
    assert!(
        per_step_mj > mj(172.0) && per_step_mj < mj(6_600.0),
        "{per_step_mj}"
    );
    // The sensors drew their 33 mA each the whole time.
    let seconds = s.robots as f64 * f64::from(s.steps) * 0.45;
    let ir_ma = out.energy.of(Part::IrSensors) / seconds * 1e-3;
    assert!((ir_ma - 132.0).abs() < 1.5, "{ir_ma}");
}

#[test]
fn the_fit_reports_the_robot_s_current_by_part_and_the_battery_life() {
    let r = measure(&FitConfig {
        controller: ControllerConfig::arena(fit_weight_seed(1)),
        steps: 100,
        seed: 1,
        kind: ControllerKind::Firmware,
        firmware: FirmwareUnderTest::robot().unwrap(),
        compare: false,
        strict_io: false,
    })
    .unwrap();
    let e = r.energy.clone().expect("the fit meters the energy");
    let part = |k: &str| {
        e.parts
            .iter()
            .find(|p| p.part == k)
            .unwrap()
            .mean_current_ma
    };
    assert!((part("ir_sensors") - 132.0).abs() < 1e-6);
    assert!((part("regulator") - 5.0).abs() < 1e-6);
    assert!((part("bridges") - 16.0).abs() < 1e-6, "two bridges driving");
    // The chip: asleep at 35 mA but for the busy share at 50 mA.
    let mcu = 35.0 + 15.0 * r.cpu_mean_percent / 100.0;
    assert!((part("mcu") - mcu).abs() < 0.01, "{} vs {mcu}", part("mcu"));
    // The motors, free: at least the no-load current of the slower wheel's duty.
    assert!(part("motors") > 0.26 * 1e3 && part("motors") < 0.6 * 1e3);
    let total: f64 = e.parts.iter().map(|p| p.mean_current_ma).sum();
    assert!((e.mean_current_ma - total).abs() < 1e-9);
    assert!((e.battery_life_h - 2000.0 / total).abs() < 1e-9);
    assert!((e.energy_per_step_mj - total * 0.45 * 12.0).abs() < 1e-6);
    // Pressed against a wall, each driven wheel slips at its traction: 0.1654 A more a motor
    // at full duty, times the duty from the pack (both wheels at full duty: 331 mA more, one
    // at 30 %: 215 mA), not the stall current.
    let free_motors = part("motors");
    let more = e.held_motors_current_ma - free_motors;
    assert!(more > 200.0 && more < 335.0, "{more} mA");
    assert_eq!(e.motor_cap.capped_wheel_substeps, 0);
    assert_eq!(e.held_motor_cap.capped_wheel_substeps, 0);
    assert!((e.capacity_for_paper_mah - 3.5 * total).abs() < 1e-9);
    // Another capacity: the same currents, a longer life.
    let big = e.with_pack(Pack::paper(2_500.0));
    assert_eq!(big.mean_current_ma, e.mean_current_ma);
    assert!((big.battery_life_h - 2_500.0 / total).abs() < 1e-9);
}
