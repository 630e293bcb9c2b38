//! The C ABI from Rust (the same extern functions a C program calls): an estimator fed through
//! it recovers coefficients that an independent computation in this test put into the samples;
//! errors come back as codes with a message naming what was wrong, never as a panic; reset
//! gives the estimates of a fresh estimator.

use aeroident_capi::sample::*;
use aeroident_capi::*;
use std::ffi::{CStr, CString};
use std::ptr::{null, null_mut};

fn message() -> String {
    // SAFETY: never NULL, NUL-terminated.
    unsafe { CStr::from_ptr(aeroident_last_error_message()) }.to_str().unwrap().to_string()
}

/// `aeroident_estimator_new`, the result code, the handle and the message.
fn new(
    kind: &str,
    model: &str,
    options: Option<&str>,
) -> (AeroidentResult, *mut AeroidentEstimator, String) {
    let (k, m) = (CString::new(kind).unwrap(), CString::new(model).unwrap());
    let o = options.map(|o| CString::new(o).unwrap());
    let mut e = null_mut();
    // SAFETY: valid strings and out pointer.
    let r = unsafe {
        aeroident_estimator_new(
            k.as_ptr(),
            m.as_ptr(),
            o.as_ref().map_or(null(), |o| o.as_ptr()),
            &mut e,
        )
    };
    (r, e, message())
}

/// The true coefficients of the synthetic longitudinal aircraft (the `longitudinal` preset's
/// order: CL, CD, Cm × 0, alpha, q, de).
const TRUE: [(&str, f64); 12] = [
    ("CL_0", 0.2),
    ("CL_alpha", 4.5),
    ("CL_q", 7.0),
    ("CL_de", 0.4),
    ("CD_0", 0.03),
    ("CD_alpha", 0.3),
    ("CD_q", 0.0),
    ("CD_de", 0.05),
    ("Cm_0", 0.02),
    ("Cm_alpha", -0.8),
    ("Cm_q", -12.0),
    ("Cm_de", -1.1),
];

/// Sample `k` of a synthetic flight: α, q, δe varied by incommensurate sines, and the
/// accelerometers and pitch acceleration that the coefficients of [`TRUE`] imply, formed here
/// from the definitions (Klein & Morelli 2006 eqs. 3.1–3.6, no thrust, no lateral motion):
/// `CX = CL sin α − CD cos α`, `CZ = −CL cos α − CD sin α`, `ax = CX q̄S/m`, `az = CZ q̄S/m`,
/// `q̇ = Cm q̄ S c̄ / Iyy`.
fn synthetic(k: usize) -> AeroidentSample {
    let t = k as f64 * 0.02;
    let (m, s_ref, cbar, iyy, v, qbar) = (5000.0, 20.0, 2.0, 30_000.0, 100.0, 5000.0);
    let alpha = 0.08 + 0.03 * (1.3 * t).sin() + 0.01 * (4.1 * t).sin();
    let q = 0.1 * (2.2 * t).cos() + 0.02 * (0.7 * t).sin();
    let de = -0.02 + 0.015 * (3.3 * t).sin() + 0.01 * (0.9 * t).cos();
    let qhat = q * cbar / (2.0 * v);
    let regressors = [1.0, alpha, qhat, de];
    let coef = |c: usize| (0..4).map(|j| TRUE[4 * c + j].1 * regressors[j]).sum::<f64>();
    let (cl, cd, cm) = (coef(0), coef(1), coef(2));
    let cx = cl * alpha.sin() - cd * alpha.cos();
    let cz = -cl * alpha.cos() - cd * alpha.sin();
    AeroidentSample {
        t_s: t,
        vt_mps: v,
        alpha_rad: alpha,
        qbar_pa: qbar,
        q_rad_s: q,
        qdot_rad_s2: cm * qbar * s_ref * cbar / iyy,
        ax_mps2: cx * qbar * s_ref / m,
        az_mps2: cz * qbar * s_ref / m,
        de_rad: de,
        mass_kg: m,
        S_m2: s_ref,
        cbar_m: cbar,
        Iyy_kgm2: iyy,
        present: AEROIDENT_HAS_Q
            | AEROIDENT_HAS_QDOT
            | AEROIDENT_HAS_AX
            | AEROIDENT_HAS_AZ
            | AEROIDENT_HAS_DE
            | AEROIDENT_HAS_CBAR
            | AEROIDENT_HAS_IYY,
        ..Default::default()
    }
}

