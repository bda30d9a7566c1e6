//! Contact manifolds: where two boxes (or a box and a wall) touch or are about to, with the
//! normal and a signed separation per contact point.
//!
//! The box–box manifold is the reference-face clipping of Box2D's `b2CollidePolygons`
//! (E. Catto, "Contact Manifolds", GDC 2007): the face of largest separation is the reference
//! face, the other box's face most anti-parallel to it is the incident face, and the incident
//! edge clipped to the reference face's side planes gives at most two points. Points farther
//! than `max_sep_m` are dropped, so a manifold can describe a contact that has not happened
//! yet (a *speculative* contact): the solver then lets the bodies close the gap but not cross it.

use crate::geometry::Obb;

/// One point of a manifold: a world point between the two surfaces and the signed separation
/// along the manifold's normal (negative: penetration).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct ManifoldPoint {
    /// World x of the point (midway between the two surfaces), metres.
    pub x: f64,
    /// World y, metres.
    pub y: f64,
    /// Separation along the normal, metres (negative when the bodies overlap there).
    pub sep: f64,
}

/// A contact manifold with one or two points; the normal points from body a to body b.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Manifold {
    /// Unit normal from a to b.
    pub nx: f64,
    /// See `nx`.
    pub ny: f64,
    /// The points (the first `count` are valid).
    pub points: [ManifoldPoint; 2],
    /// Number of valid points (1 or 2).
    pub count: usize,
    /// Which features touch (wall index, or reference side, face and incident face), so that
    /// the same contact can be found again in the next sub-step.
    pub key: u8,
}

/// The four outward face normals of a box and the corresponding half extent.
#[inline]
fn faces(o: &Obb) -> [(f64, f64, f64); 4] {
    [
        (o.c, o.s, o.hx),
        (-o.s, o.c, o.hy),
        (-o.c, -o.s, o.hx),
        (o.s, -o.c, o.hy),
    ]
}

/// The two end points of face `k` of box `o` (counter-clockwise, seen from outside).
#[inline]
fn face_ends(o: &Obb, k: usize) -> ((f64, f64), (f64, f64)) {
    // Corners: front-left, rear-left, rear-right, front-right.
    let c = o.corners();
    match k {
        0 => (c[3], c[0]), // front face (+u): front-right → front-left
        1 => (c[0], c[1]), // left face (+v): front-left → rear-left
        2 => (c[1], c[2]), // rear face (−u)
        _ => (c[2], c[3]), // right face (−v)
    }
}

/// The largest separation of `b` from the faces of `a`: (separation, face index).
#[inline]
fn max_separation(a: &Obb, b: &Obb) -> (f64, usize) {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let mut best = (f64::NEG_INFINITY, 0);
    for (k, &(nx, ny, h)) in faces(a).iter().enumerate() {
        // b's extent along the normal.
        let eb = b.hx * (nx * b.c + ny * b.s).abs() + b.hy * (-nx * b.s + ny * b.c).abs();
        let sep = dx * nx + dy * ny - h - eb;
        if sep > best.0 {
            best = (sep, k);
        }
    }
    best
}

/// Relative tolerance that keeps the reference face on `a` when both are nearly equal, so the
/// manifold does not flip between sub-steps (Box2D's `0.1 · linearSlop`, here 0.5 µm).
const FLIP_TOLERANCE_M: f64 = 5e-7;

