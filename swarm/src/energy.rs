//! The robot's charge meter: what each part draws from the battery pack, from what the pins and
//! the world say it did, and how long the paper's pack lasts at that.
//!
//! Every part hangs on the pack through a linear stage (the 5 V regulator for the logic, the
//! TA7291P's reference-controlled output for the motors), so the pack supplies each part's own
//! current and the pack's current is their sum; energy is that charge at the pack's nominal
//! voltage. The parts and where their figures come from (`docs/energy-and-stack.md` has the
//! whole account):
//! - the H8/3052F: its running current over the states the CPU is busy, its sleep current over
//!   the rest, and the A/D converter's analog and reference currents over the states it
//!   converts ([`h8_3052f::power`]);
//! - the four GP2D12 IR sensors: their supply current all the time ([`sensors::SUPPLY_CURRENT_MA`]);
//! - the two 24LC256: standby all the time, a charge per SCL clock they take part in, their
//!   write current through every write cycle ([`eeprom::DeviceStats::charge_since_uc`]);
//! - the 5 V regulator's quiescent current ([`REGULATOR_QUIESCENT_MA`]);
//! - the two TA7291P bridges: their supply current in the mode their inputs select
//!   ([`robot_board::wiring::Bridge::supply_current_ma`]);
//! - the two FA-130 motors: the DC motor model of [`world::dc_motor`], from the PWM duty, the
//!   direction, the world's wheel speed and the force the wheel transmitted to the floor, sub-step
//!   by sub-step: a free robot at a steady speed draws the no-load current, one spinning its
//!   wheels up more, and a robot pressed against a wall (its wheels slipping at the floor's
//!   traction) the current that holds the slipping wheel's friction torque.

use h8_3052f::mcu::Mcu;
use h8_3052f::pins::Board;
use h8300h::bus::Bus;
use robot_board::board::RobotBoard;
use robot_board::wiring::Bridge;
use serde::Serialize;
use world::dc_motor::DcMotor;
use world::{Direction, WheelCommand, WorldParams};

/// Cells in the paper's pack: ten (paper §2: "ten 1.2 V nickel hydrogen batteries").
pub const PAPER_CELLS: u32 = 10;
/// Nominal cell voltage, 1.2 V (paper §2).
pub const CELL_VOLTS: f64 = 1.2;
/// How long the paper's robot runs on its pack: "up to 3.5 hours" (paper §2).
pub const PAPER_BATTERY_LIFE_H: f64 = 3.5;
/// Default capacity of a cell, 2 000 mAh: the typical capacity of the AA nickel-metal hydride
/// cell most sold in 2006–2008, Sanyo's eneloop HR-3UTG (data sheet: 2 000 mAh typical,
/// 1 900 mAh minimum); high-capacity AA cells of the time gave 2 500–2 700 mAh.
pub const DEFAULT_CAPACITY_MAH: f64 = 2_000.0;
/// Quiescent current of the 5 V linear regulator that feeds the logic from the pack, 5 mA
/// (a 7805-class regulator: Fairchild LM7805 / MC78xx data sheet, "quiescent current I_Q",
/// 5.0 mA typical, 8.0 mA maximum). The paper names no regulator: an assumption.
pub const REGULATOR_QUIESCENT_MA: f64 = 5.0;
/// IR sensors on the robot: four (paper §2).
pub const IR_SENSORS: f64 = 4.0;

/// The battery pack: cells in series and their capacity.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Pack {
    /// Cells in series.
    pub cells: u32,
    /// Nominal voltage of a cell, V.
    pub cell_volts: f64,
    /// Capacity, mAh.
    pub capacity_mah: f64,
}

impl Pack {
    /// The paper's pack (ten 1.2 V cells) with cells of `capacity_mah`.
    #[must_use]
    pub const fn paper(capacity_mah: f64) -> Pack {
        Pack {
            cells: PAPER_CELLS,
            cell_volts: CELL_VOLTS,
            capacity_mah,
        }
    }

    /// Nominal voltage, V.
    #[must_use]
    pub fn volts(&self) -> f64 {
        f64::from(self.cells) * self.cell_volts
    }

    /// Hours the pack lasts at a mean current of `current_ma`.
    #[must_use]
    pub fn life_h(&self, current_ma: f64) -> f64 {
        self.capacity_mah / current_ma
    }

