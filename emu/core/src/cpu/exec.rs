//! Instruction execution: semantics and condition codes from the H8/300H Series Programming
//! Manual, section 2 (one page per instruction), timing from its Appendix A (see
//! [`super::timing`]).

use super::decode::{
    AluOp, BitNum, BitOp, BitTarget, Decoded, Instr, JumpTarget, MulDivOp, Operand, Size, UnaryOp,
};
use super::timing as t;
use super::{
    CCR_C, CCR_H, CCR_I, CCR_N, CCR_V, CCR_Z, Cpu, CpuError, Event, LAST_IN_COPY, RunState,
    StackAccess,
};
use crate::bus::Bus;
use crate::memmap::{ADDRESS_MASK, Area};

/// Size parameters used by the flag computations.
#[derive(Clone, Copy)]
pub(super) struct Sz {
    pub(super) mask: u32,
    msb: u32,
    /// Mask of the bits below the half-carry position (bit 3, 11 or 27 carries out of it).
    half: u32,
    pub(super) bytes: u32,
}

#[inline(always)]
pub(super) const fn sz(size: Size) -> Sz {
    match size {
        Size::Byte => Sz {
            mask: 0xff,
            msb: 0x80,
            half: 0x0f,
            bytes: 1,
        },
        Size::Word => Sz {
            mask: 0xffff,
            msb: 0x8000,
            half: 0x0fff,
            bytes: 2,
        },
        Size::Long => Sz {
            mask: 0xffff_ffff,
            msb: 0x8000_0000,
            half: 0x0fff_ffff,
            bytes: 4,
        },
    }
}

const NZVC: u8 = CCR_N | CCR_Z | CCR_V | CCR_C;
const HNZVC: u8 = CCR_H | NZVC;
const NZV: u8 = CCR_N | CCR_Z | CCR_V;

/// Whether branch condition `cc` (0–15, the Bcc field) holds for the flags in `ccr`
/// (programming manual, Bcc page: the condition table).
#[inline(always)]
pub(super) const fn cond_holds(cc: u8, ccr: u8) -> bool {
    let c = ccr & CCR_C != 0;
    let v = ccr & CCR_V != 0;
    let z = ccr & CCR_Z != 0;
    let n = ccr & CCR_N != 0;
    match cc & 15 {
        0 => true,
        1 => false,
        2 => !(c || z),
        3 => c || z,
        4 => !c,
        5 => c,
        6 => !z,
        7 => z,
        8 => !v,
        9 => v,
        10 => !n,
        11 => n,
        12 => n == v,
        13 => n != v,
        14 => !z && n == v,
        _ => z || n != v,
    }
}

/// The absolute address of `@aa:8` in advanced mode (H'FFFF00 + aa).
#[inline(always)]
const fn abs8(a: u8) -> u32 {
    0x00ff_ff00 | a as u32
}

/// The absolute address of `@aa:16`: sign-extended to 24 bits.
#[inline(always)]
const fn abs16(a: u16) -> u32 {
    (a as i16 as i32 as u32) & ADDRESS_MASK
}

/// Whether a memory operand takes its address from ER7: an access to the stack.
#[inline(always)]
pub(super) const fn stack_operand(op: Operand) -> bool {
    match op {
        Operand::Ind(r)
        | Operand::PostInc(r)
        | Operand::PreDec(r)
        | Operand::Disp16(r, _)
        | Operand::Disp24(r, _) => r & 7 == 7,
        _ => false,
    }
}

/// Whether `instr` writes ER7 (or a part of it) as a register: it moves SP without accessing
/// the stack (a frame allocated or released, SP loaded). The fast path leaves these to the
/// reference executor, which checks SP after them.
pub(super) const fn writes_sp(instr: Instr) -> bool {
    let r = match instr {
        Instr::Mov {
            dst: Operand::Reg(r),
            ..
        }
        | Instr::Alu { rd: r, .. }
        | Instr::Inc { rd: r, .. }
        | Instr::Dec { rd: r, .. }
        | Instr::Adds { rd: r, .. }
        | Instr::Subs { rd: r, .. }
        | Instr::Unary { rd: r, .. }
        | Instr::MulDiv { rd: r, .. } => r,
        _ => return false,
    };
    r & 7 == 7
}

impl Cpu {
    /// The lowest address a stack operand ([`stack_operand`]) of `bytes` bytes will access,
    /// computed without its side effects (`@-ER7` decrements first).
    #[inline(always)]
    pub(super) fn stack_target(&self, op: Operand, bytes: u32) -> u32 {
        let sp = self.er[7];
        match op {
            Operand::PreDec(_) => sp.wrapping_sub(bytes),
            Operand::Disp16(_, d) => sp.wrapping_add(d as i16 as i32 as u32),
            Operand::Disp24(_, d) => sp.wrapping_add(d),
            _ => sp,
        }
    }

    // ----- registers -------------------------------------------------------------------

