//! Where a program's states go, by call stack: a profile written as *folded stacks*, the
//! text format of Brendan Gregg's `flamegraph.pl`, which `inferno-flamegraph` and speedscope
//! (<https://www.speedscope.app>, "import") read as well. One line per call stack, its frames
//! from the outermost to the innermost separated by `;`, a space and the states spent in it:
//!
//! ```text
//! _start;main;compute 1840
//! _start;main;compute;tick_isr [interrupt 24] 68
//! _start;main;[sleep] 250000
//! ```
//!
//! The stacks follow the program's calls as the CPU executes them, instruction by instruction:
//! JSR and BSR enter a frame named by the function at their target, RTS leaves it; an
//! interrupt's exception handling enters a frame for its handler *under the function it
//! interrupted*, marked `[interrupt V]` with its vector, and RTE leaves it (TRAPA likewise,
//! marked `[trap N]`); a JMP to the first instruction of a function replaces the frame (a
//! tail call). The outermost frame is the code the CPU started in (the reset vector's target).
//! Names come from the image's symbols ([`CodeNames`]); without one for an address, the frame
//! is named by the address (`H'0001F0`).
//!
//! Every state of the run is in exactly one line, so the lines add up to the run's states:
//! an instruction's states go to the stack it ran in (a call's own states to the caller), an
//! interrupt's entry to its handler's frame, the states the CPU spends in sleep mode to
//! `[sleep]` under the stack that executed SLEEP, and the reset's states (the vector fetch at
//! power-on, and each watchdog reset with its 518 states) to a stack of its own, `[reset]`;
//! a watchdog reset starts the stacks afresh.

use std::collections::HashMap;
use std::fmt::Write as _;

use crate::trace::CodeNames;
use h8300h::bus::FastPathHints;
use h8300h::cpu::decode::Instr;
use h8300h::cpu::{Cpu, CpuError, Event};

/// The frame of the states spent in sleep mode.
pub const SLEEP_FRAME: &str = "[sleep]";
/// The stack of the reset's states.
pub const RESET_FRAME: &str = "[reset]";
/// Deepest stack followed: a runaway recursion folds its deeper calls into the last frame.
pub const MAX_DEPTH: usize = 512;

/// A call stack's states as they accumulate ([module docs](self)).
pub struct StackProfile {
    names: Option<std::sync::Arc<dyn CodeNames + Send + Sync>>,
    /// Interned frame names.
    frame_ids: HashMap<String, u32>,
    frame_names: Vec<String>,
    /// The current stack, outermost first (frame ids).
    stack: Vec<u32>,
    /// States per stack.
    states: HashMap<Vec<u32>, u64>,
    /// The clock up to which states are attributed.
    seen: u64,
    /// Function entry points (from the names), for tail calls: a JMP lands on one.
    entries: Option<Vec<u32>>,
}

impl std::fmt::Debug for StackProfile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StackProfile")
            .field("depth", &self.stack.len())
            .field("stacks", &self.states.len())
            .field("seen", &self.seen)
            .finish_non_exhaustive()
    }
}

impl StackProfile {
    /// A profile of a program whose CPU is at `cpu.pc()` with the clock at `now`: the states
    /// before `now` (the reset's vector fetch) go to `[reset]`. `names` name the code;
    /// `entries`, the functions' first addresses in ascending order, let a JMP to one count as
    /// a tail call (without them JMP changes no frame).
    #[must_use]
    pub fn new(
        names: Option<std::sync::Arc<dyn CodeNames + Send + Sync>>,
        entries: Option<Vec<u32>>,
        cpu: &Cpu,
        now: u64,
    ) -> StackProfile {
        let mut p = StackProfile {
            names,
            frame_ids: HashMap::new(),
            frame_names: Vec::new(),
            stack: Vec::new(),
            states: HashMap::new(),
            seen: 0,
            entries,
        };
        let reset = p.intern(RESET_FRAME.to_string());
        p.add(&[reset], now);
        p.seen = now;
        let root = p.function_frame(cpu.pc(), None);
        p.stack.push(root);
        p
    }

    fn intern(&mut self, name: String) -> u32 {
        if let Some(&id) = self.frame_ids.get(&name) {
            return id;
        }
        let id = self.frame_names.len() as u32;
        self.frame_names.push(name.clone());
        self.frame_ids.insert(name, id);
        id
    }

    /// The frame for code entered at `addr`, marked with `mark` (an interrupt, a trap).
    fn function_frame(&mut self, addr: u32, mark: Option<String>) -> u32 {
        let base = self
            .names
            .as_deref()
            .and_then(|n| n.name_at(addr).map(str::to_string))
            .unwrap_or_else(|| format!("H'{addr:06X}"));
        let name = match mark {
            Some(m) => format!("{base} [{m}]"),
            None => base,
        };
        self.intern(name)
    }

    fn add(&mut self, stack: &[u32], states: u64) {
        if states == 0 {
            return;
        }
        match self.states.get_mut(stack) {
            Some(v) => *v += states,
            None => {
                self.states.insert(stack.to_vec(), states);
            }
        }
    }

    /// States up to `now` not yet attributed (the clock moved without a step: a wait the
    /// caller made): to `[sleep]` under the current stack when `sleeping`, else to the stack.
    pub fn catch_up(&mut self, now: u64, sleeping: bool) {
        if now <= self.seen {
            return;
        }
        let dt = now - self.seen;
        self.seen = now;
        if sleeping {
            let sleep = self.intern(SLEEP_FRAME.to_string());
            let mut s = self.stack.clone();
            s.push(sleep);
            self.add(&s, dt);
        } else {
            let s = self.stack.clone();
            self.add(&s, dt);
        }
    }

