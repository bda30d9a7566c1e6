//! The ITU: PWM period and duty from GRA/GRB (docs/design.md §3.5), compare-match and counter-clear
//! timing, the flag clearing rule, interrupt vectors, and the lazily computed counter against a
//! state-by-state reference model.

use h8_3052f::mcu::{Mcu, McuConfig};
use h8_3052f::periph::itu::{
    self, CHANNEL_BASE, IMFA, IMFB, Itu, OFF_GRA, OFF_GRB, OFF_TCNT, OFF_TCR, OFF_TIER, OFF_TIOR,
    OFF_TSR, OVF, TMDR, TSTR,
};
use h8_3052f::periph::ports::{PBDDR, PBDR};
use h8_3052f::pins::NullBoard;
use h8300h::bus::Bus;
use proptest::prelude::*;
use robot_board::wiring::{Bridge, ITU_MOTOR_LEFT, ITU_MOTOR_RIGHT, motor_pins};

/// TCR: counter cleared by GRA, φ/8 (the controller's setting, docs/design.md §3.5).
const TCR_GRA_PHI8: u8 = 0x23;

fn mcu() -> Mcu<NullBoard> {
    Mcu::new(McuConfig::default(), NullBoard).unwrap()
}

fn setup(m: &mut Mcu<NullBoard>, ch: usize, tcr: u8, gra: u16, grb: u16) {
    let b = CHANNEL_BASE[ch];
    m.write8(b + OFF_TCR, tcr);
    m.write16(b + OFF_GRA, gra);
    m.write16(b + OFF_GRB, grb);
}

#[test]
fn pwm_period_is_gra_plus_one_and_high_time_grb_plus_one_counts_of_0_32_us() {
    let mut m = mcu();
    setup(&mut m, ITU_MOTOR_LEFT, TCR_GRA_PHI8, 1249, 311);
    setup(&mut m, ITU_MOTOR_RIGHT, TCR_GRA_PHI8, 1249, 936);
    m.write8(TMDR, 0x06); // PWM1, PWM2
    m.write8(TSTR, 0x06);
    let pins = motor_pins(&mut m);
    for (drive, grb) in [(pins.left, 311u64), (pins.right, 936)] {
        assert!(drive.pwm.running);
        assert_eq!(drive.pwm.period_states, 1250 * 8);
        assert_eq!(drive.pwm.high_states, (grb + 1) * 8);
    }
    // One count at φ/8 is 8 states = 0.32 µs at 25 MHz.
    let count_s = 8.0 / f64::from(m.clock_hz());
    assert!((count_s - 0.32e-6).abs() < 1e-15);
    assert!((pins.left.pwm.duty() - 312.0 / 1250.0).abs() < 1e-12);
    assert!((pins.right.pwm.duty() - 937.0 / 1250.0).abs() < 1e-12);
}

#[test]
fn the_tioca_pin_follows_the_waveform() {
    let mut m = mcu();
    setup(&mut m, 1, TCR_GRA_PHI8, 99, 24);
    m.write8(TMDR, 0x02);
    m.write8(TSTR, 0x02);
    let t_start = m.now();
    // Count edges at multiples of 8; compare A (set) at the (GRA + 1)-th edge, then every
    // 100 counts; compare B (clear) 25 counts after each A.
    let first_a = ((t_start >> 3) + 100) << 3;
    let level_at = |m: &Mcu<NullBoard>, t: u64| {
        let mut c = m.clone();
        c.advance_to(t);
        motor_pins(&mut c).left.pwm.level
    };
    assert!(!level_at(&m, first_a - 1));
    for k in 0..50u64 {
        let a = first_a + k * 800;
        assert!(level_at(&m, a), "rise {k}");
        assert!(level_at(&m, a + 199), "high {k}");
        assert!(!level_at(&m, a + 200), "fall {k}");
        assert!(!level_at(&m, a + 799), "low {k}");
    }
    // The high fraction over a long window, measured on the pin, is (GRB + 1) / (GRA + 1).
    let mut high = 0u64;
    let mut c = m.clone();
    c.advance_to(first_a);
    for _ in 0..8000 {
        c.internal(1);
        c.sync();
        if motor_pins(&mut c).left.pwm.level {
            high += 1;
        }
    }
    assert_eq!(high, 8000 * 25 / 100);
}

