//! Checks against discrete systems whose frequency response is known exactly: a second-order
//! filter driven by white noise, with and without output noise, one and two inputs.

use super::*;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

const DT: f64 = 0.01;

/// Tustin discretisation of `ωn²/(s² + 2ζωn s + ωn²)`: `(b, a)` of
/// `y[k] = Σ b_j x[k−j] − a1 y[k−1] − a2 y[k−2]`.
fn biquad(wn: f64, zeta: f64, gain: f64) -> ([f64; 3], [f64; 2]) {
    let c = 2.0 / DT;
    let d = c * c + 2.0 * zeta * wn * c + wn * wn;
    let k = gain * wn * wn / d;
    (
        [k, 2.0 * k, k],
        [(2.0 * wn * wn - 2.0 * c * c) / d, (c * c - 2.0 * zeta * wn * c + wn * wn) / d],
    )
}

/// Exact discrete response of the filter at `f_hz`.
fn response(bq: &([f64; 3], [f64; 2]), f_hz: f64) -> Complex64 {
    let z1 = Complex64::from_polar(1.0, -2.0 * PI * f_hz * DT);
    let z2 = z1 * z1;
    let (b, a) = bq;
    (b[0] + z1 * b[1] + z2 * b[2]) / (1.0 + z1 * a[0] + z2 * a[1])
}

fn filter(bq: &([f64; 3], [f64; 2]), x: &[f64]) -> Vec<f64> {
    let (b, a) = bq;
    let mut y = vec![0.0; x.len()];
    for k in 0..x.len() {
        let xm = |j: usize| if k >= j { x[k - j] } else { 0.0 };
        let ym = |y: &[f64], j: usize| if k >= j { y[k - j] } else { 0.0 };
        y[k] = b[0] * xm(0) + b[1] * xm(1) + b[2] * xm(2) - a[0] * ym(&y, 1) - a[1] * ym(&y, 2);
    }
    y
}

fn white(n: usize, sigma: f64, seed: u64) -> Vec<f64> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let d = Normal::new(0.0, sigma).unwrap();
    (0..n).map(|_| d.sample(&mut rng)).collect()
}

