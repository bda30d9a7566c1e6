//! Execution states of the H8/300H, by the manual's rule.
//!
//! The H8/300H Series Programming Manual (Appendix A, "Number of States Required for
//! Execution") gives each instruction as counts I, J, K, L, M, N of instruction fetches,
//! branch-address reads, stack operations, byte data accesses, word data accesses and internal
//! operations; the states are `I·S_I + J·S_J + K·S_K + L·S_L + M·S_M + N·S_N`, each S the states
//! of one access to the area it touches. The core performs every fetch and data access through
//! the [`crate::bus::Bus`] (which charges S per area), so only two things are left to this table:
//! the internal states N, and the *extra* instruction fetches of the one-word branches (I is one
//! more than the instruction's length: the prefetch of the branch target), charged by the core as
//! a word fetch at the target.
//!
//! With on-chip operands (S = 2 for every access, S_N = 1) the totals are those of docs/design.md §4.2;
//! `tests/timing.rs` checks them one by one.

/// Internal states (N) of MOV and LDC/STC with `@ERs+` or `@-ERd` (programming manual, Table A:
/// N = 2 for post-increment and pre-decrement modes).
pub const N_POSTINC_PREDEC: u32 = 2;

/// Internal states of Bcc d:16 and BSR d:16 (Table A: I = 2, N = 2 → 6 / 10 states with K = 2).
pub const N_BRANCH_D16: u32 = 2;

/// Internal states of JMP @aa:24 and JSR @aa:24 (Table A: N = 2; JSR @aa:24 = 10 states).
pub const N_JUMP_ABS24: u32 = 2;

/// Internal states of JMP @@aa:8 in advanced mode (Table A: I = 2, J = 2, N = 2 → 10 states).
pub const N_JMP_MEM_INDIRECT: u32 = 2;

/// Internal states of RTS and RTE in advanced mode (Table A: I = 2, K = 2, N = 2 → 10 states).
pub const N_RETURN: u32 = 2;

/// Internal states of TRAPA (programming manual, TRAPA page: 14 states = I 2, J 2, K 2, N 2).
pub const N_TRAPA: u32 = 2;

/// Internal states of MULXU.B / MULXS.B / DIVXU.B / DIVXS.B (Table A: N = 12; totals 14/16).
pub const N_MULDIV_BYTE: u32 = 12;

/// Internal states of MULXU.W / MULXS.W / DIVXU.W / DIVXS.W (Table A: N = 20; totals 22/24).
pub const N_MULDIV_WORD: u32 = 20;

/// Extra byte accesses of EEPMOV beyond the 2n of the transfer (Table A: L = 2n + 2, so EEPMOV
/// costs 8 + 4n states on chip). The core charges them as one extra access to the source area
/// and one to the destination area (the manual does not say which cycles they are).
pub const EEPMOV_EXTRA_BYTE_ACCESSES: u32 = 2;

/// Interrupt exception handling: internal processing after acceptance and after the prefetch
/// (H8/3052F hardware manual, Table 5-5 "Interrupt response time", item 6: 4 states).
pub const N_INTERRUPT_INTERNAL: u32 = 4;

/// Interrupt priority decision for an internal (on-chip peripheral) interrupt (Table 5-5,
/// item 1, note 1: 1 state for internal interrupts).
pub const N_PRIORITY_DECISION_INTERNAL: u32 = 1;

/// Interrupt priority decision for an external interrupt (NMI, IRQ0–5) (Table 5-5, item 1:
/// 2 states).
pub const N_PRIORITY_DECISION_EXTERNAL: u32 = 2;

/// States of one internal operation (S_N = 1 by the manual's definition).
pub const S_N: u32 = 1;
