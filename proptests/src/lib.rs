//! Property tests of h8swarm live in `tests/`; this library holds only what they share: how
//! many cases each property runs.
#![forbid(unsafe_code)]

/// The number of cases each property runs when `PROPTEST_CASES` is not set.
pub const DEFAULT_CASES: u32 = 10_000;

/// Cases per property: `PROPTEST_CASES` when it is set (lower for a mutation run, higher for a
/// soak), [`DEFAULT_CASES`] otherwise.
///
/// # Panics
/// When `PROPTEST_CASES` is set but is not a whole number from 1 to 4 294 967 295: a test run
/// with a mistyped case count should stop, not quietly run some other number of cases.
#[must_use]
pub fn cases() -> u32 {
    cases_from(std::env::var_os("PROPTEST_CASES").as_deref())
}

/// [`cases`] for a given value of `PROPTEST_CASES` (`None`: not set).
///
/// # Panics
/// When `value` is set but is not a whole number from 1 to 4 294 967 295.
#[must_use]
pub fn cases_from(value: Option<&std::ffi::OsStr>) -> u32 {
    let Some(value) = value else {
        return DEFAULT_CASES;
    };
    match value.to_str().and_then(|v| v.trim().parse::<u32>().ok()) {
        Some(n) if n > 0 => n,
        _ => panic!(
            "PROPTEST_CASES = {value:?} is not a number of cases: give a whole number from 1 to {}",
            u32::MAX
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::OsStr;

    #[test]
    fn ten_thousand_unless_proptest_cases_says_otherwise() {
        assert_eq!(cases_from(None), 10_000);
        assert_eq!(cases_from(Some(OsStr::new("250"))), 250);
        assert_eq!(cases_from(Some(OsStr::new(" 100000\n"))), 100_000);
        for bad in ["", "0", "-5", "1e4", "ten", "4294967296"] {
            let r = std::panic::catch_unwind(|| cases_from(Some(OsStr::new(bad))));
            assert!(r.is_err(), "{bad:?} must be refused");
        }
    }
}
