//! The number formats of docs/design.md §2.1 and the integer helpers every other module shares.
//!
//! All formats are two's complement, as the H8/300H computes them:
//!
//! | quantity | type | format |
//! |---|---|---|
//! | input x_i | [`Q7`] (i8) | 1 sign bit, 7 fraction bits: [−1, 1) |
//! | weight w_ij, output O_j, learning rate η | [`Q15`] (i16) | [−1, 1) |
//! | weighted sum y_j | [`Q22`] (i32) | Q15 × Q7 products, summed exactly |
//!
//! The learner computes on the raw bits (`to_bits`), exactly as the firmware does; the `fixed`
//! types give the values their meaning at the API and let a caller convert to and from reals.

/// A Q7 fixed-point number (an `i8` with 7 fraction bits): the network's inputs.
pub type Q7 = fixed::types::I1F7;
/// A Q15 fixed-point number (an `i16` with 15 fraction bits): weights, outputs and η.
pub type Q15 = fixed::types::I1F15;
/// A Q22 fixed-point number (an `i32` with 22 fraction bits): a weighted sum of Q15 × Q7 products.
pub type Q22 = fixed::types::I10F22;

/// Saturates an `i32` to the `i16` range.
#[inline(always)]
#[must_use]
pub const fn sat16(v: i32) -> i16 {
    if v > i16::MAX as i32 {
        i16::MAX
    } else if v < i16::MIN as i32 {
        i16::MIN
    } else {
        v as i16
    }
}

/// Saturates an `i16` to the `i8` range.
#[inline(always)]
#[must_use]
pub const fn sat8(v: i16) -> i8 {
    if v > i8::MAX as i16 {
        i8::MAX
    } else if v < i8::MIN as i16 {
        i8::MIN
    } else {
        v as i8
    }
}

/// `round_half_away_from_zero(v / 2^7)`: the Q15 × Q7 → Q15 rescaling of the update (docs/design.md §2.4),
/// for |v| ≤ 2^30 (the update's products are at most 32767 · 128 < 2^22).
///
/// Odd-symmetric (`round7(−v) = −round7(v)`), which lets the firmware fold the sign of E into η
/// before multiplying. Computed without a branch (the sign is a mask), because the sign of η·x_i
/// is as good as random and a mispredicted branch per input costs more than the arithmetic.
#[inline(always)]
#[must_use]
pub const fn round_half_away_shr7(v: i32) -> i32 {
    let sign = v >> 31; // 0 or −1
    let magnitude = (v ^ sign) - sign;
    (((magnitude + 64) >> 7) ^ sign) - sign
}

/// A proximity reading in distance units (0 = touching … 255 = 80 cm or more) as a Q7 input:
/// `p − 128` (docs/design.md §2.2).
#[inline(always)]
#[must_use]
pub const fn proximity_to_q7(p: u8) -> i8 {
    (p as i16 - 128) as i8
}

/// A Q15 output fed back as a Q7 input: `O >> 8`, an arithmetic shift (docs/design.md §2.2).
#[inline(always)]
#[must_use]
pub const fn output_to_q7(o: i16) -> i8 {
    (o >> 8) as i8
}

/// The previous evaluation as a Q7 input: `sat_i8(E >> 3)`, an arithmetic shift (docs/design.md §2.2).
#[inline(always)]
#[must_use]
pub const fn evaluation_to_q7(e: i16) -> i8 {
    sat8(e >> 3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saturation_clamps_at_both_ends() {
        assert_eq!(sat16(32_767), 32_767);
        assert_eq!(sat16(32_768), 32_767);
        assert_eq!(sat16(-32_768), -32_768);
        assert_eq!(sat16(-32_769), -32_768);
        assert_eq!(sat16(i32::MAX), 32_767);
        assert_eq!(sat16(i32::MIN), -32_768);
        assert_eq!(sat8(127), 127);
        assert_eq!(sat8(128), 127);
        assert_eq!(sat8(-129), -128);
    }

    #[test]
    fn rounding_is_half_away_from_zero_and_odd() {
        assert_eq!(round_half_away_shr7(63), 0);
        assert_eq!(round_half_away_shr7(64), 1);
        assert_eq!(round_half_away_shr7(191), 1);
        assert_eq!(round_half_away_shr7(192), 2);
        assert_eq!(round_half_away_shr7(-63), 0);
        assert_eq!(round_half_away_shr7(-64), -1);
        assert_eq!(round_half_away_shr7(-192), -2);
        for v in -100_000..100_000 {
            assert_eq!(round_half_away_shr7(-v), -round_half_away_shr7(v));
            let exact = f64::from(v) / 128.0;
            let r = f64::from(round_half_away_shr7(v));
            assert!((r - exact).abs() <= 0.5, "{v}");
            if (r - exact).abs() == 0.5 {
                assert!(r.abs() > exact.abs(), "ties go away from zero: {v}");
            }
        }
    }

    #[test]
    fn input_conversions_follow_spec_2_2() {
        assert_eq!(proximity_to_q7(0), -128);
        assert_eq!(proximity_to_q7(128), 0);
        assert_eq!(proximity_to_q7(255), 127);
        assert_eq!(output_to_q7(i16::MIN), -128);
        assert_eq!(output_to_q7(i16::MAX), 127);
        assert_eq!(output_to_q7(-1), -1);
        assert_eq!(evaluation_to_q7(1020), 127);
        assert_eq!(evaluation_to_q7(-1020), -128);
        assert_eq!(evaluation_to_q7(-1), -1);
        assert_eq!(evaluation_to_q7(15), 1);
    }
}
