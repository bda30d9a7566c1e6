//! The nominal output curve of a Sharp GP2Y0A21YK / GP2D12-class IR distance sensor (docs/design.md §3.1).
//!
//! Far branch (d ≥ 8 cm, d in cm): `V(d) = 28.48 / (d + 3.0) + 0.059` V, the design's fit to the
//! datasheet curve. It is the authority for d ≥ 8 cm, so the modelled peak is
//! `V(8 cm) = 2.648 V` (the often-quoted "≈ 3.2 V" peak is the formula's value at 6 cm; see the
//! crate docs). Beyond 80 cm the same 1/d fall continues (0.402 V at 80 cm, 0.087 V at 10 m).
//!
//! Fold-back branch (d < 8 cm): a straight line from [`FOLDBACK_CONTACT_VOLTS`] at contact up
//! to `V(8 cm)`, continuous with the far branch. Every voltage of the fold-back branch below
//! `V(8 cm)` is also produced by exactly one far distance: the ambiguity the firmware cannot
//! resolve (docs/design.md §3.3).

use crate::error::SensorError;

/// Numerator of the far-branch fit, 28.48 V·cm (docs/design.md §3.1, fit to the GP2Y0A21YK datasheet curve).
pub const CURVE_K_VOLT_CM: f64 = 28.48;
/// Distance offset of the far-branch fit, 3.0 cm (docs/design.md §3.1).
pub const CURVE_D0_CM: f64 = 3.0;
/// Asymptotic voltage of the far-branch fit, 0.059 V (docs/design.md §3.1).
pub const CURVE_V_INF_VOLTS: f64 = 0.059;
/// Start of the far branch (the curve's peak), 8 cm = 80 mm (docs/design.md §3.1).
pub const FAR_BRANCH_MIN_MM: f64 = 80.0;
/// Output at contact on the fold-back branch, 0.75 V: the middle of docs/design.md §3.1's "≈ 0.5–1 V at
/// contact" (an assumption; the datasheet does not specify the curve below 10 cm).
pub const FOLDBACK_CONTACT_VOLTS: f64 = 0.75;
/// Near end of the datasheet's valid range, 10 cm = 100 mm (docs/design.md §3.1; GP2Y0A21YK datasheet).
pub const VALID_RANGE_MIN_MM: f64 = 100.0;
/// Far end of the datasheet's valid range, 80 cm = 800 mm (docs/design.md §3.1; GP2Y0A21YK datasheet).
pub const VALID_RANGE_MAX_MM: f64 = 800.0;
/// The distance that "nothing hit" (`None`) reads as, 10 m: far beyond any arena (1.8 m
/// square, 3 m corridor, docs/design.md §5), where the curve is within 3 mV of its asymptote. Distances
/// beyond it read as it, too (a choice of this crate).
pub const NOTHING_HIT_MM: f64 = 10_000.0;

/// Far-branch voltage at `d_cm` centimetres (no range checks; meaningful for d ≥ 8 cm).
#[must_use]
pub const fn far_branch_volts_at_cm(d_cm: f64) -> f64 {
    CURVE_K_VOLT_CM / (d_cm + CURVE_D0_CM) + CURVE_V_INF_VOLTS
}

/// Inverse of the far branch: the distance in cm at which it gives `volts`
/// (`+∞` at or below the asymptote 0.059 V; no other checks).
#[must_use]
pub const fn far_branch_cm_at_volts(volts: f64) -> f64 {
    if volts <= CURVE_V_INF_VOLTS {
        return f64::INFINITY;
    }
    CURVE_K_VOLT_CM / (volts - CURVE_V_INF_VOLTS) - CURVE_D0_CM
}

/// The nominal curve's peak, `V(8 cm)` = 2.648 V.
pub const PEAK_VOLTS: f64 = far_branch_volts_at_cm(FAR_BRANCH_MIN_MM / 10.0);
/// Nominal output at 80 cm, 0.402 V (datasheet typical 0.4 V).
pub const NOMINAL_V_80CM_VOLTS: f64 = far_branch_volts_at_cm(80.0);
/// Nominal output difference between 10 cm and 80 cm, 1.848 V (datasheet range 1.75–2.25 V).
pub const NOMINAL_DV_80_TO_10CM_VOLTS: f64 = far_branch_volts_at_cm(10.0) - NOMINAL_V_80CM_VOLTS;

/// Check a distance and apply the "nothing hit" convention: `None` and anything beyond
/// [`NOTHING_HIT_MM`] (including `+∞`) give [`NOTHING_HIT_MM`]; NaN and negatives are errors.
pub fn effective_distance_mm(distance_mm: Option<f64>) -> Result<f64, SensorError> {
    match distance_mm {
        None => Ok(NOTHING_HIT_MM),
        Some(d) if d.is_nan() || d < 0.0 => Err(SensorError::BadDistance {
            value: d,
            far_mm: NOTHING_HIT_MM,
        }),
        Some(d) => Ok(d.min(NOTHING_HIT_MM)),
    }
}

