//! What every stage of the sub-step knows of a body: its pose as the stages keep it, and the
//! constants all robots share (size, mass, inertia, wheel geometry, friction).

use crate::geometry::Obb;

/// A robot's pose as the stages keep it: centre in metres and heading as its cosine and sine
/// (so that no stage takes a sine or cosine of an angle it already has).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct BodyPose {
    /// Centre x, metres.
    pub(crate) x: f64,
    /// Centre y, metres.
    pub(crate) y: f64,
    /// cos of the heading.
    pub(crate) c: f64,
    /// sin of the heading.
    pub(crate) s: f64,
}

impl BodyPose {
    /// The body's box, half extents `hx` along the heading and `hy` across.
    #[inline]
    pub(crate) fn obb(self, hx: f64, hy: f64) -> Obb {
        Obb {
            x: self.x,
            y: self.y,
            c: self.c,
            s: self.s,
            hx,
            hy,
        }
    }

    /// Whether the body's box reaches past a wall of the `w` × `h` arena.
    #[inline]
    pub(crate) fn crosses_walls(self, hx: f64, hy: f64, w: f64, h: f64) -> bool {
        let (ex, ey) = self.obb(hx, hy).aabb_half_extents();
        self.x - ex < 0.0 || self.x + ex > w || self.y - ey < 0.0 || self.y + ey > h
    }
}

/// What every robot shares: size, mass, inertia, wheel geometry and the friction coefficients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BodyConst {
    /// Half the body's length (along the heading), metres.
    pub hx: f64,
    /// Half the body's width (across the heading), metres.
    pub hy: f64,
    /// Radius of the body's bounding circle, metres.
    pub radius_m: f64,
    /// 1 / mass, 1/kg.
    pub inv_m: f64,
    /// 1 / moment of inertia about the centre, 1/(kg·m²).
    pub inv_i: f64,
    /// Half the wheel track, metres (left wheel at +, right at −, on the body's y axis).
    pub half_track: f64,
    /// Largest friction force one drive wheel can take from the floor, N.
    pub wheel_force_n: f64,
    /// Coulomb coefficient between two bodies.
    pub mu_robot: f64,
    /// Coulomb coefficient between a body and a wall.
    pub mu_wall: f64,
    /// Effective mass of a wheel's rolling row, kg.
    pub wheel_mass_long: f64,
    /// Effective mass of a wheel's sideways row, kg.
    pub wheel_mass_lat: f64,
    /// Mass, kg.
    pub mass: f64,
    /// Moment of inertia over half the wheel track, kg·m.
    pub inertia_per_half_track: f64,
}

impl BodyConst {
    /// From the body's mass, size, wheel track, one drive wheel's traction (N) and the
    /// friction coefficients.
    pub(crate) fn new(
        mass_kg: f64,
        length_m: f64,
        width_m: f64,
        track_m: f64,
        wheel_traction_n: f64,
        mu_robot: f64,
        mu_wall: f64,
    ) -> BodyConst {
        let hx = 0.5 * length_m;
        let hy = 0.5 * width_m;
        let inertia = mass_kg * (length_m * length_m + width_m * width_m) / 12.0;
        let half_track = 0.5 * track_m;
        let inv_m = 1.0 / mass_kg;
        let inv_i = 1.0 / inertia;
        BodyConst {
            hx,
            hy,
            radius_m: libm::hypot(hx, hy),
            inv_m,
            inv_i,
            half_track,
            wheel_force_n: wheel_traction_n,
            mu_robot,
            mu_wall,
            wheel_mass_long: 1.0 / (inv_m + inv_i * half_track * half_track),
            wheel_mass_lat: mass_kg,
            mass: mass_kg,
            inertia_per_half_track: inertia / half_track,
        }
    }

    /// The longitudinal forces (left, right), N, the floor gives the two drive wheels of a body
    /// whose speed along its heading changes by `d_along` (m/s) and whose turn rate changes by
    /// `d_omega` (rad/s) in a sub-step of `1 / inv_h` seconds: from m·a = F_l + F_r and
    /// I·α = (F_r − F_l)·half_track, each at most the wheel's traction.
    #[inline]
    pub(crate) fn wheel_forces(&self, d_along: f64, d_omega: f64, inv_h: f64) -> [f64; 2] {
        let sum = self.mass * d_along * inv_h;
        let diff = self.inertia_per_half_track * d_omega * inv_h;
        let cap = self.wheel_force_n;
        [
            (0.5 * (sum - diff)).clamp(-cap, cap),
            (0.5 * (sum + diff)).clamp(-cap, cap),
        ]
    }

    /// The body's box at `pose`.
    #[inline]
    pub(crate) fn obb(&self, pose: BodyPose) -> Obb {
        pose.obb(self.hx, self.hy)
    }
}