    #[inline(always)]
    pub(super) fn r8(&self, r: u8) -> u8 {
        let e = self.er[usize::from(r & 7)];
        if r & 8 == 0 { (e >> 8) as u8 } else { e as u8 }
    }

    #[inline(always)]
    pub(super) fn set_r8(&mut self, r: u8, v: u8) {
        let e = &mut self.er[usize::from(r & 7)];
        if r & 8 == 0 {
            *e = (*e & !0xff00) | (u32::from(v) << 8);
        } else {
            *e = (*e & !0xff) | u32::from(v);
        }
    }

    #[inline(always)]
    pub(super) fn r16(&self, r: u8) -> u16 {
        let e = self.er[usize::from(r & 7)];
        if r & 8 == 0 {
            e as u16
        } else {
            (e >> 16) as u16
        }
    }

    #[inline(always)]
    pub(super) fn set_r16(&mut self, r: u8, v: u16) {
        let e = &mut self.er[usize::from(r & 7)];
        if r & 8 == 0 {
            *e = (*e & 0xffff_0000) | u32::from(v);
        } else {
            *e = (*e & 0xffff) | (u32::from(v) << 16);
        }
    }

    #[inline(always)]
    pub(super) fn reg(&self, size: Size, r: u8) -> u32 {
        match size {
            Size::Byte => u32::from(self.r8(r)),
            Size::Word => u32::from(self.r16(r)),
            Size::Long => self.er[usize::from(r & 7)],
        }
    }

    #[inline(always)]
    pub(super) fn set_reg(&mut self, size: Size, r: u8, v: u32) {
        match size {
            Size::Byte => self.set_r8(r, v as u8),
            Size::Word => self.set_r16(r, v as u16),
            Size::Long => self.er[usize::from(r & 7)] = v,
        }
    }

    // ----- flags -----------------------------------------------------------------------

    #[inline(always)]
    pub(super) fn set_flags(&mut self, affected: u8, values: u8) {
        self.ccr = (self.ccr & !affected) | (values & affected);
    }

    /// N and Z of `v`, V cleared (MOV, logic operations, NOT, EXTS/EXTU).
    #[inline(always)]
    pub(super) fn flags_nzv0(&mut self, s: Sz, v: u32) {
        let mut f = 0;
        if v & s.msb != 0 {
            f |= CCR_N;
        }
        if v & s.mask == 0 {
            f |= CCR_Z;
        }
        self.set_flags(NZV, f);
    }

    /// a + b + c with H, N, Z, V, C.
    #[inline(always)]
    pub(super) fn add_flags(&mut self, s: Sz, a: u32, b: u32, c: u32, keep_z: bool) -> u32 {
        let wide = u64::from(a) + u64::from(b) + u64::from(c);
        let r = (wide as u32) & s.mask;
        let mut f = 0;
        if (a & s.half) + (b & s.half) + c > s.half {
            f |= CCR_H;
        }
        if r & s.msb != 0 {
            f |= CCR_N;
        }
        if r == 0 {
            f |= CCR_Z;
        }
        if (a ^ r) & (b ^ r) & s.msb != 0 {
            f |= CCR_V;
        }
        if wide > u64::from(s.mask) {
            f |= CCR_C;
        }
        if keep_z {
            // ADDX: Z is cleared by a non-zero result and otherwise keeps its value.
            f = (f & !CCR_Z) | (self.ccr & CCR_Z & if r == 0 { 0xff } else { 0 });
        }
        self.set_flags(HNZVC, f);
        r
    }

    /// a - b - c with H, N, Z, V, C (borrows).
    #[inline(always)]
    pub(super) fn sub_flags(&mut self, s: Sz, a: u32, b: u32, c: u32, keep_z: bool) -> u32 {
        let r = a.wrapping_sub(b).wrapping_sub(c) & s.mask;
        let mut f = 0;
        if (b & s.half) + c > (a & s.half) {
            f |= CCR_H;
        }
        if r & s.msb != 0 {
            f |= CCR_N;
        }
        if r == 0 {
            f |= CCR_Z;
        }
        if (a ^ b) & (a ^ r) & s.msb != 0 {
            f |= CCR_V;
        }
        if u64::from(b) + u64::from(c) > u64::from(a) {
            f |= CCR_C;
        }
        if keep_z {
            f = (f & !CCR_Z) | (self.ccr & CCR_Z & if r == 0 { 0xff } else { 0 });
        }
        self.set_flags(HNZVC, f);
        r
    }

    #[inline(always)]
    pub(super) fn carry(&self) -> u32 {
        u32::from(self.ccr & CCR_C)
    }

    // ----- memory ----------------------------------------------------------------------

    #[inline(always)]
    pub(super) fn read_mem<B: Bus>(bus: &mut B, size: Size, a: u32) -> u32 {
        match size {
            Size::Byte => u32::from(bus.read8(a)),
            Size::Word => u32::from(bus.read16(a)),
            Size::Long => {
                let hi = u32::from(bus.read16(a));
                let lo = u32::from(bus.read16(a.wrapping_add(2)));
                (hi << 16) | lo
            }
        }
    }

