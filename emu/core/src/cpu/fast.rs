//! The fast path's handlers: each ROM instruction decoded once into an [`Op`] of its own form
//! (operation, size and operand kind fixed; immediates masked; branch targets, condition masks
//! and prefetch states computed), so executing it is one dispatch and straight-line code.
//!
//! Every handler does what the reference executor (`exec`) does for the same instruction with
//! the same helpers (flags, operands, memory accesses), in the same order. The only change is
//! how fetches are charged: the instruction's own words as one [`Bus::internal`] lump before
//! it runs (in `Cpu::step`), and the prefetch at a branch target as [`Bus::internal`] of that
//! area's word states. Both are what the bus promised with [`crate::bus::FastPathHints::code_generation`]: a fetch
//! from ROM or RAM has no effect but the clock. Forms without a handler here are
//! [`Op::Generic`] and run on the reference executor.

use super::decode::{AluOp, Decoded, Instr, JumpTarget, Operand, Size, UnaryOp};
use super::exec::{cond_holds, stack_operand, sz, writes_sp};
use super::timing as t;
use super::{Cpu, CpuError, Event, StackAccess};
use crate::bus::Bus;
use crate::memmap::{ADDRESS_MASK, Area};

/// One cached ROM instruction of the fast path.
#[derive(Clone, Copy, Debug)]
pub(super) struct Slot {
    /// What to do.
    pub(super) op: Op,
    /// The address after the instruction.
    pub(super) next: u32,
    /// Length in words (0: an empty slot).
    pub(super) words: u8,
    /// Whether the handler always leaves PC at `next` and the run state as it was (no
    /// branch, no [`Op::Generic`]).
    pub(super) sequential: bool,
    /// Whether this is a Bcc whose target is at or before it: a loop's back edge, where
    /// [`super::ffwd`] looks for loops to fast-forward.
    pub(super) back_edge: bool,
}

