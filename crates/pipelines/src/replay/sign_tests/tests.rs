//! Tests of the sign tests on linear aircraft integrated from known derivatives, where the
//! accelerometers are formed from the force equations by their analytic state derivatives (an
//! independent computation from the finite differences the tests use).
use super::*;

/// A mapping naming the surface and accelerometer columns (only the labels are used).
fn mapping() -> Mapping {
    Mapping::from_toml_str(
        "nominal_dt_s = 0.02\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"v\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nde = { column = \"elev\", unit = \"rad\" }\ndr = { column = \"rud\", unit = \"rad\" }\naz = { column = \"nz\", unit = \"m/s2\" }\nqbar = { value = 1000.0, unit = \"Pa\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\n",
        "m.toml",
    )
    .unwrap()
}

/// A deterministic ±1 pattern standing in for sensor noise (no generator needed).
fn wiggle(k: usize, amp: f64) -> f64 {
    amp * [0.9, -0.4, -1.0, 0.3, 0.7, -0.8, 0.1][k % 7]
}

/// A 3-2-1-1 of `amp` rad starting at `t0`, 0.5-s unit.
fn input_3211(t: f64, t0: f64, amp: f64) -> f64 {
    let u = (t - t0) / 0.5;
    match u {
        u if (0.0..3.0).contains(&u) => amp,
        u if (3.0..5.0).contains(&u) => -amp,
        u if (5.0..6.0).contains(&u) => amp,
        u if (6.0..7.0).contains(&u) => -amp,
        _ => 0.0,
    }
}

const V: f64 = 80.0;

/// 30 s at 50 Hz of a short period (Euler, 20 substeps) driven by a 3-2-1-1 elevator, with
/// M_δe = −8 rad/s² per rad; the accelerometers from the force equations at the analytic α̇;
/// `de_sign` and `az_sign` flip the recorded channels as a reversed mapping would.
fn pitch_record(de_sign: f64, az_sign: f64) -> Vec<AirDataSample> {
    pitch_record_with_servo(de_sign, az_sign, None, 0.03)
}

/// [`pitch_record`] with 3-2-1-1 amplitude `amp` rad, and with `servo` = (τ s, rate limit
/// rad/s): the surface follows the command through a rate-limited first-order actuator and the
/// record holds the command.
fn pitch_record_with_servo(
    de_sign: f64,
    az_sign: f64,
    servo: Option<(f64, f64)>,
    amp: f64,
) -> Vec<AirDataSample> {
    let (za, zde, ma, mq, mde) = (-1.2, -0.1, -6.0, -2.0, -8.0);
    let (dt, sub) = (0.02, 20);
    let (mut alpha, mut q, mut theta) = (0.05_f64, 0.0, 0.05_f64);
    let mut surface = 0.0;
    let mut out = Vec::new();
    for k in 0..1500 {
        let t = k as f64 * dt;
        let cmd = input_3211(t, 2.0, amp) + input_3211(t, 15.0, -amp * 2.0 / 3.0);
        let de = if servo.is_some() { surface } else { cmd };
        let alpha_dot = za * (alpha - 0.05) + q + zde * de;
        let (u, w) = (V * alpha.cos(), V * alpha.sin());
        let w_dot = V * alpha.cos() * alpha_dot;
        let u_dot = -V * alpha.sin() * alpha_dot;
        let az = w_dot - q * u - G0_MPS2 * theta.cos();
        let ax = u_dot + q * w + G0_MPS2 * theta.sin();
        out.push(AirDataSample {
            t_s: t,
            vt_mps: V,
            alpha_rad: alpha + wiggle(k, 1e-4),
            q_rad_s: Some(q + wiggle(k + 3, 2e-4)),
            theta_rad: Some(theta),
            ax_mps2: Some(ax + wiggle(k + 1, 0.02)),
            az_mps2: Some(az_sign * (az + wiggle(k + 2, 0.05))),
            de_rad: Some(de_sign * cmd),
            ..Default::default()
        });
        for _ in 0..sub {
            let h = dt / sub as f64;
            let de = match servo {
                Some((tau, rate)) => {
                    surface += h * ((cmd - surface) / tau).clamp(-rate, rate);
                    surface
                }
                None => cmd,
            };
            let a_dot = za * (alpha - 0.05) + q + zde * de;
            let q_dot = ma * (alpha - 0.05) + mq * q + mde * de;
            alpha += h * a_dot;
            q += h * q_dot;
            theta += h * q;
        }
    }
    out
}

fn verdict(tests: &[SignTest], channel: &str) -> SignTest {
    tests.iter().find(|t| t.channel == channel).unwrap_or_else(|| panic!("{tests:?}")).clone()
}

/// The elevator and both accelerometers of a consistent record are consistent, the elevator's
/// response near its true M_δe; reversed channels are named reversed, with a warning on Cm_de
/// naming the column.
#[test]
fn pitch_record_consistent_and_reversed() {
    let t = sign_tests(&[pitch_record(1.0, 1.0)]);
    let de = verdict(&t, "de");
    assert_eq!(de.verdict, SignVerdict::Consistent, "{de:?}");
    let g = de.gain.unwrap();
    assert!((g + 8.0).abs() < 0.8, "M_δe {g}");
    for ch in ["ax", "az"] {
        let a = verdict(&t, ch);
        assert_eq!(a.verdict, SignVerdict::Consistent, "{a:?}");
        assert!((a.gain.unwrap() - 1.0).abs() < 0.1, "{a:?}");
    }
    assert!(warnings(&t, &mapping(), 0.02).is_empty());
    let t = sign_tests(&[pitch_record(-1.0, -1.0)]);
    assert_eq!(verdict(&t, "de").verdict, SignVerdict::Reversed);
    assert_eq!(verdict(&t, "az").verdict, SignVerdict::Reversed);
    let w = warnings(&t, &mapping(), 0.02);
    assert_eq!(w.len(), 2, "{w:?}");
    assert_eq!(w[0].parameter.as_deref(), Some("Cm_de"));
    assert!(w[0].text.contains("`elev`") && w[0].text.contains("scale = -1"), "{}", w[0].text);
    assert!(w[1].parameter.is_none() && w[1].text.contains("`nz`"), "{}", w[1].text);
}

/// An elevator that never moves, and accelerometers without θ, cannot be decided, and say why.
#[test]
fn unexcited_or_unsupported_channels_cannot_be_decided() {
    let mut rec = pitch_record(1.0, 1.0);
    rec.iter_mut().for_each(|s| {
        s.de_rad = Some(0.0);
        s.theta_rad = None;
    });
    let t = sign_tests(&[rec]);
    let de = verdict(&t, "de");
    assert_eq!(de.verdict, SignVerdict::Undecided);
    assert!(de.gain.is_none() && de.evidence.contains("excited"), "{de:?}");
    let az = verdict(&t, "az");
    assert_eq!(az.verdict, SignVerdict::Undecided);
    assert!(az.evidence.contains("`theta` is not mapped"), "{az:?}");
}

/// 40 s at 50 Hz of a lateral-directional model (Euler, 20 substeps) with an aileron doublet at
/// 3 s and a rudder doublet at 15 s; L_δa = −12, N_δr = −3 rad/s² per rad under aeroident's
/// conventions; β mapped or not; `dr_sign` flips the recorded rudder.
fn lateral_record(dr_sign: f64, with_beta: bool) -> Vec<AirDataSample> {
    lateral_record_with(dr_sign, with_beta, -0.2, 0.0)
}

/// [`lateral_record`] with the side force's `Y_β` (`yb`, 1/s) and `Y_δr` (`ydr`, 1/s per rad)
/// in the sideslip equation.
fn lateral_record_with(dr_sign: f64, with_beta: bool, yb: f64, ydr: f64) -> Vec<AirDataSample> {
    lateral_record_servo(dr_sign, with_beta, (yb, ydr), None)
}

/// [`lateral_record_with`] (`side` = (Y_β, Y_δr)) with `servo` = (τ s, rate limit rad/s): both
/// surfaces follow their commands through a rate-limited first-order actuator and the record
/// holds the commands.
fn lateral_record_servo(
    dr_sign: f64,
    with_beta: bool,
    (yb, ydr): (f64, f64),
    servo: Option<(f64, f64)>,
) -> Vec<AirDataSample> {
    let (lb, lp, lr, nb, np, nr) = (-10.0, -2.5, 0.8, 4.0, -0.1, -0.5);
    let mut surfaces = [0.0_f64; 2];
    let (lda, ldr, nda, ndr) = (-12.0, 1.0, -0.3, -3.0);
    let (dt, sub) = (0.02, 20);
    let (mut beta, mut p, mut r, mut phi) = (0.0_f64, 0.0, 0.0, 0.0_f64);
    let mut out = Vec::new();
    for k in 0..2000 {
        let t = k as f64 * dt;
        let doublet = |t0: f64, amp: f64| {
            if (t0..t0 + 1.0).contains(&t) {
                amp
            } else if (t0 + 1.0..t0 + 2.0).contains(&t) {
                -amp
            } else {
                0.0
            }
        };
        let cmd = [doublet(3.0, 0.05) + doublet(25.0, -0.03), doublet(15.0, 0.08)];
        let dr = if servo.is_some() { surfaces[1] } else { cmd[1] };
        let beta_dot = yb * beta + ydr * dr - r + G0_MPS2 / V * phi;
        let ay = V * beta_dot + r * V - G0_MPS2 * phi.sin();
        out.push(AirDataSample {
            t_s: t,
            vt_mps: V,
            beta_rad: with_beta.then_some(beta + wiggle(k, 2e-4)),
            p_rad_s: Some(p + wiggle(k + 1, 5e-4)),
            r_rad_s: Some(r + wiggle(k + 2, 5e-4)),
            phi_rad: Some(phi),
            theta_rad: Some(0.0),
            ay_mps2: Some(ay + wiggle(k + 4, 0.03)),
            da_rad: Some(cmd[0]),
            dr_rad: Some(dr_sign * cmd[1]),
            ..Default::default()
        });
        for _ in 0..sub {
            let h = dt / sub as f64;
            let [da, dr] = match servo {
                Some((tau, rate)) => {
                    for (x, c) in surfaces.iter_mut().zip(cmd) {
                        *x += h * ((c - *x) / tau).clamp(-rate, rate);
                    }
                    surfaces
                }
                None => cmd,
            };
            let b_dot = yb * beta + ydr * dr - r + G0_MPS2 / V * phi;
            let p_dot = lb * beta + lp * p + lr * r + lda * da + ldr * dr;
            let r_dot = nb * beta + np * p + nr * r + nda * da + ndr * dr;
            beta += h * b_dot;
            p += h * p_dot;
            r += h * r_dot;
            phi += h * p;
        }
    }
    out
}

/// Both surfaces of a lateral record are consistent with or without β; a reversed rudder is
/// named on the rudder, and `a_y` is consistent with β mapped and cannot be decided without.
#[test]
fn lateral_record_names_a_reversed_rudder() {
    for with_beta in [true, false] {
        let t = sign_tests(&[lateral_record(1.0, with_beta)]);
        assert_eq!(verdict(&t, "da").verdict, SignVerdict::Consistent, "{t:?}");
        assert_eq!(verdict(&t, "dr").verdict, SignVerdict::Consistent, "{t:?}");
        let n_dr = verdict(&t, "dr").gain.unwrap();
        assert!((n_dr + 3.0).abs() < 0.6, "N_δr {n_dr} (β {with_beta})");
        let reversed = sign_tests(&[lateral_record(-1.0, with_beta)]);
        assert_eq!(verdict(&reversed, "dr").verdict, SignVerdict::Reversed, "{reversed:?}");
        assert_eq!(verdict(&reversed, "da").verdict, SignVerdict::Consistent);
        let w = warnings(&reversed, &mapping(), 0.02);
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0].parameter.as_deref(), Some("Cn_dr"));
        assert!(w[0].text.contains("`rud`"), "{}", w[0].text);
        let ay = verdict(&t, "ay");
        if with_beta {
            assert_eq!(ay.verdict, SignVerdict::Consistent, "{ay:?}");
        } else {
            assert_eq!(ay.verdict, SignVerdict::Undecided);
            assert!(ay.evidence.contains("`beta` is not mapped"), "{ay:?}");
        }
    }
}

