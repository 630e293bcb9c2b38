//! The synthetic F-16-like test aircraft: mass, geometry and inertia of the magnitudes of the
//! JSBSim F-16 sample record (SI), a level-flight condition, a stable set of six-axis
//! derivatives, its level-trim biases and the inputs the tests fly it with.
//!
//! Test support only: compiled into the library under `cfg(test)` for the unit tests (EKF,
//! output error, experiment design, flight model), and included with `#[path]` by the update
//! bench and the `design_plan` example, which cannot reach a `cfg(test)` module. It therefore
//! names the crate `aeroident_estimators` (the library aliases itself so under `cfg(test)`).
#![allow(dead_code)]

use aeroident_estimators::flight_model::{G0_MPS2, N_STATES, Output, state};
use aeroident_estimators::sample::{AirDataSample, AircraftConstants};
use aeroident_estimators::vocabulary::{Coefficient as C, ModelStructure, Param, Term as T};
use std::vec::Vec;

/// Trim true airspeed, m/s.
pub const V0: f64 = 180.0;
/// Trim angle of attack (and pitch angle, level flight), rad.
pub const ALPHA0: f64 = 0.06;
/// Air density, kg/m³.
pub const RHO: f64 = 0.75;
/// Thrust, N, along body x through the CG.
pub const THRUST: f64 = 18_000.0;

/// Mass 9300 kg, S 27.87 m², c̄ 3.45 m, b 9.14 m, inertia (kg·m², Stevens & Lewis `Jxz` sign),
/// thrust on body x through the CG, `v0_mps = V0`.
pub fn constants() -> AircraftConstants {
    AircraftConstants {
        mass_kg: 9300.0,
        S_m2: 27.87,
        cbar_m: Some(3.45),
        b_m: Some(9.14),
        Ixx_kgm2: Some(16_660.0),
        Iyy_kgm2: Some(77_430.0),
        Izz_kgm2: Some(90_940.0),
        Ixz_kgm2: Some(1_437.0),
        thrust_arm_m: 0.0,
        thrust_incidence_rad: 0.0,
        v0_mps: Some(V0),
    }
}

/// The true derivatives (per rad, rates non-dimensional), a stable airframe; every other
/// derivative of the six-axis structure, and every bias, is 0 before trimming.
pub const DERIVATIVES: [(C, T, f64); 21] = [
    (C::CL, T::Alpha, 4.2),
    (C::CL, T::Q, 6.0),
    (C::CL, T::De, 0.45),
    (C::CD, T::Alpha, 0.35),
    (C::CD, T::De, 0.06),
    (C::Cm, T::Alpha, -0.7),
    (C::Cm, T::Q, -14.0),
    (C::Cm, T::De, -0.9),
    (C::CY, T::Beta, -0.9),
    (C::CY, T::R, 0.5),
    (C::CY, T::Dr, 0.15),
    (C::Cl, T::Beta, -0.09),
    (C::Cl, T::P, -0.45),
    (C::Cl, T::R, 0.1),
    (C::Cl, T::Da, -0.07),
    (C::Cl, T::Dr, 0.015),
    (C::Cn, T::Beta, 0.13),
    (C::Cn, T::P, -0.02),
    (C::Cn, T::R, -0.35),
    (C::Cn, T::Da, -0.01),
    (C::Cn, T::Dr, -0.07),
];

/// θ of `st` (length `st.n_params()`): the [`DERIVATIVES`] it has, 0 elsewhere (biases 0).
pub fn derivatives(st: &ModelStructure) -> Vec<f64> {
    let mut th = std::vec![0.0; st.n_params()];
    for (c, t, v) in DERIVATIVES {
        if let Some(i) = st.index_of(Param::new(c, t)) {
            th[i] = v;
        }
    }
    th
}

/// Sets the `CL`, `CD` and `Cm` biases of `th` (those `st` has) for level trim at
/// (`V0`, `ALPHA0`), δ = 0, with `k`'s mass and area: in wind axes `CL = (m g − T sin α0)/(q̄S)`,
/// `CD = T cos α0/(q̄S)`, `Cm = 0`, so `CL_0 = CL − CL_alpha α0`, `CD_0 = CD − CD_alpha α0`,
/// `Cm_0 = −Cm_alpha α0` (a missing `_alpha` term counts 0).
pub fn set_level_trim_biases(st: &ModelStructure, th: &mut [f64], k: &AircraftConstants) {
    let qs = 0.5 * RHO * V0 * V0 * k.S_m2;
    let get = |th: &[f64], c, t| st.index_of(Param::new(c, t)).map_or(0.0, |i| th[i]);
    let cl = (k.mass_kg * G0_MPS2 - THRUST * ALPHA0.sin()) / qs;
    let cd = THRUST * ALPHA0.cos() / qs;
    let biases = [
        (C::CL, cl - get(th, C::CL, T::Alpha) * ALPHA0),
        (C::CD, cd - get(th, C::CD, T::Alpha) * ALPHA0),
        (C::Cm, -get(th, C::Cm, T::Alpha) * ALPHA0),
    ];
    for (c, v) in biases {
        if let Some(i) = st.index_of(Param::new(c, T::Bias)) {
            th[i] = v;
        }
    }
}

/// The true θ of `st`: [`derivatives`] with the biases of [`set_level_trim_biases`] (mass and
/// area of [`constants`]).
pub fn trimmed_truth(st: &ModelStructure) -> Vec<f64> {
    let mut th = derivatives(st);
    set_level_trim_biases(st, &mut th, &constants());
    th
}

