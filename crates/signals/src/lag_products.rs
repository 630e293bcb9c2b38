//! Lag products `c_k = Σ_t x_t x_{t+k}`, `k = 0…max_lag`, of a series: the sums every
//! autocorrelation, Ljung–Box statistic and coloured-residual correction is built from.
//!
//! Directly the sums cost `n (max_lag + 1)` products, which is quadratic in the record when
//! the lags grow with it (a quarter of the record for the σ of a residual mean). By the
//! Wiener–Khinchin relation the same sums are the inverse transform of the periodogram of the
//! series zero-padded to at least `n + max_lag` samples, so that the circular products do not
//! wrap (Press et al., *Numerical Recipes* 3rd ed. §13.2): `O(m log m)` for `m ≥ n + max_lag`.
//! Below `DIRECT_MAX_LAG` (64) lags the direct sums are cheaper and exact to the last bit;
//! above it the transform's round-off is a few ulp of `c_0` (checked against the direct sums
//! in the tests).
//!
//! The cross products `c_k = Σ_t x_t y_{t+k}` of two series ([`cross_lag_products`](crate::lag_products::cross_lag_products)) are the
//! inverse transform of the cross periodogram `conj(X)·Y` under the same padding: the sums a
//! cross-correlation over lags is built from (the search for a channel's delay against
//! another), `O(m log m)` where the direct sums over every lag of a record are quadratic.

use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

/// The largest `max_lag` for which the sums are formed directly (cheaper than two transforms
/// of twice the record, and exact).
pub const DIRECT_MAX_LAG: usize = 64;

/// `c_k = Σ_{t=0}^{n−1−k} x_t x_{t+k}` for `k = 0…max_lag` (`max_lag + 1` values; a lag at
/// or beyond `x.len()` has no pairs and is 0). Shapes: `x` of any length, the result
/// `max_lag + 1` long.
pub fn lag_products(x: &[f64], max_lag: usize) -> Vec<f64> {
    if max_lag <= DIRECT_MAX_LAG || x.len() <= DIRECT_MAX_LAG {
        return direct(x, max_lag);
    }
    let n = x.len();
    let m = (n + max_lag.min(n)).next_power_of_two();
    let mut buf: Vec<Complex<f64>> = x.iter().map(|&v| Complex::new(v, 0.0)).collect();
    buf.resize(m, Complex::new(0.0, 0.0));
    let mut planner = FftPlanner::new();
    planner.plan_fft_forward(m).process(&mut buf);
    buf.iter_mut().for_each(|z| *z = Complex::new(z.norm_sqr(), 0.0));
    planner.plan_fft_inverse(m).process(&mut buf);
    let scale = 1.0 / m as f64;
    (0..=max_lag).map(|k| if k < n { buf[k].re * scale } else { 0.0 }).collect()
}

/// `c_k = Σ_t x_t y_{t+k}` over the pairs both series hold (`t + k` below `y.len()`, `t`
/// below `x.len()`), for `k = 0…max_lag` (`max_lag + 1` values; a lag with no pairs is 0).
/// Lags of `y` behind `x` the other way round are `cross_lag_products(y, x, …)`. Shapes: `x`
/// and `y` of any lengths, the result `max_lag + 1` long. Directly up to [`DIRECT_MAX_LAG`]
/// lags or samples, else by the transform (module doc), whose round-off is a few ulp of
/// `sqrt(Σx² Σy²)`.
pub fn cross_lag_products(x: &[f64], y: &[f64], max_lag: usize) -> Vec<f64> {
    let n = x.len().max(y.len());
    if max_lag <= DIRECT_MAX_LAG || x.len().min(y.len()) <= DIRECT_MAX_LAG {
        return cross_direct(x, y, max_lag);
    }
    let m = (n + max_lag.min(n)).next_power_of_two();
    let padded = |v: &[f64]| {
        let mut b: Vec<Complex<f64>> = v.iter().map(|&u| Complex::new(u, 0.0)).collect();
        b.resize(m, Complex::new(0.0, 0.0));
        b
    };
    let (mut bx, mut by) = (padded(x), padded(y));
    let mut planner = FftPlanner::new();
    let forward = planner.plan_fft_forward(m);
    forward.process(&mut bx);
    forward.process(&mut by);
    by.iter_mut().zip(&bx).for_each(|(b, a)| *b *= a.conj());
    planner.plan_fft_inverse(m).process(&mut by);
    let scale = 1.0 / m as f64;
    (0..=max_lag).map(|k| if k < y.len() { by[k].re * scale } else { 0.0 }).collect()
}

