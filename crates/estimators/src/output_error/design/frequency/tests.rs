use super::*;
use crate::flight_model::{Output, StateSet};
use crate::output_error::design::{
    FlightCondition, PlannedInputs, Sensor, predict_crb, trim_biases,
};
use crate::test_aircraft::{ALPHA0, RHO, THRUST, V0, constants, derivatives, three_two_one_one};
use crate::vocabulary::ModelStructure;
use nalgebra::DVector;
use std::println;

fn c(re: f64) -> Complex<f64> {
    Complex::new(re, 0.0)
}

/// (a) Closed form: the Ornstein–Uhlenbeck process `ẋ = −a x + w` observed (here with
/// negligible sensor noise) over `T` has the asymptotic Fisher information `T / (2a)` for the
/// rate `a` (the continuous-observation result; e.g. Kutoyants, *Statistical Inference for
/// Ergodic Diffusion Processes*, 2004, the OU example). Its spectrum is `q / (ω² + a²)` (+ r),
/// `∂Φ/∂a = −2a q / (ω² + a²)²`: the covariance term of the Whittle sum must reproduce it.
#[test]
fn ornstein_uhlenbeck_rate_information_is_t_over_2a() {
    let (a, q, dt, n) = (1.0, 2.0, 0.05, 8000usize);
    let t = n as f64 * dt;
    // Sensor noise far below the process spectrum at Nyquist (q dt²/π² ≈ 5e-4).
    let r = 1e-9;
    let mut m = DMatrix::zeros(1, 1);
    for k in 0..=n / 2 {
        let w = 2.0 * core::f64::consts::PI * k as f64 / t;
        let phi = CMatrix::from_element(1, 1, c(q / (w * w + a * a) + r));
        let d = CMatrix::from_element(1, 1, c(-2.0 * a * q / (w * w + a * a).powi(2)));
        let dmu = CMatrix::zeros(1, 1);
        add_bin_information(n, k == 0 || 2 * k == n, &phi, &[Some(d)], Some(&dmu), &mut m).unwrap();
    }
    let closed = t / (2.0 * a);
    println!("OU: Whittle {:.3} vs T/(2a) = {closed:.3}", m[(0, 0)]);
    // The Riemann sum over bins of width 2π/T of a smooth integrand, plus the DC bin: O(1/(aT)).
    assert!((m[(0, 0)] / closed - 1.0).abs() < 0.02, "{} vs {closed}", m[(0, 0)]);
}

/// Parseval: with a white spectrum the mean term equals `Σ_t s_tᵀ R⁻¹ s_t` exactly, for even
/// and odd record lengths.
#[test]
fn mean_term_with_white_noise_is_the_time_domain_information() {
    for n in [37usize, 40] {
        let (ny, nb) = (2, 3);
        let s: Vec<f64> =
            (0..n * ny * nb).map(|i| ((i * 7919) % 113) as f64 / 113.0 - 0.4).collect();
        let rv = [0.3, 2.0];
        let mut td = DMatrix::<f64>::zeros(nb, nb);
        for t in 0..n {
            for j in 0..ny {
                for a in 0..nb {
                    for b in 0..nb {
                        td[(a, b)] += s[(t * ny + j) * nb + a] * s[(t * ny + j) * nb + b] / rv[j];
                    }
                }
            }
        }
        let dft = dft_positive(&s, n, ny * nb);
        let phi = CMatrix::from_fn(ny, ny, |i, j| c(if i == j { rv[i] } else { 0.0 }));
        let mut fd = DMatrix::<f64>::zeros(nb, nb);
        for (k, sk) in dft.iter().enumerate() {
            let dmu = CMatrix::from_row_slice(ny, nb, sk);
            add_bin_information(
                n,
                k == 0 || 2 * k == n,
                &phi,
                &[None, None, None],
                Some(&dmu),
                &mut fd,
            )
            .unwrap();
        }
        assert!((&fd - &td).norm() < 1e-10 * td.norm(), "n = {n}\n{fd}\n{td}");
    }
}

/// A small discrete system in coloured process noise entering through its rate (like the gust
/// `−Γ ġ`): `x_{t+1} = φ x_t + b u_t − γ (g_{t+1} − g_t)`, `y_t = x_t + v_t`, gust AR(1)
/// `g_{t+1} = ρ g_t + e_t` (stationary), `e ~ N(0, q)`, `v ~ N(0, r)`, `x` known 0 at the
/// start for the mean and stationary noise.
#[derive(Clone, Copy)]
struct Small {
    phi: f64,
    b: f64,
    gamma: f64,
    rho: f64,
    q: f64,
    r: f64,
}

