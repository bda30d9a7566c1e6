//! A disassembler whose text has the form `h8300-hms-objdump -d` (GNU binutils 2.16.1) prints for
//! H8/300H code: mnemonic, a tab, operands separated by commas, lower-case hexadecimal with
//! `0x`, and objdump's own quirks (24-bit displacements and MOV absolute addresses shown with
//! `:32`, `jmp @@aa:8` in decimal, branch targets as `.+d (0xtarget)`).
//!
//! The form is checked against objdump itself by `tests/objdump_compare.rs`.

use std::fmt::Write as _;

use super::decode::{
    AluOp, BitNum, BitOp, BitTarget, Decoded, Instr, JumpTarget, MulDivOp, Operand, Size, UnaryOp,
    WordSource, decode,
};

const BYTE_REGS: [&str; 16] = [
    "r0h", "r1h", "r2h", "r3h", "r4h", "r5h", "r6h", "r7h", "r0l", "r1l", "r2l", "r3l", "r4l",
    "r5l", "r6l", "r7l",
];
const WORD_REGS: [&str; 16] = [
    "r0", "r1", "r2", "r3", "r4", "r5", "r6", "r7", "e0", "e1", "e2", "e3", "e4", "e5", "e6", "e7",
];
const LONG_REGS: [&str; 8] = ["er0", "er1", "er2", "er3", "er4", "er5", "er6", "er7"];

/// Branch condition mnemonics in the order of the condition field.
const BCC: [&str; 16] = [
    "bra", "brn", "bhi", "bls", "bcc", "bcs", "bne", "beq", "bvc", "bvs", "bpl", "bmi", "bge",
    "blt", "bgt", "ble",
];

/// The name of register `r` for operand size `size`.
#[must_use]
pub fn reg_name(size: Size, r: u8) -> &'static str {
    match size {
        Size::Byte => BYTE_REGS[usize::from(r & 15)],
        Size::Word => WORD_REGS[usize::from(r & 15)],
        Size::Long => LONG_REGS[usize::from(r & 7)],
    }
}

fn er(r: u8) -> &'static str {
    LONG_REGS[usize::from(r & 7)]
}

fn operand(out: &mut String, size: Size, op: Operand) {
    // Writing to a String cannot fail.
    let _ = match op {
        Operand::Reg(r) => write!(out, "{}", reg_name(size, r)),
        Operand::Imm(v) => write!(out, "#0x{v:x}"),
        Operand::Ind(r) => write!(out, "@{}", er(r)),
        Operand::PostInc(r) => write!(out, "@{}+", er(r)),
        Operand::PreDec(r) => write!(out, "@-{}", er(r)),
        Operand::Disp16(r, d) => write!(out, "@(0x{d:x}:16,{})", er(r)),
        Operand::Disp24(r, d) => write!(out, "@(0x{d:x}:32,{})", er(r)),
        Operand::Abs8(a) => write!(out, "@0x{a:x}:8"),
        Operand::Abs16(a) => write!(out, "@0x{a:x}:16"),
        Operand::Abs24(a) => write!(out, "@0x{a:x}:32"),
    };
}

fn branch(out: &mut String, next: u32, disp: i16) {
    let target = next.wrapping_add(disp as i32 as u32);
    let _ = if disp > 0 {
        write!(out, ".+{disp} (0x{target:x})")
    } else {
        write!(out, ".{disp} (0x{target:x})")
    };
}

fn bit_target(out: &mut String, t: BitTarget) {
    let _ = match t {
        BitTarget::Reg(r) => write!(out, "{}", BYTE_REGS[usize::from(r & 15)]),
        BitTarget::Ind(r) => write!(out, "@{}", er(r)),
        BitTarget::Abs8(a) => write!(out, "@0x{a:x}:8"),
    };
}

fn jump_target(out: &mut String, t: JumpTarget) {
    let _ = match t {
        JumpTarget::Reg(r) => write!(out, "@{}", er(r)),
        JumpTarget::Abs24(a) => write!(out, "@0x{a:x}:24"),
        JumpTarget::MemInd(a) => write!(out, "@@{a} (0x{a:x})"),
    };
}

fn mov(s: &mut String, size: Size, src: Operand, dst: Operand) {
    let _ = write!(s, "mov.{}\t", size.suffix());
    operand(s, size, src);
    s.push(',');
    operand(s, size, dst);
}

