use super::*;
use crate::experiment::metrics::{METRICS_HEADER, WindowSums};
use crate::experiment::setup::world_params;
use crate::experiment::substeps::{METER_BATCH, PIPELINE_ROBOTS, Readings, add, advance_world};
use crate::motion::MSD_LAGS;
use world::{Arena, SubstepPlan};
use world::{Behaviour, Pose};

/// The picosecond case: a robot pushing the end wall of the corridor for 500 steps of
/// 0.6 s. Time is whole states, the sub-steps cut every step exactly, and the push is one
/// collision, not one every other step (with float time, a final sub-step of ~1 ps
/// released the bumper and every step from about 429 on counted a new collision).
#[test]
fn a_robot_held_against_a_wall_counts_one_collision_over_500_steps() {
    let s = Scenario::corridor();
    let mut w = World::from_poses(
        Arena::paper_corridor(),
        world_params(&s),
        &[Pose {
            x_m: 2.5,
            y_m: 0.11,
            heading_rad: 0.0,
        }],
        1,
    )
    .unwrap();
    let (l, r) = Behaviour::Forward.wheels();
    w.set_wheels(0, l, r).unwrap();
    let period = period_states(&s);
    assert_eq!(period, 15_000_000);
    let nominal = nominal_substep_states(&s);
    assert_eq!(nominal, 500_000, "0.6 s in 30 sub-steps of 20 ms");
    let mut meters = vec![ContactMeter::new(nominal)];
    let mut per_robot = vec![0];
    let mut collisions = Vec::new();
    let mut t = 0u64;
    for _ in 0..500 {
        t += period;
        for len in w.substep_plan(t - w.elapsed_states()) {
            assert_eq!(len, nominal, "no sliver of a sub-step");
        }
        let (c, contact) = advance_world(
            &mut w,
            t,
            (&mut meters, &mut per_robot),
            false,
            &mut [],
            &mut Readings::default(),
        )
        .unwrap();
        collisions.push((c, contact));
    }
    assert_eq!(w.elapsed_states(), 500 * period, "no drift");
    let total: u64 = collisions.iter().map(|c| c.0).sum();
    assert_eq!(total, 1, "one push, one collision");
    assert_eq!(per_robot, [1], "counted for the robot");
    // From the step it arrives (2.5 m → 2.885 m at 0.15 m/s: about 4 steps) it is in
    // contact the whole step.
    assert!(collisions[10..].iter().all(|&(_, c)| c == period));
}

/// The meters fed in batches (more than [`METER_BATCH`] sub-steps a step, so full batches
/// and a remainder) or pipelined with the world's sub-steps (two threads) count what they
/// count fed after every sub-step: three robots in the corridor, one pushing the end wall,
/// two meeting head on.
#[test]
fn meters_fed_in_batches_count_as_fed_after_every_substep() {
    let mut s = Scenario::corridor();
    s.world.substep_s = 0.008;
    let poses = [
        (2.7, 0.11, 0.0),
        (1.0, 0.11, 0.0),
        (1.3, 0.12, std::f64::consts::PI),
    ];
    let poses: Vec<Pose> = poses
        .iter()
        .map(|&(x_m, y_m, heading_rad)| Pose {
            x_m,
            y_m,
            heading_rad,
        })
        .collect();
    let mut w = World::from_poses(Arena::paper_corridor(), world_params(&s), &poses, 1).unwrap();
    let (l, r) = Behaviour::Forward.wheels();
    let mut drive = crate::energy::DriveMeter::new(s.world.top_speed_m_per_s, [1.0, 1.0]);
    drive.set_commands(l, r);
    for i in 0..poses.len() {
        w.set_wheels(i, l, r).unwrap();
    }
    let period = period_states(&s);
    assert!(w.substep_plan(period).substeps() > 2 * METER_BATCH as u64);
    let nominal = nominal_substep_states(&s);
    let fresh = || {
        (
            vec![ContactMeter::new(nominal); 3],
            vec![0u64; 3],
            vec![drive.clone(); 3],
        )
    };
    // The reference: every meter fed after every sub-step.
    let mut plain = w.clone();
    let (mut m0, mut c0, mut d0) = fresh();
    let mut sums0 = Vec::new();
    for k in 1..=40u64 {
        let mut sum = (0, 0);
        for len in plain.substep_plan(k * period - plain.elapsed_states()) {
            plain.advance_states(len);
            for i in 0..3 {
                d0[i].add_substep(
                    len as f64 / f64::from(s.timing.clock_hz),
                    plain.wheel_mean_speeds(i).unwrap(),
                    plain.wheel_forces(i).unwrap(),
                );
                m0[i].sample(plain.bumpers(i).unwrap().iter().any(|&b| b), len);
                let (n, t) = m0[i].take();
                c0[i] += n;
                sum = add(sum, (n, t));
            }
        }
        sums0.push(sum);
    }
    assert!(c0.iter().all(|&c| c >= 1), "every robot collided: {c0:?}");
    // One thread in order, one thread with the pool's stages (batched), two threads
    // batched (three robots are below PIPELINE_ROBOTS) and pipelined (each sub-step fed
    // while the world makes the next).
    for (par, threads, pipeline_from) in [
        (false, 1, PIPELINE_ROBOTS),
        (true, 1, PIPELINE_ROBOTS),
        (true, 2, PIPELINE_ROBOTS),
        (true, 2, 1),
    ] {
        let mut w = w.clone();
        let (mut m, mut c, mut d) = fresh();
        let mut readings = Readings::default();
        readings.pipeline_from = pipeline_from;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let sums: Vec<_> = pool.install(|| {
            (1..=40u64)
                .map(|k| {
                    advance_world(
                        &mut w,
                        k * period,
                        (&mut m, &mut c),
                        par,
                        &mut d,
                        &mut readings,
                    )
                    .unwrap()
                })
                .collect()
        });
        assert_eq!(
            sums, sums0,
            "par {par}, {threads} threads, from {pipeline_from}"
        );
        assert_eq!(c, c0);
        assert_eq!(m, m0);
        for (a, b) in d.iter_mut().zip(d0.iter_mut()) {
            assert_eq!(a.take(), b.clone().take());
            assert_eq!(a.cap(), b.cap());
        }
    }
}

