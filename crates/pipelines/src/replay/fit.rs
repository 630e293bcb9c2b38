//! The batch fits' entry (`replay --estimator oe | fem | fdoe`): the options checked before
//! anything is read, the records read into manoeuvres by the record stage
//! ([`crate::record::read_records`]), then the time-domain fits ([`super::batch`]) or
//! frequency-domain output error ([`super::frequency`]).

use super::ReplayError;
use super::batch::{
    BatchMethod, BatchOutcome, FitOptions, check_bootstrap_refits, parse_process_noise_states,
};
use crate::estimators::{EstimatorKind, OptionError};
use crate::record::read_records;
use aeroident_estimators::flight_model::N_STATES;
use aeroident_estimators::output_error::frequency::DEFAULT_BAND_HZ;
use aeroident_estimators::output_error::{InitialStates, StepKind};
use aeroident_io::{FlightDataReader, Mapping, ModelSpec};
use std::io::Read;

/// Reads the whole record, splits it at gaps and fits it by output error (`fem`: by the
/// filter-error method with [`FemConfig::new`](aeroident_estimators::output_error::filter_error::FemConfig::new)'s defaults on [`oe_config`](super::batch::oe_config)) as `options` say.
/// A fit that does not meet both convergence criteria is reported all the same, its status
/// (`converged_in_cost`, `not_converged`) and [`termination_note`](super::batch::termination_note) in the summary; the
/// bootstrap is not run on a fit that did not converge.
///
/// # Errors
/// Fatal data errors, no usable samples, no supported model, a fit that fails
/// ([`ReplayError::Model`] with the reason), a bootstrap that fails ([`bootstrap_sigma`](super::batch::bootstrap_sigma)), and a
/// bootstrap asked of `fem` ([`ReplayError::Option`]).
pub fn fit_record<R: Read>(
    reader: FlightDataReader<R>,
    mapping: &Mapping,
    model: Option<ModelSpec>,
    options: FitOptions,
) -> Result<BatchOutcome, ReplayError> {
    fit_records(vec![reader], mapping, model, options)
}

/// [`fit_record`] over several records of one aircraft read with the same mapping (`replay A
/// --and B --and C`): each file is a manoeuvre of its own (or several, at its gaps and
/// windows), all fitted together; the time windows and the compatibility corrections apply to
/// every file, and with more than one file each rejection names its file.
///
/// # Errors
/// As [`fit_record`].
pub fn fit_records<R: Read>(
    readers: Vec<FlightDataReader<R>>,
    mapping: &Mapping,
    model: Option<ModelSpec>,
    options: FitOptions,
) -> Result<BatchOutcome, ReplayError> {
    options.check()?;
    let file = readers.iter().map(|r| r.file()).collect::<Vec<_>>().join(", ");
    let rec =
        read_records(readers, options.spike_screen, options.compat.as_ref(), &options.windows)?;
    fit_manoeuvres(rec, &file, mapping, model, options)
}

/// [`fit_records`] of one record held in memory ([`crate::record::cache::ScreenedRecord`],
/// read with `options`' spike screen): the same outcome as from its file.
///
/// # Errors
/// As [`fit_records`]; [`ReplayError::Option`] (`spike-screen`) when `record` was screened
/// otherwise than `options` asks.
pub fn fit_cached(
    record: &crate::record::cache::ScreenedRecord,
    mapping: &Mapping,
    model: Option<ModelSpec>,
    options: FitOptions,
) -> Result<BatchOutcome, ReplayError> {
    options.check()?;
    record.check_screen(options.spike_screen)?;
    let rec = crate::record::read_cached(record, options.compat.as_ref(), &options.windows)?;
    fit_manoeuvres(rec, record.file(), mapping, model, options)
}

