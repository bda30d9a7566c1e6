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
}
