//! One test per datasheet behaviour (DS21203), through the bus and the bit-banging master.

use crate::datasheet::{PAGE_BYTES, T_WC_MAX_NS, T_WC_MODEL_MIN_NS};
use crate::{
    DeviceConfig, EepromError, I2cBus, I2cMaster, I2cPins, MasterError, MasterTiming, NackStage,
    SimPins,
};

/// The MCU's φ these tests count in: the robot's 25 MHz (the crate has no clock of its own).
const CLOCK_HZ: u32 = 25_000_000;

type M = I2cMaster<SimPins>;

fn master_on(bus: I2cBus) -> M {
    let mut m = I2cMaster::new(
        SimPins::new(bus),
        MasterTiming::fast_mode(CLOCK_HZ).unwrap(),
    );
    m.init();
    m
}

fn robot(seed: u64) -> M {
    master_on(I2cBus::robot(seed, CLOCK_HZ).unwrap())
}

fn with_config(f: impl Fn(&mut DeviceConfig)) -> M {
    let mut cfg = DeviceConfig::new(0x50, 11, CLOCK_HZ);
    f(&mut cfg);
    master_on(I2cBus::with_chips(&[0x50, 0x51], &cfg).unwrap())
}

fn now(m: &M) -> u64 {
    m.pins().now()
}

fn peek(m: &mut M, chip: u8, addr: u16, n: usize) -> Vec<u8> {
    let t = now(m);
    let mut v = vec![0; n];
    m.pins_mut()
        .bus_mut()
        .device_mut(chip)
        .unwrap()
        .read(t, addr, &mut v)
        .unwrap();
    v
}

fn writes(m: &M, chip: u8, page: usize) -> u32 {
    m.pins()
        .bus()
        .device(chip)
        .unwrap()
        .write_count(page)
        .unwrap()
}

fn violations(m: &M) -> u64 {
    m.pins().bus().timing_violation_count()
}

// ---- START / STOP / control byte / ACK -------------------------------------------------

#[test]
fn start_and_stop_are_recognised_and_counted() {
    let mut m = robot(1);
    m.byte_write(0x50, 0x0010, 0xAB).unwrap();
    let s = m.pins().bus().device(0x50).unwrap().stats();
    assert_eq!((s.starts, s.stops), (1, 1));
    // The other chip sees the same conditions but is not addressed.
    let s1 = m.pins().bus().device(0x51).unwrap().stats();
    assert_eq!((s1.starts, s1.stops, s1.control_acks), (1, 1, 0));
    assert_eq!(s.control_acks, 1);
}

#[test]
fn repeated_start_ends_a_write_without_writing() {
    let mut m = robot(2);
    let mut b = [0u8; 1];
    m.random_read(0x50, 0x0123, &mut b).unwrap();
    let s = m.pins().bus().device(0x50).unwrap().stats();
    assert_eq!(s.starts, 2, "START + repeated START");
    assert_eq!(s.write_cycles, 0);
    assert!(
        m.pins()
            .bus()
            .device(0x50)
            .unwrap()
            .write_counts()
            .iter()
            .all(|&c| c == 0)
    );
    assert_eq!(
        m.pins().bus().device(0x50).unwrap().address_pointer(),
        0x0124
    );
}

#[test]
fn control_byte_selects_only_the_chip_with_matching_a2_a1_a0() {
    let mut m = robot(3);
    m.byte_write(0x51, 0x0000, 0x5A).unwrap();
    m.ack_poll(0x51, 1000).unwrap();
    assert_eq!(peek(&mut m, 0x51, 0, 1), [0x5A]);
    assert_eq!(peek(&mut m, 0x50, 0, 1), [0xFF]);
    // No chip at 0x52: the control byte is not acknowledged.
    assert_eq!(
        m.byte_write(0x52, 0, 0),
        Err(MasterError::Nack {
            device: 0x52,
            stage: NackStage::Control
        })
    );
}

#[test]
fn device_pulls_sda_low_during_the_ninth_clock_after_its_output_delay() {
    let bus = I2cBus::robot(4, CLOCK_HZ).unwrap();
    let delay = bus.device(0x50).unwrap().output_delay_states();
    assert_eq!(delay, 22, "900 ns at 25 MHz, rounded down");
    let mut p = SimPins::new(bus);
    // START
    p.sda_low();
    p.wait_states(20);
    p.scl_low();
    // control byte 1010 000 0, MSB first
    for i in (0..8).rev() {
        if (0xA0u8 >> i) & 1 == 1 {
            p.sda_release();
        } else {
            p.sda_low();
        }
        p.wait_states(50);
        p.scl_release();
        p.wait_states(20);
        p.scl_low();
    }
    p.sda_release();
    // Before the output delay the line is still released (wired-AND: nobody pulls).
    p.wait_states(delay - 1);
    assert!(p.sda_is_high(), "ACK must not appear before T_AA");
    p.wait_states(1);
    assert!(!p.sda_is_high(), "chip pulls SDA low for the ACK");
    p.wait_states(30);
    p.scl_release();
    p.wait_states(20);
    assert!(
        !p.sda_is_high(),
        "ACK held while SCL is high in the 9th clock"
    );
    p.scl_low();
    p.wait_states(delay);
    assert!(p.sda_is_high(), "ACK released after the 9th clock");
    // Wired-AND: master pulls, chip releases -> low.
    p.sda_low();
    assert!(!p.sda_is_high());
}

