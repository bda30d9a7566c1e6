//! H8/300H cost accounting (docs/design.md §2.7), re-derived from the robot firmware's compiled code.
//!
//! The learner reports what it executes to a [`Meter`] as basic blocks ([`Op`]) of the
//! firmware's learner routines (`firmware/learner.c`, compiled by `firmware/build.sh` with
//! Debian's GCC 3.4.6 for the H8/300H: `learner_step`, `learner_update`, `learner_forward`),
//! with how often each runs. [`NoopMeter`] records nothing and compiles to nothing;
//! [`H8Meter`] charges each block the H8/300H states of its instructions.
//!
//! # Where the numbers come from
//! [`OP_TABLE`] holds, for every block, its instructions as the firmware's listing
//! (`firmware/build.sh --listing DIR`, `robot.lst`) shows them, and their forms ([`Insn`]), each
//! with its states for on-chip operands from docs/design.md §4.2 and the H8/300H manuals' Table A-1
//! (2 states per fetch or data access to on-chip ROM and RAM; internal states as listed).
//! Conditional branches cost the same taken or not, so a path's cost is the sum of the blocks
//! it runs; the learner counts the data-dependent paths (a new maximum, saturations, the
//! normalising shift count, the sign of each Δ product) and charges them.
//!
//! The model follows the listing exactly: the emulator's calibration test runs the firmware's
//! routines on the H8/300H core over a grid of shapes and inputs and compares every phase with
//! this meter, so a change of either side shows at once.

/// One H8/300H instruction form with on-chip operands (docs/design.md §4.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Insn {
    /// Register-to-register ALU op (ADD/SUB/CMP/AND/OR/XOR/NEG/NOT/INC/DEC/EXTS/EXTU/MOV Rs,Rd),
    /// ADDS/SUBS, a 1-bit shift, or a byte op with an 8-bit immediate (one instruction word).
    /// docs/design.md §4.2: 2 states.
    Reg,
    /// MOV.W #xx:16 or ALU.W #xx:16 (two words). docs/design.md §4.2: 4 states.
    ImmW,
    /// MOV.L #xx:32 or ALU.L #xx:32 (three words). docs/design.md §4.2: 6 states.
    ImmL,
    /// MOV.B/MOV.W to or from @ERs. docs/design.md §4.2: 4 states.
    MovBwInd,
    /// MOV.B/MOV.W with @ERs+ or @−ERd. docs/design.md §4.2: 6 states.
    MovBwPostInc,
    /// MOV.B/MOV.W with @aa:16 or @(d:16,ERs). docs/design.md §4.2: 6 states.
    MovBwAbs16,
    /// MOV.B/MOV.W with @aa:24 (three words, one data access). docs/design.md §4.2: 8 states.
    MovBwAbs24,
    /// MOV.B/MOV.W with @(d:24,ERs) (four words, one data access). docs/design.md §4.2: 10 states.
    MovBwDisp24,
    /// MOV.L to or from @ERs. docs/design.md §4.2: 8 states.
    MovLInd,
    /// MOV.L with @ERs+ or @−ERd. docs/design.md §4.2: 10 states.
    MovLPostInc,
    /// MOV.L with @aa:16 or @(d:16,ERs). docs/design.md §4.2: 10 states.
    MovLAbs16,
    /// MOV.L with @aa:24 (four words, two data accesses): 4 · 2 + 2 · 2 = 12 states
    /// (manual Table A-1).
    MovLAbs24,
    /// PUSH.L / POP.L (MOV.L with @−ER7 / @ER7+). docs/design.md §4.2: 10 states.
    PushPopL,
    /// Bcc d:8 (BRA included), taken or not. docs/design.md §4.2: 4 states.
    Bcc8,
    /// Bcc d:16 (BRA included), taken or not. docs/design.md §4.2: 6 states.
    Bcc16,
    /// JSR @aa:24. docs/design.md §4.2: 10 states.
    JsrAbs24,
    /// RTS. docs/design.md §4.2: 10 states.
    Rts,
    /// MULXS.W Rs,ERd (16 × 16 → 32 signed). docs/design.md §4.2: 24 states.
    MulxsW,
    /// DIVXS.W Rs,ERd (32 / 16 → 16 quotient, 16 remainder, signed). docs/design.md §4.2: 24 states.
    DivxsW,
}

impl Insn {
    /// Every form, for tables and tests.
    pub const ALL: [Insn; 19] = [
        Insn::Reg,
        Insn::ImmW,
        Insn::ImmL,
        Insn::MovBwInd,
        Insn::MovBwPostInc,
        Insn::MovBwAbs16,
        Insn::MovBwAbs24,
        Insn::MovBwDisp24,
        Insn::MovLInd,
        Insn::MovLPostInc,
        Insn::MovLAbs16,
        Insn::MovLAbs24,
        Insn::PushPopL,
        Insn::Bcc8,
        Insn::Bcc16,
        Insn::JsrAbs24,
        Insn::Rts,
        Insn::MulxsW,
        Insn::DivxsW,
    ];

