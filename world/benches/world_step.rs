//! World speed: one 10 ms sub-step for 3 … 10 000 robots in the density-preserving square
//! arena with realistic motion (every wheel driven, each robot drawing a new random behaviour
//! every 0.45 s = 45 sub-steps), sensing 4 rays per robot, and the narrow phase against
//! `parry2d`.
//!
//! Criterion's throughput line gives robots (or rays, or tests) per second; the budget is
//! ≤ 50 ns per robot per sub-step and ≤ 1 µs per ray.

// A test, example or bench may use the host's f64 functions (clippy.toml): it checks the
// models within tolerances, and its own output is not a promised result.
#![allow(clippy::disallowed_methods)]

use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use world::geometry::{Obb, obb_overlap, ray_obb};
use world::{Arena, Behaviour, World, WorldParams};

/// The robots' MCU clock the world counts in here: the robot's φ, 25 MHz (the world crate has
/// no clock of its own, and does not depend on the emulator that defines the robot's).
const CLOCK_HZ: u64 = 25_000_000;

const SIZES: [usize; 4] = [3, 100, 1_000, 10_000];
const SUBSTEP_S: f64 = 0.010;
const SUBSTEPS_PER_BEHAVIOUR: u64 = 45;

/// A world of `n` robots in the scaled arena, driven for 2 s of random behaviours.
fn moving_world(n: usize, rng: &mut Pcg64) -> World {
    moving_world_with(n, rng, WorldParams::with_clock(CLOCK_HZ))
}

/// [`moving_world`] with the given parameters.
fn moving_world_with(n: usize, rng: &mut Pcg64, params: WorldParams) -> World {
    let mut w = World::new(Arena::scaled_square(n).unwrap(), params, n, 2008).unwrap();
    for k in 0..200 {
        if k % SUBSTEPS_PER_BEHAVIOUR == 0 {
            new_behaviours(&mut w, rng);
        }
        w.advance(SUBSTEP_S).unwrap();
    }
    w
}

fn new_behaviours(w: &mut World, rng: &mut Pcg64) {
    for r in 0..w.robot_count() {
        let (l, rr) = Behaviour::ALL[rng.random_range(0..4usize)].wheels();
        w.set_wheels(r, l, rr).unwrap();
    }
}

/// One serial benchmark group: at each size, robots drawing random behaviours, one 10 ms
/// sub-step an iteration, under `params`.
fn serial_group(c: &mut Criterion, name: &str, sizes: &[usize], params: &WorldParams) {
    let mut g = c.benchmark_group(name);
    g.sample_size(20)
        .measurement_time(Duration::from_secs(4))
        .warm_up_time(Duration::from_secs(1));
    for &n in sizes {
        let mut rng = Pcg64::seed_from_u64(1);
        let mut w = moving_world_with(n, &mut rng, params.clone());
        let mut k = 0u64;
        g.throughput(Throughput::Elements(n as u64));
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                if k.is_multiple_of(SUBSTEPS_PER_BEHAVIOUR) {
                    new_behaviours(&mut w, &mut rng);
                }
                k += 1;
                w.advance(black_box(SUBSTEP_S)).unwrap();
            })
        });
    }
    g.finish();
}

fn advance(c: &mut Criterion) {
    serial_group(
        c,
        "advance_10ms",
        &SIZES,
        &WorldParams::with_clock(CLOCK_HZ),
    );

    // The parallel path on two threads (results identical to `advance`).
    let mut g = c.benchmark_group("advance_par_10ms_2_threads");
    g.sample_size(20)
        .measurement_time(Duration::from_secs(4))
        .warm_up_time(Duration::from_secs(1));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    for n in [1_000, 10_000] {
        let mut rng = Pcg64::seed_from_u64(1);
        let mut w = moving_world(n, &mut rng);
        let mut k = 0u64;
        g.throughput(Throughput::Elements(n as u64));
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                if k.is_multiple_of(SUBSTEPS_PER_BEHAVIOUR) {
                    new_behaviours(&mut w, &mut rng);
                }
                k += 1;
                pool.install(|| w.advance_par(black_box(SUBSTEP_S)))
                    .unwrap();
            })
        });
    }
    g.finish();

    // The solver that sweeps each island until its velocities converge (a scenario's
    // `world.solver = "converged"`) and Newton's method (`"newton"`), beside `advance_10ms` at
    // the same sizes.
    for (group, until) in [
        (
            "advance_10ms_converged",
            world::params::Convergence::Velocity,
        ),
        ("advance_10ms_newton", world::params::Convergence::Newton),
    ] {
        let params = WorldParams {
            solver_iterations: 256,
            solver_convergence: until,
            ..WorldParams::with_clock(CLOCK_HZ)
        };
        serial_group(c, group, &[100, 1_000], &params);
    }
}

