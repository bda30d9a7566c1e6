//! The big ones: a power cut at every bus edge and at every instant class of every write cycle
//! of a full save, each followed by power-on and recovery; and exact write counts per page for
//! a save policy.

use eeprom::persist::DEFAULT_MAX_POLLS;
use eeprom::{
    CHIP_A, CHIP_B, I2cBus, I2cMaster, I2cPins, MasterTiming, Persistence, Record, RecordLayout,
    SavePolicy, SimPins, WriteCycleInfo,
};

/// The MCU's φ these tests count in: the robot's 25 MHz (the crate has no clock of its own).
const CLOCK_HZ: u32 = 25_000_000;

/// States the robot stays off after a cut (1 ms at 25 MHz).
const OFF_STATES: u64 = 25_000;

/// Why the hook is called.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum At {
    /// Right after a line transition.
    Edge,
    /// At one of the extra instants asked for.
    Probe,
}

/// Pins like [`SimPins`] (free pin operations) that call `hook` with the bus right after every
/// line transition, and at extra `probes` instants, so each can be cloned and cut there.
struct ProbePins<F: FnMut(&I2cBus, u64, At)> {
    bus: I2cBus,
    now: u64,
    probes: Vec<u64>,
    next_probe: usize,
    hook: F,
}

impl<F: FnMut(&I2cBus, u64, At)> ProbePins<F> {
    fn new(bus: I2cBus, mut probes: Vec<u64>, hook: F) -> Self {
        probes.sort_unstable();
        probes.dedup();
        let now = bus.now();
        ProbePins {
            bus,
            now,
            probes,
            next_probe: 0,
            hook,
        }
    }

    /// Moves time to `target`, stopping at every device output change and every probe.
    fn advance(&mut self, target: u64) {
        loop {
            while self
                .probes
                .get(self.next_probe)
                .is_some_and(|&p| p < self.bus.now())
            {
                self.next_probe += 1;
            }
            let probe = self.probes.get(self.next_probe).copied();
            let event = self.bus.next_event_states();
            let next = match (probe, event) {
                (Some(p), Some(e)) => Some(p.min(e)),
                (p, e) => p.or(e),
            };
            match next {
                Some(t) if t <= target => {
                    let e0 = self.bus.edges().total();
                    self.bus.advance_to(t).unwrap();
                    let is_probe = probe == Some(t);
                    if is_probe {
                        self.next_probe += 1;
                    }
                    if is_probe {
                        (self.hook)(&self.bus, t, At::Probe);
                    }
                    if self.bus.edges().total() != e0 {
                        (self.hook)(&self.bus, t, At::Edge);
                    }
                }
                _ => break,
            }
        }
        self.now = target;
    }

    fn set(&mut self, scl: Option<bool>, sda: Option<bool>) {
        self.advance(self.now);
        let (scl_low, sda_low) = self.bus.master_pulls();
        let e0 = self.bus.edges().total();
        self.bus
            .set_master(self.now, scl.unwrap_or(scl_low), sda.unwrap_or(sda_low))
            .unwrap();
        if self.bus.edges().total() != e0 {
            (self.hook)(&self.bus, self.now, At::Edge);
        }
    }
}

impl<F: FnMut(&I2cBus, u64, At)> I2cPins for ProbePins<F> {
    fn scl_low(&mut self) {
        self.set(Some(true), None);
    }
    fn scl_release(&mut self) {
        self.set(Some(false), None);
    }
    fn sda_low(&mut self) {
        self.set(None, Some(true));
    }
    fn sda_release(&mut self) {
        self.set(None, Some(false));
    }
    fn sda_is_high(&mut self) -> bool {
        self.advance(self.now);
        self.bus.lines(self.now).unwrap().sda
    }
    fn wait_states(&mut self, states: u64) {
        let target = self.now + states;
        self.advance(target);
    }
}

fn payload(seq: u32, len: usize) -> Vec<u8> {
    (0..len)
        .map(|i| (seq as usize * 31 + i * 7 + 1) as u8)
        .collect()
}

fn record(seq: u32, len: usize) -> Record {
    Record {
        sequence: seq,
        payload: payload(seq, len),
    }
}

fn persistence(len: usize) -> Persistence {
    let layout = RecordLayout::new(0, u16::try_from(len).unwrap()).unwrap();
    Persistence::new(layout, DEFAULT_MAX_POLLS).unwrap()
}

/// Cuts power on a copy of `bus` at `t`, powers on 1 ms later, recovers through the bus.
/// Returns the recovered record and whether the cut interrupted a write cycle.
fn cut_and_recover(bus: &I2cBus, t: u64, p: &Persistence) -> (Option<Record>, bool) {
    let mut b = bus.clone();
    let outcomes = b.power_cut(t).unwrap();
    let interrupted = outcomes.iter().any(|o| o.interrupted_write.is_some());
    b.power_on(t + OFF_STATES).unwrap();
    let mut m = I2cMaster::new(SimPins::new(b), MasterTiming::fast_mode(CLOCK_HZ).unwrap());
    m.init();
    (p.recover(&mut m).newest, interrupted)
}

