//! Physical parameters of the robots and the simulation, with their sources and valid ranges.

use crate::body::BodyConst;
use crate::error::WorldError;

/// Body length along the heading: 230 mm (docs/design.md §1, paper §4: robots of 230 × 180 × 130 mm).
pub const BODY_LENGTH_M: f64 = 0.230;
/// Body width across the heading: 180 mm (docs/design.md §1, paper §4).
pub const BODY_WIDTH_M: f64 = 0.180;
/// Default top wheel speed at 100 % duty: 0.15 m/s (docs/design.md §3.5; Tamiya 203:1 gearbox with 56 mm
/// wheels gives 0.14–0.18 m/s).
pub const TOP_SPEED_M_PER_S: f64 = 0.15;
/// Largest accepted top speed: 1 m/s (our limit, so a body cannot cross another in one
/// [`MAX_SUBSTEP_LIMIT_S`] sub-step; the real robot does about 0.15 m/s).
pub const MAX_TOP_SPEED_M_PER_S: f64 = 1.0;
/// Default motor time constant of the first-order wheel-speed lag: 60 ms (docs/design.md §3.5).
pub const MOTOR_TIME_CONSTANT_S: f64 = 0.060;
/// Shortest valid motor time constant: 20 ms (docs/design.md §3.5, range 20–100 ms).
pub const MOTOR_TIME_CONSTANT_MIN_S: f64 = 0.020;
/// Longest valid motor time constant: 100 ms (docs/design.md §3.5, range 20–100 ms).
pub const MOTOR_TIME_CONSTANT_MAX_S: f64 = 0.100;
/// Shortest accepted braking or coasting time constant: 5 ms (our limit).
pub const STOP_TIME_CONSTANT_MIN_S: f64 = 0.005;
/// Longest accepted braking or coasting time constant: 1 s (our limit).
pub const STOP_TIME_CONSTANT_MAX_S: f64 = 1.0;
/// Per-robot, per-wheel motor gain spread: ±5 % (docs/design.md §3.5).
pub const MOTOR_GAIN_SPREAD: f64 = 0.05;
/// Default wheel track (distance between the wheel contact lines): 160 mm. Our choice: the
/// paper gives no figure; two 56 mm Tamiya wheels about 20 mm wide sit inside the 180 mm body.
pub const WHEEL_TRACK_M: f64 = 0.160;
/// Default longest internal sub-step: 20 ms (our choice; longer `advance` calls are split).
pub const MAX_SUBSTEP_S: f64 = 0.020;
/// Smallest accepted `max_substep_s`: 10 µs (our limit, so an `advance` call stays bounded).
pub const MIN_SUBSTEP_S: f64 = 1e-5;
/// Largest accepted `max_substep_s`: 100 ms (our limit: at 1 m/s two robots close 0.2 m, about
/// the body width, so a longer sub-step could let bodies pass through each other).
pub const MAX_SUBSTEP_LIMIT_S: f64 = 0.100;
/// Largest time one `advance` call may cover: one hour (our limit, so a call always ends).
pub const MAX_ADVANCE_S: f64 = 3600.0;
/// Default sensor maximum range: 1.5 m (brief; the GP2Y0A21 is specified to 80 cm, beyond which
/// its curve keeps falling as 1/d, docs/design.md §3.1, so "farther than 1.5 m" reads as far).
pub const SENSOR_MAX_RANGE_M: f64 = 1.5;
/// Default placement clearance between bodies, and between bodies and walls: 50 mm (our choice).
pub const PLACEMENT_CLEARANCE_M: f64 = 0.050;
/// Default number of Gauss–Seidel sweeps of the velocity solver per sub-step (our choice):
/// the impulses of a contact cluster converge geometrically; 12 sweeps leave chains of up to
/// five bodies within a few per cent of the exact impulses, and what the velocities leave of an
/// overlap is removed by the position correction.
pub const SOLVER_ITERATIONS: u32 = 12;

/// Newton's method's cap of outer (impulse) iterations on an island ([`Convergence::Newton`]),
/// a safety net that is counted (`SolverStats::capped_islands`).
pub const NEWTON_MAX_OUTER: u32 = 64;

