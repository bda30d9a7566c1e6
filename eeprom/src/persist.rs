//! The persistence record codec and the A/B policy across the two chips.
//!
//! # Where a record sits
//!
//! Each chip holds one record slot at a page-aligned address (default 0x0000):
//!
//! ```text
//! slot + 0x00  commit page  (one 64-byte page; 14 bytes used)
//!              0  'H' 'K'   magic
//!              2  version   = 1
//!              3  reserved  = 0
//!              4  sequence  u32, big-endian (the H8 is big-endian)
//!              8  length    u16, payload bytes
//!             10  body CRC  u16, CRC-16/CCITT-FALSE of the body's first 6 + length bytes
//!             12  commit CRC u16, CRC-16/CCITT-FALSE of bytes 0..12
//! slot + 0x40  body, from the next page on: ceil((8 + length) / 64) pages
//!              0  sequence  u32      4  length u16      6  payload (length bytes)
//!              6 + length   CRC u16 of the 6 + length bytes before it
//! ```
//!
//! A save writes the body pages in address order, each followed by ACK polling until its write
//! cycle is over, and the commit page last. Record `n` goes to chip 0x50 when `n` is even and
//! 0x51 when odd, so a save only ever overwrites the record before the last one.
//!
//! # Why a cut at any instant leaves the last committed record readable
//!
//! A power cut spoils at most the page whose write cycle it interrupts (DS21203 gives no
//! guarantee for it; the model makes every byte of it old, new, 0xFF or a mix). During save
//! `n` on chip X, chip Y holds record `n − 1` untouched. On chip X a record is accepted only if
//! the commit block is sane (magic, version, CRC), the body's sequence and length equal the
//! commit's, the body CRC matches and equals the commit's copy, and the sequence's parity
//! matches the chip. While body pages are being written the commit page still says `n − 2`
//! (older than `n − 1`, so never preferred) or was never valid; the commit page is written only
//! after every body page is complete, so if it reads back as a valid commit for `n` the body
//! *is* record `n`. A garbled commit page can only pass its CRC and all cross-checks by
//! describing exactly the body in place. Recovery therefore returns `n − 1` or `n`, never a
//! mixture — without relying on a lucky CRC.

use crate::crc::crc16_ccitt_false;
use crate::datasheet::{ARRAY_BYTES, PAGE_BYTES};
use crate::error::{MasterError, PersistError, RecordError};
use crate::master::{I2cMaster, I2cPins};

/// Chip A of the A/B pair: even sequence numbers (A2..A0 = 000).
pub const CHIP_A: u8 = 0x50;
/// Chip B of the A/B pair: odd sequence numbers (A2..A0 = 001).
pub const CHIP_B: u8 = 0x51;
/// Magic at the start of a commit block: "HK" (Hartono–Kakita).
pub const RECORD_MAGIC: [u8; 2] = *b"HK";
/// Record format version.
pub const RECORD_VERSION: u8 = 1;
/// Bytes of a commit block.
pub const COMMIT_BYTES: usize = 14;
/// Bytes of the body before the payload: sequence (4) and length (2).
pub const BODY_HEADER_BYTES: usize = 6;
/// Bytes of a body that are not payload: header and CRC.
pub const BODY_OVERHEAD_BYTES: usize = BODY_HEADER_BYTES + 2;
/// Default bound on ACK polls after each page: 1 000 polls of ~26 µs each at 400 kHz and
/// 25 MHz, about five times the datasheet's 5 ms T_WC.
pub const DEFAULT_MAX_POLLS: u32 = 1_000;
/// Default save policy: one record every 20 steps (docs/design.md §3.6).
pub const DEFAULT_SAVE_EVERY_STEPS: u32 = 20;

/// The chip a record with sequence number `sequence` is written to.
#[must_use]
pub fn chip_for_sequence(sequence: u32) -> u8 {
    if sequence & 1 == 0 { CHIP_A } else { CHIP_B }
}

/// Whether sequence `a` is newer than `b` in serial-number arithmetic (RFC 1982 style), so a
/// counter that wraps after 2^32 saves (≈ 1 200 years at one save per 9 s) still compares right.
#[must_use]
pub fn is_newer(a: u32, b: u32) -> bool {
    a != b && a.wrapping_sub(b) < 0x8000_0000
}

/// A persisted network state.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Record {
    /// Sequence number: one more with every save.
    pub sequence: u32,
    /// The network state, opaque bytes.
    pub payload: Vec<u8>,
}