/// A pre-decoded instruction form. Register numbers are those of [`Instr`] (byte and word
/// registers 0–15, longword registers 0–7); immediates are masked to the operand size.
#[derive(Clone, Copy, Debug)]
pub(super) enum Op {
    /// No handler here: the reference executor runs the cached [`Decoded`].
    Generic,
    /// `nop`.
    Nop,
    // MOV between registers, immediate to register, memory to register, register to memory.
    MovR8 {
        rs: u8,
        rd: u8,
    },
    MovR16 {
        rs: u8,
        rd: u8,
    },
    MovR32 {
        rs: u8,
        rd: u8,
    },
    MovI8 {
        v: u32,
        rd: u8,
    },
    MovI16 {
        v: u32,
        rd: u8,
    },
    MovI32 {
        v: u32,
        rd: u8,
    },
    Ld8 {
        src: Operand,
        rd: u8,
    },
    Ld16 {
        src: Operand,
        rd: u8,
    },
    Ld32 {
        src: Operand,
        rd: u8,
    },
    St8 {
        rs: u8,
        dst: Operand,
    },
    St16 {
        rs: u8,
        dst: Operand,
    },
    St32 {
        rs: u8,
        dst: Operand,
    },
    /// A load through ER7 (a pop, a local, an argument): the stack guard checks it first.
    LdStack {
        size: Size,
        src: Operand,
        rd: u8,
    },
    /// A store through ER7 (a push, a local): the stack guard checks it first.
    StStack {
        size: Size,
        rs: u8,
        dst: Operand,
    },
    // Two-operand ALU operations, register (R) or immediate (I) source.
    AddR8 {
        rs: u8,
        rd: u8,
    },
    AddR16 {
        rs: u8,
        rd: u8,
    },
    AddR32 {
        rs: u8,
        rd: u8,
    },
    AddI8 {
        v: u32,
        rd: u8,
    },
    AddI16 {
        v: u32,
        rd: u8,
    },
    AddI32 {
        v: u32,
        rd: u8,
    },
    SubR8 {
        rs: u8,
        rd: u8,
    },
    SubR16 {
        rs: u8,
        rd: u8,
    },
    SubR32 {
        rs: u8,
        rd: u8,
    },
    SubI16 {
        v: u32,
        rd: u8,
    },
    SubI32 {
        v: u32,
        rd: u8,
    },
    CmpR8 {
        rs: u8,
        rd: u8,
    },
    CmpR16 {
        rs: u8,
        rd: u8,
    },
    CmpR32 {
        rs: u8,
        rd: u8,
    },
    CmpI8 {
        v: u32,
        rd: u8,
    },
    CmpI16 {
        v: u32,
        rd: u8,
    },
    CmpI32 {
        v: u32,
        rd: u8,
    },
    AndR8 {
        rs: u8,
        rd: u8,
    },
    AndR16 {
        rs: u8,
        rd: u8,
    },
    AndR32 {
        rs: u8,
        rd: u8,
    },
    AndI8 {
        v: u32,
        rd: u8,
    },
    AndI16 {
        v: u32,
        rd: u8,
    },
    AndI32 {
        v: u32,
        rd: u8,
    },
    OrR8 {
        rs: u8,
        rd: u8,
    },
    OrR16 {
        rs: u8,
        rd: u8,
    },
    OrR32 {
        rs: u8,
        rd: u8,
    },
    OrI8 {
        v: u32,
        rd: u8,
    },
    OrI16 {
        v: u32,
        rd: u8,
    },
    OrI32 {
        v: u32,
        rd: u8,
    },
    XorR8 {
        rs: u8,
        rd: u8,
    },
    XorR16 {
        rs: u8,
        rd: u8,
    },
    XorR32 {
        rs: u8,
        rd: u8,
    },
    XorI8 {
        v: u32,
        rd: u8,
    },
    XorI16 {
        v: u32,
        rd: u8,
    },
    XorI32 {
        v: u32,
        rd: u8,
    },
    AddxR8 {
        rs: u8,
        rd: u8,
    },
    AddxI8 {
        v: u32,
        rd: u8,
    },
    SubxR8 {
        rs: u8,
        rd: u8,
    },
    SubxI8 {
        v: u32,
        rd: u8,
    },
    // INC/DEC by 1 or 2; ADDS/SUBS as an addition of `v` (SUBS: the negated amount).
    Inc8 {
        amount: u8,
        rd: u8,
    },
    Inc16 {
        amount: u8,
        rd: u8,
    },
    Inc32 {
        amount: u8,
        rd: u8,
    },
    Dec8 {
        amount: u8,
        rd: u8,
    },
    Dec16 {
        amount: u8,
        rd: u8,
    },
    Dec32 {
        amount: u8,
        rd: u8,
    },
    Adds {
        v: u32,
        rd: u8,
    },
    // Shifts, rotates, NEG, NOT, EXTS, EXTU by size.
    Shll32 {
        rd: u8,
    },
    Shlr32 {
        rd: u8,
    },
    Shar32 {
        rd: u8,
    },
    Un8 {
        op: UnaryOp,
        rd: u8,
    },
    Un16 {
        op: UnaryOp,
        rd: u8,
    },
    Un32 {
        op: UnaryOp,
        rd: u8,
    },
    /// Bcc d:8: `mask` bit (CCR & 15) says whether the branch is taken; the prefetch costs
    /// `taken_states` at the target or `next_states` after the instruction.
    Bcc8 {
        mask: u16,
        target: u32,
        taken_states: u8,
        next_states: u8,
    },
    /// Bcc d:16 (N = 2, no prefetch).
    Bcc16 {
        mask: u16,
        target: u32,
    },
    /// BSR d:8: push, prefetch at the target.
    Bsr8 {
        target: u32,
        prefetch_states: u8,
    },
    /// BSR d:16: push, N = 2.
    Bsr16 {
        target: u32,
    },
    /// JMP @aa:24 (N = 2).
    JmpAbs {
        target: u32,
    },
    /// JSR @aa:24: push, N = 2.
    JsrAbs {
        target: u32,
    },
    /// JMP @ERn: prefetch at the target.
    JmpReg {
        r: u8,
    },
    /// JSR @ERn: push, prefetch at the target.
    JsrReg {
        r: u8,
    },
    /// RTS: pop, prefetch at the return address, N = 2.
    Rts,
}

/// The bits of [`Op::Bcc8`]'s `mask`: bit f set when condition `cc` holds for flags
/// N Z V C = f (the low nibble of CCR).
pub(super) const fn cond_mask(cc: u8) -> u16 {
    let mut m = 0u16;
    let mut f = 0u8;
    while f < 16 {
        if cond_holds(cc, f) {
            m |= 1 << f;
        }
        f += 1;
    }
    m
}

/// Word states of the prefetch at `addr` (an executable area's word read, or the internal
/// states the reference path charges elsewhere: both are that area's word states).
#[inline(always)]
const fn prefetch_states(addr: u32) -> u32 {
    Area::of(addr).word_states()
}

