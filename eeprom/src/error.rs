//! Errors. Each message says what was wrong, where, and what would be valid.

use thiserror::Error;

/// Errors of the device model, the bus and their configuration.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum EepromError {
    /// φ is zero or above the H8/3052F's maximum.
    #[error("MCU clock of {clock_hz} Hz is invalid: valid is 1 Hz ..= 25 000 000 Hz")]
    InvalidClock {
        /// The clock that was asked for.
        clock_hz: u32,
    },
    /// A 24LC256 bus address outside 0x50–0x57.
    #[error(
        "device address 0x{address:02X} is invalid: a 24LC256 answers only at 0x50..=0x57 (control code 1010, pins A2..A0)"
    )]
    InvalidDeviceAddress {
        /// The address that was asked for.
        address: u8,
    },
    /// Two devices with the same address on one bus.
    #[error("two devices at address 0x{address:02X} on one bus: each needs its own A2..A0 pins")]
    DuplicateDeviceAddress {
        /// The repeated address.
        address: u8,
    },
    /// No device at this address on the bus.
    #[error("no device at address 0x{address:02X} on this bus (present: {present})")]
    NoSuchDevice {
        /// The address asked for.
        address: u8,
        /// The addresses present, formatted.
        present: String,
    },
    /// A memory range that leaves the 32 KB array.
    #[error(
        "memory range 0x{address:04X} + {len} bytes is beyond the 24LC256 array: valid addresses are 0x0000..=0x7FFF"
    )]
    MemoryAddressOutOfRange {
        /// First address of the range.
        address: u32,
        /// Length of the range in bytes.
        len: usize,
    },
    /// A page number beyond the 512 pages.
    #[error("page {page} is beyond the array: valid pages are 0..=511")]
    PageOutOfRange {
        /// The page asked for.
        page: usize,
    },
    /// The chip is powered off.
    #[error(
        "the 24LC256 at 0x{address:02X} is powered off: power it on before reading or writing it"
    )]
    PoweredOff {
        /// The chip's bus address.
        address: u8,
    },
    /// A transaction addressed a chip in its write cycle (it would not acknowledge).
    #[error(
        "the 24LC256 at 0x{address:02X} is in its write cycle: poll it (ACK polling) until it answers"
    )]
    Busy {
        /// The chip's bus address.
        address: u8,
    },
    /// A write cycle time range outside the modelled 3–5 ms, or min > max.
    #[error(
        "write cycle time range {min_ns}..={max_ns} ns is invalid: valid is 3 000 000 <= min <= max <= 5 000 000 ns (DS21203 T_WC <= 5 ms; the design models 3-5 ms)"
    )]
    InvalidWriteCycleTime {
        /// Lower end asked for.
        min_ns: u64,
        /// Upper end asked for.
        max_ns: u64,
    },
    /// An SDA output delay outside 300–900 ns.
    #[error(
        "SDA output delay of {ns} ns is invalid: valid is 300..=900 ns (DS21203 Table 1-2 Note 2 and T_AA)"
    )]
    InvalidOutputDelay {
        /// The delay asked for.
        ns: u64,
    },
    /// The output delay rounds to zero states at this clock.
    #[error(
        "SDA output delay of {ns} ns is shorter than one state at {clock_hz} Hz: use a faster clock"
    )]
    OutputDelayBelowOneState {
        /// The delay asked for.
        ns: u64,
        /// The MCU clock.
        clock_hz: u32,
    },
    /// An endurance limit of zero.
    #[error(
        "endurance limit of {cycles} write cycles is invalid: valid is >= 1 (datasheet: 1 000 000)"
    )]
    InvalidEndurance {
        /// The limit asked for.
        cycles: u32,
    },
    /// A stuck-bit probability outside [0, 1].
    #[error("stuck-bit probability {p} is invalid: valid is 0.0..=1.0 per bit per write cycle")]
    InvalidStuckProbability {
        /// The probability asked for.
        p: f64,
    },
    /// A time earlier than one the bus or device has already seen.
    #[error(
        "time {now} states is before the last time seen, {last} states: time only moves forward"
    )]
    TimeWentBackwards {
        /// The time given.
        now: u64,
        /// The latest time already seen.
        last: u64,
    },
    /// More than eight devices on one bus.
    #[error("{count} devices on one bus: at most 8 (addresses 0x50..=0x57)")]
    TooManyDevices {
        /// Number of devices given.
        count: usize,
    },
}

/// Where in a transfer a device failed to acknowledge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NackStage {
    /// The control byte after START (device absent, powered off or busy in a write cycle).
    Control,
    /// The high address byte.
    AddressHigh,
    /// The low address byte.
    AddressLow,
    /// Data byte number `index` (from 0) of a write.
    Data {
        /// Index of the byte in the data sent.
        index: usize,
    },
    /// The read control byte after the repeated START of a random read.
    ReadControl,
}

impl core::fmt::Display for NackStage {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            NackStage::Control => write!(f, "control byte"),
            NackStage::AddressHigh => write!(f, "high address byte"),
            NackStage::AddressLow => write!(f, "low address byte"),
            NackStage::Data { index } => write!(f, "data byte {index}"),
            NackStage::ReadControl => write!(f, "read control byte after repeated START"),
        }
    }
}

