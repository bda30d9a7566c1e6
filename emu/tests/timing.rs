//! States per instruction against docs/design.md §4.2 and the H8/300H programming manual (Appendix A:
//! I·S_I + J·S_J + K·S_K + L·S_L + M·S_M + N·S_N with S = 2 for on-chip ROM/RAM, 3 per byte
//! cycle for on-chip I/O on its 8-bit bus, S_N = 1).
//!
//! Operands point at on-chip RAM unless the row says I/O.

mod common;

use common::exec;

/// (objdump text, bytes, states, where the figure comes from)
const TABLE: &[(&str, &[u8], u64, &str)] = &[
    (
        "mov.b\tr0l,r1l",
        &[0x0c, 0x89],
        2,
        "docs/design.md §4.2 MOV Rs,Rd",
    ),
    (
        "add.b\tr0l,r1l",
        &[0x08, 0x89],
        2,
        "docs/design.md §4.2 register ALU",
    ),
    (
        "add.w\tr0,r1",
        &[0x09, 0x01],
        2,
        "docs/design.md §4.2 register ALU",
    ),
    (
        "add.l\ter0,er1",
        &[0x0a, 0x81],
        2,
        "docs/design.md §4.2 register ALU",
    ),
    ("adds\t#4,er0", &[0x0b, 0x90], 2, "docs/design.md §4.2 ADDS"),
    ("subs\t#2,er0", &[0x1b, 0x80], 2, "docs/design.md §4.2 SUBS"),
    ("exts.l\ter0", &[0x17, 0xf0], 2, "docs/design.md §4.2 EXTS"),
    ("extu.w\tr0", &[0x17, 0x50], 2, "docs/design.md §4.2 EXTU"),
    (
        "shll.b\tr0l",
        &[0x10, 0x08],
        2,
        "docs/design.md §4.2 1-bit shift",
    ),
    (
        "mov.w\t#0x1234,r0",
        &[0x79, 0x00, 0x12, 0x34],
        4,
        "docs/design.md §4.2 MOV.W #16",
    ),
    (
        "add.w\t#0x1234,r0",
        &[0x79, 0x10, 0x12, 0x34],
        4,
        "docs/design.md §4.2 ALU.W #16",
    ),
    (
        "sub.w\t#0x1,r0",
        &[0x79, 0x30, 0x00, 0x01],
        4,
        "docs/design.md §4.2 ALU.W #16",
    ),
    (
        "mov.l\t#0x12345678,er0",
        &[0x7a, 0x00, 0x12, 0x34, 0x56, 0x78],
        6,
        "docs/design.md §4.2 MOV.L #32",
    ),
    (
        "add.l\t#0x1,er0",
        &[0x7a, 0x10, 0x00, 0x00, 0x00, 0x01],
        6,
        "docs/design.md §4.2 ALU.L #32",
    ),
    (
        "cmp.l\t#0x1,er0",
        &[0x7a, 0x20, 0x00, 0x00, 0x00, 0x01],
        6,
        "docs/design.md §4.2 ALU.L #32",
    ),
    (
        "mov.b\t@er1,r0l",
        &[0x68, 0x18],
        4,
        "docs/design.md §4.2 MOV.B @ERs",
    ),
    (
        "mov.w\t@er1,r0",
        &[0x69, 0x10],
        4,
        "docs/design.md §4.2 MOV.W @ERs",
    ),
    (
        "mov.b\t@(0x10:16,er1),r0l",
        &[0x6e, 0x18, 0x00, 0x10],
        6,
        "docs/design.md §4.2 @(d:16,ERs)",
    ),
    (
        "mov.w\t@0xe800:16,r0",
        &[0x6b, 0x00, 0xe8, 0x00],
        6,
        "docs/design.md §4.2 @aa:16",
    ),
    (
        "mov.b\t@er1+,r0l",
        &[0x6c, 0x18],
        6,
        "docs/design.md §4.2 @ERs+",
    ),
    (
        "mov.w\tr0,@-er1",
        &[0x6d, 0x90],
        6,
        "docs/design.md §4.2 @-ERd",
    ),
    (
        "mov.b\t@0xffe800:32,r0l",
        &[0x6a, 0x28, 0x00, 0xff, 0xe8, 0x00],
        8,
        "docs/design.md §4.2 @aa:24",
    ),
    (
        "mov.b\t@(0x10:32,er1),r0l",
        &[0x78, 0x10, 0x6a, 0x28, 0x00, 0x00, 0x00, 0x10],
        10,
        "docs/design.md §4.2 @(d:24,ERs)",
    ),
    (
        "mov.l\t@er1,er0",
        &[0x01, 0x00, 0x69, 0x10],
        8,
        "docs/design.md §4.2 MOV.L @ERs",
    ),
    (
        "mov.l\t@(0x10:16,er1),er0",
        &[0x01, 0x00, 0x6f, 0x10, 0x00, 0x10],
        10,
        "docs/design.md §4.2 MOV.L @(d:16)",
    ),
    (
        "mov.l\t@er7+,er0",
        &[0x01, 0x00, 0x6d, 0x70],
        10,
        "docs/design.md §4.2 POP.L",
    ),
    (
        "mov.l\ter0,@-er7",
        &[0x01, 0x00, 0x6d, 0xf0],
        10,
        "docs/design.md §4.2 PUSH.L",
    ),
    (
        "mov.l\t@(0x10:32,er1),er0",
        &[0x01, 0x00, 0x78, 0x10, 0x6b, 0x20, 0x00, 0x00, 0x00, 0x10],
        14,
        "docs/design.md §4.2 MOV.L @(d:24)",
    ),
    (
        "mov.l\t@0xe800:16,er0",
        &[0x01, 0x00, 0x6b, 0x00, 0xe8, 0x00],
        10,
        "manual: I=3, M=2",
    ),
    (
        "mov.l\ter0,@0xffe800:32",
        &[0x01, 0x00, 0x6b, 0xa0, 0x00, 0xff, 0xe8, 0x00],
        12,
        "manual: I=4, M=2",
    ),
    (
        "mov.w\tr0,@-er7",
        &[0x6d, 0xf0],
        6,
        "docs/design.md §4.2 PUSH.W",
    ),
    (
        "mov.w\t@er7+,r0",
        &[0x6d, 0x70],
        6,
        "docs/design.md §4.2 POP.W",
    ),
    (
        "mov.b\t@0x0:8,r0l",
        &[0x28, 0x00],
        4,
        "manual: I=1, L=1 (H'FFFF00 is RAM)",
    ),
    ("mov.b\t@0x20:8,r0l", &[0x28, 0x20], 5, "I/O byte: 2 + 3"),
    (
        "mov.w\t@0xff20:16,r0",
        &[0x6b, 0x00, 0xff, 0x20],
        10,
        "I/O word: 4 + 2 x 3",
    ),
    (
        "mov.l\t@0xffff20:32,er0",
        &[0x01, 0x00, 0x6b, 0x20, 0x00, 0xff, 0xff, 0x20],
        20,
        "I/O long: 8 + 4 x 3",
    ),
    (
        "mulxu.b\tr0l,r1",
        &[0x50, 0x81],
        14,
        "docs/design.md §4.2 MULXU.B",
    ),
    (
        "mulxu.w\tr0,er1",
        &[0x52, 0x01],
        22,
        "docs/design.md §4.2 MULXU.W",
    ),
    (
        "mulxs.b\tr0l,r1",
        &[0x01, 0xc0, 0x50, 0x81],
        16,
        "docs/design.md §4.2 MULXS.B",
    ),
    (
        "mulxs.w\tr0,er1",
        &[0x01, 0xc0, 0x52, 0x01],
        24,
        "docs/design.md §4.2 MULXS.W",
    ),
    (
        "divxu.b\tr0l,r1",
        &[0x51, 0x81],
        14,
        "docs/design.md §4.2 DIVXU.B",
    ),
    (
        "divxu.w\tr0,er1",
        &[0x53, 0x01],
        22,
        "docs/design.md §4.2 DIVXU.W",
    ),
    (
        "divxs.b\tr0l,r1",
        &[0x01, 0xd0, 0x51, 0x81],
        16,
        "docs/design.md §4.2 DIVXS.B",
    ),
    (
        "divxs.w\tr0,er1",
        &[0x01, 0xd0, 0x53, 0x01],
        24,
        "docs/design.md §4.2 DIVXS.W",
    ),
    (
        "eepmov.b\t",
        &[0x7b, 0x5c, 0x59, 0x8f],
        8,
        "docs/design.md §4.2 EEPMOV 8 + 4n, n = 0",
    ),
    (
        "eepmov.w\t",
        &[0x7b, 0xd4, 0x59, 0x8f],
        8,
        "docs/design.md §4.2 EEPMOV 8 + 4n, n = 0",
    ),
    ("sleep\t", &[0x01, 0x80], 2, "docs/design.md §4.2 SLEEP"),
    ("nop\t", &[0x00, 0x00], 2, "manual: I=1"),
    ("trapa\t#0x1", &[0x57, 0x10], 14, "manual TRAPA page: 14"),
    ("jmp\t@er1", &[0x59, 0x10], 4, "manual: I=2"),
    (
        "jmp\t@0x1000:24",
        &[0x5a, 0x00, 0x10, 0x00],
        6,
        "manual: I=2, N=2",
    ),
    (
        "jmp\t@@16 (0x10)",
        &[0x5b, 0x10],
        10,
        "manual: I=2, J=2, N=2",
    ),
    (
        "jsr\t@er1",
        &[0x5d, 0x10],
        8,
        "docs/design.md §4.2 JSR @ERn",
    ),
    (
        "jsr\t@0x1000:24",
        &[0x5e, 0x00, 0x10, 0x00],
        10,
        "docs/design.md §4.2 JSR @aa:24",
    ),
    (
        "jsr\t@@16 (0x10)",
        &[0x5f, 0x10],
        12,
        "docs/design.md §4.2 JSR @@aa:8",
    ),
    ("rts\t", &[0x54, 0x70], 10, "docs/design.md §4.2 RTS"),
    ("rte\t", &[0x56, 0x70], 10, "docs/design.md §4.2 RTE"),
    (
        "ldc\t@er1,ccr",
        &[0x01, 0x40, 0x69, 0x10],
        6,
        "manual: I=2, M=1",
    ),
    (
        "ldc\t@er1+,ccr",
        &[0x01, 0x40, 0x6d, 0x10],
        8,
        "manual: I=2, M=1, N=2",
    ),
    (
        "stc\tccr,@-er1",
        &[0x01, 0x40, 0x6d, 0x90],
        8,
        "manual: I=2, M=1, N=2",
    ),
    (
        "ldc\t@(0x10:16,er1),ccr",
        &[0x01, 0x40, 0x6f, 0x10, 0x00, 0x10],
        8,
        "manual: I=3, M=1",
    ),
    (
        "stc\tccr,@(0x10:32,er1)",
        &[0x01, 0x40, 0x78, 0x10, 0x6b, 0xa0, 0x00, 0x00, 0x00, 0x10],
        12,
        "manual: I=5, M=1",
    ),
    (
        "ldc\t@0xe800:16,ccr",
        &[0x01, 0x40, 0x6b, 0x00, 0xe8, 0x00],
        8,
        "manual: I=3, M=1",
    ),
    (
        "ldc\t@0xffe800:32,ccr",
        &[0x01, 0x40, 0x6b, 0x20, 0x00, 0xff, 0xe8, 0x00],
        10,
        "manual: I=4, M=1",
    ),
    ("ldc\t#0x80,ccr", &[0x07, 0x80], 2, "manual: I=1"),
    ("ldc\tr0l,ccr", &[0x03, 0x08], 2, "manual: I=1"),
    ("stc\tccr,r0l", &[0x02, 0x08], 2, "manual: I=1"),
    ("andc\t#0x7f,ccr", &[0x06, 0x7f], 2, "manual: I=1"),
    ("orc\t#0x80,ccr", &[0x04, 0x80], 2, "manual: I=1"),
    ("xorc\t#0x1,ccr", &[0x05, 0x01], 2, "manual: I=1"),
    (
        "bset\t#0x1,@er1",
        &[0x7d, 0x10, 0x70, 0x10],
        8,
        "manual: I=2, L=2",
    ),
    (
        "btst\t#0x1,@er1",
        &[0x7c, 0x10, 0x73, 0x10],
        6,
        "manual: I=2, L=1",
    ),
    (
        "bld\t#0x1,@0x0:8",
        &[0x7e, 0x00, 0x77, 0x10],
        6,
        "manual: I=2, L=1",
    ),
    (
        "bst\t#0x1,@0x0:8",
        &[0x7f, 0x00, 0x67, 0x10],
        8,
        "manual: I=2, L=2",
    ),
    (
        "bset\t#0x1,@0x20:8",
        &[0x7f, 0x20, 0x70, 0x10],
        10,
        "I/O: 4 + 2 x 3",
    ),
    ("bset\tr0l,r1l", &[0x60, 0x89], 2, "manual: I=1"),
    ("bnot\t#0x7,r1h", &[0x71, 0x71], 2, "manual: I=1"),
    ("daa\tr0l", &[0x0f, 0x08], 2, "manual: I=1"),
    ("das\tr0l", &[0x1f, 0x08], 2, "manual: I=1"),
    ("neg.l\ter0", &[0x17, 0xb0], 2, "manual: I=1"),
    ("not.w\tr0", &[0x17, 0x10], 2, "manual: I=1"),
    ("inc.l\t#2,er0", &[0x0b, 0xf0], 2, "manual: I=1"),
    ("dec.w\t#1,r0", &[0x1b, 0x50], 2, "manual: I=1"),
    ("addx\t#0x1,r0l", &[0x98, 0x01], 2, "manual: I=1"),
    ("subx\tr1l,r0l", &[0x1e, 0x98], 2, "manual: I=1"),
];

