//! The disassembler against the outside oracle: `h8300-hms-objdump -d` (GNU binutils 2.16.1).
//!
//! A generator writes an assembler source with every H8/300H instruction × size × addressing
//! mode the assembler accepts (registers and a spread of immediates, displacements and
//! addresses), `h8300-hms-as` assembles it, `h8300-hms-ld` links it (so branch and absolute
//! operands are resolved), `h8300-hms-objdump -d` disassembles it, and every objdump line is
//! compared with this crate's disassembler on the same bytes: same length, same text.
//!
//! Runs when `h8300-hms-as` is on PATH; otherwise prints that it was skipped (CI installs the
//! Debian packages `binutils-h8300-hms`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use h8300h::cpu::decode::decode_bytes;
use h8300h::cpu::disasm::format_instr;

const BYTE_REGS: [&str; 16] = [
    "r0h", "r1h", "r2h", "r3h", "r4h", "r5h", "r6h", "r7h", "r0l", "r1l", "r2l", "r3l", "r4l",
    "r5l", "r6l", "r7l",
];
const WORD_REGS: [&str; 16] = [
    "r0", "r1", "r2", "r3", "r4", "r5", "r6", "r7", "e0", "e1", "e2", "e3", "e4", "e5", "e6", "e7",
];
const LONG_REGS: [&str; 8] = ["er0", "er1", "er2", "er3", "er4", "er5", "er6", "er7"];

const IMM8: [u32; 6] = [0, 1, 0x0f, 0x7f, 0x80, 0xff];
const IMM16: [u32; 6] = [0, 1, 0x1234, 0x7fff, 0x8000, 0xffff];
const IMM32: [u32; 7] = [
    0,
    1,
    0xff,
    0x1234_5678,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
];
const DISP16: [&str; 5] = ["0", "2", "0x7ffe", "-2", "-0x8000"];
const DISP24: [&str; 5] = ["0", "0x10", "0x123456", "0x7ffffe", "-2"];
const ABS8: [u32; 4] = [0x00, 0x20, 0x7f, 0xff];
const ABS16: [u32; 5] = [0, 0x1234, 0x7fff, 0x8000, 0xffff];
const ABS24: [u32; 6] = [0, 0x1234, 0x7_ffff, 0xff_df10, 0xff_ff00, 0xff_ffff];

fn regs(size: char) -> Vec<&'static str> {
    match size {
        'b' => BYTE_REGS.to_vec(),
        'w' => WORD_REGS.to_vec(),
        _ => LONG_REGS.to_vec(),
    }
}

/// A spread of register pairs: every register as source and as destination at least once.
fn pairs(size: char) -> Vec<(&'static str, &'static str)> {
    let r = regs(size);
    let n = r.len();
    (0..n)
        .map(|i| (r[i], r[(i * 5 + 3) % n]))
        .collect::<Vec<_>>()
}

fn imms(size: char) -> Vec<u32> {
    match size {
        'b' => IMM8.to_vec(),
        'w' => IMM16.to_vec(),
        _ => IMM32.to_vec(),
    }
}

