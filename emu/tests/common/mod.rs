//! Shared set-up for the per-instruction tests: one instruction at H'001000 in flash, run for
//! one step on a [`Machine`], with its disassembly checked against the text the test names
//! (the disassembler itself is checked against objdump by `objdump_compare.rs`, so the bytes in
//! each test are known to encode what the test says).
#![allow(dead_code)]

use h8_3052f::machine::Machine;
use h8300h::bus::Bus;
use h8300h::cpu::decode::decode_bytes;
use h8300h::cpu::disasm::format_instr;
use h8300h::cpu::{CCR_I, Cpu, CpuError, Event};

/// Where the instruction under test sits.
pub const CODE: u32 = 0x1000;
/// A RAM address for data.
pub const DATA: u32 = 0xFF_E800;

/// The state after one step.
pub struct Step {
    pub cpu: Cpu,
    pub m: Machine,
    pub states: u64,
    pub event: Result<Event, CpuError>,
}

/// CPU and machine before the instruction: ERn = H'FFE000 + n·H'100 for n = 0–3, 5, 6
/// (RAM), ER4 = 0, ER7 = H'FFFF00, CCR = I, vectors 4 (H'10) and 9 (TRAPA #1, H'24) pointing
/// at H'002000.
pub fn machine() -> (Cpu, Machine) {
    let mut cpu = Cpu::new();
    let mut m = Machine::new();
    for n in 0..7 {
        cpu.set_er(n, 0xFF_E000 + 0x100 * n as u32);
    }
    cpu.set_er(4, 0);
    cpu.set_er(7, 0xFF_FF00);
    cpu.set_ccr(CCR_I);
    m.poke(0x10, &0x2000u32.to_be_bytes());
    m.poke(0x24, &0x2000u32.to_be_bytes());
    (cpu, m)
}

/// Runs the instruction `bytes` (whose objdump text is `text`) once after `prep`.
pub fn exec(text: &str, bytes: &[u8], prep: impl FnOnce(&mut Cpu, &mut Machine)) -> Step {
    let d = decode_bytes(bytes).unwrap_or_else(|e| panic!("{text}: {e}"));
    assert_eq!(format_instr(d, CODE), text, "bytes {bytes:02x?}");
    assert_eq!(d.len_bytes() as usize, bytes.len(), "{text}: length");
    let (mut cpu, mut m) = machine();
    m.poke(CODE, bytes);
    prep(&mut cpu, &mut m);
    cpu.set_pc(CODE);
    let t0 = m.now();
    let event = cpu.step(&mut m, u64::MAX);
    let states = m.now() - t0;
    Step {
        cpu,
        m,
        states,
        event,
    }
}

/// Reads a big-endian word of RAM or flash without a bus cycle.
pub fn peek16(m: &Machine, a: u32) -> u16 {
    u16::from_be_bytes([m.peek(a), m.peek(a + 1)])
}

/// Reads a big-endian longword of RAM or flash without a bus cycle.
pub fn peek32(m: &Machine, a: u32) -> u32 {
    (u32::from(peek16(m, a)) << 16) | u32::from(peek16(m, a + 2))
}
