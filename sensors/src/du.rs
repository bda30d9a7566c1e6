//! The firmware's linearisation table: 8-bit A/D code → distance units (docs/design.md §3.3).
//!
//! `1 du = 80/255 cm ≈ 3.14 mm`; `p = 255` means "80 cm or more". The table inverts the
//! *nominal* far branch of the curve ([`crate::curve`]), as firmware built from the datasheet
//! would:
//!
//! - code `c` stands for the centre of its voltage bin, `v_c = (c + 0.5) · 5 V / 256`
//!   ([`crate::adc::code8_centre_volts`]): the unbiased choice for a truncating converter;
//! - `DU_TABLE[c] = round(d(v_c) · 255/80)` with `d(v) = 28.48 / (v − 0.059) − 3` cm, rounded
//!   half up and clamped to `0..=255`; codes at or below the asymptote (c ≤ 2) give 255;
//! - codes above the peak `V(8 cm) = 2.648 V` (c ≥ 136; code 135 straddles it) extrapolate the
//!   same inverse formula, as firmware that simply evaluates the formula would: they give 25 du
//!   (8 cm) down to 9 du (2.8 cm) at code 255. Nominal sensors never produce them; sensors with
//!   a higher gain than nominal do, near 8 cm.
//!
//! A fold-back reading (d < 8 cm) therefore reads as its far twin: farther than it is.
//!
//! **Where the table is exact to half a du.** Where the curve is steep, one 8-bit code spans
//! at most one du of distance; the [`STEEP_CODES`] are exactly the codes whose voltage bin lies
//! on the far branch (above the asymptote, at or below the peak) and spans ≤ 1 du: codes 71–134,
//! i.e. 8.05–18.45 cm. There every entry is within 0.5 du of the curve's distance at `v_c`, and
//! any distance that reads as one of these codes is read within `0.5 + span` du (< 1.5 du).
//! Below code 71 (beyond 18.45 cm) one code step covers more than a du, up to 15 du at 80 cm:
//! the table cannot be finer than the converter.

use crate::adc::code8_centre_volts;
use crate::curve::{CURVE_D0_CM, CURVE_K_VOLT_CM, CURVE_V_INF_VOLTS};

/// Distance units per centimetre: 255 du = 80 cm (docs/design.md §3.3).
pub const DU_PER_CM: f64 = 255.0 / 80.0;
/// Millimetres per distance unit, 80/255 cm ≈ 3.137 mm (docs/design.md §3.3).
pub const MM_PER_DU: f64 = 800.0 / 255.0;
/// The largest proximity, meaning "80 cm or more / nothing seen" (docs/design.md §2.1, §3.3).
pub const DU_MAX: u8 = 255;
/// The codes where one code step spans at most one du on the far branch (see the module docs):
/// there the table is exact to half a du.
pub const STEEP_CODES: core::ops::RangeInclusive<u8> = 71..=134;

/// The table entry for one code, computed as the module docs say (usable in `const`).
#[must_use]
pub const fn du_for_code(c: u8) -> u8 {
    let v = code8_centre_volts(c);
    if v <= CURVE_V_INF_VOLTS {
        return DU_MAX;
    }
    let d_cm = CURVE_K_VOLT_CM / (v - CURVE_V_INF_VOLTS) - CURVE_D0_CM;
    let du = d_cm * DU_PER_CM;
    if du >= DU_MAX as f64 {
        DU_MAX
    } else if du <= 0.0 {
        0
    } else {
        // Round half up; du lies in (0, 255) here, so the cast cannot saturate.
        (du + 0.5) as u8
    }
}

const fn build_table() -> [u8; 256] {
    let mut t = [0u8; 256];
    let mut c = 0usize;
    while c < 256 {
        t[c] = du_for_code(c as u8);
        c += 1;
    }
    t
}

/// The firmware's ROM table: `DU_TABLE[c]` is the proximity in du for 8-bit A/D code `c`
/// (computed at compile time; see the module docs for the exact rule).
pub const DU_TABLE: [u8; 256] = build_table();

