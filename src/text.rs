//! How numbers are written in messages: short, whatever their size. `1e308` prints as `1e308`,
//! not as 309 digits, and a ratio of 10³⁰⁰ as `1e300`; ordinary values keep their plain form.

/// Significant digits kept in a message.
const DIGITS: usize = 4;

/// `x` in at most [`DIGITS`] significant digits: plain between 1e-3 and 1e6, scientific
/// (`2.5e-15`, `1e308`) outside, with trailing zeros dropped. Infinities and NaN print as
/// `inf`, `-inf` and `NaN`.
pub fn short(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".to_string();
    }
    // Rounded to DIGITS significant digits first, so that 999 999.9 is 1e6 and 0.00099999
    // is 0.001 (what `round_significant(x, DIGITS)` gives, from the one formatting).
    let sci = format!("{x:.*e}", DIGITS - 1);
    let rounded: f64 = sci.parse().unwrap_or(x);
    if (1e-3..1e6).contains(&rounded.abs()) {
        let decimals = (DIGITS as i32 - 1 - rounded.abs().log10().floor() as i32).max(0);
        return trim(&format!("{rounded:.*}", decimals as usize));
    }
    let (mantissa, exponent) = sci.split_once('e').unwrap_or((&sci, "0"));
    format!("{}e{exponent}", trim(mantissa))
}

/// `x` rounded to `digits` (at least 1) significant digits, as its decimal form in scientific
/// notation rounds it.
pub fn round_significant(x: f64, digits: usize) -> f64 {
    format!("{x:.*e}", digits.max(1) - 1).parse().unwrap_or(x)
}

/// Drops trailing zeros after a decimal point, and the point itself if nothing follows it.
fn trim(s: &str) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s.to_string()
    }
}

/// `text` on one line: control characters (a newline in a name, a key or a path) written as
/// escapes, so that an error message stays the one line the command line promises.
pub fn one_line(text: &str) -> String {
    if !text.chars().any(char::is_control) {
        return text.to_string();
    }
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{round_significant, short};

    #[test]
    fn numbers_print_short_whatever_their_size() {
        assert_eq!(short(1e308), "1e308");
        assert_eq!(short(-1e300), "-1e300");
        assert_eq!(short(1e-15), "1e-15");
        assert_eq!(short(2.5e-300), "2.5e-300");
        assert_eq!(short(0.01), "0.01");
        assert_eq!(short(2.0), "2");
        assert_eq!(short(-1.0), "-1");
        assert_eq!(short(0.0), "0");
        assert_eq!(short(123.456789), "123.5");
        assert_eq!(short(999_999.9), "1e6");
        assert_eq!(short(1.23456e9), "1.235e9");
        assert_eq!(short(0.000_999_99), "0.001");
        assert_eq!(short(f64::INFINITY), "inf");
        assert_eq!(short(f64::NAN), "NaN");
        // Every output parses back to within the kept digits.
        for &x in &[3.3e-7, 7.77e12, 0.123_456, 4.2e5, 1.0e6, 9.9996e-4] {
            let back: f64 = short(x).parse().unwrap();
            assert!((back - x).abs() <= 1e-3 * x.abs(), "{x} -> {}", short(x));
        }
    }

    #[test]
    fn rounding_keeps_the_significant_digits_asked_for() {
        assert_eq!(round_significant(5.4356e-3, 3), 5.44e-3);
        assert_eq!(round_significant(0.009_999_9, 3), 0.01);
        assert_eq!(round_significant(123_456.0, 2), 120_000.0);
        assert_eq!(round_significant(-2.345, 1), -2.0);
        assert_eq!(round_significant(0.0, 3), 0.0);
        assert_eq!(round_significant(7.0, 0), 7.0);
    }
}
