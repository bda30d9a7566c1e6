//! The GDB stub (`h8_3052f::gdb`) driven over loopback by a protocol client written for the
//! test (`gdb_client`): the robot firmware on the emulated H8/3052F, stopped at a breakpoint
//! at `learner_forward`, stepped, watched and read, each answer compared with a second
//! emulator that runs the same firmware without a debugger.

mod gdb_client;

use std::thread::JoinHandle;

use gdb_client::Client;
use h8_3052f::gdb::GdbListener;
use h8_3052f::mcu::Mcu;
use h8_3052f::pins::NullBoard;
use h8_3052f::run::{Outcome, Probes, RunOptions, RunReport, run_mcu_probed};
use h8300h::bus::Bus;
use h8300h::cpu::Cpu;
use robot_board::board::{RobotBoard, RobotConfig, robot_mcu};
use robot_board::firmware::Firmware;

/// Two seconds of emulated time: the firmware's first steps.
const BUDGET_STATES: u64 = 50_000_000;

/// The MCU `h8swarm emu` runs images on: the robot's board, nothing connected but its EEPROMs.
type EmuMcu = Mcu<RobotBoard<NullBoard>>;

/// The firmware on a fresh MCU, reset.
fn machine(fw: &Firmware) -> (Cpu, EmuMcu) {
    let mut mcu = robot_mcu(NullBoard, &RobotConfig::default()).unwrap();
    let mut cpu = Cpu::new();
    fw.install(&mut mcu, &mut cpu, None).unwrap();
    (cpu, mcu)
}

/// Starts the firmware under a stub on an ephemeral loopback port and connects a client.
fn debugged(fw: &Firmware) -> (Client, JoinHandle<RunReport>) {
    let listener = GdbListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr();
    let fw = fw.clone();
    let run = std::thread::spawn(move || {
        let mut debugger = listener.accept().unwrap();
        let (mut cpu, mut mcu) = machine(&fw);
        run_mcu_probed(
            &mut cpu,
            &mut mcu,
            &RunOptions {
                max_states: Some(BUDGET_STATES),
                ..RunOptions::default()
            },
            &mut std::io::sink(),
            Probes {
                debugger: Some(&mut debugger),
                ..Probes::default()
            },
        )
        .unwrap()
    });
    (Client::connect(addr), run)
}

/// The reference: steps `cpu` until its PC is `addr` (before executing it).
fn run_to(cpu: &mut Cpu, mcu: &mut EmuMcu, addr: u32) {
    while cpu.pc() != addr {
        assert!(mcu.now() < BUDGET_STATES, "never reached {addr:06x}");
        cpu.step(mcu, BUDGET_STATES).unwrap();
    }
}

/// The registers as GDB's h8300h layout gives them: ER0-ER7, CCR, PC, cycles, tick, inst.
fn expected_registers(cpu: &Cpu, mcu: &EmuMcu) -> Vec<u32> {
    let mut r = cpu.regs().to_vec();
    r.push(u32::from(cpu.ccr()));
    r.push(cpu.pc());
    r.push(mcu.now() as u32);
    r.push(0);
    r.push(cpu.instructions() as u32);
    r
}

