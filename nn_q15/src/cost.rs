//! H8/300H cost accounting (SPEC §2.7).
//!
//! The learner reports every primitive it performs ([`Op`]) to a [`Meter`]. [`NoopMeter`]
//! records nothing and compiles to nothing; [`H8Meter`] charges each primitive the H8/300H states
//! of the instruction sequence an H8 implementation of the learner needs for it.
//!
//! # Where the numbers come from
//! [`Insn`] lists the instruction forms that implementation uses, each with its states and byte
//! length for on-chip operands from SPEC §4.2 (Table A-1 of the H8/300H hardware manuals: every
//! fetch and data access to on-chip ROM/RAM takes 2 states over a 16-bit bus). [`OP_TABLE`] gives,
//! for every [`Op`], its instruction sequence; the states of an op are the sum over its sequence,
//! computed at compile time. The sequences are those of the H8 learner routine sketched below, the
//! register allocation being the one a hand-written routine would use (ER2 accumulator, ER4/ER5/ER6
//! pointers, E3 inner counter, R3L outer counter):
//!
//! ```text
//! forward:  MOV.L #W,ER4 ; MOV.L #Y,ER6 ; MOV.B #M,R3L
//! row:      MOV.L #X,ER5 ; MOV.W #N,E3 ; SUB.L ER2,ER2
//! mac:      MOV.W @ER4+,R0 ; MOV.B @ER5+,R1L ; EXTS.W R1 ; MULXS.W R1,ER0 ; ADD.L ER0,ER2
//!           DEC.W #1,E3 ; BNE mac
//!           MOV.L ER2,@ER6 ; ADDS #4,ER6 ; DEC.B R3L ; BNE row
//! argmax:   MOV.L @ER6+,ER0 ; CMP.L ER1,ER0 ; BLE next ; [MOV.L ER0,ER1 ; MOV.B R2H,R2L]
//! scale:    CMP.L #H'400000,ER1 ; BGE normalise          (max ≥ 1.0 in Q22?)
//! plain:    MOV.L @ER6+,ER0 ; SHAR.L ER0 ×7 ; saturate ; MOV.W R0,@ER5 ; ADDS #2,ER5
//! normalise: SHAR.L ER1 ; INC.B R3H ; CMP.L #H'8000,ER1 ; BGE …   (s times: m' = m >> s)
//!           per output: MOV.L @ER6+,ER0 ; s × (SHAR.L ER0 ; DEC.B ; BNE) ; CMP.L ER4,ER0 ; BLE low
//!           CMP.L ER1,ER0 ; BGE high ; MOV.W R0,E0 ; SUB.W R0,R0 ; SHAR.L ER0 ; DIVXS.W R1,ER0
//! update:   |E| ≤ T? ; σ·η ; per input: MOV.B @ER5+,R1L ; EXTS.W R1 ; MOV.W R2,R0 ;
//!           MULXS.W R1,ER0 ; BMI neg ; ADD.L #64,ER0 ; SHAR.L ×7 ; … ; MOV.W R0,@ER6 ; ADDS #2,ER6
//!           per weight: MOV.W @ER5+,R1 ; MOV.W @ER4,R0 ; ADD.W R1,R0 (SUB.W) ; BVC ok ;
//!           [BPL lo ; MOV.W #H'7FFF,R0 ; BRA ok | lo: MOV.W #H'8000,R0] ; ok: MOV.W R0,@ER4 ; ADDS #2,ER4
//! ```
//!
//! Conditional branches cost the same taken or not on the H8/300H (Bcc d:8 is 4 states either
//! way), so a path's cost depends only on which instructions it executes; the learner counts the
//! data-dependent paths (saturations, a new maximum, the normalising shift count) and charges them.

