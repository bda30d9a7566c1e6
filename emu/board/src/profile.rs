//! States per function, attributed by PC through the symbol table (docs/design.md §8).
//!
//! The profiler follows the firmware's calls: a JSR or BSR enters the function at its target,
//! RTS leaves it; an interrupt (or TRAPA) enters its handler, RTE leaves it; a JMP to the start
//! of another function replaces the current one (a tail call). Each frame carries the phase it
//! belongs to: its own when its function is one of a phase's functions, else its caller's. Every
//! state goes to the phase of the frame that spends it, so a phase includes its callees — except
//! callees that are phases of their own — and an interrupt's entry (priority decision, stacking,
//! vector) belongs to its handler. States spent in SLEEP waiting for an interrupt are idle; all
//! others are busy. The lowest stack pointer seen is the stack's high-water mark. A watchdog
//! reset empties the call stack (its states, and what runs until the next call, are outside
//! every phase's functions unless the reset vector's code is one).

use std::collections::HashMap;

use crate::symbols::SymbolTable;
use h8300h::bus::FastPathHints;
use h8300h::cpu::decode::Instr;
use h8300h::cpu::{Cpu, CpuError, Event};

/// A phase: a name and the functions that make it up.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PhaseDef {
    /// The phase's name in reports (`forward`).
    pub name: String,
    /// Its functions' C names (`learner_forward`).
    pub functions: Vec<String>,
}

impl PhaseDef {
    /// A phase called `name` made of `functions`.
    #[must_use]
    pub fn new(name: &str, functions: &[&str]) -> PhaseDef {
        PhaseDef {
            name: name.to_string(),
            functions: functions.iter().map(|f| (*f).to_string()).collect(),
        }
    }
}

/// A phase names a function the symbol table does not have.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "phase `{phase}`: the symbol table has no function `{function}` (a `T`/`t` symbol of the image)"
)]
pub struct UnknownFunction {
    /// The phase.
    pub phase: String,
    /// The missing function.
    pub function: String,
}

#[derive(Clone, Copy, Debug)]
struct Frame {
    phase: usize,
}

/// States by phase, idle states, and the stack's high-water mark, as they accumulate.
#[derive(Clone, Debug)]
pub struct Profiler {
    names: Vec<String>,
    by_entry: HashMap<u32, usize>,
    /// The index of states not in any phase.
    other: usize,
    stack: Vec<Frame>,
    states: Vec<u64>,
    idle: u64,
    min_sp: u32,
    last_wake: Option<u64>,
    /// When each phase's function was first entered.
    first_entries: Vec<Option<u64>>,
    /// How often each phase's functions were entered.
    entries: Vec<u64>,
    function_starts: Vec<u32>,
}

impl Profiler {
    /// A profiler for `phases` over `symbols`. States outside every phase go to `other`.
    ///
    /// # Errors
    /// [`UnknownFunction`] for a phase function the table lacks.
    pub fn new(
        symbols: &SymbolTable,
        phases: &[PhaseDef],
        other: &str,
    ) -> Result<Self, UnknownFunction> {
        let mut names = Vec::new();
        let mut by_entry = HashMap::new();
        for (i, p) in phases.iter().enumerate() {
            names.push(p.name.clone());
            for f in &p.functions {
                let sym =
                    symbols
                        .get(f)
                        .filter(|s| s.is_function())
                        .ok_or_else(|| UnknownFunction {
                            phase: p.name.clone(),
                            function: f.clone(),
                        })?;
                by_entry.insert(sym.addr, i);
            }
        }
        let other_ix = names.len();
        names.push(other.to_string());
        let function_starts = symbols
            .symbols()
            .iter()
            .filter(|s| s.is_function())
            .map(|s| s.addr)
            .collect();
        Ok(Profiler {
            states: vec![0; names.len()],
            names,
            by_entry,
            other: other_ix,
            stack: Vec::new(),
            idle: 0,
            min_sp: u32::MAX,
            last_wake: None,
            first_entries: vec![None; other_ix + 1],
            entries: vec![0; other_ix + 1],
            function_starts,
        })
    }

    /// The phase names, in order; the last is the one for states outside every phase.
    #[must_use]
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Busy states per phase so far (same order as [`Profiler::names`]).
    #[must_use]
    pub fn states(&self) -> &[u64] {
        &self.states
    }

    /// States spent asleep so far.
    #[must_use]
    pub fn idle(&self) -> u64 {
        self.idle
    }

    /// When one of `phase`'s functions was first entered (the clock after the call), if one
    /// was; `phase` indexes [`Profiler::names`].
    #[must_use]
    pub fn first_entry(&self, phase: usize) -> Option<u64> {
        self.first_entries.get(phase).copied().flatten()
    }

