//! Pin traces (`h8_3052f::trace`) of the robot firmware on the emulated H8/3052F: every edge
//! at its exact state, the same with the core's shortcuts on and off, written as VCD and read
//! back, and the phase signal naming what `--trace` names.

use std::sync::Arc;

use h8_3052f::mcu::Mcu;
use h8_3052f::periph::itu::PwmWave;
use h8_3052f::pins::NullBoard;
use h8_3052f::run::{Probes, RunOptions, run_mcu_probed};
use h8_3052f::trace::{PhaseRecorder, PinTrace, Signal};
use h8_3052f::vcd::{VcdInfo, write_vcd};
use h8300h::bus::Bus;
use h8300h::cpu::Cpu;
use robot_board::board::{RobotBoard, RobotConfig, robot_mcu};
use robot_board::firmware::{ConfigBlock, FLAG_RANDOM_WALK, Firmware, FirmwareController};

mod boards;
use boards::Wandering;

/// A 10 ms tick: 31 250 counts of φ/8.
const TICK_STATES: u64 = 31_250 * 8;
/// The firmware's PWM period: GRA = 1249, φ/8 (400 µs).
const PWM_PERIOD_STATES: u64 = 1_250 * 8;

struct Window {
    trace: PinTrace,
    phases: Vec<(u64, String)>,
    /// Each traced step's start (the ADST write, as the controller reports it).
    sensing: Vec<u64>,
    /// The behaviour the firmware chose in each traced step (its `behaviour` variable).
    behaviours: Vec<u8>,
    /// The EEPROM bus's edges over the window.
    edges: eeprom::EdgeCounts,
    /// When each traced step's work ended (the CPU went to sleep).
    sleeping: Vec<u64>,
    /// The PWM waveforms of TIOCA1 and TIOCA2 then, as the ITU's registers give them.
    waves: Vec<(PwmWave, PwmWave)>,
}

/// Runs the robot firmware (a save every 3 steps, random walk so that every behaviour
/// comes up) and traces steps `from..from + steps`.
fn traced(fast_forward: bool, from: usize, steps: usize) -> Window {
    let fw = Firmware::robot().unwrap();
    let mut mcu = robot_mcu(Wandering, &RobotConfig::default()).unwrap();
    let block = ConfigBlock {
        save_every: 3,
        flags: FLAG_RANDOM_WALK,
        ..ConfigBlock::ARENA
    };
    let mut c = FirmwareController::start(&fw, &mut mcu, Some(&block)).unwrap();
    c.set_fast_forward(fast_forward);
    for _ in 0..from {
        c.run_to_sensing(&mut mcu).unwrap();
        c.run_to_sleep(&mut mcu).unwrap();
    }
    mcu.start_trace(c.cpu().sleeping());
    c.record_phases(Arc::new(fw.symbols.clone()), mcu.now());
    let edges0 = mcu.board().eeproms().edges();
    let behaviour = fw.symbols.addr("behaviour").unwrap();
    let (mut sensing, mut behaviours) = (Vec::new(), Vec::new());
    let (mut sleeping, mut waves) = (Vec::new(), Vec::new());
    for _ in 0..steps {
        sensing.push(c.run_to_sensing(&mut mcu).unwrap());
        c.run_to_sleep(&mut mcu).unwrap();
        behaviours.push(mcu.peek(behaviour));
        sleeping.push(mcu.now());
        let wave = |mcu: &mut Mcu<RobotBoard<Wandering>>, ch| mcu.tioca(ch).wave.unwrap();
        waves.push((wave(&mut mcu, 1), wave(&mut mcu, 2)));
    }
    // A little past the last step's work, so its PWM shows.
    mcu.advance_to(mcu.now() + 5 * PWM_PERIOD_STATES);
    let phases = c.take_phases();
    let trace = mcu.finish_trace().unwrap();
    let edges = mcu.board().eeproms().edges().since(&edges0);
    Window {
        trace,
        phases,
        sensing,
        behaviours,
        edges,
        sleeping,
        waves,
    }
}

fn rises(t: &PinTrace, s: Signal) -> Vec<u64> {
    t.changes_of(s).filter(|c| c.level).map(|c| c.t).collect()
}

fn falls(t: &PinTrace, s: Signal) -> Vec<u64> {
    t.changes_of(s).filter(|c| !c.level).map(|c| c.t).collect()
}

#[test]
fn the_trace_is_the_same_with_loop_fast_forwarding_on_and_off() {
    let on = traced(true, 1, 3);
    let off = traced(false, 1, 3);
    assert!(
        on.trace.changes.len() > 1_000,
        "{} changes",
        on.trace.changes.len()
    );
    assert_eq!(on.trace, off.trace);
    assert_eq!(on.phases, off.phases);
    assert_eq!(on.sensing, off.sensing);
}