/// The batch fit of the manoeuvres `rec` of the record(s) `file`, options checked.
fn fit_manoeuvres(
    rec: crate::record::Manoeuvres,
    file: &str,
    mapping: &Mapping,
    model: Option<ModelSpec>,
    options: FitOptions,
) -> Result<BatchOutcome, ReplayError> {
    let model = match model {
        Some(m) => m,
        None => super::batch::default_model(&rec.manoeuvres[0][0], mapping)?,
    };
    let mut spread = super::constant::Spread::default();
    for m in &rec.manoeuvres {
        spread.new_manoeuvre();
        m.iter().for_each(|s| spread.push(s));
    }
    let full = model.structure;
    let (model, held) = super::constant::without_constant_terms(model, &spread, mapping);
    let mut out = match options.method {
        BatchMethod::Fdoe { band_hz } => {
            super::frequency::fit_fdoe(rec, file, mapping, Some(model), band_hz, &options)?
        }
        _ => super::batch::fit_time_domain(rec, file, mapping, Some(model), &options)?,
    };
    out.summary.warnings.extend(spread.warnings(&full, mapping));
    out.summary.insert_held(&full, &held);
    out.summary.judge(&out.model, crate::plausibility::thrust_mapped(mapping));
    Ok(out)
}

/// The options a batch fit takes, as key/value pairs (the CLI's flags, `--estimator-option
/// KEY=VALUE`, Python's keywords, a scenario's `[[estimator]]` keys): [`FitOptions::from_pairs`]
/// parses them, [`FitOptions::check`] refuses those the method does not have
/// ([`EstimatorKind::fit_options`] lists each method's).
pub const FIT_OPTION_KEYS: [&str; 8] = [
    "initial_states",
    "step",
    "bootstrap_refits",
    "max_iterations",
    "process_noise",
    "gain_constraint",
    "robust",
    "band_hz",
];

impl FitOptions {
    /// The batch fit `kind` (`oe`, `fem`, `fdoe`) with the options `pairs` give, every other
    /// one at [`FitOptions::default`]; the one parser of a batch fit's options, which the
    /// faces translate their flags and keywords into. Which option the method has is then
    /// [`FitOptions::check`]'s (the fit checks again before reading).
    ///
    /// # Errors
    /// [`OptionError::Unknown`] for a key that is no batch fit's option; [`OptionError::Invalid`]
    /// for a value of the wrong type or range, or a band given to a method other than `fdoe`.
    pub fn from_pairs<'a>(
        kind: EstimatorKind,
        pairs: impl IntoIterator<Item = (&'a str, toml::Value)>,
    ) -> Result<Self, OptionError> {
        let method = match kind {
            EstimatorKind::Fem => BatchMethod::Fem,
            EstimatorKind::Fdoe => BatchMethod::Fdoe { band_hz: DEFAULT_BAND_HZ },
            _ => BatchMethod::Oe,
        };
        let mut options = FitOptions { method, ..FitOptions::default() };
        for (key, v) in pairs {
            options.set(kind, key, &v)?;
        }
        Ok(options)
    }

    /// Sets option `key` of [`FIT_OPTION_KEYS`] from its value.
    fn set(&mut self, kind: EstimatorKind, key: &str, v: &toml::Value) -> Result<(), OptionError> {
        let invalid = |reason: String| OptionError::Invalid { kind, key: key.into(), reason };
        let count = |min: i64| {
            v.as_integer()
                .filter(|n| *n >= min)
                .and_then(|n| usize::try_from(n).ok())
                .ok_or_else(|| invalid(format!("must be an integer of at least {min}, got {v}")))
        };
        let flag = || v.as_bool().ok_or_else(|| invalid(format!("must be true or false, got {v}")));
        match key {
            "initial_states" => self.initial_states = initial_states(v).map_err(invalid)?,
            "step" => self.step = Some(step(v).map_err(invalid)?),
            "bootstrap_refits" => {
                let n = count(2)?;
                check_bootstrap_refits(n).map_err(invalid)?;
                self.bootstrap_refits = Some(n);
            }
            "max_iterations" => self.max_iterations = Some(count(1)?),
            "process_noise" => {
                let list = v.as_str().ok_or_else(|| {
                    invalid(format!("must be a list of states such as \"V,alpha,beta\", got {v}"))
                })?;
                self.process_noise = Some(parse_process_noise_states(list).map_err(invalid)?);
            }
            "gain_constraint" => self.gain_constraint = flag()?,
            "robust" => {
                self.robust = flag()?.then(aeroident_estimators::output_error::Huber::default)
            }
            "band_hz" => {
                self.method = BatchMethod::Fdoe { band_hz: band(kind, v).map_err(invalid)? }
            }
            _ => return Err(OptionError::Unknown { kind, key: key.into() }),
        }
        Ok(())
    }

