//! Per-instruction-class tests in the style of mooneye-gb's opcode tests: set registers and
//! memory, run one instruction (or a few), assert the result, the condition codes and the
//! states. Condition codes follow the H8/300H Series Programming Manual, section 2 (one page
//! per instruction); states its Appendix A (and docs/design.md §4.2, see also `timing.rs`).

mod common;

use common::{CODE, DATA, exec, machine, peek16, peek32};
use h8_3052f::machine::Machine;
use h8_3052f::periph::sci::{SCI1_SCR, SCR_TE, SCR_TIE, VECTOR_TXI1};
use h8300h::bus::Bus;
use h8300h::cpu::{CCR_C, CCR_H, CCR_I, CCR_N, CCR_U, CCR_UI, CCR_V, CCR_Z, CpuError, Event};

const HNZVC: u8 = CCR_H | CCR_N | CCR_Z | CCR_V | CCR_C;

/// Flags H N Z V C of a CCR value.
fn f(ccr: u8) -> u8 {
    ccr & HNZVC
}

// ----- data transfer -----------------------------------------------------------------------

#[test]
fn mov_register_sets_n_z_clears_v_keeps_c_and_h() {
    let s = exec("mov.b\tr0l,r1l", &[0x0c, 0x89], |c, _| {
        c.set_er(0, 0x80);
        c.set_ccr(CCR_V | CCR_C | CCR_H | CCR_Z);
    });
    assert_eq!(s.cpu.er(1) & 0xff, 0x80);
    assert_eq!(f(s.cpu.ccr()), CCR_N | CCR_C | CCR_H);
    assert_eq!(s.states, 2);
    let s = exec("mov.w\t#0x0,r0", &[0x79, 0x00, 0x00, 0x00], |c, _| {
        c.set_er(0, 0x1234_5678)
    });
    assert_eq!(s.cpu.er(0), 0x1234_0000, "only R0 changes");
    assert_eq!(f(s.cpu.ccr()), CCR_Z);
    assert_eq!(s.states, 4);
    let s = exec(
        "mov.l\t#0x80000000,er2",
        &[0x7a, 0x02, 0x80, 0x00, 0x00, 0x00],
        |_, _| {},
    );
    assert_eq!(s.cpu.er(2), 0x8000_0000);
    assert_eq!(f(s.cpu.ccr()), CCR_N);
    assert_eq!(s.states, 6);
}

#[test]
fn mov_memory_modes() {
    // @ERs, longword.
    let s = exec("mov.l\t@er1,er0", &[0x01, 0x00, 0x69, 0x10], |c, m| {
        c.set_er(1, DATA);
        m.poke(DATA, &[0xde, 0xad, 0xbe, 0xef]);
    });
    assert_eq!(s.cpu.er(0), 0xdead_beef);
    assert_eq!(f(s.cpu.ccr()), CCR_N);
    assert_eq!(s.states, 8);
    // @-ERd: pre-decrement by 2, N = 2 internal states.
    let s = exec("mov.w\tr0,@-er1", &[0x6d, 0x90], |c, _| {
        c.set_er(1, DATA + 2);
        c.set_er(0, 0x0000_4321);
    });
    assert_eq!(s.cpu.er(1), DATA);
    assert_eq!(peek16(&s.m, DATA), 0x4321);
    assert_eq!(s.states, 6);
    // POP.L = mov.l @er7+,er0.
    let s = exec("mov.l\t@er7+,er0", &[0x01, 0x00, 0x6d, 0x70], |c, m| {
        c.set_er(7, DATA);
        m.poke(DATA, &[0, 0, 0, 0]);
    });
    assert_eq!(s.cpu.er(7), DATA + 4);
    assert_eq!(s.cpu.er(0), 0);
    assert_eq!(f(s.cpu.ccr()), CCR_Z);
    assert_eq!(s.states, 10);
    // @(d:16,ERs) with a negative displacement (sign-extended).
    let s = exec(
        "mov.b\t@(0xfffe:16,er1),r0l",
        &[0x6e, 0x18, 0xff, 0xfe],
        |c, m| {
            c.set_er(1, DATA + 2);
            m.poke(DATA, &[0x5a]);
        },
    );
    assert_eq!(s.cpu.er(0) & 0xff, 0x5a);
    assert_eq!(s.states, 6);
    // @(d:24,ERd) store of a longword.
    let s = exec(
        "mov.l\ter2,@(0x10:32,er1)",
        &[0x01, 0x00, 0x78, 0x90, 0x6b, 0xa2, 0x00, 0x00, 0x00, 0x10],
        |c, _| {
            c.set_er(1, DATA);
            c.set_er(2, 0x0102_0304);
        },
    );
    assert_eq!(peek32(&s.m, DATA + 0x10), 0x0102_0304);
    assert_eq!(s.states, 14);
    // @aa:16 is sign-extended: H'E800 is H'FFE800 (RAM).
    let s = exec("mov.w\t@0xe800:16,r0", &[0x6b, 0x00, 0xe8, 0x00], |_, m| {
        m.poke(DATA, &[0x00, 0x01]);
    });
    assert_eq!(s.cpu.er(0) & 0xffff, 1);
    assert_eq!(s.states, 6);
    // A byte store to an unused I/O register: the 8-bit 3-state bus cycle costs 3.
    let s = exec("mov.b\tr0l,@0x20:8", &[0x38, 0x20], |_, _| {});
    assert_eq!(s.states, 5);
}

#[test]
fn push_of_the_stack_pointer_stores_its_old_value() {
    // mov.l er7,@-er7: the documented choice of this core (value before the decrement).
    let s = exec("mov.l\ter7,@-er7", &[0x01, 0x00, 0x6d, 0xf7], |c, _| {
        c.set_er(7, DATA + 8)
    });
    assert_eq!(s.cpu.er(7), DATA + 4);
    assert_eq!(peek32(&s.m, DATA + 4), DATA + 8);
}

// ----- arithmetic and logic ----------------------------------------------------------------

