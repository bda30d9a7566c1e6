//! Pin traces: the levels of the chip's pins and status lines as they change, each change at
//! the exact state it happens, for a logic-analyser view of a program (written as VCD files by
//! [`crate::vcd`]).
//!
//! # What is traced ([`Signal`])
//! TIOCA1 and TIOCA2 (PA4, PA6: ITU1/ITU2 outputs, or the port latch when the ITU does not
//! drive them), PB0–PB3, the EEPROM bus's SDA (P4.7) and SCL (P4.6) as *line levels*, ADST
//! and ADF of ADCSR, the ITU0 compare-match A interrupt request IMIA0 (flag and enable: the
//! robot's tick, from the compare match until the handler clears the flag) and SLEEP (the
//! CPU in sleep mode); and for each of the eleven ports (P1–P9, PA, PB) what the port itself
//! drives, one signal a pin ([`Signal::PortOut`]: the DR latch on an output pin, DDR = 1; 0 on
//! an input pin), so every port write a program makes shows at its instant.
//!
//! A line of the EEPROM bus is the wired AND of everything on it: low while the master (port
//! 4) or a part on the board pulls it low ([`Board::port4_pins`]); otherwise high only through
//! port 4's on-chip pull-up (P4PCR) or when the port drives it high; a released line without
//! pull-up floats and is traced 0, as a read of P4DR returns it ([`crate::periph::ports`]).
//! With nothing on port 4 ([`crate::pins::NullBoard`]) the lines are the port's own levels.
//!
//! # How changes are found at their instant
//! Nothing is stepped per state. Levels change for three reasons, and each is caught where
//! the chip computes it:
//! - a register write (a port latch, a DDR, ADST, an ITU register, a flag cleared): the MCU
//!   calls the tracer before the write (to record what happened up to that instant) and after
//!   it (to record the write's effect at the same instant);
//! - a peripheral's own events between writes (ITU compare matches and overflows that move
//!   TIOCA and set IMFA; A/D conversion ends that set ADF and clear ADST; an EEPROM's delayed
//!   SDA output): the tracer keeps copies of the ITU and the A/D converter taken after their
//!   last write, which evolve exactly as the real ones do until the next write, and walks
//!   their event instants ([`crate::periph::itu::Itu::next_event`],
//!   [`crate::periph::adc::Adc::next_event`]); the board logs the port-4 line changes its
//!   parts make with their instants ([`Board::set_pin_log`]);
//! - the CPU entering or leaving sleep mode ([`h8300h::bus::CpuSignal`]).
//!
//! The MCU calls the tracer only on I/O writes and CPU signals, so with no trace running the
//! cost is one test of an `Option` on those paths. Loop fast-forwarding, the fast path and the
//! model's shortcuts that skip no register access leave a trace unchanged; a shortcut that
//! replaces register accesses (the model's transaction-level save, its charged ticks) would
//! not, so trace the model with its shortcuts off.

use crate::periph::adc::Adc;
use crate::periph::itu::{IMFA, Itu};
use crate::periph::ports::{
    P4_SCL, P4_SDA, PA_TIOCA1, PA_TIOCA2, PB_TIOCA3, PB_TIOCA4, Port, PortId, Ports,
};
use crate::pins::Board;

/// A traced pin or status line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Signal {
    /// TIOCA1 (PA4): ITU1's output, the left motor's PWM on the robot.
    Tioca1,
    /// TIOCA2 (PA6): ITU2's output, the right motor's PWM.
    Tioca2,
    /// PB0: the left H-bridge's IN1.
    Pb0,
    /// PB1: the left H-bridge's IN2.
    Pb1,
    /// PB2: the right H-bridge's IN1.
    Pb2,
    /// PB3: the right H-bridge's IN2.
    Pb3,
    /// P4.7: the EEPROM bus's SDA line.
    Sda,
    /// P4.6: the EEPROM bus's SCL line.
    Scl,
    /// ADCSR.ADST: an A/D run under way.
    Adst,
    /// ADCSR.ADF: A/D end flag.
    Adf,
    /// ITU0's compare-match A interrupt request (IMFA0 and IMIEA0): the robot's 10 ms tick.
    Imia0,
    /// The CPU in sleep mode.
    Sleep,
    /// Pin `bit` (0–7) of a port as the port drives it: its DR bit while the pin is an output
    /// (DDR = 1), else 0 (named `P1_0`…`PB_7` in a VCD file).
    PortOut(PortId, u8),
}

