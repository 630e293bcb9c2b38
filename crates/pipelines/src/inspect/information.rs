//! How much a window of a record tells about each axis: the Cramér–Rao σ of the axis's
//! derivatives from its equation-error regression in that window.
//!
//! # The regressions
//!
//! - **pitch**: q̇ on α, q, δe (and a constant): `Cm_alpha`, `Cm_q`, `Cm_de`;
//! - **lateral**: ṗ and ṙ each on β, p, r, δa, δr (and a constant): `Cl_*` and `Cn_*`. A
//!   record without a β vane gets the sideslip its kinematics imply
//!   ([`crate::kinematics::sideslip`]), not `a_y`: the side force of the rudder put into a
//!   stand-in's regression moves the rudder's derivative by `−N_β Y_δr / Y_β`.
//!
//! The angular accelerations are the record's where mapped, else central differences of the
//! rates. Regressors the record lacks are left out (named in the note); an axis with no
//! surface, or without its rate, is not judged.
//!
//! # The σ and the score
//!
//! Least squares on the window's samples, with the columns centred (the constant) and scaled
//! to unit norm: σ_k = s·√[(XᵀX)⁻¹]_kk with s² = RSS/(n − k − 1), the Cramér–Rao bound of
//! equation error with white residuals (Klein & Morelli 2006, §5.1). A regressor that did not
//! move in the window (RMS below 10⁻⁶ in its SI unit: a surface held still) identifies
//! nothing: it is left out and its derivative listed as not identified. A window whose scaled
//! information matrix then has a pivot below 10⁻⁸ (a regressor the others explain) does not
//! identify the axis: no σ.
//!
//! The σ of the dimensional derivative (M_α = q̄Sc̄/I_y · Cm_α) is made non-dimensional with
//! the window's mean q̄ and V and the mapping's constants: × I/(q̄ S ℓ), and × 2V/ℓ for a rate
//! (ℓ = c̄ for pitch, b for lateral). Without the constants the scale is q̄ and V alone
//! (`nondimensional: false`): still fair between windows of one record, which is what a
//! ranking needs. A window on the ground, where q̄ is small, therefore holds little
//! information however much its surfaces moved.
//!
//! The score of an axis is the geometric mean of its identified derivatives' non-dimensional
//! σ (the `1/(2k)`-th power of the product of the diagonal of the covariance, close to the
//! D-optimal criterion): lower holds more information; one poorly determined derivative does
//! not outweigh all the others. Windows are ranked first by how many derivatives they leave
//! unidentified, then by score ([`super::rank`]).

use aeroident_estimators::AirDataSample;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use std::collections::BTreeMap;

/// An axis the candidates are ranked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// Pitch moment: q̇ on α, q, δe.
    Pitch,
    /// Roll and yaw moments: ṗ, ṙ on β, p, r, δa, δr.
    Lateral,
}

impl Axis {
    /// Both axes, in the order they are listed.
    pub const ALL: [Axis; 2] = [Axis::Pitch, Axis::Lateral];

    /// The axis's name: `pitch` or `lateral`.
    pub fn name(self) -> &'static str {
        match self {
            Axis::Pitch => "pitch",
            Axis::Lateral => "lateral",
        }
    }
}

/// What a window tells about one axis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxisInformation {
    /// The axis.
    pub axis: Axis,
    /// Samples of the regression.
    pub samples: usize,
    /// Non-dimensional Cramér–Rao σ of each derivative (`Cm_alpha`, …); empty when the window
    /// does not identify the axis.
    pub sigma: BTreeMap<String, f64>,
    /// The derivatives the window does not identify: their regressor did not move in it
    /// (RMS below 10⁻⁶ in its SI unit).
    pub not_identified: Vec<String>,
    /// Geometric mean of `sigma`: lower holds more information. `None`: not identified.
    pub score: Option<f64>,
    /// Whether the σ are non-dimensional (the mapping gives the constants) or scaled by q̄
    /// and V only.
    pub nondimensional: bool,
    /// What was left out or why the axis is not identified.
    pub note: Option<String>,
}

/// Smallest squared pivot of the unit-norm information matrix (module doc).
const MIN_PIVOT: f64 = 1e-8;

