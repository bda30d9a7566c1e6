//! The whole run loop, as `h8swarm run` does it: the learning condition only
//! (`scenarios/arena-learning-only.toml`), one repeat, from placing the robots and booting their
//! MCUs to the metrics, summary, figures and fit verdict written to a folder. Fresh swarms only:
//! a run this short never reaches the crowded, contact-heavy state an ageing swarm of learning
//! robots gets into (see docs/performance.md for the whole 2 000-step command).
//!
//! Cases, model robots: 100 robots x 200 steps and 1 000 robots x 50 steps on one thread,
//! 10 000 robots x 5 steps on two; firmware robots (the robot firmware on the H8/300H core):
//! 3 robots x 2 000 steps on one thread, 1 000 robots x 10 steps on two. Throughput is in
//! robot-steps; a step is 0.45 s of robot time, so the real-time factor is robot-steps/s x
//! 0.45 / robots.

use std::path::PathBuf;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use h8swarm::commands::args::ControllerArg;
use h8swarm::commands::run::{RunArgs, run};

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("run_loop");
    group.sample_size(10);
    let scenario = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join("arena-learning-only.toml");
    let out = std::env::temp_dir().join(format!("h8swarm-run-loop-{}", std::process::id()));
    let cases: [(ControllerArg, usize, u32, usize); 5] = [
        (ControllerArg::Model, 100, 200, 1),
        (ControllerArg::Model, 1000, 50, 1),
        (ControllerArg::Model, 10_000, 5, 2),
        (ControllerArg::Firmware, 3, 2000, 1),
        (ControllerArg::Firmware, 1000, 10, 2),
    ];
    for (controller, robots, steps, threads) in cases {
        group.throughput(Throughput::Elements(robots as u64 * u64::from(steps)));
        let args = RunArgs {
            scenario: Some(scenario.display().to_string()),
            robots: Some(robots),
            steps: Some(steps),
            repeats: Some(1),
            threads: Some(threads),
            out: Some(out.clone()),
            controller: Some(controller),
            ..RunArgs::default()
        };
        group.bench_function(
            format!(
                "learning_{}_{robots}_robots_{steps}_steps_{threads}_threads",
                match controller {
                    ControllerArg::Model => "model",
                    ControllerArg::Firmware => "firmware",
                }
            ),
            |b| b.iter(|| run(&args).expect("the run")),
        );
    }
    group.finish();
    let _ = std::fs::remove_dir_all(&out);
}

criterion_group!(run_loop, benches);
criterion_main!(run_loop);
