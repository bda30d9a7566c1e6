//! The H8/300H CPU core in advanced mode (24-bit addresses, 32-bit ER0–ER7, ER7 = SP).
//!
//! [`mod@decode`] turns instruction words into an [`decode::Instr`], `exec` carries it out,
//! [`timing`] holds the manual's internal-state counts, [`disasm`] prints instructions as
//! `h8300-hms-objdump -d` does, and [`stack`] is the stack guard
//! ([`Cpu::set_stack_guard`]).
//!
//! The core is generic over [`Bus`] (static dispatch). Every fetch and data access goes
//! through the bus, which charges the states of the area it touches; the internal states are
//! charged with [`Bus::internal`]. Two paths run the same instructions to the same states:
//! [`Cpu::step_reference`] (every word fetched through the bus, one generic executor) and
//! [`Cpu::step`] (per-form handlers for ROM code, `fast`, when the bus shows a
//! [`FastPathHints::code_generation`] token; off with [`Cpu::set_fast_path`]). [`Cpu::run`]
//! and [`Cpu::run_until`] step up to a deadline and fast-forward loops (`ffwd`, off with
//! [`Cpu::set_fast_forward`]) within the bus's promises
//! ([`FastPathHints::reads_stable_until`], [`FastPathHints::irq_stable_until`]); the skipped
//! work is counted in [`Cpu::skipped_instructions`]. [`Cpu::step`] never skips. The decode
//! caches are emptied when the bus's token changes and by [`Cpu::flush_decode_cache`].
//!
//! What the manual leaves open and what this core does (DIVXS's N flag, division by zero,
//! DAA/DAS, MOVFPE/MOVTPE as [`CpuError::Unsupported`], interrupt entry), the paths and how
//! tests hold them together: docs/emulator-accuracy.md.

pub mod decode;
pub mod disasm;
mod exec;
mod fast;
mod ffwd;
mod idle;
mod shared_code;
pub mod stack;
pub mod timing;

pub use idle::{IdleRun, MAX_CYCLE};
pub use shared_code::SharedCode;
pub use stack::{StackAccess, StackFault, StackGuard, StackGuardMode, StackRoom};

use std::sync::Arc;

use crate::bus::{BREAK_REQUEST, Bus, CpuSignal, FastPathHints, RESET_REQUEST};
use crate::memmap::Area;
use decode::{DecodeError, Decoded, Instr, WordSource, decode};

/// CCR bit 7: interrupt mask.
pub const CCR_I: u8 = 0x80;
/// CCR bit 6: user bit / interrupt mask (UI).
pub const CCR_UI: u8 = 0x40;
/// CCR bit 5: half-carry.
pub const CCR_H: u8 = 0x20;
/// CCR bit 4: user bit.
pub const CCR_U: u8 = 0x10;
/// CCR bit 3: negative.
pub const CCR_N: u8 = 0x08;
/// CCR bit 2: zero.
pub const CCR_Z: u8 = 0x04;
/// CCR bit 1: overflow.
pub const CCR_V: u8 = 0x02;
/// CCR bit 0: carry.
pub const CCR_C: u8 = 0x01;

/// Vector number of the reset exception (docs/design.md §4.1).
pub const VECTOR_RESET: u8 = 0;
/// Vector number of NMI (H8/3052F hardware manual, Table 5-3).
pub const VECTOR_NMI: u8 = 7;
/// First TRAPA vector (TRAPA #0 = 8 ... #3 = 11; docs/design.md §4.1).
pub const VECTOR_TRAPA0: u8 = 8;
/// Vector number of IRQ0 (H8/3052F hardware manual, Table 5-3; IRQ0–IRQ5 = 12–17).
pub const VECTOR_IRQ0: u8 = 12;
/// Vector number of IRQ5.
pub const VECTOR_IRQ5: u8 = 17;
/// Bytes per vector in advanced mode.
pub const VECTOR_BYTES: u32 = 4;

