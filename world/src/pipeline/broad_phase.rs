//! The broad phase: a uniform grid of the robots' centres, and from it the contact candidates
//! (pairs whose bounding circles are within the margin, robots within the margin of a wall).
//! Like a Verlet list, grid and candidates are kept until some robot has drifted half the
//! margin less the speculative distance from where it was filed, then rebuilt, so no contact
//! can be missed in between.

use rayon::prelude::*;

use crate::body::BodyPose;
use crate::grid::Grid;
use crate::pipeline::par::PAR_CHUNK;

/// Smallest broad-phase margin (a Verlet skin): pairs of bodies whose bounding circles are
/// closer than the margin, and bodies closer than it to a wall, are contact candidates; the
/// grid and the candidate lists are kept until some robot has moved half the margin less the
/// speculative contact distance since they were built (our choice: 200 mm, about 60 sub-steps
/// of 10 ms at 0.15 m/s; larger when fast robots and long sub-steps need it).
pub const BROAD_PHASE_MARGIN_M: f64 = 0.2;

/// Robot pairs (lower index first) and robots near a wall.
#[derive(Debug, Clone, Default)]
pub(crate) struct Candidates {
    /// Pairs `[i, j]`, `i < j`.
    pub(crate) pairs: Vec<[u32; 2]>,
    /// Robots near a wall.
    pub(crate) walls: Vec<u32>,
}

impl Candidates {
    /// Whether there are neither pairs nor walls.
    pub(crate) fn is_empty(&self) -> bool {
        self.pairs.is_empty() && self.walls.is_empty()
    }

    /// Forgets every pair and wall, keeping the buffers.
    pub(crate) fn clear(&mut self) {
        self.pairs.clear();
        self.walls.clear();
    }
}

/// The grid, the candidates found from it and the margins that keep them valid.
#[derive(Debug, Clone)]
pub(crate) struct BroadPhase {
    grid: Grid,
    cand: Candidates,
    /// Broad-phase margin in use, metres.
    margin_m: f64,
    /// Drift from the filed position that triggers a rebuild, metres.
    drift_limit_m: f64,
    /// Per chunk of robots, its candidates (the parallel rebuild's scratch).
    chunk_cands: Vec<Candidates>,
}

impl BroadPhase {
    /// An empty broad phase for `n` robots of bounding radius `radius_m` in a `w` × `h` arena,
    /// whose longest sub-step has the speculative distance `spec_max_m`: the margin is at least
    /// [`BROAD_PHASE_MARGIN_M`] and four speculative distances, so that it holds the
    /// speculative distance with room for drift.
    pub(crate) fn new(w: f64, h: f64, radius_m: f64, spec_max_m: f64, n: usize) -> BroadPhase {
        let margin_m = BROAD_PHASE_MARGIN_M.max(4.0 * spec_max_m);
        let drift_limit_m = 0.5 * (margin_m - spec_max_m);
        BroadPhase {
            grid: Grid::new(w, h, 2.0 * radius_m + margin_m, n),
            cand: Candidates::default(),
            margin_m,
            drift_limit_m,
            chunk_cands: vec![Candidates::default(); n.div_ceil(PAR_CHUNK)],
        }
    }

    /// The grid as last built.
    pub(crate) fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The candidates as last built.
    pub(crate) fn candidates(&self) -> &Candidates {
        &self.cand
    }

    /// How far a robot may drift from where it was filed before a rebuild, metres.
    pub(crate) fn drift_limit_m(&self) -> f64 {
        self.drift_limit_m
    }

    /// Whether some robot has drifted more than the limit from where it was filed.
    pub(crate) fn is_stale(&self, pose: &[BodyPose]) -> bool {
        let lim2 = self.drift_limit_m * self.drift_limit_m;
        pose.iter()
            .zip(&self.grid.build_xy)
            .any(|(b, [x0, y0])| (b.x - x0) * (b.x - x0) + (b.y - y0) * (b.y - y0) > lim2)
    }

    /// Rebuilds the grid and the candidate lists from the poses of robots of bounding radius
    /// `radius_m` in a `w` × `h` arena; with `parallel`, in chunks on rayon's pool, merged in
    /// index order.
    pub(crate) fn rebuild(
        &mut self,
        pose: &[BodyPose],
        radius_m: f64,
        w: f64,
        h: f64,
        parallel: bool,
    ) {
        self.grid.build(pose.iter().map(|b| (b.x, b.y)));
        let reach = 2.0 * radius_m + self.margin_m;
        let ctx = CandidateCtx {
            pose,
            grid: &self.grid,
            reach2: reach * reach,
            wall_reach: radius_m + self.margin_m,
            w,
            h,
        };
        self.cand.clear();
        if parallel && pose.len() > PAR_CHUNK {
            let n_chunks = pose.len().div_ceil(PAR_CHUNK);
            if self.chunk_cands.len() < n_chunks {
                self.chunk_cands.resize_with(n_chunks, Candidates::default);
            }
            self.chunk_cands[..n_chunks]
                .par_iter_mut()
                .enumerate()
                .for_each(|(k, out)| {
                    out.clear();
                    let lo = k * PAR_CHUNK;
                    let hi = (lo + PAR_CHUNK).min(ctx.pose.len());
                    ctx.find(lo, hi, out);
                });
            for c in &self.chunk_cands[..n_chunks] {
                self.cand.pairs.extend_from_slice(&c.pairs);
                self.cand.walls.extend_from_slice(&c.walls);
            }
        } else {
            ctx.find(0, pose.len(), &mut self.cand);
        }
    }
}

