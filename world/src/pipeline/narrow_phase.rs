//! The narrow phase: the sub-step's contacts from the broad phase's candidates (every wall or
//! pair whose manifold has a point within the speculative distance), which of them bind, and
//! so which robots are solved and which follow their wheels.

use rayon::prelude::*;

use crate::body::{BodyConst, BodyPose};
use crate::contact::{box_box, box_walls};
use crate::params::WorldParams;
use crate::pipeline::broad_phase::Candidates;
use crate::pipeline::par::PAR_CHUNK;
use crate::pipeline::solver::{Contact, WALL};

/// In a binding contact this sub-step (or in contact with such a robot): solved, not moved
/// freely.
pub(crate) const ACTIVE: u8 = 1;
/// Listed in [`NarrowPhase::active`].
const LISTED: u8 = 2;
/// In some contact (binding or not): checked for overlap after the move.
const CHECK: u8 = 4;
/// A contact binds when the robots' own wheels would bring a point to within this of touching
/// (0.1 mm: the linear estimate misses the chord of a turning corner's arc by at most about
/// R·(ω·h)²/2 ≈ 13 µm at 20 ms).
const BIND_MARGIN_M: f64 = 1e-4;

/// The largest distance two bodies' points can close in a sub-step of `h` seconds under
/// their own wheels (each point of a body of bounding radius `radius_m` moves at most
/// `v_max·(1 + 2R/track)`), with a margin of 25 % for pushes: contacts nearer than this are
/// handed to the solver.
pub(crate) fn speculative_m(params: &WorldParams, radius_m: f64, h: f64) -> f64 {
    let vmax = params.top_speed_m_per_s * (1.0 + params.motor_gain_spread);
    2.5 * vmax * (1.0 + 2.0 * radius_m / params.wheel_track_m) * h
}

/// The sub-step's contacts and the robots they concern. The later stages work on them in
/// place: the islands reorder `contacts` and `active`, the solver fills the contacts'
/// impulses.
#[derive(Debug, Clone)]
pub(crate) struct NarrowPhase {
    /// The sub-step's contacts, walls first, then pairs, in candidate order (until the islands
    /// reorder them).
    pub(crate) contacts: Vec<Contact>,
    /// Per chunk of candidates, its contacts (the parallel search's scratch).
    chunk_contacts: Vec<Vec<Contact>>,
    /// The robots solved this sub-step, in index order (until the islands reorder them).
    pub(crate) active: Vec<u32>,
    /// The robots in some contact this sub-step (solved or not), in index order.
    pub(crate) checked: Vec<u32>,
    /// Per robot, [`ACTIVE`] and the search's own marks; all zero between sub-steps.
    pub(crate) flags: Vec<u8>,
}

/// Puts `list`, the robots whose `flags` have `bit` (each once), in index order: sorted when
/// fewer than one robot in 16 is listed, otherwise read off the flags in one pass over the
/// robots (the same list either way; the cut-off is a choice, not a measured crossover).
fn in_index_order(list: &mut Vec<u32>, flags: &[u8], bit: u8) {
    if list.len() * 16 < flags.len() {
        list.sort_unstable();
    } else {
        list.clear();
        list.extend(
            flags
                .iter()
                .enumerate()
                .filter(|&(_, &f)| f & bit != 0)
                .map(|(i, _)| i as u32),
        );
    }
}

/// What the contact search reads.
pub(crate) struct Probe<'a> {
    pose: &'a [BodyPose],
    /// Squared distance between centres beyond which bodies cannot come within `spec`.
    reach2: f64,
    w: f64,
    h: f64,
    spec: f64,
    body: &'a BodyConst,
}

