//! Newton's method on an island's whole contact problem: the same rows as the
//! [`solver`](super::solver)'s sweeps (each wheel's friction disk, each contact point's normal
//! and its Coulomb friction), solved together instead of one row at a time, to the fixed point
//! the sweeps approach.
//!
//! With each friction row's bound `μ·λn` held, the problem is convex in the island's
//! velocities: minimise `½‖v − v_free‖²_M + Σ wheels B‖slip‖ + Σ points μλn|v_t|` subject to
//! `v_n ≥ target`. It is solved by the augmented Lagrangian (the proximal point method on the
//! impulses): each outer iteration minimises the smooth, strongly convex function whose
//! gradient is `M(v − v_free) − Σ Jᵀ P_K(λ̂ + ρ·r(v))` (`P_K` the projection on a row's set of
//! impulses: the wheel's disk, `λn ≥ 0`, `|λt| ≤ μλn`; `r` the row's velocity error) by
//! Newton's method (the generalised Hessian `M + Σ ρ Jᵀ DP_K J`, a dense Cholesky solve, an
//! exact line search on the slope, which is nondecreasing because the function is convex),
//! then sets `λ̂ ← P_K(λ̂ + ρ·r(v))` and the friction bounds from the new normal impulses. A
//! fixed point of this is the solution: every sticking row's velocity error zero, every sliding
//! wheel's impulse on its disk against its slip, every normal impulse complementary to its gap.
//! Impulses that are not unique (two wheels share a robot's sideways row; two points of one
//! face share its push) do not drift: the proximal step moves no impulse along a direction that
//! changes no velocity.
//!
//! The stop: an outer iteration that changes no row's impulse by more than its effective mass
//! times 0.1 µm/s (the natural residual `|λ − P_K(λ + m·r)| / m` of the sweeps' own rows then
//! below 0.1 µm/s) and no friction bound by more than that, at most
//! [`NEWTON_MAX_OUTER`](crate::params::NEWTON_MAX_OUTER) outer iterations (a cap that is
//! counted, as the sweeps' is).

use crate::body::BodyConst;
use crate::pipeline::solver::{CONTACT_SKIN_M, Contact, IslandBody, WALL};

pub(crate) use crate::params::NEWTON_MAX_ROBOTS;

/// The penalty of a row over its effective mass at the start of a solve: larger converges in
/// fewer outer iterations and makes the Newton systems stiffer.
const KAPPA: f64 = 300.0;

/// When an outer iteration does not cut the impulses' change to a quarter, the penalties are
/// doubled, up to this many times their start (a row whose impulse must travel far, e.g. a
/// normal that has to grow until a sticking wheel slides, gets there in fewer iterations).
const MAX_BOOST: f64 = 1e3;

/// A row's velocity error small enough to call the solve converged: 0.1 µm/s (1 nm over a
/// 10 ms sub-step).
const TOL_M_PER_S: f64 = 1e-7;

/// Newton steps per outer iteration, at most.
const MAX_INNER: u32 = 40;

/// A Newton step this small (m/s, the turn rate counted at the body's half-diagonal) ends an
/// outer iteration's minimisation.
const STEP_M_PER_S: f64 = 1e-14;

/// One row: `r(v) = c − (ja·v_a + jb·v_b)`, its impulse applied as `Jᵀλ`.
#[derive(Debug, Clone, Copy, Default)]
struct Row {
    /// First body (local index).
    a: u32,
    /// Second body, or [`WALL`] (none).
    b: u32,
    /// The row's Jacobian on a (vx, vy, ω).
    ja: [f64; 3],
    /// The row's Jacobian on b.
    jb: [f64; 3],
    /// The velocity the row wants (`J·v = c`).
    c: f64,
    /// Penalty, kg.
    rho: f64,
    /// The row's effective mass as the sweeps take it, kg (the penalty's unit).
    m: f64,
}

