//! Before the check fits anything: are the sensors believable at all? A channel that holds one
//! value throughout (a dead or stuck sensor) or reads in the wrong unit is misread by the fit as
//! biases, time shifts and winds (q in rad/s mapped as deg/s gave a −669 m/s airspeed bias
//! and a 3.1-s α lag, "converged"; an α in the wrong unit, "information matrix singular"). Each
//! test compares a channel with the physics of the others, so it names the channel and the
//! likely unit instead.

use aeroident_estimators::AirDataSample;
use aeroident_io::Mapping;
use aeroident_io::message::short;
use aeroident_physics::rigid_body::{SinCos, body_acceleration, body_velocity, gravity_body};
use aeroident_physics::units::G0_MPS2;

/// The sensor channels the check corrects, as sample fields.
const SENSOR_FIELDS: [&str; 12] = [
    "ax_mps2",
    "ay_mps2",
    "az_mps2",
    "p_rad_s",
    "q_rad_s",
    "r_rad_s",
    "vt_mps",
    "alpha_rad",
    "beta_rad",
    "phi_rad",
    "theta_rad",
    "psi_rad",
];

/// A gain is judged only when it lies outside [1/`BOUND`, `BOUND`]: a vane's calibration
/// (upwash, position) moves it by tens of per cent, a unit by a factor 57.3.
const BOUND: f64 = 2.0;

/// … and more than this many of its σ from 1.
const MIN_SIGMAS: f64 = 10.0;

/// Fewest differenced samples before the α vane's gain is judged.
const MIN_ROWS: usize = 50;

/// A manoeuvre judges the α vane's scale only where the kinematics move α by at least this
/// much, rad (1°; a short period moves it by several): a roll or a Dutch roll barely moves α,
/// and what is left of the kinematic α̇ there is the terms the screen leaves out (β, the
/// accelerometer's offset from the CG), which once read a vane as 0.27× the kinematics on a
/// roll window and 1.109× on the short period of the same flight.
const MIN_ALPHA_EXCURSION_RAD: f64 = 0.0175;

/// Refuses a record whose sensors the check would misread (module doc): a constant channel;
/// a gyro or attitude in the wrong unit (the Euler kinematics, [`crate::kinematics`]);
/// a normal accelerometer in the wrong unit ([`az_misread`]); an α vane in the wrong unit
/// ([`alpha_gain`]), judged on the manoeuvres that move α ([`MIN_ALPHA_EXCURSION_RAD`]). The
/// error names the channel as `mapping` does; `Ok` holds what was not judged, and why.
pub(super) fn believable(
    slices: &[&[AirDataSample]],
    mapping: &Mapping,
) -> Result<Vec<String>, String> {
    for name in SENSOR_FIELDS {
        let values: Vec<f64> =
            slices.iter().flat_map(|m| m.iter()).filter_map(|s| s.field(name)).collect();
        if values.len() >= 2 && values.iter().all(|v| *v == values[0]) {
            return Err(format!(
                "{} holds {} in all {} samples: a dead or stuck sensor; leave it out of the mapping or fix the record",
                mapping.field_label(name),
                short(values[0]),
                values.len()
            ));
        }
    }
    let kinematics = crate::kinematics::Kinematics::of_manoeuvres(slices);
    let mut misread: Vec<String> =
        kinematics.warnings(mapping).into_iter().map(|w| w.text).collect();
    // The accelerometer first: it enters the vane's kinematic α̇, and its mean needs no vane.
    misread.extend(az_misread(slices, mapping));
    let (moving, not_judged) = moving_alpha(slices, mapping);
    misread.extend(alpha_misread(&moving, mapping));
    match misread.first() {
        Some(w) => Err(format!(
            "{w}; the check would turn it into biases, time shifts and winds: fix the mapping or the record first"
        )),
        None => Ok(not_judged.into_iter().collect()),
    }
}

/// The manoeuvres whose kinematic α moves by [`MIN_ALPHA_EXCURSION_RAD`] or more, and the note
/// naming those left out of the vane's judgement (`None` when none is).
fn moving_alpha<'a>(
    slices: &[&'a [AirDataSample]],
    mapping: &Mapping,
) -> (Vec<&'a [AirDataSample]>, Option<String>) {
    let excursions: Vec<Option<f64>> = slices.iter().map(|m| alpha_excursion(m)).collect();
    let moving: Vec<&[AirDataSample]> = slices
        .iter()
        .zip(&excursions)
        .filter(|(_, e)| e.is_some_and(|e| e >= MIN_ALPHA_EXCURSION_RAD))
        .map(|(m, _)| *m)
        .collect();
    let still: Vec<String> = excursions
        .iter()
        .enumerate()
        .filter_map(|(i, e)| e.filter(|e| *e < MIN_ALPHA_EXCURSION_RAD).map(|e| (i, e)))
        .map(|(i, e)| format!("manoeuvre {} ({:.2}°)", i + 1, e.to_degrees()))
        .collect();
    let note = (!still.is_empty()).then(|| {
        format!(
            "{}'s scale is not judged on {}: the kinematics move α by less than {:.1}° there, too little to fix a vane's scale (a roll or a Dutch roll); the check runs",
            mapping.field_label("alpha_rad"),
            still.join(", "),
            MIN_ALPHA_EXCURSION_RAD.to_degrees()
        )
    });
    (moving, note)
}

