//! The robot firmware (firmware/, docs/design.md §8) running on the emulated H8/3052F: the image, the
//! configuration block, boot, steps, motors, EEPROM records, restore after a power cut.

use eeprom::persist::RecordLayout;
use h8_3052f::mcu::{Mcu, McuConfig};
use h8_3052f::pins::{Board, NullBoard};
use h8300h::bus::Bus;
use h8300h::cpu::Cpu;
use robot_board::board::{CLOCK_HZ, RobotBoard, RobotConfig, robot_mcu};
use robot_board::firmware::{
    CONFIG_BLOCK_ADDR, ConfigBlock, ConfigStatus, FLAG_RANDOM_WALK, Firmware, run_until,
};
use robot_board::wiring::{Bridge, motor_pins};

mod boards;
use boards::Wandering;

/// 10 ms ticks of φ/8 at 25 MHz, in states.
const TICK_STATES: u64 = 31_250 * 8;

fn firmware() -> Firmware {
    Firmware::robot().expect("the committed firmware parses")
}

/// The firmware installed on an MCU on the robot's board (its EEPROMs), `world` on the other
/// pins.
fn boot<B: Board>(world: B, block: Option<&ConfigBlock>) -> (Firmware, Mcu<RobotBoard<B>>, Cpu) {
    let fw = firmware();
    let mut mcu = robot_mcu(world, &RobotConfig::default()).unwrap();
    let mut cpu = Cpu::new();
    fw.install(&mut mcu, &mut cpu, block).unwrap();
    (fw, mcu, cpu)
}

fn peek_u32<B: Board>(mcu: &Mcu<B>, addr: u32) -> u32 {
    (0..4).fold(0, |v, i| (v << 8) | u32::from(mcu.peek(addr + i)))
}

fn peek_u16<B: Board>(mcu: &Mcu<B>, addr: u32) -> u16 {
    (u16::from(mcu.peek(addr)) << 8) | u16::from(mcu.peek(addr + 1))
}

fn sym(fw: &Firmware, name: &str) -> u32 {
    fw.symbols
        .addr(name)
        .unwrap_or_else(|| panic!("no symbol {name}"))
}

fn status<B: Board>(fw: &Firmware, mcu: &Mcu<B>) -> ConfigStatus {
    ConfigStatus::from_code(mcu.peek(sym(fw, "cfg_status")))
}

#[test]
fn the_image_holds_the_du_table_of_the_sensors_crate_and_the_block_at_h400() {
    let fw = firmware();
    assert!(fw.has_config_block());
    assert_eq!(sym(&fw, "config_block"), CONFIG_BLOCK_ADDR);
    let mut mcu = Mcu::new(McuConfig::default(), NullBoard).unwrap();
    mcu.load_image(&fw.image).unwrap();
    let table = sym(&fw, "du_table");
    let image_table: Vec<u8> = (0..256).map(|i| mcu.peek(table + i)).collect();
    assert_eq!(image_table, sensors::DU_TABLE.to_vec());
    // The block is erased in the image: the emulator writes it.
    assert!((0..32).all(|i| mcu.peek(CONFIG_BLOCK_ADDR + i) == 0xFF));
    assert!(
        fw.rom_bytes() > 4_000 && fw.rom_bytes() < 16_384,
        "{}",
        fw.rom_bytes()
    );
}