fn sense(c: &mut Criterion) {
    let mut g = c.benchmark_group("sense_4_rays_per_robot");
    g.sample_size(20)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_secs(1));
    for n in SIZES {
        let mut rng = Pcg64::seed_from_u64(2);
        let w = moving_world(n, &mut rng);
        g.throughput(Throughput::Elements(4 * n as u64));
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                let mut acc = 0.0;
                for r in 0..n {
                    for s in 0..4 {
                        acc += w.sense(r, s).unwrap().unwrap_or(0.0);
                    }
                }
                black_box(acc)
            })
        });
    }
    g.finish();
}

/// Hand-written f64 narrow phase against parry2d (f32) on the same 1 024 random cases.
fn narrow_phase(c: &mut Criterion) {
    use parry2d::math::{Pose, Vector};
    use parry2d::query::{Ray, RayCast, contact};
    use parry2d::shape::Cuboid;

    let (hx, hy) = (0.115, 0.09);
    let mut rng = Pcg64::seed_from_u64(3);
    let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.random::<f64>();
    // Pairs whose centres are within the broad-phase reach (0.34 m): the cases the narrow
    // phase actually sees; about half overlap.
    let pairs: Vec<(Obb, Obb)> = (0..1024)
        .map(|_| {
            let a = Obb::new(u(0.0, 10.0), u(0.0, 10.0), u(-PI, PI), hx, hy);
            let r = u(0.0, 0.34);
            let t = u(-PI, PI);
            let b = Obb::new(a.x + r * t.cos(), a.y + r * t.sin(), u(-PI, PI), hx, hy);
            (a, b)
        })
        .collect();
    let rays: Vec<(f64, f64, f64, f64, Obb)> = (0..1024)
        .map(|_| {
            let b = Obb::new(u(0.0, 10.0), u(0.0, 10.0), u(-PI, PI), hx, hy);
            let (ox, oy) = (b.x + u(-1.5, 1.5), b.y + u(-1.5, 1.5));
            let aim = (b.y - oy).atan2(b.x - ox) + u(-0.3, 0.3);
            (ox, oy, aim.cos(), aim.sin(), b)
        })
        .collect();
    let cub = Cuboid::new(Vector::new(hx as f32, hy as f32));
    let ppose = |b: &Obb| Pose::new(Vector::new(b.x as f32, b.y as f32), b.s.atan2(b.c) as f32);
    let ppairs: Vec<(Pose, Pose)> = pairs.iter().map(|(a, b)| (ppose(a), ppose(b))).collect();
    let prays: Vec<(Ray, Pose)> = rays
        .iter()
        .map(|(ox, oy, dx, dy, b)| {
            (
                Ray::new(
                    Vector::new(*ox as f32, *oy as f32),
                    Vector::new(*dx as f32, *dy as f32),
                ),
                ppose(b),
            )
        })
        .collect();

    let mut g = c.benchmark_group("narrow_phase_1024");
    g.sample_size(30)
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500));
    g.throughput(Throughput::Elements(1024));
    g.bench_function("obb_contact/hand_f64", |b| {
        b.iter(|| {
            let mut n = 0u32;
            for (a, bb) in &pairs {
                if let Some(o) = obb_overlap(black_box(a), black_box(bb), 0.0) {
                    n += (o.depth_m > 0.0) as u32;
                }
            }
            n
        })
    });
    g.bench_function("obb_contact/parry2d_f32", |b| {
        b.iter(|| {
            let mut n = 0u32;
            for (pa, pb) in &ppairs {
                if let Ok(Some(c)) = contact(black_box(pa), &cub, black_box(pb), &cub, 0.0) {
                    n += (c.dist < 0.0) as u32;
                }
            }
            n
        })
    });
    g.bench_function("ray_box/hand_f64", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (ox, oy, dx, dy, bb) in &rays {
                acc += ray_obb(*ox, *oy, *dx, *dy, black_box(bb), 1.5).unwrap_or(0.0);
            }
            acc
        })
    });
    g.bench_function("ray_box/parry2d_f32", |b| {
        b.iter(|| {
            let mut acc = 0.0f32;
            for (ray, p) in &prays {
                acc += cub.cast_ray(black_box(p), ray, 1.5, true).unwrap_or(0.0);
            }
            acc
        })
    });
    g.finish();
}

criterion_group!(benches, advance, sense, narrow_phase);
criterion_main!(benches);