/// A set a group of rows' impulses must lie in.
#[derive(Debug, Clone, Copy)]
enum Set {
    /// Two rows (a wheel's along and across) in a disk of this radius, N·s.
    Disk(f64),
    /// One row (a normal) at or above zero.
    NonNegative,
    /// One row (a friction) within ±`mu` times the normal row at this index's impulse.
    Friction(usize, f64),
}

/// A group: its first row and its set.
#[derive(Debug, Clone, Copy)]
struct Group {
    row: usize,
    set: Set,
}

/// The solver's scratch (kept between islands so that none allocates).
#[derive(Debug, Clone, Default)]
pub(crate) struct NewtonScratch {
    rows: Vec<Row>,
    groups: Vec<Group>,
    /// The outer iteration's impulses λ̂.
    lam: Vec<f64>,
    /// Each friction row's bound (μ times its normal's impulse, held through a minimisation).
    tau: Vec<f64>,
    /// `P_K(λ̂ + ρ r(v))` at the current v.
    proj: Vec<f64>,
    /// Each row's `λ̂ + ρ r(v)` at the current v, and its change along the Newton step.
    y: Vec<f64>,
    dy: Vec<f64>,
    /// Velocities (3 per body): current, free, gradient, step.
    v: Vec<f64>,
    vf: Vec<f64>,
    grad: Vec<f64>,
    step: Vec<f64>,
    /// The Newton system (n × n, row-major), factored in place.
    hess: Vec<f64>,
    /// The masses (m, m, I per body).
    mass: Vec<f64>,
}

/// Solves the island (`bodies`, `contacts` as [`solve_island`](super::solver::solve_island)
/// takes them) over a sub-step of `h` seconds: the velocities, the wheels' and the contacts'
/// impulses are written back. Returns the Newton steps taken and whether the solve converged
/// (`false`: `max_outer` outer iterations stopped it).
pub(crate) fn solve_island_newton(
    bodies: &mut [IslandBody],
    contacts: &mut [Contact],
    body: &BodyConst,
    h: f64,
    max_outer: u32,
    s: &mut NewtonScratch,
) -> (u32, bool) {
    build(bodies, contacts, body, h, s);
    let n = 3 * bodies.len();
    // The first guess: the free velocities with the warm-start impulses applied.
    s.v.clear();
    s.v.extend_from_slice(&s.vf);
    for (i, row) in s.rows.iter().enumerate() {
        apply(&mut s.v, &s.mass, row, s.lam[i]);
    }
    let mut steps = 0;
    let mut converged = false;
    let mut boost = 1.0;
    let mut last = f64::INFINITY;
    for _ in 0..max_outer {
        steps += minimise(s, n, body.radius_m);
        // λ̂ ← P_K(λ̂ + ρ r(v)): the proj of the minimiser.
        project(s, false);
        // Each row's velocity error at the minimiser: its impulse's change over its penalty.
        let mut change: f64 = 0.0;
        for (i, row) in s.rows.iter().enumerate() {
            let d = (s.proj[i] - s.lam[i]).abs() / row.rho;
            change = if d > change || d.is_nan() { d } else { change };
        }
        core::mem::swap(&mut s.lam, &mut s.proj);
        // The friction bounds from the new normal impulses (Coulomb's coupling, a fixed point
        // reached along with the impulses').
        let bound_change = bounds_from_normals(s);
        if change < TOL_M_PER_S && bound_change < TOL_M_PER_S {
            converged = true;
            break;
        }
        // A velocity error that has stopped falling: a stiffer penalty.
        if change > 0.25 * last && boost < MAX_BOOST {
            boost *= 2.0;
            for row in s.rows.iter_mut() {
                row.rho = KAPPA * boost * row.m;
            }
        }
        last = change;
    }
    // The velocities from the impulses, so that momentum balances them exactly.
    s.v.clear();
    s.v.extend_from_slice(&s.vf);
    for (i, row) in s.rows.iter().enumerate() {
        apply(&mut s.v, &s.mass, row, s.lam[i]);
    }
    write_back(bodies, contacts, s);
    (steps, converged)
}