/// The excursion (max − min) of the kinematic α over one manoeuvre, rad: `α̇` ([`alpha_rate`],
/// with β where mapped) integrated (trapezoidal) over its samples, less the line an
/// accelerometer bias integrates to. `None` without the channels on every sample.
fn alpha_excursion(slice: &[AirDataSample]) -> Option<f64> {
    let (t, rate): (Vec<f64>, Vec<f64>) =
        slice.iter().filter_map(|s| Some((s.t_s, alpha_rate(s, true)?))).unzip();
    if t.len() < 3 {
        return None;
    }
    let alpha = crate::kinematics::integral_less_line(&t, &rate);
    let (lo, hi) =
        alpha.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), a| (l.min(*a), h.max(*a)));
    (hi - lo).is_finite().then_some(hi - lo)
}

/// The forms a normal accelerometer's reading takes, `reading = k a_z + b` (`k`, `b` m/s²), with
/// what each is in words: the specific force itself first.
const AZ_FORMS: [(f64, f64, &str); 8] = [
    (1.0, 0.0, "the specific force"),
    (1.0 / G0_MPS2, 0.0, "likely a reading in g mapped as m/s²: map it with `unit = \"g\"`"),
    (G0_MPS2, 0.0, "likely m/s² data mapped in g: map it with `unit = \"m/s2\"`"),
    (1.0 / 0.3048, 0.0, "likely ft/s² data mapped as m/s²: map it with `unit = \"ft/s2\"`"),
    (0.3048, 0.0, "likely m/s² data mapped in ft/s²: map it with `unit = \"m/s2\"`"),
    (
        1.0,
        G0_MPS2,
        "likely gravity removed (a_z + 1 g, a load factor − 1 g reading 0 in level flight): map it with `offset = -1` in g (or `-9.80665` in m/s²)",
    ),
    (
        -1.0,
        -G0_MPS2,
        "likely a load factor − 1 g (n − 1, 0 in level flight, positive up): map it with `unit = \"g\"`, `scale = -1`, `offset = -1`",
    ),
    (
        -1.0,
        0.0,
        "likely a load factor (n = −a_z/g, +1 in level flight) or a reversed sign: map it with `scale = -1`",
    ),
];

/// A mean differs from a form's by at most this, m/s² (0.35 g: a gyro bias of 0.01 rad/s at
/// 200 m/s moves the kinematic mean by 2 m/s²; the forms lie 8 m/s² or more apart).
const AZ_MEAN_TOLERANCE_MPS2: f64 = 0.35 * G0_MPS2;

/// The normal accelerometer's spread is compared with the kinematics' only above this, m/s²
/// (about 0.03 g: a manoeuvre, not a steady segment).
const AZ_MIN_SPREAD_MPS2: f64 = 0.3;

/// A reading's spread may differ from a form's by this factor: the kinematic spread without
/// `ẇ` is up to about twice the specific force's, and the g forms lie a factor 9.8 apart
/// (the m/s² and ft/s² forms, 3.3 apart, may both fit).
const AZ_SPREAD_FACTOR: f64 = 2.5;

/// The normal accelerometer's reading against the force equations,
/// `a_z = ẇ − q u + p v − g cosθ cosφ` (Stevens & Lewis, 2nd ed., Table 2.5-1) without `ẇ`
/// ([`kinematic_az`]), compared by mean and spread, which a sensor's lag does not move as it
/// moves a regression's gain. Only the mean decides whether the reading is the specific force
/// (the spread without `ẇ` is the short period's `q u`, up to about twice the specific
/// force's); the spread and sign then choose among the other forms.
#[derive(Debug, Clone, Copy)]
struct AzLevels {
    /// Mean and standard deviation of the reading, m/s².
    mean: f64,
    sd: f64,
    /// The same of the kinematic value, m/s².
    kin_mean: f64,
    kin_sd: f64,
    /// Their covariance's sign.
    sign: f64,
}

impl AzLevels {
    /// The levels over the samples that carry `a_z`, `q` and `θ` ([`kinematic_az`]); `None`
    /// with fewer than [`MIN_ROWS`].
    fn of(slices: &[&[AirDataSample]]) -> Option<Self> {
        let pairs: Vec<(f64, f64)> = slices
            .iter()
            .flat_map(|m| m.iter())
            .filter_map(|s| Some((s.az_mps2?, kinematic_az(s)?)))
            .collect();
        if pairs.len() < MIN_ROWS {
            return None;
        }
        let n = pairs.len() as f64;
        let (mean, kin_mean) = (
            pairs.iter().map(|p| p.0).sum::<f64>() / n,
            pairs.iter().map(|p| p.1).sum::<f64>() / n,
        );
        let var = |f: &dyn Fn(&(f64, f64)) -> f64| pairs.iter().map(f).sum::<f64>() / n;
        let sd = var(&|p| (p.0 - mean).powi(2)).sqrt();
        let kin_sd = var(&|p| (p.1 - kin_mean).powi(2)).sqrt();
        let sign = var(&|p| (p.0 - mean) * (p.1 - kin_mean)).signum();
        Some(Self { mean, sd, kin_mean, kin_sd, sign })
    }

