//! The chip alone, for running machine code: the same [`Mcu`] as the robot's controller
//! (flash, RAM, SCI1 as console, ITU, A/D, ports, interrupt controller) with a [`NullBoard`]
//! outside it (all analog inputs at 0 V, port-2 and port-4 pins released: no EEPROMs).
//! `h8swarm emu` runs images on the robot's board instead (`robot_board::board`), so that
//! programs that use the EEPROMs find them.
//!
//! [`Machine`] is a thin wrapper that keeps the constructors the core's tests and the runner
//! use; it dereferences to [`Mcu<NullBoard>`] for everything else.

use std::ops::{Deref, DerefMut};

pub use crate::mcu::LoadError;
use crate::mcu::{Mcu, McuConfig};
use crate::pins::NullBoard;
use h8300h::bus::{Bus, FastPathHints};
use h8300h::srec::SrecImage;

/// The MCU with nothing connected outside it, at its highest φ
/// ([`crate::mcu::MAX_CLOCK_HZ`]).
#[derive(Clone, Debug)]
pub struct Machine(Mcu<NullBoard>);

impl Default for Machine {
    fn default() -> Self {
        Self::new()
    }
}

impl Machine {
    /// A machine with erased flash (H'FF), zeroed RAM, peripherals after reset and the clock
    /// at 0 (memory is allocated on first use, see [`crate::mcu`]).
    #[must_use]
    pub fn new() -> Self {
        match Mcu::new(McuConfig::default(), NullBoard) {
            Ok(m) => Machine(m),
            // The default configuration is valid: φ = the chip's highest.
            Err(e) => unreachable!("default MCU configuration rejected: {e}"),
        }
    }

    /// A machine whose flash holds `image`.
    ///
    /// # Errors
    /// [`LoadError`] if the image has data outside the flash or none at all.
    pub fn with_image(image: &SrecImage) -> Result<Self, LoadError> {
        let mut m = Self::new();
        m.load(image)?;
        Ok(m)
    }

    /// Programs `image` into the flash (nothing is written if any chunk lies outside it).
    ///
    /// # Errors
    /// [`LoadError`] if the image has data outside the flash or none at all.
    pub fn load(&mut self, image: &SrecImage) -> Result<(), LoadError> {
        self.0.load_image(image)
    }

    /// The MCU inside.
    #[must_use]
    pub fn mcu(&self) -> &Mcu<NullBoard> {
        &self.0
    }

    /// The MCU inside, mutably.
    pub fn mcu_mut(&mut self) -> &mut Mcu<NullBoard> {
        &mut self.0
    }

    /// The MCU inside, by value.
    #[must_use]
    pub fn into_mcu(self) -> Mcu<NullBoard> {
        self.0
    }
}

impl Deref for Machine {
    type Target = Mcu<NullBoard>;

    fn deref(&self) -> &Self::Target {
        &self.0
    }
}

impl DerefMut for Machine {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.0
    }
}

impl Bus for Machine {
    h8300h::forward_bus_timing!(0);
    h8300h::forward_bus_accesses!(0);
}

impl FastPathHints for Machine {
    h8300h::forward_fast_path_hints!(0);
}