/// No difference is taken across two manoeuvres: a record cut in two gives the same verdicts
/// and a gain within its σ of the whole record's.
#[test]
fn manoeuvres_are_differenced_separately() {
    let rec = pitch_record(1.0, 1.0);
    let whole = verdict(&sign_tests(std::slice::from_ref(&rec)), "de");
    let (a, b) = rec.split_at(700);
    let cut = verdict(&sign_tests(&[a, b]), "de");
    assert_eq!(cut.verdict, whole.verdict);
    assert!((cut.gain.unwrap() - whole.gain.unwrap()).abs() < whole.sigma.unwrap());
}

/// The simulation holds each recorded input over its 0.02-s interval (a zero-order hold: the
/// surface acts half a sample after its record, on average). A measured elevator leads by that
/// half sample (within 0.003 s) and gets no timing warning; a commanded one through a
/// first-order actuator limited to 3.5 rad/s (a 0.15-rad step hits the limit) leads by the
/// actuator's lag more, within 0.01 s, and the warning names it on Cm_de.
#[test]
fn commanded_elevator_leads_by_its_actuator_lag() {
    let half_sample = 0.01;
    let t = sign_tests(&[pitch_record(1.0, 1.0)]);
    let de = verdict(&t, "de");
    let lead = de.lead_s.unwrap();
    assert!((lead - half_sample).abs() < 0.003, "{de:?}");
    assert!(timing::warning(&de, &mapping(), 0.02).is_none());
    for (tau, amp) in [(0.04, 0.15), (0.025, 0.05)] {
        let t = sign_tests(&[pitch_record_with_servo(1.0, 1.0, Some((tau, 3.5)), amp)]);
        let de = verdict(&t, "de");
        let lead = de.lead_s.unwrap();
        let (lo, hi) = de.lead_interval_s.unwrap();
        assert!(
            (lead - half_sample - tau).abs() < 0.01 && lo < lead && lead < hi,
            "τ {tau}: {de:?}"
        );
        let ws = timing::warnings(&de, &mapping(), 0.02);
        let about: Vec<_> = ws.iter().map(|w| w.parameter.as_deref()).collect();
        assert_eq!(about, [Some("Cm_de"), Some("Cm_q")]);
        assert!(ws[1].text.contains("biases its damping derivative Cm_q"), "{}", ws[1].text);
        let w = &ws[0];
        assert!(
            w.text.contains("channel `de` (column `elev`) leads") && w.text.contains("commanded"),
            "{}",
            w.text
        );
    }
}

