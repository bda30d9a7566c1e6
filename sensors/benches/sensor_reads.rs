//! A million IR sensor reads (host time): what the emulator pays per A/D conversion.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use sensors::{DU_TABLE, IrParams, IrSensor, adc10_code, code8_from_adc10};

/// The MCU's φ the sensors count in: the robot's 25 MHz (the crate has no clock of its own).
const CLOCK_HZ: u32 = 25_000_000;

const READS: u64 = 1_000_000;
/// One A/D conversion with CKS = 0 at φ = 25 MHz (docs/design.md §3.2): reads 266 states apart, so a
/// million reads cover 10.6 s of emulated time and ~280 sample-and-hold refreshes.
const READ_SPACING_STATES: u64 = 266;

fn million_reads(c: &mut Criterion) {
    let mut group = c.benchmark_group("ir_sensor");
    group.throughput(Throughput::Elements(READS));
    group.sample_size(10);

    group.bench_function("sample_1M_reads", |b| {
        b.iter(|| {
            let mut s = IrSensor::new(IrParams::datasheet(CLOCK_HZ), 1)
                .expect("default parameters are valid");
            let mut acc = 0.0;
            for i in 0..READS {
                let d_mm = 100.0 + (i % 700) as f64;
                acc += s
                    .sample(i * READ_SPACING_STATES, Some(black_box(d_mm)))
                    .expect("valid distance, time forward");
            }
            black_box(acc)
        });
    });

    group.bench_function("sample_adc_du_1M_reads", |b| {
        b.iter(|| {
            let mut s = IrSensor::new(IrParams::datasheet(CLOCK_HZ), 1)
                .expect("default parameters are valid");
            let mut acc = 0u64;
            for i in 0..READS {
                let d_mm = 100.0 + (i % 700) as f64;
                let v = s
                    .sample(i * READ_SPACING_STATES, Some(black_box(d_mm)))
                    .expect("valid distance, time forward");
                acc += u64::from(DU_TABLE[usize::from(code8_from_adc10(adc10_code(v)))]);
            }
            black_box(acc)
        });
    });
    group.finish();
}

criterion_group!(benches, million_reads);
criterion_main!(benches);
