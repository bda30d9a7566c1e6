//! The H8/3052 A/D converter's transfer function and the firmware's 8-bit code (docs/design.md §3.2).
//!
//! The converter is modelled as the *ideal* 10-bit converter of the H8 hardware manuals'
//! "A/D conversion accuracy definitions" figure: the code steps from `k − 1` to `k` exactly at
//! `k · Vref / 1024`, so
//!
//! ```text
//! code10(V) = max { k ∈ 0..=1023 : V ≥ k · Vref / 1024 }      (= floor(V / Vref · 1024) clamped)
//! ```
//!
//! with Vref = 5.0 V. Negative volts (and NaN, which no real pin carries) give 0; volts at or
//! above `1023 · Vref / 1024` give 1023. The code is computed against the exact transition
//! voltages (each `k · 5 / 1024` is exact in `f64`), so it is exact at every code boundary, even
//! for the float just below a transition, where a plain `floor(V / Vref * 1024)` can round up
//! (the division can round onto the next integer).
//!
//! The result sits left-justified in the 16-bit data register (ADDRA–ADDRD, docs/design.md §3.2):
//! `ADDRn = code10 << 6`. The firmware reads only the upper byte, `c = code10 >> 2`, one step
//! of `Vref / 256` = 19.53 mV.

/// A/D reference voltage AVref = 5.0 V (docs/design.md §3.2; the AKI-H8/3052F board ties AVref to Vcc).
pub const ADC_VREF_VOLTS: f64 = 5.0;
/// Resolution of the H8/3052 A/D converter: 10 bits (docs/design.md §3.2; H8/3052F manual, A/D section).
pub const ADC_BITS: u32 = 10;
/// Number of 10-bit codes, 1024.
pub const ADC10_CODES: u16 = 1 << ADC_BITS;
/// Largest 10-bit code, 1023.
pub const ADC10_MAX: u16 = ADC10_CODES - 1;
/// Left shift of the 10-bit result in ADDRn: results are left-justified in the 16-bit
/// register (docs/design.md §3.2), so bits 15–6 hold the code and bits 5–0 read 0.
pub const ADDR_LEFT_SHIFT: u32 = 16 - ADC_BITS;
/// One 10-bit step, Vref / 1024 = 4.883 mV.
pub const ADC10_LSB_VOLTS: f64 = ADC_VREF_VOLTS / ADC10_CODES as f64;
/// One step of the firmware's 8-bit code, Vref / 256 = 19.53 mV (docs/design.md §3.2).
pub const CODE8_LSB_VOLTS: f64 = ADC_VREF_VOLTS / 256.0;

/// The transition voltage into 10-bit code `k`: `k · Vref / 1024` (exact in `f64`).
///
/// `k` above 1024 is clamped to 1024 (`Vref`).
#[must_use]
pub fn adc10_threshold_volts(k: u16) -> f64 {
    f64::from(k.min(ADC10_CODES)) * ADC10_LSB_VOLTS
}

/// The 10-bit conversion result of `volts` on an analog pin (see the module docs).
#[must_use]
pub fn adc10_code(volts: f64) -> u16 {
    // NaN and everything below the first transition read 0.
    if volts.is_nan() || volts < ADC10_LSB_VOLTS {
        return 0;
    }
    if volts >= adc10_threshold_volts(ADC10_MAX) {
        return ADC10_MAX;
    }
    // The step 5/1024 is exact in f64 and division is correctly rounded, so the quotient is
    // never below the true code k (k itself is representable) and at most rounds up onto k + 1;
    // the exact threshold check then steps back once.
    let k = (volts / ADC10_LSB_VOLTS) as u16; // in 1..=1023 here
    if volts < adc10_threshold_volts(k) {
        k - 1
    } else {
        k
    }
}

/// The 16-bit contents of ADDRn for a 10-bit result: `code10 << 6` (bits above 10 ignored).
#[must_use]
pub fn addr_register(code10: u16) -> u16 {
    (code10 & ADC10_MAX) << ADDR_LEFT_SHIFT
}