#[test]
fn every_signal_moves_at_its_hardware_instant() {
    let w = traced(true, 1, 3);
    let t = &w.trace;
    // The tick: IMIA0 rises every 10 ms exactly, and the CPU wakes at that instant.
    let ticks = rises(t, Signal::Imia0);
    assert!(ticks.len() >= 3 * 45 - 1, "{} ticks", ticks.len());
    assert!(ticks.windows(2).all(|p| p[1] - p[0] == TICK_STATES));
    let wakes = falls(t, Signal::Sleep);
    let mut asleep_ticks = 0;
    for tick in &ticks {
        // A tick that finds the CPU asleep wakes it at that instant.
        if t.level_at(Signal::Sleep, tick - 1) {
            asleep_ticks += 1;
            assert!(wakes.contains(tick), "no wake at the tick {tick}");
        }
    }
    assert!(
        asleep_ticks > 3 * 40,
        "{asleep_ticks} ticks found the CPU asleep"
    );
    // The handler clears the flag: the request never lasts a tick.
    for (r, f) in ticks.iter().zip(falls(t, Signal::Imia0)) {
        assert!(f > *r && f - r < 200, "IMIA0 {r} -> {f}");
    }
    // A/D: each step starts a scan of AN0-AN3 with CKS = 1: ADF comes 134 + 3 x 128 states
    // after ADST, and the firmware clears ADST after it.
    let adst = rises(t, Signal::Adst);
    let adf = rises(t, Signal::Adf);
    assert_eq!(adst.len(), 3);
    assert_eq!(adf.len(), 3);
    for ((s, f), sensing) in adst.iter().zip(&adf).zip(&w.sensing) {
        assert_eq!(f - s, 134 + 3 * 128);
        // The controller returns at the end of the instruction that wrote ADST.
        assert!(*sensing >= *s && sensing - s < 20, "{s} vs {sensing}");
    }
    for (f, end) in adf.iter().zip(falls(t, Signal::Adst)) {
        assert!(end > *f, "ADST cleared after ADF");
    }
    // The EEPROM bus: every line change the bus counted is in the trace (the pull-ups are on).
    let scl = t.changes_of(Signal::Scl).count() as u64;
    let sda = t.changes_of(Signal::Sda).count() as u64;
    assert_eq!(scl, w.edges.scl_rising + w.edges.scl_falling);
    assert_eq!(sda, w.edges.sda_rising + w.edges.sda_falling);
    assert!(scl > 1_000, "{scl} SCL edges: a save ran");
    // Nothing happens on the bus while the CPU sleeps.
    for c in t.changes_of(Signal::Scl) {
        assert!(
            !t.level_at(Signal::Sleep, c.t),
            "SCL moved during sleep at {}",
            c.t
        );
    }
}

/// High time of `signal` in `[from, to)`.
fn high_time(t: &PinTrace, signal: Signal, from: u64, to: u64) -> u64 {
    let mut level = t.level_at(signal, from);
    let mut at = from;
    let mut high = 0;
    for c in t.changes_of(signal).filter(|c| c.t > from && c.t < to) {
        if level {
            high += c.t - at;
        }
        level = c.level;
        at = c.t;
    }
    if level {
        high += to - at;
    }
    high
}

#[test]
fn pwm_edges_follow_gra_and_grb() {
    let w = traced(true, 1, 10);
    let t = &w.trace;
    for (signal, ch) in [(Signal::Tioca1, 1usize), (Signal::Tioca2, 2)] {
        let r = rises(t, signal);
        let f = falls(t, signal);
        // Every edge on the prescaler's φ/8 grid.
        assert!(
            r.iter().chain(&f).all(|e| e % 8 == 0),
            "ITU{ch} off the grid"
        );
    }
    // Between two steps, each motor's duty is what GRA and GRB say (the ITU's own waveform,
    // read off its registers), measured over 100 whole periods from a rising edge.
    let mut duties = std::collections::BTreeSet::new();
    for (k, wave) in w.waves.iter().enumerate() {
        let from_step = w.sleeping[k];
        for (signal, wave) in [(Signal::Tioca1, wave.0), (Signal::Tioca2, wave.1)] {
            let start = rises(t, signal)
                .into_iter()
                .find(|&e| e > from_step)
                .filter(|&e| e < from_step + 2 * PWM_PERIOD_STATES)
                .unwrap_or(from_step);
            assert_eq!(wave.period_states, PWM_PERIOD_STATES);
            let high = high_time(t, signal, start, start + 100 * wave.period_states);
            assert_eq!(high, 100 * wave.high_states, "{signal:?} after step {k}");
            duties.insert(wave.high_states * 100 / wave.period_states);
        }
    }
    // Random walk over ten steps: both duties (30 % and 100 %) came up.
    assert_eq!(
        duties.into_iter().collect::<Vec<_>>(),
        vec![30, 100],
        "behaviours {:?}",
        w.behaviours
    );
}

