//! What the robot's H8/3052F sees of the world: its four IR distance sensors and four bumpers,
//! through the A/D converter and port 2.
//!
//! The emulated MCU (crate `emu`) drives this crate: at each A/D conversion it asks a sensor
//! for "the voltage on the pin at this instant" ([`IrSensor::sample`]), giving the MCU time in
//! states and the true distance the world's ray cast found; it turns volts into the register
//! contents with [`adc10_code`] / [`addr_register`]; the firmware linearises the 8-bit code
//! with [`DU_TABLE`]. Bumper contacts become port-2 pins with [`port2_pins`], and the firmware's
//! collision count is [`CollisionCounter`].
//!
//! ```
//! use sensors::{IrParams, IrSensor, DU_TABLE, adc10_code, code8_from_adc10};
//!
//! let clock_hz = 25_000_000; // the MCU's φ (the robot's; the crate has no clock of its own)
//! let mut front = IrSensor::new(IrParams::datasheet(clock_hz), 7)?;
//! let now_states = 1_000_000; // 40 ms at φ = 25 MHz
//! let volts = front.sample(now_states, Some(300.0))?; // a wall 30 cm away
//! let c = code8_from_adc10(adc10_code(volts));
//! let p_du = DU_TABLE[usize::from(c)];
//! assert!((80..=115).contains(&p_du)); // 30 cm ≈ 96 du, give or take spread and noise
//! # Ok::<(), sensors::SensorError>(())
//! ```
//!
//! Time is in MCU states (`u64`, φ = [`IrParams::clock_hz`]); distances in millimetres (`f64`);
//! voltages in volts (`f64`). Each sensor's randomness comes from the seed it is given: the same
//! seed, parameters and calls give the same readings. Bad parameters ([`IrParams::validate`]),
//! NaN or negative distances and time going backwards are a [`SensorError`], never a panic.
//!
//! The models, their constants and their sources: docs/design.md §3.1 (the IR curve
//! ([`curve`]), the unit spread, sample-and-hold, read noise), §3.2 (A/D, [`adc`]), §3.3 (the
//! du table, [`du`]), §3.4 (bumpers, [`bumpers`]); the measured checks: docs/crates.md.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod adc;
pub mod bumpers;
pub mod curve;
pub mod du;
mod error;
pub mod ir;
mod rng;

pub use adc::{
    ADC_VREF_VOLTS, ADC10_MAX, CODE8_LSB_VOLTS, adc10_code, addr_register, code8,
    code8_centre_volts, code8_from_adc10,
};
pub use bumpers::{
    BUMPER_PORT2_MASK, Bumper, BumperSet, CollisionCounter, port2_pins, pressed_from_port2,
};
pub use curve::{FOLDBACK_CONTACT_VOLTS, NOTHING_HIT_MM, PEAK_VOLTS, nominal_volts};
pub use du::{DU_TABLE, STEEP_CODES, du_for_code};
pub use error::SensorError;
pub use ir::{DEFAULT_PERIOD_JITTER_MS, IrParams, IrSensor, SUPPLY_CURRENT_MA};
