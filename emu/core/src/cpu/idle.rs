//! Idle cycles advanced in closed form: a CPU that sleeps, is woken by a periodic
//! interrupt, runs the handler and a little of the main loop, and sleeps again at the same
//! place (a tick counter in RAM and a `while (ticks < next) sleep();`) repeats the same cycle
//! until a counter reaches a threshold. [`Cpu::run_idle`] runs two such cycles, proves from
//! them that the next ones repeat, and advances as many as it proved in one go, to exactly
//! the registers, flags, memory, clock, instruction count and device state stepping reaches.
//! Nothing here knows a program: the cycle is recognised by what it does.
//!
//! The proof. Cycles A and B (CPU asleep at the same PC at their starts s_A, s_B and at B's
//! end s_C) are recorded instruction by instruction: the registers and CCR before each, each
//! data access (address, width, direction, value, instant from the wake). They must match in
//! everything but values in RAM and registers: the same instructions (and accepted interrupts)
//! at the same PCs and instants, the same accesses at the same instants, the same CCR before
//! every instruction, the same values read from and written to ROM and devices, the devices
//! only those [`FastPathHints::idle_io`] covers, and the bus's [`FastPathHints::idle_signature`] equal at s_A and
//! s_B (the devices then repeat with period P = s_B − s_A as long as the program does). Then
//! every value of cycle j (A = 0, B = 1) is shown to be `v_A + j·(v_B − v_A)` (mod 2^32), by
//! induction over the cycle's instructions:
//! - an instruction that is not a 32-bit MOV, ADD, SUB, CMP, INC, DEC, ADDS or SUBS must see
//!   the same values in A and B in every register it may read (and memory it reads), so it
//!   does the same in every cycle;
//! - those eight are affine: their results are `v_A + j·d` when their operands are, and their
//!   flags are the same in every cycle as long as every operand and result stays inside the
//!   2^28-aligned block it is in at A and off zero (H is the carry out of bit 27; C, V, N and
//!   Z change only where a value crosses a multiple of 2^28 or reaches 0), which bounds the
//!   cycles proven; their address registers must be the same in A and B;
//! - a RAM longword whose value differs between A and B is accessed only by those 32-bit
//!   MOVs, as a whole, and its stride from the value read at the cycle's start to the value
//!   last written is the same, so each cycle reads what the previous one left; registers
//!   likewise: s_C − s_B = s_B − s_A for each.
//!
//! Then cycles 2..=J repeat A and B with the same branches, interrupts, device accesses and
//! timing, and `n` of them are advanced at once (those that end by the deadline and by
//! [`FastPathHints::idle_horizon`], the next request of a device the signature leaves out, such
//! as a free-running watchdog): registers and the changing longwords to their
//! values after cycle 1 + n, the devices and the clock by [`FastPathHints::idle_shift`] (n·P states),
//! the instruction count by n times the cycle's. The cycle after them runs as usual (the one
//! where the counter reaches its threshold and the loop ends is never skipped). A cycle that
//! fails the proof counts as a failure of its sleep PC; four mark that PC as no idle loop.

use super::decode::{AluOp, BitNum, BitTarget, Instr, Operand, Size};
use super::{Cpu, CpuError, Event, RunState};
use crate::bus::{Bus, FastPathHints};
use crate::memmap::{ADDRESS_MASK, Area};

/// Most steps (instructions and accepted interrupts) one recorded idle cycle may take.
pub const MAX_CYCLE: usize = 64;

/// Failed proofs after which a sleep PC is no idle loop for good.
const MAX_FAILS: u8 = 4;

/// The block size whose crossing may change a 32-bit ADD/SUB/CMP/MOV flag (H: bit 27).
const BLOCK: u64 = 1 << 28;