/// One H8/300H instruction form with on-chip operands, as SPEC §4.2 lists them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Insn {
    /// Register-to-register ALU op (ADD/SUB/CMP/AND/OR/XOR/NEG/NOT/INC/DEC/EXTS/EXTU/MOV Rs,Rd),
    /// ADDS/SUBS, a 1-bit shift, or a byte op with an 8-bit immediate (one instruction word).
    /// SPEC §4.2: 2 states.
    Reg,
    /// MOV.W #xx:16 or ALU.W #xx:16 (two words). SPEC §4.2: 4 states.
    ImmW,
    /// MOV.L #xx:32 or ALU.L #xx:32 (three words). SPEC §4.2: 6 states.
    ImmL,
    /// MOV.B/MOV.W to or from @ERs. SPEC §4.2: 4 states.
    MovBwInd,
    /// MOV.B/MOV.W with @ERs+ or @−ERd. SPEC §4.2: 6 states.
    MovBwPostInc,
    /// MOV.B/MOV.W with @aa:16 or @(d:16,ERs). SPEC §4.2: 6 states.
    MovBwAbs16,
    /// MOV.L to or from @ERs. SPEC §4.2: 8 states.
    MovLInd,
    /// MOV.L with @ERs+ or @−ERd. SPEC §4.2: 10 states.
    MovLPostInc,
    /// MOV.L with @aa:16 or @(d:16,ERs). SPEC §4.2: 10 states.
    MovLAbs16,
    /// PUSH.L / POP.L (MOV.L with @−ER7 / @ER7+). SPEC §4.2: 10 states.
    PushPopL,
    /// Bcc d:8 (BRA included), taken or not. SPEC §4.2: 4 states.
    Bcc8,
    /// JSR @aa:24. SPEC §4.2: 10 states.
    JsrAbs24,
    /// RTS. SPEC §4.2: 10 states.
    Rts,
    /// MULXS.W Rs,ERd (16 × 16 → 32 signed). SPEC §4.2: 24 states.
    MulxsW,
    /// DIVXS.W Rs,ERd (32 / 16 → 16 quotient, 16 remainder, signed). SPEC §4.2: 24 states.
    DivxsW,
}

impl Insn {
    /// States of the instruction with on-chip operands (SPEC §4.2).
    #[must_use]
    pub const fn states(self) -> u32 {
        match self {
            Insn::Reg => 2,
            Insn::ImmW => 4,
            Insn::ImmL => 6,
            Insn::MovBwInd => 4,
            Insn::MovBwPostInc => 6,
            Insn::MovBwAbs16 => 6,
            Insn::MovLInd => 8,
            Insn::MovLPostInc => 10,
            Insn::MovLAbs16 => 10,
            Insn::PushPopL => 10,
            Insn::Bcc8 => 4,
            Insn::JsrAbs24 => 10,
            Insn::Rts => 10,
            Insn::MulxsW => 24,
            Insn::DivxsW => 24,
        }
    }

    /// Length of the instruction in bytes (H8/300H instruction formats: one word for register
    /// ops, @ERs, @ERs+ and Bcc d:8; MOV.L memory forms carry a H'0100 prefix word; MULXS/DIVXS
    /// carry a H'01C0/H'01D0 prefix word).
    #[must_use]
    pub const fn bytes(self) -> u32 {
        match self {
            Insn::Reg | Insn::MovBwInd | Insn::MovBwPostInc | Insn::Bcc8 | Insn::Rts => 2,
            Insn::ImmW | Insn::MovBwAbs16 | Insn::MovLInd | Insn::MovLPostInc => 4,
            Insn::PushPopL | Insn::JsrAbs24 | Insn::MulxsW | Insn::DivxsW => 4,
            Insn::ImmL | Insn::MovLAbs16 => 6,
        }
    }

    /// An example mnemonic of the form, for reports.
    #[must_use]
    pub const fn example(self) -> &'static str {
        match self {
            Insn::Reg => "ADD.L ERs,ERd",
            Insn::ImmW => "MOV.W #xx:16,Rd",
            Insn::ImmL => "MOV.L #xx:32,ERd",
            Insn::MovBwInd => "MOV.W @ERs,Rd",
            Insn::MovBwPostInc => "MOV.W @ERs+,Rd",
            Insn::MovBwAbs16 => "MOV.W @aa:16,Rd",
            Insn::MovLInd => "MOV.L ERs,@ERd",
            Insn::MovLPostInc => "MOV.L @ERs+,ERd",
            Insn::MovLAbs16 => "MOV.L @aa:16,ERd",
            Insn::PushPopL => "PUSH.L ERn",
            Insn::Bcc8 => "Bcc d:8",
            Insn::JsrAbs24 => "JSR @aa:24",
            Insn::Rts => "RTS",
            Insn::MulxsW => "MULXS.W Rs,ERd",
            Insn::DivxsW => "DIVXS.W Rs,ERd",
        }
    }
}