/// Why the core stopped a program.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CpuError {
    /// The bytes at PC are no H8/300H instruction.
    #[error("undefined opcode at PC H'{pc:06X}: {bytes}")]
    UndefinedOpcode {
        /// Address of the instruction.
        pc: u32,
        /// The bytes read, as `xx xx ...`.
        bytes: String,
    },
    /// An instruction fetch went outside ROM and RAM (docs/design.md §7).
    #[error(
        "instruction fetch outside ROM and RAM at H'{addr:06X} (instruction at PC H'{pc:06X}, area {area:?}); code may run only from ROM H'000000-H'07FFFF or RAM H'FFDF10-H'FFFF0F"
    )]
    FetchOutside {
        /// Address of the instruction.
        pc: u32,
        /// The address of the refused fetch.
        addr: u32,
        /// The area that address lies in.
        area: Area,
    },
    /// An instruction the H8/3052F cannot execute.
    #[error("unsupported instruction at PC H'{pc:06X}: {text} ({why})")]
    Unsupported {
        /// Address of the instruction.
        pc: u32,
        /// The instruction, disassembled.
        text: String,
        /// Why it cannot run.
        why: &'static str,
    },
    /// A stack access left the stack's room under a guard that stops ([`stack`]).
    #[error("{0}")]
    StackOverflow(Box<StackFault>),
}

/// What one call of [`Cpu::step`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event {
    /// One instruction ran.
    Executed,
    /// An interrupt was accepted (exception handling ran; no instruction).
    Interrupt(u8),
    /// SLEEP ran with CCR.I = 1 and no NMI pending: the program has halted (docs/design.md §7). Further
    /// steps do nothing and report this again.
    Halted,
    /// The CPU is in sleep mode and the deadline passed with no interrupt to wake it.
    Asleep,
    /// The bus's reset request ([`RESET_REQUEST`]: the chip's internal reset, the watchdog's)
    /// was taken: the chip reset itself, and the CPU starts over from the reset vector
    /// (registers cleared, CCR.I = 1). No instruction ran.
    Reset,
    /// The bus asked the CPU to stop before the next instruction ([`BREAK_REQUEST`]: the chip
    /// saw something its owner wants to look at with the CPU in hand, such as the first access
    /// to a register it does not model). Nothing ran and nothing changed; the next step goes on
    /// where this one stopped ([`Cpu::last_pc`] is the instruction that was executed last).
    Break,
}

/// Run state of the CPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RunState {
    Running,
    Sleeping,
    Halted,
}

/// An empty predecode-cache slot (length 0 marks it).
const EMPTY_SLOT: Decoded = Decoded {
    instr: Instr::Nop,
    words: 0,
};

/// States of one instruction-word fetch from ROM (what the fast path charges per word).
const ROM_FETCH_STATES: u32 = Area::Rom.word_states();

/// `Cpu::last_index` when the last instruction is in `last_copy`, not in the cache.
const LAST_IN_COPY: u32 = u32::MAX;

/// The H8/300H CPU: registers, run state and the decode caches.
#[derive(Clone, Debug)]
pub struct Cpu {
    er: [u32; 8],
    pc: u32,
    ccr: u8,
    state: RunState,
    /// Set by LDC/ANDC/ORC/XORC: no interrupt is accepted before the next instruction.
    irq_inhibit: bool,
    /// Decoded ROM instructions, indexed by address / 2; grows on demand, and may be shared
    /// with other CPUs running the same image ([`SharedCode`]; copied before a write).
    cache: Arc<[Decoded]>,
    /// The fast path's handlers of the same instructions, same index, grown and shared alike.
    fast: Arc<[fast::Slot]>,
    /// The bus's [`FastPathHints::code_generation`] token the caches were filled under (0: none; the
    /// tokens of [`crate::bus::fresh_code_generation`] start at 1).
    code_generation: u64,
    /// Whether [`Cpu::step`] may take the fast path.
    fast_path: bool,
    /// Whether [`Cpu::run_until`] fast-forwards loops ([`ffwd`]).
    fast_forward: bool,
    /// What [`ffwd`] knows about each back edge taken so far, in the order they were first
    /// taken.
    loops: Vec<ffwd::Loop>,
    /// Per slot of `fast`, its back edge's place in `loops` ([`ffwd::NO_LOOP`]: none yet).
    loop_slots: Vec<u32>,
    /// Instructions fast-forwarded so far.
    skipped: u64,
    /// Idle cycles advanced in closed form so far ([`Cpu::run_idle`]).
    idle_skipped: u64,
    /// Sleep PCs whose idle cycles failed the proof, with the failures.
    idle_fails: Vec<(u32, u8)>,
    instructions: u64,
    /// Where the instruction executed last is kept (for traces and the profiler): its index
    /// in `cache` (the fast path), or [`LAST_IN_COPY`] for `last_copy`.
    last_index: u32,
    /// The instruction executed last on the reference path.
    last_copy: Decoded,
    /// Its address.
    last_copy_pc: u32,
    /// The stack guard's bounds ([`stack::Bounds::OFF`] without a guard).
    stack_bounds: stack::Bounds,
    /// The stack guard, if one is set.
    stack_guard: Option<StackGuard>,
    /// The first stack fault seen under the guard.
    stack_fault: Option<Box<StackFault>>,
}