    /// Does the reading take the form `k a_z + b`: its mean within [`AZ_MEAN_TOLERANCE_MPS2`]
    /// (times |k| above 1), and where both spread beyond [`AZ_MIN_SPREAD_MPS2`], its spread
    /// within a factor [`AZ_SPREAD_FACTOR`] of |k| times the kinematics' and its covariance of
    /// k's sign?
    fn fits(&self, k: f64, b: f64) -> bool {
        let mean_ok = self.fits_mean(k, b);
        let spread = self.kin_sd > AZ_MIN_SPREAD_MPS2
            && self.sd.max(k.abs() * self.kin_sd) > AZ_MIN_SPREAD_MPS2;
        let sd_ok =
            !spread || (self.sd / (k.abs() * self.kin_sd)).ln().abs() <= AZ_SPREAD_FACTOR.ln();
        let sign_ok = !spread || self.sign * k > 0.0;
        mean_ok && sd_ok && sign_ok
    }

    /// Does the reading's mean take the form `k a_z + b` ([`AzLevels::fits`])?
    fn fits_mean(&self, k: f64, b: f64) -> bool {
        (self.mean - (k * self.kin_mean + b)).abs() <= AZ_MEAN_TOLERANCE_MPS2 * k.abs().max(1.0)
    }

    /// `None` when the reading's mean is the specific force's; else the mismatch in words, naming every
    /// form it fits (the same words on any window of one flight that a form explains).
    fn finding(&self, label: &str) -> Option<String> {
        if self.fits_mean(AZ_FORMS[0].0, AZ_FORMS[0].1) {
            return None;
        }
        let fitting: Vec<&str> =
            AZ_FORMS[1..].iter().filter(|f| self.fits(f.0, f.1)).map(|f| f.2).collect();
        let likely = if fitting.is_empty() {
            "check its unit, sign and offset in the mapping".to_string()
        } else {
            fitting.join("; or ")
        };
        Some(format!(
            "unit mismatch: {label} reads {} ± {} m/s² (mean ± spread) where the rates and attitude give {} ± {} m/s² (−q u + p v − g cosθ cosφ, ẇ left out); {likely}",
            short(self.mean),
            short(self.sd),
            short(self.kin_mean),
            short(self.kin_sd)
        ))
    }
}

/// `a_z` from the force equations without `ẇ`: `−q u + p v − g cosθ cosφ` at one sample,
/// `p`, `φ` and β 0 where missing; `None` without `q` or `θ`. `ẇ` is left out: its mean over a
/// manoeuvre is the change of `w` over its length, and its difference of a noisy vane has a
/// spread of its own (0.001 rad at 100 Hz and 200 m/s: 14 m/s²), which no accelerometer has.
fn kinematic_az(s: &AirDataSample) -> Option<f64> {
    let v = body_velocity(s.vt_mps, SinCos::of(s.alpha_rad), SinCos::of(s.beta_rad.unwrap_or(0.0)));
    let (phi, theta) = (s.phi_rad.unwrap_or(0.0), s.theta_rad?);
    let az =
        -s.q_rad_s? * v[0] + s.p_rad_s.unwrap_or(0.0) * v[1] - G0_MPS2 * theta.cos() * phi.cos();
    az.is_finite().then_some(az)
}

/// The unit mix-ups the normal accelerometer's mean magnitude over `g` points to.
const AZ_UNIT_FACTORS: [(f64, &str); 4] = [
    (G0_MPS2, "likely m/s² data mapped in g: map it with `unit = \"m/s2\"`"),
    (1.0 / G0_MPS2, "likely a reading in g mapped as m/s²: map it with `unit = \"g\"`"),
    (1.0 / 0.3048, "likely ft/s² data mapped as m/s²: map it with `unit = \"ft/s2\"`"),
    (0.3048, "likely m/s² data mapped in ft/s²: map it with `unit = \"m/s2\"`"),
];

/// The normal accelerometer's unit-mismatch text: against the force equations where the record
/// maps `q` and `θ` ([`AzLevels`]), else when its mean magnitude over the record is
/// more than a factor [`BOUND`] from `g`: in flight `a_z` carries the load factor, whose mean
/// over any manoeuvre a flight record holds is near 1 g (a 2-g turn held throughout is the
/// rare exception). The mean does not depend on the sensors' lags, which bias a regression
/// against the force equations (a degraded record with the α vane 0.2 s late read a_z 2.7 times
/// its kinematic value).
fn az_misread(slices: &[&[AirDataSample]], mapping: &Mapping) -> Option<String> {
    if let Some(levels) = AzLevels::of(slices) {
        return levels.finding(&mapping.field_label("az_mps2"));
    }
    let values: Vec<f64> = slices.iter().flat_map(|m| m.iter()).filter_map(|s| s.az_mps2).collect();
    if values.len() < MIN_ROWS {
        return None;
    }
    let mean = values.iter().map(|v| v.abs()).sum::<f64>() / values.len() as f64;
    let factor = mean / G0_MPS2;
    if (1.0 / BOUND..=BOUND).contains(&factor) {
        return None;
    }
    let likely = AZ_UNIT_FACTORS
        .iter()
        .filter(|(f, _)| (factor / f).ln().abs() < 1.5f64.ln())
        .min_by(|a, b| (factor / a.0).ln().abs().total_cmp(&(factor / b.0).ln().abs()))
        .map_or("check its unit and scale in the mapping", |u| u.1);
    Some(format!(
        "unit mismatch: {} has a mean magnitude of {} m/s² over the record, {} g, where flight holds about 1 g; {likely}",
        mapping.field_label("az_mps2"),
        short(mean),
        short(factor)
    ))
}