/// The cross sums term by term.
fn cross_direct(x: &[f64], y: &[f64], max_lag: usize) -> Vec<f64> {
    (0..=max_lag).map(|k| x.iter().zip(y.iter().skip(k)).map(|(a, b)| a * b).sum()).collect()
}

/// The sums term by term.
fn direct(x: &[f64], max_lag: usize) -> Vec<f64> {
    (0..=max_lag).map(|k| x.iter().zip(x.iter().skip(k)).map(|(a, b)| a * b).sum()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// By hand: x = [1, 2, 3] gives c = [14, 8, 3, 0].
    #[test]
    fn analytic_short_series() {
        assert_eq!(lag_products(&[1.0, 2.0, 3.0], 3), vec![14.0, 8.0, 3.0, 0.0]);
        assert_eq!(lag_products(&[], 2), vec![0.0, 0.0, 0.0]);
    }

    /// The transform against the direct sums on 5,000 samples of a coloured series, every lag
    /// to 1,250, and lags beyond the series: equal to 1e-12 of `c_0`.
    #[test]
    fn transform_matches_the_direct_sums() {
        let mut x = Vec::with_capacity(5000);
        let (mut s, mut v) = (12345u64, 0.0);
        for _ in 0..5000 {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            v = 0.9 * v + ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
            x.push(v + 0.3);
        }
        let fast = lag_products(&x, 1250);
        let slow = direct(&x, 1250);
        for (k, (a, b)) in fast.iter().zip(&slow).enumerate() {
            assert!((a - b).abs() <= 1e-12 * slow[0], "lag {k}: {a} against {b}");
        }
        let short = lag_products(&x[..100], 150);
        assert_eq!(short.len(), 151);
        assert!(short[100..].iter().all(|c| *c == 0.0));
        let slow = direct(&x[..100], 99);
        for (a, b) in short.iter().zip(&slow) {
            assert!((a - b).abs() <= 1e-12 * slow[0]);
        }
    }

    /// A coloured series of `n` samples from seed `s`, offset by `mean`.
    fn coloured(n: usize, mut s: u64, mean: f64) -> Vec<f64> {
        let mut v = 0.0;
        (0..n)
            .map(|_| {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                v = 0.9 * v + ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
                v + mean
            })
            .collect()
    }

    /// By hand: x = [1, 2], y = [3, 4, 5] gives Σ x_t y_{t+k} = [11, 14, 5], the other way
    /// round [11, 6, 0]; the cross products of a series with itself are its lag products.
    #[test]
    fn cross_products_by_hand() {
        assert_eq!(cross_lag_products(&[1.0, 2.0], &[3.0, 4.0, 5.0], 2), vec![11.0, 14.0, 5.0]);
        assert_eq!(cross_lag_products(&[3.0, 4.0, 5.0], &[1.0, 2.0], 2), vec![11.0, 6.0, 0.0]);
        let x = coloured(300, 7, 0.2);
        assert_eq!(cross_lag_products(&x, &x, 10), lag_products(&x, 10));
    }

    /// The transform against the direct cross sums on two coloured series of unequal lengths
    /// (4,000 and 3,500 samples), every lag to 3,000 both ways and lags beyond the series:
    /// equal to 1e-12 of `sqrt(Σx² Σy²)`.
    #[test]
    fn cross_transform_matches_the_direct_sums() {
        let (x, y) = (coloured(4000, 12345, 0.3), coloured(3500, 999, -0.1));
        let scale = (lag_products(&x, 0)[0] * lag_products(&y, 0)[0]).sqrt();
        for (a, b) in [(&x, &y), (&y, &x)] {
            let fast = cross_lag_products(a, b, 4100);
            let slow = cross_direct(a, b, 4100);
            for (k, (f, s)) in fast.iter().zip(&slow).enumerate() {
                assert!((f - s).abs() <= 1e-12 * scale, "lag {k}: {f} against {s}");
            }
            assert!(fast[b.len()..].iter().all(|c| *c == 0.0));
        }
    }
}