#[test]
fn the_configuration_block_is_used_checked_or_ignored() {
    // Absent: the compiled defaults (the arena, 13 x 4).
    let (fw, mut mcu, mut cpu) = boot(NullBoard, None);
    run_until(&mut cpu, &mut mcu, 2 * TICK_STATES).unwrap();
    assert_eq!(status(&fw, &mcu), ConfigStatus::Absent);
    assert_eq!(peek_u16(&mcu, sym(&fw, "net_n_in")), 13);
    assert_eq!(mcu.peek(sym(&fw, "net_n_out")), 4);

    // Used: the corridor's network without history.
    let block = ConfigBlock {
        outputs: 2,
        history: 0,
        eta: 3277,
        ticks_per_step: 60,
        ..ConfigBlock::ARENA
    };
    let (fw, mut mcu, mut cpu) = boot(NullBoard, Some(&block));
    run_until(&mut cpu, &mut mcu, 2 * TICK_STATES).unwrap();
    assert_eq!(status(&fw, &mcu), ConfigStatus::Used);
    assert_eq!(peek_u16(&mcu, sym(&fw, "net_n_in")), 7);
    assert_eq!(mcu.peek(sym(&fw, "net_n_out")), 2);
    assert_eq!(peek_u16(&mcu, sym(&fw, "net_eta")), 3277);

    // Corrupt: one byte changed after the CRC was computed.
    let (fw, mut mcu, mut cpu) = boot(NullBoard, Some(&block));
    mcu.poke(CONFIG_BLOCK_ADDR + 10, &[0x7F]);
    cpu.reset(&mut mcu);
    run_until(&mut cpu, &mut mcu, 2 * TICK_STATES).unwrap();
    assert_eq!(status(&fw, &mcu), ConfigStatus::Corrupt);
    assert_eq!(mcu.peek(sym(&fw, "net_n_out")), 4);

    // Rejected: values the firmware cannot run, each named.
    for (bad, field) in [
        (
            ConfigBlock {
                outputs: 5,
                ..block
            },
            "outputs",
        ),
        (
            ConfigBlock {
                history: 9,
                ..block
            },
            "history",
        ),
        (
            ConfigBlock {
                spare: 300,
                ..block
            },
            "spare inputs",
        ),
        (ConfigBlock { eta: -1, ..block }, "eta"),
        (
            ConfigBlock {
                ticks_per_step: 0,
                ..block
            },
            "ticks per step",
        ),
        (
            ConfigBlock {
                channels: [0, 1, 2, 4],
                ..block
            },
            "A/D channels",
        ),
        (
            ConfigBlock {
                flags: 0x80,
                ..block
            },
            "flags",
        ),
    ] {
        let (fw, mut mcu, mut cpu) = boot(NullBoard, Some(&bad));
        run_until(&mut cpu, &mut mcu, 2 * TICK_STATES).unwrap();
        match status(&fw, &mcu) {
            ConfigStatus::Rejected { field: f, .. } => {
                assert!(f.starts_with(field), "{f} for {bad:?}")
            }
            other => panic!("{bad:?}: {other:?}"),
        }
        // The defaults run.
        assert_eq!(mcu.peek(sym(&fw, "net_n_out")), 4);
    }
}

#[test]
fn steps_come_every_k_ticks_and_the_motors_follow_the_behaviour() {
    let block = ConfigBlock {
        save_every: 0,
        ..ConfigBlock::ARENA
    };
    let (fw, mut mcu, mut cpu) = boot(Wandering, Some(&block));
    let steps = sym(&fw, "steps");
    // The first step comes with the first tick.
    run_until(&mut cpu, &mut mcu, TICK_STATES + 20_000).unwrap();
    assert_eq!(peek_u32(&mcu, steps), 1);
    let mut seen = [0u32; 4];
    for k in 1..200u64 {
        run_until(&mut cpu, &mut mcu, TICK_STATES * (1 + 45 * k) + 20_000).unwrap();
        assert_eq!(peek_u32(&mcu, steps), 1 + k as u32);
        let b = mcu.peek(sym(&fw, "behaviour"));
        assert_eq!(b, mcu.peek(sym(&fw, "net_win")));
        seen[usize::from(b)] += 1;
        let pins = motor_pins(&mut mcu);
        let (l, r) = (pins.left, pins.right);
        let (want_l, want_r, dl, dr) = match b {
            0 => (Bridge::Forward, Bridge::Forward, 1.0, 1.0),
            1 => (Bridge::Reverse, Bridge::Reverse, 1.0, 1.0),
            2 => (Bridge::Forward, Bridge::Forward, 0.3, 1.0),
            _ => (Bridge::Forward, Bridge::Forward, 1.0, 0.3),
        };
        assert_eq!((l.bridge(), r.bridge()), (want_l, want_r), "behaviour {b}");
        assert!(
            (l.pwm.duty() - dl).abs() < 1e-9 && (r.pwm.duty() - dr).abs() < 1e-9,
            "behaviour {b}: duty {} {}",
            l.pwm.duty(),
            r.pwm.duty()
        );
    }
    assert!(
        seen.iter().filter(|&&n| n > 0).count() >= 2,
        "behaviours seen {seen:?}"
    );
}