impl Default for Cpu {
    fn default() -> Self {
        Self::new()
    }
}

/// Fetches instruction words through the bus, refusing areas that are not executable.
struct BusFetch<'b, B: Bus> {
    bus: &'b mut B,
    addr: u32,
    refused: Option<u32>,
}

impl<B: Bus> WordSource for BusFetch<'_, B> {
    #[inline]
    fn next_word(&mut self) -> Option<u16> {
        let a = self.addr & crate::memmap::ADDRESS_MASK;
        if !Area::of(a).executable() {
            self.refused = Some(a);
            return None;
        }
        self.addr = self.addr.wrapping_add(2);
        Some(self.bus.read16(a))
    }
}

impl Cpu {
    /// A CPU before reset: registers 0, CCR.I set, PC 0.
    #[must_use]
    pub fn new() -> Self {
        Cpu {
            er: [0; 8],
            pc: 0,
            ccr: CCR_I,
            state: RunState::Running,
            irq_inhibit: false,
            cache: Arc::new([]),
            fast: Arc::new([]),
            code_generation: 0,
            fast_path: true,
            fast_forward: true,
            loops: Vec::new(),
            loop_slots: Vec::new(),
            skipped: 0,
            idle_skipped: 0,
            idle_fails: Vec::new(),
            instructions: 0,
            last_index: LAST_IN_COPY,
            last_copy: EMPTY_SLOT,
            last_copy_pc: 0,
            stack_bounds: stack::Bounds::OFF,
            stack_guard: None,
            stack_fault: None,
        }
    }

    /// Reset exception: CCR.I = 1, PC = the longword at vector 0 (read through the bus, 2 word
    /// reads). General registers are cleared (the manual leaves them undefined).
    pub fn reset<B: Bus>(&mut self, bus: &mut B) {
        self.er = [0; 8];
        self.ccr = CCR_I;
        self.state = RunState::Running;
        self.irq_inhibit = false;
        let v = u32::from(VECTOR_RESET) * VECTOR_BYTES;
        let hi = u32::from(bus.read16(v));
        let lo = u32::from(bus.read16(v + 2));
        self.pc = ((hi << 16) | lo) & crate::memmap::ADDRESS_MASK & !1;
    }

    /// The program counter (24 bits).
    #[must_use]
    pub const fn pc(&self) -> u32 {
        self.pc
    }

    /// Sets the program counter (masked to 24 bits, bit 0 cleared: instructions are
    /// word-aligned).
    pub fn set_pc(&mut self, pc: u32) {
        self.pc = pc & crate::memmap::ADDRESS_MASK & !1;
    }

    /// The condition code register.
    #[must_use]
    pub const fn ccr(&self) -> u8 {
        self.ccr
    }

    /// Sets the condition code register.
    pub fn set_ccr(&mut self, ccr: u8) {
        self.ccr = ccr;
    }

    /// General register ERn (n = 0–7; other values are taken modulo 8).
    #[must_use]
    pub const fn er(&self, n: usize) -> u32 {
        self.er[n & 7]
    }

    /// Sets general register ERn (n modulo 8).
    pub fn set_er(&mut self, n: usize, value: u32) {
        self.er[n & 7] = value;
    }

    /// All eight general registers.
    #[must_use]
    pub const fn regs(&self) -> [u32; 8] {
        self.er
    }

    /// Instructions executed since this CPU was created.
    #[must_use]
    pub const fn instructions(&self) -> u64 {
        self.instructions
    }

    /// The instruction executed last (a NOP of length 0 before the first).
    #[must_use]
    pub fn last_executed(&self) -> Decoded {
        if self.last_index == LAST_IN_COPY {
            self.last_copy
        } else {
            self.cache
                .get(self.last_index as usize)
                .copied()
                .unwrap_or(EMPTY_SLOT)
        }
    }

    /// The address of the instruction executed last (0 before the first): the instruction a
    /// bus access just seen belongs to, after a step or an [`Event::Break`]. After a loop was
    /// fast-forwarded, its back edge.
    #[must_use]
    pub fn last_pc(&self) -> u32 {
        if self.last_index == LAST_IN_COPY {
            self.last_copy_pc
        } else {
            self.last_index << 1
        }
    }

    /// Sets the stack guard (`None`: no guard, the default): from the next instruction on,
    /// every stack access is checked against the guard's room ([`stack`]). A fault recorded
    /// before is forgotten.
    pub fn set_stack_guard(&mut self, guard: Option<StackGuard>) {
        self.stack_guard = guard;
        self.stack_bounds = guard.map_or(stack::Bounds::OFF, |g| stack::Bounds::of(g.room));
        self.stack_fault = None;
    }

