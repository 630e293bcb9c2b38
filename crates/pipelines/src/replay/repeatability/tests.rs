use super::*;
use crate::replay::cross_check::ParameterEstimate;

fn v(manoeuvre: usize, estimate: f64, std_error: f64) -> ManoeuvreValue {
    ManoeuvreValue { manoeuvre, estimate, std_error }
}

/// Two manoeuvres of equal σ 0.1: 1.0 and 1.3 give θ̄ 1.15, χ² = 2·1.5² = 4.5 on 1 dof,
/// p = erfc(√2.25) = 0.0339 (repeats at 1 %); 1.0 and 1.5 give χ² 12.5, p = erfc(2.5) =
/// 4.07e-4 (does not), and the spread σ is then half their difference, 0.25.
#[test]
fn two_manoeuvres_against_the_analytic_chi_squared() {
    let near = Repeat::of("Cm_q", vec![v(0, 1.0, 0.1), v(1, 1.3, 0.1)]).unwrap();
    assert!((near.weighted_mean - 1.15).abs() < 1e-12);
    assert!((near.chi2 - 4.5).abs() < 1e-9 && near.dof == 1);
    assert!((near.p_value - 0.033_895).abs() < 1e-5, "{}", near.p_value);
    assert!(near.repeats);
    let far = Repeat::of("Cm_q", vec![v(0, 1.0, 0.1), v(1, 1.5, 0.1)]).unwrap();
    assert!((far.chi2 - 12.5).abs() < 1e-9);
    assert!((far.p_value - 4.0695e-4).abs() < 1e-7, "{}", far.p_value);
    assert!(!far.repeats);
    assert!((far.spread_sigma() - 0.25).abs() < 1e-12);
    // χ² 4.5 scales 0.1/√2 by √4.5: half the difference again; agreeing values keep the
    // weighted mean's own σ (the ratio is not scaled below 1).
    assert!((near.spread_sigma() - 0.15).abs() < 1e-12);
    let same = Repeat::of("x", vec![v(0, 1.0, 0.1), v(1, 1.0, 0.1)]).unwrap();
    assert!((same.spread_sigma() - 0.1 / 2f64.sqrt()).abs() < 1e-12);
    assert!(Repeat::of("x", vec![v(0, 1.0, 0.1)]).is_none());
    // Three manoeuvres of σ 1 at 0, 3 and 6: θ̄ 3, χ² 18 on 2 dof, Birge ratio √9 = 3, the
    // mean's own σ 1/√3 scaled to √3.
    let three = Repeat::of("x", vec![v(0, 0.0, 1.0), v(1, 3.0, 1.0), v(2, 6.0, 1.0)]).unwrap();
    assert!((three.chi2 - 18.0).abs() < 1e-12 && three.dof == 2);
    assert!((three.spread_sigma() - 3f64.sqrt()).abs() < 1e-12, "{}", three.spread_sigma());
    assert!(far.note().contains("#1 1.0000 ± 1.00e-1, #2 1.5000 ± 1.00e-1"), "{}", far.note());
}

/// Values drawn from one truth with their σ (three manoeuvres, σ 0.05, 0.1 and 0.2): over
/// 4000 draws the test flags 1 % of them (binomial 3σ: 0.53–1.47 %); with the third
/// manoeuvre's value 4σ off it flags most.
#[test]
fn the_false_alarm_rate_is_the_significance() {
    let sigmas = [0.05, 0.1, 0.2];
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut normal = || {
        // Box–Muller on a xorshift generator: a test needs no dependency for this.
        let mut u = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (a, b) = (u().max(1e-300), u());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    };
    let (n, mut flagged, mut shifted) = (4000, 0, 0);
    for _ in 0..n {
        let draws: Vec<f64> = sigmas.iter().map(|s| -1.0 + s * normal()).collect();
        let values = |off: f64| {
            (0..3).map(|k| v(k, draws[k] + if k == 2 { off } else { 0.0 }, sigmas[k])).collect()
        };
        flagged += usize::from(!Repeat::of("Cm_alpha", values(0.0)).unwrap().repeats);
        shifted += usize::from(!Repeat::of("Cm_alpha", values(0.8)).unwrap().repeats);
    }
    let rate = flagged as f64 / n as f64;
    assert!((0.0053..=0.0147).contains(&rate), "false alarms {rate}");
    assert!(shifted as f64 / n as f64 > 0.8, "detections {shifted}");
}