/// The learner's primitives: what it reports to a [`Meter`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Op {
    /// Load a 32-bit pointer register with an immediate address.
    PtrInit,
    /// Set an 8-bit counter or index register from an immediate.
    LoopInitB,
    /// Set a 16-bit loop counter from an immediate.
    LoopInitW,
    /// Clear a 32-bit accumulator.
    AccClear,
    /// Multiply-accumulate one Q15 weight and one Q7 input into the i32 sum.
    Mac,
    /// One iteration's loop overhead: decrement the counter, branch back.
    LoopIter,
    /// Store a 32-bit sum through a pointer and advance the pointer.
    StoreL,
    /// Load a 32-bit sum with post-increment.
    LoadL,
    /// Compare two 32-bit registers and branch.
    CmpBranch,
    /// Take a new maximum: copy the value and its index.
    NewMax,
    /// Advance an 8-bit index register.
    IndexInc,
    /// Compare a 32-bit register with an immediate and branch.
    CmpImmBranch,
    /// Store an 8-bit variable to RAM.
    StoreVarB,
    /// Arithmetic shift right of a 32-bit register by one place.
    Shr1,
    /// Saturation test of an i32 to the i16 range: two compares with immediates and branches.
    Sat16,
    /// The constant load of a saturation that clamps.
    SatClamp,
    /// Store a 16-bit value through a pointer and advance the pointer.
    StoreW,
    /// One step of the search for the normalising shift s (m' = m >> s < 2^15).
    NormShiftStep,
    /// Keep m' and −m' in registers for the bound tests.
    NormSetup,
    /// One place of a variable arithmetic shift right done in a loop.
    VarShiftStep,
    /// Shift a 16-bit y' left 15 places into the 32-bit dividend.
    Shl15,
    /// 32/16 signed division.
    Div,
    /// An unconditional or conditional branch on its own (BRA to a join point, or a sign test).
    Branch,
    /// Load a 16-bit clamp constant.
    ClampW,
    /// Load a 16-bit variable from RAM.
    LoadW,
    /// Store a 16-bit variable to RAM.
    StoreVarW,
    /// One register-to-register instruction (copy, subtract, negate, immediate byte load).
    RegOp,
    /// Copy a 16-bit value and branch on its sign (|E|; NEG.W is charged as RegOp when taken).
    AbsTest,
    /// Compare two 16-bit registers and branch.
    CmpBranchW,
    /// Compute and store one σ·Δ_i = round(σ·η·x_i / 2^7). Both sign paths take the same states: BRA (4) on the positive path against two NEG.L (2 + 2) on the negative one.
    DeltaCompute,
    /// Per-row set-up of the weight update: reload the Δ pointer and counter, test whether the row is the winner's, advance the row index.
    UpdateRow,
    /// Apply one Δ to one weight: load Δ and w, add (winner) or subtract (others), test overflow, store, advance.
    WeightApply,
    /// A weight change that overflows upward: clamp to H'7FFF.
    WeightClampHi,
    /// A weight change that overflows downward: clamp to H'8000.
    WeightClampLo,
    /// Test a byte flag in RAM and branch.
    FlagTest,
    /// Load one proximity byte and add it into D.
    SumIn,
    /// Move one 4-byte proximity block one slot deeper in the input vector.
    HistoryShift,
    /// Load one proximity byte and store p − 128 as a Q7 input (XOR with H'80).
    ProximityIn,
    /// Load one Q15 output and store its high byte (O >> 8) as a Q7 input.
    OutputIn,
    /// Convert E to the Q7 evaluation input: three 1-bit shifts, two bound tests, store.
    EvalIn,
    /// Store the bias input +127.
    BiasIn,
    /// Call and return of a routine that saves and restores ER4–ER6.
    CallFrame,
}

impl Op {
    /// Number of primitives.
    pub const COUNT: usize = Op::CallFrame as usize + 1;

    /// Every primitive, in declaration order.
    pub const ALL: [Op; Op::COUNT] = [
        Op::PtrInit,
        Op::LoopInitB,
        Op::LoopInitW,
        Op::AccClear,
        Op::Mac,
        Op::LoopIter,
        Op::StoreL,
        Op::LoadL,
        Op::CmpBranch,
        Op::NewMax,
        Op::IndexInc,
        Op::CmpImmBranch,
        Op::StoreVarB,
        Op::Shr1,
        Op::Sat16,
        Op::SatClamp,
        Op::StoreW,
        Op::NormShiftStep,
        Op::NormSetup,
        Op::VarShiftStep,
        Op::Shl15,
        Op::Div,
        Op::Branch,
        Op::ClampW,
        Op::LoadW,
        Op::StoreVarW,
        Op::RegOp,
        Op::AbsTest,
        Op::CmpBranchW,
        Op::DeltaCompute,
        Op::UpdateRow,
        Op::WeightApply,
        Op::WeightClampHi,
        Op::WeightClampLo,
        Op::FlagTest,
        Op::SumIn,
        Op::HistoryShift,
        Op::ProximityIn,
        Op::OutputIn,
        Op::EvalIn,
        Op::BiasIn,
        Op::CallFrame,
    ];