    /// The stack guard, if one is set.
    #[must_use]
    pub const fn stack_guard(&self) -> Option<StackGuard> {
        self.stack_guard
    }

    /// Raises the low end of the guard's room to `low` (the program has carved memory above
    /// its data: arrays sized at boot); a lower `low`, or no guard, changes nothing.
    pub fn raise_stack_low(&mut self, low: u32) {
        if let Some(g) = self.stack_guard.as_mut()
            && low > g.room.low
            && low <= g.room.top
        {
            g.room.low = low;
            self.stack_bounds = stack::Bounds::of(g.room);
        }
    }

    /// The first stack access that left the guard's room (under [`StackGuardMode::Warn`]; a
    /// stopping guard also keeps the fault it stopped at).
    #[must_use]
    pub fn stack_fault(&self) -> Option<&StackFault> {
        self.stack_fault.as_deref()
    }

    /// Checks a stack access of `bytes` bytes at `addr` by the instruction at `pc` (or the
    /// interrupt entry before it) against the guard: one add and one compare when it is
    /// inside.
    #[inline(always)]
    fn stack_ok(
        &mut self,
        addr: u32,
        bytes: u32,
        access: StackAccess,
        pc: u32,
    ) -> Result<(), CpuError> {
        if self.stack_bounds.inside(addr, bytes) {
            Ok(())
        } else {
            self.stack_hit(addr, bytes, access, pc)
        }
    }

    /// A stack access left the room: the fault is kept (the first one), and under a stopping
    /// guard the instruction is undone (PC at it, not counted) and the error returned.
    #[cold]
    #[inline(never)]
    fn stack_hit(
        &mut self,
        addr: u32,
        bytes: u32,
        access: StackAccess,
        pc: u32,
    ) -> Result<(), CpuError> {
        let Some(guard) = self.stack_guard else {
            return Ok(());
        };
        let instruction = match access {
            StackAccess::InterruptEntry(_) => String::new(),
            _ => disasm::format_instr(self.last_executed(), pc).replacen('\t', " ", 1),
        };
        let fault = Box::new(StackFault {
            pc,
            instruction,
            sp: self.er[7],
            addr: addr & crate::memmap::ADDRESS_MASK,
            bytes,
            access,
            room: guard.room,
            function: None,
        });
        if self.stack_fault.is_none() {
            self.stack_fault = Some(fault.clone());
        }
        match guard.mode {
            StackGuardMode::Warn => Ok(()),
            StackGuardMode::Stop => {
                if !matches!(access, StackAccess::InterruptEntry(_)) {
                    self.pc = pc;
                    self.instructions -= 1;
                }
                Err(CpuError::StackOverflow(fault))
            }
        }
    }

    /// Turns the fast path of [`Cpu::step`] on (the default) or off. Off, `step` is
    /// [`Cpu::step_reference`]. Both give the same states, bus accesses and results.
    pub fn set_fast_path(&mut self, on: bool) {
        self.fast_path = on;
    }

    /// Whether [`Cpu::step`] may take the fast path.
    #[must_use]
    pub const fn fast_path(&self) -> bool {
        self.fast_path
    }

    /// Whether SLEEP has halted the program (docs/design.md §7).
    #[must_use]
    pub fn halted(&self) -> bool {
        self.state == RunState::Halted
    }

    /// Whether the CPU is in sleep mode waiting for an interrupt.
    #[must_use]
    pub fn sleeping(&self) -> bool {
        self.state == RunState::Sleeping
    }

    /// Forgets every predecoded instruction. A bus that shows a [`FastPathHints::code_generation`]
    /// token has the caches emptied whenever its flash changes; with another bus, call this
    /// after replacing the ROM image.
    pub fn flush_decode_cache(&mut self) {
        self.last_copy = self.last_executed();
        self.last_copy_pc = self.last_pc();
        self.last_index = LAST_IN_COPY;
        self.cache = Arc::new([]);
        self.fast = Arc::new([]);
        self.loops.clear();
        self.loop_slots.clear();
        self.idle_fails.clear();
    }

    /// Empties the caches if the bus's flash token changed since they were filled.
    #[inline]
    fn check_code_generation<B: FastPathHints>(&mut self, bus: &B) -> Option<u64> {
        let token = bus.code_generation();
        if let Some(t) = token
            && t != self.code_generation
        {
            self.flush_decode_cache();
            self.code_generation = t;
        }
        token
    }

