//! Properties: nothing a caller can pass makes the decoder, the core, the S-record loader or
//! the run API panic; and the add/subtract flags agree with a reference computed in wide
//! integers.

use h8_3052f::machine::Machine;
use h8_3052f::run::{RunOptions, run_image};
use h8300h::bus::Bus;
use h8300h::cpu::decode::{Size, decode_bytes};
use h8300h::cpu::disasm::{disassemble, format_instr};
use h8300h::cpu::{CCR_C, CCR_H, CCR_N, CCR_V, CCR_Z, Cpu};
use h8300h::srec::{self, Chunk, SrecImage};
use proptest::prelude::*;

proptest! {
    #[test]
    fn decoder_and_disassembler_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..12)) {
        if let Ok(d) = decode_bytes(&bytes) {
            prop_assert!(d.len_bytes() as usize <= bytes.len());
            prop_assert!((1..=5).contains(&d.words));
            let text = format_instr(d, 0x1000);
            prop_assert!(!text.is_empty());
        }
        let lines = disassemble(&bytes, 0xff_fff0);
        let total: usize = lines.iter().map(|l| l.bytes.len()).sum();
        prop_assert_eq!(total, bytes.len());
    }

    #[test]
    fn core_never_panics_on_random_code_and_registers(
        code in proptest::collection::vec(any::<u8>(), 2..64),
        regs in proptest::array::uniform8(any::<u32>()),
        ccr in any::<u8>(),
        in_ram in any::<bool>(),
    ) {
        let mut m = Machine::new();
        let base = if in_ram { 0xff_e000 } else { 0x1000 };
        m.poke(base, &code);
        let mut cpu = Cpu::new();
        for (i, r) in regs.iter().enumerate() {
            cpu.set_er(i, *r);
        }
        cpu.set_ccr(ccr);
        cpu.set_pc(base);
        for _ in 0..32 {
            let deadline = m.now() + 100_000;
            match cpu.step(&mut m, deadline) {
                Ok(_) => {}
                Err(e) => {
                    prop_assert!(!e.to_string().is_empty());
                    break;
                }
            }
        }
    }

    #[test]
    fn srec_parser_never_panics(text in proptest::collection::vec(any::<u8>(), 0..200)) {
        let _ = srec::parse(&text);
    }

    #[test]
    fn srec_parser_never_panics_on_mutated_records(
        data in proptest::collection::vec(any::<u8>(), 1..64),
        pos in any::<usize>(),
        byte in any::<u8>(),
        cut in any::<usize>(),
    ) {
        let img = SrecImage {
            header: Some(b"p".to_vec()),
            chunks: vec![Chunk { address: 0x100, data }],
            start: Some(0x100),
        };
        let mut text = srec::write_s3(&img, 16).into_bytes();
        let p = pos % text.len();
        text[p] = byte;
        text.truncate(cut % (text.len() + 1));
        if let Err(e) = srec::parse(&text) {
            prop_assert!(e.line >= 1);
            prop_assert!(!e.to_string().is_empty());
        }
    }

    #[test]
    fn srec_round_trip(
        chunks in proptest::collection::vec((0u32..0x7_0000, proptest::collection::vec(any::<u8>(), 1..40)), 1..5),
        per in 1usize..64,
    ) {
        let img = SrecImage {
            header: Some(b"round trip".to_vec()),
            chunks: chunks.into_iter().map(|(a, d)| Chunk { address: a * 16, data: d }).collect(),
            start: Some(0),
        };
        let parsed = srec::parse(srec::write_s3(&img, per).as_bytes()).unwrap();
        // The parser merges contiguous records; compare byte by byte.
        let flat = |i: &SrecImage| {
            let mut v: Vec<(u32, u8)> = Vec::new();
            for c in &i.chunks {
                for (k, b) in c.data.iter().enumerate() {
                    v.push((c.address + k as u32, *b));
                }
            }
            v
        };
        prop_assert_eq!(flat(&parsed), flat(&img));
        prop_assert_eq!(parsed.start, Some(0));
    }

    #[test]
    fn run_image_never_panics_on_random_images(
        code in proptest::collection::vec(any::<u8>(), 2..256),
    ) {
        // A reset vector pointing at random code.
        let mut data = 0x100u32.to_be_bytes().to_vec();
        data.resize(0x100, 0);
        data.extend_from_slice(&code);
        let img = SrecImage { header: None, chunks: vec![Chunk { address: 0, data }], start: None };
        let text = srec::write_s3(&img, 32);
        let mut out = Vec::new();
        let opts = RunOptions { max_states: Some(20_000), ..RunOptions::default() };
        let r = run_image(text.as_bytes(), &opts, &mut out, None);
        prop_assert!(r.is_ok());
    }

    #[test]
    fn add_and_sub_flags_match_a_wide_reference(a in any::<u32>(), b in any::<u32>(), size in 0..3u8) {
        let (size, bits) = match size { 0 => (Size::Byte, 8), 1 => (Size::Word, 16), _ => (Size::Long, 32) };
        let mask = if bits == 32 { u32::MAX } else { (1u32 << bits) - 1 };
        let (a, b) = (a & mask, b & mask);
        // add.b r0l,r1l / add.w r0,r1 / add.l er0,er1 and the sub forms.
        let (add, sub): (&[u8], &[u8]) = match size {
            Size::Byte => (&[0x08, 0x89], &[0x18, 0x89]),
            Size::Word => (&[0x09, 0x01], &[0x19, 0x01]),
            Size::Long => (&[0x0a, 0x81], &[0x1a, 0x81]),
        };
        let run = |code: &[u8]| {
            let mut m = Machine::new();
            m.poke(0x1000, code);
            let mut cpu = Cpu::new();
            cpu.set_er(0, b);
            cpu.set_er(1, a);
            cpu.set_ccr(0);
            cpu.set_pc(0x1000);
            cpu.step(&mut m, u64::MAX).unwrap();
            (cpu.er(1) & mask, cpu.ccr())
        };
        let sa = i64::from(a) - if a >> (bits - 1) & 1 == 1 { 1i64 << bits } else { 0 };
        let sb = i64::from(b) - if b >> (bits - 1) & 1 == 1 { 1i64 << bits } else { 0 };
        let half = (1u64 << (bits - 4)) - 1;
        let flags = |r: u32, h: bool, v: bool, c: bool| {
            let mut f = 0;
            if h { f |= CCR_H; }
            if r >> (bits - 1) & 1 == 1 { f |= CCR_N; }
            if r == 0 { f |= CCR_Z; }
            if v { f |= CCR_V; }
            if c { f |= CCR_C; }
            f
        };
        let (r, ccr) = run(add);
        let wide = u64::from(a) + u64::from(b);
        prop_assert_eq!(r, wide as u32 & mask);
        let sum = sa + sb;
        let v = sum >= 1i64 << (bits - 1) || sum < -(1i64 << (bits - 1));
        let h = (u64::from(a) & half) + (u64::from(b) & half) > half;
        prop_assert_eq!(ccr, flags(r, h, v, wide > u64::from(mask)));
        let (r, ccr) = run(sub);
        prop_assert_eq!(r, a.wrapping_sub(b) & mask);
        let diff = sa - sb;
        let v = diff >= 1i64 << (bits - 1) || diff < -(1i64 << (bits - 1));
        let h = (u64::from(b) & half) > (u64::from(a) & half);
        prop_assert_eq!(ccr, flags(r, h, v, b > a));
    }
}
