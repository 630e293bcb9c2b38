use super::*;

fn method(name: &str, rows: &[(&str, f64, f64)]) -> MethodEstimates {
    MethodEstimates::new(
        name,
        "complete",
        rows.iter().map(|&(n, e, s)| ParameterEstimate::new(n, e, s)),
    )
}

fn panel(own: &str, all: &[(&str, f64, f64)]) -> Agreement {
    let mine = all.iter().find(|m| m.0 == own).unwrap();
    let others: Vec<MethodEstimates> =
        all.iter().filter(|m| m.0 != own).map(|m| method(m.0, &[("Cl_p", m.1, m.2)])).collect();
    let c = judge(&method(own, &[("Cl_p", mine.1, mine.2)]), &others);
    assert_eq!((c.compared, c.flagged), (1, usize::from(!c.parameters[0].confirmed)));
    c.parameters[0].clone()
}

/// 1.0 ± 0.1 against 1.3 ± 0.1: 0.3 > 2·0.1414 and 23 % apart, so they disagree; 1.0 ± 0.01
/// against 1.08 ± 0.01 is 5.7 combined σ but 7.4 % apart, within the relative floor; 1.0 ± 0.1
/// against 1.25 ± 0.1 is 1.77 combined σ; −1.0 ± 0.01 against −1.15 ± 0.01 is 13 % and 10.6 σ.
#[test]
fn agreement_is_two_combined_sigma_or_ten_per_cent() {
    let e = |x: f64, s: f64| Estimate { method: "m".into(), estimate: x, std_error: s };
    assert!(!e(1.0, 0.1).agrees(&e(1.3, 0.1)));
    assert!(e(1.0, 0.01).agrees(&e(1.08, 0.01)));
    assert!(e(1.0, 0.1).agrees(&e(1.25, 0.1)));
    assert!(!e(-1.0, 0.01).agrees(&e(-1.15, 0.01)));
}

/// Least squares pulled towards zero (0.6) while instrumental variables, output error and the
/// EKF agree near 1.0: rls is set aside for regressor noise, output error is confirmed by the
/// three left, and rls's own verdict names the cause.
#[test]
fn regressor_noise_is_tested_by_instrumental_variables() {
    let all = [("rls", 0.6, 0.02), ("rls-iv", 1.0, 0.05), ("oe", 1.02, 0.03), ("ekf", 0.99, 0.02)];
    let oe = panel("oe", &all);
    assert!(oe.confirmed && oe.flag.is_none(), "{oe:?}");
    assert_eq!(oe.set_aside.len(), 1);
    assert_eq!(oe.set_aside[0].method, "rls");
    assert!(oe.set_aside[0].cause.starts_with("regressor noise"), "{oe:?}");
    let rls = panel("rls", &all);
    let flag = rls.flag.unwrap();
    assert!(flag.contains("rls set aside: regressor noise"), "{flag}");
    // IV moving away from the output-error methods: the instruments are set aside, not rls.
    let away = [("rls", 1.0, 0.02), ("rls-iv", 0.6, 0.05), ("oe", 1.02, 0.03), ("ekf", 0.99, 0.02)];
    let rls = panel("rls", &away);
    assert!(rls.confirmed, "{rls:?}");
    assert_eq!(rls.set_aside[0].method, "rls-iv");
    assert!(rls.set_aside[0].cause.starts_with("its instruments"));
    // rls agreeing with IV is not set aside; oe and the EKF disagree with it unexplained.
    let close = [("rls", 0.6, 0.02), ("rls-iv", 0.7, 0.3), ("oe", 1.02, 0.03), ("ekf", 0.99, 0.02)];
    let rls = panel("rls", &close);
    assert!(rls.set_aside.is_empty() && !rls.confirmed, "{rls:?}");
    let flag = rls.flag.unwrap();
    assert!(flag.contains("split") && flag.contains("oe, ekf disagree with rls"), "{flag}");
}