/// What [`Cpu::run_idle`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IdleRun {
    /// States the CPU was busy (awake) in the cycles run or advanced.
    pub busy: u64,
    /// `Some(event)`: the run ends with this event, as [`Cpu::run_until`] would report it
    /// (the deadline passed asleep: [`Event::Asleep`]; the stop condition held after an
    /// instruction: [`Event::Executed`]; the program halted). `None`: go on as usual (the CPU
    /// is asleep or running; nothing more was due).
    pub end: Option<Event>,
}

/// One data access of a recorded cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Access {
    addr: u32,
    wide: bool,
    write: bool,
    value: u16,
    /// States from the wake to the end of the bus cycle.
    at: u64,
    /// The step it belongs to.
    step: u32,
}

/// One step of a recorded cycle: an instruction or an accepted interrupt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Instr(Instr),
    Interrupt(u8),
}

#[derive(Clone, Copy, Debug)]
struct Step {
    kind: Kind,
    pc: u32,
    regs: [u32; 8],
    ccr: u8,
    inhibit: bool,
    /// States from the wake to the step's end.
    at: u64,
}

/// A recorded idle cycle.
struct Cycle {
    start: u64,
    wake: u64,
    signature: Option<Vec<u64>>,
    regs: [u32; 8],
    ccr: u8,
    steps: Vec<Step>,
    accesses: Vec<Access>,
}

/// A bus that logs every data access of a recorded cycle.
struct Log<'b, B: FastPathHints> {
    bus: &'b mut B,
    wake: u64,
    step: u32,
    accesses: Vec<Access>,
}

impl<B: FastPathHints> Log<'_, B> {
    #[inline]
    fn note(&mut self, addr: u32, wide: bool, write: bool, value: u16) {
        let at = self.bus.now() - self.wake;
        self.accesses.push(Access {
            addr: addr & ADDRESS_MASK,
            wide,
            write,
            value,
            at,
            step: self.step,
        });
    }
}

impl<B: FastPathHints> Bus for Log<'_, B> {
    crate::forward_bus_timing!(bus);
    fn read8(&mut self, addr: u32) -> u8 {
        let v = self.bus.read8(addr);
        self.note(addr, false, false, u16::from(v));
        v
    }
    fn read16(&mut self, addr: u32) -> u16 {
        let v = self.bus.read16(addr);
        self.note(addr & !1, true, false, v);
        v
    }
    fn write8(&mut self, addr: u32, value: u8) {
        self.bus.write8(addr, value);
        self.note(addr, false, true, u16::from(value));
    }
    fn write16(&mut self, addr: u32, value: u16) {
        self.bus.write16(addr, value);
        self.note(addr & !1, true, true, value);
    }
}

impl<B: FastPathHints> FastPathHints for Log<'_, B> {
    crate::forward_fast_path_hints!(bus);
}

/// How a recording ended.
enum Recorded {
    /// A whole cycle, the CPU asleep again at the PC it started from.
    Cycle(Cycle),
    /// Anything else; `Some` is the event to end the run with.
    Other(Option<Event>),
}

/// Why a proof failed.
enum NoProof {
    /// Not now (the devices busy, too few cycles left): try again later.
    NotNow,
    /// The cycle is not one this module can advance.
    Fails,
    /// The first cycle did not span a whole period: try the next pair.
    Misaligned,
}

/// What the proof found: how to advance.
struct Plan {
    period: u64,
    busy: u64,
    instructions: u64,
    /// The last cycle index (A = 0) proven to repeat.
    last: u64,
    /// Per register: its change per cycle.
    stride: [u32; 8],
    /// Changing RAM longwords: address, value after cycle B, change per cycle.
    ram: Vec<(u32, u32, u32)>,
}

/// The registers an instruction may read (bit n: ERn, any part of it).
fn operand_regs(o: Operand) -> u8 {
    match o {
        Operand::Reg(r)
        | Operand::Ind(r)
        | Operand::PostInc(r)
        | Operand::PreDec(r)
        | Operand::Disp16(r, _)
        | Operand::Disp24(r, _) => 1 << (r & 7),
        Operand::Imm(_) | Operand::Abs8(_) | Operand::Abs16(_) | Operand::Abs24(_) => 0,
    }
}

