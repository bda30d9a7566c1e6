//! The robot's two Microchip 24LC256 serial EEPROMs at pin level, the bit-banged I²C bus they
//! sit on, the master the H8 firmware runs, and the persistence record that survives power
//! cuts (docs/design.md §3.6).
//!
//! # Layers
//! - [`Eeprom24lc256`]: one chip. It watches SDA/SCL levels over time (time in MCU states of
//!   φ, default 25 MHz) and implements START, STOP, repeated START, the control byte
//!   `1010 A2 A1 A0 R/W`, ACK/NACK (it pulls SDA low during the 9th clock), byte write, page
//!   write with wrap inside the 64-byte page, current address / random / sequential read
//!   (rolling over 0x7FFF → 0x0000), the internally timed write cycle after STOP (no ACK to
//!   its control byte while busy), a write counter per page, endurance and stuck bits, power
//!   cuts and the powered-off state.
//! - [`I2cBus`]: open-drain wired-AND SDA and SCL with pull-ups, the master and several chips
//!   (0x50 and 0x51 on the robot). It counts line transitions ([`EdgeCounts`]).
//! - [`I2cMaster`]: the bit-banging master over a small [`I2cPins`] trait: the exact pin
//!   sequence the firmware uses (documented in [`master`]). [`SimPins`] drives a bus directly
//!   with a local clock so the chips can be tested alone; the emulated H8 provides its own
//!   pins on port 4 (SDA = P4.7, SCL = P4.6) whose calls cost emulated states.
//! - [`persist`]: the record codec (sequence number, opaque payload, CRC-16/CCITT-FALSE), the
//!   A/B policy (even sequences on 0x50, odd on 0x51), boot-time recovery and the save policy.
//!
//! # Modelling choices (where the datasheet or the design is silent)
//! - **Ideal lines.** Edges are instantaneous; rise/fall times (T_R, T_F ≤ 300 ns) and spike
//!   suppression (T_SP) are not modelled. On the real board the H8's on-chip MOS pull-ups are
//!   weak, so real rise times would be far longer than the datasheet's 300 ns; the 100 kHz
//!   timing ([`MasterTiming::standard_mode`]) is there for that case.
//! - **Device output delay.** The chip changes SDA `floor(output_delay_ns · φ)` states after
//!   SCL falls; default 900 ns = T_AA max (worst case), configurable 300–900 ns (Note 2 of
//!   Table 1-2 gives the 300 ns minimum). A master that samples too early reads stale data.
//! - **Timing monitor.** Each chip checks the master against T_HIGH, T_LOW, F_CLK, T_SU:DAT,
//!   T_HD:STA, T_SU:STA, T_SU:STO and T_BUF and counts violations; it does not misbehave on
//!   them. The master here produces none (tested).
//! - **Write cycle time.** Drawn per write cycle, uniformly in whole states over
//!   `[t_wc_min_ns, t_wc_max_ns]` (default 3–5 ms, the design's model; 5 ms is the datasheet
//!   maximum), from the chip's own seeded stream. The cycle starts at the STOP; at state
//!   `start + t_wc` the page holds the new data and the chip answers again.
//! - **What a STOP writes.** Only whole data bytes the chip acknowledged; a partial byte before
//!   the STOP is dropped. A repeated START instead of a STOP drops the loaded bytes (that is how
//!   a random read sets the address without writing). An address-only write sets the pointer.
//! - **Write counter.** Counted per page at the STOP that starts a cycle, whether or not the
//!   cycle completes (a cut cycle has stressed the cells too).
//! - **Endurance.** Once a page has had more than `endurance_cycles` write cycles (default
//!   1 000 000, characterised not guaranteed), each further cycle makes each of its 512 bits
//!   stick, independently, with probability `stuck_bit_probability` (default 1/1024, not a
//!   datasheet figure). A stuck bit keeps the value it had when it stuck, through later writes
//!   and cuts. Seeded stream per chip.
//! - **Power cut during a write cycle.** Every byte of the page being written becomes, with
//!   equal odds, the old byte, the new byte, 0xFF (erased), or a mix where each bit is the old
//!   bit, the new bit or 1. Bytes of the page not in the transfer count "new" = old. Other
//!   pages are untouched. A cut before the STOP writes nothing. Seeded stream per chip.
//! - **Powered off.** No ACK, SDA released, all clocks ignored; back-door reads and loads
//!   return [`EepromError::PoweredOff`]. Power-on: standby, address pointer 0.
//! - **Simultaneous changes.** When one bus call changes both lines, the chips see SCL first.
//!
//! # Example
//!
//! ```
//! use eeprom::{I2cBus, I2cMaster, MasterTiming, Persistence, Record, SimPins};
//!
//! // The robot's bus (chips at 0x50 and 0x51) driven by the bit-banging master, every time
//! // counted in the MCU's φ (the robot's is 25 MHz; the crate has no clock of its own).
//! let clock_hz = 25_000_000;
//! let bus = I2cBus::robot(1, clock_hz)?;
//! let mut master = I2cMaster::new(SimPins::new(bus), MasterTiming::fast_mode(clock_hz)?);
//! master.init();
//! let store = Persistence::default();
//! let boot = store.recover(&mut master);
//! assert!(boot.newest.is_none()); // blank chips: start from fresh random weights
//! let record = Record { sequence: boot.next_sequence(), payload: vec![0x12; 104] };
//! let report = store.save(&mut master, &record)?;
//! assert_eq!((report.chip, report.pages_written), (0x50, 3));
//! println!("{} bus edges", master.pins().edges().total());
//! assert_eq!(store.recover(&mut master).newest, Some(record));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Randomness: each chip has three ChaCha8 streams (write-cycle time, cut corruption, wear),
//! seeded by the project's one derivation from the chip's seed, its address and the purpose
//! (`seeding::derive`); the same seeds give the same results, and no global RNG is used.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod bus;
mod cells;
pub mod clock;
pub mod crc;
pub mod datasheet;
#[cfg(test)]
mod datasheet_tests;
pub mod device;
pub mod error;
pub mod master;
pub mod persist;
pub mod sim;

pub use bus::{EdgeCounts, I2cBus, LineLevels};
pub use clock::Clock;
pub use crc::{crc16_ccitt_false, crc16_update, crc16_update_counting};
pub use device::{
    DeviceConfig, DeviceStats, Eeprom24lc256, PowerCutOutcome, TimingCheck, TimingViolation,
    WriteCycleInfo,
};
pub use error::{EepromError, MasterError, NackStage, PersistError, RecordError};
pub use master::{I2cMaster, I2cPins, MasterStats, MasterTiming};
pub use persist::{
    CHIP_A, CHIP_B, ChipReading, Persistence, Record, RecordLayout, Recovery, SavePolicy,
    SaveReport,
};
pub use sim::SimPins;
