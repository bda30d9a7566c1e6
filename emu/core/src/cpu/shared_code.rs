//! Decode tables shared by CPUs that run the same ROM image.
//!
//! A CPU's decode tables (`Cpu::cache`, the decoded instruction, and `Cpu::fast`, its fast-path
//! handler, one of each per halfword of ROM) are a function of the ROM's bytes alone. A swarm's
//! firmware robots all run one image, so the tables each robot would fill as it reaches its
//! code are the same tables: about 44 bytes a halfword, 145 KB for the robot firmware, per
//! robot. [`SharedCode`] decodes an image's range once, and [`Cpu::adopt_shared_code`] hands it
//! to any number of CPUs behind reference counts.
//!
//! Nothing a CPU does changes with sharing: a slot holds what the CPU would have decoded from
//! the same bytes, and a CPU that must store a slot of its own (an address the shared tables
//! leave empty) copies the tables first, as the flash's pages are copied on a write. Bytes that
//! differ from robot to robot (a configuration block poked over the image) are named when the
//! tables are built, and no slot whose instruction covers one of them is filled: each CPU
//! decodes those from its own flash.

use std::ops::Range;
use std::sync::Arc;

use super::decode::{Decoded, WordSource, decode};
use super::fast::Slot;
use super::{Cpu, EMPTY_SLOT};
use crate::memmap::Area;

/// An image's decoded instructions and fast-path handlers, for CPUs that share them (see the
/// module docs). Cloning shares the tables.
#[derive(Clone, Debug)]
pub struct SharedCode {
    cache: Arc<[Decoded]>,
    fast: Arc<[Slot]>,
}

/// Words from a read function, from one address on.
struct ReadWords<F: Fn(u32) -> u16> {
    read16: F,
    addr: u32,
}

impl<F: Fn(u32) -> u16> WordSource for ReadWords<F> {
    fn next_word(&mut self) -> Option<u16> {
        if Area::of(self.addr) != Area::Rom {
            return None;
        }
        let w = (self.read16)(self.addr);
        self.addr += 2;
        Some(w)
    }
}

impl SharedCode {
    /// Decodes the instruction at every even address of `range` (clipped to the ROM) from the
    /// words `read16` gives (the big-endian word at an even ROM address), leaving empty every
    /// slot whose instruction is undefined, runs past the ROM, or covers a byte of `varies`
    /// (bytes that may differ between the CPUs sharing the tables).
    #[must_use]
    pub fn decode_rom(read16: impl Fn(u32) -> u16, range: Range<u32>, varies: Range<u32>) -> Self {
        let start = range.start & !1;
        let end = range.end.min(crate::memmap::ROM_BYTES);
        let len = if end > start {
            (end as usize).div_ceil(2)
        } else {
            0
        };
        let mut cache = vec![EMPTY_SLOT; len];
        let mut fast = vec![Slot::EMPTY; len];
        let mut words = ReadWords { read16, addr: 0 };
        for pc in (start..end).step_by(2) {
            words.addr = pc;
            let Ok(d) = decode(&mut words) else {
                continue;
            };
            let bytes = pc..pc + d.len_bytes();
            if bytes.start < varies.end && varies.start < bytes.end {
                continue;
            }
            let idx = (pc >> 1) as usize;
            cache[idx] = d;
            fast[idx] = Slot::new(d, pc);
        }
        SharedCode {
            cache: cache.into(),
            fast: fast.into(),
        }
    }

    /// Slots that hold an instruction.
    #[must_use]
    pub fn filled(&self) -> usize {
        self.cache.iter().filter(|d| d.words != 0).count()
    }
}

impl Cpu {
    /// Takes `code` as this CPU's decode tables, valid while the bus shows `token` as its
    /// [`crate::bus::FastPathHints::code_generation`]: the caller promises that `code` was
    /// decoded from the bytes the bus's ROM holds under that token (outside the bytes `code`
    /// was told vary). At the next change of token the CPU empties its tables as usual and
    /// fills tables of its own.
    pub fn adopt_shared_code(&mut self, code: &SharedCode, token: u64) {
        self.flush_decode_cache();
        self.cache = Arc::clone(&code.cache);
        self.fast = Arc::clone(&code.fast);
        self.code_generation = token;
    }