/// Estimates, σ and identified flags of `e` (n parameters).
fn estimates(e: *const AeroidentEstimator, n: usize) -> (Vec<f64>, Vec<f64>, Vec<bool>) {
    let (mut v, mut s, mut id) = (vec![0.0; n], vec![0.0; n], vec![false; n]);
    // SAFETY: a live handle; buffers of n elements.
    let r = unsafe {
        aeroident_estimator_estimates(e, v.as_mut_ptr(), s.as_mut_ptr(), id.as_mut_ptr(), n)
    };
    assert_eq!(r, AeroidentResult::Ok, "{}", message());
    (v, s, id)
}

/// RLS through the C ABI on noise-free samples built from known coefficients recovers them
/// (1e-8), names them in the preset's order, has them unidentified (NaN, never 0) before any
/// sample, and reports its state.
#[test]
fn rls_through_the_c_abi_recovers_the_coefficients_put_into_the_samples() {
    let (r, e, msg) = new("rls", "longitudinal", None);
    assert_eq!(r, AeroidentResult::Ok, "{msg}");
    // SAFETY: a live handle throughout; freed at the end.
    unsafe {
        let n = aeroident_estimator_n_params(e);
        assert_eq!(n, TRUE.len());
        for (i, (name, _)) in TRUE.iter().enumerate() {
            let got = CStr::from_ptr(aeroident_estimator_param_name(e, i));
            assert_eq!(got.to_str().unwrap(), *name);
        }
        assert!(aeroident_estimator_param_name(e, n).is_null());
        let (v, s, id) = estimates(e, n);
        assert!(v.iter().chain(&s).all(|x| x.is_nan()) && id.iter().all(|b| !b));
        for k in 0..400 {
            assert_eq!(
                aeroident_estimator_update(e, &synthetic(k)),
                AeroidentResult::Ok,
                "{}",
                message()
            );
        }
        let (v, s, id) = estimates(e, n);
        for (i, (name, truth)) in TRUE.iter().enumerate() {
            // CD_q is in the preset and 0 in the truth: recovered as 0 like the others.
            assert!(id[i] && (v[i] - truth).abs() < 1e-8, "{name}: {} against {truth}", v[i]);
            assert!(s[i].is_finite() && s[i] >= 0.0, "{name}: σ {}", s[i]);
        }
        let mut st = std::mem::zeroed::<AeroidentState>();
        assert_eq!(aeroident_estimator_state(e, &mut st), AeroidentResult::Ok);
        assert_eq!(
            (st.n_params, st.n_identified, st.samples_accepted, st.samples_refused),
            (12, 12, 400, 0)
        );
        assert_eq!(st.status, AeroidentStatus::Running);
        assert_eq!(st.t_s, synthetic(399).t_s);
        assert!(!st.has_nis && st.nis.is_nan());
        aeroident_estimator_free(e);
    }
}

/// A creation that must fail: kind, model, options, the code, words of the message.
type Case<'a> = (&'a str, &'a str, Option<&'a str>, AeroidentResult, &'a [&'a str]);