/// The largest island ([`Convergence::Newton`]) solved by Newton's method; larger ones are
/// solved by sweeps.
pub const NEWTON_MAX_ROBOTS: usize = 16;
/// Default number of position-correction sweeps over the overlaps the velocity solve leaves
/// (our choice): each sweep removes an overlap along its normal with rotation; a cluster that
/// is still not clear after them stops its robots' motion early (see the crate docs).
pub const POSITION_ITERATIONS: u32 = 16;
/// Standard gravity, m/s² (for the wheels' normal force).
pub const GRAVITY_M_PER_S2: f64 = 9.806_65;
/// Robot mass: 0.5 kg (docs/design.md §1, paper §2: without batteries, the only figure the paper gives).
pub const MASS_KG: f64 = 0.5;
/// Default tyre–floor friction coefficient: 0.6 (our choice: rubber on a hard floor is
/// 0.5–0.8). The traction of a blocked robot, μ·m·g ≈ 2.9 N, is far below what the 203:1
/// gear motors can exert at stall (several N per wheel), so a blocked robot's wheels slip.
pub const MU_FLOOR: f64 = 0.6;
/// Default body–body friction coefficient: 0.3 (our choice: plastic on plastic).
pub const MU_ROBOT: f64 = 0.3;
/// Default body–wall friction coefficient: 0.3 (our choice: plastic on a painted board).
pub const MU_WALL: f64 = 0.3;
/// Default force a bumper face's contacts must carry to press its micro-switch: 0.1 N (our
/// choice; a robot driving into an obstacle pushes with its whole traction, about 2.9 N, a
/// body merely resting against one with none).
pub const BUMPER_FORCE_N: f64 = 0.1;
/// Default force below which a pressed bumper's switch releases: 0.02 N. A snap-action
/// micro-switch releases at a much lower force than it operates (hysteresis): Omron's D2F-01FL
/// (hinge lever, low operating force) operates at 0.25 N max and releases at 0.02 N min, the
/// D2F-01 at 0.74 N / 0.05 N (Omron D2F datasheet, "Operating Characteristics"). We keep the
/// data sheet's release force with our lower operating force.
pub const BUMPER_RELEASE_FORCE_N: f64 = 0.02;
/// The clock the world's unit tests count in: the robot's φ, 25 MHz (docs/design.md §4.1).
/// The crate itself has no clock: [`WorldParams::with_clock`] takes the robots' MCU clock.
#[cfg(test)]
pub(crate) const TEST_CLOCK_HZ: u64 = 25_000_000;
/// Most rays a sensor cone may use (our limit).
pub const MAX_RAYS_PER_SENSOR: u32 = 16;
/// Widest accepted sensor cone half-angle: 0.5 rad (our limit; the Sharp beam is a few degrees).
pub const MAX_CONE_HALF_ANGLE_RAD: f64 = 0.5;

/// Where a sensor sits on the body and where it looks, in the body frame (x forward along the
/// heading, y to the robot's left, angle counter-clockwise from the heading).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorMount {
    /// Mount point, metres forward of the body centre.
    pub x_m: f64,
    /// Mount point, metres to the left of the body centre.
    pub y_m: f64,
    /// Viewing direction relative to the heading, radians counter-clockwise.
    pub angle_rad: f64,
}

impl SensorMount {
    /// The four default mounts (docs/design.md §3.1): middle of the front, rear, left and right sides,
    /// facing out, in that order (sensor indices 0, 1, 2, 3).
    pub fn default_mounts(body_length_m: f64, body_width_m: f64) -> Vec<SensorMount> {
        let hl = 0.5 * body_length_m;
        let hw = 0.5 * body_width_m;
        vec![
            SensorMount {
                x_m: hl,
                y_m: 0.0,
                angle_rad: 0.0,
            },
            SensorMount {
                x_m: -hl,
                y_m: 0.0,
                angle_rad: core::f64::consts::PI,
            },
            SensorMount {
                x_m: 0.0,
                y_m: hw,
                angle_rad: core::f64::consts::FRAC_PI_2,
            },
            SensorMount {
                x_m: 0.0,
                y_m: -hw,
                angle_rad: -core::f64::consts::FRAC_PI_2,
            },
        ]
    }
}

