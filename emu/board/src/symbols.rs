//! The symbol table of a firmware image: the output of `h8300-hms-nm -n` (docs/design.md §8), committed
//! beside the image as `robot.sym`.
//!
//! Each line is `ADDRESS KIND NAME` (address in hex, kind one letter as nm prints it: `T`/`t`
//! text, `D`/`d` data, `B`/`b` bss, `A` absolute, ...). GCC's H8 COFF names carry a leading
//! underscore (`_learner_forward`); lookups accept the C name with or without it. Assembler
//! locals (`.L12`) and section symbols (`.text`) are kept but are never functions.

use std::collections::HashMap;
use std::sync::Arc;

use h8300h::cpu::StackRoom;
use h8300h::memmap::{RAM_END, RAM_START};

/// One symbol.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Symbol {
    /// Its address (24 bits used).
    pub addr: u32,
    /// nm's kind letter.
    pub kind: char,
    /// The name as in the object file (`_main`).
    pub name: String,
}

impl Symbol {
    /// Whether nm marks it as code (`T`, `t`) and it names a function, not a local label or a
    /// section.
    #[must_use]
    pub fn is_function(&self) -> bool {
        matches!(self.kind, 'T' | 't') && !self.name.starts_with('.')
    }

    /// The C name: without GCC's leading underscore.
    #[must_use]
    pub fn c_name(&self) -> &str {
        self.name.strip_prefix('_').unwrap_or(&self.name)
    }
}

/// A line of a symbol file that is not `ADDRESS KIND NAME`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "symbol file line {line}: `{text}` is not `ADDRESS KIND NAME` (as `h8300-hms-nm -n` prints it, e.g. `0000082a T _learner_forward`)"
)]
pub struct SymbolError {
    /// 1-based line number.
    pub line: usize,
    /// The line.
    pub text: String,
}

/// The symbols of an image, by address and by name. Cloning is cheap: the table is shared.
#[derive(Clone, Debug, Default)]
pub struct SymbolTable {
    inner: Arc<Tables>,
}

/// What a [`SymbolTable`] shares between its clones.
#[derive(Debug, Default)]
struct Tables {
    /// Every symbol, in address order.
    symbols: Vec<Symbol>,
    /// Index into `symbols` by name (the first symbol of that name).
    by_name: HashMap<String, usize>,
    /// Functions (start address, index into `symbols`), in address order.
    functions: Vec<(u32, usize)>,
}

