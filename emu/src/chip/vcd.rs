//! Pin traces as VCD (Value Change Dump, IEEE 1364) files, written with the `vcd` crate, for
//! GTKWave, sigrok (`sigrok-cli -i FILE -I vcd`) and any other logic-analyser tool.
//!
//! # Time
//! VCD timestamps are integers in units of the `$timescale`, which must be 1, 10 or 100 of
//! s, ms, µs, ns, ps or fs. One MCU state lasts 1/φ (40 ns at φ = 25 MHz), so the file uses
//! the largest such unit that divides the state exactly (10 ns at 25 MHz, 4 units a state;
//! 100 ps at 16 MHz, 625 a state) and writes each instant as `states × units per state`. A
//! clock whose state is no whole number of femtoseconds (φ = 3 MHz) gets 1 fs and instants
//! rounded to the nearest femtosecond. The header's `$comment` says φ, the state's length
//! and the conversion, so a reader can go back to states. Instants are absolute: states since
//! the MCU's reset, so they match `h8swarm emu --stats`, the `--trace` output and the GDB
//! stub's clock.
//!
//! # Contents
//! Scope `h8_3052f` holds one 1-bit wire per [`Signal`] (named by [`Signal::name`]);
//! scope `firmware` holds `phase`, a string variable naming the code that runs
//! ([`crate::chip::trace::PhaseRecorder`]). The values at the trace's start are given in a
//! `$dumpvars` block; a last timestamp marks its end. At one instant only a signal's final
//! level is written, and only if it changed.

use std::io::{self, Write};

use vcd::{IdCode, SimulationCommand, TimescaleUnit, Value, VarType, Writer};

use crate::chip::trace::{PinTrace, Signal};

/// The VCD time unit for a clock: (count, unit) for `$timescale`, and how many such units one
/// state lasts, or `None` when a state is no whole number of femtoseconds.
#[must_use]
pub fn timescale_for(clock_hz: u32) -> ((u32, TimescaleUnit), Option<u64>) {
    const FS_PER_S: u128 = 1_000_000_000_000_000;
    let hz = u128::from(clock_hz.max(1));
    if !FS_PER_S.is_multiple_of(hz) {
        return ((1, TimescaleUnit::FS), None);
    }
    let period_fs = FS_PER_S / hz;
    // The largest power of ten (in fs, up to 1 s) dividing the period.
    let mut exp = 0u32;
    while exp < 15 && period_fs.is_multiple_of(10u128.pow(exp + 1)) {
        exp += 1;
    }
    let units = [
        TimescaleUnit::FS,
        TimescaleUnit::PS,
        TimescaleUnit::NS,
        TimescaleUnit::US,
        TimescaleUnit::MS,
        TimescaleUnit::S,
    ];
    let unit = units[(exp / 3) as usize];
    let count = 10u32.pow(exp % 3);
    let per_state = (period_fs / 10u128.pow(exp)) as u64;
    ((count, unit), Some(per_state))
}

/// Converts states to VCD timestamps for one clock.
#[derive(Clone, Copy, Debug)]
struct Clock {
    hz: u32,
    per_state: Option<u64>,
}

impl Clock {
    fn stamp(&self, states: u64) -> u64 {
        match self.per_state {
            Some(k) => states.saturating_mul(k),
            None => {
                // Femtoseconds, rounded to nearest.
                let fs = (u128::from(states) * 1_000_000_000_000_000 + u128::from(self.hz) / 2)
                    / u128::from(self.hz.max(1));
                u64::try_from(fs).unwrap_or(u64::MAX)
            }
        }
    }
}

/// What a VCD file says about where its trace came from (for its header).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct VcdInfo {
    /// The program traced and where it ran, e.g. `firmware/robot.mot on h8swarm emu`.
    pub source: String,
}