    /// Refuses the options the method does not have ([`FitOptions::refusal`]) and a
    /// bootstrap count out of range, naming the option as the command line spells it.
    ///
    /// # Errors
    /// [`ReplayError::Option`] saying whose option it is.
    pub fn check(&self) -> Result<(), ReplayError> {
        if let Some((key, reason)) = self.refusal() {
            return Err(ReplayError::Option { option: flag_of(key), reason });
        }
        if let Some(n) = self.bootstrap_refits {
            // Before the record is read: the replicas' storage and time grow with the count.
            check_bootstrap_refits(n)
                .map_err(|reason| ReplayError::Option { option: "bootstrap", reason })?;
        }
        Ok(())
    }

    /// The first option given (set away from its default) that the method does not have by
    /// [`EstimatorKind::fit_options`], as its key of [`FIT_OPTION_KEYS`] and whose option it
    /// is; `None` when the method has every option given.
    pub fn refusal(&self) -> Option<(&'static str, String)> {
        let kind = self.method.kind();
        let given = [
            ("initial_states", self.initial_states != InitialStates::FirstSample),
            ("step", self.step.is_some()),
            ("bootstrap_refits", self.bootstrap_refits.is_some()),
            ("max_iterations", self.max_iterations.is_some()),
            ("process_noise", self.process_noise.is_some()),
            ("gain_constraint", !self.gain_constraint),
            ("robust", self.robust.is_some()),
        ];
        let (key, _) = given.into_iter().find(|(k, g)| *g && !kind.fit_options().contains(k))?;
        Some((key, whose(key, kind)))
    }
}

/// Why the batch method `kind` does not take option `key`: what the option is, the methods
/// that have it ([`EstimatorKind::fit_options`]) and, where it helps, why this one has none.
fn whose(key: &str, kind: EstimatorKind) -> String {
    let owners: Vec<String> = <EstimatorKind as crate::Named>::ALL
        .iter()
        .filter(|k| k.fit_options().contains(&key))
        .map(|k| format!("{} (`{}`)", method_name(*k), k.name()))
        .collect();
    let what = match key {
        "initial_states" => "estimating initial states",
        "step" => "the choice of Gauss–Newton step",
        "bootstrap_refits" => "the parametric bootstrap",
        "max_iterations" => "an iteration limit",
        "process_noise" => "process noise",
        "gain_constraint" => "the gain constraint",
        "robust" => "Huber's robust weighting",
        _ => "the option",
    };
    let why = match (key, kind) {
        ("bootstrap_refits", EstimatorKind::Fem) => {
            "; the filter-error method's own σ accounts for the process noise"
        }
        ("initial_states", EstimatorKind::Fdoe) => {
            "; fdoe estimates each manoeuvre's initial/final-condition terms anyway"
        }
        ("process_noise" | "gain_constraint", _) => "; output error has no filter",
        _ => "",
    };
    format!("{what} is of {}, not of {}{why}", owners.join(" and "), method_name(kind))
}

/// The batch method `kind` in words.
fn method_name(kind: EstimatorKind) -> &'static str {
    match kind {
        EstimatorKind::Fem => "the filter-error method",
        EstimatorKind::Fdoe => "frequency-domain output error",
        _ => "output error",
    }
}

/// The command line's flag (without `--`) of fit option `key`; `estimator-option` for one
/// without a flag of its own.
fn flag_of(key: &str) -> &'static str {
    match key {
        "initial_states" => "initial-states",
        "bootstrap_refits" => "bootstrap",
        "max_iterations" => "max-iterations",
        "process_noise" => "process-noise",
        "gain_constraint" => "no-gain-constraint",
        "robust" => "robust",
        "band_hz" => "band-hz",
        "step" => "estimator-option step",
        _ => "estimator-option",
    }
}