/// How many signals a trace has: the twelve named ones and eight per port.
pub const SIGNAL_COUNT: usize = 12 + 8 * 11;

/// The named signals, in the order traces list them (then the ports' pins).
const NAMED: [Signal; 12] = [
    Signal::Tioca1,
    Signal::Tioca2,
    Signal::Pb0,
    Signal::Pb1,
    Signal::Pb2,
    Signal::Pb3,
    Signal::Sda,
    Signal::Scl,
    Signal::Adst,
    Signal::Adf,
    Signal::Imia0,
    Signal::Sleep,
];

impl Signal {
    /// Every signal, in the order traces list them: the twelve named ones, then the ports'
    /// pins, P1.0–P1.7 to PB.0–PB.7.
    pub const ALL: [Signal; SIGNAL_COUNT] = {
        let mut all = [Signal::Sleep; SIGNAL_COUNT];
        let mut i = 0;
        while i < 12 {
            all[i] = NAMED[i];
            i += 1;
        }
        let mut p = 0;
        while p < 11 {
            let mut b = 0;
            while b < 8 {
                all[12 + 8 * p + b] = Signal::PortOut(PortId::ALL[p], b as u8);
                b += 1;
            }
            p += 1;
        }
        all
    };

    /// The twelve named signals (the ports' pins are not among them).
    pub const NAMED: [Signal; 12] = NAMED;

    /// The signal's name in traces (a VCD variable name: no spaces).
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Signal::Tioca1 => "TIOCA1",
            Signal::Tioca2 => "TIOCA2",
            Signal::Pb0 => "PB0",
            Signal::Pb1 => "PB1",
            Signal::Pb2 => "PB2",
            Signal::Pb3 => "PB3",
            Signal::Sda => "SDA",
            Signal::Scl => "SCL",
            Signal::Adst => "ADST",
            Signal::Adf => "ADF",
            Signal::Imia0 => "IMIA0",
            Signal::Sleep => "SLEEP",
            Signal::PortOut(p, _) => p.name(),
        }
    }

    /// What the signal is, in a few words (for a trace's header).
    #[must_use]
    pub const fn description(self) -> &'static str {
        match self {
            Signal::Tioca1 => "TIOCA1 = PA4, ITU1 output (left motor PWM)",
            Signal::Tioca2 => "TIOCA2 = PA6, ITU2 output (right motor PWM)",
            Signal::Pb0 => "PB0 (left H-bridge IN1)",
            Signal::Pb1 => "PB1 (left H-bridge IN2)",
            Signal::Pb2 => "PB2 (right H-bridge IN1)",
            Signal::Pb3 => "PB3 (right H-bridge IN2)",
            Signal::Sda => "P4.7 = SDA line level (wired AND of port, EEPROMs, pull-up)",
            Signal::Scl => "P4.6 = SCL line level (wired AND of port, EEPROMs, pull-up)",
            Signal::Adst => "ADCSR.ADST (A/D run under way)",
            Signal::Adf => "ADCSR.ADF (A/D end flag)",
            Signal::Imia0 => "ITU0 IMIA request (IMFA0 and IMIEA0: the 10 ms tick)",
            Signal::Sleep => "CPU in sleep mode",
            Signal::PortOut(..) => "the port's output: DR on output pins (DDR = 1), 0 on inputs",
        }
    }

    /// The signal's place in [`Signal::ALL`] (and in a trace's level arrays).
    #[inline]
    #[must_use]
    pub const fn index(self) -> usize {
        match self {
            Signal::Tioca1 => 0,
            Signal::Tioca2 => 1,
            Signal::Pb0 => 2,
            Signal::Pb1 => 3,
            Signal::Pb2 => 4,
            Signal::Pb3 => 5,
            Signal::Sda => 6,
            Signal::Scl => 7,
            Signal::Adst => 8,
            Signal::Adf => 9,
            Signal::Imia0 => 10,
            Signal::Sleep => 11,
            Signal::PortOut(p, b) => 12 + 8 * p.index() + (b & 7) as usize,
        }
    }
}

/// One change of a traced signal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PinChange {
    /// The instant, in states since reset.
    pub t: u64,
    /// The signal.
    pub signal: Signal,
    /// Its level from `t` on.
    pub level: bool,
}

