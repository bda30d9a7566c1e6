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
//! Scope `h8_3052f` holds one 1-bit wire per named [`Signal`] (named by [`Signal::name`]);
//! scope `firmware` holds `phase`, a string variable naming the code that runs
//! ([`crate::trace::PhaseRecorder`]); scope `ports` holds one 1-bit wire per pin of each port,
//! `P1_0`–`P1_7` to `PB_0`–`PB_7`, what the port drives ([`Signal::PortOut`]: DR on its output
//! pins, 0 on its inputs), so a program's port writes show (1-bit wires, not 8-bit vectors:
//! sigrok's VCD input reads only 1-bit wires). The values at the trace's start are given in a
//! `$dumpvars` block; a last timestamp marks its end. At one instant only a signal's final
//! level is written, and only if it changed.

use std::io::{self, Write};

use vcd::{IdCode, SimulationCommand, TimescaleUnit, Value, VarType, Writer};

use crate::periph::ports::PortId;
use crate::trace::{PinChange, PinTrace, SIGNAL_COUNT, Signal};

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

/// Memory a streamed trace may hold between two writes, for a run's memory estimate: the pin
/// changes and phase changes of one drain (a robot's step, or at most
/// [`DRAIN_CHANGES`] changes and [`DRAIN_SLICE_STATES`] of `h8swarm emu`'s run), with a margin.
pub const STREAM_BUFFER_BYTES: u64 = 64 << 20;
/// `h8swarm emu --vcd` writes what it traced once this many changes wait.
pub const DRAIN_CHANGES: usize = 1 << 16;
/// ... or once this many states passed since the last write; a trace is also caught up at
/// most this many states at a time (a long sleep with the PWM running makes its edges a
/// slice at a time, not all at once).
pub const DRAIN_SLICE_STATES: u64 = 1 << 20;

/// A VCD file written as the trace is made: the header and the values at the start first,
/// then the changes below an instant each time [`VcdStream::write_until`] is given them (pin
/// changes and phase changes, each final below that instant, merged in time order), then
/// the end ([`VcdStream::finish`]). Nothing but the changes of one write is held, so a trace
/// of any length takes bounded memory; the file is the same byte for byte as [`write_vcd`]
/// writes from the whole trace.
pub struct VcdStream<'w> {
    w: Writer<io::BufWriter<Box<dyn Write + Send + 'w>>>,
    clock: Clock,
    /// Every signal's wire, in [`Signal::ALL`] order.
    ids: Vec<IdCode>,
    phase_id: Option<IdCode>,
    levels: [bool; SIGNAL_COUNT],
    phase_now: Option<String>,
    start: u64,
}

impl std::fmt::Debug for VcdStream<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VcdStream")
            .field("start", &self.start)
            .finish_non_exhaustive()
    }
}