#[test]
fn pwm_edge_cases_follow_the_manual() {
    let mut m = mcu();
    // GRB > GRA with clear on GRA: B never matches, 100 %.
    setup(&mut m, 1, TCR_GRA_PHI8, 99, 200);
    // Cleared by GRB instead: high from compare A to the clear, GRB − GRA counts.
    setup(&mut m, 2, 0x43, 30, 99);
    m.write8(TMDR, 0x06);
    m.write8(TSTR, 0x06);
    let p = motor_pins(&mut m);
    assert_eq!(p.left.pwm.high_states, p.left.pwm.period_states);
    assert_eq!(p.right.pwm.period_states, 100 * 8);
    assert_eq!(p.right.pwm.high_states, (99 - 30) * 8);
    // Stopping the timer holds the output and reports no PWM.
    m.advance_to(m.now() + 10_000);
    let level = motor_pins(&mut m).left.pwm.level;
    assert!(level);
    m.write8(TSTR, 0x00);
    let p = motor_pins(&mut m);
    assert!(!p.left.pwm.running);
    assert_eq!(p.left.pwm.level, level);
    assert!((p.left.pwm.duty() - 1.0).abs() < 1e-12);
}

#[test]
fn direction_pins_map_to_the_h_bridge_truth_table() {
    let mut m = mcu();
    m.write8(PBDDR, 0x0F);
    for (pb, left, right) in [
        (0b0000_0001, Bridge::Forward, Bridge::Coast),
        (0b0000_0110, Bridge::Reverse, Bridge::Forward),
        (0b0000_1011, Bridge::Brake, Bridge::Reverse),
        (0b0000_1100, Bridge::Coast, Bridge::Brake),
    ] {
        m.write8(PBDR, pb);
        let p = motor_pins(&mut m);
        assert_eq!(
            (p.left.bridge(), p.right.bridge()),
            (left, right),
            "PBDR {pb:08b}"
        );
    }
    // Pins that are not outputs do not drive the bridge.
    m.write8(PBDDR, 0x00);
    assert_eq!(motor_pins(&mut m).left.bridge(), Bridge::Coast);
}

#[test]
fn compare_match_flag_and_counter_clear_timing() {
    let mut m = mcu();
    let b = CHANNEL_BASE[0];
    setup(&mut m, 0, 0x20, 49, 0xFFFF); // clear on GRA, φ
    m.write8(TSTR, 0x01);
    let t0 = m.now();
    // With φ the counter counts every state: TCNT = 49 at t0 + 49; the count edge at t0 + 50
    // takes it to 0 and sets IMFA.
    let at = |t: u64| {
        let mut c = m.clone();
        c.internal(u32::try_from(t - t0 - 3).unwrap());
        let tcnt = c.clone().read16(b + OFF_TCNT);
        let tsr = c.read8(b + OFF_TSR);
        assert_eq!(c.now(), t, "both reads are one 3-state cycle");
        (tcnt, tsr & IMFA)
    };
    assert_eq!(at(t0 + 48), (48, 0));
    assert_eq!(at(t0 + 49), (49, 0));
    assert_eq!(at(t0 + 50), (0, IMFA));
    assert_eq!(at(t0 + 51), (1, IMFA));
    assert_eq!(at(t0 + 99), (49, IMFA));
    assert_eq!(at(t0 + 100), (0, IMFA));
}

#[test]
fn flags_clear_by_reading_one_then_writing_zero() {
    let mut m = mcu();
    let b = CHANNEL_BASE[2];
    setup(&mut m, 2, 0x20, 9, 4); // φ, clear on GRA: A and B every 10 states
    m.write8(b + OFF_TIOR, 0x00);
    m.write8(TSTR, 0x04);
    m.internal(100);
    // Writing 0 before reading the flags as 1 does nothing.
    m.write8(b + OFF_TSR, 0xF8);
    let tsr = m.read8(b + OFF_TSR);
    assert_eq!(tsr & (IMFA | IMFB), IMFA | IMFB);
    // Stop the counter so the flags cannot be set again, then clear only IMFB.
    m.write8(TSTR, 0x00);
    m.write8(b + OFF_TSR, !IMFB);
    assert_eq!(m.read8(b + OFF_TSR) & (IMFA | IMFB | OVF), IMFA);
    m.write8(b + OFF_TSR, !IMFA);
    assert_eq!(m.read8(b + OFF_TSR), 0xF8);
}

#[test]
fn each_channel_requests_its_own_vectors() {
    let mut m = mcu();
    for (ch, base) in CHANNEL_BASE.into_iter().enumerate() {
        setup(&mut m, ch, 0x20, 9, 4);
        m.write8(base + OFF_TIER, IMFB);
    }
    m.write8(TSTR, 0x10); // only ITU4
    m.internal(20);
    assert_eq!(m.pending_irq(), Some(41), "IMIB4");
    m.write8(TSTR, 0x14); // ITU2 too: lower vector wins
    m.internal(20);
    assert_eq!(m.pending_irq(), Some(33), "IMIB2");
    // Overflow of ITU0 (no clear, TCNT from H'FFF0): OVI0 = 26.
    m.write8(CHANNEL_BASE[0] + OFF_TCR, 0x00);
    m.write16(CHANNEL_BASE[0] + OFF_TCNT, 0xFFF0);
    m.write8(CHANNEL_BASE[0] + OFF_TIER, OVF);
    m.write8(TSTR, 0x15);
    m.internal(30);
    assert_eq!(m.pending_irq(), Some(26), "OVI0");
    assert_eq!(itu::VECTOR_IMIA, [24, 28, 32, 36, 40]);
}

