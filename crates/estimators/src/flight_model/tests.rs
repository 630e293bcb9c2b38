use super::*;
use crate::prior::Priors;
use crate::sample::AircraftConstants;
use crate::vocabulary::{Coefficient as C, Param, Term as T};

/// The F-16-like test aircraft ([`crate::test_aircraft`]) with an offset, inclined thrust line
/// and another reference airspeed, so that every term of the model is exercised.
fn constants() -> AircraftConstants {
    AircraftConstants {
        thrust_arm_m: 0.12,
        thrust_incidence_rad: 0.02,
        v0_mps: Some(200.0),
        ..crate::test_aircraft::constants()
    }
}

/// A sample at a non-trivial, non-symmetric point: every channel present.
fn sample() -> AirDataSample {
    AirDataSample {
        t_s: 1.0,
        vt_mps: 190.0,
        alpha_rad: 0.11,
        qbar_pa: 0.5 * 0.65 * 190.0 * 190.0,
        beta_rad: Some(0.04),
        p_rad_s: Some(0.3),
        q_rad_s: Some(-0.08),
        r_rad_s: Some(0.12),
        pdot_rad_s2: Some(0.0),
        qdot_rad_s2: Some(0.0),
        rdot_rad_s2: Some(0.0),
        alphadot_rad_s: Some(0.05),
        phi_rad: Some(0.35),
        theta_rad: Some(0.16),
        ax_mps2: Some(0.8),
        ay_mps2: Some(0.3),
        az_mps2: Some(-10.5),
        de_rad: Some(-0.03),
        da_rad: Some(0.02),
        dr_rad: Some(-0.015),
        thrust_n: Some(30_000.0),
        thrust_moment_nm: None,
        rho_kgpm3: Some(0.65),
        constants: constants(),
        ..Default::default()
    }
}

/// Parameter values: the generic priors, each perturbed so no value is special.
fn theta_for(st: &ModelStructure) -> [f64; MAX_PARAMS] {
    let pri = Priors::generic(st);
    let mut th = [0.0; MAX_PARAMS];
    for (i, p) in st.params().enumerate() {
        th[i] = pri.prior[i].value * 1.1 + 0.01 * (i as f64 + 1.0);
        if p.term == T::Alphadot {
            th[i] = if p.coefficient == C::Cm { -6.0 } else { 1.7 };
        }
    }
    th
}

fn with_alphadot(st: ModelStructure) -> ModelStructure {
    let mut st = st;
    for c in [C::CL, C::CZ, C::Cm, C::Cl] {
        if st.has(c) {
            st.insert(Param::new(c, T::Alphadot));
        }
    }
    st
}

fn rich_lon() -> ModelStructure {
    ModelStructure::longitudinal()
        .with(C::CD, &[T::Alpha2, T::V])
        .with(C::CL, &[T::AlphaDe])
        .with(C::Cm, &[T::V, T::Alpha2, T::Q0])
}

/// α splines with one knot below the sample's α (0.11 rad, active) and one above (inactive),
/// and the Mach terms.
fn spline_mach_lon() -> ModelStructure {
    ModelStructure::longitudinal()
        .with(C::CL, &[T::AlphaK1, T::AlphaK2, T::Mach])
        .with(C::CD, &[T::Mach2, T::AlphaK1])
        .with(C::Cm, &[T::AlphaK2, T::AlphaK1, T::Mach])
        .with_knots(crate::vocabulary::AlphaKnots::new(&[0.05, 0.3]).unwrap())
}

fn body_lon() -> ModelStructure {
    const TT: [T; 4] = [T::Bias, T::Alpha, T::Q, T::De];
    ModelStructure::empty().with(C::CX, &TT).with(C::CZ, &TT).with(C::Cm, &TT)
}