    fn push(&mut self, frame: u32) {
        if self.stack.len() < MAX_DEPTH {
            self.stack.push(frame);
        }
    }

    fn pop(&mut self) {
        if self.stack.len() > 1 {
            self.stack.pop();
        }
    }

    /// Attributes the step that began at `t0` (with the CPU in sleep mode if `was_sleeping`)
    /// and ended at `now` with `event`, then follows the call it made (the CPU's state after
    /// it).
    pub fn after_step(
        &mut self,
        cpu: &Cpu,
        t0: u64,
        now: u64,
        was_sleeping: bool,
        event: &Result<Event, CpuError>,
    ) {
        self.catch_up(t0, was_sleeping);
        let dt = now.saturating_sub(self.seen.max(t0));
        self.seen = self.seen.max(now);
        match event {
            Ok(Event::Executed) => {
                let s = self.stack.clone();
                self.add(&s, dt);
                match cpu.last_executed().instr {
                    Instr::Jsr(_) | Instr::Bsr { .. } => {
                        let f = self.function_frame(cpu.pc(), None);
                        self.push(f);
                    }
                    Instr::Trapa(n) => {
                        let f = self.function_frame(cpu.pc(), Some(format!("trap {n}")));
                        self.push(f);
                    }
                    Instr::Rts | Instr::Rte => self.pop(),
                    Instr::Jmp(_) => {
                        let to = cpu.pc();
                        if self
                            .entries
                            .as_ref()
                            .is_some_and(|e| e.binary_search(&to).is_ok())
                        {
                            self.pop_top_for(to);
                        }
                    }
                    _ => {}
                }
            }
            Ok(Event::Interrupt(v)) => {
                let f = self.function_frame(cpu.pc(), Some(format!("interrupt {v}")));
                self.push(f);
                let s = self.stack.clone();
                self.add(&s, dt);
            }
            Ok(Event::Reset) => {
                let reset = self.intern(RESET_FRAME.to_string());
                self.add(&[reset], dt);
                self.stack.clear();
                let root = self.function_frame(cpu.pc(), None);
                self.stack.push(root);
            }
            Ok(Event::Asleep) => {
                let sleep = self.intern(SLEEP_FRAME.to_string());
                let mut s = self.stack.clone();
                s.push(sleep);
                self.add(&s, dt);
            }
            Ok(Event::Halted | Event::Break) | Err(_) => {
                let s = self.stack.clone();
                self.add(&s, dt);
            }
        }
    }

    /// A tail call: the top frame becomes the function at `to`.
    fn pop_top_for(&mut self, to: u32) {
        let f = self.function_frame(to, None);
        if let Some(top) = self.stack.last_mut() {
            *top = f;
        }
    }

    /// One step of `cpu` on `bus` up to `deadline`, attributed: a CPU in sleep mode first
    /// waits for its interrupt here (those states are `[sleep]`), then steps.
    ///
    /// # Errors
    /// The core's.
    pub fn step<B: FastPathHints>(
        &mut self,
        cpu: &mut Cpu,
        bus: &mut B,
        deadline: u64,
    ) -> Result<Event, CpuError> {
        if cpu.sleeping() {
            let t = bus.now();
            self.catch_up(t, false);
            bus.sleep_until_irq(deadline);
            self.catch_up(bus.now(), true);
        }
        let t0 = bus.now();
        let sleeping = cpu.sleeping();
        let event = cpu.step(bus, deadline);
        self.after_step(cpu, t0, bus.now(), sleeping, &event);
        event
    }

    /// The states attributed so far: the clock the profile has reached.
    #[must_use]
    pub fn total(&self) -> u64 {
        self.states.values().sum()
    }

    /// The profile in the folded format, one stack a line, in the stacks' text order.
    #[must_use]
    pub fn folded(&self) -> String {
        let mut lines: Vec<(String, u64)> = self
            .states
            .iter()
            .map(|(stack, &n)| {
                let names: Vec<&str> = stack
                    .iter()
                    .map(|&id| self.frame_names[id as usize].as_str())
                    .collect();
                (names.join(";"), n)
            })
            .collect();
        lines.sort();
        let mut out = String::new();
        for (stack, n) in lines {
            let _ = writeln!(out, "{stack} {n}");
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Names;
    impl CodeNames for Names {
        fn name_at(&self, pc: u32) -> Option<&str> {
            match pc {
                0x100..0x200 => Some("main"),
                0x200..0x300 => Some("f"),
                _ => None,
            }
        }
    }

    #[test]
    fn catch_up_attributes_waits_and_lines_add_up() {
        let mut cpu = Cpu::new();
        cpu.set_pc(0x100);
        let mut p = StackProfile::new(Some(std::sync::Arc::new(Names)), None, &cpu, 4);
        p.catch_up(10, false);
        p.catch_up(30, true);
        let text = p.folded();
        assert_eq!(text, "[reset] 4\nmain 6\nmain;[sleep] 20\n");
        assert_eq!(p.total(), 30);
        // No symbols: frames by address.
        let mut cpu = Cpu::new();
        cpu.set_pc(0x400);
        let p = StackProfile::new(None, None, &cpu, 0);
        p.folded().is_empty().then_some(()).expect("nothing yet");
        assert_eq!(p.frame_names[1], "H'000400");
    }
}
