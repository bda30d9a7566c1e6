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
//!   converts ([`emu::chip::power`]);
//! - the four GP2D12 IR sensors: their supply current all the time ([`sensors::SUPPLY_CURRENT_MA`]);
//! - the two 24LC256: standby all the time, a charge per SCL clock they take part in, their
//!   write current through every write cycle ([`eeprom::DeviceStats::charge_since_uc`]);
//! - the 5 V regulator's quiescent current ([`REGULATOR_QUIESCENT_MA`]);
//! - the two TA7291P bridges: their supply current in the mode their inputs select
//!   ([`emu::board::wiring::Bridge::supply_current_ma`]);
//! - the two FA-130 motors: the DC motor model of [`world::dc_motor`], from the PWM duty, the
//!   direction and the wheel's speed over the ground as the world moved it, sub-step by
//!   sub-step, so a robot pressed against a wall (its wheels still while driven) draws its
//!   stall current.

use emu::board::wiring::Bridge;
use emu::chip::mcu::{Board, Mcu};
use emu::core::bus::Bus;
use serde::Serialize;
use world::dc_motor::DcMotor;
use world::{Direction, Pose, WheelCommand};

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

/// The electronics of one robot (the MCU, its A/D converter, the IR sensors, the EEPROMs, the
/// regulator), metered from the MCU's own counters between two calls.
#[derive(Clone, Debug)]
pub struct ElectronicsMeter {
    last_states: u64,
    last_converting: u64,
    last_eeproms: Vec<eeprom::DeviceStats>,
}

impl ElectronicsMeter {
    /// A meter that counts from `mcu`'s present state.
    #[must_use]
    pub fn new<B: Board>(mcu: &Mcu<B>) -> Self {
        let now = mcu.now();
        ElectronicsMeter {
            last_states: now,
            last_converting: mcu.adc().converting_states(now),
            last_eeproms: mcu.i2c().devices().iter().map(|d| d.stats()).collect(),
        }
    }

