//! Where the robots start: seeded placement in the corridor (on the centre line, uniform
//! spacings) and in an open arena (rejection sampling with a bounded number of attempts), and
//! the seeded streams the world draws from.

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use seeding::Purpose;

use crate::arena::Arena;
use crate::body::BodyPose;
use crate::error::WorldError;
use crate::geometry::{Obb, obb_overlap};
use crate::params::WorldParams;

/// The generator for one purpose and one index (robot index, or 0 for world-wide purposes):
/// the project's one derivation, `seeding::derive(seed, index, purpose)`.
pub(crate) fn stream_rng(seed: u64, purpose: Purpose, index: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seeding::derive(seed, index, purpose))
}

/// A uniform draw in [0, 1).
pub(crate) fn unit(rng: &mut Pcg64) -> f64 {
    rng.random::<f64>()
}

/// Corridor placement: bodies on the centre line facing +x or −x at random, separated by the
/// clearance plus a uniformly random share of the free length (uniform spacings).
pub(crate) fn place_corridor(
    arena: &Arena,
    params: &WorldParams,
    n: usize,
    seed: u64,
) -> Result<Vec<BodyPose>, WorldError> {
    let len = params.body_length_m;
    let clr = params.placement_clearance_m;
    let (w, h) = (arena.width_m(), arena.height_m());
    if params.body_width_m > h {
        return Err(WorldError::Parameter {
            name: "body_width_m",
            value: params.body_width_m,
            valid: "a body no wider than the corridor",
        });
    }
    let free = w - n as f64 * len - (n as f64 + 1.0) * clr;
    if free < 0.0 {
        let max_fit = ((w - clr) / (len + clr)).floor().max(0.0) as usize;
        return Err(WorldError::TooManyRobots {
            requested: n,
            max_fit,
            arena: arena.describe(),
            clearance_m: clr,
        });
    }
    let mut rng = stream_rng(seed, Purpose::Placement, 0);
    let mut cuts: Vec<f64> = (0..n).map(|_| unit(&mut rng) * free).collect();
    cuts.sort_by(f64::total_cmp);
    let mut poses = Vec::with_capacity(n);
    let mut edge = 0.0; // right edge of the previous body (or the wall)
    let mut last_cut = 0.0;
    for &cut in &cuts {
        let gap = clr + (cut - last_cut);
        last_cut = cut;
        let x = edge + gap + 0.5 * len;
        edge = x + 0.5 * len;
        let backward = unit(&mut rng) < 0.5;
        let (c, s) = if backward { (-1.0, 0.0) } else { (1.0, 0.0) };
        poses.push(BodyPose {
            x,
            y: 0.5 * h,
            c,
            s,
        });
    }
    Ok(poses)
}