    /// The capacity, mAh, that lasts `hours` at `current_ma`.
    #[must_use]
    pub fn capacity_for_h(current_ma: f64, hours: f64) -> f64 {
        current_ma * hours
    }

    /// Energy, mJ, of `charge_uc` at the pack's nominal voltage.
    #[must_use]
    pub fn energy_mj(&self, charge_uc: f64) -> f64 {
        charge_uc * self.volts() * 1e-3
    }
}

impl Default for Pack {
    fn default() -> Self {
        Pack::paper(DEFAULT_CAPACITY_MAH)
    }
}

/// The parts the meter counts, in report order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// The H8/3052F's VCC: running and asleep.
    Mcu,
    /// Its A/D converter's analog and reference supplies while it converts.
    AdConverter,
    /// The four GP2D12.
    IrSensors,
    /// The two 24LC256.
    Eeproms,
    /// The 5 V regulator's own current.
    Regulator,
    /// The two TA7291P's own supply.
    Bridges,
    /// The two FA-130 through their bridges.
    Motors,
}

impl Part {
    /// Every part, in report order.
    pub const ALL: [Part; 7] = [
        Part::Mcu,
        Part::AdConverter,
        Part::IrSensors,
        Part::Eeproms,
        Part::Regulator,
        Part::Bridges,
        Part::Motors,
    ];

    /// The part in reports.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Part::Mcu => "H8/3052F (running and asleep)",
            Part::AdConverter => "A/D converter (converting)",
            Part::IrSensors => "IR sensors (4 x GP2D12)",
            Part::Eeproms => "EEPROMs (2 x 24LC256)",
            Part::Regulator => "5 V regulator",
            Part::Bridges => "H-bridges (2 x TA7291P)",
            Part::Motors => "motors (2 x FA-130)",
        }
    }

    /// A short key for machines.
    #[must_use]
    pub const fn key(self) -> &'static str {
        match self {
            Part::Mcu => "mcu",
            Part::AdConverter => "adc",
            Part::IrSensors => "ir_sensors",
            Part::Eeproms => "eeproms",
            Part::Regulator => "regulator",
            Part::Bridges => "bridges",
            Part::Motors => "motors",
        }
    }
}

/// Charge drawn from the pack by part, µC.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Charge {
    /// By [`Part`], in [`Part::ALL`]'s order.
    pub by_part_uc: [f64; 7],
}

impl Charge {
    /// The charge of one part.
    #[must_use]
    pub fn of(&self, part: Part) -> f64 {
        self.by_part_uc[part as usize]
    }

    /// Adds `uc` to `part`.
    pub fn add_to(&mut self, part: Part, uc: f64) {
        self.by_part_uc[part as usize] += uc;
    }

    /// Adds every part of `other`.
    pub fn add(&mut self, other: &Charge) {
        for (a, b) in self.by_part_uc.iter_mut().zip(other.by_part_uc) {
            *a += b;
        }
    }

    /// The sum over the parts, µC.
    #[must_use]
    pub fn total_uc(&self) -> f64 {
        self.by_part_uc.iter().sum()
    }
}

/// Each EEPROM's counters on `mcu`'s board (0x50, then 0x51).
fn eeprom_stats<W: Board>(mcu: &Mcu<RobotBoard<W>>) -> Vec<eeprom::DeviceStats> {
    let chips = mcu.board().eeproms().devices();
    chips.iter().map(|d| d.stats()).collect()
}

/// The electronics of one robot (the MCU, its A/D converter, the IR sensors, the EEPROMs, the
/// regulator), metered from the MCU's own counters between two calls.
#[derive(Clone, Debug)]
pub struct ElectronicsMeter {
    last_states: u64,
    last_converting: u64,
    last_eeproms: Vec<eeprom::DeviceStats>,
}

impl ElectronicsMeter {
    /// A meter that counts from `mcu`'s present state (the chip's counters, the EEPROMs' on
    /// its board).
    #[must_use]
    pub fn new<W: Board>(mcu: &Mcu<RobotBoard<W>>) -> Self {
        let now = mcu.now();
        ElectronicsMeter {
            last_states: now,
            last_converting: mcu.adc().converting_states(now),
            last_eeproms: eeprom_stats(mcu),
        }
    }

