//! The live view against the replay it watches: the same samples and estimates as the
//! replay's own history and `estimates.csv` lines, the feed's counts against the record as
//! written, the excitation against the standard deviation computed here, and a bounded
//! history on a long feed.

use super::*;
use crate::replay::cross_check::ParameterEstimate;
use crate::replay::{EstimateRows, ReplayOptions, replay};
use aeroident_io::{FlightDataReader, Mapping};

const MAP: &str = "nominal_dt_s = 0.1\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nq = { column = \"q\", unit = \"rad/s\" }\nax = { column = \"ax\", unit = \"m/s2\" }\naz = { column = \"az\", unit = \"m/s2\" }\nde = { column = \"de\", unit = \"rad\" }\nthrust = { value = 0.0, unit = \"N\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\ncbar = { value = 1.5, unit = \"m\" }\nIyy = { value = 2000.0, unit = \"kg*m2\" }\n";

/// δe of sample `k` of [`record`].
fn de(t: f64) -> f64 {
    0.03 * (2.9 * t).sin()
}

/// 200 samples at 0.1 s exciting α, q and δe independently; row 50 (t = 4.8 s) blank in α, and
/// a gap of 1 s before t = 12 s.
fn record() -> (String, Vec<f64>) {
    let mut csv = String::from("t,V,a,q,ax,az,de\n");
    let mut times = Vec::new();
    for k in 0..200 {
        let t = k as f64 * 0.1 + if k >= 110 { 1.0 } else { 0.0 };
        let (a, q, d) = (0.05 + 0.02 * (1.3 * t).sin(), 0.1 * (0.7 * t).cos(), de(t));
        let (ax, az) = (0.1 + 0.5 * a + 0.2 * d, -9.8 - 30.0 * a - 4.0 * d + q);
        if k == 48 {
            csv.push_str(&format!("{t:.1},50,,{q},{ax},{az},{d}\n"));
        } else {
            csv.push_str(&format!("{t:.1},50,{a},{q},{ax},{az},{d}\n"));
        }
        times.push(t);
    }
    (csv, times)
}

fn run(config: LiveConfig) -> (SharedLive, crate::replay::ReplayOutcome, String) {
    let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
    let (csv, _) = record();
    let reader = FlightDataReader::new(csv.as_bytes(), "d.csv", &m).unwrap();
    let shared = LiveState::new(config, None).shared();
    let mut lines = Vec::new();
    let opts = ReplayOptions { diff_window: 3, spike_screen: None, ..Default::default() };
    let out = {
        let mut pair = (
            LiveObserver::new(shared.clone(), None),
            EstimateRows { sinks: vec![&mut lines], flush_each: false, rate: Default::default() },
        );
        replay(reader, &m, &opts, &mut pair).unwrap()
    };
    (shared, out, String::from_utf8(lines).unwrap())
}

/// The view holds every estimated sample with the replay's own estimates and σ, and as many
/// points as `estimates.csv` has lines, the latest being the summary's final estimates; its
/// counts are those of the record as written: 200 rows, the one blank row rejected, one gap
/// of 1.1 s; the inputs are δe as written.
#[test]
fn view_holds_the_replays_samples_and_the_records_counts() {
    let (shared, out, csv) = run(LiveConfig::default());
    let live = shared.lock().unwrap();
    let names: Vec<&str> = out.history.names.clone();
    assert_eq!(live.names(), names.as_slice());
    assert_eq!(live.points().len(), csv.lines().count() - 1);
    assert_eq!(live.points().len(), out.history.samples);
    for (k, p) in live.points().iter().enumerate() {
        assert_eq!(p.seq, k as u64);
        assert_eq!(p.t, out.history.t_s[k]);
        assert_eq!(p.v, out.history.values[k]);
        assert_eq!(p.s, out.history.sigmas[k]);
        assert!((p.u[0].unwrap() - de(p.t)).abs() < 1e-12, "{p:?}");
        assert_eq!((p.u[1], p.u[2]), (None, None));
    }
    let latest = live.latest().unwrap();
    for (i, p) in out.summary.parameters.iter().enumerate() {
        assert_eq!(latest.v[i], p.result.estimate, "{}", p.result.name);
    }
    let s = live.stats();
    assert_eq!((s.rows_read, s.rows_rejected, s.gaps), (200, 1, 1));
    assert!((s.longest_gap_s - 1.1).abs() < 1e-9, "{s:?}");
    assert_eq!(s.samples_estimated, out.history.samples as u64);
    assert_eq!(s.rows_read as usize, out.summary.samples_read);
    assert!(live.ended());
}

