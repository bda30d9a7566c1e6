//! The warm start: a solve starts from the impulses the previous sub-step's solve ended with,
//! for the same contacts and wheels, so that a steady push converges in a sweep or two.

use rayon::prelude::*;

use crate::motor::MODE_DRIVE;
use crate::pipeline::drive::Motion;
use crate::pipeline::par::PAR_CHUNK;
use crate::pipeline::solver::{Contact, WALL};

/// The share of the previous sub-step's impulses a solve starts from: all of them, so that a
/// steady push converges in a sweep or two. (A wheel that is braked or coasting starts from
/// nothing instead: a braked robot held against a wall is statically indeterminate, and a full
/// warm start would keep a push that nothing sustains any more.)
const WARM_START: f64 = 1.0;

/// A solved contact's identity, point count and (normal, friction) impulses per point.
type Kept = ((u32, u32, u8), u8, [[f64; 2]; 2]);

/// What the previous solve left for the next.
#[derive(Debug, Clone)]
pub(crate) struct WarmStart {
    /// The solved contacts' impulses of the previous sub-step, sorted by contact identity.
    kept: Vec<Kept>,
    /// Per robot, the sub-step in which it was last solved (its wheel impulses warm-start the
    /// next solve only if that was the previous sub-step).
    solved_at: Vec<u64>,
}

impl WarmStart {
    /// Nothing kept yet, for `n` robots.
    pub(crate) fn new(n: usize) -> WarmStart {
        WarmStart {
            kept: Vec::new(),
            solved_at: vec![u64::MAX; n],
        }
    }

    /// Starts sub-step number `substep`'s solve from the kept impulses: each contact whose
    /// robots' motors drive, found again with as many points, takes its kept impulses; each
    /// robot of `active` solved in the previous sub-step keeps the wheel impulses of its
    /// driving wheels in `wheel_imp` (the others start from nothing), and is marked solved now.
    pub(crate) fn apply(
        &mut self,
        contacts: &mut [Contact],
        active: &[u32],
        motion: &[Motion],
        wheel_imp: &mut [[f64; 4]],
        substep: u64,
        parallel: bool,
    ) {
        let driven = |i: u32| {
            i != WALL
                && motion[i as usize]
                    .mode
                    .iter()
                    .zip(motion[i as usize].target)
                    .any(|(&m, t)| m == MODE_DRIVE && t != 0.0)
        };
        let kept = &self.kept;
        let warm = |ct: &mut Contact| {
            // A contact between robots whose motors do not drive starts from nothing (a
            // braked robot against a wall is statically indeterminate, see WARM_START).
            if !driven(ct.a) && !driven(ct.b) {
                return;
            }
            if let Ok(k) = kept.binary_search_by(|w| w.0.cmp(&ct.id()))
                && kept[k].1 == ct.count
            {
                for (p, [ln, lt]) in ct.pts.iter_mut().zip(kept[k].2) {
                    p.ln = WARM_START * ln;
                    p.lt = WARM_START * lt;
                }
            }
        };
        // Each contact looks up its own impulses: on any thread, the same result.
        if parallel && contacts.len() > PAR_CHUNK {
            contacts
                .par_iter_mut()
                .with_min_len(PAR_CHUNK / 4)
                .for_each(warm);
        } else {
            contacts.iter_mut().for_each(warm);
        }
        for &i in active {
            let i = i as usize;
            if self.solved_at[i] == substep.wrapping_sub(1) {
                for (w, x) in wheel_imp[i].iter_mut().enumerate() {
                    let driven =
                        motion[i].mode[w / 2] == MODE_DRIVE && motion[i].target[w / 2] != 0.0;
                    *x *= if driven { WARM_START } else { 0.0 };
                }
            } else {
                wheel_imp[i] = [0.0; 4];
            }
            self.solved_at[i] = substep;
        }
    }

    /// Keeps the impulses of this sub-step's `contacts` for the next.
    pub(crate) fn keep(&mut self, contacts: &[Contact]) {
        self.kept.clear();
        self.kept.extend(contacts.iter().map(|ct| {
            (
                ct.id(),
                ct.count,
                [[ct.pts[0].ln, ct.pts[0].lt], [ct.pts[1].ln, ct.pts[1].lt]],
            )
        }));
        self.kept.sort_unstable_by_key(|w| w.0);
    }
}
