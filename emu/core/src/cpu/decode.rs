//! Instruction decoding for the H8/300H in advanced mode.
//!
//! Encodings follow the H8/300H Series Programming Manual, section 2 (one page per instruction,
//! "Instruction Format") and its Table A-2 operation code map. An instruction is 1 to 5 16-bit
//! words; the decoder pulls words one at a time from a [`WordSource`] and never asks for a word
//! beyond the instruction it is decoding, so the number of words it pulled is the instruction's
//! length and the number of instruction fetches the manual's I count starts from.

/// Operand size of an instruction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Size {
    /// 8 bits (`.b`).
    Byte,
    /// 16 bits (`.w`).
    Word,
    /// 32 bits (`.l`).
    Long,
}

impl Size {
    /// The assembler suffix letter (`b`, `w`, `l`).
    #[must_use]
    pub const fn suffix(self) -> char {
        match self {
            Size::Byte => 'b',
            Size::Word => 'w',
            Size::Long => 'l',
        }
    }
}

/// A general operand (an effective address in the manual's terms).
///
/// Register numbers depend on the size of the instruction: for bytes 0–7 are R0H–R7H and
/// 8–15 are R0L–R7L; for words 0–7 are R0–R7 and 8–15 are E0–E7; for longwords 0–7 are
/// ER0–ER7. Address registers (`@ERn` and friends) are always 0–7.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Operand {
    /// Register direct.
    Reg(u8),
    /// Immediate data (zero-extended to 32 bits).
    Imm(u32),
    /// Register indirect `@ERn`.
    Ind(u8),
    /// Register indirect with post-increment `@ERn+`.
    PostInc(u8),
    /// Register indirect with pre-decrement `@-ERn`.
    PreDec(u8),
    /// Register indirect with 16-bit displacement `@(d:16,ERn)` (the raw field; it is
    /// sign-extended when the address is computed).
    Disp16(u8, u16),
    /// Register indirect with 24-bit displacement `@(d:24,ERn)` (the raw 32-bit field of the
    /// instruction, whose top byte the CPU ignores).
    Disp24(u8, u32),
    /// 8-bit absolute address `@aa:8` (H'FFFF00–H'FFFFFF).
    Abs8(u8),
    /// 16-bit absolute address `@aa:16` (sign-extended to 24 bits).
    Abs16(u16),
    /// 24-bit absolute address `@aa:24` (the raw 32-bit field of the instruction, whose top
    /// byte the CPU ignores).
    Abs24(u32),
}

impl Operand {
    /// Whether this operand is in memory (everything but register direct and immediate).
    #[must_use]
    pub const fn is_memory(self) -> bool {
        !matches!(self, Operand::Reg(_) | Operand::Imm(_))
    }
}

/// Two-operand arithmetic and logic operations (`op.size src,Rd`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AluOp {
    /// `add`.
    Add,
    /// `sub`.
    Sub,
    /// `cmp`.
    Cmp,
    /// `and`.
    And,
    /// `or`.
    Or,
    /// `xor`.
    Xor,
    /// `addx` (add with carry, byte only).
    Addx,
    /// `subx` (subtract with borrow, byte only).
    Subx,
}

impl AluOp {
    /// The mnemonic without size suffix.
    #[must_use]
    pub const fn mnemonic(self) -> &'static str {
        match self {
            AluOp::Add => "add",
            AluOp::Sub => "sub",
            AluOp::Cmp => "cmp",
            AluOp::And => "and",
            AluOp::Or => "or",
            AluOp::Xor => "xor",
            AluOp::Addx => "addx",
            AluOp::Subx => "subx",
        }
    }
}

/// One-operand register operations (`op.size Rd`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum UnaryOp {
    /// `neg`: two's complement.
    Neg,
    /// `not`: one's complement.
    Not,
    /// `exts`: sign-extend the lower half.
    Exts,
    /// `extu`: zero-extend the lower half.
    Extu,
    /// `shal`: arithmetic shift left.
    Shal,
    /// `shar`: arithmetic shift right.
    Shar,
    /// `shll`: logical shift left.
    Shll,
    /// `shlr`: logical shift right.
    Shlr,
    /// `rotxl`: rotate left through carry.
    Rotxl,
    /// `rotxr`: rotate right through carry.
    Rotxr,
    /// `rotl`: rotate left.
    Rotl,
    /// `rotr`: rotate right.
    Rotr,
}

impl UnaryOp {
    /// The mnemonic without size suffix.
    #[must_use]
    pub const fn mnemonic(self) -> &'static str {
        match self {
            UnaryOp::Neg => "neg",
            UnaryOp::Not => "not",
            UnaryOp::Exts => "exts",
            UnaryOp::Extu => "extu",
            UnaryOp::Shal => "shal",
            UnaryOp::Shar => "shar",
            UnaryOp::Shll => "shll",
            UnaryOp::Shlr => "shlr",
            UnaryOp::Rotxl => "rotxl",
            UnaryOp::Rotxr => "rotxr",
            UnaryOp::Rotl => "rotl",
            UnaryOp::Rotr => "rotr",
        }
    }
}

/// Multiply and divide operations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MulDivOp {
    /// `mulxu`: unsigned multiply.
    Mulxu,
    /// `mulxs`: signed multiply.
    Mulxs,
    /// `divxu`: unsigned divide.
    Divxu,
    /// `divxs`: signed divide.
    Divxs,
}

