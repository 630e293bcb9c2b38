use super::*;
use crate::output_error::tests::{lon, simulate_with_process_noise};
use crate::test_aircraft::trimmed_truth;

const LON_ESTIMATED: [&str; 5] = ["CL_alpha", "CL_de", "Cm_alpha", "Cm_q", "Cm_de"];

fn record(noise_scale: f64, seed: u64) -> Vec<AirDataSample> {
    let st = lon();
    let th = trimmed_truth(&st);
    simulate_with_process_noise(
        &st,
        &th,
        50.0,
        20.0,
        noise_scale,
        seed,
        [0.0; N_STATES],
        [0.0; N_STATES],
    )
}

fn config() -> FdoeConfig {
    FdoeConfig { band_hz: (0.05, 3.0), ..FdoeConfig::new(lon()) }
}

/// On a noise-free record of the nonlinear model (doublets of 2° on the elevator) the
/// linearised model recovers the derivatives it sees within 1 % (what is left is the
/// nonlinearity of the record about its mean condition); the zero-order and drag terms are
/// not estimated and keep their equation-error start.
#[test]
fn recovers_the_short_period_derivatives_of_a_noise_free_record() {
    let st = lon();
    let truth = trimmed_truth(&st);
    let rec = record(0.0, 1);
    let r = fit(&[&rec], &config()).unwrap();
    assert!(r.termination.is_converged(), "{:?}", r.termination);
    for (i, name) in r.names.iter().enumerate() {
        let estimated = LON_ESTIMATED.contains(&name.as_str());
        assert_eq!(r.estimated[i], estimated, "{name}");
        assert_eq!(r.sigma[i].is_some(), estimated, "{name}");
        if estimated {
            let rel = (r.values[i] - truth[i]) / truth[i];
            assert!(
                rel.abs() < 0.01,
                "{name}: {} vs {} ({:+.2} %)",
                r.values[i],
                truth[i],
                100.0 * rel
            );
        } else {
            assert_eq!(r.values[i], r.start[i], "{name}");
        }
    }
    assert_eq!(r.states, vec![state::ALPHA, state::Q]);
}