/// Checks the dual partials of f and h against central differences of the f64 model.
fn check_partials(st: ModelStructure) {
    let model = FlightModel::new(st).unwrap();
    let s = sample();
    let u = model.inputs(&s).unwrap();
    let theta = theta_for(&st);
    let np = st.n_params();
    let states = model.state_set().states();
    let nx = states.len();
    let mut active = [0.0; N_STATES];
    for (k, &i) in states.iter().enumerate() {
        active[k] = u.x_meas[i];
    }
    let mut lin = Linearisation::default();
    model.linearise(&theta[..np], &u, &active[..nx], &mut lin).unwrap();
    let z = [0.0; 8];
    let fh = |th: &[f64], a: &[f64]| {
        let x = model.full_state(a, &u);
        let d = model.eval(th, &u, &x, &z, &z, None).unwrap();
        let mut out = [0.0; N_STATES + N_OUTPUTS];
        for (k, &i) in states.iter().enumerate() {
            out[k] = d.xdot[i];
        }
        for o in model.state_set().outputs() {
            out[N_STATES + o.index()] = d.output(*o, &x);
        }
        out
    };
    let base = fh(&theta[..np], &active[..nx]);
    // Values agree with the plain evaluation.
    for (k, b) in base.iter().enumerate().take(nx) {
        assert!((lin.f[k] - b).abs() <= 1e-13 * (1.0 + b.abs()), "f{k}");
    }
    let close = |a: f64, b: f64| (a - b).abs() <= 2e-6 * (1.0 + a.abs().max(b.abs()));
    let outs = model.state_set().outputs();
    for col in 0..nx + np {
        let (mut ap, mut am) = (active, active);
        let (mut tp, mut tm) = (theta, theta);
        let h;
        if col < nx {
            h = 1e-6 * active[col].abs().max(1.0);
            ap[col] += h;
            am[col] -= h;
        } else {
            h = 1e-6 * theta[col - nx].abs().max(1.0);
            tp[col - nx] += h;
            tm[col - nx] -= h;
        }
        let fp = fh(&tp[..np], &ap[..nx]);
        let fm = fh(&tm[..np], &am[..nx]);
        for r in 0..nx {
            let fd = (fp[r] - fm[r]) / (2.0 * h);
            let an = if col < nx { lin.dfdx[r][col] } else { lin.dfdtheta[r][col - nx] };
            assert!(close(an, fd), "{st:?}: df{r}/dz{col}: dual {an} vs central {fd}");
        }
        for o in outs {
            let r = N_STATES + o.index();
            let fd = (fp[r] - fm[r]) / (2.0 * h);
            let k = o.index();
            let an = if col < nx { lin.dydx[k][col] } else { lin.dydtheta[k][col - nx] };
            assert!(close(an, fd), "{}: dh/dz{col}: dual {an} vs central {fd}", o.name());
        }
    }
}

#[test]
fn dual_partials_match_central_differences_longitudinal() {
    check_partials(ModelStructure::longitudinal());
    check_partials(rich_lon());
    check_partials(body_lon());
    check_partials(spline_mach_lon());
    check_partials(with_alphadot(spline_mach_lon()));
}

#[test]
fn dual_partials_match_central_differences_longitudinal_with_alphadot() {
    check_partials(with_alphadot(ModelStructure::longitudinal()));
    check_partials(with_alphadot(body_lon()));
}

#[test]
fn dual_partials_match_central_differences_lateral() {
    check_partials(ModelStructure::lateral());
    check_partials(ModelStructure::lateral().with(C::Cn, &[T::AlphaBeta]));
    // Lateral set with an α̇ term: α̇ is the sample's (not implicit).
    check_partials(with_alphadot(ModelStructure::lateral()));
}

#[test]
fn dual_partials_match_central_differences_coupled() {
    check_partials(ModelStructure::six_axis());
    check_partials(with_alphadot(ModelStructure::six_axis()));
    let model = FlightModel::new(with_alphadot(ModelStructure::six_axis())).unwrap();
    assert!(model.n_directions() > 16, "exercises the widest dual");
}

