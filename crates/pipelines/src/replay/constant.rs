//! Channels a model term needs that do not vary over the record. Such a term's regressor is
//! zero or a multiple of another's (the bias, for a constant channel), so its parameters are
//! not identifiable whatever the method: an estimator leaves them (and, for a recursive one,
//! possibly the whole model) unidentified, and the user is told which channel is the cause.
//! The batch fits (output error, filter error, frequency-domain output error) fit the model
//! without those terms ([`without_constant_terms`]) and report them `null` with the channel,
//! instead of stopping at the first unknown that has no effect on any output.
//!
//! "Does not vary" is judged without physics: every estimated sample holds exactly the same
//! value. (A held or stuck sensor, a channel set to a constant in the data, a surface not
//! moved during the manoeuvre.)

use aeroident_estimators::prior::Priors;
use aeroident_estimators::{AirDataSample, ModelStructure, Param, Term};
use aeroident_io::warning::{Warning, WarningKind};
use aeroident_io::{Mapping, ModelSpec};

/// The sample fields the regressors read (`vt_mps`: every normalised rate and the `V` term),
/// and the throttle, which no term reads but whose travel says whether the thrust changed
/// ([`crate::plausibility::unmapped_thrust_moment`]).
const FIELDS: [&str; 11] = [
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
    "throttle",
];

/// Whether term `t`'s regressor varies with the sample field `name` ([`Term::inputs`]: a
/// product needs both factors).
fn term_reads(t: Term, name: &str) -> bool {
    t.inputs().iter().any(|i| i.field() == Some(name))
}

/// The fields whose range is also kept within each manoeuvre: what moves the thrust.
const WITHIN: [&str; 2] = ["vt_mps", "throttle"];

/// An empty range of one field: `(smallest, largest, samples)`.
const EMPTY: (f64, f64, usize) = (f64::INFINITY, f64::NEG_INFINITY, 0);

/// The smallest and largest value of each of `FIELDS` over the samples pushed, and how many
/// held it; and of the airspeed and throttle within each manoeuvre.
#[derive(Debug, Clone)]
pub struct Spread {
    ranges: [(f64, f64, usize); FIELDS.len()],
    /// Per manoeuvre, the ranges of [`WITHIN`].
    within: Vec<[(f64, f64, usize); WITHIN.len()]>,
}

impl Default for Spread {
    fn default() -> Self {
        Self { ranges: [EMPTY; FIELDS.len()], within: vec![[EMPTY; WITHIN.len()]] }
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
        let current = self.within.last_mut().expect("one manoeuvre from the start");
        for (name, r) in WITHIN.iter().zip(current) {
            if let Some(v) = s.field(name) {
                *r = (r.0.min(v), r.1.max(v), r.2 + 1);
            }
        }
    }

    /// The samples pushed from now on belong to a new manoeuvre (a gap, a window, another
    /// file): a flight condition is judged within each, not across two manoeuvres flown
    /// minutes apart at different speeds.
    pub fn new_manoeuvre(&mut self) {
        if self.within.last().is_some_and(|m| m.iter().any(|r| r.2 > 0)) {
            self.within.push([EMPTY; WITHIN.len()]);
        }
    }

    /// The `(smallest, largest)` of field `WITHIN[k]` in the manoeuvre where it varied most
    /// (by `measure` of the range); `None` when no manoeuvre held it.
    fn widest_within(&self, k: usize, measure: impl Fn(f64, f64) -> f64) -> Option<(f64, f64)> {
        self.within
            .iter()
            .map(|m| m[k])
            .filter(|r| r.2 > 0)
            .map(|r| (r.0, r.1))
            .max_by(|a, b| measure(a.0, a.1).total_cmp(&measure(b.0, b.1)))
    }