/// Only converged solo fits whose σ is at most |estimate| take part: a manoeuvre that leaves
/// the parameter undetermined, or did not converge, is left out, and one manoeuvre left is no
/// test; the warnings name the parameter that does not repeat and the fits left out.
#[test]
fn only_the_manoeuvres_that_determine_a_parameter_are_compared() {
    let fit = |k: usize, status: &str, rows: &[(&str, f64, f64)]| SoloFit {
        manoeuvre: k,
        t_start_s: 10.0 * k as f64,
        t_end_s: 10.0 * k as f64 + 8.0,
        samples: 400,
        status: status.into(),
        estimates: rows.iter().map(|&(n, e, s)| ParameterEstimate::new(n, e, s)).collect(),
    };
    let fits = vec![
        fit(0, "converged", &[("Cm_q", -10.0, 0.5), ("Cl_p", -0.4, 0.01)]),
        fit(1, "converged", &[("Cm_q", -16.0, 0.5), ("Cl_p", 0.2, 0.5)]),
        fit(2, "not converged", &[("Cm_q", -40.0, 0.5), ("Cl_p", -0.41, 0.01)]),
        fit(3, "failed: too short", &[]),
    ];
    let names = ["Cm_q".to_string(), "Cl_p".to_string()];
    let r = Repeatability::assess(fits, &names);
    assert_eq!(r.parameters.len(), 1, "Cl_p has one determining manoeuvre: {r:?}");
    let cm_q = r.failed("Cm_q").unwrap();
    assert_eq!(cm_q.values.iter().map(|v| v.manoeuvre).collect::<Vec<_>>(), [0, 1]);
    assert!(r.failed("Cl_p").is_none());
    let w = r.warnings();
    assert_eq!(w.len(), 2);
    assert!(
        w[0].text.starts_with("Cm_q: does not repeat across manoeuvres to their σ: #1 -10.0000")
    );
    assert_eq!(w[0].parameter, None, "a note, not a flag");
    assert!(w[1].text.contains("#3 (not converged), #4 (failed: too short)"), "{}", w[1].text);
}

/// Both thresholds at their edge. Significance: two values of σ 0.1 apart by Δ give
/// χ² = Δ²/0.02 on 1 dof, whose 1 % point is 6.6349 (tables): Δ = 0.3640 (χ² 6.625) repeats,
/// Δ = 0.3650 (χ² 6.661) does not. Determination: a manoeuvre whose σ equals |estimate| takes
/// part, one whose σ is 1 % larger does not.
#[test]
fn the_thresholds_at_their_edge() {
    let pair = |d: f64| Repeat::of("Cm_q", vec![v(0, -1.0, 0.1), v(1, -1.0 + d, 0.1)]).unwrap();
    let (inside, outside) = (pair(0.3640), pair(0.3650));
    assert!(inside.repeats && inside.p_value > SIGNIFICANCE, "{inside:?}");
    assert!(!outside.repeats && outside.p_value < SIGNIFICANCE, "{outside:?}");
    let fit = |k: usize, e: f64, s: f64| SoloFit {
        manoeuvre: k,
        t_start_s: 0.0,
        t_end_s: 1.0,
        samples: 100,
        status: CONVERGED.into(),
        estimates: vec![ParameterEstimate::new("Cm_q", e, s)],
    };
    let names = ["Cm_q".to_string()];
    let at = Repeatability::assess(vec![fit(0, -1.0, 0.1), fit(1, -0.9, 0.9)], &names);
    assert_eq!(at.parameters[0].values.len(), 2, "σ = |estimate| takes part");
    let beyond = Repeatability::assess(vec![fit(0, -1.0, 0.1), fit(1, -0.9, 0.909)], &names);
    assert!(beyond.parameters.is_empty(), "σ above |estimate| leaves one manoeuvre: no test");
}