/// Level unaccelerated flight: lift and drag computed by hand in wind axes from weight,
/// thrust and α (L + T sin(α+σT) = W, D = T cos(α+σT), M_aero = −M_T); with those coefficients
/// every derivative is zero.
#[test]
fn analytic_steady_level_trim_has_zero_derivatives() {
    let k = constants();
    let (v, alpha, rho, thrust, de) = (150.0, 0.05, 0.9, 20_000.0, -0.02);
    let qs = 0.5 * rho * v * v * k.S_m2;
    let w = k.mass_kg * G0_MPS2;
    let cl = (w - thrust * (alpha + k.thrust_incidence_rad).sin()) / qs;
    let cd = thrust * (alpha + k.thrust_incidence_rad).cos() / qs;
    let cm = -k.thrust_arm_m * thrust / (qs * k.cbar_m.unwrap());
    for st in
        [with_alphadot(ModelStructure::longitudinal()), with_alphadot(ModelStructure::six_axis())]
    {
        let model = FlightModel::new(st).unwrap();
        let mut theta = theta_for(&st);
        // Bias terms absorb the trim values: C_0 = C_trim − C_alpha α − C_de δe (q = 0).
        let i = |c, t| st.index_of(Param::new(c, t)).unwrap();
        theta[i(C::CL, T::Bias)] =
            cl - theta[i(C::CL, T::Alpha)] * alpha - theta[i(C::CL, T::De)] * de;
        theta[i(C::CD, T::Bias)] =
            cd - theta[i(C::CD, T::Alpha)] * alpha - theta[i(C::CD, T::De)] * de;
        theta[i(C::Cm, T::Bias)] =
            cm - theta[i(C::Cm, T::Alpha)] * alpha - theta[i(C::Cm, T::De)] * de;
        for c in [C::CY, C::Cl, C::Cn] {
            if st.has(c) {
                theta[i(c, T::Bias)] = 0.0;
            }
        }
        let s = AirDataSample {
            t_s: 0.0,
            vt_mps: v,
            alpha_rad: alpha,
            qbar_pa: 0.5 * rho * v * v,
            beta_rad: Some(0.0),
            p_rad_s: Some(0.0),
            q_rad_s: Some(0.0),
            r_rad_s: Some(0.0),
            phi_rad: Some(0.0),
            theta_rad: Some(alpha),
            de_rad: Some(de),
            da_rad: Some(0.0),
            dr_rad: Some(0.0),
            thrust_n: Some(thrust),
            rho_kgpm3: Some(rho),
            constants: k,
            ..Default::default()
        };
        let u = model.inputs(&s).unwrap();
        let states = model.state_set().states();
        let active: Vec<f64> = states.iter().map(|&j| u.x_meas[j]).collect();
        let f = model.derivatives(&theta[..st.n_params()], &u, &active).unwrap();
        for (r, &j) in states.iter().enumerate() {
            assert!(f[r].abs() < 1e-12, "{}: d/dt {} = {}", st.n_params(), STATE_NAMES[j], f[r]);
        }
    }
}

/// The implicit α̇ is solved exactly: a model without α̇ terms whose biases are shifted by
/// `C_k_alphadot · α̇* c̄/2V` (α̇* the solved value) gives the same α̇ and q̇.
#[test]
fn analytic_implicit_alphadot_is_the_fixed_point() {
    let st = with_alphadot(ModelStructure::longitudinal());
    let plain = ModelStructure::longitudinal();
    let model = FlightModel::new(st).unwrap();
    let model0 = FlightModel::new(plain).unwrap();
    let s = sample();
    let u = model.inputs(&s).unwrap();
    let th = theta_for(&st);
    let x = model.full_state(&[u.x_meas[0], u.x_meas[1], u.x_meas[7], u.x_meas[4]], &u);
    let z = [0.0; 8];
    let d = model.eval(&th[..st.n_params()], &u, &x, &z, &z, None).unwrap();
    assert!(d.alphadot.abs() > 1e-3, "non-trivial α̇");
    let chat = 3.45 / (2.0 * s.vt_mps);
    let mut th0 = [0.0; MAX_PARAMS];
    for (j, p) in plain.params().enumerate() {
        th0[j] = th[st.index_of(p).unwrap()];
        if p.term == T::Bias {
            let ad = st.index_of(Param::new(p.coefficient, T::Alphadot));
            th0[j] += ad.map_or(0.0, |a| th[a] * d.alphadot * chat);
        }
    }
    let d0 = model0.eval(&th0[..plain.n_params()], &u, &x, &z, &z, None).unwrap();
    assert!((d0.alphadot - d.alphadot).abs() < 1e-13, "{} vs {}", d0.alphadot, d.alphadot);
    for i in [state::V, state::Q] {
        assert!((d0.xdot[i] - d.xdot[i]).abs() < 1e-12, "state {i}");
    }
    for i in 0..3 {
        assert!((d0.accel[i] - d.accel[i]).abs() < 1e-12, "accel {i}");
    }
}

#[test]
fn state_sets_follow_the_structure_and_partial_ones_are_refused() {
    assert_eq!(StateSet::of(&ModelStructure::longitudinal()), Ok(StateSet::Longitudinal));
    assert_eq!(StateSet::of(&body_lon()), Ok(StateSet::Longitudinal));
    assert_eq!(StateSet::of(&ModelStructure::lateral()), Ok(StateSet::Lateral));
    assert_eq!(StateSet::of(&ModelStructure::six_axis()), Ok(StateSet::Coupled));
    let cm_only = ModelStructure::empty().with(C::Cm, &[T::Alpha, T::Q]);
    assert!(matches!(
        StateSet::of(&cm_only),
        Err(EstimatorError::IncompleteAxis { lateral: false, .. })
    ));
    let cl_cn = ModelStructure::empty().with(C::Cl, &[T::Beta]).with(C::Cn, &[T::Beta]);
    assert!(StateSet::of(&cl_cn).is_err());
    let lon_no_cm = ModelStructure::empty().with(C::CL, &[T::Alpha]).with(C::CD, &[T::Bias]);
    assert!(StateSet::of(&lon_no_cm).is_err());
}

