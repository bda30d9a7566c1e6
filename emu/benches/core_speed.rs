//! Core speed: emulated states per host second on a compute-bound loop (loads, stores with
//! displacement and post-increment, 16/32-bit arithmetic, XOR, shifts, compare and branch, a
//! call with push/pop and return; the kind of code GCC makes of a C inner loop).
//!
//! Criterion's throughput is set in states, so its `thrpt` line reads "emulated states per
//! second"; the target is at least 100 M states/s (4 × real time at φ = 25 MHz).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use emu::chip::machine::Machine;
use emu::core::bus::Bus;
use emu::core::cpu::Cpu;

/// States emulated per benchmark iteration.
const STATES_PER_ITER: u64 = 2_000_000;

/// The loop at H'000100 (h8300-hms-as 2.16.1, `.h8300h`):
/// ```text
/// _start: mov.l #0xffff10,er7 ; mov.l #0xffe000,er5 ; sub.l er1,er1 ; sub.l er3,er3
/// outer:  mov.w #0x100,r6
/// loop:   mov.l @er5,er0 ; add.l er0,er1 ; mov.w @(0x2:16,er5),r2 ; add.w r2,r3
///         xor.l er1,er3 ; shll.l er1 ; mov.l er1,@(0x4:16,er5) ; mov.b @er5+,r4l
///         cmp.l #0xffe400,er5 ; bcs nowrap ; mov.l #0xffe000,er5
/// nowrap: bsr sub ; dec.w #1,r6 ; bne loop ; bra outer
/// sub:    mov.l er4,@-er7 ; extu.w r4 ; add.w r4,e3 ; mov.l @er7+,er4 ; rts
/// ```
const LOOP: [u8; 82] = [
    0x7a, 0x07, 0x00, 0xff, 0xff, 0x10, 0x7a, 0x05, 0x00, 0xff, 0xe0, 0x00, 0x1a, 0x91, 0x1a, 0xb3,
    0x79, 0x06, 0x01, 0x00, 0x01, 0x00, 0x69, 0x50, 0x0a, 0x81, 0x6f, 0x52, 0x00, 0x02, 0x09, 0x23,
    0x01, 0xf0, 0x65, 0x13, 0x10, 0x31, 0x01, 0x00, 0x6f, 0xd1, 0x00, 0x04, 0x6c, 0x5c, 0x7a, 0x25,
    0x00, 0xff, 0xe4, 0x00, 0x45, 0x06, 0x7a, 0x05, 0x00, 0xff, 0xe0, 0x00, 0x55, 0x06, 0x1b, 0x56,
    0x46, 0xd2, 0x40, 0xcc, 0x01, 0x00, 0x6d, 0xf4, 0x17, 0x54, 0x09, 0x4b, 0x01, 0x00, 0x6d, 0x74,
    0x54, 0x70,
];

fn core_speed(c: &mut Criterion) {
    let mut m = Machine::new();
    m.poke(0, &0x100u32.to_be_bytes());
    m.poke(0x100, &LOOP);
    let mut cpu = Cpu::new();
    cpu.reset(&mut m);
    let mut group = c.benchmark_group("core_speed");
    group.throughput(Throughput::Elements(STATES_PER_ITER));
    group.bench_function("compute_loop_states", |b| {
        b.iter(|| {
            let end = m.now() + STATES_PER_ITER;
            while m.now() < end {
                if cpu.step(&mut m, u64::MAX).is_err() {
                    panic!("the benchmark loop stopped at PC {:06x}", cpu.pc());
                }
            }
            cpu.er(1)
        });
    });
    group.finish();
}

criterion_group!(benches, core_speed);
criterion_main!(benches);