/// Fills the rows, groups, masses, free velocities and the warm-start impulses.
fn build(
    bodies: &[IslandBody],
    contacts: &[Contact],
    body: &BodyConst,
    h: f64,
    s: &mut NewtonScratch,
) {
    s.rows.clear();
    s.groups.clear();
    s.lam.clear();
    s.vf.clear();
    s.mass.clear();
    let bound = body.wheel_force_n * h;
    for (k, b) in bodies.iter().enumerate() {
        s.vf.extend_from_slice(&b.vel);
        s.mass
            .extend_from_slice(&[body.mass, body.mass, 1.0 / body.inv_i]);
        for (w, y_w) in [(0usize, body.half_track), (1, -body.half_track)] {
            s.groups.push(Group {
                row: s.rows.len(),
                set: Set::Disk(bound),
            });
            let one = |ja: [f64; 3], c: f64| Row {
                a: k as u32,
                b: WALL,
                ja,
                jb: [0.0; 3],
                c,
                rho: KAPPA * body.wheel_mass_long,
                m: body.wheel_mass_long,
            };
            s.rows.push(one([b.c, b.s, -y_w], b.wheel_speed[w]));
            s.rows.push(one([-b.s, b.c, 0.0], 0.0));
            s.lam.push(b.wheel_imp[2 * w]);
            s.lam.push(b.wheel_imp[2 * w + 1]);
        }
    }
    let inv_h = 1.0 / h;
    for ct in contacts {
        let (nx, ny) = (ct.nx, ct.ny);
        let (tx, ty) = (-ny, nx);
        let mu = if ct.lb == WALL {
            body.mu_wall
        } else {
            body.mu_robot
        };
        for p in &ct.pts[..usize::from(ct.count)] {
            let jac = |x: f64, y: f64| {
                let ja = [-x, -y, -(p.ra[0] * y - p.ra[1] * x)];
                let jb = if ct.lb == WALL {
                    [0.0; 3]
                } else {
                    [x, y, p.rb[0] * y - p.rb[1] * x]
                };
                (ja, jb)
            };
            let normal = s.rows.len();
            let (ja, jb) = jac(nx, ny);
            s.groups.push(Group {
                row: normal,
                set: Set::NonNegative,
            });
            s.rows.push(Row {
                a: ct.la,
                b: ct.lb,
                ja,
                jb,
                c: -(p.sep - CONTACT_SKIN_M) * inv_h,
                rho: KAPPA * p.mass_n,
                m: p.mass_n,
            });
            s.lam.push(p.ln);
            let (ja, jb) = jac(tx, ty);
            s.groups.push(Group {
                row: s.rows.len(),
                set: Set::Friction(normal, mu),
            });
            s.rows.push(Row {
                a: ct.la,
                b: ct.lb,
                ja,
                jb,
                c: 0.0,
                rho: KAPPA * p.mass_t,
                m: p.mass_t,
            });
            s.lam.push(p.lt);
        }
    }
    s.proj.clear();
    s.proj.resize(s.rows.len(), 0.0);
    s.tau.clear();
    s.tau.resize(s.rows.len(), 0.0);
    bounds_from_normals(s);
}

/// Sets each friction row's bound to μ times its normal row's impulse; returns the largest
/// change of a bound over its row's mass, m/s.
fn bounds_from_normals(s: &mut NewtonScratch) -> f64 {
    let mut change: f64 = 0.0;
    for g in &s.groups {
        if let Set::Friction(normal, mu) = g.set {
            let new = mu * s.lam[normal].max(0.0);
            let d = (new - s.tau[g.row]).abs() / s.rows[g.row].m;
            change = if d > change || d.is_nan() { d } else { change };
            s.tau[g.row] = new;
        }
    }
    change
}

/// Adds the row's impulse `λ` to the velocities `v` (masses `mass`).
#[inline]
fn apply(v: &mut [f64], mass: &[f64], row: &Row, lam: f64) {
    let a = 3 * row.a as usize;
    for j in 0..3 {
        v[a + j] += row.ja[j] * lam / mass[a + j];
    }
    if row.b != WALL {
        let b = 3 * row.b as usize;
        for j in 0..3 {
            v[b + j] += row.jb[j] * lam / mass[b + j];
        }
    }
}

