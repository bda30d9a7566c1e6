//! The memory array of one 24LC256: its bytes and the bits wear has stuck, stored page by page
//! and only for the pages that differ from a fresh chip.
//!
//! A fresh chip reads erased (H'FF) everywhere and has no stuck bit. A robot's firmware uses a
//! few pages of the 512, so a swarm of thousands of robots would otherwise hold 64 KB per chip
//! of H'FF and zero masks (docs/performance.md, "Memory"). A page gets storage of its own at
//! its first write (a programmer's load, a completed or cut write cycle, a bit stuck by wear);
//! reading a page without storage gives what the fresh chip holds. What the array holds is the same
//! either way: the store changes where bytes live, never their values.

use crate::datasheet::{ARRAY_BYTES, ERASED_BYTE, PAGE_BYTES, PAGES};

/// One page's bytes and stuck-bit masks (bit set: the cell keeps its value whatever is
/// written).
#[derive(Clone, Debug)]
struct Page {
    data: [u8; PAGE_BYTES],
    stuck: [u8; PAGE_BYTES],
}

impl Page {
    const FRESH: Page = Page {
        data: [ERASED_BYTE; PAGE_BYTES],
        stuck: [0; PAGE_BYTES],
    };
}

/// Slot number of a page without storage in [`Cells::slot`].
const FRESH_PAGE: u16 = u16::MAX;

/// The array, page by page (see the module docs).
#[derive(Clone, Debug)]
pub(crate) struct Cells {
    /// Per page, its place in `pages`, or [`FRESH_PAGE`].
    slot: Vec<u16>,
    /// The pages with storage, in the order they got it.
    pages: Vec<Page>,
}

/// Page number and offset within it of a byte address (taken modulo the array's size).
#[inline]
fn split(address: usize) -> (usize, usize) {
    let a = address % ARRAY_BYTES;
    (a / PAGE_BYTES, a % PAGE_BYTES)
}

impl Cells {
    /// A fresh chip's array: every byte erased, no bit stuck, no storage.
    pub(crate) fn fresh() -> Cells {
        Cells {
            slot: vec![FRESH_PAGE; PAGES],
            pages: Vec::new(),
        }
    }

    /// The page's storage, if it has any.
    #[inline]
    fn page(&self, page: usize) -> Option<&Page> {
        match self.slot[page] {
            FRESH_PAGE => None,
            s => Some(&self.pages[usize::from(s)]),
        }
    }

    /// The page's storage, given to it (as a fresh page) if it had none.
    fn page_mut(&mut self, page: usize) -> &mut Page {
        if self.slot[page] == FRESH_PAGE {
            // At most PAGES (512) pages ever get storage, so the slot fits a u16 below
            // FRESH_PAGE.
            self.slot[page] = self.pages.len() as u16;
            self.pages.push(Page::FRESH);
        }
        &mut self.pages[usize::from(self.slot[page])]
    }

    /// The byte at `address`.
    #[inline]
    pub(crate) fn byte(&self, address: usize) -> u8 {
        let (p, i) = split(address);
        self.page(p).map_or(ERASED_BYTE, |pg| pg.data[i])
    }

    /// Bytes from `address` on into `buf` (the range must lie inside the array).
    pub(crate) fn read(&self, address: usize, buf: &mut [u8]) {
        for (k, b) in buf.iter_mut().enumerate() {
            *b = self.byte(address + k);
        }
    }

    /// The stuck-bit mask of the byte at `address`.
    #[cfg(test)]
    pub(crate) fn stuck(&self, address: usize) -> u8 {
        let (p, i) = split(address);
        self.page(p).map_or(0, |pg| pg.stuck[i])
    }

    /// Stores `value` at `address` where no bit is stuck; stuck bits keep their value. A write
    /// of the byte already there gives a fresh page no storage.
    #[inline]
    pub(crate) fn write(&mut self, address: usize, value: u8) {
        let (p, i) = split(address);
        if self.page(p).is_none() && value == ERASED_BYTE {
            return;
        }
        let pg = self.page_mut(p);
        let m = pg.stuck[i];
        pg.data[i] = (value & !m) | (pg.data[i] & m);
    }

    /// Sticks bit `bit` of the byte at `address` at its present value.
    pub(crate) fn stick(&mut self, address: usize, bit: u8) {
        let (p, i) = split(address);
        self.page_mut(p).stuck[i] |= 1 << bit;
    }

    /// Number of stuck bits over the whole array.
    pub(crate) fn stuck_bit_count(&self) -> u64 {
        self.pages
            .iter()
            .flat_map(|pg| pg.stuck.iter())
            .map(|m| u64::from(m.count_ones()))
            .sum()
    }

    /// Pages with storage of their own (for the memory figures).
    #[cfg(test)]
    pub(crate) fn stored_pages(&self) -> usize {
        self.pages.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same operations on the page store and on a flat copy of the array (bytes and masks)
    /// give the same bytes and masks everywhere.
    #[test]
    fn the_store_holds_what_a_flat_array_holds() {
        let mut cells = Cells::fresh();
        let mut flat = vec![ERASED_BYTE; ARRAY_BYTES];
        let mut flat_stuck = vec![0u8; ARRAY_BYTES];
        // A small LCG: the test needs varied operations, not a project stream.
        let mut x: u64 = 0x2545_F491_4F6C_DD1D;
        let mut next = || {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            x >> 33
        };
        for _ in 0..20_000 {
            let r = next();
            // Addresses crowd into a few pages so that stuck bits and rewrites meet.
            let a = ((r as usize % 6) * 4_099 + (next() as usize % 300)) % ARRAY_BYTES;
            match r % 7 {
                0 => {
                    let bit = (next() % 8) as u8;
                    cells.stick(a, bit);
                    flat_stuck[a] |= 1 << bit;
                }
                1 => {
                    cells.write(a, ERASED_BYTE);
                    let m = flat_stuck[a];
                    flat[a] = (ERASED_BYTE & !m) | (flat[a] & m);
                }
                _ => {
                    let v = next() as u8;
                    cells.write(a, v);
                    let m = flat_stuck[a];
                    flat[a] = (v & !m) | (flat[a] & m);
                }
            }
        }
        for a in 0..ARRAY_BYTES {
            assert_eq!(cells.byte(a), flat[a], "byte at {a:#06x}");
            assert_eq!(cells.stuck(a), flat_stuck[a], "mask at {a:#06x}");
        }
        let stuck: u64 = flat_stuck.iter().map(|m| u64::from(m.count_ones())).sum();
        assert_eq!(cells.stuck_bit_count(), stuck);
        let mut buf = [0u8; 100];
        cells.read(4_050, &mut buf);
        assert_eq!(&buf[..], &flat[4_050..4_150]);
        assert!(
            cells.stored_pages() <= 6 * 6,
            "{} pages",
            cells.stored_pages()
        );
    }

    #[test]
    fn a_fresh_array_reads_erased_and_stores_nothing() {
        let mut cells = Cells::fresh();
        cells.write(100, ERASED_BYTE);
        assert_eq!(cells.stored_pages(), 0);
        assert_eq!(cells.byte(100), ERASED_BYTE);
        assert_eq!(cells.stuck(ARRAY_BYTES - 1), 0);
        cells.write(ARRAY_BYTES - 1, 0x12);
        assert_eq!(cells.stored_pages(), 1);
        assert_eq!(cells.byte(ARRAY_BYTES - 1), 0x12);
        assert_eq!(cells.byte(ARRAY_BYTES - 2), ERASED_BYTE);
    }
}
