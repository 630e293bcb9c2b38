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