/// The commit block that makes a body valid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Commit {
    /// Sequence number of the record.
    pub sequence: u32,
    /// Payload bytes.
    pub payload_len: u16,
    /// CRC of the body (as stored at its end).
    pub body_crc: u16,
}

impl Commit {
    /// The 14 bytes of the block.
    #[must_use]
    pub fn encode(&self) -> [u8; COMMIT_BYTES] {
        let mut b = [0u8; COMMIT_BYTES];
        b[0..2].copy_from_slice(&RECORD_MAGIC);
        b[2] = RECORD_VERSION;
        b[3] = 0;
        b[4..8].copy_from_slice(&self.sequence.to_be_bytes());
        b[8..10].copy_from_slice(&self.payload_len.to_be_bytes());
        b[10..12].copy_from_slice(&self.body_crc.to_be_bytes());
        let crc = crc16_ccitt_false(&b[0..12]);
        b[12..14].copy_from_slice(&crc.to_be_bytes());
        b
    }

    /// Parses and checks a commit block (magic, version, reserved byte, CRC, length ≤
    /// `max_payload`).
    ///
    /// # Errors
    /// The first check that fails, as a [`RecordError`].
    pub fn decode(bytes: &[u8], max_payload: u16) -> Result<Commit, RecordError> {
        let Some(b) = bytes.get(..COMMIT_BYTES) else {
            return Err(RecordError::Truncated {
                part: "commit block",
                needed: COMMIT_BYTES,
                got: bytes.len(),
            });
        };
        let stored = u16::from_be_bytes([b[12], b[13]]);
        let computed = crc16_ccitt_false(&b[0..12]);
        if b[0..2] != RECORD_MAGIC {
            return Err(RecordError::BadMagic {
                found: [b[0], b[1]],
                expected: RECORD_MAGIC,
            });
        }
        if stored != computed {
            return Err(RecordError::BadCommitCrc { stored, computed });
        }
        if b[2] != RECORD_VERSION {
            return Err(RecordError::BadVersion {
                found: b[2],
                expected: RECORD_VERSION,
            });
        }
        if b[3] != 0 {
            return Err(RecordError::BadReserved { found: b[3] });
        }
        let payload_len = u16::from_be_bytes([b[8], b[9]]);
        if payload_len > max_payload {
            return Err(RecordError::BadLength {
                len: payload_len,
                max: max_payload,
            });
        }
        Ok(Commit {
            sequence: u32::from_be_bytes([b[4], b[5], b[6], b[7]]),
            payload_len,
            body_crc: u16::from_be_bytes([b[10], b[11]]),
        })
    }
}

/// The body bytes of a record and its commit block. The caller checks the payload fits in a
/// `u16` length (see [`RecordLayout::encode`]).
fn encode_body(sequence: u32, payload: &[u8], len: u16) -> (Vec<u8>, Commit) {
    let mut body = Vec::with_capacity(payload.len() + BODY_OVERHEAD_BYTES);
    body.extend_from_slice(&sequence.to_be_bytes());
    body.extend_from_slice(&len.to_be_bytes());
    body.extend_from_slice(payload);
    let crc = crc16_ccitt_false(&body);
    body.extend_from_slice(&crc.to_be_bytes());
    (
        body,
        Commit {
            sequence,
            payload_len: len,
            body_crc: crc,
        },
    )
}

/// Parses and checks a body against its commit block.
///
/// # Errors
/// Truncated body, CRC mismatch, or disagreement with the commit.
pub fn decode_body(commit: &Commit, bytes: &[u8]) -> Result<Record, RecordError> {
    let n = usize::from(commit.payload_len);
    let needed = n + BODY_OVERHEAD_BYTES;
    let Some(b) = bytes.get(..needed) else {
        return Err(RecordError::Truncated {
            part: "record body",
            needed,
            got: bytes.len(),
        });
    };
    let stored = u16::from_be_bytes([b[needed - 2], b[needed - 1]]);
    let computed = crc16_ccitt_false(&b[..needed - 2]);
    if stored != computed {
        return Err(RecordError::BadBodyCrc { stored, computed });
    }
    let sequence = u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    if sequence != commit.sequence {
        return Err(RecordError::Mismatch {
            field: "sequence",
            commit: commit.sequence,
            body: sequence,
        });
    }
    let len = u16::from_be_bytes([b[4], b[5]]);
    if len != commit.payload_len {
        return Err(RecordError::Mismatch {
            field: "payload length",
            commit: u32::from(commit.payload_len),
            body: u32::from(len),
        });
    }
    if stored != commit.body_crc {
        return Err(RecordError::Mismatch {
            field: "body CRC",
            commit: u32::from(commit.body_crc),
            body: u32::from(stored),
        });
    }
    Ok(Record {
        sequence,
        payload: b[BODY_HEADER_BYTES..needed - 2].to_vec(),
    })
}