impl Small {
    fn input(n: usize) -> Vec<f64> {
        // Small against the noise, so that the covariance term carries much of the φ information.
        (0..n)
            .map(|t| {
                0.05 * if (t / 17) % 3 == 0 {
                    1.0
                } else if (t / 11) % 2 == 0 {
                    -0.5
                } else {
                    0.3
                }
            })
            .collect()
    }

    /// Mean and its sensitivities to (φ, b).
    fn mean(&self, n: usize) -> (Vec<f64>, Vec<[f64; 2]>) {
        let u = Self::input(n);
        let (mut x, mut dx) = (0.0, [0.0, 0.0]);
        let (mut mu, mut s) = (Vec::new(), Vec::new());
        for ut in u.iter().take(n) {
            mu.push(x);
            s.push(dx);
            dx = [self.phi * dx[0] + x, self.phi * dx[1] + ut];
            x = self.phi * x + self.b * ut;
        }
        (mu, s)
    }

    /// The noise model in state-space form: `z = (x, g)`, `(Φ, Q, stationary P)`.
    fn state_space(&self) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        let f = DMatrix::from_row_slice(
            2,
            2,
            &[self.phi, -self.gamma * (self.rho - 1.0), 0.0, self.rho],
        );
        let w = DMatrix::from_column_slice(2, 1, &[-self.gamma, 1.0]);
        let qq = &w * w.transpose() * self.q;
        let mut p = DMatrix::zeros(2, 2);
        for _ in 0..20000 {
            p = &f * p * f.transpose() + &qq;
        }
        (f, qq, p)
    }

    /// Exact stationary covariance of the noise `y − μ` over `n` samples.
    fn covariance(&self, n: usize) -> DMatrix<f64> {
        let (f, _, p) = self.state_space();
        let mut lag = vec![0.0; n];
        let mut fp = p;
        for l in lag.iter_mut() {
            *l = fp[(0, 0)];
            fp = &f * fp;
        }
        DMatrix::from_fn(n, n, |i, j| lag[i.abs_diff(j)] + if i == j { self.r } else { 0.0 })
    }

    /// Exact Gaussian Fisher information for (φ, b), `(∂μᵀK⁻¹∂μ, ½ tr(K⁻¹∂K K⁻¹∂K))`, `∂K/∂φ`
    /// by central differences.
    fn exact(&self, n: usize) -> (DMatrix<f64>, f64) {
        let (_, s) = self.mean(n);
        let k = self.covariance(n);
        let kinv = k.clone().cholesky().unwrap().inverse();
        let h = 1e-6;
        let kp = Small { phi: self.phi + h, ..*self }.covariance(n);
        let km = Small { phi: self.phi - h, ..*self }.covariance(n);
        let dk = (kp - km) / (2.0 * h);
        let sm = DMatrix::from_fn(n, 2, |t, a| s[t][a]);
        let a = &kinv * &dk;
        (sm.transpose() * &kinv * &sm, 0.5 * (&a * &a).trace())
    }

    /// The mean term by [`innovations_information`].
    fn innovations(&self, n: usize) -> DMatrix<f64> {
        let (_, s) = self.mean(n);
        let flat: Vec<f64> = s.iter().flat_map(|r| r.iter().copied()).collect();
        let (f, q, p) = self.state_space();
        let h = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        innovations_information(&f, &q, &h, &[self.r], &p, &flat, n, 2).unwrap()
    }

    /// The Whittle information of the same experiment (`with_cov`: the covariance term too).
    fn whittle(&self, n: usize, with_cov: bool) -> DMatrix<f64> {
        let (_, s) = self.mean(n);
        let flat: Vec<f64> = s.iter().flat_map(|r| r.iter().copied()).collect();
        let dft = dft_positive(&flat, n, 2);
        let mut m = DMatrix::zeros(2, 2);
        for (k, sk) in dft.iter().enumerate() {
            let w = 2.0 * core::f64::consts::PI * k as f64 / n as f64;
            let z = Complex::new(w.cos(), w.sin());
            let g = -(z - 1.0) * self.gamma / (z - self.phi);
            let dg = g / (z - self.phi);
            let phig = self.q / (Complex::new(1.0, 0.0) - z.conj() * self.rho).norm_sqr();
            let phi = g.norm_sqr() * phig + self.r;
            let dphi = 2.0 * (g.conj() * dg).re * phig;
            add_bin_information(
                n,
                k == 0 || 2 * k == n,
                &CMatrix::from_element(1, 1, c(phi)),
                &[with_cov.then(|| CMatrix::from_element(1, 1, c(dphi))), None],
                Some(&CMatrix::from_row_slice(1, 2, sk)),
                &mut m,
            )
            .unwrap();
        }
        m
    }
}