impl MulDivOp {
    /// The mnemonic without size suffix.
    #[must_use]
    pub const fn mnemonic(self) -> &'static str {
        match self {
            MulDivOp::Mulxu => "mulxu",
            MulDivOp::Mulxs => "mulxs",
            MulDivOp::Divxu => "divxu",
            MulDivOp::Divxs => "divxs",
        }
    }

    /// Whether the operation is signed (its encoding carries a 01C0/01D0 prefix word).
    #[must_use]
    pub const fn signed(self) -> bool {
        matches!(self, MulDivOp::Mulxs | MulDivOp::Divxs)
    }
}

/// Bit-manipulation operations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BitOp {
    /// `bset`: set the bit.
    Bset,
    /// `bclr`: clear the bit.
    Bclr,
    /// `bnot`: invert the bit.
    Bnot,
    /// `btst`: Z = not bit.
    Btst,
    /// `bld`: C = bit.
    Bld,
    /// `bild`: C = not bit.
    Bild,
    /// `bst`: bit = C.
    Bst,
    /// `bist`: bit = not C.
    Bist,
    /// `band`: C = C and bit.
    Band,
    /// `biand`: C = C and not bit.
    Biand,
    /// `bor`: C = C or bit.
    Bor,
    /// `bior`: C = C or not bit.
    Bior,
    /// `bxor`: C = C xor bit.
    Bxor,
    /// `bixor`: C = C xor not bit.
    Bixor,
}

impl BitOp {
    /// The mnemonic.
    #[must_use]
    pub const fn mnemonic(self) -> &'static str {
        match self {
            BitOp::Bset => "bset",
            BitOp::Bclr => "bclr",
            BitOp::Bnot => "bnot",
            BitOp::Btst => "btst",
            BitOp::Bld => "bld",
            BitOp::Bild => "bild",
            BitOp::Bst => "bst",
            BitOp::Bist => "bist",
            BitOp::Band => "band",
            BitOp::Biand => "biand",
            BitOp::Bor => "bor",
            BitOp::Bior => "bior",
            BitOp::Bxor => "bxor",
            BitOp::Bixor => "bixor",
        }
    }

    /// Whether the operation writes the byte back (read-modify-write: two byte accesses on a
    /// memory operand instead of one).
    #[must_use]
    pub const fn writes(self) -> bool {
        matches!(
            self,
            BitOp::Bset | BitOp::Bclr | BitOp::Bnot | BitOp::Bst | BitOp::Bist
        )
    }
}

/// The bit number of a bit instruction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BitNum {
    /// `#xx:3`.
    Imm(u8),
    /// The low 3 bits of a byte register (0–15 as for byte operands).
    Reg(u8),
}

/// The byte a bit instruction works on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BitTarget {
    /// A byte register (0–15).
    Reg(u8),
    /// `@ERd`.
    Ind(u8),
    /// `@aa:8`.
    Abs8(u8),
}

/// The target of JMP and JSR.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum JumpTarget {
    /// `@ERn`.
    Reg(u8),
    /// `@aa:24`.
    Abs24(u32),
    /// `@@aa:8`: the branch address is the longword at H'000000 + aa.
    MemInd(u8),
}

/// A decoded H8/300H instruction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Instr {
    /// `nop`.
    Nop,
    /// `sleep`.
    Sleep,
    /// `rts`.
    Rts,
    /// `rte`.
    Rte,
    /// `mov.size src,dst` (also PUSH/POP, which are MOV with `@-ER7`/`@ER7+`).
    Mov {
        /// Operand size.
        size: Size,
        /// Source operand.
        src: Operand,
        /// Destination operand.
        dst: Operand,
    },
    /// `movfpe @aa:16,Rd` (move from peripheral with E clock).
    Movfpe {
        /// 16-bit absolute address.
        addr: u16,
        /// Byte register.
        rd: u8,
    },
    /// `movtpe Rs,@aa:16` (move to peripheral with E clock).
    Movtpe {
        /// Byte register.
        rs: u8,
        /// 16-bit absolute address.
        addr: u16,
    },
    /// Two-operand arithmetic/logic `op.size src,Rd` with `src` a register or immediate.
    Alu {
        /// Operation.
        op: AluOp,
        /// Operand size.
        size: Size,
        /// Source: [`Operand::Reg`] or [`Operand::Imm`].
        src: Operand,
        /// Destination register.
        rd: u8,
    },
    /// `inc.size #n,Rd` (n = 1 or 2).
    Inc {
        /// Operand size.
        size: Size,
        /// 1 or 2.
        amount: u8,
        /// Register.
        rd: u8,
    },
    /// `dec.size #n,Rd` (n = 1 or 2).
    Dec {
        /// Operand size.
        size: Size,
        /// 1 or 2.
        amount: u8,
        /// Register.
        rd: u8,
    },
    /// `adds #n,ERd` (n = 1, 2 or 4).
    Adds {
        /// 1, 2 or 4.
        amount: u8,
        /// Register.
        rd: u8,
    },
    /// `subs #n,ERd` (n = 1, 2 or 4).
    Subs {
        /// 1, 2 or 4.
        amount: u8,
        /// Register.
        rd: u8,
    },
    /// One-operand operations on a register.
    Unary {
        /// Operation.
        op: UnaryOp,
        /// Operand size.
        size: Size,
        /// Register.
        rd: u8,
    },
    /// `daa Rd`.
    Daa(u8),
    /// `das Rd`.
    Das(u8),
    /// MULXU/MULXS/DIVXU/DIVXS (`size` is the size of the source register).
    MulDiv {
        /// Operation.
        op: MulDivOp,
        /// [`Size::Byte`] (Rs 8-bit, Rd 16-bit) or [`Size::Word`] (Rs 16-bit, ERd 32-bit).
        size: Size,
        /// Source register.
        rs: u8,
        /// Destination register (word register for `.b`, longword register for `.w`).
        rd: u8,
    },
    /// Bit manipulation.
    Bit {
        /// Operation.
        op: BitOp,
        /// Bit number.
        bit: BitNum,
        /// Byte operand.
        target: BitTarget,
    },
    /// `bcc d:8` / `bcc d:16`.
    Bcc {
        /// Condition code field 0–15 (0 = BRA/BT, 1 = BRN/BF, ...).
        cond: u8,
        /// Displacement from the address after the instruction.
        disp: i16,
        /// Whether this is the 16-bit displacement form.
        long: bool,
    },
    /// `bsr d:8` / `bsr d:16`.
    Bsr {
        /// Displacement from the address after the instruction.
        disp: i16,
        /// Whether this is the 16-bit displacement form.
        long: bool,
    },
    /// `jmp`.
    Jmp(JumpTarget),
    /// `jsr`.
    Jsr(JumpTarget),
    /// `trapa #x:2`.
    Trapa(u8),
    /// `eepmov.b` / `eepmov.w`.
    Eepmov {
        /// Whether this is `eepmov.w` (count in R4 rather than R4L).
        word: bool,
    },
    /// `ldc src,ccr` (immediate, byte register or word memory operand).
    Ldc(Operand),
    /// `stc ccr,dst` (byte register or word memory operand).
    Stc(Operand),
    /// `andc #xx:8,ccr`.
    Andc(u8),
    /// `orc #xx:8,ccr`.
    Orc(u8),
    /// `xorc #xx:8,ccr`.
    Xorc(u8),
}