/// All parameters of the physical world. [`WorldParams::with_clock`] gives the design values,
/// time counted in the robots' MCU clock.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldParams {
    /// Body length along the heading, metres.
    pub body_length_m: f64,
    /// Body width across the heading, metres.
    pub body_width_m: f64,
    /// Wheel speed at 100 % duty for a motor of gain 1, m/s.
    pub top_speed_m_per_s: f64,
    /// Time constant of the wheel-speed lag while driven (forward/reverse), seconds (20–100 ms).
    pub motor_time_constant_s: f64,
    /// Time constant toward standstill while braking (H/H), seconds (5 ms–1 s).
    pub brake_time_constant_s: f64,
    /// Time constant toward standstill while coasting (L/L), seconds (5 ms–1 s).
    pub coast_time_constant_s: f64,
    /// Half-width of the uniform per-wheel motor gain spread (0.05 = gains in 0.95..=1.05).
    pub motor_gain_spread: f64,
    /// Distance between the two wheels' contact lines, metres.
    pub wheel_track_m: f64,
    /// Longest internal sub-step, seconds (rounded to whole clock states); a longer advance is
    /// split into equal sub-steps of whole states (lengths differing by at most one state).
    pub max_substep_s: f64,
    /// Sensor mounts; sensor index `k` is `sensor_mounts[k]`.
    pub sensor_mounts: Vec<SensorMount>,
    /// Rays per sensor, spread evenly over the cone (1 = a single ray on the axis).
    pub rays_per_sensor: u32,
    /// Half-angle of the sensor cone, radians (ignored with one ray).
    pub cone_half_angle_rad: f64,
    /// Farthest distance a sensor reports; beyond it `sense` returns `None`, metres.
    pub sensor_max_range_m: f64,
    /// Minimum gap between bodies, and between bodies and walls, at random placement, metres.
    pub placement_clearance_m: f64,
    /// Mass of a robot, kg.
    pub mass_kg: f64,
    /// Tyre–floor friction coefficient (traction limit of each drive wheel: μ·m·g/2).
    pub mu_floor: f64,
    /// Body–body friction coefficient.
    pub mu_robot: f64,
    /// Body–wall friction coefficient.
    pub mu_wall: f64,
    /// Force a bumper face's contacts must carry between them in a sub-step to press its
    /// switch (the operating force), N.
    pub bumper_force_n: f64,
    /// Force below which a pressed bumper releases, N (at most `bumper_force_n`).
    pub bumper_release_force_n: f64,
    /// Gauss–Seidel sweeps of the velocity solver per sub-step, at most.
    pub solver_iterations: u32,
    /// When a sub-step's velocity solve of an island stops before `solver_iterations`.
    pub solver_convergence: Convergence,
    /// Position-correction sweeps per sub-step.
    pub position_iterations: u32,
    /// The clock the world's time is counted in (MCU states per second): the world advances
    /// in whole states of the clock the robots' MCUs count.
    pub clock_hz: u64,
}

/// When an island's solve stops (before its cap of sweeps).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Convergence {
    /// When a sweep changes no impulse by more than 1e-6 N·s (the solver every published result
    /// was made with, under a cap of 12 sweeps).
    #[default]
    Impulse,
    /// When a sweep changes no robot's velocity by more than 2 µm/s (its turn rate counted at
    /// the body's half-diagonal): the answer the sweeps converge to, whether or not the
    /// impulses that give it are unique (a robot pushed by its wheels against another is
    /// statically indeterminate: the impulses can drift along a direction that moves nothing).
    Velocity,
    /// Islands of up to 16 robots solved by Newton's method on the whole island to its fixed
    /// point (every row's velocity error below 0.1 µm/s, at most 64 outer iterations); larger
    /// islands by sweeps converged by impulse under the sweep cap.
    Newton,
}

impl WorldParams {
    /// The design values, the world's time counted in states of the robots' MCU clock
    /// `clock_hz` (the robot's φ is the board's, docs/design.md §4.1; the world has none of its
    /// own).
    #[must_use]
    pub fn with_clock(clock_hz: u64) -> Self {
        WorldParams {
            body_length_m: BODY_LENGTH_M,
            body_width_m: BODY_WIDTH_M,
            top_speed_m_per_s: TOP_SPEED_M_PER_S,
            motor_time_constant_s: MOTOR_TIME_CONSTANT_S,
            brake_time_constant_s: MOTOR_TIME_CONSTANT_S,
            coast_time_constant_s: MOTOR_TIME_CONSTANT_S,
            motor_gain_spread: MOTOR_GAIN_SPREAD,
            wheel_track_m: WHEEL_TRACK_M,
            max_substep_s: MAX_SUBSTEP_S,
            sensor_mounts: SensorMount::default_mounts(BODY_LENGTH_M, BODY_WIDTH_M),
            rays_per_sensor: 1,
            cone_half_angle_rad: 0.0,
            sensor_max_range_m: SENSOR_MAX_RANGE_M,
            placement_clearance_m: PLACEMENT_CLEARANCE_M,
            mass_kg: MASS_KG,
            mu_floor: MU_FLOOR,
            mu_robot: MU_ROBOT,
            mu_wall: MU_WALL,
            bumper_force_n: BUMPER_FORCE_N,
            bumper_release_force_n: BUMPER_RELEASE_FORCE_N,
            solver_iterations: SOLVER_ITERATIONS,
            solver_convergence: Convergence::Impulse,
            position_iterations: POSITION_ITERATIONS,
            clock_hz,
        }
    }
}

