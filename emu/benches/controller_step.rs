//! One controller step on the emulated MCU (host time), next to the emulated states it takes.
//!
//! `step_without_save`: a whole step period of the arena's controller as the swarm runs it: the
//! sleep through 45 ticks, then the A/D scan, the learner (13 × 4), the motors; saves are
//! switched off (one record every 1 000 000 steps) so that every iteration does the same work.
//! `step_with_save`: a step that saves one A/B record of the 13 × 4 weights through the
//! bit-banged I²C with ACK polling (every step saves). `step_with_save_pin_level`: the same
//! with the emulation shortcuts off (every tick interrupt, A/D poll and I²C pin edge emulated
//! register by register), the reference the shortcuts are measured against.
//! The emulated states of each are printed once before timing.

// A test, example or bench may use the host's f64 functions (clippy.toml): it checks the
// models within tolerances, and its own output is not a promised result.
#![allow(clippy::disallowed_methods)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use h8_3052f::mcu::Mcu;
use h8_3052f::pins::Board;
use h8300h::bus::Bus;
use robot_board::board::{CLOCK_HZ, RobotBoard, RobotConfig, robot_mcu};
use robot_board::model::{Controller, ControllerConfig};

struct Wave;

impl Board for Wave {
    fn analog_volts(&mut self, channel: u8, now: u64) -> f64 {
        let t = now as f64 / f64::from(CLOCK_HZ);
        1.4 + 1.1 * (t * (0.7 + 0.3 * f64::from(channel))).sin()
    }
    fn port2_pins(&mut self, _now: u64) -> u8 {
        0xFF
    }
}

fn setup(save_every_steps: u32, fast_forward: bool) -> (Controller, Mcu<RobotBoard<Wave>>) {
    let mut cfg = ControllerConfig::arena(1);
    cfg.save_every_steps = save_every_steps;
    cfg.fast_forward = fast_forward;
    let mut c = Controller::new(cfg).expect("valid controller");
    let mut m = robot_mcu(Wave, &RobotConfig::default()).expect("valid MCU");
    c.boot(&mut m).expect("boots");
    (c, m)
}

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("controller");
    {
        let (mut ctl, mut m) = setup(1_000_000, true);
        ctl.sleep_until_step(&mut m).expect("tick");
        ctl.step(&mut m).expect("step");
        let t0 = m.now();
        ctl.sleep_until_step(&mut m).expect("tick");
        let r = ctl.step(&mut m).expect("step");
        eprintln!(
            "controller/step_without_save: {} emulated states per step period ({} busy in the step)",
            m.now() - t0,
            r.phases.work()
        );
        group.bench_function("step_without_save", |b| {
            b.iter(|| {
                ctl.sleep_until_step(&mut m).expect("tick");
                black_box(ctl.step(&mut m).expect("step"))
            });
        });
    }
    for (name, fast) in [
        ("step_with_save", true),
        ("step_with_save_pin_level", false),
    ] {
        let (mut ctl, mut m) = setup(1, fast);
        ctl.sleep_until_step(&mut m).expect("tick");
        let r = ctl.step(&mut m).expect("step");
        eprintln!(
            "controller/{name}: {} emulated states per save ({:?})",
            r.phases.save, r.saved
        );
        group.bench_function(name, |b| {
            b.iter(|| {
                ctl.sleep_until_step(&mut m).expect("tick");
                black_box(ctl.step(&mut m).expect("step"))
            });
        });
    }
    group.finish();
}

criterion_group!(controller, benches);
criterion_main!(controller);