/// A decoded instruction and its length.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Decoded {
    /// The instruction.
    pub instr: Instr,
    /// Length in 16-bit words (1–5).
    pub words: u8,
}

impl Decoded {
    /// Length in bytes.
    #[must_use]
    pub const fn len_bytes(self) -> u32 {
        2 * self.words as u32
    }
}

/// Why a word sequence is not an instruction.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// The words do not encode any H8/300H instruction.
    #[error("undefined opcode {}", hex_words(.words))]
    Undefined {
        /// The words examined, first to last.
        words: Vec<u16>,
    },
    /// The source ran out of words in the middle of an instruction.
    #[error("truncated instruction {} (needs more words than are available)", hex_words(.words))]
    Truncated {
        /// The words read before the source ran out.
        words: Vec<u16>,
    },
}

/// Formats words as `xx xx xx xx` bytes (the form objdump prints).
#[must_use]
pub fn hex_words(words: &[u16]) -> String {
    let mut s = String::new();
    for (i, w) in words.iter().enumerate() {
        if i > 0 {
            s.push(' ');
        }
        s.push_str(&format!("{:02x} {:02x}", w >> 8, w & 0xff));
    }
    s
}

/// A source of instruction words, read in order.
pub trait WordSource {
    /// The next word of the instruction stream, or `None` when there is none (end of a byte
    /// slice, or a fetch the CPU refuses).
    fn next_word(&mut self) -> Option<u16>;
}

/// A [`WordSource`] over a big-endian byte slice.
#[derive(Clone, Debug)]
pub struct SliceSource<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> SliceSource<'a> {
    /// Words from `bytes`, starting at its first byte.
    #[must_use]
    pub const fn new(bytes: &'a [u8]) -> Self {
        SliceSource { bytes, pos: 0 }
    }
}

impl WordSource for SliceSource<'_> {
    fn next_word(&mut self) -> Option<u16> {
        let hi = *self.bytes.get(self.pos)?;
        let lo = *self.bytes.get(self.pos + 1)?;
        self.pos += 2;
        Some(u16::from_be_bytes([hi, lo]))
    }
}

/// Decodes one instruction from a byte slice.
///
/// ```
/// use h8300h::cpu::decode::{decode_bytes, DecodeError};
/// let d = decode_bytes(&[0x6A, 0x28, 0x00, 0xFF, 0xFF, 0x20]).unwrap(); // mov.b r0l,@0xffff20:24
/// assert_eq!(d.len_bytes(), 6);
/// assert!(matches!(decode_bytes(&[0x6A]), Err(DecodeError::Truncated { .. })));
/// ```
///
/// # Errors
/// [`DecodeError::Undefined`] if the bytes are no instruction, [`DecodeError::Truncated`] if the
/// slice ends inside one.
pub fn decode_bytes(bytes: &[u8]) -> Result<Decoded, DecodeError> {
    decode(&mut SliceSource::new(bytes))
}

/// Pulls words from the source and remembers them for error messages.
struct Reader<'s, S: WordSource> {
    src: &'s mut S,
    words: [u16; 5],
    n: usize,
}

/// Early-exit marker inside the decoder: the instruction is undefined or truncated.
enum Stop {
    Undefined,
    Truncated,
}

impl<S: WordSource> Reader<'_, S> {
    #[inline(always)]
    fn word(&mut self) -> Result<u16, Stop> {
        if self.n >= self.words.len() {
            return Err(Stop::Undefined);
        }
        match self.src.next_word() {
            Some(w) => {
                self.words[self.n] = w;
                self.n += 1;
                Ok(w)
            }
            None => Err(Stop::Truncated),
        }
    }

    #[inline(always)]
    fn long(&mut self) -> Result<u32, Stop> {
        let hi = self.word()?;
        let lo = self.word()?;
        Ok((u32::from(hi) << 16) | u32::from(lo))
    }
}

