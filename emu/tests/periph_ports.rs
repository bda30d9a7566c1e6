//! Ports: write-only DDRs, DR reads (latch for outputs, pins for inputs), bumpers on port 2
//! from the board, and port 4 as the open-drain master of the I²C bus on the robot's board (a
//! START and an address byte acknowledged by a 24LC256), and with nothing on port 4.

use h8_3052f::mcu::{Mcu, McuConfig};
use h8_3052f::periph::ports::{
    DDR_READ_VALUE, P2DDR, P2DR, P2PCR, P4_SCL, P4_SDA, P4DDR, P4DR, P4PCR, PADDR, PADR, PBDDR,
    PBDR,
};
use h8_3052f::pins::{Board, NullBoard};
use h8300h::bus::Bus;
use robot_board::board::{RobotBoard, RobotConfig, robot_mcu};
use robot_board::wiring::{P2_BUMPER_FRONT, P2_BUMPER_LEFT, P2_BUMPERS};
use sensors::{Bumper, BumperSet, port2_pins};

/// A board whose bumpers change with time: front pressed from state 1000, left from 2000.
#[derive(Clone, Debug, Default)]
struct BumperBoard;

impl Board for BumperBoard {
    fn analog_volts(&mut self, _channel: u8, _now_states: u64) -> f64 {
        0.0
    }
    fn port2_pins(&mut self, now_states: u64) -> u8 {
        let mut set = BumperSet::EMPTY;
        if now_states >= 1000 {
            set = set.with(Bumper::Front);
        }
        if now_states >= 2000 {
            set = set.with(Bumper::Left);
        }
        port2_pins(set)
    }
}

#[test]
fn ddrs_are_write_only_and_read_all_ones() {
    let mut m = Mcu::new(McuConfig::default(), NullBoard).unwrap();
    for ddr in [P2DDR, P4DDR, PADDR, PBDDR] {
        assert_eq!(m.read8(ddr), DDR_READ_VALUE);
        m.write8(ddr, 0x5A);
        assert_eq!(
            m.read8(ddr),
            0xFF,
            "DDR at H'{ddr:06X} reads H'FF whatever was written"
        );
    }
    // The written direction still acts: output bits read back the latch.
    m.write8(PADR, 0xA5);
    assert_eq!(m.read8(PADR), 0xA5 & 0x5A);
    m.write8(PBDR, 0xFF);
    assert_eq!(m.read8(PBDR), 0x5A);
}

#[test]
fn port2_reads_the_bumpers_through_the_pull_ups() {
    let mut m = Mcu::new(McuConfig::default(), BumperBoard).unwrap();
    m.write8(P2PCR, P2_BUMPERS);
    assert_eq!(m.read8(P2PCR), P2_BUMPERS);
    // Nothing pressed: bumper bits high through the pull-ups, P2.4–7 float (pull-up off).
    assert_eq!(m.read8(P2DR), P2_BUMPERS);
    m.internal(1000);
    assert_eq!(m.read8(P2DR), P2_BUMPERS & !P2_BUMPER_FRONT);
    m.internal(1000);
    assert_eq!(
        m.read8(P2DR),
        P2_BUMPERS & !(P2_BUMPER_FRONT | P2_BUMPER_LEFT)
    );
    // With every pull-up on, the unconnected pins read high too: exactly sensors::port2_pins.
    m.write8(P2PCR, 0xFF);
    let both = port2_pins(BumperSet::EMPTY.with(Bumper::Front).with(Bumper::Left));
    assert_eq!(m.read8(P2DR), both);
    // Without pull-ups a released switch floats and reads 0, like a pressed one.
    m.write8(P2PCR, 0x00);
    assert_eq!(m.read8(P2DR), 0x00);
    // Output bits read their latch (and their pull-up is off).
    m.write8(P2PCR, 0xFF);
    m.write8(P2DDR, 0xF0);
    m.write8(P2DR, 0xA0);
    assert_eq!(m.read8(P2DR), 0xA0 | (both & 0x0F));
}

/// Bit-banging through the MCU's port 4 exactly as firmware would (DDR = 1 pulls low).
struct Master<B: Board> {
    m: Mcu<B>,
    ddr: u8,
}

/// States between pin changes: 4 µs at 25 MHz, well above every 24LC256 minimum.
const HALF_BIT: u32 = 100;

/// An MCU on the robot's board (its EEPROMs on port 4), nothing else connected.
fn robot() -> Mcu<RobotBoard<NullBoard>> {
    robot_mcu(NullBoard, &RobotConfig::default()).unwrap()
}

impl Master<RobotBoard<NullBoard>> {
    fn new() -> Self {
        Self::on(robot())
    }
}