    /// The table entry of this primitive.
    #[must_use]
    pub const fn spec(self) -> &'static OpSpec {
        &OP_TABLE[self as usize]
    }

    /// H8/300H states of one occurrence of this primitive.
    #[must_use]
    pub const fn states(self) -> u32 {
        OP_STATES[self as usize]
    }
}

/// One entry of the cost table: a primitive, the H8/300H instruction sequence that does it, and
/// that sequence written out.
#[derive(Clone, Copy, Debug)]
pub struct OpSpec {
    /// The primitive.
    pub op: Op,
    /// Its instruction sequence (states and lengths from SPEC §4.2).
    pub insns: &'static [Insn],
    /// The sequence as assembly text (`[clamp]` marks code charged separately when it runs).
    pub asm: &'static str,
}

impl OpSpec {
    /// Sum of the states of the sequence.
    #[must_use]
    pub const fn states(&self) -> u32 {
        let mut total = 0;
        let mut i = 0;
        while i < self.insns.len() {
            total += self.insns[i].states();
            i += 1;
        }
        total
    }

    /// Sum of the byte lengths of the sequence (its ROM size when it occurs once in the code).
    #[must_use]
    pub const fn bytes(&self) -> u32 {
        let mut total = 0;
        let mut i = 0;
        while i < self.insns.len() {
            total += self.insns[i].bytes();
            i += 1;
        }
        total
    }
}

use Insn::*;