impl<'a> Probe<'a> {
    /// The search for contacts within `spec` metres among bodies at `pose` in a `w` × `h`
    /// arena.
    pub(crate) fn new(
        pose: &'a [BodyPose],
        body: &'a BodyConst,
        w: f64,
        h: f64,
        spec: f64,
    ) -> Probe<'a> {
        Probe {
            pose,
            reach2: (2.0 * body.radius_m + spec) * (2.0 * body.radius_m + spec),
            w,
            h,
            spec,
            body,
        }
    }

    /// Appends the wall contacts of the robots `walls`, in order.
    fn walls(&self, walls: &[u32], out: &mut Vec<Contact>) {
        for &i in walls {
            let b = self.pose[i as usize];
            let (ex, ey) = self.body.obb(b).aabb_half_extents();
            let near = b.x - ex <= self.spec
                || b.x + ex >= self.w - self.spec
                || b.y - ey <= self.spec
                || b.y + ey >= self.h - self.spec;
            if !near {
                continue;
            }
            box_walls(&self.body.obb(b), self.w, self.h, self.spec, |m| {
                out.push(Contact::new(i, WALL, &m, (b.x, b.y), (0.0, 0.0), self.body));
            });
        }
    }

    /// Appends the contacts of the candidate pairs, in order.
    fn pairs(&self, pairs: &[[u32; 2]], out: &mut Vec<Contact>) {
        for &[i, j] in pairs {
            let (a, b) = (self.pose[i as usize], self.pose[j as usize]);
            let (dx, dy) = (b.x - a.x, b.y - a.y);
            if dx * dx + dy * dy >= self.reach2 {
                continue;
            }
            if let Some(m) = box_box(&self.body.obb(a), &self.body.obb(b), self.spec) {
                out.push(Contact::new(i, j, &m, (a.x, a.y), (b.x, b.y), self.body));
            }
        }
    }
}

impl NarrowPhase {
    /// An empty narrow phase for `n` robots.
    pub(crate) fn new(n: usize) -> NarrowPhase {
        NarrowPhase {
            contacts: Vec::new(),
            chunk_contacts: Vec::new(),
            active: Vec::new(),
            checked: Vec::new(),
            flags: vec![0; n],
        }
    }

    /// The contacts of the sub-step: every candidate wall or pair whose manifold has a point
    /// within the probe's speculative distance, in the candidates' order (walls first, then
    /// pairs); then which bind (see [`NarrowPhase::bind`]). With `parallel`, the search runs in
    /// chunks on rayon's pool, merged in order.
    pub(crate) fn find(
        &mut self,
        probe: &Probe<'_>,
        cand: &Candidates,
        wmean: &[[f64; 2]],
        inv_track: f64,
        h: f64,
        parallel: bool,
    ) {
        self.contacts.clear();
        let n_pairs = cand.pairs.len();
        let n_walls = cand.walls.len();
        if parallel && n_pairs + n_walls > PAR_CHUNK {
            let chunks = n_pairs.max(n_walls).div_ceil(PAR_CHUNK);
            if self.chunk_contacts.len() < 2 * chunks {
                self.chunk_contacts.resize_with(2 * chunks, Vec::new);
            }
            self.chunk_contacts[..2 * chunks]
                .par_iter_mut()
                .enumerate()
                .for_each(|(k, out)| {
                    out.clear();
                    let lo = (k / 2) * PAR_CHUNK;
                    if k % 2 == 0 {
                        probe.walls(
                            &cand.walls[lo.min(n_walls)..(lo + PAR_CHUNK).min(n_walls)],
                            out,
                        );
                    } else {
                        probe.pairs(
                            &cand.pairs[lo.min(n_pairs)..(lo + PAR_CHUNK).min(n_pairs)],
                            out,
                        );
                    }
                });
            for c in self.chunk_contacts[..2 * chunks].iter().step_by(2) {
                self.contacts.extend_from_slice(c);
            }
            for c in self.chunk_contacts[1..2 * chunks].iter().step_by(2) {
                self.contacts.extend_from_slice(c);
            }
        } else {
            probe.walls(&cand.walls, &mut self.contacts);
            probe.pairs(&cand.pairs, &mut self.contacts);
        }
        self.bind(probe.pose, wmean, inv_track, h);
    }