/// A rudder with a side force of its own on an aircraft whose `Y_β` is small: `a_y` standing
/// in for β would put `−N_β Y_δr / Y_β` = +4 into `N_δr` = −3 and call the consistent rudder
/// reversed. Without β the test takes β from the kinematics and finds `N_δr` within 10 %, says
/// so, and names the reversed rudder; without φ it cannot decide, and says why.
#[test]
fn a_rudder_with_its_own_side_force_is_decided_on_the_kinematic_sideslip() {
    let (yb, ydr) = (-0.05, 0.05);
    let t = sign_tests(&[lateral_record_with(1.0, false, yb, ydr)]);
    let dr = verdict(&t, "dr");
    assert_eq!(dr.verdict, SignVerdict::Consistent, "{dr:?}");
    assert!((dr.gain.unwrap() + 3.0).abs() < 0.3, "{dr:?}");
    assert!(dr.evidence.contains("β from the kinematics"), "{}", dr.evidence);
    assert_eq!(verdict(&t, "da").verdict, SignVerdict::Consistent, "{t:?}");
    let reversed = sign_tests(&[lateral_record_with(-1.0, false, yb, ydr)]);
    assert_eq!(verdict(&reversed, "dr").verdict, SignVerdict::Reversed, "{reversed:?}");
    let no_phi: Vec<AirDataSample> = lateral_record_with(1.0, false, yb, ydr)
        .into_iter()
        .map(|s| AirDataSample { phi_rad: None, ..s })
        .collect();
    let dr = verdict(&sign_tests(&[no_phi]), "dr");
    assert_eq!(dr.verdict, SignVerdict::Undecided, "{dr:?}");
    assert!(dr.evidence.contains("a_y cannot stand in"), "{}", dr.evidence);
}