    #[inline(always)]
    pub(super) fn write_mem<B: Bus>(bus: &mut B, size: Size, a: u32, v: u32) {
        match size {
            Size::Byte => bus.write8(a, v as u8),
            Size::Word => bus.write16(a, v as u16),
            Size::Long => {
                bus.write16(a, (v >> 16) as u16);
                bus.write16(a.wrapping_add(2), v as u16);
            }
        }
    }

    /// The effective address of a memory operand, with the side effects of `@ERn+`/`@-ERn`
    /// (register update and N = 2 internal states).
    #[inline(always)]
    pub(super) fn ea<B: Bus>(&mut self, bus: &mut B, op: Operand, bytes: u32) -> u32 {
        match op {
            Operand::Ind(r) => self.er[usize::from(r & 7)],
            Operand::PostInc(r) => {
                let e = &mut self.er[usize::from(r & 7)];
                let a = *e;
                *e = a.wrapping_add(bytes);
                bus.internal(t::N_POSTINC_PREDEC);
                a
            }
            Operand::PreDec(r) => {
                let e = &mut self.er[usize::from(r & 7)];
                *e = e.wrapping_sub(bytes);
                bus.internal(t::N_POSTINC_PREDEC);
                *e
            }
            Operand::Disp16(r, d) => {
                self.er[usize::from(r & 7)].wrapping_add(d as i16 as i32 as u32) & ADDRESS_MASK
            }
            Operand::Disp24(r, d) => self.er[usize::from(r & 7)].wrapping_add(d) & ADDRESS_MASK,
            Operand::Abs8(a) => abs8(a),
            Operand::Abs16(a) => abs16(a),
            Operand::Abs24(a) => a & ADDRESS_MASK,
            // Not memory operands; the decoder never passes them here.
            Operand::Reg(_) | Operand::Imm(_) => 0,
        }
    }

    /// Reads a source operand of any kind.
    #[inline(always)]
    pub(super) fn read_operand<B: Bus>(&mut self, bus: &mut B, size: Size, op: Operand) -> u32 {
        match op {
            Operand::Reg(r) => self.reg(size, r),
            Operand::Imm(v) => v & sz(size).mask,
            mem => {
                let a = self.ea(bus, mem, sz(size).bytes);
                Self::read_mem(bus, size, a)
            }
        }
    }

    /// Writes a destination operand of any kind (immediates are ignored).
    #[inline(always)]
    pub(super) fn write_operand<B: Bus>(&mut self, bus: &mut B, size: Size, op: Operand, v: u32) {
        match op {
            Operand::Reg(r) => self.set_reg(size, r, v),
            Operand::Imm(_) => {}
            mem => {
                let a = self.ea(bus, mem, sz(size).bytes);
                Self::write_mem(bus, size, a, v);
            }
        }
    }

    // ----- control flow helpers --------------------------------------------------------

    #[inline(always)]
    pub(super) fn cond(&self, cc: u8) -> bool {
        cond_holds(cc, self.ccr)
    }

    #[inline(always)]
    pub(super) fn jump_to(&mut self, target: u32) {
        self.pc = target & ADDRESS_MASK & !1;
    }

    // ----- the executor ----------------------------------------------------------------

    /// Executes a decoded instruction whose words have been fetched (and charged); PC still
    /// points at it.
    #[inline]
    pub(super) fn execute<B: Bus>(&mut self, bus: &mut B, d: Decoded) -> Result<Event, CpuError> {
        let pc = self.pc;
        let next = pc.wrapping_add(d.len_bytes()) & ADDRESS_MASK;
        self.pc = next;
        self.instructions += 1;
        self.last_copy = d;
        self.last_copy_pc = pc;
        self.last_index = LAST_IN_COPY;
        self.exec_instr(bus, d, pc, next)
    }

    /// The operation of instruction `d` at `pc` once PC holds `next` (the address after it)
    /// and the instruction is counted: shared by the reference path and, for the forms it has
    /// no handler of its own for, the fast path.
    #[inline]
    pub(super) fn exec_instr<B: Bus>(
        &mut self,
        bus: &mut B,
        d: Decoded,
        pc: u32,
        next: u32,
    ) -> Result<Event, CpuError> {
        // The stack guard also watches SP itself: an instruction that moves it out of the room
        // (a frame allocated below the data) is where a frame-pointer function overflows.
        let (sp0, ccr0) = (self.er[7], self.ccr);
        let event = self.exec_operation(bus, d, pc, next)?;
        if self.er[7] != sp0 && !self.stack_bounds.inside(self.er[7], 0) {
            let sp = self.er[7];
            // Under a stopping guard the instruction is undone: SP and the flags as before.
            self.er[7] = sp0;
            let ccr = self.ccr;
            self.ccr = ccr0;
            self.stack_ok(sp, 0, StackAccess::MoveSp, pc)?;
            self.er[7] = sp;
            self.ccr = ccr;
        }
        Ok(event)
    }