/// Open-arena placement: rejection sampling of uniform headings and positions with the
/// clearance to walls and bodies; a bounded number of attempts.
pub(crate) fn place_open(
    arena: &Arena,
    params: &WorldParams,
    n: usize,
    seed: u64,
) -> Result<Vec<BodyPose>, WorldError> {
    let (w, h) = (arena.width_m(), arena.height_m());
    let (hx, hy) = (0.5 * params.body_length_m, 0.5 * params.body_width_m);
    let clr = params.placement_clearance_m;
    // Bodies inflated by half the clearance are disjoint and lie inside the arena shrunk by
    // half the clearance on each side: an upper bound on how many fit.
    let usable = ((w - clr).max(0.0)) * ((h - clr).max(0.0));
    let cell_area = (params.body_length_m + clr) * (params.body_width_m + clr);
    let max_fit = (usable / cell_area).floor() as usize;
    if n > max_fit {
        return Err(WorldError::TooManyRobots {
            requested: n,
            max_fit,
            arena: arena.describe(),
            clearance_m: clr,
        });
    }
    let reach = 2.0 * libm::hypot(hx, hy) + clr;
    let mut grid_cells: Vec<Vec<u32>>;
    let cell_m = reach.max((w * h / (n.max(1) as f64)).sqrt());
    let nx = ((w / cell_m).ceil() as usize).max(1);
    let ny = ((h / cell_m).ceil() as usize).max(1);
    grid_cells = vec![Vec::new(); nx * ny];
    let cell_ix = |x: f64, y: f64| -> (usize, usize) {
        let cx = ((x / cell_m).floor().max(0.0) as usize).min(nx - 1);
        let cy = ((y / cell_m).floor().max(0.0) as usize).min(ny - 1);
        (cx, cy)
    };
    let max_attempts: u64 = 1000 * n as u64 + 10_000;
    let mut attempts: u64 = 0;
    let mut rng = stream_rng(seed, Purpose::Placement, 0);
    let mut poses: Vec<BodyPose> = Vec::with_capacity(n);
    while poses.len() < n {
        if attempts >= max_attempts {
            return Err(WorldError::PlacementFailed {
                placed: poses.len(),
                requested: n,
                attempts,
                max_fit,
                arena: arena.describe(),
                clearance_m: clr,
            });
        }
        attempts += 1;
        let theta = core::f64::consts::PI * (2.0 * unit(&mut rng) - 1.0);
        let (s, c) = libm::sincos(theta);
        let ex = hx * c.abs() + hy * s.abs() + clr;
        let ey = hx * s.abs() + hy * c.abs() + clr;
        let ux = unit(&mut rng);
        let uy = unit(&mut rng);
        if 2.0 * ex > w || 2.0 * ey > h {
            continue;
        }
        let x = ex + ux * (w - 2.0 * ex);
        let y = ey + uy * (h - 2.0 * ey);
        let a = Obb { x, y, c, s, hx, hy };
        let (cx, cy) = cell_ix(x, y);
        let mut free = true;
        'scan: for row in cy.saturating_sub(1)..=(cy + 1).min(ny - 1) {
            for col in cx.saturating_sub(1)..=(cx + 1).min(nx - 1) {
                for &j in &grid_cells[row * nx + col] {
                    let b = poses[j as usize].obb(hx, hy);
                    if obb_overlap(&a, &b, -clr).is_some() {
                        free = false;
                        break 'scan;
                    }
                }
            }
        }
        if free {
            grid_cells[cy * nx + cx].push(poses.len() as u32);
            poses.push(BodyPose { x, y, c, s });
        }
    }
    Ok(poses)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arena::ArenaKind;
    use crate::params::PLACEMENT_CLEARANCE_M;

    /// The placement the world makes for `arena`'s kind.
    fn place(
        arena: &Arena,
        params: &WorldParams,
        n: usize,
        seed: u64,
    ) -> Result<Vec<BodyPose>, WorldError> {
        match arena.kind() {
            ArenaKind::Corridor => place_corridor(arena, params, n, seed),
            ArenaKind::Open => place_open(arena, params, n, seed),
        }
    }

    /// Every body keeps `clr` from the walls (in the corridor: along it, and inside it across)
    /// and from every other body.
    fn assert_clearance(arena: &Arena, params: &WorldParams, poses: &[BodyPose], clr: f64) {
        let (hx, hy) = (0.5 * params.body_length_m, 0.5 * params.body_width_m);
        let (w, h) = (arena.width_m(), arena.height_m());
        for (i, b) in poses.iter().enumerate() {
            let (ex, ey) = b.obb(hx, hy).aabb_half_extents();
            assert!(b.x - ex >= clr - 1e-12 && b.x + ex <= w - clr + 1e-12);
            if arena.kind() == ArenaKind::Open {
                assert!(b.y - ey >= clr - 1e-12 && b.y + ey <= h - clr + 1e-12);
            } else {
                assert!(!b.crosses_walls(hx, hy, w, h));
            }
            for (j, c) in poses.iter().enumerate().skip(i + 1) {
                assert!(
                    obb_overlap(&b.obb(hx, hy), &c.obb(hx, hy), -clr + 1e-12).is_none(),
                    "{i} {j}"
                );
            }
        }
    }

    #[test]
    fn placement_is_non_overlapping_and_deterministic() {
        let params = WorldParams::with_clock(crate::params::TEST_CLOCK_HZ);
        for (arena, n) in [
            (Arena::square(), 3),
            (Arena::square(), 15),
            (Arena::scaled_square(300).unwrap(), 300),
            (Arena::paper_corridor(), 3),
            (Arena::paper_corridor(), 8),
        ] {
            let a = place(&arena, &params, n, 5).unwrap();
            let b = place(&arena, &params, n, 5).unwrap();
            let c = place(&arena, &params, n, 6).unwrap();
            assert_eq!(a, b);
            assert_ne!(a, c);
            assert_eq!(a.len(), n);
            assert_clearance(&arena, &params, &a, PLACEMENT_CLEARANCE_M);
            if arena.kind() == ArenaKind::Corridor {
                for p in &a {
                    assert_eq!(p.y, 0.11);
                    assert!(p.s == 0.0 && p.c.abs() == 1.0);
                }
            }
        }
        // Headings in the corridor are both ways across seeds.
        let mut dirs = std::collections::BTreeSet::new();
        for seed in 0..20 {
            for p in place(&Arena::paper_corridor(), &params, 3, seed).unwrap() {
                dirs.insert(p.c as i64);
            }
        }
        assert_eq!(dirs.len(), 2);
    }

    #[test]
    fn crowded_placement_is_an_error_that_says_how_many_fit() {
        let params = WorldParams::with_clock(crate::params::TEST_CLOCK_HZ);
        // Corridor: 3.0 m holds floor((3.0 − 0.05) / 0.28) = 10 robots at 5 cm.
        assert!(place(&Arena::paper_corridor(), &params, 10, 1).is_ok());
        let e = place(&Arena::paper_corridor(), &params, 11, 1).unwrap_err();
        assert!(
            matches!(
                e,
                WorldError::TooManyRobots {
                    requested: 11,
                    max_fit: 10,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("at most 10 fit"), "{e}");
        // Square: the area bound is (1.75)² / (0.28 · 0.23) = 47.
        let e = place(&Arena::square(), &params, 48, 1).unwrap_err();
        assert!(
            matches!(e, WorldError::TooManyRobots { max_fit: 47, .. }),
            "{e}"
        );
        // Below the bound but beyond what random placement reaches: bounded attempts, then an
        // error.
        let e = place(&Arena::square(), &params, 46, 1).unwrap_err();
        assert!(
            matches!(
                e,
                WorldError::PlacementFailed {
                    requested: 46,
                    attempts: 56_000,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("after 56000 random attempts"), "{e}");
        // A body wider than the corridor.
        let wide = WorldParams {
            body_width_m: 0.25,
            ..WorldParams::with_clock(crate::params::TEST_CLOCK_HZ)
        };
        assert!(place(&Arena::paper_corridor(), &wide, 1, 1).is_err());
        // Zero robots: nothing placed.
        assert!(place(&Arena::square(), &params, 0, 1).unwrap().is_empty());
    }
}
