//! The frequency responses of simulated F-16 chirp flights (scenarios/sim/chirp_*.toml: sensor
//! noise, light turbulence) against the analytic responses `C (jωI − A)⁻¹ B` of the
//! linearisation at the same trim, and the fitted modes against its eigenvalues.
//!
//! Like with like: the record's surface channels are the actuators' outputs (the mapping's
//! `elevator_rad` etc.), so the linearisation's B (surface inputs) is compared without the
//! actuator; the sensed rates carry white noise only (no filter, no delay). Both are
//! perturbations about the same trim (the spectra remove each window's mean and trend).

use aeroident_io::{FlightDataReader, Mapping};
use aeroident_models::f16::{CONTROL_NAMES, F16, N_STATES, P, Q, R, STATE_NAMES};
use aeroident_models::linearize::{Linearization, ModeName, f16_modes, linearize_f16};
use aeroident_pipelines::freqresp::{FreqRespOptions, freqresp};
use aeroident_pipelines::sim::{SimRun, load_scenario, run};
use aeroident_signals::Input;
use aeroident_signals::spectral::{Complex64, SpectralOptions, frequency_responses};
use aeroident_signals::tf_fit::TfSpec;
use nalgebra::{DMatrix, SVector};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn simulate(name: &str) -> SimRun {
    let path = root().join(format!("scenarios/sim/{name}.toml"));
    run(&load_scenario(&path).unwrap(), path.parent().unwrap()).unwrap()
}

fn csv(run: &SimRun) -> String {
    let mut t = run.table.columns.join(",");
    t.push('\n');
    for k in 0..run.table.data[0].len() {
        let row: Vec<String> = run.table.data.iter().map(|c| format!("{:.12e}", c[k])).collect();
        t.push_str(&row.join(","));
        t.push('\n');
    }
    t
}

/// `C (jωI − A)⁻¹ B` of state `out` to control column `input` at `w` rad/s.
fn analytic(a: &DMatrix<Complex64>, b: &[f64], out: usize, w: f64) -> Complex64 {
    let n = N_STATES;
    let mut m = -a.clone();
    for i in 0..n {
        m[(i, i)] += Complex64::new(0.0, w);
    }
    let rhs = nalgebra::DVector::from_iterator(n, b.iter().map(|v| Complex64::new(*v, 0.0)));
    m.lu().solve(&rhs).unwrap()[out]
}

struct Axis {
    scenario: &'static str,
    input: &'static str,
    output: &'static str,
    state: usize,
    control: usize,
    fit: &'static str,
    mode: ModeName,
}