    /// States of the instruction with on-chip operands (docs/design.md §4.2).
    #[must_use]
    pub const fn states(self) -> u32 {
        match self {
            Insn::Reg => 2,
            Insn::ImmW => 4,
            Insn::ImmL => 6,
            Insn::MovBwInd => 4,
            Insn::MovBwPostInc => 6,
            Insn::MovBwAbs16 => 6,
            Insn::MovBwAbs24 => 8,
            Insn::MovBwDisp24 => 10,
            Insn::MovLInd => 8,
            Insn::MovLPostInc => 10,
            Insn::MovLAbs16 => 10,
            Insn::MovLAbs24 => 12,
            Insn::PushPopL => 10,
            Insn::Bcc8 => 4,
            Insn::Bcc16 => 6,
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
            Insn::ImmW | Insn::MovBwAbs16 | Insn::MovLInd | Insn::MovLPostInc | Insn::Bcc16 => 4,
            Insn::PushPopL | Insn::JsrAbs24 | Insn::MulxsW | Insn::DivxsW => 4,
            Insn::ImmL | Insn::MovLAbs16 | Insn::MovBwAbs24 => 6,
            Insn::MovLAbs24 | Insn::MovBwDisp24 => 8,
        }
    }

    /// An example of the form in objdump's syntax, with its encoding (for tests that run it
    /// on the core and for reports).
    #[must_use]
    pub const fn example(self) -> (&'static str, &'static [u8]) {
        match self {
            Insn::Reg => ("add.l er1,er2", &[0x0A, 0x92]),
            Insn::ImmW => ("mov.w #0x1234,r0", &[0x79, 0x00, 0x12, 0x34]),
            Insn::ImmL => ("add.l #0x40,er2", &[0x7A, 0x12, 0x00, 0x00, 0x00, 0x40]),
            Insn::MovBwInd => ("mov.w @er0,r2", &[0x69, 0x02]),
            Insn::MovBwPostInc => ("mov.w @er5+,r3", &[0x6D, 0x53]),
            Insn::MovBwAbs16 => ("mov.b @(0x1:16,er0),r2l", &[0x6E, 0x0A, 0x00, 0x01]),
            Insn::MovBwAbs24 => (
                "mov.b @0xffdf90:24,r2l",
                &[0x6A, 0x2A, 0x00, 0xFF, 0xDF, 0x90],
            ),
            Insn::MovBwDisp24 => (
                "mov.b @(0x10:24,er2),r2l",
                &[0x78, 0x20, 0x6A, 0x2A, 0x00, 0x00, 0x00, 0x10],
            ),
            Insn::MovLInd => ("mov.l er1,@er2", &[0x01, 0x00, 0x69, 0xA1]),
            Insn::MovLPostInc => ("mov.l @er5+,er3", &[0x01, 0x00, 0x6D, 0x53]),
            Insn::MovLAbs16 => (
                "mov.l @(0x20:16,er7),er2",
                &[0x01, 0x00, 0x6F, 0x72, 0x00, 0x20],
            ),
            Insn::MovLAbs24 => (
                "mov.l @0xffdf70:24,er6",
                &[0x01, 0x00, 0x6B, 0x26, 0x00, 0xFF, 0xDF, 0x70],
            ),
            Insn::PushPopL => ("mov.l er4,@-er7", &[0x01, 0x00, 0x6D, 0xF4]),
            Insn::Bcc8 => ("bne .+0", &[0x46, 0x00]),
            Insn::Bcc16 => ("bne .+0:16", &[0x58, 0x60, 0x00, 0x00]),
            Insn::JsrAbs24 => ("jsr @0x000000:24", &[0x5E, 0x00, 0x00, 0x00]),
            Insn::Rts => ("rts", &[0x54, 0x70]),
            Insn::MulxsW => ("mulxs.w r2,er3", &[0x01, 0xC0, 0x52, 0x23]),
            Insn::DivxsW => ("divxs.w r4,er2", &[0x01, 0xD0, 0x53, 0x42]),
        }
    }
}