    /// Decodes the instruction at `pc` through the bus without executing it, charging its fetch
    /// states like an execution would. Used by tracing; most callers want [`Cpu::step`].
    fn fetch_decode<B: Bus>(&mut self, bus: &mut B) -> Result<Decoded, CpuError> {
        let pc = self.pc;
        if Area::of(pc) == Area::Rom {
            let idx = (pc >> 1) as usize;
            if let Some(d) = self.cache.get(idx)
                && d.words != 0
            {
                let d = *d;
                // Charge the instruction fetches the cached copy saved us from reading.
                let mut a = pc;
                for _ in 0..d.words {
                    bus.read16(a);
                    a = a.wrapping_add(2);
                }
                return Ok(d);
            }
            let d = self.decode_through_bus(bus)?;
            if Area::of(pc + d.len_bytes() - 1) == Area::Rom {
                *shared_code::own_slot(&mut self.cache, idx, EMPTY_SLOT) = d;
            }
            return Ok(d);
        }
        self.decode_through_bus(bus)
    }

    fn decode_through_bus<B: Bus>(&mut self, bus: &mut B) -> Result<Decoded, CpuError> {
        let pc = self.pc;
        let mut src = BusFetch {
            bus,
            addr: pc,
            refused: None,
        };
        match decode(&mut src) {
            Ok(d) => Ok(d),
            Err(e) => {
                if let Some(addr) = src.refused {
                    return Err(CpuError::FetchOutside {
                        pc,
                        addr,
                        area: Area::of(addr),
                    });
                }
                let words = match &e {
                    DecodeError::Undefined { words } | DecodeError::Truncated { words } => words,
                };
                Err(CpuError::UndefinedOpcode {
                    pc,
                    bytes: decode::hex_words(words),
                })
            }
        }
    }

    /// Whether a request `v` of [`Bus::pending_irq`] gets through the CCR mask: an interrupt
    /// while CCR.I = 0; NMI, a reset request and a break request always.
    #[inline]
    fn accepts(&self, v: u8) -> bool {
        self.ccr & CCR_I == 0 || matches!(v, VECTOR_NMI | RESET_REQUEST | BREAK_REQUEST)
    }

    /// Before an instruction: ends the one-instruction delay after LDC/ANDC/ORC/XORC, or
    /// takes a pending request the mask lets through (an interrupt's exception handling, a
    /// reset, a break) and returns the step's event.
    #[inline(always)]
    fn take_interrupt<B: Bus>(&mut self, bus: &mut B) -> Result<Option<Event>, CpuError> {
        if self.irq_inhibit {
            return Ok(self.after_inhibit(bus));
        }
        if let Some(v) = bus.pending_irq()
            && self.accepts(v)
        {
            return self.take_request(bus, v).map(Some);
        }
        Ok(None)
    }

    /// The boundary right after LDC/ANDC/ORC/XORC: no interrupt is accepted, but a reset or a
    /// break request is taken (a break keeps the delay for the instruction that follows).
    #[cold]
    #[inline(never)]
    fn after_inhibit<B: Bus>(&mut self, bus: &mut B) -> Option<Event> {
        match bus.pending_irq() {
            Some(BREAK_REQUEST) => {
                bus.cpu_signal(CpuSignal::Break { pc: self.last_pc() });
                Some(Event::Break)
            }
            Some(RESET_REQUEST) => {
                self.reset_exception(bus);
                Some(Event::Reset)
            }
            _ => {
                self.irq_inhibit = false;
                None
            }
        }
    }

    /// Takes request `v` (accepted): an interrupt's exception handling, the reset exception,
    /// or a break.
    #[inline(never)]
    fn take_request<B: Bus>(&mut self, bus: &mut B, v: u8) -> Result<Event, CpuError> {
        match v {
            BREAK_REQUEST => {
                bus.cpu_signal(CpuSignal::Break { pc: self.last_pc() });
                Ok(Event::Break)
            }
            RESET_REQUEST => {
                self.reset_exception(bus);
                Ok(Event::Reset)
            }
            _ => {
                self.interrupt(bus, v)?;
                Ok(Event::Interrupt(v))
            }
        }
    }

    /// The reset exception for the bus's reset request ([`RESET_REQUEST`]): the chip resets
    /// itself and holds the CPU for the reset's duration ([`CpuSignal::Reset`]), then the CPU
    /// starts as after power-on ([`Cpu::reset`]: registers cleared, CCR.I = 1, PC from vector
    /// 0). The instruction count, the decode caches and the stack guard carry on.
    #[cold]
    fn reset_exception<B: Bus>(&mut self, bus: &mut B) {
        bus.cpu_signal(CpuSignal::Reset);
        self.reset(bus);
    }