/// An accepted interrupt: the instant its exception handling began and its vector.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Accepted {
    /// The instant, in states since reset.
    pub t: u64,
    /// The vector.
    pub vector: u8,
}

/// A finished trace: every signal's level at the start and each change after it, in time
/// order (changes at one instant in the order the chip made them; only real changes are
/// kept), from `start` to `end`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PinTrace {
    /// φ of the MCU (states per second).
    pub clock_hz: u32,
    /// The first instant of the trace (states).
    pub start: u64,
    /// The last instant of the trace (states).
    pub end: u64,
    /// Each signal's level at `start`, in [`Signal::ALL`] order.
    pub initial: [bool; SIGNAL_COUNT],
    /// The changes after `start`.
    pub changes: Vec<PinChange>,
    /// The interrupts accepted during the trace.
    pub interrupts: Vec<Accepted>,
}

impl PinTrace {
    /// The level of `signal` at `t` (the initial level before `start`).
    #[must_use]
    pub fn level_at(&self, signal: Signal, t: u64) -> bool {
        self.changes
            .iter()
            .take_while(|c| c.t <= t)
            .filter(|c| c.signal == signal)
            .last()
            .map_or(self.initial[signal.index()], |c| c.level)
    }

    /// The changes of one signal, in time order.
    pub fn changes_of(&self, signal: Signal) -> impl Iterator<Item = &PinChange> {
        self.changes.iter().filter(move |c| c.signal == signal)
    }
}

/// A trace under way, held by the MCU.
#[derive(Clone, Debug)]
pub(crate) struct Tracer {
    start: u64,
    initial: [bool; SIGNAL_COUNT],
    levels: [bool; SIGNAL_COUNT],
    changes: Vec<PinChange>,
    interrupts: Vec<Accepted>,
    /// The ITU as of its last write (it evolves from there as the real one does).
    itu: Itu,
    /// The A/D converter as of its last write.
    adc: Adc,
    /// The port-4 line levels as the board leaves them ([`Board::port4_pins`]), as of the last
    /// logged change taken.
    lines: u8,
    sleeping: bool,
    /// Changes up to this instant are recorded.
    caught_up: u64,
}

/// What the tracer reads off the chip to work out the levels.
pub(crate) struct ChipView<'a, B: Board> {
    pub(crate) ports: &'a Ports,
    pub(crate) board: &'a mut B,
}

impl Tracer {
    /// Starts a trace at `now` from the chip's present state (`sleeping`: whether the CPU is in
    /// sleep mode now).
    pub(crate) fn start<B: Board>(
        now: u64,
        itu: &Itu,
        adc: &Adc,
        chip: ChipView<'_, B>,
        sleeping: bool,
    ) -> Tracer {
        chip.board.set_pin_log(true);
        let lines = chip.board.port4_pins(now);
        let mut t = Tracer {
            start: now,
            initial: [false; SIGNAL_COUNT],
            levels: [false; SIGNAL_COUNT],
            changes: Vec::new(),
            interrupts: Vec::new(),
            itu: itu.clone(),
            adc: adc.clone(),
            lines,
            sleeping,
            caught_up: now,
        };
        t.levels = t.compute(now, chip.ports);
        t.initial = t.levels;
        t
    }

    /// Every signal's level at `t` from the copies, the port-4 line levels taken so far and the ports.
    fn compute(&self, t: u64, ports: &Ports) -> [bool; SIGNAL_COUNT] {
        let mut v = [false; SIGNAL_COUNT];
        let pa = ports.port_a();
        let pin_a = |ch: usize, bit: u8| {
            let (level, drives) = self.itu.output_at(ch, t);
            if drives {
                level
            } else {
                pa.output_levels() & bit != 0
            }
        };
        v[Signal::Tioca1.index()] = pin_a(1, PA_TIOCA1);
        v[Signal::Tioca2.index()] = pin_a(2, PA_TIOCA2);
        let mut pb = ports.port_b().output_levels();
        for (ch, bit) in [(3, PB_TIOCA3), (4, PB_TIOCA4)] {
            let (level, drives) = self.itu.output_at(ch, t);
            if drives {
                pb = (pb & !bit) | if level { bit } else { 0 };
            }
        }
        for (k, s) in [Signal::Pb0, Signal::Pb1, Signal::Pb2, Signal::Pb3]
            .into_iter()
            .enumerate()
        {
            v[s.index()] = pb & (1 << k) != 0;
        }
        let p4 = ports.port4();
        v[Signal::Sda.index()] = line_level(self.lines, &p4, P4_SDA);
        v[Signal::Scl.index()] = line_level(self.lines, &p4, P4_SCL);
        let (adst, adf) = self.adc.status_at(t);
        v[Signal::Adst.index()] = adst;
        v[Signal::Adf.index()] = adf;
        v[Signal::Imia0.index()] = self.itu.requests_of(0, t) & IMFA != 0;
        v[Signal::Sleep.index()] = self.sleeping;
        for p in PortId::ALL {
            let out = ports.port(p).output_levels();
            for b in 0..8u8 {
                v[Signal::PortOut(p, b).index()] = out & (1 << b) != 0;
            }
        }
        v
    }

