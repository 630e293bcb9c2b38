//! Fast plain-decimal text of `f64` for the large CSV files (`aeroident run`'s time series, a
//! replay's `estimates.csv`): the layout of `{}` (`Display`), written from Ryu's shortest
//! round-trip digits (the `ryu` crate) into a reused buffer instead of `core::fmt`'s machinery,
//! which was a third of `aeroident run`'s wall time on the time series.
//!
//! `Display` and Ryu both print the shortest digit string that reads back to the same `f64`
//! (the nearest one when several are that short). They differ in layout, which [`push_f64`]
//! undoes (Ryu writes `1.0`, `1e-7`, `1.5e20` where `Display` writes `1`, `0.0000001`,
//! `150000000000000000000`), and in one rare case: when `x` lies exactly halfway between the
//! two nearest shortest strings (e.g. `1308548795726862.25`, whose neighbours `.2` and `.3`
//! both read back to it), Ryu rounds the last digit to even and `core::fmt` up. Either text
//! reads back to the same `x` (tests: against `Display` itself and against parsing).

/// Appends `x` to `out` exactly as `write!(out, "{x}")` would.
pub fn push_f64(out: &mut String, buf: &mut ryu::Buffer, x: f64) {
    if !x.is_finite() {
        // NaN, inf, -inf: rare, and `Display` names them.
        out.push_str(&x.to_string());
        return;
    }
    let s = buf.format_finite(x);
    let (sign, body) = match s.strip_prefix('-') {
        Some(b) => ("-", b),
        None => ("", s),
    };
    out.push_str(sign);
    match body.split_once('e') {
        None => out.push_str(body.strip_suffix(".0").unwrap_or(body)),
        Some((mantissa, exp)) => {
            let exp: i32 = exp.parse().unwrap_or(0);
            let (int, frac) = mantissa.split_once('.').unwrap_or((mantissa, ""));
            push_plain(out, int, frac, exp);
        }
    }
}

/// Appends `x` rounded to `digits` (1–17) significant digits, in Ryu's layout (`0.001234`,
/// `1.234e-9`: an exponent outside its plain range, so a tiny value is not a run of zeros);
/// zero and non-finite values as [`push_f64`] writes them. The rounding is to nearest, ties to
/// even, of `x` scaled by a power of ten: the decimal `format!("{x:.*e}", digits - 1)` gives,
/// except that a value within an ulp of a tie may round to the other side (one unit of the
/// last digit), since the scaling itself rounds. A result whose shortest text would need more
/// digits (the scaled value missed its decimal, or `x` is subnormal or beyond 10^±22) is
/// written by that formatting instead.
pub fn push_significant(out: &mut String, buf: &mut ryu::Buffer, x: f64, digits: usize) {
    if x == 0.0 || !x.is_finite() {
        push_f64(out, buf, x);
        return;
    }
    let shift = digits as i32 - 1 - x.abs().log10().floor() as i32;
    // Powers of ten up to 10^22 are exact doubles, so the quotient is correctly rounded.
    let rounded = match shift {
        0..=22 => (x * 10f64.powi(shift)).round_ties_even() / 10f64.powi(shift),
        -22..=-1 => (x / 10f64.powi(-shift)).round_ties_even() * 10f64.powi(-shift),
        _ => f64::NAN,
    };
    let text = buf.format(rounded);
    let mantissa = text.split('e').next().unwrap_or(text);
    let sig = mantissa.bytes().filter(u8::is_ascii_digit).skip_while(|d| *d == b'0').count();
    if rounded.is_finite() && sig <= digits {
        out.push_str(text.strip_suffix(".0").unwrap_or(text));
    } else {
        out.push_str(&format!("{x:.*e}", digits.saturating_sub(1)));
    }
}

