//! Exact loop fast-forwarding for [`Cpu::run_until`]: a loop whose next iterations
//! are known without running them is advanced in closed form, to exactly the registers, flags,
//! clock, instruction count and memory the stepped run would reach at the same instruction
//! boundary. Nothing here knows a program: the loops are recognised by what they do.
//!
//! It starts where the fast path takes a backward branch (a Bcc whose target is at or before
//! it, the loop's back edge) and classifies that edge once:
//! - **Countdown** (delay loops): the loop is two instructions, an INC, DEC, or ADD/SUB of an
//!   immediate on one register (byte, word or long) and a BNE back to it. Each iteration adds
//!   the same amount and costs the same states (the two instructions' ROM fetches and the
//!   branch's prefetch or N states: no data access, so no device sees it), so the iterations
//!   left until the register reaches zero follow from its value (the congruence
//!   `v + i·d ≡ 0 (mod 2^bits)`). All but the last are skipped: the register is set to its value
//!   one iteration before the landing point and the counting instruction's own handler runs
//!   once, so the flags are the ones it leaves (DEC keeps H and C, ADD sets them).
//! - **Fixed point** (poll loops, spins): any other back edge is watched for one iteration
//!   through a recording bus. If that iteration wrote nothing, returned to the loop's head with
//!   every register and CCR as they were, and every read it made comes with the bus's promise
//!   that re-reading gives the same and changes nothing ([`FastPathHints::reads_stable_until`]: ROM and
//!   RAM for ever, the A/D converter's registers until its next event), then each further
//!   iteration repeats it exactly, reads included, and is skipped. Four iterations that fail
//!   the test (a write, a changed register, a read with no promise, a body of more than
//!   [`MAX_BODY`] instructions) mark the edge as no poll loop for good, so ordinary loops pay
//!   for the watching only a few times.
//!
//! Either way the skipped iterations end no later than (a) the run's deadline, (b) the
//! instant until which the bus promises no new interrupt request ([`FastPathHints::irq_stable_until`];
//! the decision at every skipped boundary is then the one the stepped run would see), and (c)
//! for a fixed point, the earliest end of its reads' promises. The iterations after that run
//! normally. A bus that makes no promises (the defaults) gets no fast-forwarding.
//!
//! The run's `stop` condition is not asked inside a skipped stretch: a skipped loop touches no
//! device and changes no run state, so a condition on those is unaffected, but one on
//! registers, time or instruction counts (a breakpoint) needs fast-forwarding off
//! ([`Cpu::set_fast_forward`]).

use super::decode::Size;
use super::exec::sz;
use super::fast::{Op, Slot};
use super::timing as t;
use super::{Cpu, CpuError, Event, ROM_FETCH_STATES, RunState};
use crate::bus::{Bus, FastPathHints};

/// Most instructions one watched iteration of a poll loop may take.
pub const MAX_BODY: u32 = 24;

/// Failed watches after which a back edge is no poll loop for good.
const MAX_FAILS: u8 = 4;

/// The condition code of BNE.
const COND_NE: u8 = 6;

/// `Cpu::loop_slots` of a slot whose back edge has no entry yet.
pub(super) const NO_LOOP: u32 = u32::MAX;

/// Back edges `Cpu::loops` gives entries of their own (a program has tens; the bound keeps the
/// list under 1 MB whatever the image); the entry at this index is a shared [`Loop::Never`] for
/// any back edge beyond them, which then simply runs (fast-forwarding is an option, never
/// needed for the right answer).
const MAX_LOOPS: usize = u16::MAX as usize - 1;

/// What is known about one back edge (`Cpu::loops`, reached through `Cpu::loop_slots`).
#[derive(Clone, Copy, Debug, Default)]
pub(super) enum Loop {
    /// Not classified yet.
    #[default]
    Unseen,
    /// A two-instruction countdown loop.
    Countdown {
        /// Slot index of the counting instruction (the loop's head).
        head: u32,
        /// Its operand size.
        size: Size,
        /// Its register.
        rd: u8,
        /// What one iteration adds (modulo the size).
        delta: u32,
        /// States of one iteration.
        states: u32,
    },
    /// Watched as a possible fixed point; `fails` watches failed so far.
    Watch {
        /// Failed watches so far.
        fails: u8,
    },
    /// Not a loop this module can skip.
    Never,
}

/// What a fast-forward attempt ended with.
pub(super) enum Outcome {
    /// Go on at the CPU's PC (iterations may have been skipped).
    Continue,
    /// An instruction of a watched iteration reported this event (an interrupt accepted).
    Event(Event),
    /// The run's stop condition became true after a watched instruction.
    Stop,
}

/// A bus that notes what one watched iteration does: whether it wrote, and until when its
/// reads stay the same.
struct Recorder<'b, B: FastPathHints> {
    bus: &'b mut B,
    /// The earliest end of the reads' promises (0: a read without one).
    stable_until: u64,
    wrote: bool,
}