    /// [`Cpu::exec_instr`] without the check of SP after it.
    #[inline]
    fn exec_operation<B: Bus>(
        &mut self,
        bus: &mut B,
        d: Decoded,
        pc: u32,
        next: u32,
    ) -> Result<Event, CpuError> {
        match d.instr {
            Instr::Nop => {}
            Instr::Mov { size, src, dst } => self.mov(bus, size, src, dst, pc)?,
            Instr::Alu { op, size, src, rd } => {
                let b = match src {
                    Operand::Reg(r) => self.reg(size, r),
                    Operand::Imm(v) => v & sz(size).mask,
                    _ => 0,
                };
                self.alu(op, size, b, rd);
            }
            Instr::Inc { size, amount, rd } => self.inc_dec(true, size, amount, rd),
            Instr::Dec { size, amount, rd } => self.inc_dec(false, size, amount, rd),
            Instr::Adds { amount, rd } => {
                let e = &mut self.er[usize::from(rd & 7)];
                *e = e.wrapping_add(u32::from(amount));
            }
            Instr::Subs { amount, rd } => {
                let e = &mut self.er[usize::from(rd & 7)];
                *e = e.wrapping_sub(u32::from(amount));
            }
            Instr::Unary { op, size, rd } => self.unary(op, size, rd),
            Instr::Daa(r) => self.daa(r),
            Instr::Das(r) => self.das(r),
            Instr::MulDiv { op, size, rs, rd } => self.muldiv(bus, op, size, rs, rd),
            Instr::Bit { op, bit, target } => self.bit_guarded(bus, op, bit, target, pc)?,
            Instr::Bcc { cond, disp, long } => self.bcc(bus, cond, disp, long, next),
            Instr::Bsr { disp, long } => self.bsr(bus, disp, long, pc, next)?,
            Instr::Jmp(tgt) => self.jmp_jsr(bus, tgt, false, pc, next)?,
            Instr::Jsr(tgt) => self.jmp_jsr(bus, tgt, true, pc, next)?,
            Instr::Rts => self.rts(bus, pc)?,
            Instr::Rte => self.rte(bus, pc)?,
            Instr::Trapa(n) => self.trapa(bus, n, pc, next)?,
            Instr::Sleep => return Ok(self.sleep(bus)),
            Instr::Eepmov { word } => self.eepmov(bus, word),
            Instr::Ldc(src) => self.ldc(bus, src, pc)?,
            Instr::Stc(dst) => self.stc(bus, dst, pc)?,
            Instr::Andc(v) => {
                self.ccr &= v;
                self.irq_inhibit = true;
            }
            Instr::Orc(v) => {
                self.ccr |= v;
                self.irq_inhibit = true;
            }
            Instr::Xorc(v) => {
                self.ccr ^= v;
                self.irq_inhibit = true;
            }
            Instr::Movfpe { .. } | Instr::Movtpe { .. } => return Err(self.e_clock_move(d, pc)),
        }
        Ok(Event::Executed)
    }

    /// `mov.size src,dst`, its stack operands checked by the stack guard first.
    #[inline(always)]
    fn mov<B: Bus>(
        &mut self,
        bus: &mut B,
        size: Size,
        src: Operand,
        dst: Operand,
        pc: u32,
    ) -> Result<(), CpuError> {
        let bytes = sz(size).bytes;
        if stack_operand(src) {
            self.stack_ok(self.stack_target(src, bytes), bytes, StackAccess::Read, pc)?;
        }
        if stack_operand(dst) {
            self.stack_ok(self.stack_target(dst, bytes), bytes, StackAccess::Write, pc)?;
        }
        let v = self.read_operand(bus, size, src);
        self.write_operand(bus, size, dst, v);
        self.flags_nzv0(sz(size), v);
        Ok(())
    }

    /// A bit instruction, its access through `@ER7` checked by the stack guard first (a write
    /// for the ones that change the byte).
    #[inline(always)]
    fn bit_guarded<B: Bus>(
        &mut self,
        bus: &mut B,
        op: BitOp,
        bit: BitNum,
        target: BitTarget,
        pc: u32,
    ) -> Result<(), CpuError> {
        if matches!(target, BitTarget::Ind(r) if r & 7 == 7) {
            let writes = matches!(
                op,
                BitOp::Bset | BitOp::Bclr | BitOp::Bnot | BitOp::Bst | BitOp::Bist
            );
            let access = if writes {
                StackAccess::Write
            } else {
                StackAccess::Read
            };
            self.stack_ok(self.er[7], 1, access, pc)?;
        }
        self.bit(bus, op, bit, target);
        Ok(())
    }

    /// `bcc d:8` / `bcc d:16` with the instruction after it at `next`: d:16 has N = 2, d:8
    /// the prefetch at the target if taken, after the instruction if not.
    #[inline(always)]
    fn bcc<B: Bus>(&mut self, bus: &mut B, cond: u8, disp: i16, long: bool, next: u32) {
        let taken = self.cond(cond);
        let target = next.wrapping_add(disp as i32 as u32) & ADDRESS_MASK;
        if long {
            bus.internal(t::N_BRANCH_D16);
        } else {
            Self::fetch_charge(bus, if taken { target } else { next });
        }
        if taken {
            self.jump_to(target);
        }
    }

