//! From the measured run to the report: the lines per phase, the memory and EEPROM lines, the
//! margins and the one-line verdict with the tightest of them.
//!
//! The report gives the maximum and mean states per phase (with the other controller's mean
//! and the ratio when both ran), the time at φ against the step period, the RAM items against
//! the 8 192 bytes, the ROM against the 512 KB of flash, the EEPROM traffic and the lifetime the
//! endurance allows, and a one-line verdict with the tightest margin.

use super::config::{ENDURANCE_CYCLES, FitConfig, PHASE_SAVE};
use super::meter::{Measured, Metered};
use super::report::{
    EepromLine, EnergyReport, FitReport, MemLine, PartLine, PhaseLine, Spread, StackLine,
};
use crate::energy::{PAPER_BATTERY_LIFE_H, Pack, Part, mean_current_ma};
use h8300h::memmap::{RAM_BYTES, ROM_BYTES};
use robot_board::firmware::Firmware;
use robot_board::model::ControllerConfig;

impl EnergyReport {
    fn new(m: &Metered, pack: Pack, step_period_s: f64) -> EnergyReport {
        let mut free = m.electronics;
        free.add(&m.free);
        let parts = Part::ALL
            .iter()
            .map(|&p| PartLine {
                part: p.key(),
                name: p.name(),
                mean_current_ma: mean_current_ma(free.of(p), m.seconds),
                energy_per_step_mj: 0.0,
            })
            .collect();
        let held_motors = mean_current_ma(m.held.of(Part::Motors), m.seconds);
        let held_rest = mean_current_ma(
            free.total_uc() - free.of(Part::Motors) - free.of(Part::Bridges)
                + m.held.of(Part::Bridges),
            m.seconds,
        );
        EnergyReport {
            pack,
            step_period_s,
            parts,
            mean_current_ma: 0.0,
            energy_per_step_mj: 0.0,
            battery_life_h: 0.0,
            held_motors_current_ma: held_motors,
            held_mean_current_ma: held_rest + held_motors,
            held_battery_life_h: 0.0,
            paper_battery_life_h: PAPER_BATTERY_LIFE_H,
            capacity_for_paper_mah: 0.0,
            motor_cap: m.free_cap,
            held_motor_cap: m.held_cap,
        }
        .with_pack(pack)
    }

    /// The same draw from another pack (a different capacity).
    #[must_use]
    pub fn with_pack(&self, pack: Pack) -> EnergyReport {
        let mut r = self.clone();
        r.pack = pack;
        // mA × s = mC; at the pack's volts, mJ.
        let per_step = |ma: f64| ma * self.step_period_s * pack.volts();
        for p in &mut r.parts {
            p.energy_per_step_mj = per_step(p.mean_current_ma);
        }
        r.mean_current_ma = r.parts.iter().map(|p| p.mean_current_ma).sum();
        r.energy_per_step_mj = per_step(r.mean_current_ma);
        r.battery_life_h = pack.life_h(r.mean_current_ma);
        r.held_battery_life_h = pack.life_h(r.held_mean_current_ma);
        r.capacity_for_paper_mah = Pack::capacity_for_h(r.mean_current_ma, PAPER_BATTERY_LIFE_H);
        r
    }
}

pub(super) fn spread_of(values: &[u64]) -> Spread {
    if values.is_empty() {
        return Spread::default();
    }
    Spread {
        max: values.iter().copied().max().unwrap_or(0),
        mean: values.iter().sum::<u64>() as f64 / values.len() as f64,
    }
}

pub(super) fn report(cfg: &FitConfig, m: &Measured, other: Option<&Measured>) -> FitReport {
    let c = &cfg.controller;
    let clock_hz = c.clock_hz;
    let phases = phase_lines(clock_hz, m, other);
    let save_max = m
        .phase(PHASE_SAVE)
        .map_or(0, |v| v.iter().copied().max().unwrap_or(0));
    let busy_per_step = spread_of(&m.busy);
    let period_states = c.step_period_s * f64::from(clock_hz);
    let cpu_mean_percent = busy_per_step.mean / period_states * 100.0;
    let cpu_worst_percent = busy_per_step.max as f64 / period_states * 100.0;
    let ram_used: u32 = m.ram.iter().map(|l| l.bytes).sum();
    let fw = &cfg.firmware.firmware;
    let rom = rom_lines(fw);
    let rom_used = fw.rom_bytes() as u32;
    let n_in = c.n_inputs();
    let eeprom = eeprom_line(c, save_max);
    let margins = Margins::new(ram_used, rom_used, cpu_worst_percent, m.stack.as_ref());
    let verdict = format!(
        "{}: {}{}{} x {} network, RAM {} of {} B, ROM {} B of {} KB, worst step {:.2} % of the {} s period (mean {:.3} %); tightest margin: {} with {:.1} % left",
        if margins.fits { "FITS" } else { "DOES NOT FIT" },
        margins.stack_note,
        unmodelled_note(&m.unmodelled),
        n_in,
        c.behaviours,
        ram_used,
        RAM_BYTES,
        rom_used,
        ROM_BYTES / 1024,
        cpu_worst_percent,
        c.step_period_s,
        cpu_mean_percent,
        margins.tightest,
        margins.tightest_percent
    );
    FitReport {
        controller: cfg.kind,
        source: m.source.clone(),
        compared_with: other.map(|o| o.source.clone()),
        n_in,
        n_out: c.behaviours,
        history: c.layout.history(),
        bias: c.layout.bias(),
        spare: c.layout.spare(),
        eta: c.params.eta().to_bits(),
        threshold: c.params.threshold(),
        save_every_steps: c.save_every_steps,
        step_period_s: c.step_period_s,
        clock_hz,
        steps: cfg.steps,
        seed: cfg.seed,
        boot_states: m.boot_states,
        phases,
        busy_per_step,
        cpu_mean_percent,
        cpu_worst_percent,
        ram: m.ram.clone(),
        ram_used,
        stack_high_water: m.stack_high_water,
        stack: m.stack.clone(),
        energy: m
            .energy
            .as_ref()
            .map(|e| EnergyReport::new(e, Pack::default(), c.step_period_s)),
        rom,
        rom_used,
        eeprom,
        fits: margins.fits,
        tightest: margins.tightest,
        tightest_margin_percent: margins.tightest_percent,
        verdict,
        unmodelled: m.unmodelled.iter().map(|(_, line)| line.clone()).collect(),
    }
}

