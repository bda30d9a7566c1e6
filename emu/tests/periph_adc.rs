//! The A/D converter through the MCU's bus: conversion time (266 / 134 states), ADF at exactly
//! that state, the input sampled at the sampling instant (a board whose voltage changes with
//! time), scan order and repetition, ADI, the ADF clearing rule and the ADDR byte order.

use h8_3052f::mcu::{Mcu, McuConfig};
use h8_3052f::periph::adc::{
    ADCR, ADCSR, ADCSR_ADF, ADCSR_ADIE, ADCSR_ADST, ADCSR_CKS, ADCSR_SCAN, ADDRA, ADDRB, ADDRC,
    ADDRD, CONV_STATES_CKS0, CONV_STATES_CKS1, SAMPLE_OFFSET_CKS0, SAMPLE_OFFSET_CKS1,
    SCAN_CONV_STATES_CKS0, VECTOR_ADI,
};
use h8_3052f::periph::intc::{IPRA, IPRA_ITU0, IPRB, IPRB_AD};
use h8_3052f::pins::Board;
use h8300h::bus::Bus;
use h8300h::memmap::IO_ACCESS_STATES;
use sensors::adc10_code;

/// A board whose channel n reads `base[n] + slope · t` volts and that records every question.
#[derive(Clone, Debug, Default)]
struct RampBoard {
    base: [f64; 8],
    slope_v_per_state: f64,
    asked: Vec<(u8, u64)>,
}

impl Board for RampBoard {
    fn analog_volts(&mut self, channel: u8, now_states: u64) -> f64 {
        self.asked.push((channel, now_states));
        self.base[usize::from(channel)] + self.slope_v_per_state * now_states as f64
    }
    fn port2_pins(&mut self, _now_states: u64) -> u8 {
        0xFF
    }
}

fn mcu(board: RampBoard) -> Mcu<RampBoard> {
    Mcu::new(McuConfig::default(), board).unwrap()
}

/// Writes ADCSR and returns the instant the write took effect (the end of its bus cycle).
fn start(m: &mut Mcu<RampBoard>, adcsr: u8) -> u64 {
    m.write8(ADCSR, adcsr);
    m.now()
}

/// ADCSR as read by a byte read that ends exactly at `t` (on a copy of the MCU).
fn adcsr_at(m: &Mcu<RampBoard>, t: u64) -> u8 {
    let mut c = m.clone();
    let wait = t - c.now() - u64::from(IO_ACCESS_STATES);
    c.internal(u32::try_from(wait).unwrap());
    let v = c.read8(ADCSR);
    assert_eq!(c.now(), t);
    v
}

fn read_addr(m: &mut Mcu<RampBoard>, addr: u32) -> u16 {
    m.read16(addr)
}

#[test]
fn single_conversion_ends_exactly_266_states_after_adst() {
    let mut m = mcu(RampBoard::default());
    m.internal(1001);
    let t0 = start(&mut m, ADCSR_ADST | 1);
    let before = adcsr_at(&m, t0 + CONV_STATES_CKS0 - 1);
    assert_eq!(before & (ADCSR_ADF | ADCSR_ADST), ADCSR_ADST);
    let after = adcsr_at(&m, t0 + CONV_STATES_CKS0);
    assert_eq!(
        after & (ADCSR_ADF | ADCSR_ADST),
        ADCSR_ADF,
        "ADF set, ADST cleared"
    );
    assert_eq!(CONV_STATES_CKS0, 266);
}

#[test]
fn single_conversion_with_cks_takes_134_states() {
    let mut m = mcu(RampBoard::default());
    let t0 = start(&mut m, ADCSR_ADST | ADCSR_CKS | 3);
    assert_eq!(adcsr_at(&m, t0 + 133) & ADCSR_ADF, 0);
    assert_eq!(adcsr_at(&m, t0 + 134) & (ADCSR_ADF | ADCSR_ADST), ADCSR_ADF);
    assert_eq!(CONV_STATES_CKS1, 134);
}

#[test]
fn the_input_is_sampled_at_the_sampling_instant() {
    // 10 mV per state: the pin voltage differs by ~2.7 V between the start and the end.
    let board = RampBoard {
        slope_v_per_state: 0.01,
        ..RampBoard::default()
    };
    let mut m = mcu(board);
    let t0 = start(&mut m, ADCSR_ADST); // AN0, CKS = 0
    m.advance_to(t0 + 400);
    let t_sample = t0 + SAMPLE_OFFSET_CKS0;
    assert_eq!(SAMPLE_OFFSET_CKS0, 80);
    assert_eq!(m.board().asked, vec![(0, t_sample)]);
    let code = adc10_code(0.01 * t_sample as f64);
    assert_eq!(read_addr(&mut m, ADDRA), code << 6);
    // Neither the voltage at the start nor the one at the end would give that code.
    assert_ne!(adc10_code(0.01 * t0 as f64), code);
    assert_ne!(adc10_code(0.01 * (t0 + 266) as f64), code);

    // With CKS = 1 the sample is taken 40 states after the start.
    let t1 = start(&mut m, ADCSR_ADST | ADCSR_CKS | 1);
    m.advance_to(t1 + 200);
    assert_eq!(m.board().asked[1], (1, t1 + SAMPLE_OFFSET_CKS1));
    assert_eq!(SAMPLE_OFFSET_CKS1, 40);
}

