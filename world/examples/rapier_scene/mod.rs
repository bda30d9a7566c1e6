//! The scene of the examples that put rapier2d beside the world's own solver (`solver_compare`,
//! `wall_angle`): a walled rectangle, and a differential-drive robot's wheels. Rapier has no
//! wheels, so each wheel is a
//! force at its contact patch, explicit per step, that drives the patch's speed along the heading
//! towards the motor's mean speed over the step and resists its sideways slip, limited together
//! to the patch's Coulomb friction (μ_floor · m · g / 2).

// A test, example or bench may use the host's f64 functions (clippy.toml): it checks the
// models within tolerances, and its own output is not a promised result.
#![allow(clippy::disallowed_methods)]

use rapier2d::prelude::*;

/// A world without gravity (the floor is the plane of the scene), stepped by `dt` s, with four
/// walls 0.5 m thick around the rectangle from (0, 0) to (`width`, `height`) m, of friction
/// `friction` against the bodies.
pub fn walled_world(width: f64, height: f64, friction: f64, dt: f64) -> PhysicsWorld {
    let mut pw = PhysicsWorld::new();
    pw.gravity = Vector::ZERO;
    pw.integration_parameters.dt = dt as Real;
    let t = 0.5;
    for (x, y, hx, hy) in [
        (width / 2.0, -t, width / 2.0 + t, t),
        (width / 2.0, height + t, width / 2.0 + t, t),
        (-t, height / 2.0, t, height / 2.0 + t),
        (width + t, height / 2.0, t, height / 2.0 + t),
    ] {
        pw.colliders.insert(
            ColliderBuilder::cuboid(hx as Real, hy as Real)
                .translation(Vector::new(x as Real, y as Real))
                .friction(friction as Real)
                .build(),
        );
    }
    pw
}

/// The wheel model of one robot body.
pub struct Wheels {
    /// The body's mass, kg.
    pub mass: f64,
    /// Half the wheel track, m.
    pub half_track: f64,
    /// The effective mass of a wheel's patch along the heading (the body's mass and its turning
    /// inertia seen from the wheel), kg.
    pub m_long: f64,
    /// The largest force a patch carries (Coulomb friction of half the weight), N.
    pub max_force_n: f64,
}

impl Wheels {
    /// Wheels of a body of `mass` kg and turning inertia `inertia` kg·m², on a track of
    /// `2 · half_track` m, on a floor of friction `mu_floor`.
    pub fn new(mass: f64, inertia: f64, half_track: f64, mu_floor: f64) -> Self {
        Self {
            mass,
            half_track,
            m_long: 1.0 / (1.0 / mass + half_track * half_track / inertia),
            max_force_n: mu_floor * mass * world::params::GRAVITY_M_PER_S2 * 0.5,
        }
    }

    /// Replaces the body's forces with the two wheels' for a step of `h` s in which the left
    /// and right patches should move at `mean` m/s along the heading.
    pub fn apply(&self, b: &mut RigidBody, mean: [f64; 2], h: f64) {
        b.reset_forces(false);
        let (s, c) = f64::from(b.rotation().angle()).sin_cos();
        let v = b.linvel();
        let (vx, vy, om) = (f64::from(v.x), f64::from(v.y), f64::from(b.angvel()));
        let tr = b.translation();
        for (w, y_w) in [(0usize, self.half_track), (1, -self.half_track)] {
            let (rx, ry) = (-s * y_w, c * y_w);
            let (px, py) = (vx - om * ry, vy + om * rx);
            let along = px * c + py * s;
            let across = -px * s + py * c;
            let mut fl = self.m_long * (mean[w] - along) / h;
            let mut ft = self.mass * 0.5 * (-across) / h;
            let mag = fl.hypot(ft);
            if mag > self.max_force_n {
                fl *= self.max_force_n / mag;
                ft *= self.max_force_n / mag;
            }
            let f = Vector::new((fl * c - ft * s) as Real, (fl * s + ft * c) as Real);
            let at = Vector::new(tr.x + rx as Real, tr.y + ry as Real);
            b.add_force_at_point(f, at, false);
        }
    }
}
