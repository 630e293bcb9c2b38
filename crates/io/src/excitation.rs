//! The excitation a log records of itself: ArduPilot's SYSID chirps (`SIDS`, `SIDD`).
//!
//! ArduPilot's system-identification mode (Copter `mode_systemid.cpp`, Plane `systemid.cpp`,
//! the waveform `AP_Math/chirp.cpp`) writes, when a sweep starts, one **`SIDS`** message
//! (`TimeUS,Ax,Mag,FSt,FSp,TFin,TC,TR,TFout`, format `QBfffffff`): the axis `SID_AXIS`, the
//! magnitude, the start and stop frequencies (Hz), the fade-in time, the time at constant
//! frequency before the sweep (`2/FSt`), the record time `TR` and the fade-out time (s). While
//! it runs it writes **`SIDD`** (`TimeUS,Time,Targ,F,Gx,Gy,Gz,Ax,Ay,Az`, format `Qfffffffff`,
//! units `ss-zkkkooo`): the waveform time, the waveform sample `Targ` added on the axis, its
//! instantaneous frequency (Hz), the IMU rates (deg/s) and accelerations (m/s²).
//!
//! **Span of a sweep.** In `Chirp::update` the fade-in, the constant-frequency dwell and the
//! fade-out all lie inside `TR`: the waveform is zero after `TR`. Plane starts the waveform at
//! the `SIDS` message and stops writing `SIDD` when it completes; Copter waits
//! `SYSTEM_ID_DELAY` = 1 s first (its `SIDD.Time` counts from the mode change) and writes
//! `SIDD` until the mode is left. A sweep's span is therefore from its `SIDS` time to its last
//! `SIDD` sample before the next `SIDS` whose `Time` is at most `TR + 1 s`; with no `SIDD`
//! sample, `TR` after the `SIDS` time (and [`Sweep::sidd_samples`] is 0).
//!
//! **Axes** (`SID_AXIS`, both vehicles' `AxisType`) and the unit of `Targ` on each
//! ([`axis`]): 1–3 `INPUT_*` and 4–6 `RECOVER_*` an attitude offset in deg (Copter's yaw
//! axes: a yaw-rate offset in deg/s), 7–9 `RATE_*` a body-rate offset in deg/s, 10–13
//! `MIX_*` an offset to the multirotor mixer's input (−1…1, throttle 0…1), 14–19 (Copter) a
//! position (m) or velocity (m/s) disturbance or input, 20–21 `FW_INPUT_*` an offset to the
//! plane's demanded roll or pitch in deg, 22–23 `FW_MIX_*` an offset to the plane's aileron or
//! elevator mixer output (−1…1 of full throw). The injected signal is given in SI: deg and
//! deg/s become rad and rad/s; the others are as logged.

use crate::FlightDataError;
use crate::log_contents::TopicFilter;
use crate::table::Topic;
use std::path::Path;

/// Copter's `SYSTEM_ID_DELAY`: the waveform starts this long after the mode change, s.
pub const COPTER_DELAY_S: f64 = 1.0;

/// What one `SID_AXIS` value excites.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Axis {
    /// `SID_AXIS` value.
    pub number: u8,
    /// ArduPilot's `AxisType` name, e.g. `FW_MIX_PITCH`.
    pub name: &'static str,
    /// The unit `Targ` is logged in.
    pub unit: &'static str,
    /// Factor from `Targ` to SI (π/180 for deg and deg/s, else 1).
    pub to_si: f64,
    /// The mapping channel of the surface the axis moves directly (`FW_MIX_ROLL`: `da`,
    /// `FW_MIX_PITCH`: `de`); `None` where the waveform enters a control loop.
    pub surface: Option<&'static str>,
}

const DEG: f64 = std::f64::consts::PI / 180.0;