#[test]
fn add_flags_half_carry_overflow_carry() {
    let s = exec("add.b\t#0x1,r0l", &[0x88, 0x01], |c, _| c.set_er(0, 0x7f));
    assert_eq!(s.cpu.er(0) & 0xff, 0x80);
    assert_eq!(f(s.cpu.ccr()), CCR_H | CCR_N | CCR_V);
    assert_eq!(s.states, 2);
    let s = exec("add.b\t#0x1,r0l", &[0x88, 0x01], |c, _| c.set_er(0, 0xff));
    assert_eq!(s.cpu.er(0) & 0xff, 0);
    assert_eq!(f(s.cpu.ccr()), CCR_H | CCR_Z | CCR_C);
    // Word: H is the carry out of bit 11.
    let s = exec("add.w\t#0x1,r0", &[0x79, 0x10, 0x00, 0x01], |c, _| {
        c.set_er(0, 0x0fff)
    });
    assert_eq!(s.cpu.er(0) & 0xffff, 0x1000);
    assert_eq!(f(s.cpu.ccr()), CCR_H);
    assert_eq!(s.states, 4);
    // Longword: H is the carry out of bit 27.
    let s = exec("add.l\ter0,er1", &[0x0a, 0x81], |c, _| {
        c.set_er(0, 1);
        c.set_er(1, 0xffff_ffff);
    });
    assert_eq!(s.cpu.er(1), 0);
    assert_eq!(f(s.cpu.ccr()), CCR_H | CCR_Z | CCR_C);
    assert_eq!(s.states, 2);
}

#[test]
fn sub_and_cmp_borrow_flags() {
    let s = exec("sub.b\tr0l,r1l", &[0x18, 0x89], |c, _| {
        c.set_er(0, 1);
        c.set_er(1, 0);
    });
    assert_eq!(s.cpu.er(1) & 0xff, 0xff);
    assert_eq!(f(s.cpu.ccr()), CCR_H | CCR_N | CCR_C);
    let s = exec("sub.w\tr0,r1", &[0x19, 0x01], |c, _| {
        c.set_er(0, 1);
        c.set_er(1, 0x8000);
    });
    assert_eq!(s.cpu.er(1) & 0xffff, 0x7fff);
    assert_eq!(f(s.cpu.ccr()), CCR_H | CCR_V);
    let s = exec("cmp.b\t#0x5,r0l", &[0xa8, 0x05], |c, _| c.set_er(0, 0x05));
    assert_eq!(s.cpu.er(0), 5, "CMP does not write");
    assert_eq!(f(s.cpu.ccr()), CCR_Z);
    let s = exec("cmp.l\ter0,er1", &[0x1f, 0x81], |c, _| {
        c.set_er(0, 0x8000_0000);
        c.set_er(1, 0x7fff_ffff);
    });
    // 0x7fffffff - 0x80000000: borrow and overflow, result negative.
    assert_eq!(f(s.cpu.ccr()), CCR_N | CCR_V | CCR_C);
    assert_eq!(s.states, 2);
}

#[test]
fn logic_ops_set_n_z_clear_v_keep_c() {
    let s = exec("and.b\t#0xf,r0l", &[0xe8, 0x0f], |c, _| {
        c.set_er(0, 0xf0);
        c.set_ccr(CCR_C | CCR_V);
    });
    assert_eq!(s.cpu.er(0) & 0xff, 0);
    assert_eq!(f(s.cpu.ccr()), CCR_Z | CCR_C);
    let s = exec("or.w\tr0,r1", &[0x64, 0x01], |c, _| {
        c.set_er(0, 0x8000);
        c.set_er(1, 0x0001);
    });
    assert_eq!(s.cpu.er(1) & 0xffff, 0x8001);
    assert_eq!(f(s.cpu.ccr()), CCR_N);
    let s = exec("xor.l\ter0,er1", &[0x01, 0xf0, 0x65, 0x01], |c, _| {
        c.set_er(0, 0xffff_0000);
        c.set_er(1, 0x0fff_0000);
    });
    assert_eq!(s.cpu.er(1), 0xf000_0000);
    assert_eq!(f(s.cpu.ccr()), CCR_N);
    assert_eq!(s.states, 4);
}

#[test]
fn addx_subx_use_carry_and_only_clear_z() {
    let s = exec("addx\tr0l,r1l", &[0x0e, 0x89], |c, _| {
        c.set_er(0, 0x10);
        c.set_er(1, 0x20);
        c.set_ccr(CCR_C | CCR_Z);
    });
    assert_eq!(s.cpu.er(1) & 0xff, 0x31);
    assert_eq!(f(s.cpu.ccr()), 0, "non-zero result clears Z");
    // A zero result keeps Z as it was: 1 stays 1 ...
    let s = exec("addx\tr0l,r1l", &[0x0e, 0x89], |c, _| {
        c.set_er(0, 0xff);
        c.set_er(1, 0x00);
        c.set_ccr(CCR_C | CCR_Z);
    });
    assert_eq!(s.cpu.er(1) & 0xff, 0);
    assert_eq!(f(s.cpu.ccr()), CCR_H | CCR_Z | CCR_C);
    // ... and 0 stays 0.
    let s = exec("addx\tr0l,r1l", &[0x0e, 0x89], |c, _| {
        c.set_er(0, 0xff);
        c.set_er(1, 0x00);
        c.set_ccr(CCR_C);
    });
    assert_eq!(f(s.cpu.ccr()), CCR_H | CCR_C);
    let s = exec("subx\tr0l,r1l", &[0x1e, 0x89], |c, _| {
        c.set_er(0, 0x00);
        c.set_er(1, 0x00);
        c.set_ccr(CCR_C | CCR_Z);
    });
    assert_eq!(s.cpu.er(1) & 0xff, 0xff);
    assert_eq!(f(s.cpu.ccr()), CCR_H | CCR_N | CCR_C);
    assert_eq!(s.states, 2);
}

