//! Position correction: what the linearised velocity solve left of an overlap (a turning
//! corner, a cluster that did not converge) is pushed apart by position sweeps; what they do
//! not clear stops early in the sub-step, at a time of impact.

use crate::body::{BodyConst, BodyPose};
use crate::contact::{Manifold, box_box, box_walls};
use crate::geometry::obb_overlap;
use crate::pipeline::broad_phase::Candidates;
use crate::pipeline::sensing::Bumpers;

/// The gap a position correction opens (10 µm): more than the contact skin (the solver's
/// `CONTACT_SKIN_M`), so that a correction that pushes a body a little into a neighbour (a
/// chain of contacts) still leaves the neighbour's pair clear, and a chain clears in a few
/// sweeps instead of converging on the skin forever. Far below anything a sensor (3 mm per du)
/// or a metric resolves.
const CORRECTION_GAP_M: f64 = 1e-5;

/// What the corrections move and read.
pub(crate) struct Scene<'a> {
    /// The bodies' poses after the solve (corrected in place).
    pub(crate) pose: &'a mut [BodyPose],
    /// The poses at the start of the sub-step.
    pub(crate) prev: &'a [BodyPose],
    /// The bodies' velocities (a robot stopped early loses its own).
    pub(crate) vel: &'a mut [[f64; 3]],
    /// The bumpers' faces, which take the corrections' pushes.
    pub(crate) bumpers: &'a mut Bumpers,
    /// The broad phase's candidates.
    pub(crate) cand: &'a Candidates,
    /// The bodies' size, mass and inertia.
    pub(crate) body: &'a BodyConst,
    /// Arena width, metres.
    pub(crate) w: f64,
    /// Arena height, metres.
    pub(crate) h: f64,
}

/// What one sub-step's corrections did (for the solver's statistics).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Corrected {
    /// Whether the velocity solve had left an overlap.
    pub(crate) overlapped: bool,
    /// Position sweeps run.
    pub(crate) sweeps: u64,
    /// Robots stopped early.
    pub(crate) stopped: u64,
}

/// The corrections' state across sub-steps.
#[derive(Debug, Clone)]
pub(crate) struct Corrections {
    /// Correction epoch: one per sweep, counted over the whole run.
    epoch: u64,
    /// Per robot, the epoch in which it last moved in the corrections.
    last_move: Vec<u64>,
    /// Overlaps found by the latest check.
    overlaps: Candidates,
}

impl Corrections {
    /// Nothing moved yet, for `n` robots.
    pub(crate) fn new(n: usize) -> Corrections {
        Corrections {
            epoch: 1,
            last_move: vec![0; n],
            overlaps: Candidates::default(),
        }
    }

    /// Removes the overlaps the velocity solve left among the robots `checked` (those in some
    /// contact) in a sub-step of `h` seconds: position sweeps over the overlapping pairs and
    /// walls, each pushing the bodies apart along the contact normal with rotation, weighted by
    /// mass and inertia, to `CORRECTION_GAP_M`; after every sweep the candidates of the robots
    /// it moved are tested again. What is still overlapping after `iterations` sweeps stops
    /// early: its robots move only the largest fraction (1/2, 1/4, …, 0) of this sub-step's
    /// motion at which nothing overlaps (a time of impact: no body jumps anywhere, it is only
    /// kept from going on), and so do robots whose motion ends in those robots.
    pub(crate) fn clear_overlaps(
        &mut self,
        s: &mut Scene<'_>,
        checked: &[u32],
        iterations: u32,
        h: f64,
    ) -> Corrected {
        let mut done = Corrected::default();
        self.epoch += 1;
        let mut since = self.epoch;
        for &i in checked {
            self.last_move[i as usize] = self.epoch;
        }
        for _ in 0..iterations {
            self.collect_overlaps(s, since);
            if self.overlaps.is_empty() {
                return done;
            }
            done.overlapped = true;
            done.sweeps += 1;
            self.epoch += 1;
            since = self.epoch;
            let list = core::mem::take(&mut self.overlaps);
            for &i in &list.walls {
                self.correct_wall(s, i as usize, h);
            }
            for &[i, j] in &list.pairs {
                self.correct_pair(s, i as usize, j as usize, h);
            }
            self.overlaps = list;
        }
        self.collect_overlaps(s, since);
        if !self.overlaps.is_empty() {
            done.stopped = self.stop_early(s);
        }
        done
    }

