//! After the check: does each channel match the kinematics where the check aligned it? The
//! check's time shifts start at none and descend to the nearest minimum of its cost. A channel
//! late by seconds (a logger's delay, another record's column) can stop in a minimum a motion's
//! period away from its delay: the biases and scale factors take what they can, the check
//! "converges", and the channel's residual is simply large (ATTAS with β 3 s late: a shift of
//! −0.74 s and nothing more said; the HFB-320's α 10 s late, before the α screen: no finding).
//! A shift beyond ±[`MAX_SHIFT_S`] is refused as implausible for a sensor in any case.
//!
//! The test: per manoeuvre, the correlation of the measured channel with its reconstruction
//! from the kinematics (the check's own model output, its fitted shift included), over lags up
//! to three quarters of the manoeuvre. A channel whose best lag lies beyond the search range
//! and leaves less than a quarter of the misfit `1 − c²` of the aligned one is named with that
//! lag. The factor of four keeps a slow periodic motion (a phugoid), whose correlation returns
//! near a period later, from passing for a delay: the aligned correlation of a channel that
//! fits is near 1, and a wrong lag does not quarter its small misfit.

use crate::record::corrections::MAX_SHIFT_S;
use aeroident_estimators::compat::{CompatResult, Unknown};

/// Fewest overlapping samples a lag is judged on (and at least a quarter of the manoeuvre).
const MIN_OVERLAP: usize = 20;

/// The best lag must cut the misfit `1 − c²` to below this share of the aligned one's.
const MISFIT_SHARE: f64 = 0.25;

/// One finding per channel of `r` that matches the kinematics best at a lag more than
/// [`MAX_SHIFT_S`] from the check's own shift in some manoeuvre (module doc); `lengths` are
/// the manoeuvres' sample counts (in the order `r` concatenates them), `dt_s` their sample
/// interval.
pub(super) fn misaligned(lengths: &[usize], r: &CompatResult, dt_s: f64) -> Vec<String> {
    let ny = r.outputs.len();
    let mut out = Vec::new();
    if lengths.iter().sum::<usize>() * ny != r.predicted.len() {
        return out;
    }
    for (j, ch) in r.outputs.iter().enumerate() {
        // The model output carries the check's own shift of the channel, so a lag found
        // against it adds to that shift.
        let shift = r.reported(Unknown::TimeShift(*ch)).map_or(0.0, |(v, _)| v);
        let mut named = Vec::new();
        let mut start = 0;
        for (m, &n) in lengths.iter().enumerate() {
            let rows = start..start + n;
            start += n;
            let y: Vec<f64> = rows.clone().map(|k| r.predicted[k * ny + j]).collect();
            let z: Vec<f64> =
                rows.map(|k| r.predicted[k * ny + j] + r.residuals[k * ny + j]).collect();
            let Some((lag, best, aligned)) = best_lag(&z, &y) else { continue };
            let late_s = lag as f64 * dt_s;
            let misfit = |c: f64| 1.0 - c * c;
            if late_s.abs() > MAX_SHIFT_S && misfit(best) < MISFIT_SHARE * misfit(aligned) {
                named.push(format!(
                    "{:+.1} s in manoeuvre {} (correlation {best:.2} there, {aligned:.2} at the check's {shift:+.3} s)",
                    shift + late_s,
                    m + 1,
                ));
            }
        }
        if !named.is_empty() {
            out.push(format!(
                "{} does not fit the kinematics where the check aligns it: it matches them best when read later by {}, beyond the ±{MAX_SHIFT_S} s a sensor's lag plausibly reaches; a delayed or misaligned channel (its time stamps, or another record's column), whose biases, scale factor and shift from this check mean nothing until it is aligned",
                ch.name(),
                named.join("; ")
            ));
        }
    }
    out
}

/// The lag `L` (samples; > 0: `z` lags `y`, `z[k] ≈ y[k − L]`) of the largest correlation of
/// `z` with `y` over the overlaps of at least a quarter of their length (and [`MIN_OVERLAP`]),
/// with that correlation and the one at lag 0; `None` for a series too short or constant.
///
/// Every lag's correlation comes from sums over its overlap ([`Lagged`]), its cross products
/// by the transform of [`aeroident_signals::lag_products::cross_lag_products`]: a whole
/// flight's manoeuvre of 48,000 samples has 72,000 lags, and their direct sums cost a
/// product per lag and sample. A lag replaces the best so far only when it beats it by more
/// than [`TIE`], the sums' round-off, so of equally good lags the aligned one (else the
/// earliest) is kept, as exact sums keep it; the two correlations returned are formed
/// directly over their overlaps.
fn best_lag(z: &[f64], y: &[f64]) -> Option<(isize, f64, f64)> {
    let n = z.len().min(y.len());
    let min_overlap = (n / 4).max(MIN_OVERLAP);
    if n < min_overlap {
        return None;
    }
    let (z, y) = (&z[..n], &y[..n]);
    let max_lag = n - min_overlap;
    let aligned = correlation(z, y)?;
    let lagged = Lagged::new(z, y, max_lag);
    let mut best = (0, aligned);
    for lag in -(max_lag as isize)..=max_lag as isize {
        if let Some(c) = lagged.correlation(lag).filter(|c| *c > best.1 + TIE) {
            best = (lag, c);
        }
    }
    let (za, ya) = overlap(z, y, best.0);
    Some((best.0, correlation(za, ya).unwrap_or(best.1), aligned))
}