#[test]
fn states_match_spec_4_2_and_the_manual() {
    let mut bad = Vec::new();
    for &(text, bytes, want, source) in TABLE {
        let s = exec(text, bytes, |_, _| {});
        assert!(s.event.is_ok(), "{text}: {:?}", s.event);
        if s.states != want {
            bad.push(format!(
                "{text:28} {} states, want {want} ({source})",
                s.states
            ));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn branches_take_the_same_states_taken_or_not() {
    // beq .+2 (d:8): 4 states; beq d:16: 6 states (docs/design.md §4.2), whatever Z is.
    for z in [false, true] {
        let ccr = if z { h8300h::cpu::CCR_Z } else { 0 };
        let s = exec("beq\t.+2 (0x1004)", &[0x47, 0x02], |c, _| c.set_ccr(ccr));
        assert_eq!(s.states, 4);
        assert_eq!(s.cpu.pc(), if z { 0x1004 } else { 0x1002 });
        let s = exec("beq\t.+16 (0x1014)", &[0x58, 0x70, 0x00, 0x10], |c, _| {
            c.set_ccr(ccr)
        });
        assert_eq!(s.states, 6);
        assert_eq!(s.cpu.pc(), if z { 0x1014 } else { 0x1004 });
    }
    // BSR d:8 / d:16: 8 / 10 states (docs/design.md §4.2).
    let s = exec("bsr\t.-4 (0xffe)", &[0x55, 0xfc], |_, _| {});
    assert_eq!((s.states, s.cpu.pc()), (8, 0xffe));
    let s = exec("bsr\t.+256 (0x1104)", &[0x5c, 0x00, 0x01, 0x00], |_, _| {});
    assert_eq!((s.states, s.cpu.pc()), (10, 0x1104));
}

#[test]
fn eepmov_costs_8_plus_4n() {
    for n in [1u32, 5, 17] {
        let s = exec("eepmov.b\t", &[0x7b, 0x5c, 0x59, 0x8f], |c, _| {
            c.set_er(4, n);
        });
        assert_eq!(s.states, u64::from(8 + 4 * n), "n = {n}");
        let s = exec("eepmov.w\t", &[0x7b, 0xd4, 0x59, 0x8f], |c, _| {
            c.set_er(4, n);
        });
        assert_eq!(s.states, u64::from(8 + 4 * n), "n = {n}");
    }
}