/// The information `samples` (one window, time order) hold about `axis`.
pub fn information(samples: &[AirDataSample], axis: Axis) -> AxisInformation {
    let mut out = AxisInformation {
        axis,
        samples: 0,
        sigma: BTreeMap::new(),
        not_identified: vec![],
        score: None,
        nondimensional: false,
        note: None,
    };
    let kinematic = (axis == Axis::Lateral
        && samples.first().is_some_and(|s| s.beta_rad.is_none()))
    .then(|| crate::kinematics::sideslip::filled(&[samples]))
    .flatten()
    .and_then(|m| m.into_iter().next());
    let samples = kinematic.as_deref().unwrap_or(samples);
    let equations = match axis {
        Axis::Pitch => vec![pitch(samples)],
        Axis::Lateral => lateral(samples),
    };
    let mut notes = Vec::new();
    for eq in equations {
        match eq.and_then(|eq| eq.solve(samples)) {
            Ok(solved) => {
                out.samples = solved.samples;
                out.nondimensional = solved.nondimensional;
                out.sigma.extend(solved.sigma);
                out.not_identified.extend(solved.not_identified);
                notes.extend(solved.note);
            }
            Err(why) => {
                notes.push(why);
                out.sigma.clear();
                out.not_identified.clear();
                break;
            }
        }
    }
    if !out.sigma.is_empty() {
        let mean_ln = out.sigma.values().map(|s| s.ln()).sum::<f64>() / out.sigma.len() as f64;
        out.score = Some(mean_ln.exp());
    }
    notes.dedup();
    out.note = (!notes.is_empty()).then(|| notes.join("; "));
    out
}

/// A channel of a sample: `None` where the record lacks it.
type Pick = fn(&AirDataSample) -> Option<f64>;

