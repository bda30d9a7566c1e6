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
//! // Time counted in the robots' MCU clock: 25 MHz (the world has no clock of its own).
//! let mut w = World::new(Arena::square(), WorldParams::with_clock(25_000_000), 3, 42)?;
//! let (l, r) = Behaviour::TurnLeftForward.wheels();
//! w.set_wheels(0, l, r)?;
//! for _ in 0..45 {
//!     w.advance_states(250_000); // one 0.45 s step, 10 ms = 250 000 states at a time
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
//! - **Bodies** are oriented rectangles 230 mm along the heading × 180 mm across (docs/design.md §1),
//!   centred on the midpoint of the wheel axle (the robot turns about its body centre).
//! - **Motors** (docs/design.md §3.5): commanded wheel speed = duty × top speed (0.15 m/s) × motor gain
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
//!   arc for the sub-step's *mean* wheel speeds (the exact integral of the lag) when it touches
//!   nothing, so the heading change is exact, straight-line distance is exact, and constant
//!   wheel speeds give the same path whatever the sub-step length (to rounding).
//! - **Time** is counted in whole clock states (`clock_hz`, the robots' MCU clock: one clock
//!   rules it all, the world counts the states the robots' MCUs count). [`World::advance_states`]
//!   cuts an interval into [`World::substep_plan`]'s fewest equal sub-steps of at most
//!   `max_substep_s` (default 20 ms; lengths differing by one state at most, adding up exactly),
//!   so there is no floating-point accumulation of time and no sliver of a sub-step. Robots are
//!   processed in index order. [`World::advance`] takes seconds, rounded to states (for tests).
//! - **Bodies are rigid and pushed by their wheels**, not placed: a robot has mass 0.5 kg
//!   (docs/design.md §1) and the inertia of a uniform box; each of its two drive wheels grips the floor
//!   and makes the body's velocity at the wheel equal the wheel's rim speed along it and zero
//!   across it, with a force of at most `μ_floor · m·g/2` (default μ 0.6, about 1.5 N per
//!   wheel); past that it slips, and a slipping wheel's friction points against the slip of its
//!   contact patch (isotropic Coulomb: a wheel spinning against a blocked body holds it only
//!   weakly sideways). The 203:1 gear motors could push harder at stall, so a
//!   blocked robot pushes with its traction and its wheels slip ([`World::wheel_speeds`] still
//!   shows the motors' speed). A robot touching nothing follows its wheels exactly.
//!   [`World::wheel_forces`] gives the longitudinal force each wheel transmitted over the latest
//!   sub-step (a solved robot's wheel impulses over the sub-step; a free robot's m·a split
//!   between its wheels by the rigid-body equations), what the motors had to push: a robot
//!   pushing a wall, its traction; one cruising free, nothing.
//! - **Contacts** (robot–wall, robot–robot; [`SolverStats`] counts what they did): at the start
//!   of each sub-step every candidate pair and wall gives a contact manifold (reference-face
//!   clipping, one or two points, Box2D's method) when it is within the *speculative distance*
//!   (the farthest two bodies can close in a sub-step under their wheels, plus 25 %). A contact
//!   binds when the robots' own wheels would close it; the robots in binding contacts, and in
//!   turn every robot touching one of them, are solved together by sequential impulses
//!   (projected Gauss–Seidel, Catto 2005) on their velocities: the wheels' friction-limited
//!   grip, the contacts' normal impulses (push, never pull; a gap may close to the 10 nm skin,
//!   no further) and Coulomb friction along them (μ 0.3 robot–robot and robot–wall). The solve
//!   runs island by island (robots joined by robot–robot contacts, found by union–find), each
//!   until a sweep changes no impulse by more than 1e-6 N·s (2 µm/s on a 0.5 kg robot; other
//!   stopping rules, and Newton's method on a whole island, by `WorldParams::solver_convergence`),
//!   and
//!   contacts and wheels with a driving motor are warm-started from the previous sub-step's
//!   impulses (braked or coasting ones start from nothing: a braked robot held against a wall
//!   is statically indeterminate, and a kept push would outlive what sustained it). So bodies push each other (two equal tractions
//!   balance), slide along walls and each other when friction allows, and turn under an
//!   off-centre contact (a robot driving into a wall less than atan(width/length) + atan(μ_wall)
//!   = 54.7° off its normal turns square to it and stays, wheels slipping, as a differential-drive
//!   robot does; at a flatter angle it turns along the wall and slides; docs/physics.md derives it and
//!   `tests/wall_angle.rs` checks it against a plain-Coulomb reference). Poses follow the exact motion of the
//!   solved velocities. What the linearised solve leaves of an overlap (a turning corner) is
//!   removed by position sweeps that push along the contact normal with rotation, weighted by
//!   mass and inertia, to a 10 µm gap (so that a chain of contacts clears in a few sweeps); if `position_iterations` sweeps do not clear a cluster, its robots stop
//!   early in the sub-step: they move the largest fraction 1, 1/2, …, 0 of their motion at
//!   which nothing overlaps (a time of impact, never a jump back). **After every sub-step no
//!   body overlaps a wall or another body** (tests check it over thousands of crowded
//!   sub-steps). There is no reset anywhere.
//! - **Bumpers** (docs/design.md §3.4): a switch is pressed in a sub-step when the contacts on its face
//!   carried at least `bumper_force_n` (default 0.1 N) between them over the sub-step: the
//!   solver's normal impulses plus the position corrections' pushes, a push of λ (kg·m) counting
//!   as the impulse λ / h. A contact's face is the one its normal points at in the body frame (the
//!   larger of the forward and sideways components wins; exact diagonals go to front/rear); a
//!   robot resting against a wall without pushing does not hold its switch. A pressed switch
//!   releases only when its face carries less than `bumper_release_force_n` (default 0.02 N: a
//!   snap-action micro-switch's release force, far below its operating force; Omron D2F data
//!   sheet). A press is a force, so it does not depend on the sub-step's length. Without the
//!   threshold and the hysteresis, a robot rubbing lightly along a wall, its turning corner
//!   corrected out of a sub-micrometre overlap in every second sub-step, would read pressed,
//!   released, pressed… and count a collision every 40 ms (`tests/bumper_rub.rs`).
//! - **Sensors** (docs/design.md §3.1): by default four, at the middle of the front, rear, left and right
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
//! - **Threads**: [`World::advance_states_par`] runs the per-robot phases (motors, free
//!   motion, candidate search, contact search) on rayon's pool in fixed chunks merged in index
//!   order; the contact solve runs island by island, islands in parallel (each island's solve
//!   reads and writes only its own robots and contacts). Results are bit-identical to
//!   [`World::advance_states`] whatever the thread count.
//! - **Corridor metric**: [`World::corridor_gaps_m`] gives the free gaps between neighbouring
//!   robots along the corridor (sorted by centre x; gap = shortest distance between the two
//!   outlines, which for robots facing along the corridor is face to face; the gaps to the end
//!   walls are excluded); [`World::corridor_gap_cv`] their coefficient of variation
//!   (population standard deviation / mean).

#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod arena;
mod body;
mod contact;
pub mod dc_motor;
pub mod error;
pub mod geometry;
mod grid;
pub mod motor;
pub mod params;
mod pipeline;
mod placement;
mod world;

pub use arena::{Arena, ArenaKind, Segment};
pub use error::WorldError;
pub use motor::{Behaviour, Direction, WheelCommand};
pub use params::{SensorMount, WorldParams};
pub use pipeline::broad_phase::BROAD_PHASE_MARGIN_M;
pub use pipeline::par::PAR_STAGE_ROBOTS;
pub use pipeline::solver::CONTACT_SKIN_M;
pub use world::{
    FRONT, LEFT, MAX_ROBOTS, Pose, REAR, RIGHT, SolverStats, SubstepPlan, World,
    coefficient_of_variation,
};
