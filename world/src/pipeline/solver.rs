//! The contact solver: sequential impulses (projected Gauss–Seidel) on the velocities of the
//! robots that touch something, with the wheels' traction as friction-limited velocity
//! constraints, Coulomb friction at the contacts and speculative contacts for the gaps.
//!
//! Each robot is a rigid box of mass `m` and moment of inertia `I` on two driven wheels. A wheel
//! grips the floor: it makes the body's velocity at the wheel's contact point equal its rim
//! speed along the wheel and zero across it, with a force up to `μ_floor · m·g/2` (half the
//! weight on each drive wheel; the caster carries little); past that the wheel slips. A contact
//! between two bodies (or a body and a wall) pushes them apart along its normal, never pulls,
//! and resists sliding along it with Coulomb friction `μ · normal force`. These are the
//! impulse-level equations of Box2D's solver (E. Catto, "Iterative Dynamics with Temporal
//! Coherence", GDC 2005), solved in a fixed order so the result is deterministic.
//!
//! Speculative contacts (Catto, "Continuous collision", GDC 2013): a contact whose points are
//! `sep > 0` apart allows the bodies to approach by `sep` in the sub-step, no more; one with
//! `sep < 0` (an overlap, left by the linearisation of a rotation) is pushed apart by `−sep`
//! within the sub-step.

use crate::body::BodyConst;
use crate::contact::Manifold;
use crate::params::Convergence;

/// The gap the solver closes a contact to, and pushes an overlap apart to (10 nm), so that
/// bodies do not touch even after rounding; far below anything a sensor or a metric resolves.
pub const CONTACT_SKIN_M: f64 = 1e-8;

/// A robot–robot or robot–wall contact and the solver's state for its points.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Contact {
    /// First robot.
    pub a: u32,
    /// Second robot, or [`WALL`].
    pub b: u32,
    /// First robot's index in its island (set before the solve).
    pub la: u32,
    /// Second robot's index in its island, or [`WALL`].
    pub lb: u32,
    /// Unit normal from a to b.
    pub nx: f64,
    /// See `nx`.
    pub ny: f64,
    /// Number of points (1 or 2).
    pub count: u8,
    /// The manifold's feature key (see `Manifold::key`).
    pub key: u8,
    /// The points.
    pub pts: [ContactRow; 2],
}

/// `Contact::b` of a wall contact.
pub(crate) const WALL: u32 = u32::MAX;

/// One contact point's solver rows.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct ContactRow {
    /// Lever arm from a's centre, metres.
    pub ra: [f64; 2],
    /// Lever arm from b's centre (zero for a wall), metres.
    pub rb: [f64; 2],
    /// Separation at the start of the sub-step, metres.
    pub sep: f64,
    /// Effective mass along the normal, kg.
    pub mass_n: f64,
    /// Effective mass along the tangent, kg.
    pub mass_t: f64,
    /// Accumulated normal impulse, N·s (≥ 0).
    pub ln: f64,
    /// Accumulated friction impulse, N·s.
    pub lt: f64,
}

impl Contact {
    /// A contact from a manifold between robots `a` and `b` (or a wall) at the given centres.
    pub(crate) fn new(
        a: u32,
        b: u32,
        m: &Manifold,
        ca: (f64, f64),
        cb: (f64, f64),
        body: &BodyConst,
    ) -> Contact {
        let mut c = Contact {
            a,
            b,
            la: 0,
            lb: b,
            nx: m.nx,
            ny: m.ny,
            count: m.count as u8,
            key: m.key,
            pts: [ContactRow::default(); 2],
        };
        let wall = b == WALL;
        let (tx, ty) = (-m.ny, m.nx);
        for (row, p) in c.pts.iter_mut().zip(&m.points[..m.count]) {
            let ra = [p.x - ca.0, p.y - ca.1];
            let rb = if wall {
                [0.0; 2]
            } else {
                [p.x - cb.0, p.y - cb.1]
            };
            let inv_b = if wall { 0.0 } else { body.inv_m };
            let inv_ib = if wall { 0.0 } else { body.inv_i };
            let rna = cross(ra, m.nx, m.ny);
            let rnb = cross(rb, m.nx, m.ny);
            let rta = cross(ra, tx, ty);
            let rtb = cross(rb, tx, ty);
            let kn = body.inv_m + inv_b + body.inv_i * rna * rna + inv_ib * rnb * rnb;
            let kt = body.inv_m + inv_b + body.inv_i * rta * rta + inv_ib * rtb * rtb;
            *row = ContactRow {
                ra,
                rb,
                sep: p.sep,
                mass_n: 1.0 / kn,
                mass_t: 1.0 / kt,
                ln: 0.0,
                lt: 0.0,
            };
        }
        c
    }