impl<'w> VcdStream<'w> {
    /// Writes the header and the values at `start` (`initial`: each signal's level in
    /// [`Signal::ALL`] order; `phase`: `Some(name)` for a trace with a phase signal, the
    /// name at `start`).
    ///
    /// # Errors
    /// The writer's I/O errors.
    pub fn start(
        out: Box<dyn Write + Send + 'w>,
        clock_hz: u32,
        start: u64,
        initial: [bool; SIGNAL_COUNT],
        phase: Option<&str>,
        info: &VcdInfo,
    ) -> io::Result<VcdStream<'w>> {
        let ((count, unit), per_state) = timescale_for(clock_hz);
        let clock = Clock {
            hz: clock_hz,
            per_state,
        };
        let mut w = Writer::new(io::BufWriter::with_capacity(1 << 16, out));
        w.version(concat!("h8swarm ", env!("CARGO_PKG_VERSION")))?;
        let state_ns = 1e9 / f64::from(clock_hz.max(1));
        let conversion = match per_state {
            Some(k) => format!("timestamp = states x {k}"),
            None => "timestamp = states x 1e15 / phi, rounded to the nearest fs".to_string(),
        };
        let mut comment = format!(
            "H8/3052F pin trace. {source}. Clock phi = {clock_hz} Hz: 1 state = {state_ns} ns; \
             timescale {count} {unit}, {conversion} (states since the MCU's reset). \
             Trace from state {start} to the last timestamp.",
            source = if info.source.is_empty() {
                "h8swarm"
            } else {
                &info.source
            },
        );
        for s in Signal::NAMED {
            comment.push_str(&format!(" {}: {}.", s.name(), s.description()));
        }
        if phase.is_some() {
            comment.push_str(" phase: the function that runs (symbol table).");
        }
        comment.push_str(
            " P1_0-PB_7: what each port drives on each pin (DR on its output pins, 0 on its inputs).",
        );
        w.comment(&comment)?;
        w.timescale(count, unit)?;
        w.add_module("h8_3052f")?;
        let mut ids: Vec<IdCode> = Vec::with_capacity(SIGNAL_COUNT);
        for s in Signal::NAMED {
            ids.push(w.add_wire(1, s.name())?);
        }
        w.upscope()?;
        let phase_id = match phase {
            Some(_) => {
                w.add_module("firmware")?;
                let id = w.add_var(VarType::String, 1, "phase", None)?;
                w.upscope()?;
                Some(id)
            }
            None => None,
        };
        w.add_module("ports")?;
        for p in PortId::ALL {
            for b in 0..8 {
                ids.push(w.add_wire(1, &format!("{}_{b}", p.name()))?);
            }
        }
        w.upscope()?;
        w.enddefinitions()?;
        w.timestamp(clock.stamp(start))?;
        w.begin(SimulationCommand::Dumpvars)?;
        for (i, id) in ids.iter().enumerate().take(Signal::NAMED.len()) {
            w.change_scalar(*id, bit(initial[i]))?;
        }
        if let (Some(id), Some(name)) = (phase_id, phase) {
            w.change_string(id, name)?;
        }
        for (i, id) in ids.iter().enumerate().skip(Signal::NAMED.len()) {
            w.change_scalar(*id, bit(initial[i]))?;
        }
        w.end()?;
        Ok(VcdStream {
            w,
            clock,
            ids,
            phase_id,
            levels: initial,
            phase_now: phase.map(str::to_string),
            start,
        })
    }

    /// Writes the changes (each list in time order) at instants below `upto`, after `start`;
    /// at one instant only a signal's last level is written, and only if it changed. Changes
    /// at `upto` or later are not written: give them again with a later `upto`.
    ///
    /// # Errors
    /// The writer's I/O errors.
    pub fn write_until(
        &mut self,
        pins: &[PinChange],
        phases: &[(u64, String)],
        upto: u64,
    ) -> io::Result<()> {
        let (mut i, mut k) = (0, 0);
        // Phases at or before the start are the start's value.
        while k < phases.len() && phases[k].0 <= self.start {
            self.phase_now = Some(phases[k].1.clone());
            k += 1;
        }
        loop {
            let t = match (pins.get(i).map(|c| c.t), phases.get(k).map(|p| p.0)) {
                (Some(a), Some(b)) => a.min(b),
                (Some(a), None) => a,
                (None, Some(b)) => b,
                (None, None) => break,
            };
            if t >= upto {
                break;
            }
            let mut now = self.levels;
            while let Some(c) = pins.get(i).filter(|c| c.t == t) {
                now[c.signal.index()] = c.level;
                i += 1;
            }
            let mut phase_at: Option<&str> = self.phase_now.as_deref();
            while let Some(p) = phases.get(k).filter(|p| p.0 == t) {
                phase_at = Some(p.1.as_str());
                k += 1;
            }
            let phase_changed = phase_at != self.phase_now.as_deref();
            if now != self.levels || phase_changed {
                self.w.timestamp(self.clock.stamp(t))?;
                for (n, id) in self.ids.iter().enumerate().take(Signal::NAMED.len()) {
                    if now[n] != self.levels[n] {
                        self.w.change_scalar(*id, bit(now[n]))?;
                    }
                }
                if let (true, Some(id), Some(name)) = (phase_changed, self.phase_id, phase_at) {
                    self.w.change_string(id, name)?;
                }
                for (n, id) in self.ids.iter().enumerate().skip(Signal::NAMED.len()) {
                    if now[n] != self.levels[n] {
                        self.w.change_scalar(*id, bit(now[n]))?;
                    }
                }
            }
            self.levels = now;
            if phase_changed {
                self.phase_now = phase_at.map(str::to_string);
            }
        }
        Ok(())
    }

    /// Writes the changes before `end` and the end's timestamp, and flushes the file.
    ///
    /// # Errors
    /// The writer's I/O errors.
    pub fn finish(
        mut self,
        pins: &[PinChange],
        phases: &[(u64, String)],
        end: u64,
    ) -> io::Result<()> {
        self.write_until(pins, phases, end.saturating_add(1))?;
        self.w.timestamp(self.clock.stamp(end.max(self.start)))?;
        self.w.flush()
    }
}

/// Writes `trace` (and the phase changes, if any) as a VCD file to `out` (a [`VcdStream`]
/// given the whole trace at once).
///
/// # Errors
/// Only the writer's I/O errors.
pub fn write_vcd<'w, W: Write + Send + 'w>(
    out: W,
    trace: &PinTrace,
    phases: Option<&[(u64, String)]>,
    info: &VcdInfo,
) -> io::Result<()> {
    let at_start = phases.map(|p| {
        p.iter()
            .take_while(|(t, _)| *t <= trace.start)
            .last()
            .map_or(crate::trace::UNNAMED_PHASE, |(_, n)| n.as_str())
    });
    let mut v = VcdStream::start(
        Box::new(out),
        trace.clock_hz,
        trace.start,
        trace.initial,
        at_start,
        info,
    )?;
    v.write_until(
        &trace.changes,
        phases.unwrap_or(&[]),
        trace.end.saturating_add(1),
    )?;
    v.finish(&[], &[], trace.end)
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
            timescale_for(crate::mcu::MAX_CLOCK_HZ),
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