/// The assembler source with every form.
fn generate() -> String {
    let mut s = String::from("\t.h8300h\n\t.text\n\t.global _start\n_start:\n");
    let l = |s: &mut String, line: String| {
        s.push('\t');
        s.push_str(&line);
        s.push('\n');
    };
    // MOV: register, immediate and every memory mode, both directions.
    for sz in ['b', 'w', 'l'] {
        for (a, b) in pairs(sz) {
            l(&mut s, format!("mov.{sz} {a},{b}"));
        }
        for (i, v) in imms(sz).into_iter().enumerate() {
            let r = regs(sz)[i % regs(sz).len()];
            l(&mut s, format!("mov.{sz} #0x{v:x},{r}"));
        }
        for (i, r) in regs(sz).into_iter().enumerate() {
            let e = LONG_REGS[(i * 3 + 1) % 8];
            let d16 = DISP16[i % DISP16.len()];
            let d24 = DISP24[i % DISP24.len()];
            l(&mut s, format!("mov.{sz} @{e},{r}"));
            l(&mut s, format!("mov.{sz} {r},@{e}"));
            l(&mut s, format!("mov.{sz} @({d16}:16,{e}),{r}"));
            l(&mut s, format!("mov.{sz} {r},@({d16}:16,{e})"));
            l(&mut s, format!("mov.{sz} @({d24}:24,{e}),{r}"));
            l(&mut s, format!("mov.{sz} {r},@({d24}:24,{e})"));
            l(&mut s, format!("mov.{sz} @{e}+,{r}"));
            l(&mut s, format!("mov.{sz} {r},@-{e}"));
            let a16 = ABS16[i % ABS16.len()];
            let a24 = ABS24[i % ABS24.len()];
            l(&mut s, format!("mov.{sz} @0x{a16:x}:16,{r}"));
            l(&mut s, format!("mov.{sz} {r},@0x{a16:x}:16"));
            l(&mut s, format!("mov.{sz} @0x{a24:x}:24,{r}"));
            l(&mut s, format!("mov.{sz} {r},@0x{a24:x}:24"));
            if sz == 'b' {
                let a8 = ABS8[i % ABS8.len()];
                l(&mut s, format!("mov.b @0x{:x}:8,{r}", 0xff_ff00 | a8));
                l(&mut s, format!("mov.b {r},@0x{:x}:8", 0xff_ff00 | a8));
            }
        }
    }
    for r in WORD_REGS.iter().take(8) {
        l(&mut s, format!("push.w {r}"));
        l(&mut s, format!("pop.w {r}"));
    }
    for r in LONG_REGS {
        l(&mut s, format!("push.l {r}"));
        l(&mut s, format!("pop.l {r}"));
    }
    for (i, r) in BYTE_REGS.iter().enumerate() {
        let a = ABS16[i % ABS16.len()];
        l(&mut s, format!("movfpe @0x{a:x}:16,{r}"));
        l(&mut s, format!("movtpe {r},@0x{a:x}:16"));
    }
    // Two-operand arithmetic and logic.
    for op in ["add", "sub", "cmp", "and", "or", "xor"] {
        for sz in ['b', 'w', 'l'] {
            for (a, b) in pairs(sz) {
                l(&mut s, format!("{op}.{sz} {a},{b}"));
            }
            if !(op == "sub" && sz == 'b') {
                for (i, v) in imms(sz).into_iter().enumerate() {
                    let r = regs(sz)[(i * 3) % regs(sz).len()];
                    l(&mut s, format!("{op}.{sz} #0x{v:x},{r}"));
                }
            }
        }
    }
    for op in ["addx", "subx"] {
        for (a, b) in pairs('b') {
            l(&mut s, format!("{op} {a},{b}"));
        }
        for (i, v) in IMM8.into_iter().enumerate() {
            l(&mut s, format!("{op} #0x{v:x},{}", BYTE_REGS[(i * 7) % 16]));
        }
    }
    // INC/DEC/ADDS/SUBS.
    for op in ["inc", "dec"] {
        for r in BYTE_REGS {
            l(&mut s, format!("{op}.b {r}"));
        }
        for n in [1, 2] {
            for r in WORD_REGS {
                l(&mut s, format!("{op}.w #{n},{r}"));
            }
            for r in LONG_REGS {
                l(&mut s, format!("{op}.l #{n},{r}"));
            }
        }
    }
    for op in ["adds", "subs"] {
        for n in [1, 2, 4] {
            for r in LONG_REGS {
                l(&mut s, format!("{op} #{n},{r}"));
            }
        }
    }
    // One-operand operations.
    for op in [
        "neg", "not", "shal", "shar", "shll", "shlr", "rotxl", "rotxr", "rotl", "rotr",
    ] {
        for sz in ['b', 'w', 'l'] {
            for r in regs(sz) {
                l(&mut s, format!("{op}.{sz} {r}"));
            }
        }
    }
    for op in ["exts", "extu"] {
        for r in WORD_REGS {
            l(&mut s, format!("{op}.w {r}"));
        }
        for r in LONG_REGS {
            l(&mut s, format!("{op}.l {r}"));
        }
    }
    for op in ["daa", "das"] {
        for r in BYTE_REGS {
            l(&mut s, format!("{op} {r}"));
        }
    }
    // Multiply and divide.
    for op in ["mulxu", "mulxs", "divxu", "divxs"] {
        for i in 0..16 {
            l(
                &mut s,
                format!("{op}.b {},{}", BYTE_REGS[i], WORD_REGS[(i * 5 + 3) % 16]),
            );
            l(
                &mut s,
                format!("{op}.w {},{}", WORD_REGS[i], LONG_REGS[(i * 3 + 1) % 8]),
            );
        }
    }
    // Bit manipulation: register, @ERd and @aa:8 targets; immediate and register bit numbers.
    let bit_ops = [
        "bset", "bclr", "bnot", "btst", "bld", "bild", "bst", "bist", "band", "biand", "bor",
        "bior", "bxor", "bixor",
    ];
    for op in bit_ops {
        for n in 0..8 {
            let r = BYTE_REGS[(n * 5 + 2) % 16];
            let e = LONG_REGS[(n * 3) % 8];
            let a = 0xff_ff00 | ABS8[n % ABS8.len()];
            l(&mut s, format!("{op} #{n},{r}"));
            l(&mut s, format!("{op} #{n},@{e}"));
            l(&mut s, format!("{op} #{n},@0x{a:x}:8"));
        }
        if matches!(op, "bset" | "bclr" | "bnot" | "btst") {
            for (i, rn) in BYTE_REGS.iter().enumerate() {
                let r = BYTE_REGS[(i * 5 + 2) % 16];
                let e = LONG_REGS[(i * 3) % 8];
                let a = 0xff_ff00 | ABS8[i % ABS8.len()];
                l(&mut s, format!("{op} {rn},{r}"));
                l(&mut s, format!("{op} {rn},@{e}"));
                l(&mut s, format!("{op} {rn},@0x{a:x}:8"));
            }
        }
    }
    // Branches: every condition, both widths, backwards and forwards.
    let conds = [
        "bra", "brn", "bhi", "bls", "bcc", "bcs", "bne", "beq", "bvc", "bvs", "bpl", "bmi", "bge",
        "blt", "bgt", "ble", "bt", "bf", "bhs", "blo",
    ];
    for (i, c) in conds.iter().enumerate() {
        s.push_str(&format!(".Lb{i}:\n"));
        l(&mut s, format!("{c} .Lb{i}:8"));
        l(&mut s, format!("{c} .Lf{i}:8"));
        l(&mut s, format!("{c} .Lb{i}:16"));
        l(&mut s, format!("{c} .Lf{i}:16"));
        l(&mut s, format!("{c} .Lfar:16"));
        s.push_str(&format!(".Lf{i}:\n"));
    }
    // The extreme displacements, as raw words (objdump disassembles them as branches).
    for c in 0..16u32 {
        for w in [
            format!("0x{:x}", 0x4000 | c << 8 | 0x7e),
            format!("0x{:x}", 0x4000 | c << 8 | 0x80),
            format!("0x{:x},0x7ffe", 0x5800 | c << 4),
            format!("0x{:x},0x8000", 0x5800 | c << 4),
        ] {
            l(&mut s, format!(".word {w}"));
        }
    }
    s.push_str(".Lbsr:\n");
    l(&mut s, "bsr .Lbsr:8".into());
    l(&mut s, "bsr .Lbsrf:8".into());
    l(&mut s, "bsr .Lbsr:16".into());
    l(&mut s, "bsr .Lfar:16".into());
    s.push_str(".Lbsrf:\n");
    l(
        &mut s,
        ".word 0x557e,0x5580,0x5c00,0x7ffe,0x5c00,0x8000".into(),
    );
    for op in ["jmp", "jsr"] {
        for r in LONG_REGS {
            l(&mut s, format!("{op} @{r}"));
        }
        for a in ABS24 {
            l(&mut s, format!("{op} @0x{a:x}:24"));
        }
        for a in [0u32, 0x10, 0x80, 0xfc] {
            l(&mut s, format!("{op} @@0x{a:x}:8"));
        }
    }
    // System control.
    for line in ["rts", "rte", "nop", "sleep", "eepmov.b", "eepmov.w"] {
        l(&mut s, line.to_string());
    }
    for n in 0..4 {
        l(&mut s, format!("trapa #{n}"));
    }
    for v in IMM8 {
        l(&mut s, format!("ldc #0x{v:x},ccr"));
        l(&mut s, format!("andc #0x{v:x},ccr"));
        l(&mut s, format!("orc #0x{v:x},ccr"));
        l(&mut s, format!("xorc #0x{v:x},ccr"));
    }
    for r in BYTE_REGS {
        l(&mut s, format!("ldc {r},ccr"));
        l(&mut s, format!("stc ccr,{r}"));
    }
    for (i, e) in LONG_REGS.iter().enumerate() {
        let d16 = DISP16[i % DISP16.len()];
        let d24 = DISP24[i % DISP24.len()];
        let a16 = ABS16[i % ABS16.len()];
        let a24 = ABS24[i % ABS24.len()];
        l(&mut s, format!("ldc @{e},ccr"));
        l(&mut s, format!("stc ccr,@{e}"));
        l(&mut s, format!("ldc @({d16}:16,{e}),ccr"));
        l(&mut s, format!("stc ccr,@({d16}:16,{e})"));
        l(&mut s, format!("ldc @({d24}:24,{e}),ccr"));
        l(&mut s, format!("stc ccr,@({d24}:24,{e})"));
        l(&mut s, format!("ldc @{e}+,ccr"));
        l(&mut s, format!("stc ccr,@-{e}"));
        l(&mut s, format!("ldc @0x{a16:x}:16,ccr"));
        l(&mut s, format!("stc ccr,@0x{a16:x}:16"));
        l(&mut s, format!("ldc @0x{a24:x}:24,ccr"));
        l(&mut s, format!("stc ccr,@0x{a24:x}:24"));
    }
    // A far target for the 16-bit branches.
    l(&mut s, ".space 0x6000".into());
    s.push_str(".Lfar:\n");
    l(&mut s, "nop".into());
    s
}

