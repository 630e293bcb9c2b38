//! A long record judged by its manoeuvres, not as one kinematic integration.
//!
//! The check integrates the kinematics over each manoeuvre from an initial state of its own,
//! with constant biases and a steady wind. Over a stretch of many minutes without a gap the
//! wind, the trim and the sensors' own drift change, so one integration over it does not
//! describe the data: on an 80-minute simulated flight it did not converge and read an
//! airspeed bias of −587,000 m/s, after six minutes of computing. A stretch longer than
//! [`LONG_STRETCH_S`] is therefore judged on the manoeuvres `inspect` finds in it, the best
//! [`LONG_RECORD_SET_SIZE`] per axis by the information they hold (`--window auto:N`'s
//! choice), and a warning names them. A record without a mapped surface, or without a
//! manoeuvre found in flight, is checked whole, and the warning says that too.

use crate::inspect::detect::DetectionRule;
use crate::inspect::rank::union_of_sets;
use crate::record::Manoeuvres;
use crate::window::TimeWindow;
use aeroident_estimators::AirDataSample;

/// The longest stretch without a gap (s) checked as one manoeuvre: ten minutes, longer than a
/// phugoid (a light aircraft's is about a minute, an airliner's two or three) or a test card's
/// sequence of inputs, short enough that the wind and the trim stay put.
pub const LONG_STRETCH_S: f64 = 600.0;

/// Windows per axis a long stretch is judged on: each window brings six initial states of its
/// own, and the biases' σ falls only as the square root of the windows (on the 80-minute
/// simulated flight of docs/real-data.md the α bias's σ is 0.0019 rad on four per axis, eight
/// windows, and 0.0009 on all 106: thirteen times the windows for half the σ).
pub const LONG_RECORD_SET_SIZE: usize = 4;

/// What a record read whole is checked on.
#[derive(Debug, Clone, PartialEq)]
pub enum Judged {
    /// The record as read: no stretch is longer than [`LONG_STRETCH_S`].
    Whole,
    /// The windows chosen from a long stretch, and the warning that names them.
    Windows(Vec<TimeWindow>, String),
    /// A long stretch checked whole all the same, and the warning that says why.
    WholeLong(String),
}

/// What `manoeuvres` (a record read without windows, one file) is checked on.
pub fn judged(manoeuvres: &[Vec<AirDataSample>]) -> Judged {
    let span = |m: &Vec<AirDataSample>| match (m.first(), m.last()) {
        (Some(a), Some(b)) => b.t_s - a.t_s,
        _ => 0.0,
    };
    let longest = manoeuvres.iter().map(span).fold(0.0, f64::max);
    if longest <= LONG_STRETCH_S {
        return Judged::Whole;
    }
    let head = format!(
        "the record runs {longest:.1} s without a gap, longer than the {LONG_STRETCH_S:.0} s \
         one kinematic integration holds (the wind, the trim and the sensors' drift change)"
    );
    let samples: Vec<AirDataSample> = manoeuvres.iter().flatten().copied().collect();
    let rule = DetectionRule::default();
    let Some(ranking) = crate::inspect::rank_samples(&samples, &rule, LONG_RECORD_SET_SIZE) else {
        return Judged::WholeLong(format!(
            "{head}, and no surface (`de`, `da`, `dr`) is mapped to find its manoeuvres on: it \
             is checked whole; give `--window START:END` for each manoeuvre"
        ));
    };
    let windows = union_of_sets(&ranking.window_sets);
    if windows.is_empty() {
        return Judged::WholeLong(format!(
            "{head}, and no manoeuvre was found in flight on its surfaces: it is checked whole; \
             give `--window START:END` for each manoeuvre"
        ));
    }
    let spans: Vec<String> =
        windows.iter().map(|w| format!("{:.2}–{:.2} s", w.start_s, w.end_s)).collect();
    Judged::Windows(
        windows.clone(),
        format!(
            "{head}: it is checked on its best {LONG_RECORD_SET_SIZE} manoeuvres per axis by the \
             information they hold, {} window(s): {}; give `--window START:END` to check other \
             spans, or `--window auto` for every manoeuvre in flight",
            windows.len(),
            spans.join(", ")
        ),
    )
}

