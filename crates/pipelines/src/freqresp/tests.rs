//! The stage on a CSV record of a known discrete system, read through a mapping.

use super::*;
use aeroident_io::Mapping;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::f64::consts::PI;

const MAP: &str = "nominal_dt_s = 0.02\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"V\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nq = { column = \"q\", unit = \"rad/s\" }\nde = { column = \"de\", unit = \"deg\" }\nrho = { value = 1.0, unit = \"kg/m3\" }\nmass = { value = 1000.0, unit = \"kg\" }\nS = { value = 10.0, unit = \"m2\" }\ncbar = { value = 1.5, unit = \"m\" }\nIyy = { value = 2000.0, unit = \"kg*m2\" }\n";

const DT: f64 = 0.02;
/// `q[k] = A q[k−1] + G (1 − A) de[k−1]` (de in rad): exact response
/// `G (1 − A) z⁻¹ / (1 − A z⁻¹)`.
const A: f64 = 0.95;
const G: f64 = -2.0;

fn exact(f_hz: f64) -> aeroident_signals::spectral::Complex64 {
    let z1 = aeroident_signals::spectral::Complex64::from_polar(1.0, -2.0 * PI * f_hz * DT);
    G * (1.0 - A) * z1 / (1.0 - A * z1)
}

/// 8 000 rows of white elevator (deg in the file) and the lagged pitch rate, row 4 001 missing
/// (a hole: two stretches).
fn record() -> String {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    let d = Normal::new(0.0, 1.0).unwrap();
    let mut csv = String::from("t,V,a,q,de\n");
    let (mut q, mut de_prev) = (0.0, 0.0);
    for k in 0..8000 {
        let de_deg: f64 = d.sample(&mut rng);
        q = A * q + G * (1.0 - A) * de_prev;
        de_prev = de_deg.to_radians();
        if k != 4000 {
            csv.push_str(&format!("{:.2},50,0.05,{q:.9e},{de_deg:.9e}\n", k as f64 * DT));
        }
    }
    csv
}

fn run(opts: &FreqRespOptions) -> Result<FreqRespOutcome, RecordError> {
    let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
    let csv = record();
    let reader = FlightDataReader::new(csv.as_bytes(), "r.csv", &m).unwrap();
    freqresp(reader, opts)
}

fn opts(inputs: &[&str], outputs: &[&str]) -> FreqRespOptions {
    FreqRespOptions {
        inputs: inputs.iter().map(|s| s.to_string()).collect(),
        outputs: outputs.iter().map(|s| s.to_string()).collect(),
        ..FreqRespOptions::default()
    }
}

#[test]
fn record_through_the_mapping_gives_the_systems_response_in_si() {
    let mut o = opts(&["de"], &["q"]);
    o.fits = vec![TfSpec::parse("q/de:0/1").unwrap()];
    let r = run(&o).unwrap();
    assert_eq!((r.stretches, r.samples), (2, 7999));
    assert!((r.dt_s - DT).abs() < 1e-12);
    let p = &r.pairs[0];
    for k in 0..p.frequency_hz.len() {
        let h = exact(p.frequency_hz[k]);
        let db = p.magnitude_db[k] - 20.0 * h.norm().log10();
        let deg = p.phase_deg[k] - h.arg().to_degrees();
        let deg = (deg + 180.0).rem_euclid(360.0) - 180.0;
        assert!(db.abs() < 0.3 && deg.abs() < 2.0, "{} Hz: {db} dB {deg} deg", p.frequency_hz[k]);
        assert!(p.coherence[k] > 0.99);
    }
    // The discrete lag is close to G·a/(s + a) with a = −ln(A)/Δt at low frequency.
    let pole = &r.fits[0].fit.poles[0];
    let a = -A.ln() / DT;
    assert!((pole.wn_rad_s.unwrap() - a).abs() < 0.05 * a, "{pole:?} vs {a}");
}

#[test]
fn bad_channels_and_windows_are_named() {
    let e = run(&opts(&["de"], &["p"])).unwrap_err().to_string();
    assert!(e.contains("--output") && e.contains("`p` is not in the record"), "{e}");
    let e = run(&opts(&["elevator"], &["q"])).unwrap_err().to_string();
    assert!(e.contains("--input") && e.contains("`elevator` is not a channel"), "{e}");
    let mut o = opts(&["de"], &["q"]);
    o.spectral.window_lengths_s = vec![100.0];
    let e = run(&o).unwrap_err().to_string();
    assert!(
        e.contains("`--windows-s`") && e.contains("longer than the longest contiguous stretch"),
        "{e}"
    );
    let e = run(&opts(&["vt"], &["q"])).unwrap_err().to_string();
    assert!(e.contains("input `vt` is not excited"), "{e}");
    let mut o = opts(&["de"], &["q"]);
    o.fits = vec![TfSpec::parse("r/dr:0/2").unwrap()];
    let e = run(&o).unwrap_err().to_string();
    assert!(e.contains("--fit") && e.contains("no response of `r` to `dr`"), "{e}");
}

/// Each spectral or fit option out of range is named as the command line spells it (an option
/// that exists), and the ones the options alone decide are refused before the record is read.
#[test]
fn options_out_of_range_are_named_by_their_flag() {
    type Set = fn(&mut FreqRespOptions);
    let cases: [(Set, &str); 6] = [
        (|o| o.spectral.points_per_decade = 1_000_000_000_000, "`--points-per-decade`"),
        (|o| o.spectral.points_per_decade = usize::MAX, "`--points-per-decade`"),
        (|o| o.spectral.f_max_hz = Some(30.0), "`--f-max-hz`"),
        (|o| o.spectral.f_min_hz = Some(1e-4), "`--f-min-hz`"),
        (|o| o.fit.min_coherence = f64::NAN, "`--min-coherence`"),
        (|o| o.fit.min_coherence = 1.5, "`--min-coherence`"),
    ];
    for (set, flag) in cases {
        let mut o = opts(&["de"], &["q"]);
        set(&mut o);
        let e = run(&o).unwrap_err().to_string();
        assert!(e.contains(flag), "{flag}: {e}");
    }
    // Refused before reading: a record that could not be read gives the option's error.
    let mut o = opts(&["de"], &["q"]);
    o.spectral.points_per_decade = 1_000_000;
    let m = Mapping::from_toml_str(MAP, "m.toml").unwrap();
    let reader = FlightDataReader::new("t,V,a,q,de\n".as_bytes(), "r.csv", &m).unwrap();
    let e = freqresp(reader, &o).unwrap_err().to_string();
    assert!(e.contains("`--points-per-decade`") && e.contains("1000"), "{e}");
}

/// The coherent band runs from the first to the last frequency at or above the threshold (in
/// rad/s), counting every such point; none without one.
#[test]
fn coherent_band_of_a_pair() {
    let p = PairResponse {
        input: "de".into(),
        output: "q".into(),
        frequency_hz: vec![0.1, 0.2, 0.3, 0.4, 0.5],
        magnitude_db: vec![0.0; 5],
        phase_deg: vec![0.0; 5],
        coherence: vec![0.5, 0.8, 0.3, 0.9, 0.7],
        multiple_coherence: vec![0.0; 5],
        random_error: vec![0.0; 5],
        magnitude_error_db: vec![0.0; 5],
        phase_error_deg: vec![0.0; 5],
        re: vec![0.0; 5],
        im: vec![0.0; 5],
    };
    let b = coherent_band(&p, GOOD_COHERENCE).unwrap();
    assert_eq!((b.lo_rad_s, b.hi_rad_s), (2.0 * PI * 0.2, 2.0 * PI * 0.4));
    assert_eq!((b.points, b.of), (2, 5));
    assert_eq!(coherent_band(&p, 0.95), None);
}