#[test]
fn inc_dec_adds_subs() {
    // INC/DEC: N Z V; H and C unchanged.
    let s = exec("inc\tr0l", &[0x0a, 0x08], |c, _| {
        c.set_er(0, 0x7f);
        c.set_ccr(CCR_C | CCR_H);
    });
    assert_eq!(s.cpu.er(0) & 0xff, 0x80);
    assert_eq!(f(s.cpu.ccr()), CCR_N | CCR_V | CCR_C | CCR_H);
    let s = exec("dec.w\t#2,r0", &[0x1b, 0xd0], |c, _| c.set_er(0, 1));
    assert_eq!(s.cpu.er(0) & 0xffff, 0xffff);
    assert_eq!(f(s.cpu.ccr()), CCR_N);
    let s = exec("dec.w\t#2,r0", &[0x1b, 0xd0], |c, _| c.set_er(0, 0x8001));
    assert_eq!(s.cpu.er(0) & 0xffff, 0x7fff);
    assert_eq!(f(s.cpu.ccr()), CCR_V);
    let s = exec("inc.l\t#1,er0", &[0x0b, 0x70], |c, _| {
        c.set_er(0, 0xffff_ffff)
    });
    assert_eq!(s.cpu.er(0), 0);
    assert_eq!(f(s.cpu.ccr()), CCR_Z);
    // ADDS/SUBS: no flags.
    let s = exec("adds\t#4,er0", &[0x0b, 0x90], |c, _| {
        c.set_er(0, 0xffff_fffe);
        c.set_ccr(0);
    });
    assert_eq!(s.cpu.er(0), 2);
    assert_eq!(s.cpu.ccr(), 0);
    let s = exec("subs\t#1,er0", &[0x1b, 0x00], |c, _| {
        c.set_er(0, 0);
        c.set_ccr(CCR_Z);
    });
    assert_eq!(s.cpu.er(0), 0xffff_ffff);
    assert_eq!(s.cpu.ccr(), CCR_Z);
    assert_eq!(s.states, 2);
}

#[test]
fn neg_not_exts_extu() {
    let s = exec("neg.b\tr0l", &[0x17, 0x88], |c, _| c.set_er(0, 0x80));
    assert_eq!(s.cpu.er(0) & 0xff, 0x80);
    assert_eq!(f(s.cpu.ccr()), CCR_N | CCR_V | CCR_C);
    let s = exec("neg.b\tr0l", &[0x17, 0x88], |c, _| c.set_er(0, 0));
    assert_eq!(f(s.cpu.ccr()), CCR_Z);
    let s = exec("neg.w\tr0", &[0x17, 0x90], |c, _| c.set_er(0, 1));
    assert_eq!(s.cpu.er(0) & 0xffff, 0xffff);
    assert_eq!(f(s.cpu.ccr()), CCR_H | CCR_N | CCR_C);
    let s = exec("not.l\ter0", &[0x17, 0x30], |c, _| {
        c.set_er(0, 0xffff_ffff);
        c.set_ccr(CCR_C | CCR_V);
    });
    assert_eq!(s.cpu.er(0), 0);
    assert_eq!(f(s.cpu.ccr()), CCR_Z | CCR_C);
    let s = exec("exts.w\tr0", &[0x17, 0xd0], |c, _| c.set_er(0, 0xaaaa_0080));
    assert_eq!(s.cpu.er(0), 0xaaaa_ff80);
    assert_eq!(f(s.cpu.ccr()), CCR_N);
    let s = exec("extu.l\ter0", &[0x17, 0x70], |c, _| {
        c.set_er(0, 0xffff_8000)
    });
    assert_eq!(s.cpu.er(0), 0x0000_8000);
    assert_eq!(f(s.cpu.ccr()), 0);
    assert_eq!(s.states, 2);
}

#[test]
fn shifts_and_rotates() {
    // (text, bytes, value, C in, result, flags out)
    type Case = (&'static str, &'static [u8], u32, bool, u32, u8);
    let cases: &[Case] = &[
        (
            "shal.b\tr0l",
            &[0x10, 0x88],
            0x40,
            false,
            0x80,
            CCR_N | CCR_V,
        ),
        (
            "shal.b\tr0l",
            &[0x10, 0x88],
            0xc0,
            false,
            0x80,
            CCR_N | CCR_C,
        ),
        (
            "shar.w\tr0",
            &[0x11, 0x90],
            0x8001,
            false,
            0xc000,
            CCR_N | CCR_C,
        ),
        ("shll.l\ter0", &[0x10, 0x30], 0x8000_0001, false, 2, CCR_C),
        ("shlr.b\tr0l", &[0x11, 0x08], 0x81, false, 0x40, CCR_C),
        ("rotxl.b\tr0l", &[0x12, 0x08], 0x80, true, 0x01, CCR_C),
        (
            "rotxr.w\tr0",
            &[0x13, 0x10],
            0x0001,
            false,
            0,
            CCR_Z | CCR_C,
        ),
        ("rotl.l\ter0", &[0x12, 0xb0], 0x8000_0000, false, 1, CCR_C),
        (
            "rotr.b\tr0l",
            &[0x13, 0x88],
            0x01,
            false,
            0x80,
            CCR_N | CCR_C,
        ),
    ];
    for &(text, bytes, v, c_in, want, flags) in cases {
        let s = exec(text, bytes, |c, _| {
            c.set_er(0, v);
            c.set_ccr(if c_in { CCR_C | CCR_H } else { CCR_H | CCR_V });
        });
        let mask = if text.ends_with("r0l") {
            0xff
        } else if text.ends_with("er0") {
            0xffff_ffff
        } else {
            0xffff
        };
        assert_eq!(s.cpu.er(0) & mask, want, "{text}");
        assert_eq!(f(s.cpu.ccr()), flags | CCR_H, "{text}: H is kept");
        assert_eq!(s.states, 2);
    }
}