/// A basic block of the firmware's learner routines: what the learner reports to a [`Meter`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Op {
    /// `learner_step` entry: frame, the three callee-saved registers, D = p0 + p1 + p2 + p3, E = 0.
    InEntry,
    /// Load x's address and test `net_started`.
    InStartedTest,
    /// E = D − D(t−1) and the call of `learner_update` (the JSR runs in the caller).
    InEval,
    /// Test the history depth.
    InHistoryTest,
    /// Pointers and count of the history move (4H bytes, from the end).
    InHistorySetup,
    /// Move one history byte one block deeper.
    InHistoryByte,
    /// The four readings p − 128 (XOR H'80) into x.
    InReadings,
    /// Where the past outputs go (4 + 4H), the outputs' address and count.
    InOutputsSetup,
    /// One past output's high byte (O >> 8) into x.
    InOutput,
    /// E >> 3 and its upper bound test.
    InEvalScale,
    /// E >> 3 above 127: clamp (never with |E| ≤ 1020, kept for completeness).
    InEvalHigh,
    /// E >> 3 lower bound test.
    InEvalLowTest,
    /// E >> 3 below −128: clamp.
    InEvalLow,
    /// Store sat_i8(E >> 3) and test the bias flag.
    InEvalStore,
    /// Store the bias input +127.
    InBias,
    /// The call of `learner_forward`.
    InForwardCall,
    /// D(t−1) = D, started = 1, the winner as the result, restore and return.
    InExit,
    /// `learner_update` entry: frame, registers, T and −T, the test E > T.
    UpdEntry,
    /// E ≤ T: the test E ≥ −T (the dead zone when it holds).
    UpdLowTest,
    /// σ·η: load η, test the sign of E.
    UpdSign,
    /// E < 0: negate η.
    UpdNeg,
    /// x and Δ pointers, N.
    UpdDeltaSetup,
    /// One Δ: σ·η · x_i (MULXS.W) and its sign test.
    DeltaHead,
    /// Product ≥ 0: (p + 64) >> 7 as SHLL.L and byte moves.
    DeltaPos,
    /// Product < 0: −((64 − p) >> 7).
    DeltaNeg,
    /// Store Δ_i, count down.
    DeltaTail,
    /// Weights, winner and M for the row loop.
    UpdRowsSetup,
    /// One row: Δ pointer, N, is it the winner's?
    UpdRowHead,
    /// One weight: w ± Δ (ADD.W for the winner, SUB.W for the others), BVC, store.
    UpdWeight,
    /// Overflow towards the top: H'7FFF (C tells the direction).
    UpdClampHi,
    /// Overflow towards the bottom: H'7FFF, then H'8000.
    UpdClampLo,
    /// The winner's row ends with a BRA to the row loop's tail.
    UpdWinRowExit,
    /// Next row.
    UpdRowTail,
    /// Restore and return.
    UpdExit,
    /// `learner_forward` entry: frame, registers, the arrays' addresses and the shape into the frame.
    FwdEntry,
    /// One output's sum: x pointer, N, clear the accumulator.
    FwdRowSetup,
    /// One multiply-accumulate: w (Q15) × x (Q7) into the Q22 sum.
    FwdMac,
    /// Store y_j, next output.
    FwdRowEnd,
    /// The maximum starts at y_0.
    FwdArgmaxInit,
    /// The argmax loop's test (M times: M − 1 candidates and the exit).
    FwdArgmaxTest,
    /// One candidate y_j against the maximum.
    FwdArgmaxLoad,
    /// A new maximum and its index.
    FwdNewMax,
    /// Store the winner, rewind y, M; is the maximum below 1.0 (2^22)?
    FwdScaleTest,
    /// Below 1.0, one output: load y_j, test y_j < −2^22.
    FwdPlainHead,
    /// y_j < −2^22: O_j = −32768.
    FwdPlainLow,
    /// O_j = bits 7..22 of y_j (SHLL.L and byte moves).
    FwdPlainOut,
    /// Next output.
    FwdPlainTail,
    /// Leave the plain branch.
    FwdPlainExit,
    /// At or above 1.0: the maximum >> 8 (byte moves), shift count 0.
    FwdNormSetup,
    /// The normalising loop's test m' ≥ 2^15 (s − 7 times).
    FwdNormTest,
    /// One more place: m' >>= 1.
    FwdNormShift,
    /// m' and its sign-extended copy.
    FwdNormReady,
    /// One output: load y_j, >> 8 (byte moves), the shift counter.
    FwdNormHead,
    /// The shift loop's test (s − 7 times per output).
    FwdNormStepTest,
    /// y'_j >>= 1.
    FwdNormStep,
    /// Is y'_j ≤ −m'?
    FwdNormLowTest,
    /// O_j = −32768.
    FwdNormLow,
    /// Is y'_j ≥ m'?
    FwdNormHighTest,
    /// O_j = 32767 ((m' << 15) / m' = 32768 does not fit).
    FwdNormHigh,
    /// O_j = (y'_j << 15) / m' with DIVXS.W.
    FwdNormDiv,
    /// Next output.
    FwdNormTail,
    /// Restore and return.
    FwdExit,
}

impl Op {
    /// Number of blocks.
    pub const COUNT: usize = Op::FwdExit as usize + 1;

    /// Every block, in declaration order.
    pub const ALL: [Op; Op::COUNT] = [
        Op::InEntry,
        Op::InStartedTest,
        Op::InEval,
        Op::InHistoryTest,
        Op::InHistorySetup,
        Op::InHistoryByte,
        Op::InReadings,
        Op::InOutputsSetup,
        Op::InOutput,
        Op::InEvalScale,
        Op::InEvalHigh,
        Op::InEvalLowTest,
        Op::InEvalLow,
        Op::InEvalStore,
        Op::InBias,
        Op::InForwardCall,
        Op::InExit,
        Op::UpdEntry,
        Op::UpdLowTest,
        Op::UpdSign,
        Op::UpdNeg,
        Op::UpdDeltaSetup,
        Op::DeltaHead,
        Op::DeltaPos,
        Op::DeltaNeg,
        Op::DeltaTail,
        Op::UpdRowsSetup,
        Op::UpdRowHead,
        Op::UpdWeight,
        Op::UpdClampHi,
        Op::UpdClampLo,
        Op::UpdWinRowExit,
        Op::UpdRowTail,
        Op::UpdExit,
        Op::FwdEntry,
        Op::FwdRowSetup,
        Op::FwdMac,
        Op::FwdRowEnd,
        Op::FwdArgmaxInit,
        Op::FwdArgmaxTest,
        Op::FwdArgmaxLoad,
        Op::FwdNewMax,
        Op::FwdScaleTest,
        Op::FwdPlainHead,
        Op::FwdPlainLow,
        Op::FwdPlainOut,
        Op::FwdPlainTail,
        Op::FwdPlainExit,
        Op::FwdNormSetup,
        Op::FwdNormTest,
        Op::FwdNormShift,
        Op::FwdNormReady,
        Op::FwdNormHead,
        Op::FwdNormStepTest,
        Op::FwdNormStep,
        Op::FwdNormLowTest,
        Op::FwdNormLow,
        Op::FwdNormHighTest,
        Op::FwdNormHigh,
        Op::FwdNormDiv,
        Op::FwdNormTail,
        Op::FwdExit,
    ];

