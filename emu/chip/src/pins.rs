//! The pins of the H8/3052F as the world outside the chip drives them: the [`Board`] trait,
//! which answers for the input pins the chip samples and takes what it drives on its
//! open-drain port-4 pins, and [`NullBoard`], nothing connected.
//!
//! The chip knows its pins, not the parts on them: what sits on a pin (a sensor, a bumper, an
//! EEPROM) is the board layer's business (`robot_board::wiring`, `robot_board::board`).

/// The robot outside the chip, as the MCU's pins see it.
///
/// Every instant a board is given is not earlier than one it was given before and not later
/// than the MCU's clock. The port-4 methods, the event, the log and the power hooks have
/// defaults for a board with nothing on port 4 and no parts that keep time of their own.
pub trait Board {
    /// Volts on analog input ANn at `now_states` (called at each conversion's sampling instant).
    fn analog_volts(&mut self, channel: u8, now_states: u64) -> f64;
    /// Levels of the port-2 input pins (bit n = P2.n) at `now_states`: 0 where something pulls
    /// the pin low (a pressed bumper), 1 where nothing does — such a pin reads high only with
    /// its on-chip pull-up enabled (P2PCR), as the robot's bumpers are wired (`robot_board::wiring`).
    fn port2_pins(&mut self, now_states: u64) -> u8;

    /// The port-4 pins the chip pulls low from `now_states` on (bit n = P4.n: an output bit
    /// whose latch is 0, [`crate::periph::ports::Port::driven_low`]), told at every write to
    /// P4DDR or P4DR. Port 4 is used open-drain (docs/design.md §3.6): a pin is pulled low or
    /// released, never driven high. Default: nothing listens.
    fn port4_drive(&mut self, _pulled_low: u8, _now_states: u64) {}

    /// Levels of the port-4 lines at `now_states` as the outside leaves them (bit n = P4.n): 0
    /// where something holds the line low (a part on it, or the line's wired AND with the
    /// chip's own pull), 1 where nothing does — a released line reads high only through its
    /// on-chip pull-up (P4PCR). Default: nothing connected, every line released (0xFF), so
    /// the chip reads back its own levels.
    fn port4_pins(&mut self, _now_states: u64) -> u8 {
        0xFF
    }

    /// What the outside drives on the pins of port `port` at `now_states`: the board's side of
    /// ports 1, 3, 5–9, A and B (ports 2 and 4 have their own methods above). The pins it does
    /// not drive read high through a pull-up, else float (read 0); an output pin of the chip
    /// reads its latch whatever the board says. What a board drives is a function of time the
    /// chip may ask about for any instant since the board was last synchronised
    /// ([`Board::sync`]), in order; it changes only at the instants
    /// [`Board::next_pin_change`] gives. Default: nothing connected ([`ExternalPins::NONE`]).
    fn port_pins(&self, _port: PortId, _now_states: u64) -> ExternalPins {
        ExternalPins::NONE
    }

    /// The first instant after `now_states` at which [`Board::port_pins`] changes for any
    /// port, if it will: the chip catches its IRQ inputs up to each such instant (an edge is
    /// never missed) and wakes a sleeping CPU for an enabled IRQ. Default: never.
    fn next_pin_change(&self, _now_states: u64) -> Option<u64> {
        None
    }

    /// The first instant after `now_states` at which the board's own parts change something
    /// without the chip (an EEPROM's write cycle ending), if one is scheduled. The MCU counts
    /// it among its events ([`crate::mcu::Mcu::next_event`]) and fast-forwards an idle loop
    /// only while there is none. Default: none.
    fn next_event_states(&self, _now_states: u64) -> Option<u64> {
        None
    }

    /// Brings the board's own parts up to `now_states` (the MCU's [`crate::mcu::Mcu::sync`]).
    /// Default: nothing to do.
    fn sync(&mut self, _now_states: u64) {}

    /// The latest instant the board's own parts have been brought to (never later than the
    /// MCU's clock): a pin trace takes the board's logged changes whole up to here. Default:
    /// 0, no time of its own.
    fn now_states(&self) -> u64 {
        0
    }

    /// Starts (`true`) or stops (`false`) logging each change of the port-4 line levels with
    /// its instant, for a pin trace ([`crate::trace`]). Stopping discards what was not taken.
    /// Default: no log (the lines never change by themselves).
    fn set_pin_log(&mut self, _on: bool) {}

    /// The port-4 line changes logged since the last call, in time order: (instant, levels
    /// from then on, as [`Board::port4_pins`] reads them). Default: none.
    fn take_pin_log(&mut self) -> Vec<(u64, u8)> {
        Vec::new()
    }

    /// The robot's power is cut at `now_states` (the MCU's [`crate::mcu::Mcu::power_cut`]):
    /// the board's parts lose power. Default: nothing to do.
    fn power_cut(&mut self, _now_states: u64) {}

    /// The robot's power comes back at `now_states` (the MCU's
    /// [`crate::mcu::Mcu::power_on`]). Default: nothing to do.
    fn power_on(&mut self, _now_states: u64) {}
}

/// A board with nothing connected: every analog input at 0 V, every port-2 and port-4 pin
/// released (high with its pull-up; the chip reads back its own levels on port 4, so an I²C
/// transfer bit-banged there gets no ACK). What the chip's [`crate::machine::Machine`] runs
/// machine code with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NullBoard;

impl Board for NullBoard {
    fn analog_volts(&mut self, _channel: u8, _now_states: u64) -> f64 {
        0.0
    }

    fn port2_pins(&mut self, _now_states: u64) -> u8 {
        0xFF
    }
}

/// One of the chip's eleven I/O ports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum PortId {
    /// Port 1 (address bus A7–A0 in the expanded modes).
    P1,
    /// Port 2 (the robot's bumpers).
    P2,
    /// Port 3.
    P3,
    /// Port 4 (the robot's EEPROM bus).
    P4,
    /// Port 5 (P5.0–3).
    P5,
    /// Port 6 (P6.0–6).
    P6,
    /// Port 7 (input only; the analog inputs AN0–AN7).
    P7,
    /// Port 8 (P8.0–4; IRQ0–IRQ3 on P8.0–3).
    P8,
    /// Port 9 (P9.0–5; the SCIs' pins, IRQ4/IRQ5 on P9.4–5).
    P9,
    /// Port A (the ITU's TIOCA0–2, the robot's motor PWM).
    PA,
    /// Port B (TIOCA3/TIOCA4, the robot's H-bridge inputs).
    PB,
}

/// What the outside drives on a port's pins ([`Board::port_pins`]): where `driven` has a 1,
/// the pin is held at the level of the same bit of `levels`; the other pins are left alone (an
/// input pin then reads high only through its pull-up, else floats and reads 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExternalPins {
    /// The pins something outside drives.
    pub driven: u8,
    /// Their levels.
    pub levels: u8,
}

impl ExternalPins {
    /// Nothing connected.
    pub const NONE: ExternalPins = ExternalPins {
        driven: 0,
        levels: 0,
    };
}