#[test]
fn daa_das_adjust_bcd() {
    // 15 + 27 = 3C in binary; DAA makes 42.
    let s = exec("daa\tr0l", &[0x0f, 0x08], |c, _| {
        c.set_er(0, 0x3c);
        c.set_ccr(0);
    });
    assert_eq!(s.cpu.er(0) & 0xff, 0x42);
    assert_eq!(f(s.cpu.ccr()) & (CCR_N | CCR_Z | CCR_C), 0);
    // 99 + 01 = 9A; DAA makes 00 with a decimal carry.
    let s = exec("daa\tr0l", &[0x0f, 0x08], |c, _| {
        c.set_er(0, 0x9a);
        c.set_ccr(0);
    });
    assert_eq!(s.cpu.er(0) & 0xff, 0x00);
    assert_eq!(f(s.cpu.ccr()) & (CCR_N | CCR_Z | CCR_C), CCR_Z | CCR_C);
    // 19 + 08 = 21 with H set; DAA makes 27.
    let s = exec("daa\tr0l", &[0x0f, 0x08], |c, _| {
        c.set_er(0, 0x21);
        c.set_ccr(CCR_H);
    });
    assert_eq!(s.cpu.er(0) & 0xff, 0x27);
    // 42 - 15 = 2D with a half borrow; DAS makes 27.
    let s = exec("das\tr0l", &[0x1f, 0x08], |c, _| {
        c.set_er(0, 0x2d);
        c.set_ccr(CCR_H);
    });
    assert_eq!(s.cpu.er(0) & 0xff, 0x27);
    // 10 - 20 = F0 with a borrow; DAS makes 90 and keeps C.
    let s = exec("das\tr0l", &[0x1f, 0x08], |c, _| {
        c.set_er(0, 0xf0);
        c.set_ccr(CCR_C);
    });
    assert_eq!(s.cpu.er(0) & 0xff, 0x90);
    assert_eq!(s.cpu.ccr() & CCR_C, CCR_C);
    assert_eq!(s.states, 2);
}

// ----- multiply and divide -----------------------------------------------------------------

#[test]
fn multiply_unsigned_and_signed() {
    let s = exec("mulxu.b\tr0l,r1", &[0x50, 0x81], |c, _| {
        c.set_er(0, 0x10);
        c.set_er(1, 0xabcd_1234);
        c.set_ccr(CCR_Z);
    });
    assert_eq!(s.cpu.er(1), 0xabcd_0340);
    assert_eq!(s.cpu.ccr(), CCR_Z, "MULXU leaves the flags");
    assert_eq!(s.states, 14);
    let s = exec("mulxu.w\tr0,er1", &[0x52, 0x01], |c, _| {
        c.set_er(0, 0xffff);
        c.set_er(1, 0x1234_ffff);
    });
    assert_eq!(s.cpu.er(1), 0xfffe_0001);
    assert_eq!(s.states, 22);
    let s = exec("mulxs.b\tr0l,r1", &[0x01, 0xc0, 0x50, 0x81], |c, _| {
        c.set_er(0, 0x03);
        c.set_er(1, 0x00fe);
    });
    assert_eq!(s.cpu.er(1) & 0xffff, 0xfffa);
    assert_eq!(f(s.cpu.ccr()), CCR_N);
    assert_eq!(s.states, 16);
    let s = exec("mulxs.w\tr0,er1", &[0x01, 0xc0, 0x52, 0x01], |c, _| {
        c.set_er(0, 0x8000);
        c.set_er(1, 0x8000);
    });
    assert_eq!(s.cpu.er(1), 0x4000_0000);
    assert_eq!(f(s.cpu.ccr()), 0);
    assert_eq!(s.states, 24);
    let s = exec("mulxs.w\tr0,er1", &[0x01, 0xc0, 0x52, 0x01], |c, _| {
        c.set_er(0, 0);
        c.set_er(1, 0x7fff);
    });
    assert_eq!(f(s.cpu.ccr()), CCR_Z);
}

#[test]
fn divide_unsigned() {
    let s = exec("divxu.b\tr0l,r1", &[0x51, 0x81], |c, _| {
        c.set_er(0, 0x10);
        c.set_er(1, 263);
    });
    assert_eq!(s.cpu.er(1) & 0xffff, 0x0710, "remainder 7 : quotient 16");
    assert_eq!(f(s.cpu.ccr()), 0);
    assert_eq!(s.states, 14);
    // N follows the divisor's top bit.
    let s = exec("divxu.b\tr0l,r1", &[0x51, 0x81], |c, _| {
        c.set_er(0, 0x80);
        c.set_er(1, 0x0100);
    });
    assert_eq!(s.cpu.er(1) & 0xffff, 0x0002);
    assert_eq!(f(s.cpu.ccr()), CCR_N);
    let s = exec("divxu.w\tr0,er1", &[0x53, 0x01], |c, _| {
        c.set_er(0, 7);
        c.set_er(1, 100_000);
    });
    assert_eq!(s.cpu.er(1), (5 << 16) | 14_285);
    assert_eq!(s.states, 22);
}

#[test]
fn divide_signed() {
    let s = exec("divxs.b\tr0l,r1", &[0x01, 0xd0, 0x51, 0x81], |c, _| {
        c.set_er(0, 2);
        c.set_er(1, 0xfff9); // -7
    });
    assert_eq!(s.cpu.er(1) & 0xffff, 0xfffd, "remainder -1 : quotient -3");
    assert_eq!(f(s.cpu.ccr()), CCR_N);
    assert_eq!(s.states, 16);
    let s = exec("divxs.w\tr0,er1", &[0x01, 0xd0, 0x53, 0x01], |c, _| {
        c.set_er(0, 0xfff9); // -7
        c.set_er(1, 100_000);
    });
    assert_eq!(s.cpu.er(1), (5 << 16) | (-14_285i32 as u32 & 0xffff));
    assert_eq!(f(s.cpu.ccr()), CCR_N);
    assert_eq!(s.states, 24);
}

#[test]
fn divide_by_zero_sets_z_and_leaves_the_register() {
    let s = exec("divxu.b\tr0l,r1", &[0x51, 0x81], |c, _| {
        c.set_er(0, 0);
        c.set_er(1, 0x1234);
    });
    assert_eq!(s.cpu.er(1), 0x1234);
    assert_eq!(f(s.cpu.ccr()), CCR_Z);
    assert_eq!(s.states, 14);
    let s = exec("divxs.w\tr0,er1", &[0x01, 0xd0, 0x53, 0x01], |c, _| {
        c.set_er(0, 0);
        c.set_er(1, 0x8000_0000);
    });
    assert_eq!(s.cpu.er(1), 0x8000_0000);
    assert_eq!(f(s.cpu.ccr()), CCR_Z | CCR_N);
    assert_eq!(s.states, 24);
}

