//! Model structure determination on real records (../shared/flightdata; skipped with a
//! message when absent, a failure under CI), against what NASA SIDPAC's `swr` and `offit`
//! keep on the same records: the Twin Otter's pitching moment and normal force need α² beside
//! α, q̂ and δe; the HFB-320's (Jategaonkar 2015 test case 4) need V/V0 beside α, q̂ and δe,
//! the book's structure.

use crate::common;
use aeroident_estimators::structure::{Ranking, StepwiseConfig};
use aeroident_estimators::{Coefficient, Term};
use aeroident_io::{Mapping, open_log};
use aeroident_pipelines::structure::{AutoModel, Method, Scope, select_model, select_structure};
use common::{shared, workspace};

const SWR: Method = Method::Stepwise(StepwiseConfig { f_in: 20.0, f_out: 20.0 });
const MOF: Method = Method::Orthogonal(Ranking::Generation);

/// The kept terms of each of `coefficients`, or `None` when the record is absent.
fn kept(
    rel: &str,
    mapping: &str,
    coefficients: &[Coefficient],
    candidates: &[Term],
    method: Method,
) -> Option<Vec<Vec<&'static str>>> {
    let data = shared(rel)?;
    let m = Mapping::from_path(&workspace().join("mappings").join(mapping)).unwrap();
    let reader = open_log(&data.display().to_string(), None, &m).unwrap();
    let selections = select_structure(reader, coefficients, candidates, method).unwrap();
    Some(
        selections
            .iter()
            .map(|s| {
                eprintln!(
                    "{rel} {} {}: {}",
                    method.name(),
                    s.coefficient.name(),
                    s.selection.stopped
                );
                s.kept().iter().map(|t| t.name()).collect()
            })
            .collect(),
    )
}

/// Twin Otter 018 with candidates α, q̂, δe, α², α·δe: stepwise regression keeps α, q̂, δe, α²
/// for Cm (partial F of α·δe 12.3 < 20) and for CZ. (Orthogonal functions keep α, q̂, δe for
/// Cm: α² lowers the PSE less than its penalty on this record.)
#[test]
fn val_twin_otter_018_keeps_alpha_q_de_alpha2() {
    let candidates = [Term::Alpha, Term::Q, Term::De, Term::Alpha2, Term::AlphaDe];
    let Some(sel) = kept(
        "sidpac_twin_otter/csv/totter_lon_020213f1_018.csv",
        "twin_otter.toml",
        &[Coefficient::Cm, Coefficient::CZ],
        &candidates,
        SWR,
    ) else {
        return;
    };
    for s in sel {
        assert_eq!(s, ["alpha", "q", "de", "alpha2"]);
    }
}

/// HFB-320 (hfb320_1_10) with candidates α, q̂, δe, V/V0, α², α·δe: stepwise regression keeps
/// α, q̂, δe, V for the lift (CL and CZ) and, with α² offered only once α is in (the record's
/// α spans 0.086–0.126 rad, where the two are 0.9988 correlated), for Cm too; orthogonal
/// functions keep the same for Cm.
#[test]
fn val_hfb320_keeps_alpha_q_de_v() {
    let candidates = [Term::Alpha, Term::Q, Term::De, Term::V, Term::Alpha2, Term::AlphaDe];
    let rel = "jategaonkar_hfb320_attas/csv/hfb320_1_10.csv";
    let Some(lift) =
        kept(rel, "hfb320.toml", &[Coefficient::CL, Coefficient::CZ], &candidates, SWR)
    else {
        return;
    };
    for s in lift {
        assert_eq!(s, ["alpha", "q", "de", "V"]);
    }
    let pitch = kept(rel, "hfb320.toml", &[Coefficient::Cm], &candidates, MOF).unwrap();
    assert_eq!(pitch[0], ["alpha", "q", "de", "V"]);
    let pitch = kept(rel, "hfb320.toml", &[Coefficient::Cm], &candidates, SWR).unwrap();
    assert_eq!(pitch[0], ["alpha", "q", "de", "V"]);
}