impl Slot {
    /// An empty slot.
    pub(super) const EMPTY: Slot = Slot {
        op: Op::Generic,
        next: 0,
        words: 0,
        sequential: false,
        back_edge: false,
    };

    /// The handler of instruction `d` at `pc` (in ROM).
    pub(super) fn new(d: Decoded, pc: u32) -> Slot {
        let next = pc.wrapping_add(d.len_bytes()) & ADDRESS_MASK;
        // An instruction that sets SP as a register runs on the reference executor, which
        // checks SP after it for the stack guard.
        let op = if writes_sp(d.instr) {
            Op::Generic
        } else {
            op_of(d.instr, next)
        };
        let sequential = !matches!(
            op,
            Op::Generic
                | Op::Bcc8 { .. }
                | Op::Bcc16 { .. }
                | Op::Bsr8 { .. }
                | Op::Bsr16 { .. }
                | Op::JmpAbs { .. }
                | Op::JsrAbs { .. }
                | Op::JmpReg { .. }
                | Op::JsrReg { .. }
                | Op::Rts
        );
        let back_edge = match op {
            Op::Bcc8 { target, .. } | Op::Bcc16 { target, .. } => target <= pc,
            _ => false,
        };
        Slot {
            op,
            next,
            words: d.words,
            sequential,
            back_edge,
        }
    }
}

/// `#imm` masked to `size`, as the reference path reads it.
const fn imm(size: Size, v: u32) -> u32 {
    v & sz(size).mask
}

/// The handler of `instr`, whose following instruction is at `next`.
fn op_of(instr: Instr, next: u32) -> Op {
    use Size::{Byte, Long, Word};
    let branch_target = |disp: i16| next.wrapping_add(disp as i32 as u32) & ADDRESS_MASK;
    match instr {
        Instr::Nop => Op::Nop,
        Instr::Mov { size, src, dst } => mov_op(size, src, dst),
        Instr::Alu { op, size, src, rd } => alu_op(op, size, src, rd),
        Instr::Inc { size, amount, rd } => match size {
            Byte => Op::Inc8 { amount, rd },
            Word => Op::Inc16 { amount, rd },
            Long => Op::Inc32 { amount, rd },
        },
        Instr::Dec { size, amount, rd } => match size {
            Byte => Op::Dec8 { amount, rd },
            Word => Op::Dec16 { amount, rd },
            Long => Op::Dec32 { amount, rd },
        },
        Instr::Adds { amount, rd } => Op::Adds {
            v: u32::from(amount),
            rd,
        },
        Instr::Subs { amount, rd } => Op::Adds {
            v: u32::from(amount).wrapping_neg(),
            rd,
        },
        Instr::Unary { op, size, rd } => match (op, size) {
            (UnaryOp::Shll, Long) => Op::Shll32 { rd },
            (UnaryOp::Shlr, Long) => Op::Shlr32 { rd },
            (UnaryOp::Shar, Long) => Op::Shar32 { rd },
            (op, Byte) => Op::Un8 { op, rd },
            (op, Word) => Op::Un16 { op, rd },
            (op, Long) => Op::Un32 { op, rd },
        },
        Instr::Bcc { cond, disp, long } => bcc_op(cond, branch_target(disp), long, next),
        Instr::Bsr { disp, long } => bsr_op(branch_target(disp), long),
        Instr::Jmp(JumpTarget::Abs24(a)) => Op::JmpAbs {
            target: a & ADDRESS_MASK & !1,
        },
        Instr::Jsr(JumpTarget::Abs24(a)) => Op::JsrAbs {
            target: a & ADDRESS_MASK & !1,
        },
        Instr::Jmp(JumpTarget::Reg(r)) => Op::JmpReg { r },
        Instr::Jsr(JumpTarget::Reg(r)) => Op::JsrReg { r },
        Instr::Rts => Op::Rts,
        _ => Op::Generic,
    }
}

