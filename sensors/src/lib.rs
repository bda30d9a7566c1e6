//! What the robot's H8/3052F sees of the world: its four IR distance sensors and four bumpers,
//! through the A/D converter and port 2 (docs/design.md §3.1–3.4).
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
//! # Units
//! Time is in MCU states (`u64`, φ = [`IrParams::clock_hz`], 25 MHz by default: 1 state = 40 ns);
//! distances in millimetres (`f64`); voltages in volts (`f64`).
//!
//! # The IR sensor model (Sharp GP2Y0A21YK / GP2D12 class)
//!
//! **Nominal curve** ([`nominal_volts`], module [`curve`]): `V(d) = 28.48 / (d + 3.0) + 0.059` V
//! for d ≥ 8 cm (d in cm), continuing its 1/d fall beyond the datasheet's 80 cm. Below 8 cm the
//! output folds back along a straight line to 0.75 V at contact ([`FOLDBACK_CONTACT_VOLTS`],
//! the middle of the 0.5–1 V a GP2D12 gives at contact). The fit's formula is the authority for
//! d ≥ 8 cm (docs/design.md §3.1): the often-quoted "≈ 3.2 V" peak is the formula's value at 6 cm,
//! not at 8 cm, so the modelled peak is
//! **2.648 V at 8 cm**, continuous with the fold-back line. With it, the reading at 5 cm
//! (1.936 V) equals the reading at 12.17 cm: the fold-back ambiguity is real.
//!
//! **Nothing hit.** `None` as a distance reads as 10 m ([`NOTHING_HIT_MM`]): 0.087 V, within
//! 3 mV of the curve's asymptote. Distances beyond 10 m, `+∞` included, read as 10 m too. NaN or
//! negative distances are errors.
//!
//! **Per-sensor spread**, drawn once at construction from the datasheet's unit-to-unit spread:
//! the output at 80 cm uniform in 0.25–0.55 V (0.4 ± 0.15 V) and the difference
//! V(10 cm) − V(80 cm) uniform in 1.75–2.25 V, independently. They fix a gain and offset on the
//! nominal curve, `V_s(d) = gain · V(d) + offset` with `gain = ΔV / 1.848 V` and
//! `offset = V80 − gain · 0.402 V`, applied to the whole curve (fold-back included), the output
//! clamped to 0 V … 5 V (the supply). Note that the nominal formula's ΔV (1.848 V) lies in the
//! lower half of the datasheet range, so the average sensor is about 8 % steeper than the curve
//! the firmware's table inverts, as a real robot's sensors are against a typical-curve table.
//!
//! **Sample-and-hold.** The sensor measures on its own clock and holds its output in between.
//! Each sensor draws its own period P uniformly in `38.3 ± (9.6 − 2·0.4)` ms and a random phase;
//! refresh instant k is `t_k = t_0 + k·P + e_k` with independent jitter `e_k` uniform in
//! ±0.4 ms ([`DEFAULT_PERIOD_JITTER_MS`], an assumption: the datasheet gives only the 38.3 ±
//! 9.6 ms spread). Intervals are therefore `P + e_{k+1} − e_k`: mean P, always inside the
//! datasheet's 28.7–47.9 ms, and the schedule depends only on the seed, never on when the
//! caller happens to look (the jitter of cycle k is a counter-based draw). At a call at or after
//! a refresh instant the held value becomes the sensor's curve at the distance given with that
//! call: the world calls [`IrSensor::sample`] with the distance *at the read instant* (at
//! 0.15 m/s a robot moves at most about 7 mm in a 47.9 ms period; a world that wants the
//! distance at the refresh instant itself can call [`IrSensor::update`] at
//! [`IrSensor::next_refresh_states`]). The first call latches at once: the sensor was already
//! measuring before the emulation began.
//!
//! **Read noise**, per A/D sample: Gaussian σ = 15 mV, plus with probability 0.1 a spike uniform
//! in +150…200 mV. the design's spikes are ~0.1 ms wide every ~1 ms; a 5–11 µs conversion lands in
//! one with probability ≈ 0.1. They are modelled as independent per read, which is right
//! unless one sensor is read twice within 0.1 ms or in lock-step with its LED pulses (the
//! firmware reads each sensor once per step). The sum is clamped to 0 V … 5 V.
//!
//! **Randomness.** Each sensor owns its randomness, from the `u64` seed the caller gives, split
//! into independent streams per purpose (spread, timing, noise) by the project's one
//! derivation (`seeding::derive`), each a PCG-64 generator (`rand_pcg`).
//! Same seed, same parameters and same calls ⇒ identical readings. The noise stream advances
//! once per [`IrSensor::sample`]; [`IrSensor::update`] draws nothing.
//!
//! **Errors**, never panics: parameters outside their physical range
//! ([`IrParams::validate`] lists them), NaN/negative distances and time going backwards
//! return a [`SensorError`] naming the value and the valid range.
//!
//! # A/D conversion (module [`adc`], docs/design.md §3.2)
//! Ideal 10-bit converter at Vref = 5.0 V: code k from `k · 5/1024` V upward (the H8 manual's
//! ideal conversion characteristic), clamped to 0..=1023, exact at every boundary; ADDRn =
//! code << 6 (left-justified); the firmware's byte `c = code >> 2`, 19.53 mV per step.
//!
//! # Distance units (module [`du`], docs/design.md §3.3)
//! [`DU_TABLE`] maps c to du (1 du = 80/255 cm), computed at compile time by inverting the
//! nominal far branch at each code's bin centre `(c + 0.5) · 5/256` V, rounded, clamped to
//! 0..=255; codes above the peak extrapolate the formula (down to 9 du at code 255), codes at
//! or below V(80 cm) read 255. Exact to ±0.5 du on codes 71–134 ([`STEEP_CODES`], 8.05–18.45 cm),
//! where one code spans at most 1 du.
//!
//! # Bumpers (module [`bumpers`], docs/design.md §3.4)
//! Front, rear, left, right on P2.0–P2.3, active low with pull-ups; the collision counter
//! counts released→pressed edges.
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
