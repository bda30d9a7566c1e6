//! The controller on the emulated MCU: boot, the tick, steps within bounds derived here from
//! docs/design.md §4.2, saves and their restore, a power cut in the middle of a save, determinism.

// A test, example or bench may use the host's f64 functions (clippy.toml): it checks the
// models within tolerances, and its own output is not a promised result.
#![allow(clippy::disallowed_methods)]

use h8_3052f::mcu::Mcu;
use h8_3052f::pins::Board;
use h8300h::bus::{Bus, FastPathHints};
use nn_q15::Q15;
use robot_board::board::{CLOCK_HZ, RobotBoard, RobotConfig, robot_mcu};
use robot_board::model::{Controller, ControllerConfig, ModelBus, StepReport};

/// A board whose four sensors read voltages that change with time (so the learner sees
/// rewards, punishments and dead zones).
struct Wave;

impl Board for Wave {
    fn analog_volts(&mut self, channel: u8, now: u64) -> f64 {
        let t = now as f64 / f64::from(CLOCK_HZ);
        1.4 + 1.1 * (t * (0.7 + 0.3 * f64::from(channel))).sin()
    }
    fn port2_pins(&mut self, _now: u64) -> u8 {
        0xFF
    }
}

fn mcu(seed: u64) -> Mcu<RobotBoard<Wave>> {
    robot_mcu(
        Wave,
        &RobotConfig {
            clock_hz: CLOCK_HZ,
            eeprom_seed: seed,
        },
    )
    .expect("a valid MCU")
}

fn run(c: &mut Controller, m: &mut Mcu<RobotBoard<Wave>>, steps: u32) -> Vec<StepReport> {
    (0..steps)
        .map(|_| {
            c.sleep_until_step(m).expect("the tick wakes the CPU");
            c.step(m).expect("the step runs")
        })
        .collect()
}

#[test]
fn steps_come_every_45_ticks_of_10_ms() {
    let mut m = mcu(1);
    let mut c = Controller::new(ControllerConfig::arena(7)).expect("valid");
    c.boot(&mut m).expect("boots");
    let r = run(&mut c, &mut m, 4);
    let tick = 31_250 * 8; // 10 ms at φ/8, 25 MHz
    for w in r.windows(2) {
        let gap = w[1].start_states - w[0].start_states;
        // The next step starts 45 ticks later, give or take the difference of where each step
        // began inside its tick handler's aftermath (well under a tick).
        assert!(gap.abs_diff(45 * tick) < 1_000, "{gap}");
    }
    assert_eq!(c.ticks_per_step(), 45);
}

/// States of the forward pass of a 13 × 4 network, bounded from docs/design.md §4.2 alone: each
/// multiply-accumulate is two post-increment loads (6 + 6), EXTS (2), MULXS.W (24) and ADD.L
/// (2), and each loop iteration at least a decrement (2) and a branch (4); the rest of the
/// routine (row set-up, the argmax, the scaling of 4 outputs, its call and return) is at most
/// 4 × 200 states even on its slowest path (a normalising shift of up to 17 places per output).
const MAC_13X4_MIN: u64 = 52 * (6 + 6 + 2 + 24 + 2 + 2 + 4);
const FORWARD_13X4_MAX: u64 = MAC_13X4_MIN + 4 * 200 + 17 * 14 + 4 * 17 * 8;

/// The A/D phase: a scan of four conversions with CKS = 1 (docs/design.md §3.2: 134 states; the later
/// conversions of a scan 128, H8/3052F hardware manual) at least; at most those plus one more
/// poll of ADF (MOV.B @aa:8 = 2 + 3 states, BGE = 4), the set-up and the start write
/// (MOV.B @aa:24 = 8, four register ops, 2 + 3), the stop write and a clear (2 + 5 + 2), four
/// channel lookups and result reads (four register ops, MOV.B @(d:24) = 10, AND.L and ADD.L
/// #imm = 6 each, SHLL.L, MOV.B @ERn from I/O = 2 + 3) with the du lookup (EXTU ×2,
/// MOV.B @(d:24) = 10), the store and the loop (MOV.B @ERn = 4, ADD.B, CMP.B, BLS = 4), and
/// the return (RTS = 10) — the firmware's ad_scan.
const ADC_MIN: u64 = 134 + 3 * 128;
const ADC_MAX: u64 = 4 * 134
    + 9
    + (8 + 4 * 2 + 5)
    + (2 + 5 + 2)
    + 4 * ((4 * 2 + 10 + 6 + 2 + 6 + 5) + (2 * 2 + 10) + (4 + 2 + 2 + 4))
    + 10;