/// Convert a distance in millimetres to distance units, unrounded (no clamping).
#[must_use]
pub fn mm_to_du(distance_mm: f64) -> f64 {
    distance_mm / MM_PER_DU
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adc::{code8, code8_bin_volts};
    use crate::curve::{PEAK_VOLTS, far_branch_volts_at_cm, nominal_volts};

    fn v(d_mm: f64) -> f64 {
        nominal_volts(Some(d_mm)).unwrap()
    }

    /// The far-branch distance (du) at `volts`, found by bisection on the forward formula
    /// (unclamped, out to 10^10 cm), not through the closed-form inverse the table uses.
    fn du_by_bisection(volts: f64) -> f64 {
        let (mut near_cm, mut far_cm) = (8.0, 1e10);
        assert!(
            far_branch_volts_at_cm(near_cm) >= volts && far_branch_volts_at_cm(far_cm) <= volts
        );
        for _ in 0..200 {
            let mid = 0.5 * (near_cm + far_cm);
            if far_branch_volts_at_cm(mid) > volts {
                near_cm = mid
            } else {
                far_cm = mid
            }
        }
        mm_to_du(near_cm * 10.0)
    }

    /// Distance span (du) of the far-branch distances whose voltage falls in code `c`'s bin.
    fn span_du(c: u8) -> f64 {
        let (lo, hi) = code8_bin_volts(c);
        du_by_bisection(lo) - du_by_bisection(hi)
    }

    #[test]
    fn monotone_non_increasing() {
        for c in 1..=255usize {
            assert!(
                DU_TABLE[c] <= DU_TABLE[c - 1],
                "code {c}: {} > {}",
                DU_TABLE[c],
                DU_TABLE[c - 1]
            );
        }
    }

    #[test]
    fn end_points() {
        // 255 for every code whose centre is at or below V(80 cm) = 0.402 V (c ≤ 20) ...
        for (c, &du) in DU_TABLE.iter().enumerate().take(21) {
            assert_eq!(du, 255, "code {c}");
        }
        // ... and not above it.
        assert!(DU_TABLE[21] < 255);
        // Extrapolated top end: code 255 (4.99 V) reads 2.78 cm = 8.85 du.
        assert_eq!(DU_TABLE[255], 9);
        assert_eq!(DU_TABLE, build_table());
    }

    #[test]
    fn steep_range_is_exactly_where_one_code_spans_at_most_one_du() {
        for c in 0..=255u8 {
            let (lo, hi) = code8_bin_volts(c);
            let on_far_branch = lo > CURVE_V_INF_VOLTS && hi <= PEAK_VOLTS;
            let steep = on_far_branch && span_du(c) <= 1.0;
            assert_eq!(steep, STEEP_CODES.contains(&c), "code {c}");
        }
    }

    #[test]
    fn within_half_a_du_where_steep() {
        for c in STEEP_CODES {
            let exact = du_by_bisection(code8_centre_volts(c));
            let err = (f64::from(DU_TABLE[usize::from(c)]) - exact).abs();
            assert!(
                err <= 0.5,
                "code {c}: table {} vs curve {exact:.3}",
                DU_TABLE[usize::from(c)]
            );
        }
    }

    #[test]
    fn distances_read_back_within_half_a_du_plus_the_bin_span() {
        // Every 0.01 mm from 8 cm to 20 cm: where the code is a steep one, the table's du is
        // within 0.5 du (rounding) + the bin's span of the true du.
        let mut checked = 0;
        for i in 0..=12_000 {
            let d_mm = 80.0 + f64::from(i) * 0.01;
            let c = code8(v(d_mm));
            if !STEEP_CODES.contains(&c) {
                continue;
            }
            checked += 1;
            let err = (f64::from(DU_TABLE[usize::from(c)]) - mm_to_du(d_mm)).abs();
            let bound = 0.5 + span_du(c);
            assert!(
                err <= bound,
                "{d_mm} mm: code {c}, err {err:.3} > {bound:.3}"
            );
            assert!(err < 1.5);
        }
        assert!(checked > 10_000);
    }

    #[test]
    fn fold_back_is_misread_as_farther() {
        // Up to 7 cm the far twin is more than 1.5 du beyond the true distance, so neither the
        // 8-bit quantisation nor the table's rounding can hide it.
        for i in 0..=700 {
            let d_mm = f64::from(i) * 0.1;
            let read = DU_TABLE[usize::from(code8(v(d_mm)))];
            assert!(
                f64::from(read) > mm_to_du(d_mm) + 1.5,
                "{d_mm} mm read as {read} du"
            );
        }
        // 5 cm (16 du) reads as code 99, about 12.1 cm: 39 du.
        assert_eq!(code8(v(50.0)), 99);
        assert_eq!(DU_TABLE[99], 39);
    }
}
