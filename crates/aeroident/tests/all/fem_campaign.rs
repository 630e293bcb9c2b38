//! The batch filter-error estimator (`[[estimator]] kind = "fem"`) in the closed-loop `run`
//! experiment (crates/pipelines/src/aircraft/batch.rs).

use aeroident_pipelines::aircraft::Scenario;
use aeroident_pipelines::aircraft::experiment::run;
use aeroident_pipelines::aircraft::summary::summarize;
use std::path::PathBuf;

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The short Monte Carlo scenario (10 s, sensor noise, light turbulence) with FEM and OE: the
/// filter-error fit converges on the unsmoothed samples, estimates process noise on V, α, β
/// (positive, finite σ), its innovations on α and β are within a factor 2 of the vane noise
/// (0.1°; the filter follows the gusts, so they are neither the turbulence-driven output error
/// nor far below the sensor noise), and every primary derivative is within 15 % of the
/// reference F-16's true local derivative.
#[test]
fn fem_in_a_turbulent_run_converges_with_process_noise_on_the_air_data_states() {
    let text = std::fs::read_to_string(workspace().join("scenarios/montecarlo/short.toml"))
        .expect("scenarios/montecarlo/short.toml");
    let sc = Scenario::from_toml(
        &format!("{text}\n[[estimator]]\nkind = \"fem\"\nmodel = \"six-axis\"\n"),
        "<test>",
    )
    .unwrap();
    let out = run(&sc).unwrap();
    let ch = out.channels.iter().find(|c| c.label == "fem").unwrap();
    assert!(ch.failure.is_none(), "{:?}", ch.failure);
    assert_eq!(ch.status, Some("converged"));
    let fit = ch.batch.as_ref().expect("batch log");
    let names: Vec<&str> = fit.process_noise.iter().map(|n| n.state.as_str()).collect();
    assert_eq!(names, ["vt_mps", "alpha_rad", "beta_rad"]);
    for n in &fit.process_noise {
        let (f, s) = (n.f, n.std_error.unwrap());
        assert!(f > 0.0 && f.is_finite() && s > 0.0 && s.is_finite(), "{}: F {f} σ {s}", n.state);
    }
    let vane = 0.1_f64.to_radians();
    for (name, rms) in fit.outputs.iter().zip(&fit.residual_rms) {
        if name == "alpha_rad" || name == "beta_rad" {
            assert!((0.5 * vane..2.0 * vane).contains(rms), "{name}: innovation rms {rms}");
        }
    }
    // FEM reports the coloured-residual σ where formed, else the Cramér–Rao one
    // (docs/uncertainty.md, "Filter-error method: σ and bias").
    let cand = |k: &str| fit.sigma_candidates.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
    let expected = if fit.coloured_sigma {
        cand("coloured").or_else(|| cand("coloured_theta")).expect("coloured σ")
    } else {
        cand("cramer_rao").expect("Cramér–Rao σ")
    };
    let s = summarize(&out).unwrap();
    let reported: Vec<f64> =
        s.parameters.iter().filter(|p| p.estimator == "fem").filter_map(|p| p.std_error).collect();
    assert_eq!(reported, expected, "the reported σ is the coloured candidate where formed");
    for p in s.parameters.iter().filter(|p| p.primary && p.estimator == "fem") {
        let (f, t) = (p.estimate.unwrap(), p.reference.unwrap());
        assert!(((f - t) / t).abs() < 0.15, "{}: {f} vs truth {t}", p.name);
    }
}

/// Options of the `fem` entry are checked when the scenario is read, naming the field.
#[test]
fn fem_options_are_checked() {
    let base = "kind = \"run\"\nname = \"x\"\nduration_s = 1.0\n[[estimator]]\nkind = \"fem\"\nmodel = \"six-axis\"\n";
    let e = Scenario::from_toml(&format!("{base}process_noise = \"alpha,gamma\"\n"), "<t>")
        .unwrap_err();
    assert!(e.to_string().contains("gamma"), "{e}");
    let e = Scenario::from_toml(&format!("{base}samples = \"filtered\"\n"), "<t>").unwrap_err();
    assert!(e.to_string().contains("samples"), "{e}");
    let e = Scenario::from_toml(&format!("{base}step = \"concentrated\"\n"), "<t>").unwrap_err();
    assert!(e.to_string().contains("step"), "{e}");
    assert!(
        Scenario::from_toml(&format!("{base}process_noise = \"alpha, beta\"\n"), "<t>").is_ok()
    );
    assert!(Scenario::from_toml(&format!("{base}samples = \"smoothed\"\n"), "<t>").is_ok());
    let sc = Scenario::from_path(&workspace().join("scenarios/montecarlo/with-fem.toml")).unwrap();
    assert!(sc.estimator.iter().any(|e| e.label() == "fem"));
    assert!(sc.estimator.iter().any(|e| e.label() == "oe"));
}