#[test]
fn sleep_fast_forwards_to_the_next_tick() {
    let mut m = mcu();
    setup(&mut m, 0, TCR_GRA_PHI8, 3124, 0xFFFF);
    m.write8(CHANNEL_BASE[0] + OFF_TIER, IMFA);
    m.write8(TSTR, 0x01);
    let t0 = m.now();
    let first = ((t0 >> 3) + 3125) << 3;
    // A deadline before the tick: the clock stops at the deadline, no interrupt.
    assert!(!m.sleep_until_irq(first - 1));
    assert_eq!(m.now(), first - 1);
    assert!(m.sleep_until_irq(u64::MAX));
    assert_eq!(m.now(), first);
    assert_eq!(m.pending_irq(), Some(24));
    // A thousand ticks later (25 M states), still one jump per tick.
    for k in 1..=1000u64 {
        let tsr = m.read8(CHANNEL_BASE[0] + OFF_TSR);
        m.write8(CHANNEL_BASE[0] + OFF_TSR, tsr & !IMFA);
        assert_eq!(m.pending_irq(), None);
        assert!(m.sleep_until_irq(u64::MAX));
        assert_eq!(m.now(), first + k * 25_000);
    }
}

/// A state-by-state model of one channel, straight from the manual's description.
#[derive(Clone, Debug)]
struct Reference {
    tcnt: u16,
    flags: u8,
    tioca: bool,
}

impl Reference {
    fn step_to(&mut self, from: u64, to: u64, shift: u32, cfg: &Cfg) {
        for t in from + 1..=to {
            if t % (1 << shift) != 0 {
                continue;
            }
            let pre = self.tcnt;
            let a = pre == cfg.gra;
            let b = pre == cfg.grb;
            if a {
                self.flags |= IMFA;
            }
            if b {
                self.flags |= IMFB;
            }
            if pre == 0xFFFF {
                self.flags |= OVF;
            }
            if cfg.pwm {
                if a && !b {
                    self.tioca = true;
                } else if b && !a {
                    self.tioca = false;
                }
            } else if a && cfg.ioa == 3 {
                self.tioca = !self.tioca;
            }
            let clear = match cfg.cclr {
                1 => a,
                2 => b,
                _ => false,
            };
            self.tcnt = if clear { 0 } else { pre.wrapping_add(1) };
        }
    }
}

#[derive(Clone, Debug)]
struct Cfg {
    shift: u32,
    cclr: u8,
    gra: u16,
    grb: u16,
    tcnt0: u16,
    pwm: bool,
    /// IOA: 0 (no output) or 3 (toggle), only outside PWM mode.
    ioa: u8,
}