#[test]
fn a_result_is_sampled_even_when_nobody_looks_until_later() {
    // The board is asked with the sampling instant, not with the time of the late access.
    let board = RampBoard {
        slope_v_per_state: 1e-4,
        ..RampBoard::default()
    };
    let mut m = mcu(board);
    let t0 = start(&mut m, ADCSR_ADST | 2);
    m.internal(1_000_000);
    let v = read_addr(&mut m, ADDRC);
    assert_eq!(m.board().asked, vec![(2, t0 + 80)]);
    assert_eq!(v, adc10_code(1e-4 * (t0 + 80) as f64) << 6);
}

#[test]
fn scan_mode_converts_the_group_in_order_and_repeats() {
    let board = RampBoard {
        base: [0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0],
        ..RampBoard::default()
    };
    let mut m = mcu(board);
    let t0 = start(&mut m, ADCSR_ADST | ADCSR_SCAN | 3); // AN0..AN3
    // Visit every conversion end so each is sampled.
    let ends: Vec<u64> = (0..10)
        .map(|k| t0 + CONV_STATES_CKS0 + k * SCAN_CONV_STATES_CKS0)
        .collect();
    for &e in &ends {
        m.advance_to(e);
    }
    let asked = m.board().asked.clone();
    assert_eq!(asked.len(), 10);
    for (k, &(ch, t)) in asked.iter().enumerate() {
        assert_eq!(usize::from(ch), k % 4, "conversion {k}");
        assert_eq!(t, ends[k] - (CONV_STATES_CKS0 - SAMPLE_OFFSET_CKS0));
    }
    // Results in ADDRA–D; ADST still set (scan repeats), ADF set after the first round.
    for (i, addr) in [ADDRA, ADDRB, ADDRC, ADDRD].into_iter().enumerate() {
        let v = 0.5 * (i as f64 + 1.0);
        assert_eq!(read_addr(&mut m, addr), adc10_code(v) << 6);
    }
    let s = m.read8(ADCSR);
    assert_eq!(s & (ADCSR_ADF | ADCSR_ADST), ADCSR_ADF | ADCSR_ADST);
}

#[test]
fn scan_adf_comes_at_the_end_of_each_round() {
    let mut m = mcu(RampBoard::default());
    let t0 = start(&mut m, ADCSR_ADST | ADCSR_SCAN | 1); // AN0, AN1
    let round_end = t0 + CONV_STATES_CKS0 + SCAN_CONV_STATES_CKS0;
    assert_eq!(adcsr_at(&m, round_end - 1) & ADCSR_ADF, 0);
    assert_ne!(adcsr_at(&m, round_end) & ADCSR_ADF, 0);
    // Clear ADF after the first round; it returns at the end of the second.
    let mut c = m.clone();
    c.advance_to(round_end);
    assert_ne!(c.read8(ADCSR) & ADCSR_ADF, 0);
    c.write8(ADCSR, ADCSR_ADST | ADCSR_SCAN | 1);
    assert_eq!(c.read8(ADCSR) & ADCSR_ADF, 0);
    let second_end = round_end + 2 * SCAN_CONV_STATES_CKS0;
    assert_eq!(adcsr_at(&c, second_end - 1) & ADCSR_ADF, 0);
    assert_ne!(adcsr_at(&c, second_end) & ADCSR_ADF, 0);
}

#[test]
fn scan_of_the_upper_group_fills_addra_to_addrc() {
    let board = RampBoard {
        base: [0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 4.0],
        ..RampBoard::default()
    };
    let mut m = mcu(board);
    let t0 = start(&mut m, ADCSR_ADST | ADCSR_SCAN | 6); // AN4..AN6
    for k in 0..3 {
        m.advance_to(t0 + CONV_STATES_CKS0 + k * SCAN_CONV_STATES_CKS0);
    }
    let chans: Vec<u8> = m.board().asked.iter().map(|&(c, _)| c).collect();
    assert_eq!(chans, vec![4, 5, 6]);
    assert_eq!(read_addr(&mut m, ADDRA), adc10_code(1.0) << 6);
    assert_eq!(read_addr(&mut m, ADDRC), adc10_code(3.0) << 6);
    assert_eq!(read_addr(&mut m, ADDRD), 0);
}