/// The innovations form of the mean term is the exact `∂μᵀ K⁻¹ ∂μ` with the full `N × N`
/// covariance (to rounding).
#[test]
fn innovations_mean_term_is_exact() {
    let sys = Small { phi: 0.85, b: 1.0, gamma: 0.6, rho: 0.9, q: 1.0, r: 0.05 };
    for n in [50usize, 200] {
        let (ex, _) = sys.exact(n);
        let kf = sys.innovations(n);
        assert!((&kf - &ex).norm() < 1e-7 * ex.norm(), "n = {n}\n{kf}\n{ex}");
    }
}

/// (c) The turbulent case against the exact time-domain Gaussian Fisher information with the
/// full `N × N` output covariance. The Whittle mean term is far off on short records here (the
/// rate-driven noise has a spectral zero at DC, where the record's end transient dominates the
/// low bins: 10× on F_bb at N = 150): that is why the mean term is computed exactly. The
/// Whittle covariance term is within the asymptotic error, of the order (noise correlation
/// time ≈ 1/(1−ρ) = 10 samples) / N, and shrinks as N grows.
#[test]
fn hybrid_information_matches_exact_time_domain_information_of_a_small_turbulent_system() {
    let sys = Small { phi: 0.85, b: 1.0, gamma: 0.6, rho: 0.9, q: 1.0, r: 0.05 };
    let mut errs = Vec::new();
    for n in [150usize, 400] {
        let (ex_mean, ex_cov) = sys.exact(n);
        let wh_cov = sys.whittle(n, true)[(0, 0)] - sys.whittle(n, false)[(0, 0)];
        let mut ex = ex_mean.clone();
        ex[(0, 0)] += ex_cov;
        let mut hy = sys.innovations(n);
        hy[(0, 0)] += wh_cov;
        let se = ex.clone().try_inverse().unwrap();
        let sh = hy.clone().try_inverse().unwrap();
        let err =
            (0..2).map(|i| ((sh[(i, i)] / se[(i, i)]).sqrt() - 1.0).abs()).fold(0.0_f64, f64::max);
        let cov_share = ex_cov / ex[(0, 0)];
        println!(
            "N = {n}: covariance term exact {ex_cov:.1}, Whittle {wh_cov:.1}; share {cov_share:.2}; max σ error {err:.4}"
        );
        assert!(cov_share > 0.3, "the test must exercise the covariance term");
        errs.push(((wh_cov / ex_cov) - 1.0).abs());
        assert!(err < 0.06, "N = {n}: σ error {err}");
    }
    assert!(errs[1] < 0.03 && errs[1] < errs[0], "covariance-term error must shrink: {errs:?}");
}

/// Dryden shaping filters (MIL-F-8785C; the signals crate's realisation) at `V0`, intensities
/// `sigma` (m/s) and one scale length `l` (m).
fn dryden(sigma: [f64; 3], l: f64) -> GustModel {
    let a = V0 / l;
    let first = ShapingFilter {
        a: DMatrix::from_element(1, 1, -a),
        b: DVector::from_element(1, 1.0),
        c: DVector::from_element(1, sigma[0] * (2.0 * a).sqrt()),
    };
    let second = |s: f64| ShapingFilter {
        a: DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -a * a, -2.0 * a]),
        b: DVector::from_column_slice(&[0.0, 1.0]),
        c: DVector::from_column_slice(&[s * a.sqrt() * a, s * a.sqrt() * 3f64.sqrt()]),
    };
    GustModel { filters: [first, second(sigma[1]), second(sigma[2])] }
}

/// The shaping filter's PSD `|H|²/π` is the Dryden PSD (module doc convention).
#[test]
fn dryden_filter_response_has_the_dryden_psd() {
    let (l, sw) = (533.0, 1.3);
    let g = dryden([sw, sw, sw], l);
    for w in [0.01, 0.3, 2.0, 20.0] {
        let x2 = (l * w / V0).powi(2);
        let pi = core::f64::consts::PI;
        let pw = sw * sw * l / (pi * V0) * (1.0 + 3.0 * x2) / (1.0 + x2).powi(2);
        let pu = sw * sw * 2.0 * l / (pi * V0) / (1.0 + x2);
        let hu = g.filters[0].response(w).unwrap().norm_sqr() / pi;
        let hw = g.filters[2].response(w).unwrap().norm_sqr() / pi;
        assert!((hu / pu - 1.0).abs() < 1e-10 && (hw / pw - 1.0).abs() < 1e-10, "{w}");
    }
}