/// The handler of `mov.size src,dst`.
fn mov_op(size: Size, src: Operand, dst: Operand) -> Op {
    use Operand::{Imm, Reg};
    use Size::{Byte, Long, Word};
    match (size, src, dst) {
        (Byte, Reg(rs), Reg(rd)) => Op::MovR8 { rs, rd },
        (Word, Reg(rs), Reg(rd)) => Op::MovR16 { rs, rd },
        (Long, Reg(rs), Reg(rd)) => Op::MovR32 { rs, rd },
        (Byte, Imm(v), Reg(rd)) => Op::MovI8 {
            v: imm(Byte, v),
            rd,
        },
        (Word, Imm(v), Reg(rd)) => Op::MovI16 {
            v: imm(Word, v),
            rd,
        },
        (Long, Imm(v), Reg(rd)) => Op::MovI32 {
            v: imm(Long, v),
            rd,
        },
        (size, src, Reg(rd)) if stack_operand(src) => Op::LdStack { size, src, rd },
        (size, Reg(rs), dst) if stack_operand(dst) => Op::StStack { size, rs, dst },
        (Byte, src, Reg(rd)) if src.is_memory() => Op::Ld8 { src, rd },
        (Word, src, Reg(rd)) if src.is_memory() => Op::Ld16 { src, rd },
        (Long, src, Reg(rd)) if src.is_memory() => Op::Ld32 { src, rd },
        (Byte, Reg(rs), dst) if dst.is_memory() => Op::St8 { rs, dst },
        (Word, Reg(rs), dst) if dst.is_memory() => Op::St16 { rs, dst },
        (Long, Reg(rs), dst) if dst.is_memory() => Op::St32 { rs, dst },
        _ => Op::Generic,
    }
}

/// The handler of `op.size src,Rd` (a two-operand ALU operation).
fn alu_op(op: AluOp, size: Size, src: Operand, rd: u8) -> Op {
    use Operand::{Imm, Reg};
    use Size::{Byte, Long, Word};
    match (op, size, src) {
        (AluOp::Add, Byte, Reg(rs)) => Op::AddR8 { rs, rd },
        (AluOp::Add, Word, Reg(rs)) => Op::AddR16 { rs, rd },
        (AluOp::Add, Long, Reg(rs)) => Op::AddR32 { rs, rd },
        (AluOp::Add, Byte, Imm(v)) => Op::AddI8 {
            v: imm(Byte, v),
            rd,
        },
        (AluOp::Add, Word, Imm(v)) => Op::AddI16 {
            v: imm(Word, v),
            rd,
        },
        (AluOp::Add, Long, Imm(v)) => Op::AddI32 {
            v: imm(Long, v),
            rd,
        },
        (AluOp::Sub, Byte, Reg(rs)) => Op::SubR8 { rs, rd },
        (AluOp::Sub, Word, Reg(rs)) => Op::SubR16 { rs, rd },
        (AluOp::Sub, Long, Reg(rs)) => Op::SubR32 { rs, rd },
        (AluOp::Sub, Word, Imm(v)) => Op::SubI16 {
            v: imm(Word, v),
            rd,
        },
        (AluOp::Sub, Long, Imm(v)) => Op::SubI32 {
            v: imm(Long, v),
            rd,
        },
        (AluOp::Cmp, Byte, Reg(rs)) => Op::CmpR8 { rs, rd },
        (AluOp::Cmp, Word, Reg(rs)) => Op::CmpR16 { rs, rd },
        (AluOp::Cmp, Long, Reg(rs)) => Op::CmpR32 { rs, rd },
        (AluOp::Cmp, Byte, Imm(v)) => Op::CmpI8 {
            v: imm(Byte, v),
            rd,
        },
        (AluOp::Cmp, Word, Imm(v)) => Op::CmpI16 {
            v: imm(Word, v),
            rd,
        },
        (AluOp::Cmp, Long, Imm(v)) => Op::CmpI32 {
            v: imm(Long, v),
            rd,
        },
        (AluOp::And, Byte, Reg(rs)) => Op::AndR8 { rs, rd },
        (AluOp::And, Word, Reg(rs)) => Op::AndR16 { rs, rd },
        (AluOp::And, Long, Reg(rs)) => Op::AndR32 { rs, rd },
        (AluOp::And, Byte, Imm(v)) => Op::AndI8 {
            v: imm(Byte, v),
            rd,
        },
        (AluOp::And, Word, Imm(v)) => Op::AndI16 {
            v: imm(Word, v),
            rd,
        },
        (AluOp::And, Long, Imm(v)) => Op::AndI32 {
            v: imm(Long, v),
            rd,
        },
        (AluOp::Or, Byte, Reg(rs)) => Op::OrR8 { rs, rd },
        (AluOp::Or, Word, Reg(rs)) => Op::OrR16 { rs, rd },
        (AluOp::Or, Long, Reg(rs)) => Op::OrR32 { rs, rd },
        (AluOp::Or, Byte, Imm(v)) => Op::OrI8 {
            v: imm(Byte, v),
            rd,
        },
        (AluOp::Or, Word, Imm(v)) => Op::OrI16 {
            v: imm(Word, v),
            rd,
        },
        (AluOp::Or, Long, Imm(v)) => Op::OrI32 {
            v: imm(Long, v),
            rd,
        },
        (AluOp::Xor, Byte, Reg(rs)) => Op::XorR8 { rs, rd },
        (AluOp::Xor, Word, Reg(rs)) => Op::XorR16 { rs, rd },
        (AluOp::Xor, Long, Reg(rs)) => Op::XorR32 { rs, rd },
        (AluOp::Xor, Byte, Imm(v)) => Op::XorI8 {
            v: imm(Byte, v),
            rd,
        },
        (AluOp::Xor, Word, Imm(v)) => Op::XorI16 {
            v: imm(Word, v),
            rd,
        },
        (AluOp::Xor, Long, Imm(v)) => Op::XorI32 {
            v: imm(Long, v),
            rd,
        },
        (AluOp::Addx, Byte, Reg(rs)) => Op::AddxR8 { rs, rd },
        (AluOp::Addx, Byte, Imm(v)) => Op::AddxI8 {
            v: imm(Byte, v),
            rd,
        },
        (AluOp::Subx, Byte, Reg(rs)) => Op::SubxR8 { rs, rd },
        (AluOp::Subx, Byte, Imm(v)) => Op::SubxI8 {
            v: imm(Byte, v),
            rd,
        },
        _ => Op::Generic,
    }
}