impl<B: FastPathHints> Recorder<'_, B> {
    #[inline]
    fn note(&mut self, addr: u32) {
        let until = self.bus.reads_stable_until(addr).unwrap_or(0);
        self.stable_until = self.stable_until.min(until);
    }
}

impl<B: FastPathHints> Bus for Recorder<'_, B> {
    crate::forward_bus_timing!(bus);
    #[inline]
    fn read8(&mut self, addr: u32) -> u8 {
        let v = self.bus.read8(addr);
        self.note(addr);
        v
    }
    #[inline]
    fn read16(&mut self, addr: u32) -> u16 {
        let v = self.bus.read16(addr);
        self.note(addr);
        v
    }
    #[inline]
    fn write8(&mut self, addr: u32, value: u8) {
        self.wrote = true;
        self.bus.write8(addr, value);
    }
    #[inline]
    fn write16(&mut self, addr: u32, value: u16) {
        self.wrote = true;
        self.bus.write16(addr, value);
    }
}

impl<B: FastPathHints> FastPathHints for Recorder<'_, B> {
    crate::forward_fast_path_hints!(bus);
}

/// The smallest `i >= 1` with `v + i·d ≡ 0 (mod 2^bits)`: the iterations until a counter of
/// `bits` bits at `v` that gains `d` an iteration reaches zero; `None` if it never does.
#[must_use]
pub fn iterations_to_zero(v: u32, d: u32, bits: u32) -> Option<u64> {
    let modulus = 1u64 << bits;
    let mask = modulus - 1;
    let (v, d) = (u64::from(v) & mask, u64::from(d) & mask);
    if d == 0 {
        return (v == 0).then_some(1);
    }
    // d = 2^s · d' with d' odd: solvable only when 2^s divides v, then modulo 2^(bits - s).
    let s = d.trailing_zeros();
    if v & ((1u64 << s) - 1) != 0 {
        return None;
    }
    let m = modulus >> s;
    let (v, d) = (v >> s, d >> s);
    // The inverse of the odd d' modulo 2^64 (Newton's iteration doubles the correct bits).
    let mut inv = d;
    for _ in 0..6 {
        inv = inv.wrapping_mul(2u64.wrapping_sub(d.wrapping_mul(inv)));
    }
    let i = (m - v % m) % m * (inv % m) % m;
    Some(if i == 0 { m } else { i })
}

/// The counting instruction of a countdown loop: (size, register, what it adds).
fn counter_of(op: Op) -> Option<(Size, u8, u32)> {
    let neg = |size: Size, v: u32| v.wrapping_neg() & sz(size).mask;
    Some(match op {
        Op::AddI8 { v, rd } => (Size::Byte, rd, v),
        Op::AddI16 { v, rd } => (Size::Word, rd, v),
        Op::AddI32 { v, rd } => (Size::Long, rd, v),
        Op::SubI16 { v, rd } => (Size::Word, rd, neg(Size::Word, v)),
        Op::SubI32 { v, rd } => (Size::Long, rd, neg(Size::Long, v)),
        Op::Inc8 { amount, rd } => (Size::Byte, rd, u32::from(amount)),
        Op::Inc16 { amount, rd } => (Size::Word, rd, u32::from(amount)),
        Op::Inc32 { amount, rd } => (Size::Long, rd, u32::from(amount)),
        Op::Dec8 { amount, rd } => (Size::Byte, rd, neg(Size::Byte, u32::from(amount))),
        Op::Dec16 { amount, rd } => (Size::Word, rd, neg(Size::Word, u32::from(amount))),
        Op::Dec32 { amount, rd } => (Size::Long, rd, neg(Size::Long, u32::from(amount))),
        _ => return None,
    })
}

/// The bits of a size.
const fn bits(size: Size) -> u32 {
    match size {
        Size::Byte => 8,
        Size::Word => 16,
        Size::Long => 32,
    }
}

impl Cpu {
    /// Turns loop fast-forwarding in [`Cpu::run_until`] and [`Cpu::run`] on (the default) or
    /// off. Either way the runs reach the same states at the same instants; off, every
    /// instruction is executed (and the `stop` condition asked after each).
    pub fn set_fast_forward(&mut self, on: bool) {
        self.fast_forward = on;
    }

    /// Whether loop fast-forwarding is on.
    #[must_use]
    pub const fn fast_forward(&self) -> bool {
        self.fast_forward
    }

    /// Instructions advanced in closed form so far (counted in [`Cpu::instructions`] too).
    #[must_use]
    pub const fn skipped_instructions(&self) -> u64 {
        self.skipped
    }