#[test]
fn scl_edges_of_a_byte_write_are_exactly_37_clocks_plus_start_and_stop() {
    let mut m = robot(5);
    let e0 = m.pins().edges();
    m.byte_write(0x50, 0x1234, 0x00).unwrap();
    let e = m.pins().edges().since(&e0);
    // START: 1 SCL fall; 4 bytes x 9 clocks; STOP: 1 SCL rise.
    assert_eq!(e.scl_falling, 1 + 36);
    assert_eq!(e.scl_rising, 36 + 1);
    // SDA: START fall and STOP rise at least, and every edge is counted in the total.
    assert!(e.sda_falling >= 1 && e.sda_rising >= 1);
    assert_eq!(
        e.total(),
        e.scl_falling + e.scl_rising + e.sda_falling + e.sda_rising
    );
}

// ---- writes ----------------------------------------------------------------------------

#[test]
fn byte_write_then_random_read() {
    let mut m = robot(6);
    m.byte_write(0x50, 0x7FFF, 0x42).unwrap();
    m.ack_poll(0x50, 1000).unwrap();
    let mut b = [0u8; 1];
    m.random_read(0x50, 0x7FFF, &mut b).unwrap();
    assert_eq!(b, [0x42]);
    assert_eq!(writes(&m, 0x50, 511), 1);
    assert_eq!(violations(&m), 0);
}

#[test]
fn page_write_wraps_to_the_start_of_the_same_page() {
    let mut m = robot(7);
    let data: Vec<u8> = (1..=10).collect();
    // Offset 60 of page 2 (0x80): 4 bytes fit, 6 wrap to 0x80..0x85.
    m.write_raw(0x50, 0x00BC, &data).unwrap();
    m.ack_poll(0x50, 1000).unwrap();
    assert_eq!(peek(&mut m, 0x50, 0x00BC, 4), [1, 2, 3, 4]);
    assert_eq!(peek(&mut m, 0x50, 0x0080, 6), [5, 6, 7, 8, 9, 10]);
    assert_eq!(
        peek(&mut m, 0x50, 0x0086, 54),
        vec![0xFF; 54],
        "untouched in the page"
    );
    assert_eq!(
        peek(&mut m, 0x50, 0x00C0, 8),
        vec![0xFF; 8],
        "next page untouched"
    );
    assert_eq!(writes(&m, 0x50, 2), 1);
    assert_eq!(writes(&m, 0x50, 3), 0);
}

#[test]
fn more_than_64_bytes_overwrite_the_earliest() {
    let mut m = robot(8);
    let data: Vec<u8> = (0..70).collect();
    m.write_raw(0x50, 0x0200, &data).unwrap();
    m.ack_poll(0x50, 1000).unwrap();
    let page = peek(&mut m, 0x50, 0x0200, PAGE_BYTES);
    let mut expected: Vec<u8> = (0..64).collect();
    expected[..6].copy_from_slice(&[64, 65, 66, 67, 68, 69]);
    assert_eq!(page, expected);
    assert_eq!(peek(&mut m, 0x50, 0x0240, 1), [0xFF]);
}

#[test]
fn page_write_refuses_to_cross_a_page_and_bad_arguments() {
    let mut m = robot(9);
    let e = m.page_write(0x50, 0x003E, &[1, 2, 3]).unwrap_err();
    assert!(matches!(
        e,
        MasterError::CrossesPage {
            room: 2,
            boundary: 0x40,
            ..
        }
    ));
    assert!(e.to_string().contains("0x0040"), "{e}");
    assert!(matches!(
        m.page_write(0x50, 0x0000, &[]),
        Err(MasterError::EmptyTransfer { .. })
    ));
    assert!(matches!(
        m.page_write(0x50, 0x8000, &[1]),
        Err(MasterError::MemoryAddressOutOfRange { address: 0x8000 })
    ));
    assert!(matches!(
        m.byte_write(0x48, 0, 1),
        Err(MasterError::InvalidDeviceAddress { address: 0x48 })
    ));
    let mut empty: [u8; 0] = [];
    assert!(m.random_read(0x50, 0, &mut empty).is_err());
    assert!(m.current_address_read(0x60, &mut [0u8; 1]).is_err());
    assert_eq!(m.ack_poll(0x50, 0), Err(MasterError::InvalidPollBound));
    // A full page is fine.
    m.page_write(0x50, 0x0040, &[7; 64]).unwrap();
}