/// 300 s at 10 Hz of a phugoid at constant α: θ = 0.05 sin(0.15 t), the speed trading with
/// height (`V̇ = −g sinθ` plus a small thrust wave) and the specific force along x from the
/// force equations; `ax_of` maps that force to the recorded channel.
fn phugoid_record(ax_of: impl Fn(f64, f64) -> f64) -> Vec<AirDataSample> {
    let (alpha, w_rate) = (0.05_f64, 0.15);
    let theta = |t: f64| 0.05 * (w_rate * t).sin();
    let v_dot = |t: f64| -G0_MPS2 * theta(t).sin() + 0.2 * (w_rate * t + 1.0).sin();
    let mut v = V;
    let mut out = Vec::new();
    for k in 0..3000 {
        let t = 0.1 * k as f64;
        let q = 0.05 * w_rate * (w_rate * t).cos();
        let fx = v_dot(t) * alpha.cos() + q * v * alpha.sin() + G0_MPS2 * theta(t).sin();
        let fz = v_dot(t) * alpha.sin() - q * v * alpha.cos() - G0_MPS2 * theta(t).cos();
        out.push(AirDataSample {
            t_s: t,
            vt_mps: v,
            alpha_rad: alpha,
            q_rad_s: Some(q + wiggle(k, 1e-4)),
            theta_rad: Some(theta(t)),
            ax_mps2: Some(ax_of(fx + wiggle(k + 1, 0.01), theta(t))),
            az_mps2: Some(fz + wiggle(k + 2, 0.02)),
            ..Default::default()
        });
        // Midpoint steps of 0.01 s: the speed to 1e-6 m/s over the record.
        for j in 0..10 {
            v += 0.01 * v_dot(t + 0.01 * (j as f64 + 0.5));
        }
    }
    out
}

