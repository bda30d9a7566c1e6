//! The wheels' part of a sub-step: the motors (each wheel's speed over the sub-step, the exact
//! first-order lag) and the motion of the robots that touch nothing (the exact arc of their
//! wheels' mean speeds).

use crate::body::{BodyConst, BodyPose};
use crate::geometry::arc_step;
use crate::motor::LagCoefficients;
use crate::pipeline::narrow_phase::ACTIVE;

/// A robot's two wheels: speeds now, commanded speeds and which lag applies.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Motion {
    /// Wheel speeds now, m/s (left, right).
    pub(crate) speed: [f64; 2],
    /// Commanded wheel speeds, m/s (duty × top speed × gain × sign).
    pub(crate) target: [f64; 2],
    /// Which lag applies: drive, brake or coast.
    pub(crate) mode: [u8; 2],
}

/// What the motor and free-motion stages need for one sub-step.
#[derive(Clone, Copy)]
pub(crate) struct Drive {
    /// The motors' lag over the sub-step.
    pub(crate) lag: LagCoefficients,
    /// 1 / wheel track, 1/m.
    pub(crate) inv_track: f64,
    /// The sub-step's length, seconds.
    pub(crate) h: f64,
    /// 1 / h.
    pub(crate) inv_h: f64,
    /// The bodies' mass, inertia, wheel geometry and traction (for the free robots' wheel
    /// forces).
    pub(crate) body: BodyConst,
}

/// The wheel-speed difference below which a wheel is taken to have reached its target speed:
/// 1e-12 m/s, a picometre per second, far below anything the model resolves.
const SPEED_SNAP_M_S: f64 = 1e-12;

impl Drive {
    /// Motors for a slice of robots: wheel speeds follow their targets with the exact
    /// first-order lag; `wmean` gets each wheel's mean speed over the sub-step (the exact
    /// integral of the lag) and `prev` the pose at its start.
    pub(crate) fn motors(
        &self,
        motion: &mut [Motion],
        wmean: &mut [[f64; 2]],
        prev: &mut [BodyPose],
        pose: &[BodyPose],
    ) {
        for (((m, mean), pr), p) in motion.iter_mut().zip(wmean).zip(prev).zip(pose) {
            *pr = *p;
            for (w, mean_w) in mean.iter_mut().enumerate() {
                let l = self.lag.by_mode[usize::from(m.mode[w]).min(2)];
                let mut diff = m.speed[w] - m.target[w];
                // A speed within SPEED_SNAP_M_S of its target has arrived: without the snap, a
                // wheel decaying to a zero target keeps shrinking through subnormal floats,
                // which cost x86 cores about a hundred cycles per operation.
                if diff.abs() < SPEED_SNAP_M_S {
                    diff = 0.0;
                }
                *mean_w = m.target[w] + diff * l.mean_factor;
                m.speed[w] = m.target[w] + diff * l.decay;
            }
        }
    }

    /// Robots touching nothing (no `ACTIVE` flag) follow their wheels: the exact arc of the
    /// sub-step's mean wheel speeds (exact heading change and, for straight motion, exact
    /// distance); their velocity becomes the wheels' twist, and their wheel forces those that
    /// changed the velocity they had along their heading.
    pub(crate) fn free(
        &self,
        pose: &mut [BodyPose],
        vel: &mut [[f64; 3]],
        force: &mut [[f64; 2]],
        wmean: &[[f64; 2]],
        flags: &[u8],
    ) {
        for ((((p, v), fw), w), &f) in pose.iter_mut().zip(vel).zip(force).zip(wmean).zip(flags) {
            if f & ACTIVE != 0 {
                continue;
            }
            let along = 0.5 * (w[0] + w[1]);
            let omega = (w[1] - w[0]) * self.inv_track;
            let along0 = v[0] * p.c + v[1] * p.s;
            *fw = self
                .body
                .wheel_forces(along - along0, omega - v[2], self.inv_h);
            let (dx, dy, c, s) = arc_step(p.c, p.s, along, omega, self.h);
            p.x += dx;
            p.y += dy;
            p.c = c;
            p.s = s;
            *v = [along * c, along * s, omega];
        }
    }
}