/// The handler of `bcc` (`long`: d:16) to `target`, the instruction after it at `next`.
fn bcc_op(cond: u8, target: u32, long: bool, next: u32) -> Op {
    if long {
        Op::Bcc16 {
            mask: cond_mask(cond),
            target: target & !1,
        }
    } else {
        Op::Bcc8 {
            mask: cond_mask(cond),
            target: target & !1,
            taken_states: prefetch_states(target) as u8,
            next_states: prefetch_states(next) as u8,
        }
    }
}

/// The handler of `bsr` (`long`: d:16) to `target`.
fn bsr_op(target: u32, long: bool) -> Op {
    if long {
        Op::Bsr16 {
            target: target & !1,
        }
    } else {
        Op::Bsr8 {
            target: target & !1,
            prefetch_states: prefetch_states(target) as u8,
        }
    }
}

/// `op.size Rs,Rd` through the reference ALU (constant operation and size fold away).
macro_rules! alu_r {
    ($cpu:ident, $op:ident, $size:ident, $rs:expr, $rd:expr) => {{
        let b = $cpu.reg(Size::$size, $rs);
        $cpu.alu(AluOp::$op, Size::$size, b, $rd);
    }};
}

/// `op.size #v,Rd` through the reference ALU.
macro_rules! alu_i {
    ($cpu:ident, $op:ident, $size:ident, $v:expr, $rd:expr) => {{
        $cpu.alu(AluOp::$op, Size::$size, $v, $rd);
    }};
}