/// The EKF apart while fem agrees with oe: the EKF's noise model; fem and the EKF together
/// apart from oe: process noise, and oe is set aside.
#[test]
fn process_noise_is_tested_by_the_filter_error_method() {
    let ekf_off = [("oe", -0.44, 0.01), ("fem", -0.43, 0.01), ("ekf", -0.30, 0.01)];
    let ekf = panel("ekf", &ekf_off);
    assert!(ekf.flag.unwrap().contains("the EKF's noise model"));
    assert!(panel("oe", &ekf_off).confirmed);
    let oe_off = [("oe", -0.30, 0.01), ("fem", -0.44, 0.01), ("ekf", -0.43, 0.01)];
    let oe = panel("oe", &oe_off);
    assert!(!oe.confirmed && oe.flag.as_ref().unwrap().contains("process noise"), "{oe:?}");
    let fem = panel("fem", &oe_off);
    assert!(fem.confirmed, "{fem:?}");
    // fem apart while the EKF agrees with oe: not process noise (oe is kept), and nothing
    // tested explains fem's value, so fem is flagged; oe is flagged by fem's disagreement
    // too: no vote decides between them.
    let fem_off = [("oe", -0.44, 0.01), ("fem", -0.07, 0.01), ("ekf", -0.43, 0.01)];
    let fem = panel("fem", &fem_off);
    assert!(fem.set_aside.is_empty() && !fem.confirmed, "{fem:?}");
    let oe = panel("oe", &fem_off);
    assert!(oe.set_aside.is_empty(), "{oe:?}");
    assert!(oe.flag.unwrap().contains("fem disagree with oe"));
}

/// Methods that share a bias confirm nothing: rls and ftr agreeing (least squares both) leave
/// rls unconfirmed; oe and fdoe likewise; with fem beside them oe is confirmed. A majority does
/// not outvote a method: three least-squares-family estimates against oe flag oe, not confirm
/// the three.
#[test]
fn agreement_within_a_bias_family_confirms_nothing_and_nothing_is_outvoted() {
    let ls = panel("rls", &[("rls", 1.0, 0.01), ("ftr", 1.01, 0.01)]);
    assert!(ls.flag.unwrap().contains("only methods open to the same bias as rls"));
    let oe = panel("oe", &[("oe", 1.0, 0.01), ("fdoe", 1.01, 0.01)]);
    assert!(!oe.confirmed);
    assert!(panel("oe", &[("oe", 1.0, 0.01), ("fdoe", 1.01, 0.01), ("fem", 0.99, 0.01)]).confirmed);
    let many = [("oe", 1.0, 0.01), ("rls", 0.6, 0.01), ("ftr", 0.61, 0.01), ("smpe", 0.6, 0.01)];
    let oe = panel("oe", &many);
    assert!(oe.flag.unwrap().contains("rls, ftr, smpe disagree with oe"));
    let rls = panel("rls", &many);
    assert!(rls.flag.unwrap().contains("oe disagree with rls"));
    assert_eq!(bias_family("smpe-finite-time"), bias_family("rls"));
    assert_ne!(bias_family("rls-iv"), bias_family("rls"));
}

/// Two methods that disagree with no test explaining it: a split, with both camps named; an
/// estimate no other method gives is not confirmed either.
#[test]
fn an_unexplained_split_and_a_lone_estimate_are_flagged() {
    let a = panel("oe", &[("oe", 1.0, 0.01), ("rls", 2.0, 0.01)]);
    assert!(!a.confirmed);
    assert_eq!(a.camps, vec![vec!["oe".to_string()], vec!["rls".to_string()]]);
    let flag = a.flag.unwrap();
    assert!(
        flag.contains("split") && flag.contains("oe 1.0000") && flag.contains(" | rls 2.0000"),
        "{flag}"
    );
    let alone = panel("oe", &[("oe", 1.0, 0.01)]);
    assert!(alone.flag.unwrap().contains("no other method gives Cl_p"));
    // Rows without a finite positive σ are not compared; a failed method gives a warning.
    let m =
        MethodEstimates::new("ekf", "complete", [ParameterEstimate::new("Cl_p", 1.0, f64::NAN)]);
    assert!(m.estimates.is_empty());
    let c = judge(&method("oe", &[("Cl_p", 1.0, 0.1)]), &[MethodEstimates::failed("fem", "no β")]);
    let w = warnings(&c);
    assert_eq!(w.len(), 2);
    assert!(w[0].text.contains("fem failed: no β"), "{:?}", w[0]);
}

