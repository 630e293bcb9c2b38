//! Tests of the kinematic unit check on attitudes integrated from known rates.
use super::*;

/// A mapping naming the rate and attitude columns (only the labels are used).
fn mapping() -> Mapping {
    Mapping::from_toml_str(
        "nominal_dt_s = 0.02\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"v\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\np = { column = \"P_col\", unit = \"rad/s\" }\nq = { column = \"Q_col\", unit = \"deg/s\" }\nr = { column = \"R_col\", unit = \"rad/s\" }\nphi = { column = \"phi\", unit = \"rad\" }\ntheta = { column = \"theta\", unit = \"rad\" }\npsi = { column = \"psi\", unit = \"rad\" }\nqbar = { value = 1000.0, unit = \"Pa\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\n",
        "m.toml",
    )
    .unwrap()
}

/// 60 s at 50 Hz of rates `p, q, r` (sums of sinusoids, with gyro biases absent from the
/// attitude) and the attitude integrated from them by the Euler kinematics (RK4, 10 substeps),
/// the rates multiplied by `scale` = (k_p, k_q, k_r) as a wrong unit would; `noise` adds a
/// deterministic ±noise pattern to the attitudes.
fn flight(scale: [f64; 3], noise: f64) -> Vec<AirDataSample> {
    let rates = |t: f64| {
        [
            0.3 * (0.7 * t).sin() + 0.1 * (2.3 * t).sin(),
            0.1 * (0.5 * t).sin() + 0.05 * (1.9 * t).cos(),
            0.08 * (0.3 * t).cos() + 0.04 * (1.3 * t).sin(),
        ]
    };
    let f = |t: f64, x: [f64; 3]| {
        let [p, q, r] = rates(t);
        let (sp, cp) = x[0].sin_cos();
        let (tt, ct) = (x[1].tan(), x[1].cos());
        [p + tt * (q * sp + r * cp), q * cp - r * sp, (q * sp + r * cp) / ct]
    };
    let (dt, sub) = (0.02, 10);
    let mut x = [0.1, 0.05, 0.0];
    let mut out = Vec::new();
    for k in 0..3000 {
        let t = k as f64 * dt;
        let [p, q, r] = rates(t);
        let wiggle = noise * if k % 2 == 0 { 1.0 } else { -1.0 };
        out.push(AirDataSample {
            t_s: t,
            p_rad_s: Some(scale[0] * p + 0.002),
            q_rad_s: Some(scale[1] * q - 0.001),
            r_rad_s: Some(scale[2] * r),
            phi_rad: Some(x[0] + wiggle),
            theta_rad: Some(x[1] - wiggle),
            psi_rad: Some(wrapped(x[2] + wiggle)),
            ..Default::default()
        });
        let h = dt / sub as f64;
        for j in 0..sub {
            let ts = t + j as f64 * h;
            let add = |a: [f64; 3], b: [f64; 3], c: f64| {
                [a[0] + c * b[0], a[1] + c * b[1], a[2] + c * b[2]]
            };
            let k1 = f(ts, x);
            let k2 = f(ts + h / 2.0, add(x, k1, h / 2.0));
            let k3 = f(ts + h / 2.0, add(x, k2, h / 2.0));
            let k4 = f(ts + h, add(x, k3, h));
            x = std::array::from_fn(|i| {
                x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            });
        }
    }
    out
}

fn check(samples: &[AirDataSample]) -> Kinematics {
    let mut k = Kinematics::default();
    samples.iter().for_each(|s| k.push(s));
    k
}

/// Consistent units: every gain is 1 within 1 % (the finite difference against the midpoint's
/// kinematics is second order in dt) and nothing is warned, with attitude noise too.
#[test]
fn analytic_consistent_rates_give_unit_gains_and_no_warning() {
    for noise in [0.0, 0.0002] {
        let k = check(&flight([1.0; 3], noise));
        let (gains, r2) = k.gains().unwrap();
        assert_eq!(gains.len(), 3);
        for (field, g, s) in &gains {
            assert!((g - 1.0).abs() < 0.01, "{field}: {g} ± {s} (noise {noise})");
        }
        assert!(r2 > 0.9, "{r2}");
        assert!(k.warnings(&mapping()).is_empty(), "{:?}", k.warnings(&mapping()));
    }
}

/// q read 57.3 times too small (rad/s data mapped as deg/s), or p 57.3 times too large, or r
/// with its sign reversed: that channel alone is named, with its column and the likely unit.
#[test]
fn analytic_a_rate_in_the_wrong_unit_is_named() {
    let m = mapping();
    let w = check(&flight([1.0, 1.0 / DEG_PER_RAD, 1.0], 0.0002)).warnings(&m);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("channel `q`") && w[0].contains("Q_col"), "{}", w[0]);
    assert!(
        w[0].contains("57.3 times too small") && w[0].contains("rad/s data mapped as deg/s"),
        "{}",
        w[0]
    );
    let w = check(&flight([DEG_PER_RAD, 1.0, 1.0], 0.0002)).warnings(&m);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("channel `p`") && w[0].contains("deg/s data mapped as rad/s"),
        "{}",
        w[0]
    );
    let w = check(&flight([1.0, 1.0, -1.0], 0.0002)).warnings(&m);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("channel `r`") && w[0].contains("sign"), "{}", w[0]);
}

/// A channel that does not move (p held at 0) or too short a record is not judged.
#[test]
fn analytic_a_still_channel_or_a_short_record_is_not_judged() {
    let mut s = flight([1.0, 1.0 / DEG_PER_RAD, 1.0], 0.0);
    assert!(check(&s[..15]).gains().is_none());
    for x in &mut s {
        x.p_rad_s = Some(0.0);
    }
    let (gains, _) = check(&s).gains().unwrap();
    assert!(gains.iter().all(|g| g.0 != "p_rad_s"), "{gains:?}");
}