/// With white sensor noise the Cramér–Rao σ describe the scatter of 24 records: per
/// parameter the scatter is 0.6–1.6 × the mean σ and the mean estimate within 3 standard
/// errors of the truth (less the linearisation's own offset, measured on the noise-free record).
#[test]
fn cramer_rao_sigma_matches_the_scatter_over_noisy_records() {
    let clean = fit(&[&record(0.0, 1)], &config()).unwrap();
    let runs: Vec<FdoeResult> =
        (0..24).map(|seed| fit(&[&record(1.0, 100 + seed)], &config()).unwrap()).collect();
    for name in LON_ESTIMATED {
        let est: Vec<f64> = runs.iter().map(|r| r.get(name).unwrap().0).collect();
        let sig: Vec<f64> = runs.iter().map(|r| r.get(name).unwrap().1).collect();
        let n = est.len() as f64;
        let mean = est.iter().sum::<f64>() / n;
        let sd = (est.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let sigma = sig.iter().sum::<f64>() / n;
        let centre = clean.get(name).unwrap().0;
        std::println!("{name}: mean {mean:.4} (clean {centre:.4}) scatter {sd:.4} σ {sigma:.4}");
        assert!((0.6..=1.6).contains(&(sd / sigma)), "{name}: scatter {sd} vs σ {sigma}");
        assert!((mean - centre).abs() < 3.0 * sd / n.sqrt(), "{name}: mean {mean} vs {centre}");
    }
}

/// A band with no frequency of the record, a band upside down and non-uniform sampling are
/// refused with what is wrong.
#[test]
fn errors_name_the_band_and_the_sampling() {
    let rec = record(0.0, 1);
    let e = fit(&[&rec], &FdoeConfig { band_hz: (0.001, 0.01), ..config() }).unwrap_err();
    assert!(e.to_string().contains("no frequency in the band"), "{e}");
    let e = fit(&[&rec], &FdoeConfig { band_hz: (2.0, 1.0), ..config() }).unwrap_err();
    assert!(e.to_string().contains("0 < f_min < f_max"), "{e}");
    let mut bad = rec.clone();
    bad.remove(300);
    let e = fit(&[&bad], &config()).unwrap_err();
    assert!(
        e.to_string().contains("uniform sampling") && e.to_string().contains("t = 6.02"),
        "{e}"
    );
}

/// The fast transform equals the defining sum `Σ_i x_i e^{−j2πki/N}` at every bin, on a length
/// with a large prime factor (rustfft's slowest path) and on a power of two.
#[test]
fn dft_equals_the_defining_sum() {
    for n in [97usize, 256] {
        let x: Vec<f64> = (0..n).map(|i| ((i * i) % 13) as f64 - 0.3 * (i as f64).sin()).collect();
        let bins: Vec<usize> = (1..n / 2).step_by(7).collect();
        let fft = rustfft::FftPlanner::<f64>::new().plan_fft_forward(n);
        let fast = dft(&*fft, &x, &bins);
        for (&k, got) in bins.iter().zip(&fast) {
            let w = -2.0 * core::f64::consts::PI * k as f64 / n as f64;
            let direct = x
                .iter()
                .enumerate()
                .fold(C64::new(0.0, 0.0), |a, (i, v)| a + C64::from_polar(*v, w * i as f64));
            assert!(
                (got - direct).norm() < 1e-9 * (1.0 + direct.norm()),
                "n {n} k {k}: {got} vs {direct}"
            );
        }
    }
}

/// The information matrix's inverse holds over any range of parameter units: a correlated
/// 2×2 with standard deviations 10⁻¹⁴⁰ and 10¹⁴⁰ (ρ = 0.6) is inverted to its closed form
/// `[[1/a², −ρ/(ab)], [−ρ/(ab), 1/b²]] / (1 − ρ²)`, which only the Jacobi scaling reaches
/// (unscaled, or scaled the wrong way, its entries leave the floating-point range).
#[test]
fn analytic_spd_inverse_holds_over_any_range_of_units() {
    let (a, b, rho) = (1e-140_f64, 1e140_f64, 0.6);
    let m = nalgebra::DMatrix::from_row_slice(2, 2, &[a * a, rho * a * b, rho * a * b, b * b]);
    let inv = spd_inverse(&m).expect("positive definite");
    let k = 1.0 / (1.0 - rho * rho);
    let want = [k / (a * a), -k * rho / (a * b), -k * rho / (a * b), k / (b * b)];
    for (i, w) in want.iter().enumerate() {
        let got = inv[(i / 2, i % 2)];
        assert!((got - w).abs() <= 1e-12 * w.abs(), "[{}][{}]: {got} vs {w}", i / 2, i % 2);
    }
    let singular = nalgebra::DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
    assert!(spd_inverse(&singular).is_none());
}

/// A frequency-domain fit whose sensitivities cannot be formed at its second iterate keeps the
/// first (the same fit stopped after one iteration), not converged with the failure named.
#[test]
fn a_numerical_failure_at_a_later_iterate_keeps_the_last_good_one() {
    let rec = record(1.0, 3);
    let mut cfg = config();
    cfg.max_iterations = 1;
    let one = fit(&[&rec], &cfg).unwrap();
    cfg.max_iterations = 50;
    crate::output_error::fault::fail_after(2);
    let kept = fit(&[&rec], &cfg).unwrap();
    let why = NotConverged::NumericalFailure {
        what: crate::output_error::fault::WHAT,
        t_s: crate::output_error::fault::T_S,
    };
    assert_eq!(kept.termination, Termination::NotConverged(why));
    assert_eq!(kept.values, one.values);
    // Debug text: the start's step in σ is NaN, which `==` never equals.
    assert_eq!(format!("{:?}", kept.iterations), format!("{:?}", one.iterations));
    assert!(kept.sigma.iter().flatten().all(|v| v.is_finite()));
}
