//! The timeline save: the pin-level save's outcome and states, computed from timelines.
//!
//! The bit-banging master's pin sequence does not depend on the bytes it sends, only on how
//! many and on the ACK bits it reads, so each piece of a save has a fixed timeline: a page
//! write of n bytes; the START that opens ACK polling; one unanswered poll (the control byte and
//! the repeated START of the next); the answered poll (the control byte and the STOP). Each
//! timeline is recorded once, by running the real master ([`eeprom::I2cMaster`]) against
//! recording pins that charge exactly what the port-4 pins charge ([`super::charging::FwPins`]: 7
//! states per pin operation, the tick taken at the end of each operation and each wait), and
//! noting the points where the tick could be taken, the instants the chip decides on a control
//! byte (the fall of SCL after its eighth bit) and the STOP edge.
//!
//! A save then walks the timelines on the MCU's clock: the tick interrupt runs for real at the
//! first point at or after its instant, shifting the rest; each page reaches the chip at
//! transaction level at its STOP edge ([`eeprom::I2cBus::write_transaction`]: the same memory,
//! counters and seeded write-cycle time as the pin-level transfer); each poll is answered iff the
//! chip's write cycle has ended by its decision instant. The result — the states of the save, the
//! polls, the chips' contents — is the pin-level one; the controller's tests compare the two run
//! for run. Only the bus's edge counter differs (it counts pin-level traffic).

use std::sync::{Arc, Mutex, OnceLock};

use eeprom::persist::{COMMIT_BYTES, Persistence, Record, SaveReport, chip_for_sequence};
use eeprom::{I2cMaster, I2cPins, MasterTiming};

use super::ControllerError;
use super::ModelBus;
use super::charging::{Fw, PIN_OP_STATES};

/// Of a pin read's 7 states, those up to the end of its bus access (`MOV.B @P4DR:8` = 2 + 3):
/// the first point the tick can be taken at.
const READ_ACCESS_STATES: u64 = 5;
/// ACK polls per page before a save gives up (as the pin-level save's bound).
const MAX_POLLS: u32 = super::MAX_POLLS;
/// The largest page write.
const PAGE: usize = 64;

/// One piece of a save's pin sequence, from the master's point of view (no interrupts).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Piece {
    /// Offsets (from the piece's start) of the points where the tick can be taken: the end of
    /// every pin operation and wait, and of every pin read's bus access.
    points: Vec<u64>,
    /// Length in states.
    total: u64,
    /// Offset of the first control byte's decision, if the piece sends one.
    decision: Option<u64>,
    /// Offset of the STOP edge, if the piece ends a transfer.
    stop: Option<u64>,
}

/// What happens in a piece that the save must act on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mark {
    Decision,
    Stop,
}

/// Pins that record the timeline of what the master does, answering reads from a script.
struct Recorder {
    t: u64,
    scl_high: bool,
    sda_high: bool,
    bit: u32,
    first_byte: bool,
    points: Vec<u64>,
    events: Vec<(Event, u64)>,
    answers: Vec<bool>,
}

/// An instant in a recorded sequence.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Event {
    /// A START completed (its SCL fall).
    StartDone,
    /// The chip decided on the control byte (the fall after its eighth bit).
    Decision,
    /// The STOP edge.
    Stop,
}

impl Recorder {
    fn new(answers: &[bool]) -> Self {
        Self {
            t: 0,
            scl_high: true,
            sda_high: true,
            bit: 0,
            first_byte: false,
            points: Vec::new(),
            events: Vec::new(),
            answers: answers.iter().rev().copied().collect(),
        }
    }

    fn op(&mut self) {
        self.t += PIN_OP_STATES;
        self.points.push(self.t);
    }
}

impl I2cPins for Recorder {
    fn scl_low(&mut self) {
        self.op();
        self.scl_high = false;
        match self.bit {
            // The fall that completes a START (no bit clocked yet).
            0 if self.first_byte => self.events.push((Event::StartDone, self.t)),
            8 if self.first_byte => self.events.push((Event::Decision, self.t)),
            9 => {
                self.bit = 0;
                self.first_byte = false;
            }
            _ => {}
        }
    }

