//! Numbers for one-line messages, the same in every front end (the
//! planner's errors, the CLI, the Python bindings): at most 6 significant
//! digits, no trailing zeros.

use alloc::borrow::ToOwned;
use alloc::format;
use alloc::string::String;

/// `x` for a one-line message: plain decimals for moderate magnitudes,
/// scientific (`1e300`, `-2.5e-9`) when the value rounded to 6 significant
/// digits has |x| ≥ 1e6 or |x| < 1e-4 (zero excepted), and `inf`, `-inf`,
/// `NaN` for non-finite values. Examples: 0.5 → `0.5`, 5.0 → `5`,
/// 3.491234567 → `3.49123`, 1e-9 → `1e-9`, 1e300 → `1e300`.
pub fn readable(x: f64) -> String {
    if x.is_nan() {
        return "NaN".to_owned();
    }
    if x.is_infinite() {
        return if x > 0.0 { "inf" } else { "-inf" }.to_owned();
    }
    if x == 0.0 {
        return "0".to_owned();
    }
    // The exponent after rounding to 6 significant digits.
    let sci = format!("{x:.5e}");
    let (mantissa, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    if !(-4..6).contains(&exp) {
        return format!("{}e{exp}", strip_zeros(mantissa));
    }
    let decimals = usize::try_from(5 - exp).unwrap_or(0);
    strip_zeros(&format!("{x:.decimals$}")).to_owned()
}

/// "1.50000" → "1.5", "2.00000" → "2", "300" → "300".
fn strip_zeros(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::readable;

    #[test]
    fn examples() {
        for (x, want) in [
            (1e300, "1e300"),
            (0.5, "0.5"),
            (5.0, "5"),
            (1e-9, "1e-9"),
            (3.491234567, "3.49123"),
            (-2.5e-9, "-2.5e-9"),
            (123456.0, "123456"),
            (999999.4, "999999"),
            (999999.7, "1e6"),
            (1e6, "1e6"),
            (1234567.0, "1.23457e6"),
            (1e-4, "0.0001"),
            (9.99999e-5, "9.99999e-5"),
            (0.000123456789, "0.000123457"),
            (-42.0, "-42"),
            (100.0, "100"),
            (0.0, "0"),
            (-0.0, "0"),
            (f64::INFINITY, "inf"),
            (f64::NEG_INFINITY, "-inf"),
            (f64::NAN, "NaN"),
            (f64::MAX, "1.79769e308"),
            (f64::MIN_POSITIVE, "2.22507e-308"),
            (5e-324, "4.94066e-324"),
        ] {
            assert_eq!(readable(x), want, "{x:e}");
        }
    }

    #[test]
    fn round_trips_to_six_digits() {
        for &x in &[1.0, 0.1, 7.25, 12345.6, 0.00271828, 3.3e-7, 6.02214e23] {
            let back: f64 = readable(x).parse().unwrap();
            assert!((back - x).abs() <= 5e-6 * x.abs(), "{x} {back}");
        }
    }
}