#[test]
fn the_arena_step_is_cut_into_23_substeps_a_state_apart() {
    let s = Scenario::arena();
    assert_eq!(period_states(&s), 11_250_000);
    assert_eq!(nominal_substep_states(&s), 489_130);
    let plan: Vec<u64> = SubstepPlan::new(11_250_000, 500_000).collect();
    assert_eq!(plan.len(), 23);
    assert_eq!(plan.iter().sum::<u64>(), 11_250_000);
    assert!(plan.iter().all(|&l| l == 489_130 || l == 489_131));
}

/// Step metrics that differ every step (so a sum over the wrong steps shows).
fn metrics_of(k: u32, gap: bool) -> StepMetrics {
    let x = f64::from(k);
    StepMetrics {
        mean_d: 700.0 + libm::sin(x * 0.37) * 50.0,
        collisions_per_robot: f64::from(k % 7) / 3.0,
        contact_percent: 100.0 * libm::cos(x * 0.11).abs(),
        held_percent: f64::from(k % 5) * 20.0,
        shuttling_percent: f64::from(k % 4) * 10.0,
        circling_percent: f64::from(k % 2) * 5.0,
        exploring_percent: 30.0 + f64::from(k % 7),
        moving_percent: f64::from(k % 3) * 50.0,
        moved_mm: 70.0 / (1.0 + x),
        net_mm: 30.0 / (1.0 + x),
        msd_cm2: [
            Some(x),
            (k >= 10).then_some(2.0 * x),
            (k >= 100).then_some(3.0 * x),
        ],
        fresh_cells: f64::from(k % 11) / 3.0,
        new_cells: f64::from(k % 13) / 7.0,
        gap_cv: (gap && !k.is_multiple_of(9)).then_some(0.1 + x * 1e-4),
        touching: gap.then_some(k.is_multiple_of(9)),
        cpu_load_percent: 0.3 + x * 1e-6,
        energy_per_robot_mj: 3500.0 + libm::cos(x),
    }
}

/// The kept sums equal the sums of the same steps taken afterwards (as the summary and the
/// figure took them when every step was kept), for windows that do and do not divide the
/// run.
#[test]
fn window_sums_equal_the_sums_of_the_kept_steps() {
    for (steps, win, gap) in [
        (1000, 250, false),
        (1234, 500, true),
        (150, 150, true),
        (7, 3, false),
    ] {
        let all: Vec<StepMetrics> = (0..steps).map(|k| metrics_of(k, gap)).collect();
        let mut m = RunMetrics::new(steps, win);
        for (k, s) in all.iter().enumerate() {
            m.add(k as u32, s);
        }
        let sum = |r: std::ops::Range<u32>| {
            let mut w = WindowSums::default();
            for s in &all[r.start as usize..r.end as usize] {
                w.add(s);
            }
            w
        };
        // Spot-check one field the direct way too (not through WindowSums::add).
        let d: f64 = all[(steps - win) as usize..].iter().map(|s| s.mean_d).sum();
        assert_eq!(m.last.mean_d, d);
        assert_eq!(*m.first(), sum(0..win));
        assert_eq!(m.last, sum(steps - win..steps));
        assert_eq!(m.whole, sum(0..steps));
        assert_eq!(m.whole_windows().len() as u32, steps / win);
        for (w, got) in m.whole_windows().iter().enumerate() {
            let w = w as u32;
            assert_eq!(*got, sum(w * win..(w + 1) * win));
        }
        assert_eq!(m.whole.is_corridor(), gap);
        if gap {
            assert_eq!(m.whole.touching_steps, steps.div_ceil(9));
            assert_eq!(m.whole.gap_cv_steps + m.whole.touching_steps, steps);
        }
        assert_eq!(
            m.whole.msd_steps,
            [steps, steps.saturating_sub(10), steps.saturating_sub(100)]
        );
    }
}