/// Decodes one instruction, pulling exactly its words from `src`.
///
/// # Errors
/// [`DecodeError::Undefined`] if the words are no H8/300H instruction, [`DecodeError::Truncated`]
/// if the source runs out inside one.
#[inline]
pub fn decode<S: WordSource>(src: &mut S) -> Result<Decoded, DecodeError> {
    let mut r = Reader {
        src,
        words: [0; 5],
        n: 0,
    };
    match decode_inner(&mut r) {
        Ok(instr) => Ok(Decoded {
            instr,
            words: r.n as u8,
        }),
        Err(Stop::Undefined) => Err(DecodeError::Undefined {
            words: r.words[..r.n].to_vec(),
        }),
        Err(Stop::Truncated) => Err(DecodeError::Truncated {
            words: r.words[..r.n].to_vec(),
        }),
    }
}

const fn hi4(b: u8) -> u8 {
    b >> 4
}
const fn lo4(b: u8) -> u8 {
    b & 0xf
}

/// A 3-bit register field whose top bit must be 0 (`0rrr`).
fn r3(nibble: u8) -> Result<u8, Stop> {
    if nibble & 8 == 0 {
        Ok(nibble)
    } else {
        Err(Stop::Undefined)
    }
}

fn expect(cond: bool) -> Result<(), Stop> {
    if cond { Ok(()) } else { Err(Stop::Undefined) }
}

const ALU_RR_BYTE: [Option<AluOp>; 16] = [
    None,
    None,
    None,
    None,
    None,
    None,
    None,
    None,
    Some(AluOp::Add),  // 08
    None,              // 09 add.w
    None,              // 0a
    None,              // 0b
    None,              // 0c mov.b
    None,              // 0d mov.w
    Some(AluOp::Addx), // 0e
    None,
];

/// Decodes one instruction: the first word's first byte picks the opcode group, each group
/// decoded by a function of its own.
fn decode_inner<S: WordSource>(r: &mut Reader<'_, S>) -> Result<Instr, Stop> {
    let w0 = r.word()?;
    let [op, b1] = w0.to_be_bytes();
    use Instr as I;
    use Operand as O;
    let instr = match op {
        0x00..=0x07 => decode_control(r, op, b1)?,
        0x08 | 0x09 | 0x0c..=0x0e | 0x14..=0x16 | 0x18 | 0x19 | 0x1c..=0x1e | 0x64..=0x66 => {
            decode_register_alu(op, b1)?
        }
        0x0a | 0x0b | 0x0f | 0x1a | 0x1b | 0x1f => decode_add_sub_pairs(op, b1)?,
        0x10..=0x13 | 0x17 => decode_shift_unary(op, b1)?,
        0x20..=0x2f => I::Mov {
            size: Size::Byte,
            src: O::Abs8(b1),
            dst: O::Reg(op & 0xf),
        },
        0x30..=0x3f => I::Mov {
            size: Size::Byte,
            src: O::Reg(op & 0xf),
            dst: O::Abs8(b1),
        },
        0x40..=0x4f => I::Bcc {
            cond: op & 0xf,
            disp: i16::from(b1 as i8),
            long: false,
        },
        0x50..=0x5f => decode_branch_muldiv(r, op, b1)?,
        0x60..=0x63 | 0x67..=0x7f => decode_bit_mov(r, op, b1)?,
        0x80..=0x8f => alu_imm8(AluOp::Add, op, b1),
        0x90..=0x9f => alu_imm8(AluOp::Addx, op, b1),
        0xa0..=0xaf => alu_imm8(AluOp::Cmp, op, b1),
        0xb0..=0xbf => alu_imm8(AluOp::Subx, op, b1),
        0xc0..=0xcf => alu_imm8(AluOp::Or, op, b1),
        0xd0..=0xdf => alu_imm8(AluOp::Xor, op, b1),
        0xe0..=0xef => alu_imm8(AluOp::And, op, b1),
        0xf0..=0xff => I::Mov {
            size: Size::Byte,
            src: O::Imm(u32::from(b1)),
            dst: O::Reg(op & 0xf),
        },
    };
    Ok(instr)
}

/// Decodes the control group H'00-H'07: NOP, the H'01 prefix, STC/LDC, ORC/XORC/ANDC.
fn decode_control<S: WordSource>(r: &mut Reader<'_, S>, op: u8, b1: u8) -> Result<Instr, Stop> {
    let (bh, bl) = (hi4(b1), lo4(b1));
    use Instr as I;
    use Operand as O;
    let instr = match op {
        0x00 => {
            expect(b1 == 0)?;
            I::Nop
        }
        0x01 => decode_01(r, b1)?,
        0x02 => {
            expect(bh == 0)?;
            I::Stc(O::Reg(bl))
        }
        0x03 => {
            expect(bh == 0)?;
            I::Ldc(O::Reg(bl))
        }
        0x04 => I::Orc(b1),
        0x05 => I::Xorc(b1),
        0x06 => I::Andc(b1),
        0x07 => I::Ldc(O::Imm(u32::from(b1))),
        _ => return Err(Stop::Undefined),
    };
    Ok(instr)
}