#[test]
fn a_gdb_client_reads_breaks_steps_watches_and_kills_the_firmware() {
    let fw = Firmware::robot().unwrap();
    let forward = fw.symbols.addr("learner_forward").unwrap();
    let ticks = fw.symbols.addr("ticks").unwrap();
    let (mut reference_cpu, mut reference) = machine(&fw);
    let (mut gdb, run) = debugged(&fw);

    // Stopped before the first instruction: the registers are the reset state.
    let stop = gdb.handshake();
    assert!(stop.starts_with("S05") || stop.starts_with("T05"), "{stop}");
    assert_eq!(
        gdb.registers(),
        expected_registers(&reference_cpu, &reference)
    );
    // The target description names the architecture.
    let xml = gdb.ask("qXfer:features:read:target.xml:0,fff");
    assert!(xml.contains("h8300:h8300h"), "{xml}");

    // Memory: the flash as the image holds it; RAM written and read back; I/O refused.
    let code = gdb.read(forward, 16).unwrap();
    let flash: Vec<u8> = (0..16).map(|i| reference.peek(forward + i)).collect();
    assert_eq!(code, flash);
    let scratch = 0x00FF_FF00 - 0x100; // RAM under the initial stack, unused at reset
    assert_eq!(gdb.write(scratch, &[0xDE, 0xAD, 0xBE, 0xEF]), "OK");
    assert_eq!(gdb.read(scratch, 4).unwrap(), [0xDE, 0xAD, 0xBE, 0xEF]);
    assert!(gdb.write(0x00FF_FFB0, &[0]).starts_with('E'), "I/O write");
    assert_eq!(gdb.write(scratch, &[0, 0, 0, 0]), "OK");

    // A breakpoint at learner_forward: continue stops there, in the state the reference
    // reaches without a debugger (same registers, same clock).
    assert_eq!(gdb.ask(&format!("Z0,{forward:x},2")), "OK");
    let stop = gdb.ask("c");
    assert!(
        stop.starts_with("T05") && stop.contains("swbreak"),
        "{stop}"
    );
    run_to(&mut reference_cpu, &mut reference, forward);
    assert_eq!(
        gdb.registers(),
        expected_registers(&reference_cpu, &reference)
    );
    let clock = gdb.monitor("clock");
    assert!(
        clock.contains(&format!("clock: {} states", reference.now())),
        "{clock}"
    );
    assert!(
        clock.contains(&format!("{} instructions", reference_cpu.instructions())),
        "{clock}"
    );

    // Single steps: one instruction each, as the reference executes it.
    for _ in 0..3 {
        let stop = gdb.ask("s");
        assert!(stop.starts_with("T05") || stop.starts_with("S05"), "{stop}");
        reference_cpu.step(&mut reference, BUDGET_STATES).unwrap();
        assert_eq!(
            gdb.registers(),
            expected_registers(&reference_cpu, &reference)
        );
    }
    assert_ne!(reference_cpu.pc(), forward);

    // A write watchpoint on `ticks`: the next stop is in the tick interrupt's handler, just
    // after it counted the tick.
    assert_eq!(gdb.ask(&format!("z0,{forward:x},2")), "OK");
    let before = gdb.read(ticks, 4).unwrap();
    assert_eq!(gdb.ask(&format!("Z2,{ticks:x},4")), "OK");
    let stop = gdb.ask("c");
    assert!(stop.starts_with("T05") && stop.contains("watch"), "{stop}");
    assert!(
        stop.contains(&format!("{ticks:x}")),
        "{stop} names the watched address"
    );
    let after = gdb.read(ticks, 4).unwrap();
    assert_eq!(
        u32::from_be_bytes(after.clone().try_into().unwrap()),
        u32::from_be_bytes(before.try_into().unwrap()) + 1,
        "one tick counted"
    );
    let pc = gdb.registers()[9];
    let isr = fw.symbols.function_at(pc).unwrap().c_name().to_string();
    assert_eq!(isr, "tick_isr");
    // The reference agrees: the first write to `ticks` after the breakpoint's steps leaves
    // the clock where the stub's is.
    let mut last = [0u8; 4];
    loop {
        reference_cpu.step(&mut reference, BUDGET_STATES).unwrap();
        for (i, b) in last.iter_mut().enumerate() {
            *b = reference.peek(ticks + i as u32);
        }
        if last[..] == after[..] {
            break;
        }
    }
    assert_eq!(
        gdb.registers(),
        expected_registers(&reference_cpu, &reference)
    );
    // Watchpoints are for RAM only.
    let io = gdb.ask("Z2,ffffb0,1");
    assert!(io.starts_with('E') || io.is_empty(), "{io}");

    // Kill: the run ends as killed.
    gdb.send("vKill;1");
    let report = run.join().unwrap();
    assert_eq!(report.outcome, Outcome::Killed);
}

#[test]
fn a_client_that_detaches_lets_the_firmware_run_on_to_the_same_end() {
    let fw = Firmware::robot().unwrap();
    let (mut gdb, run) = debugged(&fw);
    gdb.handshake();
    let forward = fw.symbols.addr("learner_forward").unwrap();
    assert_eq!(gdb.ask(&format!("Z1,{forward:x},2")), "OK");
    let stop = gdb.ask("c");
    assert!(
        stop.starts_with("T05") && stop.contains("hwbreak"),
        "{stop}"
    );
    assert_eq!(gdb.ask("D"), "OK");
    let report = run.join().unwrap();
    // Without a debugger, the same budget ends the same way at the same clock.
    let (mut cpu, mut mcu) = machine(&fw);
    let plain = run_mcu_probed(
        &mut cpu,
        &mut mcu,
        &RunOptions {
            max_states: Some(BUDGET_STATES),
            ..RunOptions::default()
        },
        &mut std::io::sink(),
        Probes::default(),
    )
    .unwrap();
    assert_eq!(report.outcome, Outcome::MaxStates);
    assert_eq!(report, plain);
}