#[test]
fn stop_in_the_middle_of_a_byte_writes_only_whole_bytes() {
    let mut m = robot(10);
    // Address the chip and send one whole data byte by hand, then half a byte and a STOP.
    {
        let p = m.pins_mut();
        let byte = |p: &mut SimPins, b: u8| {
            for i in (0..8).rev() {
                if (b >> i) & 1 == 1 {
                    p.sda_release();
                } else {
                    p.sda_low();
                }
                p.wait_states(50);
                p.scl_release();
                p.wait_states(20);
                p.scl_low();
            }
            p.sda_release();
            p.wait_states(50);
            p.scl_release();
            p.wait_states(20);
            p.scl_low();
        };
        p.sda_low();
        p.wait_states(20);
        p.scl_low();
        for b in [0xA0, 0x01, 0x00, 0x11] {
            byte(p, b);
        }
        // Four bits of a second data byte, then STOP.
        for _ in 0..4 {
            p.sda_low();
            p.wait_states(50);
            p.scl_release();
            p.wait_states(20);
            p.scl_low();
        }
        p.sda_low();
        p.wait_states(50);
        p.scl_release();
        p.wait_states(20);
        p.sda_release();
        p.wait_states(40);
    }
    m.ack_poll(0x50, 1000).unwrap();
    assert_eq!(peek(&mut m, 0x50, 0x0100, 2), [0x11, 0xFF]);
    assert_eq!(writes(&m, 0x50, 4), 1);
}

#[test]
fn address_only_write_sets_the_pointer_and_starts_no_write_cycle() {
    let mut m = robot(11);
    m.write_raw(0x50, 0x0456, &[]).unwrap();
    assert_eq!(
        m.pins().bus().device(0x50).unwrap().address_pointer(),
        0x0456
    );
    assert_eq!(m.ack_poll(0x50, 1).unwrap(), 1, "not busy");
    assert!(
        m.pins()
            .bus()
            .device(0x50)
            .unwrap()
            .write_counts()
            .iter()
            .all(|&c| c == 0)
    );
}

// ---- reads -----------------------------------------------------------------------------

#[test]
fn current_address_read_follows_the_last_write_and_read() {
    let mut m = robot(12);
    m.page_write(0x50, 0x0300, &[10, 11, 12]).unwrap();
    m.ack_poll(0x50, 1000).unwrap();
    // After a write the pointer is just past the last byte written.
    assert_eq!(
        m.pins().bus().device(0x50).unwrap().address_pointer(),
        0x0303
    );
    m.pins_mut()
        .bus_mut()
        .device_mut(0x50)
        .unwrap()
        .load(0x0303, &[13])
        .unwrap();
    let mut b = [0u8; 1];
    m.current_address_read(0x50, &mut b).unwrap();
    assert_eq!(b, [13]);
    m.random_read(0x50, 0x0300, &mut b).unwrap();
    assert_eq!(b, [10]);
    m.current_address_read(0x50, &mut b).unwrap();
    assert_eq!(b, [11], "pointer is last read + 1");
}

#[test]
fn after_a_wrapping_page_write_the_pointer_wraps_too() {
    let mut m = robot(13);
    m.write_raw(0x50, 0x003F, &[1, 2]).unwrap();
    m.ack_poll(0x50, 1000).unwrap();
    assert_eq!(
        m.pins().bus().device(0x50).unwrap().address_pointer(),
        0x0001
    );
}

#[test]
fn sequential_read_rolls_over_from_7fff_to_0000() {
    let mut m = robot(14);
    {
        let d = m.pins_mut().bus_mut().device_mut(0x51).unwrap();
        d.load(0x7FFD, &[1, 2, 3]).unwrap();
        d.load(0x0000, &[4, 5]).unwrap();
    }
    let mut b = [0u8; 5];
    m.random_read(0x51, 0x7FFD, &mut b).unwrap();
    assert_eq!(b, [1, 2, 3, 4, 5]);
    assert_eq!(
        m.pins().bus().device(0x51).unwrap().address_pointer(),
        0x0002
    );
    // A long sequential read across many pages.
    let pattern: Vec<u8> = (0..200u32).map(|i| (i * 7 + 3) as u8).collect();
    m.pins_mut()
        .bus_mut()
        .device_mut(0x51)
        .unwrap()
        .load(0x1000, &pattern)
        .unwrap();
    let mut long = vec![0u8; 200];
    m.random_read(0x51, 0x1000, &mut long).unwrap();
    assert_eq!(long, pattern);
    assert_eq!(violations(&m), 0);
}

#[test]
fn a_master_that_samples_before_t_aa_reads_stale_bits() {
    let mut m = robot(15);
    m.pins_mut()
        .bus_mut()
        .device_mut(0x50)
        .unwrap()
        .load(0x0000, &[0x55])
        .unwrap();
    let mut fast = *m.timing();
    fast.scl_low_states = 5; // 200 ns, far below T_LOW and T_AA
    let mut bad = I2cMaster::new(m.into_pins(), fast);
    let mut b = [0u8; 1];
    let r = bad.random_read(0x50, 0x0000, &mut b);
    assert!(
        r.is_err() || b != [0x55],
        "too-fast clocking must not read correctly"
    );
    assert!(
        bad.pins().bus().timing_violation_count() > 0,
        "the chip noticed"
    );
}

