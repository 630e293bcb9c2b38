//! Channels a model term needs that do not vary over the record. Such a term's regressor is
//! zero or a multiple of another's (the bias, for a constant channel), so its parameters are
//! not identifiable whatever the method: an estimator leaves them (and, for a recursive one,
//! possibly the whole model) unidentified, and the user is told which channel is the cause.
//!
//! "Does not vary" is judged without physics: every estimated sample holds exactly the same
//! value. (A held or stuck sensor, a channel set to a constant in the data, a surface not
//! moved during the manoeuvre.)

use aeroident_estimators::{AirDataSample, ModelStructure, Term};
use aeroident_io::Mapping;
use aeroident_io::warning::{Warning, WarningKind};

/// The sample fields the regressors read, besides `V` (which every normalised rate reads and
/// the `V` term itself).
const FIELDS: [&str; 10] = [
    "alpha_rad",
    "beta_rad",
    "p_rad_s",
    "q_rad_s",
    "r_rad_s",
    "alphadot_rad_s",
    "de_rad",
    "da_rad",
    "dr_rad",
    "vt_mps",
];

/// Whether term `t`'s regressor varies with the sample field `name` ([`Term::inputs`]: a
/// product needs both factors).
fn term_reads(t: Term, name: &str) -> bool {
    t.inputs().iter().any(|i| i.field() == Some(name))
}

/// The smallest and largest value of each of `FIELDS` over the samples pushed, and how many
/// held it.
#[derive(Debug, Clone)]
pub struct Spread {
    ranges: [(f64, f64, usize); FIELDS.len()],
}

impl Default for Spread {
    fn default() -> Self {
        Self { ranges: [(f64::INFINITY, f64::NEG_INFINITY, 0); FIELDS.len()] }
    }
}

impl Spread {
    /// Takes one estimated sample into account.
    pub fn push(&mut self, s: &AirDataSample) {
        for (name, r) in FIELDS.iter().zip(&mut self.ranges) {
            if let Some(v) = s.field(name) {
                *r = (r.0.min(v), r.1.max(v), r.2 + 1);
            }
        }
    }

    /// One warning per channel that held one value in every sample (at least 2) and that a
    /// term of `structure` needs, naming the channel as `mapping` does and the parameters it
    /// leaves unidentifiable.
    ///
    /// Also one warning per α knot of `structure` outside the α range seen (a recursive replay
    /// cannot refuse such a knot before it has read the record, as the batch fits do): the
    /// spline term is then zero throughout, or `α − k`, which the constant and `alpha` span.
    pub fn warnings(&self, structure: &ModelStructure, mapping: &Mapping) -> Vec<Warning> {
        let (lo, hi, n) = self.ranges[0];
        let knots = structure.knots().as_slice().iter().enumerate();
        let outside = knots.filter(|(_, k)| n > 0 && !(lo < **k && **k < hi)).map(|(i, k)| {
            format!(
                "α knot {} ({:.3}°) lies outside the α range of the estimated samples ({:.3}° to {:.3}°): the parameters of `{}` cannot be identified",
                i + 1,
                k.to_degrees(),
                lo.to_degrees(),
                hi.to_degrees(),
                Term::spline(i).map_or("", |t| t.name())
            )
        });
        let constant = FIELDS.iter().zip(&self.ranges).filter(|(_, r)| r.2 >= 2 && r.0 == r.1);
        let mut out: Vec<Warning> = outside.map(Warning::from).collect();
        out.extend(constant.filter_map(|(name, &(v, _, n))| {
                let params: Vec<&str> = structure
                    .params()
                    .filter(|p| term_reads(p.term, name))
                    .map(|p| p.name())
                    .collect();
                (!params.is_empty()).then(|| {
                    let text = format!(
                        "constant channel: {} does not vary over the record ({v} in all {n} estimated samples), so the terms that need it cannot be identified: {}",
                        mapping.field_label(name),
                        params.join(", ")
                    );
                    Warning::new(WarningKind::ConstantChannel, text)
                })
        }));
        out
    }
}