fn cfg_strategy() -> impl Strategy<Value = Cfg> {
    let small = 0u16..300;
    let value = prop_oneof![small, 0xFF00u16..=0xFFFF, any::<u16>()];
    (
        0u32..4,
        0u8..3,
        value.clone(),
        value.clone(),
        value,
        any::<bool>(),
        prop_oneof![Just(0u8), Just(3u8)],
    )
        .prop_map(|(shift, cclr, gra, grb, tcnt0, pwm, ioa)| Cfg {
            shift,
            cclr,
            gra,
            grb,
            tcnt0,
            pwm,
            ioa: if pwm { 0 } else { ioa },
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// The O(1) lazy counter agrees with stepping every state: TCNT, the three flags and
    /// TIOCA at every access instant.
    #[test]
    fn lazy_counter_matches_a_state_by_state_model(
        cfg in cfg_strategy(),
        start in 0u64..64,
        gaps in prop::collection::vec(1u64..3000, 1..12),
    ) {
        let base = CHANNEL_BASE[0];
        let mut itu = Itu::new();
        let tcr = (cfg.cclr << 5) | cfg.shift as u8;
        itu.write(base + OFF_TCR, tcr, 0);
        itu.write(base + OFF_TIOR, cfg.ioa, 0);
        itu.write(base + OFF_GRA, (cfg.gra >> 8) as u8, 0);
        itu.write(base + OFF_GRA + 1, cfg.gra as u8, 0);
        itu.write(base + OFF_GRB, (cfg.grb >> 8) as u8, 0);
        itu.write(base + OFF_GRB + 1, cfg.grb as u8, 0);
        itu.write(base + OFF_TCNT, (cfg.tcnt0 >> 8) as u8, 0);
        itu.write(base + OFF_TCNT + 1, cfg.tcnt0 as u8, 0);
        itu.write(TMDR, u8::from(cfg.pwm), 0);
        itu.write(TSTR, 0x01, start);
        let mut reference = Reference { tcnt: cfg.tcnt0, flags: 0, tioca: false };
        let mut t = start;
        for gap in gaps {
            let next = t + gap;
            reference.step_to(t, next, cfg.shift, &cfg);
            t = next;
            prop_assert_eq!(itu.tcnt(0, t), reference.tcnt, "TCNT at {}", t);
            prop_assert_eq!(itu.read(base + OFF_TSR, t) & 0x07, reference.flags, "TSR at {}", t);
            prop_assert_eq!(itu.tioca(0, t).0, reference.tioca, "TIOCA at {}", t);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// The steady-state waveform `Itu::pwm` reports is what the pin does, state by state, over
    /// one period after the first.
    #[test]
    fn reported_pwm_wave_matches_the_pin(
        shift in 0u32..4,
        clear_on_b in any::<bool>(),
        gra in 0u16..150,
        grb in 0u16..150,
        start in 0u64..16,
    ) {
        let base = CHANNEL_BASE[1];
        let mut itu = Itu::new();
        let cclr: u8 = if clear_on_b { 2 } else { 1 };
        itu.write(base + OFF_TCR, (cclr << 5) | shift as u8, 0);
        itu.write(base + OFF_GRA, (gra >> 8) as u8, 0);
        itu.write(base + OFF_GRA + 1, gra as u8, 0);
        itu.write(base + OFF_GRB, (grb >> 8) as u8, 0);
        itu.write(base + OFF_GRB + 1, grb as u8, 0);
        itu.write(TMDR, 0x02, 0);
        itu.write(TSTR, 0x02, start);
        let counts = u64::from(if clear_on_b { grb } else { gra }) + 1;
        let period = counts << shift;
        // Settle for two periods, then measure one, state by state.
        let t0 = start + 2 * period + (1 << shift);
        let mut high = 0;
        for t in t0..t0 + period {
            if itu.tioca(1, t).0 {
                high += 1;
            }
        }
        let level = itu.tioca(1, t0 + period).0;
        let wave = itu.pwm(1, level).unwrap();
        prop_assert_eq!(wave.period_states, period);
        prop_assert_eq!(wave.high_states, high);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// As above, with register writes while the counter runs (GRA, GRB or TCNT rewritten at
    /// access instants, as firmware changing the PWM duty does).
    #[test]
    fn lazy_counter_matches_the_model_across_register_writes(
        cfg in cfg_strategy(),
        steps in prop::collection::vec((1u64..2500, 0u8..4, any::<u16>()), 1..16),
    ) {
        let base = CHANNEL_BASE[3];
        let mut itu = Itu::new();
        let mut cfg = cfg;
        itu.write(base + OFF_TCR, (cfg.cclr << 5) | cfg.shift as u8, 0);
        itu.write(base + OFF_TIOR, cfg.ioa, 0);
        let put16 = |itu: &mut Itu, off: u32, v: u16, t: u64| {
            itu.write(base + off, (v >> 8) as u8, t);
            itu.write(base + off + 1, v as u8, t);
        };
        put16(&mut itu, OFF_GRA, cfg.gra, 0);
        put16(&mut itu, OFF_GRB, cfg.grb, 0);
        put16(&mut itu, OFF_TCNT, cfg.tcnt0, 0);
        itu.write(TMDR, if cfg.pwm { 0x08 } else { 0 }, 0);
        itu.write(TSTR, 0x08, 0);
        let mut reference = Reference { tcnt: cfg.tcnt0, flags: 0, tioca: false };
        let mut t = 0;
        for (gap, what, value) in steps {
            let next = t + gap;
            reference.step_to(t, next, cfg.shift, &cfg);
            t = next;
            prop_assert_eq!(itu.tcnt(3, t), reference.tcnt, "TCNT at {}", t);
            prop_assert_eq!(itu.read(base + OFF_TSR, t) & 0x07, reference.flags, "TSR at {}", t);
            prop_assert_eq!(itu.tioca(3, t).0, reference.tioca, "TIOCA at {}", t);
            // Small values keep compare matches frequent.
            let v = if value & 0x8000 != 0 { value } else { value % 300 };
            match what {
                0 => { put16(&mut itu, OFF_GRA, v, t); cfg.gra = v; }
                1 => { put16(&mut itu, OFF_GRB, v, t); cfg.grb = v; }
                2 => { put16(&mut itu, OFF_TCNT, v, t); reference.tcnt = v; }
                _ => {}
            }
        }
    }
}