/// A cursor from scratch (a late client) gets the whole history; the next update from the
/// same cursor gets no point again but still the latest sample and the states.
#[test]
fn a_late_client_gets_the_whole_history_once() {
    let (shared, out, _) = run(LiveConfig::default());
    let live = shared.lock().unwrap();
    let mut cursor = Cursor::default();
    let first = live.update(&mut cursor);
    assert_eq!(first.points.len(), out.history.samples);
    assert_eq!(first.points[0].t, out.history.t_s[0]);
    assert_eq!(first.states.len(), out.history.names.len());
    let again = live.update(&mut cursor);
    assert!(again.points.is_empty());
    assert_eq!(again.latest.map(|p| p.t), out.history.t_s.last().copied());
    let json = serde_json::to_value(&again).unwrap();
    assert_eq!(json["stats"]["rows_read"], 200);
}

/// The excitation of δe is its standard deviation over the last window, computed here from
/// the record's own δe; δa and δr are not recorded.
#[test]
fn excitation_is_the_inputs_deviation_over_the_window() {
    let config = LiveConfig { excitation_window_s: 1.05, ..Default::default() };
    let (shared, _, _) = run(config);
    let live = shared.lock().unwrap();
    let t_end = live.latest().unwrap().t;
    let (_, times) = record();
    let xs: Vec<f64> = times
        .iter()
        .filter(|t| **t <= t_end + 1e-9 && t_end - **t <= 1.05)
        .map(|t| de(*t))
        .collect();
    assert_eq!(xs.len(), 11);
    let mean = xs.iter().sum::<f64>() / 11.0;
    let sd = (xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / 11.0).sqrt();
    let e = live.excitation();
    assert!((e[0].unwrap() - sd).abs() < 1e-12, "{e:?} vs {sd}");
    assert!(sd > 0.005, "{sd}");
    assert_eq!((e[1], e[2]), (None, None));
}

/// The summary's verdicts and flags reach the view at the end: each status as the summary
/// has it; a flagged derivative shows its flags as the reason.
#[test]
fn the_summary_concludes_the_view() {
    let (shared, mut out, _) = run(LiveConfig::default());
    let flagged = out.summary.parameters[0].result.name.clone();
    out.summary.parameters[0].result.flags = vec!["cross-check: not confirmed".into()];
    out.summary.parameters[0].result.status = "flagged".into();
    let mut live = shared.lock().unwrap();
    assert!(!live.concluded());
    live.conclude(&out.summary);
    let u = live.update(&mut Cursor::default());
    let verdicts = u.verdicts.unwrap();
    for (v, p) in verdicts.iter().zip(&out.summary.parameters) {
        assert_eq!(v.status, p.result.status);
    }
    assert_eq!(live.names()[0], flagged);
    assert_eq!(u.states[0].phase, Phase::Flagged);
    assert_eq!(u.states[0].reason.as_deref(), Some("cross-check: not confirmed"));
    assert_eq!(u.status, Some(out.summary.status.as_str()));
}