/// The `SID_AXIS` values of Copter's and Plane's `AxisType` (module doc).
pub const AXES: [Axis; 23] = {
    const fn a(number: u8, name: &'static str, unit: &'static str, to_si: f64) -> Axis {
        Axis { number, name, unit, to_si, surface: None }
    }
    [
        a(1, "INPUT_ROLL", "deg", DEG),
        a(2, "INPUT_PITCH", "deg", DEG),
        a(3, "INPUT_YAW", "deg (Copter: deg/s)", DEG),
        a(4, "RECOVER_ROLL", "deg", DEG),
        a(5, "RECOVER_PITCH", "deg", DEG),
        a(6, "RECOVER_YAW", "deg (Copter: deg/s)", DEG),
        a(7, "RATE_ROLL", "deg/s", DEG),
        a(8, "RATE_PITCH", "deg/s", DEG),
        a(9, "RATE_YAW", "deg/s", DEG),
        a(10, "MIX_ROLL", "mixer (-1..1)", 1.0),
        a(11, "MIX_PITCH", "mixer (-1..1)", 1.0),
        a(12, "MIX_YAW", "mixer (-1..1)", 1.0),
        a(13, "MIX_THROTTLE", "mixer (0..1)", 1.0),
        a(14, "DISTURB_POS_LAT", "m", 1.0),
        a(15, "DISTURB_POS_LONG", "m", 1.0),
        a(16, "DISTURB_VEL_LAT", "m/s", 1.0),
        a(17, "DISTURB_VEL_LONG", "m/s", 1.0),
        a(18, "INPUT_VEL_LAT", "m/s", 1.0),
        a(19, "INPUT_VEL_LONG", "m/s", 1.0),
        a(20, "FW_INPUT_ROLL", "deg", DEG),
        a(21, "FW_INPUT_PITCH", "deg", DEG),
        Axis {
            number: 22,
            name: "FW_MIX_ROLL",
            unit: "mixer (-1..1)",
            to_si: 1.0,
            surface: Some("da"),
        },
        Axis {
            number: 23,
            name: "FW_MIX_PITCH",
            unit: "mixer (-1..1)",
            to_si: 1.0,
            surface: Some("de"),
        },
    ]
};

/// The axis of `SID_AXIS` value `number`, `None` for one neither vehicle defines.
pub fn axis(number: u8) -> Option<&'static Axis> {
    AXES.iter().find(|a| a.number == number)
}

/// The axis named `text`: its `SID_AXIS` number or its name (case-insensitive).
pub fn axis_by_name(text: &str) -> Option<&'static Axis> {
    let t = text.trim();
    match t.parse::<u8>() {
        Ok(n) => axis(n),
        Err(_) => AXES.iter().find(|a| a.name.eq_ignore_ascii_case(t)),
    }
}

/// One sweep a log records (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    /// The axis excited.
    pub axis: Axis,
    /// `SIDS.Mag`, in [`Axis::unit`].
    pub magnitude: f64,
    /// `SIDS.FSt`, `SIDS.FSp`: start and stop frequency, Hz.
    pub band_hz: (f64, f64),
    /// `SIDS.TFin`, `SIDS.TC`, `SIDS.TR`, `SIDS.TFout`: fade-in, constant-frequency dwell,
    /// record (the whole waveform) and fade-out times, s.
    pub fade_in_s: f64,
    /// See [`Sweep::fade_in_s`].
    pub const_freq_s: f64,
    /// See [`Sweep::fade_in_s`].
    pub record_s: f64,
    /// See [`Sweep::fade_in_s`].
    pub fade_out_s: f64,
    /// The span used, log time, s (module doc).
    pub span_s: (f64, f64),
    /// `SIDD` samples in the span.
    pub sidd_samples: usize,
}

/// The sweeps of a log and the injected waveform in SI.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Excitation {
    /// Sweeps in log order.
    pub sweeps: Vec<Sweep>,
    /// `SIDD` times in the sweeps' spans, s.
    pub t_s: Vec<f64>,
    /// `SIDD.Targ` at those times in SI (× [`Axis::to_si`] of its sweep).
    pub injected: Vec<f64>,
}

/// The excitation of the DataFlash log at `path`: only `SIDS` and `SIDD` are kept while it is
/// streamed. A log without `SIDS` gives no sweeps.
///
/// # Errors
/// The reader's errors ([`crate::dataflash::read_dataflash_filtered`]); a `SIDS` with an axis
/// no vehicle defines or a band or record time that is not positive, naming the file and the
/// message's time.
pub fn read_sysid(path: &Path) -> Result<Excitation, FlightDataError> {
    let columns = ["SIDS.Ax", "SIDS.Mag", "SIDS.FSt", "SIDS.FSp", "SIDS.TFin", "SIDS.TC"];
    let more = ["SIDS.TR", "SIDS.TFout", "SIDD.Time", "SIDD.Targ"];
    let filter = TopicFilter::columns(columns.into_iter().chain(more), []);
    let contents = crate::dataflash::read_dataflash_filtered(path, &filter)?;
    let topic = |name: &str| contents.topics.iter().find(|t| t.name == name);
    sysid_excitation(topic("SIDS"), topic("SIDD"), &path.display().to_string())
}