/// An incomplete axis is explained in the model file's coefficient names, whichever
/// estimator simulates it.
#[test]
fn errors_incomplete_axis_names_what_it_needs_and_what_is_declared() {
    let cd_cm = ModelStructure::empty().with(C::CD, &[T::Bias]).with(C::Cm, &[T::Q]);
    let e = StateSet::of(&cd_cm).unwrap_err().to_string();
    assert_eq!(
        e,
        "a longitudinal model needs a force pair (CL and CD, or CX and CZ) and Cm (its states V, alpha, theta, q are integrated); this model declares CD, Cm"
    );
    let cl_cn = ModelStructure::empty().with(C::Cl, &[T::Beta]).with(C::Cn, &[T::Beta]);
    let e = StateSet::of(&cl_cn).unwrap_err().to_string();
    assert!(e.starts_with("a lateral-directional model needs CY, Cl and Cn"), "{e}");
    assert!(e.ends_with("this model declares Cl, Cn"), "{e}");
}

#[test]
fn missing_channels_and_constants_are_named() {
    let lat = FlightModel::new(ModelStructure::lateral()).unwrap();
    let mut s = sample();
    s.theta_rad = None;
    assert!(matches!(
        lat.inputs(&s),
        Err(EstimatorError::NonFiniteInput { field: "theta_rad", .. })
    ));
    let mut s = sample();
    s.da_rad = None;
    assert!(matches!(lat.inputs(&s), Err(EstimatorError::NonFiniteInput { field: "da_rad", .. })));
    let mut s = sample();
    s.constants.b_m = None;
    assert!(matches!(lat.inputs(&s), Err(EstimatorError::InvalidConfig { field: "b_m", .. })));
    let lon = FlightModel::new(ModelStructure::longitudinal()).unwrap();
    // A purely longitudinal record (no lateral channels, no roll/yaw inertia) is accepted.
    let mut s = sample();
    s.beta_rad = None;
    s.p_rad_s = None;
    s.r_rad_s = None;
    s.phi_rad = None;
    s.constants.Ixx_kgm2 = None;
    s.constants.Izz_kgm2 = None;
    s.constants.Ixz_kgm2 = None;
    let u = lon.inputs(&s).unwrap();
    assert_eq!(u.x_meas[state::P], 0.0);
    s.constants.Iyy_kgm2 = None;
    assert!(matches!(lon.inputs(&s), Err(EstimatorError::InvalidConfig { field: "Iyy_kgm2", .. })));
}

/// The flight model's regressors are the vocabulary's: at the measured state, every term of a
/// six-axis structure with all α products (which `Term::value` computes from the sample
/// independently) has the value the model writes into `xi`.
#[test]
fn regressors_of_every_term_match_the_vocabulary() {
    let mut st = ModelStructure::six_axis();
    for c in [C::Cl, C::Cn] {
        st = st.with(c, &[T::AlphaBeta, T::AlphaP, T::AlphaR, T::AlphaDa, T::AlphaDr]);
    }
    st = st.with(C::CY, &[T::AlphaBeta]);
    st = st.with(C::Cm, &[T::AlphaQ, T::Alpha2, T::AlphaDe, T::V, T::Q0]);
    // Every spline (knots on both sides of the sample's α = 0.11 rad) and the Mach terms.
    let splines = [T::AlphaK1, T::AlphaK2, T::AlphaK3, T::AlphaK4, T::Mach, T::Mach2];
    let knots = crate::vocabulary::AlphaKnots::new(&[-0.1, 0.05, 0.1, 0.2]).unwrap();
    let st_splines = ModelStructure::longitudinal()
        .with(C::CL, &splines)
        .with(C::Cm, &splines)
        .with_knots(knots);
    for st in [st, st_splines] {
        let st = st.validated().unwrap();
        let model = FlightModel::new(st).unwrap();
        let s = sample();
        let u = model.inputs(&s).unwrap();
        let z = [0.0; 8];
        let mut xi = [f64::NAN; MAX_PARAMS];
        let th = theta_for(&st);
        model.eval(&th[..st.n_params()], &u, &u.x_meas, &z, &z, Some(&mut xi)).unwrap();
        for (j, p) in st.params().enumerate() {
            let want = st.value(p.term, &s).unwrap();
            assert!(
                (xi[j] - want).abs() < 1e-14 * want.abs().max(1.0),
                "{}: {} vs {want}",
                p.name(),
                xi[j]
            );
        }
    }
}
