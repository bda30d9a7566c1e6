//! The H8/300H core running machine code on the [`Mcu`]: SLEEP wakes on the ITU0 tick with the
//! clock fast-forwarded (one jump, not stepped), interrupt entry through vector 24 with the
//! manual's state count, and the run API on the same MCU.

use h8_3052f::machine::Machine;
use h8_3052f::mcu::{Mcu, McuConfig};
use h8_3052f::periph::itu;
use h8_3052f::pins::NullBoard;
use h8300h::bus::{Bus, FastPathHints};
use h8300h::cpu::{CCR_I, Cpu, Event};
use h8300h::memmap::ADDRESS_MASK;

/// The tick program (assembled once with h8300-hms-as 2.16.1, `.h8300h`):
/// ```text
/// 100: mov.l #0xffff10,er7       7a 07 00 ff ff 10
/// 106: mov.w #3124,r0            79 00 0c 34        ; GRA0 = 3124: 1 kHz at φ/8, 25 MHz
/// 10a: mov.w r0,@0xff6a:16       6b 80 ff 6a
/// 10e: mov.b #0x23,r0l           f8 23              ; TCR0: clear on GRA, φ/8
/// 110: mov.b r0l,@0x64:8         38 64
/// 112: mov.b #0x1,r0l            f8 01
/// 114: mov.b r0l,@0x66:8         38 66              ; TIER0: IMIEA
/// 116: mov.b r0l,@0x60:8         38 60              ; TSTR: STR0
/// 118: andc #0x7f,ccr            06 7f
/// 11a: sleep                     01 80
/// 11c: orc #0x80,ccr             04 80
/// 11e: sleep                     01 80              ; halt, exit status R0L
/// 200: mov.b @0x67:8,r1l         29 67              ; IMIA0 handler: read TSR0
/// 202: bclr #0x0,r1l             72 09
/// 204: mov.b r1l,@0x67:8         39 67              ; clear IMFA
/// 206: mov.b #0x2a,r0l           f8 2a
/// 208: rte                       56 70
/// ```
const MAIN: [u8; 32] = [
    0x7a, 0x07, 0x00, 0xff, 0xff, 0x10, 0x79, 0x00, 0x0c, 0x34, 0x6b, 0x80, 0xff, 0x6a, 0xf8, 0x23,
    0x38, 0x64, 0xf8, 0x01, 0x38, 0x66, 0x38, 0x60, 0x06, 0x7f, 0x01, 0x80, 0x04, 0x80, 0x01, 0x80,
];
const ISR: [u8; 10] = [0x29, 0x67, 0x72, 0x09, 0x39, 0x67, 0xf8, 0x2a, 0x56, 0x70];
const GRA: u64 = 3124;
const SLEEP_PC: u32 = 0x11a;

/// A bus in front of the MCU that records when TSTR was written and counts how the clock was
/// moved.
struct Probe<'a> {
    m: &'a mut Mcu<NullBoard>,
    tstr_written_at: Option<u64>,
    sleep_calls: u32,
    bus_calls: u64,
}

/// The probe promises nothing: every instruction word is fetched through it.
impl FastPathHints for Probe<'_> {}

impl Bus for Probe<'_> {
    fn now(&self) -> u64 {
        self.m.now()
    }
    fn read8(&mut self, addr: u32) -> u8 {
        self.bus_calls += 1;
        self.m.read8(addr)
    }
    fn read16(&mut self, addr: u32) -> u16 {
        self.bus_calls += 1;
        self.m.read16(addr)
    }
    fn write8(&mut self, addr: u32, value: u8) {
        self.bus_calls += 1;
        self.m.write8(addr, value);
        if addr & ADDRESS_MASK == itu::TSTR {
            self.tstr_written_at = Some(self.m.now());
        }
    }
    fn write16(&mut self, addr: u32, value: u16) {
        self.bus_calls += 1;
        self.m.write16(addr, value);
    }
    fn internal(&mut self, states: u32) {
        self.bus_calls += 1;
        self.m.internal(states);
    }
    fn pending_irq(&self) -> Option<u8> {
        self.m.pending_irq()
    }
    fn sleep_until_irq(&mut self, deadline: u64) -> bool {
        self.sleep_calls += 1;
        self.m.sleep_until_irq(deadline)
    }
}

fn tick_mcu() -> Mcu<NullBoard> {
    let mut m = Mcu::new(McuConfig::default(), NullBoard).unwrap();
    m.poke(0, &0x100u32.to_be_bytes());
    m.poke(24 * 4, &0x200u32.to_be_bytes());
    m.poke(0x100, &MAIN);
    m.poke(0x200, &ISR);
    m
}