    /// Which contacts bind: those that the robots' own wheels would close (to within
    /// `BIND_MARGIN_M`, which covers the chord of a turning corner's arc). A robot in a binding
    /// contact is solved, and so, in turn, is every robot in a contact with a solved one
    /// (its motion is no longer its wheels'); the rest follow their wheels exactly, and
    /// their contacts are checked for overlap after the move. Keeps the contacts of solved
    /// robots only, and lists the solved robots and the checked ones in index order.
    fn bind(&mut self, pose: &[BodyPose], wmean: &[[f64; 2]], inv_track: f64, h: f64) {
        self.active.clear();
        self.checked.clear();
        let twist = |i: usize| -> [f64; 3] {
            let w = wmean[i];
            let v = 0.5 * (w[0] + w[1]);
            let p = pose[i];
            [v * p.c, v * p.s, (w[1] - w[0]) * inv_track]
        };
        for ct in &self.contacts {
            let a = ct.a as usize;
            let wall = ct.b == WALL;
            let ua = twist(a);
            let ub = if wall { [0.0; 3] } else { twist(ct.b as usize) };
            let binds = ct.pts[..usize::from(ct.count)].iter().any(|p| {
                let rvx = (ub[0] - ub[2] * p.rb[1]) - (ua[0] - ua[2] * p.ra[1]);
                let rvy = (ub[1] + ub[2] * p.rb[0]) - (ua[1] + ua[2] * p.ra[0]);
                p.sep + (rvx * ct.nx + rvy * ct.ny) * h < BIND_MARGIN_M
            });
            for i in [ct.a, ct.b] {
                if i != WALL && self.flags[i as usize] & CHECK == 0 {
                    self.flags[i as usize] |= CHECK;
                    self.checked.push(i);
                }
            }
            if binds {
                for i in [ct.a, ct.b] {
                    if i != WALL {
                        self.flags[i as usize] |= ACTIVE;
                    }
                }
            }
        }
        loop {
            let mut grew = false;
            for ct in &self.contacts {
                if ct.b == WALL {
                    continue;
                }
                let (fa, fb) = (self.flags[ct.a as usize], self.flags[ct.b as usize]);
                if (fa ^ fb) & ACTIVE != 0 {
                    self.flags[ct.a as usize] |= ACTIVE;
                    self.flags[ct.b as usize] |= ACTIVE;
                    grew = true;
                }
            }
            if !grew {
                break;
            }
        }
        let flags = &self.flags;
        self.contacts
            .retain(|ct| flags[ct.a as usize] & ACTIVE != 0);
        for ct in &self.contacts {
            for i in [ct.a, ct.b] {
                if i != WALL && self.flags[i as usize] & LISTED == 0 {
                    self.flags[i as usize] |= LISTED;
                    self.active.push(i);
                }
            }
        }
        in_index_order(&mut self.active, &self.flags, LISTED);
        in_index_order(&mut self.checked, &self.flags, CHECK);
    }

    /// Clears the flags of the checked robots (the only ones set) for the next sub-step.
    pub(crate) fn clear_flags(&mut self) {
        for &i in &self.checked {
            self.flags[i as usize] = 0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Read off the flags or sorted, the listed robots come out the same, in index order.
    #[test]
    fn listed_robots_come_out_in_index_order_either_way() {
        // Pushed in the order a contact list would meet them.
        let pushed: Vec<u32> = vec![40, 3, 17, 63, 0, 22, 5];
        let mut sorted = pushed.clone();
        sorted.sort_unstable();
        // 7 of 256 robots: sorted; 7 of 64: read off the flags.
        for n in [256, 64] {
            let mut flags = vec![0u8; n];
            for &i in &pushed {
                flags[i as usize] |= CHECK;
            }
            flags[9] |= ACTIVE; // another bit: not listed
            let mut list = pushed.clone();
            in_index_order(&mut list, &flags, CHECK);
            assert_eq!(list, sorted, "{n} robots");
        }
    }
}