    /// Whether the next boundary takes an interrupt (then nothing may be skipped before it).
    fn interrupt_due<B: FastPathHints>(&self, bus: &B) -> bool {
        !self.irq_inhibit && bus.pending_irq().is_some_and(|v| self.accepts(v))
    }

    /// After the back edge in slot `edge` was taken (PC at the loop's head): advances the loop
    /// as far as it exactly can (module docs).
    pub(super) fn loop_back<B: FastPathHints, F: FnMut(&Cpu, &B) -> bool>(
        &mut self,
        bus: &mut B,
        edge: usize,
        deadline: u64,
        stop: &mut F,
    ) -> Result<Outcome, CpuError> {
        match *self.loop_at(edge) {
            Loop::Never => Ok(Outcome::Continue),
            Loop::Unseen => {
                *self.loop_at(edge) = self.classify(edge);
                self.loop_back(bus, edge, deadline, stop)
            }
            Loop::Countdown {
                head,
                size,
                rd,
                delta,
                states,
            } => {
                self.countdown(
                    bus,
                    edge,
                    head as usize,
                    (size, rd, delta, states),
                    deadline,
                )?;
                Ok(Outcome::Continue)
            }
            Loop::Watch { fails } => {
                let (outcome, failed) = self.watch(bus, edge, deadline, stop)?;
                if failed {
                    *self.loop_at(edge) = if fails + 1 >= MAX_FAILS {
                        Loop::Never
                    } else {
                        Loop::Watch { fails: fails + 1 }
                    };
                }
                Ok(outcome)
            }
        }
    }

    /// What is known of the back edge in slot `edge` ([`Loop::Unseen`] the first time). A
    /// program has tens of back edges, so the table indexed like the decode caches holds only
    /// their places in a short list (4 bytes a slot rather than a `Loop`'s 16).
    #[inline]
    fn loop_at(&mut self, edge: usize) -> &mut Loop {
        let k = match self.loop_slots.get(edge) {
            Some(&k) if k != NO_LOOP => k as usize,
            _ => self.new_loop(edge),
        };
        &mut self.loops[k]
    }

    /// Gives the back edge in slot `edge` an entry ([`Loop::Unseen`]); returns its place.
    #[cold]
    fn new_loop(&mut self, edge: usize) -> usize {
        if self.loop_slots.len() <= edge {
            self.loop_slots.resize(edge + 1, NO_LOOP);
        }
        let k = self.loops.len();
        if k >= MAX_LOOPS {
            if k == MAX_LOOPS {
                self.loops.push(Loop::Never);
            }
            return MAX_LOOPS;
        }
        self.loop_slots[edge] = k as u32;
        self.loops.push(Loop::Unseen);
        k
    }

    /// What kind of loop the back edge in slot `edge` closes (PC at its target).
    fn classify(&self, edge: usize) -> Loop {
        let target = self.pc;
        let head = (target >> 1) as usize;
        let e = self.fast[edge];
        let (mask, branch_states) = match e.op {
            Op::Bcc8 {
                mask, taken_states, ..
            } => (mask, u32::from(taken_states)),
            Op::Bcc16 { mask, .. } => (mask, t::N_BRANCH_D16),
            _ => return Loop::Watch { fails: 0 },
        };
        if let Some(h) = self.fast.get(head)
            && h.words != 0
            && (h.next >> 1) as usize == edge
            && mask == super::fast::cond_mask(COND_NE)
            && let Some((size, rd, delta)) = counter_of(h.op)
        {
            let states =
                (u32::from(h.words) + u32::from(e.words)) * ROM_FETCH_STATES + branch_states;
            return Loop::Countdown {
                head: head as u32,
                size,
                rd,
                delta,
                states,
            };
        }
        Loop::Watch { fails: 0 }
    }

    /// A countdown loop at its head: skips all iterations but the last that end by the
    /// deadline and before the interrupt decision may change.
    fn countdown<B: FastPathHints>(
        &mut self,
        bus: &mut B,
        edge: usize,
        head: usize,
        (size, rd, delta, states): (Size, u8, u32, u32),
        deadline: u64,
    ) -> Result<(), CpuError> {
        if self.interrupt_due(bus) {
            return Ok(());
        }
        let v = self.reg(size, rd);
        let left = iterations_to_zero(v, delta, bits(size)).map_or(u64::MAX, |k| k - 1);
        let now = bus.now();
        let limit = deadline.min(bus.irq_stable_until());
        if limit <= now {
            return Ok(());
        }
        let j = left
            .min((limit - now) / u64::from(states))
            .min(u64::from(u32::MAX / states));
        if j < 2 {
            return Ok(());
        }
        // One iteration before the landing point, then the counting instruction itself: the
        // register and the flags it leaves.
        let mask = sz(size).mask;
        let before = v.wrapping_add((j as u32 - 1).wrapping_mul(delta)) & mask;
        self.set_reg(size, rd, before);
        let head_pc = (head as u32) << 1;
        let slot: Slot = self.fast[head];
        self.exec_fast(bus, head_pc, head, slot.next)?;
        bus.internal(j as u32 * states);
        self.pc = head_pc;
        self.last_index = edge as u32;
        // exec_fast counted one.
        self.instructions += 2 * j - 1;
        self.skipped += 2 * j;
        Ok(())
    }