/// Where the record slot sits on each chip and the largest payload it holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RecordLayout {
    slot_addr: u16,
    max_payload_bytes: u16,
}

impl Default for RecordLayout {
    /// Slot at 0x0000, payloads up to what fills the chip (32 696 bytes).
    fn default() -> Self {
        RecordLayout {
            slot_addr: 0,
            max_payload_bytes: u16::try_from(ARRAY_BYTES - PAGE_BYTES - BODY_OVERHEAD_BYTES)
                .unwrap_or(u16::MAX),
        }
    }
}

fn body_pages_for(payload_len: usize) -> usize {
    (payload_len + BODY_OVERHEAD_BYTES).div_ceil(PAGE_BYTES)
}

impl RecordLayout {
    /// A slot at `slot_addr` (page-aligned) for payloads up to `max_payload_bytes`.
    ///
    /// # Errors
    /// A slot not on a page boundary, or one that would run past 0x7FFF.
    pub fn new(slot_addr: u16, max_payload_bytes: u16) -> Result<RecordLayout, PersistError> {
        if usize::from(slot_addr) % PAGE_BYTES != 0 {
            return Err(PersistError::SlotNotPageAligned { slot_addr });
        }
        let slot_bytes = PAGE_BYTES * (1 + body_pages_for(usize::from(max_payload_bytes)));
        if usize::from(slot_addr) + slot_bytes > ARRAY_BYTES {
            let room = ARRAY_BYTES.saturating_sub(usize::from(slot_addr) + PAGE_BYTES);
            return Err(PersistError::SlotDoesNotFit {
                slot_addr,
                max_payload: max_payload_bytes,
                slot_bytes,
                largest: room.saturating_sub(BODY_OVERHEAD_BYTES),
            });
        }
        Ok(RecordLayout {
            slot_addr,
            max_payload_bytes,
        })
    }

    /// First address of the slot (the commit page).
    #[must_use]
    pub fn slot_addr(&self) -> u16 {
        self.slot_addr
    }

    /// Address of the body (the page after the commit page).
    #[must_use]
    pub fn body_addr(&self) -> u16 {
        self.slot_addr + PAGE_BYTES as u16
    }

    /// Largest payload the slot holds.
    #[must_use]
    pub fn max_payload_bytes(&self) -> u16 {
        self.max_payload_bytes
    }

    /// Pages a record with `payload_len` bytes of payload spans: the commit page plus
    /// `ceil((8 + payload_len) / 64)` body pages. Each save writes each of them once.
    #[must_use]
    pub fn pages_per_record(&self, payload_len: usize) -> usize {
        1 + body_pages_for(payload_len)
    }

    /// Page numbers (0..=511) a record with `payload_len` bytes of payload occupies on its chip.
    #[must_use]
    pub fn pages_of_record(&self, payload_len: usize) -> std::ops::Range<usize> {
        let first = usize::from(self.slot_addr) / PAGE_BYTES;
        first..first + self.pages_per_record(payload_len)
    }

    /// Pages reserved by the slot (for the largest payload).
    #[must_use]
    pub fn slot_pages(&self) -> usize {
        self.pages_per_record(usize::from(self.max_payload_bytes))
    }

    /// Bytes of one saved record (commit block + body) for `payload_len`.
    #[must_use]
    pub fn bytes_per_save(&self, payload_len: usize) -> usize {
        COMMIT_BYTES + payload_len + BODY_OVERHEAD_BYTES
    }

    /// The commit block and body bytes of `record`.
    ///
    /// # Errors
    /// [`PersistError::PayloadTooLarge`] beyond the slot.
    pub fn encode(&self, record: &Record) -> Result<([u8; COMMIT_BYTES], Vec<u8>), PersistError> {
        let len = u16::try_from(record.payload.len())
            .ok()
            .filter(|&l| l <= self.max_payload_bytes)
            .ok_or(PersistError::PayloadTooLarge {
                len: record.payload.len(),
                max: self.max_payload_bytes,
            })?;
        let (body, commit) = encode_body(record.sequence, &record.payload, len);
        Ok((commit.encode(), body))
    }

