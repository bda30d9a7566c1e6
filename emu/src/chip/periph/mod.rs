//! On-chip peripherals of the H8/3052F, one file per module (as in simavr). Each is
//! synchronised lazily to the MCU clock: it keeps the state it was last brought up to date and
//! works out counters and flags from the elapsed states when accessed, and can say when it next
//! needs attention (for SLEEP fast-forward).
//!
//! - [`adc`]: the 10-bit A/D converter (ADDRA–D, ADCSR, ADCR; single and scan mode);
//! - [`itu`]: the 16-bit integrated timer unit, channels 0–4 (compare match, PWM mode);
//! - [`ports`]: ports 2, 4, A and B (write-only DDRs, pull-ups);
//! - [`intc`]: the interrupt controller's priority decision (IPRA/IPRB);
//! - [`sci`]: SCI1, the console.

pub mod adc;
pub mod intc;
pub mod itu;
pub mod ports;
pub mod sci;
