//! Trim validation against the published SLJ trim tables.
//!
//! Reference values: Stevens, Lewis & Johnson, *Aircraft Control and Simulation*, 3rd ed. (2015),
//! Table 3.6-2 (p. 193, steady level flight at sea level, xcg = 0.35) and Table 3.6-3 (p. 195,
//! 502 ft/s at sea level: xcg 0.35, 0.30, 0.38 and a 0.3 rad/s coordinated turn at xcg 0.30), as
//! transcribed in AlexS12/FlightMechanicsSimulator.jl test/f16/trimmer.jl
//! (commit 0559deb0f65bbee80d2782f593fc5ec794528420), which cites those pages. Tolerances are the
//! printed precision (half a unit of the last printed digit, widened where noted).

use aeroident_models::f16::{ALPHA, BETA, F16, P, PHI, Q, R, THETA};
use aeroident_models::trim::{TrimCondition, TrimManeuver, trim};

/// (vt_fps, throttle, alpha_deg, elevator_deg) of SLJ Table 3.6-2.
const TABLE_3_6_2: [(f64, f64, f64, f64); 16] = [
    (130.0, 0.816, 45.6, 20.1),
    (140.0, 0.736, 40.3, -1.36),
    (150.0, 0.619, 34.6, 0.173),
    (170.0, 0.464, 27.2, 0.621),
    (200.0, 0.287, 19.7, 0.723),
    (260.0, 0.148, 11.6, -0.09),
    (300.0, 0.122, 8.49, -0.591),
    (350.0, 0.107, 5.87, -0.539),
    (400.0, 0.108, 4.16, -0.591),
    (440.0, 0.113, 3.19, -0.671),
    (500.0, 0.137, 2.14, -0.756),
    (540.0, 0.160, 1.63, -0.798),
    (600.0, 0.200, 1.04, -0.846),
    (640.0, 0.230, 0.742, -0.871),
    (700.0, 0.282, 0.382, -0.900),
    (800.0, 0.378, -0.045, -0.943),
];

/// Relative digits: tolerance of a value printed with 3 significant digits.
fn tol3(v: f64) -> f64 {
    // half a unit in the 3rd significant digit, plus a floor for values printed like -0.09.
    let mag = 10f64.powf(v.abs().max(1e-3).log10().floor() - 2.0);
    0.5 * mag + 1e-3
}

#[test]
fn val_slj_table_3_6_2_level_trims() {
    let f16 = F16::new(0.35).unwrap();
    for &(vt, thtl, alpha_deg, de_deg) in &TABLE_3_6_2 {
        let t = trim(&f16, &TrimCondition::level(0.0, vt)).unwrap();
        assert!(t.max_abs_residual() < 1e-8, "vt {vt}: residual {:?}", t.residual);
        let a = t.state[ALPHA].to_degrees();
        let e = t.controls.elevator_rad.to_degrees();
        println!(
            "vt {vt}: thtl {:.4} alpha {:.4} de {:.4} (published {thtl} {alpha_deg} {de_deg}) cost {:e}",
            t.controls.throttle, a, e, t.cost
        );
        assert!(
            (t.controls.throttle - thtl).abs() <= tol3(thtl),
            "vt {vt}: throttle {} vs {thtl}",
            t.controls.throttle
        );
        assert!((a - alpha_deg).abs() <= tol3(alpha_deg), "vt {vt}: alpha {a} vs {alpha_deg}");
        assert!((e - de_deg).abs() <= tol3(de_deg), "vt {vt}: elevator {e} vs {de_deg}");
    }
}