/// The parts of `z` and `y` (equal lengths) that pair at lag `lag` (`z[k]` with `y[k − lag]`).
fn overlap<'a>(z: &'a [f64], y: &'a [f64], lag: isize) -> (&'a [f64], &'a [f64]) {
    let (n, k) = (z.len(), lag.unsigned_abs().min(z.len()));
    if lag >= 0 { (&z[k..n], &y[..n - k]) } else { (&z[..n - k], &y[k..n]) }
}

/// How much a lag's correlation must exceed the best so far to replace it: far above the
/// round-off of the sums (about 1e-13 on the tests' series), far below any difference that
/// decides a finding.
const TIE: f64 = 1e-9;

/// Sums from which the correlation of two series at every lag follows in `O(1)`: prefix sums
/// of each series and of its square, and the cross products at each lag both ways. The series
/// are centred on their own means first: a correlation does not change with an offset, and
/// centred sums do not lose the overlap's variance to cancellation against a large mean (an
/// airspeed of 200 m/s that varies by 1).
struct Lagged {
    /// Prefix sums of `z`, `z²`, `y`, `y²` (`n + 1` each).
    z: Vec<f64>,
    zz: Vec<f64>,
    y: Vec<f64>,
    yy: Vec<f64>,
    /// `Σ_t y_t z_{t+L}` at `L = 0…max_lag` (z late), and `Σ_t z_t y_{t+L}` (z early).
    late: Vec<f64>,
    early: Vec<f64>,
}

impl Lagged {
    fn new(z: &[f64], y: &[f64], max_lag: usize) -> Self {
        use aeroident_signals::lag_products::cross_lag_products;
        let centred = |v: &[f64]| {
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            v.iter().map(|x| x - mean).collect::<Vec<f64>>()
        };
        let (zc, yc) = (centred(z), centred(y));
        let prefix = |v: &[f64], f: fn(f64) -> f64| {
            let mut out = Vec::with_capacity(v.len() + 1);
            out.push(0.0);
            v.iter().fold(0.0, |acc, &x| {
                out.push(acc + f(x));
                acc + f(x)
            });
            out
        };
        Self {
            z: prefix(&zc, |x| x),
            zz: prefix(&zc, |x| x * x),
            y: prefix(&yc, |x| x),
            yy: prefix(&yc, |x| x * x),
            late: cross_lag_products(&yc, &zc, max_lag),
            early: cross_lag_products(&zc, &yc, max_lag),
        }
    }

    /// Pearson's correlation at `lag` (as [`best_lag`]'s) from the sums; `None` where either
    /// overlap is constant to the sums' round-off, or beyond the lags formed.
    fn correlation(&self, lag: isize) -> Option<f64> {
        let k = lag.unsigned_abs();
        let (cross, z_from, y_from) =
            if lag >= 0 { (self.late.get(k)?, k, 0) } else { (self.early.get(k)?, 0, k) };
        let len = (self.z.len() - 1).checked_sub(k)?;
        let sum = |p: &[f64], from: usize| p[from + len] - p[from];
        let (sz, szz) = (sum(&self.z, z_from), sum(&self.zz, z_from));
        let (sy, syy) = (sum(&self.y, y_from), sum(&self.yy, y_from));
        let m = len as f64;
        let (ab, aa, bb) = (cross - sz * sy / m, szz - sz * sz / m, syy - sy * sy / m);
        let constant = |var: f64, squares: f64| var <= VARIANCE_FLOOR * squares;
        (!constant(aa, szz) && !constant(bb, syy)).then(|| ab / (aa * bb).sqrt())
    }
}

/// An overlap whose sum of squared deviations is below this share of its sum of squares is
/// constant to the round-off of the prefix sums.
const VARIANCE_FLOOR: f64 = 1e-10;