/// Least squares on an equation whose β regressor is noisy (the F-16 lateral record's Cl:
/// rls Cl_β −0.048 against −0.13 from the others): Cl_p −0.364 ± 0.024 agrees with IV's
/// −0.409 ± 0.014 within 2 combined σ, but IV moves it 11 % towards the output-error methods,
/// so it shares the bias shown on Cl_β. Cl_δa, which IV moves 1.3 %, stays confirmed; a Cn
/// term, in an equation where no bias was shown, is judged by σ alone.
#[test]
fn regressor_noise_shown_on_one_term_sets_aside_the_terms_it_moves_in_that_equation() {
    let rows = |rls: [f64; 4]| {
        [("Cl_beta", rls[0], 0.005), ("Cl_p", rls[1], 0.0236), ("Cl_da", rls[2], 0.00077)]
            .into_iter()
            .chain([("Cn_r", rls[3], 0.02)])
            .collect::<Vec<_>>()
    };
    let own = method("rls", &rows([-0.048, -0.364, -0.0502, -0.30]));
    let others = [
        method("rls-iv", &rows([-0.133, -0.409, -0.0495, -0.335])),
        method("oe", &rows([-0.128, -0.438, -0.0510, -0.34])),
        method("fem", &rows([-0.133, -0.411, -0.0505, -0.34])),
        method("ekf", &rows([-0.136, -0.405, -0.0507, -0.34])),
    ];
    let c = judge(&own, &others);
    let get = |n: &str| c.parameters.iter().find(|a| a.parameter == n).unwrap();
    assert!(!get("Cl_beta").confirmed);
    let p = get("Cl_p");
    let flag = p.flag.as_deref().unwrap_or_default();
    assert!(flag.contains("regressor noise in the Cl equation (shown on Cl_beta)"), "{p:?}");
    assert!(get("Cl_da").confirmed, "{:?}", get("Cl_da"));
    // Cn_r: IV moves it 10.4 %, but no bias was shown in the Cn equation.
    assert!(get("Cn_r").confirmed, "{:?}", get("Cn_r"));
    assert_eq!(c.flagged, 2);
    // Without the Cl_β evidence no cause is shown, but output error disagrees with rls's
    // Cl_p (2.2 combined σ, 17 %): flagged as unexplained, where a vote confirmed it (3 of 4).
    let lone = judge(
        &method("rls", &[("Cl_p", -0.364, 0.0236)]),
        &others
            .iter()
            .map(|m| {
                method(
                    &m.method,
                    &[("Cl_p", m.get("Cl_p").unwrap().estimate, m.get("Cl_p").unwrap().std_error)],
                )
            })
            .collect::<Vec<_>>(),
    );
    let flag = lone.parameters[0].flag.as_deref().unwrap_or_default();
    assert!(flag.contains("oe disagree with rls"), "{:?}", lone.parameters[0]);
}

/// The default regressor-noise test of least squares: rls Cl_β −0.048 ± 0.005 against
/// instrumental variables' −0.133 ± 0.02 (4.1 combined σ and 64 %) is doubted, with both
/// values; Cl_p −0.40 ± 0.02 against −0.41 ± 0.02 (2.4 %) is not; a parameter IV does not give
/// is not; a failed IV replay doubts nothing.
#[test]
fn least_squares_is_doubted_where_instrumental_variables_move_it() {
    let own =
        method("rls", &[("Cl_beta", -0.048, 0.005), ("Cl_p", -0.40, 0.02), ("Cl_r", 0.1, 0.01)]);
    let iv = method("rls-iv", &[("Cl_beta", -0.133, 0.02), ("Cl_p", -0.41, 0.02)]);
    let w = regressor_noise(&own, &iv);
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].parameter.as_deref(), Some("Cl_beta"));
    assert!(
        w[0].text.starts_with("regressor noise: instrumental variables move rls -0.0480 ± 5.00e-3 to -0.1330 ± 2.00e-2"),
        "{}",
        w[0].text
    );
    assert!(regressor_noise(&own, &MethodEstimates::failed("rls-iv", "no β")).is_empty());
}

