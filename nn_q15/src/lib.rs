//! # nn_q15 — the Hartono–Kakita embedded learner in fixed point
//!
//! The two-layer, continuously learning network of Hartono & Kakita (ICANN 2008), written as the
//! H8/3052F would run it: Q7 inputs, Q15 weights and outputs, exact i32 sums (docs/design.md §2.1), the
//! forward pass of docs/design.md §2.3 and the reward/punish update of docs/design.md §2.4, bit-exact to their integer
//! definitions. `#![no_std]`, no allocation, dependencies `fixed` and `heapless` only: it could be
//! linked into real firmware.
//!
//! Every primitive the learner performs is reported to a [`Meter`]: [`NoopMeter`] compiles to
//! nothing, [`H8Meter`] charges the H8/300H states of the instruction sequence each primitive
//! needs ([`cost`]). The learner's RAM footprint on the H8 is a constant,
//! [`Learner::RAM_BYTES`], itemised in [`Learner::RAM_ITEMS`].
//!
//! ```
//! use nn_q15::{H8Meter, InputLayout, Learner, Network, Params, Phase};
//!
//! // The arena's network: 13 inputs (4 proximities, 4 delayed, 4 past outputs, E), 4 behaviours.
//! let mut learner =
//!     Learner::<13, 4>::new(Network::zeroed(), Params::ARENA, InputLayout::DEFAULT).unwrap();
//! let mut meter = H8Meter::new();
//! let step = learner.step(&[120, 255, 80, 200], &mut meter);
//! println!("{} after {} states", step.behaviour.name(), meter.total_states());
//! assert!(meter.states(Phase::Forward) > 0);
//! assert_eq!(Learner::<13, 4>::RAM_BYTES, 176);
//! ```
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod cost;
pub mod error;
pub mod format;
pub mod input;
pub mod learner;
pub mod limits;
pub mod net;

pub use cost::{H8Meter, Meter, NoopMeter, Op, Phase};
pub use error::{ConfigError, ParamError, ShapeError};
pub use format::{Q7, Q15, Q22};
pub use input::{InputLayout, SENSORS};
pub use learner::{
    Behaviour, DynLearner, Learner, MAX_WEIGHTS, RamItem, StepOut, ram_bytes, ram_items,
};
pub use limits::{MAX_BEHAVIOURS, MAX_HISTORY, MAX_INPUTS, MAX_OUTPUTS, MIN_OUTPUTS};
pub use net::{ForwardOut, Network, Params, Shape, UpdateKind, forward_slice, update_slice};