    /// The table entry of this block.
    #[must_use]
    pub const fn spec(self) -> &'static OpSpec {
        &OP_TABLE[self as usize]
    }

    /// H8/300H states of one run of this block.
    #[must_use]
    pub const fn states(self) -> u32 {
        OP_STATES[self as usize]
    }
}

/// One entry of the cost table: a block, its instruction forms, and its instructions as the
/// firmware's listing shows them.
#[derive(Clone, Copy, Debug)]
pub struct OpSpec {
    /// The block.
    pub op: Op,
    /// Its instruction forms (states and lengths from docs/design.md §4.2).
    pub insns: &'static [Insn],
    /// Its instructions (objdump's syntax; `@name:24` for a variable's absolute address).
    pub asm: &'static str,
}

impl OpSpec {
    /// Sum of the states of the block's instructions.
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

    /// Sum of the byte lengths of the block's instructions.
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

/// The cost table: for each [`Op`] (in declaration order) its instructions.
pub const OP_TABLE: [OpSpec; Op::COUNT] = [
    OpSpec {
        op: Op::InEntry,
        insns: &[
            Reg, PushPopL, PushPopL, PushPopL, Reg, MovBwInd, Reg, MovBwAbs16, Reg, Reg,
            MovBwAbs16, Reg, Reg, MovBwAbs16, Reg, Reg, Reg, MovBwAbs16,
        ],
        asm: "subs #4,er7; mov.l er4-er6,@-er7; mov.l er0,er4; mov.b @er0,r5l; extu.w r5; 3 x (mov.b @(k:16,er0),r2l; extu.w r2; add.w r2,r5); sub.w r2,r2; mov.w r2,@(0xe:16,er7)",
    },
    OpSpec {
        op: Op::InStartedTest,
        insns: &[MovLAbs24, MovBwAbs24, Bcc8],
        asm: "mov.l @net_x:24,er6; mov.b @net_started:24,r2l; beq",
    },
    OpSpec {
        op: Op::InEval,
        insns: &[MovBwAbs24, Reg, Reg, MovBwAbs16, Reg, JsrAbs24],
        asm: "mov.w @net_d_prev:24,r2; mov.w r5,r3; sub.w r2,r3; mov.w r3,@(0xe:16,er7); mov.w r3,r0; jsr @learner_update",
    },
    OpSpec {
        op: Op::InHistoryTest,
        insns: &[MovBwAbs24, Bcc8],
        asm: "mov.b @net_history:24,r2l; beq",
    },
    OpSpec {
        op: Op::InHistorySetup,
        insns: &[Reg, Reg, Reg, Reg, Reg, Reg, Reg, Reg, Reg, Reg, Reg],
        asm: "extu.w r2; extu.l er2; shll.l er2; shll.l er2; mov.l er2,er3; add.l er6,er3; mov.l er3,er1; adds #2,er1; adds #1,er1; subs #1,er3; mov.w r2,r0",
    },
    OpSpec {
        op: Op::InHistoryByte,
        insns: &[MovBwInd, Reg, MovBwInd, Reg, Reg, Bcc8],
        asm: "mov.b @er3,r2l; subs #1,er3; mov.b r2l,@er1; subs #1,er1; dec.w #1,r0; bne",
    },
    OpSpec {
        op: Op::InReadings,
        insns: &[
            MovBwInd, Reg, MovBwInd, MovBwAbs16, Reg, MovBwAbs16, MovBwAbs16, Reg, MovBwAbs16,
            MovBwAbs16, Reg, MovBwAbs16,
        ],
        asm: "mov.b @er4,r2l; xor.b #0x80,r2l; mov.b r2l,@er6; 3 x (mov.b @(k:16,er4),r2l; xor.b #0x80,r2l; mov.b r2l,@(k:16,er6))",
    },
    OpSpec {
        op: Op::InOutputsSetup,
        insns: &[
            Reg, MovBwAbs24, Reg, Reg, Reg, MovLAbs24, Reg, Reg, Reg, MovBwAbs24,
        ],
        asm: "sub.l er2,er2; mov.b @net_history:24,r2l; shll.l er2; shll.l er2; add.b #4,r2l; mov.l @net_o:24,er0; sub.l er1,er1; mov.b r2l,r1l; add.l er6,er1; mov.b @net_n_out:24,r3l",
    },
    OpSpec {
        op: Op::InOutput,
        insns: &[MovBwPostInc, MovBwInd, Reg, Reg, Bcc8],
        asm: "mov.w @er0+,r2; mov.b r2h,@er1; adds #1,er1; add.b #-1,r3l; bne",
    },
    OpSpec {
        op: Op::InEvalScale,
        insns: &[MovBwAbs16, Reg, Reg, Reg, ImmW, Bcc8],
        asm: "mov.w @(0xe:16,er7),r0; shar.w r0 (x3); cmp.w #0x7f,r0; ble",
    },
    OpSpec {
        op: Op::InEvalHigh,
        insns: &[ImmW, Bcc8],
        asm: "mov.w #0x7f,r0; bra",
    },
    OpSpec {
        op: Op::InEvalLowTest,
        insns: &[ImmW, Bcc8],
        asm: "cmp.w #0xff80,r0; bge",
    },
    OpSpec {
        op: Op::InEvalLow,
        insns: &[ImmW],
        asm: "mov.w #0xff80,r0",
    },
    OpSpec {
        op: Op::InEvalStore,
        insns: &[MovBwInd, Reg, MovBwAbs24, Bcc8],
        asm: "mov.b r0l,@er1; adds #1,er1; mov.b @net_bias:24,r2l; beq",
    },
    OpSpec {
        op: Op::InBias,
        insns: &[Reg, MovBwInd],
        asm: "mov.b #0x7f,r2l; mov.b r2l,@er1",
    },
    OpSpec {
        op: Op::InForwardCall,
        insns: &[JsrAbs24],
        asm: "jsr @learner_forward",
    },
    OpSpec {
        op: Op::InExit,
        insns: &[
            MovBwAbs24, Reg, MovBwAbs24, Reg, MovBwAbs24, PushPopL, PushPopL, PushPopL, Reg, Rts,
        ],
        asm: "mov.w r5,@net_d_prev:24; mov.b #1,r2l; mov.b r2l,@net_started:24; sub.l er0,er0; mov.b @net_win:24,r0l; mov.l @er7+,er6-er4; adds #4,er7; rts",
    },
    OpSpec {
        op: Op::UpdEntry,
        insns: &[
            Reg, Reg, PushPopL, PushPopL, PushPopL, MovBwAbs24, Reg, Reg, Reg, Bcc8,
        ],
        asm: "subs #4,er7 (x2); mov.l er4-er6,@-er7; mov.w @net_threshold:24,r2; mov.w r2,r3; neg.w r3; cmp.w r2,r0; bgt",
    },
    OpSpec {
        op: Op::UpdLowTest,
        insns: &[Reg, Bcc16],
        asm: "cmp.w r3,r0; bge:16",
    },
    OpSpec {
        op: Op::UpdSign,
        insns: &[MovBwAbs24, Reg, Bcc8],
        asm: "mov.w @net_eta:24,r6; mov.w r0,r0; bgt",
    },
    OpSpec {
        op: Op::UpdNeg,
        insns: &[Reg],
        asm: "neg.w r6",
    },
    OpSpec {
        op: Op::UpdDeltaSetup,
        insns: &[MovLAbs24, MovLAbs24, MovLAbs16, MovBwAbs24],
        asm: "mov.l @net_x:24,er5; mov.l @net_delta:24,er4; mov.l er4,@(0xc:16,er7); mov.w @net_n_in:24,r1",
    },
    OpSpec {
        op: Op::DeltaHead,
        insns: &[MovBwPostInc, Reg, MulxsW, Reg, Bcc8],
        asm: "mov.b @er5+,r2l; exts.w r2; mulxs.w r6,er2; mov.l er2,er2; blt",
    },
    OpSpec {
        op: Op::DeltaPos,
        insns: &[ImmL, Reg, Reg, Reg, Reg, Reg, Reg, Bcc8],
        asm: "add.l #0x40,er2; mov.l er4,er3; adds #2,er4; shll.l er2; mov.w e2,r0; mov.b r2h,r2l; mov.b r0l,r2h; bra",
    },
    OpSpec {
        op: Op::DeltaNeg,
        insns: &[Reg, Reg, Reg, Reg, Reg, Reg, Reg, Reg, Reg, Reg, Reg, Reg],
        asm: "sub.l er3,er3; add.b #0x40,r3l; sub.l er2,er3; mov.l er3,er2; mov.l er4,er3; adds #2,er4; shll.l er2; mov.w e2,r0; mov.b r2h,r2l; mov.b r0l,r2h; exts.l er2; neg.w r2",
    },
    OpSpec {
        op: Op::DeltaTail,
        insns: &[MovBwInd, Reg, Bcc8],
        asm: "mov.w r2,@er3; dec.w #1,r1; bne",
    },
    OpSpec {
        op: Op::UpdRowsSetup,
        insns: &[MovLAbs24, MovBwAbs24, MovBwAbs16, MovBwAbs24, Reg],
        asm: "mov.l @net_w:24,er0; mov.b @net_win:24,r2l; mov.b r2l,@(0x13:16,er7); mov.b @net_n_out:24,r6l; sub.b r5l,r5l",
    },
    OpSpec {
        op: Op::UpdRowHead,
        insns: &[MovLAbs16, MovBwAbs24, MovBwAbs16, Reg, Bcc8],
        asm: "mov.l @(0xc:16,er7),er4; mov.w @net_n_in:24,r1; mov.b @(0x13:16,er7),r3l; cmp.b r3l,r5l; bne",
    },
    OpSpec {
        op: Op::UpdWeight,
        insns: &[MovBwInd, MovBwPostInc, Reg, Bcc8, MovBwInd, Reg, Reg, Bcc8],
        asm: "mov.w @er0,r2; mov.w @er4+,r3; add.w r3,r2 | sub.w r3,r2; bvc; mov.w r2,@er0; adds #2,er0; dec.w #1,r1; bne",
    },
    OpSpec {
        op: Op::UpdClampHi,
        insns: &[ImmW, Bcc8],
        asm: "mov.w #0x7fff,r2; bcc | bcs",
    },
    OpSpec {
        op: Op::UpdClampLo,
        insns: &[ImmW, Bcc8, ImmW],
        asm: "mov.w #0x7fff,r2; bcc | bcs; mov.w #0x8000,r2",
    },
    OpSpec {
        op: Op::UpdWinRowExit,
        insns: &[Bcc8],
        asm: "bra",
    },
    OpSpec {
        op: Op::UpdRowTail,
        insns: &[Reg, Reg, Bcc16],
        asm: "add.b #1,r5l; cmp.b r6l,r5l; bcs:16",
    },
    OpSpec {
        op: Op::UpdExit,
        insns: &[PushPopL, PushPopL, PushPopL, Reg, Reg, Rts],
        asm: "mov.l @er7+,er6-er4; adds #4,er7 (x2); rts",
    },
    OpSpec {
        op: Op::FwdEntry,
        insns: &[
            ImmL, PushPopL, PushPopL, PushPopL, MovLAbs24, MovLAbs24, MovLAbs16, MovLAbs16,
            MovLAbs24, MovLAbs16, MovBwAbs24, MovBwAbs16, MovLAbs24, MovLAbs16, MovBwAbs24,
            MovBwAbs16,
        ],
        asm: "add.l #-24,er7; mov.l er4-er6,@-er7; mov.l @net_w:24,er5; mov.l @net_y:24,er1; mov.l er1,@(0x20:16,er7); mov.l er1,@(0x10:16,er7); mov.l @net_o:24,er2; mov.l er2,@(0x1c:16,er7); mov.b @net_n_out:24,r6l; mov.b r6l,@(0x1b:16,er7); mov.l @net_x:24,er3; mov.l er3,@(0x14:16,er7); mov.w @net_n_in:24,r1; mov.w r1,@(0xe:16,er7)",
    },
    OpSpec {
        op: Op::FwdRowSetup,
        insns: &[MovLAbs16, MovBwAbs16, Reg],
        asm: "mov.l @(0x14:16,er7),er4; mov.w @(0xe:16,er7),r0; sub.l er1,er1",
    },
    OpSpec {
        op: Op::FwdMac,
        insns: &[MovBwPostInc, MovBwPostInc, Reg, MulxsW, Reg, Reg, Bcc8],
        asm: "mov.w @er5+,r3; mov.b @er4+,r2l; exts.w r2; mulxs.w r2,er3; add.l er3,er1; dec.w #1,r0; bne",
    },
    OpSpec {
        op: Op::FwdRowEnd,
        insns: &[MovLAbs16, MovLInd, Reg, MovLAbs16, Reg, Bcc8],
        asm: "mov.l @(0x20:16,er7),er2; mov.l er1,@er2; adds #4,er2; mov.l er2,@(0x20:16,er7); add.b #-1,r6l; bne",
    },
    OpSpec {
        op: Op::FwdArgmaxInit,
        insns: &[MovLAbs16, Reg, MovLPostInc, MovLAbs16],
        asm: "mov.l @(0x10:16,er7),er3; mov.l er3,er5; mov.l @er5+,er3; mov.l er5,@(0x20:16,er7)",
    },
    OpSpec {
        op: Op::FwdArgmaxTest,
        insns: &[Reg, MovBwAbs16, Reg, Bcc8],
        asm: "add.b #1,r6l; mov.b @(0x1b:16,er7),r1l; cmp.b r1l,r6l; bcc",
    },
    OpSpec {
        op: Op::FwdArgmaxLoad,
        insns: &[MovLAbs16, MovLPostInc, MovLAbs16, Reg, Bcc8],
        asm: "mov.l @(0x20:16,er7),er5; mov.l @er5+,er2; mov.l er5,@(0x20:16,er7); cmp.l er3,er2; ble",
    },
    OpSpec {
        op: Op::FwdNewMax,
        insns: &[Reg, Reg, Bcc8],
        asm: "mov.l er2,er3; mov.b r6l,r0l; bra",
    },
    OpSpec {
        op: Op::FwdScaleTest,
        insns: &[MovBwAbs24, MovLAbs16, MovLAbs16, MovBwAbs16, ImmL, Bcc8],
        asm: "mov.b r0l,@net_win:24; mov.l @(0x10:16,er7),er2; mov.l er2,@(0x20:16,er7); mov.b @(0x1b:16,er7),r6l; cmp.l #0x3fffff,er3; bgt",
    },
    OpSpec {
        op: Op::FwdPlainHead,
        insns: &[MovLAbs16, MovLPostInc, MovLAbs16, ImmL, Bcc8],
        asm: "mov.l @(0x20:16,er7),er3; mov.l @er3+,er0; mov.l er3,@(0x20:16,er7); cmp.l #0xffc00000,er0; bge",
    },
    OpSpec {
        op: Op::FwdPlainLow,
        insns: &[ImmW, MovLAbs16, MovBwInd, Reg, MovLAbs16, Bcc8],
        asm: "mov.w #0x8000,r2; mov.l @(0x1c:16,er7),er5; mov.w r2,@er5; adds #2,er5; mov.l er5,@(0x1c:16,er7); bra",
    },
    OpSpec {
        op: Op::FwdPlainOut,
        insns: &[MovLAbs16, Reg, Reg, MovLAbs16, Reg, Reg, Reg, Reg, MovBwInd],
        asm: "mov.l @(0x1c:16,er7),er2; mov.l er2,er1; adds #2,er1; mov.l er1,@(0x1c:16,er7); shll.l er0; mov.w e0,r3; mov.b r0h,r0l; mov.b r3l,r0h; mov.w r0,@er2",
    },
    OpSpec {
        op: Op::FwdPlainTail,
        insns: &[Reg, Bcc8],
        asm: "add.b #-1,r6l; bne",
    },
    OpSpec {
        op: Op::FwdPlainExit,
        insns: &[Bcc16],
        asm: "bra:16",
    },
    OpSpec {
        op: Op::FwdNormSetup,
        insns: &[Reg, Reg, Reg, Reg, Reg, Reg, Reg],
        asm: "sub.b r0l,r0l; mov.w e3,r2; mov.b r3h,r3l; mov.b r2l,r3h; mov.b r2h,r2l; exts.w r2; mov.w r2,e3",
    },
    OpSpec {
        op: Op::FwdNormTest,
        insns: &[ImmL, Bcc8],
        asm: "cmp.l #0x7fff,er3; ble",
    },
    OpSpec {
        op: Op::FwdNormShift,
        insns: &[Reg, Reg, Bcc8],
        asm: "shar.l er3; add.b #1,r0l; bra",
    },
    OpSpec {
        op: Op::FwdNormReady,
        insns: &[Reg, Reg, Reg],
        asm: "mov.w r3,r4; mov.w r3,r1; exts.l er1",
    },
    OpSpec {
        op: Op::FwdNormHead,
        insns: &[
            MovLAbs16,
            MovLPostInc,
            MovLAbs16,
            Reg,
            Reg,
            Reg,
            Reg,
            Reg,
            Reg,
            Reg,
        ],
        asm: "mov.l @(0x20:16,er7),er5; mov.l @er5+,er3; mov.l er5,@(0x20:16,er7); mov.w e3,r2; mov.b r3h,r3l; mov.b r2l,r3h; mov.b r2h,r2l; exts.w r2; mov.w r2,e3; mov.b r0l,r2l",
    },
    OpSpec {
        op: Op::FwdNormStepTest,
        insns: &[Reg, Bcc8],
        asm: "mov.b r2l,r2l; beq",
    },
    OpSpec {
        op: Op::FwdNormStep,
        insns: &[Reg, Reg, Bcc8],
        asm: "shar.l er3; add.b #-1,r2l; bra",
    },
    OpSpec {
        op: Op::FwdNormLowTest,
        insns: &[Reg, Reg, Reg, Bcc8],
        asm: "mov.l er1,er2; neg.l er2; cmp.l er3,er2; blt",
    },
    OpSpec {
        op: Op::FwdNormLow,
        insns: &[ImmW, MovLAbs16, MovBwInd, Reg, MovLAbs16, Bcc8],
        asm: "mov.w #0x8000,r2; mov.l @(0x1c:16,er7),er3; mov.w r2,@er3; adds #2,er3; mov.l er3,@(0x1c:16,er7); bra",
    },
    OpSpec {
        op: Op::FwdNormHighTest,
        insns: &[Reg, Bcc8],
        asm: "cmp.l er3,er1; bgt",
    },
    OpSpec {
        op: Op::FwdNormHigh,
        insns: &[ImmW, MovLAbs16, MovBwInd, Reg, MovLAbs16, Bcc8],
        asm: "mov.w #0x7fff,r2; mov.l @(0x1c:16,er7),er5; mov.w r2,@er5; adds #2,er5; mov.l er5,@(0x1c:16,er7); bra",
    },
    OpSpec {
        op: Op::FwdNormDiv,
        insns: &[
            Reg, Reg, Reg, Reg, Reg, MovLAbs16, Reg, Reg, MovLAbs16, DivxsW, MovBwInd,
        ],
        asm: "mov.l er3,er2; shlr.w e2; mov.w r2,e2; xor.w r2,r2; rotxr.l er2; mov.l @(0x1c:16,er7),er3; mov.l er3,er5; adds #2,er5; mov.l er5,@(0x1c:16,er7); divxs.w r4,er2; mov.w r2,@er3",
    },
    OpSpec {
        op: Op::FwdNormTail,
        insns: &[Reg, Bcc16],
        asm: "add.b #-1,r6l; bne:16",
    },
    OpSpec {
        op: Op::FwdExit,
        insns: &[PushPopL, PushPopL, PushPopL, ImmL, Rts],
        asm: "mov.l @er7+,er6-er4; add.l #24,er7; rts",
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

/// The phases of a learner step, in the order the firmware runs them (docs/design.md §3.5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Phase {
    /// D(t), E(t−1) and the input vector for step t.
    Input,
    /// The update with E(t−1) on x(t−1) (docs/design.md §2.4).
    Update,
    /// The forward pass on x(t) (docs/design.md §2.3).
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
    /// The learner ran block `op` `count` times.
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

/// A meter that charges H8/300H states per phase from [`OP_STATES`] and counts every block.
///
/// It keeps one count per (phase, block) pair and each phase's states, the counts weighted by
/// [`OP_STATES`], as it goes: a charge is two additions, and the states are read without
/// summing the table (the model controller reads every phase's states every step).
#[derive(Clone, Debug)]
pub struct H8Meter {
    phase: Phase,
    counts: [[u64; Op::COUNT]; Phase::COUNT],
    states: [u64; Phase::COUNT],
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
            states: [0; Phase::COUNT],
        }
    }

    /// States charged to `phase` so far.
    #[must_use]
    pub fn states(&self, phase: Phase) -> u64 {
        self.states[phase as usize]
    }

    /// States charged to every phase so far.
    #[must_use]
    pub fn total_states(&self) -> u64 {
        Phase::ALL.iter().map(|&p| self.states(p)).sum()
    }

    /// How many times block `op` ran so far, over all phases.
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
        self.states[self.phase as usize] += u64::from(count) * u64::from(OP_STATES[op as usize]);
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
    fn the_mac_is_two_loads_exts_mulxs_add_and_the_loop() {
        // docs/design.md §2.7: "one multiply-accumulate: two post-increment loads, EXTS, MULXS.W, ADD.L";
        // docs/design.md §4.2: @ERs+ 6, EXTS 2, MULXS.W 24, ADD.L 2; the loop's DEC.W 2 and BNE 4.
        assert_eq!(Op::FwdMac.states(), 6 + 6 + 2 + 24 + 2 + 2 + 4);
        assert_eq!(Op::FwdNormDiv.states(), 62);
        // A dead-zone update: entry 52, the second bound test 8, exit 44.
        assert_eq!(
            Op::UpdEntry.states() + Op::UpdLowTest.states() + Op::UpdExit.states(),
            104
        );
    }

    #[test]
    fn states_follow_the_fetch_rule_for_register_and_immediate_forms() {
        // With 2-state on-chip fetches, an instruction with no data access and no internal
        // states costs 2 states per instruction word.
        for insn in [Insn::Reg, Insn::ImmW, Insn::ImmL] {
            assert_eq!(insn.states(), insn.bytes(), "{insn:?}");
        }
        // A branch fetches its own words and then refills the prefetch queue at the target
        // (taken) or the next word (not taken).
        assert_eq!(Insn::Bcc8.states(), 2 * Insn::Bcc8.bytes());
        for insn in Insn::ALL {
            assert_eq!(insn.example().1.len() as u32, insn.bytes(), "{insn:?}");
        }
    }

    #[test]
    fn h8_meter_charges_per_phase_and_noop_records_nothing() {
        let mut m = H8Meter::new();
        m.enter(Phase::Forward);
        m.charge(Op::FwdMac, 13);
        m.enter(Phase::Update);
        m.charge(Op::UpdWeight, 1);
        assert_eq!(m.states(Phase::Forward), 13 * 46);
        assert_eq!(m.states(Phase::Update), 28);
        assert_eq!(m.states(Phase::Input), 0);
        assert_eq!(m.total_states(), 13 * 46 + 28);
        assert_eq!(m.count(Op::FwdMac), 13);
        m.reset();
        assert_eq!(m.total_states(), 0);
    }

    #[test]
    fn a_phases_running_states_are_its_counts_weighted_by_the_table() {
        let mut m = H8Meter::new();
        for (i, &op) in Op::ALL.iter().enumerate() {
            m.enter(Phase::ALL[i % Phase::COUNT]);
            m.charge(op, 1 + (i as u32 * 7) % 5);
        }
        m.enter(Phase::Update);
        m.charge(Op::FwdMac, 3);
        for p in Phase::ALL {
            let weighted: u64 = Op::ALL
                .iter()
                .map(|&op| m.count_in(p, op) * u64::from(op.states()))
                .sum();
            assert_eq!(m.states(p), weighted, "{p:?}");
        }
    }
}
