//! The four micro-switch bumpers on port 2 (docs/design.md §3.4) and the firmware's collision counter.
//!
//! Each switch pulls its pin to ground when pressed; the H8/3052's port-2 MOS pull-ups
//! (P2PCR) hold it high when released: **active low**. Bit assignment (a choice of this crate;
//! the paper does not give the wiring):
//!
//! | pin | bumper |
//! |---|---|
//! | P2.0 | front |
//! | P2.1 | rear |
//! | P2.2 | left |
//! | P2.3 | right |
//! | P2.4–P2.7 | not connected: read 1 through their pull-ups |
//!
//! A collision is a released→pressed transition of any bumper (docs/design.md §3.4). The firmware keeps
//! the previous sample and counts one collision per sample in which at least one bumper went
//! from released to pressed (two bumpers hit in the same sample — a corner — are one collision;
//! a second bumper pressed in a later sample while the first is still held is another). No
//! contact bounce is modelled: the firmware samples once per step (0.45–0.60 s), far longer
//! than a micro-switch's few milliseconds of bounce.

/// Port-2 bit of the front bumper (P2.0; a choice of this crate).
pub const BUMPER_FRONT_BIT: u8 = 0;
/// Port-2 bit of the rear bumper (P2.1).
pub const BUMPER_REAR_BIT: u8 = 1;
/// Port-2 bit of the left bumper (P2.2).
pub const BUMPER_LEFT_BIT: u8 = 2;
/// Port-2 bit of the right bumper (P2.3).
pub const BUMPER_RIGHT_BIT: u8 = 3;
/// The port-2 bits wired to bumpers (P2.0–P2.3).
pub const BUMPER_PORT2_MASK: u8 = 0x0F;

/// One of the four bumpers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Bumper {
    /// Front bumper, P2.0.
    Front,
    /// Rear bumper, P2.1.
    Rear,
    /// Left bumper, P2.2.
    Left,
    /// Right bumper, P2.3.
    Right,
}

impl Bumper {
    /// All four, in bit order.
    pub const ALL: [Bumper; 4] = [Bumper::Front, Bumper::Rear, Bumper::Left, Bumper::Right];

    /// The port-2 bit this bumper is wired to.
    #[must_use]
    pub const fn port2_bit(self) -> u8 {
        match self {
            Bumper::Front => BUMPER_FRONT_BIT,
            Bumper::Rear => BUMPER_REAR_BIT,
            Bumper::Left => BUMPER_LEFT_BIT,
            Bumper::Right => BUMPER_RIGHT_BIT,
        }
    }
}

/// A set of bumpers (pressed ones, or newly pressed ones), as a bit mask in port-2 bit order
/// (1 = in the set; note that the *pins* are active low).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct BumperSet(u8);

impl BumperSet {
    /// No bumper.
    pub const EMPTY: BumperSet = BumperSet(0);

    /// The set from a mask in port-2 bit order (bits outside [`BUMPER_PORT2_MASK`] ignored).
    #[must_use]
    pub const fn from_mask(mask: u8) -> Self {
        BumperSet(mask & BUMPER_PORT2_MASK)
    }

    /// The set from four flags in the order front, rear, left, right.
    #[must_use]
    pub const fn from_flags(front: bool, rear: bool, left: bool, right: bool) -> Self {
        BumperSet(
            (front as u8) << BUMPER_FRONT_BIT
                | (rear as u8) << BUMPER_REAR_BIT
                | (left as u8) << BUMPER_LEFT_BIT
                | (right as u8) << BUMPER_RIGHT_BIT,
        )
    }

    /// The mask in port-2 bit order.
    #[must_use]
    pub const fn mask(self) -> u8 {
        self.0
    }

    /// Whether `bumper` is in the set.
    #[must_use]
    pub const fn contains(self, bumper: Bumper) -> bool {
        self.0 & (1 << bumper.port2_bit()) != 0
    }

    /// The set with `bumper` added.
    #[must_use]
    pub const fn with(self, bumper: Bumper) -> Self {
        BumperSet(self.0 | 1 << bumper.port2_bit())
    }

    /// Whether the set is empty.
    #[must_use]
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// How many bumpers are in the set.
    #[must_use]
    pub const fn len(self) -> u32 {
        self.0.count_ones()
    }
}

/// The port-2 input pins for the pressed bumpers: active low, P2.0–P2.3 as in the module docs,
/// unconnected P2.4–P2.7 high through their pull-ups.
#[must_use]
pub const fn port2_pins(pressed: BumperSet) -> u8 {
    !pressed.mask()
}

/// The pressed bumpers as the firmware decodes them from a port-2 read.
#[must_use]
pub const fn pressed_from_port2(pins: u8) -> BumperSet {
    BumperSet::from_mask(!pins)
}