// ---- write cycle, busy, polling --------------------------------------------------------

#[test]
fn busy_chip_does_not_ack_its_control_byte_and_polling_counts_tries() {
    let mut m = robot(16);
    m.byte_write(0x50, 0x0000, 1).unwrap();
    let cycle = m
        .pins()
        .bus()
        .device(0x50)
        .unwrap()
        .current_write_cycle()
        .unwrap();
    let t_wc = cycle.end_states - cycle.start_states;
    assert!(
        (75_000..=125_000).contains(&t_wc),
        "3..5 ms at 25 MHz: {t_wc}"
    );
    // Busy: a read is refused at the control byte.
    let mut b = [0u8; 1];
    assert_eq!(
        m.random_read(0x50, 0, &mut b),
        Err(MasterError::Nack {
            device: 0x50,
            stage: NackStage::Control
        })
    );
    // The other chip is not busy.
    m.random_read(0x51, 0, &mut b).unwrap();
    // A bound too small times out with an error naming the chip.
    let e = m.ack_poll(0x50, 3).unwrap_err();
    assert!(
        matches!(
            e,
            MasterError::PollTimeout {
                device: 0x50,
                polls: 3,
                ..
            }
        ),
        "{e}"
    );
    let t_before = now(&m);
    let polls = m.ack_poll(0x50, 1000).unwrap();
    assert!(polls > 1);
    let t_after = now(&m);
    assert!(
        t_after >= cycle.end_states,
        "ACK only after the cycle ended"
    );
    // The last NACKed poll began before the end: the poll count fits the remaining time.
    let per_poll = (t_after - t_before) / u64::from(polls);
    assert!(t_before + (u64::from(polls) - 1) * per_poll <= cycle.end_states + per_poll);
    assert!(m.pins().bus().device(0x50).unwrap().stats().busy_nacks >= u64::from(polls) - 1);
    assert_eq!(peek(&mut m, 0x50, 0, 1), [1]);
}

#[test]
fn write_cycle_time_is_seeded_and_stays_in_range() {
    let draw = |seed: u64| {
        let mut m = robot(seed);
        let mut v = Vec::new();
        for i in 0..20u16 {
            m.byte_write(0x50, i * 64, 0).unwrap();
            let c = m
                .pins()
                .bus()
                .device(0x50)
                .unwrap()
                .current_write_cycle()
                .unwrap();
            v.push(c.end_states - c.start_states);
            m.ack_poll(0x50, 1000).unwrap();
        }
        v
    };
    let a = draw(100);
    assert_eq!(a, draw(100), "same seed, same times");
    assert_ne!(a, draw(101));
    assert!(a.iter().all(|t| (75_000..=125_000).contains(t)));
    // A fixed t_WC is allowed (min = max), at the ends of the range too.
    let mut m = with_config(|c| {
        c.t_wc_min_ns = T_WC_MAX_NS;
        c.t_wc_max_ns = T_WC_MAX_NS;
    });
    m.byte_write(0x50, 0, 0).unwrap();
    let c = m
        .pins()
        .bus()
        .device(0x50)
        .unwrap()
        .current_write_cycle()
        .unwrap();
    assert_eq!(c.end_states - c.start_states, 125_000);
    let m = with_config(|c| {
        c.t_wc_min_ns = T_WC_MODEL_MIN_NS;
        c.t_wc_max_ns = T_WC_MODEL_MIN_NS;
    });
    assert_eq!(
        m.pins().bus().device(0x50).unwrap().t_wc_range_states(),
        (75_000, 75_000)
    );
}

#[test]
fn write_counter_counts_every_write_cycle_per_page() {
    let mut m = robot(17);
    for _ in 0..3 {
        m.page_write(0x50, 0x0040, &[1, 2]).unwrap();
        m.ack_poll(0x50, 1000).unwrap();
    }
    m.byte_write(0x50, 0x007F, 9).unwrap();
    m.ack_poll(0x50, 1000).unwrap();
    m.byte_write(0x51, 0x0040, 9).unwrap();
    m.ack_poll(0x51, 1000).unwrap();
    assert_eq!(writes(&m, 0x50, 1), 4);
    assert_eq!(writes(&m, 0x51, 1), 1);
    assert_eq!(writes(&m, 0x50, 0), 0);
    let total: u32 = m
        .pins()
        .bus()
        .device(0x50)
        .unwrap()
        .write_counts()
        .iter()
        .sum();
    assert_eq!(total, 4);
}

// ---- endurance -------------------------------------------------------------------------