    /// The charge since the last call (or since [`Self::new`]), of which the CPU was busy for
    /// `busy_states`.
    pub fn take<B: Board>(&mut self, mcu: &Mcu<B>, busy_states: u64) -> Charge {
        let now = mcu.now();
        let clock_hz = mcu.clock_hz();
        let interval = now.saturating_sub(self.last_states);
        let converting = mcu.adc().converting_states(now);
        let q = emu::chip::power::mcu_charge_uc(
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
        let stats: Vec<eeprom::DeviceStats> =
            mcu.i2c().devices().iter().map(|d| d.stats()).collect();
        let eeproms: f64 = stats
            .iter()
            .zip(&self.last_eeproms)
            .map(|(s, before)| s.charge_since_uc(before, interval, clock_hz))
            .sum();
        c.add_to(Part::Eeproms, eeproms);
        self.last_states = now;
        self.last_converting = converting;
        self.last_eeproms = stats;
        c
    }
}

/// One robot's motors and their bridges, metered sub-step by sub-step from the wheel commands
/// and the wheels' speed over the ground.
#[derive(Clone, Debug)]
pub struct DriveMeter {
    motor: DcMotor,
    top_speed_m_per_s: f64,
    gains: [f64; 2],
    commands: [WheelCommand; 2],
    charge: Charge,
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
        }
    }

    /// The commands the bridges get from now on (left, right).
    pub fn set_commands(&mut self, left: WheelCommand, right: WheelCommand) {
        self.commands = [left, right];
    }

    /// The pack current of one wheel's motor and bridge, A, with the wheel at `ground_m_per_s`
    /// over the ground along the robot's heading.
    #[must_use]
    pub fn currents_a(&self, wheel: usize, ground_m_per_s: f64) -> (f64, f64) {
        let c = self.commands[wheel & 1];
        let bridge = bridge_of(c.direction).supply_current_ma() * 1e-3;
        let sign = match c.direction {
            Direction::Forward => 1.0,
            Direction::Reverse => -1.0,
            Direction::Brake | Direction::Coast => return (0.0, bridge),
        };
        let target = c.duty * self.top_speed_m_per_s * self.gains[wheel & 1];
        let ratio = if target > 0.0 {
            sign * ground_m_per_s / target
        } else {
            0.0
        };
        (self.motor.pack_current_a(c.duty, ratio), bridge)
    }

    /// Adds a sub-step of `dt_s` seconds in which the wheels (left, right) moved at
    /// `ground_m_per_s` over the ground along the heading.
    pub fn add_substep(&mut self, dt_s: f64, ground_m_per_s: [f64; 2]) {
        for (w, &v) in ground_m_per_s.iter().enumerate() {
            let (motor, bridge) = self.currents_a(w, v);
            self.charge.add_to(Part::Motors, motor * dt_s * 1e6);
            self.charge.add_to(Part::Bridges, bridge * dt_s * 1e6);
        }
    }

    /// The motors' and bridges' charge since the last call.
    pub fn take(&mut self) -> Charge {
        std::mem::take(&mut self.charge)
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

/// The wheels' mean speeds over the ground along the heading (left, right), m/s, of a body that
/// went from `before` to `after` in `dt_s`, its wheels `track_m` apart: the centre's
/// displacement along the mean heading, less (left) or plus (right) half the track times the
/// turn.
#[must_use]
pub fn ground_speeds(before: &Pose, after: &Pose, dt_s: f64, track_m: f64) -> [f64; 2] {
    if dt_s <= 0.0 {
        return [0.0; 2];
    }
    let mut turn = after.heading_rad - before.heading_rad;
    if turn > std::f64::consts::PI {
        turn -= std::f64::consts::TAU;
    } else if turn < -std::f64::consts::PI {
        turn += std::f64::consts::TAU;
    }
    let mid = before.heading_rad + turn / 2.0;
    let along = (after.x_m - before.x_m) * mid.cos() + (after.y_m - before.y_m) * mid.sin();
    let half = turn * track_m / 2.0;
    [(along - half) / dt_s, (along + half) / dt_s]
}

/// Wheels with no obstacle: each follows its command's speed with the world's first-order lag,
/// for a meter where there is no world (the fit).
#[derive(Clone, Debug)]
pub struct FreeWheels {
    speeds_m_per_s: [f64; 2],
    tau_s: f64,
    top_speed_m_per_s: f64,
}

impl FreeWheels {
    /// Wheels at rest, lag `tau_s`, full-duty speed `top_speed_m_per_s`.
    #[must_use]
    pub fn new(top_speed_m_per_s: f64, tau_s: f64) -> Self {
        FreeWheels {
            speeds_m_per_s: [0.0; 2],
            tau_s,
            top_speed_m_per_s,
        }
    }

    /// Runs `meter` for `seconds` under its commands, in sub-steps of at most `substep_s`,
    /// with the wheels free (`held`: false) or held still (a robot against a wall: true).
    pub fn run(&mut self, meter: &mut DriveMeter, seconds: f64, substep_s: f64, held: bool) {
        let n = (seconds / substep_s).ceil().max(1.0);
        let dt = seconds / n;
        let decay = (-dt / self.tau_s).exp();
        let mean_factor = self.tau_s / dt * (1.0 - decay);
        for _ in 0..n as u64 {
            let mut mean = [0.0; 2];
            for (w, m) in mean.iter_mut().enumerate() {
                let c = meter.commands[w];
                let target = match c.direction {
                    Direction::Forward => c.duty * self.top_speed_m_per_s,
                    Direction::Reverse => -c.duty * self.top_speed_m_per_s,
                    Direction::Brake | Direction::Coast => 0.0,
                };
                let v0 = self.speeds_m_per_s[w];
                *m = target + (v0 - target) * mean_factor;
                self.speeds_m_per_s[w] = target + (v0 - target) * decay;
            }
            meter.add_substep(dt, if held { [0.0; 2] } else { mean });
        }
    }
}

/// The battery life of one condition of a run: its first and last windows.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BatteryLine {
    /// The condition.
    pub condition: crate::robot::Condition,
    /// A robot's mean current over the first window, mA (over the repeats).
    pub first_current_ma: f64,
    /// Over the last window, mA.
    pub last_current_ma: f64,
    /// Hours the pack lasts at the first window's mean energy per step (the interval from the
    /// energy's).
    pub first_h: crate::summary::Estimate,
    /// At the last window's.
    pub last_h: crate::summary::Estimate,
}