/// A long feed keeps a bounded history on a doubling stride, with its first sample, every
/// kept point on the stride grid, and the exact latest sample.
#[test]
fn history_is_bounded_on_a_long_feed() {
    let config = LiveConfig { max_points: 100, ..Default::default() };
    let shared = LiveState::new(config, None).shared();
    let mut o = LiveObserver::new(shared.clone(), None);
    o.start(&["Cm_alpha"]).unwrap();
    let n = 50_000u64;
    for k in 0..n {
        o.estimate(k as f64 * 0.01, &[Some(k as f64)], &[None]).unwrap();
        assert!(shared.lock().unwrap().points().len() <= 101);
    }
    let live = shared.lock().unwrap();
    let pts = live.points();
    let stride = live.update(&mut Cursor::default()).stride;
    assert!(stride >= n / 100 && stride <= 4 * n / 100, "{stride}");
    assert_eq!(pts[0].seq, 0);
    assert!(pts.iter().all(|p| p.seq % stride == 0));
    assert!(pts.windows(2).all(|w| w[1].seq - w[0].seq == stride));
    assert_eq!(live.latest().unwrap().v[0], Some((n - 1) as f64));
}

/// An estimate far outside the conventional range (Cm_alpha = +5 with a small σ) flags the
/// derivative while running, naming the range.
#[test]
fn an_implausible_estimate_is_flagged_live() {
    let shared = LiveState::new(LiveConfig::default(), None).shared();
    let mut o = LiveObserver::new(shared.clone(), None);
    o.start(&["Cm_alpha", "CL_alpha"]).unwrap();
    o.estimate(0.0, &[Some(5.0), Some(5.0)], &[Some(0.01), Some(0.01)]).unwrap();
    let states = shared.lock().unwrap().states();
    assert_eq!(states[0].phase, Phase::Flagged);
    assert!(states[0].reason.as_deref().unwrap().contains("Cm_alpha"), "{states:?}");
    assert_eq!(states[1].phase, Phase::Converging, "{states:?}");
}

/// `replay`'s own final estimates of `kind` on the [`record`], or why it failed.
fn replayed_alone(
    kind: crate::estimators::EstimatorKind,
) -> Result<Vec<ParameterEstimate>, String> {
    let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
    let (csv, _) = record();
    let reader = FlightDataReader::new(csv.as_bytes(), "d.csv", &m).unwrap();
    let opts =
        ReplayOptions { estimator: kind, diff_window: 3, spike_screen: None, ..Default::default() };
    let out = replay(reader, &m, &opts, &mut ()).map_err(|e| e.to_string())?;
    let rows = out.summary.parameters.iter().map(|p| &p.result);
    Ok(rows.filter_map(ParameterEstimate::of).collect())
}

/// With the running cross-check, the other real-time methods follow the feed's own events:
/// at the end each holds exactly the estimates a replay of its own of the record gives, and
/// the last judgement is the panel's verdict on those and the feed's final estimates.
#[test]
fn the_running_cross_check_follows_the_feed_as_replays_of_their_own() {
    use crate::estimators::EstimatorKind;
    use crate::replay::cross_check::{MethodEstimates, judge};
    let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
    let (csv, _) = record();
    let reader = FlightDataReader::new(csv.as_bytes(), "d.csv", &m).unwrap();
    let shared = LiveState::new(LiveConfig::default(), None).shared();
    let opts = ReplayOptions { diff_window: 3, spike_screen: None, ..Default::default() };
    let mut o = LiveObserver::new(shared.clone(), None).with_cross_check(true);
    assert!(o.begin("d.csv", &m, &opts));
    let out = replay(reader, &m, &opts, &mut o).unwrap();
    let live = shared.lock().unwrap();
    let check = live.cross_check().expect("judged at the end of the feed").clone();
    let methods: Vec<&str> = check.methods.iter().map(|m| m.method.as_str()).collect();
    assert_eq!(methods, ["rls", "rls-iv", "ekf"]);
    let mut with_estimates = 0;
    for (kind, member) in [EstimatorKind::RlsIv, EstimatorKind::Ekf].iter().zip(&check.methods[1..])
    {
        match replayed_alone(*kind) {
            Ok(rows) => {
                assert_eq!(member.estimates, rows, "{}", member.method);
                with_estimates += usize::from(!rows.is_empty());
            }
            Err(e) => assert_eq!(member.status, format!("failed: {e}"), "{}", member.method),
        }
    }
    assert!(with_estimates >= 1, "{check:?}");
    let own_rows = out.summary.parameters.iter().map(|p| &p.result);
    let own_rows = own_rows.filter_map(ParameterEstimate::of);
    let own = MethodEstimates::new("rls", "running", own_rows);
    assert_eq!(check, judge(&own, &check.methods[1..]));
    assert!(live.update(&mut Cursor::default()).cross_check.unwrap().starts_with("rls-iv, ekf"));
}