/// The manifold of two boxes, or `None` when no point is within `max_sep_m` (or the boxes are
/// farther apart than that along some face normal).
pub(crate) fn box_box(a: &Obb, b: &Obb, max_sep_m: f64) -> Option<Manifold> {
    let (sep_a, face_a) = max_separation(a, b);
    if sep_a > max_sep_m {
        return None;
    }
    let (sep_b, face_b) = max_separation(b, a);
    if sep_b > max_sep_m {
        return None;
    }
    let (rf, inc, face, flip) = if sep_b > sep_a + FLIP_TOLERANCE_M {
        (b, a, face_b, true)
    } else {
        (a, b, face_a, false)
    };
    let (nx, ny, _) = faces(rf)[face];
    // Incident face: the face of `inc` most anti-parallel to the reference normal.
    let mut inc_face = 0;
    let mut min_dot = f64::INFINITY;
    for (k, &(fx, fy, _)) in faces(inc).iter().enumerate() {
        let d = fx * nx + fy * ny;
        if d < min_dot {
            min_dot = d;
            inc_face = k;
        }
    }
    let (v1, v2) = face_ends(inc, inc_face);
    let (r1, r2) = face_ends(rf, face);
    // Side planes of the reference face: tangent t from r1 to r2.
    let (tx, ty) = (r2.0 - r1.0, r2.1 - r1.1);
    let len = libm::hypot(tx, ty);
    let (tx, ty) = (tx / len, ty / len);
    let lo = r1.0 * tx + r1.1 * ty;
    let hi = r2.0 * tx + r2.1 * ty;
    // Clip the incident segment to lo <= t·p <= hi.
    let clip = |p: (f64, f64), q: (f64, f64), bound: f64, keep_above: bool| {
        let dp = p.0 * tx + p.1 * ty - bound;
        let dq = q.0 * tx + q.1 * ty - bound;
        let (dp, dq) = if keep_above { (dp, dq) } else { (-dp, -dq) };
        let inside = |d: f64| d >= 0.0;
        match (inside(dp), inside(dq)) {
            (true, true) => Some((p, q)),
            (false, false) => None,
            (true, false) => {
                let t = dp / (dp - dq);
                Some((p, (p.0 + t * (q.0 - p.0), p.1 + t * (q.1 - p.1))))
            }
            (false, true) => {
                let t = dp / (dp - dq);
                Some(((p.0 + t * (q.0 - p.0), p.1 + t * (q.1 - p.1)), q))
            }
        }
    };
    let off = r1.0 * nx + r1.1 * ny;
    let Some((p, q)) = clip(v1, v2, lo, true).and_then(|(p, q)| clip(p, q, hi, false)) else {
        // The incident edge lies beside the reference face (the boxes meet corner to corner):
        // the incident corner deepest along the normal, with its separation along it (no
        // more than the distance between the boxes, so the contact errs on the safe side).
        let v = if v1.0 * nx + v1.1 * ny <= v2.0 * nx + v2.1 * ny {
            v1
        } else {
            v2
        };
        let sep = v.0 * nx + v.1 * ny - off;
        if sep > max_sep_m {
            return None;
        }
        let mut m = Manifold {
            nx: if flip { -nx } else { nx },
            ny: if flip { -ny } else { ny },
            key: 0x80 | (u8::from(flip) << 4) | ((face as u8) << 2) | inc_face as u8,
            count: 1,
            ..Manifold::default()
        };
        m.points[0] = ManifoldPoint {
            x: v.0 - 0.5 * sep * nx,
            y: v.1 - 0.5 * sep * ny,
            sep,
        };
        return Some(m);
    };
    let mut m = Manifold {
        nx: if flip { -nx } else { nx },
        ny: if flip { -ny } else { ny },
        key: (u8::from(flip) << 4) | ((face as u8) << 2) | inc_face as u8,
        ..Manifold::default()
    };
    for v in [p, q] {
        let sep = v.0 * nx + v.1 * ny - off;
        if sep <= max_sep_m {
            // Midway between the incident point and the reference face.
            m.points[m.count] = ManifoldPoint {
                x: v.0 - 0.5 * sep * nx,
                y: v.1 - 0.5 * sep * ny,
                sep,
            };
            m.count += 1;
        }
    }
    (m.count > 0).then_some(m)
}

