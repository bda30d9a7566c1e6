//! The bus every program on the emulated MCU talks through.
//!
//! As in mooneye-gb, time is right by construction: every access advances the MCU clock by the
//! states of the area it touches ([`crate::memmap::Area`]), so a program (the Rust controller
//! or machine code run by the H8/300H core) cannot touch the hardware without paying for it.
//! Internal operation states (the manual's N·S_N) are charged with [`Bus::internal`].

use std::sync::atomic::{AtomicU64, Ordering};

/// What the CPU tells the chip about itself, at the instant it happens
/// ([`Bus::cpu_signal`]): on the H8/3052F the CPU's sleep mode and its acceptance of an
/// interrupt are seen by the rest of the chip (the clock pulse generator stops the CPU's
/// clock; the interrupt controller is acknowledged). For observers such as pin traces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CpuSignal {
    /// SLEEP put the CPU into sleep mode (at the end of the instruction).
    Sleep,
    /// An interrupt request took the CPU out of sleep mode (before its acceptance).
    Wake,
    /// The interrupt with this vector was accepted: its exception handling begins now.
    Interrupt(u8),
    /// The CPU takes the bus's reset request ([`RESET_REQUEST`]) now: the chip resets itself
    /// (its modules to their reset state) and holds the CPU in reset for as long as the reset
    /// lasts (the bus advances the clock to its end); then the CPU reads the reset vector.
    Reset,
    /// The CPU stopped before the next instruction for the bus's break request
    /// ([`BREAK_REQUEST`]): the bus withdraws the request. `pc` is the address of the
    /// instruction executed last ([`crate::cpu::Cpu::last_pc`]), the one whose access the bus
    /// wanted seen.
    Break {
        /// The instruction executed last.
        pc: u32,
    },
}

/// What [`Bus::pending_irq`] returns for a **reset request**: vector 0, the reset exception.
/// The chip's own reset (the watchdog's internal reset, H8/3052F hardware manual section 12)
/// is taken at the next instruction boundary whatever CCR says, wakes a sleeping CPU, and
/// beats every interrupt; the CPU then signals [`CpuSignal::Reset`] and starts over from the
/// reset vector ([`crate::cpu::Event::Reset`]).
pub const RESET_REQUEST: u8 = 0;

/// What [`Bus::pending_irq`] returns for a **break request**: no vector (the H8/300H has 61)
/// but the bus's request that the CPU stop before the next instruction and return to its
/// caller ([`crate::cpu::Event::Break`]), for instance so that the caller can name the
/// instruction that just touched a register the chip does not model. Taken whatever CCR says,
/// before any interrupt, without waking a sleeping CPU; the CPU signals
/// [`CpuSignal::Break`] and the bus withdraws the request.
pub const BREAK_REQUEST: u8 = 0xFF;

/// A bus on the H8/3052F's 24-bit address space with a clock in states.
///
/// Conventions shared by every implementation:
/// - addresses are masked to 24 bits ([`crate::memmap::ADDRESS_MASK`]);
/// - word accesses ignore address bit 0 (the H8/300H always accesses words at even addresses);
/// - the clock advances by the access's states *before* the access takes effect, so a device
///   sees a read or write at the instant the bus cycle ends;
/// - a read from an unmapped address returns 0xFF (a floating bus reads high) and costs an
///   8-bit 3-state cycle; the H8/300H core refuses to *fetch* from there (docs/design.md §7).
pub trait Bus {
    /// The current time in states since reset.
    fn now(&self) -> u64;
    /// Reads one byte.
    fn read8(&mut self, addr: u32) -> u8;
    /// Reads one word (big-endian, address bit 0 ignored).
    fn read16(&mut self, addr: u32) -> u16;
    /// Writes one byte.
    fn write8(&mut self, addr: u32, value: u8);
    /// Writes one word (big-endian, address bit 0 ignored).
    fn write16(&mut self, addr: u32, value: u16);
    /// Charges `states` internal operation states (no bus access).
    fn internal(&mut self, states: u32);
    /// The vector number of the highest-priority interrupt that is requested and enabled at its
    /// source, if any. Masking by CCR.I is the CPU's business, not the bus's. Besides the
    /// vectors, a bus may return [`RESET_REQUEST`] (the chip resets itself) or
    /// [`BREAK_REQUEST`] (stop before the next instruction); both beat every interrupt.
    fn pending_irq(&self) -> Option<u8>;
    /// SLEEP: advances the clock until an interrupt request is pending or the clock reaches
    /// `deadline`, whichever is first. Returns whether an interrupt is pending.
    fn sleep_until_irq(&mut self, deadline: u64) -> bool;