/// `initial_states`: `"first-sample"` (each manoeuvre starts at its first sample's states) or
/// `"estimate"` (every integrated state estimated).
fn initial_states(v: &toml::Value) -> Result<InitialStates, String> {
    match v.as_str() {
        Some("first-sample") => Ok(InitialStates::FirstSample),
        Some("estimate") => Ok(InitialStates::Estimate([true; N_STATES])),
        _ => Err(format!(
            "`{}` is not `first-sample` or `estimate`",
            v.as_str().map_or_else(|| v.to_string(), str::to_string)
        )),
    }
}

/// `step`: `"relaxation"` (Jategaonkar's, `R` held in the step) or `"concentrated"` (the
/// curvature of `R(β)` included), [`StepKind`].
fn step(v: &toml::Value) -> Result<StepKind, String> {
    match v.as_str() {
        Some("relaxation") => Ok(StepKind::Relaxation),
        Some("concentrated") => Ok(StepKind::Concentrated),
        _ => Err(format!("must be \"relaxation\" or \"concentrated\", got {v}")),
    }
}

/// `band_hz`: `[f_min, f_max]` in Hz of `fdoe`; refused for the other methods.
fn band(kind: EstimatorKind, v: &toml::Value) -> Result<(f64, f64), String> {
    if kind != EstimatorKind::Fdoe {
        return Err(format!(
            "is the band of frequency-domain output error (fdoe), not of `{}`",
            kind.name()
        ));
    }
    let num = |x: &toml::Value| x.as_float().or_else(|| x.as_integer().map(|i| i as f64));
    match v.as_array().map(|a| a.iter().map(num).collect::<Option<Vec<f64>>>()) {
        Some(Some(b)) if b.len() == 2 => Ok((b[0], b[1])),
        _ => Err(format!("must be [f_min, f_max] in Hz, got {v}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use toml::Value as V;

    /// Every batch fit option parses to its field from the value a face gives; a key no batch
    /// fit has is refused naming it; a value of the wrong type or range names what it must be;
    /// the band is fdoe's alone; and an option the method does not have is refused by
    /// `check`, naming whose it is.
    #[test]
    fn errors_fit_options_are_parsed_once_and_refused_by_name() {
        let oe = FitOptions::from_pairs(
            EstimatorKind::Oe,
            [
                ("initial_states", V::String("estimate".into())),
                ("bootstrap_refits", V::Integer(7)),
                ("max_iterations", V::Integer(9)),
                ("robust", V::Boolean(true)),
            ],
        )
        .unwrap();
        assert_eq!(oe.method, BatchMethod::Oe);
        assert_eq!(oe.initial_states, InitialStates::Estimate([true; N_STATES]));
        assert_eq!((oe.bootstrap_refits, oe.max_iterations), (Some(7), Some(9)));
        assert!(oe.robust.is_some() && oe.check().is_ok());
        let fem = FitOptions::from_pairs(
            EstimatorKind::Fem,
            [
                ("process_noise", V::String("V,alpha,q".into())),
                ("gain_constraint", V::Boolean(false)),
            ],
        )
        .unwrap();
        assert_eq!(fem.method, BatchMethod::Fem);
        assert_eq!(fem.process_noise, Some(parse_process_noise_states("V,alpha,q").unwrap()));
        assert!(!fem.gain_constraint && fem.check().is_ok());
        let band = V::Array(vec![0.2.into(), 2.0.into()]);
        let fdoe =
            FitOptions::from_pairs(EstimatorKind::Fdoe, [("band_hz", band.clone())]).unwrap();
        assert_eq!(fdoe.method, BatchMethod::Fdoe { band_hz: (0.2, 2.0) });
        let plain = FitOptions::from_pairs(EstimatorKind::Fdoe, []).unwrap();
        assert_eq!(plain.method, BatchMethod::Fdoe { band_hz: DEFAULT_BAND_HZ });

        let e = FitOptions::from_pairs(EstimatorKind::Oe, [("forgetting", V::Float(0.9))]);
        assert_eq!(
            e.unwrap_err(),
            OptionError::Unknown { kind: EstimatorKind::Oe, key: "forgetting".into() }
        );
        let e = FitOptions::from_pairs(EstimatorKind::Oe, [("band_hz", band)]).unwrap_err();
        assert!(e.to_string().contains("band of frequency-domain output error"), "{e}");
        let e = FitOptions::from_pairs(EstimatorKind::Oe, [("max_iterations", V::Integer(0))]);
        assert!(e.unwrap_err().to_string().contains("at least 1, got 0"));
        let e = FitOptions::from_pairs(EstimatorKind::Oe, [("bootstrap_refits", V::Integer(1))]);
        assert!(e.unwrap_err().to_string().contains("at least 2"));
        let e =
            FitOptions::from_pairs(EstimatorKind::Oe, [("initial_states", V::String("x".into()))]);
        assert!(e.unwrap_err().to_string().contains("`x` is not `first-sample` or `estimate`"));
        let e = FitOptions::from_pairs(EstimatorKind::Fem, [("robust", V::String("yes".into()))]);
        assert!(e.unwrap_err().to_string().contains("must be true or false"));

        let robust_fem = FitOptions::from_pairs(EstimatorKind::Fem, [("robust", V::Boolean(true))]);
        let e = robust_fem.unwrap().check().unwrap_err().to_string();
        assert!(e.contains("`--robust`") && e.contains("output error"), "{e}");
        let noise_oe =
            FitOptions::from_pairs(EstimatorKind::Oe, [("process_noise", V::String("V".into()))]);
        let e = noise_oe.unwrap().check().unwrap_err().to_string();
        assert!(e.contains("filter-error method"), "{e}");
    }

    /// A value a face could give for each option of [`FIT_OPTION_KEYS`], away from its
    /// default.
    fn given(key: &str) -> V {
        match key {
            "initial_states" => V::String("estimate".into()),
            "step" => V::String("relaxation".into()),
            "bootstrap_refits" => V::Integer(5),
            "max_iterations" => V::Integer(12),
            "process_noise" => V::String("V,alpha".into()),
            "gain_constraint" | "robust" => V::Boolean(key == "robust"),
            "band_hz" => V::Array(vec![0.2.into(), 2.0.into()]),
            other => panic!("no value for `{other}`"),
        }
    }

    /// The registry's list of each batch method's options is what the parser and `check` take:
    /// every listed option parses and passes, every other option of [`FIT_OPTION_KEYS`] is
    /// refused (by the parser or by `check`) and its message names a method that has it; a
    /// real-time estimator lists none.
    #[test]
    fn errors_each_method_takes_exactly_the_options_the_registry_lists() {
        for kind in [EstimatorKind::Oe, EstimatorKind::Fem, EstimatorKind::Fdoe] {
            let takes = kind.fit_options();
            assert!(takes.iter().all(|k| FIT_OPTION_KEYS.contains(k)), "{takes:?}");
            let all = takes.iter().map(|k| (*k, given(k)));
            let o = FitOptions::from_pairs(kind, all).unwrap_or_else(|e| panic!("{e}"));
            assert!(o.check().is_ok() && o.refusal().is_none(), "{}: {:?}", kind.name(), o);
            for key in FIT_OPTION_KEYS.iter().filter(|k| !takes.contains(k)) {
                let refused = match FitOptions::from_pairs(kind, [(*key, given(key))]) {
                    Err(e) => e.to_string(),
                    Ok(o) => o.check().map_or_else(|e| e.to_string(), |()| String::new()),
                };
                assert!(!refused.is_empty(), "{} took `{key}`", kind.name());
                let owner = <EstimatorKind as crate::Named>::ALL
                    .iter()
                    .find(|k| k.fit_options().contains(key))
                    .unwrap();
                assert!(refused.contains(owner.name()), "{}: {key}: {refused}", kind.name());
            }
        }
        for kind in <EstimatorKind as crate::Named>::ALL.iter().filter(|k| !k.is_batch()) {
            assert!(kind.fit_options().is_empty(), "{}", kind.name());
        }
    }
}