fn check_range(
    name: &'static str,
    value: f64,
    min: f64,
    max: f64,
    valid: &'static str,
) -> Result<(), WorldError> {
    if value.is_nan() || value < min || value > max {
        Err(WorldError::Parameter { name, value, valid })
    } else {
        Ok(())
    }
}

fn check_time_constant(
    name: &'static str,
    value_s: f64,
    min_s: f64,
    max_s: f64,
) -> Result<(), WorldError> {
    if value_s.is_nan() || value_s < min_s || value_s > max_s {
        Err(WorldError::TimeConstant {
            name,
            value_s,
            min_s,
            max_s,
        })
    } else {
        Ok(())
    }
}

impl WorldParams {
    /// Checks every parameter; the error names the first bad one and its valid range.
    pub fn validate(&self) -> Result<(), WorldError> {
        self.check_body_and_drive()?;
        self.check_sensors()?;
        self.check_placement_and_contacts()?;
        self.check_clock()
    }

    /// The body's size, the motors, the wheels and the sub-step.
    fn check_body_and_drive(&self) -> Result<(), WorldError> {
        check_range(
            "body_length_m",
            self.body_length_m,
            0.01,
            10.0,
            "a length in 0.01..=10 m",
        )?;
        check_range(
            "body_width_m",
            self.body_width_m,
            0.01,
            10.0,
            "a width in 0.01..=10 m",
        )?;
        if self.top_speed_m_per_s.is_nan()
            || self.top_speed_m_per_s <= 0.0
            || self.top_speed_m_per_s > MAX_TOP_SPEED_M_PER_S
        {
            return Err(WorldError::TopSpeed {
                value_m_per_s: self.top_speed_m_per_s,
                max_m_per_s: MAX_TOP_SPEED_M_PER_S,
            });
        }
        check_time_constant(
            "motor_time_constant_s",
            self.motor_time_constant_s,
            MOTOR_TIME_CONSTANT_MIN_S,
            MOTOR_TIME_CONSTANT_MAX_S,
        )?;
        check_time_constant(
            "brake_time_constant_s",
            self.brake_time_constant_s,
            STOP_TIME_CONSTANT_MIN_S,
            STOP_TIME_CONSTANT_MAX_S,
        )?;
        check_time_constant(
            "coast_time_constant_s",
            self.coast_time_constant_s,
            STOP_TIME_CONSTANT_MIN_S,
            STOP_TIME_CONSTANT_MAX_S,
        )?;
        check_range(
            "motor_gain_spread",
            self.motor_gain_spread,
            0.0,
            0.5,
            "a fraction in 0..=0.5",
        )?;
        check_range(
            "wheel_track_m",
            self.wheel_track_m,
            0.01,
            10.0,
            "a distance in 0.01..=10 m",
        )?;
        check_range(
            "max_substep_s",
            self.max_substep_s,
            MIN_SUBSTEP_S,
            MAX_SUBSTEP_LIMIT_S,
            "a time in 0.00001..=0.1 s",
        )?;
        Ok(())
    }

    /// The sensor mounts (on or inside the body), their rays, cone and range.
    fn check_sensors(&self) -> Result<(), WorldError> {
        let hl = 0.5 * self.body_length_m;
        let hw = 0.5 * self.body_width_m;
        for m in &self.sensor_mounts {
            // The mount must lie on or inside the body outline (a small tolerance for rounding).
            check_range(
                "sensor mount x_m",
                m.x_m,
                -hl - 1e-12,
                hl + 1e-12,
                "a point on or inside the body: |x_m| <= body_length_m / 2",
            )?;
            check_range(
                "sensor mount y_m",
                m.y_m,
                -hw - 1e-12,
                hw + 1e-12,
                "a point on or inside the body: |y_m| <= body_width_m / 2",
            )?;
            check_range(
                "sensor mount angle_rad",
                m.angle_rad,
                -4.0 * core::f64::consts::PI,
                4.0 * core::f64::consts::PI,
                "an angle in -4π..=4π rad",
            )?;
        }
        if self.rays_per_sensor == 0 || self.rays_per_sensor > MAX_RAYS_PER_SENSOR {
            return Err(WorldError::Parameter {
                name: "rays_per_sensor",
                value: f64::from(self.rays_per_sensor),
                valid: "a count in 1..=16",
            });
        }
        check_range(
            "cone_half_angle_rad",
            self.cone_half_angle_rad,
            0.0,
            MAX_CONE_HALF_ANGLE_RAD,
            "an angle in 0..=0.5 rad",
        )?;
        check_range(
            "sensor_max_range_m",
            self.sensor_max_range_m,
            0.001,
            100.0,
            "a distance in 0.001..=100 m",
        )?;
        Ok(())
    }