fn tool(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

fn run(cmd: &Path, args: &[&str], dir: &Path) -> String {
    let out = Command::new(cmd)
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap_or_else(|e| panic!("cannot run {}: {e}", cmd.display()));
    assert!(
        out.status.success(),
        "{} {:?} failed:\n{}",
        cmd.display(),
        args,
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// One instruction as objdump shows it.
struct ObjLine {
    addr: u32,
    bytes: Vec<u8>,
    text: String,
}

fn parse_objdump(listing: &str) -> Vec<ObjLine> {
    let mut out: Vec<ObjLine> = Vec::new();
    for line in listing.lines() {
        let Some((addr, rest)) = line.split_once(":\t") else {
            continue;
        };
        let Ok(addr) = u32::from_str_radix(addr.trim(), 16) else {
            continue;
        };
        let (hex, text) = match rest.split_once('\t') {
            Some((h, t)) => (h, Some(t)),
            None => (rest, None),
        };
        let bytes: Vec<u8> = hex
            .split_whitespace()
            .map(|b| u8::from_str_radix(b, 16).expect("hex byte"))
            .collect();
        match text {
            Some(t) => out.push(ObjLine {
                addr,
                bytes,
                text: t.to_string(),
            }),
            None => {
                if let Some(last) = out.last_mut() {
                    last.bytes.extend(bytes);
                }
            }
        }
    }
    out
}

#[test]
fn disassembler_matches_objdump_on_every_assembler_form() {
    let (Some(as_), Some(ld), Some(objdump)) = (
        tool("h8300-hms-as"),
        tool("h8300-hms-ld"),
        tool("h8300-hms-objdump"),
    ) else {
        println!(
            "SKIPPED: h8300-hms-as/ld/objdump not on PATH (install binutils-h8300-hms to run the comparison)"
        );
        return;
    };
    let dir = std::env::temp_dir().join(format!("emu-objdump-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let src = generate();
    std::fs::write(dir.join("forms.s"), &src).expect("write source");
    run(&as_, &["forms.s", "-o", "forms.o"], &dir);
    run(
        &ld,
        &[
            "-mh8300h", "-Ttext", "0x100", "-e", "_start", "forms.o", "-o", "forms.x",
        ],
        &dir,
    );
    let listing = run(&objdump, &["-d", "forms.x"], &dir);
    let _ = std::fs::remove_dir_all(&dir);

    let lines = parse_objdump(&listing);
    let mut compared = 0usize;
    let mut failures = String::new();
    let mut nfail = 0usize;
    for ol in &lines {
        if ol.text.starts_with(".word") {
            // objdump found no instruction here; the generator emits none of these.
            nfail += 1;
            let _ = writeln!(failures, "{:6x}: objdump printed {:?}", ol.addr, ol.text);
            continue;
        }
        let mine =
            decode_bytes(&ol.bytes).map(|d| (d.len_bytes() as usize, format_instr(d, ol.addr)));
        let ok = match &mine {
            Ok((n, text)) => *n == ol.bytes.len() && *text == ol.text,
            Err(_) => false,
        };
        if !ok {
            nfail += 1;
            if nfail <= 60 {
                let _ = writeln!(
                    failures,
                    "{:6x}: {:02x?}\n   objdump: {:?}\n   mine:    {:?}",
                    ol.addr, ol.bytes, ol.text, mine
                );
            }
        }
        compared += 1;
    }
    println!("objdump comparison: {compared} instruction forms compared, {nfail} mismatches");
    assert!(
        compared > 1000,
        "too few lines parsed from objdump: {compared}"
    );
    assert!(nfail == 0, "{nfail} mismatches, first ones:\n{failures}");
}

#[test]
fn generator_covers_every_mnemonic_family() {
    let src = generate();
    for m in [
        "mov.b", "mov.w", "mov.l", "push.w", "pop.l", "movfpe", "movtpe", "add.l", "sub.w",
        "cmp.b", "and.l", "or.w", "xor.b", "addx", "subx", "inc.w", "dec.l", "adds", "subs",
        "neg.l", "not.b", "exts.w", "extu.l", "shal.b", "shar.w", "shll.l", "shlr.b", "rotxl.w",
        "rotxr.l", "rotl.b", "rotr.w", "daa", "das", "mulxu.b", "mulxs.w", "divxu.w", "divxs.b",
        "bset", "bclr", "bnot", "btst", "bld", "bild", "bst", "bist", "band", "biand", "bor",
        "bior", "bxor", "bixor", "bra", "bsr", "jmp", "jsr", "rts", "rte", "nop", "sleep", "trapa",
        "eepmov.b", "eepmov.w", "ldc", "stc", "andc", "orc", "xorc",
    ] {
        assert!(
            src.contains(&format!("\t{m} ")) || src.contains(&format!("\t{m}\n")),
            "{m}"
        );
    }
}
