//! One full save of a persistence record through the pin-level bus and 24LC256 models (host
//! time), and the bus edges and emulated time a save takes (printed once before measuring).
//!
//! Payloads: 104 bytes (the arena network's 13 × 4 Q15 weights: 3 pages with the commit page)
//! and 300 bytes (6 pages). Each iteration starts from the same snapshot (chips holding records
//! 0..=3), so every iteration does the same work: save #4 on chip 0x50 with ACK polling.

use std::hint::black_box;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use eeprom::{I2cBus, I2cMaster, MasterTiming, Persistence, Record, RecordLayout, SimPins};

/// The MCU's φ these tests count in: the robot's 25 MHz (the crate has no clock of its own).
const CLOCK_HZ: u32 = 25_000_000;

fn record(seq: u32, len: usize) -> Record {
    Record {
        sequence: seq,
        payload: (0..len).map(|i| (i * 13 + seq as usize) as u8).collect(),
    }
}

fn snapshot(p: &Persistence, len: usize) -> I2cBus {
    let mut m = I2cMaster::new(
        SimPins::new(I2cBus::robot(1, CLOCK_HZ).unwrap()),
        MasterTiming::fast_mode(CLOCK_HZ).unwrap(),
    );
    m.init();
    for s in 0..4 {
        p.save(&mut m, &record(s, len)).unwrap();
    }
    m.into_pins().into_bus().unwrap()
}

fn report(p: &Persistence, bus: &I2cBus, len: usize) {
    let mut m = I2cMaster::new(
        SimPins::new(bus.clone()),
        MasterTiming::fast_mode(CLOCK_HZ).unwrap(),
    );
    let e0 = m.pins().edges();
    let t0 = m.pins().now();
    let rep = p.save(&mut m, &record(4, len)).unwrap();
    let e = m.pins().edges().since(&e0);
    let states = m.pins().now() - t0;
    let st = m.stats();
    let mut r = I2cMaster::new(
        SimPins::new(m.into_pins().into_bus().unwrap()),
        MasterTiming::fast_mode(CLOCK_HZ).unwrap(),
    );
    let r0 = r.pins().edges().total();
    let rt0 = r.pins().now();
    let rec = p.recover(&mut r);
    assert_eq!(rec.newest, Some(record(4, len)));
    println!(
        "save of {len} B payload ({} record bytes, {} pages on chip 0x{:02X}): {} bus edges \
         (SCL {}+{}, SDA {}+{}), {} pin operations, {} ACK polls {:?}, {} states = {:.3} ms at 25 MHz; \
         recovery: {} edges, {:.3} ms",
        rep.record_bytes,
        rep.pages_written,
        rep.chip,
        e.total(),
        e.scl_rising,
        e.scl_falling,
        e.sda_rising,
        e.sda_falling,
        st.pin_ops,
        rep.polls_per_page.iter().sum::<u32>(),
        rep.polls_per_page,
        states,
        states as f64 / 25_000.0,
        r.pins().edges().total() - r0,
        (r.pins().now() - rt0) as f64 / 25_000.0,
    );
}

fn bench_save(c: &mut Criterion) {
    let mut group = c.benchmark_group("eeprom_save");
    group.sample_size(20);
    for len in [104usize, 300] {
        let p = Persistence::new(RecordLayout::new(0, 512).unwrap(), 1_000).unwrap();
        let bus = snapshot(&p, len);
        report(&p, &bus, len);
        let rec = record(4, len);
        group.bench_function(format!("save_{len}B"), |b| {
            b.iter_batched(
                || bus.clone(),
                |bus| {
                    let mut m = I2cMaster::new(
                        SimPins::new(bus),
                        MasterTiming::fast_mode(CLOCK_HZ).unwrap(),
                    );
                    black_box(p.save(&mut m, black_box(&rec)).unwrap());
                    m
                },
                BatchSize::LargeInput,
            );
        });
    }
    group.finish();
}

criterion_group!(benches, bench_save);
criterion_main!(benches);
