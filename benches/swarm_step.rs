//! One step of the swarm: every robot's emulated H8/3052F sleeps to the step instant (its tick
//! interrupts), the world advances 0.45 s in 20 ms sub-steps with collisions and bumpers, every
//! robot casts its four rays, samples its sensors through the A/D converter, runs the learner,
//! sets its motors, and one step in twenty saves its weights to the EEPROMs — the full models,
//! the arena scaled to keep the paper's density. Throughput is in robot-steps; a step is 0.45 s
//! of robot time, so the real-time factor is robot-steps/s × 0.45 / robots.
//!
//! Model robots (the Rust model of the controller): 3, 100 and 1 000 robots on one thread
//! (robots stepped one after the other on the benchmark's own thread); 1 000 and 10 000 robots
//! on two (robots stepped in parallel, the whole measurement inside a two-thread pool).
//! Firmware robots (the robot firmware as machine code on the H8/300H core), in the same run:
//! 3 robots on one thread, 100 and 1 000 on two; the targets are 2 000×, 50× and 5× real
//! time.
//!
//! The cost of a step grows as the robots learn their way into corners and against each other
//! (more contacts to resolve), so a swarm is measured over steps 25 to 1 000 of its life and
//! then replaced by a fresh one (the boot is not timed). Criterion's samples cover whichever
//! steps of those lives its iteration counts reach, so a figure is a mean over steps 25–1 000
//! only roughly; runs differ by up to ±15 % on a 2-core machine.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use swarm::experiment::Swarm;
use swarm::robot::{Condition, Images};
use swarm::scenario::Scenario;

/// Steps of a swarm's life that are measured before it is replaced.
const LIFE: usize = 1000;
/// Steps run before measuring (boot, the first sensor periods).
const WARM: usize = 25;

fn swarm(robots: usize, parallel: bool, firmware: bool) -> Swarm {
    let mut s = Scenario::arena();
    s.robots = robots;
    s.steps = LIFE as u32;
    if firmware {
        s.controller.kind = swarm::scenario::ControllerKind::Firmware;
    }
    let images = Images::load(&s).expect("the robot firmware");
    let mut swarm =
        Swarm::new(&s, Condition::Learning, 0, false, images.as_ref()).expect("the swarm fits");
    swarm.set_parallel(parallel);
    for _ in 0..WARM {
        swarm.step().expect("a step");
    }
    swarm
}

/// Times `iters` steps, replacing the swarm whenever it has lived `LIFE` steps.
fn timed(s: &mut Swarm, age: &mut usize, iters: u64, fresh: &dyn Fn() -> Swarm) -> Duration {
    let mut spent = Duration::ZERO;
    for _ in 0..iters {
        if *age >= LIFE {
            *s = fresh();
            *age = WARM;
        }
        let t = Instant::now();
        s.step().expect("a step");
        black_box(&s);
        spent += t.elapsed();
        *age += 1;
    }
    spent
}

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("swarm_step");
    group.sample_size(10);
    let cases: [(usize, usize, bool); 8] = [
        (3, 1, false),
        (100, 1, false),
        (1000, 1, false),
        (1000, 2, false),
        (10_000, 2, false),
        (3, 1, true),
        (100, 2, true),
        (1000, 2, true),
    ];
    for (robots, threads, firmware) in cases {
        group.throughput(Throughput::Elements(robots as u64));
        let kind = if firmware { "firmware" } else { "model" };
        let name = format!("{kind}_{robots}_robots_{threads}_threads");
        if threads == 1 {
            let fresh = || swarm(robots, false, firmware);
            let (mut s, mut age) = (fresh(), WARM);
            group.bench_function(name, |b| {
                b.iter_custom(|iters| timed(&mut s, &mut age, iters, &fresh));
            });
        } else {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a thread pool");
            let fresh = || swarm(robots, true, firmware);
            let (mut s, mut age) = (pool.install(fresh), WARM);
            group.bench_function(name, |b| {
                b.iter_custom(|iters| pool.install(|| timed(&mut s, &mut age, iters, &fresh)));
            });
        }
    }
    group.finish();
}

criterion_group!(swarm_step, benches);
criterion_main!(swarm_step);
