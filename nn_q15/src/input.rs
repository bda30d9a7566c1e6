//! The input vector of docs/design.md §2.2.
//!
//! In this order: the K = 4 current proximities `p_k(t) − 128` as Q7; the same 4 from each of
//! the H previous steps (H = 1 by default, 0 … 8), newest first; the previous step's outputs
//! `O_j(t−1) >> 8` (M values); the previous evaluation `sat_i8(E(t−1) >> 3)`; optionally a bias
//! input +127 (off by default: the paper has none). At the first step, history, past outputs and
//! the past evaluation are 0.
//!
//! The history needs no buffer of its own: the delayed proximities of step t are the current
//! and younger delayed proximities of step t−1, so the learner shifts them one block deeper in
//! place (one 32-bit move per block on the H8) before writing the new readings.

use crate::error::ConfigError;
use crate::limits::MAX_HISTORY;

/// Number of proximity sensors K (front, rear, left, right: docs/design.md §1).
pub const SENSORS: usize = 4;

/// How the input vector is made up: history depth and bias.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InputLayout {
    history: u8,
    bias: bool,
    spare: u16,
}

impl Default for InputLayout {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl InputLayout {
    /// The default layout: history depth 1, no bias (N = 13 with four behaviours).
    pub const DEFAULT: InputLayout = InputLayout {
        history: 1,
        bias: false,
        spare: 0,
    };

    /// A layout with `history` delayed copies of the proximities and an optional bias input.
    ///
    /// # Errors
    /// [`ConfigError::History`] when `history` exceeds [`MAX_HISTORY`].
    pub const fn new(history: usize, bias: bool) -> Result<InputLayout, ConfigError> {
        if history > MAX_HISTORY {
            return Err(ConfigError::History { got: history });
        }
        Ok(InputLayout {
            history: history as u8,
            bias,
            spare: 0,
        })
    }

    /// The same layout with `spare` inputs held at 0 after the others (for what-if studies).
    #[must_use]
    pub const fn with_spare(self, spare: u16) -> InputLayout {
        InputLayout { spare, ..self }
    }

    /// Number of spare inputs.
    #[must_use]
    pub const fn spare(self) -> usize {
        self.spare as usize
    }

    /// The history depth H.
    #[must_use]
    pub const fn history(self) -> usize {
        self.history as usize
    }

    /// Whether the bias input is present.
    #[must_use]
    pub const fn bias(self) -> bool {
        self.bias
    }

    /// Number of inputs N for `n_out` behaviours: `4·(1 + H) + M + 1 (+ 1 with bias) (+ spare)`.
    #[must_use]
    pub const fn n_inputs(self, n_out: usize) -> usize {
        SENSORS * (1 + self.history as usize) + n_out + 1 + self.bias as usize + self.spare as usize
    }

    /// Index of the first past output in the vector.
    #[must_use]
    pub const fn outputs_at(self) -> usize {
        SENSORS * (1 + self.history as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_layout_has_13_inputs_in_the_arena_and_11_in_the_corridor() {
        assert_eq!(InputLayout::DEFAULT.n_inputs(4), 13);
        assert_eq!(InputLayout::DEFAULT.n_inputs(2), 11);
        assert_eq!(InputLayout::new(0, true).unwrap().n_inputs(4), 10);
        assert_eq!(InputLayout::new(8, false).unwrap().n_inputs(4), 41);
        assert_eq!(
            InputLayout::new(9, false),
            Err(ConfigError::History { got: 9 })
        );
        assert_eq!(InputLayout::DEFAULT.with_spare(243).n_inputs(4), 256);
    }
}
