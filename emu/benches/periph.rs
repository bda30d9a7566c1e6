//! Peripheral access speed on the [`Mcu`]: nanoseconds per register read or write (ITU, A/D,
//! ports with the I²C bus behind port 4) and per SLEEP fast-forward to the next ITU0 tick.
//!
//! Each access benchmark performs `ACCESSES` bus accesses per iteration; criterion's
//! throughput line then reads "accesses per second" (its inverse is the time per access,
//! including the bus cycle's clock advance and the peripheral's lazy catch-up).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use h8_3052f::mcu::{Mcu, McuConfig};
use h8_3052f::periph::adc::{ADCSR, ADCSR_ADST, ADCSR_SCAN, ADDRA};
use h8_3052f::periph::itu::{
    CHANNEL_BASE, IMFA, OFF_GRA, OFF_GRB, OFF_TCNT, OFF_TCR, OFF_TIER, OFF_TSR, TMDR, TSTR,
};
use h8_3052f::periph::ports::{P2DR, P2PCR, P4DDR, P4PCR};
use h8_3052f::pins::NullBoard;
use h8300h::bus::Bus;
use std::hint::black_box;

const ACCESSES: u64 = 1000;

/// An MCU as the robot's controller sets it up: a 1 kHz tick on ITU0, PWM on ITU1/ITU2, the
/// A/D scanning AN0–AN3, pull-ups on.
fn robot_mcu() -> Mcu<NullBoard> {
    let mut m = Mcu::new(McuConfig::default(), NullBoard).unwrap();
    for (ch, gra, grb) in [(0, 3124, 0xFFFF), (1, 1249, 400), (2, 1249, 900)] {
        let b = CHANNEL_BASE[ch];
        m.write8(b + OFF_TCR, 0x23);
        m.write16(b + OFF_GRA, gra);
        m.write16(b + OFF_GRB, grb);
    }
    m.write8(CHANNEL_BASE[0] + OFF_TIER, IMFA);
    m.write8(TMDR, 0x06);
    m.write8(TSTR, 0x07);
    m.write8(ADCSR, ADCSR_ADST | ADCSR_SCAN | 3);
    m.write8(P2PCR, 0xFF);
    m.write8(P4PCR, 0xC0);
    m
}

fn accesses(c: &mut Criterion) {
    let mut group = c.benchmark_group("periph_access");
    group.throughput(Throughput::Elements(ACCESSES));
    let tsr0 = CHANNEL_BASE[0] + OFF_TSR;
    let tcnt0 = CHANNEL_BASE[0] + OFF_TCNT;
    let grb1 = CHANNEL_BASE[1] + OFF_GRB;

    let mut m = robot_mcu();
    group.bench_function("itu_tsr_read8", |b| {
        b.iter(|| {
            let mut x = 0u8;
            for _ in 0..ACCESSES {
                x ^= m.read8(black_box(tsr0));
            }
            x
        });
    });
    let mut m = robot_mcu();
    group.bench_function("itu_tcnt_read16", |b| {
        b.iter(|| {
            let mut x = 0u16;
            for _ in 0..ACCESSES {
                x ^= m.read16(black_box(tcnt0));
            }
            x
        });
    });
    let mut m = robot_mcu();
    group.bench_function("itu_grb_write16", |b| {
        b.iter(|| {
            for i in 0..ACCESSES {
                m.write16(black_box(grb1), 200 + (i as u16 & 0x1FF));
            }
        });
    });
    let mut m = robot_mcu();
    group.bench_function("adc_adcsr_read8_scanning", |b| {
        b.iter(|| {
            let mut x = 0u8;
            for _ in 0..ACCESSES {
                x ^= m.read8(black_box(ADCSR));
            }
            x
        });
    });
    let mut m = robot_mcu();
    group.bench_function("adc_addra_read16_scanning", |b| {
        b.iter(|| {
            let mut x = 0u16;
            for _ in 0..ACCESSES {
                x ^= m.read16(black_box(ADDRA));
            }
            x
        });
    });
    let mut m = robot_mcu();
    group.bench_function("port2_read8", |b| {
        b.iter(|| {
            let mut x = 0u8;
            for _ in 0..ACCESSES {
                x ^= m.read8(black_box(P2DR));
            }
            x
        });
    });
    let mut m = robot_mcu();
    group.bench_function("port4_ddr_write8_i2c", |b| {
        b.iter(|| {
            for i in 0..ACCESSES {
                // Toggle SDA only (SCL stays released): a line change on the bus every write.
                m.write8(black_box(P4DDR), if i & 1 == 0 { 0x80 } else { 0x00 });
            }
        });
    });
    let mut m = robot_mcu();
    group.bench_function("tier_write8_then_pending_irq", |b| {
        // A write invalidates the cached interrupt decision: this is the cost of recomputing
        // it (three running ITU channels, the A/D scan, SCI1).
        let tier1 = CHANNEL_BASE[1] + OFF_TIER;
        b.iter(|| {
            let mut n = 0u32;
            for _ in 0..ACCESSES {
                m.write8(black_box(tier1), 0);
                n += u32::from(m.pending_irq().is_some());
            }
            n
        });
    });
    let m = robot_mcu();
    group.bench_function("pending_irq_cached", |b| {
        b.iter(|| {
            let mut n = 0u32;
            for _ in 0..ACCESSES {
                n += u32::from(black_box(&m).pending_irq().is_some());
            }
            n
        });
    });
    group.finish();
}

fn sleep_fast_forward(c: &mut Criterion) {
    let mut group = c.benchmark_group("sleep_fast_forward");
    group.throughput(Throughput::Elements(1));
    let mut m = robot_mcu();
    let tsr0 = CHANNEL_BASE[0] + OFF_TSR;
    // One iteration: sleep to the next 1 kHz tick (25 000 states), then clear IMFA as the
    // handler does.
    group.bench_function("tick_wake_and_clear", |b| {
        b.iter(|| {
            let woke = m.sleep_until_irq(u64::MAX);
            let tsr = m.read8(tsr0);
            m.write8(tsr0, tsr & !IMFA);
            woke
        });
    });
    group.finish();
}

criterion_group!(benches, accesses, sleep_fast_forward);
criterion_main!(benches);