    /// The identity of the contact across sub-steps: robots and touching features.
    pub(crate) fn id(&self) -> (u32, u32, u8) {
        (self.a, self.b, self.key)
    }

    /// Total normal impulse over the points, N·s.
    pub(crate) fn normal_impulse(&self) -> f64 {
        self.pts[..usize::from(self.count)]
            .iter()
            .map(|p| p.ln)
            .sum()
    }
}

/// `r × (x, y)` in 2-D.
#[inline]
fn cross(r: [f64; 2], x: f64, y: f64) -> f64 {
    r[0] * y - r[1] * x
}

/// One robot of an island as the solver sees it: heading at the start of the sub-step, its
/// world-frame velocity (vx, vy, ω; the momentum in, the solution out), its wheels' rim speeds
/// over the sub-step (left, right) and their accumulated impulses (left along, left across,
/// right along, right across; the warm-start guess in, the solution out).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct IslandBody {
    /// cos of the heading.
    pub c: f64,
    /// sin of the heading.
    pub s: f64,
    /// Velocity (vx, vy, ω).
    pub vel: [f64; 3],
    /// Wheel rim speeds, m/s.
    pub wheel_speed: [f64; 2],
    /// Wheel impulses, N·s.
    pub wheel_imp: [f64; 4],
}

/// One sub-step's velocity solve of an island (robots connected by contacts; contacts refer
/// to them by `la`, `lb`): the warm-start impulses are applied, then up to `iterations`
/// Gauss–Seidel sweeps, each over the bodies' wheels in order, then the contacts in order,
/// until a sweep has converged by `until` ([`Convergence`]; `vel0` holds the velocities at a
/// sweep's start, one entry per body, and may be empty for [`Convergence::Impulse`]). Returns
/// the sweeps run and whether the last of them converged (`false`: the cap stopped the solve).
pub(crate) fn solve_island(
    bodies: &mut [IslandBody],
    contacts: &mut [Contact],
    body: &BodyConst,
    h: f64,
    iterations: u32,
    until: Convergence,
    vel0: &mut [[f64; 3]],
) -> (u32, bool) {
    match until {
        // Sweeps under the Newton solver (its large islands) are converged by impulse.
        Convergence::Impulse | Convergence::Newton => {
            solve_island_until::<false>(bodies, contacts, body, h, iterations, &mut [])
        }
        Convergence::Velocity => {
            solve_island_until::<true>(bodies, contacts, body, h, iterations, vel0)
        }
    }
}