/// DIVXS.B/.W flags by the programming manual (2.2.26): "The N flag is set to 1 if the
/// dividend and divisor have different signs, and cleared to 0 if they have the same sign. The
/// N flag may therefore be set to 1 when the quotient is zero."; Z = 1 only for a zero
/// divisor; H, V, C unchanged. Each case: (dividend, divisor, Rd/ERd after, N, Z).
#[test]
fn divxs_n_follows_the_operand_signs_even_for_a_zero_quotient() {
    let n = |b: bool| if b { CCR_N } else { 0 };
    let z = |b: bool| if b { CCR_Z } else { 0 };
    // DIVXS.B R0L,R1: R1 (16 bits) / R0L (8 bits) -> R1H remainder, R1L quotient.
    let byte_cases: [(i16, i8, u16, bool, bool); 14] = [
        (-1, 5, 0xff00, true, false),       // quotient 0, remainder -1
        (-3, 100, 0xfd00, true, false),     // quotient 0, remainder -3
        (3, -100, 0x0300, true, false),     // quotient 0, remainder 3
        (0, -5, 0x0000, true, false),       // 0 has the sign of a positive number
        (0, 5, 0x0000, false, false),       // quotient 0, same signs
        (-7, -2, 0xff03, false, false),     // 3 remainder -1
        (7, -2, 0x01fd, true, false),       // -3 remainder 1
        (-7, 2, 0xfffd, true, false),       // -3 remainder -1
        (-128, 1, 0x0080, true, false),     // quotient -128 fits
        (5, 0, 5, false, true),             // by zero: register unchanged
        (-5, 0, 0xfffb, true, true),        // by zero, negative dividend
        (1000, -1, 0x0018, true, false),    // overflow: low byte of -1000 = H'FC18
        (-32768, -1, 0x0000, false, false), // overflow: 32768, low byte 0, same signs
        (-32768, 1, 0x0000, true, false),   // overflow: low byte of -32768
    ];
    for (dividend, divisor, after, nf, zf) in byte_cases {
        for keep in [0, CCR_H | CCR_V | CCR_C] {
            let s = exec("divxs.b\tr0l,r1", &[0x01, 0xd0, 0x51, 0x81], |c, _| {
                c.set_er(0, u32::from(divisor as u8));
                c.set_er(1, 0xabcd_0000 | u32::from(dividend as u16));
                c.set_ccr(CCR_I | keep | CCR_N | CCR_Z);
            });
            let case = format!("divxs.b {dividend} / {divisor}, H V C = {keep:#x}");
            assert_eq!(s.cpu.er(1), 0xabcd_0000 | u32::from(after), "{case}");
            assert_eq!(f(s.cpu.ccr()), keep | n(nf) | z(zf), "{case}");
            assert_eq!(s.states, 16, "{case}");
        }
    }
    // DIVXS.W R0,ER1: ER1 (32 bits) / R0 (16 bits) -> E1 remainder, R1 quotient.
    let word_cases: [(i32, i16, u32, bool, bool); 12] = [
        (-1, 5, 0xffff_0000, true, false),
        (-3, 100, 0xfffd_0000, true, false),
        (3, -100, 0x0003_0000, true, false),
        (0, -5, 0, true, false),
        (-100_000, -7, (-5i32 as u32) << 16 | 14_285, false, false),
        (
            100_000,
            -7,
            5 << 16 | (-14_285i32 as u32 & 0xffff),
            true,
            false,
        ),
        (-32_768, 1, 0x0000_8000, true, false),
        (5, 0, 5, false, true),
        (i32::MIN, 0, 0x8000_0000, true, true),
        (i32::MAX, 1, 0x0000_ffff, false, false), // overflow: low word of the quotient
        (i32::MIN, -1, 0, false, false),          // overflow: 2^31, low word 0
        (-100_000, 1, 0x0000_7960, true, false),  // overflow: low word of -100000
    ];
    for (dividend, divisor, after, nf, zf) in word_cases {
        for keep in [0, CCR_H | CCR_V | CCR_C] {
            let s = exec("divxs.w\tr0,er1", &[0x01, 0xd0, 0x53, 0x01], |c, _| {
                c.set_er(0, 0x1234_0000 | u32::from(divisor as u16));
                c.set_er(1, dividend as u32);
                c.set_ccr(CCR_I | keep | CCR_N | CCR_Z);
            });
            let case = format!("divxs.w {dividend} / {divisor}, H V C = {keep:#x}");
            assert_eq!(s.cpu.er(1), after, "{case}");
            assert_eq!(
                s.cpu.er(0),
                0x1234_0000 | u32::from(divisor as u16),
                "{case}"
            );
            assert_eq!(f(s.cpu.ccr()), keep | n(nf) | z(zf), "{case}");
            assert_eq!(s.states, 24, "{case}");
        }
    }
}

#[test]
fn divide_overflow_keeps_the_low_quotient_bits() {
    // H'FFFF / 1 does not fit 8 bits (the manual's overflow example): quotient low byte, rest 0.
    let s = exec("divxu.b\tr0l,r1", &[0x51, 0x81], |c, _| {
        c.set_er(0, 1);
        c.set_er(1, 0xffff);
    });
    assert_eq!(s.cpu.er(1) & 0xffff, 0x00ff);
    assert_eq!(f(s.cpu.ccr()), 0);
}

// ----- bit manipulation --------------------------------------------------------------------

#[test]
fn bit_set_clear_not_test_on_a_register() {
    let s = exec("bset\t#0x3,r1l", &[0x70, 0x39], |c, _| c.set_er(1, 0));
    assert_eq!(s.cpu.er(1), 0x08);
    assert_eq!(s.states, 2);
    let s = exec("bclr\t#0x3,r1l", &[0x72, 0x39], |c, _| c.set_er(1, 0xff));
    assert_eq!(s.cpu.er(1), 0xf7);
    let s = exec("bnot\t#0x3,r1l", &[0x71, 0x39], |c, _| c.set_er(1, 0x0f));
    assert_eq!(s.cpu.er(1), 0x07);
    let s = exec("btst\t#0x3,r1l", &[0x73, 0x39], |c, _| {
        c.set_er(1, 0x08);
        c.set_ccr(CCR_Z | CCR_C);
    });
    assert_eq!(f(s.cpu.ccr()), CCR_C, "bit set: Z = 0, C kept");
    let s = exec("btst\t#0x3,r1l", &[0x73, 0x39], |c, _| {
        c.set_er(1, 0xf7);
        c.set_ccr(0);
    });
    assert_eq!(f(s.cpu.ccr()), CCR_Z);
}