/// The excitation from the `SIDS` and `SIDD` topics (module doc); `file` names the log.
///
/// # Errors
/// As [`read_sysid`].
pub fn sysid_excitation(
    sids: Option<&Topic>,
    sidd: Option<&Topic>,
    file: &str,
) -> Result<Excitation, FlightDataError> {
    let mut out = Excitation::default();
    let Some(sids) = sids else { return Ok(out) };
    let empty = Topic { name: "SIDD".into(), t_s: Vec::new(), fields: Vec::new() };
    let sidd = sidd.unwrap_or(&empty);
    let (time, targ) = (field(sidd, "Time"), field(sidd, "Targ"));
    for (i, &t0) in sids.t_s.iter().enumerate() {
        let v = |name: &str| field(sids, name).map_or(f64::NAN, |f| f[i]);
        let next = sids.t_s.get(i + 1).copied().unwrap_or(f64::INFINITY);
        let mut sweep = setup(&v, t0, file)?;
        let limit = sweep.record_s + COPTER_DELAY_S;
        let first = sidd.t_s.partition_point(|t| *t < t0);
        let mut k = first;
        while k < sidd.t_s.len() && sidd.t_s[k] < next && time.is_none_or(|w| w[k] <= limit) {
            if let Some(targ) = targ {
                out.t_s.push(sidd.t_s[k]);
                out.injected.push(targ[k] * sweep.axis.to_si);
            }
            k += 1;
        }
        sweep.sidd_samples = k - first;
        if k > first {
            sweep.span_s.1 = sidd.t_s[k - 1];
        }
        out.sweeps.push(sweep);
    }
    Ok(out)
}

fn field<'a>(t: &'a Topic, name: &str) -> Option<&'a [f64]> {
    t.fields.iter().find(|(f, _)| f == name).map(|(_, v)| v.as_slice())
}

/// The sweep a `SIDS` message at `t0` sets up (`v` reads its fields), its span nominal.
fn setup(v: &dyn Fn(&str) -> f64, t0: f64, file: &str) -> Result<Sweep, FlightDataError> {
    let bad = |message: String| FlightDataError::Format {
        file: file.to_string(),
        message: format!("SIDS at {t0} s: {message}"),
    };
    let ax = v("Ax");
    let axis = (ax.fract() == 0.0 && (0.0..=255.0).contains(&ax))
        .then(|| axis(ax as u8))
        .flatten()
        .ok_or_else(|| bad(format!("axis `Ax` = {ax} is not a SID_AXIS of Copter or Plane")))?;
    let (f0, f1, tr) = (v("FSt"), v("FSp"), v("TR"));
    if !(f0 > 0.0 && f1 > 0.0 && f0.is_finite() && f1.is_finite()) {
        return Err(bad(format!("frequencies FSt = {f0}, FSp = {f1} Hz must be positive")));
    }
    if !(tr > 0.0 && tr.is_finite()) {
        return Err(bad(format!("record time TR = {tr} s must be positive")));
    }
    Ok(Sweep {
        axis: *axis,
        magnitude: v("Mag"),
        band_hz: (f0, f1),
        fade_in_s: v("TFin"),
        const_freq_s: v("TC"),
        record_s: tr,
        fade_out_s: v("TFout"),
        span_s: (t0, t0 + tr),
        sidd_samples: 0,
    })
}

