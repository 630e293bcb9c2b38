//! Numbers and lists as error and warning messages show them: short enough to read whatever
//! value a user typed (a 310-digit number, a list of a million entries), with what was left
//! out counted, so a message stays a line.

/// `v` in a short form: plain with at most four decimals when its magnitude lies in
/// `[10⁻³, 10⁶)` (or it is 0), otherwise scientific with four significant digits (`1.000e12`);
/// `NaN`, `inf` and `-inf` as Rust writes them ([`aeroident_physics::text::Short`]).
pub fn short(v: f64) -> String {
    aeroident_physics::text::Short(v).to_string()
}

/// Longest text [`exact_or_short`] keeps exact ([`aeroident_physics::text::EXACT_MAX`]).
pub use aeroident_physics::text::EXACT_MAX;

/// `v` as Rust writes it (the shortest text that reads back as `v`) when that takes at most
/// [`EXACT_MAX`] characters, else in the [`short`] form
/// ([`aeroident_physics::text::ExactOrShort`]). For values a message compares (a time and the
/// previous one, a value and its limit), which must stay told apart: `1.5708` would hide that
/// `1.57081` passes the limit `1.5707963267948966`, while Rust writes `1e300` out in 301
/// digits.
pub fn exact_or_short(v: f64) -> String {
    aeroident_physics::text::ExactOrShort(v).to_string()
}

/// A count in the short form of [`short`]: in full below 10⁶, else scientific.
pub fn short_count(n: usize) -> String {
    if n < 1_000_000 { n.to_string() } else { format!("{:.3e}", n as f64) }
}

/// The first `max` of `items` joined with `, `, then `… and N more` when some were left out.
pub fn list<T: std::fmt::Display>(items: &[T], max: usize) -> String {
    let shown: Vec<String> = items.iter().take(max).map(ToString::to_string).collect();
    let mut text = shown.join(", ");
    if items.len() > max {
        text.push_str(&format!(" … and {} more", items.len() - max));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_short_whatever_their_size() {
        assert_eq!(short(0.6), "0.6");
        assert_eq!(short(-12.345678), "-12.3457");
        assert_eq!(short(0.0), "0");
        assert_eq!(short(1e300), "1.000e300");
        assert_eq!(short(-2.5e-7), "-2.500e-7");
        assert_eq!(short(f64::NAN), "NaN");
        assert_eq!(short(f64::MAX), "1.798e308");
        assert_eq!(short_count(999_999), "999999");
        assert_eq!(short_count(10_000_000), "1.000e7");
    }

    #[test]
    fn values_are_exact_unless_their_text_is_long() {
        assert_eq!(exact_or_short(std::f64::consts::FRAC_PI_2), "1.5707963267948966");
        assert_eq!(exact_or_short(1234.567891), "1234.567891");
        assert_eq!(exact_or_short(-0.000012345678901234568), "-0.000012345678901234568");
        assert_eq!(exact_or_short(1e300), "1.000e300");
        assert_eq!(exact_or_short(-1e-300), "-1.000e-300");
        assert_eq!(exact_or_short(1e308), "1.000e308");
        assert_eq!(exact_or_short(f64::INFINITY), "inf");
    }

    #[test]
    fn long_lists_are_cut_with_a_count() {
        let v: Vec<u32> = (1..=1_000_000).collect();
        assert_eq!(list(&v, 3), "1, 2, 3 … and 999997 more");
        assert_eq!(list(&v[..2], 3), "1, 2");
        assert_eq!(list::<u32>(&[], 3), "");
    }
}
