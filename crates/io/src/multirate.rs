//! From a multi-rate log's topics to the one [`Table`](crate::table::Table) a mapping reads:
//! select the columns the mapping needs, align them as its `[align]` table says
//! ([`crate::align`]), and add the derived columns of `[attitude]` and `[air_data]`.
//!
//! # Derived columns
//!
//! - `[attitude]` (quaternion `q = (w, x, y, z)`, body → NED, as PX4 `vehicle_attitude.q` and
//!   ArduPilot `XKQ.Q1..Q4` log it), normalised, to the 3-2-1 Euler angles (Stevens & Lewis
//!   3rd ed. §1.8, quaternion ↔ Euler):
//!   `φ = atan2(2(wx + yz), 1 − 2(x² + y²))`, `θ = asin(2(wy − xz))`,
//!   `ψ = atan2(2(wz + xy), 1 − 2(y² + z²))` → [`EULER_PHI`], [`EULER_THETA`], [`EULER_PSI`].
//!   Before alignment the quaternion's sign is made continuous (`q` and `−q` are the same
//!   attitude; interpolating between them would pass through zero); linear alignment then
//!   interpolates the components and the conversion normalises (nlerp: exact at the samples,
//!   error O(Δθ²) between them).
//! - `[air_data]`: the air-relative velocity `v_n − w_n` (NED velocity minus the wind's north
//!   and east components, no vertical wind) rotated into body axes with the transpose of the
//!   quaternion's direction-cosine matrix, `(u, v, w) = Cᵀ(q)(v_n − w_n)`, gives
//!   `V = |(u, v, w)|`, `α = atan2(w, u)`, `β = asin(v / V)` (Stevens & Lewis 3rd ed.
//!   eq. 2.3-6) → [`AIR_VT`], [`AIR_ALPHA`], [`AIR_BETA`]. Below `min_vt_mps` the flow angles
//!   are undefined: `air.alpha`/`air.beta` are NaN there and the reader rejects the row naming
//!   the column (`air.vt` is kept). These are **inertial** flow angles (GNSS/EKF velocity and
//!   an estimated wind, not vanes): gusts the wind estimate does not follow appear as α, β
//!   errors.

use crate::FlightDataError;
use crate::align::{Aligned, Clock, TIME_COLUMN, align_with_room, select};
use crate::mapping::{
    AIR_ALPHA, AIR_BETA, AIR_VT, EULER_PHI, EULER_PSI, EULER_THETA, Mapping, Source,
};
use crate::table::Topic;

/// Is `column` one this module derives (not read from the log)?
pub fn is_derived(column: &str) -> bool {
    [EULER_PHI, EULER_THETA, EULER_PSI, AIR_VT, AIR_ALPHA, AIR_BETA].contains(&column)
}

/// The `(column, needed by)` pairs `mapping` reads from a log, in channel order, then the
/// `[attitude]` and `[air_data]` inputs.
pub fn needed_columns(mapping: &Mapping) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    let mut add = |c: &str, by: String| {
        if !is_derived(c) && !out.iter().any(|(x, _)| x == c) {
            out.push((c.to_string(), by));
        }
    };
    for (ch, m) in &mapping.channels {
        if let Source::Columns(cols) = &m.source {
            for (c, _) in cols {
                add(c, format!("channel `{}`", ch.key()));
            }
        }
    }
    if let Some(q) = &mapping.quaternion {
        for c in q {
            add(c, "[attitude] quaternion".into());
        }
    }
    if let Some(a) = &mapping.air_data {
        for c in &a.ned_velocity {
            add(c, "[air_data] ned_velocity".into());
        }
        for c in a.wind_ne.iter().flatten() {
            add(c, "[air_data] wind_ne".into());
        }
    }
    out
}

/// Unit quaternion (w, x, y, z) → (φ, θ, ψ), rad (module doc). NaN for a zero quaternion.
pub fn euler_from_quaternion(q: [f64; 4]) -> [f64; 3] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if !(n > 0.0 && n.is_finite()) {
        return [f64::NAN; 3];
    }
    let [w, x, y, z] = q.map(|c| c / n);
    let phi = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let theta = (2.0 * (w * y - x * z)).clamp(-1.0, 1.0).asin();
    let psi = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    [phi, theta, psi]
}

