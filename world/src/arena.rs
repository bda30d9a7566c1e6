//! Arenas: walled axis-aligned rectangles with the origin at the lower-left corner.

use crate::error::WorldError;

/// Length of the paper's corridor (environment 1): 3.0 m (docs/design.md §5).
pub const CORRIDOR_LENGTH_M: f64 = 3.0;
/// The corridor is the robot width plus 4 cm wide (docs/design.md §5).
pub const CORRIDOR_EXTRA_WIDTH_M: f64 = 0.04;
/// Side of the paper's square arena (environment 2): 1.8 m (docs/design.md §5).
pub const SQUARE_SIDE_M: f64 = 1.8;
/// Robots in the paper's runs: 3 (docs/design.md §5); the scaled arena keeps 3 robots per 1.8 m × 1.8 m.
pub const PAPER_ROBOTS: usize = 3;
/// Largest accepted arena side: 10 km (our limit).
pub const MAX_ARENA_SIDE_M: f64 = 10_000.0;

/// How robots are laid out in an arena and which metrics apply.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArenaKind {
    /// A corridor along x: robots placed in one line on the centre line, facing along it;
    /// the gap metric ([`crate::World::corridor_gaps_m`]) applies.
    Corridor,
    /// An open walled floor: robots placed at uniform positions and headings.
    Open,
}

/// A wall: a line segment on the arena boundary, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// First end point (x, y), metres.
    pub a: (f64, f64),
    /// Second end point (x, y), metres.
    pub b: (f64, f64),
}

/// A walled rectangle `[0, width_m] × [0, height_m]`; walls are its four zero-thickness sides.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arena {
    kind: ArenaKind,
    width_m: f64,
    height_m: f64,
}

impl Arena {
    /// The paper's corridor (environment 1): 3.0 m along x, `body_width_m + 0.04` m across.
    pub fn corridor(body_width_m: f64) -> Result<Arena, WorldError> {
        Self::corridor_with_clearance(body_width_m, CORRIDOR_EXTRA_WIDTH_M)
    }

    /// A corridor 3.0 m along x and `body_width_m + clearance_m` across (the paper gives no
    /// width; `clearance_m` in 0.001..=1 m).
    pub fn corridor_with_clearance(
        body_width_m: f64,
        clearance_m: f64,
    ) -> Result<Arena, WorldError> {
        if body_width_m.is_nan() || !(0.01..=10.0).contains(&body_width_m) {
            return Err(WorldError::Parameter {
                name: "body_width_m",
                value: body_width_m,
                valid: "a width in 0.01..=10 m",
            });
        }
        if clearance_m.is_nan() || !(0.001..=1.0).contains(&clearance_m) {
            return Err(WorldError::Parameter {
                name: "clearance_m",
                value: clearance_m,
                valid: "a clearance in 0.001..=1 m",
            });
        }
        Ok(Arena {
            kind: ArenaKind::Corridor,
            width_m: CORRIDOR_LENGTH_M,
            height_m: body_width_m + clearance_m,
        })
    }

    /// The paper's corridor for the design body (180 mm wide): 3.0 m × 0.22 m.
    pub fn paper_corridor() -> Arena {
        Arena {
            kind: ArenaKind::Corridor,
            width_m: CORRIDOR_LENGTH_M,
            height_m: crate::params::BODY_WIDTH_M + CORRIDOR_EXTRA_WIDTH_M,
        }
    }

    /// The paper's square arena (environment 2): 1.8 m × 1.8 m.
    pub fn square() -> Arena {
        Arena {
            kind: ArenaKind::Open,
            width_m: SQUARE_SIDE_M,
            height_m: SQUARE_SIDE_M,
        }
    }

    /// A square arena for `n_robots` at the paper's density (3 robots per 1.8 m × 1.8 m):
    /// side = 1.8 m · sqrt(n / 3).
    pub fn scaled_square(n_robots: usize) -> Result<Arena, WorldError> {
        if n_robots == 0 {
            return Err(WorldError::Parameter {
                name: "n_robots",
                value: 0.0,
                valid: "at least 1 robot for a scaled arena",
            });
        }
        let side_m = SQUARE_SIDE_M * (n_robots as f64 / PAPER_ROBOTS as f64).sqrt();
        Arena::rectangle(side_m, side_m)
    }

    /// An open walled rectangle of the given size, metres (each side in (0, 10 000]).
    pub fn rectangle(width_m: f64, height_m: f64) -> Result<Arena, WorldError> {
        for (name, v) in [("arena width_m", width_m), ("arena height_m", height_m)] {
            if v.is_nan() || v <= 0.0 || v > MAX_ARENA_SIDE_M {
                return Err(WorldError::Parameter {
                    name,
                    value: v,
                    valid: "a side > 0 and <= 10 000 m",
                });
            }
        }
        Ok(Arena {
            kind: ArenaKind::Open,
            width_m,
            height_m,
        })
    }

    /// Layout kind.
    pub fn kind(&self) -> ArenaKind {
        self.kind
    }

    /// Extent along x, metres (the corridor's length).
    pub fn width_m(&self) -> f64 {
        self.width_m
    }

    /// Extent along y, metres (the corridor's width).
    pub fn height_m(&self) -> f64 {
        self.height_m
    }

    /// The four walls, counter-clockwise from the bottom: y = 0, x = width, y = height, x = 0.
    pub fn walls(&self) -> [Segment; 4] {
        let (w, h) = (self.width_m, self.height_m);
        [
            Segment {
                a: (0.0, 0.0),
                b: (w, 0.0),
            },
            Segment {
                a: (w, 0.0),
                b: (w, h),
            },
            Segment {
                a: (w, h),
                b: (0.0, h),
            },
            Segment {
                a: (0.0, h),
                b: (0.0, 0.0),
            },
        ]
    }

    /// A short description for messages, e.g. `corridor 3 m x 0.22 m`.
    pub fn describe(&self) -> String {
        let name = match self.kind {
            ArenaKind::Corridor => "corridor",
            ArenaKind::Open => "arena",
        };
        format!("{name} {} m x {} m", self.width_m, self.height_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_sizes() {
        let c = Arena::paper_corridor();
        assert_eq!(c.width_m(), 3.0);
        assert!((c.height_m() - 0.22).abs() < 1e-15);
        assert_eq!(c, Arena::corridor(0.18).unwrap());
        let s = Arena::square();
        assert_eq!((s.width_m(), s.height_m()), (1.8, 1.8));
        let s3 = Arena::scaled_square(3).unwrap();
        assert!((s3.width_m() - 1.8).abs() < 1e-12);
        let s300 = Arena::scaled_square(300).unwrap();
        assert!((s300.width_m() - 18.0).abs() < 1e-12);
    }

    #[test]
    fn bad_sizes_are_errors() {
        assert!(Arena::scaled_square(0).is_err());
        assert!(Arena::rectangle(f64::NAN, 1.0).is_err());
        assert!(Arena::rectangle(1.0, -1.0).is_err());
        assert!(Arena::rectangle(1.0, f64::INFINITY).is_err());
        assert!(Arena::corridor(f64::NAN).is_err());
    }

    #[test]
    fn walls_close_the_boundary() {
        let w = Arena::square().walls();
        for k in 0..4 {
            assert_eq!(w[k].b, w[(k + 1) % 4].a);
        }
    }
}