    /// The placement clearance, the solver, the masses, frictions and bumper forces.
    fn check_placement_and_contacts(&self) -> Result<(), WorldError> {
        check_range(
            "placement_clearance_m",
            self.placement_clearance_m,
            0.0,
            10.0,
            "a distance in 0..=10 m",
        )?;
        for (name, v) in [
            ("solver_iterations", self.solver_iterations),
            ("position_iterations", self.position_iterations),
        ] {
            if v == 0 || v > 256 {
                return Err(WorldError::Parameter {
                    name,
                    value: f64::from(v),
                    valid: "a count in 1..=256",
                });
            }
        }
        check_range(
            "mass_kg",
            self.mass_kg,
            0.01,
            100.0,
            "a mass in 0.01..=100 kg",
        )?;
        check_range(
            "mu_floor",
            self.mu_floor,
            0.05,
            2.0,
            "a coefficient in 0.05..=2",
        )?;
        check_range(
            "mu_robot",
            self.mu_robot,
            0.0,
            2.0,
            "a coefficient in 0..=2",
        )?;
        check_range("mu_wall", self.mu_wall, 0.0, 2.0, "a coefficient in 0..=2")?;
        check_range(
            "bumper_force_n",
            self.bumper_force_n,
            0.0,
            100.0,
            "a force in 0..=100 N",
        )?;
        check_range(
            "bumper_release_force_n",
            self.bumper_release_force_n,
            0.0,
            self.bumper_force_n,
            "a force in 0..=bumper_force_n",
        )?;
        Ok(())
    }

    /// The clock, and that the sub-step is at least one of its states.
    fn check_clock(&self) -> Result<(), WorldError> {
        if self.clock_hz < 1_000 || self.clock_hz > 1_000_000_000 {
            return Err(WorldError::Parameter {
                name: "clock_hz",
                value: self.clock_hz as f64,
                valid: "a clock in 1 kHz..=1 GHz",
            });
        }
        if (self.max_substep_s * self.clock_hz as f64).round() < 1.0 {
            return Err(WorldError::Parameter {
                name: "max_substep_s",
                value: self.max_substep_s,
                valid: "at least one clock state",
            });
        }
        Ok(())
    }

    /// Largest longitudinal force one drive wheel takes from the floor, N: its traction,
    /// `μ_floor · m·g/2` (half the weight on each drive wheel). Past it the wheel slips.
    pub fn wheel_traction_n(&self) -> f64 {
        self.body().wheel_force_n
    }

    /// The longitudinal forces (left, right), N, along the heading, that a robot touching
    /// nothing takes from the floor when, over a sub-step of `h_s` seconds, its speed along its
    /// heading changes by `d_along_m_per_s` and its turn rate by `d_omega_rad_per_s`: the rigid
    /// body's m·Δv/h = F_l + F_r and I·Δω/h = (F_r − F_l)·track/2, each at most
    /// [`WorldParams::wheel_traction_n`]. What [`crate::World::wheel_forces`] gives a free
    /// robot, for a meter without a world.
    pub fn free_wheel_forces_n(
        &self,
        d_along_m_per_s: f64,
        d_omega_rad_per_s: f64,
        h_s: f64,
    ) -> [f64; 2] {
        self.body()
            .wheel_forces(d_along_m_per_s, d_omega_rad_per_s, 1.0 / h_s)
    }

    /// What every robot shares, from these parameters: size, mass, inertia, wheel geometry,
    /// traction (`μ_floor · m·g/2` per drive wheel) and friction.
    pub(crate) fn body(&self) -> BodyConst {
        BodyConst::new(
            self.mass_kg,
            self.body_length_m,
            self.body_width_m,
            self.wheel_track_m,
            self.mu_floor * self.mass_kg * GRAVITY_M_PER_S2 * 0.5,
            self.mu_robot,
            self.mu_wall,
        )
    }
}