    fn scl_release(&mut self) {
        self.op();
        self.scl_high = true;
        self.bit += 1;
    }

    fn sda_low(&mut self) {
        self.op();
        if self.sda_high && self.scl_high {
            // START: the next byte is a control byte.
            self.bit = 0;
            self.first_byte = true;
        }
        self.sda_high = false;
    }

    fn sda_release(&mut self) {
        self.op();
        if !self.sda_high && self.scl_high {
            self.events.push((Event::Stop, self.t));
            self.first_byte = false;
            self.bit = 0;
        }
        self.sda_high = true;
    }

    fn sda_is_high(&mut self) -> bool {
        self.t += READ_ACCESS_STATES;
        self.points.push(self.t);
        self.t += PIN_OP_STATES - READ_ACCESS_STATES;
        self.points.push(self.t);
        if self.bit == 9 {
            // The ACK bit: answer from the script (true = ACK, read low).
            !self.answers.pop().unwrap_or(true)
        } else {
            self.sda_high
        }
    }

    fn wait_states(&mut self, states: u64) {
        if states > 0 {
            self.t += states;
            self.points.push(self.t);
        }
    }

    fn op_states(&self) -> u64 {
        PIN_OP_STATES
    }
}

/// Cuts `points` (absolute, from a recording) to `from..=to`, relative to `from`.
fn piece(rec: &Recorder, from: u64, to: u64) -> Piece {
    let rel = |t: u64| t - from;
    Piece {
        points: rec
            .points
            .iter()
            .copied()
            .filter(|&p| p > from && p <= to)
            .map(rel)
            .collect(),
        total: to - from,
        decision: rec
            .events
            .iter()
            .find(|(e, t)| *e == Event::Decision && *t > from && *t <= to)
            .map(|&(_, t)| rel(t)),
        stop: rec
            .events
            .iter()
            .find(|(e, t)| *e == Event::Stop && *t > from && *t <= to)
            .map(|&(_, t)| rel(t)),
    }
}

fn events(rec: &Recorder, kind: Event) -> Vec<u64> {
    rec.events
        .iter()
        .filter(|(e, _)| *e == kind)
        .map(|&(_, t)| t)
        .collect()
}

/// The recorded pieces of a save for one master timing; page writes are recorded when first
/// needed (a save uses at most three sizes). The pieces are a function of the timing alone, so
/// every controller with the same timing shares one set ([`SaveTimelines::shared`]).
#[derive(Debug)]
pub struct SaveTimelines {
    timing: MasterTiming,
    /// Page writes of 1..=64 bytes (index n − 1), recorded by the first save that needs one.
    page_writes: [OnceLock<Piece>; PAGE],
    /// ACK polling's opening START.
    poll_start: Piece,
    /// An unanswered poll: the control byte and the repeated START of the next.
    poll_unanswered: Piece,
    /// The answered poll: the control byte and the STOP.
    poll_answered: Piece,
}

fn master_error(e: eeprom::MasterError) -> ControllerError {
    ControllerError::Persist(e.into())
}

/// The timelines recorded so far in this process, one set per master timing.
static SHARED: Mutex<Vec<Arc<SaveTimelines>>> = Mutex::new(Vec::new());

impl SaveTimelines {
    /// The process's one set of timelines for `timing`, recorded on first use.
    ///
    /// # Errors
    /// Only if the master refuses its own recording (it cannot).
    pub fn shared(timing: MasterTiming) -> Result<Arc<SaveTimelines>, ControllerError> {
        // A panic elsewhere while the lock was held leaves the list as it was: every entry in
        // it is complete, so a poisoned lock's contents are still good.
        let mut sets = SHARED
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(t) = sets.iter().find(|t| t.timing == timing) {
            return Ok(Arc::clone(t));
        }
        let t = Arc::new(Self::record(timing)?);
        sets.push(Arc::clone(&t));
        Ok(t)
    }