    /// Runs one step: accepts a pending interrupt, or executes one instruction, or (in sleep
    /// mode) waits for an interrupt until the clock reaches `deadline`.
    ///
    /// Takes the fast path (see the module docs) when it is on and the bus shows a
    /// [`FastPathHints::code_generation`] token; otherwise this is [`Cpu::step_reference`].
    ///
    /// # Errors
    /// [`CpuError`] on an undefined opcode, a fetch outside ROM/RAM or an unsupported
    /// instruction; the CPU state is left as it was before the instruction (PC at it).
    #[inline]
    pub fn step<B: FastPathHints>(
        &mut self,
        bus: &mut B,
        deadline: u64,
    ) -> Result<Event, CpuError> {
        if self.fast_ready(bus) {
            return self.step_fast(bus);
        }
        self.step_not_ready(bus, deadline)
    }

    /// Whether the fast path may run this step: on, running, and the caches filled under the
    /// bus's present token.
    #[inline(always)]
    fn fast_ready<B: FastPathHints>(&self, bus: &B) -> bool {
        self.fast_path
            && self.state == RunState::Running
            && bus.code_generation() == Some(self.code_generation)
    }

    /// A step when [`Cpu::fast_ready`] says no: a new token (the caches are emptied and the
    /// fast path runs), or the reference path.
    #[inline(never)]
    fn step_not_ready<B: FastPathHints>(
        &mut self,
        bus: &mut B,
        deadline: u64,
    ) -> Result<Event, CpuError> {
        if self.fast_path
            && self.state == RunState::Running
            && self.check_code_generation(bus).is_some()
        {
            return self.step_fast(bus);
        }
        self.step_reference(bus, deadline)
    }

    /// Runs steps until the clock reaches `deadline` or a step reports anything but
    /// [`Event::Executed`] (an interrupt accepted, the program halted, the CPU asleep past the
    /// deadline), and returns that step's event, or [`Event::Executed`] once the clock has
    /// reached `deadline` (at once, running nothing, if it already had).
    ///
    /// [`Cpu::run_until`] with no stop condition: see there for what it shares with stepping.
    ///
    /// # Errors
    /// As [`Cpu::step`].
    pub fn run<B: FastPathHints>(&mut self, bus: &mut B, deadline: u64) -> Result<Event, CpuError> {
        self.run_until(bus, deadline, |_, _| false)
    }

    /// [`Cpu::run`] that also returns ([`Event::Executed`]) after any executed instruction
    /// after which `stop(cpu, bus)` holds (entering sleep mode with `|cpu, _| cpu.sleeping()`,
    /// an I/O effect with a condition on the bus).
    ///
    /// The same as calling [`Cpu::step`] with `deadline` while the clock is below it, the steps
    /// report [`Event::Executed`] and `stop` does not hold: same states, bus accesses and
    /// results at the instant it returns. It is faster in two ways. On the fast path PC goes
    /// from one instruction to the next in a local. And with loop fast-forwarding on
    /// ([`Cpu::set_fast_forward`], the default) a delay loop or a poll loop whose next
    /// iterations are known is advanced in closed form to exactly the state stepping would
    /// reach (the `ffwd` module: which loops, and the bounds: the deadline, the next possible
    /// interrupt request, the reads' stability). A skipped stretch touches no device and
    /// changes no run state, and `stop` is not asked inside it: a condition on registers,
    /// time or instruction counts needs fast-forwarding off.
    ///
    /// # Errors
    /// As [`Cpu::step`].
    pub fn run_until<B: FastPathHints, F: FnMut(&Cpu, &B) -> bool>(
        &mut self,
        bus: &mut B,
        deadline: u64,
        mut stop: F,
    ) -> Result<Event, CpuError> {
        while bus.now() < deadline {
            if !self.fast_ready(bus) {
                let event = self.step_not_ready(bus, deadline)?;
                if event != Event::Executed {
                    return Ok(event);
                }
                if stop(self, bus) {
                    return Ok(event);
                }
                continue;
            }
            // The fast path with PC kept in a local (what `step_fast` does, step after step):
            // after an instruction that can only go on to the next, the next PC is the slot's,
            // not a reload of the one just stored.
            let mut pc = self.pc;
            loop {
                if let Some(event) = self.take_interrupt(bus)? {
                    return Ok(event);
                }
                let idx = (pc >> 1) as usize;
                if let Some(slot) = self.fast.get(idx)
                    && slot.words != 0
                {
                    let (words, next, sequential, back_edge) =
                        (slot.words, slot.next, slot.sequential, slot.back_edge);
                    bus.internal(u32::from(words) * ROM_FETCH_STATES);
                    let event = self.exec_fast(bus, pc, idx, next)?;
                    if event != Event::Executed {
                        return Ok(event);
                    }
                    if stop(self, bus) {
                        return Ok(event);
                    }
                    if sequential {
                        pc = next;
                    } else if self.state == RunState::Running {
                        pc = self.pc;
                        if back_edge && pc <= (idx as u32) << 1 && self.fast_forward {
                            match self.loop_back(bus, idx, deadline, &mut stop)? {
                                ffwd::Outcome::Continue => {}
                                ffwd::Outcome::Event(event) => return Ok(event),
                                ffwd::Outcome::Stop => return Ok(Event::Executed),
                            }
                            if self.state != RunState::Running {
                                break;
                            }
                            pc = self.pc;
                        }
                    } else {
                        // Asleep or halted: the outer loop takes the reference path.
                        break;
                    }
                } else {
                    // Not cached yet: one step the usual way, then from the top.
                    let event = self.fast_miss(bus, pc, idx)?;
                    if event != Event::Executed {
                        return Ok(event);
                    }
                    if stop(self, bus) {
                        return Ok(event);
                    }
                    break;
                }
                if bus.now() >= deadline || bus.code_generation() != Some(self.code_generation) {
                    break;
                }
            }
        }
        Ok(Event::Executed)
    }