/// The cost table: for each [`Op`] (in declaration order) its H8/300H instruction sequence.
pub const OP_TABLE: [OpSpec; Op::COUNT] = [
    OpSpec {
        op: Op::PtrInit,
        insns: &[ImmL],
        asm: "MOV.L #addr,ER5",
    },
    OpSpec {
        op: Op::LoopInitB,
        insns: &[Reg],
        asm: "MOV.B #n,R3L",
    },
    OpSpec {
        op: Op::LoopInitW,
        insns: &[ImmW],
        asm: "MOV.W #n,E3",
    },
    OpSpec {
        op: Op::AccClear,
        insns: &[Reg],
        asm: "SUB.L ER2,ER2",
    },
    OpSpec {
        op: Op::Mac,
        insns: &[MovBwPostInc, MovBwPostInc, Reg, MulxsW, Reg],
        asm: "MOV.W @ER4+,R0 ; MOV.B @ER5+,R1L ; EXTS.W R1 ; MULXS.W R1,ER0 ; ADD.L ER0,ER2",
    },
    OpSpec {
        op: Op::LoopIter,
        insns: &[Reg, Bcc8],
        asm: "DEC.W #1,E3 ; BNE loop",
    },
    OpSpec {
        op: Op::StoreL,
        insns: &[MovLInd, Reg],
        asm: "MOV.L ER2,@ER6 ; ADDS #4,ER6",
    },
    OpSpec {
        op: Op::LoadL,
        insns: &[MovLPostInc],
        asm: "MOV.L @ER6+,ER0",
    },
    OpSpec {
        op: Op::CmpBranch,
        insns: &[Reg, Bcc8],
        asm: "CMP.L ER1,ER0 ; BLE next",
    },
    OpSpec {
        op: Op::NewMax,
        insns: &[Reg, Reg],
        asm: "MOV.L ER0,ER1 ; MOV.B R2H,R2L",
    },
    OpSpec {
        op: Op::IndexInc,
        insns: &[Reg],
        asm: "INC.B R2H",
    },
    OpSpec {
        op: Op::CmpImmBranch,
        insns: &[ImmL, Bcc8],
        asm: "CMP.L #H'400000,ER1 ; BGE normalise",
    },
    OpSpec {
        op: Op::StoreVarB,
        insns: &[MovBwAbs16],
        asm: "MOV.B R2L,@var:16",
    },
    OpSpec {
        op: Op::Shr1,
        insns: &[Reg],
        asm: "SHAR.L ER0",
    },
    OpSpec {
        op: Op::Sat16,
        insns: &[ImmL, Bcc8, ImmL, Bcc8],
        asm: "CMP.L #H'7FFF,ER0 ; BLE 1f ; [clamp] ; 1: CMP.L #-H'8000,ER0 ; BGE 2f ; [clamp] ; 2:",
    },
    OpSpec {
        op: Op::SatClamp,
        insns: &[ImmL],
        asm: "MOV.L #H'7FFF,ER0 (or #-H'8000)",
    },
    OpSpec {
        op: Op::StoreW,
        insns: &[MovBwInd, Reg],
        asm: "MOV.W R0,@ER5 ; ADDS #2,ER5",
    },
    OpSpec {
        op: Op::NormShiftStep,
        insns: &[Reg, Reg, ImmL, Bcc8],
        asm: "SHAR.L ER1 ; INC.B R3H ; CMP.L #H'8000,ER1 ; BGE 1b",
    },
    OpSpec {
        op: Op::NormSetup,
        insns: &[Reg, Reg],
        asm: "MOV.L ER1,ER4 ; NEG.L ER4",
    },
    OpSpec {
        op: Op::VarShiftStep,
        insns: &[Reg, Reg, Bcc8],
        asm: "SHAR.L ER0 ; DEC.B R2L ; BNE 1b",
    },
    OpSpec {
        op: Op::Shl15,
        insns: &[Reg, Reg, Reg],
        asm: "MOV.W R0,E0 ; SUB.W R0,R0 ; SHAR.L ER0",
    },
    OpSpec {
        op: Op::Div,
        insns: &[DivxsW],
        asm: "DIVXS.W R1,ER0",
    },
    OpSpec {
        op: Op::Branch,
        insns: &[Bcc8],
        asm: "BRA store",
    },
    OpSpec {
        op: Op::ClampW,
        insns: &[ImmW],
        asm: "MOV.W #H'7FFF,R0",
    },
    OpSpec {
        op: Op::LoadW,
        insns: &[MovBwAbs16],
        asm: "MOV.W @var:16,R0",
    },
    OpSpec {
        op: Op::StoreVarW,
        insns: &[MovBwAbs16],
        asm: "MOV.W R0,@var:16",
    },
    OpSpec {
        op: Op::RegOp,
        insns: &[Reg],
        asm: "SUB.W R1,R2",
    },
    OpSpec {
        op: Op::AbsTest,
        insns: &[Reg, Bcc8],
        asm: "MOV.W R0,R1 ; BPL 1f",
    },
    OpSpec {
        op: Op::CmpBranchW,
        insns: &[Reg, Bcc8],
        asm: "CMP.W R2,R1 ; BLE done",
    },
    OpSpec {
        op: Op::DeltaCompute,
        insns: &[
            MovBwPostInc,
            Reg,
            Reg,
            MulxsW,
            Bcc8,
            ImmL,
            Reg,
            Reg,
            Reg,
            Reg,
            Reg,
            Reg,
            Reg,
            Bcc8,
            MovBwInd,
            Reg,
        ],
        asm: "MOV.B @ER5+,R1L ; EXTS.W R1 ; MOV.W R2,R0 ; MULXS.W R1,ER0 ; BMI 1f ; ADD.L #64,ER0 ; SHAR.L ER0 ×7 ; BRA 2f ; 1: NEG.L ER0 ; ADD.L #64,ER0 ; SHLR.L ER0 ×7 ; NEG.L ER0 ; 2: MOV.W R0,@ER6 ; ADDS #2,ER6",
    },
    OpSpec {
        op: Op::UpdateRow,
        insns: &[ImmL, ImmW, MovBwAbs16, Reg, Bcc8, Reg, Reg, Bcc8],
        asm: "MOV.L #DELTA,ER5 ; MOV.W #N,E3 ; MOV.B @WIN:16,R3H ; CMP.B R3H,R3L ; BNE other ; … ; INC.B R3L ; CMP.B #M,R3L ; BNE row",
    },
    OpSpec {
        op: Op::WeightApply,
        insns: &[MovBwPostInc, MovBwInd, Reg, Bcc8, MovBwInd, Reg],
        asm: "MOV.W @ER5+,R1 ; MOV.W @ER4,R0 ; ADD.W R1,R0 ; BVC 1f ; [clamp] ; 1: MOV.W R0,@ER4 ; ADDS #2,ER4",
    },
    OpSpec {
        op: Op::WeightClampHi,
        insns: &[Bcc8, ImmW, Bcc8],
        asm: "BPL lo ; MOV.W #H'7FFF,R0 ; BRA 1b",
    },
    OpSpec {
        op: Op::WeightClampLo,
        insns: &[Bcc8, ImmW],
        asm: "BPL lo ; lo: MOV.W #H'8000,R0",
    },
    OpSpec {
        op: Op::FlagTest,
        insns: &[MovBwAbs16, Bcc8],
        asm: "MOV.B @FLAG:16,R0L ; BEQ first",
    },
    OpSpec {
        op: Op::SumIn,
        insns: &[MovBwPostInc, Reg, Reg],
        asm: "MOV.B @ER4+,R0L ; EXTU.W R0 ; ADD.W R0,R2",
    },
    OpSpec {
        op: Op::HistoryShift,
        insns: &[MovLPostInc, MovLPostInc, Reg, Bcc8],
        asm: "MOV.L @-ER5,ER0 ; MOV.L ER0,@-ER6 ; DEC.B R3L ; BNE 1b",
    },
    OpSpec {
        op: Op::ProximityIn,
        insns: &[MovBwPostInc, Reg, MovBwInd, Reg],
        asm: "MOV.B @ER4+,R0L ; XOR.B #H'80,R0L ; MOV.B R0L,@ER6 ; ADDS #1,ER6",
    },
    OpSpec {
        op: Op::OutputIn,
        insns: &[MovBwPostInc, MovBwInd, Reg],
        asm: "MOV.W @ER4+,R0 ; MOV.B R0H,@ER6 ; ADDS #1,ER6",
    },
    OpSpec {
        op: Op::EvalIn,
        insns: &[Reg, Reg, Reg, ImmW, Bcc8, ImmW, Bcc8, MovBwInd, Reg],
        asm: "SHAR.W R0 ×3 ; CMP.W #127,R0 ; BLE 1f ; [clamp] ; 1: CMP.W #-128,R0 ; BGE 2f ; [clamp] ; 2: MOV.B R0L,@ER6 ; ADDS #1,ER6",
    },
    OpSpec {
        op: Op::BiasIn,
        insns: &[Reg, MovBwInd],
        asm: "MOV.B #127,R0L ; MOV.B R0L,@ER6",
    },
    OpSpec {
        op: Op::CallFrame,
        insns: &[
            JsrAbs24, PushPopL, PushPopL, PushPopL, PushPopL, PushPopL, PushPopL, Rts,
        ],
        asm: "JSR @routine:24 ; PUSH.L ER4 ; PUSH.L ER5 ; PUSH.L ER6 ; … ; POP.L ER6 ; POP.L ER5 ; POP.L ER4 ; RTS",
    },
];