/// Each wrong argument gives its code and a message naming it; nothing panics.
#[test]
fn errors_are_codes_with_a_message_naming_what_was_wrong() {
    let cases: [Case; 6] = [
        (
            "kalman",
            "longitudinal",
            None,
            AeroidentResult::InvalidArgument,
            &["unknown estimator kind `kalman`", "rls | rls-iv"],
        ),
        (
            "rls",
            "[coefficients]\nCm = [\"alpha\", \"elevator\"]\n",
            None,
            AeroidentResult::Model,
            &["line 2", "unknown term `elevator`"],
        ),
        ("rls", "six-axes", None, AeroidentResult::Model, &["preset name"]),
        (
            "ekf",
            "longitudinal",
            Some("forgetting = 0.9"),
            AeroidentResult::Option,
            &["ekf: unknown option `forgetting`", "parameter_walk_per_sqrt_s"],
        ),
        (
            "rls",
            "longitudinal",
            Some("forgetting = 1.5"),
            AeroidentResult::Build,
            &["estimator `rls`", "forgetting"],
        ),
        ("oe", "longitudinal", None, AeroidentResult::Build, &["batch method"]),
    ];
    for (kind, model, options, code, words) in cases {
        let (r, e, msg) = new(kind, model, options);
        assert_eq!((r, e.is_null()), (code, true), "{kind} {model}: {msg}");
        for w in words {
            assert!(msg.contains(w), "{kind}: `{w}` not in: {msg}");
        }
    }
    let (r, e, msg) = new("rls", "longitudinal", Some("forgetting = "));
    assert!(r == AeroidentResult::Option && e.is_null() && msg.contains("TOML"), "{msg}");
    // SAFETY: NULL arguments are what is tested; valid ones otherwise.
    unsafe {
        let mut e = null_mut();
        let m = CString::new("longitudinal").unwrap();
        assert_eq!(
            aeroident_estimator_new(null(), m.as_ptr(), null(), &mut e),
            AeroidentResult::NullPointer
        );
        assert!(message().contains("kind is NULL"), "{}", message());
        assert_eq!(
            aeroident_estimator_new(m.as_ptr(), m.as_ptr(), null(), null_mut()),
            AeroidentResult::NullPointer
        );
        let bad = [0xffu8, 0];
        assert_eq!(
            aeroident_estimator_new(bad.as_ptr().cast(), m.as_ptr(), null(), &mut e),
            AeroidentResult::InvalidArgument
        );
        assert!(message().contains("kind is not UTF-8"), "{}", message());
        assert_eq!(
            aeroident_estimator_update(null_mut(), &synthetic(0)),
            AeroidentResult::NullPointer
        );
        assert_eq!(aeroident_estimator_n_params(null()), 0);
        assert!(aeroident_estimator_method(null()).is_null());
        aeroident_estimator_free(null_mut());
    }
}

/// A sample the estimator cannot use is refused with the field named and the state
/// unchanged; a short buffer and undefined presence bits are refused; the message is cleared
/// by the next call that succeeds.
#[test]
fn errors_refused_samples_leave_the_estimator_as_it_was() {
    let (_, e, _) = new("rls", "longitudinal", None);
    // SAFETY: a live handle throughout; freed at the end.
    unsafe {
        for k in 0..50 {
            assert_eq!(aeroident_estimator_update(e, &synthetic(k)), AeroidentResult::Ok);
        }
        let before = estimates(e, 12);
        let no_qdot = AeroidentSample {
            present: synthetic(50).present & !AEROIDENT_HAS_QDOT,
            ..synthetic(50)
        };
        assert_eq!(aeroident_estimator_update(e, &no_qdot), AeroidentResult::SampleRefused);
        // Named by the field the coefficient lacks, not the coefficient (docs/c-abi.md).
        assert!(
            message().contains("`qdot_rad_s2`") && message().contains("t = 1 s"),
            "{}",
            message()
        );
        let nan_alpha = AeroidentSample { alpha_rad: f64::NAN, ..synthetic(50) };
        assert_eq!(aeroident_estimator_update(e, &nan_alpha), AeroidentResult::SampleRefused);
        assert!(message().contains("alpha_rad"), "{}", message());
        let nan_flagged = AeroidentSample { qdot_rad_s2: f64::INFINITY, ..synthetic(50) };
        assert_eq!(aeroident_estimator_update(e, &nan_flagged), AeroidentResult::SampleRefused);
        assert!(message().contains("qdot_rad_s2"), "{}", message());
        let undefined =
            AeroidentSample { present: synthetic(50).present | 1 << 31, ..synthetic(50) };
        assert_eq!(aeroident_estimator_update(e, &undefined), AeroidentResult::InvalidArgument);
        assert!(message().contains("0x80000000"), "{}", message());
        let after = estimates(e, 12);
        assert_eq!(
            format!("{before:?}"),
            format!("{after:?}"),
            "refused samples changed the estimates"
        );
        assert!(message().is_empty(), "a call that succeeded leaves no message");
        let mut v = [0.0; 11];
        assert_eq!(
            aeroident_estimator_estimates(e, v.as_mut_ptr(), null_mut(), null_mut(), 11),
            AeroidentResult::BufferTooSmall
        );
        assert!(
            message().contains("11 elements") && message().contains("12 parameters"),
            "{}",
            message()
        );
        let mut st = std::mem::zeroed::<AeroidentState>();
        aeroident_estimator_state(e, &mut st);
        assert_eq!((st.samples_accepted, st.samples_refused), (50, 3));
        aeroident_estimator_free(e);
    }
}

