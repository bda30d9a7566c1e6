//! A reference model of one robot driving into the wall x = `wall_x` (used by the
//! `wall_angle` test and example): plain Coulomb friction integrated explicitly in
//! 10 µs steps, independent of the world crate's solver.
//!
//! Each drive wheel takes a force of μ_floor·m·g/2 against the slip velocity of its contact
//! patch (the body's velocity at the wheel minus the rim speed along the heading), isotropic,
//! smoothed below 1 mm/s. The wall is a stiff penalty (10⁵ N/m, critically damped) at the
//! body's corners, with Coulomb friction μ_wall against the corner's sliding. The rim speeds
//! follow their targets with the motors' first-order lag. The body and wheel constants are the
//! world's defaults.

// A test, example or bench may use the host's f64 functions (clippy.toml): it checks the
// models within tolerances, and its own output is not a promised result.
#![allow(clippy::disallowed_methods)]

use world::params::{
    BODY_LENGTH_M, BODY_WIDTH_M, GRAVITY_M_PER_S2, MASS_KG, MOTOR_TIME_CONSTANT_S, MU_FLOOR,
    TOP_SPEED_M_PER_S, WHEEL_TRACK_M,
};

/// One sample: time s, centre x m, centre y m, heading rad.
pub type Sample = (f64, f64, f64, f64);

/// The scene: a robot at rest at (x, y) with the given heading, wheel duties (left, right,
/// forward), the wall's x and its friction coefficient; sampled every `every_s` for `run_s`.
pub struct Scene {
    /// Start centre x, m.
    pub x: f64,
    /// Start centre y, m.
    pub y: f64,
    /// Start heading, rad.
    pub heading: f64,
    /// Left and right duty, forward.
    pub duty: [f64; 2],
    /// The wall's x, m.
    pub wall_x: f64,
    /// Robot–wall Coulomb coefficient.
    pub mu_wall: f64,
    /// Sampling interval, s.
    pub every_s: f64,
    /// Duration, s.
    pub run_s: f64,
}

/// Integrates the scene; one sample every `every_s`.
pub fn run(scene: &Scene) -> Vec<Sample> {
    const DT: f64 = 1e-5;
    const EPS: f64 = 1e-3;
    const K: f64 = 1e5;
    let (hx, hy, half_track) = (BODY_LENGTH_M / 2.0, BODY_WIDTH_M / 2.0, WHEEL_TRACK_M / 2.0);
    let c_wall = 2.0 * (K * MASS_KG).sqrt();
    let inv_i = 12.0 / (MASS_KG * (BODY_LENGTH_M.powi(2) + BODY_WIDTH_M.powi(2)));
    let wheel_max = MU_FLOOR * MASS_KG * GRAVITY_M_PER_S2 * 0.5;
    let (mut x, mut y, mut phi) = (scene.x, scene.y, scene.heading);
    let (mut vx, mut vy, mut om) = (0.0f64, 0.0f64, 0.0f64);
    let mut speed = [0.0f64; 2];
    let decay = (-DT / MOTOR_TIME_CONSTANT_S).exp();
    let per_sample = (scene.every_s / DT).round() as usize;
    let samples = (scene.run_s / scene.every_s).round() as usize;
    let mut track = Vec::with_capacity(samples);
    for k in 1..=samples {
        for _ in 0..per_sample {
            for (s, d) in speed.iter_mut().zip(scene.duty) {
                let target = d * TOP_SPEED_M_PER_S;
                *s = target + (*s - target) * decay;
            }
            let (s, c) = phi.sin_cos();
            let (mut fx, mut fy, mut tq) = (0.0, 0.0, 0.0);
            for (rim, y_w) in [(speed[0], half_track), (speed[1], -half_track)] {
                let (rx, ry) = (-s * y_w, c * y_w);
                let sx = vx - om * ry - rim * c;
                let sy = vy + om * rx - rim * s;
                let k = wheel_max / (sx * sx + sy * sy + EPS * EPS).sqrt();
                let (gx, gy) = (-k * sx, -k * sy);
                fx += gx;
                fy += gy;
                tq += rx * gy - ry * gx;
            }
            for (bx, by) in [(hx, hy), (hx, -hy), (-hx, hy), (-hx, -hy)] {
                let (rx, ry) = (bx * c - by * s, bx * s + by * c);
                let pen = x + rx - scene.wall_x;
                if pen <= 0.0 {
                    continue;
                }
                let (cvx, cvy) = (vx - om * ry, vy + om * rx);
                let n = (K * pen + c_wall * cvx).max(0.0);
                let f = -scene.mu_wall * n * cvy / (cvy * cvy + EPS * EPS).sqrt();
                fx -= n;
                fy += f;
                tq += rx * f + ry * n;
            }
            vx += fx / MASS_KG * DT;
            vy += fy / MASS_KG * DT;
            om += tq * inv_i * DT;
            x += vx * DT;
            y += vy * DT;
            phi += om * DT;
        }
        track.push((k as f64 * scene.every_s, x, y, phi));
    }
    track
}