/// The address registers of an operand (none for registers and immediates).
fn address_regs(o: Operand) -> u8 {
    if o.is_memory() { operand_regs(o) } else { 0 }
}

/// The registers a step may read: a conservative superset (all of them when unsure).
fn inputs(kind: Kind) -> u8 {
    match kind {
        Kind::Interrupt(_) => 1 << 7,
        Kind::Instr(i) => match i {
            Instr::Nop
            | Instr::Sleep
            | Instr::Bcc { .. }
            | Instr::Andc(_)
            | Instr::Orc(_)
            | Instr::Xorc(_) => 0,
            Instr::Rts | Instr::Rte => 1 << 7,
            Instr::Mov { src, dst, .. } => operand_regs(src) | operand_regs(dst),
            Instr::Alu { src, rd, .. } => operand_regs(src) | 1 << (rd & 7),
            Instr::Inc { rd, .. } | Instr::Dec { rd, .. } | Instr::Unary { rd, .. } => {
                1 << (rd & 7)
            }
            Instr::Adds { rd, .. } | Instr::Subs { rd, .. } => 1 << (rd & 7),
            Instr::Bit { bit, target, .. } => {
                let b = match bit {
                    BitNum::Imm(_) => 0,
                    BitNum::Reg(r) => 1 << (r & 7),
                };
                b | match target {
                    BitTarget::Reg(r) | BitTarget::Ind(r) => 1 << (r & 7),
                    BitTarget::Abs8(_) => 0,
                }
            }
            _ => 0xFF,
        },
    }
}

/// Whether a step is one of the affine 32-bit operations.
fn affine(kind: Kind) -> bool {
    match kind {
        Kind::Instr(Instr::Mov {
            size: Size::Long, ..
        })
        | Kind::Instr(Instr::Inc {
            size: Size::Long, ..
        })
        | Kind::Instr(Instr::Dec {
            size: Size::Long, ..
        })
        | Kind::Instr(Instr::Adds { .. })
        | Kind::Instr(Instr::Subs { .. }) => true,
        Kind::Instr(Instr::Alu {
            op,
            size: Size::Long,
            src,
            ..
        }) => {
            matches!(op, AluOp::Add | AluOp::Sub | AluOp::Cmp)
                && matches!(src, Operand::Reg(_) | Operand::Imm(_))
        }
        _ => false,
    }
}

/// The last cycle index `j` for which `v_A + j·(v_B − v_A)` stays in the 2^28 block of `v_A`
/// and off zero (`u64::MAX` when it does not change).
fn span(va: u32, vb: u32) -> u64 {
    let d = i64::from(vb.wrapping_sub(va) as i32);
    if d == 0 {
        return u64::MAX;
    }
    let v = i64::from(va);
    let block = (u64::from(va) / BLOCK * BLOCK) as i64;
    let lo = block.max(1);
    let hi = block + BLOCK as i64 - 1;
    if v < lo {
        return 0;
    }
    let j = if d > 0 { (hi - v) / d } else { (v - lo) / -d };
    j as u64
}

/// A longword from two word values.
fn long(hi: u16, lo: u16) -> u32 {
    (u32::from(hi) << 16) | u32::from(lo)
}

impl Cpu {
    /// Idle cycles advanced in closed form so far ([`Cpu::run_idle`]).
    #[must_use]
    pub const fn idle_cycles_skipped(&self) -> u64 {
        self.idle_skipped
    }