/// [`solve_island`], converged by velocity (`BY_VELOCITY`) or by impulse.
#[inline(always)]
fn solve_island_until<const BY_VELOCITY: bool>(
    bodies: &mut [IslandBody],
    contacts: &mut [Contact],
    body: &BodyConst,
    h: f64,
    iterations: u32,
    vel0: &mut [[f64; 3]],
) -> (u32, bool) {
    let inv_h = 1.0 / h;
    let wheel_bound = body.wheel_force_n * h;
    // Warm start: the impulses the caller kept from the previous sub-step (the same contact,
    // the same wheels) are applied first, so that a steady push converges at once.
    for b in bodies.iter_mut() {
        let (c, s) = (b.c, b.s);
        for (w, y_w) in [(0usize, body.half_track), (1, -body.half_track)] {
            let (dl, dt) = (b.wheel_imp[2 * w], b.wheel_imp[2 * w + 1]);
            b.vel[0] += (dl * c - dt * s) * body.inv_m;
            b.vel[1] += (dl * s + dt * c) * body.inv_m;
            b.vel[2] -= dl * y_w * body.inv_i;
        }
    }
    for ct in contacts.iter() {
        let (nx, ny) = (ct.nx, ct.ny);
        for p in &ct.pts[..usize::from(ct.count)] {
            let px = p.ln * nx - p.lt * ny;
            let py = p.ln * ny + p.lt * nx;
            apply(bodies, ct.la, ct.lb, p, px, py, body);
        }
    }
    let mut sweeps = 0;
    for _ in 0..iterations {
        sweeps += 1;
        if BY_VELOCITY {
            for (v0, b) in vel0.iter_mut().zip(bodies.iter()) {
                *v0 = b.vel;
            }
        }
        // The largest impulse change of the sweep: below CONVERGED_N_S the sweep changed no
        // velocity by more than a few µm/s and the rest would change nothing that shows.
        let mut change: f64 = 0.0;
        for b in bodies.iter_mut() {
            let (c, s) = (b.c, b.s);
            for (w, y_w) in [(0usize, body.half_track), (1, -body.half_track)] {
                let v = b.vel;
                // Wheel contact point at r = R·(0, y_w) = (−s·y_w, c·y_w).
                let along = v[0] * c + v[1] * s - v[2] * y_w;
                let across = -v[0] * s + v[1] * c;
                let d_long = body.wheel_mass_long * (b.wheel_speed[w] - along);
                let d_lat = -body.wheel_mass_lat * across;
                // The wheel's friction disk: the accumulated impulse is clamped to it.
                let (old_l, old_t) = (b.wheel_imp[2 * w], b.wheel_imp[2 * w + 1]);
                let (mut nl, mut nt) = (old_l + d_long, old_t + d_lat);
                let mag2 = nl * nl + nt * nt;
                if mag2 > wheel_bound * wheel_bound {
                    // The wheel slides: Coulomb friction points against the slip. The rows'
                    // own masses (m_long ≈ 0.26 kg, m_lat = 0.5 kg) would make the clamped
                    // impulse's direction the slip weighted by them (sideways slip resisted
                    // 1.9 times too hard); one mass for both rows makes the fixed point on
                    // the friction disk point exactly against the slip.
                    let m = body.wheel_mass_long;
                    nl = old_l + m * (b.wheel_speed[w] - along);
                    nt = old_t - m * across;
                    let mag2 = nl * nl + nt * nt;
                    if mag2 > wheel_bound * wheel_bound {
                        let k = wheel_bound / mag2.sqrt();
                        nl *= k;
                        nt *= k;
                    }
                }
                let (d_long, d_lat) = (nl - old_l, nt - old_t);
                change = larger(larger(change, d_long.abs()), d_lat.abs());
                b.wheel_imp[2 * w] = nl;
                b.wheel_imp[2 * w + 1] = nt;
                // Impulse along e = (c, s) and f = (−s, c) at the wheel; r × e = −y_w, r × f = 0.
                b.vel[0] += (d_long * c - d_lat * s) * body.inv_m;
                b.vel[1] += (d_long * s + d_lat * c) * body.inv_m;
                b.vel[2] -= d_long * y_w * body.inv_i;
            }
        }
        // Each contact works on copies of its robots' velocities (a wall's stays zero), written
        // back after its rows: the same arithmetic as on the island's bodies in place.
        for ct in contacts.iter_mut() {
            let (mut va, mut vb) = velocities(bodies, ct.la, ct.lb);
            let d = if ct.lb == WALL {
                contact_rows::<true>(&mut va, &mut vb, ct, body.mu_wall, body, inv_h)
            } else {
                contact_rows::<false>(&mut va, &mut vb, ct, body.mu_robot, body, inv_h)
            };
            change = larger(change, d);
            store(bodies, ct.la, ct.lb, va, vb);
        }
        if BY_VELOCITY {
            let mut moved: f64 = 0.0;
            for (v0, b) in vel0.iter().zip(bodies.iter()) {
                moved = larger(moved, (b.vel[0] - v0[0]).abs());
                moved = larger(moved, (b.vel[1] - v0[1]).abs());
                moved = larger(moved, (b.vel[2] - v0[2]).abs() * body.radius_m);
            }
            if moved < CONVERGED_M_PER_S {
                return (sweeps, true);
            }
        } else if change < CONVERGED_N_S {
            return (sweeps, true);
        }
    }
    (sweeps, false)
}

