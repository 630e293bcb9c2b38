//! Estimator errors in the user's terms.
//!
//! The estimators (no_std core) name the [`AirDataSample`](aeroident_estimators::AirDataSample)
//! field they could not use (`r_rad_s`, `Iyy_kgm2`, …), and give an absent channel as the value
//! NaN (the EKF initialising its states, the flight model's inputs). The user wrote a mapping
//! channel (`r`) fed by a column. [`estimator_error`] rewrites such an error to name the channel
//! and where the mapping takes it from: a user knows the mapping's channels and columns, not the
//! estimator's internal field names.

use aeroident_estimators::EstimatorError;
use aeroident_io::Mapping;

/// `e` with its sample field replaced by the mapping channel that feeds it
/// ([`Mapping::describe_field`]) and an absent value (NaN: the reader never yields a
/// non-finite value) said as absent; errors about the estimator's own configuration unchanged.
pub fn estimator_error(e: &EstimatorError, mapping: &Mapping) -> String {
    use EstimatorError as E;
    use aeroident_io::message::exact_or_short;
    let describe = |field: &str| mapping.describe_field(field);
    match *e {
        E::NonFiniteInput { field, value, t_s } => match describe(field) {
            Some(d) if value.is_nan() => {
                format!("{d} has no value at t = {t_s} s, and the estimator needs it")
            }
            Some(d) => format!("unusable input {d} = {} at t = {t_s} s", exact_or_short(value)),
            None => e.to_string(),
        },
        E::ImplausibleInput { field, value, t_s, limit } => match describe(field) {
            Some(d) => format!(
                "implausible input {d} = {} at t = {t_s} s (limit {})",
                exact_or_short(value),
                exact_or_short(limit)
            ),
            None => e.to_string(),
        },
        E::InvalidConfig { field, value, reason } => match describe(field) {
            Some(d) if value.is_nan() => format!("{d}: {reason}"),
            Some(d) => format!("{d} = {}: {reason}", exact_or_short(value)),
            None => e.to_string(),
        },
        E::Numerical { .. } | E::IncompleteAxis { .. } | E::TooLarge { .. } => e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::ekf::{Ekf, EkfConfig};
    use aeroident_estimators::{Estimator, ModelStructure};
    use aeroident_io::{FlightDataReader, RecordEvent};

    /// Every lateral channel the EKF needs except the rudder `dr` (a model input; an
    /// unmeasured state such as `r` would be carried as a state instead).
    const MAP: &str = "nominal_dt_s = 0.02\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nbeta = { column = \"b\", unit = \"rad\" }\np = { column = \"P_dps\", unit = \"deg/s\" }\nq = { column = \"Q_dps\", unit = \"deg/s\" }\nphi = { column = \"phi\", unit = \"rad\" }\ntheta = { column = \"theta\", unit = \"rad\" }\nax = { column = \"ax\", unit = \"m/s2\" }\nay = { column = \"ay\", unit = \"m/s2\" }\naz = { column = \"az\", unit = \"m/s2\" }\nda = { column = \"da\", unit = \"rad\" }\nr = { column = \"r\", unit = \"rad/s\" }\nrho = { value = 1.2, unit = \"kg/m3\" }\nmass = { value = 9000.0, unit = \"kg\" }\nS = { value = 28.0, unit = \"m2\" }\ncbar = { value = 3.5, unit = \"m\" }\nb = { value = 9.0, unit = \"m\" }\nIxx = { value = 12000.0, unit = \"kg*m2\" }\nIyy = { value = 75000.0, unit = \"kg*m2\" }\nIzz = { value = 85000.0, unit = \"kg*m2\" }\nIxz = { value = 1300.0, unit = \"kg*m2\" }\n";

    /// The lateral EKF fed a record without `dr` refuses the sample; the message names the
    /// channel `dr` and the mapping file, not the sample field `dr_rad`.
    #[test]
    fn errors_ekf_missing_channel_is_named_as_the_mapping_channel() {
        let m = Mapping::from_toml_str(MAP, "lat.toml").unwrap();
        let csv = "t,V,a,b,P_dps,Q_dps,phi,theta,ax,ay,az,da,r\n0,150,0.05,0.01,1,0,0.02,0.05,0.3,0.1,-9.8,0.01,0.0\n";
        let mut reader = FlightDataReader::new(csv.as_bytes(), "lat.csv", &m).unwrap();
        let Some(Ok(RecordEvent::Sample { sample, .. })) = reader.next() else {
            panic!("the row is a sample")
        };
        let st = ModelStructure::preset("lateral").unwrap();
        let mut ekf = Ekf::new(EkfConfig::new(st)).unwrap();
        let e = ekf.update(&sample).unwrap_err();
        assert!(e.to_string().contains("dr_rad"), "the core names its field: {e}");
        let text = estimator_error(&e, &m);
        assert!(text.starts_with("channel `dr` (not mapped in lat.toml) has no value"), "{text}");
        assert!(!text.contains("dr_rad") && !text.contains("NaN"), "{text}");
    }

    /// A mapped channel is named with its column; a constant as a constant; an error about the
    /// estimator's configuration is unchanged.
    #[test]
    fn errors_mapped_channels_name_their_column_or_constant() {
        let m = Mapping::from_toml_str(MAP, "lat.toml").unwrap();
        let e = EstimatorError::ImplausibleInput {
            field: "p_rad_s",
            value: 40.0,
            t_s: 1.5,
            limit: 20.0,
        };
        let text = estimator_error(&e, &m);
        assert_eq!(
            text,
            "implausible input channel `p` (column `P_dps` of lat.toml) = 40 at t = 1.5 s (limit 20)"
        );
        let e =
            EstimatorError::InvalidConfig { field: "Iyy_kgm2", value: -1.0, reason: "must be > 0" };
        assert_eq!(
            estimator_error(&e, &m),
            "channel `Iyy` (a constant in lat.toml) = -1: must be > 0"
        );
        let e = EstimatorError::InvalidConfig {
            field: "gate_sigmas",
            value: 0.0,
            reason: "must be > 0",
        };
        assert_eq!(estimator_error(&e, &m), e.to_string());
    }
}