/// A doublet at time `t` (s): `amp` on `[t0, t0 + width)`, `−amp` on `[t0 + width, t0 + 2 width)`,
/// 0 elsewhere.
pub fn doublet(t: f64, t0: f64, width: f64, amp: f64) -> f64 {
    if t >= t0 && t < t0 + width {
        amp
    } else if t >= t0 + width && t < t0 + 2.0 * width {
        -amp
    } else {
        0.0
    }
}

/// A 3-2-1-1 of unit `unit_s` and amplitude `amp` starting at each of `starts_s` (summed),
/// sampled every `dt_s` from 0 to `duration_s` inclusive.
pub fn three_two_one_one(
    starts_s: &[f64],
    unit_s: f64,
    amp: f64,
    duration_s: f64,
    dt_s: f64,
) -> Vec<f64> {
    let n = (duration_s / dt_s).round() as usize + 1;
    (0..n)
        .map(|i| {
            starts_s.iter().fold(0.0, |sum, t0| {
                sum + match (i as f64 * dt_s - t0) / unit_s {
                    u if (0.0..3.0).contains(&u) => amp,
                    u if (3.0..5.0).contains(&u) => -amp,
                    u if (5.0..6.0).contains(&u) => amp,
                    u if (6.0..7.0).contains(&u) => -amp,
                    _ => 0.0,
                }
            })
        })
        .collect()
}

/// A sample of the test aircraft at `t_s` in the full flight-model state `x` (`V, α, β, p, q,
/// r, φ, θ`, SI) with surfaces `(δe, δa, δr)` rad, `THRUST`, `RHO` (q̄ from them) and the
/// constants `k`; no specific forces or angular accelerations (the caller adds those it has).
pub fn sample(
    t_s: f64,
    x: &[f64; N_STATES],
    (de, da, dr): (f64, f64, f64),
    k: AircraftConstants,
) -> AirDataSample {
    AirDataSample {
        t_s,
        vt_mps: x[state::V],
        alpha_rad: x[state::ALPHA],
        qbar_pa: 0.5 * RHO * x[state::V] * x[state::V],
        beta_rad: Some(x[state::BETA]),
        p_rad_s: Some(x[state::P]),
        q_rad_s: Some(x[state::Q]),
        r_rad_s: Some(x[state::R]),
        phi_rad: Some(x[state::PHI]),
        theta_rad: Some(x[state::THETA]),
        de_rad: Some(de),
        da_rad: Some(da),
        dr_rad: Some(dr),
        thrust_n: Some(THRUST),
        rho_kgpm3: Some(RHO),
        constants: k,
        ..Default::default()
    }
}

/// Sets the channel of output `o` in `s` to `v` ([`Output::set_measured`]).
pub fn set_output(s: &mut AirDataSample, o: Output, v: f64) {
    o.set_measured(s, v);
}

/// `n` samples (interval `dt_s`) of the six-axis flight model flown from level trim with the
/// generic priors as its aerodynamics (lateral biases zero), elevator, aileron and rudder
/// doublets at 1, 6 and 12 s of every `period_s`, every channel present (specific forces and
/// angular accelerations from the model; four Euler substeps of dt/4): the stream the update
/// bench and the update-time example replay through every estimator.
#[allow(dead_code)] // used by the bench and the example, not by every unit test
pub fn six_axis_stream(n: usize, dt_s: f64, period_s: f64) -> Vec<AirDataSample> {
    use aeroident_estimators::flight_model::{FlightModel, ModelInputs};
    use aeroident_estimators::prior::Priors;
    let st = ModelStructure::six_axis();
    let model = FlightModel::new(st).unwrap();
    let pri = Priors::generic(&st);
    let mut th: Vec<f64> = (0..st.n_params()).map(|i| pri.prior[i].value).collect();
    let k = AircraftConstants { v0_mps: None, ..constants() };
    set_level_trim_biases(&st, &mut th, &k);
    let i = |c, t| st.index_of(Param::new(c, t)).unwrap();
    for c in [C::CY, C::Cl, C::Cn] {
        th[i(c, T::Bias)] = 0.0;
    }
    let db = |t: f64, t0: f64, a: f64| doublet(t, t0, 0.5, a);
    let mut x = [V0, ALPHA0, 0.0, 0.0, 0.0, 0.0, 0.0, ALPHA0];
    let z8 = [0.0; 8];
    let mut out = Vec::with_capacity(n);
    for step in 0..n {
        let t = step as f64 * dt_s;
        let tc = t % period_s;
        let surfaces = (db(tc, 1.0, 0.03), db(tc, 6.0, -0.04), db(tc, 12.0, 0.05));
        let mut s = sample(t, &x, surfaces, k);
        let u: ModelInputs = model.inputs(&s).unwrap();
        let d = model.eval(&th, &u, &x, &z8, &z8, None).unwrap();
        s.ax_mps2 = Some(d.accel[0]);
        s.ay_mps2 = Some(d.accel[1]);
        s.az_mps2 = Some(d.accel[2]);
        s.pdot_rad_s2 = Some(d.xdot[3]);
        s.qdot_rad_s2 = Some(d.xdot[4]);
        s.rdot_rad_s2 = Some(d.xdot[5]);
        out.push(s);
        for _ in 0..4 {
            let f = model.eval(&th, &u, &x, &z8, &z8, None).unwrap().xdot;
            for j in 0..8 {
                x[j] += 0.25 * dt_s * f[j];
            }
        }
    }
    out
}
