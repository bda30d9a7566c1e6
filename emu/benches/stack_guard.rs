//! What the stack guard costs when nothing overflows: the same work with the guard off and on,
//! side by side in one run (`cargo bench -p emu --bench stack_guard`).
//!
//! - `crcmacdiv` and `compute_loop`: the core-speed workloads of `core_speed.rs` (compute
//!   only; the loop makes a call with a push and a pop every iteration), on the fast path
//!   with [`Cpu::run`]; throughput in emulated states per second.
//! - `firmware_step`: the robot firmware under `FirmwareController`, one step period (its
//!   ticks, the step, a save every 20 steps), the way a swarm runs it.
//!
//! The guard checks only the instructions that touch the stack (pushes, calls, returns,
//! interrupt entries, loads and stores through ER7) and those that set SP as a register; the
//! ratio of the `on` and `off` lines is its cost.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use h8_3052f::machine::Machine;
use h8_3052f::mcu::{Mcu, McuConfig};
use h8_3052f::pins::NullBoard;
use h8300h::bus::Bus;
use h8300h::cpu::{Cpu, StackGuard, StackGuardMode, StackRoom};
use h8300h::srec;
use robot_board::firmware::{ConfigBlock, Firmware, FirmwareController};

/// States emulated per iteration of the compute workloads.
const STATES_PER_ITER: u64 = 2_000_000;

/// The core-speed benchmark program (`tests/programs/crcmacdiv.c`).
const CRCMACDIV_MOT: &[u8] = include_bytes!("../tests/programs/crcmacdiv.mot");

/// `core_speed.rs`'s loop at H'000100: loads, stores, arithmetic, and `bsr sub` with
/// `mov.l er4,@-er7 ; … ; mov.l @er7+,er4 ; rts` in every iteration.
const LOOP: [u8; 82] = [
    0x7a, 0x07, 0x00, 0xff, 0xff, 0x10, 0x7a, 0x05, 0x00, 0xff, 0xe0, 0x00, 0x1a, 0x91, 0x1a, 0xb3,
    0x79, 0x06, 0x01, 0x00, 0x01, 0x00, 0x69, 0x50, 0x0a, 0x81, 0x6f, 0x52, 0x00, 0x02, 0x09, 0x23,
    0x01, 0xf0, 0x65, 0x13, 0x10, 0x31, 0x01, 0x00, 0x6f, 0xd1, 0x00, 0x04, 0x6c, 0x5c, 0x7a, 0x25,
    0x00, 0xff, 0xe4, 0x00, 0x45, 0x06, 0x7a, 0x05, 0x00, 0xff, 0xe0, 0x00, 0x55, 0x06, 0x1b, 0x56,
    0x46, 0xd2, 0x40, 0xcc, 0x01, 0x00, 0x6d, 0xf4, 0x17, 0x54, 0x09, 0x4b, 0x01, 0x00, 0x6d, 0x74,
    0x54, 0x70,
];

/// The guard settings compared: off, and on (stopping) over `room`.
fn guards(room: StackRoom) -> [(&'static str, Option<StackGuard>); 2] {
    [
        ("off", None),
        (
            "on",
            Some(StackGuard {
                room,
                mode: StackGuardMode::Stop,
            }),
        ),
    ]
}

fn run_states(cpu: &mut Cpu, m: &mut Machine, states: u64) {
    let end = m.now() + states;
    while m.now() < end {
        if cpu.run(m, end).is_err() {
            panic!("the benchmark program stopped at PC {:06x}", cpu.pc());
        }
    }
}

fn crcmacdiv(c: &mut Criterion) {
    let image = srec::parse(CRCMACDIV_MOT).expect("crcmacdiv.mot parses");
    let mut group = c.benchmark_group("stack_guard_crcmacdiv");
    group.throughput(Throughput::Elements(STATES_PER_ITER));
    for (name, guard) in guards(StackRoom::RAM) {
        let mut m = Machine::with_image(&image).expect("crcmacdiv.mot loads");
        let mut cpu = Cpu::new();
        cpu.set_stack_guard(guard);
        group.bench_function(name, |b| {
            b.iter(|| {
                cpu.reset(&mut m);
                run_states(&mut cpu, &mut m, STATES_PER_ITER);
                cpu.er(0)
            });
        });
    }
    group.finish();
}

fn compute_loop(c: &mut Criterion) {
    let mut group = c.benchmark_group("stack_guard_compute_loop");
    group.throughput(Throughput::Elements(STATES_PER_ITER));
    for (name, guard) in guards(StackRoom::RAM) {
        let mut m = Machine::new();
        m.poke(0, &0x100u32.to_be_bytes());
        m.poke(0x100, &LOOP);
        let mut cpu = Cpu::new();
        cpu.set_stack_guard(guard);
        cpu.reset(&mut m);
        group.bench_function(name, |b| {
            b.iter(|| {
                run_states(&mut cpu, &mut m, STATES_PER_ITER);
                cpu.er(1)
            });
        });
    }
    group.finish();
}

fn firmware_step(c: &mut Criterion) {
    let fw = Firmware::robot().expect("the robot firmware");
    let mut group = c.benchmark_group("stack_guard_firmware_step");
    group.throughput(Throughput::Elements(1));
    for (name, guard) in guards(fw.stack_room()) {
        let mut mcu = Mcu::new(McuConfig::default(), NullBoard).expect("an MCU");
        let mut ctl = FirmwareController::start(&fw, &mut mcu, Some(&ConfigBlock::ARENA))
            .expect("the firmware loads");
        if guard.is_none() {
            ctl.disable_stack_guard();
        }
        group.bench_function(name, |b| {
            b.iter(|| {
                ctl.run_to_sensing(&mut mcu).expect("a step begins");
                ctl.run_to_sleep(&mut mcu).expect("it sleeps again");
                mcu.now()
            });
        });
    }
    group.finish();
}

criterion_group!(benches, crcmacdiv, compute_loop, firmware_step);
criterion_main!(benches);