    /// How often one of `phase`'s functions was entered so far.
    #[must_use]
    pub fn entries(&self, phase: usize) -> u64 {
        self.entries.get(phase).copied().unwrap_or(0)
    }

    /// When the CPU last woke from SLEEP (an interrupt ended the wait), if it has.
    #[must_use]
    pub fn last_wake(&self) -> Option<u64> {
        self.last_wake
    }

    /// The lowest ER7 seen (u32::MAX before the first instruction).
    #[must_use]
    pub fn min_sp(&self) -> u32 {
        self.min_sp
    }

    fn current(&self) -> usize {
        self.stack.last().map_or(self.other, |f| f.phase)
    }

    /// Enters the function at `entry` as a call would (for a caller that sets the PC itself
    /// rather than executing a JSR: its RTS leaves the frame again); `now` is the clock.
    pub fn enter_function(&mut self, entry: u32, now: u64) {
        self.enter_at(entry, now);
    }

    fn enter_at(&mut self, entry: u32, now: u64) {
        let own = self.by_entry.get(&entry).copied();
        // An entry into a phase from outside it (a phase's functions calling each other stay
        // one entry).
        if let Some(p) = own
            && self.current() != p
        {
            self.entries[p] += 1;
            if self.first_entries[p].is_none() {
                self.first_entries[p] = Some(now);
            }
        }
        let phase = own.unwrap_or_else(|| self.current());
        // A runaway recursion must not grow the shadow stack without bound.
        if self.stack.len() < 4096 {
            self.stack.push(Frame { phase });
        }
    }

    fn leave(&mut self) {
        self.stack.pop();
    }

    /// Runs `cpu` on `bus` until the clock reaches `deadline` or the CPU halts, attributing
    /// every state. Returns the last event ([`Event::Asleep`] when the deadline came).
    ///
    /// # Errors
    /// The core's error, with the CPU left at the failing instruction.
    pub fn run<B: FastPathHints>(
        &mut self,
        cpu: &mut Cpu,
        bus: &mut B,
        deadline: u64,
    ) -> Result<Event, CpuError> {
        loop {
            match self.run_one(cpu, bus, deadline)? {
                Event::Halted => return Ok(Event::Halted),
                Event::Asleep => return Ok(Event::Asleep),
                Event::Executed | Event::Interrupt(_) | Event::Reset | Event::Break => {}
            }
        }
    }

    /// One step of the CPU (an instruction, an interrupt's entry, or the wait in SLEEP up to
    /// the next interrupt or `deadline`), attributed.
    ///
    /// # Errors
    /// The core's error, with the CPU left at the failing instruction.
    pub fn run_one<B: FastPathHints>(
        &mut self,
        cpu: &mut Cpu,
        bus: &mut B,
        deadline: u64,
    ) -> Result<Event, CpuError> {
        {
            if bus.now() >= deadline {
                return Ok(Event::Asleep);
            }
            if cpu.sleeping() {
                // Wait for the interrupt here, so that the wait is idle and only the entry is
                // the handler's.
                let t = bus.now();
                bus.sleep_until_irq(deadline);
                self.idle += bus.now() - t;
                if bus.now() >= deadline {
                    return Ok(Event::Asleep);
                }
                self.last_wake = Some(bus.now());
            }
            let t0 = bus.now();
            let event = cpu.step(bus, deadline)?;
            let dt = bus.now() - t0;
            match event {
                Event::Executed => {
                    let cur = self.current();
                    self.states[cur] += dt;
                    match cpu.last_executed().instr {
                        Instr::Jsr(_) | Instr::Bsr { .. } | Instr::Trapa(_) => {
                            self.enter_at(cpu.pc(), bus.now());
                        }
                        Instr::Rts | Instr::Rte => self.leave(),
                        Instr::Jmp(_) => {
                            let to = cpu.pc();
                            if self.function_starts.binary_search(&to).is_ok() {
                                self.leave();
                                self.enter_at(to, bus.now());
                            }
                        }
                        _ => {}
                    }
                }
                Event::Interrupt(_) => {
                    self.enter_at(cpu.pc(), t0);
                    let cur = self.current();
                    self.states[cur] += dt;
                }
                Event::Asleep => self.idle += dt,
                Event::Halted | Event::Break => {
                    let cur = self.current();
                    self.states[cur] += dt;
                }
                // A watchdog reset: the program starts over, outside every function.
                Event::Reset => {
                    self.stack.clear();
                    let cur = self.current();
                    self.states[cur] += dt;
                }
            }
            self.min_sp = self.min_sp.min(cpu.er(7));
            Ok(event)
        }
    }
}
