//! Errors of the learner's constructors and runtime-shaped entry points.
//!
//! `no_std`: each error implements [`core::fmt::Display`] and [`core::error::Error`] by hand.

use core::fmt;

use crate::limits::{MAX_BEHAVIOURS, MAX_HISTORY, MAX_INPUTS, MAX_OUTPUTS, MIN_OUTPUTS};

/// A network shape or a slice that does not fit it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeError {
    /// N outside 1 ..= 256 (the no-overflow bound of docs/design.md §2.1).
    Inputs {
        /// The number of inputs asked for.
        got: usize,
    },
    /// M outside 2 ..= 8 (the learner core's bound).
    Outputs {
        /// The number of outputs asked for.
        got: usize,
    },
    /// A learner that drives the robot with M outside 2 ..= 4: one output per behaviour, and
    /// the robot has four (docs/design.md §2.2).
    Behaviours {
        /// The number of outputs asked for.
        got: usize,
    },
    /// A slice whose length does not match the shape.
    Length {
        /// Which slice.
        what: &'static str,
        /// The length the shape needs.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// A winner index that is not an output.
    Winner {
        /// The index given.
        got: usize,
        /// The number of outputs.
        n_out: usize,
    },
}

impl fmt::Display for ShapeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ShapeError::Inputs { got } => write!(
                f,
                "{got} inputs is outside the no-overflow bound: valid is 1 to {}",
                MAX_INPUTS
            ),
            ShapeError::Outputs { got } => write!(
                f,
                "{got} outputs: valid is {} to {}",
                MIN_OUTPUTS, MAX_OUTPUTS
            ),
            ShapeError::Behaviours { got } => write!(
                f,
                "{got} outputs: a learner that drives the robot has one per enabled behaviour, {} to {}",
                MIN_OUTPUTS, MAX_BEHAVIOURS
            ),
            ShapeError::Length {
                what,
                expected,
                got,
            } => write!(f, "{what} has {got} values, the shape needs {expected}"),
            ShapeError::Winner { got, n_out } => {
                write!(
                    f,
                    "winner {got} is not an output: valid is 0 to {}",
                    n_out - 1
                )
            }
        }
    }
}

impl core::error::Error for ShapeError {}

/// A learning parameter out of range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamError {
    /// η outside 0 ..= 32767 (Q15, ≥ 0).
    Eta {
        /// The value given.
        got: i32,
    },
    /// T outside 0 ..= 32767 (du, ≥ 0).
    Threshold {
        /// The value given.
        got: i32,
    },
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ParamError::Eta { got } => write!(
                f,
                "learning rate eta = {got} is out of range: valid is 0 to 32767 (Q15, 0.1 = 3277)"
            ),
            ParamError::Threshold { got } => write!(
                f,
                "threshold T = {got} is out of range: valid is 0 to 32767 (distance units)"
            ),
        }
    }
}

impl core::error::Error for ParamError {}

/// A learner configuration that does not fit together.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConfigError {
    /// History depth outside 0 ..= 8 (docs/design.md §2.2).
    History {
        /// The depth asked for.
        got: usize,
    },
    /// The input layout needs a different N than the network has.
    Inputs {
        /// N the layout needs.
        layout: usize,
        /// N the network has.
        network: usize,
    },
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ConfigError::History { got } => write!(
                f,
                "history depth {got} is out of range: valid is 0 to {}",
                MAX_HISTORY
            ),
            ConfigError::Inputs { layout, network } => write!(
                f,
                "the input layout makes {layout} inputs but the network has {network}"
            ),
        }
    }
}

impl core::error::Error for ConfigError {}
