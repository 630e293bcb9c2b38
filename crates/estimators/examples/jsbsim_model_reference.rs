//! The model-reference estimators (corrected SMPE, gradient law (3.3), published SMPE) and RLS
//! for reference on the JSBSim sample records, with the records' true derivatives: prints one
//! Markdown table per record.
//!
//! ```text
//! cargo run --release -p aeroident-estimators --example jsbsim_model_reference [CSV TRUTH lateral|longitudinal]...
//! ```
//!
//! Without arguments: the F-16 aileron/rudder doublets (lateral preset, noisy channels) and the
//! F-16 elevator doublet (longitudinal preset) of `../shared/flightdata`. Default gains (none
//! tuned to these records: `aeroident_estimators::model_reference` documents each choice).

#[path = "../tests/all/common/records.rs"]
mod records;

use aeroident_estimators::model_reference::{
    CorrectedSmpeEstimator, GradientEstimator, ModelReferenceConfig, PublishedSmpeEstimator,
};
use aeroident_estimators::rls::{Rls, RlsConfig};
use aeroident_estimators::{Estimator, ModelStructure, Priors, Status};
use std::path::PathBuf;
use std::time::Instant;

struct Outcome {
    name: &'static str,
    values: Vec<f64>,
    identified: Vec<bool>,
    note: String,
}

fn run(mut e: Box<dyn Estimator>, samples: &[aeroident_estimators::AirDataSample]) -> Outcome {
    let start = Instant::now();
    let mut note = String::new();
    let mut used = 0;
    for s in samples {
        if let Err(err) = e.update(s).map(|_| ()) {
            note = if e.estimates().status == Status::Diverged {
                format!("diverged at t = {:.2} s ({err})", s.t_s)
            } else {
                format!("refused a sample at t = {:.2} s: {err}", s.t_s)
            };
            break;
        }
        used += 1;
    }
    let dt = start.elapsed().as_secs_f64();
    if note.is_empty() {
        note = format!("{used} samples, {:.0} samples/s", used as f64 / dt);
    }
    let n = e.structure().n_params();
    let est = e.estimates();
    Outcome {
        name: e.method(),
        values: (0..n).map(|i| est.raw_value(i)).collect(),
        identified: (0..n).map(|i| est.value(i).is_some()).collect(),
        note,
    }
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let jobs: Vec<(PathBuf, PathBuf, ModelStructure)> = if args.is_empty() {
        let mut v = Vec::new();
        if let (Some(c), Some(t)) = (
            records::shared_record("jsbsim_samples/f16_ail_rud_doublets_20s_60Hz.csv"),
            records::shared_record("jsbsim_samples/f16_ail_rud_doublets_truth.json"),
        ) {
            v.push((c, t, ModelStructure::lateral()));
        }
        if let (Some(c), Some(t)) = (
            records::shared_record("jsbsim_f16_sample/f16_doublet_20s_120Hz.csv"),
            records::shared_record("jsbsim_f16_sample/f16_true_derivatives_trim.json"),
        ) {
            v.push((c, t, ModelStructure::longitudinal()));
        }
        v
    } else {
        args.chunks(3)
            .map(|a| {
                let st = ModelStructure::preset(a.get(2).map_or("lateral", |s| s.as_str()))
                    .ok_or("preset: lateral | longitudinal | six-axis")?;
                Ok((PathBuf::from(&a[0]), PathBuf::from(a.get(1).ok_or("TRUTH missing")?), st))
            })
            .collect::<Result<_, String>>()?
    };
    for (csv, truth_path, st, noisy) in
        jobs.into_iter().flat_map(|(c, t, s)| [(c.clone(), t.clone(), s, true), (c, t, s, false)])
    {
        let channels = |noisy| records::JsbsimChannels { noisy, angular_accelerations: true };
        let rec = records::jsbsim(&csv, channels(noisy))?;
        let has_noisy = records::jsbsim(&csv, channels(!noisy))?.samples != rec.samples;
        if !noisy && !has_noisy {
            continue; // no noisy channels: the one run was already printed
        }
        let truth = records::read_truth(&truth_path)?;
        // Cross-check: measured coefficients (from the possibly noisy channels) vs JSBSim's.
        let mut worst = [0.0f64; 8];
        for (s, l) in rec.samples.iter().zip(&rec.logged) {
            for (k, m) in s.measured_coefficients().iter().enumerate() {
                if let Some(m) = m {
                    worst[k] = worst[k].max((m - l[k]).abs());
                }
            }
        }
        let channels =
            if noisy && has_noisy { "noisy channels (`_noisy` columns)" } else { "clean channels" };
        println!("\n## {} — {channels}, {} samples\n", csv.display(), rec.samples.len());
        println!(
            "max |measured − logged| coefficient: CL {:.1e}, CD {:.1e}, CY {:.1e}, Cl {:.1e}, Cm {:.1e}, Cn {:.1e}\n",
            worst[3], worst[4], worst[1], worst[5], worst[6], worst[7]
        );
        let priors = Priors::generic(&st);
        let outcomes = [
            run(
                Box::new(Rls::new(st, RlsConfig::default()).map_err(|e| e.to_string())?),
                &rec.samples,
            ),
            run(
                Box::new(
                    CorrectedSmpeEstimator::new(st, &priors, ModelReferenceConfig::default())
                        .map_err(|e| e.to_string())?,
                ),
                &rec.samples,
            ),
            run(
                Box::new(
                    GradientEstimator::new(st, &priors, ModelReferenceConfig::default())
                        .map_err(|e| e.to_string())?,
                ),
                &rec.samples,
            ),
            run(
                Box::new(
                    PublishedSmpeEstimator::new(st, &priors, ModelReferenceConfig::default())
                        .map_err(|e| e.to_string())?,
                ),
                &rec.samples,
            ),
        ];
        print!("| parameter | truth |");
        for o in &outcomes {
            print!(" {} | err % |", o.name);
        }
        println!();
        println!("|---|---|{}", "---|---|".repeat(outcomes.len()));
        for (i, p) in st.params().enumerate() {
            let t = truth.get(p.name()).copied();
            print!("| {} | {} |", p.name(), t.map_or("—".into(), |t| format!("{t:.4}")));
            for o in &outcomes {
                let v = o.values[i];
                let shown = if o.identified[i] { format!("{v:.4}") } else { format!("({v:.4})") };
                let err = match t {
                    Some(t) if t != 0.0 && o.identified[i] => {
                        format!("{:+.1}", 100.0 * (v - t) / t)
                    }
                    _ => "—".into(),
                };
                print!(" {shown} | {err} |");
            }
            println!();
        }
        println!();
        for o in &outcomes {
            println!("- {}: {}", o.name, o.note);
        }
        println!("\n(values in parentheses: not identified / not a result)");
    }
    Ok(())
}