fn bin() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_aeroident"))
}

/// `replay DATA --map mappings/MAP ARGS --out DIR` through the binary: asserts success;
/// returns `summary.json` and, when written (`--model auto`), `model.toml` read back as a model
/// file, and whether stderr printed a selection path.
fn replay_out(
    data: &std::path::Path,
    map: &str,
    args: &[&str],
    name: &str,
) -> (serde_json::Value, Option<aeroident_io::ModelSpec>, bool) {
    let out =
        std::env::temp_dir().join(format!("aeroident-structure-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let o = bin()
        .arg("replay")
        .arg(data)
        .arg("--map")
        .arg(workspace().join("mappings").join(map))
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{name}: {stderr}");
    let summary =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let model_file = out.join("model.toml");
    let model =
        model_file.exists().then(|| aeroident_io::ModelSpec::from_path(&model_file).unwrap());
    let _ = std::fs::remove_dir_all(&out);
    (summary, model, stderr.contains("structure: "))
}

/// [`replay_out`] of a `--model auto` run: the selection path was printed and the model saved.
fn auto_replay(
    data: &std::path::Path,
    map: &str,
    args: &[&str],
    name: &str,
) -> (serde_json::Value, aeroident_io::ModelSpec) {
    let (summary, model, printed) = replay_out(data, map, args, name);
    assert!(printed, "{name}: the selection path is printed on stderr");
    (summary, model.expect("model.toml written"))
}

/// `f16 sim scenarios/sim/SCENARIO --out DIR/sim` through the binary, in a fresh temporary
/// `DIR` (returned) named after `name`.
fn simulate(scenario: &str, name: &str) -> std::path::PathBuf {
    let out = std::env::temp_dir().join(format!("aeroident-f16-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let sim = bin()
        .args(["f16", "sim"])
        .arg(workspace().join("scenarios/sim").join(scenario))
        .arg("--out")
        .arg(out.join("sim"))
        .output()
        .unwrap();
    assert!(sim.status.success(), "{}", String::from_utf8_lossy(&sim.stderr));
    out
}

/// One coefficient's entry of `structure_selection`.
fn selected<'a>(summary: &'a serde_json::Value, coefficient: &str) -> &'a serde_json::Value {
    summary["structure_selection"]["coefficients"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["coefficient"] == coefficient)
        .unwrap_or_else(|| panic!("{coefficient} not selected"))
}

fn strings(v: &serde_json::Value) -> Vec<&str> {
    v.as_array().unwrap().iter().map(|s| s.as_str().unwrap()).collect()
}

fn sigma(summary: &serde_json::Value, name: &str) -> f64 {
    let p = summary["parameters"].as_array().unwrap().iter().find(|p| p["name"] == name);
    p.unwrap_or_else(|| panic!("{name} not estimated"))["std_error"].as_f64().unwrap()
}

/// The σ of `name` without its unmodelled share: the noise and timing σ, which the bias of a
/// missing term is measured against.
fn noise_sigma(summary: &serde_json::Value, name: &str) -> f64 {
    let p = summary["parameters"].as_array().unwrap().iter().find(|p| p["name"] == name);
    let u = p.unwrap()["unmodelled_std_error"].as_f64().unwrap_or(0.0);
    (sigma(summary, name).powi(2) - u * u).sqrt()
}

fn estimate(summary: &serde_json::Value, name: &str) -> f64 {
    let p = summary["parameters"].as_array().unwrap().iter().find(|p| p["name"] == name);
    p.unwrap_or_else(|| panic!("{name} not estimated"))["estimate"].as_f64().unwrap()
}

/// c172x (JSBSim, whose model has Cm_adothat −5.14 beside Cm_qhat −12.27): with α̇ among the
/// candidates `--model auto` keeps it for Cm, and every estimator then puts Cm_q within 20 % of
/// JSBSim's own value (the truth file's finite differences), where the longitudinal preset
/// reports the sum −17.3 under the name Cm_q (`replay_records.rs`). The saved model file holds
/// the structure that was fitted.
#[test]
fn val_c172x_auto_selects_alphadot_and_brings_cm_q_within_20_percent() {
    let Some(data) = shared("jsbsim_samples/c172x_elevator_3211_15s_60Hz.csv") else { return };
    let truth_file = data.with_file_name("c172x_elevator_3211_truth.json");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(truth_file).unwrap()).unwrap();
    let cm_q = truth["derivatives"]["Cm_qhat"].as_f64().unwrap();
    let candidates = "alpha,q,alphadot,de,V,alpha2,alpha_de";
    for est in ["rls", "ekf", "oe"] {
        let args = ["--model", "auto:longitudinal", "--candidates", candidates, "--estimator", est];
        let (s, model) = auto_replay(&data, "jsbsim_clean.toml", &args, est);
        let cm = selected(&s, "Cm");
        assert!(strings(&cm["kept"]).contains(&"alphadot"), "{est}: {cm}");
        assert_eq!(strings(&cm["candidates"]).len(), 6, "V needs v0, unmapped: {cm}");
        assert_eq!(strings(&s["structure_selection"]["unavailable"]), ["V"]);
        let fitted: Vec<&str> = s["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p["name"].as_str().unwrap())
            .collect();
        assert_eq!(fitted, model.structure.names().collect::<Vec<_>>(), "{est}");
        let q = estimate(&s, "Cm_q");
        assert!((q - cm_q).abs() < 0.2 * cm_q.abs(), "{est}: Cm_q {q} vs JSBSim {cm_q}");
    }
}

/// The same record with the default candidates: without a compatibility check α̇ is not
/// offered and the selection says why; with `--compat auto` (which times α against the
/// kinematics) it is offered to CL and Cm, Cm keeps it, and output error's Cm_q is within
/// 20 % of JSBSim's (measured: −12.38 against −12.27).
#[test]
fn val_c172x_alphadot_is_offered_once_alpha_is_timed() {
    let Some(data) = shared("jsbsim_samples/c172x_elevator_3211_15s_60Hz.csv") else { return };
    let truth_file = data.with_file_name("c172x_elevator_3211_truth.json");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(truth_file).unwrap()).unwrap();
    let cm_q = truth["derivatives"]["Cm_qhat"].as_f64().unwrap();
    let plain = ["--model", "auto:longitudinal", "--estimator", "rls"];
    let (s, _) = auto_replay(&data, "jsbsim_clean.toml", &plain, "c172-untimed");
    let note = s["structure_selection"]["alphadot"].as_str().unwrap();
    assert!(note.starts_with("alphadot not offered") && note.contains("--compat auto"), "{note}");
    assert!(!strings(&selected(&s, "Cm")["candidates"]).contains(&"alphadot"));
    let timed = ["--model", "auto:longitudinal", "--compat", "auto", "--estimator", "oe"];
    let (s, _) = auto_replay(&data, "jsbsim_clean.toml", &timed, "c172-timed");
    let note = s["structure_selection"]["alphadot"].as_str().unwrap();
    assert!(note.starts_with("alphadot offered"), "{note}");
    assert!(strings(&selected(&s, "Cm")["kept"]).contains(&"alphadot"), "{}", selected(&s, "Cm"));
    let q = estimate(&s, "Cm_q");
    assert!((q - cm_q).abs() < 0.2 * cm_q.abs(), "Cm_q {q} vs JSBSim {cm_q}");
    // Each candidate is kept or left out with its reason; stepwise stopped, so no term that
    // was offered would pass the cut-off against the final model.
    for c in s["structure_selection"]["coefficients"].as_array().unwrap() {
        let left = c["left_out"].as_array().unwrap();
        let mut all: Vec<&str> = strings(&c["kept"]);
        all.extend(left.iter().map(|l| l["term"].as_str().unwrap()));
        all.sort_unstable();
        let mut offered = strings(&c["candidates"]);
        offered.sort_unstable();
        assert_eq!(all, offered, "{c}");
        for l in left.iter().filter(|l| l.get("waiting_for").is_none()) {
            assert!(l["partial_f"].as_f64().is_none_or(|f| f <= 20.0), "{l}");
        }
    }
}

/// Twin Otter 018 (SIDPAC), `--model auto --estimator oe --validate-on 019`: the default
/// candidates select SIDPAC's Cm structure (α, q̂, δe, α²; α·δe at partial F 12.3 stays
/// out) and leave α̇ out unless asked; the selected model, fitted by output error on 018,
/// predicts manoeuvre 019 at least as well as the longitudinal preset does (α, q and az fit
/// within 1 point of it or better).
#[test]
fn val_twin_otter_auto_structure_validates_on_another_manoeuvre() {
    let Some(data) = shared("sidpac_twin_otter/csv/totter_lon_020213f1_018.csv") else { return };
    let other = data.with_file_name("totter_lon_020213f1_019.csv");
    let other = other.to_str().unwrap();
    let fit = |model: &str| {
        let args = ["--model", model, "--estimator", "oe", "--validate-on", other];
        replay_out(&data, "twin_otter.toml", &args, model).0
    };
    let auto = fit("auto");
    let cm = selected(&auto, "Cm");
    assert_eq!(strings(&cm["kept"]), ["alpha", "q", "de", "alpha2"], "{cm}");
    assert!(!strings(&cm["candidates"]).contains(&"alphadot"));
    assert_eq!(auto["structure_selection"]["scope"], "longitudinal");
    let preset = fit("longitudinal");
    let fit_percent = |s: &serde_json::Value, output: &str| {
        let outputs = s["validation_on"]["outputs"].as_array().unwrap();
        let o = outputs.iter().find(|o| o["name"] == output).unwrap();
        o["fit_percent"].as_f64().unwrap()
    };
    for output in ["alpha_rad", "q_rad_s", "az_mps2"] {
        let (a, p) = (fit_percent(&auto, output), fit_percent(&preset, output));
        assert!(a > p - 1.0, "{output}: selected structure {a} % vs preset {p} % on 019");
    }
}

/// `--model auto` needs the whole record and a known scope; `--select`/`--candidates` need
/// `--model auto`; a candidate must be a vocabulary term other than the constant.
#[test]
fn errors_model_auto_arguments() {
    let map = workspace().join("mappings/twin_otter.toml");
    let data = workspace().join("examples/data/does-not-matter.csv");
    let run = |args: &[&str]| {
        let o = bin().arg("replay").args(args).arg("--map").arg(&map).output().unwrap();
        assert!(!o.status.success(), "{args:?} succeeded");
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let d = data.to_str().unwrap();
    assert!(run(&["-", "--model", "auto"]).contains("whole record"));
    assert!(run(&[d, "--model", "auto:pitch"]).contains("auto:longitudinal"));
    let e = run(&[d, "--model", "longitudinal", "--select", "mof"]);
    assert!(e.contains("option `--select`") && e.contains("`auto`"), "{e}");
    let e = run(&[d, "--model", "auto", "--candidates", "alpha,bogus"]);
    assert!(e.contains("`bogus`"), "{e}");
    assert!(run(&[d, "--model", "auto", "--candidates", "0"]).contains("`0`"));
    let e = run(&[d, "--model", "longitudinal", "--knots-deg", "5"]);
    assert!(e.contains("knots") && e.contains("`auto`"), "{e}");
    let e = run(&[d, "--model", "auto", "--knots-deg", "5,3"]);
    assert!(e.contains("α knots") && e.contains("ascending"), "{e}");
}

/// A scope the record cannot measure says what the mapping lacks: the HFB-320 record is
/// longitudinal (no lateral rates nor inertias mapped).
#[test]
fn val_model_auto_lateral_on_a_longitudinal_record_names_what_is_missing() {
    let Some(data) = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let map = workspace().join("mappings/hfb320.toml");
    let o = bin()
        .arg("replay")
        .arg(&data)
        .arg("--map")
        .arg(&map)
        .args(["--model", "auto:lateral"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(e.contains("does not measure it") && e.contains("span b"), "{e}");
}

/// `--model auto:six-axis` on the shipped flight of the default main job
/// (`scenarios/sim/default_excitation_measured.toml` read through
/// `mappings/aeroident-sim-measured.toml`), judged against the structure of the Stevens & Lewis
/// tables the simulator flies (2nd ed., Appendix A): every coefficient keeps the terms the
/// tables give a first-order effect at trim (CL, Cm: α, q̂, δe; CY: β, δa, δr; Cl: β, p̂, r̂,
/// δa, δr; Cn: β, r̂, δa, δr), and `Cl` keeps `alpha_beta` (the tables' Cl_β varies with α).
/// The shipped `models/f16_default_selected.toml` is then checked to be that selection (it is
/// regenerated from it; the physics above is what validates it).
#[test]
fn val_f16_default_flight_selects_the_tables_structure() {
    let out = simulate("default_excitation_measured.toml", "select");
    let args = ["--model", "auto:six-axis", "--estimator", "rls"];
    let (s, model) =
        auto_replay(&out.join("sim/timeseries.csv"), "aeroident-sim-measured.toml", &args, "f16");
    let tables: [(&str, &[&str]); 6] = [
        ("CL", &["alpha", "q", "de"]),
        ("Cm", &["alpha", "q", "de"]),
        ("CY", &["beta", "da", "dr"]),
        ("Cl", &["beta", "p", "r", "da", "dr", "alpha_beta"]),
        ("Cn", &["beta", "r", "da", "dr"]),
        ("CD", &["alpha"]),
    ];
    for (coefficient, terms) in tables {
        let kept = strings(&selected(&s, coefficient)["kept"]);
        for t in terms {
            assert!(kept.contains(t), "{coefficient} lacks {t}: {kept:?}");
        }
    }
    let shipped =
        aeroident_io::ModelSpec::from_path(&workspace().join("models/f16_default_selected.toml"))
            .unwrap();
    assert_eq!(model.structure, shipped.structure, "regenerate models/f16_default_selected.toml");
    let _ = std::fs::remove_dir_all(&out);
}

/// An F-16 flight whose α crosses the tables' 5° breakpoint
/// (`scenarios/sim/breakpoint_crossing_measured.toml`, 3.3–9.2°, sensor noise, turbulence).
/// `--knots-deg 5` offers `alpha_k1` at that knot to the longitudinal coefficients. With the
/// spline in the model (`models/f16_breakpoint_spline.toml`), RLS puts `Cm_alpha` (the slope
/// below the knot) and `Cm_alpha_k1` (the slope's jump there) within 3σ (the noise σ, without
/// the unmodelled share) of the tables' own
/// values (`aircraft::truth`, finite differences each side of the breakpoint: −0.138 and
/// −0.051). The preset's single `Cm_alpha` misses the local slope at the trim by more than
/// 3σ: its σ does not show the structure's bias.
#[test]
fn val_f16_spline_at_a_table_breakpoint() {
    use aeroident_estimators::vocabulary::{AlphaKnots, ModelStructure, Param};
    use aeroident_models::f16::{AeroIncrements, F16};
    use aeroident_models::trim::{TrimCondition, trim};
    let out = simulate("breakpoint_crossing_measured.toml", "spline");
    let data = out.join("sim/timeseries.csv");
    let map = "aeroident-sim-measured.toml";
    let args = ["--model", "auto:longitudinal", "--knots-deg", "5"];
    let (s, _) = auto_replay(&data, map, &args, "f16-knots");
    assert_eq!(s["structure_selection"]["alpha_knots_deg"][0].as_f64(), Some(5.0));
    assert!(strings(&selected(&s, "Cm")["candidates"]).contains(&"alpha_k1"));

    let f16 = F16::new(0.30).unwrap();
    let t = trim(&f16, &TrimCondition::level(20_000.0, 480.0)).unwrap();
    let ld = aeroident_pipelines::aircraft::truth::local_derivatives(
        &f16,
        &t.state,
        &t.controls,
        &AeroIncrements::zero(),
    )
    .unwrap();
    let spline_model = workspace().join("models/f16_breakpoint_spline.toml");
    let (s, ..) = replay_out(&data, map, &["--model", spline_model.to_str().unwrap()], "spline");
    let st = ModelStructure::longitudinal()
        .with(Coefficient::Cm, &[Term::AlphaK1])
        .with_knots(AlphaKnots::new(&[5f64.to_radians()]).unwrap());
    for name in ["Cm_alpha", "Cm_alpha_k1"] {
        let truth = ld.truth(&st, Param::from_name(name).unwrap()).unwrap();
        let (e, sd) = (estimate(&s, name), noise_sigma(&s, name));
        eprintln!("{name}: {e:.4} ± {sd:.4}, truth {truth:.4}");
        assert!((e - truth).abs() < 3.0 * sd, "{name}: {e} ± {sd} vs truth {truth}");
    }
    let (s, ..) = replay_out(&data, map, &["--model", "longitudinal"], "preset");
    let local = ld.derivative(Param::from_name("Cm_alpha").unwrap()).unwrap();
    let (e, sd) = (estimate(&s, "Cm_alpha"), noise_sigma(&s, "Cm_alpha"));
    eprintln!("preset Cm_alpha: {e:.4} ± {sd:.4}, local truth {local:.4}");
    assert!((e - local).abs() > 3.0 * sd, "the preset's Cm_alpha {e} ± {sd} vs {local}");
    let _ = std::fs::remove_dir_all(&out);
}

/// The structure campaigns fly the default main job: everything but their estimators is
/// `scenarios/default.toml`'s, and the model files they name load.
#[test]
fn structure_campaigns_fly_the_default_scenario() {
    use aeroident_pipelines::aircraft::scenario::Scenario;
    let load =
        |p: &str| Scenario::from_path(&workspace().join(p)).unwrap_or_else(|e| panic!("{p}: {e}"));
    let default = load("scenarios/default.toml");
    for path in
        ["scenarios/montecarlo/with-selected.toml", "scenarios/montecarlo/with-alpha-products.toml"]
    {
        let mut sc = load(path);
        assert!(sc.estimator.len() >= 2, "{path}");
        sc.name = default.name.clone();
        sc.description = default.description.clone();
        sc.estimator = default.estimator.clone();
        assert_eq!(sc, default, "{path} flies another experiment than scenarios/default.toml");
    }
}

/// A selection on too few samples for its candidates warns, in the path printed and in
/// `structure_selection.warnings`: the HFB-320 record's first 20 rows (under 10 samples per
/// term of CL's regression on α, q̂ and the constant) warn; the whole record (601 rows) does
/// not.
#[test]
fn a_selection_on_few_samples_warns() {
    use aeroident_pipelines::structure::{AutoModel, SAMPLES_PER_TERM, select_model};
    let Some(data) = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv") else { return };
    let m = Mapping::from_path(&workspace().join("mappings/hfb320.toml")).unwrap();
    let text = std::fs::read_to_string(&data).unwrap();
    let short = std::env::temp_dir().join(format!("aeroident-few-{}.csv", std::process::id()));
    let head: Vec<&str> = text.lines().take(21).collect();
    std::fs::write(&short, head.join("\n") + "\n").unwrap();
    let auto = AutoModel::from_args("auto:longitudinal", "swr", &["alpha".into(), "q".into()]);
    let auto = auto.unwrap().unwrap();
    for (file, warned) in [(&short, true), (&data, false)] {
        let reader = open_log(&file.display().to_string(), None, &m).unwrap();
        let s = select_model(vec![reader], &m, &auto, None, &[], 5).unwrap();
        assert_eq!(s.samples_used < 3 * SAMPLES_PER_TERM, warned, "{} samples", s.samples_used);
        let w = s.report().warnings;
        assert_eq!(w.len(), usize::from(warned), "{w:?}");
        let printed =
            s.path_lines().iter().any(|l| l.starts_with("warning: structure selection on"));
        assert_eq!(printed, warned);
        if warned {
            assert!(w[0].contains(&format!("on {} samples for up to 3 terms", s.samples_used)));
        }
    }
    std::fs::remove_file(&short).ok();
}

/// The scope plain `--model auto` settles on, or `None` when the record is absent.
fn auto_scope(rel: &str, mapping: &str) -> Option<(Scope, Option<String>)> {
    let data = shared(rel)?;
    let m = Mapping::from_path(&workspace().join("mappings").join(mapping)).unwrap();
    let reader = open_log(&data.display().to_string(), None, &m).unwrap();
    let auto = AutoModel::parse("auto", SWR).unwrap().unwrap();
    let s = select_model(vec![reader], &m, &auto, None, &[], 5).unwrap();
    Some((s.scope, s.scope_reason))
}

/// Plain `--model auto` fits the axes a record excites, on records whose inputs are known:
/// JSBSim's c172x flown with an elevator 3-2-1-1 alone (ailerons and rudder held) is
/// longitudinal, its F-16 flown with aileron and rudder doublets alone (elevator held) is
/// lateral, each with the partial F of the idle surfaces in the reason; the ATTAS lateral
/// mapping (no `q`) is lateral, where it used to be taken for longitudinal and refused.
#[test]
fn val_model_auto_fits_the_axes_the_record_excites() {
    let Some((c172, why)) =
        auto_scope("jsbsim_samples/c172x_elevator_3211_15s_60Hz.csv", "jsbsim.toml")
    else {
        return;
    };
    assert_eq!(c172, Scope::Longitudinal);
    let why = why.unwrap();
    assert!(
        why.contains("Cl: da") && why.contains("Cn: da") && why.contains("auto:six-axis"),
        "{why}"
    );
    let (f16, why) =
        auto_scope("jsbsim_samples/f16_ail_rud_doublets_20s_60Hz.csv", "jsbsim.toml").unwrap();
    assert_eq!(f16, Scope::Lateral);
    assert!(why.unwrap().contains("Cm: de"));
    let (attas, why) =
        auto_scope("jategaonkar_hfb320_attas/csv/fAttasAilRud1.csv", "attas_lateral.toml").unwrap();
    assert_eq!((attas, why), (Scope::Lateral, None));
}

/// The second reading guards the first: UAV-OAT's 11-13 `el_3` is an elevator 3-2-1-1 whose
/// `Cm_δe` falls just short of the cut-off (partial F 20.0) while the autopilot's aileron
/// corrections pass it in `Cl`; the elevator moved most, so neither axis is dropped. Its
/// `el_1` of 2023 (the elevator's the only surface term kept) is longitudinal.
#[test]
fn val_model_auto_keeps_both_axes_when_the_two_readings_disagree() {
    let dir = "uav_oat/csv/uavoat_";
    let Some((el3, why)) =
        auto_scope(&format!("{dir}2022_05_07_11_13_57_el_3.csv"), "uav_oat.toml")
    else {
        return;
    };
    assert_eq!((el3, why), (Scope::SixAxis, None));
    let (el1, _) =
        auto_scope(&format!("{dir}2023_02_01_14_21_28_el_1.csv"), "uav_oat.toml").unwrap();
    assert_eq!(el1, Scope::Longitudinal);
}
