//! Numbers as messages show them, without allocating (the crate is `no_std`): short enough to
//! read whatever value a user typed (a 310-digit number, 1e300), so a message stays a line.

use core::fmt;

/// Displays its value in a short form: plain with at most four decimals when the magnitude lies
/// in `[10⁻³, 10⁶)` (or it is 0), otherwise scientific with four significant digits
/// (`1.000e12`); `NaN`, `inf` and `-inf` as Rust writes them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Short(pub f64);

impl fmt::Display for Short {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if !v.is_finite() {
            write!(f, "{v}")
        } else if v == 0.0 || (1e-3..1e6).contains(&libm::fabs(v)) {
            // Rounded to four decimals, then written as Rust writes it (no trailing zeros).
            write!(f, "{}", libm::round(v * 1e4) / 1e4)
        } else {
            write!(f, "{v:.3e}")
        }
    }
}

/// The longest text [`ExactOrShort`] keeps exact: room for the 17 significant digits of any
/// `f64`, a sign, a point and a few zeros (`-0.000012345678901234568`).
pub const EXACT_MAX: usize = 24;

/// Displays its value as Rust writes it (the shortest text that reads back as the value) when
/// that takes at most [`EXACT_MAX`] characters, else as [`Short`]: values a message compares
/// stay told apart, while `1e300` is not written out in 301 digits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactOrShort(pub f64);

impl fmt::Display for ExactOrShort {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        /// Counts the characters written instead of keeping them.
        struct Count(usize);
        impl fmt::Write for Count {
            fn write_str(&mut self, s: &str) -> fmt::Result {
                self.0 += s.chars().count();
                Ok(())
            }
        }
        let mut n = Count(0);
        fmt::Write::write_fmt(&mut n, format_args!("{}", self.0))?;
        if n.0 <= EXACT_MAX { write!(f, "{}", self.0) } else { write!(f, "{}", Short(self.0)) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;
    use std::string::ToString;

    /// Ordinary values exactly, 1e300 and 1e-300 short, non-finite values as Rust writes them.
    #[test]
    fn exact_when_short_else_short() {
        assert_eq!(ExactOrShort(1.2345678901234567).to_string(), "1.2345678901234567");
        assert_eq!(ExactOrShort(-40.0).to_string(), "-40");
        assert_eq!(ExactOrShort(1e300).to_string(), "1.000e300");
        assert_eq!(ExactOrShort(1e-300).to_string(), "1.000e-300");
        assert_eq!(ExactOrShort(f64::NAN).to_string(), "NaN");
        assert_eq!(ExactOrShort(1e20).to_string(), "100000000000000000000");
        assert_eq!(ExactOrShort(1e24).to_string(), "1.000e24");
    }
}