#[test]
fn the_step_lies_within_bounds_derived_from_the_instruction_states() {
    let mut m = mcu(2);
    let mut c = Controller::new(ControllerConfig::arena(3)).expect("valid");
    c.boot(&mut m).expect("boots");
    for r in run(&mut c, &mut m, 100) {
        let p = r.phases;
        assert!((ADC_MIN..=ADC_MAX).contains(&p.adc), "A/D {}", p.adc);
        assert!(
            (MAC_13X4_MIN..=FORWARD_13X4_MAX).contains(&p.forward),
            "forward {}",
            p.forward
        );
        // The update: nothing but its test in the dead zone, else 13 Δ (MULXS.W and the
        // rounding, 74 states each) and 52 weight changes (28 states each) at least.
        if matches!(
            r.update,
            Some(nn_q15::UpdateKind::Reward | nn_q15::UpdateKind::Punish)
        ) {
            assert!(p.update >= 13 * 74 + 52 * 28, "update {}", p.update);
            assert!(
                p.update <= 13 * 74 + 52 * (28 + 12) + 4 * 30 + 300,
                "update {}",
                p.update
            );
        } else {
            assert!(p.update <= 150, "dead-zone update {}", p.update);
        }
        // Motors: two word writes to the ITU (2 fetches + 6 states over the 8-bit bus) and one
        // byte write to port B (2 + 3) at least.
        assert!(p.motors >= 2 * (4 + 6) + 5, "motors {}", p.motors);
        if r.saved.is_some() {
            // Three pages, each followed by a 3-5 ms write cycle polled to its end: at least
            // 9 ms (225 000 states), at most 3 × (5 ms + one poll) plus the transfers.
            assert!((225_000..=600_000).contains(&p.save), "save {}", p.save);
        } else {
            assert_eq!(p.save, 0);
        }
    }
}

#[test]
fn saves_write_records_that_a_reboot_restores() {
    let mut m = mcu(1);
    let mut c = Controller::new(ControllerConfig::arena(7)).expect("valid");
    assert_eq!(c.boot(&mut m).expect("boots").restored, None);
    let reports = run(&mut c, &mut m, 40);
    let saves: Vec<_> = reports.iter().filter_map(|r| r.saved.clone()).collect();
    assert_eq!(saves.len(), 2, "one record every 20 steps");
    assert_eq!((saves[0].sequence, saves[0].chip), (0, 0x50));
    assert_eq!((saves[1].sequence, saves[1].chip), (1, 0x51));
    // Each page's 3-5 ms write cycle is polled every ~256 µs (a poll and the firmware's
    // 200 µs pause): 12 to 20 polls a page.
    assert!(
        saves
            .iter()
            .all(|s| s.pages == 3 && (3 * 11..=3 * 21).contains(&s.polls)),
        "{saves:?}"
    );
    let weights = c.learner().weights().to_vec();
    let mut again = Controller::new(ControllerConfig::arena(99)).expect("valid");
    assert_eq!(again.boot(&mut m).expect("boots").restored, Some(1));
    assert_eq!(again.learner().weights(), &weights[..]);
}

/// Delegates to an MCU and cuts the robot's power once the clock passes `cut_at`.
struct CutAt<'a> {
    mcu: &'a mut Mcu<RobotBoard<Wave>>,
    cut_at: u64,
    cut: bool,
}

impl CutAt<'_> {
    fn check(&mut self) {
        if !self.cut && self.mcu.now() >= self.cut_at {
            self.mcu.power_cut();
            self.cut = true;
        }
    }
}

impl Bus for CutAt<'_> {
    fn now(&self) -> u64 {
        self.mcu.now()
    }
    fn read8(&mut self, addr: u32) -> u8 {
        let v = self.mcu.read8(addr);
        self.check();
        v
    }
    fn read16(&mut self, addr: u32) -> u16 {
        let v = self.mcu.read16(addr);
        self.check();
        v
    }
    fn write8(&mut self, addr: u32, value: u8) {
        self.mcu.write8(addr, value);
        self.check();
    }
    fn write16(&mut self, addr: u32, value: u16) {
        self.mcu.write16(addr, value);
        self.check();
    }
    fn internal(&mut self, states: u32) {
        self.mcu.internal(states);
        self.check();
    }
    fn pending_irq(&self) -> Option<u8> {
        self.mcu.pending_irq()
    }
    fn sleep_until_irq(&mut self, deadline: u64) -> bool {
        self.mcu.sleep_until_irq(deadline)
    }
}

/// No emulation shortcuts through the wrapper: the model runs it register by register.
impl FastPathHints for CutAt<'_> {}
impl ModelBus for CutAt<'_> {}

