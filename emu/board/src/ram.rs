//! The 8 KB of on-chip RAM as a budget: the controller's state placed item by item.
//!
//! Items are placed upwards from H'FFDF10 in the order given, each on an even address (the
//! H8/300H accesses words and longwords at even addresses only); the stack grows down from the
//! top, H'FFFF10, and is placed as the last item so that the map shows what is left. An item
//! that does not fit is an error naming it, its size and by how much it overflows.

use std::fmt;

use h8300h::memmap::{RAM_BYTES, RAM_END, RAM_START};

/// One placed item.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Placed {
    /// What the item holds.
    pub name: String,
    /// Its first address.
    pub addr: u32,
    /// Its size in bytes (as asked for, before alignment).
    pub bytes: u32,
}

/// An item that does not fit in the on-chip RAM.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "RAM overflow: item `{item}` ({bytes} bytes) placed at H'{addr:06X} needs {over_by} bytes more than the {capacity}-byte on-chip RAM (H'{start:06X}-H'{end:06X}) holds; {used_before} bytes were already used by earlier items",
    capacity = RAM_BYTES,
    start = RAM_START,
    end = RAM_END
)]
pub struct RamOverflow {
    /// The item that did not fit.
    pub item: String,
    /// Its size.
    pub bytes: u32,
    /// Where it would have started.
    pub addr: u32,
    /// Bytes used by the items before it (alignment included).
    pub used_before: u32,
    /// How many bytes past the end of RAM it would reach.
    pub over_by: u32,
}

/// The RAM budget with the items placed so far.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RamMap {
    items: Vec<Placed>,
    used: u32,
}

impl RamMap {
    /// An empty map.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Places `bytes` bytes for `name` at the next even address.
    ///
    /// # Errors
    /// [`RamOverflow`] when the item would reach past the end of the on-chip RAM.
    pub fn place(&mut self, name: impl Into<String>, bytes: u32) -> Result<u32, RamOverflow> {
        let name = name.into();
        let offset = self.used.next_multiple_of(2);
        let addr = RAM_START + offset;
        let end = u64::from(offset) + u64::from(bytes);
        if end > u64::from(RAM_BYTES) {
            return Err(RamOverflow {
                item: name,
                bytes,
                addr,
                used_before: self.used,
                over_by: u32::try_from(end - u64::from(RAM_BYTES)).unwrap_or(u32::MAX),
            });
        }
        self.items.push(Placed { name, addr, bytes });
        self.used = offset + bytes;
        Ok(addr)
    }

    /// The items in placement order.
    #[must_use]
    pub fn items(&self) -> &[Placed] {
        &self.items
    }

    /// Bytes used, alignment padding included.
    #[must_use]
    pub const fn used(&self) -> u32 {
        self.used
    }

    /// Bytes left.
    #[must_use]
    pub const fn free(&self) -> u32 {
        RAM_BYTES - self.used
    }
}

impl fmt::Display for RamMap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for item in &self.items {
            writeln!(f, "H'{:06X} {:>6}  {}", item.addr, item.bytes, item.name)?;
        }
        write!(
            f,
            "used {} of {} bytes, {} free",
            self.used,
            RAM_BYTES,
            self.free()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_are_placed_upwards_on_even_addresses() {
        let mut m = RamMap::new();
        assert_eq!(m.place("a", 3).unwrap(), RAM_START);
        assert_eq!(m.place("b", 2).unwrap(), RAM_START + 4);
        assert_eq!(m.used(), 6);
        assert_eq!(m.free(), 8192 - 6);
        assert_eq!(m.items()[1].name, "b");
    }

    #[test]
    fn overflow_names_the_item_and_the_excess() {
        let mut m = RamMap::new();
        m.place("stack", 100).unwrap();
        let err = m.place("weights w (i16, N x M)", 8100).unwrap_err();
        assert_eq!(err.item, "weights w (i16, N x M)");
        assert_eq!(err.over_by, 100 + 8100 - 8192);
        let text = err.to_string();
        assert!(text.contains("weights w (i16, N x M)"), "{text}");
        assert!(text.contains("needs 8 bytes more"), "{text}");
        // A full map still accepts nothing more, and an exact fit is fine.
        let mut m = RamMap::new();
        assert!(m.place("all", 8192).is_ok());
        assert!(m.place("one more", 1).is_err());
    }
}
