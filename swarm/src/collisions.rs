//! Counting collisions and contact time from the bumpers, in clock states.
//!
//! **A collision** is the start of a bumper contact (any of the four switches pressed) that
//! lasts at least one sub-step of the nominal length (the step period cut into the fewest
//! equal sub-steps of at most `world.substep_s`: 19.57 ms in the arena's 0.45 s step, 20 ms
//! in the corridor's 0.60 s); and a contact ends only when the switches stay released that
//! long. It is a switch debounce in time, as firmware reads a micro-switch: a sliver of
//! release between two pushes (a sub-step too short for anything to move) is not a new
//! collision, and no choice of sub-step length can create one.
//!
//! **Contact time** is the time any switch is pressed, summed over sub-steps weighted by their
//! length: a fraction of the step that sub-steps of any length measure alike.

/// One robot's collision counter and contact clock.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ContactMeter {
    /// How long a new switch state must hold to be taken, states.
    debounce_states: u64,
    /// The debounced state: in contact or not.
    in_contact: bool,
    /// The latest raw state and how long it has held, states.
    raw: bool,
    raw_held_states: u64,
    collisions: u64,
    contact_states: u64,
}

impl ContactMeter {
    /// A meter that takes a new state once it has held `debounce_states` (at least 1); it
    /// starts released, so a robot that starts pressed counts one collision once the press has
    /// held that long.
    #[must_use]
    pub fn new(debounce_states: u64) -> Self {
        Self {
            debounce_states: debounce_states.max(1),
            in_contact: false,
            raw: false,
            raw_held_states: 0,
            collisions: 0,
            contact_states: 0,
        }
    }

    /// Feeds the switches' state over the latest `states` (a sub-step): `pressed` when any
    /// switch was pressed in it.
    pub fn sample(&mut self, pressed: bool, states: u64) {
        if pressed {
            self.contact_states += states;
        }
        if pressed == self.raw {
            self.raw_held_states = self.raw_held_states.saturating_add(states);
        } else {
            self.raw = pressed;
            self.raw_held_states = states;
        }
        if self.raw != self.in_contact && self.raw_held_states >= self.debounce_states {
            self.in_contact = self.raw;
            if self.in_contact {
                self.collisions += 1;
            }
        }
    }

    /// Collisions counted since the last call, and the states in contact since then.
    pub fn take(&mut self) -> (u64, u64) {
        (
            core::mem::take(&mut self.collisions),
            core::mem::take(&mut self.contact_states),
        )
    }

    /// Whether the robot is in a (debounced) contact now.
    #[must_use]
    pub fn in_contact(&self) -> bool {
        self.in_contact
    }
}

/// How many steps a robot's motion is looked back on to call it stuck.
pub const STUCK_WINDOW_STEPS: usize = 100;
/// A robot that moved less than this over [`STUCK_WINDOW_STEPS`] steps while its motors drove
/// is stuck, metres (1 mm).
pub const STUCK_DISTANCE_M: f64 = 0.001;

/// One robot's record of the last [`STUCK_WINDOW_STEPS`] steps: how far it moved in each and
/// whether its motors drove.
#[derive(Clone, Debug, PartialEq)]
pub struct StuckDetector {
    moved_m: Vec<f64>,
    drove: Vec<bool>,
    next: usize,
    filled: usize,
}

impl Default for StuckDetector {
    fn default() -> Self {
        Self {
            moved_m: vec![0.0; STUCK_WINDOW_STEPS],
            drove: vec![false; STUCK_WINDOW_STEPS],
            next: 0,
            filled: 0,
        }
    }
}

impl StuckDetector {
    /// Records a step: the straight-line distance the robot's centre moved in it and whether
    /// some wheel was driven (forward or reverse at a duty above 0) through it; returns
    /// whether the robot is stuck: over the last [`STUCK_WINDOW_STEPS`] steps its motors drove
    /// in every one and it moved less than [`STUCK_DISTANCE_M`] in all (path length).
    pub fn record(&mut self, moved_m: f64, drove: bool) -> bool {
        self.moved_m[self.next] = moved_m;
        self.drove[self.next] = drove;
        self.next = (self.next + 1) % STUCK_WINDOW_STEPS;
        self.filled = (self.filled + 1).min(STUCK_WINDOW_STEPS);
        self.filled == STUCK_WINDOW_STEPS
            && self.drove.iter().all(|&d| d)
            && self.moved_m.iter().sum::<f64>() < STUCK_DISTANCE_M
    }
}