    /// Records the polling pieces by running the master with `timing` against recording pins.
    ///
    /// # Errors
    /// Only if the master refuses its own recording (it cannot).
    pub fn record(timing: MasterTiming) -> Result<Self, ControllerError> {
        // Three polls: two unanswered, then answered.
        let mut rec = Recorder::new(&[false, false, true]);
        I2cMaster::new(&mut rec, timing)
            .ack_poll(0x50, 3)
            .map_err(master_error)?;
        // START, then a poll begins at each START's completion.
        let starts = events(&rec, Event::StartDone);
        let (s0, s1, s2) = match starts[..] {
            [a, b, c] => (a, b, c),
            _ => return Err(master_error(eeprom::MasterError::InvalidPollBound)),
        };
        Ok(Self {
            timing,
            page_writes: std::array::from_fn(|_| OnceLock::new()),
            poll_start: piece(&rec, 0, s0),
            poll_unanswered: piece(&rec, s1, s2),
            poll_answered: piece(&rec, s2, rec.t),
        })
    }

    /// The page write of `n` bytes (1 ..= 64), recorded unless it is already.
    fn page_write(&self, n: usize) -> Result<&Piece, ControllerError> {
        let slot = self.page_writes.get(n.wrapping_sub(1)).ok_or_else(|| {
            master_error(eeprom::MasterError::EmptyTransfer {
                operation: "page write",
            })
        })?;
        if let Some(p) = slot.get() {
            return Ok(p);
        }
        let mut rec = Recorder::new(&[]);
        I2cMaster::new(&mut rec, self.timing)
            .page_write(0x50, 0, &[0; PAGE][..n])
            .map_err(master_error)?;
        let total = rec.t;
        // Two threads may record the same piece at once; the recordings are equal, and the
        // first one stored is the one every save uses.
        Ok(slot.get_or_init(|| piece(&rec, 0, total)))
    }
}