    /// The CPU entered or left sleep mode, or accepted an interrupt, now (see
    /// [`CpuSignal`]). Changes nothing; the default ignores it.
    #[inline]
    fn cpu_signal(&mut self, signal: CpuSignal) {
        let _ = signal;
    }
}

/// What a bus may promise about itself so that the core can skip work without changing a
/// single state or access: the extension of [`Bus`] for the CPU's fast path (decoded ROM
/// instructions charged without their fetches), its loop fast-forwarding and its idle-cycle
/// fast-forwarding ([`crate::cpu`]).
///
/// Every method has a conservative default that promises nothing, so implementing the trait
/// with an empty body (or wrapping a bus in [`NoHints`]) gives a CPU that fetches every
/// instruction word through [`Bus::read16`] and skips nothing.
pub trait FastPathHints: Bus {
    /// A token for the flash contents, which lets the CPU decode ROM instructions once and
    /// charge their fetches without reading them ([`crate::cpu`]'s fast path).
    ///
    /// `Some(token)` is the bus's promise that
    /// - a word read from ROM or RAM has no effect but advancing the clock by the area's word
    ///   states ([`crate::memmap::Area::word_states`]): no device sees an instruction
    ///   fetch, so the CPU may charge it with [`Bus::internal`] instead;
    /// - the token changes whenever a byte of the flash changes, and two buses whose flash
    ///   differs never show the same token (draw tokens from [`fresh_code_generation`]).
    ///
    /// `None` (the default) promises nothing, and the CPU fetches every instruction word
    /// through [`Bus::read16`] (as a probe that counts or intercepts bus cycles needs).
    fn code_generation(&self) -> Option<u64> {
        None
    }

    /// An instant before which [`Bus::pending_irq`] keeps its present answer as long as the
    /// program writes nothing (time alone changes no request before it), for the core's
    /// loop fast-forwarding ([`crate::cpu`]). The default, [`Bus::now`], promises
    /// nothing, and no loop is skipped.
    fn irq_stable_until(&self) -> u64 {
        self.now()
    }

    /// An instant before which every read of `addr` returns what a read now returns and has
    /// no effect beyond what one read has (re-reading changes nothing), as long as the program
    /// writes nothing: ROM and RAM for ever, a peripheral register until that module's next
    /// event, if the bus knows it. For the core's poll-loop fast-forwarding and the model
    /// controller's ADF poll. `None` (the default): unknown, and no loop reading `addr` is
    /// skipped.
    fn reads_stable_until(&self, addr: u32) -> Option<u64> {
        let _ = addr;
        None
    }

    /// For the core's idle-cycle fast-forwarding ([`crate::cpu::Cpu::run_idle`]): a
    /// description of the devices' state now, relative to now. The promise: if two
    /// descriptions taken `P` states apart are equal, and in between the program's only device
    /// accesses are to addresses [`FastPathHints::idle_io`] accepts, then the devices repeat with period
    /// `P` as long as the program repeats the same accesses at the same offsets (same reads,
    /// same interrupt requests at the same instants). `None` (the default): no promise.
    fn idle_signature(&mut self) -> Option<Vec<u64>> {
        None
    }

    /// For the core's idle-cycle fast-forwarding: the instant up to which the devices outside
    /// [`FastPathHints::idle_signature`] leave the program alone — no interrupt or reset
    /// request of theirs appears before it (a free-running watchdog's next overflow). Idle
    /// cycles are advanced only as far as they end by it; the cycle in which it falls is run.
    /// The default, `u64::MAX`: nothing outside the signature ever requests.
    fn idle_horizon(&self) -> u64 {
        u64::MAX
    }

