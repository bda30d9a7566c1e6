//! The stack guard: the first instruction whose stack access leaves the stack's room, caught
//! where it happens instead of when a wild RTS finally fetches from outside ROM and RAM.
//!
//! The room is a range of addresses, `[low, top)`: from the end of the data the program uses
//! (its `.data` and `.bss`, and what it carves at boot) up to the stack's top (the initial SP;
//! the first push lands just below it). The layer that loads the image says where they are
//! ([`StackRoom`]); without a symbol table the room is the whole on-chip RAM.
//!
//! What is checked, every time, before the access changes anything:
//! - the implicit stack accesses: the return address a JSR or BSR pushes, the PC and CCR an
//!   interrupt's or TRAPA's entry pushes, what RTS and RTE pop;
//! - every data access whose address comes from ER7: `@ER7`, `@ER7+`, `@-ER7` (PUSH and POP
//!   are MOV.L with these), `@(d:16,ER7)`, `@(d:24,ER7)`, in MOV, LDC/STC and the bit
//!   instructions.
//!
//! An access is outside the room when any of its bytes is below `low` (the stack ran into the
//! data or off RAM: an overflow) or at or above `top` (it reads or writes above the stack's
//! top: popping more than was pushed, a frame that is not there). The check costs one add and
//! one compare, and only the instructions that touch the stack pay it: the fast path gives the
//! loads and stores through ER7 handlers of their own, so every other instruction runs as
//! before. With no guard set the bounds are such that the compare never fires.
//!
//! What happens then is the [`StackGuardMode`]: [`StackGuardMode::Stop`] stops the program
//! with [`super::CpuError::StackOverflow`] with the CPU as it was before the instruction (PC
//! at it); [`StackGuardMode::Warn`] lets it go on and keeps the first fault
//! ([`super::Cpu::stack_fault`]).

use crate::memmap::{ADDRESS_MASK, RAM_END, RAM_START};

/// The addresses the stack may use: `low` up to (not including) `top`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StackRoom {
    /// The lowest address the stack may use: the end of the data the program uses.
    pub low: u32,
    /// One past the highest address the stack may use: the stack's top (the initial SP).
    pub top: u32,
}

impl StackRoom {
    /// The whole on-chip RAM, H'FFDF10 to H'FFFF0F: the room when nothing else is known.
    pub const RAM: StackRoom = StackRoom {
        low: RAM_START,
        top: RAM_END + 1,
    };

    /// Bytes in the room.
    #[must_use]
    pub const fn bytes(&self) -> u32 {
        self.top.saturating_sub(self.low)
    }
}

/// What the core does when a stack access leaves the room.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StackGuardMode {
    /// Stop the program at the instruction ([`super::CpuError::StackOverflow`]).
    #[default]
    Stop,
    /// Keep the first fault ([`super::Cpu::stack_fault`]) and go on.
    Warn,
}

/// A stack guard: the room and what to do when an access leaves it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StackGuard {
    /// The room.
    pub room: StackRoom,
    /// Stop or warn.
    pub mode: StackGuardMode,
}

impl StackGuard {
    /// A guard that stops the program, over `room`.
    #[must_use]
    pub const fn stop(room: StackRoom) -> StackGuard {
        StackGuard {
            room,
            mode: StackGuardMode::Stop,
        }
    }
}

/// Which kind of stack access left the room.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StackAccess {
    /// A JSR or BSR pushing its return address.
    Call,
    /// RTS popping the return address.
    Return,
    /// An interrupt's entry pushing PC and CCR (the vector is given).
    InterruptEntry(u8),
    /// TRAPA pushing PC and CCR.
    Trap,
    /// RTE popping PC and CCR.
    ReturnFromException,
    /// A data write through ER7 (`@-ER7` is a push).
    Write,
    /// A data read through ER7 (`@ER7+` is a pop).
    Read,
    /// An instruction that sets ER7 as a register moves SP out of the room (a frame allocated
    /// below the data: the accesses to it may go through the frame pointer, unseen).
    MoveSp,
}

impl StackAccess {
    /// The access in words, for messages.
    #[must_use]
    pub fn describe(self) -> String {
        match self {
            StackAccess::Call => "the call pushes its return address".to_string(),
            StackAccess::Return => "RTS pops its return address".to_string(),
            StackAccess::InterruptEntry(v) => {
                format!("the entry of interrupt vector {v} pushes PC and CCR")
            }
            StackAccess::Trap => "TRAPA pushes PC and CCR".to_string(),
            StackAccess::ReturnFromException => "RTE pops PC and CCR".to_string(),
            StackAccess::Write => "it writes through ER7".to_string(),
            StackAccess::Read => "it reads through ER7".to_string(),
            StackAccess::MoveSp => "it moves SP".to_string(),
        }
    }
}