/// The firmware's released→pressed edge detector and collision counter.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CollisionCounter {
    previous: BumperSet,
    collisions: u64,
}

impl CollisionCounter {
    /// A counter that assumes every bumper was released before the first sample, so a robot
    /// that starts pressed against a wall counts one collision at its first sample.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            previous: BumperSet::EMPTY,
            collisions: 0,
        }
    }

    /// A counter whose previous sample is the port-2 read `pins` (nothing counted for it).
    #[must_use]
    pub const fn starting_from(pins: u8) -> Self {
        Self {
            previous: pressed_from_port2(pins),
            collisions: 0,
        }
    }

    /// Feed one port-2 read; returns the bumpers that went from released to pressed since the
    /// previous read, and counts one collision if there is any.
    pub fn sample(&mut self, pins: u8) -> BumperSet {
        let pressed = pressed_from_port2(pins);
        let new = BumperSet::from_mask(pressed.mask() & !self.previous.mask());
        self.previous = pressed;
        if !new.is_empty() {
            self.collisions += 1;
        }
        new
    }

    /// Collisions counted so far.
    #[must_use]
    pub const fn collisions(&self) -> u64 {
        self.collisions
    }

    /// Read and reset the count (e.g. once per step, for collisions per step).
    pub fn take_collisions(&mut self) -> u64 {
        core::mem::take(&mut self.collisions)
    }

    /// The bumpers pressed at the previous read.
    #[must_use]
    pub const fn previous(&self) -> BumperSet {
        self.previous
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn pins_are_active_low_with_pull_ups() {
        assert_eq!(port2_pins(BumperSet::EMPTY), 0xFF);
        assert_eq!(
            port2_pins(BumperSet::EMPTY.with(Bumper::Front)),
            0b1111_1110
        );
        assert_eq!(port2_pins(BumperSet::EMPTY.with(Bumper::Rear)), 0b1111_1101);
        assert_eq!(port2_pins(BumperSet::EMPTY.with(Bumper::Left)), 0b1111_1011);
        assert_eq!(
            port2_pins(BumperSet::EMPTY.with(Bumper::Right)),
            0b1111_0111
        );
        assert_eq!(
            port2_pins(BumperSet::from_flags(true, true, true, true)),
            0xF0
        );
        // Only P2.0–P2.3 are bumpers: low upper bits (say, outputs) are not presses.
        assert_eq!(pressed_from_port2(0x0F), BumperSet::EMPTY);
    }

    #[test]
    fn edges_count_collisions() {
        let f = port2_pins(BumperSet::from_flags(true, false, false, false));
        let fl = port2_pins(BumperSet::from_flags(true, false, true, false));
        let none = port2_pins(BumperSet::EMPTY);
        let mut c = CollisionCounter::new();
        assert!(c.sample(none).is_empty());
        assert_eq!(c.sample(f), BumperSet::EMPTY.with(Bumper::Front));
        assert_eq!(c.collisions(), 1);
        // Held: no new collision.
        assert!(c.sample(f).is_empty());
        assert_eq!(c.collisions(), 1);
        // A second bumper while the first is held: a new collision.
        assert_eq!(c.sample(fl), BumperSet::EMPTY.with(Bumper::Left));
        assert_eq!(c.collisions(), 2);
        // Release (pressed→released) is not a collision.
        assert!(c.sample(none).is_empty());
        assert_eq!(c.collisions(), 2);
        // A corner hit pressing two at once: one collision.
        assert_eq!(c.sample(fl).len(), 2);
        assert_eq!(c.take_collisions(), 3);
        assert_eq!(c.collisions(), 0);
        // Starting pressed.
        assert_eq!(CollisionCounter::new().sample(f).len(), 1);
        let mut s = CollisionCounter::starting_from(f);
        assert!(s.sample(f).is_empty());
        assert_eq!(s.collisions(), 0);
    }

    proptest! {
        #[test]
        fn round_trip_and_edge_rule(a in 0u8..16, b in 0u8..16) {
            let pa = BumperSet::from_mask(a);
            let pb = BumperSet::from_mask(b);
            prop_assert_eq!(pressed_from_port2(port2_pins(pa)), pa);
            for bumper in Bumper::ALL {
                prop_assert_eq!(port2_pins(pa) & (1 << bumper.port2_bit()) == 0, pa.contains(bumper));
            }
            let mut c = CollisionCounter::starting_from(port2_pins(pa));
            let new = c.sample(port2_pins(pb));
            for bumper in Bumper::ALL {
                prop_assert_eq!(new.contains(bumper), !pa.contains(bumper) && pb.contains(bumper));
            }
            prop_assert_eq!(c.collisions(), u64::from(!new.is_empty()));
        }
    }
}