#[test]
fn past_the_endurance_limit_bits_stick() {
    // Limit 2, every bit sticks on the first write past it: the page keeps its old data.
    let mut m = with_config(|c| {
        c.endurance_cycles = 2;
        c.stuck_bit_probability = 1.0;
    });
    for (i, v) in [0x11u8, 0x22, 0x33].iter().enumerate() {
        m.page_write(0x50, 0x0000, &[*v; 64]).unwrap();
        m.ack_poll(0x50, 1000).unwrap();
        let stuck = m.pins().bus().device(0x50).unwrap().stuck_bit_count();
        if i < 2 {
            assert_eq!(stuck, 0, "no wear within the limit");
        }
    }
    assert_eq!(
        peek(&mut m, 0x50, 0, 64),
        vec![0x22; 64],
        "3rd write had no effect"
    );
    assert_eq!(m.pins().bus().device(0x50).unwrap().stuck_bit_count(), 512);
    // Other pages still work.
    m.byte_write(0x50, 0x0040, 0x44).unwrap();
    m.ack_poll(0x50, 1000).unwrap();
    assert_eq!(peek(&mut m, 0x50, 0x0040, 1), [0x44]);
    assert_eq!(writes(&m, 0x50, 0), 3);
}

#[test]
fn wear_is_probabilistic_and_seeded() {
    let run = |seed: u64| {
        let mut cfg = DeviceConfig::new(0x50, seed, CLOCK_HZ);
        cfg.endurance_cycles = 1;
        cfg.stuck_bit_probability = 0.05;
        let mut m = master_on(I2cBus::with_chips(&[0x50], &cfg).unwrap());
        for v in [0x00u8, 0xFF, 0x00, 0xFF] {
            m.page_write(0x50, 0x0000, &[v; 64]).unwrap();
            m.ack_poll(0x50, 1000).unwrap();
        }
        let page = peek(&mut m, 0x50, 0, 64);
        (m.pins().bus().device(0x50).unwrap().stuck_bit_count(), page)
    };
    let (n, page) = run(5);
    assert!(n > 0 && n < 512, "some but not all bits stuck: {n}");
    let zeros: u32 = page.iter().map(|b| b.count_zeros()).sum();
    assert!(
        zeros > 0 && u64::from(zeros) <= n,
        "stuck-at-0 bits show in the 0xFF write"
    );
    assert_eq!(run(5), (n, page), "same seed, same wear");
    assert_ne!(run(6).1, run(5).1);
}

// ---- power -----------------------------------------------------------------------------

#[test]
fn power_cut_during_the_write_cycle_leaves_the_page_undefined_and_others_intact() {
    let mut seen = [false; 4];
    for seed in 0..40 {
        let mut m = robot(seed);
        let old: Vec<u8> = (0..64).map(|i| i as u8).collect();
        let new: Vec<u8> = (0..64).map(|i| 0x80 | (i as u8)).collect();
        {
            let d = m.pins_mut().bus_mut().device_mut(0x50).unwrap();
            d.load(0x0400, &old).unwrap();
            d.load(0x0440, &[0x5A; 64]).unwrap();
            d.load(0x03C0, &[0xA5; 64]).unwrap();
        }
        m.page_write(0x50, 0x0400, &new).unwrap();
        let c = m
            .pins()
            .bus()
            .device(0x50)
            .unwrap()
            .current_write_cycle()
            .unwrap();
        let t = c.start_states + (c.end_states - c.start_states) / 2;
        let out = m.pins_mut().bus_mut().power_cut(t).unwrap();
        assert_eq!(out[0].interrupted_write, Some(c));
        assert_eq!(out[1].interrupted_write, None);
        m.pins_mut().bus_mut().power_on(t + 1000).unwrap();
        let page = peek(&mut m, 0x50, 0x0400, 64);
        for i in 0..64 {
            let (o, n, v) = (old[i], new[i], page[i]);
            // Every bit is the old bit, the new bit, or erased (1): a 0 needs a 0 in old or new.
            assert_eq!(!v & o & n, 0, "0 bit from nowhere at byte {i}");
            if v == o {
                seen[0] = true;
            } else if v == n {
                seen[1] = true;
            } else if v == 0xFF {
                seen[2] = true;
            } else {
                seen[3] = true;
            }
        }
        assert_eq!(peek(&mut m, 0x50, 0x0440, 64), vec![0x5A; 64]);
        assert_eq!(peek(&mut m, 0x50, 0x03C0, 64), vec![0xA5; 64]);
        assert_eq!(writes(&m, 0x50, 16), 1, "the cut cycle counts as a write");
    }
    assert_eq!(seen, [true; 4], "old, new, 0xFF and mixes all occur");
}

#[test]
fn power_cut_outcome_is_seeded() {
    let run = |seed| {
        let mut m = robot(seed);
        m.page_write(0x50, 0, &[0; 64]).unwrap();
        let c = m
            .pins()
            .bus()
            .device(0x50)
            .unwrap()
            .current_write_cycle()
            .unwrap();
        m.pins_mut()
            .bus_mut()
            .power_cut(c.start_states + 1)
            .unwrap();
        m.pins_mut().bus_mut().power_on(c.end_states + 1).unwrap();
        peek(&mut m, 0x50, 0, 64)
    };
    assert_eq!(run(3), run(3));
    assert_ne!(run(3), run(4));
}