/// Errors of the bit-banging master.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MasterError {
    /// A device address outside 0x50–0x57.
    #[error("device address 0x{address:02X} is invalid: a 24LC256 answers only at 0x50..=0x57")]
    InvalidDeviceAddress {
        /// The address asked for.
        address: u8,
    },
    /// A memory address beyond 0x7FFF.
    #[error("memory address 0x{address:04X} is beyond the 24LC256 array: valid is 0x0000..=0x7FFF")]
    MemoryAddressOutOfRange {
        /// The address asked for.
        address: u32,
    },
    /// A transfer of zero bytes.
    #[error("{operation} of zero bytes: give at least one byte")]
    EmptyTransfer {
        /// The operation asked for.
        operation: &'static str,
    },
    /// A page write that would leave its 64-byte page (the chip would wrap inside the page).
    #[error(
        "page write of {len} bytes at 0x{address:04X} crosses the 64-byte page boundary at 0x{boundary:04X}: the chip would wrap to the page start; split the write at the boundary (at most {room} bytes here)"
    )]
    CrossesPage {
        /// Start address.
        address: u16,
        /// Bytes asked for.
        len: usize,
        /// First address of the next page.
        boundary: u32,
        /// Bytes that fit before the boundary.
        room: usize,
    },
    /// A device did not acknowledge.
    #[error("device 0x{device:02X} did not acknowledge the {stage}")]
    Nack {
        /// The device addressed.
        device: u8,
        /// Where it failed.
        stage: NackStage,
    },
    /// ACK polling gave up.
    #[error(
        "device 0x{device:02X} still busy after {polls} ACK polls (~{waited_states} states): write cycle did not end, or the chip is absent or off"
    )]
    PollTimeout {
        /// The device polled.
        device: u8,
        /// Polls sent.
        polls: u32,
        /// States the polling took, as counted by the master.
        waited_states: u64,
    },
    /// A poll bound of zero.
    #[error("ACK polling bound of 0 tries: give at least 1")]
    InvalidPollBound,
    /// A device keeps SDA low after nine clocks.
    #[error("SDA still held low after {clocks} SCL clocks: bus cannot be freed")]
    BusStuck {
        /// Clocks sent.
        clocks: u32,
    },
    /// A bad timing configuration.
    #[error("master timing: {0}")]
    Config(#[from] EepromError),
}

/// Why a stored record is not valid. Never a panic: garbage in, one of these out.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum RecordError {
    /// Fewer bytes than the part needs.
    #[error("{part} truncated: {got} bytes, need {needed}")]
    Truncated {
        /// Which part ("commit block", "record body").
        part: &'static str,
        /// Bytes needed.
        needed: usize,
        /// Bytes given.
        got: usize,
    },
    /// Commit block does not start with the magic.
    #[error("bad magic {found:02X?} at the commit block: expected {expected:02X?}")]
    BadMagic {
        /// Bytes found.
        found: [u8; 2],
        /// Bytes expected.
        expected: [u8; 2],
    },
    /// Unknown format version.
    #[error("record format version {found}: only version {expected} is known")]
    BadVersion {
        /// Version found.
        found: u8,
        /// Version expected.
        expected: u8,
    },
    /// Reserved byte not zero.
    #[error("reserved byte of the commit block is 0x{found:02X}: must be 0x00")]
    BadReserved {
        /// Value found.
        found: u8,
    },
    /// Payload length larger than the slot holds.
    #[error("payload length {len} bytes exceeds the slot's maximum of {max} bytes")]
    BadLength {
        /// Length found.
        len: u16,
        /// Largest valid length.
        max: u16,
    },
    /// CRC of the commit block wrong.
    #[error("commit block CRC mismatch: stored 0x{stored:04X}, computed 0x{computed:04X}")]
    BadCommitCrc {
        /// CRC stored.
        stored: u16,
        /// CRC computed.
        computed: u16,
    },
    /// CRC of the body wrong.
    #[error("record body CRC mismatch: stored 0x{stored:04X}, computed 0x{computed:04X}")]
    BadBodyCrc {
        /// CRC stored.
        stored: u16,
        /// CRC computed.
        computed: u16,
    },
    /// Commit block and body disagree.
    #[error("commit block and body disagree on the {field}: commit {commit}, body {body}")]
    Mismatch {
        /// Field name.
        field: &'static str,
        /// Value in the commit block.
        commit: u32,
        /// Value in the body.
        body: u32,
    },
    /// A record on the wrong chip for its sequence number's parity.
    #[error(
        "record with sequence {sequence} found on chip 0x{chip:02X}: even sequences live on 0x50, odd on 0x51"
    )]
    WrongChip {
        /// Sequence number found.
        sequence: u32,
        /// Chip it was read from.
        chip: u8,
    },
}

/// Errors of the A/B persistence layer.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PersistError {
    /// A slot start that is not on a 64-byte page boundary.
    #[error("record slot at 0x{slot_addr:04X} is not page-aligned: use a multiple of 64")]
    SlotNotPageAligned {
        /// Address asked for.
        slot_addr: u16,
    },
    /// A slot that does not fit in the 32 KB array.
    #[error(
        "record slot at 0x{slot_addr:04X} for payloads up to {max_payload} bytes needs {slot_bytes} bytes and would end past 0x7FFF: the largest payload there is {largest} bytes"
    )]
    SlotDoesNotFit {
        /// Slot start.
        slot_addr: u16,
        /// Largest payload asked for.
        max_payload: u16,
        /// Bytes the slot would take.
        slot_bytes: usize,
        /// Largest payload that fits at this slot address.
        largest: usize,
    },
    /// A payload larger than the slot.
    #[error("payload of {len} bytes is too large for the record slot: at most {max} bytes")]
    PayloadTooLarge {
        /// Bytes given.
        len: usize,
        /// Largest payload of the layout.
        max: u16,
    },
    /// A poll bound of zero.
    #[error("ACK polling bound of 0 tries: give at least 1")]
    InvalidPollBound,
    /// A save every 0 steps.
    #[error("save period of 0 steps: give at least 1")]
    InvalidSavePeriod,
    /// The bus transfer failed.
    #[error("bus transfer failed: {0}")]
    Master(#[from] MasterError),
}
