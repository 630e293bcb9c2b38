//! The tool's own `f16 sim` output replays through the shipped `mappings/aeroident-sim.toml`,
//! unedited, and returns the simulated F-16's true derivatives: the sim's scenario
//! `scenarios/sim/six_axis_excitation.toml` (elevator 3-2-1-1, aileron and rudder doublets, no
//! noise) → `timeseries.csv` → `open_log` + `replay` (RLS, six-axis preset) → compared with the
//! model's local derivatives at the trim (`aircraft::truth`, central differences of the F-16's
//! coefficient tables: an independent computation, not a replay).

use aeroident::outdir::OutputDir;
use aeroident::sim::write_outputs;
use aeroident_estimators::vocabulary::Param;
use aeroident_io::{Mapping, ModelSpec, open_log};
use aeroident_models::f16::{AeroIncrements, F16};
use aeroident_pipelines::aircraft::truth::local_derivatives;
use aeroident_pipelines::replay::{ReplayOptions, replay};
use aeroident_pipelines::sim::{load_scenario, run};
use std::path::PathBuf;

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn val_f16_sim_output_replays_with_the_shipped_mapping_to_the_true_derivatives() {
    let scenario = workspace().join("scenarios/sim/six_axis_excitation.toml");
    let sc = load_scenario(&scenario).unwrap();
    let sim = run(&sc, scenario.parent().unwrap()).unwrap();
    let dir = std::env::temp_dir().join(format!("aeroident-sim-replay-{}", std::process::id()));
    let mut od = OutputDir::open(&dir, "f16 sim", &[]).unwrap();
    write_outputs(&sim, &mut od).unwrap();
    od.finish();
    let csv = dir.join("timeseries.csv").display().to_string();

    let mapping = Mapping::from_path(&workspace().join("mappings/aeroident-sim.toml")).unwrap();
    let reader = open_log(&csv, None, &mapping).unwrap();
    let opts = ReplayOptions {
        model: Some(ModelSpec::from_arg("six-axis").unwrap()),
        ..Default::default()
    };
    let out = replay(reader, &mapping, &opts, &mut ()).unwrap();
    assert_eq!(out.summary.samples_rejected, 0);
    assert_eq!(out.summary.samples_read, sim.table.data[0].len());
    assert!(out.differentiated.is_empty(), "the sim writes ṗ, q̇, ṙ, α̇: nothing differentiated");

    let f16 = F16::new(sc.aircraft.as_ref().unwrap().xcg).unwrap();
    let truth =
        local_derivatives(&f16, &sim.trim.state, &sim.trim.controls, &AeroIncrements::zero())
            .unwrap();
    let mut worst = (0.0f64, String::new());
    let mut checked = 0;
    for p in &out.summary.parameters {
        let param = Param::from_name(&p.name).unwrap();
        // Biases have no single true value over a nonlinear record (`None`).
        // The F-16's aileron and the sample's share one convention (> 0 rolls left): the
        // aileron derivatives are the tables' as they are.
        let Some(t) = truth.derivative(param) else { continue };
        let est = p.estimate.unwrap_or_else(|| panic!("{} not identified", p.name));
        let rel = (est - t).abs() / t.abs();
        eprintln!("{:10} estimate {est:+.5}  truth {t:+.5}  error {:5.2} %", p.name, 100.0 * rel);
        if SCORED.iter().all(|s| *s != p.name) {
            continue;
        }
        checked += 1;
        if rel > worst.0 {
            worst = (rel, p.name.clone());
        }
        assert!(rel < 0.05, "{}: estimate {est} vs truth {t} ({:.1} %)", p.name, 100.0 * rel);
    }
    eprintln!("worst of {checked} scored: {} at {:.2} %", worst.1, 100.0 * worst.0);
    assert_eq!(checked, SCORED.len());
    std::fs::remove_dir_all(&dir).ok();
}

/// The derivatives scored (within 5 %): every derivative of the six-axis preset except the
/// drag derivatives (CD is nonlinear in α and barely excited by a 1° 3-2-1-1: CD_alpha, CD_q,
/// CD_de are off by 35 % or more) and the two weak cross terms CY_p, Cn_p (18 % and 9 %:
/// roll rate is excited only by the aileron doublet, and its side-force and yaw effects are
/// small). Measured (printed with `--nocapture`): worst scored Cl_r 2.1 %, most below 0.5 %.
const SCORED: &[&str] = &[
    "CY_beta", "CY_da", "CY_dr", "CL_alpha", "CL_q", "CL_de", "Cl_beta", "Cl_p", "Cl_r", "Cl_da",
    "Cl_dr", "Cm_alpha", "Cm_q", "Cm_de", "Cn_beta", "Cn_r", "Cn_da", "Cn_dr",
];
