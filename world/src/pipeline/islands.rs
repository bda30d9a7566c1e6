//! The islands: the solved robots split into groups joined by robot–robot contacts (found by
//! union–find), each solved on its own, in order or on rayon's pool.

use core::ops::Range;

use rayon::prelude::*;

use crate::body::{BodyConst, BodyPose};
use crate::params::Convergence;
use crate::pipeline::newton::{NEWTON_MAX_ROBOTS, NewtonScratch, solve_island_newton};
use crate::pipeline::par::PAR_ISLAND_ROBOTS;
use crate::pipeline::solver::{Contact, IslandBody, WALL, solve_island};

/// Newton's method's limits under [`Convergence::Newton`]: its cap of outer iterations
/// ([`crate::params::NEWTON_MAX_OUTER`]) and the largest island it solves
/// ([`NEWTON_MAX_ROBOTS`]; larger ones are swept).
#[derive(Debug, Clone, Copy)]
pub(crate) struct NewtonLimits {
    /// Outer iterations, at most.
    pub(crate) max_outer: u32,
    /// Robots in an island, at most.
    pub(crate) max_robots: usize,
}

/// What a sub-step's solve of its islands did.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Solved {
    /// Gauss–Seidel sweeps, summed over the islands solved by sweeps.
    pub sweeps: u64,
    /// Islands a cap stopped before they converged.
    pub capped: u64,
    /// Islands solved by Newton's method.
    pub newton_islands: u64,
    /// Newton steps, summed over them.
    pub newton_steps: u64,
}

impl Solved {
    /// The sum of two counts.
    fn add(self, o: Solved) -> Solved {
        Solved {
            sweeps: self.sweeps + o.sweeps,
            capped: self.capped + o.capped,
            newton_islands: self.newton_islands + o.newton_islands,
            newton_steps: self.newton_steps + o.newton_steps,
        }
    }
}

/// Solves one island by the solver `until` chooses (Newton's method for a small island under
/// [`Convergence::Newton`], sweeps otherwise) and counts what it did.
#[allow(clippy::too_many_arguments)]
fn solve_one(
    bodies: &mut [IslandBody],
    contacts: &mut [Contact],
    body: &BodyConst,
    h: f64,
    iterations: u32,
    until: Convergence,
    vel0: &mut [[f64; 3]],
    (newton, limits): (&mut NewtonScratch, NewtonLimits),
) -> Solved {
    if until == Convergence::Newton && bodies.len() <= limits.max_robots {
        let (steps, converged) =
            solve_island_newton(bodies, contacts, body, h, limits.max_outer, newton);
        Solved {
            sweeps: 0,
            capped: u64::from(!converged),
            newton_islands: 1,
            newton_steps: u64::from(steps),
        }
    } else {
        // Under `Newton` an island too large for it is swept under the impulse test
        // (`solve_island` takes `Newton` so).
        let (sweeps, converged) = solve_island(bodies, contacts, body, h, iterations, until, vel0);
        Solved {
            sweeps: u64::from(sweeps),
            capped: u64::from(!converged),
            newton_islands: 0,
            newton_steps: 0,
        }
    }
}

/// The islands of the latest sub-step and the scratch that sorts robots and contacts into
/// them.
#[derive(Debug, Clone)]
pub(crate) struct Islands {
    /// Union-find parents of the active robots (scratch, by robot).
    uf: Vec<u32>,
    /// Island number of a union-find root (scratch, by robot; `u32::MAX` when unset).
    root_island: Vec<u32>,
    /// Per active robot (in the order [`Islands::build`] gives `active`), what the solver
    /// needs.
    pub(crate) bodies: Vec<IslandBody>,
    /// Per island, its range in `active`/`bodies` and in `contacts`.
    ranges: Vec<(Range<usize>, Range<usize>)>,
    /// Island of each active robot (scratch, in `active`'s order before the sort).
    isl_of: Vec<u32>,
    /// First place of each island in `active` (scratch; one more entry than islands).
    isl_start: Vec<usize>,
    /// Next free place of each island (scratch).
    isl_fill: Vec<usize>,
    /// `active` being sorted into islands (scratch).
    active_scratch: Vec<u32>,
    /// `contacts` being sorted into islands (scratch).
    contact_scratch: Vec<Contact>,
    /// Each body's velocity at the start of a sweep (scratch, like `bodies`, for a solve
    /// converged by velocity; empty otherwise).
    vel0: Vec<[f64; 3]>,
    /// Newton's method's scratch (for islands solved in order).
    newton: NewtonScratch,
    /// Newton's method's limits (the params' constants; tests lower them).
    pub(crate) newton_limits: NewtonLimits,
    /// When set, each solve appends every island's size and its distance from the fixed point
    /// after the solve (m/s, `newton::fixed_point_residual`).
    #[cfg(test)]
    pub(crate) residuals: Option<Vec<(usize, f64)>>,
}