#[test]
fn bit_carry_operations_truth_tables() {
    // (text, bytes, f(bit, c) -> new C)
    type Op = fn(bool, bool) -> bool;
    let ops: &[(&str, &[u8], Op)] = &[
        ("bld\t#0x3,r1l", &[0x77, 0x39], |b, _| b),
        ("bild\t#0x3,r1l", &[0x77, 0xb9], |b, _| !b),
        ("band\t#0x3,r1l", &[0x76, 0x39], |b, c| c && b),
        ("biand\t#0x3,r1l", &[0x76, 0xb9], |b, c| c && !b),
        ("bor\t#0x3,r1l", &[0x74, 0x39], |b, c| c || b),
        ("bior\t#0x3,r1l", &[0x74, 0xb9], |b, c| c || !b),
        ("bxor\t#0x3,r1l", &[0x75, 0x39], |b, c| c != b),
        ("bixor\t#0x3,r1l", &[0x75, 0xb9], |b, c| c == b),
    ];
    for &(text, bytes, op) in ops {
        for bit in [false, true] {
            for c in [false, true] {
                let s = exec(text, bytes, |cpu, _| {
                    cpu.set_er(1, if bit { 0x08 } else { 0xf7 });
                    cpu.set_ccr(if c { CCR_C | CCR_Z } else { CCR_Z });
                });
                assert_eq!(
                    s.cpu.ccr() & CCR_C != 0,
                    op(bit, c),
                    "{text} bit={bit} c={c}"
                );
                assert_eq!(s.cpu.ccr() & CCR_Z, CCR_Z, "{text}: other flags kept");
                assert_eq!(
                    s.cpu.er(1),
                    if bit { 0x08 } else { 0xf7 },
                    "{text} writes nothing"
                );
                assert_eq!(s.states, 2);
            }
        }
    }
    // BST / BIST store C (or its inverse) into the bit.
    for c in [false, true] {
        let s = exec("bst\t#0x3,r1l", &[0x67, 0x39], |cpu, _| {
            cpu.set_er(1, 0x55);
            cpu.set_ccr(if c { CCR_C } else { 0 });
        });
        assert_eq!(s.cpu.er(1), if c { 0x5d } else { 0x55 });
        let s = exec("bist\t#0x3,r1l", &[0x67, 0xb9], |cpu, _| {
            cpu.set_er(1, 0x55);
            cpu.set_ccr(if c { CCR_C } else { 0 });
        });
        assert_eq!(s.cpu.er(1), if c { 0x55 } else { 0x5d });
    }
}

#[test]
fn bit_operations_on_memory() {
    // Bit number from a register (modulo 8), target @ERd: read-modify-write (L = 2).
    let s = exec("bset\tr0l,@er1", &[0x7d, 0x10, 0x60, 0x80], |c, m| {
        c.set_er(0, 0x0b);
        c.set_er(1, DATA);
        m.poke(DATA, &[0x00]);
    });
    assert_eq!(s.m.peek(DATA), 0x08);
    assert_eq!(s.states, 8);
    // @aa:8 in RAM (H'FFFF00).
    let s = exec("bclr\t#0x0,@0x0:8", &[0x7f, 0x00, 0x72, 0x00], |_, m| {
        m.poke(0xff_ff00, &[0xff]);
    });
    assert_eq!(s.m.peek(0xff_ff00), 0xfe);
    assert_eq!(s.states, 8);
    // BTST on memory only reads (L = 1).
    let s = exec("btst\t#0x1,@er1", &[0x7c, 0x10, 0x73, 0x10], |c, m| {
        c.set_er(1, DATA);
        m.poke(DATA, &[0x02]);
        c.set_ccr(CCR_Z);
    });
    assert_eq!(f(s.cpu.ccr()), 0);
    assert_eq!(s.states, 6);
}

// ----- branches, calls, returns ------------------------------------------------------------

#[test]
fn every_branch_condition() {
    let names = [
        "bra", "brn", "bhi", "bls", "bcc", "bcs", "bne", "beq", "bvc", "bvs", "bpl", "bmi", "bge",
        "blt", "bgt", "ble",
    ];
    for cc in 0..16u8 {
        for flags in 0..16u8 {
            let (n, z, v, c) = (
                flags & 8 != 0,
                flags & 4 != 0,
                flags & 2 != 0,
                flags & 1 != 0,
            );
            let want = match cc {
                0 => true,
                1 => false,
                2 => !c && !z,
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
            };
            let text = format!("{}\t.+16 (0x1012)", names[usize::from(cc)]);
            let s = exec(&text, &[0x40 | cc, 0x10], |cpu, _| cpu.set_ccr(flags));
            assert_eq!(s.cpu.pc() == 0x1012, want, "{text} with NZVC = {flags:04b}");
            assert_eq!(s.cpu.ccr(), flags, "branches change no flag");
            assert_eq!(s.states, 4);
        }
    }
}

#[test]
fn bsr_jsr_push_the_return_address_and_rts_pops_it() {
    let s = exec("bsr\t.+2 (0x1004)", &[0x55, 0x02], |_, _| {});
    assert_eq!(s.cpu.pc(), 0x1004);
    assert_eq!(s.cpu.er(7), 0xff_fefc);
    assert_eq!(peek32(&s.m, 0xff_fefc), 0x1002);
    assert_eq!(s.states, 8);
    // JSR @@aa:8: the target is the longword at H'10 (set to H'2000 by the harness).
    let s = exec("jsr\t@@16 (0x10)", &[0x5f, 0x10], |_, _| {});
    assert_eq!(s.cpu.pc(), 0x2000);
    assert_eq!(peek32(&s.m, 0xff_fefc), 0x1002);
    assert_eq!(s.states, 12);
    let s = exec("rts\t", &[0x54, 0x70], |c, m| {
        c.set_er(7, DATA);
        m.poke(DATA, &0x0000_3456u32.to_be_bytes());
    });
    assert_eq!(s.cpu.pc(), 0x3456);
    assert_eq!(s.cpu.er(7), DATA + 4);
    assert_eq!(s.states, 10);
    // JMP @ERn: bit 0 of the target is ignored (instructions are word-aligned).
    let s = exec("jmp\t@er1", &[0x59, 0x10], |c, _| c.set_er(1, 0x0000_2001));
    assert_eq!(s.cpu.pc(), 0x2000);
    assert_eq!(s.states, 4);
}