    /// The candidates with a robot moved at or after epoch `since` that overlap now, into
    /// `overlaps`.
    fn collect_overlaps(&mut self, s: &Scene<'_>, since: u64) {
        self.overlaps.clear();
        let moved = &self.last_move;
        let (hx, hy) = (s.body.hx, s.body.hy);
        for &i in &s.cand.walls {
            if moved[i as usize] >= since && s.pose[i as usize].crosses_walls(hx, hy, s.w, s.h) {
                self.overlaps.walls.push(i);
            }
        }
        let reach2 = 4.0 * s.body.radius_m * s.body.radius_m;
        for &[i, j] in &s.cand.pairs {
            if moved[i as usize] < since && moved[j as usize] < since {
                continue;
            }
            let (a, b) = (s.pose[i as usize], s.pose[j as usize]);
            if (b.x - a.x) * (b.x - a.x) + (b.y - a.y) * (b.y - a.y) >= reach2 {
                continue;
            }
            if obb_overlap(&s.body.obb(a), &s.body.obb(b), 0.0).is_some() {
                self.overlaps.pairs.push([i, j]);
            }
        }
    }

    /// Moves and turns robot `i` by a position impulse (px, py) applied at lever arm r.
    #[inline]
    fn nudge(&mut self, s: &mut Scene<'_>, i: usize, px: f64, py: f64, r: [f64; 2]) {
        let b = &mut s.pose[i];
        b.x += px * s.body.inv_m;
        b.y += py * s.body.inv_m;
        let dtheta = (r[0] * py - r[1] * px) * s.body.inv_i;
        if dtheta != 0.0 {
            let (sn, cs) = libm::sincos(dtheta);
            let (c, s) = (b.c * cs - b.s * sn, b.s * cs + b.c * sn);
            let k = 1.5 - 0.5 * (c * c + s * s);
            b.c = c * k;
            b.s = s * k;
        }
        self.last_move[i] = self.epoch;
    }

    /// One position correction of robot `i` against the walls: per wall in contact, the
    /// deepest point is pushed out to the gap, then the manifold is taken again (a corner
    /// pushed out turns the body, which moves the other corner). A push of `λ` (kg·m) in a
    /// sub-step of `h` seconds is the impulse λ / h on the bumper face it acts on.
    fn correct_wall(&mut self, s: &mut Scene<'_>, i: usize, h: f64) {
        let skin = CORRECTION_GAP_M;
        for _ in 0..4 {
            let mut deepest: Option<(Manifold, usize)> = None;
            box_walls(&s.body.obb(s.pose[i]), s.w, s.h, skin, |m| {
                for k in 0..m.count {
                    if deepest.is_none_or(|(d, dk)| m.points[k].sep < d.points[dk].sep) {
                        deepest = Some((m, k));
                    }
                }
            });
            let Some((m, k)) = deepest else {
                return;
            };
            let p = m.points[k];
            let c = p.sep - skin;
            if c >= 0.0 {
                return;
            }
            let b = s.pose[i];
            let r = [p.x - b.x, p.y - b.y];
            let rn = r[0] * m.ny - r[1] * m.nx;
            let kn = s.body.inv_m + s.body.inv_i * rn * rn;
            // The wall does not give way: the body takes the whole push, into the arena.
            let lambda = -c / kn;
            s.bumpers.push_face(i, b, m.nx, m.ny, lambda / h);
            self.nudge(s, i, -lambda * m.nx, -lambda * m.ny, r);
        }
    }