/// Union–find root of `i`, halving the path on the way.
fn find(uf: &mut [u32], mut i: u32) -> u32 {
    while uf[i as usize] != i {
        let p = uf[uf[i as usize] as usize];
        uf[i as usize] = p;
        i = p;
    }
    i
}

impl Islands {
    /// No islands yet, for `n` robots.
    pub(crate) fn new(n: usize) -> Islands {
        Islands {
            uf: vec![0; n],
            root_island: vec![u32::MAX; n],
            bodies: Vec::new(),
            ranges: Vec::new(),
            isl_of: Vec::new(),
            isl_start: Vec::new(),
            isl_fill: Vec::new(),
            active_scratch: Vec::new(),
            contact_scratch: Vec::new(),
            vel0: Vec::new(),
            newton: NewtonScratch::default(),
            newton_limits: NewtonLimits {
                max_outer: crate::params::NEWTON_MAX_OUTER,
                max_robots: NEWTON_MAX_ROBOTS,
            },
            #[cfg(test)]
            residuals: None,
        }
    }

    /// Splits the solved robots `active` (in index order) into islands (connected by
    /// robot–robot contacts), numbered in order of their lowest robot: `active` is reordered
    /// island by island (index order within each), `contacts` likewise (their order kept
    /// within each island), every contact gets its robots' places in the island, and
    /// `bodies` the solver's view of each robot (from `pose`, `vel`, `wmean`, `wheel_imp`).
    pub(crate) fn build(
        &mut self,
        active: &mut Vec<u32>,
        contacts: &mut Vec<Contact>,
        pose: &[BodyPose],
        vel: &[[f64; 3]],
        wmean: &[[f64; 2]],
        wheel_imp: &[[f64; 4]],
    ) {
        let islands = self.number(active, contacts);
        self.sort_robots(active, islands);
        self.sort_contacts(contacts, islands);
        for &i in active.iter() {
            self.root_island[i as usize] = u32::MAX;
        }
        self.bodies.clear();
        for &i in active.iter() {
            let i = i as usize;
            self.bodies.push(IslandBody {
                c: pose[i].c,
                s: pose[i].s,
                vel: vel[i],
                wheel_speed: wmean[i],
                wheel_imp: wheel_imp[i],
            });
        }
    }

    /// Joins the robots of each robot–robot contact and numbers the islands in order of each
    /// island's lowest robot (`active` is in index order) into `isl_of`; returns how many.
    fn number(&mut self, active: &[u32], contacts: &[Contact]) -> usize {
        for &i in active {
            self.uf[i as usize] = i;
        }
        for ct in contacts {
            if ct.b != WALL {
                let (ra, rb) = (find(&mut self.uf, ct.a), find(&mut self.uf, ct.b));
                if ra != rb {
                    // The lower root wins, so the result does not depend on contact order.
                    let (lo, hi) = (ra.min(rb), ra.max(rb));
                    self.uf[hi as usize] = lo;
                }
            }
        }
        let mut count = 0u32;
        self.isl_of.clear();
        for &i in active {
            let r = find(&mut self.uf, i) as usize;
            if self.root_island[r] == u32::MAX {
                self.root_island[r] = count;
                count += 1;
            }
            self.isl_of.push(self.root_island[r]);
        }
        for &i in active {
            let r = find(&mut self.uf, i) as usize;
            self.root_island[r] = u32::MAX;
        }
        count as usize
    }

    /// Reorders `active` island by island, index order within each (a stable counting sort),
    /// and records each robot's island and place in it (through the `uf` scratch, no longer
    /// needed for the roots).
    fn sort_robots(&mut self, active: &mut Vec<u32>, islands: usize) {
        self.isl_start.clear();
        self.isl_start.resize(islands + 1, 0);
        for &k in &self.isl_of {
            self.isl_start[k as usize + 1] += 1;
        }
        for k in 0..islands {
            self.isl_start[k + 1] += self.isl_start[k];
        }
        self.isl_fill.clear();
        self.isl_fill.extend_from_slice(&self.isl_start[..islands]);
        self.active_scratch.clear();
        self.active_scratch.resize(active.len(), 0);
        for (k, &i) in active.iter().enumerate() {
            let isl = self.isl_of[k] as usize;
            self.active_scratch[self.isl_fill[isl]] = i;
            self.isl_fill[isl] += 1;
        }
        core::mem::swap(active, &mut self.active_scratch);
        self.ranges.clear();
        for isl in 0..islands {
            let range = self.isl_start[isl]..self.isl_start[isl + 1];
            for (local, &i) in active[range.clone()].iter().enumerate() {
                self.uf[i as usize] = local as u32;
                self.root_island[i as usize] = isl as u32;
            }
            self.ranges.push((range, 0..0));
        }
    }

