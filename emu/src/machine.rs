//! A simple H8/3052F system for running programs on the core: 512 KB flash holding an
//! S-record image, 8 KB RAM, SCI1 as console, and every other I/O register reading 0 and
//! ignoring writes. It implements [`Bus`] with the access states of [`crate::memmap`], and is
//! what `h8swarm emu` runs images on.

use crate::bus::Bus;
use crate::memmap::{ADDRESS_MASK, Area, RAM_BYTES, RAM_START, ROM_BYTES, ROM_END};
use crate::periph::sci::Sci;
use crate::srec::SrecImage;

/// Why an image cannot be loaded into the flash.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LoadError {
    /// Data outside the on-chip flash.
    #[error(
        "image data at H'{address:06X}..H'{end:06X} lies outside the on-chip flash H'000000-H'{rom_end:06X}; an S-record image may only load flash",
        end = .address.wrapping_add(*.len as u32).wrapping_sub(1),
        rom_end = ROM_END
    )]
    OutsideFlash {
        /// First address of the offending chunk.
        address: u32,
        /// Its length in bytes.
        len: usize,
    },
    /// No data at all.
    #[error("the image holds no data records")]
    Empty,
}

/// The simple system: memories, SCI1 and the clock.
#[derive(Clone, Debug)]
pub struct Machine {
    rom: Vec<u8>,
    ram: Vec<u8>,
    sci: Sci,
    now: u64,
}

impl Default for Machine {
    fn default() -> Self {
        Self::new()
    }
}

impl Machine {
    /// A machine with erased flash (H'FF), zeroed RAM, SCI1 after reset and the clock at 0.
    #[must_use]
    pub fn new() -> Self {
        Machine {
            rom: vec![0xff; ROM_BYTES as usize],
            ram: vec![0; RAM_BYTES as usize],
            sci: Sci::new(),
            now: 0,
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
        if image.data_len() == 0 {
            return Err(LoadError::Empty);
        }
        for c in &image.chunks {
            let end = u64::from(c.address) + c.data.len() as u64;
            if end > u64::from(ROM_BYTES) {
                return Err(LoadError::OutsideFlash {
                    address: c.address,
                    len: c.data.len(),
                });
            }
        }
        for c in &image.chunks {
            let a = c.address as usize;
            self.rom[a..a + c.data.len()].copy_from_slice(&c.data);
        }
        Ok(())
    }

    /// Writes bytes into flash or RAM directly (no bus cycle, no time): test set-up.
    /// Bytes at addresses outside flash and RAM are ignored.
    pub fn poke(&mut self, addr: u32, bytes: &[u8]) {
        for (i, &b) in bytes.iter().enumerate() {
            let a = addr.wrapping_add(i as u32) & ADDRESS_MASK;
            match Area::of(a) {
                Area::Rom => self.rom[a as usize] = b,
                Area::Ram => self.ram[(a - RAM_START) as usize] = b,
                _ => {}
            }
        }
    }

    /// Reads a byte of flash or RAM directly (no bus cycle, no time); other areas read H'FF.
    #[must_use]
    pub fn peek(&self, addr: u32) -> u8 {
        let a = addr & ADDRESS_MASK;
        match Area::of(a) {
            Area::Rom => self.rom[a as usize],
            Area::Ram => self.ram[(a - RAM_START) as usize],
            _ => 0xff,
        }
    }

    /// SCI1.
    #[must_use]
    pub fn sci(&self) -> &Sci {
        &self.sci
    }

    /// SCI1, mutably (to collect console output).
    pub fn sci_mut(&mut self) -> &mut Sci {
        &mut self.sci
    }

    fn io_read8(&mut self, a: u32) -> u8 {
        if Sci::decodes(a) {
            self.sci.read(a, self.now)
        } else {
            0
        }
    }

    fn io_write8(&mut self, a: u32, v: u8) {
        if Sci::decodes(a) {
            self.sci.write(a, v, self.now);
        }
    }
}

impl Bus for Machine {
    #[inline]
    fn now(&self) -> u64 {
        self.now
    }

    #[inline]
    fn read8(&mut self, addr: u32) -> u8 {
        let a = addr & ADDRESS_MASK;
        let area = Area::of(a);
        self.now += u64::from(area.byte_states());
        match area {
            Area::Rom => self.rom[a as usize],
            Area::Ram => self.ram[(a - RAM_START) as usize],
            Area::Io => self.io_read8(a),
            Area::Unmapped => 0xff,
        }
    }

    #[inline]
    fn read16(&mut self, addr: u32) -> u16 {
        let a = addr & ADDRESS_MASK & !1;
        match Area::of(a) {
            Area::Rom => {
                self.now += u64::from(Area::Rom.word_states());
                let i = a as usize;
                u16::from_be_bytes([self.rom[i], self.rom[i + 1]])
            }
            Area::Ram => {
                self.now += u64::from(Area::Ram.word_states());
                let i = (a - RAM_START) as usize;
                u16::from_be_bytes([self.ram[i], self.ram[i + 1]])
            }
            Area::Io => {
                // Two byte cycles on the 8-bit bus, upper byte first.
                self.now += u64::from(Area::Io.byte_states());
                let hi = self.io_read8(a);
                self.now += u64::from(Area::Io.byte_states());
                let lo = self.io_read8(a + 1);
                u16::from_be_bytes([hi, lo])
            }
            Area::Unmapped => {
                self.now += u64::from(Area::Unmapped.word_states());
                0xffff
            }
        }
    }

    #[inline]
    fn write8(&mut self, addr: u32, value: u8) {
        let a = addr & ADDRESS_MASK;
        let area = Area::of(a);
        self.now += u64::from(area.byte_states());
        match area {
            Area::Ram => self.ram[(a - RAM_START) as usize] = value,
            Area::Io => self.io_write8(a, value),
            // Flash is not writable through the bus; nothing answers unmapped addresses.
            Area::Rom | Area::Unmapped => {}
        }
    }

    #[inline]
    fn write16(&mut self, addr: u32, value: u16) {
        let a = addr & ADDRESS_MASK & !1;
        let [hi, lo] = value.to_be_bytes();
        match Area::of(a) {
            Area::Ram => {
                self.now += u64::from(Area::Ram.word_states());
                let i = (a - RAM_START) as usize;
                self.ram[i] = hi;
                self.ram[i + 1] = lo;
            }
            Area::Io => {
                self.now += u64::from(Area::Io.byte_states());
                self.io_write8(a, hi);
                self.now += u64::from(Area::Io.byte_states());
                self.io_write8(a + 1, lo);
            }
            area @ (Area::Rom | Area::Unmapped) => self.now += u64::from(area.word_states()),
        }
    }

    #[inline]
    fn internal(&mut self, states: u32) {
        self.now += u64::from(states);
    }

    #[inline]
    fn pending_irq(&self) -> Option<u8> {
        self.sci.pending_irq(self.now)
    }

    fn sleep_until_irq(&mut self, deadline: u64) -> bool {
        if self.pending_irq().is_some() {
            return true;
        }
        match self.sci.next_irq_time(self.now) {
            Some(t) if t <= deadline => {
                self.now = self.now.max(t);
                self.sci.sync(self.now);
                true
            }
            _ => {
                if deadline != u64::MAX {
                    self.now = self.now.max(deadline);
                    self.sci.sync(self.now);
                }
                false
            }
        }
    }
}