    /// The charge since the last call (or since [`Self::new`]), of which the CPU was busy for
    /// `busy_states`.
    pub fn take<W: Board>(&mut self, mcu: &Mcu<RobotBoard<W>>, busy_states: u64) -> Charge {
        let now = mcu.now();
        let clock_hz = mcu.clock_hz();
        let interval = now.saturating_sub(self.last_states);
        let converting = mcu.adc().converting_states(now);
        let q = h8_3052f::power::mcu_charge_uc(
            interval,
            busy_states,
            converting.saturating_sub(self.last_converting),
            clock_hz,
        );
        let mut c = Charge::default();
        c.add_to(Part::Mcu, q.core_uc);
        c.add_to(Part::AdConverter, q.adc_uc);
        let seconds = interval as f64 / f64::from(clock_hz.max(1));
        c.add_to(
            Part::IrSensors,
            IR_SENSORS * sensors::SUPPLY_CURRENT_MA * seconds * 1e3,
        );
        c.add_to(Part::Regulator, REGULATOR_QUIESCENT_MA * seconds * 1e3);
        let chips = mcu.board().eeproms().devices();
        let eeproms: f64 = chips
            .iter()
            .zip(&self.last_eeproms)
            .map(|(d, before)| d.stats().charge_since_uc(before, interval, clock_hz))
            .sum();
        c.add_to(Part::Eeproms, eeproms);
        self.last_states = now;
        self.last_converting = converting;
        // The counters kept in place: a take allocates nothing (it runs once per robot-step).
        if self.last_eeproms.len() == chips.len() {
            for (last, d) in self.last_eeproms.iter_mut().zip(chips) {
                *last = d.stats();
            }
        } else {
            self.last_eeproms = eeprom_stats(mcu);
        }
        c
    }
}

/// How often the motors' current met the drive voltage's bound ([`world::dc_motor::MotorCurrent`]):
/// counted over wheel-sub-steps in which a motor was driven (forward or reverse).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct CurrentCap {
    /// Wheel-sub-steps with the motor driven.
    pub driven_wheel_substeps: u64,
    /// Of those, the ones whose torque asked for more current than the drive voltage allows,
    /// cut to it.
    pub capped_wheel_substeps: u64,
}

impl CurrentCap {
    /// Adds `other`'s counts.
    pub fn add(&mut self, other: CurrentCap) {
        self.driven_wheel_substeps += other.driven_wheel_substeps;
        self.capped_wheel_substeps += other.capped_wheel_substeps;
    }
}

/// What one wheel's motor and bridge draw from the pack in a sub-step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WheelDraw {
    /// The motor's share of the pack current (the PWM duty × its current), A.
    pub motor_a: f64,
    /// The bridge's supply current, A.
    pub bridge_a: f64,
    /// Whether the motor was driven (forward or reverse).
    pub driven: bool,
    /// Whether the drive voltage's bound cut the motor's current.
    pub capped: bool,
}

/// One robot's motors and their bridges, metered sub-step by sub-step from the wheel commands,
/// the world's wheel speeds and the forces the wheels transmitted to the floor.
#[derive(Clone, Debug)]
pub struct DriveMeter {
    motor: DcMotor,
    top_speed_m_per_s: f64,
    gains: [f64; 2],
    commands: [WheelCommand; 2],
    charge: Charge,
    cap: CurrentCap,
}

impl DriveMeter {
    /// Motors whose full duty runs the wheels free at `top_speed_m_per_s` times their `gains`
    /// (left, right: the world's motor gains), both coasting.
    #[must_use]
    pub fn new(top_speed_m_per_s: f64, gains: [f64; 2]) -> Self {
        DriveMeter {
            motor: DcMotor::fa130(top_speed_m_per_s),
            top_speed_m_per_s,
            gains,
            commands: [WheelCommand::coast(); 2],
            charge: Charge::default(),
            cap: CurrentCap::default(),
        }
    }

    /// The same meter with another motor model (a gearbox of another efficiency).
    #[must_use]
    pub fn with_motor(self, motor: DcMotor) -> Self {
        DriveMeter { motor, ..self }
    }

    /// The commands the bridges get from now on (left, right).
    pub fn set_commands(&mut self, left: WheelCommand, right: WheelCommand) {
        self.commands = [left, right];
    }