impl<B: Board> Master<B> {
    fn on(mut m: Mcu<B>) -> Self {
        m.write8(P4PCR, P4_SDA | P4_SCL);
        m.write8(P4DR, 0x00);
        m.write8(P4DDR, 0x00);
        Master { m, ddr: 0 }
    }
    fn set(&mut self, scl_low: bool, sda_low: bool) {
        self.ddr = (if scl_low { P4_SCL } else { 0 }) | (if sda_low { P4_SDA } else { 0 });
        self.m.write8(P4DDR, self.ddr);
        self.m.internal(HALF_BIT);
    }
    fn sda(&mut self) -> bool {
        self.m.read8(P4DR) & P4_SDA != 0
    }
    fn start(&mut self) {
        self.set(false, false);
        self.set(false, true); // SDA falls while SCL is high
        self.set(true, true);
    }
    /// Sends a byte MSB first; returns whether the slave acknowledged.
    fn byte(&mut self, b: u8) -> bool {
        for i in (0..8).rev() {
            let low = b & (1 << i) == 0;
            self.set(true, low);
            self.set(false, low);
            self.set(true, low);
        }
        self.set(true, false);
        self.set(false, false);
        let ack = !self.sda();
        self.set(true, false);
        ack
    }
}

#[test]
fn port4_bit_banging_reaches_a_24lc256_which_acknowledges_its_address() {
    let mut bus = Master::new();
    let edges0 = bus.m.board().eeproms().edges();
    bus.start();
    // The START reached the bus at the instant of the write.
    let e = bus.m.board().eeproms().edges().since(&edges0);
    assert_eq!((e.sda_falling, e.scl_falling), (1, 1));
    assert!(bus.m.board().eeproms().now() <= bus.m.now());
    // Control byte 1010 000 0: write to the chip at 0x50; it pulls SDA low on the 9th clock.
    assert!(bus.byte(0xA0), "chip 0x50 acknowledges after a START");
    assert_eq!(bus.m.board().eeproms().timing_violation_count(), 0);
}

#[test]
fn with_nothing_on_port_4_the_master_reads_its_own_lines_and_gets_no_ack() {
    let mut bus = Master::on(Mcu::new(McuConfig::default(), NullBoard).unwrap());
    bus.start();
    assert!(!bus.sda(), "the master's own pull on SDA reads back low");
    assert!(
        !bus.byte(0xA0),
        "no chip on the lines: SDA stays high on the 9th clock"
    );
    bus.set(false, false);
    assert!(bus.sda(), "released: high through the pull-up");
}

#[test]
fn without_a_start_nobody_acknowledges() {
    let mut bus = Master::new();
    bus.set(false, false);
    bus.set(true, false);
    assert!(!bus.byte(0xA0), "no START: the chips ignore the byte");
    // An address nobody has: no ACK either, even after a START.
    let mut bus = Master::new();
    bus.start();
    assert!(!bus.byte(0xAE), "no chip at 0x57");
}

#[test]
fn released_i2c_lines_need_the_pull_ups_to_read_high() {
    let mut m = robot();
    // Pull-ups off: released lines float and read 0.
    assert_eq!(m.read8(P4DR) & (P4_SDA | P4_SCL), 0);
    m.write8(P4PCR, P4_SDA | P4_SCL);
    assert_eq!(m.read8(P4DR) & (P4_SDA | P4_SCL), P4_SDA | P4_SCL);
    // Pulling SDA low: the line reads low; with DDR = 1 the DR read returns the latch (0).
    m.write8(P4DDR, P4_SDA);
    assert_eq!(m.board().eeproms().master_pulls(), (false, true));
    assert_eq!(m.read8(P4DR) & (P4_SDA | P4_SCL), P4_SCL);
    // A 1 in DR with DDR = 1 does not pull the line.
    m.write8(P4DR, P4_SDA);
    assert_eq!(m.board().eeproms().master_pulls(), (false, false));
}

#[test]
fn power_cut_releases_the_lines_and_forgets_ram() {
    let mut m = robot();
    m.write8(P4DDR, P4_SDA | P4_SCL);
    m.write16(0xFF_E000, 0xBEEF);
    assert_eq!(m.board().eeproms().master_pulls(), (true, true));
    assert!(m.board().last_power_cut().is_empty());
    m.power_cut();
    assert_eq!(m.board().last_power_cut().len(), 2);
    assert_eq!(m.board().eeproms().master_pulls(), (false, false));
    assert!(!m.has_ram());
    assert_eq!(m.read16(0xFF_E000), 0);
    let t = m.now() + 1_000_000;
    m.power_on(t);
    assert_eq!(m.now(), t);
    assert!(
        m.board()
            .eeproms()
            .devices()
            .iter()
            .all(eeprom::Eeprom24lc256::is_powered)
    );
}