/// The accuracy targets (1 dB, 5° against the linearisation), as a measurement: run with
/// `cargo test --release -p aeroident-pipelines --test all freqresp_f16:: -- --include-ignored --nocapture`
/// (it prints every axis's numbers). Ignored in CI because the targets are not met on these
/// records (docs/frequency-response.md, "Measured against the linearisation").
#[test]
#[ignore = "targets not met yet: see docs/frequency-response.md"]
fn chirp_responses_match_the_linearisation_and_the_fitted_modes_its_eigenvalues() {
    let axes = [
        Axis {
            scenario: "chirp_elevator",
            input: "de",
            output: "q",
            state: Q,
            control: 1,
            fit: "q/de:1/2+delay@0.5:10",
            mode: ModeName::ShortPeriod,
        },
        Axis {
            scenario: "chirp_aileron",
            input: "da",
            output: "p",
            state: P,
            control: 2,
            fit: "",
            mode: ModeName::Roll,
        },
        Axis {
            scenario: "chirp_rudder",
            input: "dr",
            output: "r",
            state: R,
            control: 3,
            fit: "r/dr:3/4+delay",
            mode: ModeName::DutchRoll,
        },
    ];
    let mut failures = Vec::new();
    let mapping = Mapping::from_path(&root().join("mappings/aeroident-sim-measured.toml")).unwrap();
    for ax in &axes {
        let sim = simulate(ax.scenario);
        let lin =
            linearize_f16(&F16::new(0.30).unwrap(), &sim.trim.state, &sim.trim.controls).unwrap();
        let a = DMatrix::from_fn(N_STATES, N_STATES, |i, j| Complex64::new(lin.a[(i, j)], 0.0));
        let b: Vec<f64> = (0..N_STATES).map(|i| lin.b[(i, ax.control)]).collect();
        let text = csv(&sim);
        let reader = FlightDataReader::new(text.as_bytes(), ax.scenario, &mapping).unwrap();
        let opts = FreqRespOptions {
            inputs: vec![ax.input.into()],
            outputs: vec![ax.output.into()],
            fits: if ax.fit.is_empty() { vec![] } else { vec![TfSpec::parse(ax.fit).unwrap()] },
            ..FreqRespOptions::default()
        };
        let r = freqresp(reader, &opts).unwrap();
        let p = &r.pairs[0];
        let (mut db, mut deg, mut used, mut beyond) = (0.0f64, 0.0f64, 0, Vec::new());
        for k in 0..p.frequency_hz.len() {
            let w = 2.0 * std::f64::consts::PI * p.frequency_hz[k];
            if !(0.1..=10.0).contains(&w) || p.coherence[k] < 0.8 {
                continue;
            }
            let h = analytic(&a, &b, ax.state, w);
            let ratio = Complex64::new(p.re[k], p.im[k]) / h;
            if std::env::var("F16_DEBUG").is_ok() {
                eprintln!(
                    "{w:.3} rad/s γ² {:.3} Δ {:.3} dB {:.2} deg ε {:.4}",
                    p.coherence[k],
                    20.0 * ratio.norm().log10(),
                    ratio.arg().to_degrees(),
                    p.random_error[k]
                );
            }
            let e = p.random_error[k];
            let (ddb, ddeg) = ((20.0 * ratio.norm().log10()).abs(), ratio.arg().to_degrees().abs());
            if ddb > 1.0 || ddeg > 5.0 {
                beyond.push(format!("{w:.3} rad/s: {ddb:.2} dB {ddeg:.1} deg, ε {e:.3}"));
            }
            db = db.max((20.0 * ratio.norm().log10()).abs());
            deg = deg.max(ratio.arg().to_degrees().abs());
            used += 1;
        }
        eprintln!(
            "{}/{}: {used} points with γ² ≥ 0.8 in 0.1–10 rad/s, max |Δ| {db:.3} dB {deg:.2} deg",
            ax.output, ax.input
        );
        assert!(used >= 30, "{}/{}: only {used} coherent points", ax.output, ax.input);
        if !beyond.is_empty() {
            failures.push(format!("{}/{}: beyond 1 dB / 5° at {beyond:?}", ax.output, ax.input));
        }
        if let Some(fit) = r.fits.first() {
            let truth = f16_modes(&lin.a).into_iter().find(|m| m.name == ax.mode).unwrap();
            let pole = fit
                .fit
                .poles
                .iter()
                .filter(|f| f.zeta.is_some_and(|z| z < 1.0))
                .min_by(|x, y| {
                    (x.wn_rad_s.unwrap() - truth.wn_rad_s)
                        .abs()
                        .total_cmp(&(y.wn_rad_s.unwrap() - truth.wn_rad_s).abs())
                })
                .unwrap();
            let (wn, zeta) = (pole.wn_rad_s.unwrap(), pole.zeta.unwrap());
            let (ew, ez) = ((wn / truth.wn_rad_s - 1.0) * 100.0, (zeta / truth.zeta - 1.0) * 100.0);
            eprintln!(
                "{}: ωn {wn:.4} vs {:.4} rad/s ({ew:+.2} %), ζ {zeta:.4} vs {:.4} ({ez:+.2} %), J {:.1}",
                fit.spec, truth.wn_rad_s, truth.zeta, fit.fit.cost
            );
            let sw = 100.0 * 3.0 * pole.wn_sigma_rad_s.unwrap_or(f64::NAN) / truth.wn_rad_s;
            let sz = 100.0 * 3.0 * pole.zeta_sigma.unwrap_or(f64::NAN) / truth.zeta;
            eprintln!("  3σ of the fit: ωn {sw:.2} %, ζ {sz:.2} %");
            if !(ew.abs() <= 5.0 && ez.abs() <= 5.0) {
                failures.push(format!("{}: ωn {ew} %, ζ {ez} %", fit.spec));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The linearisation driven by the record's own surface history `u` (control column
/// `control`), from trim: `δẋ = A δx + B δu` by RK4 at the record's step, the surface
/// interpolated linearly within a step (it is a continuous actuator state in the sim, so a
/// zero-order hold would add a half-step delay the flight does not have). Returns state `out`.
fn linear_truth(
    lin: &Linearization<N_STATES, 4>,
    u: &[f64],
    u_trim: f64,
    control: usize,
    out: usize,
    dt: f64,
) -> Vec<f64> {
    let mut dx = SVector::<f64, N_STATES>::zeros();
    let mut y = Vec::with_capacity(u.len());
    for k in 0..u.len() {
        y.push(dx[out]);
        let next = u.get(k + 1).copied().unwrap_or(u[k]);
        let f = |x: &SVector<f64, N_STATES>, s: f64| {
            let mut du = SVector::<f64, 4>::zeros();
            du[control] = u[k] + s * (next - u[k]) - u_trim;
            lin.a * x + lin.b * du
        };
        let k1 = f(&dx, 0.0);
        let k2 = f(&(dx + k1 * (dt / 2.0)), 0.5);
        let k3 = f(&(dx + k2 * (dt / 2.0)), 0.5);
        let k4 = f(&(dx + k3 * dt), 1.0);
        dx += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0);
    }
    y
}

/// `(ω rad/s, γ², 20 log₁₀|Ĥ/H|, ∠(Ĥ/H) deg)` of the composite estimate of `y` to `u` (the
/// defaults of `aeroident freqresp`) against the analytic response, at every grid point.
fn deviations(u: &[f64], y: &[f64], dt: f64, h: impl Fn(f64) -> Complex64) -> Vec<[f64; 4]> {
    let st = vec![vec![u.to_vec(), y.to_vec()]];
    let r = frequency_responses(&st, &["u".into()], &["y".into()], dt, &SpectralOptions::default())
        .unwrap();
    let p = &r.pairs[0];
    (0..p.frequency_hz.len())
        .map(|k| {
            let w = 2.0 * std::f64::consts::PI * p.frequency_hz[k];
            let ratio = Complex64::new(p.re[k], p.im[k]) / h(w);
            [w, p.coherence[k], 20.0 * ratio.norm().log10(), ratio.arg().to_degrees()]
        })
        .collect()
}

/// One cause of the q/de misses, checked: the open-loop elevator chirp excites the phugoid
/// (ωn 0.06 rad/s, ζ 0.1), so the airspeed wanders by ±60 ft/s over the sweep, and each
/// frequency is measured at the dynamic pressure the flight holds when the chirp passes it.
/// Above the short period q/de ≈ M_δe/(jω) ∝ q̄, so in calm air, on the true q, the deviation
/// from the trim's linearisation must be `20 log₁₀(q̄(t_ω)/q̄_trim)`, with `t_ω` the time the
/// sweep's instantaneous frequency is ω — while the linearisation driven by the same surface
/// history (the exact linear truth) shows no deviation there, so the estimator is not the cause.
#[test]
fn q_de_above_the_short_period_follows_the_dynamic_pressure_the_flight_holds() {
    let path = root().join("scenarios/sim/chirp_elevator.toml");
    let mut sc = load_scenario(&path).unwrap();
    sc.wind.clear();
    let sim = run(&sc, path.parent().unwrap()).unwrap();
    let lin = linearize_f16(&F16::new(0.30).unwrap(), &sim.trim.state, &sim.trim.controls).unwrap();
    let a = DMatrix::from_fn(N_STATES, N_STATES, |i, j| Complex64::new(lin.a[(i, j)], 0.0));
    let b: Vec<f64> = (0..N_STATES).map(|i| lin.b[(i, 1)]).collect();
    let h = |w: f64| analytic(&a, &b, Q, w);
    let (dt, de) = (sc.run.dt_s, sim.table.column("elevator_rad").unwrap());
    let flown = deviations(de, sim.table.column("q_rad_s").unwrap(), dt, h);
    let y_lin = linear_truth(&lin, de, sim.trim.controls.elevator_rad, 1, Q, dt);
    let exact = deviations(de, &y_lin, dt, h);
    let Input::Sweep(sweep) = sc.input[0].input.build_in(&root()).unwrap() else {
        panic!("chirp_elevator's input is a sweep")
    };
    let t = sim.table.column("t_s").unwrap();
    let qbar = sim.table.column("qbar_psf").unwrap();
    let mut largest = 0.0f64;
    for (f, e) in flown.iter().zip(&exact).filter(|(f, _)| (3.0..=10.0).contains(&f[0])) {
        // The first sample at which the sweep has reached ω.
        let k = t.iter().position(|&ts| sweep.instantaneous_frequency_rad_s(ts) >= f[0]).unwrap();
        let qbar_db = 20.0 * (qbar[k] / qbar[0]).log10();
        largest = largest.max(qbar_db.abs());
        assert!(f[1] > 0.99, "{:.3} rad/s: calm air, true channels, γ² {}", f[0], f[1]);
        assert!(e[2].abs() < 0.1, "{:.3} rad/s: the linear truth is off by {} dB", e[0], e[2]);
        assert!(
            (f[2] - qbar_db).abs() < 0.15,
            "{:.3} rad/s: Δ {:.3} dB but q̄ then {qbar_db:+.3} dB from trim",
            f[0],
            f[2]
        );
    }
    assert!(largest > 0.5, "the q̄ drift must matter here ({largest:.2} dB at most)");
}

/// Whether a deviation `[ω, γ², dB, deg]` is beyond the targets' 1 dB / 5°.
fn beyond(d: &[f64; 4]) -> bool {
    d[2].abs() > 1.0 || d[3].abs() > 5.0
}

/// The complex ratio a deviation `[ω, γ², dB, deg]` stands for.
fn ratio_of(d: &[f64; 4]) -> Complex64 {
    Complex64::from_polar(10f64.powf(d[2] / 20.0), d[3].to_radians())
}

/// `r` as a deviation `[ω, γ², dB, deg]` at `w`.
fn deviation_of(r: Complex64, w: f64) -> [f64; 4] {
    [w, f64::NAN, 20.0 * r.norm().log10(), r.arg().to_degrees()]
}

/// The stated cause of a miss of the linear truth (docs/frequency-response.md, cause 2): the
/// longest window (half the record, `t_w` s) resolves no better than its Hann main lobe
/// ±2/T_w, and within it the analytic response `h` changes by more than 1 dB / 5°.
fn resolution_cause(h: &impl Fn(f64) -> Complex64, w: f64, t_w: f64) -> bool {
    let lobe = 2.0 * std::f64::consts::PI * 2.0 / t_w;
    (0..=20).map(|j| w - lobe + 2.0 * lobe * f64::from(j) / 20.0).filter(|v| *v > 0.0).any(|v| {
        let r = h(v) / h(w);
        20.0 * r.norm().log10().abs() > 1.0 || r.arg().to_degrees().abs() > 5.0
    })
}

/// The linearisation at the condition `run` holds around step `k`: its states and surfaces
/// averaged over `half` steps either side (the chirp's own oscillation averages out, the
/// drift from trim stays).
fn local_linearisation(run: &SimRun, k: usize, half: usize) -> Linearization<N_STATES, 4> {
    let (lo, hi) = (k.saturating_sub(half), (k + half).min(run.table.data[0].len() - 1));
    let mean = |name: &str| {
        let c = run.table.column(name).unwrap();
        c[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64
    };
    let x = SVector::<f64, N_STATES>::from_fn(|i, _| mean(STATE_NAMES[i]));
    let u = SVector::<f64, 4>::from_fn(|i, _| mean(CONTROL_NAMES[i]));
    linearize_f16(&F16::new(0.30).unwrap(), &x, &run.trim.controls.with_vector(&u)).unwrap()
}

/// One chirp flown three ways (see [`chirp_misses_split_into_design_drift_and_random_error`]).
struct ThreeWays {
    /// The flown estimate (sensed rate), its coherence and random error per grid point.
    flown: aeroident_signals::spectral::PairResponse,
    /// Deviations from the trim's response: the linear truth's and the calm-air flight's.
    truth: Vec<[f64; 4]>,
    calm_d: Vec<[f64; 4]>,
    calm: SimRun,
    lin: Linearization<N_STATES, 4>,
    sweep: aeroident_signals::Sweep,
    dt: f64,
}

/// `name`'s chirp (surface `surface`, rate `rate`, state `state`, control column `control`)
/// flown as it is, flown in calm air, and through the linearisation driven by the flown
/// surface history.
fn three_ways(name: &str, surface: &str, rate: &str, state: usize, control: usize) -> ThreeWays {
    let path = root().join(format!("scenarios/sim/{name}.toml"));
    let sc = load_scenario(&path).unwrap();
    let flown = run(&sc, path.parent().unwrap()).unwrap();
    let mut calm_sc = sc.clone();
    calm_sc.wind.clear();
    let calm = run(&calm_sc, path.parent().unwrap()).unwrap();
    let lin =
        linearize_f16(&F16::new(0.30).unwrap(), &flown.trim.state, &flown.trim.controls).unwrap();
    let h = response(&lin, control, state);
    let dt = sc.run.dt_s;
    let u_trim = flown.trim.controls.to_vector()[control];
    let (u, u_calm) = (flown.table.column(surface).unwrap(), calm.table.column(surface).unwrap());
    let truth = deviations(u, &linear_truth(&lin, u, u_trim, control, state, dt), dt, &h);
    let calm_d = deviations(u_calm, calm.table.column(rate).unwrap(), dt, &h);
    let st = vec![vec![u.to_vec(), flown.table.column(&format!("meas_{rate}")).unwrap().to_vec()]];
    let r =
        frequency_responses(&st, &["u".into()], &["y".into()], dt, &Default::default()).unwrap();
    let Input::Sweep(sweep) = sc.input[0].input.build_in(&root()).unwrap() else {
        panic!("{name}'s input is a sweep")
    };
    ThreeWays { flown: r.pairs[0].clone(), truth, calm_d, calm, lin, sweep, dt }
}

/// `C (jωI − A)⁻¹ B` of `lin`, state `state` to control column `control`, as a function of ω.
fn response(
    lin: &Linearization<N_STATES, 4>,
    control: usize,
    state: usize,
) -> impl Fn(f64) -> Complex64 + use<> {
    let a = DMatrix::from_fn(N_STATES, N_STATES, |i, j| Complex64::new(lin.a[(i, j)], 0.0));
    let b: Vec<f64> = (0..N_STATES).map(|i| lin.b[(i, control)]).collect();
    move |w| analytic(&a, &b, state, w)
}

/// Why the flown estimate at grid point `k` (ω = `w`) is beyond 1 dB / 5°, each part checked
/// against its stated cause; the parts whose cause does not hold. The estimate is the trim's
/// response × the linear truth's deviation (design) × the calm-air flight's over the linear
/// truth (drift) × the flown over the calm-air estimate (random):
/// - design, where the linear truth misses: the response changes beyond 1 dB / 5° within the
///   longest window's main lobe ([`resolution_cause`]);
/// - drift: the calm-air flight over the linear truth is, within 1 dB / 5°, what the
///   linearisation at the condition the flight holds when the sweep passes ω (averaged over
///   two periods of ω either side) gives over the trim's;
/// - random: the flown estimate within 4ε of the calm-air one (the complex error of an
///   estimate is Rayleigh-distributed with scale ε: beyond 4ε has odds e⁻⁸ ≈ 3·10⁻⁴ per point).
fn unexplained_parts(f: &ThreeWays, k: usize, w: f64, control: usize, state: usize) -> Vec<String> {
    let h = response(&f.lin, control, state);
    let (truth, calm) = (&f.truth[k], &f.calm_d[k]);
    let mut missing = Vec::new();
    let t = f.calm.table.column("t_s").unwrap();
    if beyond(truth) && !resolution_cause(&h, w, 0.5 * t[t.len() - 1]) {
        missing.push(format!("the linear truth misses ({truth:.2?}) where the response is flat"));
    }
    let k_w = t.iter().position(|&ts| f.sweep.instantaneous_frequency_rad_s(ts) >= w).unwrap();
    let half = (2.0 * 2.0 * std::f64::consts::PI / w / f.dt) as usize;
    let local = response(&local_linearisation(&f.calm, k_w, half), control, state)(w) / h(w);
    let drift = ratio_of(calm) / ratio_of(truth);
    let left = deviation_of(drift / local, w);
    if beyond(&left) {
        let (d, l) = (deviation_of(drift, w), deviation_of(local, w));
        missing.push(format!("drift {d:.2?}, the local linearisation {l:.2?}"));
    }
    let p = &f.flown;
    let z =
        (Complex64::new(p.re[k], p.im[k]) / h(w) / ratio_of(calm) - 1.0).norm() / p.random_error[k];
    if z > 4.0 {
        missing.push(format!("the flown estimate {z:.1} ε from the calm-air one"));
    }
    missing
}

/// The misses of [`chirp_responses_match_the_linearisation_and_the_fitted_modes_its_eigenvalues`]
/// split by cause, one flight per axis three ways: the linearisation driven by the flight's own
/// surface history (what the estimator and the chirp's design miss on the exact linear system),
/// the same chirp flown in calm air read on the true channels (adds what the nonlinear flight's
/// drift from trim does), and the scenario as it is (adds turbulence and sensor noise, judged
/// against the point's random error ε). Prints the numbers of docs/frequency-response.md
/// (`-- --nocapture`). Being shared by another run explains nothing: every coherent miss is
/// split into those three parts and each part is checked against its stated cause
/// ([`unexplained_parts`]): the linear truth misses only where the response changes beyond
/// 1 dB / 5° within the longest window's resolution, the calm-air flight departs from the
/// linear truth as the linearisation at the condition it holds at that frequency says, and the
/// flown estimate lies within 4ε of the calm-air one.
#[test]
fn chirp_misses_split_into_design_drift_and_random_error() {
    let axes = [
        ("chirp_elevator", "elevator_rad", "q_rad_s", Q, 1),
        ("chirp_aileron", "aileron_rad", "p_rad_s", P, 2),
        ("chirp_rudder", "rudder_rad", "r_rad_s", R, 3),
    ];
    let mut unexplained = Vec::new();
    for (name, surface, rate, state, control) in axes {
        let f = three_ways(name, surface, rate, state, control);
        let h = response(&f.lin, control, state);
        let p = &f.flown;
        let (mut n, mut design, mut drift, mut random) = (0, 0, 0, 0);
        for k in 0..p.frequency_hz.len() {
            let w = 2.0 * std::f64::consts::PI * p.frequency_hz[k];
            if !(0.1..=10.0).contains(&w) || p.coherence[k] < 0.8 {
                continue;
            }
            let ratio = Complex64::new(p.re[k], p.im[k]) / h(w);
            let d = [w, p.coherence[k], 20.0 * ratio.norm().log10(), ratio.arg().to_degrees()];
            if !beyond(&d) {
                continue;
            }
            n += 1;
            let (c, truth) = (&f.calm_d[k], &f.truth[k]);
            eprintln!(
                "  {name} {w:.3} rad/s γ² {:.3}: flown {:+.2} dB {:+.1}°, calm {:+.2} dB {:+.1}°, linear truth {:+.2} dB {:+.1}° (ε {:.3})",
                d[1], d[2], d[3], c[2], c[3], truth[2], truth[3], p.random_error[k]
            );
            if beyond(truth) {
                design += 1;
            } else if beyond(c) {
                drift += 1;
            } else {
                random += 1;
            }
            let missing = unexplained_parts(&f, k, w, control, state);
            if !missing.is_empty() {
                unexplained.push(format!("{name} {w:.3} rad/s: {missing:?}"));
            }
        }
        eprintln!(
            "{name}: {n} coherent points beyond 1 dB / 5°: {design} the linear truth misses too, {drift} the calm-air flight misses (not the linear truth), {random} neither"
        );
    }
    assert!(unexplained.is_empty(), "misses whose stated cause does not hold: {unexplained:#?}");
}
