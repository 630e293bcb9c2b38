//! The verdict on each parameter of a finished replay, in its `summary.json` entry: a status
//! and the flags that explain it, judged once here for every face (the console table,
//! `report.html`, Python).
//!
//! The flags: every warning of the run about the parameter (sign checks, cross-check
//! disagreements), an imprecise estimate ([`super::precision`]), a value a conventional
//! aircraft cannot have ([`crate::plausibility`]), a reference outside ±2σ. The status:
//! `diverged` when the estimator diverged; `not identified` without an estimate (a drag term
//! of a record without thrust is withdrawn, with the reason); else `flagged` with any flag and
//! `identified` without one (docs/output-schema.md).

use super::{ReplayOutcome, precision};
use aeroident_io::parameter::STATUS_DIVERGED;

/// Sets the status and flags of every parameter of `outcome` (module doc), the drag terms
/// withdrawn unless `thrust_mapped`; judging again after a later stage (the cross-check)
/// replaces the earlier verdict.
pub fn judge(outcome: &mut ReplayOutcome, thrust_mapped: bool) {
    let diverged = outcome.diverged();
    let model = &outcome.model;
    let summary = &mut outcome.summary;
    for p in &mut summary.parameters {
        let r = &mut p.result;
        r.flags = summary.warnings.about(&r.name);
        if diverged {
            r.judge(Some(STATUS_DIVERGED));
            continue;
        }
        // A withdrawn drag term is judged by its reason alone.
        crate::plausibility::check(model, thrust_mapped, std::iter::once(&mut *r));
        if let Some(relative) = precision::imprecise(&r.name, r.estimate, r.std_error) {
            r.flag(precision::flag(relative));
        }
        r.judge(None);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::replay::{ReplayOptions, replay};
    use aeroident_io::parameter::{STATUS_FLAGGED, STATUS_IDENTIFIED};
    use aeroident_io::{FlightDataReader, Mapping};

    const MAP: &str = "nominal_dt_s = 0.1\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nq = { column = \"q\", unit = \"rad/s\" }\nax = { column = \"ax\", unit = \"m/s2\" }\naz = { column = \"az\", unit = \"m/s2\" }\nde = { column = \"de\", unit = \"rad\" }\nthrust = { value = 0.0, unit = \"N\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\ncbar = { value = 1.5, unit = \"m\" }\nIyy = { value = 2000.0, unit = \"kg*m2\" }\n";

    /// A finished replay of 200 samples exciting α, q and δe independently.
    fn outcome() -> ReplayOutcome {
        let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
        let mut csv = String::from("t,V,a,q,ax,az,de\n");
        for k in 0..200 {
            let t = f64::from(k) * 0.1;
            let (a, q, d) =
                (0.05 + 0.02 * (1.3 * t).sin(), 0.1 * (0.7 * t).cos(), 0.03 * (2.9 * t).sin());
            let (ax, az) = (0.1 + 0.5 * a + 0.2 * d, -9.8 - 30.0 * a - 4.0 * d + q);
            csv.push_str(&format!("{t:.1},50,{a},{q},{ax},{az},{d}\n"));
        }
        let reader = FlightDataReader::new(csv.as_bytes(), "d.csv", &m).unwrap();
        let opts = ReplayOptions { diff_window: 3, spike_screen: None, ..Default::default() };
        replay(reader, &m, &opts, &mut ()).unwrap()
    }

    /// The verdict carries the precision rule: `CL_alpha` set to 4.0 ± 0.2 (5 %) is judged as
    /// the rest of its flags say, and with σ 0.8 (20 %) gets the precision flag on top and is
    /// `flagged`; a diverged run marks every parameter `diverged` whatever its numbers.
    #[test]
    fn the_verdict_adds_the_precision_flag_and_marks_a_divergence() {
        let mut o = outcome();
        let i = o.summary.parameters.iter().position(|p| p.result.name == "CL_alpha").unwrap();
        let set = |o: &mut ReplayOutcome, sigma: f64| {
            let r = &mut o.summary.parameters[i].result;
            (r.estimate, r.std_error) = (Some(4.0), Some(sigma));
            judge(o, true);
            o.summary.parameters[i].result.clone()
        };
        let precise = set(&mut o, 0.2);
        let imprecise = set(&mut o, 0.8);
        let precision = precision::flag(0.2);
        assert!(!precise.flags.contains(&precision), "{:?}", precise.flags);
        assert_eq!(imprecise.flags.last(), Some(&precision), "{:?}", imprecise.flags);
        assert_eq!(imprecise.flags.len(), precise.flags.len() + 1);
        assert_eq!(imprecise.status, STATUS_FLAGGED);
        let status = if precise.flags.is_empty() { STATUS_IDENTIFIED } else { STATUS_FLAGGED };
        assert_eq!(precise.status, status);
        o.summary.status = aeroident_estimators::Status::Diverged.name().into();
        assert!(o.diverged());
        judge(&mut o, true);
        assert!(o.summary.parameters.iter().all(|p| p.result.status == STATUS_DIVERGED));
    }
}