/// The first stack access that left the room.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StackFault {
    /// The instruction (for an interrupt's entry, the instruction it interrupted).
    pub pc: u32,
    /// The instruction, disassembled (empty for an interrupt's entry).
    pub instruction: String,
    /// ER7 before the instruction.
    pub sp: u32,
    /// The lowest address of the access.
    pub addr: u32,
    /// Bytes accessed.
    pub bytes: u32,
    /// What kind of access.
    pub access: StackAccess,
    /// The room it left.
    pub room: StackRoom,
    /// The function holding `pc`, when the layer that loaded the image knows it.
    pub function: Option<String>,
}

impl StackFault {
    /// Whether the access went below the room (an overflow into the data or off RAM), rather
    /// than above its top.
    #[must_use]
    pub fn below(&self) -> bool {
        self.addr < self.room.low
    }

    /// Bytes of the access outside the room: below `low` for an overflow, at or above `top`
    /// otherwise.
    #[must_use]
    pub fn bytes_over(&self) -> u32 {
        if self.below() {
            self.room.low - self.addr
        } else {
            (self.addr + self.bytes).saturating_sub(self.room.top)
        }
    }
}

impl std::fmt::Display for StackFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let what = if self.below() {
            "stack overflow"
        } else {
            "stack access above the stack's top"
        };
        write!(f, "{what} at PC H'{:06X}", self.pc)?;
        if let Some(func) = &self.function {
            write!(f, " in `{func}`")?;
        }
        if !self.instruction.is_empty() {
            write!(f, " (`{}`)", self.instruction)?;
        }
        if self.access == StackAccess::MoveSp {
            write!(
                f,
                ": it moves SP from H'{:06X} to H'{:06X}",
                self.sp & ADDRESS_MASK,
                self.addr
            )?;
        } else {
            write!(
                f,
                ": {}, {} bytes at H'{:06X} with SP H'{:06X}",
                self.access.describe(),
                self.bytes,
                self.addr,
                self.sp & ADDRESS_MASK
            )?;
        }
        write!(
            f,
            ", {} bytes {} the stack's room H'{:06X}-H'{:06X}",
            self.bytes_over(),
            if self.below() { "below" } else { "above" },
            self.room.low,
            self.room.top.saturating_sub(1)
        )?;
        if self.below() {
            write!(
                f,
                " (the end of the program's data to its initial SP: {} bytes)",
                self.room.bytes()
            )?;
        }
        Ok(())
    }
}

/// The bounds the check compares with: `low` and the room's size, or, with no guard, bounds
/// that no 24-bit access can leave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Bounds {
    pub(super) low: u32,
    pub(super) span: u32,
}

impl Bounds {
    /// No guard: every address is inside (an address is at most 24 bits, an access at most
    /// 4 bytes, the span 2^32 − 1).
    pub(super) const OFF: Bounds = Bounds {
        low: 0,
        span: u32::MAX,
    };

    /// The bounds of `room`.
    pub(super) const fn of(room: StackRoom) -> Bounds {
        Bounds {
            low: room.low & ADDRESS_MASK,
            span: room.top.saturating_sub(room.low),
        }
    }

    /// Whether the `bytes` bytes at `addr` lie inside: one subtraction, one addition, one
    /// compare.
    #[inline(always)]
    pub(super) const fn inside(self, addr: u32, bytes: u32) -> bool {
        let off = (addr & ADDRESS_MASK).wrapping_sub(self.low) as u64;
        off + bytes as u64 <= self.span as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_guard_lets_every_access_through() {
        for addr in [0, 0xFF_DF10, 0xFF_FFFC, 0xFF_FFFF, u32::MAX] {
            assert!(Bounds::OFF.inside(addr, 4), "{addr:#x}");
        }
    }

    #[test]
    fn the_room_s_edges() {
        let b = Bounds::of(StackRoom {
            low: 0xFF_E000,
            top: 0xFF_FF10,
        });
        assert!(b.inside(0xFF_E000, 4));
        assert!(!b.inside(0xFF_DFFE, 4));
        assert!(!b.inside(0xFF_DFFF, 1));
        assert!(b.inside(0xFF_FF0C, 4));
        assert!(!b.inside(0xFF_FF0E, 4));
        assert!(!b.inside(0xFF_FF10, 2));
        // An address that wrapped below zero is outside, not a huge offset that wraps back.
        assert!(!b.inside(0xFFFF_FFFC, 4));
    }

    #[test]
    fn a_fault_says_how_far_it_went() {
        let f = StackFault {
            pc: 0x512,
            instruction: "mov.l\ter6,@-er7".to_string(),
            sp: 0xFF_E002,
            addr: 0xFF_DFFE,
            bytes: 4,
            access: StackAccess::Write,
            room: StackRoom {
                low: 0xFF_E000,
                top: 0xFF_FF10,
            },
            function: Some("recurse".to_string()),
        };
        assert!(f.below());
        assert_eq!(f.bytes_over(), 2);
        let text = f.to_string();
        assert!(
            text.contains("stack overflow at PC H'000512 in `recurse`"),
            "{text}"
        );
        assert!(text.contains("2 bytes below"), "{text}");
    }
}