    /// For a CPU asleep in its idle loop: runs two idle cycles (wake by an interrupt, the
    /// handler, the main loop back to SLEEP at the same PC) through a logging bus and, if they
    /// prove that the cycles after them repeat (module docs), advances as many of those as
    /// were proven and end by `deadline`, to the state stepping reaches. `stop` is asked after
    /// every instruction run (not inside the advanced cycles, which touch only the devices
    /// [`FastPathHints::idle_io`] covers). Does nothing unless loop fast-forwarding is on
    /// ([`Cpu::set_fast_forward`]), the CPU is asleep and the bus makes the promises.
    ///
    /// # Errors
    /// As [`Cpu::step`].
    pub fn run_idle<B: FastPathHints, F: FnMut(&Cpu, &B) -> bool>(
        &mut self,
        bus: &mut B,
        deadline: u64,
        stop: &mut F,
    ) -> Result<IdleRun, CpuError> {
        let mut run = IdleRun { busy: 0, end: None };
        let pc = self.pc;
        if !self.fast_forward
            || self.state != RunState::Sleeping
            || self.irq_inhibit
            || self
                .idle_fails
                .iter()
                .any(|&(p, n)| p == pc && n >= MAX_FAILS)
        {
            return Ok(run);
        }
        let mut a = match self.record_cycle(bus, deadline, stop, &mut run.busy)? {
            Recorded::Cycle(c) => c,
            Recorded::Other(end) => {
                run.end = end;
                return Ok(run);
            }
        };
        let mut tries = 0;
        let plan = loop {
            let b = match self.record_cycle(bus, deadline, stop, &mut run.busy)? {
                Recorded::Cycle(c) => c,
                Recorded::Other(end) => {
                    run.end = end;
                    return Ok(run);
                }
            };
            tries += 1;
            match self.prove(bus, &a, &b) {
                Ok(p) => break p,
                Err(NoProof::Misaligned) if tries < 2 => a = b,
                Err(NoProof::NotNow) => return Ok(run),
                Err(NoProof::Fails | NoProof::Misaligned) => {
                    match self.idle_fails.iter_mut().find(|(p, _)| *p == pc) {
                        Some((_, n)) => *n += 1,
                        None => self.idle_fails.push((pc, 1)),
                    }
                    return Ok(run);
                }
            }
        };
        // Cycles 2..=last are proven; advance those that end by the deadline and by the
        // instant a device outside the signature next requests.
        let now = bus.now();
        let room = deadline.min(bus.idle_horizon()).saturating_sub(now) / plan.period;
        let n = (plan.last - 1).min(room).min(u64::from(u32::MAX));
        if n == 0 {
            return Ok(run);
        }
        let n32 = n as u32;
        let ram: Vec<(u32, u32)> = plan
            .ram
            .iter()
            .map(|&(a, v, d)| (a, v.wrapping_add(d.wrapping_mul(n32))))
            .collect();
        if !bus.idle_shift(n * plan.period, &ram) {
            return Ok(run);
        }
        for (r, d) in self.er.iter_mut().zip(plan.stride) {
            *r = r.wrapping_add(d.wrapping_mul(n32));
        }
        self.instructions += n * plan.instructions;
        self.skipped += n * plan.instructions;
        self.idle_skipped += n;
        run.busy += n * plan.busy;
        Ok(run)
    }