    /// Decodes a record from an image of the slot as read from `chip` (bytes from the slot's
    /// first address on: the commit page, then the body). Malformed input gives an error,
    /// never a panic.
    ///
    /// # Errors
    /// Any [`RecordError`]: truncated, bad magic/version/CRC/length, commit and body
    /// disagreeing, or a sequence whose parity does not match `chip`.
    pub fn decode_slot(&self, chip: u8, image: &[u8]) -> Result<Record, RecordError> {
        let commit = Commit::decode(image, self.max_payload_bytes)?;
        let body = image.get(PAGE_BYTES..).unwrap_or(&[]);
        if body.is_empty() {
            return Err(RecordError::Truncated {
                part: "record body",
                needed: usize::from(commit.payload_len) + BODY_OVERHEAD_BYTES,
                got: 0,
            });
        }
        let record = decode_body(&commit, body)?;
        check_chip(chip, record.sequence)?;
        Ok(record)
    }
}

fn check_chip(chip: u8, sequence: u32) -> Result<(), RecordError> {
    if chip_for_sequence(sequence) == chip {
        Ok(())
    } else {
        Err(RecordError::WrongChip { sequence, chip })
    }
}

/// What one save did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SaveReport {
    /// The chip written.
    pub chip: u8,
    /// Sequence number saved.
    pub sequence: u32,
    /// Pages written (body pages, then the commit page).
    pub pages_written: usize,
    /// ACK polls after each page, in write order.
    pub polls_per_page: Vec<u32>,
    /// Record bytes sent (commit block + body).
    pub record_bytes: usize,
}

/// What recovery found on one chip.
#[derive(Clone, Debug, PartialEq)]
pub enum ChipReading {
    /// A valid record with this sequence number.
    Valid {
        /// Its sequence number.
        sequence: u32,
    },
    /// The chip answered but holds no valid record.
    Invalid(RecordError),
    /// The chip did not answer (absent, off, or the bus failed).
    NoResponse(MasterError),
    /// A sane commit block for this sequence, but the other chip holds a newer valid record,
    /// so the body was not read.
    Superseded {
        /// Sequence number in the commit block.
        sequence: u32,
    },
}

/// The outcome of recovery at boot.
#[derive(Clone, Debug, PartialEq)]
pub struct Recovery {
    /// The newest valid record, or `None`: the firmware then starts from fresh random weights.
    pub newest: Option<Record>,
    /// What each chip held: `[chip 0x50, chip 0x51]`.
    pub chips: [ChipReading; 2],
}

impl Recovery {
    /// The sequence number the next save should use: one past the newest, or 0.
    #[must_use]
    pub fn next_sequence(&self) -> u32 {
        self.newest
            .as_ref()
            .map_or(0, |r| r.sequence.wrapping_add(1))
    }
}

/// Saves and recovers records on the A/B pair through a master.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Persistence {
    layout: RecordLayout,
    max_polls: u32,
}

impl Default for Persistence {
    fn default() -> Self {
        Persistence {
            layout: RecordLayout::default(),
            max_polls: DEFAULT_MAX_POLLS,
        }
    }
}

impl Persistence {
    /// Persistence with `layout`, polling each page's write cycle at most `max_polls` times.
    ///
    /// # Errors
    /// [`PersistError::InvalidPollBound`] for zero polls.
    pub fn new(layout: RecordLayout, max_polls: u32) -> Result<Persistence, PersistError> {
        if max_polls == 0 {
            return Err(PersistError::InvalidPollBound);
        }
        Ok(Persistence { layout, max_polls })
    }

    /// The slot layout.
    #[must_use]
    pub fn layout(&self) -> &RecordLayout {
        &self.layout
    }

    /// Saves `record` on its chip (even sequence → 0x50, odd → 0x51): body pages in address
    /// order, then the commit page, ACK-polling each write cycle to its end. When this returns
    /// `Ok` the record is committed.
    ///
    /// # Errors
    /// Payload too large for the slot; a NACK or poll time-out on the bus.
    pub fn save<P: I2cPins>(
        &self,
        master: &mut I2cMaster<P>,
        record: &Record,
    ) -> Result<SaveReport, PersistError> {
        let (commit, body) = self.layout.encode(record)?;
        let chip = chip_for_sequence(record.sequence);
        let mut polls_per_page = Vec::with_capacity(body.len() / PAGE_BYTES + 2);
        for (k, chunk) in body.chunks(PAGE_BYTES).enumerate() {
            let addr = self.layout.body_addr() + (k * PAGE_BYTES) as u16;
            master.page_write(chip, addr, chunk)?;
            polls_per_page.push(master.ack_poll(chip, self.max_polls)?);
        }
        master.page_write(chip, self.layout.slot_addr(), &commit)?;
        polls_per_page.push(master.ack_poll(chip, self.max_polls)?);
        Ok(SaveReport {
            chip,
            sequence: record.sequence,
            pages_written: polls_per_page.len(),
            polls_per_page,
            record_bytes: COMMIT_BYTES + body.len(),
        })
    }