    /// Reorders `contacts` island by island, their order kept within each (a stable counting
    /// sort), and gives each its robots' places in the island.
    fn sort_contacts(&mut self, contacts: &mut Vec<Contact>, islands: usize) {
        self.isl_fill.clear();
        self.isl_fill.resize(islands + 1, 0);
        for ct in contacts.iter() {
            self.isl_fill[self.root_island[ct.a as usize] as usize + 1] += 1;
        }
        for k in 0..islands {
            self.isl_fill[k + 1] += self.isl_fill[k];
        }
        for (isl, range) in self.ranges.iter_mut().enumerate() {
            range.1 = self.isl_fill[isl]..self.isl_fill[isl + 1];
        }
        self.contact_scratch.clear();
        self.contact_scratch
            .resize(contacts.len(), Contact::default());
        for ct in contacts.iter() {
            let isl = self.root_island[ct.a as usize] as usize;
            let mut c = *ct;
            c.la = self.uf[ct.a as usize];
            c.lb = if ct.b == WALL {
                WALL
            } else {
                self.uf[ct.b as usize]
            };
            self.contact_scratch[self.isl_fill[isl]] = c;
            self.isl_fill[isl] += 1;
        }
        core::mem::swap(contacts, &mut self.contact_scratch);
    }

    /// The islands [`Islands::build`] made.
    pub(crate) fn len(&self) -> usize {
        self.ranges.len()
    }

    /// Solves every island (its `bodies` and its share of `contacts`, as [`Islands::build`]
    /// sorted them) over a sub-step of `h` seconds with at most `iterations` sweeps each;
    /// with `parallel` and enough robots, islands on rayon's pool (each island's solve is the
    /// same on any thread). Returns what the solves did.
    pub(crate) fn solve(
        &mut self,
        contacts: &mut [Contact],
        body: &BodyConst,
        h: f64,
        iterations: u32,
        until: Convergence,
        parallel: bool,
    ) -> Solved {
        // The test's probe: each island's velocities before the solve.
        #[cfg(test)]
        let before: Option<Vec<[f64; 3]>> = self
            .residuals
            .as_ref()
            .map(|_| self.bodies.iter().map(|b| b.vel).collect());
        // Each body's velocity at a sweep's start, for a solve converged by velocity.
        let n = if until == Convergence::Velocity {
            self.bodies.len()
        } else {
            0
        };
        self.vel0.resize(n, [0.0; 3]);
        let done = if parallel && self.bodies.len() > PAR_ISLAND_ROBOTS && self.ranges.len() > 1 {
            // Islands share nothing: each is solved on whichever thread, with the same
            // result as in order.
            let mut jobs = Vec::with_capacity(self.ranges.len());
            let (mut bodies, mut contacts) = (&mut self.bodies[..], &mut *contacts);
            let mut vel0 = &mut self.vel0[..];
            for (b, c) in &self.ranges {
                let (bi, rest) = core::mem::take(&mut bodies).split_at_mut(b.len());
                bodies = rest;
                let (ci, rest) = core::mem::take(&mut contacts).split_at_mut(c.len());
                contacts = rest;
                let (vi, rest) = core::mem::take(&mut vel0).split_at_mut(b.len().min(n));
                vel0 = rest;
                jobs.push((bi, ci, vi));
            }
            let limits = self.newton_limits;
            jobs.par_iter_mut()
                .with_min_len(16)
                .map_init(NewtonScratch::default, |newton, (b, c, v)| {
                    solve_one(b, c, body, h, iterations, until, v, (newton, limits))
                })
                .reduce(Solved::default, Solved::add)
        } else {
            let mut total = Solved::default();
            for (b, c) in &self.ranges {
                total = total.add(solve_one(
                    &mut self.bodies[b.clone()],
                    &mut contacts[c.clone()],
                    body,
                    h,
                    iterations,
                    until,
                    if n == 0 {
                        &mut []
                    } else {
                        &mut self.vel0[b.clone()]
                    },
                    (&mut self.newton, self.newton_limits),
                ));
            }
            total
        };
        #[cfg(test)]
        if let (Some(out), Some(before)) = (self.residuals.as_mut(), before) {
            for (b, c) in &self.ranges {
                out.push((
                    b.len(),
                    crate::pipeline::newton::fixed_point_residual(
                        &before[b.clone()],
                        &self.bodies[b.clone()],
                        &contacts[c.clone()],
                        body,
                        h,
                    ),
                ));
            }
        }
        done
    }
}
