//! Running a program image on the core: the API behind `h8swarm emu`.
//!
//! [`run_image`] parses a `.mot` image, loads it into a [`Machine`] — the same [`Mcu`] the
//! robot's controller runs on (flash, RAM, SCI1 as console, ITU, A/D, ports, interrupt
//! controller) with a [`NullBoard`](crate::pins::NullBoard) outside it (no EEPROMs; `h8swarm
//! emu` runs [`run_mcu_probed`] on the robot's board instead) — resets the CPU through vector
//! 0 and runs it until the program halts
//! (SLEEP with CCR.I = 1 and no NMI pending; exit status = low byte of R0, docs/design.md §7), the state
//! budget runs out, or the core stops on an error (undefined opcode, fetch outside ROM/RAM).
//! Bytes the program transmits on SCI1 go to the console writer as they leave TDR; the
//! optional trace writer gets one line per instruction: address, disassembly (objdump's form)
//! and the states it took.
//!
//! The stack guard ([`h8300h::cpu::stack`]) is the CPU's: [`run_image`] sets one over the
//! whole on-chip RAM (it has no symbol table to know better), a caller of [`run_mcu`] sets
//! its own (`h8swarm emu` takes the room from the image's symbols). A stopping guard ends the
//! run with [`Outcome::Error`]; a warning guard's first fault is in
//! [`RunReport::stack_fault`]. Either way the fault names its function when the probes carry
//! the code's names.

use std::fmt::Write as _;
use std::io::Write;

use crate::gdb::DebugAction;
use crate::machine::{LoadError, Machine};
use crate::mcu::{IoReport, Mcu};
use crate::pins::Board;
use crate::profile::StackProfile;
use crate::trace::{CodeNames, PhaseRecorder, phase_name};
use h8300h::bus::Bus;
use h8300h::cpu::disasm::format_instr;
use h8300h::cpu::{Cpu, CpuError, Event, StackFault, StackGuard, StackRoom};
use h8300h::srec::{self, SrecError};

/// Options of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunOptions {
    /// Stop once the clock reaches this many states (checked between instructions, so the
    /// last instruction may end a few states past it). `None`: no limit.
    pub max_states: Option<u64>,
    /// Stop at the first access to an address the chip does not model
    /// ([`Outcome::Unmodelled`]) instead of reporting it and going on.
    pub strict_io: bool,
}

/// How a run ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// SLEEP with CCR.I = 1 and no NMI pending (docs/design.md §7).
    Halted {
        /// The low byte of R0.
        exit_status: u8,
    },
    /// The clock reached [`RunOptions::max_states`].
    MaxStates,
    /// The core refused to go on (undefined opcode, fetch outside ROM/RAM, unsupported
    /// instruction); the error names the PC and the bytes.
    Error(CpuError),
    /// SLEEP with interrupts enabled and no interrupt source that could ever wake the CPU, with
    /// no state budget to run out: the program would sleep forever.
    SleptForever {
        /// PC after the SLEEP instruction.
        pc: u32,
    },
    /// A GDB client killed the program.
    Killed,
    /// The program touched an address the chip does not model, under
    /// [`RunOptions::strict_io`].
    Unmodelled(IoReport),
}

/// Counters of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunStats {
    /// Instructions executed.
    pub instructions: u64,
    /// States elapsed (the MCU clock at the end).
    pub states: u64,
    /// `states / φ` in seconds, at the MCU's φ.
    pub emulated_seconds: f64,
    /// The MCU's φ in Hz.
    pub clock_hz: u32,
    /// Interrupts accepted.
    pub interrupts: u64,
    /// Bytes transmitted on SCI1.
    pub console_bytes: u64,
    /// Watchdog resets (internal resets of the chip).
    pub resets: u64,
}

/// The result of a run: how it ended and what it cost.
#[derive(Clone, Debug, PartialEq)]
pub struct RunReport {
    /// How the run ended.
    pub outcome: Outcome,
    /// Counters.
    pub stats: RunStats,
    /// The first stack access that left the stack's room, under a guard that only warns
    /// (a stopping guard's fault is the [`Outcome::Error`]).
    pub stack_fault: Option<StackFault>,
    /// The first access to each address the chip does not model, with the instruction that
    /// made it ([`crate::mcu::IoReport`]).
    pub io_reports: Vec<IoReport>,
}