    /// Reads and checks the commit block on one chip.
    fn read_commit<P: I2cPins>(
        &self,
        master: &mut I2cMaster<P>,
        chip: u8,
    ) -> Result<Commit, ChipReading> {
        let mut commit_bytes = [0u8; COMMIT_BYTES];
        master
            .random_read(chip, self.layout.slot_addr(), &mut commit_bytes)
            .map_err(ChipReading::NoResponse)?;
        let commit = Commit::decode(&commit_bytes, self.layout.max_payload_bytes)
            .map_err(ChipReading::Invalid)?;
        check_chip(chip, commit.sequence).map_err(ChipReading::Invalid)?;
        Ok(commit)
    }

    /// Reads and checks the body `commit` describes on one chip.
    fn read_body<P: I2cPins>(
        &self,
        master: &mut I2cMaster<P>,
        chip: u8,
        commit: &Commit,
    ) -> Result<Record, ChipReading> {
        let mut body = vec![0u8; usize::from(commit.payload_len) + BODY_OVERHEAD_BYTES];
        master
            .random_read(chip, self.layout.body_addr(), &mut body)
            .map_err(ChipReading::NoResponse)?;
        decode_body(commit, &body).map_err(ChipReading::Invalid)
    }

    /// Reads and checks the record on one chip: the commit block, then (if it is sane) the body
    /// it describes, in two random reads.
    ///
    /// # Errors
    /// What the chip held instead of a valid record ([`ChipReading::Invalid`] or
    /// [`ChipReading::NoResponse`]).
    pub fn read_chip<P: I2cPins>(
        &self,
        master: &mut I2cMaster<P>,
        chip: u8,
    ) -> Result<Record, ChipReading> {
        let commit = self.read_commit(master, chip)?;
        self.read_body(master, chip, &commit)
    }

    /// Boot-time recovery: reads both chips' commit blocks, then the bodies newest first
    /// (by sequence number, serial arithmetic) until one checks out, and returns that record,
    /// or `None` if neither chip holds a valid one. An older record whose newer rival is valid
    /// is not read ([`ChipReading::Superseded`]): the result is the same and boot is faster.
    /// Never fails: a chip that does not answer counts as holding nothing.
    pub fn recover<P: I2cPins>(&self, master: &mut I2cMaster<P>) -> Recovery {
        let chips_addr = [CHIP_A, CHIP_B];
        let commits = chips_addr.map(|chip| self.read_commit(master, chip));
        let order = match (&commits[0], &commits[1]) {
            (Ok(a), Ok(b)) if is_newer(b.sequence, a.sequence) => [1, 0],
            _ => [0, 1],
        };
        let mut chips = [
            ChipReading::Superseded { sequence: 0 },
            ChipReading::Superseded { sequence: 0 },
        ];
        let mut newest: Option<Record> = None;
        for i in order {
            chips[i] = match &commits[i] {
                Err(reading) => reading.clone(),
                Ok(commit) if newest.is_some() => ChipReading::Superseded {
                    sequence: commit.sequence,
                },
                Ok(commit) => match self.read_body(master, chips_addr[i], commit) {
                    Ok(record) => {
                        let sequence = record.sequence;
                        newest = Some(record);
                        ChipReading::Valid { sequence }
                    }
                    Err(reading) => reading,
                },
            };
        }
        Recovery { newest, chips }
    }
}

/// When the robot saves: once every `every_steps` steps (steps counted from 1; a save is due
/// after step `k · every_steps`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SavePolicy {
    every_steps: u32,
}

impl Default for SavePolicy {
    fn default() -> Self {
        SavePolicy {
            every_steps: DEFAULT_SAVE_EVERY_STEPS,
        }
    }
}

impl SavePolicy {
    /// A save every `every_steps` steps.
    ///
    /// # Errors
    /// [`PersistError::InvalidSavePeriod`] for zero.
    pub fn new(every_steps: u32) -> Result<SavePolicy, PersistError> {
        if every_steps == 0 {
            return Err(PersistError::InvalidSavePeriod);
        }
        Ok(SavePolicy { every_steps })
    }

    /// Steps between saves.
    #[must_use]
    pub fn every_steps(&self) -> u32 {
        self.every_steps
    }