/// A two-operand ALU operation (ADDX and SUBX have no size suffix).
fn alu(s: &mut String, op: AluOp, size: Size, src: Operand, rd: u8) {
    if matches!(op, AluOp::Addx | AluOp::Subx) {
        let _ = write!(s, "{}\t", op.mnemonic());
    } else {
        let _ = write!(s, "{}.{}\t", op.mnemonic(), size.suffix());
    }
    operand(s, size, src);
    let _ = write!(s, ",{}", reg_name(size, rd));
}

/// INC or DEC (`mnemonic`); the byte form is `byte_form Rd`, without the amount.
fn inc_dec(s: &mut String, mnemonic: &str, byte_form: &str, size: Size, amount: u8, rd: u8) {
    if size == Size::Byte {
        let _ = write!(s, "{byte_form}\t{}", reg_name(size, rd));
    } else {
        let _ = write!(
            s,
            "{mnemonic}.{}\t#{amount},{}",
            size.suffix(),
            reg_name(size, rd)
        );
    }
}

fn unary(s: &mut String, op: UnaryOp, size: Size, rd: u8) {
    let _ = write!(
        s,
        "{}.{}\t{}",
        op.mnemonic(),
        size.suffix(),
        reg_name(size, rd)
    );
}

/// MULXU/MULXS/DIVXU/DIVXS: the destination is twice the source's size.
fn muldiv(s: &mut String, op: MulDivOp, size: Size, rs: u8, rd: u8) {
    let dsize = if size == Size::Byte {
        Size::Word
    } else {
        Size::Long
    };
    let _ = write!(
        s,
        "{}.{}\t{},{}",
        op.mnemonic(),
        size.suffix(),
        reg_name(size, rs),
        reg_name(dsize, rd)
    );
}

fn bit_instr(s: &mut String, op: BitOp, num: BitNum, target: BitTarget) {
    let _ = write!(s, "{}\t", op.mnemonic());
    let _ = match num {
        BitNum::Imm(n) => write!(s, "#0x{n:x}"),
        BitNum::Reg(r) => write!(s, "{}", reg_name(Size::Byte, r)),
    };
    s.push(',');
    bit_target(s, target);
}

/// The objdump text of `d`, an instruction at address `addr` (used for branch targets).
///
/// ```
/// use h8300h::cpu::decode::decode_bytes;
/// use h8300h::cpu::disasm::format_instr;
/// assert_eq!(format_instr(decode_bytes(&[0xF8, 0x2A]).unwrap(), 0x100), "mov.b\t#0x2a,r0l");
/// // A branch shows its target.
/// assert_eq!(format_instr(decode_bytes(&[0x40, 0x10]).unwrap(), 0x100), "bra\t.+16 (0x112)");
/// ```
#[must_use]
pub fn format_instr(d: Decoded, addr: u32) -> String {
    let mut out = String::with_capacity(32);
    let next = addr.wrapping_add(d.len_bytes());
    let s = &mut out;
    match d.instr {
        Instr::Nop => s.push_str("nop\t"),
        Instr::Sleep => s.push_str("sleep\t"),
        Instr::Rts => s.push_str("rts\t"),
        Instr::Rte => s.push_str("rte\t"),
        Instr::Mov { size, src, dst } => mov(s, size, src, dst),
        Instr::Movfpe { addr, rd } => {
            let _ = write!(s, "movfpe\t@0x{addr:x}:16,{}", reg_name(Size::Byte, rd));
        }
        Instr::Movtpe { rs, addr } => {
            let _ = write!(s, "movtpe\t{},@0x{addr:x}:16", reg_name(Size::Byte, rs));
        }
        Instr::Alu { op, size, src, rd } => alu(s, op, size, src, rd),
        // objdump 2.16.1 prints INC.B without its suffix but DEC.B with it.
        Instr::Inc { size, amount, rd } => inc_dec(s, "inc", "inc", size, amount, rd),
        Instr::Dec { size, amount, rd } => inc_dec(s, "dec", "dec.b", size, amount, rd),
        Instr::Adds { amount, rd } => {
            let _ = write!(s, "adds\t#{amount},{}", er(rd));
        }
        Instr::Subs { amount, rd } => {
            let _ = write!(s, "subs\t#{amount},{}", er(rd));
        }
        Instr::Unary { op, size, rd } => unary(s, op, size, rd),
        Instr::Daa(r) => {
            let _ = write!(s, "daa\t{}", reg_name(Size::Byte, r));
        }
        Instr::Das(r) => {
            let _ = write!(s, "das\t{}", reg_name(Size::Byte, r));
        }
        Instr::MulDiv { op, size, rs, rd } => muldiv(s, op, size, rs, rd),
        Instr::Bit { op, bit, target } => bit_instr(s, op, bit, target),
        Instr::Bcc { cond, disp, .. } => {
            let _ = write!(s, "{}\t", BCC[usize::from(cond & 15)]);
            branch(s, next, disp);
        }
        Instr::Bsr { disp, .. } => {
            s.push_str("bsr\t");
            branch(s, next, disp);
        }
        Instr::Jmp(t) => {
            s.push_str("jmp\t");
            jump_target(s, t);
        }
        Instr::Jsr(t) => {
            s.push_str("jsr\t");
            jump_target(s, t);
        }
        Instr::Trapa(n) => {
            let _ = write!(s, "trapa\t#0x{n:x}");
        }
        Instr::Eepmov { word } => s.push_str(if word { "eepmov.w\t" } else { "eepmov.b\t" }),
        Instr::Ldc(src) => {
            s.push_str("ldc\t");
            operand(s, Size::Byte, src);
            s.push_str(",ccr");
        }
        Instr::Stc(dst) => {
            s.push_str("stc\tccr,");
            operand(s, Size::Byte, dst);
        }
        Instr::Andc(v) => {
            let _ = write!(s, "andc\t#0x{v:x},ccr");
        }
        Instr::Orc(v) => {
            let _ = write!(s, "orc\t#0x{v:x},ccr");
        }
        Instr::Xorc(v) => {
            let _ = write!(s, "xorc\t#0x{v:x},ccr");
        }
    }
    out
}