/// `rec` cut to `windows` (time order, not overlapping): each window's samples of each
/// manoeuvre, a manoeuvre of their own with the origin of the one they came from; pieces of
/// fewer than two samples are left out. The counts of rows read and rejected stay the
/// record's.
pub fn within(rec: Manoeuvres, windows: &[TimeWindow]) -> Manoeuvres {
    let mut manoeuvres = Vec::new();
    let mut origins = Vec::new();
    for w in windows {
        for (m, origin) in rec.manoeuvres.iter().zip(&rec.origins) {
            let lo = m.partition_point(|s| s.t_s < w.start_s);
            let hi = m.partition_point(|s| s.t_s <= w.end_s);
            if hi >= lo + 2 {
                manoeuvres.push(m[lo..hi].to_vec());
                origins.push(origin.clone());
            }
        }
    }
    Manoeuvres { manoeuvres, origins, ..rec }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_io::RejectionLog;

    /// A level flight sampled at 10 Hz from `t0` for `duration_s`, the short period
    /// (`α̇ = −1.2 α + q − 0.1 δe`, `q̇ = −4 α − 1.5 q − 6 δe`, Euler at 0.01 s) excited by a
    /// doublet of 0.05 rad at each of `doublets_s`.
    fn stretch(t0: f64, duration_s: f64, doublets_s: &[f64]) -> Vec<AirDataSample> {
        let elevator = |t: f64| {
            let at = |d: f64| match t - d {
                x if (0.0..1.0).contains(&x) => 0.05,
                x if (1.0..2.0).contains(&x) => -0.05,
                _ => 0.0,
            };
            // A trim wander of 0.1 mrad: a surface that holds exactly still between inputs
            // would read as quantised in steps of the doublet's size.
            doublets_s.iter().map(|&d| at(d)).sum::<f64>() + 1e-4 * (0.37 * t).sin()
        };
        let (mut alpha, mut q) = (0.0_f64, 0.0_f64);
        let steps = (duration_s * 100.0).round() as usize;
        let mut out = Vec::new();
        for k in 0..=steps {
            let t = t0 + k as f64 * 0.01;
            let de = elevator(t);
            let alpha_dot = -1.2 * alpha + q - 0.1 * de;
            let q_dot = -4.0 * alpha - 1.5 * q - 6.0 * de;
            if k % 10 == 0 {
                out.push(AirDataSample {
                    t_s: t,
                    vt_mps: 150.0,
                    alpha_rad: 0.05 + alpha,
                    qbar_pa: 0.5 * 1.2 * 150.0 * 150.0,
                    q_rad_s: Some(q),
                    qdot_rad_s2: Some(q_dot),
                    p_rad_s: Some(0.0),
                    r_rad_s: Some(0.0),
                    theta_rad: Some(0.05),
                    phi_rad: Some(0.0),
                    ax_mps2: Some(0.0),
                    az_mps2: Some(-9.8),
                    de_rad: Some(de),
                    ..AirDataSample::default()
                });
            }
            alpha += 0.01 * alpha_dot;
            q += 0.01 * q_dot;
        }
        out
    }

    /// The edge: a stretch of exactly the limit is checked whole, one a sample longer is not.
    #[test]
    fn a_stretch_longer_than_the_limit_is_judged_by_its_manoeuvres() {
        let at_limit = stretch(0.0, LONG_STRETCH_S, &[100.0, 300.0]);
        assert_eq!(judged(&[at_limit]), Judged::Whole);
        let doublets = [100.0, 250.0, 400.0, 550.0];
        let longer = stretch(0.0, LONG_STRETCH_S + 0.1, &doublets);
        let outcome = judged(&[longer]);
        let Judged::Windows(windows, note) = outcome else {
            panic!("a stretch beyond the limit is judged by its manoeuvres: {outcome:?}")
        };
        // Four doublets, four per axis: each doublet's window, and nothing between them.
        assert_eq!(windows.len(), 4, "{windows:?}");
        for (w, d) in windows.iter().zip(doublets) {
            assert!(w.start_s <= d && w.end_s >= d + 2.0 && w.end_s - w.start_s < 60.0, "{w:?}");
        }
        assert!(note.contains("600 s") && note.contains("4 window(s)"), "{note}");
    }

    /// Without a surface, or with surfaces that never move, a long stretch is checked whole
    /// and the warning says why.
    #[test]
    fn a_long_stretch_without_manoeuvres_is_checked_whole_with_the_reason() {
        let mut still = stretch(0.0, 900.0, &[]);
        let Judged::WholeLong(why) = judged(std::slice::from_ref(&still)) else {
            panic!("no manoeuvre: checked whole")
        };
        assert!(why.contains("no manoeuvre was found"), "{why}");
        still.iter_mut().for_each(|s| s.de_rad = None);
        let Judged::WholeLong(why) = judged(&[still]) else { panic!("no surface: whole") };
        assert!(why.contains("no surface"), "{why}");
    }

    /// A window that spans a gap gives a piece on each side; a piece of one sample is dropped;
    /// the counts stay the record's.
    #[test]
    fn a_record_cut_to_windows_keeps_each_piece_and_its_origin() {
        let a = stretch(0.0, 10.0, &[]);
        let b = stretch(20.0, 10.0, &[]);
        let rec = Manoeuvres {
            manoeuvres: vec![a, b],
            origins: vec![("f.csv".into(), 2), ("f.csv".into(), 105)],
            rejections: RejectionLog::default(),
            read: 202,
            rejected: 0,
            notes: vec![],
        };
        let windows =
            [TimeWindow { start_s: 5.0, end_s: 25.0 }, TimeWindow { start_s: 29.95, end_s: 40.0 }];
        let cut = within(rec, &windows);
        let spans: Vec<(f64, f64, usize)> =
            cut.manoeuvres.iter().map(|m| (m[0].t_s, m[m.len() - 1].t_s, m.len())).collect();
        assert_eq!(spans.len(), 2, "the one-sample piece at 30 s is dropped: {spans:?}");
        assert!((spans[0].0 - 5.0).abs() < 1e-9 && (spans[0].1 - 10.0).abs() < 1e-9);
        assert!((spans[1].0 - 20.0).abs() < 1e-9 && (spans[1].1 - 25.0).abs() < 1e-9);
        assert_eq!(cut.origins[1], ("f.csv".to_string(), 105));
        assert_eq!(cut.read, 202);
    }
}