const fn op_states_table() -> [u32; Op::COUNT] {
    let mut out = [0; Op::COUNT];
    let mut i = 0;
    while i < Op::COUNT {
        // The table is in declaration order; this is checked at compile time below.
        assert!(OP_TABLE[i].op as usize == i);
        out[i] = OP_TABLE[i].states();
        i += 1;
    }
    out
}

/// States of every [`Op`], indexed by `op as usize`, computed from [`OP_TABLE`].
pub const OP_STATES: [u32; Op::COUNT] = op_states_table();

/// A routine of the H8 learner as code: how many times each primitive's instruction sequence
/// appears in its text (not how often it runs), plus instructions on paths no primitive covers.
/// Its size is the ROM estimate of the routine.
#[derive(Clone, Copy, Debug)]
pub struct Routine {
    /// The routine's name.
    pub name: &'static str,
    /// (primitive, number of places its sequence appears in the code).
    pub code: &'static [(Op, u32)],
    /// Instructions of alternative paths that no primitive's sequence lists.
    pub extra: &'static [Insn],
}

impl Routine {
    /// Estimated code size in bytes.
    #[must_use]
    pub const fn bytes(&self) -> u32 {
        let mut total = 0;
        let mut i = 0;
        while i < self.code.len() {
            total += self.code[i].0.spec().bytes() * self.code[i].1;
            i += 1;
        }
        let mut k = 0;
        while k < self.extra.len() {
            total += self.extra[k].bytes();
            k += 1;
        }
        total
    }
}