/// One sweep's rows of contact `ct` between velocities `va` and `vb` (`TO_WALL`: b is a wall,
/// `vb` is zero and stays so), friction coefficient `mu`: each point's normal row (push,
/// never pull, towards the speculative target), then its friction row against the updated
/// velocities. Returns the largest impulse change.
#[inline(always)]
fn contact_rows<const TO_WALL: bool>(
    va: &mut [f64; 3],
    vb: &mut [f64; 3],
    ct: &mut Contact,
    mu: f64,
    body: &BodyConst,
    inv_h: f64,
) -> f64 {
    let mut change: f64 = 0.0;
    let (nx, ny) = (ct.nx, ct.ny);
    let (tx, ty) = (-ny, nx);
    for p in ct.pts[..usize::from(ct.count)].iter_mut() {
        let (rvx, rvy) = point_velocity(va, vb, p);
        let vn = rvx * nx + rvy * ny;
        // Allowed approach: close the gap down to the skin (sep > 0), or open an overlap to it
        // (sep < 0).
        let target = -(p.sep - CONTACT_SKIN_M) * inv_h;
        let new = (p.ln + p.mass_n * (target - vn)).max(0.0);
        let d = new - p.ln;
        p.ln = new;
        change = larger(change, d.abs());
        push::<TO_WALL>(va, vb, p, d * nx, d * ny, body);
        // Friction against the updated velocities.
        let (rvx, rvy) = point_velocity(va, vb, p);
        let vt = rvx * tx + rvy * ty;
        let bound = mu * p.ln;
        let new_t = (p.lt - p.mass_t * vt).clamp(-bound, bound);
        let dt = new_t - p.lt;
        p.lt = new_t;
        change = larger(change, dt.abs());
        push::<TO_WALL>(va, vb, p, dt * tx, dt * ty, body);
    }
    change
}

/// Velocity of b's contact point relative to a's, from their velocities.
#[inline(always)]
fn point_velocity(va: &[f64; 3], vb: &[f64; 3], p: &ContactRow) -> (f64, f64) {
    (
        (vb[0] - vb[2] * p.rb[1]) - (va[0] - va[2] * p.ra[1]),
        (vb[1] + vb[2] * p.rb[0]) - (va[1] + va[2] * p.ra[0]),
    )
}

/// Applies the impulse (px, py) to b at its lever arm (unless `TO_WALL`) and (−px, −py) to a.
#[inline(always)]
fn push<const TO_WALL: bool>(
    va: &mut [f64; 3],
    vb: &mut [f64; 3],
    p: &ContactRow,
    px: f64,
    py: f64,
    body: &BodyConst,
) {
    va[0] -= px * body.inv_m;
    va[1] -= py * body.inv_m;
    va[2] -= (p.ra[0] * py - p.ra[1] * px) * body.inv_i;
    if !TO_WALL {
        vb[0] += px * body.inv_m;
        vb[1] += py * body.inv_m;
        vb[2] += (p.rb[0] * py - p.rb[1] * px) * body.inv_i;
    }
}

/// The larger of a sweep's largest impulse change so far and `x`, an impulse change's size:
/// what `f64::max` gives for them, NaN included (a NaN `x` leaves `change`), without the
/// instructions its NaN handling costs on x86-64.
#[inline(always)]
fn larger(change: f64, x: f64) -> f64 {
    if x > change { x } else { change }
}

/// An impulse change small enough to call a sweep converged: 1e-6 N·s, a velocity change of
/// 2 µm/s on a 0.5 kg robot (40 nm over a 20 ms sub-step; what it leaves of an overlap the
/// position sweeps remove).
const CONVERGED_N_S: f64 = 1e-6;

/// A velocity change small enough to call a sweep converged by velocity: 2 µm/s (40 nm over a
/// 20 ms sub-step), what [`CONVERGED_N_S`] makes of a 0.5 kg robot's velocity.
const CONVERGED_M_PER_S: f64 = 2e-6;

/// Applies the impulse (px, py) to robot `lb` of the island at its lever arm (unless it is a
/// wall) and (−px, −py) to robot `la`.
#[inline]
fn apply(
    bodies: &mut [IslandBody],
    la: u32,
    lb: u32,
    p: &ContactRow,
    px: f64,
    py: f64,
    body: &BodyConst,
) {
    let (mut va, mut vb) = velocities(bodies, la, lb);
    if lb == WALL {
        push::<true>(&mut va, &mut vb, p, px, py, body);
    } else {
        push::<false>(&mut va, &mut vb, p, px, py, body);
    }
    store(bodies, la, lb, va, vb);
}

/// Copies of the velocities of robots `la` and `lb` of the island (a wall's: zero).
#[inline(always)]
fn velocities(bodies: &[IslandBody], la: u32, lb: u32) -> ([f64; 3], [f64; 3]) {
    let va = bodies[la as usize].vel;
    if lb == WALL {
        (va, [0.0; 3])
    } else {
        debug_assert_ne!(la, lb, "a contact joins two robots");
        (va, bodies[lb as usize].vel)
    }
}

/// Writes [`velocities`]' copies back (a wall's is dropped).
#[inline(always)]
fn store(bodies: &mut [IslandBody], la: u32, lb: u32, va: [f64; 3], vb: [f64; 3]) {
    bodies[la as usize].vel = va;
    if lb != WALL {
        bodies[lb as usize].vel = vb;
    }
}