#[test]
fn records_are_eeprom_persist_records_and_survive_a_power_cut() {
    let block = ConfigBlock {
        save_every: 5,
        ..ConfigBlock::ARENA
    };
    let (fw, mut mcu, mut cpu) = boot(Wandering, Some(&block));
    let end = TICK_STATES * (1 + 45 * 23) + 20_000; // 24 steps: saves after steps 5, 10, 15, 20
    run_until(&mut cpu, &mut mcu, end).unwrap();
    assert_eq!(
        mcu.board().eeproms().timing_violation_count(),
        0,
        "the firmware's I2C keeps DS21203's timing"
    );
    assert_eq!(peek_u32(&mcu, sym(&fw, "rec_sequence")), 4);
    assert_eq!(peek_u16(&mcu, sym(&fw, "rec_failures")), 0);
    let layout = RecordLayout::new(0, 104).unwrap();
    let now = mcu.now();
    let mut newest = None;
    for chip in [0x50u8, 0x51] {
        let mut image = vec![0u8; 4 * 64];
        mcu.board_mut()
            .eeproms_mut()
            .device_mut(chip)
            .unwrap()
            .read(now, 0, &mut image)
            .unwrap();
        let record = layout.decode_slot(chip, &image).unwrap();
        assert_eq!(record.sequence % 2, u32::from(chip - 0x50));
        if record.sequence == 3 {
            newest = Some(record);
        }
    }
    let newest = newest.expect("record 3 on chip 0x51");
    // After step 20 the weights were saved; four more steps have changed them since (maybe).
    // Cut the power, power on, reboot: the firmware restores record 3.
    mcu.power_cut();
    let t = mcu.now() + u64::from(CLOCK_HZ);
    mcu.power_on(t);
    cpu.reset(&mut mcu);
    run_until(&mut cpu, &mut mcu, t + 2 * TICK_STATES).unwrap();
    assert_eq!(mcu.peek(sym(&fw, "restored")), 1);
    assert_eq!(peek_u32(&mcu, sym(&fw, "rec_sequence")), 4);
    let w = peek_u32(&mcu, sym(&fw, "net_w"));
    let weights: Vec<u8> = (0..104).map(|i| mcu.peek(w + i)).collect();
    assert_eq!(weights, newest.payload);
}

#[test]
fn the_random_walk_flag_overrides_the_choice_but_not_the_learner() {
    let block = ConfigBlock {
        flags: FLAG_RANDOM_WALK,
        save_every: 0,
        ..ConfigBlock::ARENA
    };
    let (fw, mut mcu, mut cpu) = boot(Wandering, Some(&block));
    let (mut differ, mut counts) = (0, [0u32; 4]);
    for k in 0..200u64 {
        run_until(&mut cpu, &mut mcu, TICK_STATES * (1 + 45 * k) + 20_000).unwrap();
        let b = mcu.peek(sym(&fw, "behaviour"));
        counts[usize::from(b)] += 1;
        differ += u32::from(b != mcu.peek(sym(&fw, "net_win")));
    }
    assert!(counts.iter().all(|&n| n > 25), "{counts:?}");
    assert!(differ > 100, "{differ}");
}

#[test]
fn a_fault_halts_with_the_vector_named() {
    let (fw, mut mcu, mut cpu) = boot(NullBoard, None);
    run_until(&mut cpu, &mut mcu, 2 * TICK_STATES).unwrap();
    // Jump into the stub of vector 11 (TRAPA #3) as an unexpected exception would.
    cpu.set_pc(sym(&fw, "_vector_stubs") + 6 * 10);
    let e = run_until(&mut cpu, &mut mcu, 3 * TICK_STATES)
        .unwrap_err()
        .to_string();
    assert!(e.contains("0x8B") && e.contains("vector 11"), "{e}");
}