    /// What one wheel's motor and bridge draw with the wheel turning at `speed_m_per_s` (the
    /// world's mean wheel speed over the sub-step, signed along the robot's heading) and
    /// transmitting `force_n` between the floor and the body (N, signed along the heading: the
    /// world's `wheel_forces`).
    #[must_use]
    pub fn draw(&self, wheel: usize, speed_m_per_s: f64, force_n: f64) -> WheelDraw {
        let c = self.commands[wheel & 1];
        let bridge_a = bridge_of(c.direction).supply_current_ma() * 1e-3;
        let sign = match c.direction {
            Direction::Forward => 1.0,
            Direction::Reverse => -1.0,
            Direction::Brake | Direction::Coast => {
                return WheelDraw {
                    motor_a: 0.0,
                    bridge_a,
                    driven: false,
                    capped: false,
                };
            }
        };
        let target = c.duty * self.top_speed_m_per_s * self.gains[wheel & 1];
        let ratio = if target > 0.0 {
            sign * speed_m_per_s / target
        } else {
            0.0
        };
        let m = self.motor.current(c.duty, ratio, sign * force_n);
        WheelDraw {
            motor_a: c.duty.clamp(0.0, 1.0) * m.motor_a,
            bridge_a,
            driven: true,
            capped: m.capped,
        }
    }

    /// Adds a sub-step of `dt_s` seconds in which the wheels (left, right) turned at
    /// `speeds_m_per_s` and transmitted `forces_n` (both signed along the heading; the world's
    /// `wheel_mean_speeds` and `wheel_forces`).
    pub fn add_substep(&mut self, dt_s: f64, speeds_m_per_s: [f64; 2], forces_n: [f64; 2]) {
        for w in 0..2 {
            let d = self.draw(w, speeds_m_per_s[w], forces_n[w]);
            self.charge.add_to(Part::Motors, d.motor_a * dt_s * 1e6);
            self.charge.add_to(Part::Bridges, d.bridge_a * dt_s * 1e6);
            self.cap.driven_wheel_substeps += u64::from(d.driven);
            self.cap.capped_wheel_substeps += u64::from(d.capped);
        }
    }

    /// The motors' and bridges' charge since the last call.
    pub fn take(&mut self) -> Charge {
        std::mem::take(&mut self.charge)
    }

    /// How often the drive voltage's bound cut a motor's current, since the meter was made.
    #[must_use]
    pub fn cap(&self) -> CurrentCap {
        self.cap
    }
}

/// The bridge mode of a wheel command.
const fn bridge_of(d: Direction) -> Bridge {
    match d {
        Direction::Forward => Bridge::Forward,
        Direction::Reverse => Bridge::Reverse,
        Direction::Brake => Bridge::Brake,
        Direction::Coast => Bridge::Coast,
    }
}

/// Wheels of a robot alone on the floor, for a meter where there is no world (the fit): each
/// follows its command's speed with the world's first-order lag, and the floor gives the wheels
/// what the world would give them, free ([`WorldParams::free_wheel_forces_n`]: the body's
/// acceleration) or pressed against a wall the whole time (the body still: each turning wheel
/// slips at its traction against its turning).
#[derive(Clone, Debug)]
pub struct FreeWheels {
    speeds_m_per_s: [f64; 2],
    /// The mean speeds of the previous sub-step (the body's speeds, free), m/s.
    means_m_per_s: [f64; 2],
    params: WorldParams,
}

impl FreeWheels {
    /// Wheels at rest on a robot of `params` (its top speed, drive lag, mass, inertia, wheel
    /// track and traction).
    #[must_use]
    pub fn new(params: &WorldParams) -> Self {
        FreeWheels {
            speeds_m_per_s: [0.0; 2],
            means_m_per_s: [0.0; 2],
            params: params.clone(),
        }
    }