fn est(method: &str, estimate: f64, std_error: f64) -> Estimate {
    Estimate { method: method.into(), estimate, std_error }
}

fn agreement(parameter: &str, estimates: Vec<Estimate>, set_aside: &[(&str, &str)]) -> Agreement {
    Agreement {
        parameter: parameter.into(),
        estimates,
        set_aside: set_aside
            .iter()
            .map(|&(m, c)| SetAside { method: m.into(), cause: c.into() })
            .collect(),
        camps: Vec::new(),
        confirmed: false,
        flag: None,
    }
}

/// The bias families: output error in time and frequency share one; instrumental variables,
/// the filter-error method, the EKF and least squares are each their own, and the other
/// equation-error estimators share least squares'.
#[test]
fn every_method_has_its_bias_family() {
    let f = bias_family;
    assert_eq!(
        (f("oe"), f("fdoe")),
        ("output error: process noise", "output error: process noise")
    );
    assert_eq!((f("fem"), f("ekf")), ("filter error", "the EKF's noise model"));
    assert_eq!(
        (f("rls-iv"), f("rls")),
        ("instrumental variables", "equation error: regressor noise")
    );
    assert_eq!((f("ftr"), f("smpe")), (f("rls"), f("rls")));
}

/// The output-error mean is the mean of `oe`, `fem` and `ekf` only (1, 3 → 2, the rls value
/// left out); none of them: `None`.
#[test]
fn the_output_error_mean_is_a_mean_of_those_methods() {
    let all = [est("oe", 1.0, 0.1), est("fem", 3.0, 0.1), est("rls", 100.0, 0.1)];
    assert_eq!(output_error_mean(&all), Some(2.0));
    assert_eq!(output_error_mean(&all[..1]), Some(1.0));
    assert_eq!(output_error_mean(&all[2..]), None);
}

/// Which of least squares and its instruments is set aside, at the edge: instruments exactly
/// as far from the output-error value as least squares (0.5 either side of oe's 1.0) do not
/// move it away, so least squares is set aside for regressor noise; a hair further and the
/// instruments are.
#[test]
fn the_instruments_are_set_aside_only_when_strictly_further() {
    let at = |iv: f64| {
        tested_causes(&[est("oe", 1.0, 0.01), est("rls", 0.5, 0.01), est("rls-iv", iv, 0.01)])
    };
    let equal = at(1.5);
    assert_eq!(equal.len(), 1);
    assert_eq!(equal[0].method, "rls");
    assert!(equal[0].cause.starts_with(REGRESSOR_NOISE), "{equal:?}");
    let further = at(1.500_001);
    assert_eq!(further[0].method, "rls-iv");
    assert!(further[0].cause.starts_with("its instruments"), "{further:?}");
}

/// The equations where a least-squares method was set aside for regressor noise: one entry per
/// coefficient and method, on the first parameter it was shown; another method in the same
/// equation and the same method in another equation each add one; other causes none.
#[test]
fn each_noisy_equation_is_listed_once_per_method() {
    let noise = "regressor noise: instrumental variables move …";
    let first = [
        agreement("Cl_beta", Vec::new(), &[("rls", noise)]),
        agreement("Cl_p", Vec::new(), &[("rls", noise)]),
        agreement("Cl_da", Vec::new(), &[("ftr", noise)]),
        agreement("Cn_r", Vec::new(), &[("rls", noise)]),
        agreement("Cm_q", Vec::new(), &[("rls", "its instruments: …")]),
    ];
    let got = noisy_equations(&first);
    let want = [("Cl", "rls", "Cl_beta"), ("Cl", "ftr", "Cl_da"), ("Cn", "rls", "Cn_r")];
    let want: Vec<(String, String, String)> =
        want.iter().map(|&(c, m, p)| (c.into(), m.into(), p.into())).collect();
    assert_eq!(got, want);
}