#[test]
fn power_cut_at_the_end_of_the_write_cycle_keeps_the_new_data() {
    let mut m = robot(18);
    m.page_write(0x50, 0, &[7; 64]).unwrap();
    let c = m
        .pins()
        .bus()
        .device(0x50)
        .unwrap()
        .current_write_cycle()
        .unwrap();
    let out = m.pins_mut().bus_mut().power_cut(c.end_states).unwrap();
    assert_eq!(out[0].interrupted_write, None, "cycle over at end_states");
    m.pins_mut().bus_mut().power_on(c.end_states + 10).unwrap();
    assert_eq!(peek(&mut m, 0x50, 0, 64), vec![7; 64]);
}

#[test]
fn power_cut_before_the_stop_writes_nothing() {
    let mut m = robot(19);
    // Send a page write but cut the power just before its STOP: send bytes by hand.
    let data = [1u8, 2, 3];
    {
        let p = m.pins_mut();
        p.sda_low();
        p.wait_states(20);
        p.scl_low();
        for b in [0xA0u8, 0x00, 0x00].iter().chain(data.iter()) {
            for i in (0..8).rev() {
                if (b >> i) & 1 == 1 {
                    p.sda_release();
                } else {
                    p.sda_low();
                }
                p.wait_states(50);
                p.scl_release();
                p.wait_states(20);
                p.scl_low();
            }
            p.sda_release();
            p.wait_states(50);
            p.scl_release();
            p.wait_states(20);
            p.scl_low();
        }
        p.sda_low();
        p.wait_states(50);
        p.scl_release();
        p.wait_states(20);
        let t = p.now();
        let out = p.bus_mut().power_cut(t).unwrap();
        assert!(out[0].discarded_transfer);
        assert_eq!(out[0].interrupted_write, None);
        p.bus_mut().power_on(t + 100).unwrap();
    }
    m.init();
    assert_eq!(peek(&mut m, 0x50, 0, 3), [0xFF; 3]);
    assert_eq!(writes(&m, 0x50, 0), 0);
}

#[test]
fn powered_off_chip_does_not_ack_releases_sda_and_refuses_api_reads() {
    let mut m = robot(20);
    m.byte_write(0x51, 0x0010, 0x99).unwrap();
    m.ack_poll(0x51, 1000).unwrap();
    let t = now(&m);
    m.pins_mut().bus_mut().power_off_device(t, 0x51).unwrap();
    let mut b = [0u8; 1];
    assert_eq!(
        m.random_read(0x51, 0x0010, &mut b),
        Err(MasterError::Nack {
            device: 0x51,
            stage: NackStage::Control
        })
    );
    assert!(!m.pins().bus().device(0x51).unwrap().pulls_sda());
    let t = now(&m);
    let mut v = [0u8; 1];
    assert_eq!(
        m.pins_mut()
            .bus_mut()
            .device_mut(0x51)
            .unwrap()
            .read(t, 0x10, &mut v),
        Err(EepromError::PoweredOff { address: 0x51 })
    );
    // Chip 0x50 still works.
    m.random_read(0x50, 0x0010, &mut b).unwrap();
    // Power on again later: data kept, pointer reset to 0.
    let t = now(&m) + 250_000;
    m.pins_mut().bus_mut().power_on_device(t, 0x51).unwrap();
    assert_eq!(m.pins().bus().device(0x51).unwrap().address_pointer(), 0);
    m.random_read(0x51, 0x0010, &mut b).unwrap();
    assert_eq!(b, [0x99]);
}

#[test]
fn power_cut_while_the_chip_drives_sda_releases_the_line() {
    let mut m = robot(21);
    m.pins_mut()
        .bus_mut()
        .device_mut(0x50)
        .unwrap()
        .load(0, &[0x00; 4])
        .unwrap();
    let mut p = m.into_pins();
    // Random read by hand up to the first data bit (0): the chip pulls SDA.
    let mut tmp = I2cMaster::new(&mut p, MasterTiming::fast_mode(CLOCK_HZ).unwrap());
    let mut b = [0u8; 1];
    tmp.random_read(0x50, 0, &mut b).unwrap();
    // Start a current-address read and stop after the ACK clock, leaving the chip driving 0.
    p.sda_low();
    p.wait_states(20);
    p.scl_low();
    for i in (0..8).rev() {
        if (0xA1u8 >> i) & 1 == 1 {
            p.sda_release();
        } else {
            p.sda_low();
        }
        p.wait_states(50);
        p.scl_release();
        p.wait_states(20);
        p.scl_low();
    }
    p.sda_release();
    p.wait_states(50);
    p.scl_release();
    p.wait_states(20);
    p.scl_low();
    p.wait_states(50);
    assert!(!p.sda_is_high(), "chip drives the first data bit (0)");
    // MCU reset without power loss: the bus-clear sequence frees the line.
    let mut fresh = I2cMaster::new(&mut p, MasterTiming::fast_mode(CLOCK_HZ).unwrap());
    let clocks = fresh.bus_clear().unwrap();
    assert!(clocks >= 1);
    assert!(fresh.pins_mut().sda_is_high());
    fresh.random_read(0x50, 0, &mut b).unwrap();
    // Now cut power while the chip drives SDA low: the line is released at once.
    p.sda_low();
    p.wait_states(20);
    p.scl_low();
    for i in (0..8).rev() {
        if (0xA1u8 >> i) & 1 == 1 {
            p.sda_release();
        } else {
            p.sda_low();
        }
        p.wait_states(50);
        p.scl_release();
        p.wait_states(20);
        p.scl_low();
    }
    p.sda_release();
    p.wait_states(50);
    p.scl_release();
    p.wait_states(20);
    p.scl_low();
    p.wait_states(50);
    assert!(!p.sda_is_high());
    let t = p.now();
    p.bus_mut().power_cut(t).unwrap();
    assert!(p.sda_is_high(), "nobody pulls: pull-up wins");
}