#[test]
fn a_power_cut_in_the_middle_of_a_save_leaves_the_last_committed_weights() {
    // Find when the second save (sequence 1, on chip 0x51) runs in an uninterrupted twin.
    let twin = {
        let mut m = mcu(5);
        let mut c = Controller::new(ControllerConfig::arena(11)).expect("valid");
        c.boot(&mut m).expect("boots");
        run(&mut c, &mut m, 40)
    };
    let second = twin
        .iter()
        .filter(|r| r.saved.is_some())
        .nth(1)
        .expect("two saves");
    let save_start = second.start_states
        + second.phases.adc
        + second.phases.input
        + second.phases.update
        + second.phases.forward
        + second.phases.motors;
    // Cut at several instants inside that save: during the first page, the polling, the
    // commit page.
    for frac in [0.05, 0.3, 0.55, 0.8, 0.97] {
        let mut m = mcu(5);
        let mut c = Controller::new(ControllerConfig::arena(11)).expect("valid");
        c.boot(&mut m).expect("boots");
        let mut committed: Vec<Q15> = Vec::new();
        for _ in 0..39 {
            c.sleep_until_step(&mut m).expect("ticks");
            let r = c.step(&mut m).expect("steps");
            if r.saved.is_some() {
                committed = c.learner().weights().to_vec();
            }
        }
        assert_eq!(committed.len(), 52, "the first save happened");
        c.sleep_until_step(&mut m).expect("ticks");
        let cut_at = save_start + (second.phases.save as f64 * frac) as u64;
        {
            let mut bus = CutAt {
                mcu: &mut m,
                cut_at,
                cut: false,
            };
            // On the robot the CPU dies with the cut; the emulation runs the rest of the step's
            // code against a reset MCU and powered-off chips, so its outcome means nothing.
            let _ = c.step(&mut bus);
            assert!(bus.cut, "the cut happened at {frac}");
        }
        let now = m.now();
        m.power_on(now + u64::from(CLOCK_HZ));
        let mut rebooted = Controller::new(ControllerConfig::arena(12)).expect("valid");
        let boot = rebooted.boot(&mut m).expect("boots");
        assert_eq!(boot.restored, Some(0), "cut at {frac} of the save");
        assert_eq!(
            rebooted.learner().weights(),
            &committed[..],
            "cut at {frac}"
        );
    }
}

#[test]
fn same_seeds_same_steps() {
    let go = || {
        let mut m = mcu(9);
        let mut c = Controller::new(ControllerConfig::corridor(4)).expect("valid");
        c.boot(&mut m).expect("boots");
        (run(&mut c, &mut m, 50), m.now())
    };
    assert_eq!(go(), go());
}

#[test]
fn fast_forward_gives_identical_steps_sleeps_and_clock() {
    // Saves at many different offsets from the tick (the save lasts 1.5 ticks), both paper
    // settings.
    for (corridor, save_every, steps) in [(false, 7, 60), (false, 3, 150), (true, 2, 60)] {
        fast_forward_case(corridor, save_every, steps);
    }
}

fn fast_forward_case(corridor: bool, save_every: u32, steps: u32) {
    let go = |fast: bool| {
        let mut m = mcu(3);
        let mut cfg = if corridor {
            ControllerConfig::corridor(5)
        } else {
            ControllerConfig::arena(5)
        };
        cfg.fast_forward = fast;
        cfg.save_every_steps = save_every;
        let mut c = Controller::new(cfg).expect("valid");
        c.boot(&mut m).expect("boots");
        let mut log = Vec::new();
        for _ in 0..steps {
            let s = c.sleep_until_step(&mut m).expect("ticks");
            let r = c.step(&mut m).expect("steps");
            log.push((s, r, m.now()));
        }
        // What the chips hold and how often each page was written.
        let now = m.now();
        let chips: Vec<(Vec<u8>, Vec<u32>)> = [0x50u8, 0x51]
            .iter()
            .map(|&a| {
                let d = m.board_mut().eeproms_mut().device_mut(a).expect("chip");
                let mut mem = vec![0u8; 1024];
                d.read(now, 0, &mut mem).expect("read");
                (mem, d.write_counts().to_vec())
            })
            .collect();
        let edges = m.board().eeproms().edges().total();
        (log, chips, edges)
    };
    let ((slow, slow_chips, slow_edges), (fast, fast_chips, fast_edges)) = (go(false), go(true));
    assert_eq!(slow.len(), fast.len());
    for (k, (a, b)) in slow.iter().zip(&fast).enumerate() {
        assert_eq!(a, b, "step {k}");
    }
    assert!(slow.iter().filter(|(_, r, _)| r.saved.is_some()).count() >= 8);
    assert!(
        slow.iter().any(|(_, r, _)| r.phases.isr > 0),
        "a tick came during a step"
    );
    assert_eq!(slow_chips, fast_chips, "EEPROM contents and write counts");
    assert!(
        slow_chips[0].1.iter().sum::<u32>() >= 12,
        "records were written"
    );
    // The fast path moves no lines: only the boot's pin-level recovery shows on the bus.
    assert!(fast_edges < slow_edges / 10, "{fast_edges} vs {slow_edges}");
}