#[derive(Default, Debug)]
struct Tally {
    cuts: u64,
    edge_cuts: u64,
    instant_cuts: u64,
    interrupted: u64,
    recovered_prev: u64,
    recovered_new: u64,
    wrong: Vec<(u64, Option<u32>)>,
}

/// Runs `pre` saves, then the save of `seq` with a cut at every edge and every write-cycle
/// instant class; returns the tally.
fn exhaustive(seed: u64, seq: u32, len: usize) -> (Tally, u64, Vec<WriteCycleInfo>) {
    let p = persistence(len);
    let chip = eeprom::persist::chip_for_sequence(seq);
    // Bring the chips to the state before save `seq`: saves 0..seq all committed.
    let mut m = I2cMaster::new(
        SimPins::new(I2cBus::robot(seed, CLOCK_HZ).unwrap()),
        MasterTiming::fast_mode(CLOCK_HZ).unwrap(),
    );
    m.init();
    for s in 0..seq {
        p.save(&mut m, &record(s, len)).unwrap();
    }
    let before = m.into_pins().into_bus().unwrap();
    let prev = seq.checked_sub(1).map(|s| record(s, len));
    let new = record(seq, len);

    // Reference run: find the write cycles of the save.
    let mut cycles: Vec<WriteCycleInfo> = Vec::new();
    let mut edges_in_save = 0u64;
    {
        let hook = |bus: &I2cBus, _t: u64, _at: At| {
            if let Some(c) = bus.device(chip).unwrap().current_write_cycle()
                && cycles.last() != Some(&c)
            {
                cycles.push(c);
            }
        };
        let pins = ProbePins::new(before.clone(), Vec::new(), hook);
        let e0 = pins.bus.edges().total();
        let mut m = I2cMaster::new(pins, MasterTiming::fast_mode(CLOCK_HZ).unwrap());
        p.save(&mut m, &new).unwrap();
        edges_in_save += m.pins().bus.edges().total() - e0;
    }
    assert_eq!(cycles.len(), p.layout().pages_per_record(len));

    // Instant classes of each write cycle: first state, middle, last state, just after (end),
    // one state later.
    let mut probes = Vec::new();
    let mut expect_interrupted = std::collections::HashMap::new();
    for c in &cycles {
        let (s, e) = (c.start_states, c.end_states);
        for (t, inside) in [
            (s + 1, true),
            (s + (e - s) / 2, true),
            (e - 1, true),
            (e, false),
            (e + 1, false),
        ] {
            probes.push(t);
            expect_interrupted.insert(t, inside);
        }
    }

    let mut tally = Tally::default();
    {
        let hook = |bus: &I2cBus, t: u64, at: At| {
            let (got, interrupted) = cut_and_recover(bus, t, &p);
            tally.cuts += 1;
            match at {
                At::Probe => {
                    tally.instant_cuts += 1;
                    assert_eq!(interrupted, expect_interrupted[&t], "instant {t}");
                }
                At::Edge => tally.edge_cuts += 1,
            }
            tally.interrupted += u64::from(interrupted);
            if got.as_ref() == Some(&new) {
                tally.recovered_new += 1;
            } else if got == prev {
                tally.recovered_prev += 1;
            } else {
                tally.wrong.push((t, got.map(|r| r.sequence)));
            }
        };
        let pins = ProbePins::new(before.clone(), probes, hook);
        let mut m = I2cMaster::new(pins, MasterTiming::fast_mode(CLOCK_HZ).unwrap());
        p.save(&mut m, &new).unwrap();
        // And once more after the save returned: the new record must be there.
        let t = m.pins().now;
        let (got, _) = cut_and_recover(&m.pins().bus, t, &p);
        assert_eq!(got, Some(new.clone()));
    }
    (tally, edges_in_save, cycles)
}

fn check(seed: u64, seq: u32, len: usize) -> Tally {
    let (t, edges, cycles) = exhaustive(seed, seq, len);
    println!(
        "seed {seed} save #{seq} payload {len} B: {} pages, {edges} bus edges; cut points tried {} \
         ({} at edges, {} at write-cycle instants), {} interrupted a write cycle; \
         recovered previous {} / new {} / wrong {}",
        cycles.len(),
        t.cuts,
        t.edge_cuts,
        t.instant_cuts,
        t.interrupted,
        t.recovered_prev,
        t.recovered_new,
        t.wrong.len()
    );
    assert!(
        t.wrong.is_empty(),
        "recovered something else at {:?}",
        &t.wrong[..t.wrong.len().min(10)]
    );
    assert_eq!(
        t.recovered_prev + t.recovered_new,
        t.cuts,
        "100 % of cut points"
    );
    assert_eq!(t.edge_cuts, edges, "a cut at every edge");
    assert_eq!(t.instant_cuts, 5 * cycles.len() as u64);
    assert!(t.recovered_prev > 0 && t.recovered_new > 0);
    t
}