/// One equation-error regression: the output, its coefficient's prefix, the regressors.
struct Equation {
    /// `Cm`, `Cl` or `Cn`.
    coefficient: &'static str,
    /// The angular acceleration, or the rate to differentiate.
    output: (Pick, bool),
    /// Name, channel, whether it is a rate (scaled by 2V/ℓ).
    regressors: Vec<(&'static str, Pick, bool)>,
    /// The inertia and reference length of the non-dimensional scale.
    scale: fn(&AirDataSample) -> Option<(f64, f64)>,
    /// Regressors left out (the record lacks them).
    left_out: Vec<&'static str>,
}

/// The pitch equation (module doc), or why the record cannot give it.
fn pitch(samples: &[AirDataSample]) -> Result<Equation, String> {
    let first = samples.first().ok_or("no sample")?;
    let output: (Pick, bool) = match (first.qdot_rad_s2, first.q_rad_s) {
        (Some(_), _) => (|s| s.qdot_rad_s2, false),
        (None, Some(_)) => (|s| s.q_rad_s, true),
        (None, None) => return Err("no pitch rate q".into()),
    };
    if first.de_rad.is_none() {
        return Err("no elevator δe".into());
    }
    Ok(Equation {
        coefficient: "Cm",
        output,
        regressors: vec![
            ("alpha", |s| Some(s.alpha_rad), false),
            ("q", |s| s.q_rad_s, true),
            ("de", |s| s.de_rad, false),
        ],
        scale: |s| Some((s.constants.Iyy_kgm2?, s.constants.cbar_m?)),
        left_out: vec![],
    })
}

/// The roll and yaw equations (module doc), or why the record cannot give them.
fn lateral(samples: &[AirDataSample]) -> Vec<Result<Equation, String>> {
    let Some(first) = samples.first() else { return vec![Err("no sample".into())] };
    let mut regressors: Vec<(&'static str, Pick, bool)> = Vec::new();
    let mut left_out = Vec::new();
    let candidates: [(&'static str, Pick, bool); 5] = [
        ("beta", |s| s.beta_rad, false),
        ("p", |s| s.p_rad_s, true),
        ("r", |s| s.r_rad_s, true),
        ("da", |s| s.da_rad, false),
        ("dr", |s| s.dr_rad, false),
    ];
    for (name, pick, rate) in candidates {
        let have = pick(first).is_some();
        if have {
            regressors.push((name, pick, rate));
        } else if name != "beta" {
            left_out.push(name);
        }
    }
    if !regressors.iter().any(|r| r.0 == "da" || r.0 == "dr") {
        return vec![Err("no aileron δa or rudder δr".into())];
    }
    let roll: (Pick, bool) = match (first.pdot_rad_s2, first.p_rad_s) {
        (Some(_), _) => (|s| s.pdot_rad_s2, false),
        (None, Some(_)) => (|s| s.p_rad_s, true),
        (None, None) => return vec![Err("no roll rate p".into())],
    };
    let yaw: (Pick, bool) = match (first.rdot_rad_s2, first.r_rad_s) {
        (Some(_), _) => (|s| s.rdot_rad_s2, false),
        (None, Some(_)) => (|s| s.r_rad_s, true),
        (None, None) => return vec![Err("no yaw rate r".into())],
    };
    let eq = |coefficient, output, scale: fn(&AirDataSample) -> Option<(f64, f64)>| {
        Ok(Equation {
            coefficient,
            output,
            regressors: regressors.clone(),
            scale,
            left_out: left_out.clone(),
        })
    };
    vec![
        eq("Cl", roll, |s| Some((s.constants.Ixx_kgm2?, s.constants.b_m?))),
        eq("Cn", yaw, |s| Some((s.constants.Izz_kgm2?, s.constants.b_m?))),
    ]
}

/// A solved regression: the non-dimensional σ by derivative name.
struct Solved {
    samples: usize,
    sigma: Vec<(String, f64)>,
    not_identified: Vec<String>,
    nondimensional: bool,
    note: Option<String>,
}

impl Equation {
    /// The rows `(output, regressors, q̄, V)` of `samples` where every channel is finite; the
    /// output differentiated centrally where it is a rate.
    fn rows(&self, samples: &[AirDataSample]) -> Vec<Row> {
        let (pick, differentiate) = self.output;
        let range =
            if differentiate { 1..samples.len().saturating_sub(1) } else { 0..samples.len() };
        range
            .filter_map(|k| {
                let s = &samples[k];
                let y = if differentiate {
                    let (a, b) = (&samples[k - 1], &samples[k + 1]);
                    (pick(b)? - pick(a)?) / (b.t_s - a.t_s)
                } else {
                    pick(s)?
                };
                let x: Option<Vec<f64>> = self.regressors.iter().map(|r| r.1(s)).collect();
                let x = x?;
                let ok = y.is_finite() && x.iter().all(|v| v.is_finite()) && s.qbar_pa > 0.0;
                ok.then_some((y, x, s.qbar_pa, s.vt_mps))
            })
            .collect()
    }

    /// The regression's non-dimensional σ (module doc), or why the window does not identify it.
    fn solve(&self, samples: &[AirDataSample]) -> Result<Solved, String> {
        let rows = self.rows(samples);
        let n = rows.len();
        let mean = |f: &dyn Fn(&Row) -> f64| rows.iter().map(f).sum::<f64>() / n.max(1) as f64;
        // A regressor that did not move in the window identifies nothing: left out, named.
        let (kept, still): (Vec<usize>, Vec<usize>) = (0..self.regressors.len()).partition(|&j| {
            let m = mean(&|r| r.1[j]);
            mean(&|r| (r.1[j] - m).powi(2)).sqrt() >= MIN_MOVEMENT
        });
        let k = kept.len();
        if k == 0 {
            return Err("no regressor moved".into());
        }
        if n < 3 * (k + 1) {
            return Err(format!("{n} usable samples, fewer than 3 per parameter"));
        }
        let x_mean: Vec<f64> = kept.iter().map(|&j| mean(&|r| r.1[j])).collect();
        let mut x = DMatrix::from_fn(n, k, |i, c| rows[i].1[kept[c]] - x_mean[c]);
        let norms: Vec<f64> = (0..k).map(|c| x.column(c).norm()).collect();
        for (c, norm) in norms.iter().enumerate() {
            x.column_mut(c).scale_mut(1.0 / norm);
        }
        let y_mean = mean(&|r| r.0);
        let y = DVector::from_fn(n, |i, _| rows[i].0 - y_mean);
        let chol = (x.transpose() * &x).cholesky().ok_or("regressors collinear")?;
        let pivot = (0..k).map(|c| chol.l()[(c, c)].powi(2)).fold(f64::INFINITY, f64::min);
        if pivot.is_nan() || pivot < MIN_PIVOT {
            return Err("regressors collinear".into());
        }
        let theta = chol.solve(&(x.transpose() * &y));
        let s2 = (&y - &x * theta).norm_squared() / (n - k - 1) as f64;
        let cov = chol.inverse();
        let (qbar, v) = (mean(&|r| r.2), mean(&|r| r.3));
        let constants = (self.scale)(&samples[0]).filter(|_| samples[0].constants.S_m2 > 0.0);
        let (inertia, length) = constants.unwrap_or((1.0, 1.0));
        let area = if constants.is_some() { samples[0].constants.S_m2 } else { 1.0 };
        let sigma = kept
            .iter()
            .enumerate()
            .map(|(c, &j)| {
                let (name, _, rate) = self.regressors[j];
                let dimensional = (s2 * cov[(c, c)]).sqrt() / norms[c];
                let rate_scale = if rate { 2.0 * v / length } else { 1.0 };
                let sigma = dimensional * inertia / (qbar * area * length) * rate_scale;
                (format!("{}_{name}", self.coefficient), sigma)
            })
            .collect();
        let not_identified = still
            .iter()
            .map(|&j| format!("{}_{}", self.coefficient, self.regressors[j].0))
            .collect();
        let note = (!self.left_out.is_empty())
            .then(|| format!("no {} in the record: left out", self.left_out.join(", ")));
        Ok(Solved { samples: n, sigma, not_identified, nondimensional: constants.is_some(), note })
    }
}

/// One row of a regression: output, regressors, q̄ (Pa), V (m/s).
type Row = (f64, Vec<f64>, f64, f64);

/// Smallest RMS movement of a regressor in a window (its SI unit: rad, rad/s, m/s²) for it to
/// identify its derivative: far below any sensor's noise, far above the round-off of a
/// surface a simulation holds still.
const MIN_MOVEMENT: f64 = 1e-6;

#[cfg(test)]
mod tests {
    use super::*;

    /// A pitch record of known dynamics q̇ = −4α − 1.5q − 8δe + white noise (σ 0.01) with a
    /// multistep on δe: the Cramér–Rao σ of `Cm_de` agrees with the spread of the estimate
    /// over independent noise (the σ is a real standard deviation, not a ranking number), and
    /// a window of the same length with δe still (and so α, q still) is not identified.
    #[test]
    fn analytic_sigma_is_the_spread_and_a_still_window_identifies_nothing() {
        let record = |seed: u64, input: bool| -> Vec<AirDataSample> {
            let (mut alpha, mut q) = (0.0f64, 0.0f64);
            let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
            let mut noise = move || {
                // Sum of 12 uniforms: a unit-variance near-Gaussian.
                (0..12)
                    .map(|_| {
                        state = state
                            .wrapping_mul(6364136223846793005)
                            .wrapping_add(1442695040888963407);
                        (state >> 11) as f64 / (1u64 << 53) as f64
                    })
                    .sum::<f64>()
                    - 6.0
            };
            (0..1000)
                .map(|k| {
                    let t = k as f64 * 0.02;
                    let de =
                        if input { 0.02 * ((t * 0.7).floor() as i64 % 3 - 1) as f64 } else { 0.0 };
                    let qdot_true = -4.0 * alpha - 1.5 * q - 8.0 * de;
                    let s = AirDataSample {
                        t_s: t,
                        vt_mps: 100.0,
                        qbar_pa: 5000.0,
                        alpha_rad: alpha,
                        q_rad_s: Some(q),
                        qdot_rad_s2: Some(qdot_true + 0.01 * noise()),
                        de_rad: Some(de),
                        ..Default::default()
                    };
                    q += qdot_true * 0.02;
                    alpha += (q - 2.0 * alpha) * 0.02;
                    s
                })
                .collect()
        };
        let sigmas: Vec<f64> = (0..40)
            .map(|seed| information(&record(seed, true), Axis::Pitch).sigma["Cm_de"])
            .collect();
        let mean_sigma = sigmas.iter().sum::<f64>() / sigmas.len() as f64;
        // Without constants the scale is 1/q̄: σ(M_de) / 5000. The regression's own σ of
        // M_de, computed apart with ordinary least squares over 40 seeds, must match it: here
        // the estimate's spread is compared through the score's definition.
        let est: Vec<f64> = (0..40).map(|seed| ols_de(&record(seed, true))).collect();
        let m = est.iter().sum::<f64>() / est.len() as f64;
        let spread = (est.iter().map(|e| (e - m).powi(2)).sum::<f64>() / 39.0).sqrt() / 5000.0;
        assert!((mean_sigma / spread - 1.0).abs() < 0.35, "σ {mean_sigma} vs spread {spread}");
        assert!((m + 8.0).abs() < 0.05, "M_de {m}");
        let still = information(&record(1, false), Axis::Pitch);
        assert!(still.score.is_none(), "{still:?}");
        assert_eq!(still.note.as_deref(), Some("no regressor moved"));
    }

    /// The least-squares M_de of q̇ on α, q, δe and a constant, apart from [`information`].
    fn ols_de(s: &[AirDataSample]) -> f64 {
        let x = DMatrix::from_fn(s.len(), 4, |i, j| match j {
            0 => 1.0,
            1 => s[i].alpha_rad,
            2 => s[i].q_rad_s.unwrap(),
            _ => s[i].de_rad.unwrap(),
        });
        let y = DVector::from_fn(s.len(), |i, _| s[i].qdot_rad_s2.unwrap());
        let theta = (x.transpose() * &x).cholesky().unwrap().solve(&(x.transpose() * y));
        theta[3]
    }

    /// A record without a lateral surface or without q says so instead of a score.
    #[test]
    fn missing_channels_are_named() {
        let s = vec![AirDataSample { vt_mps: 100.0, qbar_pa: 1.0, ..Default::default() }; 50];
        let pitch = information(&s, Axis::Pitch);
        assert!(pitch.score.is_none() && pitch.note.as_deref() == Some("no pitch rate q"));
        let lat = information(&s, Axis::Lateral);
        assert!(lat.note.as_deref() == Some("no aileron δa or rudder δr"), "{lat:?}");
    }
}
