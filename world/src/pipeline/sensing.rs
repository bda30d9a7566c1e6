//! What the robots sense: the bumpers (a switch is pressed when the contacts on its face carry
//! force over a sub-step, with a snap-action switch's hysteresis) and the IR sensors' rays
//! (cast against the walls and the bodies the broad phase's grid puts near them).

use crate::body::{BodyConst, BodyPose};
use crate::geometry::{ray_obb, ray_walls, side_of};
use crate::grid::Grid;
use crate::params::WorldParams;
use crate::pipeline::solver::{Contact, WALL};

/// The bumper switches of every robot and the impulses their faces take in a sub-step.
#[derive(Debug, Clone)]
pub(crate) struct Bumpers {
    /// Per robot, the switches as of the latest sub-step (bit `1 << face`).
    pressed: Vec<u8>,
    /// The switches as the previous sub-step left them (a pressed switch releases at a lower
    /// force than it operates).
    held: Vec<u8>,
    /// Normal impulse each face took in the current sub-step, from the solver's contacts and
    /// the position corrections (front, rear, left, right), N·s.
    face_impulse: Vec<[f64; 4]>,
    /// The robots with some face impulse in the current sub-step.
    pushed: Vec<u32>,
}

impl Bumpers {
    /// Every switch released, for `n` robots.
    pub(crate) fn new(n: usize) -> Bumpers {
        Bumpers {
            pressed: vec![0; n],
            held: vec![0; n],
            face_impulse: vec![[0.0; 4]; n],
            pushed: Vec::new(),
        }
    }

    /// Robot `robot`'s switches: `[front, rear, left, right]`, `true` = pressed.
    pub(crate) fn of(&self, robot: usize) -> [bool; 4] {
        let b = self.pressed[robot];
        [b & 1 != 0, b & 2 != 0, b & 4 != 0, b & 8 != 0]
    }

    /// Robot `robot`'s switches as bits (`1 << face`).
    #[cfg(test)]
    pub(crate) fn bits(&self, robot: usize) -> u8 {
        self.pressed[robot]
    }

    /// A new sub-step: the switches as they are become the held ones, and all read released
    /// until [`Bumpers::press`].
    pub(crate) fn begin_substep(&mut self) {
        core::mem::swap(&mut self.pressed, &mut self.held);
        self.pressed.fill(0);
    }

    /// Adds a normal impulse (N·s, > 0 to count) to the face of robot `i` (at pose `b`) that
    /// faces the world direction (fx, fy).
    #[inline]
    pub(crate) fn push_face(&mut self, i: usize, b: BodyPose, fx: f64, fy: f64, impulse: f64) {
        if impulse <= 0.0 {
            return;
        }
        let side = side_of(fx * b.c + fy * b.s, -fx * b.s + fy * b.c);
        let f = &mut self.face_impulse[i];
        if f.iter().all(|&x| x == 0.0) {
            self.pushed.push(i as u32);
        }
        f[side] += impulse;
    }

    /// Adds the solved contacts' normal impulses to the faces they act on (bodies at `pose`).
    pub(crate) fn push_contacts(&mut self, contacts: &[Contact], pose: &[BodyPose]) {
        for ct in contacts {
            let j = ct.normal_impulse();
            self.push_face(ct.a as usize, pose[ct.a as usize], ct.nx, ct.ny, j);
            if ct.b != WALL {
                self.push_face(ct.b as usize, pose[ct.b as usize], -ct.nx, -ct.ny, j);
            }
        }
    }

    /// Presses every switch whose face took more than `operate` N·s this sub-step, or, if it
    /// was held, more than `release`; clears the faces' impulses for the next sub-step.
    pub(crate) fn press(&mut self, operate: f64, release: f64) {
        for &i in &self.pushed {
            let i = i as usize;
            let held = self.held[i];
            for (side, j) in self.face_impulse[i].iter_mut().enumerate() {
                let threshold = if held & (1 << side) != 0 {
                    release
                } else {
                    operate
                };
                if *j > threshold {
                    self.pressed[i] |= 1 << side;
                }
                *j = 0.0;
            }
        }
        self.pushed.clear();
    }
}

/// A sensor's mount point and ray directions in the body frame.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MountRays {
    /// Mount x, body frame, metres.
    pub(crate) x: f64,
    /// Mount y, body frame, metres.
    pub(crate) y: f64,
    /// The cone's ray directions (cos, sin), body frame.
    pub(crate) dirs: Vec<(f64, f64)>,
}

impl MountRays {
    /// Every sensor of `params`: its mount and its `rays_per_sensor` directions spread evenly
    /// over the cone.
    pub(crate) fn all(params: &WorldParams) -> Vec<MountRays> {
        params
            .sensor_mounts
            .iter()
            .map(|m| {
                let k = params.rays_per_sensor;
                let dirs = (0..k)
                    .map(|r| {
                        let off = if k == 1 {
                            0.0
                        } else {
                            params.cone_half_angle_rad
                                * (2.0 * f64::from(r) / f64::from(k - 1) - 1.0)
                        };
                        let (s, c) = libm::sincos(m.angle_rad + off);
                        (c, s)
                    })
                    .collect();
                MountRays {
                    x: m.x_m,
                    y: m.y_m,
                    dirs,
                }
            })
            .collect()
    }
}