/// The learner's three routines as code, following the routine sketched in the module docs
/// (the callee half of [`Op::CallFrame`], pushes, pops and RTS, is counted with the callee).
pub const LEARNER_ROUTINES: [Routine; 3] = [
    Routine {
        name: "learner input (D, E, input vector)",
        code: &[
            (Op::CallFrame, 1),
            (Op::PtrInit, 7),
            (Op::AccClear, 1),
            (Op::LoopInitB, 4),
            (Op::SumIn, 1),
            (Op::LoopIter, 3),
            (Op::FlagTest, 1),
            (Op::LoadW, 1),
            (Op::RegOp, 2),
            (Op::StoreVarW, 1),
            (Op::HistoryShift, 1),
            (Op::ProximityIn, 1),
            (Op::OutputIn, 1),
            (Op::EvalIn, 1),
            (Op::ClampW, 2),
            (Op::BiasIn, 1),
        ],
        extra: &[],
    },
    Routine {
        name: "learner update",
        code: &[
            (Op::CallFrame, 1),
            (Op::LoadW, 3),
            (Op::AbsTest, 1),
            (Op::RegOp, 2),
            (Op::CmpBranchW, 1),
            (Op::Branch, 2),
            (Op::PtrInit, 3),
            (Op::LoopInitW, 1),
            (Op::DeltaCompute, 1),
            (Op::LoopIter, 3),
            (Op::LoopInitB, 1),
            (Op::UpdateRow, 1),
            (Op::WeightApply, 2),
            (Op::WeightClampHi, 2),
            (Op::WeightClampLo, 2),
        ],
        // The negative-product path of the Δ computation: NEG.L, ADD.L #64, SHLR.L ×7, NEG.L.
        extra: &[
            Insn::Reg,
            Insn::ImmL,
            Insn::Reg,
            Insn::Reg,
            Insn::Reg,
            Insn::Reg,
            Insn::Reg,
            Insn::Reg,
            Insn::Reg,
            Insn::Reg,
        ],
    },
    Routine {
        name: "learner forward pass",
        code: &[
            (Op::CallFrame, 1),
            (Op::PtrInit, 8),
            (Op::LoopInitB, 7),
            (Op::LoopInitW, 1),
            (Op::AccClear, 1),
            (Op::Mac, 1),
            (Op::LoopIter, 5),
            (Op::StoreL, 1),
            (Op::LoadL, 4),
            (Op::CmpBranch, 3),
            (Op::NewMax, 1),
            (Op::IndexInc, 1),
            (Op::StoreVarB, 1),
            (Op::CmpImmBranch, 1),
            (Op::Shr1, 7),
            (Op::Sat16, 1),
            (Op::SatClamp, 2),
            (Op::StoreW, 2),
            (Op::NormShiftStep, 1),
            (Op::NormSetup, 1),
            (Op::RegOp, 1),
            (Op::VarShiftStep, 1),
            (Op::Shl15, 1),
            (Op::Div, 1),
            (Op::Branch, 2),
            (Op::ClampW, 2),
        ],
        extra: &[],
    },
];

/// The phases of a learner step, in the order the firmware runs them (SPEC §3.5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Phase {
    /// D(t), E(t−1) and the input vector for step t.
    Input,
    /// The update with E(t−1) on x(t−1) (SPEC §2.4).
    Update,
    /// The forward pass on x(t) (SPEC §2.3).
    Forward,
}

impl Phase {
    /// Number of phases.
    pub const COUNT: usize = 3;
    /// Every phase in order.
    pub const ALL: [Phase; Phase::COUNT] = [Phase::Input, Phase::Update, Phase::Forward];

    /// A short lower-case name.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Phase::Input => "input",
            Phase::Update => "update",
            Phase::Forward => "forward",
        }
    }
}

/// What the learner reports its work to.
pub trait Meter {
    /// Whether the meter records anything. The learner skips the bookkeeping a meter would need
    /// (counting saturations and the like) when this is `false`, so an inactive meter costs
    /// nothing at all.
    const ACTIVE: bool;
    /// The learner enters `phase`; later charges belong to it.
    fn enter(&mut self, phase: Phase);
    /// The learner performed `op` `count` times.
    fn charge(&mut self, op: Op, count: u32);
}

/// A meter that records nothing: every call compiles to nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoopMeter;

impl Meter for NoopMeter {
    const ACTIVE: bool = false;
    #[inline(always)]
    fn enter(&mut self, _phase: Phase) {}
    #[inline(always)]
    fn charge(&mut self, _op: Op, _count: u32) {}
}

/// A meter that charges H8/300H states per phase from [`OP_STATES`] and counts every primitive.
///
/// It keeps one count per (phase, primitive) pair, so a charge is a single addition; states are
/// the counts weighted by [`OP_STATES`] when asked for.
#[derive(Clone, Debug)]
pub struct H8Meter {
    phase: Phase,
    counts: [[u64; Op::COUNT]; Phase::COUNT],
}

impl Default for H8Meter {
    fn default() -> Self {
        Self::new()
    }
}