    /// Watches one iteration of the loop closed by slot `edge` (PC at its head) and, if it is a
    /// fixed point, skips the identical iterations after it. Returns what to do next and
    /// whether the watch failed (the loop is no fixed point, or not now for good reasons).
    fn watch<B: FastPathHints, F: FnMut(&Cpu, &B) -> bool>(
        &mut self,
        bus: &mut B,
        edge: usize,
        deadline: u64,
        stop: &mut F,
    ) -> Result<(Outcome, bool), CpuError> {
        let head = self.pc;
        let (regs, ccr) = (self.er, self.ccr);
        let (t0, n0) = (bus.now(), self.instructions);
        let mut rec = Recorder {
            bus,
            stable_until: u64::MAX,
            wrote: false,
        };
        let mut closed = false;
        for _ in 0..MAX_BODY {
            // The run would stop here.
            if rec.bus.now() >= deadline {
                return Ok((Outcome::Continue, false));
            }
            let event = self.step_fast(&mut rec)?;
            if event != Event::Executed {
                return Ok((Outcome::Event(event), false));
            }
            if stop(self, rec.bus) {
                return Ok((Outcome::Stop, false));
            }
            if self.state != RunState::Running
                || rec.bus.code_generation() != Some(self.code_generation)
            {
                return Ok((Outcome::Continue, false));
            }
            if self.last_index == edge as u32 {
                if self.pc != head {
                    // The loop ended (the back edge fell through): nothing to skip, no failure.
                    return Ok((Outcome::Continue, false));
                }
                closed = true;
                break;
            }
        }
        let same = closed && !rec.wrote && self.er == regs && self.ccr == ccr;
        if !same || rec.stable_until == 0 {
            return Ok((Outcome::Continue, true));
        }
        let stable_until = rec.stable_until;
        let now = bus.now();
        let states = now - t0;
        let count = self.instructions - n0;
        let limit = deadline.min(bus.irq_stable_until()).min(stable_until);
        if states == 0 || limit <= now || self.interrupt_due(bus) {
            return Ok((Outcome::Continue, false));
        }
        let j = ((limit - now) / states).min(u64::from(u32::MAX) / states);
        if j >= 1 {
            bus.internal((j * states) as u32);
            self.instructions += j * count;
            self.skipped += j * count;
        }
        Ok((Outcome::Continue, false))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The iterations by stepping the counter, for small widths.
    fn by_steps(v: u32, d: u32, bits: u32) -> Option<u64> {
        let mask = (1u64 << bits) - 1;
        let mut x = u64::from(v) & mask;
        for i in 1..=(1u64 << bits) {
            x = (x + u64::from(d)) & mask;
            if x == 0 {
                return Some(i);
            }
        }
        None
    }

    #[test]
    fn iterations_to_zero_agrees_with_stepping_for_every_byte_counter_and_step() {
        for v in 0..256 {
            for d in 0..256 {
                assert_eq!(
                    iterations_to_zero(v, d, 8),
                    by_steps(v, d, 8),
                    "v {v} d {d}"
                );
            }
        }
    }

    #[test]
    fn iterations_to_zero_agrees_with_stepping_for_11_bit_counters() {
        for v in (0..2048).step_by(7) {
            for d in 0..2048 {
                assert_eq!(
                    iterations_to_zero(v, d, 11),
                    by_steps(v, d, 11),
                    "v {v} d {d}"
                );
            }
        }
    }

    #[test]
    fn iterations_to_zero_for_words_and_longs() {
        assert_eq!(iterations_to_zero(833, 0xFFFF, 16), Some(833));
        assert_eq!(iterations_to_zero(0, 0xFFFF, 16), Some(65_536));
        assert_eq!(iterations_to_zero(6, 0xFFFE, 16), Some(3));
        assert_eq!(iterations_to_zero(7, 0xFFFE, 16), None);
        assert_eq!(iterations_to_zero(0, 0xFFFF_FFFF, 32), Some(1 << 32));
        for (v, d) in [
            (1u32, 0xFFFF_FFFFu32),
            (100, 0xFFFF_FFFC),
            (12, 4),
            (5, 0x8000_0001),
        ] {
            let i = iterations_to_zero(v, d, 32).unwrap();
            assert_eq!(
                (u64::from(v) + i * u64::from(d)) % (1u64 << 32),
                0,
                "v {v} d {d}"
            );
        }
    }
}