/// `J·v` of a row.
#[inline]
fn jv(v: &[f64], row: &Row) -> f64 {
    let a = 3 * row.a as usize;
    let mut x = row.ja[0] * v[a] + row.ja[1] * v[a + 1] + row.ja[2] * v[a + 2];
    if row.b != WALL {
        let b = 3 * row.b as usize;
        x += row.jb[0] * v[b] + row.jb[1] * v[b + 1] + row.jb[2] * v[b + 2];
    }
    x
}

/// `λ̂ + ρ r(v)` of row `i`.
#[inline]
fn y_of(s: &NewtonScratch, v: &[f64], i: usize) -> f64 {
    let row = &s.rows[i];
    s.lam[i] + row.rho * (row.c - jv(v, row))
}

/// The slope along the step of the rows' part of the augmented Lagrangian at `t`:
/// `Σ P_K(y + t·dy)·dy / ρ`.
fn rows_slope(s: &NewtonScratch, t: f64) -> f64 {
    let y = |i: usize| s.y[i] + t * s.dy[i];
    let mut f = 0.0;
    for g in &s.groups {
        let i = g.row;
        let rho = s.rows[i].rho;
        f += match g.set {
            Set::Disk(bound) => {
                let (y0, y1) = (y(i), y(i + 1));
                let r = (y0 * y0 + y1 * y1).sqrt();
                let k = if r > bound { bound / r } else { 1.0 };
                k * (y0 * s.dy[i] + y1 * s.dy[i + 1])
            }
            Set::NonNegative => y(i).max(0.0) * s.dy[i],
            Set::Friction(..) => y(i).clamp(-s.tau[i], s.tau[i]) * s.dy[i],
        } / rho;
    }
    f
}

/// Sets `proj` to `P_K(λ̂ + ρ r(v))` at `s.v`; with `hessian`, adds each group's
/// `ρ Jᵀ DP J` to `s.hess` (which holds M).
fn project(s: &mut NewtonScratch, hessian: bool) {
    let n = s.v.len();
    s.y.clear();
    for i in 0..s.rows.len() {
        let y = y_of(s, &s.v, i);
        s.y.push(y);
    }
    for g in 0..s.groups.len() {
        let Group { row: i, set } = s.groups[g];
        let y0 = s.y[i];
        match set {
            Set::Disk(bound) => {
                let y1 = s.y[i + 1];
                let r = (y0 * y0 + y1 * y1).sqrt();
                // DP: the identity inside the disk; (B/r)(I − ŷŷᵀ) outside.
                let dp = if r <= bound {
                    s.proj[i] = y0;
                    s.proj[i + 1] = y1;
                    [1.0, 0.0, 1.0]
                } else {
                    let k = bound / r;
                    s.proj[i] = k * y0;
                    s.proj[i + 1] = k * y1;
                    let (u0, u1) = (y0 / r, y1 / r);
                    [k * (1.0 - u0 * u0), -k * u0 * u1, k * (1.0 - u1 * u1)]
                };
                if hessian {
                    // Both rows act on one body: ρ Jᵀ DP J over its 3 × 3 block.
                    let (ra, rb) = (s.rows[i], s.rows[i + 1]);
                    let a = 3 * ra.a as usize;
                    for p in 0..3 {
                        for q in 0..3 {
                            let jp = [ra.ja[p], rb.ja[p]];
                            let jq = [ra.ja[q], rb.ja[q]];
                            let x = jp[0] * (dp[0] * jq[0] + dp[1] * jq[1])
                                + jp[1] * (dp[1] * jq[0] + dp[2] * jq[1]);
                            s.hess[(a + p) * n + a + q] += ra.rho * x;
                        }
                    }
                }
            }
            Set::NonNegative => {
                s.proj[i] = y0.max(0.0);
                if hessian && y0 > 0.0 {
                    add_outer(&mut s.hess, n, &s.rows[i]);
                }
            }
            Set::Friction(..) => {
                let bound = s.tau[i];
                s.proj[i] = y0.clamp(-bound, bound);
                if hessian && y0.abs() < bound {
                    add_outer(&mut s.hess, n, &s.rows[i]);
                }
            }
        }
    }
}