impl H8Meter {
    /// A meter with nothing charged yet.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            phase: Phase::Input,
            counts: [[0; Op::COUNT]; Phase::COUNT],
        }
    }

    /// States charged to `phase` so far.
    #[must_use]
    pub fn states(&self, phase: Phase) -> u64 {
        self.counts[phase as usize]
            .iter()
            .zip(OP_STATES)
            .map(|(&n, s)| n * u64::from(s))
            .sum()
    }

    /// States charged to every phase so far.
    #[must_use]
    pub fn total_states(&self) -> u64 {
        Phase::ALL.iter().map(|&p| self.states(p)).sum()
    }

    /// How many times `op` was charged so far, over all phases.
    #[must_use]
    pub fn count(&self, op: Op) -> u64 {
        self.counts.iter().map(|per_op| per_op[op as usize]).sum()
    }

    /// How many times `op` was charged in `phase` so far.
    #[must_use]
    pub const fn count_in(&self, phase: Phase, op: Op) -> u64 {
        self.counts[phase as usize][op as usize]
    }

    /// The states per phase so far, in [`Phase::ALL`] order.
    #[must_use]
    pub fn phase_states(&self) -> [u64; Phase::COUNT] {
        Phase::ALL.map(|p| self.states(p))
    }

    /// Forgets everything charged so far.
    pub fn reset(&mut self) {
        *self = Self::new();
    }
}

impl Meter for H8Meter {
    const ACTIVE: bool = true;
    #[inline(always)]
    fn enter(&mut self, phase: Phase) {
        self.phase = phase;
    }
    #[inline(always)]
    fn charge(&mut self, op: Op, count: u32) {
        self.counts[self.phase as usize][op as usize] += u64::from(count);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_in_declaration_order_and_complete() {
        for (i, op) in Op::ALL.iter().enumerate() {
            assert_eq!(*op as usize, i);
            assert_eq!(OP_TABLE[i].op, *op);
            assert!(!OP_TABLE[i].insns.is_empty());
        }
    }

    #[test]
    fn the_spec_example_mac_is_two_loads_exts_mulxs_add() {
        // SPEC §2.7: "one multiply-accumulate: two post-increment loads, EXTS, MULXS.W, ADD.L";
        // SPEC §4.2: @ERs+ 6, EXTS 2, MULXS.W 24, ADD.L (register) 2.
        assert_eq!(Op::Mac.states(), 6 + 6 + 2 + 24 + 2);
        assert_eq!(Op::Div.states(), 24);
        assert_eq!(Op::LoopIter.states(), 2 + 4);
        assert_eq!(Op::CallFrame.states(), 10 + 6 * 10 + 10);
    }

    #[test]
    fn states_follow_the_fetch_rule_for_register_and_immediate_forms() {
        // With 2-state on-chip fetches, an instruction with no data access and no internal
        // states costs 2 states per instruction word.
        for insn in [Insn::Reg, Insn::ImmW, Insn::ImmL] {
            assert_eq!(insn.states(), insn.bytes(), "{insn:?}");
        }
        // A branch fetches its own word and then refills the prefetch queue at the target
        // (taken) or the next word (not taken): two fetches either way.
        assert_eq!(Insn::Bcc8.states(), 2 * Insn::Bcc8.bytes());
    }

    #[test]
    fn routine_sizes_add_up_from_the_sequences() {
        // The forward routine holds one multiply-accumulate sequence (12 bytes: two 2-byte
        // loads, EXTS, a 4-byte MULXS.W, ADD.L) among everything else.
        assert_eq!(Op::Mac.spec().bytes(), 2 + 2 + 2 + 4 + 2);
        for r in LEARNER_ROUTINES {
            assert!(
                r.bytes() > 100 && r.bytes() < 1000,
                "{}: {}",
                r.name,
                r.bytes()
            );
        }
    }

    #[test]
    fn h8_meter_charges_per_phase_and_noop_records_nothing() {
        let mut m = H8Meter::new();
        m.enter(Phase::Forward);
        m.charge(Op::Mac, 13);
        m.enter(Phase::Update);
        m.charge(Op::Div, 1);
        assert_eq!(m.states(Phase::Forward), 13 * 40);
        assert_eq!(m.states(Phase::Update), 24);
        assert_eq!(m.states(Phase::Input), 0);
        assert_eq!(m.total_states(), 13 * 40 + 24);
        assert_eq!(m.count(Op::Mac), 13);
        m.reset();
        assert_eq!(m.total_states(), 0);
    }
}