/// Decodes the ALU operations and MOVs between registers (byte and word ADD, ADDX, SUB,
/// SUBX, CMP, AND, OR, XOR; MOV.B and MOV.W).
fn decode_register_alu(op: u8, b1: u8) -> Result<Instr, Stop> {
    let (bh, bl) = (hi4(b1), lo4(b1));
    use Instr as I;
    use Operand as O;
    let instr = match op {
        0x08 | 0x0e => I::Alu {
            op: ALU_RR_BYTE[usize::from(op & 0xf)].ok_or(Stop::Undefined)?,
            size: Size::Byte,
            src: O::Reg(bh),
            rd: bl,
        },
        0x09 | 0x19 | 0x1d | 0x64 | 0x65 | 0x66 => I::Alu {
            op: match op {
                0x09 => AluOp::Add,
                0x19 => AluOp::Sub,
                0x1d => AluOp::Cmp,
                0x64 => AluOp::Or,
                0x65 => AluOp::Xor,
                _ => AluOp::And,
            },
            size: Size::Word,
            src: O::Reg(bh),
            rd: bl,
        },
        0x0c => I::Mov {
            size: Size::Byte,
            src: O::Reg(bh),
            dst: O::Reg(bl),
        },
        0x0d => I::Mov {
            size: Size::Word,
            src: O::Reg(bh),
            dst: O::Reg(bl),
        },
        0x14 | 0x15 | 0x16 | 0x18 | 0x1c | 0x1e => I::Alu {
            op: match op {
                0x14 => AluOp::Or,
                0x15 => AluOp::Xor,
                0x16 => AluOp::And,
                0x18 => AluOp::Sub,
                0x1c => AluOp::Cmp,
                _ => AluOp::Subx,
            },
            size: Size::Byte,
            src: O::Reg(bh),
            rd: bl,
        },
        _ => return Err(Stop::Undefined),
    };
    Ok(instr)
}

/// Decodes the opcodes that come in pairs, H'0x adding and H'1x subtracting: INC/DEC
/// (and longword ADD/SUB), ADDS/SUBS (and INC/DEC word and long), DAA/DAS (and longword MOV
/// and CMP).
fn decode_add_sub_pairs(op: u8, b1: u8) -> Result<Instr, Stop> {
    let (bh, bl) = (hi4(b1), lo4(b1));
    use Instr as I;
    use Operand as O;
    let instr = match op {
        0x0a | 0x1a => {
            if bh == 0 {
                if op == 0x0a {
                    I::Inc {
                        size: Size::Byte,
                        amount: 1,
                        rd: bl,
                    }
                } else {
                    I::Dec {
                        size: Size::Byte,
                        amount: 1,
                        rd: bl,
                    }
                }
            } else {
                expect(bh & 8 != 0)?;
                I::Alu {
                    op: if op == 0x0a { AluOp::Add } else { AluOp::Sub },
                    size: Size::Long,
                    src: O::Reg(bh & 7),
                    rd: r3(bl)?,
                }
            }
        }
        0x0b | 0x1b => {
            let inc = op == 0x0b;
            match bh {
                0x0 | 0x8 | 0x9 => {
                    let amount = match bh {
                        0x0 => 1,
                        0x8 => 2,
                        _ => 4,
                    };
                    let rd = r3(bl)?;
                    if inc {
                        I::Adds { amount, rd }
                    } else {
                        I::Subs { amount, rd }
                    }
                }
                0x5 | 0xd | 0x7 | 0xf => {
                    let amount = if bh & 8 == 0 { 1 } else { 2 };
                    let (size, rd) = if bh & 2 == 0 {
                        (Size::Word, bl)
                    } else {
                        (Size::Long, r3(bl)?)
                    };
                    if inc {
                        I::Inc { size, amount, rd }
                    } else {
                        I::Dec { size, amount, rd }
                    }
                }
                _ => return Err(Stop::Undefined),
            }
        }
        0x0f | 0x1f => {
            if bh == 0 {
                if op == 0x0f { I::Daa(bl) } else { I::Das(bl) }
            } else {
                expect(bh & 8 != 0)?;
                let rs = bh & 7;
                let rd = r3(bl)?;
                if op == 0x0f {
                    I::Mov {
                        size: Size::Long,
                        src: O::Reg(rs),
                        dst: O::Reg(rd),
                    }
                } else {
                    I::Alu {
                        op: AluOp::Cmp,
                        size: Size::Long,
                        src: O::Reg(rs),
                        rd,
                    }
                }
            }
        }
        _ => return Err(Stop::Undefined),
    };
    Ok(instr)
}

