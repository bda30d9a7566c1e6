//! The one error type of the crate.

use thiserror::Error;

/// What went wrong when building or driving a sensor model.
///
/// Every variant names the offending value and says what would have been valid, so a caller
/// (the emulator, a scenario file) can report it to the user unchanged.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum SensorError {
    /// A model parameter is outside its physical range.
    #[error("IR sensor parameter `{name}` = {value} is out of range: valid is {valid}")]
    ParamOutOfRange {
        /// The parameter's field name in [`IrParams`](crate::IrParams).
        name: &'static str,
        /// The value given.
        value: f64,
        /// The valid range, in words.
        valid: String,
    },
    /// A distance that cannot be a distance (NaN or negative).
    #[error(
        "distance_mm = {value} is not a distance: expected a number >= 0 mm \
         (None means nothing hit; anything beyond {far_mm} mm reads as {far_mm} mm)"
    )]
    BadDistance {
        /// The value given.
        value: f64,
        /// The distance at which the model reads "nothing hit".
        far_mm: f64,
    },
    /// The caller's clock went backwards between two calls on the same sensor.
    #[error(
        "time went backwards on an IR sensor: called at {now_states} states after a call at \
         {last_states} states (time must be non-decreasing)"
    )]
    TimeBackwards {
        /// The instant given now.
        now_states: u64,
        /// The instant of the previous call.
        last_states: u64,
    },
}