/// The α vane's unit-mismatch text when its gain ([`alpha_gain`]) is judged off, or the text
/// of a vane that does not follow the kinematics at all (a gain within 3σ of 0).
fn alpha_misread(slices: &[&[AirDataSample]], mapping: &Mapping) -> Option<String> {
    // The kinematic rate takes the side velocity from β: a β channel that is late or wrong
    // would be blamed on α (ATTAS with β 1 s late: gain 0.35). Judged with β and without
    // (v = 0, the lateral terms lost), α is named only when both are off.
    let with = alpha_gain(slices, true)?;
    let (k, sigma) = match alpha_gain(slices, false) {
        Some(without) if (without.0 - 1.0).abs() < (with.0 - 1.0).abs() => without,
        _ => with,
    };
    let off = !(1.0 / BOUND..=BOUND).contains(&k);
    if !off || (k - 1.0).abs() <= MIN_SIGMAS * sigma {
        return None;
    }
    // No relation, or one against the motion: a unit would scale the motion, not remove or
    // reverse it.
    let unrelated = if k.abs() <= 3.0 * sigma {
        Some("does not follow")
    } else {
        (k < 0.0).then_some("moves against")
    };
    if let Some(how) = unrelated {
        return Some(format!(
            "{} {how} the angle of attack the rates, accelerometers and attitude give (its rate's gain on theirs {} ± {}, where 1 is a vane that agrees): a reversed sign (`scale = -1`), a channel delayed or misaligned in time (its time stamps), or another column or record",
            mapping.field_label("alpha_rad"),
            short(k),
            short(sigma)
        ));
    }
    let deg = 180.0 / core::f64::consts::PI;
    let near = |target: f64| (k - target).abs() <= (0.2 * target).max(3.0 * sigma);
    let likely = if near(1.0 / deg) {
        "likely radians mapped as degrees"
    } else if near(deg) {
        "likely degrees mapped as radians"
    } else {
        "check its unit and scale in the mapping"
    };
    Some(format!(
        "unit mismatch: {} moves {} ± {} times as fast as the angle of attack the rates, accelerometers and attitude give (1 when its unit agrees); {likely}",
        mapping.field_label("alpha_rad"),
        short(k),
        short(sigma)
    ))
}

/// The gain `(k, σ)` of the least-squares fit `α̇_m = k α̇ + b`, where `α̇_m` is the vane's
/// central difference and `α̇ = (u ẇ − w u̇)/(u² + w²)` the kinematic rate from the force
/// equations (Stevens & Lewis, 2nd ed., Table 2.5-1) with `(u, v, w)` from the air data (`v` = 0 without `with_beta`) and the
/// measured specific forces: dominated by `q`, so a vane in the wrong unit shows as a factor 57.3.
/// `None` without the channels or with too few samples.
pub(super) fn alpha_gain(slices: &[&[AirDataSample]], with_beta: bool) -> Option<(f64, f64)> {
    let mut rows: Vec<(f64, f64)> = Vec::new();
    for m in slices {
        for w in m.windows(3) {
            let span = w[2].t_s - w[0].t_s;
            if span.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                continue;
            }
            let measured = (w[2].alpha_rad - w[0].alpha_rad) / span;
            if let Some(kinematic) = alpha_rate(&w[1], with_beta) {
                rows.push((measured, kinematic));
            }
        }
    }
    if rows.len() < MIN_ROWS {
        return None;
    }
    let n = rows.len() as f64;
    let (my, mx) =
        (rows.iter().map(|r| r.0).sum::<f64>() / n, rows.iter().map(|r| r.1).sum::<f64>() / n);
    let sxx: f64 = rows.iter().map(|r| (r.1 - mx).powi(2)).sum();
    let sxy: f64 = rows.iter().map(|r| (r.1 - mx) * (r.0 - my)).sum();
    if sxx.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let k = sxy / sxx;
    let sse: f64 = rows.iter().map(|r| (r.0 - my - k * (r.1 - mx)).powi(2)).sum();
    let sigma = (sse / (n - 2.0) / sxx).sqrt();
    (k.is_finite() && sigma.is_finite()).then_some((k, sigma))
}