    /// `bsr d:8` / `bsr d:16`: push the return address `next`, then as an always-taken Bcc.
    #[inline(always)]
    fn bsr<B: Bus>(
        &mut self,
        bus: &mut B,
        disp: i16,
        long: bool,
        pc: u32,
        next: u32,
    ) -> Result<(), CpuError> {
        let target = next.wrapping_add(disp as i32 as u32) & ADDRESS_MASK;
        self.push32(bus, next, StackAccess::Call, pc)?;
        if long {
            bus.internal(t::N_BRANCH_D16);
        } else {
            Self::fetch_charge(bus, target);
        }
        self.jump_to(target);
        Ok(())
    }

    /// `jmp` (`call` false) or `jsr` (`call` true, pushing `next`) to `tgt`.
    #[inline(always)]
    fn jmp_jsr<B: Bus>(
        &mut self,
        bus: &mut B,
        tgt: JumpTarget,
        call: bool,
        pc: u32,
        next: u32,
    ) -> Result<(), CpuError> {
        let target = match tgt {
            JumpTarget::Reg(r) => self.er[usize::from(r & 7)] & ADDRESS_MASK,
            JumpTarget::Abs24(a) => a & ADDRESS_MASK,
            JumpTarget::MemInd(a) => {
                let a = u32::from(a);
                let hi = u32::from(bus.read16(a));
                let lo = u32::from(bus.read16(a + 2));
                ((hi << 16) | lo) & ADDRESS_MASK
            }
        };
        if call {
            self.push32(bus, next, StackAccess::Call, pc)?;
        }
        match tgt {
            // JMP/JSR @ERn: I = 2 (the target prefetch).
            JumpTarget::Reg(_) => Self::fetch_charge(bus, target),
            // @aa:24: I = 2 (both words of the instruction), N = 2.
            JumpTarget::Abs24(_) => bus.internal(t::N_JUMP_ABS24),
            // @@aa:8: I = 2 (the target prefetch); JMP has N = 2, JSR none.
            JumpTarget::MemInd(_) => {
                Self::fetch_charge(bus, target);
                if !call {
                    bus.internal(t::N_JMP_MEM_INDIRECT);
                }
            }
        }
        self.jump_to(target);
        Ok(())
    }

    /// `rts`: pop the return address, prefetch there, N = 2.
    #[inline(always)]
    fn rts<B: Bus>(&mut self, bus: &mut B, pc: u32) -> Result<(), CpuError> {
        let ret = self.pop32(bus, StackAccess::Return, pc)? & ADDRESS_MASK;
        Self::fetch_charge(bus, ret);
        bus.internal(t::N_RETURN);
        self.jump_to(ret);
        Ok(())
    }

    /// `rte`: pop CCR and the return address, prefetch there, N = 2.
    #[inline(always)]
    fn rte<B: Bus>(&mut self, bus: &mut B, pc: u32) -> Result<(), CpuError> {
        let frame = self.pop32(bus, StackAccess::ReturnFromException, pc)?;
        self.ccr = (frame >> 24) as u8;
        let ret = frame & ADDRESS_MASK;
        Self::fetch_charge(bus, ret);
        bus.internal(t::N_RETURN);
        self.jump_to(ret);
        Ok(())
    }

    /// `trapa #n`: exception handling through vector TRAPA0 + n, returning to `next`.
    #[inline(always)]
    fn trapa<B: Bus>(&mut self, bus: &mut B, n: u8, pc: u32, next: u32) -> Result<(), CpuError> {
        let v = super::VECTOR_TRAPA0 + (n & 3);
        self.enter_exception(bus, v, next, StackAccess::Trap, pc)?;
        let target = self.pc;
        Self::fetch_charge(bus, target);
        bus.internal(t::N_TRAPA);
        Ok(())
    }

    /// `sleep`: the CPU sleeps until an interrupt, or halts for good when interrupts are
    /// masked and no NMI is pending (nothing could wake it).
    #[inline(always)]
    fn sleep<B: Bus>(&mut self, bus: &mut B) -> Event {
        // NMI and a reset request would wake it even so.
        let wakes = matches!(
            bus.pending_irq(),
            Some(super::VECTOR_NMI | crate::bus::RESET_REQUEST)
        );
        if self.ccr & CCR_I != 0 && !wakes {
            self.state = RunState::Halted;
            return Event::Halted;
        }
        self.state = RunState::Sleeping;
        bus.cpu_signal(crate::bus::CpuSignal::Sleep);
        Event::Executed
    }