/// Adds `ρ JᵀJ` of one row to the n × n matrix `hess`.
fn add_outer(hess: &mut [f64], n: usize, row: &Row) {
    let parts = [(row.a, row.ja), (row.b, row.jb)];
    for &(p, jp) in &parts {
        if p == WALL {
            continue;
        }
        for &(q, jq) in &parts {
            if q == WALL {
                continue;
            }
            let (p3, q3) = (3 * p as usize, 3 * q as usize);
            for x in 0..3 {
                for y in 0..3 {
                    hess[(p3 + x) * n + q3 + y] += row.rho * jp[x] * jq[y];
                }
            }
        }
    }
}

/// Minimises the augmented Lagrangian over the velocities `s.v` (λ̂ held) by Newton's method
/// with a backtracking line search. Returns the Newton steps taken.
fn minimise(s: &mut NewtonScratch, n: usize, radius: f64) -> u32 {
    let mut steps = 0;
    for _ in 0..MAX_INNER {
        s.hess.clear();
        s.hess.resize(n * n, 0.0);
        for k in 0..n {
            s.hess[k * n + k] = s.mass[k];
        }
        project(s, true);
        // The gradient M(v − v_free) − Σ Jᵀ P.
        s.grad.clear();
        for k in 0..n {
            s.grad.push(s.mass[k] * (s.v[k] - s.vf[k]));
        }
        for (i, row) in s.rows.iter().enumerate() {
            apply_unscaled(&mut s.grad, row, -s.proj[i]);
        }
        // The step: H d = −g.
        s.step.clear();
        s.step.extend(s.grad.iter().map(|g| -g));
        if !cholesky_solve(&mut s.hess, &mut s.step, n) {
            break;
        }
        steps += 1;
        // Along the step each row's y is linear and the kinetic part quadratic in t.
        s.dy.clear();
        for i in 0..s.rows.len() {
            let row = &s.rows[i];
            let d = -row.rho * jv(&s.step, row);
            s.dy.push(d);
        }
        let (mut q1, mut q2) = (0.0, 0.0);
        for k in 0..n {
            q1 += s.mass[k] * (s.v[k] - s.vf[k]) * s.step[k];
            q2 += 0.5 * s.mass[k] * s.step[k] * s.step[k];
        }
        // The exact minimum along the step (the slope is nondecreasing in t: the function is
        // convex): the full step if the slope at it is still downhill, else the slope's root
        // by regula falsi (Illinois) between 0 and 1.
        let slope0: f64 = s.grad.iter().zip(&s.step).map(|(g, d)| g * d).sum();
        // Not downhill (or NaN): nothing to gain.
        if slope0 >= 0.0 || slope0.is_nan() {
            break;
        }
        let mut t = 1.0;
        let slope1 = q1 + 2.0 * q2 + rows_slope(s, 1.0);
        if slope1 > 0.0 {
            let (mut lo, mut flo, mut hi, mut fhi) = (0.0, slope0, 1.0, slope1);
            let mut side = 0i8;
            for _ in 0..60 {
                t = (lo * fhi - hi * flo) / (fhi - flo);
                if !(t > lo && t < hi) {
                    t = 0.5 * (lo + hi);
                }
                let f = q1 + 2.0 * q2 * t + rows_slope(s, t);
                if f > 0.0 {
                    hi = t;
                    fhi = f;
                    if side == 1 {
                        flo *= 0.5;
                    }
                    side = 1;
                } else {
                    lo = t;
                    flo = f;
                    if side == -1 {
                        fhi *= 0.5;
                    }
                    side = -1;
                }
                if hi - lo < 1e-3 * hi || f == 0.0 {
                    break;
                }
            }
        }
        for (v, d) in s.v.iter_mut().zip(&s.step) {
            *v += t * d;
        }
        let mut moved: f64 = 0.0;
        for (k, d) in s.step.iter().enumerate() {
            let d = d.abs() * if k % 3 == 2 { radius } else { 1.0 };
            moved = if d > moved || d.is_nan() { d } else { moved };
        }
        if moved < STEP_M_PER_S || moved.is_nan() {
            return steps;
        }
    }
    steps
}

