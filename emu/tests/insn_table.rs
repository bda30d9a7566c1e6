//! One source of state counts: every instruction form of `nn_q15`'s cost
//! table ([`nn_q15::cost::Insn`]) is run on the H8/300H core from on-chip flash with on-chip RAM
//! operands, and the states the core counts must be the table's.

use h8_3052f::mcu::{Mcu, McuConfig};
use h8_3052f::pins::NullBoard;
use h8300h::bus::Bus;
use h8300h::cpu::Cpu;
use nn_q15::cost::Insn;

/// Where the instruction is placed (flash) and where its pointers point (RAM, word-aligned).
const CODE: u32 = 0x1000;
const DATA: u32 = 0xFF_E000;

#[test]
fn every_insn_form_costs_on_the_core_what_the_table_says() {
    for insn in Insn::ALL {
        let (text, bytes) = insn.example();
        let mut mcu = Mcu::new(McuConfig::default(), NullBoard).unwrap();
        mcu.poke(CODE, bytes);
        // A return address for RTS, non-zero divisors and pointers into RAM.
        mcu.poke(DATA, &[0x00, 0x00, 0x20, 0x00]);
        let mut cpu = Cpu::new();
        for r in 0..7 {
            cpu.set_er(r, DATA);
        }
        cpu.set_er(4, DATA | 0x0100_0007); // DIVXS.W R4: a divisor of 7
        cpu.set_er(7, DATA);
        cpu.set_pc(CODE);
        let t0 = mcu.now();
        cpu.step(&mut mcu, u64::MAX)
            .unwrap_or_else(|e| panic!("{insn:?} ({text}): {e}"));
        let decoded = h8300h::cpu::disasm::format_instr(cpu.last_executed(), CODE);
        assert_eq!(
            mcu.now() - t0,
            u64::from(insn.states()),
            "{insn:?}: `{text}` ran as `{decoded}`"
        );
        assert_eq!(
            u32::from(cpu.last_executed().words) * 2,
            insn.bytes(),
            "{insn:?}: `{text}` decoded as `{decoded}`"
        );
    }
}