impl Cpu {
    /// Runs the cached instruction at `pc` (cache index `idx`, a filled slot) whose words have
    /// been charged; `next` is the address after it.
    #[inline(always)]
    pub(super) fn exec_fast<B: Bus>(
        &mut self,
        bus: &mut B,
        pc: u32,
        idx: usize,
        next: u32,
    ) -> Result<Event, CpuError> {
        self.pc = next;
        self.instructions += 1;
        self.last_index = idx as u32;
        // Matched in place: each handler reads only its own fields.
        match self.fast[idx].op {
            Op::Generic => {
                let d = self.cache[idx];
                return self.exec_instr(bus, d, pc, next);
            }
            Op::Nop => {}
            Op::MovR8 { rs, rd } => self.mov_reg(Size::Byte, self.reg(Size::Byte, rs), rd),
            Op::MovR16 { rs, rd } => self.mov_reg(Size::Word, self.reg(Size::Word, rs), rd),
            Op::MovR32 { rs, rd } => self.mov_reg(Size::Long, self.reg(Size::Long, rs), rd),
            Op::MovI8 { v, rd } => self.mov_reg(Size::Byte, v, rd),
            Op::MovI16 { v, rd } => self.mov_reg(Size::Word, v, rd),
            Op::MovI32 { v, rd } => self.mov_reg(Size::Long, v, rd),
            Op::Ld8 { src, rd } => self.load(bus, Size::Byte, src, rd),
            Op::Ld16 { src, rd } => self.load(bus, Size::Word, src, rd),
            Op::Ld32 { src, rd } => self.load(bus, Size::Long, src, rd),
            Op::St8 { rs, dst } => self.store(bus, Size::Byte, rs, dst),
            Op::St16 { rs, dst } => self.store(bus, Size::Word, rs, dst),
            Op::St32 { rs, dst } => self.store(bus, Size::Long, rs, dst),
            Op::LdStack { size, src, rd } => self.load_stack(bus, size, src, rd, pc)?,
            Op::StStack { size, rs, dst } => self.store_stack(bus, size, rs, dst, pc)?,
            Op::AddR8 { rs, rd } => alu_r!(self, Add, Byte, rs, rd),
            Op::AddR16 { rs, rd } => alu_r!(self, Add, Word, rs, rd),
            Op::AddR32 { rs, rd } => alu_r!(self, Add, Long, rs, rd),
            Op::AddI8 { v, rd } => alu_i!(self, Add, Byte, v, rd),
            Op::AddI16 { v, rd } => alu_i!(self, Add, Word, v, rd),
            Op::AddI32 { v, rd } => alu_i!(self, Add, Long, v, rd),
            Op::SubR8 { rs, rd } => alu_r!(self, Sub, Byte, rs, rd),
            Op::SubR16 { rs, rd } => alu_r!(self, Sub, Word, rs, rd),
            Op::SubR32 { rs, rd } => alu_r!(self, Sub, Long, rs, rd),
            Op::SubI16 { v, rd } => alu_i!(self, Sub, Word, v, rd),
            Op::SubI32 { v, rd } => alu_i!(self, Sub, Long, v, rd),
            Op::CmpR8 { rs, rd } => alu_r!(self, Cmp, Byte, rs, rd),
            Op::CmpR16 { rs, rd } => alu_r!(self, Cmp, Word, rs, rd),
            Op::CmpR32 { rs, rd } => alu_r!(self, Cmp, Long, rs, rd),
            Op::CmpI8 { v, rd } => alu_i!(self, Cmp, Byte, v, rd),
            Op::CmpI16 { v, rd } => alu_i!(self, Cmp, Word, v, rd),
            Op::CmpI32 { v, rd } => alu_i!(self, Cmp, Long, v, rd),
            Op::AndR8 { rs, rd } => alu_r!(self, And, Byte, rs, rd),
            Op::AndR16 { rs, rd } => alu_r!(self, And, Word, rs, rd),
            Op::AndR32 { rs, rd } => alu_r!(self, And, Long, rs, rd),
            Op::AndI8 { v, rd } => alu_i!(self, And, Byte, v, rd),
            Op::AndI16 { v, rd } => alu_i!(self, And, Word, v, rd),
            Op::AndI32 { v, rd } => alu_i!(self, And, Long, v, rd),
            Op::OrR8 { rs, rd } => alu_r!(self, Or, Byte, rs, rd),
            Op::OrR16 { rs, rd } => alu_r!(self, Or, Word, rs, rd),
            Op::OrR32 { rs, rd } => alu_r!(self, Or, Long, rs, rd),
            Op::OrI8 { v, rd } => alu_i!(self, Or, Byte, v, rd),
            Op::OrI16 { v, rd } => alu_i!(self, Or, Word, v, rd),
            Op::OrI32 { v, rd } => alu_i!(self, Or, Long, v, rd),
            Op::XorR8 { rs, rd } => alu_r!(self, Xor, Byte, rs, rd),
            Op::XorR16 { rs, rd } => alu_r!(self, Xor, Word, rs, rd),
            Op::XorR32 { rs, rd } => alu_r!(self, Xor, Long, rs, rd),
            Op::XorI8 { v, rd } => alu_i!(self, Xor, Byte, v, rd),
            Op::XorI16 { v, rd } => alu_i!(self, Xor, Word, v, rd),
            Op::XorI32 { v, rd } => alu_i!(self, Xor, Long, v, rd),
            Op::AddxR8 { rs, rd } => alu_r!(self, Addx, Byte, rs, rd),
            Op::AddxI8 { v, rd } => alu_i!(self, Addx, Byte, v, rd),
            Op::SubxR8 { rs, rd } => alu_r!(self, Subx, Byte, rs, rd),
            Op::SubxI8 { v, rd } => alu_i!(self, Subx, Byte, v, rd),
            Op::Inc8 { amount, rd } => self.inc_dec(true, Size::Byte, amount, rd),
            Op::Inc16 { amount, rd } => self.inc_dec(true, Size::Word, amount, rd),
            Op::Inc32 { amount, rd } => self.inc_dec(true, Size::Long, amount, rd),
            Op::Dec8 { amount, rd } => self.inc_dec(false, Size::Byte, amount, rd),
            Op::Dec16 { amount, rd } => self.inc_dec(false, Size::Word, amount, rd),
            Op::Dec32 { amount, rd } => self.inc_dec(false, Size::Long, amount, rd),
            Op::Adds { v, rd } => {
                let e = &mut self.er[usize::from(rd & 7)];
                *e = e.wrapping_add(v);
            }
            Op::Shll32 { rd } => self.unary(UnaryOp::Shll, Size::Long, rd),
            Op::Shlr32 { rd } => self.unary(UnaryOp::Shlr, Size::Long, rd),
            Op::Shar32 { rd } => self.unary(UnaryOp::Shar, Size::Long, rd),
            Op::Un8 { op, rd } => self.unary(op, Size::Byte, rd),
            Op::Un16 { op, rd } => self.unary(op, Size::Word, rd),
            Op::Un32 { op, rd } => self.unary(op, Size::Long, rd),
            Op::Bcc8 {
                mask,
                target,
                taken_states,
                next_states,
            } => self.bcc8(bus, mask, target, taken_states, next_states),
            Op::Bcc16 { mask, target } => self.bcc16(bus, mask, target),
            Op::Bsr8 {
                target,
                prefetch_states,
            } => self.bsr8(bus, target, prefetch_states, pc, next)?,
            Op::Bsr16 { target } => self.bsr16(bus, target, pc, next)?,
            Op::JmpAbs { target } => self.jmp_abs(bus, target),
            Op::JsrAbs { target } => self.jsr_abs(bus, target, pc, next)?,
            Op::JmpReg { r } => self.jmp_reg(bus, r),
            Op::JsrReg { r } => self.jsr_reg(bus, r, pc, next)?,
            Op::Rts => self.rts_fast(bus, pc)?,
        }
        Ok(Event::Executed)
    }