    /// Runs `meter` for `seconds` under its commands, in sub-steps of at most `substep_s`,
    /// with the wheels free (`held`: false) or pressed against a wall (`held`: true).
    pub fn run(&mut self, meter: &mut DriveMeter, seconds: f64, substep_s: f64, held: bool) {
        let n = (seconds / substep_s).ceil().max(1.0);
        let dt = seconds / n;
        let tau_s = self.params.motor_time_constant_s;
        let top = self.params.top_speed_m_per_s;
        let decay = libm::exp(-dt / tau_s);
        let mean_factor = tau_s / dt * (1.0 - decay);
        let traction = self.params.wheel_traction_n();
        let inv_track = 1.0 / self.params.wheel_track_m;
        for _ in 0..n as u64 {
            let mut mean = [0.0; 2];
            for (w, m) in mean.iter_mut().enumerate() {
                let c = meter.commands[w];
                let target = match c.direction {
                    Direction::Forward => c.duty * top,
                    Direction::Reverse => -c.duty * top,
                    Direction::Brake | Direction::Coast => 0.0,
                };
                let v0 = self.speeds_m_per_s[w];
                *m = target + (v0 - target) * mean_factor;
                self.speeds_m_per_s[w] = target + (v0 - target) * decay;
            }
            let forces = if held {
                // The body does not move: each wheel slips at its own speed, and the floor's
                // friction pushes against the slip.
                mean.map(|v| if v == 0.0 { 0.0 } else { traction.copysign(v) })
            } else {
                let (p, q) = (self.means_m_per_s, mean);
                self.params.free_wheel_forces_n(
                    0.5 * (q[0] + q[1]) - 0.5 * (p[0] + p[1]),
                    ((q[1] - q[0]) - (p[1] - p[0])) * inv_track,
                    dt,
                )
            };
            self.means_m_per_s = mean;
            meter.add_substep(dt, mean, forces);
        }
    }
}