    /// Whether this CPU's decode tables are shared with `code` (not copied).
    #[must_use]
    pub fn shares_code(&self, code: &SharedCode) -> bool {
        Arc::ptr_eq(&self.cache, &code.cache) && Arc::ptr_eq(&self.fast, &code.fast)
    }
}

/// Slot `idx` of `table`, made this table's own (copied first if it is shared) and grown with
/// `empty` slots to hold it (to a power of two, so filling a table costs amortised O(1) a
/// slot).
pub(super) fn own_slot<T: Copy>(table: &mut Arc<[T]>, idx: usize, empty: T) -> &mut T {
    if table.len() <= idx {
        let len = (idx + 1).next_power_of_two();
        *table = table
            .iter()
            .copied()
            .chain(std::iter::repeat_n(empty, len - table.len()))
            .collect();
    }
    &mut Arc::make_mut(table)[idx]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::decode::SliceSource;

    /// A ROM of `bytes` at address 0.
    fn reader(bytes: &[u8]) -> impl Fn(u32) -> u16 + '_ {
        move |a| {
            let i = a as usize;
            u16::from_be_bytes([
                bytes.get(i).copied().unwrap_or(0xFF),
                bytes.get(i + 1).copied().unwrap_or(0xFF),
            ])
        }
    }

    #[test]
    fn slots_hold_what_decoding_each_address_gives_except_where_bytes_vary() {
        // mov.l #h'12345678,er1 (3 words); nop; mov.b r0l,r1h; rts; nop.
        let rom = [
            0x7A, 0x01, 0x12, 0x34, 0x56, 0x78, 0x00, 0x00, 0x0C, 0x81, 0x54, 0x70, 0x00, 0x00,
        ];
        let code = SharedCode::decode_rom(reader(&rom), 0..rom.len() as u32, 8..9);
        for pc in (0..rom.len() as u32).step_by(2) {
            let idx = (pc >> 1) as usize;
            let plain = decode(&mut SliceSource::new(&rom[pc as usize..]));
            let got = code.cache[idx];
            let covers_varying = plain
                .as_ref()
                .is_ok_and(|d| pc < 9 && 8 < pc + d.len_bytes());
            match plain {
                Ok(d) if !covers_varying => {
                    assert_eq!(got, d, "slot at H'{pc:X}");
                    assert_eq!(code.fast[idx].words, d.words);
                }
                _ => {
                    assert_eq!(got.words, 0, "slot at H'{pc:X} should be empty");
                    assert_eq!(code.fast[idx].words, 0);
                }
            }
        }
        // The MOV.L's slot and the NOP's are filled; the MOV.B at 8 covers the varying byte.
        assert_eq!(code.cache[0].words, 3);
        assert_eq!(code.cache[3].words, 1);
        assert_eq!(code.cache[4].words, 0);
    }

    #[test]
    fn a_cpu_writing_a_slot_copies_shared_tables_and_grows_its_own() {
        let shared: Arc<[u32]> = vec![1, 2, 3].into();
        let mut mine = Arc::clone(&shared);
        *own_slot(&mut mine, 1, 0) = 20;
        assert_eq!(&*shared, &[1, 2, 3], "the shared table is untouched");
        assert_eq!(&*mine, &[1, 20, 3]);
        *own_slot(&mut mine, 5, 0) = 6;
        assert_eq!(&*mine, &[1, 20, 3, 0, 0, 6, 0, 0]);
        let before = Arc::as_ptr(&mine);
        *own_slot(&mut mine, 7, 0) = 8;
        assert_eq!(
            Arc::as_ptr(&mine),
            before,
            "a table of its own is written in place"
        );
    }
}