/// Port 2 shows each robot's MCU the bumpers the world pressed (a user image may read
/// them; before, the pins read released whatever the world did).
#[test]
fn the_board_shows_the_world_s_bumpers_on_port_2() {
    use h8_3052f::pins::Board;
    let mut s = Scenario::arena();
    s.robots = 10;
    s.steps = 300;
    let mut swarm = Swarm::new(&s, Condition::Learning, 0, false, None).unwrap();
    let mut pressed = 0;
    for _ in 0..s.steps {
        swarm.step().unwrap();
        for i in 0..s.robots {
            let b = swarm.world().bumpers(i).unwrap();
            pressed += usize::from(b.iter().any(|&x| x));
            let board = &mut swarm.robot_mut(i).unwrap().mcu.board_mut().world;
            assert_eq!(board.bumpers, b);
            let [front, rear, left, right] = b;
            let want =
                sensors::port2_pins(sensors::BumperSet::from_flags(front, rear, left, right));
            assert_eq!(board.port2_pins(0), want);
        }
    }
    assert!(
        pressed > 50,
        "only {pressed} pressed robot-steps: the test saw too few"
    );
}

/// A run keeps sums per window, not its steps: the rows go to the file as the steps
/// complete, and the kept sums are the sums of those rows; the arena paths are kept for
/// the first and last snapshot steps only.
#[test]
fn a_run_streams_its_rows_and_keeps_window_sums() {
    let mut s = Scenario::arena();
    s.steps = 450;
    s.window = 100;
    let dir = std::env::temp_dir().join(format!("h8swarm-rows-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rows = dir.join("rows.csv");
    let mut swarm = Swarm::new(&s, Condition::Learning, 0, true, None).unwrap();
    swarm.set_rows(&rows).unwrap();
    for k in 0..s.steps {
        swarm.step().unwrap();
        // Step k completes when step k + 1 begins.
        assert_eq!(swarm.metrics().whole.steps, k);
    }
    let out = swarm.finish().unwrap();
    let text = std::fs::read_to_string(&rows).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let parsed: Vec<Vec<String>> = text
        .lines()
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    assert_eq!(parsed.len(), 450);
    let mut again = RunMetrics::new(s.steps, s.window);
    for (k, r) in parsed.iter().enumerate() {
        assert_eq!(r[0], "learning");
        assert_eq!(r[2], k.to_string());
        let f = |i: usize| r[i].parse::<f64>().unwrap();
        let opt = |i: usize| (!r[i].is_empty()).then(|| f(i));
        assert_eq!(r.len(), METRICS_HEADER.len());
        again.add(
            k as u32,
            &StepMetrics {
                mean_d: f(3),
                collisions_per_robot: f(4),
                contact_percent: f(5),
                held_percent: f(6),
                shuttling_percent: f(7),
                circling_percent: f(8),
                exploring_percent: f(9),
                moving_percent: f(10),
                moved_mm: f(11),
                net_mm: f(12),
                msd_cm2: [opt(13), opt(14), opt(15)],
                fresh_cells: f(16),
                new_cells: f(17),
                gap_cv: opt(18),
                touching: opt(19).map(|t| t != 0.0),
                cpu_load_percent: f(20),
                energy_per_robot_mj: f(21),
            },
        );
        let classes = f(6) + f(7) + f(8) + f(9);
        assert!(
            (classes - 100.0).abs() < 1e-9,
            "step {k}: classes sum to {classes}"
        );
    }
    assert_eq!(out.metrics, again);
    assert_eq!(
        out.metrics.windows.len(),
        5,
        "four whole windows and a partial one"
    );
    assert_eq!(out.metrics.whole_windows().len(), 4);
    assert!(
        out.metrics.whole.collisions_per_robot > 0.0,
        "something happened"
    );
    assert_eq!(
        METRICS_HEADER[13..16],
        MSD_LAGS.map(|l| format!("msd_{l}_cm2"))[..],
        "the MSD columns name their lags"
    );
    assert_eq!(
        out.metrics.whole.msd_steps,
        MSD_LAGS.map(|l| 451 - l as u32)
    );
    // Every robot's tally adds up to its steps, and it was somewhere.
    for t in &out.robots {
        assert_eq!(t.class_steps.iter().sum::<u32>(), 450);
        assert!(t.cells_visited >= 1 && t.last_window_cells >= 1);
        assert!(t.net_m <= t.distance_m + 1e-9);
    }
    let t = out.track.unwrap();
    assert!(t.early.iter().all(|p| p.len() == SNAPSHOT_STEPS));
    assert!(t.late.iter().all(|p| p.len() == SNAPSHOT_STEPS));
    assert_ne!(t.early, t.late);
}