    /// Records the signals that differ at `t` from their last level.
    fn sample(&mut self, t: u64, ports: &Ports) {
        let now = self.compute(t, ports);
        for s in Signal::ALL {
            let i = s.index();
            if now[i] != self.levels[i] {
                self.levels[i] = now[i];
                self.changes.push(PinChange {
                    t,
                    signal: s,
                    level: now[i],
                });
            }
        }
    }

    /// Records every change up to `now` that happened without a write: the peripherals'
    /// events and the board's logged port-4 changes, in time order. The board is brought to
    /// `now` first (as the next access would; it changes nothing it would not).
    pub(crate) fn catch_up<B: Board>(&mut self, now: u64, chip: ChipView<'_, B>) {
        chip.board.sync(now);
        let log = chip.board.take_pin_log();
        let mut log = log.into_iter().peekable();
        let mut t = self.caught_up;
        loop {
            let next = [
                self.itu.next_event(t),
                self.adc.next_event(t),
                log.peek().map(|&(at, _)| at),
            ]
            .into_iter()
            .flatten()
            .filter(|&e| e <= now)
            .min();
            let Some(e) = next else { break };
            while let Some(&(at, levels)) = log.peek()
                && at <= e
            {
                self.lines = levels;
                log.next();
            }
            // The modules' next events lie strictly after `t`; a logged line change is never
            // before the instant the trace last caught up to.
            t = e.max(t);
            self.sample(t, chip.ports);
        }
        self.caught_up = now.max(self.caught_up);
    }

    /// After a write at `now`: takes fresh copies of the modules written to and records the
    /// write's effect.
    pub(crate) fn after_write<B: Board>(
        &mut self,
        now: u64,
        itu: Option<&Itu>,
        adc: Option<&Adc>,
        chip: ChipView<'_, B>,
    ) {
        if let Some(itu) = itu {
            self.itu = itu.clone();
        }
        if let Some(adc) = adc {
            self.adc = adc.clone();
        }
        // The write may have moved the board's lines (port 4): take them.
        for (_, levels) in chip.board.take_pin_log() {
            self.lines = levels;
        }
        self.sample(now, chip.ports);
        self.caught_up = now.max(self.caught_up);
    }

    /// The CPU entered (`true`) or left sleep mode at `now` (after [`Tracer::catch_up`]).
    pub(crate) fn set_sleeping(&mut self, now: u64, sleeping: bool, ports: &Ports) {
        self.sleeping = sleeping;
        self.sample(now, ports);
    }

    /// An interrupt was accepted at `now`.
    pub(crate) fn accepted(&mut self, now: u64, vector: u8) {
        self.interrupts.push(Accepted { t: now, vector });
    }

    /// The last interrupt accepted so far, if any.
    pub(crate) fn last_accepted(&self) -> Option<Accepted> {
        self.interrupts.last().copied()
    }

    /// The trace's first instant and the levels then.
    pub(crate) fn beginning(&self) -> (u64, [bool; SIGNAL_COUNT]) {
        (self.start, self.initial)
    }

    /// Changes recorded and not yet drained.
    pub(crate) fn pending(&self) -> usize {
        self.changes.len()
    }

    /// Changes are recorded up to this instant.
    pub(crate) fn caught_up(&self) -> u64 {
        self.caught_up
    }

    /// Takes the changes before `t` (in time order; the later ones stay) and the interrupts
    /// accepted before it (only the last is kept, for [`Tracer::last_accepted`]).
    pub(crate) fn drain_before(&mut self, t: u64) -> Vec<PinChange> {
        self.changes.sort_by_key(|c| c.t);
        let n = self.changes.partition_point(|c| c.t < t);
        let last = self.interrupts.last().copied();
        self.interrupts.clear();
        self.interrupts.extend(last);
        self.changes.drain(..n).collect()
    }

