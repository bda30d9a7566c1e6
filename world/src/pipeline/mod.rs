//! The stages of a sub-step, in the order the world's step runs them:
//!
//! 1. [`drive`]: the motors give each wheel's speed over the sub-step;
//! 2. [`narrow_phase`]: the contacts among the [`broad_phase`]'s candidates, and which bind;
//! 3. [`drive`] again: robots touching nothing follow their wheels; the others are
//!    [`warm_start`]ed, sorted into [`islands`] and solved by the [`solver`];
//! 4. [`corrections`]: what the solve left of an overlap is pushed apart;
//! 5. [`sensing`]: the bumpers take the contacts' and the corrections' pushes;
//! 6. [`broad_phase`]: rebuilt once some robot has drifted too far.
//!
//! The IR rays ([`sensing`]) are cast between steps, on demand. No stage knows the world that
//! holds them: each takes the slices and constants it works on.

pub(crate) mod broad_phase;
pub(crate) mod corrections;
pub(crate) mod drive;
pub(crate) mod islands;
pub(crate) mod narrow_phase;
pub(crate) mod newton;
pub mod par;
pub(crate) mod sensing;
pub(crate) mod solver;
pub(crate) mod warm_start;