impl RunReport {
    /// The report as one JSON object (for `--stats` on stderr): outcome, exit status (or
    /// null), error text (or null), instructions, states, emulated seconds, φ, interrupts,
    /// console bytes.
    #[must_use]
    pub fn to_json(&self) -> String {
        let (outcome, exit_status, error) = match &self.outcome {
            Outcome::Halted { exit_status } => ("halted", Some(*exit_status), None),
            Outcome::MaxStates => ("max_states", None, None),
            Outcome::Error(e) => ("error", None, Some(e.to_string())),
            Outcome::SleptForever { .. } => ("slept_forever", None, None),
            Outcome::Killed => ("killed", None, None),
            Outcome::Unmodelled(r) => ("unmodelled", None, Some(r.describe(None))),
        };
        let json = StatsJson {
            outcome,
            exit_status,
            error,
            stack_warning: self.stack_fault.as_ref().map(ToString::to_string),
            instructions: self.stats.instructions,
            states: self.stats.states,
            emulated_seconds: self.stats.emulated_seconds,
            phi_hz: u64::from(self.stats.clock_hz),
            interrupts: self.stats.interrupts,
            console_bytes: self.stats.console_bytes,
            resets: self.stats.resets,
            unmodelled_accesses: self.io_reports.len(),
        };
        // A struct of numbers, strings and options always serialises.
        serde_json::to_string(&json).unwrap_or_default()
    }
}

/// The `--stats` object, field by field in output order.
#[derive(serde::Serialize)]
struct StatsJson {
    outcome: &'static str,
    exit_status: Option<u8>,
    error: Option<String>,
    stack_warning: Option<String>,
    instructions: u64,
    states: u64,
    emulated_seconds: f64,
    phi_hz: u64,
    interrupts: u64,
    console_bytes: u64,
    /// Left out when 0 (the output of a program without is as it always was).
    #[serde(skip_serializing_if = "is_zero")]
    resets: u64,
    /// Left out when 0.
    #[serde(skip_serializing_if = "is_zero_usize")]
    unmodelled_accesses: usize,
}

/// For `skip_serializing_if`.
#[allow(clippy::trivially_copy_pass_by_ref)]
fn is_zero(v: &u64) -> bool {
    *v == 0
}

/// For `skip_serializing_if`.
#[allow(clippy::trivially_copy_pass_by_ref)]
fn is_zero_usize(v: &usize) -> bool {
    *v == 0
}