impl SymbolTable {
    /// Parses nm output. Blank lines are skipped.
    ///
    /// # Errors
    /// [`SymbolError`] naming the first malformed line.
    pub fn parse(text: &str) -> Result<Self, SymbolError> {
        let mut symbols = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.trim();
            if line.is_empty() {
                continue;
            }
            let bad = || SymbolError {
                line: i + 1,
                text: raw.to_string(),
            };
            let mut parts = line.split_whitespace();
            let (Some(a), Some(k), Some(name), None) =
                (parts.next(), parts.next(), parts.next(), parts.next())
            else {
                return Err(bad());
            };
            let addr = u64::from_str_radix(a, 16).map_err(|_| bad())?;
            let mut kind = k.chars();
            let (Some(kind), None) = (kind.next(), kind.next()) else {
                return Err(bad());
            };
            // A name is shown in traces and on the terminal: no control or format characters
            // (a right-to-left override would reorder what follows it).
            if name.chars().any(|c| c.is_control() || is_format_char(c)) || kind.is_control() {
                return Err(bad());
            }
            symbols.push(Symbol {
                addr: (addr & 0xFF_FFFF) as u32,
                kind,
                name: name.to_string(),
            });
        }
        symbols.sort_by_key(|s| s.addr);
        let mut by_name = HashMap::new();
        for (i, s) in symbols.iter().enumerate() {
            by_name.entry(s.name.clone()).or_insert(i);
        }
        let functions = symbols
            .iter()
            .enumerate()
            .filter(|(_, s)| s.is_function())
            .map(|(i, s)| (s.addr, i))
            .collect();
        Ok(SymbolTable {
            inner: Arc::new(Tables {
                symbols,
                by_name,
                functions,
            }),
        })
    }

    /// The stack's room the image's symbols give (see [`h8300h::cpu::stack`]): from the
    /// end of its data (`__bss_end`, else `_end`/`end`, else the on-chip RAM's start) to its
    /// stack's top (`__stack_top`, else `__stack`/`_stack`, else one past the RAM's end). The
    /// arrays a program carves above its data at boot are not in it yet: see
    /// [`SymbolTable::heap_end_pointer`].
    #[must_use]
    pub fn stack_room(&self) -> StackRoom {
        let in_ram = |a: u32| (RAM_START..=RAM_END + 1).contains(&a);
        let low = ["_bss_end", "end", "_end"]
            .iter()
            .find_map(|n| self.addr(n).filter(|&a| in_ram(a)))
            .unwrap_or(RAM_START);
        let top = ["_stack_top", "_stack", "stack"]
            .iter()
            .find_map(|n| self.addr(n).filter(|&a| in_ram(a) && a > low))
            .unwrap_or(RAM_END + 1);
        StackRoom { low, top }
    }

    /// The address of the program's `heap_end` variable, when it has one: a pointer to the end
    /// of the memory it carved above its data at boot (the robot firmware's network arrays),
    /// which raises the stack room's low end once the program has booted.
    #[must_use]
    pub fn heap_end_pointer(&self) -> Option<u32> {
        self.get("heap_end")
            .filter(|s| matches!(s.kind, 'b' | 'B' | 'd' | 'D'))
            .map(|s| s.addr)
    }

    /// The symbol called `name`: the C name (`learner_forward`) or the object file's
    /// (`_learner_forward`).
    #[must_use]
    pub fn get(&self, name: &str) -> Option<&Symbol> {
        let t = &*self.inner;
        t.by_name
            .get(name)
            .or_else(|| t.by_name.get(&format!("_{name}")))
            .map(|&i| &t.symbols[i])
    }

    /// The address of `name` (see [`SymbolTable::get`]).
    #[must_use]
    pub fn addr(&self, name: &str) -> Option<u32> {
        self.get(name).map(|s| s.addr)
    }

    /// Every symbol in address order.
    #[must_use]
    pub fn symbols(&self) -> &[Symbol] {
        &self.inner.symbols
    }

    /// The function whose code holds `pc`: the last function symbol at or below it.
    #[must_use]
    pub fn function_at(&self, pc: u32) -> Option<&Symbol> {
        let t = &*self.inner;
        let k = t.functions.partition_point(|&(a, _)| a <= pc);
        k.checked_sub(1).map(|k| &t.symbols[t.functions[k].1])
    }

    /// The first addresses of the functions, ascending (for a profile's tail calls,
    /// [`h8_3052f::profile::StackProfile::new`]).
    #[must_use]
    pub fn function_entries(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self.inner.functions.iter().map(|&(a, _)| a).collect();
        v.dedup();
        v
    }

    /// Whether a function starts exactly at `addr`.
    #[must_use]
    pub fn is_function_start(&self, addr: u32) -> bool {
        self.inner
            .functions
            .binary_search_by_key(&addr, |&(a, _)| a)
            .is_ok()
    }
}

/// A program counter's phase is the C name of the function holding it (code in flash only: a
/// PC in RAM has no name).
impl h8_3052f::trace::CodeNames for SymbolTable {
    fn name_at(&self, pc: u32) -> Option<&str> {
        if h8300h::memmap::Area::of(pc) != h8300h::memmap::Area::Rom {
            return None;
        }
        self.function_at(pc).map(Symbol::c_name)
    }
}

/// Whether `c` is a Unicode format character (general category Cf, Unicode 15.1's
/// UnicodeData.txt: among them the bidirectional controls U+061C, U+200E, U+200F, U+202A to
/// U+202E and U+2066 to U+2069, the zero-width U+200B to U+200D and U+2060, the byte-order
/// mark U+FEFF, the interlinear annotations U+FFF9 to U+FFFB and the tags U+E0001 and U+E0020
/// to U+E007F) or the line or paragraph separator (U+2028, U+2029: they end a line on some
/// terminals).
#[must_use]
pub fn is_format_char(c: char) -> bool {
    matches!(
        c,
        '\u{ad}'
            | '\u{600}'..='\u{605}'
            | '\u{61c}'
            | '\u{6dd}'
            | '\u{70f}'
            | '\u{890}'..='\u{891}'
            | '\u{8e2}'
            | '\u{180e}'
            | '\u{200b}'..='\u{200f}'
            | '\u{2028}'..='\u{202e}'
            | '\u{2060}'..='\u{2064}'
            | '\u{2066}'..='\u{206f}'
            | '\u{feff}'
            | '\u{fff9}'..='\u{fffb}'
            | '\u{110bd}'
            | '\u{110cd}'
            | '\u{13430}'..='\u{1343f}'
            | '\u{1bca0}'..='\u{1bca3}'
            | '\u{1d173}'..='\u{1d17a}'
            | '\u{e0001}'
            | '\u{e0020}'..='\u{e007f}'
    )
}