/// A gravity-compensated `a_x` in a phugoid regresses on the kinematics with a gain near 0
/// (the speed change is mostly gravity's), decided, and is named with its form, as is a
/// reading in g; the raw specific force is consistent with a gain near 1.
#[test]
fn an_accelerometer_that_is_not_a_specific_force_is_named_with_its_form() {
    let ax = |t: &[SignTest]| verdict(t, "ax");
    let raw = ax(&sign_tests(&[phugoid_record(|f, _| f)]));
    assert_eq!(raw.verdict, SignVerdict::Consistent, "{raw:?}");
    assert!((raw.gain.unwrap() - 1.0).abs() < 0.05, "{raw:?}");
    let compensated = sign_tests(&[phugoid_record(|f, theta| f - G0_MPS2 * theta.sin())]);
    let a = ax(&compensated);
    assert_eq!(a.verdict, SignVerdict::NotASpecificForce, "{a:?}");
    assert!(a.gain.unwrap().abs() < 1.0 / SCALE_BOUND, "{a:?}");
    assert!(a.evidence.contains("likely gravity removed"), "{}", a.evidence);
    let w = warnings(&compensated, &mapping(), 0.1);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].text.contains("is not a specific force as mapped"), "{}", w[0].text);
    assert_eq!(verdict(&compensated, "az").verdict, SignVerdict::Consistent);
    let in_g = ax(&sign_tests(&[phugoid_record(|f, _| f / G0_MPS2)]));
    assert_eq!(in_g.verdict, SignVerdict::NotASpecificForce, "{in_g:?}");
    assert!(in_g.evidence.contains("a reading in g mapped as m/s²"), "{}", in_g.evidence);
}

/// Commanded aileron and rudder through a 0.04-s servo, on a record without β: each lead is
/// found (half a sample of hold plus τ, within 0.01 s) and warned on the surface's control and
/// damping derivatives, as the elevator's is.
#[test]
fn commanded_aileron_and_rudder_lead_by_their_actuator_lag() {
    let tau = 0.04;
    let rec = lateral_record_servo(1.0, false, (-0.2, 0.0), Some((tau, 3.5)));
    let t = sign_tests(&[rec]);
    for (ch, about) in [("da", ["Cl_da", "Cl_p"]), ("dr", ["Cn_dr", "Cn_r"])] {
        let s = verdict(&t, ch);
        assert_eq!(s.verdict, SignVerdict::Consistent, "{s:?}");
        let lead = s.lead_s.unwrap();
        assert!((lead - 0.01 - tau).abs() < 0.01, "{ch}: {s:?}");
        let ws = timing::warnings(&s, &mapping(), 0.02);
        let named: Vec<_> = ws.iter().map(|w| w.parameter.as_deref()).collect();
        assert_eq!(named, about.map(Some), "{ch}: {ws:?}");
    }
}