/// The wheels get what docs/design.md §3.5 asks of each behaviour: measured on the TIOCA1/TIOCA2 pins
/// themselves, sampled every 8 states (one φ/8 count) over several PWM periods after the
/// step, not read back from the timer's registers; and the H-bridge inputs on port B.
#[test]
fn each_behaviour_drives_the_pins_with_its_duty_and_direction() {
    use nn_q15::Behaviour;
    use robot_board::wiring::{Bridge, motor_pins};
    let period = u64::from(robot_board::model::PWM_PERIOD_COUNTS) * 8;
    for (b, duty, bridge) in [
        (Behaviour::Forward, (1.0, 1.0), Bridge::Forward),
        (Behaviour::Backward, (1.0, 1.0), Bridge::Reverse),
        (Behaviour::TurnLeftForward, (0.3, 1.0), Bridge::Forward),
        (Behaviour::TurnRightForward, (1.0, 0.3), Bridge::Forward),
    ] {
        let mut m = mcu(3);
        let mut c = Controller::new(ControllerConfig::arena(5)).expect("valid");
        c.boot(&mut m).expect("boots");
        for _ in 0..2 {
            c.sleep_until_step(&mut m).expect("the tick wakes the CPU");
            c.step_with(&mut m, Some(b)).expect("the step runs");
        }
        // Let the new compare values take over (a full period), then sample four periods.
        let start = m.now() + period;
        let (mut high_l, mut high_r, mut n) = (0u64, 0u64, 0u64);
        let mut t = start;
        while t < start + 4 * period {
            m.advance_to(t);
            let p = motor_pins(&mut m);
            high_l += u64::from(p.left.pwm.level);
            high_r += u64::from(p.right.pwm.level);
            assert_eq!(
                (p.left.bridge(), p.right.bridge()),
                (bridge, bridge),
                "{b:?}"
            );
            n += 1;
            t += 8;
        }
        let measured = (high_l as f64 / n as f64, high_r as f64 / n as f64);
        assert!(
            (measured.0 - duty.0).abs() < 0.002 && (measured.1 - duty.1).abs() < 0.002,
            "{b:?}: pins high {measured:?} of the time, want {duty:?}"
        );
    }
}

/// The `Wave` voltages moved to other A/D inputs: sensor k's voltage on `channels[k]`.
struct Rewired {
    channels: [u8; 4],
}

impl Board for Rewired {
    fn analog_volts(&mut self, channel: u8, now: u64) -> f64 {
        match self.channels.iter().position(|&c| c == channel) {
            Some(k) => Wave.analog_volts(k as u8, now),
            None => 0.0,
        }
    }
    fn port2_pins(&mut self, _now: u64) -> u8 {
        0xFF
    }
}

/// Sensors wired to other inputs of the scan group, or to the other group (AN4–AN7, scanned
/// with CH = 7 into ADDRA–ADDRD), read exactly what the default wiring reads, in the same
/// states.
#[test]
fn rewired_sensors_read_the_same() {
    let reference = {
        let mut m = mcu(2);
        let mut c = Controller::new(ControllerConfig::arena(6)).expect("valid");
        c.boot(&mut m).expect("boots");
        run(&mut c, &mut m, 30)
    };
    for channels in [[3, 2, 1, 0], [4, 5, 6, 7], [6, 4, 7, 5]] {
        let mut m = robot_mcu(
            Rewired { channels },
            &RobotConfig {
                clock_hz: CLOCK_HZ,
                eeprom_seed: 2,
            },
        )
        .expect("a valid MCU");
        let mut cfg = ControllerConfig::arena(6);
        cfg.sensor_channels = channels;
        let mut c = Controller::new(cfg).expect("valid");
        c.boot(&mut m).expect("boots");
        let got: Vec<StepReport> = (0..30)
            .map(|_| {
                c.sleep_until_step(&mut m).expect("the tick wakes the CPU");
                c.step(&mut m).expect("the step runs")
            })
            .collect();
        assert_eq!(got, reference, "{channels:?}");
    }
}