/// The verdict's note on what the image uses that the chip does not model (empty when
/// nothing): `uses MAR0AR of the DMAC and FLMCR1 of the flash, not modelled; `.
pub(super) fn unmodelled_note(unmodelled: &[(String, String)]) -> String {
    let what: Vec<&str> = unmodelled.iter().map(|(w, _)| w.as_str()).collect();
    match what.as_slice() {
        [] => String::new(),
        [one] => format!("uses {one}, not modelled; "),
        [first @ .., last] => format!("uses {} and {last}, not modelled; ", first.join(", ")),
    }
}

/// Each phase's states per step period (the maximum in µs at `clock_hz`), with the other
/// controller's and the ratio of the means when both ran.
pub(super) fn phase_lines(clock_hz: u32, m: &Measured, other: Option<&Measured>) -> Vec<PhaseLine> {
    let us = |states: u64| states as f64 / f64::from(clock_hz) * 1e6;
    m.phases
        .iter()
        .map(|(name, v)| {
            let s = spread_of(v);
            let o = other.and_then(|o| o.phase(name)).map(spread_of);
            PhaseLine {
                phase: name.clone(),
                states: s,
                max_us: us(s.max),
                other: o,
                ratio: o
                    .filter(|o| o.mean > 0.0 && s.mean > 0.0)
                    .map(|o| s.mean / o.mean),
            }
        })
        .collect()
}

/// The image's ROM: its S-record data, and the configuration block within it when it has one.
pub(super) fn rom_lines(fw: &Firmware) -> Vec<MemLine> {
    let mut rom = vec![MemLine {
        item: format!("{} (S-record data)", fw.name),
        addr: 0,
        bytes: fw.rom_bytes() as u32,
    }];
    if fw.has_config_block() {
        rom.push(MemLine {
            item: "of which the configuration block".to_string(),
            addr: robot_board::firmware::CONFIG_BLOCK_ADDR,
            bytes: robot_board::firmware::CONFIG_BLOCK_BYTES as u32,
        });
    }
    rom
}

/// The EEPROM traffic of the controller's saves and the lifetime the endurance allows (the
/// longest save, `save_max` states, measured).
pub(super) fn eeprom_line(c: &ControllerConfig, save_max: u64) -> EepromLine {
    let payload = 2 * c.n_inputs() * c.behaviours;
    let record = eeprom::persist::RecordLayout::default();
    let saves_per_hour = 3600.0 / (c.step_period_s * f64::from(c.save_every_steps));
    let page_writes_per_hour = saves_per_hour / 2.0;
    EepromLine {
        bytes_per_save: record.bytes_per_save(payload),
        pages_per_save: record.pages_per_record(payload),
        saves_per_hour,
        page_writes_per_hour,
        lifetime_hours: ENDURANCE_CYCLES / page_writes_per_hour,
        save_max_states: save_max,
    }
}

/// The margins left in RAM, ROM, the CPU's worst step and the stack's room: the tightest, and
/// whether all are left.
pub(super) struct Margins {
    fits: bool,
    tightest: &'static str,
    tightest_percent: f64,
    /// The verdict's note on a stack that left its room (empty when it did not).
    stack_note: String,
}

impl Margins {
    fn new(
        ram_used: u32,
        rom_used: u32,
        cpu_worst_percent: f64,
        stack: Option<&StackLine>,
    ) -> Margins {
        let mut margins = vec![
            (
                "RAM",
                100.0 * (1.0 - f64::from(ram_used) / f64::from(RAM_BYTES)),
            ),
            (
                "ROM",
                100.0 * (1.0 - f64::from(rom_used) / f64::from(ROM_BYTES)),
            ),
            ("CPU (worst step)", 100.0 - cpu_worst_percent),
        ];
        // The stack's room: what the lowest SP left of it, or how far past it the first access
        // outside went (then it does not fit, whatever the RAM total says).
        let mut stack_note = String::new();
        if let Some(st) = stack {
            let room = f64::from(st.room_bytes.max(1));
            let left = match st.overflow_bytes {
                Some(over) => -f64::from(over),
                None => st.left_bytes as f64,
            };
            margins.push(("stack", 100.0 * left / room));
            if let Some(text) = &st.overflow {
                stack_note = format!(
                    "the stack leaves its room by {} B ({text}); ",
                    st.overflow_bytes.unwrap_or(0)
                );
            }
        }
        let (tightest, tightest_percent) = margins
            .iter()
            .copied()
            .fold(("RAM", f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        Margins {
            fits: margins.iter().all(|m| m.1 >= 0.0),
            tightest,
            tightest_percent,
            stack_note,
        }
    }
}