/// Writes `trace` (and the phase changes, if any) as a VCD file to `out`.
///
/// # Errors
/// Only the writer's I/O errors.
pub fn write_vcd<W: Write>(
    out: W,
    trace: &PinTrace,
    phases: Option<&[(u64, String)]>,
    info: &VcdInfo,
) -> io::Result<()> {
    let ((count, unit), per_state) = timescale_for(trace.clock_hz);
    let clock = Clock {
        hz: trace.clock_hz,
        per_state,
    };
    let mut w = Writer::new(io::BufWriter::new(out));
    w.version(concat!("h8swarm ", env!("CARGO_PKG_VERSION")))?;
    let state_ns = 1e9 / f64::from(trace.clock_hz.max(1));
    let conversion = match per_state {
        Some(k) => format!("timestamp = states x {k}"),
        None => "timestamp = states x 1e15 / phi, rounded to the nearest fs".to_string(),
    };
    let mut comment = format!(
        "H8/3052F pin trace. {source}. Clock phi = {hz} Hz: 1 state = {state_ns} ns; \
         timescale {count} {unit}, {conversion} (states since the MCU's reset). \
         Trace from state {start} to state {end}.",
        source = if info.source.is_empty() {
            "h8swarm"
        } else {
            &info.source
        },
        hz = trace.clock_hz,
        start = trace.start,
        end = trace.end,
    );
    for s in Signal::ALL {
        comment.push_str(&format!(" {}: {}.", s.name(), s.description()));
    }
    if phases.is_some() {
        comment.push_str(" phase: the function that runs (symbol table).");
    }
    w.comment(&comment)?;
    w.timescale(count, unit)?;
    w.add_module("h8_3052f")?;
    let mut ids: Vec<IdCode> = Vec::with_capacity(Signal::ALL.len());
    for s in Signal::ALL {
        ids.push(w.add_wire(1, s.name())?);
    }
    w.upscope()?;
    let phase_id = match phases {
        Some(_) => {
            w.add_module("firmware")?;
            let id = w.add_var(VarType::String, 1, "phase", None)?;
            w.upscope()?;
            Some(id)
        }
        None => None,
    };
    w.enddefinitions()?;

    // Initial values.
    let phases = phases.unwrap_or(&[]);
    let mut phase_ix = 0;
    let mut phase_now: Option<&str> = None;
    while phase_ix < phases.len() && phases[phase_ix].0 <= trace.start {
        phase_now = Some(phases[phase_ix].1.as_str());
        phase_ix += 1;
    }
    w.timestamp(clock.stamp(trace.start))?;
    w.begin(SimulationCommand::Dumpvars)?;
    let mut levels = trace.initial;
    for (i, id) in ids.iter().enumerate() {
        w.change_scalar(*id, bit(levels[i]))?;
    }
    if let Some(id) = phase_id {
        w.change_string(id, phase_now.unwrap_or(crate::chip::trace::UNNAMED_PHASE))?;
    }
    w.end()?;

    // Changes, grouped by instant: a signal's last level at an instant, if it differs.
    let changes = &trace.changes;
    let mut i = 0;
    loop {
        let next_pin = changes.get(i).map(|c| c.t);
        let next_phase = phases.get(phase_ix).map(|p| p.0);
        let t = match (next_pin, next_phase) {
            (Some(a), Some(b)) => a.min(b),
            (Some(a), None) => a,
            (None, Some(b)) => b,
            (None, None) => break,
        };
        if t > trace.end {
            break;
        }
        let mut now = levels;
        while let Some(c) = changes.get(i).filter(|c| c.t == t) {
            now[c.signal as usize] = c.level;
            i += 1;
        }
        let mut phase_at = phase_now;
        while let Some(p) = phases.get(phase_ix).filter(|p| p.0 == t) {
            phase_at = Some(p.1.as_str());
            phase_ix += 1;
        }
        let pins_changed = now != levels;
        let phase_changed = phase_at != phase_now;
        if pins_changed || phase_changed {
            w.timestamp(clock.stamp(t))?;
            for (k, id) in ids.iter().enumerate() {
                if now[k] != levels[k] {
                    w.change_scalar(*id, bit(now[k]))?;
                }
            }
            if let (true, Some(id), Some(name)) = (phase_changed, phase_id, phase_at) {
                w.change_string(id, name)?;
            }
        }
        levels = now;
        phase_now = phase_at;
    }
    w.timestamp(clock.stamp(trace.end))?;
    w.flush()?;
    Ok(())
}

fn bit(level: bool) -> Value {
    if level { Value::V1 } else { Value::V0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timescales_divide_the_state_exactly() {
        assert_eq!(
            timescale_for(25_000_000),
            ((10, TimescaleUnit::NS), Some(4))
        );
        assert_eq!(
            timescale_for(16_000_000),
            ((100, TimescaleUnit::PS), Some(625))
        );
        assert_eq!(
            timescale_for(20_000_000),
            ((10, TimescaleUnit::NS), Some(5))
        );
        assert_eq!(
            timescale_for(2_000_000),
            ((100, TimescaleUnit::NS), Some(5))
        );
        assert_eq!(timescale_for(3_000_000), ((1, TimescaleUnit::FS), None));
        let c = Clock {
            hz: 3_000_000,
            per_state: None,
        };
        // 1 state = 333 333 333.3 fs.
        assert_eq!(c.stamp(1), 333_333_333);
        assert_eq!(c.stamp(3), 1_000_000_000);
    }
}