#[test]
fn sleep_wakes_on_the_itu0_tick_by_fast_forward_and_enters_vector_24() {
    let mut m = tick_mcu();
    let mut cpu = Cpu::new();
    cpu.reset(&mut m);
    let mut probe = Probe {
        m: &mut m,
        tstr_written_at: None,
        sleep_calls: 0,
        bus_calls: 0,
    };
    // Run up to and including the first SLEEP.
    while cpu.pc() != SLEEP_PC {
        assert_eq!(cpu.step(&mut probe, u64::MAX), Ok(Event::Executed));
    }
    assert_eq!(cpu.step(&mut probe, u64::MAX), Ok(Event::Executed));
    assert!(cpu.sleeping());
    let t_start = probe.tstr_written_at.expect("TSTR written");
    // The prescaler runs from reset: counts at multiples of 8 states after the write; IMFA
    // is set at the count that takes TCNT from GRA to 0, the (GRA + 1)-th.
    let t_match = ((t_start >> 3) + GRA + 1) << 3;
    let t_asleep = probe.now();
    assert!(t_asleep < t_match);

    // One step: the CPU sleeps, the clock jumps to the compare match, the interrupt is taken.
    let calls_before = probe.bus_calls;
    assert_eq!(cpu.step(&mut probe, u64::MAX), Ok(Event::Interrupt(24)));
    assert_eq!(probe.sleep_calls, 1, "one fast-forward, not a stepped wait");
    let calls = probe.bus_calls - calls_before;
    assert!(
        calls < 20,
        "{calls} bus calls for a {}-state wait",
        t_match - t_asleep
    );
    // Interrupt entry (H8/3052F manual Table 5-5 as the core charges it): priority decision
    // 1 + prefetch 2 + PC/CCR push 2 × 2 + vector 2 × 2 + handler prefetch 2 + internal 4 = 17.
    assert_eq!(probe.now(), t_match + 17);
    assert_eq!(cpu.pc(), 0x200);
    assert_ne!(cpu.ccr() & CCR_I, 0);
    let sp = cpu.er(7);
    assert_eq!(sp, 0xFF_FF10 - 4);
    let frame = u32::from_be_bytes([m.peek(sp), m.peek(sp + 1), m.peek(sp + 2), m.peek(sp + 3)]);
    assert_eq!(
        frame & 0x00FF_FFFF,
        SLEEP_PC + 2,
        "return address after SLEEP"
    );
    assert_eq!(
        frame >> 24,
        0,
        "CCR pushed with I = 0 (interrupts were enabled)"
    );

    // The handler clears IMFA, returns, and the program halts with R0L = 0x2a.
    let mut events = Vec::new();
    for _ in 0..20 {
        let e = cpu.step(&mut m, u64::MAX).unwrap();
        events.push(e);
        if e == Event::Halted {
            break;
        }
    }
    assert_eq!(events.last(), Some(&Event::Halted), "{events:?}");
    assert_eq!(cpu.er(0) & 0xff, 0x2a);
    assert_eq!(m.pending_irq(), None, "IMFA cleared by the handler");
    assert_eq!(m.read8(0xFF_FF67) & itu::IMFA, 0);
}

#[test]
fn the_tick_keeps_its_period_across_many_sleeps() {
    // The same set-up but the handler returns to a SLEEP loop: ten ticks, each exactly
    // 3125 × 8 states after the previous one, each taken by a single fast-forward.
    let mut m = tick_mcu();
    // Replace "orc #0x80,ccr; sleep" after the first SLEEP with "bra .-2" (back to SLEEP).
    m.poke(0x11c, &[0x40, 0xfc]);
    let mut cpu = Cpu::new();
    cpu.reset(&mut m);
    let mut entries = Vec::new();
    while entries.len() < 10 {
        let t0 = m.now();
        match cpu.step(&mut m, u64::MAX).unwrap() {
            Event::Interrupt(v) => {
                assert_eq!(v, 24);
                entries.push(m.now());
            }
            Event::Executed => {}
            e => panic!("unexpected {e:?} at {t0}"),
        }
    }
    for w in entries.windows(2) {
        assert_eq!(w[1] - w[0], (GRA + 1) * 8);
    }
}

#[test]
fn machine_runs_on_the_mcu_with_its_peripherals() {
    // Machine is an Mcu<NullBoard>: the ITU answers machine code run through the run API.
    let mut m = Machine::new();
    m.poke(0, &0x100u32.to_be_bytes());
    m.poke(24 * 4, &0x200u32.to_be_bytes());
    m.poke(0x100, &MAIN);
    m.poke(0x200, &ISR);
    let mut cpu = Cpu::new();
    cpu.reset(&mut m);
    let mut out = Vec::new();
    let report = h8_3052f::run::run_machine(
        &mut cpu,
        &mut m,
        &h8_3052f::run::RunOptions::default(),
        &mut out,
        None,
    )
    .unwrap();
    assert_eq!(
        report.outcome,
        h8_3052f::run::Outcome::Halted { exit_status: 0x2a }
    );
    assert_eq!(report.stats.interrupts, 1);
    assert!(report.stats.states > GRA * 8);
    assert_eq!(m.clock_hz(), 25_000_000);
}