// ---- timing and bus --------------------------------------------------------------------

#[test]
fn master_meets_every_datasheet_minimum_in_both_modes_and_with_pin_costs() {
    for (timing, op) in [
        (MasterTiming::fast_mode(25_000_000).unwrap(), 0),
        (MasterTiming::fast_mode(25_000_000).unwrap(), 7),
        (MasterTiming::fast_mode(25_000_000).unwrap(), 40),
        (MasterTiming::standard_mode(25_000_000).unwrap(), 0),
        (MasterTiming::standard_mode(25_000_000).unwrap(), 13),
    ] {
        let mut m = I2cMaster::new(
            SimPins::new(I2cBus::robot(22, CLOCK_HZ).unwrap()).with_op_states(op),
            timing,
        );
        m.init();
        m.page_write(0x50, 0x0000, &[0x00, 0xFF, 0x5A, 0xA5])
            .unwrap();
        m.ack_poll(0x50, 5000).unwrap();
        let mut b = [0u8; 4];
        m.random_read(0x50, 0x0000, &mut b).unwrap();
        assert_eq!(b, [0x00, 0xFF, 0x5A, 0xA5], "op {op}");
        m.current_address_read(0x50, &mut b[..1]).unwrap();
        assert_eq!(
            m.pins().bus().timing_violation_count(),
            0,
            "op {op}: {:?}",
            m.pins().bus().device(0x50).unwrap().timing_violations()
        );
        // The master's own count of elapsed states equals the pins' clock.
        assert_eq!(m.stats().elapsed_states, m.pins().now());
    }
}

#[test]
fn master_timing_at_25_mhz_is_400_khz_class() {
    let t = MasterTiming::fast_mode(25_000_000).unwrap();
    assert_eq!(t.scl_high_states, 15);
    assert_eq!(t.scl_low_states, 48);
    assert!(
        t.scl_low_states + t.scl_high_states >= 63,
        "period >= 2.5 us"
    );
    assert_eq!(t.data_setup_states, 3);
    assert_eq!(t.bus_free_states, 33);
    assert!(matches!(
        MasterTiming::fast_mode(0),
        Err(EepromError::InvalidClock { clock_hz: 0 })
    ));
    let s = MasterTiming::standard_mode(25_000_000).unwrap();
    assert_eq!(s.scl_high_states, 100);
    assert_eq!(s.scl_low_states, 150);
}

#[test]
fn too_fast_master_is_reported_by_the_timing_monitor() {
    let t = MasterTiming {
        scl_high_states: 10, // 400 ns < 600 ns
        ..MasterTiming::fast_mode(CLOCK_HZ).unwrap()
    };
    let mut m = I2cMaster::new(SimPins::new(I2cBus::robot(23, CLOCK_HZ).unwrap()), t);
    m.init();
    let _ = m.byte_write(0x50, 0, 0);
    let v = m.pins().bus().device(0x50).unwrap().timing_violations();
    assert!(
        v.iter()
            .any(|v| v.check == crate::TimingCheck::SclHigh && v.measured_states == 10)
    );
}

#[test]
fn bus_rejects_duplicates_unknown_devices_and_time_going_back() {
    let cfg = DeviceConfig::new(0x50, 1, CLOCK_HZ);
    assert!(matches!(
        I2cBus::with_chips(&[0x50, 0x50], &cfg),
        Err(EepromError::DuplicateDeviceAddress { address: 0x50 })
    ));
    assert!(matches!(
        I2cBus::with_chips(&[0x58], &cfg),
        Err(EepromError::InvalidDeviceAddress { address: 0x58 })
    ));
    let mut bus = I2cBus::robot(1, CLOCK_HZ).unwrap();
    let e = bus.device(0x53).unwrap_err();
    assert!(e.to_string().contains("0x50, 0x51"), "{e}");
    bus.set_master(100, false, true).unwrap();
    assert!(matches!(
        bus.set_master(99, false, false),
        Err(EepromError::TimeWentBackwards { now: 99, last: 100 })
    ));
    assert!(bus.lines(50).is_err());
    assert_eq!(
        bus.lines(100).unwrap(),
        crate::LineLevels {
            scl: true,
            sda: false
        }
    );
    let nine: Vec<u8> = (0x50..=0x57).collect();
    assert!(I2cBus::with_chips(&nine, &cfg).is_ok());
}