#[test]
fn val_slj_table_3_6_3_trims_at_502_fps() {
    // (xcg, throttle, elevator_deg, alpha_rad) printed in Table 3.6-3.
    for &(xcg, thtl, de, alpha) in &[
        (0.35, 0.1385, -0.7588, 0.03691),
        (0.30, 0.1485, -1.931, 0.03936),
        (0.38, 0.1325, -0.05590, 0.03544),
    ] {
        let t = trim(&F16::new(xcg).unwrap(), &TrimCondition::level(0.0, 502.0)).unwrap();
        assert!(t.max_abs_residual() < 1e-8);
        println!(
            "xcg {xcg}: thtl {:.5} de {:.5} alpha {:.6}",
            t.controls.throttle,
            t.controls.elevator_rad.to_degrees(),
            t.state[ALPHA]
        );
        assert!(
            (t.controls.throttle - thtl).abs() < 6e-5,
            "xcg {xcg} throttle {}",
            t.controls.throttle
        );
        assert!(
            (t.controls.elevator_rad.to_degrees() - de).abs() < 6e-4,
            "xcg {xcg} de {}",
            t.controls.elevator_rad.to_degrees()
        );
        assert!((t.state[ALPHA] - alpha).abs() < 6e-6, "xcg {xcg} alpha {}", t.state[ALPHA]);
        assert!((t.state[THETA] - alpha).abs() < 6e-6);
        assert!(t.state[BETA].abs() < 1e-7);
    }
}

#[test]
fn val_slj_table_3_6_3_coordinated_turn() {
    let cond = TrimCondition {
        alt_ft: 0.0,
        vt_fps: 502.0,
        gamma_rad: 0.0,
        maneuver: TrimManeuver::CoordinatedTurn { turn_rate_rad_s: 0.3 },
    };
    let t = trim(&F16::new(0.30).unwrap(), &cond).unwrap();
    assert!(t.max_abs_residual() < 1e-8, "{:?}", t.residual);
    let s = &t.state;
    let c = &t.controls;
    println!("turn: {s:?} {c:?}");
    for (name, got, want, tol) in [
        ("alpha", s[ALPHA], 0.2485, 5e-4),
        ("beta", s[BETA], 4.8e-4, 5e-5),
        ("phi", s[PHI], 1.367, 5e-4),
        ("theta", s[THETA], 0.05185, 5e-5),
        ("p", s[P], -0.01555, 5e-6),
        ("q", s[Q], 0.2934, 5e-5),
        ("r", s[R], 0.06071, 5e-6),
        ("throttle", c.throttle, 0.8499, 5e-4),
        ("elevator_deg", c.elevator_rad.to_degrees(), -6.256, 5e-4),
        ("aileron_deg", c.aileron_rad.to_degrees(), 0.09891, 5e-5),
        ("rudder_deg", c.rudder_rad.to_degrees(), -0.4218, 5e-4),
    ] {
        assert!((got - want).abs() <= tol, "{name}: {got} vs published {want}");
    }
}

#[test]
fn analytic_pull_up_trim_balances_and_has_more_load() {
    // A steady pull-up at q = 0.1 rad/s needs nz = 1 + q·V/g at the bottom (γ = 0, θ = α):
    // the normal load factor follows from the centripetal acceleration (SLJ §3.6 pull-up).
    let f16 = F16::new(0.30).unwrap();
    let q = 0.1;
    let cond = TrimCondition {
        alt_ft: 10_000.0,
        vt_fps: 600.0,
        gamma_rad: 0.0,
        maneuver: TrimManeuver::PullUp { pitch_rate_rad_s: q },
    };
    let t = trim(&f16, &cond).unwrap();
    assert!(t.max_abs_residual() < 1e-8);
    let o = f16.outputs(0.0, &t.state, &t.controls).unwrap();
    // Load factor along the stability z axis: nz·cosα + nx·sinα (thrust included) = 1 + qV/g at γ = 0.
    let a = t.state[ALPHA];
    let n_normal = o.nz_g * a.cos() + o.nx_g * a.sin();
    let want = 1.0 + q * 600.0 / 32.17;
    assert!((n_normal - want).abs() < 1e-6, "{n_normal} vs {want}");
}