/// `α̇` of one sample from the force equations (see [`alpha_gain`]), the side velocity from
/// its β (`with_beta`) or 0.
fn alpha_rate(s: &AirDataSample, with_beta: bool) -> Option<f64> {
    let a = [s.ax_mps2?, s.ay_mps2.unwrap_or(0.0), s.az_mps2?];
    let omega = [s.p_rad_s.unwrap_or(0.0), s.q_rad_s?, s.r_rad_s.unwrap_or(0.0)];
    let (phi, theta) = (SinCos::of(s.phi_rad.unwrap_or(0.0)), SinCos::of(s.theta_rad?));
    let beta = s.beta_rad.filter(|_| with_beta).unwrap_or(0.0);
    let v = body_velocity(s.vt_mps, SinCos::of(s.alpha_rad), SinCos::of(beta));
    let d = body_acceleration(v, omega, gravity_body(G0_MPS2, phi, theta), a);
    let uw = v[0] * v[0] + v[2] * v[2];
    (uw > 0.0).then(|| (v[0] * d[2] - v[2] * d[0]) / uw)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pull_up() -> Vec<AirDataSample> {
        let dt = 0.02;
        let mut samples = Vec::new();
        for i in 0..1000 {
            let t = i as f64 * dt;
            let (vt, vt_dot) = (100.0 + 2.0 * (0.5 * t).sin(), (0.5 * t).cos());
            let q = 0.1 * (2.0 * t).sin();
            let theta = 0.05 - 0.05 * (2.0 * t).cos();
            let alpha = 0.05 + 0.02 * (1.3 * t).sin();
            let alpha_dot = 0.026 * (1.3 * t).cos();
            // u̇ = a_x − g sinθ − q w and ẇ = a_z + g cosθ + q u (wings level, no roll or yaw):
            // choose a_x, a_z so that (u ẇ − w u̇)/V² = α̇, with u = V cosα, w = V sinα.
            let (u, w) = (vt * alpha.cos(), vt * alpha.sin());
            let u_dot = vt_dot * alpha.cos() - w * alpha_dot;
            let w_dot = vt_dot * alpha.sin() + u * alpha_dot;
            samples.push(AirDataSample {
                t_s: t,
                vt_mps: vt,
                alpha_rad: alpha,
                q_rad_s: Some(q),
                theta_rad: Some(theta),
                ax_mps2: Some(u_dot + G0_MPS2 * theta.sin() + q * w),
                az_mps2: Some(w_dot - q * u - G0_MPS2 * theta.cos()),
                ..AirDataSample::default()
            });
        }
        samples
    }

    fn mapping() -> Mapping {
        Mapping::from_toml_str(
            "[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"v\", unit = \"m/s\" }\nalpha = { column = \"aoa\", unit = \"deg\" }\nq = { column = \"q\", unit = \"rad/s\" }\ntheta = { column = \"th\", unit = \"rad\" }\nax = { column = \"ax\", unit = \"m/s2\" }\naz = { column = \"az\", unit = \"m/s2\" }\nqbar = { value = 1000.0, unit = \"Pa\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\n",
            "m.toml",
        )
        .unwrap()
    }

    #[test]
    fn believable_refuses_a_stuck_channel_and_a_vane_in_the_wrong_unit_and_passes_a_flown_record() {
        let samples = pull_up();
        assert_eq!(believable(&[&samples], &mapping()), Ok(vec![]));
        assert_eq!(believable(&[&samples[..1]], &mapping()), Ok(vec![]));
        let stuck: Vec<AirDataSample> =
            samples.iter().map(|s| AirDataSample { q_rad_s: Some(0.02), ..*s }).collect();
        let e = believable(&[&stuck[..500], &stuck[500..]], &mapping()).unwrap_err();
        assert!(
            e.starts_with("channel `q` (column `q`")
                && e.contains("holds 0.02 in all 1000 samples: a dead or stuck sensor"),
            "{e}"
        );
        let radians: Vec<AirDataSample> = samples
            .iter()
            .map(|s| AirDataSample { alpha_rad: s.alpha_rad.to_radians(), ..*s })
            .collect();
        let e = believable(&[&radians], &mapping()).unwrap_err();
        assert!(
            e.contains("likely radians mapped as degrees; the check would turn it into biases"),
            "{e}"
        );
    }

    fn with_az(factor: f64, n: usize) -> Vec<AirDataSample> {
        let az = |i: usize| {
            if i.is_multiple_of(2) { -factor * G0_MPS2 } else { -factor * G0_MPS2 * 0.5 }
        };
        (0..n)
            .map(|i| AirDataSample { az_mps2: Some(az(i) * 4.0 / 3.0), ..AirDataSample::default() })
            .collect()
    }

    #[test]
    fn the_normal_accelerometer_is_judged_by_its_mean_magnitude_from_fifty_rows() {
        let text = |factor: f64, n: usize| az_misread(&[&with_az(factor, n)], &mapping());
        assert_eq!(text(3.0, 49), None);
        assert_eq!(text(1.99, 50), None);
        assert_eq!(text(0.51, 50), None);
        for (factor, likely) in [
            (2.01, "check its unit and scale in the mapping"),
            (0.49, "check its unit and scale in the mapping"),
            (9.0, "likely m/s² data mapped in g: map it with `unit = \"m/s2\"`"),
            (0.3048, "likely m/s² data mapped in ft/s²"),
            (3.0, "likely ft/s² data mapped as m/s²"),
            (0.1, "likely a reading in g mapped as m/s²"),
        ] {
            let t = text(factor, 50).unwrap_or_else(|| panic!("{factor}"));
            assert!(
                t.starts_with("unit mismatch: channel `az` (column `az`) has a mean magnitude of "),
                "{t}"
            );
            assert!(
                t.contains(likely) && t.contains(&format!(", {} g, ", short(factor))),
                "{factor}: {t}"
            );
        }
        let at_one_and_a_half: Vec<AirDataSample> = (0..50)
            .map(|_| AirDataSample {
                az_mps2: Some(-48.26107283464566),
                ..AirDataSample::default()
            })
            .collect();
        let t = az_misread(&[&at_one_and_a_half], &mapping()).unwrap();
        assert!(
            t.ends_with("check its unit and scale in the mapping"),
            "exactly 1.5 × 1/0.3048: {t}"
        );
    }

    /// A pull-up at 100 m/s, q = 0.1 sin(2t) rad/s, with α following the kinematics exactly
    /// (α̇ = q + (a_z + g cosθ)/V with the specific force chosen so): the gain is 1; the same
    /// α divided by 57.3 (radians mapped as degrees) gives 1/57.3 and names it.
    #[test]
    fn the_alpha_vane_gain_is_one_on_consistent_data_and_names_a_unit() {
        let mut samples = pull_up();
        let (k, sigma) = alpha_gain(&[&samples], true).unwrap();
        assert!((k - 1.0).abs() < 1e-3 && sigma < 1e-3, "{k} ± {sigma}");
        let mapping = Mapping::from_toml_str(
            "[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"v\", unit = \"m/s\" }\nalpha = { column = \"aoa\", unit = \"deg\" }\nq = { column = \"q\", unit = \"rad/s\" }\ntheta = { column = \"th\", unit = \"rad\" }\nax = { column = \"ax\", unit = \"m/s2\" }\naz = { column = \"az\", unit = \"m/s2\" }\nqbar = { value = 1000.0, unit = \"Pa\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\n",
            "m.toml",
        )
        .unwrap();
        assert!(alpha_misread(&[&samples], &mapping).is_none());
        for s in &mut samples {
            s.alpha_rad /= 180.0 / core::f64::consts::PI;
        }
        let (k, _) = alpha_gain(&[&samples], true).unwrap();
        assert!((k * 57.2958 - 1.0).abs() < 0.05, "{k}");
        let text = alpha_misread(&[&samples], &mapping).unwrap();
        assert!(text.contains("likely radians mapped as degrees"), "{text}");
        assert!(text.contains("column `aoa`"), "{text}");
        // The normal accelerometer: about −1 g in m/s² passes; the same in g (−1) or in
        // ft/s² mapped as m/s² (−32.2) is named with its likely unit.
        assert!(az_misread(&[&samples], &mapping).is_none());
        for (scale, likely) in
            [(1.0 / G0_MPS2, "a reading in g"), (1.0 / 0.3048, "ft/s² data mapped as m/s²")]
        {
            let scaled: Vec<AirDataSample> = samples
                .iter()
                .map(|s| AirDataSample { az_mps2: s.az_mps2.map(|a| a * scale), ..*s })
                .collect();
            let text = az_misread(&[&scaled], &mapping).unwrap();
            assert!(text.contains(likely) && text.contains("column `az`"), "{text}");
        }
    }

    fn vane(rows: usize, gain: f64, wobble: f64, beta: Option<f64>) -> Vec<AirDataSample> {
        let kinematic = |i: usize| 0.003 + if i.is_multiple_of(2) { 0.01 } else { -0.01 };
        let measured = |i: usize| {
            let e = if i % 4 < 2 { wobble } else { -wobble };
            gain * kinematic(i) + 0.001 + e
        };
        let mut alpha = vec![0.05; rows + 2];
        for i in 1..=rows {
            alpha[i + 1] = alpha[i - 1] + 0.2 * measured(i - 1);
        }
        (0..rows + 2)
            .map(|i| {
                let target = if (1..=rows).contains(&i) { kinematic(i - 1) } else { 0.0 };
                AirDataSample {
                    t_s: 0.1 * i as f64,
                    vt_mps: 100.0,
                    alpha_rad: alpha[i],
                    beta_rad: beta,
                    q_rad_s: Some(0.0),
                    theta_rad: Some(0.0),
                    ax_mps2: Some(0.0),
                    az_mps2: Some(target * 100.0 / alpha[i].cos() - G0_MPS2),
                    ..AirDataSample::default()
                }
            })
            .collect()
    }

    #[test]
    fn the_alpha_gain_is_the_least_squares_slope_with_its_standard_error_from_fifty_rows() {
        let (k, sigma) = alpha_gain(&[&vane(52, 2.0, 0.005, None)], true).unwrap();
        let expected_sigma = (52.0 * 0.005f64.powi(2) / 50.0 / (52.0 * 1e-4)).sqrt();
        assert!((k - 2.0).abs() < 1e-9, "{k}");
        assert!((sigma / expected_sigma - 1.0).abs() < 1e-6, "{sigma} {expected_sigma}");
        assert!(alpha_gain(&[&vane(50, 2.0, 0.005, None)], true).is_some());
        assert_eq!(alpha_gain(&[&vane(49, 2.0, 0.005, None)], true), None);
        let mut repeated = vane(50, 2.0, 0.005, None);
        repeated[2].t_s = repeated[0].t_s;
        assert_eq!(alpha_gain(&[&repeated], true), None);
        let mut stopped = vane(52, 2.0, 0.005, None);
        stopped[10].vt_mps = 0.0;
        let (k, _) = alpha_gain(&[&stopped], true).expect("the row without a velocity is left out");
        assert!((k - 2.0).abs() < 0.01, "{k}");
        assert_eq!(alpha_gain(&[&vane(52, 1e160, 1e160, None)], true), None, "σ overflows");
        let (k, _) = alpha_gain(&[&vane(52, 1.0, 0.0, Some(60f64.to_radians()))], true).unwrap();
        assert!((k - 0.5).abs() < 1e-9, "with β the kinematic rate doubles: {k}");
    }

    #[test]
    fn an_alpha_vane_is_named_outside_half_to_twice_beyond_ten_sigma_with_its_likely_cause() {
        let text =
            |gain: f64, wobble: f64| alpha_misread(&[&vane(52, gain, wobble, None)], &mapping());
        for gain in [1.9, 0.6] {
            assert_eq!(text(gain, 0.002), None, "{gain}");
        }
        assert_eq!(text(2.5, 0.015), None);
        for (gain, wobble, cause) in [
            (2.1, 0.005, "check its unit and scale in the mapping"),
            (0.45, 0.002, "check its unit and scale in the mapping"),
            (2.5, 0.005, "check its unit and scale in the mapping"),
            (57.3 * 1.19, 0.005, "likely degrees mapped as radians"),
            (57.3 * 1.21, 0.005, "check its unit and scale in the mapping"),
            (-1.0, 0.005, "channel `alpha` (column `aoa`) moves against the angle of attack"),
            (0.0, 0.0001, "channel `alpha` (column `aoa`) does not follow the angle of attack"),
        ] {
            let t = text(gain, wobble).unwrap_or_else(|| panic!("{gain}"));
            assert!(t.contains(cause), "{gain}: {t}");
        }
    }

    #[test]
    fn the_alpha_vane_is_judged_by_the_gain_with_or_without_sideslip_nearer_one() {
        let beta = Some(60f64.to_radians());
        let text = |gain: f64| alpha_misread(&[&vane(52, gain, 0.001, beta)], &mapping());
        assert_eq!(text(2.4), None);
        assert_eq!(text(0.6), None);
        assert_eq!(text(0.8), None);
        let t = text(4.8).unwrap();
        assert!(t.contains("moves 2.4 ± "), "{t}");
    }

    /// 20 s of a wings-level roll-free "lateral" window at 100 m/s: the kinematics move α by
    /// 0.1° (q = 0.002 sin 2t), and the vane wobbles 0.06° on its own, so its gain against the
    /// kinematics is far from 1 without saying anything about its scale.
    fn still_alpha() -> Vec<AirDataSample> {
        (0..1000)
            .map(|i| {
                let t = 0.02 * i as f64;
                let (theta, q) = (0.05 - 0.001 * (2.0 * t).cos(), 0.002 * (2.0 * t).sin());
                AirDataSample {
                    t_s: t,
                    vt_mps: 100.0 + 0.1 * (0.2 * t).sin(),
                    alpha_rad: 0.05 + 0.001 * (0.7 * t).sin(),
                    q_rad_s: Some(q),
                    theta_rad: Some(theta),
                    ax_mps2: Some(G0_MPS2 * theta.sin()),
                    az_mps2: Some(-G0_MPS2 * theta.cos()),
                    ..AirDataSample::default()
                }
            })
            .collect()
    }

    /// A window whose kinematics barely move α does not judge the vane's scale: alone or beside
    /// a pull-up it is named in a note and the check runs; the pull-up still judges a vane in
    /// the wrong unit.
    #[test]
    fn a_window_that_barely_moves_alpha_does_not_judge_the_vane() {
        let (pull, still) = (pull_up(), still_alpha());
        assert!(alpha_misread(&[&still], &mapping()).is_some(), "the gain alone would refuse it");
        let notes = believable(&[&pull, &still], &mapping()).unwrap();
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(
            notes[0].starts_with(
                "channel `alpha` (column `aoa`)'s scale is not judged on manoeuvre 2 (0."
            ) && notes[0].contains("the check runs"),
            "{}",
            notes[0]
        );
        assert_eq!(believable(&[&still], &mapping()).map(|n| n.len()), Ok(1));
        let radians: Vec<AirDataSample> = pull
            .iter()
            .map(|s| AirDataSample { alpha_rad: s.alpha_rad.to_radians(), ..*s })
            .collect();
        let e = believable(&[&radians, &still], &mapping()).unwrap_err();
        assert!(e.contains("likely radians mapped as degrees"), "{e}");
    }

    /// A normal accelerometer that reads the load factor − 1 g is named as such on a pull-up,
    /// and on a steady window (no spread to judge) among the forms a mean near 0 allows: the
    /// same finding, never a unit the mapping already has as the only advice. The specific
    /// force itself passes on both, and a reading in g is named on the pull-up alone.
    #[test]
    fn the_normal_accelerometer_form_is_the_one_that_explains_every_window() {
        let (pull, still) = (pull_up(), still_alpha());
        let with = |rec: &[AirDataSample], f: &dyn Fn(f64) -> f64| -> Vec<AirDataSample> {
            rec.iter().map(|s| AirDataSample { az_mps2: s.az_mps2.map(f), ..*s }).collect()
        };
        assert_eq!(az_misread(&[&pull], &mapping()), None);
        assert_eq!(az_misread(&[&still], &mapping()), None);
        let n_minus_one = |a: f64| -a / G0_MPS2 - 1.0;
        let load = |a: f64| G0_MPS2 * n_minus_one(a);
        let texts: Vec<String> = [&pull, &still]
            .iter()
            .map(|rec| az_misread(&[&with(rec, &load)], &mapping()).unwrap())
            .collect();
        let form = "likely a load factor − 1 g (n − 1, 0 in level flight, positive up)";
        for t in &texts {
            assert!(t.contains(form) && t.contains("channel `az`"), "{t}");
        }
        assert!(!texts[0].contains("; or "), "the pull-up fixes the form: {}", texts[0]);
        let in_g = az_misread(&[&with(&pull, &|a| a / G0_MPS2)], &mapping()).unwrap();
        assert!(
            in_g.contains("a reading in g mapped as m/s²") && !in_g.contains("; or "),
            "{in_g}"
        );
    }

    /// Levels of a reading whose mean is `kin_mean + offset` and whose spread is `ratio` times
    /// the kinematics' (1 m/s², a manoeuvre), in phase.
    fn levels(offset: f64, ratio: f64) -> AzLevels {
        AzLevels { mean: -9.0 + offset, sd: ratio, kin_mean: -9.0, kin_sd: 1.0, sign: 1.0 }
    }

    /// The specific force is decided by the mean alone, at 0.35 g either side; a form is taken
    /// with a spread up to 2.5 times its own either way, and not beyond.
    #[test]
    fn the_accelerometer_thresholds_hold_at_their_edges() {
        let edge = AZ_MEAN_TOLERANCE_MPS2;
        for sign in [1.0, -1.0] {
            assert_eq!(levels(sign * edge * 0.99, 1.0).finding("a_z"), None);
            assert!(levels(sign * edge * 1.01, 1.0).finding("a_z").is_some());
        }
        // Gravity removed (a_z + g): its spread decides between it and no form at all.
        let removed = "likely gravity removed";
        for ratio in [AZ_SPREAD_FACTOR * 0.99, 1.0 / (AZ_SPREAD_FACTOR * 0.99)] {
            let t = levels(G0_MPS2, ratio).finding("a_z").unwrap();
            assert!(t.contains(removed), "{ratio}: {t}");
        }
        for ratio in [AZ_SPREAD_FACTOR * 1.01, 1.0 / (AZ_SPREAD_FACTOR * 1.01)] {
            let t = levels(G0_MPS2, ratio).finding("a_z").unwrap();
            assert!(!t.contains(removed) && t.contains("check its unit"), "{ratio}: {t}");
        }
        // Out of phase, it is not the form whatever the spread.
        let against = AzLevels { sign: -1.0, ..levels(G0_MPS2, 1.0) };
        assert!(!against.finding("a_z").unwrap().contains(removed));
    }

    /// A manoeuvre judges the vane from a 1° kinematic α excursion: the still window's pitch
    /// rate scaled so that α moves 0.99° is noted and left out, 1.01° judged (its
    /// accelerometers carry gravity alone, so the kinematic α̇ is q and scales with it).
    #[test]
    fn the_vane_is_judged_from_one_degree_of_alpha() {
        let still = still_alpha();
        let base = alpha_excursion(&still).unwrap();
        let scaled = |target: f64| -> Vec<AirDataSample> {
            let k = target / base;
            still
                .iter()
                .map(|s| AirDataSample { q_rad_s: s.q_rad_s.map(|q| q * k), ..*s })
                .collect()
        };
        let below = scaled(MIN_ALPHA_EXCURSION_RAD * 0.99);
        let above = scaled(MIN_ALPHA_EXCURSION_RAD * 1.01);
        let excursion = alpha_excursion(&above).unwrap();
        assert!((excursion / MIN_ALPHA_EXCURSION_RAD - 1.01).abs() < 1e-3, "{excursion}");
        let (moving, note) = moving_alpha(&[&below], &mapping());
        assert!(moving.is_empty() && note.is_some_and(|n| n.contains("(0.99°)")));
        let (moving, note) = moving_alpha(&[&above], &mapping());
        assert_eq!((moving.len(), note), (1, None));
    }
}