    /// A load through ER7 ([`Op::LdStack`]), checked by the stack guard first.
    #[inline(always)]
    fn load_stack<B: Bus>(
        &mut self,
        bus: &mut B,
        size: Size,
        src: Operand,
        rd: u8,
        pc: u32,
    ) -> Result<(), CpuError> {
        let bytes = sz(size).bytes;
        self.stack_ok(self.stack_target(src, bytes), bytes, StackAccess::Read, pc)?;
        self.load(bus, size, src, rd);
        Ok(())
    }

    /// A store through ER7 ([`Op::StStack`]), checked by the stack guard first.
    #[inline(always)]
    fn store_stack<B: Bus>(
        &mut self,
        bus: &mut B,
        size: Size,
        rs: u8,
        dst: Operand,
        pc: u32,
    ) -> Result<(), CpuError> {
        let bytes = sz(size).bytes;
        self.stack_ok(self.stack_target(dst, bytes), bytes, StackAccess::Write, pc)?;
        self.store(bus, size, rs, dst);
        Ok(())
    }

    /// [`Op::Bcc8`]: the prefetch at the target if taken, after the instruction if not.
    #[inline(always)]
    fn bcc8<B: Bus>(
        &mut self,
        bus: &mut B,
        mask: u16,
        target: u32,
        taken_states: u8,
        next_states: u8,
    ) {
        if (mask >> (self.ccr & 15)) & 1 != 0 {
            bus.internal(u32::from(taken_states));
            self.pc = target;
        } else {
            bus.internal(u32::from(next_states));
        }
    }

    /// [`Op::Bcc16`]: N = 2 either way.
    #[inline(always)]
    fn bcc16<B: Bus>(&mut self, bus: &mut B, mask: u16, target: u32) {
        bus.internal(t::N_BRANCH_D16);
        if (mask >> (self.ccr & 15)) & 1 != 0 {
            self.pc = target;
        }
    }