/// Decodes shifts and rotates (H'10-H'13) and the one-operand group H'17 (NOT, NEG, EXTU,
/// EXTS).
fn decode_shift_unary(op: u8, b1: u8) -> Result<Instr, Stop> {
    let (bh, bl) = (hi4(b1), lo4(b1));
    use Instr as I;
    let instr = match op {
        0x10..=0x13 => {
            // Shifts and rotates: op 10 = shll/shal, 11 = shlr/shar, 12 = rotxl/rotl,
            // 13 = rotxr/rotr; b1 high nibble: 0/1/3 = logical-or-through-carry .b/.w/.l,
            // 8/9/b = arithmetic-or-plain-rotate .b/.w/.l.
            let alt = bh & 8 != 0;
            let size = match bh & 7 {
                0 => Size::Byte,
                1 => Size::Word,
                3 => Size::Long,
                _ => return Err(Stop::Undefined),
            };
            let rd = if size == Size::Long { r3(bl)? } else { bl };
            let uop = match (op, alt) {
                (0x10, false) => UnaryOp::Shll,
                (0x10, true) => UnaryOp::Shal,
                (0x11, false) => UnaryOp::Shlr,
                (0x11, true) => UnaryOp::Shar,
                (0x12, false) => UnaryOp::Rotxl,
                (0x12, true) => UnaryOp::Rotl,
                (0x13, false) => UnaryOp::Rotxr,
                _ => UnaryOp::Rotr,
            };
            I::Unary { op: uop, size, rd }
        }
        0x17 => {
            let (uop, size) = match bh {
                0x0 => (UnaryOp::Not, Size::Byte),
                0x1 => (UnaryOp::Not, Size::Word),
                0x3 => (UnaryOp::Not, Size::Long),
                0x5 => (UnaryOp::Extu, Size::Word),
                0x7 => (UnaryOp::Extu, Size::Long),
                0x8 => (UnaryOp::Neg, Size::Byte),
                0x9 => (UnaryOp::Neg, Size::Word),
                0xb => (UnaryOp::Neg, Size::Long),
                0xd => (UnaryOp::Exts, Size::Word),
                0xf => (UnaryOp::Exts, Size::Long),
                _ => return Err(Stop::Undefined),
            };
            let rd = if size == Size::Long { r3(bl)? } else { bl };
            I::Unary { op: uop, size, rd }
        }
        _ => return Err(Stop::Undefined),
    };
    Ok(instr)
}

/// Decodes H'5x: MULXU/DIVXU, RTS/RTE/TRAPA, BSR, the 16-bit-displacement branches, JMP and
/// JSR.
fn decode_branch_muldiv<S: WordSource>(
    r: &mut Reader<'_, S>,
    op: u8,
    b1: u8,
) -> Result<Instr, Stop> {
    let (bh, bl) = (hi4(b1), lo4(b1));
    use Instr as I;
    let instr = match op {
        0x50 | 0x51 => I::MulDiv {
            op: if op == 0x50 {
                MulDivOp::Mulxu
            } else {
                MulDivOp::Divxu
            },
            size: Size::Byte,
            rs: bh,
            rd: bl,
        },
        0x52 | 0x53 => I::MulDiv {
            op: if op == 0x52 {
                MulDivOp::Mulxu
            } else {
                MulDivOp::Divxu
            },
            size: Size::Word,
            rs: bh,
            rd: r3(bl)?,
        },
        0x54 => {
            expect(b1 == 0x70)?;
            I::Rts
        }
        0x55 => I::Bsr {
            disp: i16::from(b1 as i8),
            long: false,
        },
        0x56 => {
            expect(b1 == 0x70)?;
            I::Rte
        }
        0x57 => {
            expect(b1 & 0xcf == 0)?;
            I::Trapa(bh & 3)
        }
        0x58 => {
            expect(bl == 0)?;
            let d = r.word()?;
            I::Bcc {
                cond: bh,
                disp: d as i16,
                long: true,
            }
        }
        0x59 | 0x5d => {
            expect(bl == 0)?;
            let t = JumpTarget::Reg(r3(bh)?);
            if op == 0x59 { I::Jmp(t) } else { I::Jsr(t) }
        }
        0x5a | 0x5e => {
            let lo = r.word()?;
            let t = JumpTarget::Abs24((u32::from(b1) << 16) | u32::from(lo));
            if op == 0x5a { I::Jmp(t) } else { I::Jsr(t) }
        }
        0x5b | 0x5f => {
            let t = JumpTarget::MemInd(b1);
            if op == 0x5b { I::Jmp(t) } else { I::Jsr(t) }
        }
        0x5c => {
            expect(b1 == 0)?;
            let d = r.word()?;
            I::Bsr {
                disp: d as i16,
                long: true,
            }
        }
        _ => return Err(Stop::Undefined),
    };
    Ok(instr)
}

/// Decodes H'6x-H'7x: bit manipulation, MOV between registers and memory, MOV and ALU
/// operations with immediates, EEPMOV.
fn decode_bit_mov<S: WordSource>(r: &mut Reader<'_, S>, op: u8, b1: u8) -> Result<Instr, Stop> {
    let (bh, bl) = (hi4(b1), lo4(b1));
    use Instr as I;
    let instr = match op {
        0x60..=0x63 => I::Bit {
            op: match op {
                0x60 => BitOp::Bset,
                0x61 => BitOp::Bnot,
                0x62 => BitOp::Bclr,
                _ => BitOp::Btst,
            },
            bit: BitNum::Reg(bh),
            target: BitTarget::Reg(bl),
        },
        0x67 | 0x70..=0x77 => I::Bit {
            op: bit_op_imm(op, bh & 8 != 0)?,
            bit: BitNum::Imm(bh & 7),
            target: BitTarget::Reg(bl),
        },
        0x68..=0x6f | 0x78 => {
            if op == 0x6a && bh & 7 == 4 {
                let addr = r.word()?;
                return Ok(if bh & 8 == 0 {
                    I::Movfpe { addr, rd: bl }
                } else {
                    I::Movtpe { rs: bl, addr }
                });
            }
            let m = mem_form(r, Family::MovBw, op, b1)?;
            mov_dir(m.size, m.store, m.mem, m.reg)
        }
        0x79 => {
            let imm = u32::from(r.word()?);
            imm_op(bh, Size::Word, imm, bl)?
        }
        0x7a => {
            let rd = r3(bl)?;
            let imm = r.long()?;
            imm_op(bh, Size::Long, imm, rd)?
        }
        0x7b => {
            let w1 = r.word()?;
            match (b1, w1) {
                (0x5c, 0x598f) => I::Eepmov { word: false },
                (0xd4, 0x598f) => I::Eepmov { word: true },
                _ => return Err(Stop::Undefined),
            }
        }
        0x7c..=0x7f => {
            let target = if op <= 0x7d {
                expect(bl == 0)?;
                BitTarget::Ind(r3(bh)?)
            } else {
                BitTarget::Abs8(b1)
            };
            let w1 = r.word()?;
            let [op2, c1] = w1.to_be_bytes();
            expect(lo4(c1) == 0)?;
            let (ch, reads) = (hi4(c1), op & 1 == 0);
            let (bop, bit) = match op2 {
                0x63 if reads => (BitOp::Btst, BitNum::Reg(ch)),
                0x73..=0x77 if reads => (bit_op_imm(op2, ch & 8 != 0)?, BitNum::Imm(ch & 7)),
                0x60..=0x62 if !reads => (
                    match op2 {
                        0x60 => BitOp::Bset,
                        0x61 => BitOp::Bnot,
                        _ => BitOp::Bclr,
                    },
                    BitNum::Reg(ch),
                ),
                0x67 | 0x70..=0x72 if !reads => {
                    (bit_op_imm(op2, ch & 8 != 0)?, BitNum::Imm(ch & 7))
                }
                _ => return Err(Stop::Undefined),
            };
            if matches!(op2, 0x70..=0x73) {
                expect(ch & 8 == 0)?;
            }
            I::Bit {
                op: bop,
                bit,
                target,
            }
        }
        _ => return Err(Stop::Undefined),
    };
    Ok(instr)
}