/// After a reset, the estimator gives exactly the estimates of a fresh one fed the same
/// samples (EKF: a model state and priors to restart from), and its counts start again.
#[test]
fn reset_gives_the_estimates_of_a_fresh_estimator() {
    let (_, fresh, _) = new("ekf", "longitudinal", Some("parameter_walk_per_sqrt_s = 0.001"));
    let (_, used, _) = new("ekf", "longitudinal", Some("parameter_walk_per_sqrt_s = 0.001"));
    let samples: Vec<AeroidentSample> = (0..300)
        .map(|k| AeroidentSample {
            theta_rad: 0.05,
            present: synthetic(k).present | AEROIDENT_HAS_THETA,
            ..synthetic(k)
        })
        .collect();
    // SAFETY: live handles throughout; freed at the end.
    unsafe {
        for s in samples.iter().rev().take(100).rev() {
            aeroident_estimator_update(used, s);
        }
        assert_eq!(aeroident_estimator_reset(used), AeroidentResult::Ok, "{}", message());
        for s in &samples {
            assert_eq!(aeroident_estimator_update(fresh, s), aeroident_estimator_update(used, s));
        }
        let (a, b) = (estimates(fresh, 12), estimates(used, 12));
        assert!(a.2.iter().any(|x| *x), "the EKF identified nothing");
        assert_eq!(format!("{a:?}"), format!("{b:?}"));
        let mut st = std::mem::zeroed::<AeroidentState>();
        aeroident_estimator_state(used, &mut st);
        assert_eq!(st.samples_accepted + st.samples_refused, 300);
        assert!(st.has_nis && st.nis.is_finite(), "{st:?}");
        assert_eq!(CStr::from_ptr(aeroident_estimator_method(used)).to_str().unwrap(), "ekf");
        aeroident_estimator_free(fresh);
        aeroident_estimator_free(used);
    }
}

/// A full six-axis sample (every field set, plausible values) for sample `k`.
fn six_axis(k: usize) -> AeroidentSample {
    let t = k as f64 * 0.02;
    let s = synthetic(k);
    AeroidentSample {
        beta_rad: 0.01 * (1.7 * t).sin(),
        p_rad_s: 0.05 * (2.3 * t).sin(),
        r_rad_s: 0.03 * (1.1 * t).cos(),
        pdot_rad_s2: 0.1 * (2.3 * t).cos(),
        rdot_rad_s2: -0.03 * (1.1 * t).sin(),
        alphadot_rad_s: 0.0,
        phi_rad: 0.02,
        theta_rad: 0.08,
        psi_rad: 0.0,
        ay_mps2: 0.2 * (1.7 * t).sin(),
        da_rad: 0.01 * (2.9 * t).sin(),
        dr_rad: 0.01 * (1.9 * t).cos(),
        rho_kgpm3: 1.0,
        b_m: 12.0,
        Ixx_kgm2: 20_000.0,
        Izz_kgm2: 45_000.0,
        Ixz_kgm2: 1_000.0,
        v0_mps: 100.0,
        present: AEROIDENT_HAS_ALL & !AEROIDENT_HAS_THRUST_MOMENT & !AEROIDENT_HAS_THROTTLE,
        thrust_n: 0.0,
        ..s
    }
}