    /// Runs one idle cycle from sleep back to sleep, logging it.
    fn record_cycle<B: FastPathHints, F: FnMut(&Cpu, &B) -> bool>(
        &mut self,
        bus: &mut B,
        deadline: u64,
        stop: &mut F,
        busy: &mut u64,
    ) -> Result<Recorded, CpuError> {
        let pc0 = self.pc;
        let start = bus.now();
        let signature = bus.idle_signature();
        let (regs, ccr) = (self.er, self.ccr);
        if start >= deadline || !bus.sleep_until_irq(deadline) {
            return Ok(Recorded::Other(Some(Event::Asleep)));
        }
        let wake = bus.now();
        let mut log = Log {
            bus,
            wake,
            step: 0,
            accesses: Vec::with_capacity(32),
        };
        let mut steps = Vec::with_capacity(32);
        loop {
            if steps.len() >= MAX_CYCLE || log.bus.now() >= deadline {
                *busy += log.bus.now() - wake;
                return Ok(Recorded::Other(None));
            }
            let (pc, regs, ccr, inhibit) = (self.pc, self.er, self.ccr, self.irq_inhibit);
            log.step = steps.len() as u32;
            let event = self.step(&mut log, deadline)?;
            let kind = match event {
                Event::Interrupt(v) => Kind::Interrupt(v),
                Event::Executed => Kind::Instr(self.last_executed().instr),
                other => {
                    *busy += log.bus.now() - wake;
                    return Ok(Recorded::Other(Some(other)));
                }
            };
            steps.push(Step {
                kind,
                pc,
                regs,
                ccr,
                inhibit,
                at: log.bus.now() - wake,
            });
            if event == Event::Executed && stop(self, log.bus) {
                *busy += log.bus.now() - wake;
                return Ok(Recorded::Other(Some(Event::Executed)));
            }
            if self.state != RunState::Running {
                break;
            }
        }
        *busy += log.bus.now() - wake;
        if self.state != RunState::Sleeping || self.pc != pc0 {
            return Ok(Recorded::Other(None));
        }
        Ok(Recorded::Cycle(Cycle {
            start,
            wake,
            signature,
            regs,
            ccr,
            steps,
            accesses: log.accesses,
        }))
    }

    /// Checks that cycles A and B prove the next ones (module docs); the CPU is at B's end.
    fn prove<B: FastPathHints>(&self, bus: &B, a: &Cycle, b: &Cycle) -> Result<Plan, NoProof> {
        use NoProof::{Fails, Misaligned, NotNow};
        let (Some(sa), Some(sb)) = (&a.signature, &b.signature) else {
            return Err(NotNow);
        };
        let period = b.start - a.start;
        let end = bus.now();
        if sa != sb || end - b.start != period || a.wake - a.start != b.wake - b.start {
            // A began somewhere else in the period (the first sleep after other work).
            return Err(Misaligned);
        }
        if a.steps.len() != b.steps.len()
            || a.accesses.len() != b.accesses.len()
            || a.ccr != b.ccr
            || b.ccr != self.ccr
        {
            return Err(Fails);
        }
        let stride = self.register_stride(a, b)?;
        let last = self.steps_repeat(a, b)?;
        accesses_repeat(bus, a, b)?;
        let ram = ram_strides(&ram_records(a, b))?;
        if last < 2 {
            return Err(NotNow);
        }
        let instructions = a
            .steps
            .iter()
            .filter(|s| matches!(s.kind, Kind::Instr(_)))
            .count() as u64;
        Ok(Plan {
            period,
            busy: end - b.wake,
            instructions,
            last,
            stride,
            ram,
        })
    }

    /// The registers at the three boundaries (A's start, B's start, now): the same change per
    /// cycle, which is returned.
    fn register_stride(&self, a: &Cycle, b: &Cycle) -> Result<[u32; 8], NoProof> {
        let mut stride = [0u32; 8];
        for (r, s) in stride.iter_mut().enumerate() {
            *s = b.regs[r].wrapping_sub(a.regs[r]);
            if self.er[r].wrapping_sub(b.regs[r]) != *s {
                return Err(NoProof::Fails);
            }
        }
        Ok(stride)
    }