#[test]
fn phases_name_the_firmware_functions() {
    let w = traced(true, 1, 3);
    let names: Vec<&str> = w.phases.iter().map(|(_, n)| n.as_str()).collect();
    for f in [
        "ad_scan",
        "learner_step",
        "learner_update",
        "learner_forward",
        "motors_set",
        "record_save",
        "tick_isr",
        "main",
    ] {
        assert!(
            names.contains(&f),
            "phase {f} missing from {:?}",
            &names[..20]
        );
    }
    // In time order, and each change a real change.
    assert!(
        w.phases
            .windows(2)
            .all(|p| p[0].0 <= p[1].0 && p[0].1 != p[1].1)
    );
    // ad_scan starts before ADST rises in the same step.
    let adst = rises(&w.trace, Signal::Adst)[0];
    let scan = w
        .phases
        .iter()
        .rfind(|(t, n)| n == "ad_scan" && *t <= adst)
        .unwrap();
    assert!(adst - scan.0 < 200);
}

#[test]
fn the_vcd_file_reads_back_with_the_states_as_timestamps() {
    let w = traced(true, 1, 3);
    let mut bytes = Vec::new();
    write_vcd(
        &mut bytes,
        &w.trace,
        Some(&w.phases),
        &VcdInfo {
            source: "test".into(),
        },
    )
    .unwrap();
    let mut parser = vcd::Parser::new(&bytes[..]);
    let header = parser.parse_header().unwrap();
    assert_eq!(header.timescale, Some((10, vcd::TimescaleUnit::NS)));
    let mut ids = std::collections::HashMap::new();
    for s in Signal::ALL {
        let var = match s {
            Signal::PortOut(p, b) => header
                .find_var(&["ports", &format!("{}_{b}", p.name())])
                .unwrap(),
            _ => header.find_var(&["h8_3052f", s.name()]).unwrap(),
        };
        assert_eq!(var.size, 1);
        ids.insert(var.code, s);
    }
    let phase = header.find_var(&["firmware", "phase"]).unwrap().code;
    let (mut now, mut changes, mut phases) = (0u64, Vec::new(), Vec::new());
    let mut first = true;
    for cmd in parser {
        match cmd.unwrap() {
            vcd::Command::Timestamp(ts) => {
                assert_eq!(ts % 4, 0, "a timestamp between states");
                now = ts / 4;
            }
            vcd::Command::ChangeScalar(id, v) if !first => {
                changes.push((now, ids[&id], v == vcd::Value::V1));
            }
            vcd::Command::ChangeString(id, s) if id == phase => phases.push((now, s)),
            vcd::Command::End(vcd::SimulationCommand::Dumpvars) => first = false,
            _ => {}
        }
    }
    // The same changes as the trace (it holds no same-instant glitches here).
    let expected: Vec<(u64, Signal, bool)> = w
        .trace
        .changes
        .iter()
        .map(|c| (c.t, c.signal, c.level))
        .collect();
    let mut got = changes.clone();
    let mut want = expected.clone();
    got.sort_by_key(|c| (c.0, c.1));
    want.sort_by_key(|c| (c.0, c.1));
    assert_eq!(got, want);
    assert_eq!(now, w.trace.end);
    assert_eq!(phases, w.phases);
}

#[test]
fn the_instruction_trace_and_the_phase_signal_name_the_same_code() {
    // `h8swarm emu` on the robot firmware, the robot's board with nothing connected but its
    // EEPROMs: 30 ms, boot and ticks.
    let fw = Firmware::robot().unwrap();
    let mut mcu = robot_mcu(NullBoard, &RobotConfig::default()).unwrap();
    let mut cpu = Cpu::new();
    fw.install(&mut mcu, &mut cpu, None).unwrap();
    mcu.start_trace(false);
    let names = Arc::new(fw.symbols.clone());
    let mut phases = PhaseRecorder::new(names.clone());
    let mut lines = Vec::new();
    run_mcu_probed(
        &mut cpu,
        &mut mcu,
        &RunOptions {
            max_states: Some(3 * TICK_STATES),
            ..RunOptions::default()
        },
        &mut std::io::sink(),
        Probes {
            trace: Some(&mut lines),
            names: Some(names.as_ref()),
            phases: Some(&mut phases),
            debugger: None,
            vcd: None,
            profile: None,
        },
    )
    .unwrap();
    let text = String::from_utf8(lines).unwrap();
    let mut from_trace: Vec<&str> = Vec::new();
    for line in text.lines() {
        let name = line.rsplit("  ").next().unwrap();
        if from_trace.last() != Some(&name) {
            from_trace.push(name);
        }
    }
    let from_vcd: Vec<&str> = phases.changes().iter().map(|(_, n)| n.as_str()).collect();
    assert!(from_vcd.contains(&"boot") && from_vcd.contains(&"tick_isr"));
    assert_eq!(from_trace, from_vcd);
    let trace = mcu.finish_trace().unwrap();
    assert!(rises(&trace, Signal::Imia0).len() >= 2);
}