/// Every setting of the model controller's configuration that concerns the controller reaches
/// the firmware through the block: network shape, η, T, save period, step period, clock, A/D
/// wiring and the weight seed (the firmware's fresh weights are the model's).
#[test]
fn the_model_controllers_settings_reach_the_firmware_through_the_block() {
    use nn_q15::{InputLayout, Params};
    use robot_board::model::{ControllerConfig, fresh_weights};
    let mut cfg = ControllerConfig::corridor(0x1234_5678_9ABC_DEF0);
    cfg.behaviours = 3;
    cfg.layout = InputLayout::new(2, true).unwrap().with_spare(5);
    cfg.params = Params::new(1000, 17).unwrap();
    cfg.save_every_steps = 7;
    cfg.step_period_s = 0.3;
    cfg.clock_hz = 16_000_000;
    cfg.sensor_channels = [7, 4, 5, 6];
    let block = ConfigBlock::from_controller(&cfg).unwrap();
    assert_eq!(
        block,
        ConfigBlock {
            outputs: 3,
            history: 2,
            flags: robot_board::firmware::FLAG_BIAS,
            spare: 5,
            eta: 1000,
            threshold: 17,
            save_every: 7,
            ticks_per_step: 30,
            tick_counts: 20_000,
            channels: [7, 4, 5, 6],
            seed: 0x1234_5678 ^ 0x9ABC_DEF0,
        }
    );
    assert_eq!(block.n_inputs(), cfg.n_inputs());

    // The firmware boots with it: its network, parameters and fresh weights are the model's.
    let (fw, mut mcu, mut cpu) = boot(NullBoard, Some(&block));
    run_until(&mut cpu, &mut mcu, 2 * TICK_STATES).unwrap();
    assert_eq!(status(&fw, &mcu), ConfigStatus::Used);
    assert_eq!(
        usize::from(peek_u16(&mcu, sym(&fw, "net_n_in"))),
        cfg.n_inputs()
    );
    assert_eq!(peek_u16(&mcu, sym(&fw, "net_threshold")), 17);
    let w = peek_u32(&mcu, sym(&fw, "net_w"));
    let n = cfg.n_inputs() * 3;
    let firmware_weights: Vec<i16> = (0..n as u32)
        .map(|k| peek_u16(&mcu, w + 2 * k) as i16)
        .collect();
    let model_weights: Vec<i16> = fresh_weights(cfg.weight_seed, n)
        .iter()
        .map(|q| q.to_bits())
        .collect();
    assert_eq!(firmware_weights, model_weights);

    // Settings the block cannot carry are named.
    let mut bad = cfg.clone();
    bad.save_every_steps = 70_000;
    assert_eq!(
        ConfigBlock::from_controller(&bad).unwrap_err().field,
        "save_every_steps"
    );
    bad = cfg.clone();
    bad.step_period_s = 0.455;
    assert_eq!(
        ConfigBlock::from_controller(&bad).unwrap_err().field,
        "step_period_s"
    );
}

/// A board that reads 1.0 V on AN7 only (about 30 cm) and 0 V elsewhere (nothing seen).
struct OneChannel;

impl Board for OneChannel {
    fn analog_volts(&mut self, channel: u8, _now_states: u64) -> f64 {
        if channel == 7 { 1.0 } else { 0.0 }
    }
    fn port2_pins(&mut self, _now_states: u64) -> u8 {
        0xFF
    }
}

#[test]
fn the_sensors_are_read_from_the_configured_channels() {
    for (channels, front_sees) in [
        ([7, 4, 5, 6], true),
        ([0, 1, 2, 3], false),
        ([4, 7, 5, 6], false),
    ] {
        let block = ConfigBlock {
            channels,
            ..ConfigBlock::ARENA
        };
        let (fw, mut mcu, mut cpu) = boot(OneChannel, Some(&block));
        run_until(&mut cpu, &mut mcu, TICK_STATES + 20_000).unwrap();
        let x = peek_u32(&mcu, sym(&fw, "net_x"));
        // x[0] = p(front) - 128: 255 du (far) reads 127.
        let front = mcu.peek(x) as i8;
        assert_eq!(front < 100, front_sees, "{channels:?}: x[0] = {front}");
        if channels == [4, 7, 5, 6] {
            assert!((mcu.peek(x + 1) as i8) < 100, "the rear sensor sits on AN7");
        }
    }
}

