//! The bounds of the learner's shapes and configuration: how many inputs, outputs, behaviours
//! and history blocks a network or a learner may have. The constructors check against them and
//! the errors name them.

/// Most inputs a network may have: with |w·x| ≤ 2^15 · 2^7 = 2^22 per product, 256 products sum
/// to at most 2^30, inside an `i32` (docs/design.md §2.1: "no overflow for N ≤ 256").
pub const MAX_INPUTS: usize = 256;
/// Fewest outputs (the corridor's forward and backward, docs/design.md §2.2).
pub const MIN_OUTPUTS: usize = 2;
/// Most outputs of the learner core (forward pass, update, replay): 8. A robot enables 2 or 4
/// behaviours ([`MAX_BEHAVIOURS`]); wider shapes are for what-if studies and for the
/// calibration of the cost model against the firmware, whose routines take up to 8.
pub const MAX_OUTPUTS: usize = 8;
/// Most behaviours a robot's learner drives: the four primitive behaviours (docs/design.md
/// §2.2). The learner core takes up to [`MAX_OUTPUTS`] outputs; the robot's learners
/// (`Learner`, `DynLearner`) map each output to a behaviour, so they take at most four.
pub const MAX_BEHAVIOURS: usize = 4;
/// Deepest history the layout allows (docs/design.md §2.2: 0 … 8).
pub const MAX_HISTORY: usize = 8;
