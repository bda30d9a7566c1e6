//! Core speed: emulated states per host second on code without I/O, on the fast path
//! ([`Cpu::step`]) and on the reference path ([`Cpu::step_reference`]) side by side, so one run
//! shows both and their ratio.
//!
//! - `crcmacdiv`: the C program `tests/programs/crcmacdiv.c` (a bitwise CRC-32, the firmware
//!   learner's MULXS.W multiply-accumulate loop, DIVXS.W), built by that folder's `build.sh`.
//!   Each iteration runs its first 2 M states after reset, which are compute only: the program
//!   touches no I/O register until its rounds are done (about 6 M states; checked by
//!   `tests/fast_path.rs`).
//! - `compute_loop`: a hand-assembled loop (loads, stores with displacement and
//!   post-increment, 16/32-bit arithmetic, XOR, shifts, compare and branch, a call with
//!   push/pop and return; the kind of code GCC makes of a C inner loop).
//!
//! Criterion's throughput is set in states, so each `thrpt` line reads "emulated states per
//! second"; the goal is at least 500 M states/s on the fast path (20 × real time at φ = 25 MHz).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use h8_3052f::machine::Machine;
use h8300h::bus::Bus;
use h8300h::cpu::Cpu;
use h8300h::srec;

/// States emulated per benchmark iteration.
const STATES_PER_ITER: u64 = 2_000_000;

/// The benchmark program's image, as `tests/programs/build.sh` makes it.
const CRCMACDIV_MOT: &[u8] = include_bytes!("../tests/programs/crcmacdiv.mot");

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

/// How a benchmark drives the core.
#[derive(Clone, Copy)]
enum Drive {
    /// [`Cpu::step`] in a loop (the fast path).
    Step,
    /// [`Cpu::run`] to the end of the window (the fast path).
    Run,
    /// [`Cpu::step_reference`] in a loop.
    Reference,
}

/// Runs `cpu` for `states` states.
fn run_states(cpu: &mut Cpu, m: &mut Machine, states: u64, drive: Drive) {
    let end = m.now() + states;
    while m.now() < end {
        let r = match drive {
            Drive::Step => cpu.step(m, u64::MAX),
            Drive::Run => cpu.run(m, end),
            Drive::Reference => cpu.step_reference(m, u64::MAX),
        };
        if r.is_err() {
            panic!("the benchmark program stopped at PC {:06x}", cpu.pc());
        }
    }
}

/// The benchmark lines: fast path by step and by run, reference path.
const DRIVES: [(&str, Drive); 3] = [
    ("fast", Drive::Step),
    ("fast_run", Drive::Run),
    ("reference", Drive::Reference),
];

fn crcmacdiv(c: &mut Criterion) {
    let image = srec::parse(CRCMACDIV_MOT).expect("crcmacdiv.mot parses");
    let mut group = c.benchmark_group("core_speed_crcmacdiv");
    group.throughput(Throughput::Elements(STATES_PER_ITER));
    for (name, drive) in DRIVES {
        let mut m = Machine::with_image(&image).expect("crcmacdiv.mot loads");
        let mut cpu = Cpu::new();
        group.bench_function(name, |b| {
            b.iter(|| {
                // From reset: start-up code, then the kernels (no I/O in this window).
                cpu.reset(&mut m);
                run_states(&mut cpu, &mut m, STATES_PER_ITER, drive);
                cpu.er(0)
            });
        });
    }
    group.finish();
}

fn compute_loop(c: &mut Criterion) {
    let mut group = c.benchmark_group("core_speed");
    group.throughput(Throughput::Elements(STATES_PER_ITER));
    for (suffix, drive) in DRIVES {
        let name = format!("compute_loop_states_{suffix}");
        let mut m = Machine::new();
        m.poke(0, &0x100u32.to_be_bytes());
        m.poke(0x100, &LOOP);
        let mut cpu = Cpu::new();
        cpu.reset(&mut m);
        group.bench_function(&name, |b| {
            b.iter(|| {
                run_states(&mut cpu, &mut m, STATES_PER_ITER, drive);
                cpu.er(1)
            });
        });
    }
    group.finish();
}

criterion_group!(benches, crcmacdiv, compute_loop);
criterion_main!(benches);