/// Mean current, mA, of `charge_uc` over `seconds`.
#[must_use]
pub fn mean_current_ma(charge_uc: f64, seconds: f64) -> f64 {
    if seconds > 0.0 {
        charge_uc / seconds * 1e-3
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One drive wheel's traction with the world's defaults, μ_floor · m·g/2 = 1.4710 N.
    fn traction_n() -> f64 {
        WorldParams::with_clock(u64::from(robot_board::board::CLOCK_HZ)).wheel_traction_n()
    }

    #[test]
    fn a_full_duty_robot_pressed_against_a_wall_draws_the_friction_limited_current() {
        let mut d = DriveMeter::new(0.15, [1.0, 1.0]);
        d.set_commands(WheelCommand::forward(1.0), WheelCommand::forward(1.0));
        // One second pressed against a wall: the wheels slip at their commanded speed, each
        // pushing with its traction.
        let f = traction_n();
        d.add_substep(1.0, [0.15, 0.15], [f, f]);
        let q = d.take();
        // By hand, a motor: I₀ + F·r / (G·η·Kt) = 0.2 + 1.4710 × 0.028 / (203.7 × 0.6561 ×
        // 1.8629e-3) = 0.2 + 0.1654 A; the pack gives it at full duty. Two motors for 1 s:
        // 0.7308 C, not the stall's 6.36 C.
        let m = DcMotor::fa130(0.15);
        let per_motor = 0.2 + f * 0.028 / (203.7 * GEARBOX * m.ke_v_s_per_rad);
        assert!(
            (q.of(Part::Motors) - 2.0 * per_motor * 1e6).abs() < 1e-6,
            "{q:?}"
        );
        assert!((q.of(Part::Motors) - 0.7308e6).abs() < 0.0005e6, "{q:?}");
        assert!((q.of(Part::Bridges) - 16_000.0).abs() < 1e-9);
        // Reversing into a wall: speeds and forces backwards, the same.
        d.set_commands(WheelCommand::reverse(1.0), WheelCommand::reverse(1.0));
        d.add_substep(1.0, [-0.15, -0.15], [-f, -f]);
        assert!((d.take().of(Part::Motors) - 2.0 * per_motor * 1e6).abs() < 1e-6);
        assert_eq!(
            d.cap(),
            CurrentCap {
                driven_wheel_substeps: 4,
                capped_wheel_substeps: 0
            }
        );
    }

    const GEARBOX: f64 = world::dc_motor::GEARBOX_EFFICIENCY;

    #[test]
    fn a_free_robot_at_a_constant_speed_draws_the_no_load_current() {
        let mut d = DriveMeter::new(0.15, [1.0, 1.0]);
        d.set_commands(WheelCommand::forward(1.0), WheelCommand::forward(0.3));
        // At their commanded speeds, no force from the floor: I₀ each, the pack 1 × 0.2 A and
        // 0.3 × 0.2 A.
        d.add_substep(1.0, [0.15, 0.045], [0.0, 0.0]);
        let q = d.take();
        assert!((q.of(Part::Motors) - 0.26e6).abs() < 1e-6, "{q:?}");
        assert!((q.of(Part::Bridges) - 16_000.0).abs() < 1e-9);
        // Backward, free: the same; braking and coasting: no motor current, the bridges'
        // own (8 mA driving, 6.5 mA braking, 0 coasting).
        d.set_commands(WheelCommand::reverse(1.0), WheelCommand::brake());
        d.add_substep(1.0, [-0.15, 0.0], [0.0, 0.5]);
        let q = d.take();
        assert!((q.of(Part::Motors) - 0.2e6).abs() < 1e-6);
        assert!((q.of(Part::Bridges) - (8.0 + 6.5) * 1e3).abs() < 1e-9);
        d.set_commands(WheelCommand::coast(), WheelCommand::coast());
        d.add_substep(1.0, [0.1, 0.1], [-0.5, -0.5]);
        assert_eq!(d.take().total_uc(), 0.0);
        // A wheel slowing to a lower command while the floor brakes the robot: nothing back.
        d.set_commands(WheelCommand::forward(0.3), WheelCommand::forward(0.3));
        d.add_substep(1.0, [0.1, 0.1], [-0.3, -0.3]);
        assert_eq!(d.take().of(Part::Motors), 0.0);
    }

    #[test]
    fn the_pack_and_its_life() {
        let p = Pack::default();
        assert_eq!(p.volts(), 12.0);
        assert_eq!(p.life_h(500.0), 4.0);
        assert_eq!(Pack::capacity_for_h(600.0, 3.5), 2100.0);
        assert!((p.energy_mj(1000.0) - 12.0).abs() < 1e-12);
        assert_eq!(mean_current_ma(450_000.0, 1.0), 450.0);
    }

    #[test]
    fn free_wheels_settle_to_the_no_load_current_and_held_ones_to_the_friction_current() {
        let params = WorldParams {
            motor_gain_spread: 0.0,
            ..WorldParams::with_clock(u64::from(robot_board::board::CLOCK_HZ))
        };
        let mut d = DriveMeter::new(0.15, [1.0, 1.0]);
        d.set_commands(WheelCommand::forward(1.0), WheelCommand::forward(0.3));
        let mut w = FreeWheels::new(&params);
        // Starting from rest: the first 0.45 s carry the surge of spinning the rotors up.
        w.run(&mut d, 0.45, 0.01, false);
        let first = d.take().of(Part::Motors);
        w.run(&mut d, 0.45, 0.01, false);
        let settled = d.take().of(Part::Motors);
        assert!(first > settled);
        // Settled: 0.2 A at full duty, 0.3 × 0.2 A at 30 %, for 0.45 s.
        let want = (0.2 + 0.3 * 0.2) * 0.45 * 1e6;
        assert!((settled - want).abs() / want < 1e-3, "{settled} vs {want}");
        // Pressed against a wall the whole time, settled: each motor carries its slipping
        // wheel's friction, 0.3654 A; the pack 1 × and 0.3 × that.
        let mut held = DriveMeter::new(0.15, [1.0, 1.0]);
        held.set_commands(WheelCommand::forward(1.0), WheelCommand::forward(0.3));
        let mut w = FreeWheels::new(&params);
        w.run(&mut held, 1.0, 0.01, true);
        let _ = held.take();
        w.run(&mut held, 1.0, 0.01, true);
        let q = held.take().of(Part::Motors);
        let want = 1.3 * 0.3654 * 1e6;
        assert!((q - want).abs() / want < 1e-3, "{q} vs {want}");
        // Once, the drive voltage's bound cut the current: the 30 % wheel's first 10 ms from
        // rest, when the world's lag spins it up to a mean 7.9 % of its free speed while it
        // pushes with its traction. The rotor then asks 0.3 · 3.18 − 0.0595 A, the load
        // 0.165 A more: above the 0.954 A stall current at 30 % duty.
        assert_eq!(
            held.cap(),
            CurrentCap {
                driven_wheel_substeps: 400,
                capped_wheel_substeps: 1
            }
        );
    }
}