    /// Whether accesses to the device register at `addr` are covered by
    /// [`FastPathHints::idle_signature`]'s promise. The default: none is.
    fn idle_io(&self, addr: u32) -> bool {
        let _ = addr;
        false
    }

    /// Moves the clock `states` ahead (a whole number of the periods [`FastPathHints::idle_signature`]
    /// found) with the devices where repeating their period would bring them, and stores the
    /// longwords `ram` (address, value) without bus cycles: the state a program repeating its
    /// idle cycle reaches. Returns whether it did; the default does nothing and says no.
    fn idle_shift(&mut self, states: u64, ram: &[(u32, u32)]) -> bool {
        let _ = (states, ram);
        false
    }
}

/// The [`Bus`] methods that make no memory access (time, internal states, interrupts, CPU
/// signals), forwarded to the bus in field `$f` of `self`: for wrappers of a bus that watch or
/// change only its accesses. Used inside an `impl Bus for …` block.
#[macro_export]
macro_rules! forward_bus_timing {
    ($f:tt) => {
        #[inline]
        fn now(&self) -> u64 {
            self.$f.now()
        }
        #[inline]
        fn internal(&mut self, states: u32) {
            self.$f.internal(states);
        }
        #[inline]
        fn pending_irq(&self) -> Option<u8> {
            self.$f.pending_irq()
        }
        fn sleep_until_irq(&mut self, deadline: u64) -> bool {
            self.$f.sleep_until_irq(deadline)
        }
        #[inline]
        fn cpu_signal(&mut self, signal: $crate::bus::CpuSignal) {
            self.$f.cpu_signal(signal);
        }
    };
}

/// The [`Bus`] accesses (reads and writes of bytes and words), forwarded to the bus in field
/// `$f` of `self`; with [`forward_bus_timing!`], a whole forwarding `impl Bus`.
#[macro_export]
macro_rules! forward_bus_accesses {
    ($f:tt) => {
        #[inline]
        fn read8(&mut self, addr: u32) -> u8 {
            self.$f.read8(addr)
        }
        #[inline]
        fn read16(&mut self, addr: u32) -> u16 {
            self.$f.read16(addr)
        }
        #[inline]
        fn write8(&mut self, addr: u32, value: u8) {
            self.$f.write8(addr, value);
        }
        #[inline]
        fn write16(&mut self, addr: u32, value: u16) {
            self.$f.write16(addr, value);
        }
    };
}

/// The fast path's promises about code, interrupts and reads ([`FastPathHints`]'s
/// `code_generation`, `irq_stable_until`, `reads_stable_until`) forwarded to the bus in field
/// `$f` of `self`; the idle-cycle methods keep their defaults (no promise). Used inside an
/// `impl FastPathHints for …` block.
#[macro_export]
macro_rules! forward_fast_path_hints {
    ($f:tt) => {
        #[inline]
        fn code_generation(&self) -> Option<u64> {
            self.$f.code_generation()
        }
        #[inline]
        fn irq_stable_until(&self) -> u64 {
            self.$f.irq_stable_until()
        }
        #[inline]
        fn reads_stable_until(&self, addr: u32) -> Option<u64> {
            self.$f.reads_stable_until(addr)
        }
    };
}

/// A [`Bus`] with no fast-path promises: every [`FastPathHints`] method at its default. For a
/// bus that implements only [`Bus`] (a flat memory, a probe), to run the CPU on it.
#[derive(Debug)]
pub struct NoHints<'b, B: Bus>(pub &'b mut B);

impl<B: Bus> Bus for NoHints<'_, B> {
    crate::forward_bus_timing!(0);
    crate::forward_bus_accesses!(0);
}

impl<B: Bus> FastPathHints for NoHints<'_, B> {}

/// The source of [`FastPathHints::code_generation`] tokens: one process-wide counter, so a token is
/// never reused, whichever bus draws it.
static NEXT_CODE_GENERATION: AtomicU64 = AtomicU64::new(1);

/// A token no bus has shown before (for [`FastPathHints::code_generation`]): draw one whenever the flash
/// may have changed.
#[must_use]
pub fn fresh_code_generation() -> u64 {
    NEXT_CODE_GENERATION.fetch_add(1, Ordering::Relaxed)
}