#[test]
fn power_cut_at_every_edge_and_write_cycle_instant_of_a_multi_page_save() {
    // 104-byte payload (13 x 4 Q15 weights of the arena network): body 112 B = 2 pages, plus
    // the commit page: 3 write cycles. Save #5 overwrites #3 on chip 0x51; #4 is on 0x50.
    let t = check(2024, 5, 104);
    assert!(t.interrupted > 0);
}

#[test]
fn power_cut_at_every_edge_of_the_very_first_save() {
    // Fresh chips: "previous" is nothing, the firmware then starts from random weights.
    check(7, 0, 104);
}

#[test]
fn power_cut_at_every_edge_of_the_second_save() {
    // Chip 0x51 still blank, chip 0x50 holds #0.
    check(8, 1, 104);
}

#[test]
fn power_cut_at_every_edge_of_a_larger_save() {
    // 300-byte payload: body 308 B = 5 pages, plus the commit page.
    check(99, 6, 300);
}

#[test]
fn writes_per_page_are_counted_exactly_for_a_save_policy() {
    let policy = SavePolicy::new(20).unwrap();
    let len = 104;
    let p = persistence(len);
    let mut m = I2cMaster::new(
        SimPins::new(I2cBus::robot(42, CLOCK_HZ).unwrap()),
        MasterTiming::fast_mode(CLOCK_HZ).unwrap(),
    );
    m.init();
    let mut seq = 0u32;
    for step in 1..=1000u64 {
        if policy.is_due(step) {
            p.save(&mut m, &record(seq, len)).unwrap();
            seq += 1;
        }
    }
    assert_eq!(u64::from(seq), policy.saves_in(1000));
    let expected = policy.writes_per_record_page(1000, 0);
    assert_eq!(expected, [25, 25]);
    let pages = p.layout().pages_of_record(len);
    for (chip, want) in [(CHIP_A, expected[0]), (CHIP_B, expected[1])] {
        let counts = m.pins().bus().device(chip).unwrap().write_counts();
        for (page, &n) in counts.iter().enumerate() {
            let w = if pages.contains(&page) { want } else { 0 };
            assert_eq!(u64::from(n), w, "chip 0x{chip:02X} page {page}");
        }
    }
    assert_eq!(m.pins().bus().timing_violation_count(), 0);
    let r = p.recover(&mut m);
    assert_eq!(r.newest, Some(record(49, len)));
}

#[test]
fn repeated_random_cuts_never_lose_the_last_committed_record() {
    // A robot that keeps losing power at seeded random instants during its saves, and boots
    // again each time: recovery must always give the last committed record or the one being
    // saved, and the sequence must go on from there.
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let len = 150;
    let p = persistence(len);
    let mut bus = I2cBus::robot(77, CLOCK_HZ).unwrap();
    let mut committed: Option<Record> = None;
    let mut in_flight: Option<Record> = None;
    let (mut cut_saves, mut whole_saves, mut got_new) = (0, 0, 0);
    for _ in 0..40 {
        let mut m = I2cMaster::new(
            SimPins::new(bus),
            MasterTiming::fast_mode(CLOCK_HZ).unwrap(),
        );
        m.init();
        let rec = p.recover(&mut m);
        match in_flight.take() {
            Some(new) if rec.newest.as_ref() == Some(&new) => got_new += 1,
            _ => assert_eq!(rec.newest, committed, "last committed record lost"),
        }
        committed = rec.newest.clone();
        let next = record(rec.next_sequence(), len);
        let t0 = m.pins().now();
        let cut_at = t0 + rng.random_range(0..900_000u64);
        let start = m.into_pins().into_bus().unwrap();
        let mut snapshot = None;
        let finished = {
            let hook = |b: &I2cBus, _t: u64, at: At| {
                if at == At::Probe {
                    snapshot = Some(b.clone());
                }
            };
            let mut m = I2cMaster::new(
                ProbePins::new(start, vec![cut_at], hook),
                MasterTiming::fast_mode(CLOCK_HZ).unwrap(),
            );
            p.save(&mut m, &next).unwrap();
            m.into_pins().bus
        };
        if let Some(mut b) = snapshot {
            b.power_cut(cut_at).unwrap();
            b.power_on(cut_at + OFF_STATES).unwrap();
            bus = b;
            in_flight = Some(next);
            cut_saves += 1;
        } else {
            committed = Some(next);
            bus = finished;
            let t = bus.now();
            bus.power_cut(t).unwrap();
            bus.power_on(t + OFF_STATES).unwrap();
            whole_saves += 1;
        }
    }
    println!(
        "random cuts: {cut_saves} saves cut ({got_new} of them recovered as new), {whole_saves} whole"
    );
    assert!(cut_saves > 5 && whole_saves > 5);
}