/// What the candidate search reads.
struct CandidateCtx<'a> {
    pose: &'a [BodyPose],
    grid: &'a Grid,
    reach2: f64,
    /// A robot whose centre is nearer a wall than this is a wall candidate.
    wall_reach: f64,
    w: f64,
    h: f64,
}

impl CandidateCtx<'_> {
    /// Candidates for robots `lo..hi`: those whose bounding circle is within the margin of a
    /// wall, and pairs (i, j > i) whose centres are within two bounding radii plus the margin.
    fn find(&self, lo: usize, hi: usize, out: &mut Candidates) {
        let nx = self.grid.nx();
        let ny = self.grid.ny();
        for i in lo..hi {
            let b = self.pose[i];
            // By the bounding circle, so that turning cannot bring a body to a wall unseen.
            let e = self.wall_reach;
            if b.x - e < 0.0 || b.x + e > self.w || b.y - e < 0.0 || b.y + e > self.h {
                out.walls.push(i as u32);
            }
            let (cx, cy) = self.grid.cell_of(i);
            let (c0, c1) = (cx.saturating_sub(1), (cx + 1).min(nx - 1));
            let (r0, r1) = (cy.saturating_sub(1), (cy + 1).min(ny - 1));
            for row in r0..=r1 {
                for col in c0..=c1 {
                    for &j in self.grid.cell(col, row) {
                        if (j as usize) <= i {
                            continue;
                        }
                        let q = self.pose[j as usize];
                        let (dx, dy) = (q.x - b.x, q.y - b.y);
                        if dx * dx + dy * dy < self.reach2 {
                            out.pairs.push([i as u32, j]);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::body::BodyConst;
    use crate::geometry::obb_overlap;
    use crate::params::WorldParams;
    use crate::pipeline::narrow_phase::speculative_m;
    use core::f64::consts::PI;
    use proptest::prelude::*;

    /// A broad phase built over arbitrary (possibly overlapping) poses, given as fractions
    /// (x, y) of a `side` × 0.7·`side` arena and a heading, with the margins of `params`.
    pub(crate) fn scene(
        params: &WorldParams,
        side: f64,
        xs: &[(f64, f64, f64)],
    ) -> (Vec<BodyPose>, BodyConst, BroadPhase) {
        let body = params.body();
        let (w, h) = (side, side * 0.7);
        let pose: Vec<BodyPose> = xs
            .iter()
            .map(|&(fx, fy, th)| {
                let (s, c) = libm::sincos(th);
                BodyPose {
                    x: fx * w,
                    y: fy * h,
                    c,
                    s,
                }
            })
            .collect();
        let states = (params.max_substep_s * params.clock_hz as f64).round();
        let spec_max = speculative_m(params, body.radius_m, states / params.clock_hz as f64);
        let mut broad = BroadPhase::new(w, h, body.radius_m, spec_max, pose.len());
        broad.rebuild(&pose, body.radius_m, w, h, false);
        (pose, body, broad)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Overlapping pairs found through the grid equal brute force, and every robot that
        /// reaches past a wall is a wall candidate.
        #[test]
        fn broad_phase_equals_brute_force(
            side in 1.0f64..8.0,
            xs in proptest::collection::vec((0.0f64..1.0, 0.0f64..1.0, -PI..PI), 1..80),
        ) {
            let n = xs.len();
            let (pose, body, broad) = scene(&WorldParams::with_clock(crate::params::TEST_CLOCK_HZ), side, &xs);
            let obb = |i: usize| body.obb(pose[i]);
            let mut via_grid = std::collections::BTreeSet::new();
            for &[i, j] in &broad.candidates().pairs {
                if obb_overlap(&obb(i as usize), &obb(j as usize), 0.0).is_some() {
                    via_grid.insert((i as usize, j as usize));
                }
            }
            let mut brute = std::collections::BTreeSet::new();
            for (i, b) in pose.iter().enumerate() {
                for j in i + 1..n {
                    if obb_overlap(&obb(i), &obb(j), 0.0).is_some() {
                        brute.insert((i, j));
                    }
                }
                if b.crosses_walls(body.hx, body.hy, side, side * 0.7) {
                    prop_assert!(broad.candidates().walls.contains(&(i as u32)));
                }
            }
            prop_assert_eq!(via_grid, brute);
        }
    }

    /// The parallel rebuild, chunk by chunk, gives the serial one's candidates in the same
    /// order.
    #[test]
    fn parallel_rebuild_equals_serial() {
        let xs: Vec<(f64, f64, f64)> = (0..3 * PAR_CHUNK + 7)
            .map(|k| {
                let f = k as f64;
                ((f * 0.618_034).fract(), (f * 0.414_214).fract(), f)
            })
            .collect();
        let (pose, body, serial) = scene(
            &WorldParams::with_clock(crate::params::TEST_CLOCK_HZ),
            12.0,
            &xs,
        );
        let mut parallel = serial.clone();
        parallel.rebuild(&pose, body.radius_m, 12.0, 8.4, true);
        assert!(!serial.candidates().pairs.is_empty());
        assert_eq!(serial.candidates().pairs, parallel.candidates().pairs);
        assert_eq!(serial.candidates().walls, parallel.candidates().walls);
    }
}