/// The manifolds of a box against the four walls of the arena `[0, w] × [0, h]`: for each
/// wall, the corners within `max_sep_m` of it (at most two: the two nearest), with the
/// normal pointing from the box into the wall. Calls `out` once per wall in contact, in the
/// order left, right, bottom, top.
pub(crate) fn box_walls(o: &Obb, w: f64, h: f64, max_sep_m: f64, mut out: impl FnMut(Manifold)) {
    let corners = o.corners();
    for key in 0..4u8 {
        // Normal from the box into the wall, and each corner's distance from the wall.
        let (nx, ny) = match key {
            0 => (-1.0, 0.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (0.0, 1.0),
        };
        let d: [f64; 4] = core::array::from_fn(|k| {
            let (x, y) = corners[k];
            match key {
                0 => x,
                1 => w - x,
                2 => y,
                _ => h - y,
            }
        });
        // The two nearest corners (ties to the lower index), in corner order.
        let mut first = 0;
        for k in 1..4 {
            if d[k] < d[first] {
                first = k;
            }
        }
        if d[first] > max_sep_m {
            continue;
        }
        let mut second = usize::from(first == 0);
        for k in 0..4 {
            if k != first && d[k] < d[second] {
                second = k;
            }
        }
        let mut m = Manifold {
            nx,
            ny,
            key,
            ..Manifold::default()
        };
        let (lo, hi) = (first.min(second), first.max(second));
        for k in [lo, hi] {
            if d[k] <= max_sep_m {
                let (x, y) = corners[k];
                m.points[m.count] = ManifoldPoint {
                    x: x + 0.5 * d[k] * nx,
                    y: y + 0.5 * d[k] * ny,
                    sep: d[k],
                };
                m.count += 1;
            }
        }
        out(m);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::obb_overlap;
    use core::f64::consts::PI;

    #[test]
    fn face_to_face_gives_two_points_at_the_gap() {
        let a = Obb::new(0.0, 0.0, 0.0, 0.115, 0.09);
        let b = Obb::new(0.235, 0.0, PI, 0.115, 0.09);
        let m = box_box(&a, &b, 0.01).unwrap();
        assert_eq!(m.count, 2);
        assert!((m.nx - 1.0).abs() < 1e-12 && m.ny.abs() < 1e-12);
        for p in &m.points[..2] {
            assert!((p.sep - 0.005).abs() < 1e-12, "{p:?}");
            assert!((p.x - 0.1175).abs() < 1e-12);
        }
        assert!(box_box(&a, &b, 0.004).is_none());
    }

    #[test]
    fn normal_points_from_a_to_b_either_way() {
        let a = Obb::new(0.0, 0.0, 0.3, 0.115, 0.09);
        let b = Obb::new(0.0, 0.17, 0.0, 0.115, 0.09);
        let m = box_box(&a, &b, 0.01).unwrap();
        assert!(m.ny > 0.9, "{m:?}");
        let m2 = box_box(&b, &a, 0.01).unwrap();
        assert!(m2.ny < -0.9, "{m2:?}");
    }

    #[test]
    fn penetration_depth_matches_the_sat() {
        for k in 0..200 {
            let t = f64::from(k) * 0.0314;
            let a = Obb::new(0.0, 0.0, t, 0.115, 0.09);
            let b = Obb::new(
                0.2 * libm::cos(t),
                0.15 * libm::sin(1.3 * t),
                -t,
                0.115,
                0.09,
            );
            if let Some(o) = obb_overlap(&a, &b, 0.0) {
                let m = box_box(&a, &b, 0.01).expect("overlapping boxes have a manifold");
                let deepest = m.points[..m.count]
                    .iter()
                    .map(|p| p.sep)
                    .fold(f64::INFINITY, f64::min);
                assert!(deepest < 0.0, "{k}: {m:?} {o:?}");
                assert!((-deepest - o.depth_m).abs() < 1e-9, "{k}: {deepest} {o:?}");
            }
        }
    }

    #[test]
    fn walls_give_the_nearest_corners() {
        let o = Obb::new(0.12, 0.5, 0.0, 0.115, 0.09);
        let mut got = Vec::new();
        box_walls(&o, 2.0, 1.0, 0.01, |m| got.push(m));
        assert_eq!(got.len(), 1);
        let m = got[0];
        assert_eq!((m.nx, m.ny, m.count), (-1.0, 0.0, 2));
        assert!((m.points[0].sep - 0.005).abs() < 1e-12);
        let tilted = Obb::new(0.2, 0.5, 0.5, 0.115, 0.09);
        let mut got = Vec::new();
        box_walls(&tilted, 2.0, 1.0, 0.2, |m| got.push(m));
        assert_eq!(got[0].count, 2);
        assert!(got[0].points[0].sep != got[0].points[1].sep);
    }
}