/// The nominal curve at a distance already checked by [`effective_distance_mm`].
#[must_use]
pub(crate) fn nominal_volts_checked(d_mm: f64) -> f64 {
    if d_mm >= FAR_BRANCH_MIN_MM {
        far_branch_volts_at_cm(d_mm / 10.0)
    } else {
        FOLDBACK_CONTACT_VOLTS + (PEAK_VOLTS - FOLDBACK_CONTACT_VOLTS) * (d_mm / FAR_BRANCH_MIN_MM)
    }
}

/// The nominal (typical-sensor, noiseless) output in volts at `distance_mm`.
///
/// `None` means nothing hit and reads as [`NOTHING_HIT_MM`]. NaN or negative distances are
/// errors.
pub fn nominal_volts(distance_mm: Option<f64>) -> Result<f64, SensorError> {
    effective_distance_mm(distance_mm).map(nominal_volts_checked)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v(d_mm: f64) -> f64 {
        nominal_volts(Some(d_mm)).unwrap()
    }

    #[test]
    fn key_points_of_the_curve() {
        assert!((v(80.0) - 2.6481).abs() < 1e-4, "peak {}", v(80.0));
        assert_eq!(v(80.0), PEAK_VOLTS);
        // the often-quoted "3.2 V" peak is the formula's value at 6 cm.
        assert!((far_branch_volts_at_cm(6.0) - 3.2234).abs() < 1e-4);
        assert!((v(100.0) - 2.2498).abs() < 1e-4);
        assert!((v(800.0) - 0.4021).abs() < 1e-4);
        assert!((NOMINAL_DV_80_TO_10CM_VOLTS - 1.8477).abs() < 1e-4);
        assert_eq!(v(0.0), FOLDBACK_CONTACT_VOLTS);
        assert!((0.5..=1.0).contains(&FOLDBACK_CONTACT_VOLTS));
        // Continuity at the peak: the fold-back line ends where the far branch starts.
        let below = v(80.0f64.next_down());
        assert!((below - PEAK_VOLTS).abs() < 1e-12);
    }

    #[test]
    fn nothing_hit_and_bad_distances() {
        let far = nominal_volts(None).unwrap();
        assert_eq!(far, v(NOTHING_HIT_MM));
        assert!((far - (28.48 / 1003.0 + 0.059)).abs() < 1e-12);
        assert_eq!(v(1e9), far);
        assert_eq!(v(f64::INFINITY), far);
        assert!(matches!(
            nominal_volts(Some(f64::NAN)),
            Err(SensorError::BadDistance { .. })
        ));
        let err = nominal_volts(Some(-1.0)).unwrap_err();
        assert!(err.to_string().contains("distance_mm = -1"), "{err}");
    }

    #[test]
    fn fold_back_ambiguity_is_real() {
        // The reading at 5 cm equals the reading at one distance beyond 10 cm.
        let v5 = v(50.0);
        let d_far_cm = far_branch_cm_at_volts(v5);
        assert!(d_far_cm > 10.0, "far twin at {d_far_cm} cm");
        // Find the twin independently, by bisection on the forward curve over 10–80 cm.
        let (mut lo, mut hi) = (100.0, 800.0);
        assert!(v(lo) > v5 && v(hi) < v5);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if v(mid) > v5 { lo = mid } else { hi = mid }
        }
        assert!((lo / 10.0 - d_far_cm).abs() < 1e-9);
        assert!((v(lo) - v5).abs() < 1e-9);
        // ... and the firmware's 8-bit codes of the two agree as well.
        assert_eq!(crate::adc::code8(v5), crate::adc::code8(v(lo)));
    }

    proptest! {
        #[test]
        fn far_branch_strictly_decreasing(a in 80.0f64..10_000.0, b in 80.0f64..10_000.0) {
            prop_assume!(a != b);
            let (near, far) = if a < b { (a, b) } else { (b, a) };
            prop_assert!(v(near) > v(far), "V({near}) = {} vs V({far}) = {}", v(near), v(far));
        }

        #[test]
        fn fold_back_strictly_increasing(a in 0.0f64..80.0, b in 0.0f64..80.0) {
            prop_assume!(a != b);
            let (near, far) = if a < b { (a, b) } else { (b, a) };
            prop_assert!(v(near) < v(far));
            prop_assert!(v(far) <= PEAK_VOLTS);
        }

        #[test]
        fn inverse_round_trips(d_cm in 8.0f64..1000.0) {
            let back = far_branch_cm_at_volts(far_branch_volts_at_cm(d_cm));
            prop_assert!((back - d_cm).abs() < 1e-9 * d_cm.max(1.0) * 100.0);
        }

        #[test]
        fn every_fold_back_reading_has_a_far_twin(d in 0.0f64..80.0) {
            let twin_cm = far_branch_cm_at_volts(v(d));
            prop_assert!(twin_cm >= 8.0 - 1e-9);
            prop_assert!((v(twin_cm * 10.0) - v(d)).abs() < 1e-9);
        }
    }
}