    /// Whether a save is due after step `step` (steps counted from 1).
    #[must_use]
    pub fn is_due(&self, step: u64) -> bool {
        step > 0 && step.is_multiple_of(u64::from(self.every_steps))
    }

    /// Saves made in a run of `steps` steps.
    #[must_use]
    pub fn saves_in(&self, steps: u64) -> u64 {
        steps / u64::from(self.every_steps)
    }

    /// Write cycles each page of the record lands on, per chip `[0x50, 0x51]`, in a run of
    /// `steps` steps whose first save has sequence `first_sequence`. Pages outside the record
    /// get none.
    #[must_use]
    pub fn writes_per_record_page(&self, steps: u64, first_sequence: u32) -> [u64; 2] {
        let n = self.saves_in(steps);
        let first_on_a = first_sequence & 1 == 0;
        let (first, second) = (n.div_ceil(2), n / 2);
        if first_on_a {
            [first, second]
        } else {
            [second, first]
        }
    }

    /// Write cycles per hour on each record page of one chip, with steps of `step_period_s`.
    #[must_use]
    pub fn page_writes_per_hour(&self, step_period_s: f64) -> f64 {
        3600.0 / (step_period_s * f64::from(self.every_steps) * 2.0)
    }

    /// Hours until the record pages reach `endurance_cycles` writes.
    #[must_use]
    pub fn endurance_lifetime_hours(&self, step_period_s: f64, endurance_cycles: u32) -> f64 {
        f64::from(endurance_cycles) / self.page_writes_per_hour(step_period_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    /// The MCU's φ these tests count in: the robot's 25 MHz (the crate has no clock of its own).
    const CLOCK_HZ: u32 = 25_000_000;
    use crate::{I2cBus, MasterTiming, SimPins};
    use proptest::prelude::*;

    fn slot_image(layout: &RecordLayout, record: &Record) -> Vec<u8> {
        let (commit, body) = layout.encode(record).unwrap();
        let mut image = vec![0xFF; PAGE_BYTES];
        image[..COMMIT_BYTES].copy_from_slice(&commit);
        image.extend_from_slice(&body);
        image
    }

    #[test]
    fn record_layout_and_page_count() {
        let l = RecordLayout::default();
        assert_eq!((l.slot_addr(), l.body_addr()), (0x0000, 0x0040));
        assert_eq!(l.max_payload_bytes(), 32_696);
        assert_eq!(l.slot_pages(), 512);
        // 104-byte payload (13 x 4 Q15 weights): body 112 bytes = 2 pages, + commit page.
        assert_eq!(l.pages_per_record(104), 3);
        assert_eq!(l.pages_of_record(104), 0..3);
        assert_eq!(l.pages_per_record(56), 2);
        assert_eq!(l.pages_per_record(57), 3);
        assert_eq!(l.pages_per_record(0), 2);
        assert_eq!(l.bytes_per_save(104), 126);
        let l = RecordLayout::new(0x1000, 200).unwrap();
        assert_eq!(l.pages_of_record(200), 64..69);
    }

    #[test]
    fn layout_errors_say_what_fits() {
        assert_eq!(
            RecordLayout::new(0x0010, 10),
            Err(PersistError::SlotNotPageAligned { slot_addr: 0x0010 })
        );
        let e = RecordLayout::new(0x7FC0, 10).unwrap_err();
        assert!(
            matches!(e, PersistError::SlotDoesNotFit { largest: 0, .. }),
            "{e}"
        );
        let e = RecordLayout::new(0x7F00, 1000).unwrap_err();
        assert!(
            matches!(e, PersistError::SlotDoesNotFit { largest: 184, .. }),
            "{e}"
        );
        assert!(RecordLayout::new(0x7F00, 184).is_ok());
        assert!(RecordLayout::new(0x7F00, 185).is_err());
        let l = RecordLayout::new(0, 100).unwrap();
        let big = Record {
            sequence: 0,
            payload: vec![0; 101],
        };
        assert_eq!(
            l.encode(&big),
            Err(PersistError::PayloadTooLarge { len: 101, max: 100 })
        );
        let huge = Record {
            sequence: 0,
            payload: vec![0; 70_000],
        };
        assert!(RecordLayout::default().encode(&huge).is_err());
        assert_eq!(Persistence::new(l, 0), Err(PersistError::InvalidPollBound));
    }

    #[test]
    fn a_b_chips_and_serial_order() {
        assert_eq!(chip_for_sequence(0), CHIP_A);
        assert_eq!(chip_for_sequence(1), CHIP_B);
        assert_eq!(chip_for_sequence(u32::MAX), CHIP_B);
        assert!(is_newer(1, 0));
        assert!(!is_newer(0, 1));
        assert!(!is_newer(5, 5));
        assert!(is_newer(0, u32::MAX), "wraps");
        assert!(is_newer(3, u32::MAX - 2));
    }

    #[test]
    fn malformed_records_are_reported_as_invalid() {
        let l = RecordLayout::new(0, 300).unwrap();
        let rec = Record {
            sequence: 6,
            payload: (0..200u32).map(|i| i as u8).collect(),
        };
        let good = slot_image(&l, &rec);
        assert_eq!(l.decode_slot(CHIP_A, &good), Ok(rec.clone()));
        assert!(matches!(
            l.decode_slot(CHIP_B, &good),
            Err(RecordError::WrongChip {
                sequence: 6,
                chip: CHIP_B
            })
        ));
        let mut g = good.clone();
        g[0] = b'X';
        assert!(matches!(
            l.decode_slot(CHIP_A, &g),
            Err(RecordError::BadMagic { .. })
        ));
        let mut g = good.clone();
        g[5] ^= 1;
        assert!(matches!(
            l.decode_slot(CHIP_A, &g),
            Err(RecordError::BadCommitCrc { .. })
        ));
        let mut g = good.clone();
        g[PAGE_BYTES + 100] ^= 0x10;
        assert!(matches!(
            l.decode_slot(CHIP_A, &g),
            Err(RecordError::BadBodyCrc { .. })
        ));
        // A sane commit block with a bad version, reserved byte or length.
        let patch = |f: &dyn Fn(&mut [u8])| {
            let mut g = good.clone();
            f(&mut g[..COMMIT_BYTES]);
            let crc = crc16_ccitt_false(&g[..12]);
            g[12..14].copy_from_slice(&crc.to_be_bytes());
            l.decode_slot(CHIP_A, &g)
        };
        assert!(matches!(
            patch(&|b| b[2] = 2),
            Err(RecordError::BadVersion { found: 2, .. })
        ));
        assert!(matches!(
            patch(&|b| b[3] = 1),
            Err(RecordError::BadReserved { found: 1 })
        ));
        assert!(matches!(
            patch(&|b| b[8..10].copy_from_slice(&301u16.to_be_bytes())),
            Err(RecordError::BadLength { len: 301, max: 300 })
        ));
        assert!(matches!(
            patch(&|b| b[8..10].copy_from_slice(&199u16.to_be_bytes())),
            Err(RecordError::BadBodyCrc { .. })
        ));
        assert!(matches!(
            patch(&|b| b[4..8].copy_from_slice(&8u32.to_be_bytes())),
            Err(RecordError::Mismatch {
                field: "sequence",
                commit: 8,
                body: 6
            })
        ));
        assert!(matches!(
            patch(&|b| b[10] ^= 0xFF),
            Err(RecordError::Mismatch {
                field: "body CRC",
                ..
            })
        ));
        // Truncated anywhere: an error, never a panic.
        for n in 0..good.len() {
            let r = l.decode_slot(CHIP_A, &good[..n]);
            assert!(r.is_err(), "truncated to {n} bytes");
        }
        assert!(matches!(
            l.decode_slot(CHIP_A, &good[..PAGE_BYTES + 10]),
            Err(RecordError::Truncated {
                part: "record body",
                needed: 208,
                got: 10
            })
        ));
        // An erased chip.
        assert!(matches!(
            l.decode_slot(CHIP_A, &[0xFF; 1024]),
            Err(RecordError::BadMagic { .. })
        ));
    }

    proptest! {
        #[test]
        fn encode_decode_round_trip(seq in any::<u32>(), payload in proptest::collection::vec(any::<u8>(), 0..400)) {
            let l = RecordLayout::new(0, 400).unwrap();
            let rec = Record { sequence: seq, payload };
            let image = slot_image(&l, &rec);
            prop_assert_eq!(l.decode_slot(chip_for_sequence(seq), &image), Ok(rec));
        }

        #[test]
        fn any_corrupted_record_byte_is_rejected(
            seq in any::<u32>(),
            payload in proptest::collection::vec(any::<u8>(), 0..200),
            pos in any::<usize>(),
            flip in 1u8..=255,
        ) {
            let l = RecordLayout::new(0, 200).unwrap();
            let rec = Record { sequence: seq, payload };
            let mut image = slot_image(&l, &rec);
            // Only the bytes the record uses (commit block and body).
            let used: Vec<usize> = (0..COMMIT_BYTES).chain(PAGE_BYTES..image.len()).collect();
            let i = used[pos % used.len()];
            image[i] ^= flip;
            prop_assert!(l.decode_slot(chip_for_sequence(seq), &image).is_err());
        }

        #[test]
        fn garbage_never_panics(image in proptest::collection::vec(any::<u8>(), 0..700), chip in 0x50u8..=0x51) {
            let l = RecordLayout::new(0, 500).unwrap();
            let _ = l.decode_slot(chip, &image);
            let _ = Commit::decode(&image, 500);
        }
    }

    #[test]
    fn save_policy_counts() {
        assert_eq!(SavePolicy::new(0), Err(PersistError::InvalidSavePeriod));
        let p = SavePolicy::default();
        assert_eq!(p.every_steps(), 20);
        assert!(!p.is_due(0) && !p.is_due(19) && p.is_due(20) && p.is_due(1000));
        assert_eq!(p.saves_in(1000), 50);
        assert_eq!(p.writes_per_record_page(1000, 0), [25, 25]);
        assert_eq!(p.writes_per_record_page(1020, 0), [26, 25]);
        assert_eq!(p.writes_per_record_page(1020, 7), [25, 26]);
        // docs/design.md §3.6: arena step 0.45 s, one save per 20 steps, A/B: ~5 000 h to 1e6 writes.
        let h = p.endurance_lifetime_hours(0.45, 1_000_000);
        assert!((h - 5_000.0).abs() < 1e-6, "{h}");
        assert!((p.page_writes_per_hour(0.45) - 200.0).abs() < 1e-9);
    }

    #[test]
    fn save_then_recover_through_the_bus_alternates_chips() {
        let mut m = I2cMaster::new(
            SimPins::new(I2cBus::robot(9, CLOCK_HZ).unwrap()),
            MasterTiming::fast_mode(CLOCK_HZ).unwrap(),
        );
        m.init();
        let p = Persistence::new(RecordLayout::new(0, 256).unwrap(), DEFAULT_MAX_POLLS).unwrap();
        let r = p.recover(&mut m);
        assert_eq!(r.newest, None);
        assert_eq!(r.next_sequence(), 0);
        assert!(matches!(
            r.chips[0],
            ChipReading::Invalid(RecordError::BadMagic { .. })
        ));
        for seq in 0..5u32 {
            let rec = Record {
                sequence: seq,
                payload: vec![seq as u8; 100 + seq as usize],
            };
            let rep = p.save(&mut m, &rec).unwrap();
            assert_eq!(rep.chip, chip_for_sequence(seq));
            assert_eq!(rep.pages_written, 3);
            assert!(rep.polls_per_page.iter().all(|&n| n > 1));
            let r = p.recover(&mut m);
            assert_eq!(r.newest, Some(rec));
            assert_eq!(r.next_sequence(), seq + 1);
        }
        let r = p.recover(&mut m);
        assert_eq!(
            r.chips,
            [
                ChipReading::Valid { sequence: 4 },
                ChipReading::Superseded { sequence: 3 }
            ]
        );
        assert_eq!(p.read_chip(&mut m, CHIP_B).map(|r| r.sequence), Ok(3));
        assert_eq!(m.pins().bus().timing_violation_count(), 0);
        // A bad body on the newest record: recovery falls back to the other chip.
        let t = m.pins().now();
        let d = m.pins_mut().bus_mut().device_mut(CHIP_A).unwrap();
        let mut byte = [0u8; 1];
        d.read(t, 0x0050, &mut byte).unwrap();
        d.load(0x0050, &[byte[0] ^ 0x01]).unwrap();
        let r = p.recover(&mut m);
        assert_eq!(r.newest.as_ref().map(|r| r.sequence), Some(3));
        assert!(matches!(
            r.chips[0],
            ChipReading::Invalid(RecordError::BadBodyCrc { .. })
        ));
        assert_eq!(r.chips[1], ChipReading::Valid { sequence: 3 });
        // A chip that does not answer counts as empty.
        let t = m.pins().now();
        m.pins_mut().bus_mut().power_off_device(t, CHIP_A).unwrap();
        let r = p.recover(&mut m);
        assert_eq!(r.newest.map(|r| r.sequence), Some(3));
        assert!(matches!(r.chips[0], ChipReading::NoResponse(_)));
        // Saving to a chip that is off fails with a NACK, not a panic.
        let e = p
            .save(
                &mut m,
                &Record {
                    sequence: 6,
                    payload: vec![1],
                },
            )
            .unwrap_err();
        assert!(matches!(
            e,
            PersistError::Master(MasterError::Nack { device: CHIP_A, .. })
        ));
    }
}