/// A robot counts as moving in a step when its centre moved at least this far between the two
/// step instants, millimetres. A free robot covers 44-67 mm in a 0.45 s step (a turn or
/// straight ahead at 0.15 m/s); one pressed against a wall or another body moves well under
/// a millimetre; 5 mm lies far from both.
pub const MOVING_MIN_MM: f64 = 5.0;

/// One robot's record over a whole run: how far it moved, how often it collided, and its stuck
/// spells. A **stuck spell** is a run of steps in which [`StuckDetector`] says stuck; its
/// **onset** is the step the robot's stillness began ([`STUCK_WINDOW_STEPS`] − 1 steps before
/// the detector first says so). A spell is **lasting** when the detector says stuck for at
/// least `lasting_steps` steps in a row, or until the run ends.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotTally {
    /// Distance its centre moved, summed step to step, metres.
    pub distance_m: f64,
    /// Collisions counted for its behaviours.
    pub collisions: u64,
    /// Steps in which it moved at least [`MOVING_MIN_MM`].
    pub moving_steps: u32,
    /// Steps the detector said stuck.
    pub stuck_steps: u32,
    /// Distance moved in the run's last window, metres.
    pub last_window_distance_m: f64,
    /// Collisions in the run's last window.
    pub last_window_collisions: u64,
    /// Onset step of its first lasting stuck spell, if it had one.
    pub first_lasting_stuck_step: Option<u32>,
    /// Whether the detector said stuck at the run's last step.
    pub ends_stuck: bool,
    /// The current spell: its onset and how many steps the detector has said stuck in it.
    spell: Option<(u32, u32)>,
    lasting_steps: u32,
}

impl RobotTally {
    /// An empty record; spells of at least `lasting_steps` flagged steps are lasting.
    #[must_use]
    pub fn new(lasting_steps: u32) -> Self {
        Self {
            distance_m: 0.0,
            collisions: 0,
            moving_steps: 0,
            stuck_steps: 0,
            last_window_distance_m: 0.0,
            last_window_collisions: 0,
            first_lasting_stuck_step: None,
            ends_stuck: false,
            spell: None,
            lasting_steps: lasting_steps.max(1),
        }
    }

    /// Records step `k`: the distance moved in it (metres), the collisions counted for it,
    /// whether the detector said stuck at its end, and whether it is in the last window.
    pub fn record(&mut self, k: u32, moved_m: f64, collisions: u64, stuck: bool, last: bool) {
        self.distance_m += moved_m;
        self.collisions += collisions;
        if moved_m * 1000.0 >= MOVING_MIN_MM {
            self.moving_steps += 1;
        }
        if last {
            self.last_window_distance_m += moved_m;
            self.last_window_collisions += collisions;
        }
        self.ends_stuck = stuck;
        if stuck {
            self.stuck_steps += 1;
            let onset = k.saturating_sub(STUCK_WINDOW_STEPS as u32 - 1);
            let (onset, flagged) = self.spell.map_or((onset, 1), |(o, n)| (o, n + 1));
            self.spell = Some((onset, flagged));
            if flagged >= self.lasting_steps && self.first_lasting_stuck_step.is_none() {
                self.first_lasting_stuck_step = Some(onset);
            }
        } else {
            self.spell = None;
        }
    }

    /// Whether the detector says stuck now (at the latest step recorded).
    #[must_use]
    pub fn stuck_now(&self) -> bool {
        self.spell.is_some()
    }

