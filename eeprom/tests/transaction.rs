//! The transaction-level write is the pin-level page write without the edges: same memory,
//! same write counter, same seeded write-cycle time, same chip statistics but for the edges.

use eeprom::{I2cBus, I2cMaster, MasterTiming, SimPins};

/// The MCU's φ these tests count in: the robot's 25 MHz (the crate has no clock of its own).
const CLOCK_HZ: u32 = 25_000_000;

fn data(n: usize, salt: u8) -> Vec<u8> {
    (0..n).map(|i| (i as u8).wrapping_mul(37) ^ salt).collect()
}

#[test]
fn transaction_writes_match_pin_level_page_writes() {
    let timing = MasterTiming::fast_mode(25_000_000).expect("timing");
    let mut pins = SimPins::new(I2cBus::robot(42, CLOCK_HZ).expect("bus"));
    let mut fast = I2cBus::robot(42, CLOCK_HZ).expect("bus");
    // A mix of pages, offsets that wrap inside the page, both chips, repeated pages.
    let writes: [(u8, u16, usize); 7] = [
        (0x50, 0x0000, 64),
        (0x51, 0x0040, 30),
        (0x50, 0x0030, 40),
        (0x50, 0x7FC0, 64),
        (0x51, 0x0041, 1),
        (0x50, 0x0000, 64),
        (0x51, 0x1234, 12),
    ];
    for (k, &(dev, addr, n)) in writes.iter().enumerate() {
        let bytes = data(n, k as u8);
        {
            let mut master = I2cMaster::new(&mut pins, timing);
            master
                .write_raw(dev, addr, &bytes)
                .expect("pin-level write");
            master.ack_poll(dev, 10_000).expect("ready again");
        }
        let slow = pins.bus().device(dev).expect("chip");
        let cycle = slow
            .last_completed_write_cycle()
            .expect("a write cycle ran");
        let end = fast
            .write_transaction(cycle.start_states, dev, addr, &bytes)
            .expect("transaction");
        assert_eq!(end, cycle.end_states, "write {k}: the same seeded t_WC");
        let f = fast.device(dev).expect("chip");
        assert_eq!(
            f.current_write_cycle().map(|c| (c.page, c.bytes)),
            Some((cycle.page, cycle.bytes))
        );
        assert_eq!(
            f.address_pointer(),
            slow.address_pointer(),
            "write {k}: pointer"
        );
    }
    let now = pins.now() + 200_000;
    pins.bus_mut().advance_to(now).expect("advance");
    fast.advance_to(now).expect("advance");
    for dev in [0x50, 0x51] {
        let (mut a, mut b) = (vec![0u8; 32 * 1024], vec![0u8; 32 * 1024]);
        pins.bus_mut()
            .device_mut(dev)
            .expect("chip")
            .read(now, 0, &mut a)
            .expect("read");
        fast.device_mut(dev)
            .expect("chip")
            .read(now, 0, &mut b)
            .expect("read");
        assert!(a == b, "chip 0x{dev:02X}: memory differs");
        let (sa, sb) = (
            pins.bus().device(dev).expect("chip"),
            fast.device(dev).expect("chip"),
        );
        assert_eq!(sa.write_counts(), sb.write_counts());
        assert_eq!(sa.stats().write_cycles, sb.stats().write_cycles);
        assert_eq!(sa.stats().bytes_received, sb.stats().bytes_received);
    }
    assert_eq!(fast.edges().total(), 0, "no edges at transaction level");
}

#[test]
fn transactions_refuse_busy_and_unpowered_chips() {
    let mut bus = I2cBus::robot(1, CLOCK_HZ).expect("bus");
    let end = bus
        .write_transaction(1000, 0x50, 0, &[1, 2, 3])
        .expect("write");
    assert!(end > 1000 + 3 * 25_000 - 1, "a 3-5 ms write cycle");
    assert_eq!(bus.busy_until(2000, 0x50).expect("chip"), Some(end));
    let e = bus.write_transaction(2000, 0x50, 64, &[4]).unwrap_err();
    assert!(e.to_string().contains("write cycle"), "{e}");
    assert_eq!(bus.busy_until(end, 0x50).expect("chip"), None);
    bus.power_cut(end + 10).expect("cut");
    assert!(bus.write_transaction(end + 20, 0x51, 0, &[1]).is_err());
    assert!(
        bus.write_transaction(end + 20, 0x57, 0, &[1]).is_err(),
        "no such chip"
    );
}