/// Walks `piece` on the MCU from now: the tick is taken, for real, at the first point at or
/// after its instant; the marks are reported with their instants (an edge at a point comes
/// before the tick taken there).
fn walk<B: ModelBus>(
    fw: &mut Fw<'_, B>,
    piece: &Piece,
    mut mark: impl FnMut(&mut Fw<'_, B>, Mark, u64),
) {
    let start = fw.now();
    let mut shift = 0u64;
    let mut done = 0u64;
    let mut marks: Vec<(u64, Mark)> = [
        piece.decision.map(|d| (d, Mark::Decision)),
        piece.stop.map(|s| (s, Mark::Stop)),
    ]
    .into_iter()
    .flatten()
    .collect();
    marks.sort_unstable_by_key(|m| m.0);
    let mut next_mark = 0;
    loop {
        let tick_point = fw
            .interrupts_enabled
            .then_some(())
            .and(fw.next_tick_at)
            .and_then(|due| {
                let i = piece
                    .points
                    .partition_point(|&p| p <= done || start + shift + p < due);
                piece.points.get(i).copied()
            });
        let upto = tick_point.unwrap_or(piece.total);
        while next_mark < marks.len() && marks[next_mark].0 <= upto {
            let (rel, m) = marks[next_mark];
            mark(fw, m, start + shift + rel);
            next_mark += 1;
        }
        let target = start + shift + upto;
        fw.idle(target - fw.now());
        match tick_point {
            Some(p) => {
                fw.tick_handler();
                shift = fw.now() - start - p;
                done = p;
            }
            None => break,
        }
    }
}

/// The instant `piece`'s decision would happen if walked from now (with the tick, if it
/// comes first, taken at its point).
fn decision_at<B: ModelBus>(fw: &Fw<'_, B>, piece: &Piece, isr_states: u64) -> Option<u64> {
    let start = fw.now();
    let d = piece.decision?;
    let delayed = fw.interrupts_enabled
        && fw
            .next_tick_at
            .is_some_and(|due| piece.points.iter().any(|&p| p < d && start + p >= due));
    Some(start + d + if delayed { isr_states } else { 0 })
}

/// Whether the chip answers its control byte at `t`: powered, present and not in a write cycle.
fn chip_answers<B: ModelBus>(
    fw: &mut Fw<'_, B>,
    t: u64,
    chip: u8,
) -> Result<bool, ControllerError> {
    let bus = fw.bus.eeprom_bus().ok_or_else(|| {
        ControllerError::I2c(eeprom::EepromError::NoSuchDevice {
            address: chip,
            present: String::new(),
        })
    })?;
    let busy = bus.busy_until(t, chip)?.is_some();
    let powered = bus.device(chip)?.is_powered();
    Ok(powered && !busy)
}

/// Saves `record` as [`Persistence::save`] does — the body pages in address order, then the
/// commit page, each followed by ACK polling — with the pin-level outcome.
///
/// # Errors
/// A chip that does not answer (off, missing) or never ends its write cycle within the poll
/// bound, as the pin-level save would report it.
pub fn save<B: ModelBus>(
    fw: &mut Fw<'_, B>,
    persistence: &Persistence,
    timelines: &SaveTimelines,
    isr_states: u64,
    record: &Record,
) -> Result<SaveReport, ControllerError> {
    let (commit, body) = persistence.layout().encode(record)?;
    let chip = chip_for_sequence(record.sequence);
    let layout = persistence.layout();
    let mut polls_per_page = Vec::with_capacity(body.len() / PAGE + 2);
    let pages = body
        .chunks(PAGE)
        .enumerate()
        .map(|(k, c)| (layout.body_addr() + (k * PAGE) as u16, c))
        .chain(std::iter::once((layout.slot_addr(), &commit[..])));
    for (address, data) in pages {
        let piece = timelines.page_write(data.len())?;
        let mut failure: Option<ControllerError> = None;
        walk(fw, piece, |fw, m, t| {
            if failure.is_some() {
                return;
            }
            let outcome = match m {
                Mark::Decision => chip_answers(fw, t, chip).and_then(|ok| {
                    if ok {
                        Ok(())
                    } else {
                        Err(ControllerError::Persist(
                            eeprom::MasterError::Nack {
                                device: chip,
                                stage: eeprom::NackStage::Control,
                            }
                            .into(),
                        ))
                    }
                }),
                Mark::Stop => fw
                    .bus
                    .eeprom_bus()
                    .map_or(Ok(0), |b| b.write_transaction(t, chip, address, data))
                    .map(|_| ())
                    .map_err(ControllerError::I2c),
            };
            if let Err(e) = outcome {
                failure = Some(e);
            }
        });
        if let Some(e) = failure {
            return Err(e);
        }
        // ACK polling until the chip answers.
        walk(fw, &timelines.poll_start, |_, _, _| {});
        let mut polls = 1u32;
        let period = timelines.poll_unanswered.total;
        let offset = timelines.poll_unanswered.decision.unwrap_or(0);
        loop {
            // In bulk: the polls that end before the tick can come and decide before the write
            // cycle ends are all unanswered and alike.
            let now = fw.now();
            let due = if fw.interrupts_enabled {
                fw.next_tick_at.unwrap_or(now)
            } else {
                u64::MAX
            };
            let end = match fw.bus.eeprom_bus().map(|b| b.busy_until(now, chip)) {
                Some(Ok(Some(end))) => end,
                _ => now,
            };
            if let Some(free) = due.saturating_sub(now + 1).checked_div(period) {
                let unanswered = end.saturating_sub(now + offset).div_ceil(period);
                let bulk = free.min(unanswered).min(u64::from(MAX_POLLS - polls));
                if bulk > 0 {
                    fw.idle(bulk * period);
                    polls += u32::try_from(bulk).unwrap_or(0);
                }
            }
            let decision =
                decision_at(fw, &timelines.poll_unanswered, isr_states).unwrap_or_else(|| fw.now());
            if chip_answers(fw, decision, chip)? {
                walk(fw, &timelines.poll_answered, |_, _, _| {});
                break;
            }
            if polls >= MAX_POLLS {
                return Err(ControllerError::Persist(
                    eeprom::MasterError::PollTimeout {
                        device: chip,
                        polls,
                        waited_states: 0,
                    }
                    .into(),
                ));
            }
            walk(fw, &timelines.poll_unanswered, |_, _, _| {});
            polls += 1;
        }
        polls_per_page.push(polls);
    }
    Ok(SaveReport {
        chip,
        sequence: record.sequence,
        pages_written: polls_per_page.len(),
        polls_per_page,
        record_bytes: COMMIT_BYTES + body.len(),
    })
}