/// What a ray is cast against: the walls of a `w` × `h` arena and the bodies, found through
/// the broad phase's grid.
pub(crate) struct RayScene<'a> {
    /// The bodies' poses now.
    pub(crate) pose: &'a [BodyPose],
    /// The bodies' size.
    pub(crate) body: &'a BodyConst,
    /// The grid, with robots filed where they were at its last build.
    pub(crate) grid: &'a Grid,
    /// How far a robot may have moved since the grid was built, metres.
    pub(crate) drift_limit_m: f64,
    /// Arena width, metres.
    pub(crate) w: f64,
    /// Arena height, metres.
    pub(crate) h: f64,
    /// Range of the sensors, metres.
    pub(crate) range: f64,
}

impl RayScene<'_> {
    /// Distance in millimetres from robot `robot`'s sensor `m` to the nearest wall or other
    /// robot's body along its rays (the nearest over its cone), or `None` if nothing is within
    /// range. The robot's own body is never hit.
    pub(crate) fn sense(&self, robot: usize, m: &MountRays) -> Option<f64> {
        let b = self.pose[robot];
        let ox = b.x + b.c * m.x - b.s * m.y;
        let oy = b.y + b.s * m.x + b.c * m.y;
        let mut best: Option<f64> = None;
        for &(dc, ds) in &m.dirs {
            let dx = b.c * dc - b.s * ds;
            let dy = b.s * dc + b.c * ds;
            if let Some(t) = self.cast(robot, ox, oy, dx, dy)
                && best.is_none_or(|bt| t < bt)
            {
                best = Some(t);
            }
        }
        best.map(|t| t * 1000.0)
    }

    /// Casts one ray (unit direction) and returns the nearest hit in metres within range.
    fn cast(&self, own: usize, ox: f64, oy: f64, dx: f64, dy: f64) -> Option<f64> {
        let range = self.range;
        let t_wall = ray_walls(ox, oy, dx, dy, self.w, self.h);
        let (mut t_max, mut hit) = if t_wall <= range {
            (t_wall, true)
        } else {
            (range, false)
        };
        // Cells whose robots (filed by their centre at the last build, which may have moved
        // up to half the margin since) can reach the segment.
        let r = self.body.radius_m;
        let pad = r + self.drift_limit_m;
        let (ex, ey) = (ox + dx * t_max, oy + dy * t_max);
        let c0 = self.grid.col(ox.min(ex) - pad);
        let c1 = self.grid.col(ox.max(ex) + pad);
        let r0 = self.grid.row(oy.min(ey) - pad);
        let r1 = self.grid.row(oy.max(ey) + pad);
        for row in r0..=r1 {
            for col in c0..=c1 {
                for &j in self.grid.cell(col, row) {
                    let j = j as usize;
                    if j == own {
                        continue;
                    }
                    let b = self.pose[j];
                    let (rx, ry) = (b.x - ox, b.y - oy);
                    let tc = rx * dx + ry * dy;
                    if tc < -r || tc > t_max + r {
                        continue;
                    }
                    let perp2 = rx * rx + ry * ry - tc * tc;
                    if perp2 > r * r {
                        continue;
                    }
                    if let Some(t) = ray_obb(ox, oy, dx, dy, &self.body.obb(b), t_max)
                        && (t < t_max || !hit)
                    {
                        t_max = t;
                        hit = true;
                    }
                }
            }
        }
        hit.then_some(t_max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::broad_phase::tests::scene;
    use core::f64::consts::PI;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Every ray cast through the grid equals a brute-force cast against all walls and
        /// robots.
        #[test]
        fn rays_equal_brute_force(
            side in 1.0f64..8.0,
            xs in proptest::collection::vec((0.0f64..1.0, 0.0f64..1.0, -PI..PI), 1..80),
        ) {
            let params = WorldParams {
                rays_per_sensor: 3,
                cone_half_angle_rad: 0.05,
                ..WorldParams::with_clock(crate::params::TEST_CLOCK_HZ)
            };
            let (pose, body, broad) = scene(&params, side, &xs);
            let (w, h) = (side, side * 0.7);
            let rays = RayScene {
                pose: &pose,
                body: &body,
                grid: broad.grid(),
                drift_limit_m: broad.drift_limit_m(),
                w,
                h,
                range: params.sensor_max_range_m,
            };
            let mounts = MountRays::all(&params);
            for robot in 0..pose.len() {
                for m in &mounts {
                    let b = pose[robot];
                    let ox = b.x + b.c * m.x - b.s * m.y;
                    let oy = b.y + b.s * m.x + b.c * m.y;
                    let mut brute: Option<f64> = None;
                    for &(dc, ds) in &m.dirs {
                        let dx = b.c * dc - b.s * ds;
                        let dy = b.s * dc + b.c * ds;
                        let mut t = ray_walls(ox, oy, dx, dy, w, h);
                        for (j, &q) in pose.iter().enumerate() {
                            if j != robot
                                && let Some(tj) = ray_obb(ox, oy, dx, dy, &body.obb(q), f64::INFINITY)
                            {
                                t = t.min(tj);
                            }
                        }
                        if t <= params.sensor_max_range_m && brute.is_none_or(|bt| t < bt) {
                            brute = Some(t);
                        }
                    }
                    prop_assert_eq!(rays.sense(robot, m), brute.map(|t| t * 1000.0));
                }
            }
        }
    }
}