#[test]
fn adi_is_requested_with_adie_and_follows_the_priority() {
    let mut m = mcu(RampBoard::default());
    let t0 = start(&mut m, ADCSR_ADST | ADCSR_ADIE);
    assert_eq!(m.pending_irq(), None);
    // The sleep jumps to the end of the conversion and wakes on ADI.
    assert!(m.sleep_until_irq(u64::MAX));
    assert_eq!(m.now(), t0 + CONV_STATES_CKS0);
    assert_eq!(m.pending_irq(), Some(VECTOR_ADI));
    // Priority registers do not hide a lone request.
    m.write8(IPRB, IPRB_AD);
    m.write8(IPRA, IPRA_ITU0);
    assert_eq!(m.pending_irq(), Some(VECTOR_ADI));
    // Clearing ADIE withdraws the request but keeps ADF.
    m.write8(ADCSR, 0x80);
    assert_eq!(m.pending_irq(), None);
    assert_ne!(m.read8(ADCSR) & ADCSR_ADF, 0);
}

#[test]
fn adf_clears_only_after_it_was_read_as_one() {
    let mut m = mcu(RampBoard::default());
    let t0 = start(&mut m, ADCSR_ADST);
    m.advance_to(t0 + 300);
    // Writing 0 without having read ADF = 1 leaves it set.
    m.write8(ADCSR, 0);
    assert_ne!(m.read8(ADCSR) & ADCSR_ADF, 0);
    // Now it was read as 1: writing 0 clears it; writing 1 would not.
    m.write8(ADCSR, ADCSR_ADF);
    assert_ne!(m.read8(ADCSR) & ADCSR_ADF, 0);
    m.write8(ADCSR, 0);
    assert_eq!(m.read8(ADCSR) & ADCSR_ADF, 0);
}

#[test]
fn clearing_adst_aborts_the_conversion() {
    let board = RampBoard {
        base: [3.0; 8],
        ..RampBoard::default()
    };
    let mut m = mcu(board);
    let t0 = start(&mut m, ADCSR_ADST);
    m.advance_to(t0 + 100);
    m.write8(ADCSR, 0);
    m.advance_to(t0 + 1000);
    assert_eq!(m.read8(ADCSR) & (ADCSR_ADF | ADCSR_ADST), 0);
    assert_eq!(read_addr(&mut m, ADDRA), 0);
    assert!(m.board().asked.is_empty());
}

#[test]
fn addr_low_byte_comes_from_the_temporary_register() {
    let board = RampBoard {
        base: [1.0, 4.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ..RampBoard::default()
    };
    let mut m = mcu(board);
    let t0 = start(&mut m, ADCSR_ADST | ADCSR_SCAN | 1);
    m.advance_to(t0 + 1000);
    let a = adc10_code(1.0) << 6;
    let b = adc10_code(4.0) << 6;
    assert_ne!(a & 0xC0, b & 0xC0, "test needs different low bytes");
    // Upper byte of ADDRA, then the lower byte of ADDRB: the temporary register still holds
    // ADDRA's lower byte.
    assert_eq!(m.read8(ADDRA), (a >> 8) as u8);
    assert_eq!(m.read8(ADDRB + 1), a as u8);
    assert_eq!(m.read8(ADDRB), (b >> 8) as u8);
    assert_eq!(m.read8(ADDRB + 1), b as u8);
    // ADCR: TRGE stored, other bits read 1.
    assert_eq!(m.read8(ADCR), 0x7F);
    m.write8(ADCR, 0xFF);
    assert_eq!(m.read8(ADCR), 0xFF);
}

/// The chip's transfer function is the one the sensor model quantises with: the same code at
/// every transition voltage, one ulp either side of it, and across the range.
#[test]
fn the_chips_transfer_function_is_the_sensor_models() {
    use h8_3052f::periph::adc::{addr_register, code10};
    let mut volts = vec![f64::NAN, -1.0, 0.0, 5.0, 6.0, f64::INFINITY];
    for k in 0..=1024u32 {
        let t = f64::from(k) * 5.0 / 1024.0;
        volts.extend([t, t.next_down(), t.next_up()]);
    }
    volts.extend((0..20_000).map(|i| f64::from(i) * 5.5 / 20_000.0 - 0.2));
    for v in volts {
        assert_eq!(code10(v), adc10_code(v), "{v}");
        assert_eq!(
            addr_register(code10(v)),
            sensors::addr_register(adc10_code(v)),
            "{v}"
        );
    }
}