/// The firmware's 8-bit code from a 10-bit result: `c = code10 >> 2`, i.e. the upper byte of
/// ADDRn (bits above 10 ignored).
#[must_use]
pub fn code8_from_adc10(code10: u16) -> u8 {
    // Masked to 10 bits, the shifted value is at most 255.
    ((code10 & ADC10_MAX) >> 2) as u8
}

/// The firmware's 8-bit code for `volts` on the pin: [`code8_from_adc10`] of [`adc10_code`].
#[must_use]
pub fn code8(volts: f64) -> u8 {
    code8_from_adc10(adc10_code(volts))
}

/// The voltage bin `[low, high)` that reads as 8-bit code `c`: `[c · Vref/256, (c+1) · Vref/256)`
/// (code 255 also takes everything above its upper edge).
#[must_use]
pub fn code8_bin_volts(c: u8) -> (f64, f64) {
    let c = f64::from(c);
    (c * CODE8_LSB_VOLTS, (c + 1.0) * CODE8_LSB_VOLTS)
}

/// The voltage that represents 8-bit code `c`: the centre of its bin, `(c + 0.5) · Vref/256`.
#[must_use]
pub const fn code8_centre_volts(c: u8) -> f64 {
    (c as f64 + 0.5) * CODE8_LSB_VOLTS
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn exact_at_every_10bit_boundary() {
        for k in 1..=ADC10_MAX {
            let t = adc10_threshold_volts(k);
            assert_eq!(
                t,
                f64::from(k) * 5.0 / 1024.0,
                "threshold {k} must be exact"
            );
            assert_eq!(adc10_code(t), k, "at the transition into {k}");
            assert_eq!(
                adc10_code(t.next_down()),
                k - 1,
                "just below the transition into {k}"
            );
        }
    }

    #[test]
    fn clamps_and_nan() {
        assert_eq!(adc10_code(-1.0), 0);
        assert_eq!(adc10_code(-0.0), 0);
        assert_eq!(adc10_code(0.0), 0);
        assert_eq!(adc10_code(f64::NAN), 0);
        assert_eq!(adc10_code(f64::NEG_INFINITY), 0);
        assert_eq!(adc10_code(5.0), 1023);
        assert_eq!(adc10_code(12.0), 1023);
        assert_eq!(adc10_code(f64::INFINITY), 1023);
        assert_eq!(adc10_code(5.0 - ADC10_LSB_VOLTS), 1023);
        assert_eq!(adc10_code((5.0 - ADC10_LSB_VOLTS).next_down()), 1022);
    }

    #[test]
    fn register_and_8bit_code() {
        assert_eq!(addr_register(0), 0);
        assert_eq!(addr_register(1), 0x0040);
        assert_eq!(addr_register(1023), 0xFFC0);
        assert_eq!(
            addr_register(0x3FF | 0xFC00),
            0xFFC0,
            "bits above 10 ignored"
        );
        assert_eq!(code8_from_adc10(1023), 255);
        assert_eq!(code8_from_adc10(4), 1);
        assert_eq!(code8_from_adc10(3), 0);
        for k in 0..=ADC10_MAX {
            // The firmware's byte is the upper byte of the left-justified register.
            assert_eq!(u16::from(code8_from_adc10(k)), addr_register(k) >> 8);
        }
    }

    #[test]
    fn exact_at_every_8bit_boundary() {
        assert!((CODE8_LSB_VOLTS - 0.019_531_25).abs() < 1e-15);
        for c in 1..=255u8 {
            let (lo, hi) = code8_bin_volts(c);
            assert_eq!(code8(lo), c);
            assert_eq!(code8(lo.next_down()), c - 1);
            assert!(code8_centre_volts(c) > lo && code8_centre_volts(c) < hi);
            assert_eq!(code8(code8_centre_volts(c)), c);
        }
    }

    proptest! {
        #[test]
        fn monotone_and_within_one_lsb(a in -1.0f64..6.0, b in -1.0f64..6.0) {
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            prop_assert!(adc10_code(lo) <= adc10_code(hi));
            if (0.0..5.0).contains(&a) {
                let k = adc10_code(a);
                prop_assert!(adc10_threshold_volts(k) <= a);
                prop_assert!(a < adc10_threshold_volts(k + 1));
            }
        }
    }
}
