//! # world — the physical side of the h8swarm
//!
//! Arenas with walls, robot bodies, motor dynamics, differential-drive kinematics, collisions
//! that press bumpers, and IR sensor rays. It takes motor commands in (PWM duty and H-bridge
//! direction per wheel) and gives true distances (mm) and bumper states out; it knows nothing
//! of the other h8swarm crates.
//!
//! ```
//! use world::{Arena, Behaviour, World, WorldParams, FRONT};
//!
//! let mut w = World::new(Arena::square(), WorldParams::default(), 3, 42)?;
//! let (l, r) = Behaviour::TurnLeftForward.wheels();
//! w.set_wheels(0, l, r)?;
//! for _ in 0..45 {
//!     w.advance(0.010)?; // one 0.45 s behaviour step in 10 ms sub-steps
//! }
//! let d_mm = w.sense(0, FRONT)?; // Some(distance) or None beyond 1.5 m
//! let pressed = w.bumpers(0)?;   // [front, rear, left, right]
//! # let _ = (d_mm, pressed);
//! # Ok::<(), world::WorldError>(())
//! ```
//!
//! ## Frames and units
//! World frame: x to the right, y up, origin at the arena's lower-left corner, metres.
//! Headings are radians counter-clockwise from +x. Body frame: x forward along the heading,
//! y to the robot's left. Speeds m/s, times s; sensor distances are returned in **mm**.
//!
//! ## The model, and the choices where the spec is silent
//! - **Arenas** ([`Arena`]) are walled axis-aligned rectangles; walls are the four zero-thickness
//!   sides. The corridor (paper env. 1) is 3.0 m along x and body width + 4 cm (0.22 m) across;
//!   the square arena (env. 2) is 1.8 m; [`Arena::scaled_square`] keeps the paper's density
//!   (side = 1.8 m · sqrt(n/3)).
//! - **Bodies** are oriented rectangles 230 mm along the heading × 180 mm across (SPEC §1),
//!   centred on the midpoint of the wheel axle (the robot turns about its body centre).
//! - **Motors** (SPEC §3.5): commanded wheel speed = duty × top speed (0.15 m/s) × motor gain
//!   (uniform in 1 ± 5 %, drawn once per robot and wheel from the seed, one stream per robot)
//!   × sign (forward +, reverse −). The wheel speed follows it with a first-order lag, τ = 60 ms
//!   (valid 20–100 ms), integrated exactly (`exp(−dt/τ)`), so any sub-step is stable.
//!   **Brake** (H/H) drives the speed to 0 with `brake_time_constant_s`, default the same 60 ms:
//!   shorting a DC motor's terminals gives the same electromechanical time constant as driving
//!   it from a voltage source (J·R/k²), with target 0. **Coast** (L/L) drives it to 0 with
//!   `coast_time_constant_s`, default also 60 ms (an open motor is slowed only by friction,
//!   which in a 203:1 gearbox is large; a longer value can be set).
//! - **Kinematics**: differential drive with wheel track 160 mm (our choice, the paper gives
//!   none: 56 mm Tamiya wheels inside the 180 mm body). Per sub-step the body follows the exact
//!   arc for the sub-step's *mean* wheel speeds (the exact integral of the lag), so the heading
//!   change is exact, straight-line distance is exact, and constant wheel speeds give the same
//!   path whatever the sub-step length (to rounding).
//! - **Time**: [`World::advance`] splits a call into equal sub-steps of at most
//!   `max_substep_s` (default 20 ms, at most 100 ms so bodies cannot pass through each
//!   other); robots are processed in index order.
//! - **Collisions** (robot–wall, robot–robot) are resolved after the move, in robot index
//!   order (each robot: walls, then its pairs with higher-index robots), for a fixed number of
//!   passes (default 32, stopping early after a clean pass: see
//!   [`params::COLLISION_ITERATIONS`] for why so many). The first pass resolves the
//!   contacts present after the move; each later pass re-tests only the pairs with a robot
//!   moved by the pass before (the others were clean and have not moved), so a clean pass
//!   proves that nothing overlaps. An overlap is removed by pushing along the
//!   minimum-translation vector of the separating-axis test, a robot pair sharing it equally
//!   (equal masses), to a gap of [`CONTACT_SKIN_M`] (1 nm); a robot held by a wall, or by a
//!   robot held by a wall, does not give way, so the other takes the whole push. The model is kinematic (no
//!   momentum: a 0.5 kg robot on 203:1 gear motors moves at its wheel speed), so removing the
//!   displacement into the contact *is* cancelling the velocity component into it; the wheels
//!   keep turning (they slip against the floor) and [`World::wheel_speeds`] still shows the
//!   motor's speed. Contacts do not rotate bodies. If a robot still overlaps after the passes,
//!   its rotation for the sub-step is dropped (it slides without turning, e.g. wedged across
//!   the narrow corridor) and the passes rerun; a robot that still overlaps keeps its previous
//!   pose (blocked), and so in turn does any robot pushed into it. The previous state had no
//!   overlap, so **no body ever penetrates a wall or another body after a sub-step**.
//! - **Bumpers** (SPEC §3.4): a switch is pressed when its robot overlapped something during
//!   the latest sub-step, on the side given by the contact normal in the body frame: the
//!   larger of the forward and sideways components wins (a corner contact goes to the face the
//!   normal points at most; exact diagonals go to front/rear). A robot resting against a wall
//!   without pushing does not hold its switch (the switch spring lifts it off).
//! - **Sensors** (SPEC §3.1): by default four, at the middle of the front, rear, left and right
//!   sides, facing out (indices [`FRONT`], [`REAR`], [`LEFT`], [`RIGHT`]); mounts, rays per
//!   sensor (a cone) and range are parameters. [`World::sense`] casts from the mount against
//!   the walls and every other robot's body and returns the distance to the nearest hit in mm,
//!   or `None` beyond the range (default 1.5 m). Several cone rays report the nearest hit.
//! - **Broad phase**: a uniform grid, filled by counting sort into reused buffers, with cells of
//!   at least two bounding radii (2 × 146 mm) plus a 200 mm margin, enlarged to about one
//!   robot per cell (≈ 1.04 m at the paper's density). From it come the candidate pairs
//!   (bounding circles within the margin, from the 3 × 3 neighbouring cells) and the robots
//!   whose bounding circle is within the margin of a wall. Like a Verlet list, grid and candidates are kept until some
//!   robot has moved more than half the margin (100 mm, about 0.67 s at full speed) from where
//!   it was filed, then rebuilt; no overlap can be missed in between. Rays visit the cells of
//!   their bounding box padded by a body radius plus that drift. Cost grows linearly with the
//!   number of robots.
//! - **Placement** ([`World::new`]): corridor: on the centre line, facing +x or −x at random,
//!   spaced by the clearance plus uniform random spacings; open arena: uniform positions and
//!   headings, rejection-sampled with the clearance (default 50 mm) to walls and bodies, at
//!   most `1000·n + 10 000` attempts. Too many robots is an error that says how many fit.
//! - **Randomness**: only from the seed: placement and each robot's motor gains have their own
//!   streams, derived by the project's one rule (`seeding::derive(seed, robot, MotorGain)`,
//!   `derive(seed, 0, Placement)`), so adding a robot changes no other robot's gains.
//! - **Threads**: [`World::advance_par`] runs the per-robot phases (motors and kinematics,
//!   candidate search, the first pass's overlap tests) on rayon's pool in fixed chunks merged
//!   in index order; the pushes run on one thread in index order. Results are bit-identical to
//!   [`World::advance`] whatever the thread count.
//! - **Corridor metric**: [`World::corridor_gaps_m`] gives the free gaps between neighbouring
//!   robots along the corridor (sorted by centre x; gap = shortest distance between the two
//!   outlines, which for robots facing along the corridor is face to face; the gaps to the end
//!   walls are excluded); [`World::corridor_gap_cv`] their coefficient of variation
//!   (population standard deviation / mean).

#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod arena;
pub mod error;
pub mod geometry;
mod grid;
pub mod motor;
pub mod params;
mod world;

pub use arena::{Arena, ArenaKind, Segment};
pub use error::WorldError;
pub use motor::{Behaviour, Direction, WheelCommand};
pub use params::{SensorMount, WorldParams};
pub use world::{
    BROAD_PHASE_MARGIN_M, CONTACT_SKIN_M, FRONT, LEFT, MAX_ROBOTS, Pose, REAR, RIGHT, World,
    coefficient_of_variation,
};