    /// One step on the fast path: the CPU is running, the path is on and the caches match the
    /// bus's token.
    #[inline(always)]
    fn step_fast<B: Bus>(&mut self, bus: &mut B) -> Result<Event, CpuError> {
        if let Some(event) = self.take_interrupt(bus)? {
            return Ok(event);
        }
        let pc = self.pc;
        let idx = (pc >> 1) as usize;
        if let Some(slot) = self.fast.get(idx)
            && slot.words != 0
        {
            // The words of a cached ROM instruction: no device sees their fetch (the bus's
            // promise), so they cost their states as one lump.
            let (words, next) = (slot.words, slot.next);
            bus.internal(u32::from(words) * ROM_FETCH_STATES);
            return self.exec_fast(bus, pc, idx, next);
        }
        self.fast_miss(bus, pc, idx)
    }

    /// The fast path at an address whose handler is not cached yet: decodes through the bus
    /// (charging the fetches as the reference path does), caches a ROM instruction's handler
    /// and runs it; code in RAM (or straddling the end of ROM) runs on the reference executor.
    #[inline(never)]
    fn fast_miss<B: Bus>(&mut self, bus: &mut B, pc: u32, idx: usize) -> Result<Event, CpuError> {
        let d = self.decode_through_bus(bus)?;
        if Area::of(pc) == Area::Rom && Area::of(pc + d.len_bytes() - 1) == Area::Rom {
            let slot = fast::Slot::new(d, pc);
            *shared_code::own_slot(&mut self.cache, idx, EMPTY_SLOT) = d;
            *shared_code::own_slot(&mut self.fast, idx, fast::Slot::EMPTY) = slot;
            return self.exec_fast(bus, pc, idx, slot.next);
        }
        self.execute(bus, d)
    }

    /// One step on the reference path: every instruction word fetched through
    /// [`Bus::read16`], the generic executor. [`Cpu::step`] with the fast path off, and the
    /// yardstick the fast path is tested and benchmarked against.
    ///
    /// # Errors
    /// As [`Cpu::step`].
    pub fn step_reference<B: FastPathHints>(
        &mut self,
        bus: &mut B,
        deadline: u64,
    ) -> Result<Event, CpuError> {
        self.check_code_generation(bus);
        match self.state {
            RunState::Running => {}
            RunState::Halted => return Ok(Event::Halted),
            RunState::Sleeping => {
                loop {
                    match bus.pending_irq() {
                        // A break does not wake the CPU: it stops here, still asleep.
                        Some(BREAK_REQUEST) => {
                            bus.cpu_signal(CpuSignal::Break { pc: self.last_pc() });
                            return Ok(Event::Break);
                        }
                        Some(v) if self.accepts(v) => break,
                        _ => {}
                    }
                    if bus.now() >= deadline || !bus.sleep_until_irq(deadline) {
                        return Ok(Event::Asleep);
                    }
                }
                self.state = RunState::Running;
                bus.cpu_signal(CpuSignal::Wake);
            }
        }
        if let Some(event) = self.take_interrupt(bus)? {
            return Ok(event);
        }
        let d = self.fetch_decode(bus)?;
        self.execute(bus, d)
    }