/// Registers, CCR, PC, instructions, clock and RAM at a step's end.
type StepEnd = ([u32; 8], u8, u32, u64, u64, Vec<u8>);

/// What a firmware robot's run leaves, for comparing two runs.
#[derive(Debug, PartialEq)]
struct Trace {
    sensing: Vec<u64>,
    busy: Vec<u64>,
    regs: [u32; 8],
    pc: u32,
    ccr: u8,
    instructions: u64,
    ram: Vec<u8>,
    /// Registers, CCR, PC, instructions, clock and RAM at the end of every step.
    states: Vec<StepEnd>,
    write_counts: Vec<Vec<u32>>,
    violations: Vec<u64>,
}

fn controller_trace(fast_forward: bool, steps: usize) -> (Trace, u64, u64) {
    use h8300h::memmap::{RAM_BYTES, RAM_START};
    use robot_board::firmware::FirmwareController;
    let fw = firmware();
    let mut mcu = robot_mcu(Wandering, &RobotConfig::default()).unwrap();
    let block = ConfigBlock {
        save_every: 3,
        ..ConfigBlock::ARENA
    };
    let mut c = FirmwareController::start(&fw, &mut mcu, Some(&block)).unwrap();
    c.set_fast_forward(fast_forward);
    let (mut sensing, mut busy, mut states) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..steps {
        sensing.push(c.run_to_sensing(&mut mcu).unwrap());
        c.run_to_sleep(&mut mcu).unwrap();
        busy.push(c.take_busy());
        // The whole state at every step's end: registers, flags, count, clock, RAM.
        let cpu = c.cpu();
        let ram: Vec<u8> = (0..RAM_BYTES).map(|i| mcu.peek(RAM_START + i)).collect();
        states.push((
            cpu.regs(),
            cpu.ccr(),
            cpu.pc(),
            cpu.instructions(),
            mcu.now(),
            ram,
        ));
    }
    let cpu = c.cpu();
    let trace = Trace {
        sensing,
        busy,
        regs: cpu.regs(),
        pc: cpu.pc(),
        ccr: cpu.ccr(),
        instructions: cpu.instructions(),
        ram: (0..RAM_BYTES).map(|i| mcu.peek(RAM_START + i)).collect(),
        states,
        write_counts: mcu
            .board()
            .eeproms()
            .devices()
            .iter()
            .map(|d| d.write_counts().to_vec())
            .collect(),
        violations: mcu
            .board()
            .eeproms()
            .devices()
            .iter()
            .map(|d| d.timing_violation_count())
            .collect(),
    };
    (trace, cpu.skipped_instructions(), cpu.idle_cycles_skipped())
}

#[test]
fn the_robot_runs_alike_with_loop_fast_forwarding_on_and_off() {
    // 120 steps with a save every 3: delay loops (the I2C bit timing, ACK polling's pauses),
    // the ADF poll and the idle cycles between steps (tick interrupt, handler, back to sleep)
    // are skipped on one side, executed on the other; the whole state is compared at every
    // step's end.
    let (on, skipped, idle) = controller_trace(true, 120);
    let (off, none, no_idle) = controller_trace(false, 120);
    assert_eq!((none, no_idle), (0, 0));
    assert!(
        skipped > on.instructions / 4,
        "{skipped} of {} instructions skipped",
        on.instructions
    );
    // 45 ticks a step: most of them advanced in closed form (two are run to prove the rest,
    // and the one that ends the wait is run).
    assert!(idle > 120 * 30, "{idle} idle cycles advanced");
    assert!(
        on.write_counts.iter().flatten().any(|&n| n > 0),
        "records were saved"
    );
    assert_eq!(on.states.len(), off.states.len());
    for (k, (a, b)) in on.states.iter().zip(&off.states).enumerate() {
        assert!(a == b, "step {k}: the states differ");
    }
    assert_eq!(on, off);
}
