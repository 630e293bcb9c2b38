//! The repeatability test of an online replay with two or more windows
//! (`replay --window A:B --window C:D`, `--window auto`): each window replayed alone by the same
//! estimator and options, the estimates tested for agreement against their σ
//! ([`crate::replay::repeatability`]), as the batch fits test their manoeuvres. The reported
//! estimate stays the replay over every window; a parameter whose windows disagree gets the
//! test's note, and the σ of their spread where that is the larger.

use super::cross_check::{abandoned, online_replay};
use super::{Guard, JobLog, Records, Step};
use crate::replay::cross_check::ParameterEstimate;
use crate::replay::repeatability::{CONVERGED, Repeatability, SoloFit};
use crate::replay::{ReplayError, ReplayOptions, ReplayOutcome};
use crate::window::TimeWindow;

/// The test on `outcome`, the replay of `records` with `base`. With two or more windows and a
/// record (not a live feed, which cannot be read again), each window is replayed alone under
/// `guard`; the test's warnings go to `log` and the summary, each parameter that does not
/// repeat is widened ([`Repeatability::widen`]) and the test is kept in
/// `outcome.repeatability` for the verdict's note. A stop abandons it with a warning.
///
/// # Errors
/// The face could not run the step.
pub fn repeat_step(
    records: &Records,
    base: &ReplayOptions,
    outcome: &mut ReplayOutcome,
    guard: &mut impl Guard,
    log: &mut dyn JobLog,
) -> Result<(), ReplayError> {
    if base.windows.len() < 2 || records.live {
        return Ok(());
    }
    log.note("repeatability: replaying each window alone");
    let (again, opts) = (records.clone(), base.clone());
    let summary = &mut outcome.summary;
    let Some(fits) = guard.run(Step::Repeatability, move || solo_fits(&again, &opts))? else {
        abandoned("the repeatability test", log, &mut summary.warnings);
        return Ok(());
    };
    let names: Vec<String> = summary.parameters.iter().map(|p| p.result.name.clone()).collect();
    let rep = Repeatability::assess(fits, &names);
    for w in rep.warnings() {
        log.warning(&w.text);
        summary.warnings.push(w);
    }
    for p in &mut summary.parameters {
        rep.widen(&mut p.result);
    }
    outcome.repeatability = Some(rep);
    Ok(())
}

/// Each window of `base` replayed alone, on the rayon pool.
fn solo_fits(records: &Records, base: &ReplayOptions) -> Vec<SoloFit> {
    use rayon::prelude::*;
    let windows = &base.windows;
    windows.par_iter().enumerate().map(|(k, w)| solo_fit(k, *w, records, base)).collect()
}