    /// The sample fields that held one value in every sample (at least 2).
    fn constant_fields(&self) -> impl Iterator<Item = (&'static str, f64, usize)> + '_ {
        FIELDS
            .iter()
            .zip(&self.ranges)
            .filter(|(_, r)| r.2 >= 2 && r.0 == r.1)
            .map(|(name, &(v, _, n))| (*name, v, n))
    }

    /// The parameters of `structure` whose term reads a channel that held one value in every
    /// sample, each with that channel's sample field (the first, for a product of two): no
    /// method can identify them.
    pub fn constant_terms(&self, structure: &ModelStructure) -> Vec<(Param, &'static str)> {
        let fields: Vec<&'static str> = self.constant_fields().map(|(name, _, _)| name).collect();
        structure
            .params()
            .filter_map(|p| fields.iter().find(|f| term_reads(p.term, f)).map(|f| (p, *f)))
            .collect()
    }

    /// One warning per channel that held one value in every sample (at least 2) and that a
    /// term of `structure` needs, naming the channel as `mapping` does and the parameters it
    /// leaves unidentifiable.
    ///
    /// Also one warning per α knot of `structure` outside the α range seen (a recursive replay
    /// cannot refuse such a knot before it has read the record, as the batch fits do): the
    /// spline term is then zero throughout, or `α − k`, which the constant and `alpha` span.
    /// And the warning about the `Cm` terms of a record without thrust whose speed or
    /// throttle varied within a manoeuvre ([`crate::plausibility::unmapped_thrust_moment`]).
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
        let mut out: Vec<Warning> = outside.map(Warning::from).collect();
        out.extend(self.constant_fields().filter_map(|(name, v, n)| {
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
        out.extend(crate::plausibility::unmapped_thrust_moment(
            structure,
            mapping,
            self.widest_within(0, crate::plausibility::relative_variation),
            self.widest_within(1, |lo, hi| hi - lo),
        ));
        out
    }
}

/// `model` without the parameters a batch fit cannot identify on the samples `spread` has seen
/// ([`Spread::constant_terms`]), and those parameters, each with the reason (the channel named
/// as `mapping` names it). Fitting without a term holds it at 0:
/// a surface held at one value then contributes through the coefficient's constant term, which
/// absorbs it. The reduced model keeps the name, description, references and plausible ranges
/// of `model`, and each kept parameter its prior. When every parameter would go, `model` is
/// returned whole (the fit then names what it cannot identify).
pub fn without_constant_terms(
    model: ModelSpec,
    spread: &Spread,
    mapping: &Mapping,
) -> (ModelSpec, Vec<(Param, String)>) {
    let held = spread.constant_terms(&model.structure);
    if held.is_empty() || held.len() == model.structure.n_params() {
        return (model, Vec::new());
    }
    let mut structure = model.structure;
    held.iter().for_each(|(p, _)| structure.remove(*p));
    let held = held.into_iter().map(|(p, field)| {
        let why = format!(
            "not identified: {} does not vary over the record, so no method can tell this term from the constant; the fit held it at 0",
            mapping.field_label(field)
        );
        (p, why)
    });
    let held = held.collect();
    let mut priors = Priors::generic(&structure);
    for (i, p) in structure.params().enumerate() {
        if let Some(j) = model.structure.params().position(|q| q == p) {
            priors.set(i, model.priors.prior[j]);
        }
    }
    (ModelSpec { structure, priors, ..model }, held)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two manoeuvres held at 50 and 60 m/s (each within 2 %) draw no thrust doubt, though the
    /// record spans 18 %; one manoeuvre that itself goes from 50 to 60 m/s does, with its 18 %.
    #[test]
    fn the_thrust_doubt_is_judged_within_each_manoeuvre() {
        let map = "[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\n";
        let mapping = Mapping::from_toml_str(map, "m.toml").unwrap();
        let lon = ModelStructure::preset("longitudinal").unwrap();
        let at = |v: f64| AirDataSample { vt_mps: v, ..AirDataSample::default() };
        let doubt = |spread: &Spread| {
            let w = spread.warnings(&lon, &mapping);
            w.into_iter().find(|w| w.text.starts_with("thrust is not mapped")).map(|w| w.text)
        };
        let mut two = Spread::default();
        [50.0, 50.5, 51.0].iter().for_each(|v| two.push(&at(*v)));
        two.new_manoeuvre();
        [60.0, 60.5, 61.0].iter().for_each(|v| two.push(&at(*v)));
        assert_eq!(doubt(&two), None);
        let mut one = Spread::default();
        [50.0, 55.0, 60.0].iter().for_each(|v| one.push(&at(*v)));
        let text = doubt(&one).unwrap();
        assert!(text.contains("the airspeed varied 18 % within a manoeuvre"), "{text}");
        // A new manoeuvre before any sample, or twice in a row, adds no empty one.
        let mut s = Spread::default();
        s.new_manoeuvre();
        s.new_manoeuvre();
        assert_eq!(s.within.len(), 1);
    }
}
