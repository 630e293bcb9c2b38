use super::*;

fn screen() -> SpikeScreen {
    SpikeScreen::default()
}

/// The samples of `x` the stage rejects (one channel: thrust).
fn flagged(x: &[f64]) -> Vec<usize> {
    let events = x.iter().enumerate().map(|(k, &v)| {
        Ok(RecordEvent::Sample {
            row: k as u64,
            sample: AirDataSample {
                vt_mps: 100.0,
                alpha_rad: 0.1,
                qbar_pa: 4000.0,
                thrust_n: Some(v),
                ..Default::default()
            },
        })
    });
    Screened::new(events, Some(screen()))
        .filter_map(|e| match e.unwrap() {
            RecordEvent::Rejected { row, .. } => Some(row as usize),
            _ => None,
        })
        .collect()
}

/// Deterministic pseudo-noise in ±1 (a linear congruential sequence), no generator needed.
fn noise(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

/// Steps, doublets and 3-2-1-1 manoeuvres down to one sample per unit, on quiet and on noisy
/// channels, pass: none of their samples is an isolated spike.
#[test]
fn manoeuvres_pass() {
    for unit in 1..=6 {
        // 3-2-1-1 of `unit` samples per unit between quiet stretches.
        let mut x = vec![0.0; 20];
        for (len, v) in [(3, 1.0), (2, -1.0), (1, 1.0), (1, -1.0)] {
            x.extend(std::iter::repeat_n(v, len * unit));
        }
        x.extend(vec![0.0; 20]);
        assert_eq!(flagged(&x), Vec::<usize>::new(), "3-2-1-1, {unit} samples per unit");
        let noisy: Vec<f64> = x.iter().zip(noise(x.len(), 3)).map(|(a, b)| a + 0.01 * b).collect();
        assert_eq!(flagged(&noisy), Vec::<usize>::new(), "noisy 3-2-1-1, unit {unit}");
        // A doublet.
        let mut d = vec![0.0; 20];
        d.extend(std::iter::repeat_n(0.5, unit));
        d.extend(std::iter::repeat_n(-0.5, unit));
        d.extend(vec![0.0; 20]);
        assert_eq!(flagged(&d), Vec::<usize>::new(), "doublet, unit {unit}");
    }
    // A step with an intermediate sample, and a ramp.
    let step: Vec<f64> = (0..40)
        .map(|k| {
            if k < 20 {
                0.0
            } else if k == 20 {
                0.4
            } else {
                1.0
            }
        })
        .collect();
    assert!(flagged(&step).is_empty());
    let ramp: Vec<f64> = (0..40).map(|k| k as f64 * 0.1).collect();
    assert!(flagged(&ramp).is_empty());
    // Gaussian-like noise of any level passes.
    assert!(flagged(&noise(2000, 7)).is_empty());
    // A quantisation flick of one step on a constant channel (ATTAS rudder, 0.0215° steps)
    // passes, as does a departure within the range of the channel's context.
    let mut c = vec![0.62513; 30];
    c[11] = 0.64658;
    assert!(flagged(&c).is_empty());
    let mut v: Vec<f64> = (0..60).map(|k| 108.0 + 0.02 * k as f64).collect();
    v[40] -= 0.35;
    assert!(flagged(&v).is_empty());
}

/// An isolated spike is found, on a quiet and on a noisy channel, at the start, the middle
/// and the end of a record, whichever its sign; the verdict gives the window's median.
#[test]
fn isolated_spikes_are_found() {
    let base: Vec<f64> = noise(60, 11).iter().map(|v| 11_600.0 + 30.0 * v).collect();
    for (k, v) in [(0, 1e6), (30, 1e6), (59, 1e6), (30, -2e4), (31, 13_000.0)] {
        let mut x = base.clone();
        x[k] = v;
        assert_eq!(flagged(&x), vec![k], "spike {v} at {k}");
    }
    let mut x = base.clone();
    x[30] = 1e6;
    let context: Vec<f64> =
        x.iter().enumerate().filter(|(k, _)| *k != 30).map(|(_, v)| *v).collect();
    let (median, threshold) = screen().spike(&x[25..36], 5, &context).unwrap();
    assert!((median - 11_600.0).abs() < 30.0, "{median}");
    // The threshold: 5 % of the largest |thrust| of the context.
    assert!((580.0..600.0).contains(&threshold), "{threshold}");
}

/// The stage: a spike row becomes a rejection naming the channel (counted), the other events
/// pass in order; a gap restarts the window (a level change across it is no spike); with the
/// screen off everything passes.
#[test]
fn the_stage_rejects_the_spike_row_only() {
    let sample = |row: u64, thrust: f64| RecordEvent::Sample {
        row,
        sample: AirDataSample {
            t_s: row as f64 * 0.1,
            vt_mps: 100.0,
            alpha_rad: 0.1,
            qbar_pa: 4000.0,
            thrust_n: Some(thrust),
            ..Default::default()
        },
    };
    let mut input: Vec<RecordEvent> =
        (0..30).map(|k| sample(k, 11_600.0 + (k % 3) as f64)).collect();
    input[12] = sample(12, 1e6);
    input.insert(20, RecordEvent::Gap { row: 19, dt_s: 1.0, nominal_dt_s: 0.1 });
    for e in input.iter_mut().skip(21) {
        if let RecordEvent::Sample { sample, .. } = e {
            sample.thrust_n = Some(20_000.0);
        }
    }
    // The first sample after the gap is a lone value: a lone level is no spike either.
    let mut stage = Screened::new(input.clone().into_iter().map(Ok), Some(screen()));
    let out: Vec<RecordEvent> = stage.by_ref().map(Result::unwrap).collect();
    assert_eq!(out.len(), input.len());
    assert_eq!(stage.rejected(), 1);
    let RecordEvent::Rejected { row: 12, problem } = &out[12] else { panic!("{:?}", out[12]) };
    assert_eq!(problem.kind(), "isolated spike");
    let text = problem.to_string();
    assert!(text.contains("thrust_n") && text.contains("1000000"), "{text}");
    assert!(matches!(out[20], RecordEvent::Gap { row: 19, .. }));
    assert!(
        out.iter().enumerate().all(|(k, e)| k == 12 || !matches!(e, RecordEvent::Rejected { .. }))
    );
    let off: Vec<_> =
        Screened::new(input.clone().into_iter().map(Ok), None).map(Result::unwrap).collect();
    assert!(off.iter().all(|e| !matches!(e, RecordEvent::Rejected { .. })));
}

/// Bad settings are named.
#[test]
fn bad_settings_are_named() {
    let bad = SpikeScreen { half_width: 1, ..screen() };
    assert!(bad.check().unwrap_err().contains("half-width 1"));
    let bad = SpikeScreen { hampel_t: f64::NAN, ..screen() };
    assert!(bad.check().unwrap_err().contains("Hampel t"));
    assert!(screen().check().is_ok());
}

/// The rejections (row, problem) and warnings of the stage over samples whose thrust is `x`
/// and elevator `de`.
fn screened(x: &[f64], de: &[f64]) -> (Vec<(usize, RowProblem)>, Vec<String>) {
    let events = x.iter().zip(de).enumerate().map(|(k, (&v, &d))| {
        Ok(RecordEvent::Sample {
            row: k as u64,
            sample: AirDataSample {
                t_s: k as f64 * 0.1,
                vt_mps: 100.0,
                alpha_rad: 0.1,
                qbar_pa: 4000.0,
                thrust_n: Some(v),
                de_rad: Some(d),
                ..Default::default()
            },
        })
    });
    let stage = Screened::new(events, Some(screen()));
    let notes = stage.notes();
    let rejected = stage
        .filter_map(|e| match e.unwrap() {
            RecordEvent::Rejected { row, problem } => Some((row as usize, problem)),
            _ => None,
        })
        .collect();
    let notes = notes.lock().unwrap().clone();
    (rejected, notes)
}

/// Runs of 2 and 3 gross outliers with the channel back at its level on both sides are
/// rejected whole, each row naming the channel, its value and the run; on a quiet and a noisy
/// channel, whichever the sign, near the record's start and end as in its middle.
#[test]
fn short_runs_of_spikes_are_found() {
    let base: Vec<f64> = noise(80, 5).iter().map(|v| 11_600.0 + 30.0 * v).collect();
    let quiet = vec![11_600.0; 80];
    let de = vec![0.0; 80];
    for x0 in [&base, &quiet] {
        for (at, len, v) in [(40, 2, 1e6), (40, 3, 1e6), (40, 3, -5e4), (7, 2, 2e5), (72, 3, 2e5)] {
            let mut x = x0.clone();
            x[at..at + len].iter_mut().for_each(|s| *s = v);
            let (rejected, notes) = screened(&x, &de);
            let rows: Vec<usize> = rejected.iter().map(|r| r.0).collect();
            assert_eq!(rows, (at..at + len).collect::<Vec<_>>(), "{len} × {v} at {at}");
            for (_, p) in &rejected {
                assert_eq!(p.kind(), "spike run");
                let RowProblem::Spike { field, value, samples, .. } = p else { panic!("{p}") };
                assert_eq!((field.as_str(), *value, *samples), ("`thrust_n`", v, len));
            }
            assert!(notes.is_empty(), "{notes:?}");
        }
    }
    // Two run members need not be equal: q̄ × 10 on two noisy samples.
    let mut x = base.clone();
    x[30] *= 10.0;
    x[31] *= 10.0;
    assert_eq!(screened(&x, &de).0.iter().map(|r| r.0).collect::<Vec<_>>(), [30, 31]);
}

/// Runs of 4 and 5 are reported (a warning naming the channel, the time and the length), not
/// rejected; a run of 6 is neither. Short pulses on a control input (a genuine manoeuvre's)
/// are neither rejected nor reported, nor is a short excursion that does not come back (a step
/// in two stages) or one within the range of its context.
#[test]
fn longer_runs_are_reported_and_manoeuvre_like_runs_pass() {
    let quiet = vec![11_600.0; 80];
    let de = vec![0.0; 80];
    for len in [4, 5, 6] {
        let mut x = quiet.clone();
        x[40..40 + len].iter_mut().for_each(|s| *s = 1e6);
        let (rejected, notes) = screened(&x, &de);
        assert!(rejected.is_empty(), "{len}: {rejected:?}");
        if len <= WARN_RUN_MAX {
            assert_eq!(notes.len(), 1, "{len}: {notes:?}");
            assert!(
                notes[0].contains("thrust_n")
                    && notes[0].contains(&format!("for {len} samples from t = 4 s")),
                "{}",
                notes[0]
            );
        } else {
            assert!(notes.is_empty(), "{len}: {notes:?}");
        }
    }
    for len in 2..=WARN_RUN_MAX {
        let mut d = de.clone();
        d[40..40 + len].iter_mut().for_each(|s| *s = 0.1);
        assert_eq!(screened(&quiet, &d), (vec![], vec![]), "elevator pulse of {len}");
    }
    let mut x = quiet.clone();
    x[40..42].iter_mut().for_each(|s| *s = 1e6);
    x[42..].iter_mut().for_each(|s| *s = 5e5);
    assert_eq!(screened(&x, &de), (vec![], vec![]), "step in two stages");
    let mut x = quiet.clone();
    x[10] = 1e6;
    x[11] = -1e6;
    x[40..42].iter_mut().for_each(|s| *s = 1e6);
    let (rejected, notes) = screened(&x, &de);
    assert!(rejected.iter().all(|r| r.0 < 40) && notes.is_empty(), "{rejected:?} {notes:?}");
}

/// Runs of 2 and 3 gross outliers at the very start or end of a record, where the channel's
/// level is on one side only, are rejected whole (judged against the rest of the record).
#[test]
fn short_runs_at_the_record_edges_are_found() {
    let base: Vec<f64> = noise(60, 5).iter().map(|v| 11_600.0 + 30.0 * v).collect();
    let de = vec![0.0; 60];
    for (at, len) in [(0, 2), (0, 3), (58, 2), (57, 3)] {
        let mut x = base.clone();
        x[at..at + len].iter_mut().for_each(|s| *s *= 10.0);
        let (rejected, notes) = screened(&x, &de);
        let rows: Vec<usize> = rejected.iter().map(|r| r.0).collect();
        assert_eq!(rows, (at..at + len).collect::<Vec<_>>(), "{len} at {at}");
        assert!(rejected.iter().all(|r| r.1.kind() == "spike run"), "{rejected:?}");
        assert!(notes.is_empty(), "{notes:?}");
    }
}

/// Spikes two samples apart, each within the others' windows, are each rejected: the other
/// spikes set neither the window's range nor the context's.
#[test]
fn alternating_spikes_are_found() {
    let base: Vec<f64> = noise(80, 9).iter().map(|v| 0.02 * v).collect();
    for at in [vec![30, 32, 34], vec![30, 32], vec![0, 2, 4], vec![75, 77, 79]] {
        let mut x = base.clone();
        at.iter().for_each(|&k| x[k] = 0.9);
        assert_eq!(flagged(&x), at, "spikes at {at:?}");
    }
}

/// Clusters of short runs a row or two apart on a response channel (±0.02 of noise, members
/// at 0.9: as q in rad/s, a jump out and back each sample that no rigid airframe makes) are
/// rejected whole, each member only: the other runs of the cluster set neither the range around
/// a run nor its context, as the other spikes of a window do not for a single one. The samples
/// between the runs pass.
#[test]
fn clusters_of_short_runs_are_found() {
    let base: Vec<f64> = noise(80, 11).iter().map(|v| 0.02 * v).collect();
    let clusters: [&[usize]; 7] = [
        &[30, 31, 33],
        &[30, 32, 33],
        &[30, 31, 34, 35],
        &[30, 31, 32, 34, 35, 36],
        &[30, 31, 33, 34, 36],
        &[30, 33, 34],
        &[0, 1, 3],
    ];
    for at in clusters {
        let mut x = base.clone();
        at.iter().for_each(|&k| x[k] = 0.9);
        let (rejected, notes) = screened(&x, &vec![0.0; 80]);
        let rows: Vec<usize> = rejected.iter().map(|r| r.0).collect();
        assert_eq!(rows, at, "cluster {at:?}: {rejected:?}");
        assert!(notes.is_empty(), "{notes:?}");
    }
}

/// The deviations' median merged from the sorted values equals the median of the deviations
/// sorted again, bit for bit: odd and even windows, ties, values all equal, a median between
/// two values, negative zero, and the screen's window lengths (5 to 21) of noisy values.
#[test]
fn the_merged_deviation_median_equals_a_second_sort() {
    let reference = |v: &[f64]| {
        let mut sorted = v.to_vec();
        let med = median(&mut sorted);
        let mut dev: Vec<f64> = v.iter().map(|x| (x - med).abs()).collect();
        (med, median(&mut dev))
    };
    let mut cases: Vec<Vec<f64>> = vec![
        vec![1.0],
        vec![1.0, 2.0],
        vec![3.0, 3.0, 3.0, 3.0],
        vec![0.0, -0.0, 0.0, 1.0, -1.0],
        vec![1.0, 2.0, 2.0, 2.0, 9.0, -7.0],
        vec![0.1, 0.2, 0.30000000000000004, 0.3, 1e-300, -1e300],
    ];
    for (n, seed) in (5..=21).zip(1u64..) {
        let mut v = noise(n, seed);
        v[n / 3] = v[n / 2]; // a tie
        cases.push(v.iter().map(|x| (x * 1e3).round() / 1e3).collect()); // coarse: many ties
        cases.push(v);
    }
    for v in &cases {
        let mut sorted = v.clone();
        let med = median(&mut sorted);
        let got = (med, median_deviation(&sorted, med));
        let want = reference(v);
        assert_eq!(
            (got.0.to_bits(), got.1.to_bits()),
            (want.0.to_bits(), want.1.to_bits()),
            "{v:?}"
        );
    }
}