/// Pearson's correlation of `a` with `b` (equal lengths); `None` when either is constant.
fn correlation(a: &[f64], b: &[f64]) -> Option<f64> {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        let (dx, dy) = (x - ma, y - mb);
        ab += dx * dy;
        aa += dx * dx;
        bb += dy * dy;
    }
    (aa > 0.0 && bb > 0.0).then(|| ab / (aa * bb).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::compat::Channel;

    /// A chirp-like signal 10 s late (100 samples at 10 Hz) is found at lag +100 with a
    /// correlation of 1; the aligned signal at lag 0; a constant gives nothing.
    #[test]
    fn the_best_lag_is_the_delay() {
        let s = |k: isize| {
            let t = k as f64 * 0.1;
            (0.05 * t * t).sin() + 0.3 * (0.7 * t).cos()
        };
        let y: Vec<f64> = (0..600).map(s).collect();
        let late: Vec<f64> = (0..600).map(|k| s(k - 100)).collect();
        let (lag, best, aligned) = best_lag(&late, &y).unwrap();
        assert_eq!(lag, 100);
        assert!((best - 1.0).abs() < 1e-12 && aligned < 0.5, "{best} {aligned}");
        let (lag, best, _) = best_lag(&y, &y).unwrap();
        assert!(lag == 0 && (best - 1.0).abs() < 1e-12, "{lag} {best}");
        assert_eq!(best_lag(&[1.0; 100], &y[..100]), None);
    }

    fn chirp(k: isize) -> f64 {
        let t = k as f64 * 0.1;
        (0.05 * t * t).sin() + 0.3 * (0.7 * t).cos()
    }

    fn checked(
        outputs: Vec<Channel>,
        shift: Option<f64>,
        rows: &[Vec<(f64, f64)>],
    ) -> CompatResult {
        let (unknowns, values, sigma) = match shift {
            Some(v) => (vec![Unknown::TimeShift(outputs[outputs.len() - 1])], vec![v], vec![0.01]),
            None => (Vec::new(), Vec::new(), Vec::new()),
        };
        let (mut predicted, mut residuals) = (Vec::new(), Vec::new());
        for k in 0..rows[0].len() {
            for channel in rows {
                predicted.push(channel[k].0);
                residuals.push(channel[k].1 - channel[k].0);
            }
        }
        CompatResult {
            unknowns,
            values,
            sigma,
            sigma_coloured: None,
            outputs,
            residual_rms: Vec::new(),
            residual_mean: Vec::new(),
            predicted,
            residuals,
            reconstructed: Vec::new(),
            termination: aeroident_estimators::output_error::Termination::Converged,
            iterations: 1,
            notes: Vec::new(),
        }
    }

    fn late_by(samples: isize, n: isize, echo: f64) -> Vec<(f64, f64)> {
        (0..n).map(|k| (chirp(k), chirp(k - samples) + echo * chirp(k))).collect()
    }

    #[test]
    fn a_channel_ten_seconds_late_in_the_second_manoeuvre_is_named_there_with_the_checks_shift() {
        let aligned = late_by(0, 1200, 0.0);
        let mut beta = late_by(0, 600, 0.0);
        beta.extend(late_by(100, 600, 0.0));
        let r = checked(vec![Channel::Alpha, Channel::Beta], Some(0.1), &[aligned, beta]);
        let out = misaligned(&[600, 600], &r, 0.1);
        assert_eq!(out.len(), 1, "{out:?}");
        assert!(out[0].starts_with("beta_rad does not fit the kinematics where the check aligns it: it matches them best when read later by +10.1 s in manoeuvre 2 (correlation 1.00 there, "), "{out:?}");
        assert!(out[0].contains(" at the check's +0.100 s), beyond the ±0.5 s"), "{out:?}");
        assert!(misaligned(&[600, 599], &r, 0.1).is_empty());
    }

    #[test]
    fn a_lag_is_named_beyond_half_a_second_and_only_when_it_quarters_the_misfit() {
        let named = |rows: Vec<(f64, f64)>| {
            misaligned(&[600], &checked(vec![Channel::Alpha], None, &[rows]), 0.1)
        };
        assert!(named(late_by(5, 600, 0.0)).is_empty());
        let out = named(late_by(6, 600, 0.0));
        assert_eq!(out.len(), 1, "{out:?}");
        assert!(
            out[0].contains("read later by +0.6 s in manoeuvre 1 (correlation 1.00 there"),
            "{out:?}"
        );
        assert!(named(late_by(100, 600, 0.6)).is_empty());
        assert_eq!(named(late_by(100, 600, 0.0)).len(), 1);
    }

    #[test]
    fn the_lag_search_reaches_back_and_forward_over_three_quarters_of_the_record() {
        let y: Vec<f64> = (0..600).map(chirp).collect();
        let shifted = |samples: isize| (0..600).map(|k| chirp(k - samples)).collect::<Vec<_>>();
        assert_eq!(best_lag(&shifted(-100), &y).unwrap().0, -100);
        assert_eq!(best_lag(&shifted(450), &y).unwrap().0, 450);
        assert_ne!(best_lag(&shifted(460), &y).unwrap().0, 460);
        let (lag, best, aligned) = best_lag(&y[..20], &y[..20]).unwrap();
        assert_eq!((lag, best, aligned), (0, 1.0, 1.0));
        assert_eq!(best_lag(&y[..19], &y[..19]), None);
        assert_eq!(best_lag(&y[..100], &[2.0; 100]), None);
    }

    #[test]
    fn of_equally_good_lags_the_aligned_one_is_kept() {
        let square: Vec<f64> = (0..600).map(|k| if k % 40 < 20 { 1.0 } else { -1.0 }).collect();
        assert_eq!(best_lag(&square, &square), Some((0, 1.0, 1.0)));
    }

    /// A random walk of `n` samples about `mean` from seed `s`, with white noise on it.
    fn noisy(n: usize, mut s: u64, mean: f64) -> Vec<f64> {
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut walk = 0.0;
        (0..n)
            .map(|_| {
                walk = 0.98 * walk + next();
                mean + walk + 0.3 * next()
            })
            .collect()
    }

    /// Every lag's correlation from the sums and the transform equals Pearson's formed
    /// directly over its overlap, to 1e-12, on random series 3,000 samples long about an
    /// airspeed's mean (200) and a vane's (0.05), both ways; and the best lag found is the
    /// direct search's.
    #[test]
    fn the_correlation_at_every_lag_is_the_direct_ones() {
        let (z, y) = (noisy(3000, 11, 200.0), noisy(3000, 29, 0.05));
        let late: Vec<f64> = (0..3000).map(|k| y[(k + 2960) % 3000] + 0.5 * z[k] / 200.0).collect();
        for (a, b) in [(&z, &y), (&y, &z), (&late, &y)] {
            let max_lag = 3000 - 750;
            let lagged = Lagged::new(a, b, max_lag);
            let mut direct_best = (0, correlation(a, b).unwrap());
            for lag in -(max_lag as isize)..=max_lag as isize {
                let (za, ya) = overlap(a, b, lag);
                let direct = correlation(za, ya).unwrap();
                let fast = lagged.correlation(lag).unwrap();
                assert!((fast - direct).abs() < 1e-12, "lag {lag}: {fast} against {direct}");
                if direct > direct_best.1 + TIE {
                    direct_best = (lag, direct);
                }
            }
            let (lag, best, _) = best_lag(a, b).unwrap();
            assert_eq!((lag, best), direct_best);
        }
        assert_eq!(best_lag(&late, &y).unwrap().0, 40);
        assert_eq!(Lagged::new(&z, &y, 10).correlation(11), None);
    }

    #[test]
    fn the_correlation_is_pearsons() {
        let c = correlation(&[1.0, 2.0, 3.0, 4.0], &[1.0, 3.0, 2.0, 4.0]).unwrap();
        assert!((c - 0.8).abs() < 1e-15, "{c}");
        assert_eq!(correlation(&[1.0, 2.0, 3.0, 4.0], &[8.0, 6.0, 4.0, 2.0]), Some(-1.0));
        let c = correlation(&[2.0, 4.0, 4.0, 6.0], &[1.0, 1.0, 2.0, 4.0]).unwrap();
        assert!((c - 3f64.sqrt() / 2.0).abs() < 1e-15, "{c}");
        assert_eq!(correlation(&[1.0, 2.0, 3.0], &[5.0, 5.0, 5.0]), None);
        assert_eq!(correlation(&[5.0, 5.0, 5.0], &[1.0, 2.0, 3.0]), None);
    }

    #[test]
    fn a_reversed_channel_is_not_named_late_where_a_lag_fits_no_better_than_alignment() {
        let square = |k: usize| if k % 40 < 20 { 1.0 } else { -1.0 };
        let reversed: Vec<(f64, f64)> = (0..640).map(|k| (square(k), -square(k))).collect();
        let (lag, best, aligned) = best_lag(
            &reversed.iter().map(|r| r.1).collect::<Vec<_>>(),
            &reversed.iter().map(|r| r.0).collect::<Vec<_>>(),
        )
        .unwrap();
        assert!(lag.abs() > 5 && best == 1.0 && aligned == -1.0, "{lag} {best} {aligned}");
        let r = checked(vec![Channel::Alpha], None, &[reversed]);
        assert!(misaligned(&[640], &r, 0.1).is_empty());
    }
}