    /// `eepmov.b` / `eepmov.w` (`word`): copies R4L / R4 bytes from @ER5+ to @ER6+.
    #[inline(always)]
    fn eepmov<B: Bus>(&mut self, bus: &mut B, word: bool) {
        let count = if word {
            u32::from(self.r16(4))
        } else {
            u32::from(self.r8(12))
        };
        let src_area = Area::of(self.er[5]);
        let dst_area = Area::of(self.er[6]);
        for _ in 0..count {
            let b = bus.read8(self.er[5]);
            bus.write8(self.er[6], b);
            self.er[5] = self.er[5].wrapping_add(1);
            self.er[6] = self.er[6].wrapping_add(1);
        }
        if word {
            self.set_r16(4, 0);
        } else {
            self.set_r8(12, 0);
        }
        debug_assert_eq!(t::EEPMOV_EXTRA_BYTE_ACCESSES, 2);
        bus.internal(src_area.byte_states() + dst_area.byte_states());
    }

    /// `ldc src,ccr` (a memory source is a word access whose upper byte is CCR).
    #[inline(always)]
    fn ldc<B: Bus>(&mut self, bus: &mut B, src: Operand, pc: u32) -> Result<(), CpuError> {
        if stack_operand(src) {
            self.stack_ok(self.stack_target(src, 2), 2, StackAccess::Read, pc)?;
        }
        self.ccr = match src {
            Operand::Imm(v) => v as u8,
            Operand::Reg(r) => self.r8(r),
            mem => {
                let a = self.ea(bus, mem, 2);
                (bus.read16(a) >> 8) as u8
            }
        };
        self.irq_inhibit = true;
        Ok(())
    }

    /// `stc ccr,dst` (a memory destination is a word write of CCR in both bytes).
    #[inline(always)]
    fn stc<B: Bus>(&mut self, bus: &mut B, dst: Operand, pc: u32) -> Result<(), CpuError> {
        match dst {
            _ if stack_operand(dst) => {
                self.stack_ok(self.stack_target(dst, 2), 2, StackAccess::Write, pc)?;
                let a = self.ea(bus, dst, 2);
                bus.write16(a, u16::from_be_bytes([self.ccr, self.ccr]));
            }
            Operand::Reg(r) => self.set_r8(r, self.ccr),
            Operand::Imm(_) => {}
            mem => {
                let a = self.ea(bus, mem, 2);
                bus.write16(a, u16::from_be_bytes([self.ccr, self.ccr]));
            }
        }
        Ok(())
    }

    /// MOVFPE/MOVTPE `d` at `pc` is not run: the instruction is undone (PC at it, not
    /// counted) and this is the error.
    #[cold]
    fn e_clock_move(&mut self, d: Decoded, pc: u32) -> CpuError {
        self.pc = pc;
        self.instructions -= 1;
        CpuError::Unsupported {
            pc,
            text: super::disasm::format_instr(d, pc),
            why: "MOVFPE/MOVTPE synchronise with the E clock, which the H8/3052F does not have",
        }
    }

    /// `op.size b,Rd` for the two-operand ALU operations, `b` the source value (masked).
    #[inline(always)]
    pub(super) fn alu(&mut self, op: AluOp, size: Size, b: u32, rd: u8) {
        let s = sz(size);
        let a = self.reg(size, rd);
        match op {
            AluOp::Add => {
                let r = self.add_flags(s, a, b, 0, false);
                self.set_reg(size, rd, r);
            }
            AluOp::Addx => {
                let c = self.carry();
                let r = self.add_flags(s, a, b, c, true);
                self.set_reg(size, rd, r);
            }
            AluOp::Sub => {
                let r = self.sub_flags(s, a, b, 0, false);
                self.set_reg(size, rd, r);
            }
            AluOp::Subx => {
                let c = self.carry();
                let r = self.sub_flags(s, a, b, c, true);
                self.set_reg(size, rd, r);
            }
            AluOp::Cmp => {
                self.sub_flags(s, a, b, 0, false);
            }
            AluOp::And | AluOp::Or | AluOp::Xor => {
                let r = match op {
                    AluOp::And => a & b,
                    AluOp::Or => a | b,
                    _ => a ^ b,
                };
                self.set_reg(size, rd, r);
                self.flags_nzv0(s, r);
            }
        }
    }

    /// INC (`inc` true) or DEC by `amount` (1 or 2).
    #[inline(always)]
    pub(super) fn inc_dec(&mut self, inc: bool, size: Size, amount: u8, rd: u8) {
        let s = sz(size);
        let a = self.reg(size, rd);
        let b = u32::from(amount);
        let r = if inc {
            a.wrapping_add(b) & s.mask
        } else {
            a.wrapping_sub(b) & s.mask
        };
        let overflow = if inc {
            (a ^ r) & (b ^ r) & s.msb != 0
        } else {
            (a ^ b) & (a ^ r) & s.msb != 0
        };
        let mut f = 0;
        if r & s.msb != 0 {
            f |= CCR_N;
        }
        if r == 0 {
            f |= CCR_Z;
        }
        if overflow {
            f |= CCR_V;
        }
        self.set_flags(NZV, f);
        self.set_reg(size, rd, r);
    }