/// `(V, α, β)` from the air-relative NED velocity and the attitude quaternion (module doc);
/// α, β are NaN when `V < min_vt`.
pub fn air_data(q: [f64; 4], v_ned: [f64; 3], min_vt: f64) -> [f64; 3] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if !(n > 0.0 && n.is_finite()) {
        return [f64::NAN; 3];
    }
    let [w, x, y, z] = q.map(|c| c / n);
    // Body → NED direction-cosine matrix C(q); body velocity = Cᵀ v_ned.
    let c = [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
    ];
    let b: [f64; 3] =
        std::array::from_fn(|j| c[0][j] * v_ned[0] + c[1][j] * v_ned[1] + c[2][j] * v_ned[2]);
    let vt = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
    if vt < min_vt {
        return [vt, f64::NAN, f64::NAN];
    }
    [vt, b[2].atan2(b[0]), (b[1] / vt).clamp(-1.0, 1.0).asin()]
}

/// Makes the quaternion columns of `topic` sign-continuous (flip `q_k` when `q_k · q_{k−1} < 0`).
fn continuous_quaternion(topic: &mut Topic, fields: &[&str; 4]) {
    let idx: Vec<usize> =
        fields.iter().filter_map(|f| topic.fields.iter().position(|(n, _)| n == f)).collect();
    if idx.len() != 4 {
        return;
    }
    for k in 1..topic.t_s.len() {
        let dot: f64 = idx.iter().map(|&i| topic.fields[i].1[k] * topic.fields[i].1[k - 1]).sum();
        if dot < 0.0 {
            for &i in &idx {
                topic.fields[i].1[k] = -topic.fields[i].1[k];
            }
        }
    }
}