    /// Ends the trace at `now` (after [`Tracer::catch_up`]).
    pub(crate) fn finish<B: Board>(mut self, now: u64, clock_hz: u32, board: &mut B) -> PinTrace {
        board.set_pin_log(false);
        // Changes at one instant stay in the order they were made; the board's log may deliver
        // a change late (with its own instant), so sort by instant, stably.
        self.changes.sort_by_key(|c| c.t);
        PinTrace {
            clock_hz,
            start: self.start,
            end: now.max(self.start),
            initial: self.initial,
            changes: self.changes,
            interrupts: self.interrupts,
        }
    }
}

/// A line of port 4 (bit `bit`) as the pin sees it: low when the board holds it low (someone
/// pulls it; `lines` as [`Board::port4_pins`] reads them); else high through the pull-up of an
/// input pin or when the port drives a 1; else floating, traced as 0.
fn line_level(lines: u8, p4: &Port, bit: u8) -> bool {
    lines & bit != 0 && (p4.pulled_up() & bit != 0 || p4.output_levels() & bit != 0)
}

/// Names the code a program counter is in (a firmware's functions, from its symbol table:
/// `robot_board::symbols::SymbolTable` implements it), for the phase signal of a trace and the
/// instruction trace of `h8swarm emu --trace`.
pub trait CodeNames {
    /// The name of the code holding `pc` (`None`: outside every named piece of code).
    fn name_at(&self, pc: u32) -> Option<&str>;
}

/// The phase a trace shows for a program counter outside every named piece of code.
pub const UNNAMED_PHASE: &str = "?";

/// The phase of the code at `pc` (its name, or [`UNNAMED_PHASE`]): what the phase signal of a
/// trace and the instruction trace both show.
#[must_use]
pub fn phase_name(names: &dyn CodeNames, pc: u32) -> &str {
    names.name_at(pc).unwrap_or(UNNAMED_PHASE)
}

/// Which piece of code the CPU runs, as it changes: the phase signal of a trace.
///
/// The phase at an instant is the name ([`phase_name`]) of the code holding the instruction
/// the CPU executes then. An interrupt's exception handling (from its acceptance to the
/// handler's first instruction) belongs to the handler; while the CPU sleeps the phase stays
/// that of the SLEEP instruction's code (the SLEEP signal shows the sleep).
pub struct PhaseRecorder {
    names: std::sync::Arc<dyn CodeNames + Send + Sync>,
    current: Option<String>,
    changes: Vec<(u64, String)>,
}

impl std::fmt::Debug for PhaseRecorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PhaseRecorder")
            .field("current", &self.current)
            .field("changes", &self.changes.len())
            .finish_non_exhaustive()
    }
}

impl PhaseRecorder {
    /// A recorder naming code with `names`.
    #[must_use]
    pub fn new(names: std::sync::Arc<dyn CodeNames + Send + Sync>) -> PhaseRecorder {
        PhaseRecorder {
            names,
            current: None,
            changes: Vec::new(),
        }
    }

    /// The code at `pc` runs from `t` on.
    pub fn observe(&mut self, t: u64, pc: u32) {
        let name = phase_name(self.names.as_ref(), pc);
        if self.current.as_deref() != Some(name) {
            self.current = Some(name.to_string());
            self.changes.push((t, name.to_string()));
        }
    }

    /// The names used.
    #[must_use]
    pub fn names(&self) -> &(dyn CodeNames + Send + Sync) {
        self.names.as_ref()
    }

    /// The changes recorded so far: (instant, phase from then on), in time order.
    #[must_use]
    pub fn changes(&self) -> &[(u64, String)] {
        &self.changes
    }

    /// Changes recorded and not yet taken.
    #[must_use]
    pub fn pending(&self) -> usize {
        self.changes.len()
    }

    /// Takes the changes before `t` (the later ones stay; the phase being recorded goes on).
    pub fn drain_before(&mut self, t: u64) -> Vec<(u64, String)> {
        let n = self.changes.partition_point(|c| c.0 < t);
        self.changes.drain(..n).collect()
    }

    /// Takes the changes recorded so far and starts afresh (the next observation records
    /// its phase whatever it is).
    pub fn take(&mut self) -> Vec<(u64, String)> {
        self.current = None;
        std::mem::take(&mut self.changes)
    }
}