    /// [`Op::Bsr8`]: push `next`, prefetch at the target.
    #[inline(always)]
    fn bsr8<B: Bus>(
        &mut self,
        bus: &mut B,
        target: u32,
        prefetch_states: u8,
        pc: u32,
        next: u32,
    ) -> Result<(), CpuError> {
        self.push32(bus, next, StackAccess::Call, pc)?;
        bus.internal(u32::from(prefetch_states));
        self.pc = target;
        Ok(())
    }

    /// [`Op::Bsr16`]: push `next`, N = 2.
    #[inline(always)]
    fn bsr16<B: Bus>(
        &mut self,
        bus: &mut B,
        target: u32,
        pc: u32,
        next: u32,
    ) -> Result<(), CpuError> {
        self.push32(bus, next, StackAccess::Call, pc)?;
        bus.internal(t::N_BRANCH_D16);
        self.pc = target;
        Ok(())
    }

    /// [`Op::JmpAbs`]: N = 2.
    #[inline(always)]
    fn jmp_abs<B: Bus>(&mut self, bus: &mut B, target: u32) {
        bus.internal(t::N_JUMP_ABS24);
        self.pc = target;
    }

    /// [`Op::JsrAbs`]: push `next`, N = 2.
    #[inline(always)]
    fn jsr_abs<B: Bus>(
        &mut self,
        bus: &mut B,
        target: u32,
        pc: u32,
        next: u32,
    ) -> Result<(), CpuError> {
        self.push32(bus, next, StackAccess::Call, pc)?;
        bus.internal(t::N_JUMP_ABS24);
        self.pc = target;
        Ok(())
    }

    /// [`Op::JmpReg`]: prefetch at the target.
    #[inline(always)]
    fn jmp_reg<B: Bus>(&mut self, bus: &mut B, r: u8) {
        let target = self.er[usize::from(r & 7)] & ADDRESS_MASK;
        bus.internal(prefetch_states(target));
        self.jump_to(target);
    }

    /// [`Op::JsrReg`]: push `next`, prefetch at the target.
    #[inline(always)]
    fn jsr_reg<B: Bus>(&mut self, bus: &mut B, r: u8, pc: u32, next: u32) -> Result<(), CpuError> {
        // The target is read before the push (JSR @ER7 jumps to ER7's old value).
        let target = self.er[usize::from(r & 7)] & ADDRESS_MASK;
        self.push32(bus, next, StackAccess::Call, pc)?;
        bus.internal(prefetch_states(target));
        self.jump_to(target);
        Ok(())
    }

    /// [`Op::Rts`]: pop, prefetch at the return address, N = 2.
    #[inline(always)]
    fn rts_fast<B: Bus>(&mut self, bus: &mut B, pc: u32) -> Result<(), CpuError> {
        let ret = self.pop32(bus, StackAccess::Return, pc)? & ADDRESS_MASK;
        bus.internal(prefetch_states(ret) + t::N_RETURN);
        self.jump_to(ret);
        Ok(())
    }

    /// MOV of `v` into a register: the reference path's MOV with a register destination.
    #[inline(always)]
    fn mov_reg(&mut self, size: Size, v: u32, rd: u8) {
        self.set_reg(size, rd, v);
        self.flags_nzv0(sz(size), v);
    }

    /// MOV from memory to a register (the reference path's operand read, then the write).
    #[inline(always)]
    fn load<B: Bus>(&mut self, bus: &mut B, size: Size, src: Operand, rd: u8) {
        let v = self.read_operand(bus, size, src);
        self.set_reg(size, rd, v);
        self.flags_nzv0(sz(size), v);
    }

    /// MOV from a register to memory (the value is read before `@-ERd` decrements).
    #[inline(always)]
    fn store<B: Bus>(&mut self, bus: &mut B, size: Size, rs: u8, dst: Operand) {
        let v = self.reg(size, rs);
        self.write_operand(bus, size, dst, v);
        self.flags_nzv0(sz(size), v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn condition_masks_agree_with_the_condition_table() {
        for cc in 0..16u8 {
            let m = cond_mask(cc);
            for ccr in 0..=255u8 {
                assert_eq!(
                    (m >> (ccr & 15)) & 1 != 0,
                    cond_holds(cc, ccr),
                    "cc {cc} ccr {ccr:#x}"
                );
            }
        }
    }

    #[test]
    fn a_slot_is_small() {
        assert!(
            std::mem::size_of::<Slot>() <= 20,
            "{}",
            std::mem::size_of::<Slot>()
        );
    }
}