/// The digits `int frac` (one leading digit, `int.frac × 10^exp`) without an exponent.
fn push_plain(out: &mut String, int: &str, frac: &str, exp: i32) {
    // Position of the decimal point after the first digit of `int frac`.
    let point = int.len() as i32 + exp;
    let digits_len = (int.len() + frac.len()) as i32;
    let digit = |k: i32| {
        let k = k as usize;
        if k < int.len() { int.as_bytes()[k] } else { frac.as_bytes()[k - int.len()] }
    };
    if point <= 0 {
        out.push_str("0.");
        out.extend(std::iter::repeat_n('0', (-point) as usize));
        (0..digits_len).for_each(|k| out.push(digit(k) as char));
    } else if point >= digits_len {
        (0..digits_len).for_each(|k| out.push(digit(k) as char));
        out.extend(std::iter::repeat_n('0', (point - digits_len) as usize));
    } else {
        (0..point).for_each(|k| out.push(digit(k) as char));
        out.push('.');
        (point..digits_len).for_each(|k| out.push(digit(k) as char));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `push_f64` reads back to `x` and is `Display`'s text, or differs from it only in the
    /// last digit by one, where both are shortest and read back to `x` (a tie, module doc).
    fn check(x: f64, buf: &mut ryu::Buffer) {
        let mut s = String::new();
        push_f64(&mut s, buf, x);
        let d = format!("{x}");
        let bits = x.to_bits();
        if x.is_nan() {
            assert_eq!(s, d);
            return;
        }
        assert_eq!(s.parse::<f64>().map(f64::to_bits), Ok(bits), "{s} for bits {bits:#x}");
        if s != d {
            let (a, b) = (s.as_bytes(), d.as_bytes());
            let n = a.len();
            let last_differs_by_one = n == b.len()
                && a[..n - 1] == b[..n - 1]
                && (i32::from(a[n - 1]) - i32::from(b[n - 1])).abs() == 1;
            assert!(last_differs_by_one, "{s} against {d} for bits {bits:#x}");
        }
    }

    /// The tie of the module doc: the digit rounded to even.
    #[test]
    fn tie_rounds_the_last_digit_to_even() {
        let mut s = String::new();
        // 1308548795726862.25 exactly (the spacing of f64 there is 0.25).
        let x = f64::from_bits(0x4312_9879_088f_f039);
        assert_eq!(x - 1_308_548_795_726_862.0, 0.25);
        push_f64(&mut s, &mut ryu::Buffer::new(), x);
        assert_eq!(s, "1308548795726862.2");
    }

    /// Every layout `Display` uses: integers, small and large magnitudes (Ryu's exponent
    /// forms on both sides), signed zeros, subnormals, the extremes and non-finite values.
    #[test]
    fn same_text_as_display_on_edge_values() {
        let mut buf = ryu::Buffer::new();
        for x in [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            0.3,
            100.0,
            123456.0,
            1e15,
            1e16,
            1.5e20,
            -2.5e-7,
            1e-5,
            1e-6,
            1e-7,
            1.234567e-300,
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
            std::f64::consts::PI,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            check(x, &mut buf);
        }
    }

    /// Random bit patterns (every exponent) and random values at the scales of the CSV.
    #[test]
    fn same_text_as_display_on_random_values() {
        let mut buf = ryu::Buffer::new();
        // SplitMix64: a fixed, dependency-free stream of 64-bit patterns.
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        };
        for _ in 0..200_000 {
            let bits = next();
            check(f64::from_bits(bits), &mut buf);
            let unit = (bits >> 11) as f64 / (1u64 << 53) as f64;
            let scale = 10f64.powi((bits % 17) as i32 - 8);
            check((unit - 0.5) * scale, &mut buf);
            check((bits % 100_000) as f64 * 0.01, &mut buf);
        }
    }

    /// `push_significant` reads back to the value `format!("{x:.3e}")` (core's exactly
    /// rounded decimal) reads back to, over magnitudes from 1e-30 to 1e30 and both signs, in
    /// at most 11 characters (`-0.00006741`); zero is `0`.
    #[test]
    fn significant_digits_read_back_as_the_exactly_rounded_decimal() {
        let mut buf = ryu::Buffer::new();
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        for k in 0..20_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let mantissa = 1.0 + (state >> 11) as f64 / (1u64 << 53) as f64 * 9.0;
            let x = mantissa * 10f64.powi((k % 61) - 30) * if k % 2 == 0 { 1.0 } else { -1.0 };
            let mut s = String::new();
            push_significant(&mut s, &mut buf, x, 4);
            let exact: f64 = format!("{x:.3e}").parse().unwrap();
            assert_eq!(s.parse::<f64>().ok(), Some(exact), "{x:e}: {s}");
            assert!(s.len() <= 11, "{x:e}: {s}");
        }
        let mut s = String::new();
        push_significant(&mut s, &mut buf, 0.0, 4);
        assert_eq!(s, "0");
        // Exact ties (0.15625 is a binary fraction) go to the even digit, as core's formatting.
        for (x, tie) in [(0.156_25, "0.1562"), (-0.156_25, "-0.1562"), (2.0625, "2.062")] {
            s.clear();
            push_significant(&mut s, &mut buf, x, 4);
            assert_eq!(s.parse::<f64>(), tie.parse::<f64>(), "{x}: {s}");
            assert_eq!(s.parse::<f64>().ok(), format!("{x:.3e}").parse::<f64>().ok(), "{x}");
        }
    }
}