    /// The steps of A and B: the same in everything but affine values. Returns the number of
    /// further cycles for which every affine value keeps its flags ([`span`]'s minimum).
    fn steps_repeat(&self, a: &Cycle, b: &Cycle) -> Result<u64, NoProof> {
        use NoProof::Fails;
        let mut last = u64::MAX;
        for (i, (sa, sb)) in a.steps.iter().zip(&b.steps).enumerate() {
            if sa.kind != sb.kind
                || sa.pc != sb.pc
                || sa.at != sb.at
                || sa.ccr != sb.ccr
                || sa.inhibit != sb.inhibit
            {
                return Err(Fails);
            }
            // Registers after the step: before the next one, or at the cycle's end.
            let after = |c: &Cycle, end_regs: [u32; 8]| -> [u32; 8] {
                c.steps.get(i + 1).map_or(end_regs, |s| s.regs)
            };
            let (aa, ab) = (after(a, b.regs), after(b, self.er));
            if !affine(sa.kind) {
                let m = inputs(sa.kind);
                for r in 0..8 {
                    if m & (1 << r) != 0 && sa.regs[r] != sb.regs[r] {
                        return Err(Fails);
                    }
                }
                continue;
            }
            let Kind::Instr(instr) = sa.kind else {
                return Err(Fails);
            };
            for (va, vb) in affine_values(instr, sa, sb, &aa, &ab)? {
                last = last.min(span(va, vb));
            }
        }
        Ok(last)
    }
}

/// The values an affine instruction's flags depend on, in cycle A and in cycle B (`sa`, `sb`:
/// the step in each; `aa`, `ab`: the registers after it): the source, the destination and the
/// result; `(1, 1)` where there is none.
fn affine_values(
    instr: Instr,
    sa: &Step,
    sb: &Step,
    aa: &[u32; 8],
    ab: &[u32; 8],
) -> Result<[(u32, u32); 3], NoProof> {
    use NoProof::Fails;
    let reg = |r: u8| (sa.regs[usize::from(r & 7)], sb.regs[usize::from(r & 7)]);
    let out = |r: u8| (aa[usize::from(r & 7)], ab[usize::from(r & 7)]);
    let mut values: [(u32, u32); 3] = [(1, 1); 3];
    match instr {
        Instr::Mov { src, dst, .. } => {
            let m = address_regs(src) | address_regs(dst);
            for r in 0..8 {
                if m & (1 << r) != 0 && sa.regs[r] != sb.regs[r] {
                    return Err(Fails);
                }
            }
            values[0] = match (src, dst) {
                (Operand::Reg(r), _) => reg(r),
                (_, Operand::Reg(r)) => out(r),
                _ => return Err(Fails),
            };
        }
        Instr::Alu { op, src, rd, .. } => {
            let s = match src {
                Operand::Reg(r) => reg(r),
                Operand::Imm(v) => (v, v),
                _ => return Err(Fails),
            };
            let d = reg(rd);
            values[0] = s;
            values[1] = d;
            values[2] = if op == AluOp::Cmp {
                (d.0.wrapping_sub(s.0), d.1.wrapping_sub(s.1))
            } else {
                out(rd)
            };
        }
        Instr::Inc { rd, .. } | Instr::Dec { rd, .. } => {
            values[0] = reg(rd);
            values[1] = out(rd);
        }
        // ADDS/SUBS: no flags, any value.
        _ => {}
    }
    Ok(values)
}

/// The data accesses of A and B: the same but for RAM values, and to devices only those the
/// bus covers ([`FastPathHints::idle_io`]).
fn accesses_repeat<B: FastPathHints>(bus: &B, a: &Cycle, b: &Cycle) -> Result<(), NoProof> {
    use NoProof::Fails;
    for (x, y) in a.accesses.iter().zip(&b.accesses) {
        if x.addr != y.addr
            || x.wide != y.wide
            || x.write != y.write
            || x.at != y.at
            || x.step != y.step
        {
            return Err(Fails);
        }
        match Area::of(x.addr) {
            Area::Ram => {}
            Area::Io if !bus.idle_io(x.addr) => return Err(Fails),
            _ if x.value != y.value => return Err(Fails),
            _ => {}
        }
    }
    Ok(())
}

/// One data access of the cycle, or the two word accesses of a 32-bit MOV taken together, with
/// its value in A and in B.
#[derive(Clone, Copy)]
struct Record {
    addr: u32,
    len: u32,
    write: bool,
    va: u32,
    vb: u32,
    /// The two words of a longword MOV.
    long: bool,
}