/// Window `k` replayed alone ([`online_replay`], estimates only): its estimates and reported σ
/// when the replay ended with estimates (the test's `converged`), `failed: why` when it
/// failed, diverged or ended `initialising`.
fn solo_fit(k: usize, w: TimeWindow, records: &Records, base: &ReplayOptions) -> SoloFit {
    let opts = ReplayOptions { windows: vec![w], ..base.clone() };
    let mut fit = SoloFit::of(k, &[]);
    (fit.t_start_s, fit.t_end_s) = (w.start_s, w.end_s);
    match online_replay(records, &opts) {
        Ok(o) => {
            let t = &o.history.t_s;
            if let (Some(first), Some(last)) = (t.first(), t.last()) {
                (fit.t_start_s, fit.t_end_s) = (*first, *last);
            }
            fit.samples = o.history.samples;
            let rows = o.summary.parameters.iter().filter_map(|p| ParameterEstimate::of(p));
            fit.estimates = rows.filter(ParameterEstimate::usable).collect();
            fit.status = CONVERGED.into();
        }
        Err(why) => fit.status = format!("failed: {why}"),
    }
    fit
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::job::InPlace;
    use crate::replay::replay;
    use aeroident_io::{FlightDataReader, Mapping, StdErrorSource};

    const MAP: &str = "nominal_dt_s = 0.1\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nq = { column = \"q\", unit = \"rad/s\" }\nax = { column = \"ax\", unit = \"m/s2\" }\naz = { column = \"az\", unit = \"m/s2\" }\nde = { column = \"de\", unit = \"rad\" }\nthrust = { value = 0.0, unit = \"N\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\ncbar = { value = 1.5, unit = \"m\" }\nIyy = { value = 2000.0, unit = \"kg*m2\" }\n";

    /// 80 s at 10 Hz with α, q and δe excited independently and a_z noisy (a fixed
    /// pseudo-random sequence); from 40 s the lift slope is a third higher: a_z takes −40 α
    /// instead of −30 α, everything else the same.
    fn record() -> String {
        let mut csv = String::from("t,V,a,q,ax,az,de\n");
        let mut state: u64 = 12345;
        for k in 0..800 {
            let t = f64::from(k) * 0.1;
            let (a, q, d) =
                (0.05 + 0.02 * (1.3 * t).sin(), 0.1 * (0.7 * t).cos(), 0.03 * (2.9 * t).sin());
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let noise = 0.05 * ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
            let slope = if t < 40.0 { 30.0 } else { 40.0 };
            let (ax, az) = (0.1 + 0.5 * a + 0.2 * d, -9.8 - slope * a - 4.0 * d + q + noise);
            csv.push_str(&format!("{t:.1},50,{a},{q},{ax},{az},{d}\n"));
        }
        csv
    }

    /// The record replayed by RLS over `windows` (the estimating step alone).
    fn replayed(m: &Mapping, windows: &[TimeWindow]) -> ReplayOutcome {
        let csv = record();
        let reader = FlightDataReader::new(csv.as_bytes(), "d.csv", m).unwrap();
        replay(reader, m, &options(windows), &mut ()).unwrap()
    }

    fn options(windows: &[TimeWindow]) -> ReplayOptions {
        let windows = windows.to_vec();
        ReplayOptions { diff_window: 3, spike_screen: None, windows, ..Default::default() }
    }

    /// Two windows of one aircraft whose lift slope changed between them: each window's value
    /// and σ in the test are the window replayed alone; the χ² is recomputed here from them;
    /// CL_α does not repeat, its σ is raised to the Birge-scaled σ of the weighted mean
    /// (recomputed here) and the verdict carries the note; CL_0 and CL_δe, the same in both
    /// windows, repeat.
    #[test]
    fn windows_of_a_changed_lift_slope_do_not_repeat_and_widen_its_sigma() {
        let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
        let path =
            std::env::temp_dir().join(format!("aeroident-repeat-{}.csv", std::process::id()));
        std::fs::write(&path, record()).unwrap();
        let windows =
            [TimeWindow { start_s: 0.0, end_s: 39.9 }, TimeWindow { start_s: 40.0, end_s: 79.9 }];
        let records = Records::one(path.display().to_string(), m.clone());
        let mut joint = replayed(&m, &windows);
        repeat_step(&records, &options(&windows), &mut joint, &mut InPlace, &mut ()).unwrap();
        std::fs::remove_file(&path).unwrap();
        let rep = joint.repeatability.clone().expect("two windows are tested");
        assert_eq!(rep.fits.len(), 2);
        assert!(rep.fits.iter().all(|f| f.status == CONVERGED), "{:?}", rep.fits);
        let alone: Vec<ReplayOutcome> = windows.iter().map(|w| replayed(&m, &[*w])).collect();
        let value = |o: &ReplayOutcome, name: &str| {
            let p = o.summary.parameters.iter().find(|p| p.result.name == name).unwrap();
            (p.result.estimate.unwrap(), p.result.std_error.unwrap())
        };
        for r in &rep.parameters {
            let (mut sw, mut swx) = (0.0, 0.0);
            for v in &r.values {
                let (x, s) = value(&alone[v.manoeuvre], &r.parameter);
                assert_eq!((v.estimate, v.std_error), (x, s), "{}", r.parameter);
                (sw, swx) = (sw + 1.0 / (s * s), swx + x / (s * s));
            }
            let chi2: f64 =
                r.values.iter().map(|v| ((v.estimate - swx / sw) / v.std_error).powi(2)).sum();
            assert!((r.chi2 - chi2).abs() <= 1e-9 * chi2.max(1.0), "{}", r.parameter);
        }
        let cl = rep.parameters.iter().find(|r| r.parameter == "CL_alpha").unwrap();
        let (first, second) = (cl.values[0].estimate, cl.values[1].estimate);
        assert!(!cl.repeats && (second / first - 4.0 / 3.0).abs() < 0.05, "{cl:?}");
        let sw: f64 = cl.values.iter().map(|v| v.std_error.powi(-2)).sum();
        let birge = (cl.chi2 / cl.dof as f64).sqrt() / sw.sqrt();
        let p = joint.summary.parameters.iter().find(|p| p.result.name == "CL_alpha").unwrap();
        assert!((p.result.std_error.unwrap() - birge).abs() <= 1e-12 * birge);
        assert_eq!(p.result.std_error_source, Some(StdErrorSource::Repeatability));
        for name in ["CL_0", "CL_de"] {
            let r = rep.parameters.iter().find(|r| r.parameter == name);
            assert!(r.is_some_and(|r| r.repeats), "{name}: {r:?}");
        }
        crate::replay::verdict::judge(&mut joint, true);
        let p = joint.summary.parameters.iter().find(|p| p.result.name == "CL_alpha").unwrap();
        assert!(p.result.notes.contains(&cl.note()), "{:?}", p.result.notes);
    }
}
