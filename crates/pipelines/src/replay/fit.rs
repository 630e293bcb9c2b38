//! The batch fits' entry (`replay --estimator oe | fem | fdoe`): the options checked before
//! anything is read, the records read into manoeuvres by the record stage
//! ([`crate::record::read_records`]), then the time-domain fits ([`super::batch`]) or
//! frequency-domain output error ([`super::frequency`]).

use super::ReplayError;
use super::batch::{
    BatchMethod, BatchOutcome, FitOptions, check_bootstrap_refits, check_fdoe_options,
};
use crate::record::read_records;
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
    if options.method != BatchMethod::Fem && options.process_noise.is_some() {
        return Err(ReplayError::Option {
            option: "process-noise",
            reason: "process noise is the filter-error method's (`--estimator fem`); output error has none".into(),
        });
    }
    if options.method != BatchMethod::Fem && !options.gain_constraint {
        return Err(ReplayError::Option {
            option: "no-gain-constraint",
            reason: "the gain constraint is the filter-error method's (`--estimator fem`); output error has no filter".into(),
        });
    }
    if options.method == BatchMethod::Fem && options.robust.is_some() {
        return Err(ReplayError::Option {
            option: "robust",
            reason: "Huber's robust weights are of output error (`--estimator oe`), not of the filter-error method".into(),
        });
    }
    if options.method == BatchMethod::Fem && options.bootstrap_refits.is_some() {
        return Err(ReplayError::Option {
            option: "bootstrap",
            reason: "the parametric bootstrap is of output error (`--estimator oe`); the filter-error method's own σ accounts for the process noise".into(),
        });
    }
    if let BatchMethod::Fdoe { .. } = options.method {
        check_fdoe_options(&options)?;
    }
    if let Some(n) = options.bootstrap_refits {
        // Before the record is read: the replicas' storage and time grow with the count.
        check_bootstrap_refits(n)
            .map_err(|reason| ReplayError::Option { option: "bootstrap", reason })?;
    }
    let file = readers.iter().map(|r| r.file()).collect::<Vec<_>>().join(", ");
    let rec =
        read_records(readers, options.spike_screen, options.compat.as_ref(), &options.windows)?;
    if let BatchMethod::Fdoe { band_hz } = options.method {
        return super::frequency::fit_fdoe(rec, &file, mapping, model, band_hz, &options);
    }
    super::batch::fit_time_domain(rec, &file, mapping, model, &options)
}