fn lon_plan(duration_s: f64) -> DesignPlan {
    let st = ModelStructure::longitudinal();
    let cond = FlightCondition::level(V0, ALPHA0, RHO, THRUST);
    let theta = trim_biases(&st, &derivatives(&st), &constants(), &cond).unwrap();
    let dt = 0.02;
    let de = three_two_one_one(&[1.0], 0.4, 0.02, duration_s, dt);
    let sigma = |o: Output| match o {
        Output::Vt => 0.3,
        Output::Alpha | Output::Beta => 0.002,
        Output::Ax | Output::Ay | Output::Az => 0.08,
        Output::Pdot | Output::Qdot | Output::Rdot => 0.05,
        _ => 0.003,
    };
    let sensors = StateSet::Longitudinal
        .outputs()
        .iter()
        .map(|&o| Sensor { output: o, sigma: sigma(o) })
        .collect();
    DesignPlan::new(
        st,
        theta,
        constants(),
        cond,
        vec![PlannedInputs { dt_s: dt, de_rad: de, ..Default::default() }],
        sensors,
    )
}

/// (b) No turbulence: the frequency-domain bound is the time-domain bound (Parseval, exact to
/// rounding, not just within a few %); a lateral-only gust (`v_g`) does not reach the
/// longitudinal states at `β = 0` (Γ's columns), while vertical turbulence raises the bound.
#[test]
fn calm_air_equals_predict_crb_and_gust_axes_are_routed() {
    let plan = lon_plan(20.0);
    let calm = predict_crb(&plan).unwrap();
    let zero = predict_crb_turbulent(&plan, &dryden([0.0; 3], 533.0)).unwrap();
    let lateral = predict_crb_turbulent(&plan, &dryden([0.0, 2.0, 0.0], 533.0)).unwrap();
    for i in 0..calm.n() {
        let (a, b) = (calm.sigma[i].unwrap(), zero.sigma[i].unwrap());
        assert!((a / b - 1.0).abs() < 1e-8, "{}: {a} vs {b}", calm.names[i]);
        let l = lateral.sigma[i].unwrap();
        assert!((a / l - 1.0).abs() < 1e-8, "{}: v_g changed a longitudinal bound", calm.names[i]);
    }
    // Light-ish vertical turbulence, σ_w = 1 m/s, L = 533 m, V = V0 (Dryden w form).
    let turb = predict_crb_turbulent(&plan, &dryden([0.0, 0.0, 1.0], 533.0)).unwrap();
    let mut larger = 0;
    for i in 0..calm.n_params {
        let r = turb.sigma[i].unwrap() / calm.sigma[i].unwrap();
        println!("{:<12} turbulent / calm σ = {r:.2}", calm.names[i]);
        larger += usize::from(r > 1.0);
    }
    assert!(larger * 2 > calm.n_params, "turbulence must raise most bounds");
}

/// Γ is the Jacobian of `(V, α, β) = (|v|, atan(w/u), asin(v/V))` with respect to the body
/// velocity (central differences at a general attitude, β ≠ 0), rows in the set's state order.
#[test]
fn gust_input_matrix_is_the_wind_axis_jacobian() {
    let (vt, al, be) = (150.0_f64, 0.2_f64, -0.1_f64);
    let body = [vt * al.cos() * be.cos(), vt * be.sin(), vt * al.sin() * be.cos()];
    let wind_axes = |b: [f64; 3]| {
        let v = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
        [v, b[2].atan2(b[0]), (b[1] / v).asin()]
    };
    let states = StateSet::Coupled.states();
    let g = gust_input_matrix(states, vt, al, be);
    for k in 0..3 {
        let h = 1e-4;
        let (mut bp, mut bm) = (body, body);
        bp[k] += h;
        bm[k] -= h;
        let (fp, fm) = (wind_axes(bp), wind_axes(bm));
        for (r, &st) in states.iter().enumerate() {
            let want = if st < 3 { (fp[st] - fm[st]) / (2.0 * h) } else { 0.0 };
            assert!(
                (g[(r, k)] - want).abs() < 1e-9,
                "row {st} column {k}: {} vs {want}",
                g[(r, k)]
            );
        }
    }
    // Longitudinal set: rows V, α (filter order V, α, θ, q), no β row.
    let gl = gust_input_matrix(StateSet::Longitudinal.states(), vt, al, 0.0);
    assert_eq!(gl.nrows(), 4);
    assert!((gl[(1, 2)] - al.cos() / vt).abs() < 1e-15 && gl[(2, 2)] == 0.0);
}