#[test]
fn rte_restores_ccr_and_pc() {
    let s = exec("rte\t", &[0x56, 0x70], |c, m| {
        c.set_er(7, DATA);
        m.poke(DATA, &[CCR_N | CCR_C, 0x00, 0x20, 0x00]);
    });
    assert_eq!(s.cpu.ccr(), CCR_N | CCR_C);
    assert_eq!(s.cpu.pc(), 0x2000);
    assert_eq!(s.cpu.er(7), DATA + 4);
    assert_eq!(s.states, 10);
}

// ----- system control ----------------------------------------------------------------------

#[test]
fn trapa_pushes_pc_and_ccr_and_sets_i() {
    let s = exec("trapa\t#0x2", &[0x57, 0x20], |c, m| {
        c.set_ccr(CCR_Z | CCR_U);
        m.poke(0x28, &0x0000_3000u32.to_be_bytes()); // vector 10
    });
    assert_eq!(s.cpu.pc(), 0x3000);
    assert_eq!(
        s.cpu.ccr(),
        CCR_I | CCR_Z | CCR_U,
        "I set, UI (a user bit) kept"
    );
    assert_eq!(s.cpu.er(7), 0xff_fefc);
    assert_eq!(
        peek32(&s.m, 0xff_fefc),
        (u32::from(CCR_Z | CCR_U) << 24) | 0x1002
    );
    assert_eq!(s.states, 14);
    assert_eq!(s.cpu.ccr() & CCR_UI, 0);
}

#[test]
fn ccr_instructions() {
    let s = exec("ldc\t#0x0,ccr", &[0x07, 0x00], |_, _| {});
    assert_eq!(s.cpu.ccr(), 0);
    let s = exec("andc\t#0x7f,ccr", &[0x06, 0x7f], |c, _| c.set_ccr(0xff));
    assert_eq!(s.cpu.ccr(), 0x7f);
    let s = exec("orc\t#0x1,ccr", &[0x04, 0x01], |c, _| c.set_ccr(0x80));
    assert_eq!(s.cpu.ccr(), 0x81);
    let s = exec("xorc\t#0x81,ccr", &[0x05, 0x81], |c, _| c.set_ccr(0x80));
    assert_eq!(s.cpu.ccr(), 0x01);
    let s = exec("stc\tccr,@-er1", &[0x01, 0x40, 0x6d, 0x90], |c, _| {
        c.set_er(1, DATA + 2);
        c.set_ccr(0x8a);
    });
    assert_eq!(s.cpu.er(1), DATA);
    assert_eq!(peek16(&s.m, DATA), 0x8a8a);
    assert_eq!(s.states, 8);
    let s = exec("ldc\t@er1+,ccr", &[0x01, 0x40, 0x6d, 0x10], |c, m| {
        c.set_er(1, DATA);
        m.poke(DATA, &[0x05, 0xaa]);
    });
    assert_eq!(s.cpu.ccr(), 0x05, "LDC takes the upper byte of the word");
    assert_eq!(s.cpu.er(1), DATA + 2);
    assert_eq!(s.states, 8);
}

#[test]
fn eepmov_copies_a_block() {
    let s = exec("eepmov.b\t", &[0x7b, 0x5c, 0x59, 0x8f], |c, m| {
        c.set_er(4, 0x1234_5603); // R4L = 3
        c.set_er(5, DATA);
        c.set_er(6, DATA + 0x100);
        m.poke(DATA, &[1, 2, 3, 4]);
    });
    assert_eq!(
        [
            s.m.peek(DATA + 0x100),
            s.m.peek(DATA + 0x101),
            s.m.peek(DATA + 0x102),
            s.m.peek(DATA + 0x103)
        ],
        [1, 2, 3, 0]
    );
    assert_eq!(s.cpu.er(4), 0x1234_5600, "R4L counted down to 0");
    assert_eq!((s.cpu.er(5), s.cpu.er(6)), (DATA + 3, DATA + 0x103));
    assert_eq!(s.states, 8 + 4 * 3);
    let s = exec("eepmov.w\t", &[0x7b, 0xd4, 0x59, 0x8f], |c, _| {
        c.set_er(4, 0x0000_012c); // R4 = 300
        c.set_er(5, DATA);
        c.set_er(6, DATA + 0x400);
    });
    assert_eq!(s.cpu.er(4), 0);
    assert_eq!(s.cpu.er(6), DATA + 0x400 + 300);
    assert_eq!(s.states, 8 + 4 * 300);
}

#[test]
fn sleep_with_mask_set_halts_and_with_mask_clear_waits() {
    let s = exec("sleep\t", &[0x01, 0x80], |_, _| {});
    assert_eq!(s.event, Ok(Event::Halted));
    assert!(s.cpu.halted());
    assert_eq!(s.states, 2);
    let mut s = exec("sleep\t", &[0x01, 0x80], |c, _| c.set_ccr(0));
    assert_eq!(s.event, Ok(Event::Executed));
    assert!(s.cpu.sleeping());
    // Nothing can wake it: the next step sleeps until the deadline.
    let t = s.m.now();
    assert_eq!(s.cpu.step(&mut s.m, t + 1000), Ok(Event::Asleep));
    assert_eq!(s.m.now(), t + 1000);
}

/// Runs `program` from CODE with SCI1's TXI requested (TE and TIE set) and the TXI vector
/// pointing at a handler at H'3000 (`nop`), for `steps` steps; returns the events.
fn run_with_txi(program: &[u8], ccr: u8, steps: usize) -> (Vec<Event>, h8300h::cpu::Cpu, Machine) {
    let (mut cpu, mut m) = machine();
    m.poke(CODE, program);
    m.poke(u32::from(VECTOR_TXI1) * 4, &0x3000u32.to_be_bytes());
    m.poke(0x3000, &[0x00, 0x00]);
    m.write8(SCI1_SCR, SCR_TE | SCR_TIE);
    cpu.set_pc(CODE);
    cpu.set_ccr(ccr);
    let mut events = Vec::new();
    for _ in 0..steps {
        events.push(cpu.step(&mut m, u64::MAX).expect("step"));
    }
    (events, cpu, m)
}