/// One disassembled instruction of a listing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Line {
    /// Address of the first byte.
    pub addr: u32,
    /// The instruction's bytes (for an undecodable word: that word).
    pub bytes: Vec<u8>,
    /// The text (objdump's form); `None` where the bytes are no instruction.
    pub text: Option<String>,
}

/// Disassembles a byte slice loaded at `base`, one [`Line`] per instruction. Bytes that decode
/// to no instruction become one line per word with `text: None` (and a trailing odd byte one
/// line of its own), as objdump steps over them.
///
/// ```
/// let lines = h8300h::cpu::disasm::disassemble(&[0xF8, 0x2A, 0x01, 0x80], 0x100);
/// let text: Vec<_> = lines.iter().map(|l| (l.addr, l.text.clone().unwrap())).collect();
/// // objdump writes a tab after every mnemonic, with operands or without.
/// assert_eq!(text, [(0x100, "mov.b\t#0x2a,r0l".to_string()), (0x102, "sleep\t".to_string())]);
/// ```
#[must_use]
pub fn disassemble(bytes: &[u8], base: u32) -> Vec<Line> {
    let mut lines = Vec::new();
    let mut pos = 0usize;
    while pos < bytes.len() {
        let addr = base.wrapping_add(pos as u32);
        let rest = &bytes[pos..];
        let mut src = super::decode::SliceSource::new(rest);
        match decode(&mut src) {
            Ok(d) => {
                let n = d.len_bytes() as usize;
                lines.push(Line {
                    addr,
                    bytes: rest[..n].to_vec(),
                    text: Some(format_instr(d, addr)),
                });
                pos += n;
            }
            Err(_) => {
                let n = rest.len().min(2);
                lines.push(Line {
                    addr,
                    bytes: rest[..n].to_vec(),
                    text: None,
                });
                pos += n;
            }
        }
    }
    lines
}

/// Formats a [`Line`] the way `objdump -d` lays it out: address, up to four bytes per row,
/// then the text; longer instructions continue on rows of their own.
#[must_use]
pub fn objdump_layout(line: &Line) -> String {
    let mut out = String::new();
    for (row, chunk) in line.bytes.chunks(4).enumerate() {
        let a = line.addr.wrapping_add(4 * row as u32);
        let _ = write!(out, "{a:6x}:\t");
        for b in chunk {
            let _ = write!(out, "{b:02x} ");
        }
        if row == 0 {
            for _ in chunk.len()..4 {
                out.push_str("   ");
            }
            out.push('\t');
            out.push_str(line.text.as_deref().unwrap_or(".word"));
        }
        out.push('\n');
    }
    out
}

/// A [`WordSource`] that counts nothing and serves a fixed array (used by the trace writer).
#[derive(Clone, Debug)]
pub struct ArraySource {
    words: [u16; 5],
    pos: usize,
}

impl ArraySource {
    /// Serves `words` in order.
    #[must_use]
    pub const fn new(words: [u16; 5]) -> Self {
        ArraySource { words, pos: 0 }
    }
}

impl WordSource for ArraySource {
    fn next_word(&mut self) -> Option<u16> {
        let w = *self.words.get(self.pos)?;
        self.pos += 1;
        Some(w)
    }
}