fn alu_imm8(op: AluOp, opcode: u8, imm: u8) -> Instr {
    Instr::Alu {
        op,
        size: Size::Byte,
        src: Operand::Imm(u32::from(imm)),
        rd: opcode & 0xf,
    }
}

/// `79 xr` / `7A xr` immediate forms: x selects MOV, ADD, CMP, SUB, OR, XOR, AND.
fn imm_op(sel: u8, size: Size, imm: u32, rd: u8) -> Result<Instr, Stop> {
    let src = Operand::Imm(imm);
    let op = match sel {
        0 => {
            return Ok(Instr::Mov {
                size,
                src,
                dst: Operand::Reg(rd),
            });
        }
        1 => AluOp::Add,
        2 => AluOp::Cmp,
        3 => AluOp::Sub,
        4 => AluOp::Or,
        5 => AluOp::Xor,
        6 => AluOp::And,
        _ => return Err(Stop::Undefined),
    };
    Ok(Instr::Alu { op, size, src, rd })
}

/// The instructions that share the MOV family's memory forms (Table A-2's rows 68–6F and 78):
/// the same address modes, encoded the same way, with these differences.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Family {
    /// MOV.B and MOV.W: opcodes 68–6F (bit 0 set for words), and 78 followed by 6A or 6B for
    /// `@(d:24,ERs)`; the data register is any of 0–15.
    MovBw,
    /// MOV.L after its 01 00 prefix word: the word opcodes only; the data register is an ERn
    /// (checked by the caller). In the 78 form, GNU as repeats the direction bit in bit 7 of
    /// the register byte (78 1sss 0000), and the two must agree.
    MovL,
    /// LDC/STC after the 01 40 prefix word: the word opcodes only; the register field is 0
    /// (checked by the caller for the word it decodes, here for the 78 form's second word).
    Ccr,
}

/// A memory operand decoded from a MOV-family word, with what the word says around it.
struct MemForm {
    /// The operand size the opcode selects (byte or word; MOV.L and LDC/STC set their own).
    size: Size,
    /// The memory operand.
    mem: Operand,
    /// The direction bit: register to memory.
    store: bool,
    /// The data register field (4 bits, unchecked unless the family requires it).
    reg: u8,
}

/// Decodes the memory operand of the MOV-family word `op c` (`c` = direction bit and address
/// register in the high nibble, data register in the low one), pulling the words of its
/// displacement or address: the one decoder of these forms for MOV.B/W, MOV.L and LDC/STC.
/// (MOVFPE/MOVTPE, which share row 6A, are the caller's.)
fn mem_form<S: WordSource>(
    r: &mut Reader<'_, S>,
    family: Family,
    op: u8,
    c: u8,
) -> Result<MemForm, Stop> {
    use Operand as O;
    let (ch, cl) = (hi4(c), lo4(c));
    let (ers, store) = (ch & 7, ch & 8 != 0);
    let word_only = family != Family::MovBw;
    let size = if op & 1 == 0 { Size::Byte } else { Size::Word };
    if word_only && op != 0x78 && size == Size::Byte {
        return Err(Stop::Undefined);
    }
    let mem = match op {
        0x68 | 0x69 => O::Ind(ers),
        0x6c | 0x6d => {
            if store {
                O::PreDec(ers)
            } else {
                O::PostInc(ers)
            }
        }
        0x6e | 0x6f => O::Disp16(ers, r.word()?),
        0x6a | 0x6b => match ers {
            0 => O::Abs16(r.word()?),
            2 => O::Abs24(r.long()?),
            _ => return Err(Stop::Undefined),
        },
        0x78 => {
            // 78 s0 + 6A/6B [2|A]r + the 32-bit displacement.
            expect(cl == 0)?;
            if family != Family::MovL {
                expect(ch & 8 == 0)?;
            }
            let [op2, c2] = r.word()?.to_be_bytes();
            let size = match op2 {
                0x6a if !word_only => Size::Byte,
                0x6b => Size::Word,
                _ => return Err(Stop::Undefined),
            };
            expect(hi4(c2) & 7 == 2)?;
            let store = hi4(c2) & 8 != 0;
            match family {
                Family::MovL => expect(store == (ch & 8 != 0))?,
                Family::Ccr => expect(lo4(c2) == 0)?,
                Family::MovBw => {}
            }
            let d = r.long()?;
            return Ok(MemForm {
                size,
                mem: O::Disp24(ers, d),
                store,
                reg: lo4(c2),
            });
        }
        _ => return Err(Stop::Undefined),
    };
    Ok(MemForm {
        size,
        mem,
        store,
        reg: cl,
    })
}