#[test]
fn interrupt_entry_pushes_pc_ccr_and_costs_17_states() {
    let (mut cpu, mut m) = machine();
    m.poke(CODE, &[0x00, 0x00]);
    m.poke(u32::from(VECTOR_TXI1) * 4, &0x3000u32.to_be_bytes());
    m.write8(SCI1_SCR, SCR_TE | SCR_TIE);
    cpu.set_pc(CODE);
    cpu.set_ccr(CCR_Z);
    let t0 = m.now();
    assert_eq!(
        cpu.step(&mut m, u64::MAX),
        Ok(Event::Interrupt(VECTOR_TXI1))
    );
    // Priority decision 1 (internal interrupt) + stack 4 + vector 4 + prefetch 4 + internal 4.
    assert_eq!(m.now() - t0, 17);
    assert_eq!(cpu.pc(), 0x3000);
    assert_eq!(cpu.ccr(), CCR_I | CCR_Z);
    assert_eq!(peek32(&m, 0xff_fefc), (u32::from(CCR_Z) << 24) | CODE);
}

#[test]
fn masked_interrupts_wait_and_ldc_family_delays_acceptance() {
    // With I = 1 the interrupt is not taken.
    let (ev, _, _) = run_with_txi(&[0x00, 0x00, 0x00, 0x00], CCR_I, 2);
    assert_eq!(ev, vec![Event::Executed, Event::Executed]);
    // ANDC clears I; the instruction after it still runs before the interrupt is taken.
    let (ev, cpu, _) = run_with_txi(&[0x06, 0x7f, 0x00, 0x00, 0x00, 0x00], CCR_I, 3);
    assert_eq!(
        ev,
        vec![
            Event::Executed,
            Event::Executed,
            Event::Interrupt(VECTOR_TXI1)
        ]
    );
    assert_eq!(cpu.pc(), 0x3000);
}

// ----- errors ------------------------------------------------------------------------------

#[test]
fn undefined_opcode_names_pc_and_bytes() {
    let (mut cpu, mut m) = machine();
    m.poke(CODE, &[0x00, 0x01]);
    cpu.set_pc(CODE);
    let e = cpu.step(&mut m, u64::MAX).unwrap_err();
    assert_eq!(
        e,
        CpuError::UndefinedOpcode {
            pc: CODE,
            bytes: "00 01".into()
        }
    );
    let msg = e.to_string();
    assert!(msg.contains("H'001000") && msg.contains("00 01"), "{msg}");
    assert_eq!(cpu.pc(), CODE, "PC stays at the bad instruction");
}

#[test]
fn fetch_outside_rom_and_ram_is_an_error() {
    let (mut cpu, mut m) = machine();
    cpu.set_pc(0x08_0000);
    let e = cpu.step(&mut m, u64::MAX).unwrap_err();
    assert!(
        matches!(e, CpuError::FetchOutside { pc: 0x08_0000, .. }),
        "{e}"
    );
    cpu.set_pc(0xff_ff20);
    let e = cpu.step(&mut m, u64::MAX).unwrap_err();
    assert!(
        matches!(e, CpuError::FetchOutside { pc: 0xff_ff20, .. }),
        "{e}"
    );
    // An instruction that starts in ROM but runs off its end.
    let (mut cpu, mut m) = machine();
    m.poke(0x07_fffe, &[0x7a, 0x00]);
    cpu.set_pc(0x07_fffe);
    let e = cpu.step(&mut m, u64::MAX).unwrap_err();
    assert!(
        matches!(
            e,
            CpuError::FetchOutside {
                addr: 0x08_0000,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn movfpe_is_refused_on_the_h8_3052f() {
    let s = exec(
        "movfpe\t@0x100:16,r1l",
        &[0x6a, 0x49, 0x01, 0x00],
        |_, _| {},
    );
    assert!(matches!(
        s.event,
        Err(CpuError::Unsupported { pc: CODE, .. })
    ));
    assert_eq!(s.cpu.pc(), CODE);
}

#[test]
fn code_runs_from_ram_too() {
    let (mut cpu, mut m) = machine();
    m.poke(DATA, &[0x79, 0x00, 0x12, 0x34]); // mov.w #0x1234,r0
    cpu.set_pc(DATA);
    assert_eq!(cpu.step(&mut m, u64::MAX), Ok(Event::Executed));
    assert_eq!(cpu.er(0) & 0xffff, 0x1234);
}

#[test]
fn sleep_fast_forwards_to_the_sci_interrupt_that_wakes_it() {
    use h8_3052f::periph::sci::{SCI1_SSR, SCI1_TDR, SSR_TDRE};
    let (mut cpu, mut m) = machine();
    m.poke(CODE, &[0x01, 0x80]); // sleep
    m.poke(u32::from(VECTOR_TXI1) * 4, &0x3000u32.to_be_bytes());
    m.poke(0x3000, &[0x00, 0x00]);
    m.write8(SCI1_SCR, SCR_TE);
    // Two bytes: the first goes straight to the shift register, the second waits a frame.
    for b in [b'a', b'b'] {
        let ssr = m.read8(SCI1_SSR);
        assert_ne!(ssr & SSR_TDRE, 0);
        m.write8(SCI1_TDR, b);
        m.write8(SCI1_SSR, ssr & !SSR_TDRE);
    }
    let frame = m.sci().frame_states();
    assert_eq!(frame, 10 * 32 * 256, "8N1 at the reset BRR of H'FF");
    m.write8(SCI1_SCR, SCR_TE | SCR_TIE);
    let wake_at = m.sci().next_irq_time(m.now()).expect("TXI will come");
    cpu.set_pc(CODE);
    cpu.set_ccr(0);
    assert_eq!(cpu.step(&mut m, u64::MAX), Ok(Event::Executed));
    assert!(cpu.sleeping());
    assert_eq!(
        cpu.step(&mut m, u64::MAX),
        Ok(Event::Interrupt(VECTOR_TXI1))
    );
    // Woken exactly when TDRE came back, then 17 states of interrupt entry.
    assert_eq!(m.now(), wake_at + 17);
    assert_eq!(cpu.pc(), 0x3000);
    assert_eq!(peek32(&m, 0xff_fefc), CODE + 2, "returns after the SLEEP");
    assert_eq!(m.sci_mut().take_output(), b"ab");
}
