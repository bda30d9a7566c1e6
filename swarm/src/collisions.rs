//! Counting collisions and contact time from the bumpers, in clock states (where the robots go,
//! held in place or exploring, is [`crate::motion`]'s).
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

/// A robot counts as moving in a step when its centre moved at least this far between the two
/// step instants, millimetres (a reference only: a shuttler is moving every step, see
/// [`crate::motion`]). A free robot covers 44-67 mm in a 0.45 s step (a turn or straight ahead
/// at 0.15 m/s); one pressed against a wall or another body moves well under a millimetre.
pub const MOVING_MIN_MM: f64 = 5.0;

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
}