/// A's and B's accesses as [`Record`]s: longword MOVs' word pairs joined.
fn ram_records(a: &Cycle, b: &Cycle) -> Vec<Record> {
    let mut records = Vec::new();
    let mut k = 0;
    while k < a.accesses.len() {
        let (x, y) = (a.accesses[k], b.accesses[k]);
        let step = a.steps[x.step as usize].kind;
        let long_mov = affine(step) && matches!(step, Kind::Instr(Instr::Mov { .. }));
        if long_mov
            && k + 1 < a.accesses.len()
            && a.accesses[k + 1].step == x.step
            && a.accesses[k + 1].addr == x.addr + 2
            && a.accesses[k + 1].write == x.write
            && x.wide
        {
            let (x2, y2) = (a.accesses[k + 1], b.accesses[k + 1]);
            records.push(Record {
                addr: x.addr,
                len: 4,
                write: x.write,
                va: long(x.value, x2.value),
                vb: long(y.value, y2.value),
                long: true,
            });
            k += 2;
        } else {
            let len = if x.wide { 2 } else { 1 };
            records.push(Record {
                addr: x.addr,
                len,
                write: x.write,
                va: u32::from(x.value),
                vb: u32::from(y.value),
                long: false,
            });
            k += 1;
        }
    }
    records
}

/// The RAM longwords whose values change from A to B, as (address, value at B's end, change
/// per cycle): each must be accessed only as a whole longword, written in the cycle, and read
/// (if at all, before the first write) with the same change. A changing value of any other
/// access fails.
fn ram_strides(records: &[Record]) -> Result<Vec<(u32, u32, u32)>, NoProof> {
    use NoProof::Fails;
    let mut ram: Vec<(u32, u32, u32)> = Vec::new();
    for r in records {
        let addr = r.addr;
        if r.va == r.vb || Area::of(addr) != Area::Ram {
            continue;
        }
        if !r.long || ram.iter().any(|&(a2, _, _)| a2 == addr) {
            if !r.long {
                return Err(Fails);
            }
            continue;
        }
        // Every record touching the longword is a whole longword record there.
        let mut first_read: Option<(u32, u32)> = None;
        let mut seen_write = false;
        let mut last_write: Option<(u32, u32)> = None;
        for o in records {
            if o.addr < addr + 4 && addr < o.addr + o.len {
                if o.addr != addr || !o.long {
                    return Err(Fails);
                }
                if o.write {
                    seen_write = true;
                    last_write = Some((o.va, o.vb));
                } else if !seen_write && first_read.is_none() {
                    first_read = Some((o.va, o.vb));
                }
            }
        }
        let Some((wa, wb)) = last_write else {
            return Err(Fails);
        };
        let d = wb.wrapping_sub(wa);
        if let Some((ra, rb)) = first_read
            && rb.wrapping_sub(ra) != d
        {
            return Err(Fails);
        }
        ram.push((addr, wb, d));
    }
    Ok(ram)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn span_stays_inside_the_block_and_off_zero() {
        // Counting up from 5 by 1: fine to the end of the first block.
        assert_eq!(span(5, 6), BLOCK - 1 - 5);
        // Counting -44, -43, ... towards zero: the last index is the one at -1.
        let v = (-44i32) as u32;
        assert_eq!(span(v, v.wrapping_add(1)), 43);
        // Down towards zero: stops at 1.
        assert_eq!(span(10, 8), 4);
        // Unchanged: no bound.
        assert_eq!(span(7, 7), u64::MAX);
        // Changing from zero: no cycle beyond A.
        assert_eq!(span(0, 1), 0);
        // Already outside: a stride leaving the block at once.
        assert_eq!(span((BLOCK - 1) as u32, BLOCK as u32), 0);
    }
}