/// What learning costs or saves in battery life against a control, in the last window.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BatteryComparison {
    /// The control.
    pub against: crate::robot::Condition,
    /// Learning's battery life less the control's, hours.
    pub change_h: f64,
    /// The same in percent of the control's.
    pub change_percent: f64,
    /// Whether the two energies' 95 % intervals are apart.
    pub apart: bool,
}

/// The battery life of a run's conditions for the paper's pack.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BatteryReport {
    /// The pack.
    pub pack: Pack,
    /// The paper's figure: "up to 3.5 hours".
    pub paper_h: f64,
    /// Per condition.
    pub conditions: Vec<BatteryLine>,
    /// Learning against each control present.
    pub learning_against: Vec<BatteryComparison>,
    /// A robot's mean current by part over each condition's whole runs, mA.
    pub by_part: Vec<ConditionParts>,
}

/// A robot's mean current by part over a condition's whole runs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConditionParts {
    /// The condition.
    pub condition: crate::robot::Condition,
    /// ([`Part::key`], mA) in [`Part::ALL`]'s order.
    pub current_ma: Vec<(&'static str, f64)>,
}

impl ConditionParts {
    /// The mean current by part of `runs` (one condition's), each `robot_seconds` long
    /// (robots × steps × step period).
    #[must_use]
    pub fn of(
        condition: crate::robot::Condition,
        runs: &[&crate::experiment::RunOutput],
        robot_seconds: f64,
    ) -> Self {
        let mut total = Charge::default();
        for r in runs {
            total.add(&r.energy);
        }
        let seconds = robot_seconds * runs.len() as f64;
        ConditionParts {
            condition,
            current_ma: Part::ALL
                .iter()
                .map(|&p| (p.key(), mean_current_ma(total.of(p), seconds)))
                .collect(),
        }
    }
}