    /// Closes the run: a spell still going at the end is lasting.
    pub fn finish(&mut self) {
        if let Some((onset, _)) = self.spell
            && self.first_lasting_stuck_step.is_none()
        {
            self.first_lasting_stuck_step = Some(onset);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sliver_of_release_is_not_a_new_collision() {
        // The picosecond case: pressed, then a 1-state release, then pressed again.
        let mut m = ContactMeter::new(500_000);
        m.sample(true, 500_000);
        m.sample(false, 1);
        m.sample(true, 500_000);
        assert_eq!(m.take().0, 1);
        // A release that holds a whole sub-step ends the contact; the next press counts.
        m.sample(false, 500_000);
        m.sample(true, 500_000);
        assert_eq!(m.take().0, 1);
    }

    #[test]
    fn a_press_shorter_than_a_substep_is_not_a_collision() {
        let mut m = ContactMeter::new(500_000);
        m.sample(true, 499_999);
        m.sample(false, 500_000);
        assert_eq!(m.take(), (0, 499_999));
    }

    #[test]
    fn counts_and_contact_time_do_not_depend_on_how_time_is_cut() {
        // The same switch history (in states) fed in pieces of 1 state, 20 ms and 19.57 ms.
        let history: [(bool, u64); 6] = [
            (false, 2_000_000),
            (true, 3_000_000),
            (false, 1_000_000),
            (true, 4_000_000),
            (false, 500_000),
            (true, 1_500_000),
        ];
        let run = |piece: u64| {
            let mut m = ContactMeter::new(400_000);
            for (pressed, len) in history {
                let mut left = len;
                while left > 0 {
                    let d = left.min(piece);
                    m.sample(pressed, d);
                    left -= d;
                }
            }
            m.take()
        };
        let reference = run(1_000);
        assert_eq!(reference, (3, 8_500_000));
        assert_eq!(run(500_000), reference);
        assert_eq!(run(489_130), reference);
    }

    #[test]
    fn a_robot_that_drives_but_does_not_move_is_stuck_after_the_window() {
        let mut s = StuckDetector::default();
        for k in 0..STUCK_WINDOW_STEPS {
            let stuck = s.record(1e-6, true);
            assert_eq!(stuck, k + 1 == STUCK_WINDOW_STEPS, "{k}");
        }
        // One step of real motion frees it for a window.
        assert!(!s.record(0.01, true));
        // A robot whose motors are off is not stuck, however still.
        let mut idle = StuckDetector::default();
        for _ in 0..2 * STUCK_WINDOW_STEPS {
            assert!(!idle.record(0.0, false));
        }
    }

    #[test]
    fn a_tally_finds_the_first_lasting_spell_and_its_onset() {
        let mut t = RobotTally::new(50);
        let w = STUCK_WINDOW_STEPS as u32;
        // Steps 0..200 free; a short spell flagged at 200..230 (onset 101); free again; a
        // long one flagged from 400 on (onset 301), lasting once flagged 50 times.
        for k in 0..600u32 {
            let stuck = (200..230).contains(&k) || k >= 400;
            t.record(
                k,
                if stuck { 0.0 } else { 0.05 },
                u64::from(k == 10),
                stuck,
                k >= 500,
            );
        }
        assert_eq!(t.first_lasting_stuck_step, Some(400 - (w - 1)));
        assert!(t.ends_stuck);
        assert_eq!(t.stuck_steps, 30 + 200);
        assert_eq!(t.collisions, 1);
        assert_eq!(t.last_window_collisions, 0);
        assert_eq!(t.moving_steps, 600 - 230);
        assert!((t.distance_m - 0.05 * 370.0).abs() < 1e-9);
        assert_eq!(t.last_window_distance_m, 0.0);
        // A spell too short to be lasting still is, when the run ends in it.
        let mut end = RobotTally::new(500);
        for k in 0..300u32 {
            end.record(k, 0.0, 0, k >= 250, false);
        }
        assert_eq!(end.first_lasting_stuck_step, None);
        end.finish();
        assert_eq!(end.first_lasting_stuck_step, Some(250 - (w - 1)));
        // A robot never stuck has none.
        let mut free = RobotTally::new(50);
        free.record(0, 0.06, 0, false, true);
        free.finish();
        assert_eq!(
            (free.first_lasting_stuck_step, free.ends_stuck),
            (None, false)
        );
    }
}
