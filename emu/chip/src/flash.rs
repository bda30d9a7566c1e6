//! The on-chip flash (512 KB), held in 1 KB pages that robots running the same image share.
//!
//! Every robot of a swarm runs the same image; a copy per robot would make a swarm of 10 000
//! firmware robots hold 5 GB of identical bytes. [`Flash`] keeps the array as pages behind
//! reference counts: an image is programmed once into a [`Flash`] and each robot's MCU takes a
//! clone of it (the page table, 4 KB). A write to a page (a configuration block poked over the
//! image, a debugger's write) copies that page for the writer alone, so what each MCU reads is
//! exactly what its own writes made of the image: sharing changes where bytes live, never
//! their values. Erased pages (H'FF) are one page shared by all.

use std::fmt;
use std::sync::{Arc, OnceLock};

use h8300h::memmap::ROM_BYTES;
use h8300h::srec::SrecImage;

/// Bytes per shared page.
pub const FLASH_PAGE_BYTES: usize = 1024;
/// Pages in the flash.
const PAGES: usize = ROM_BYTES as usize / FLASH_PAGE_BYTES;

type Page = [u8; FLASH_PAGE_BYTES];

/// The erased page every unprogrammed page of every flash points to.
fn erased_page() -> Arc<Page> {
    static ERASED: OnceLock<Arc<Page>> = OnceLock::new();
    Arc::clone(ERASED.get_or_init(|| Arc::new([0xFF; FLASH_PAGE_BYTES])))
}

/// The flash array as shared pages (see the module docs). Cloning copies the page table, not
/// the pages.
#[derive(Clone)]
pub struct Flash {
    pages: Box<[Arc<Page>]>,
}

impl fmt::Debug for Flash {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let erased = erased_page();
        let programmed = self
            .pages
            .iter()
            .filter(|p| !Arc::ptr_eq(p, &erased))
            .count();
        f.debug_struct("Flash")
            .field("programmed_pages", &programmed)
            .finish()
    }
}

impl Default for Flash {
    fn default() -> Self {
        Self::erased()
    }
}

impl Flash {
    /// An erased flash: H'FF everywhere.
    #[must_use]
    pub fn erased() -> Flash {
        let e = erased_page();
        Flash {
            pages: (0..PAGES).map(|_| Arc::clone(&e)).collect(),
        }
    }

    /// An erased flash with `image` programmed into it. The caller has checked that every
    /// chunk lies inside the flash ([`crate::mcu::Mcu::load_image`] does); bytes beyond it are
    /// ignored.
    #[must_use]
    pub fn with_image(image: &SrecImage) -> Flash {
        let mut f = Flash::erased();
        f.program(image);
        f
    }

    /// Programs `image`'s chunks over the present contents (bytes beyond the flash ignored).
    pub fn program(&mut self, image: &SrecImage) {
        for c in &image.chunks {
            for (i, &b) in c.data.iter().enumerate() {
                let a = c.address as usize + i;
                if a < ROM_BYTES as usize {
                    self.set(a, b);
                }
            }
        }
    }

    /// The byte at flash offset `a` (below 512 K).
    #[inline]
    #[must_use]
    pub fn byte(&self, a: usize) -> u8 {
        self.pages[a / FLASH_PAGE_BYTES][a % FLASH_PAGE_BYTES]
    }

    /// The big-endian word at the even flash offset `a` (below 512 K); both bytes lie in one
    /// page.
    #[inline]
    #[must_use]
    pub fn word(&self, a: usize) -> u16 {
        let page = &self.pages[a / FLASH_PAGE_BYTES];
        let i = (a % FLASH_PAGE_BYTES) & !1;
        u16::from_be_bytes([page[i], page[i | 1]])
    }

    /// Sets the byte at flash offset `a` (below 512 K), copying its page first if another
    /// flash shares it.
    pub fn set(&mut self, a: usize, value: u8) {
        let page = &mut self.pages[a / FLASH_PAGE_BYTES];
        if page[a % FLASH_PAGE_BYTES] != value {
            Arc::make_mut(page)[a % FLASH_PAGE_BYTES] = value;
        }
    }

    /// Pages this flash holds alone (not shared with any other flash, nor erased): what it
    /// costs in memory beyond its page table.
    #[must_use]
    pub fn own_pages(&self) -> usize {
        self.pages
            .iter()
            .filter(|p| Arc::strong_count(p) == 1)
            .count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use h8300h::srec::Chunk;

    fn image(address: u32, data: &[u8]) -> SrecImage {
        SrecImage {
            chunks: vec![Chunk {
                address,
                data: data.to_vec(),
            }],
            ..SrecImage::default()
        }
    }

    #[test]
    fn clones_share_pages_until_one_writes() {
        let mut base = Flash::with_image(&image(0x3FE, &[1, 2, 3, 4, 5]));
        assert_eq!(
            (0x3FC..0x405).map(|a| base.byte(a)).collect::<Vec<_>>(),
            [0xFF, 0xFF, 1, 2, 3, 4, 5, 0xFF, 0xFF]
        );
        assert_eq!(base.own_pages(), 2);
        assert_eq!(base.word(0x3FE), 0x0102);
        assert_eq!(base.word(0x400), 0x0304);
        let mut robot = base.clone();
        assert_eq!(robot.own_pages(), 0);
        robot.set(0x400, 9);
        assert_eq!(robot.byte(0x400), 9);
        assert_eq!(base.byte(0x400), 3, "the other flash keeps its byte");
        assert_eq!(robot.own_pages(), 1);
        // Writing the value already there copies nothing.
        base.set(0x3FE, 1);
        assert_eq!(base.own_pages(), 1);
        assert_eq!(Flash::erased().byte(ROM_BYTES as usize - 1), 0xFF);
    }
}