/// Why a run could not start or could not write its output. The message names the stage; the
/// cause is the error's `source()` (print the chain, as `anyhow`'s `{:#}` does).
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The image is not a valid S-record file.
    #[error("bad image")]
    Srec(#[from] SrecError),
    /// The image does not fit the flash.
    #[error("cannot load image")]
    Load(#[from] LoadError),
    /// Writing the console or the trace failed.
    #[error("writing output failed")]
    Io(#[from] std::io::Error),
}

/// Parses `mot` (S-record text), loads it into a fresh [`Machine`], resets the CPU and runs it
/// (see [`run_machine`]) under a stopping stack guard over the whole on-chip RAM.
///
/// # Errors
/// [`RunError`] if the image is malformed or does not fit the flash, or output cannot be
/// written. How the *program* ended (including core errors) is in [`RunReport::outcome`].
pub fn run_image(
    mot: &[u8],
    options: &RunOptions,
    console: &mut dyn Write,
    trace: Option<&mut dyn Write>,
) -> Result<RunReport, RunError> {
    let image = srec::parse(mot)?;
    let mut machine = Machine::with_image(&image)?;
    let mut cpu = Cpu::new();
    cpu.set_stack_guard(Some(StackGuard::stop(StackRoom::RAM)));
    cpu.reset(&mut machine);
    Ok(run_machine(
        &mut cpu,
        &mut machine,
        options,
        console,
        trace,
    )?)
}

/// Runs `cpu` on `machine` from its current state until the program halts, the budget runs
/// out or the core stops on an error; SCI1's output goes to `console`, one line per
/// instruction to `trace` if given.
///
/// # Errors
/// Only I/O errors of the writers.
pub fn run_machine(
    cpu: &mut Cpu,
    machine: &mut Machine,
    options: &RunOptions,
    console: &mut dyn Write,
    trace: Option<&mut dyn Write>,
) -> std::io::Result<RunReport> {
    run_mcu(cpu, machine.mcu_mut(), options, console, trace)
}

/// [`run_machine`] on any [`Mcu`], whatever board is outside it (a
/// [`NullBoard`](crate::pins::NullBoard), the robot's board for `h8swarm emu` and machine-code
/// controllers). `emulated_seconds` uses the MCU's φ.
///
/// # Errors
/// Only I/O errors of the writers.
pub fn run_mcu<B: Board>(
    cpu: &mut Cpu,
    machine: &mut Mcu<B>,
    options: &RunOptions,
    console: &mut dyn Write,
    trace: Option<&mut dyn Write>,
) -> std::io::Result<RunReport> {
    run_mcu_probed(
        cpu,
        machine,
        options,
        console,
        Probes {
            trace,
            ..Probes::default()
        },
    )
}

/// What a run records besides the console output.
#[derive(Default)]
pub struct Probes<'a> {
    /// One line per step: address, disassembly (objdump's form), states, and the name of the
    /// code it ran in when [`Probes::names`] are given.
    pub trace: Option<&'a mut dyn Write>,
    /// The names of the code (a firmware's functions) for the trace lines.
    pub names: Option<&'a dyn CodeNames>,
    /// The phase signal of a pin trace ([`PhaseRecorder`]): the code that runs, as it changes.
    /// (The pin trace itself is the MCU's: [`Mcu::start_trace`] before the run,
    /// [`Mcu::finish_trace`] after it.)
    pub phases: Option<&'a mut PhaseRecorder>,
    /// A GDB client's control of the run ([`crate::gdb::Debugger`]): breakpoints,
    /// watchpoints, single steps; the run waits while the client has the program stopped.
    pub debugger: Option<&'a mut crate::gdb::Debugger>,
    /// Where the pin trace under way (and the phases) go as the run makes them
    /// ([`crate::vcd::VcdStream`]): written whenever [`crate::vcd::DRAIN_CHANGES`]
    /// changes wait or [`crate::vcd::DRAIN_SLICE_STATES`] states passed, so the trace is
    /// never held whole. What is left at the end is the caller's to finish.
    pub vcd: Option<&'a mut crate::vcd::VcdStream<'static>>,
    /// A profile of where the states go by call stack ([`StackProfile`]), started before the
    /// run: every step is attributed (the waits in sleep mode to `[sleep]`).
    pub profile: Option<&'a mut StackProfile>,
}

/// Writes the pin trace's and the phases' changes up to now into `vcd` (see [`Probes::vcd`]).
///
/// # Errors
/// The file's I/O errors.
pub fn drain_into<B: Board>(
    vcd: &mut crate::vcd::VcdStream<'_>,
    machine: &mut Mcu<B>,
    mut phases: Option<&mut PhaseRecorder>,
) -> std::io::Result<()> {
    machine.drain_trace(crate::vcd::DRAIN_SLICE_STATES, &mut |pins, upto| {
        let ph = phases
            .as_deref_mut()
            .map(|p| p.drain_before(upto))
            .unwrap_or_default();
        vcd.write_until(&pins, &ph, upto)
    })
}

/// The trace's line for one step into `line`: the instruction (or the interrupt's entry, the
/// sleep, the error) at `pc`, the states it took, and the code it ran in when `names` are
/// known.
fn trace_line(
    line: &mut String,
    cpu: &Cpu,
    pc: u32,
    states: u64,
    event: &Result<Event, CpuError>,
    names: Option<&dyn CodeNames>,
) {
    line.clear();
    match event {
        Ok(Event::Executed | Event::Halted) => {
            let text = format_instr(cpu.last_executed(), pc).replacen('\t', " ", 1);
            let _ = write!(line, "{pc:06x}: {text:<40} {states:>4} states");
        }
        Ok(Event::Interrupt(v)) => {
            let _ = write!(
                line,
                "{pc:06x}: <interrupt vector {v} -> {:06x}> {states:>4} states",
                cpu.pc()
            );
        }
        Ok(Event::Asleep) => {
            let _ = write!(line, "{pc:06x}: <asleep> {states:>4} states");
        }
        Ok(Event::Reset) => {
            let _ = write!(
                line,
                "{pc:06x}: <watchdog reset -> {:06x}> {states:>4} states",
                cpu.pc()
            );
        }
        Ok(Event::Break) => {}
        Err(e) => {
            let _ = write!(line, "{pc:06x}: <error: {e}>");
        }
    }
    if let Some(n) = names {
        // The code the step ran in: the instruction's, or the handler's for an
        // interrupt's entry (as the phase signal of a pin trace names it).
        let at = match event {
            Ok(Event::Interrupt(_) | Event::Reset) => cpu.pc(),
            _ => pc,
        };
        let _ = write!(line, "  {}", phase_name(n, at));
    }
    line.push('\n');
}

/// Tells the phase recorder where the step that began at `t0` left the program: after an
/// instruction, at its end; after an interrupt's entry, at the instant the interrupt was
/// taken (within the step).
fn observe_step<B: Board>(
    p: &mut PhaseRecorder,
    cpu: &Cpu,
    machine: &Mcu<B>,
    t0: u64,
    event: &Result<Event, CpuError>,
) {
    match event {
        Ok(Event::Executed | Event::Reset) => p.observe(machine.now(), cpu.pc()),
        Ok(Event::Interrupt(_)) => {
            let at = machine
                .trace_last_interrupt()
                .map_or(t0, |a| a.t.clamp(t0, machine.now()));
            p.observe(at, cpu.pc());
        }
        _ => {}
    }
}

/// [`run_mcu`] with every probe: an instruction trace naming the code, the phase signal of a
/// pin trace, a debugger.
///
/// # Errors
/// Only I/O errors of the writers.
pub fn run_mcu_probed<B: Board>(
    cpu: &mut Cpu,
    machine: &mut Mcu<B>,
    options: &RunOptions,
    console: &mut dyn Write,
    probes: Probes<'_>,
) -> std::io::Result<RunReport> {
    let Probes {
        mut trace,
        names,
        mut phases,
        mut debugger,
        mut vcd,
        mut profile,
    } = probes;
    // The first access to an address the chip does not model stops the CPU, so that the
    // report names its instruction.
    machine.set_io_break(true);
    let mut drained_at = machine.now();
    let deadline = options.max_states.unwrap_or(u64::MAX);
    if let Some(p) = phases.as_deref_mut() {
        p.observe(machine.now(), cpu.pc());
    }
    let start_instructions = cpu.instructions();
    let mut interrupts = 0u64;
    let mut line = String::new();
    let outcome = loop {
        if machine.now() >= deadline {
            break Outcome::MaxStates;
        }
        if let Some(d) = debugger.as_deref_mut() {
            match d.before_step(cpu, machine) {
                DebugAction::Run => {}
                DebugAction::Detached => debugger = None,
                DebugAction::Kill => break Outcome::Killed,
            }
        }
        if let Some(p) = profile.as_deref_mut()
            && debugger.is_none()
            && cpu.sleeping()
        {
            // The wait in sleep mode is the profile's `[sleep]`, not the interrupt's entry.
            p.catch_up(machine.now(), false);
            machine.sleep_until_irq(deadline);
            p.catch_up(machine.now(), true);
        }
        let pc = cpu.pc();
        let t0 = machine.now();
        let was_sleeping = cpu.sleeping();
        let event = match debugger.as_deref_mut() {
            Some(d) => d.step(cpu, machine, deadline),
            None => cpu.step(machine, deadline),
        };
        if let Some(p) = profile.as_deref_mut() {
            p.after_step(cpu, t0, machine.now(), was_sleeping, &event);
        }
        if event == Ok(Event::Break) {
            if options.strict_io
                && let Some(r) = machine.io_reports().last()
            {
                break Outcome::Unmodelled(*r);
            }
            continue;
        }
        if let Some(w) = trace.as_deref_mut() {
            trace_line(&mut line, cpu, pc, machine.now() - t0, &event, names);
            w.write_all(line.as_bytes())?;
        }
        if let Some(p) = phases.as_deref_mut() {
            observe_step(p, cpu, machine, t0, &event);
        }
        if let Some(v) = vcd.as_deref_mut()
            && drain_due(machine, phases.as_deref(), drained_at)
        {
            drain_into(v, machine, phases.as_deref_mut())?;
            drained_at = machine.now();
        }
        match event {
            Ok(Event::Executed | Event::Reset | Event::Break) => {}
            Ok(Event::Interrupt(_)) => interrupts += 1,
            Ok(Event::Halted) => {
                break Outcome::Halted {
                    exit_status: cpu.er(0) as u8,
                };
            }
            Ok(Event::Asleep) if deadline == u64::MAX => {
                break Outcome::SleptForever { pc: cpu.pc() };
            }
            Ok(Event::Asleep) => break Outcome::MaxStates,
            Err(e) => break stopped_by(e, cpu, machine, debugger.as_deref_mut(), names),
        }
        if machine.sci().has_output() {
            console.write_all(machine.sci().output())?;
            machine.sci_mut().clear_output();
        }
    };
    if let Some(d) = debugger {
        let status = match &outcome {
            Outcome::Halted { exit_status } => Some(*exit_status),
            _ => None,
        };
        d.finish(status, std::time::Duration::from_secs(2));
    }
    let now = machine.now();
    machine.sci_mut().flush(now);
    console.write_all(machine.sci().output())?;
    machine.sci_mut().clear_output();
    console.flush()?;
    if let Some(w) = trace {
        w.flush()?;
    }
    Ok(report(
        cpu,
        machine,
        outcome,
        names,
        start_instructions,
        interrupts,
    ))
}

/// Whether the pin trace's or the phases' changes are due to be written to the VCD (see
/// [`Probes::vcd`]), the last write having been at `drained_at`.
fn drain_due<B: Board>(machine: &Mcu<B>, phases: Option<&PhaseRecorder>, drained_at: u64) -> bool {
    machine.trace_pending() >= crate::vcd::DRAIN_CHANGES
        || phases.is_some_and(|p| p.pending() >= crate::vcd::DRAIN_CHANGES)
        || machine.now() - drained_at >= crate::vcd::DRAIN_SLICE_STATES
}

/// The outcome of a run the core stopped with error `e`: the error is reported to the
/// debugger, and a stack overflow names its function when `names` are known.
#[cold]
fn stopped_by<B: Board>(
    mut e: CpuError,
    cpu: &mut Cpu,
    machine: &mut Mcu<B>,
    debugger: Option<&mut crate::gdb::Debugger>,
    names: Option<&dyn CodeNames>,
) -> Outcome {
    if let Some(d) = debugger {
        d.report_error(cpu, machine);
    }
    if let (CpuError::StackOverflow(f), Some(n)) = (&mut e, names) {
        f.function = n.name_at(f.pc).map(str::to_string);
    }
    Outcome::Error(e)
}

/// The report of a run that ended with `outcome`: the stack guard's fault (named when `names`
/// are known; an overflow that stopped the run is in the outcome) and the statistics since
/// `start_instructions`.
fn report<B: Board>(
    cpu: &Cpu,
    machine: &Mcu<B>,
    outcome: Outcome,
    names: Option<&dyn CodeNames>,
    start_instructions: u64,
    interrupts: u64,
) -> RunReport {
    let states = machine.now();
    let stack_fault = match &outcome {
        Outcome::Error(CpuError::StackOverflow(_)) => None,
        _ => cpu.stack_fault().map(|f| {
            let mut f = f.clone();
            f.function = names.and_then(|n| n.name_at(f.pc)).map(str::to_string);
            f
        }),
    };
    RunReport {
        stack_fault,
        outcome,
        stats: RunStats {
            instructions: cpu.instructions() - start_instructions,
            states,
            emulated_seconds: states as f64 / f64::from(machine.clock_hz()),
            clock_hz: machine.clock_hz(),
            interrupts,
            console_bytes: machine.sci().bytes_sent(),
            resets: machine.resets(),
        },
        io_reports: machine.io_reports().to_vec(),
    }
}