/// Adds `Jᵀλ` of a row (an impulse, not divided by the masses) to `g`.
#[inline]
fn apply_unscaled(g: &mut [f64], row: &Row, lam: f64) {
    let a = 3 * row.a as usize;
    for j in 0..3 {
        g[a + j] += row.ja[j] * lam;
    }
    if row.b != WALL {
        let b = 3 * row.b as usize;
        for j in 0..3 {
            g[b + j] += row.jb[j] * lam;
        }
    }
}

/// Solves `A x = b` for the symmetric positive definite n × n `a` (row-major, overwritten by
/// its Cholesky factor), `b` overwritten by `x`. `false` if `a` is not positive definite.
fn cholesky_solve(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d <= 0.0 || d.is_nan() {
            return false;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut x = a[i * n + j];
            for k in 0..j {
                x -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = x / d;
        }
    }
    for i in 0..n {
        let mut x = b[i];
        for k in 0..i {
            x -= a[i * n + k] * b[k];
        }
        b[i] = x / a[i * n + i];
    }
    for i in (0..n).rev() {
        let mut x = b[i];
        for k in i + 1..n {
            x -= a[k * n + i] * b[k];
        }
        b[i] = x / a[i * n + i];
    }
    true
}

/// Writes the velocities and impulses back to the island.
fn write_back(bodies: &mut [IslandBody], contacts: &mut [Contact], s: &NewtonScratch) {
    for (k, b) in bodies.iter_mut().enumerate() {
        b.vel = [s.v[3 * k], s.v[3 * k + 1], s.v[3 * k + 2]];
        b.wheel_imp.copy_from_slice(&s.lam[4 * k..4 * k + 4]);
    }
    let mut i = 4 * bodies.len();
    for ct in contacts.iter_mut() {
        for p in ct.pts[..usize::from(ct.count)].iter_mut() {
            p.ln = s.lam[i];
            p.lt = s.lam[i + 1];
            i += 2;
        }
    }
}

/// The island's distance from the fixed point, m/s: the largest natural residual
/// `|λ − P_K(λ + m·r(v))| / m` over its rows (`m` the row's effective mass as the sweeps use
/// it), with `vf` the velocities before the solve, `bodies` and `contacts` after it; and the
/// largest momentum error `|M(v − v_free) − Jᵀλ| / M`. Zero exactly when every row's condition
/// holds: the test of any solver's answer.
#[cfg(test)]
pub(crate) fn fixed_point_residual(
    vf: &[[f64; 3]],
    bodies: &[IslandBody],
    contacts: &[Contact],
    body: &BodyConst,
    h: f64,
) -> f64 {
    let mut probe: Vec<IslandBody> = bodies.to_vec();
    for (b, v) in probe.iter_mut().zip(vf) {
        b.vel = *v;
    }
    let mut s = NewtonScratch::default();
    build(&probe, contacts, body, h, &mut s);
    s.v = bodies.iter().flat_map(|b| b.vel).collect();
    // Rows at their own masses, as a sweep would take them (the wheel's disk at one mass).
    for row in s.rows.iter_mut() {
        row.rho = row.m;
    }
    project(&mut s, false);
    let mut worst: f64 = 0.0;
    for (i, row) in s.rows.iter().enumerate() {
        worst = worst.max((s.proj[i] - s.lam[i]).abs() / row.rho);
    }
    let mut v = s.vf.clone();
    for (i, row) in s.rows.iter().enumerate() {
        apply(&mut v, &s.mass, row, s.lam[i]);
    }
    for (k, (a, b)) in v.iter().zip(&s.v).enumerate() {
        let scale = if k % 3 == 2 { body.radius_m } else { 1.0 };
        worst = worst.max((a - b).abs() * scale);
    }
    worst
}