// ---- properties --------------------------------------------------------------------------

mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// Writes of any length at any address (wrapping inside their page, the last 64 bytes
        /// winning) read back as a plain model of the datasheet's rules predicts.
        #[test]
        fn writes_and_sequential_reads_match_a_reference_model(
            seed in any::<u64>(),
            writes in proptest::collection::vec((0u16..0x0400, proptest::collection::vec(any::<u8>(), 1..80)), 1..5),
        ) {
            let mut m = robot(seed);
            let mut model = vec![0xFFu8; 0x0400 + 64];
            for (addr, data) in &writes {
                m.write_raw(0x51, *addr, data).unwrap();
                m.ack_poll(0x51, 1000).unwrap();
                let base = usize::from(*addr) & !63;
                for (k, &b) in data.iter().enumerate() {
                    let off = (usize::from(*addr) + k) % 64;
                    model[base + off] = b;
                }
            }
            let mut back = vec![0u8; 0x0400];
            m.random_read(0x51, 0, &mut back).unwrap();
            prop_assert_eq!(&back[..], &model[..0x0400]);
            prop_assert_eq!(m.pins().bus().timing_violation_count(), 0);
        }

        /// Any sequence of pin operations, waits and power cuts: no panic, and a master can
        /// always free the bus and talk to the chips afterwards.
        #[test]
        fn arbitrary_pin_wiggling_never_panics(
            seed in any::<u64>(),
            ops in proptest::collection::vec((0u8..8, 0u64..200), 0..600),
        ) {
            let mut p = SimPins::new(I2cBus::robot(seed, CLOCK_HZ).unwrap());
            for (op, n) in ops {
                match op {
                    0 => p.scl_low(),
                    1 => p.scl_release(),
                    2 => p.sda_low(),
                    3 => p.sda_release(),
                    4 => { let _ = p.sda_is_high(); }
                    5 => p.wait_states(n * 100),
                    6 if n < 5 => {
                        let t = p.now();
                        p.bus_mut().power_cut(t).unwrap();
                        p.bus_mut().power_on(t + n * 1000 + 1).unwrap();
                    }
                    _ => p.wait_states(n),
                }
            }
            prop_assert!(p.error().is_none());
            // Whatever state the chips were left in, wait out any write cycle, clear the bus
            // and use it.
            p.advance(200_000).unwrap();
            let mut m = I2cMaster::new(p, MasterTiming::fast_mode(CLOCK_HZ).unwrap());
            m.bus_clear().unwrap();
            m.byte_write(0x50, 0x0123, 0x77).unwrap();
            m.ack_poll(0x50, 1000).unwrap();
            let mut b = [0u8; 1];
            m.random_read(0x50, 0x0123, &mut b).unwrap();
            prop_assert_eq!(b, [0x77]);
        }
    }
}

// ---- supply current (DS21203 Table 1-1) ------------------------------------------------

#[test]
fn a_page_write_charges_its_clocks_its_write_cycle_and_standby() {
    use crate::datasheet::CHARGE_PER_CLOCK_NC;
    let mut m = robot(31);
    let before = m.pins().bus().device(0x50).unwrap().stats();
    let t0 = now(&m);
    m.page_write(0x50, 0x0040, &[0x5A; PAGE_BYTES]).unwrap();
    let s = m.pins().bus().device(0x50).unwrap().stats();
    let t = now(&m) - t0;
    // Control byte, two address bytes, 64 data bytes: 67 bytes of 9 clocks each.
    assert_eq!(s.clocks() - before.clocks(), 9 * 67);
    assert_eq!(s.write_cycles, 1);
    let (lo, hi) = m.pins().bus().device(0x50).unwrap().t_wc_range_states();
    assert!((lo..=hi).contains(&s.write_cycle_states));
    // By hand: 603 clocks at 1 nC, the drawn T_WC at 3 mA, and 1 µA over the interval; at
    // 25 MHz one state is 40 ns.
    assert!((CHARGE_PER_CLOCK_NC - 1.0).abs() < 1e-12);
    let want = 603.0 * 1e-3 + s.write_cycle_states as f64 * 40e-9 * 3e3 + t as f64 * 40e-9 * 1.0;
    let got = s.charge_since_uc(&before, t, 25_000_000);
    assert!((got - want).abs() < 1e-9, "{got} vs {want}");
    // 4 ms of write cycle is about 12 µC: it dominates the 0.6 µC of the clocks.
    assert!((got - 12.6).abs() < 3.1, "{got}");
}
