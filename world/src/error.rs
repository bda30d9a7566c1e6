//! Errors returned by the world for bad parameters, bad indices and impossible placements.

use thiserror::Error;

/// Everything a caller can get wrong when building or driving a [`crate::World`].
///
/// Every message says what was wrong, where, and what would be valid.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum WorldError {
    /// A time constant (motor lag, braking or coasting) outside its valid range.
    #[error("{name} = {value_s} s is outside the valid range {min_s}..={max_s} s")]
    TimeConstant {
        /// Which parameter (`motor_time_constant_s`, ...).
        name: &'static str,
        /// The value given, in seconds.
        value_s: f64,
        /// Smallest valid value, in seconds.
        min_s: f64,
        /// Largest valid value, in seconds.
        max_s: f64,
    },
    /// The top wheel speed is not a positive number within the physical limit.
    #[error(
        "top speed {value_m_per_s} m/s is invalid: it must be a number > 0 and <= {max_m_per_s} m/s"
    )]
    TopSpeed {
        /// The value given, in m/s.
        value_m_per_s: f64,
        /// Largest accepted top speed, in m/s.
        max_m_per_s: f64,
    },
    /// A time step that is not a positive finite number within the per-call limit.
    #[error("time step dt = {value_s} s is invalid: it must be a number > 0 and <= {max_s} s")]
    TimeStep {
        /// The value given, in seconds.
        value_s: f64,
        /// Largest accepted step for one call, in seconds.
        max_s: f64,
    },
    /// A robot index at or beyond the number of robots.
    #[error("robot index {index} is out of range: this world has {count} robots (0..{count})")]
    RobotIndex {
        /// The index given.
        index: usize,
        /// Number of robots in the world.
        count: usize,
    },
    /// A PWM duty that is not a number in [0, 1].
    #[error("{wheel} wheel duty {value} is invalid: it must be a number in 0..=1")]
    Duty {
        /// `"left"` or `"right"`.
        wheel: &'static str,
        /// The value given.
        value: f64,
    },
    /// A sensor index at or beyond the number of configured sensor mounts.
    #[error(
        "unknown sensor {index}: robots carry {count} sensors (0..{count}: front, rear, left, right for the default mounts)"
    )]
    UnknownSensor {
        /// The index given.
        index: usize,
        /// Number of configured sensors.
        count: usize,
    },
    /// Any other parameter outside its valid range.
    #[error("parameter {name} = {value} is invalid: {valid}")]
    Parameter {
        /// Which parameter.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What would be valid.
        valid: &'static str,
    },
    /// More robots than the arena can hold at the placement clearance.
    #[error(
        "{requested} robots do not fit in the {arena}: at most {max_fit} fit at a clearance of {clearance_m} m"
    )]
    TooManyRobots {
        /// Robots asked for.
        requested: usize,
        /// Upper bound on how many fit.
        max_fit: usize,
        /// A short description of the arena.
        arena: String,
        /// The placement clearance, in metres.
        clearance_m: f64,
    },
    /// Random placement gave up after its bounded number of attempts.
    #[error(
        "placed only {placed} of {requested} robots in the {arena} after {attempts} random attempts \
         (area bound {max_fit} robots at a clearance of {clearance_m} m; random placement jams at about \
         half of that): use fewer robots, a larger arena or a smaller clearance"
    )]
    PlacementFailed {
        /// Robots placed before giving up.
        placed: usize,
        /// Robots asked for.
        requested: usize,
        /// Attempts made in total.
        attempts: u64,
        /// Area upper bound on how many fit.
        max_fit: usize,
        /// A short description of the arena.
        arena: String,
        /// The placement clearance, in metres.
        clearance_m: f64,
    },
    /// A given pose puts a robot's body (partly) outside the arena walls.
    #[error(
        "robot {robot} at ({x_m} m, {y_m} m) with heading {heading_rad} rad is not inside the {width_m} m x {height_m} m arena"
    )]
    PoseOutsideArena {
        /// The robot.
        robot: usize,
        /// Its x, in metres.
        x_m: f64,
        /// Its y, in metres.
        y_m: f64,
        /// Its heading, in radians.
        heading_rad: f64,
        /// Arena width (x), in metres.
        width_m: f64,
        /// Arena height (y), in metres.
        height_m: f64,
    },
    /// Two given poses make two bodies overlap.
    #[error("robots {a} and {b} overlap by {depth_m} m at the given poses")]
    PosesOverlap {
        /// The lower robot index.
        a: usize,
        /// The higher robot index.
        b: usize,
        /// Penetration depth, in metres.
        depth_m: f64,
    },
    /// The number of poses given does not match the number of robots.
    #[error("{given} poses given for {expected} robots")]
    PoseCount {
        /// Poses given.
        given: usize,
        /// Robots expected.
        expected: usize,
    },
    /// A query that only makes sense in the corridor was made in another arena.
    #[error("{what} is defined for the corridor arena only, this world has a {arena}")]
    NotACorridor {
        /// The query.
        what: &'static str,
        /// A short description of the arena.
        arena: String,
    },
}