/// The shared-bias rule at its edges, regressor noise shown in the Cl equation: instruments
/// that move rls by exactly 10 % of the larger value (10 → 9) do not set it aside, by more
/// (10 → 8, towards oe's 10.5) do; equally far from the output-error value (10 and 8 about 9)
/// is not towards it; 20 → 30 with oe at 40 is.
#[test]
fn the_shared_bias_rule_at_its_edges() {
    let noisy = [("Cl".to_string(), "rls".to_string(), "Cl_beta".to_string())];
    let at = |ls: f64, iv: f64, oe: f64| {
        let a = agreement(
            "Cl_p",
            vec![est("rls", ls, 0.01), est("rls-iv", iv, 0.01), est("oe", oe, 0.01)],
            &[],
        );
        shared_bias(&a, &noisy)
    };
    assert!(at(9.0, 10.0, 10.5).is_none(), "exactly 10 % is not more");
    let s = at(8.0, 10.0, 10.5).unwrap();
    assert!(
        s.method == "rls" && s.cause.contains("in the Cl equation (shown on Cl_beta)"),
        "{s:?}"
    );
    assert!(at(8.0, 10.0, 9.0).is_none(), "as far from oe is not towards it");
    assert!(at(20.0, 30.0, 40.0).is_some());
    let other = agreement(
        "Cn_r",
        vec![est("rls", 8.0, 0.01), est("rls-iv", 10.0, 0.01), est("oe", 10.5, 0.01)],
        &[],
    );
    assert!(shared_bias(&other, &noisy).is_none(), "no bias shown in the Cn equation");
}

/// Camps of mutual agreement, ascending: 1.00 and 1.01 (± 0.01) agree, 2.0 stands alone.
#[test]
fn estimates_that_agree_share_a_camp() {
    let (a, b, c) = (est("oe", 1.0, 0.01), est("fem", 1.01, 0.01), est("ekf", 2.0, 0.01));
    assert_eq!(camps(&[&c, &a, &b]), [vec!["oe".to_string(), "fem".into()], vec!["ekf".into()]]);
}

/// A real UAV's elevator multistep (uav_oat `el_3`, CL_α): rls 2.30 ± 0.47 agrees with
/// rls-iv 1.78 ± 0.60, the EKF 3.42 ± 0.54 and oe 4.66 ± 1.16, which split among themselves
/// (rls-iv against the EKF: 1.64 > 2·0.81; against oe: 2.88 > 2·1.31). Every method that
/// would confirm rls has a rival that rls agrees with too: contested, not confirmed. One
/// confirming method that agrees with every other (fdoe 42.7 ± 26) confirms it again, and a
/// panel without a split is unchanged.
#[test]
fn agreement_with_both_sides_of_a_split_confirms_neither() {
    let split =
        [("rls", 2.30, 0.47), ("rls-iv", 1.78, 0.60), ("ekf", 3.42, 0.54), ("oe", 4.66, 1.16)];
    let rls = panel("rls", &split);
    assert!(!rls.confirmed && rls.set_aside.is_empty(), "{rls:?}");
    let flag = rls.flag.unwrap();
    assert!(flag.contains("every method that confirms rls on Cl_p disagrees"), "{flag}");
    assert!(flag.contains("rls-iv with ekf") && flag.contains("oe with rls-iv"), "{flag}");
    let mut wide = split.to_vec();
    wide.push(("fdoe", 42.7, 26.0));
    assert!(panel("rls", &wide).confirmed);
    let calm = [("rls", 2.30, 0.47), ("rls-iv", 2.0, 0.60), ("ekf", 2.6, 0.54), ("oe", 2.9, 1.16)];
    assert!(panel("rls", &calm).confirmed);
}