/// The injected waveform at time `t`, s: linear between the `SIDD` samples either side when
/// they are at most `hold_s` apart, `None` outside the sweeps or across a gap.
pub fn injected_at(e: &Excitation, t: f64, hold_s: f64) -> Option<f64> {
    let k = e.t_s.partition_point(|x| *x <= t);
    if k == 0 {
        return None;
    }
    let (t0, x0) = (e.t_s[k - 1], e.injected[k - 1]);
    if t == t0 {
        return Some(x0);
    }
    let (&t1, &x1) = (e.t_s.get(k)?, e.injected.get(k)?);
    (t1 - t0 <= hold_s).then(|| x0 + (x1 - x0) * (t - t0) / (t1 - t0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn topic(name: &str, t_s: Vec<f64>, fields: Vec<(&str, Vec<f64>)>) -> Topic {
        let fields = fields.into_iter().map(|(f, v)| (f.to_string(), v)).collect();
        Topic { name: name.into(), t_s, fields }
    }

    /// A Copter-style sweep (SIDD from the mode change on, past the waveform's end) and a
    /// Plane-style one (SIDD only while the waveform runs).
    #[test]
    fn spans_end_at_the_waveforms_end_or_the_last_sidd() {
        let sids = topic(
            "SIDS",
            vec![10.0, 40.0],
            vec![
                ("Ax", vec![8.0, 23.0]),
                ("Mag", vec![5.0, 0.1]),
                ("FSt", vec![0.5, 0.2]),
                ("FSp", vec![5.0, 8.0]),
                ("TFin", vec![1.0, 1.0]),
                ("TC", vec![4.0, 10.0]),
                ("TR", vec![20.0, 15.0]),
                ("TFout", vec![1.0, 1.0]),
            ],
        );
        // Copter: 10.1 … 35 s (Time 0.1 … 25); Plane: 40.1 … 55 s (Time 0.1 … 15).
        let mut t = Vec::new();
        let mut time = Vec::new();
        for k in 1..=250 {
            t.push(10.0 + 0.1 * f64::from(k));
            time.push(0.1 * f64::from(k));
        }
        for k in 1..=150 {
            t.push(40.0 + 0.1 * f64::from(k));
            time.push(0.1 * f64::from(k));
        }
        let targ: Vec<f64> = (0..t.len()).map(|k| k as f64).collect();
        let sidd = topic("SIDD", t, vec![("Time", time), ("Targ", targ.clone())]);
        let e = sysid_excitation(Some(&sids), Some(&sidd), "x.bin").unwrap();
        let (a, b) = (&e.sweeps[0], &e.sweeps[1]);
        assert_eq!((a.axis.name, b.axis.name), ("RATE_PITCH", "FW_MIX_PITCH"));
        // Copter: TR + 1 s of waveform time (SIDD Time 21.0), at 31.0 s.
        assert_eq!(a.sidd_samples, 210);
        assert!((a.span_s.0 - 10.0).abs() < 1e-12 && (a.span_s.1 - 31.0).abs() < 1e-9);
        assert!((b.span_s.0 - 40.0).abs() < 1e-12 && (b.span_s.1 - 55.0).abs() < 1e-9);
        assert_eq!(b.sidd_samples, 150);
        // deg/s to rad/s on RATE_PITCH, as logged on FW_MIX_PITCH.
        assert!((e.injected[3] - 3.0 * DEG).abs() < 1e-15);
        assert_eq!(e.injected[210], 250.0);
        let mid = injected_at(&e, 10.15, 0.15).unwrap();
        assert!((mid - 0.5 * DEG).abs() < 1e-12, "{mid}");
        assert_eq!(injected_at(&e, 36.0, 0.15), None, "between the sweeps");
        assert_eq!(injected_at(&e, 5.0, 0.15), None, "before");
    }

    #[test]
    fn errors_bad_setup_names_the_message() {
        let sids = |ax: f64, tr: f64| {
            let one = |x: f64| vec![x];
            topic(
                "SIDS",
                vec![3.0],
                vec![
                    ("Ax", one(ax)),
                    ("Mag", one(1.0)),
                    ("FSt", one(0.5)),
                    ("FSp", one(5.0)),
                    ("TFin", one(1.0)),
                    ("TC", one(4.0)),
                    ("TR", one(tr)),
                    ("TFout", one(1.0)),
                ],
            )
        };
        let e = sysid_excitation(Some(&sids(40.0, 10.0)), None, "x.bin").unwrap_err();
        assert!(e.to_string().contains("x.bin: SIDS at 3 s: axis `Ax` = 40"), "{e}");
        let e = sysid_excitation(Some(&sids(23.0, 0.0)), None, "x.bin").unwrap_err();
        assert!(e.to_string().contains("TR = 0 s"), "{e}");
        let e = sysid_excitation(Some(&sids(23.0, 10.0)), None, "x.bin").unwrap();
        assert_eq!((e.sweeps[0].sidd_samples, e.sweeps[0].span_s), (0, (3.0, 13.0)));
        assert_eq!(axis_by_name("fw_mix_pitch").map(|a| a.number), Some(23));
        assert_eq!(axis_by_name("8").map(|a| a.name), Some("RATE_PITCH"));
    }
}