    /// One position correction of the pair (i, j): the deepest point of their manifold is
    /// pushed apart to the gap, shared by mass and inertia, then the manifold is taken again
    /// for the other point. The push is an impulse on both robots' faces, as in
    /// [`Corrections::correct_wall`].
    fn correct_pair(&mut self, s: &mut Scene<'_>, i: usize, j: usize, h: f64) {
        let skin = CORRECTION_GAP_M;
        for _ in 0..2 {
            let Some(m) = box_box(&s.body.obb(s.pose[i]), &s.body.obb(s.pose[j]), skin) else {
                return;
            };
            let k = if m.count == 2 && m.points[1].sep < m.points[0].sep {
                1
            } else {
                0
            };
            let p = m.points[k];
            let c = p.sep - skin;
            if c >= 0.0 {
                return;
            }
            let (a, b) = (s.pose[i], s.pose[j]);
            let ra = [p.x - a.x, p.y - a.y];
            let rb = [p.x - b.x, p.y - b.y];
            let rna = ra[0] * m.ny - ra[1] * m.nx;
            let rnb = rb[0] * m.ny - rb[1] * m.nx;
            let kn = 2.0 * s.body.inv_m + s.body.inv_i * (rna * rna + rnb * rnb);
            let lambda = -c / kn;
            s.bumpers.push_face(i, a, m.nx, m.ny, lambda / h);
            s.bumpers.push_face(j, b, -m.nx, -m.ny, lambda / h);
            self.nudge(s, i, -lambda * m.nx, -lambda * m.ny, ra);
            self.nudge(s, j, lambda * m.nx, lambda * m.ny, rb);
        }
    }

    /// The last resort when position sweeps leave an overlap: the robots involved (and, in
    /// turn, any robot whose end pose overlaps their stopped poses) move only a fraction of
    /// this sub-step's motion, the largest of 1, 1/2, …, 1/1024, 0 at which nothing they touch
    /// overlaps, and lose their velocity. Their start poses were free of overlaps, so this
    /// ends. Returns how many robots stopped.
    fn stop_early(&mut self, s: &mut Scene<'_>) -> u64 {
        let mut group: Vec<u32> = Vec::new();
        let mut ends: Vec<BodyPose> = Vec::new();
        let add = |i: u32, group: &mut Vec<u32>, ends: &mut Vec<BodyPose>, pose: &[BodyPose]| {
            if !group.contains(&i) {
                group.push(i);
                ends.push(pose[i as usize]);
            }
        };
        for &i in &self.overlaps.walls {
            add(i, &mut group, &mut ends, s.pose);
        }
        for &[i, j] in &self.overlaps.pairs {
            add(i, &mut group, &mut ends, s.pose);
            add(j, &mut group, &mut ends, s.pose);
        }
        loop {
            if self.back_off(s, &group, &ends) {
                break;
            }
            // At fraction 0 the group is where it started, free of overlaps among itself: what
            // still overlaps is a robot outside the group ending in it, which joins the group.
            let before = group.len();
            for &i in &self.overlaps.walls {
                add(i, &mut group, &mut ends, s.pose);
            }
            for k in 0..self.overlaps.pairs.len() {
                let [i, j] = self.overlaps.pairs[k];
                add(i, &mut group, &mut ends, s.pose);
                add(j, &mut group, &mut ends, s.pose);
            }
            if group.len() == before {
                break;
            }
        }
        for &i in &group {
            s.vel[i as usize] = [0.0; 3];
        }
        group.len() as u64
    }

    /// Moves the robots `group` a fraction 1/2, 1/4, …, 1/1024, 0 of the way from their start
    /// poses to `ends`, until nothing overlaps; whether that was reached (if not, the group is
    /// at its start poses and `overlaps` holds what still overlaps).
    fn back_off(&mut self, s: &mut Scene<'_>, group: &[u32], ends: &[BodyPose]) -> bool {
        let mut fraction = 1.0;
        for _ in 0..=11 {
            fraction = if fraction > 1.0 / 1024.0 {
                fraction * 0.5
            } else {
                0.0
            };
            self.epoch += 1;
            for (k, &i) in group.iter().enumerate() {
                let i = i as usize;
                s.pose[i] = interpolate(s.prev[i], ends[k], fraction);
                self.last_move[i] = self.epoch;
            }
            self.collect_overlaps(s, self.epoch);
            if self.overlaps.is_empty() {
                return true;
            }
            if fraction == 0.0 {
                break;
            }
        }
        false
    }
}

/// The pose a fraction `f` of the way from `a` to `b` (position linearly, heading by the
/// shorter rotation).
fn interpolate(a: BodyPose, b: BodyPose, f: f64) -> BodyPose {
    let dtheta = libm::atan2(a.c * b.s - a.s * b.c, a.c * b.c + a.s * b.s);
    let (sn, cs) = libm::sincos(f * dtheta);
    BodyPose {
        x: a.x + f * (b.x - a.x),
        y: a.y + f * (b.y - a.y),
        c: a.c * cs - a.s * sn,
        s: a.s * cs + a.c * sn,
    }
}