    /// Decodes the instruction at PC without side effects on the CPU, reading the words through
    /// `bus` (which charges them: use it on a scratch bus or accept the states).
    ///
    /// # Errors
    /// As [`Cpu::step`].
    pub fn peek_decode<B: Bus>(&mut self, bus: &mut B) -> Result<Decoded, CpuError> {
        self.decode_through_bus(bus)
    }

    /// Pushes a longword on the stack (ER7 -= 4; two word writes), checked by the stack guard
    /// first (`access` by the instruction at `pc`).
    #[inline]
    fn push32<B: Bus>(
        &mut self,
        bus: &mut B,
        v: u32,
        access: StackAccess,
        pc: u32,
    ) -> Result<(), CpuError> {
        let sp = self.er[7].wrapping_sub(4);
        self.stack_ok(sp, 4, access, pc)?;
        self.er[7] = sp;
        bus.write16(sp, (v >> 16) as u16);
        bus.write16(sp.wrapping_add(2), v as u16);
        Ok(())
    }

    /// Pops a longword from the stack (two word reads; ER7 += 4), checked by the stack guard
    /// first.
    #[inline]
    fn pop32<B: Bus>(
        &mut self,
        bus: &mut B,
        access: StackAccess,
        pc: u32,
    ) -> Result<u32, CpuError> {
        let sp = self.er[7];
        self.stack_ok(sp, 4, access, pc)?;
        let hi = u32::from(bus.read16(sp));
        let lo = u32::from(bus.read16(sp.wrapping_add(2)));
        self.er[7] = sp.wrapping_add(4);
        Ok((hi << 16) | lo)
    }

    /// Reads the 24-bit address in vector `v` (two word reads: J = 2).
    #[inline]
    fn read_vector<B: Bus>(bus: &mut B, v: u8) -> u32 {
        let a = u32::from(v) * VECTOR_BYTES;
        let hi = u32::from(bus.read16(a));
        let lo = u32::from(bus.read16(a + 2));
        ((hi << 16) | lo) & crate::memmap::ADDRESS_MASK & !1
    }

    /// Exception handling shared by interrupts and TRAPA: push PC and CCR, set I, load PC from
    /// the vector.
    fn enter_exception<B: Bus>(
        &mut self,
        bus: &mut B,
        v: u8,
        return_pc: u32,
        access: StackAccess,
        pc: u32,
    ) -> Result<(), CpuError> {
        let frame = (u32::from(self.ccr) << 24) | (return_pc & crate::memmap::ADDRESS_MASK);
        self.push32(bus, frame, access, pc)?;
        self.ccr |= CCR_I;
        self.pc = Self::read_vector(bus, v);
        Ok(())
    }

    /// Interrupt exception handling (H8/3052F hardware manual, section 5.4 and Table 5-5).
    /// The stack guard sees the push before anything happens.
    fn interrupt<B: Bus>(&mut self, bus: &mut B, v: u8) -> Result<(), CpuError> {
        let pc = self.pc;
        self.stack_ok(
            self.er[7].wrapping_sub(4),
            4,
            StackAccess::InterruptEntry(v),
            pc,
        )?;
        bus.cpu_signal(CpuSignal::Interrupt(v));
        let external = v == VECTOR_NMI || (VECTOR_IRQ0..=VECTOR_IRQ5).contains(&v);
        bus.internal(if external {
            timing::N_PRIORITY_DECISION_EXTERNAL
        } else {
            timing::N_PRIORITY_DECISION_INTERNAL
        });
        let ret = self.pc;
        // Prefetch after acceptance (at the return address; not executed).
        Self::fetch_charge(bus, ret);
        self.enter_exception(bus, v, ret, StackAccess::InterruptEntry(v), pc)?;
        // Prefetch of the first instruction of the handler.
        let target = self.pc;
        Self::fetch_charge(bus, target);
        bus.internal(timing::N_INTERRUPT_INTERNAL);
        Ok(())
    }

    /// Charges one instruction-fetch cycle at `addr` (a branch-target prefetch: the extra I of
    /// one-word branches). Reads only executable areas, so a bad target has no side effects on
    /// devices; elsewhere it charges the area's word states as internal time.
    #[inline]
    fn fetch_charge<B: Bus>(bus: &mut B, addr: u32) {
        let area = Area::of(addr);
        if area.executable() {
            bus.read16(addr);
        } else {
            bus.internal(area.word_states());
        }
    }
}