impl BatteryReport {
    /// The battery life of each condition of `stats` for `pack`, steps of `step_period_s`.
    #[must_use]
    pub fn of(stats: &[crate::summary::ConditionStats], pack: Pack, step_period_s: f64) -> Self {
        use crate::summary::Estimate;
        // mJ per step → mA: mJ / V = mC, per second = mA.
        let ma = |mj: f64| mj / pack.volts() / step_period_s;
        let life = |e: &Estimate| -> Estimate {
            let h = |mj: f64| (mj > 0.0).then(|| pack.life_h(ma(mj)));
            Estimate {
                mean: h(e.mean).unwrap_or(f64::INFINITY),
                lo: e.hi.and_then(h),
                hi: e.lo.and_then(h),
                n: e.n,
            }
        };
        let conditions: Vec<BatteryLine> = stats
            .iter()
            .map(|c| BatteryLine {
                condition: c.condition,
                first_current_ma: ma(c.first.energy_per_robot_step_mj.mean),
                last_current_ma: ma(c.last.energy_per_robot_step_mj.mean),
                first_h: life(&c.first.energy_per_robot_step_mj),
                last_h: life(&c.last.energy_per_robot_step_mj),
            })
            .collect();
        let learning = stats
            .iter()
            .find(|c| c.condition == crate::robot::Condition::Learning);
        let learning_against = match learning {
            None => Vec::new(),
            Some(l) => stats
                .iter()
                .filter(|c| c.condition != crate::robot::Condition::Learning)
                .map(|c| {
                    let (hl, hc) = (
                        life(&l.last.energy_per_robot_step_mj).mean,
                        life(&c.last.energy_per_robot_step_mj).mean,
                    );
                    BatteryComparison {
                        against: c.condition,
                        change_h: hl - hc,
                        change_percent: (hl / hc - 1.0) * 100.0,
                        apart: l
                            .last
                            .energy_per_robot_step_mj
                            .apart_from(&c.last.energy_per_robot_step_mj),
                    }
                })
                .collect(),
        };
        BatteryReport {
            pack,
            paper_h: PAPER_BATTERY_LIFE_H,
            conditions,
            learning_against,
            by_part: Vec::new(),
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

    #[test]
    fn a_full_duty_stall_draws_the_stall_current_through_a_driving_bridge() {
        let mut d = DriveMeter::new(0.15, [1.0, 1.0]);
        d.set_commands(WheelCommand::forward(1.0), WheelCommand::forward(1.0));
        // One second pressed against a wall: both wheels still.
        d.add_substep(1.0, [0.0, 0.0]);
        let q = d.take();
        let m = DcMotor::fa130(0.15);
        let stall_a = m.full_duty_volts / m.resistance_ohm;
        // By hand: 2 × 3.18 A for 1 s is 6.36 C; the bridges 2 × 8 mA.
        assert!((q.of(Part::Motors) - 2.0 * stall_a * 1e6).abs() < 1e-6);
        assert!((q.of(Part::Motors) - 6.36e6).abs() < 0.02e6, "{q:?}");
        assert!((q.of(Part::Bridges) - 16_000.0).abs() < 1e-9);
        // Free-running at full duty: the no-load current.
        d.add_substep(1.0, [0.15, 0.15]);
        assert!((d.take().of(Part::Motors) - 0.4e6).abs() < 1e-6);
        // Backward, free: the same; braking and coasting: no motor current.
        d.set_commands(WheelCommand::reverse(1.0), WheelCommand::brake());
        d.add_substep(1.0, [-0.15, 0.0]);
        let q = d.take();
        assert!((q.of(Part::Motors) - 0.2e6).abs() < 1e-6);
        assert!((q.of(Part::Bridges) - (8.0 + 6.5) * 1e3).abs() < 1e-9);
    }

    #[test]
    fn a_turn_splits_the_ground_speed_between_the_wheels() {
        let a = Pose {
            x_m: 1.0,
            y_m: 1.0,
            heading_rad: 0.0,
        };
        // Straight ahead 3 mm in 20 ms: 0.15 m/s on both wheels.
        let b = Pose { x_m: 1.003, ..a };
        let v = ground_speeds(&a, &b, 0.02, 0.16);
        assert!((v[0] - 0.15).abs() < 1e-12 && (v[1] - 0.15).abs() < 1e-12);
        // A turn in place to the left by 0.01 rad: the left wheel back, the right forward.
        let c = Pose {
            heading_rad: 0.01,
            ..a
        };
        let v = ground_speeds(&a, &c, 0.02, 0.16);
        assert!(
            (v[0] + 0.04).abs() < 1e-12 && (v[1] - 0.04).abs() < 1e-12,
            "{v:?}"
        );
        // Across ±π.
        let d = Pose {
            heading_rad: std::f64::consts::PI - 0.005,
            ..a
        };
        let e = Pose {
            heading_rad: -std::f64::consts::PI + 0.005,
            ..a
        };
        let v = ground_speeds(&d, &e, 0.02, 0.16);
        assert!((v[1] - 0.04).abs() < 1e-9, "{v:?}");
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
    fn free_wheels_settle_to_the_no_load_current() {
        let mut d = DriveMeter::new(0.15, [1.0, 1.0]);
        d.set_commands(WheelCommand::forward(1.0), WheelCommand::forward(0.3));
        let mut w = FreeWheels::new(0.15, 0.06);
        // Starting from rest: the first 0.45 s carry the acceleration's surge.
        w.run(&mut d, 0.45, 0.01, false);
        let first = d.take().of(Part::Motors);
        w.run(&mut d, 0.45, 0.01, false);
        let settled = d.take().of(Part::Motors);
        assert!(first > settled);
        // Settled: 0.2 A at full duty, 0.3 × 0.2 A at 30 %, for 0.45 s.
        let want = (0.2 + 0.3 * 0.2) * 0.45 * 1e6;
        assert!((settled - want).abs() / want < 1e-3, "{settled} vs {want}");
        // Held still the whole time: the stall current.
        w.run(&mut d, 1.0, 0.01, true);
        let held = d.take().of(Part::Motors);
        assert!(held > 3.0e6, "{held}");
    }
}