/// A judgement in which the methods split on a derivative flags it with the panel's words; one
/// in which they agree, or in which no other method estimates it yet, does not; the summary's
/// flags replace the running ones at the end.
#[test]
fn a_split_flags_the_derivative_while_it_lasts() {
    use crate::replay::cross_check::{MethodEstimates, judge};
    let shared = LiveState::new(LiveConfig::default(), None).shared();
    let mut o = LiveObserver::new(shared.clone(), None);
    o.start(&["Cm_q", "Cm_alpha"]).unwrap();
    o.estimate(5.0, &[Some(-25.0), Some(-1.0)], &[Some(1.5), Some(0.02)]).unwrap();
    let row = ParameterEstimate::new;
    let own = MethodEstimates::new(
        "ekf",
        "running",
        [row("Cm_q", -25.0, 1.5), row("Cm_alpha", -1.0, 0.02)],
    );
    let split = [
        MethodEstimates::new(
            "rls",
            "running",
            [row("Cm_q", -43.0, 1.2), row("Cm_alpha", -1.01, 0.02)],
        ),
        MethodEstimates::new(
            "rls-iv",
            "running",
            [row("Cm_q", -47.0, 1.4), row("Cm_alpha", -0.99, 0.03)],
        ),
    ];
    let mut live = shared.lock().unwrap();
    live.cross_checked(5.0, &judge(&own, &split));
    let states = live.states();
    assert_eq!(states[0].phase, Phase::Flagged);
    let reason = states[0].reason.as_deref().unwrap();
    assert!(reason.starts_with("cross-check: the methods split on Cm_q"), "{reason}");
    assert!(reason.contains("rls -43") && reason.contains("ekf -25"), "{reason}");
    assert_eq!(states[1].phase, Phase::Converging, "{states:?}");
    // The others have no estimate yet: nothing disputes the feed's.
    let waiting =
        [MethodEstimates::new("rls", "running", []), MethodEstimates::new("rls-iv", "running", [])];
    live.cross_checked(6.0, &judge(&own, &waiting));
    assert!(live.states().iter().all(|s| s.phase != Phase::Flagged), "{:?}", live.states());
    live.cross_checked(7.0, &judge(&own, &split));
    assert!(live.update(&mut Cursor::default()).cross_check.unwrap().contains("dispute 1 of 2"));
}

/// The corrections the replay applies and refuses are on the page from the feed's start, in
/// the summary's words, before any sample (the summary lists them only at the end).
#[test]
fn the_corrections_are_listed_when_the_feed_begins() {
    let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
    let mut compat = crate::record::Corrections::default();
    compat.applied.push("q_rad_s bias +3.0e-3 rad/s".into());
    compat.refused.push("alpha_rad time shift: beyond its bounds".into());
    let opts = ReplayOptions { compat: Some(compat.clone()), ..Default::default() };
    let shared = LiveState::new(LiveConfig::default(), None).shared();
    let mut o = LiveObserver::new(shared.clone(), None);
    assert!(!o.begin("d.csv", &m, &opts), "no cross-check was asked for");
    let live = shared.lock().unwrap();
    assert!(live.latest().is_none());
    let mut cursor = Cursor::default();
    let shown: Vec<String> = live.update(&mut cursor).warnings.to_vec();
    let summary: Vec<String> = compat.warnings().map(|w| w.to_string()).collect();
    assert_eq!(shown, summary);
    assert_eq!(shown.len(), 2);
    assert!(shown[1].starts_with("compat refused: alpha_rad"), "{shown:?}");
}