    #[inline(always)]
    pub(super) fn unary(&mut self, op: UnaryOp, size: Size, rd: u8) {
        let s = sz(size);
        let a = self.reg(size, rd);
        let c_in = self.carry();
        let msb_set = a & s.msb != 0;
        let lsb_set = a & 1 != 0;
        // (result, new carry or None to leave C, V)
        let (r, c, v) = match op {
            UnaryOp::Neg => {
                let r = self.sub_flags(s, 0, a, 0, false);
                self.set_reg(size, rd, r);
                return;
            }
            UnaryOp::Not => {
                let r = !a & s.mask;
                self.set_reg(size, rd, r);
                self.flags_nzv0(s, r);
                return;
            }
            UnaryOp::Exts | UnaryOp::Extu => {
                let r = match (size, op) {
                    (Size::Word, UnaryOp::Exts) => u32::from(a as u8 as i8 as i16 as u16),
                    (Size::Word, _) => a & 0xff,
                    (_, UnaryOp::Exts) => a as u16 as i16 as i32 as u32,
                    _ => a & 0xffff,
                };
                self.set_reg(size, rd, r);
                self.flags_nzv0(s, r);
                return;
            }
            UnaryOp::Shal => {
                let r = (a << 1) & s.mask;
                // V: the sign changed (bit msb and bit msb-1 differed before the shift).
                let v = msb_set != (a & (s.msb >> 1) != 0);
                (r, msb_set, v)
            }
            UnaryOp::Shll => ((a << 1) & s.mask, msb_set, false),
            UnaryOp::Shar => ((a >> 1) | (a & s.msb), lsb_set, false),
            UnaryOp::Shlr => (a >> 1, lsb_set, false),
            UnaryOp::Rotxl => (((a << 1) | c_in) & s.mask, msb_set, false),
            UnaryOp::Rotxr => ((a >> 1) | if c_in != 0 { s.msb } else { 0 }, lsb_set, false),
            UnaryOp::Rotl => (((a << 1) & s.mask) | u32::from(msb_set), msb_set, false),
            UnaryOp::Rotr => ((a >> 1) | if lsb_set { s.msb } else { 0 }, lsb_set, false),
        };
        let mut f = 0;
        if r & s.msb != 0 {
            f |= CCR_N;
        }
        if r == 0 {
            f |= CCR_Z;
        }
        if v {
            f |= CCR_V;
        }
        if c {
            f |= CCR_C;
        }
        self.set_flags(NZVC, f);
        self.set_reg(size, rd, r);
    }

    /// DAA: decimal adjust after an addition of two BCD bytes (programming manual, DAA page).
    fn daa(&mut self, rd: u8) {
        let a = self.r8(rd);
        let c = self.ccr & CCR_C != 0;
        let h = self.ccr & CCR_H != 0;
        let mut adj = 0u8;
        let mut carry = c;
        if h || (a & 0x0f) > 9 {
            adj |= 0x06;
        }
        if c || a > 0x99 {
            adj |= 0x60;
            carry = true;
        }
        let r = a.wrapping_add(adj);
        let mut f = 0;
        if r & 0x80 != 0 {
            f |= CCR_N;
        }
        if r == 0 {
            f |= CCR_Z;
        }
        if carry {
            f |= CCR_C;
        }
        self.set_flags(CCR_N | CCR_Z | CCR_C, f);
        self.set_r8(rd, r);
    }

    /// DAS: decimal adjust after a subtraction of two BCD bytes (programming manual, DAS page).
    fn das(&mut self, rd: u8) {
        let a = self.r8(rd);
        let c = self.ccr & CCR_C != 0;
        let h = self.ccr & CCR_H != 0;
        let mut adj = 0u8;
        if h {
            adj |= 0x06;
        }
        if c {
            adj |= 0x60;
        }
        let r = a.wrapping_sub(adj);
        let mut f = 0;
        if r & 0x80 != 0 {
            f |= CCR_N;
        }
        if r == 0 {
            f |= CCR_Z;
        }
        self.set_flags(CCR_N | CCR_Z, f);
        self.set_r8(rd, r);
    }

