//! The evidence of a finished replay for the one judge ([`crate::verdict`]): the run's warnings
//! about each parameter, the plausibility check, the estimator's final state, whether the
//! estimate repeats across the record's windows.

use super::ReplayOutcome;
use crate::verdict::{self, Evidence};
use aeroident_io::parameter::STATUS_DIVERGED;

/// Sets the status, flags and notes of every parameter of `outcome` ([`crate::verdict`]), the
/// drag terms withdrawn unless `thrust_mapped`, a value that does not repeat across windows
/// as a note ([`super::repeatability`]); judging again after a later stage (the
/// cross-check) replaces the earlier verdict.
pub fn judge(outcome: &mut ReplayOutcome, thrust_mapped: bool) {
    let diverged = outcome.diverged();
    let (model, repeatability) = (&outcome.model, outcome.repeatability.as_ref());
    let summary = &mut outcome.summary;
    let unconverged = verdict::unconverged(&summary.status);
    for p in &mut summary.parameters {
        let r = &mut p.result;
        r.flags.clear();
        r.combines = verdict::combinations(&r.name, &summary.correlations);
        let evidence = Evidence {
            doubts: summary.warnings.about(&r.name),
            plausibility: Some((model, thrust_mapped)),
            estimate_doubts: unconverged.iter().cloned().collect(),
            failure: diverged.then_some(STATUS_DIVERGED),
            notes: repeatability
                .and_then(|rep| rep.failed(&r.name))
                .map(super::repeatability::Repeat::note)
                .into_iter()
                .chain(verdict::combination_notes(&r.name, &summary.correlations))
                .collect(),
        };
        verdict::judge(r, &evidence);
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

    /// The precision rule is a note, never a flag: `CL_alpha` set to 4.0 ± 0.2 (5 %) has no
    /// note, with σ 0.8 (20 %) it has the precision note and the same flags and status; an
    /// estimator that ended `initialising` flags every estimate; a diverged run marks every
    /// parameter `diverged` whatever its numbers.
    #[test]
    fn precision_is_a_note_and_an_unfinished_or_diverged_estimator_is_judged() {
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
        let precision = crate::replay::precision::flag(0.2);
        // This record does not separate CL_alpha from CL_0: that note is in both.
        let own = |n: &Vec<String>| -> Vec<String> {
            n.iter().filter(|t| !t.starts_with("combines with")).cloned().collect()
        };
        assert!(own(&precise.notes).is_empty(), "{:?}", precise.notes);
        let partner = precise.combines.iter().find(|c| c.with == "CL_0");
        assert!(partner.is_some_and(|c| c.rho.abs() > 0.9), "{:?}", precise.combines);
        assert_eq!(own(&imprecise.notes), [precision]);
        assert_eq!((&imprecise.flags, &imprecise.status), (&precise.flags, &precise.status));
        let status = if precise.flags.is_empty() { STATUS_IDENTIFIED } else { STATUS_FLAGGED };
        assert_eq!(precise.status, status);
        o.summary.status = aeroident_estimators::Status::Initialising.name().into();
        judge(&mut o, true);
        let doubt = crate::verdict::unconverged("initialising").unwrap();
        for p in o.summary.parameters.iter().filter(|p| p.estimate.is_some()) {
            assert_eq!((p.status.as_str(), p.flags.contains(&doubt)), (STATUS_FLAGGED, true));
        }
        o.summary.status = aeroident_estimators::Status::Diverged.name().into();
        assert!(o.diverged());
        judge(&mut o, true);
        assert!(o.summary.parameters.iter().all(|p| p.result.status == STATUS_DIVERGED));
    }
}