fn names(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

fn opts() -> SpectralOptions {
    SpectralOptions { f_max_hz: Some(5.0), ..SpectralOptions::default() }
}

/// Largest |dB| and |deg| deviation from the exact response over the grid.
fn deviation(p: &PairResponse, exact: impl Fn(f64) -> Complex64) -> (f64, f64) {
    deviation_where(p, exact, 0.0)
}

/// [`deviation`] at the grid points whose coherence is at least `min_coherence`.
fn deviation_where(
    p: &PairResponse,
    exact: impl Fn(f64) -> Complex64,
    min_coherence: f64,
) -> (f64, f64) {
    let (mut db, mut deg) = (0.0f64, 0.0f64);
    for k in (0..p.frequency_hz.len()).filter(|&k| p.coherence[k] >= min_coherence) {
        let h = exact(p.frequency_hz[k]);
        let est = Complex64::new(p.re[k], p.im[k]);
        let (d1, d2) =
            ((20.0 * (est.norm() / h.norm()).log10()).abs(), (est / h).arg().to_degrees().abs());
        if std::env::var("SPECTRAL_DEBUG").is_ok() {
            eprintln!(
                "{:.4} Hz {d1:.3} dB {d2:.2} deg coh {:.4}",
                p.frequency_hz[k], p.coherence[k]
            );
        }
        db = db.max(d1);
        deg = deg.max(d2);
    }
    (db, deg)
}

#[test]
fn noise_free_second_order_system_is_recovered_with_unit_coherence() {
    let bq = biquad(2.0 * PI * 0.8, 0.3, 2.0);
    let x = white(30_000, 1.0, 1);
    let y = filter(&bq, &x);
    let r =
        frequency_responses(&[vec![x, y]], &names(&["u"]), &names(&["y"]), DT, &opts()).unwrap();
    let p = &r.pairs[0];
    let (db, deg) = deviation(p, |f| response(&bq, f));
    assert!(db < 0.3 && deg < 2.0, "deviation {db} dB {deg} deg");
    let min_coh = p.coherence.iter().copied().fold(1.0, f64::min);
    assert!(min_coh > 0.99, "coherence {min_coh}");
    // The grid spans 2/T_max to f_max at 40 points per decade.
    assert!((p.frequency_hz[0] - 2.0 / r.window_lengths_s[0]).abs() < 1e-12);
    assert!(*p.frequency_hz.last().unwrap() <= 5.0 + 1e-9);
}

#[test]
fn noisy_output_stays_within_its_random_error_and_the_error_matches_the_scatter() {
    let bq = biquad(2.0 * PI * 0.8, 0.3, 2.0);
    let seeds = 16;
    let mut logs: Vec<Vec<f64>> = Vec::new();
    let mut eps_mean: Vec<f64> = Vec::new();
    for seed in 0..seeds {
        let x = white(20_000, 1.0, 100 + seed);
        let noise = white(20_000, 1.5, 200 + seed);
        let y: Vec<f64> = filter(&bq, &x).iter().zip(&noise).map(|(a, b)| a + b).collect();
        let r = frequency_responses(&[vec![x, y]], &names(&["u"]), &names(&["y"]), DT, &opts())
            .unwrap();
        let p = &r.pairs[0];
        let rel: Vec<f64> = (0..p.frequency_hz.len())
            .map(|k| {
                Complex64::new(p.re[k], p.im[k]).norm() / response(&bq, p.frequency_hz[k]).norm()
            })
            .map(f64::ln)
            .collect();
        logs.push(rel);
        if eps_mean.is_empty() {
            eps_mean = vec![0.0; p.random_error.len()];
        }
        eps_mean.iter_mut().zip(&p.random_error).for_each(|(m, e)| *m += e / seeds as f64);
    }
    // ε is the σ of ln|H| to first order: compare with the scatter over seeds, averaged over
    // frequency bands of 10 grid points (each band's ratio from 160 values).
    let n = eps_mean.len();
    for band in (0..n).collect::<Vec<_>>().chunks(10) {
        let (mut var, mut e2) = (0.0, 0.0);
        for &k in band {
            let mean = logs.iter().map(|l| l[k]).sum::<f64>() / seeds as f64;
            var += logs.iter().map(|l| (l[k] - mean).powi(2)).sum::<f64>() / (seeds - 1) as f64;
            e2 += eps_mean[k] * eps_mean[k];
        }
        let ratio = (var / e2).sqrt();
        assert!(
            (0.5..2.0).contains(&ratio),
            "band from {} Hz: observed/predicted σ = {ratio}",
            band[0]
        );
    }
}

#[test]
fn two_correlated_inputs_are_separated_by_conditioning() {
    let b1 = biquad(2.0 * PI * 0.8, 0.3, 2.0);
    let b2 = biquad(2.0 * PI * 2.0, 0.6, -0.5);
    let n = 30_000;
    let x1 = white(n, 1.0, 5);
    // The second input partly follows the first (a crossfeed): SISO estimates would be biased.
    let x2: Vec<f64> = white(n, 1.0, 6).iter().zip(&x1).map(|(a, b)| a + 0.7 * b).collect();
    let y: Vec<f64> = filter(&b1, &x1).iter().zip(filter(&b2, &x2)).map(|(a, b)| a + b).collect();
    let r =
        frequency_responses(&[vec![x1, x2, y]], &names(&["a", "b"]), &names(&["y"]), DT, &opts())
            .unwrap();
    // Near input a's resonance the leakage of its large response is noise to input b's
    // estimate; the partial coherence says so (it drops to about 0.75 there), so compare where
    // it is high, as a user filters a response.
    let (db1, deg1) = deviation_where(&r.pairs[0], |f| response(&b1, f), 0.95);
    let (db2, deg2) = deviation_where(&r.pairs[1], |f| response(&b2, f), 0.95);
    let kept = r.pairs[1].coherence.iter().filter(|&&g| g >= 0.95).count();
    assert!(kept * 10 >= r.pairs[1].coherence.len() * 8, "only {kept} points kept");
    // Everywhere, coherence high or not, the random error from the partial coherence covers
    // the deviation (3ε, plus 0.5 % for the taper's bias).
    for (p, bq) in r.pairs.iter().zip([&b1, &b2]) {
        for k in 0..p.frequency_hz.len() {
            let ratio = Complex64::new(p.re[k], p.im[k]) / response(bq, p.frequency_hz[k]);
            let bound = 3.0 * p.random_error[k] + 0.005;
            assert!(
                ratio.norm().ln().abs() < bound && ratio.arg().abs() < bound,
                "{} at {} Hz: ratio {ratio}, ε {}",
                p.input,
                p.frequency_hz[k],
                p.random_error[k]
            );
        }
    }
    assert!(db1 < 0.5 && deg1 < 3.0, "input a: {db1} dB {deg1} deg");
    assert!(db2 < 0.5 && deg2 < 3.0, "input b: {db2} dB {deg2} deg");
    let worst = r.pairs[0].multiple_coherence.iter().copied().fold(1.0, f64::min);
    assert!(worst > 0.95, "multiple coherence down to {worst} with no noise");
}

#[test]
fn stretches_are_windowed_separately_and_gaps_do_not_leak() {
    let bq = biquad(2.0 * PI * 0.8, 0.3, 2.0);
    let mk = |seed| {
        let x = white(8_000, 1.0, seed);
        let y = filter(&bq, &x);
        vec![x, y]
    };
    // Two stretches of unrelated data: joined they would not be one record.
    let o = SpectralOptions { window_lengths_s: vec![40.0, 20.0, 10.0], ..opts() };
    let r = frequency_responses(&[mk(11), mk(12)], &names(&["u"]), &names(&["y"]), DT, &o).unwrap();
    let (db, deg) = deviation(&r.pairs[0], |f| response(&bq, f));
    assert!(db < 0.5 && deg < 3.0, "{db} dB {deg} deg");
}

#[test]
fn bad_input_is_named() {
    let x = white(2_000, 1.0, 1);
    let y = x.clone();
    let long = SpectralOptions { window_lengths_s: vec![30.0], ..opts() };
    let e = frequency_responses(
        &[vec![x.clone(), y.clone()]],
        &names(&["de"]),
        &names(&["q"]),
        DT,
        &long,
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("`window_lengths_s`") && e.to_string().contains("longer"),
        "{e}"
    );
    let zero = vec![0.0; 2_000];
    let e =
        frequency_responses(&[vec![zero, y.clone()]], &names(&["de"]), &names(&["q"]), DT, &opts())
            .unwrap_err();
    assert!(e.to_string().contains("input `de` is not excited"), "{e}");
    let low = SpectralOptions { f_min_hz: Some(0.01), ..opts() };
    let e = frequency_responses(
        &[vec![x.clone(), y.clone()]],
        &names(&["de"]),
        &names(&["q"]),
        DT,
        &low,
    )
    .unwrap_err();
    assert!(e.to_string().contains("`f_min_hz`"), "{e}");
    let mut bad = y;
    bad[7] = f64::NAN;
    let e = frequency_responses(&[vec![x, bad]], &names(&["de"]), &names(&["q"]), DT, &opts())
        .unwrap_err();
    assert!(e.to_string().contains("sample 7"), "{e}");
}

#[test]
fn points_per_decade_beyond_the_limit_are_refused_before_any_grid_is_made() {
    let x = white(2_000, 1.0, 3);
    let y = x.clone();
    // The largest value, whose grid count once wrapped to an empty grid (and an index panic),
    // a value that would allocate terabytes, and one just above the limit.
    for ppd in [usize::MAX, 1_000_000_000_000, MAX_POINTS_PER_DECADE + 1] {
        let o = SpectralOptions { points_per_decade: ppd, ..opts() };
        let e = o.check().unwrap_err().to_string();
        assert!(e.contains("`points_per_decade`") && e.contains("1000"), "{e}");
        let zero = vec![0.0; 2_000];
        let e =
            frequency_responses(&[vec![zero, y.clone()]], &names(&["de"]), &names(&["q"]), DT, &o)
                .unwrap_err();
        assert!(matches!(e, SpectralError::Option { option: "points_per_decade", .. }), "{e}");
    }
    let at_limit = SpectralOptions { points_per_decade: MAX_POINTS_PER_DECADE, ..opts() };
    assert!(at_limit.check().is_ok());
    let r =
        frequency_responses(&[vec![x, y]], &names(&["de"]), &names(&["q"]), DT, &at_limit).unwrap();
    // f_max 5 Hz, f_min 2/T_max: the grid holds decades × 1000 + 1 points.
    let p = &r.pairs[0];
    let decades = (p.frequency_hz[p.frequency_hz.len() - 1] / p.frequency_hz[0]).log10();
    assert_eq!(p.frequency_hz.len(), (decades * 1000.0).round() as usize + 1);
}

#[test]
fn log_grid_of_bounds_that_give_no_decade_is_empty_instead_of_wrapping() {
    assert!(log_grid(1.0, f64::INFINITY, 40).is_empty());
    assert!(log_grid(0.0, 10.0, 40).is_empty());
    assert!(log_grid(10.0, 1.0, 40).is_empty());
    assert!(log_grid(1.0, 10.0, 0).is_empty());
    let g = log_grid(1.0, 100.0, 2);
    assert_eq!(g.len(), 5);
    assert!((g[1] - 10f64.sqrt()).abs() < 1e-12 && (g[4] - 100.0).abs() < 1e-9, "{g:?}");
}

#[test]
fn options_that_are_not_finite_are_named() {
    let cases: [(SpectralOptions, &str); 5] = [
        (SpectralOptions { overlap: f64::NAN, ..opts() }, "overlap"),
        (SpectralOptions { window_lengths_s: vec![10.0, -1.0], ..opts() }, "window_lengths_s"),
        (SpectralOptions { f_min_hz: Some(f64::NAN), ..opts() }, "f_min_hz"),
        (SpectralOptions { f_max_hz: Some(f64::INFINITY), ..opts() }, "f_max_hz"),
        (SpectralOptions { f_min_hz: Some(3.0), f_max_hz: Some(2.0), ..opts() }, "f_max_hz"),
    ];
    for (o, name) in cases {
        match o.check() {
            Err(SpectralError::Option { option, .. }) => assert_eq!(option, name),
            other => panic!("{name}: {other:?}"),
        }
    }
}

#[test]
fn log_chirp_drive_recovers_the_response() {
    // The F-16 flight-test input: a logarithmic sweep 0.1–20 rad/s over 240 s with fades.
    let bq = biquad(2.0 * PI * 0.3, 0.5, 3.0);
    let sweep =
        crate::Sweep::new(1.0, 0.1, 20.0, 5.0, 240.0, crate::SweepLaw::Logarithmic, 5.0).unwrap();
    let x: Vec<f64> =
        (0..25_000).map(|k| crate::InputSignal::value(&sweep, k as f64 * DT)).collect();
    let y = filter(&bq, &x);
    let o = SpectralOptions {
        f_min_hz: Some(0.1 / (2.0 * PI) * 1.5),
        f_max_hz: Some(2.0),
        ..SpectralOptions::default()
    };
    let r = frequency_responses(&[vec![x, y]], &names(&["u"]), &names(&["y"]), DT, &o).unwrap();
    let (db, deg) = deviation_where(&r.pairs[0], |f| response(&bq, f), 0.8);
    assert!(db < 1.0 && deg < 5.0, "{db} dB {deg} deg");
}

/// An upper bound not above the lower one names the upper bound's field and says why in words
/// any face can show: no other field's spelling in the reason (a CLI user once read the
/// Python keyword `f_min_hz` there).
#[test]
fn errors_an_upper_bound_not_above_the_lower_names_it_in_plain_words() {
    let o =
        SpectralOptions { f_min_hz: Some(10.0), f_max_hz: Some(1.0), ..SpectralOptions::default() };
    match o.check() {
        Err(SpectralError::Option { option, reason }) => {
            assert_eq!(option, "f_max_hz");
            assert_eq!(reason, "1 Hz is not above the lowest frequency asked for, 10 Hz");
        }
        other => panic!("{other:?}"),
    }
}

/// The composite of two windows' spectra at one frequency is their average weighted by
/// `1/ε² = 2 n_d γ²/(1 − γ²)` (Tischler & Remple §8.6): a window of coherence 0.99 giving
/// H = 1 and one of coherence 0.5 giving H = 2, each of 10 averages, compose to
/// (w₁·1 + w₂·2)/(w₁ + w₂) = 1.0099…, where an unweighted average would give 1.5.
#[test]
fn analytic_composite_weights_each_window_by_its_random_error() {
    let c = |re: f64| Complex64::new(re, 0.0);
    // Single input: S = [Gxx, Gxy; Gyx, Gyy], H = Gxy/Gxx, γ² = |Gxy|²/(Gxx Gyy).
    let window = |h: f64, coherence: f64| (vec![c(1.0), c(h), c(h), c(h * h / coherence)], 10.0);
    let weight = |coherence: f64| 2.0 * 10.0 * coherence / (1.0 - coherence);
    let expected = (weight(0.99) * 1.0 + weight(0.5) * 2.0) / (weight(0.99) + weight(0.5));
    let solved = composite([window(1.0, 0.99), window(2.0, 0.5)].into_iter(), 1).unwrap();
    assert!((solved.h[0] - c(expected)).norm() < 1e-12, "{} vs {expected}", solved.h[0]);
}

/// The Gauss–Jordan inverse needs its row pivoting: a complex 3×3 matrix whose first two
/// diagonal elements are zero, a row permutation of an upper-triangular one, so that each
/// column has one usable pivot and the largest element of that column must be taken (another
/// column's element would pick a zero pivot). `A · A⁻¹` must be the identity to rounding, and
/// a singular matrix has none.
#[test]
fn analytic_inverse_pivots_on_the_largest_element_of_its_column() {
    let c = |re: f64, im: f64| Complex64::new(re, im);
    #[rustfmt::skip]
    let a = [
        c(0.0, 0.0), c(2.0, 1.0), c(1.0, 0.0),
        c(0.0, 0.0), c(0.0, 0.0), c(3.0, -1.0),
        c(1.5, 0.5), c(0.0, 0.0), c(4.0, 0.0),
    ];
    let inv = invert(&a, 3).expect("invertible (det = (1.5+0.5i)(2+i)(3−i))");
    for i in 0..3 {
        for j in 0..3 {
            let p: Complex64 = (0..3).map(|k| a[i * 3 + k] * inv[k * 3 + j]).sum();
            let want = if i == j { 1.0 } else { 0.0 };
            assert!((p - c(want, 0.0)).norm() < 1e-12, "(A·A⁻¹)[{i}][{j}] = {p}");
        }
    }
    let singular = [c(1.0, 0.0), c(2.0, 0.0), c(2.0, 0.0), c(4.0, 0.0)];
    assert!(invert(&singular, 2).is_none());
}