/// Every real-time kind refuses a six-axis sample without `Ixz` or `b` naming that field, as
/// the EKF does and docs/c-abi.md promises (rls, rls-iv, ftr, smpe and gradient named the
/// coefficient instead: "non-finite input `Cl` = NaN").
#[test]
fn errors_a_missing_constant_is_named_by_its_field() {
    for kind in ["rls", "rls-iv", "ftr", "smpe", "smpe-corrected", "smpe-finite-time", "gradient"] {
        for (bit, field) in [(AEROIDENT_HAS_IXZ, "Ixz_kgm2"), (AEROIDENT_HAS_B, "b_m")] {
            let (r, e, msg) = new(kind, "six-axis", None);
            if r != AeroidentResult::Ok {
                // A kind without a six-axis form says so; that is another test's matter.
                assert!(e.is_null(), "{kind}: {msg}");
                continue;
            }
            let mut refused = None;
            for k in 0..20 {
                let s = AeroidentSample { present: six_axis(k).present & !bit, ..six_axis(k) };
                // SAFETY: a live handle and a valid sample.
                let r = unsafe { aeroident_estimator_update(e, &s) };
                if r != AeroidentResult::Ok {
                    refused = Some((r, message()));
                    break;
                }
            }
            // SAFETY: the handle from `new`, freed once.
            unsafe { aeroident_estimator_free(e) };
            let (r, msg) =
                refused.unwrap_or_else(|| panic!("{kind}: a sample without {field} taken"));
            assert_eq!(r, AeroidentResult::SampleRefused, "{kind}: {msg}");
            assert!(msg.contains(&format!("`{field}`")), "{kind} without {field}: {msg}");
        }
    }
}

/// The verdicts through the C ABI are the library's judge on the same numbers
/// (`aeroident_pipelines::verdict::judge_estimate`, computed here from the estimates the C ABI
/// gives): before a sample every parameter is `not identified`; after the synthetic flight,
/// which carries no thrust, the lift and pitch terms are identified and the drag terms are
/// not (withdrawn: without thrust the axial force is not the aircraft's drag), each with the
/// flag saying so; a buffer too small is refused.
#[test]
fn verdicts_are_the_librarys_judge_on_the_c_estimates() {
    use aeroident_pipelines::verdict::judge_estimate;
    let (r, e, msg) = new("rls", "longitudinal", None);
    assert_eq!(r, AeroidentResult::Ok, "{msg}");
    let model = aeroident_io::ModelSpec::preset("longitudinal").unwrap();
    // SAFETY: a live handle throughout; freed at the end.
    unsafe {
        let n = aeroident_estimator_n_params(e);
        let mut out = vec![AeroidentVerdict::Identified; n];
        assert!(aeroident_estimator_flags(e, 0).is_null(), "no flags before any verdicts");
        assert_eq!(aeroident_estimator_verdicts(e, out.as_mut_ptr(), n), AeroidentResult::Ok);
        assert!(out.iter().all(|v| *v == AeroidentVerdict::NotIdentified), "{out:?}");
        for k in 0..400 {
            assert_eq!(aeroident_estimator_update(e, &synthetic(k)), AeroidentResult::Ok);
        }
        let r = aeroident_estimator_verdicts(e, out.as_mut_ptr(), n - 1);
        assert_eq!(r, AeroidentResult::BufferTooSmall, "{}", message());
        assert_eq!(aeroident_estimator_verdicts(e, out.as_mut_ptr(), n), AeroidentResult::Ok);
        let (v, s, _) = estimates(e, n);
        for (i, (name, _)) in TRUE.iter().enumerate() {
            let flags = CStr::from_ptr(aeroident_estimator_flags(e, i)).to_str().unwrap();
            let value = v[i].is_finite().then_some(v[i]);
            let sigma = s[i].is_finite().then_some(s[i]);
            let lib = judge_estimate(name, value, sigma, "running", &model, false);
            assert_eq!(flags, lib.flags.join("\n"), "{name}");
            let want = match lib.status.as_str() {
                "identified" => AeroidentVerdict::Identified,
                "flagged" => AeroidentVerdict::Flagged,
                "diverged" => AeroidentVerdict::Diverged,
                _ => AeroidentVerdict::NotIdentified,
            };
            assert_eq!(out[i], want, "{name}: {flags}");
            if name.starts_with("CD_") {
                assert_ne!(out[i], AeroidentVerdict::Identified, "{name}: {flags}");
                assert!(flags.contains("thrust"), "{name}: {flags}");
            } else {
                assert_eq!(out[i], AeroidentVerdict::Identified, "{name}: {flags}");
            }
        }
        assert!(aeroident_estimator_flags(e, n).is_null());
        aeroident_estimator_free(e);
    }
}