/// The aligned table `mapping` reads from a log's `topics` (module doc). `file` names the log.
///
/// # Errors
/// [`FlightDataError::BadSpec`] for a mapping without `[align]`, with a time column other than
/// [`TIME_COLUMN`], or with quaternion components from different topics;
/// [`FlightDataError::MissingTopic`] naming the first column (topic/message and field) the log
/// lacks and what needs it; the errors of [`crate::align::align`].
pub fn log_table(
    topics: &[Topic],
    mapping: &Mapping,
    file: &str,
) -> Result<Aligned, FlightDataError> {
    let bad = |channel: &str, reason: String| FlightDataError::BadSpec {
        file: mapping.file.clone(),
        channel: channel.to_string(),
        reason,
    };
    let spec = mapping.align.as_ref().ok_or_else(|| {
        bad("align", "a multi-rate log needs an [align] table (rate_hz or clock, method)".into())
    })?;
    match &mapping.time.source {
        Source::Columns(c) if c.len() == 1 && c[0].0 == TIME_COLUMN => {}
        _ => {
            return Err(bad(
                "time",
                format!("the time column of an aligned log is `{TIME_COLUMN}` (unit \"s\")"),
            ));
        }
    }
    let mut chosen = select(topics, &needed_columns(mapping), file)?;
    if let Clock::Topic(name) = &spec.clock
        && !chosen.iter().any(|t| &t.name == name)
    {
        let t = topics.iter().find(|t| &t.name == name).ok_or_else(|| {
            FlightDataError::MissingTopic {
                file: file.to_string(),
                column: name.clone(),
                needed_by: "[align] clock".into(),
                reason: format!("the log has no topic/message `{name}`"),
            }
        })?;
        chosen.push(Topic { name: t.name.clone(), t_s: t.t_s.clone(), fields: Vec::new() });
    }
    let q_split: Option<Vec<(String, &str)>> = mapping
        .quaternion
        .as_ref()
        .map(|q| q.iter().filter_map(|c| crate::align::split_column(c)).collect());
    if let Some(parts) = &q_split {
        if parts.len() != 4 || parts.iter().any(|(t, _)| *t != parts[0].0) {
            return Err(bad(
                "attitude.quaternion",
                "the four components must be fields of one topic".into(),
            ));
        }
        let fields = [parts[0].1, parts[1].1, parts[2].1, parts[3].1];
        if let Some(t) = chosen.iter_mut().find(|t| t.name == parts[0].0) {
            continuous_quaternion(t, &fields);
        }
    }
    // The derived columns and their row-by-row temporaries (quaternions: 4, Euler angles:
    // 3 + 3, air data: 3 + 3) count against the table's memory cap too.
    let room = if mapping.quaternion.is_some() { 10 } else { 0 }
        + if mapping.air_data.is_some() { 6 } else { 0 };
    let mut out = align_with_room(&chosen, &spec.clock, spec.method, file, room)?;
    let col = |out: &Aligned, name: &str| {
        let key = match crate::align::split_column(name) {
            Some((t, f)) => format!("{t}.{f}"),
            None => name.to_string(),
        };
        out.table.names.iter().position(|n| *n == key)
    };
    if let Some(q) = &mapping.quaternion {
        let qi: Vec<usize> = q.iter().filter_map(|c| col(&out, c)).collect();
        let rows = out.table.columns[0].len();
        let qs: Vec<[f64; 4]> =
            (0..rows).map(|r| std::array::from_fn(|k| out.table.columns[qi[k]][r])).collect();
        let e: Vec<[f64; 3]> = qs.iter().map(|q| euler_from_quaternion(*q)).collect();
        for (k, name) in [EULER_PHI, EULER_THETA, EULER_PSI].iter().enumerate() {
            out.table.names.push(name.to_string());
            out.table.columns.push(e.iter().map(|x| x[k]).collect());
        }
        if let Some(a) = &mapping.air_data {
            let vi: Vec<usize> = a.ned_velocity.iter().filter_map(|c| col(&out, c)).collect();
            let wi: Vec<usize> = a.wind_ne.iter().flatten().filter_map(|c| col(&out, c)).collect();
            let air: Vec<[f64; 3]> = (0..rows)
                .map(|r| {
                    let v = |k: usize| out.table.columns[vi[k]][r];
                    let w = |k: usize| wi.get(k).map_or(0.0, |&i| out.table.columns[i][r]);
                    air_data(qs[r], [v(0) - w(0), v(1) - w(1), v(2)], a.min_vt_mps)
                })
                .collect();
            for (k, name) in [AIR_VT, AIR_ALPHA, AIR_BETA].iter().enumerate() {
                out.table.names.push(name.to_string());
                out.table.columns.push(air.iter().map(|x| x[k]).collect());
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// q = q_z(ψ) ⊗ q_y(θ) ⊗ q_x(φ) (3-2-1), independent of the conversion under test.
    fn q_from_euler(phi: f64, theta: f64, psi: f64) -> [f64; 4] {
        let (sr, cr) = (phi / 2.0).sin_cos();
        let (sp, cp) = (theta / 2.0).sin_cos();
        let (sy, cy) = (psi / 2.0).sin_cos();
        [
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        ]
    }

    #[test]
    fn analytic_euler_round_trip_and_sign_invariance() {
        for &(phi, theta, psi) in
            &[(0.3, -0.2, 1.1), (-2.5, 1.2, -3.0), (0.0, 0.0, 0.0), (1.5, -1.4, 0.2)]
        {
            let q = q_from_euler(phi, theta, psi);
            for s in [1.0, -1.0, 2.5] {
                let e = euler_from_quaternion(q.map(|c| c * s));
                assert!((e[0] - phi).abs() < 1e-12, "{e:?}");
                assert!((e[1] - theta).abs() < 1e-12, "{e:?}");
                assert!((e[2] - psi).abs() < 1e-12, "{e:?}");
            }
        }
        assert!(euler_from_quaternion([0.0; 4])[0].is_nan());
    }

    #[test]
    fn analytic_air_data_from_attitude_and_velocity() {
        // Level wings, pitched 0.1 rad, flying horizontally at 20 m/s, heading 0.5 rad:
        // α = θ − γ = 0.1, β = 0.
        let q = q_from_euler(0.0, 0.1, 0.5);
        let v = [20.0 * 0.5f64.cos(), 20.0 * 0.5f64.sin(), 0.0];
        let [vt, a, b] = air_data(q, v, 1.0);
        assert!((vt - 20.0).abs() < 1e-12 && (a - 0.1).abs() < 1e-12 && b.abs() < 1e-12);
        // Wings level, θ = 0, velocity 0.05 rad right of the nose: β = +0.05.
        let q = q_from_euler(0.0, 0.0, 0.3);
        let v = [15.0 * 0.35f64.cos(), 15.0 * 0.35f64.sin(), 0.0];
        let [_, a, b] = air_data(q, v, 1.0);
        assert!(a.abs() < 1e-12 && (b - 0.05).abs() < 1e-12, "{a} {b}");
        // Any attitude: the rotation keeps the speed.
        let q = q_from_euler(0.4, 0.25, 0.0);
        let v = [12.0 * 0.2f64.cos(), 0.0, -12.0 * 0.2f64.sin()];
        let [vt, _, _] = air_data(q, v, 1.0);
        assert!((vt - 12.0).abs() < 1e-12);
        // Below the threshold the flow angles are undefined, the speed is kept.
        let [vt, a, b] = air_data(q, [0.5, 0.0, 0.0], 1.0);
        assert!((vt - 0.5).abs() < 1e-12 && a.is_nan() && b.is_nan());
    }

    #[test]
    fn analytic_log_table_aligns_and_derives_the_columns_a_mapping_reads() {
        let q = q_from_euler(0.2, 0.1, 0.5);
        let att = Topic {
            name: "att".into(),
            t_s: (0..=40).map(|i| i as f64 * 0.05).collect(),
            fields: (0..4).map(|k| (format!("q[{k}]"), vec![q[k]; 41])).collect(),
        };
        // Horizontal flight along the heading at 10 + t m/s (a ramp), 10 Hz; 2 m/s wind from
        // the north is subtracted.
        let vel = |t: f64| 10.0 + t;
        let ts: Vec<f64> = (0..=20).map(|i| 0.01 + i as f64 * 0.1).collect();
        let pos = Topic {
            name: "pos".into(),
            fields: vec![
                ("vx".into(), ts.iter().map(|&t| vel(t) * 0.5f64.cos() + 2.0).collect()),
                ("vy".into(), ts.iter().map(|&t| vel(t) * 0.5f64.sin()).collect()),
                ("vz".into(), vec![0.0; 21]),
                ("wn".into(), vec![2.0; 21]),
                ("we".into(), vec![0.0; 21]),
            ],
            t_s: ts,
        };
        let text = r#"
[time]
column = "time_s"
unit = "s"
[align]
rate_hz = 50.0
method = "linear"
[attitude]
quaternion = ["att.q[0]", "att.q[1]", "att.q[2]", "att.q[3]"]
[air_data]
ned_velocity = ["pos.vx", "pos.vy", "pos.vz"]
wind_ne = ["pos.wn", "pos.we"]
[channels]
vt = { column = "air.vt", unit = "m/s" }
alpha = { column = "air.alpha", unit = "rad" }
phi = { column = "euler.phi", unit = "rad" }
mass = { value = 1.0, unit = "kg" }
S = { value = 1.0, unit = "m2" }
rho = { value = 1.225, unit = "kg/m3" }
"#;
        let m = Mapping::from_toml_str(text, "m.toml").unwrap();
        let out = log_table(&[att.clone(), pos], &m, "log").unwrap();
        let c = |n: &str| &out.table.columns[out.table.names.iter().position(|x| x == n).unwrap()];
        let t = c(TIME_COLUMN);
        assert!((t[0] - 0.01).abs() < 1e-12 && t.len() == 100, "{} rows", t.len());
        for (r, &ti) in t.iter().enumerate() {
            assert!((c(EULER_PHI)[r] - 0.2).abs() < 1e-12);
            assert!((c(EULER_THETA)[r] - 0.1).abs() < 1e-12);
            // α of the true air velocity at this time (banked, so α ≠ θ: air_data is
            // checked analytically above).
            let [_, a, _] = air_data(q, [vel(ti) * 0.5f64.cos(), vel(ti) * 0.5f64.sin(), 0.0], 1.0);
            assert!((c(AIR_ALPHA)[r] - a).abs() < 1e-12);
            assert!((c(AIR_VT)[r] - vel(ti)).abs() < 1e-9, "linear alignment is exact on the ramp");
        }
        // The quaternion topic alone lacks the velocity: the error names the column and user.
        let e = log_table(&[att], &m, "log").unwrap_err().to_string();
        assert!(
            e.starts_with(
                "log: `pos.vx` for [air_data] ned_velocity: the log has no topic/message `pos`"
            ),
            "{e}"
        );
    }

    #[test]
    fn quaternion_sign_flips_are_removed_before_interpolation() {
        let q = q_from_euler(0.1, 0.2, 0.3);
        let mut t = Topic {
            name: "att".into(),
            t_s: vec![0.0, 0.1, 0.2],
            fields: (0..4).map(|k| (format!("q[{k}]"), vec![q[k], -q[k], q[k]])).collect(),
        };
        continuous_quaternion(&mut t, &["q[0]", "q[1]", "q[2]", "q[3]"]);
        for (f, qk) in t.fields.iter().zip(q) {
            assert_eq!(f.1, vec![qk; 3]);
        }
    }
}