/// A MOV between register `reg` and memory operand `mem`; `store` is the direction bit.
fn mov_dir(size: Size, store: bool, mem: Operand, reg: u8) -> Instr {
    if store {
        Instr::Mov {
            size,
            src: Operand::Reg(reg),
            dst: mem,
        }
    } else {
        Instr::Mov {
            size,
            src: mem,
            dst: Operand::Reg(reg),
        }
    }
}

/// The bit operation of opcodes 67 and 70–77 (`inv` is bit 7 of the following byte).
fn bit_op_imm(op: u8, inv: bool) -> Result<BitOp, Stop> {
    Ok(match (op, inv) {
        (0x67, false) => BitOp::Bst,
        (0x67, true) => BitOp::Bist,
        (0x70, false) => BitOp::Bset,
        (0x71, false) => BitOp::Bnot,
        (0x72, false) => BitOp::Bclr,
        (0x73, false) => BitOp::Btst,
        (0x74, false) => BitOp::Bor,
        (0x74, true) => BitOp::Bior,
        (0x75, false) => BitOp::Bxor,
        (0x75, true) => BitOp::Bixor,
        (0x76, false) => BitOp::Band,
        (0x76, true) => BitOp::Biand,
        (0x77, false) => BitOp::Bld,
        (0x77, true) => BitOp::Bild,
        _ => return Err(Stop::Undefined),
    })
}

/// Instructions with the 01 prefix byte.
fn decode_01<S: WordSource>(r: &mut Reader<'_, S>, b1: u8) -> Result<Instr, Stop> {
    use Instr as I;
    use Operand as O;
    match b1 {
        0x00 => {
            // MOV.L with memory operands: 01 00 + a MOV.W-like word.
            let [op, c1] = r.word()?.to_be_bytes();
            let m = mem_form(r, Family::MovL, op, c1)?;
            Ok(mov_dir(Size::Long, m.store, m.mem, r3(m.reg)?))
        }
        0x40 => {
            // LDC/STC with memory operands: 01 40 + a MOV.W-like word whose register field is 0.
            let [op, c1] = r.word()?.to_be_bytes();
            expect(lo4(c1) == 0)?;
            let m = mem_form(r, Family::Ccr, op, c1)?;
            Ok(if m.store {
                I::Stc(m.mem)
            } else {
                I::Ldc(m.mem)
            })
        }
        0x80 => Ok(I::Sleep),
        0xc0 | 0xd0 => {
            let w1 = r.word()?;
            let [op, c1] = w1.to_be_bytes();
            let (ch, cl) = (hi4(c1), lo4(c1));
            let (mop, size, rd) = match (b1, op) {
                (0xc0, 0x50) => (MulDivOp::Mulxs, Size::Byte, cl),
                (0xc0, 0x52) => (MulDivOp::Mulxs, Size::Word, r3(cl)?),
                (0xd0, 0x51) => (MulDivOp::Divxs, Size::Byte, cl),
                (0xd0, 0x53) => (MulDivOp::Divxs, Size::Word, r3(cl)?),
                _ => return Err(Stop::Undefined),
            };
            Ok(I::MulDiv {
                op: mop,
                size,
                rs: ch,
                rd,
            })
        }
        0xf0 => {
            let w1 = r.word()?;
            let [op, c1] = w1.to_be_bytes();
            let aop = match op {
                0x64 => AluOp::Or,
                0x65 => AluOp::Xor,
                0x66 => AluOp::And,
                _ => return Err(Stop::Undefined),
            };
            Ok(I::Alu {
                op: aop,
                size: Size::Long,
                src: O::Reg(r3(hi4(c1))?),
                rd: r3(lo4(c1))?,
            })
        }
        _ => Err(Stop::Undefined),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_of_some_forms() {
        let cases: &[(&[u8], u8)] = &[
            (&[0x00, 0x00], 1),
            (&[0x7a, 0x04, 0x12, 0x34, 0x56, 0x78], 3),
            (
                &[0x01, 0x00, 0x78, 0x20, 0x6b, 0x25, 0x00, 0x12, 0x34, 0x56],
                5,
            ),
            (&[0x7b, 0x5c, 0x59, 0x8f], 2),
            (&[0x5e, 0x00, 0x12, 0x34], 2),
        ];
        for (bytes, words) in cases {
            assert_eq!(decode_bytes(bytes).unwrap().words, *words, "{bytes:02x?}");
        }
    }

    #[test]
    fn undefined_and_truncated_are_errors() {
        assert!(matches!(
            decode_bytes(&[0x00, 0x01]),
            Err(DecodeError::Undefined { .. })
        ));
        assert!(matches!(
            decode_bytes(&[0x7a, 0x04, 0x12]),
            Err(DecodeError::Truncated { .. })
        ));
        assert!(matches!(
            decode_bytes(&[]),
            Err(DecodeError::Truncated { .. })
        ));
    }
}