    pub(super) fn muldiv<B: Bus>(&mut self, bus: &mut B, op: MulDivOp, size: Size, rs: u8, rd: u8) {
        bus.internal(if size == Size::Byte {
            t::N_MULDIV_BYTE
        } else {
            t::N_MULDIV_WORD
        });
        match (op, size) {
            (MulDivOp::Mulxu, Size::Byte) => {
                let p = u16::from(self.r16(rd) as u8) * u16::from(self.r8(rs));
                self.set_r16(rd, p);
            }
            (MulDivOp::Mulxu, _) => {
                let p = u32::from(self.er[usize::from(rd & 7)] as u16) * u32::from(self.r16(rs));
                self.er[usize::from(rd & 7)] = p;
            }
            (MulDivOp::Mulxs, Size::Byte) => {
                let p = i16::from(self.r16(rd) as u8 as i8) * i16::from(self.r8(rs) as i8);
                self.set_r16(rd, p as u16);
                self.nz_flags(p < 0, p == 0);
            }
            (MulDivOp::Mulxs, _) => {
                let p = i32::from(self.er[usize::from(rd & 7)] as u16 as i16)
                    * i32::from(self.r16(rs) as i16);
                self.er[usize::from(rd & 7)] = p as u32;
                self.nz_flags(p < 0, p == 0);
            }
            (MulDivOp::Divxu, Size::Byte) => {
                let divisor = self.r8(rs);
                self.nz_flags(divisor & 0x80 != 0, divisor == 0);
                if divisor != 0 {
                    let dividend = self.r16(rd);
                    let q = dividend / u16::from(divisor);
                    let r = dividend % u16::from(divisor);
                    self.set_r16(rd, (r << 8) | (q & 0xff));
                }
            }
            (MulDivOp::Divxu, _) => {
                let divisor = self.r16(rs);
                self.nz_flags(divisor & 0x8000 != 0, divisor == 0);
                if divisor != 0 {
                    let dividend = self.er[usize::from(rd & 7)];
                    let q = dividend / u32::from(divisor);
                    let r = dividend % u32::from(divisor);
                    self.er[usize::from(rd & 7)] = (r << 16) | (q & 0xffff);
                }
            }
            (MulDivOp::Divxs, Size::Byte) => {
                let divisor = i32::from(self.r8(rs) as i8);
                let dividend = i32::from(self.r16(rd) as i16);
                // N: the signs differ (even when the quotient is 0); Z: the divisor is 0.
                self.nz_flags((dividend < 0) != (divisor < 0), divisor == 0);
                if divisor != 0 {
                    let q = dividend / divisor;
                    let r = dividend % divisor;
                    self.set_r16(rd, ((r as u16 & 0xff) << 8) | (q as u16 & 0xff));
                }
            }
            (MulDivOp::Divxs, _) => {
                let divisor = i64::from(self.r16(rs) as i16);
                let dividend = i64::from(self.er[usize::from(rd & 7)] as i32);
                self.nz_flags((dividend < 0) != (divisor < 0), divisor == 0);
                if divisor != 0 {
                    let q = dividend / divisor;
                    let r = dividend % divisor;
                    self.er[usize::from(rd & 7)] =
                        ((r as u32 & 0xffff) << 16) | (q as u32 & 0xffff);
                }
            }
        }
    }

    #[inline(always)]
    pub(super) fn nz_flags(&mut self, n: bool, z: bool) {
        let f = if n { CCR_N } else { 0 } | if z { CCR_Z } else { 0 };
        self.set_flags(CCR_N | CCR_Z, f);
    }

    pub(super) fn bit<B: Bus>(&mut self, bus: &mut B, op: BitOp, bit: BitNum, target: BitTarget) {
        let n = match bit {
            BitNum::Imm(n) => n & 7,
            BitNum::Reg(r) => self.r8(r) & 7,
        };
        let mask = 1u8 << n;
        let addr = match target {
            BitTarget::Reg(_) => 0,
            BitTarget::Ind(r) => self.er[usize::from(r & 7)] & ADDRESS_MASK,
            BitTarget::Abs8(a) => abs8(a),
        };
        let byte = match target {
            BitTarget::Reg(r) => self.r8(r),
            _ => bus.read8(addr),
        };
        let bit_set = byte & mask != 0;
        let c = self.ccr & CCR_C != 0;
        let set_c = |cpu: &mut Cpu, v: bool| cpu.set_flags(CCR_C, if v { CCR_C } else { 0 });
        let new = match op {
            BitOp::Bset => Some(byte | mask),
            BitOp::Bclr => Some(byte & !mask),
            BitOp::Bnot => Some(byte ^ mask),
            BitOp::Bst => Some(if c { byte | mask } else { byte & !mask }),
            BitOp::Bist => Some(if c { byte & !mask } else { byte | mask }),
            BitOp::Btst => {
                self.set_flags(CCR_Z, if bit_set { 0 } else { CCR_Z });
                None
            }
            BitOp::Bld => {
                set_c(self, bit_set);
                None
            }
            BitOp::Bild => {
                set_c(self, !bit_set);
                None
            }
            BitOp::Band => {
                set_c(self, c && bit_set);
                None
            }
            BitOp::Biand => {
                set_c(self, c && !bit_set);
                None
            }
            BitOp::Bor => {
                set_c(self, c || bit_set);
                None
            }
            BitOp::Bior => {
                set_c(self, c || !bit_set);
                None
            }
            BitOp::Bxor => {
                set_c(self, c != bit_set);
                None
            }
            BitOp::Bixor => {
                set_c(self, c == bit_set);
                None
            }
        };
        if let Some(v) = new {
            match target {
                BitTarget::Reg(r) => self.set_r8(r, v),
                _ => bus.write8(addr, v),
            }
        }
    }
}
