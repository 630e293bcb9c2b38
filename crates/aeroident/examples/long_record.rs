//! A long synthetic six-axis flight record as CSV on stdout, for the bounded-memory check of
//! `aeroident replay` (target: 24 h of 100 Hz through `replay -` and `replay FILE
//! --out DIR` with peak RSS ≤ 64 MB and the throughput of the last hour within 20 % of the
//! first).
//!
//! Flies the synthetic six-axis test aircraft of `crates/estimators/src/test_aircraft.rs` (the
//! stream of the update bench and the `update_times` example: level trim at 180 m/s, generic
//! priors as its aerodynamics, elevator, aileron and rudder doublets at 1, 6 and 12 s of every
//! 20 s, four Euler substeps per sample), but streams it: one row is formatted and written at a
//! time, so the generator itself runs in constant memory for any length.
//!
//! Every value is written as `{:+.9e}` (16 characters), so every data row has the same length
//! ([`ROW_BYTES`]) and the byte offset of row `k` is `header + k · ROW_BYTES`: a monitor of the
//! bytes a replay has read (`/proc/PID/io` `rchar`) knows which sample it is at
//! (`scripts/long_replay.sh`).
//!
//! Run: `cargo run --release -p aeroident --example long_record -- [HOURS] [RATE_HZ]
//! [--mapping FILE]` (default 24 h at 100 Hz, 8.64 M rows, ≈ 2.6 GB). `--mapping FILE` writes
//! the matching channel mapping (SI units, the constants of the test aircraft) to FILE.
//! Progress and the state every simulated hour go to stderr.
#![allow(missing_docs)]

#[path = "../../estimators/src/test_aircraft.rs"]
mod test_aircraft;

use aeroident_estimators::flight_model::{FlightModel, ModelInputs};
use aeroident_estimators::prior::Priors;
use aeroident_estimators::sample::AircraftConstants;
use aeroident_estimators::vocabulary::{Coefficient as C, ModelStructure, Param, Term as T};
use std::io::Write;

/// Columns of the record, in order: (CSV name, mapping channel, unit).
const COLUMNS: [(&str, &str, &str); 18] = [
    ("time_s", "time", "s"),
    ("vt_mps", "vt", "m/s"),
    ("alpha_rad", "alpha", "rad"),
    ("beta_rad", "beta", "rad"),
    ("p_radps", "p", "rad/s"),
    ("q_radps", "q", "rad/s"),
    ("r_radps", "r", "rad/s"),
    ("phi_rad", "phi", "rad"),
    ("theta_rad", "theta", "rad"),
    ("de_rad", "de", "rad"),
    ("da_rad", "da", "rad"),
    ("dr_rad", "dr", "rad"),
    ("ax_mps2", "ax", "m/s2"),
    ("ay_mps2", "ay", "m/s2"),
    ("az_mps2", "az", "m/s2"),
    ("pdot_radps2", "pdot", "rad/s2"),
    ("qdot_radps2", "qdot", "rad/s2"),
    ("rdot_radps2", "rdot", "rad/s2"),
];

/// Bytes of one data row: 18 fields of 16 characters, 17 commas and a newline.
pub const ROW_BYTES: usize = 18 * 16 + 17 + 1;

/// The channel mapping of the record: columns in SI, constants of the test aircraft.
fn mapping(k: &AircraftConstants, dt_s: f64) -> String {
    let mut m = String::from(
        "# Synthetic six-axis record of examples/long_record.rs (the test aircraft of\n\
         # crates/estimators/src/test_aircraft.rs), SI units.\n",
    );
    m += "description = \"long_record example: synthetic six-axis test aircraft\"\n";
    m += &format!(
        "nominal_dt_s = {dt_s}\n\n[time]\ncolumn = \"time_s\"\nunit = \"s\"\n\n[channels]\n"
    );
    for (col, ch, unit) in &COLUMNS[1..] {
        m += &format!("{ch} = {{ column = \"{col}\", unit = \"{unit}\" }}\n");
    }
    let opt = |v: Option<f64>| v.unwrap_or(f64::NAN);
    for (ch, v, unit) in [
        ("thrust", test_aircraft::THRUST, "N"),
        ("rho", test_aircraft::RHO, "kg/m3"),
        ("mass", k.mass_kg, "kg"),
        ("S", k.S_m2, "m2"),
        ("cbar", opt(k.cbar_m), "m"),
        ("b", opt(k.b_m), "m"),
        ("Ixx", opt(k.Ixx_kgm2), "kg*m2"),
        ("Iyy", opt(k.Iyy_kgm2), "kg*m2"),
        ("Izz", opt(k.Izz_kgm2), "kg*m2"),
        ("Ixz", opt(k.Ixz_kgm2), "kg*m2"),
    ] {
        m += &format!("{ch} = {{ value = {v:?}, unit = \"{unit}\" }}\n");
    }
    m
}

fn main() -> std::io::Result<()> {
    let mut args = std::env::args().skip(1);
    let mut nums = Vec::new();
    let mut mapping_path = None;
    while let Some(a) = args.next() {
        if a == "--mapping" {
            mapping_path = args.next();
        } else {
            nums.push(a.parse::<f64>().unwrap_or_else(|_| panic!("not a number: {a}")));
        }
    }
    let hours = nums.first().copied().unwrap_or(24.0);
    let rate_hz = nums.get(1).copied().unwrap_or(100.0);
    let dt_s = 1.0 / rate_hz;
    let n = (hours * 3600.0 * rate_hz).round() as usize;

    let st = ModelStructure::six_axis();
    let model = FlightModel::new(st).expect("six-axis flight model");
    let pri = Priors::generic(&st);
    let mut th: Vec<f64> = (0..st.n_params()).map(|i| pri.prior[i].value).collect();
    let k = AircraftConstants { v0_mps: None, ..test_aircraft::constants() };
    test_aircraft::set_level_trim_biases(&st, &mut th, &k);
    for c in [C::CY, C::Cl, C::Cn] {
        th[st.index_of(Param::new(c, T::Bias)).expect("bias")] = 0.0;
    }
    if let Some(p) = mapping_path {
        std::fs::write(&p, mapping(&k, dt_s))?;
        eprintln!("mapping written to {p}");
    }

    let out = std::io::stdout().lock();
    let mut out = std::io::BufWriter::with_capacity(1 << 16, out);
    let header: Vec<&str> = COLUMNS.iter().map(|c| c.0).collect();
    writeln!(out, "{}", header.join(","))?;
    let db = |t: f64, t0: f64, a: f64| test_aircraft::doublet(t, t0, 0.5, a);
    let (v0, a0) = (test_aircraft::V0, test_aircraft::ALPHA0);
    let mut x = [v0, a0, 0.0, 0.0, 0.0, 0.0, 0.0, a0];
    let z8 = [0.0; 8];
    let per_hour = (3600.0 * rate_hz).round() as usize;
    let mut line = String::with_capacity(ROW_BYTES);
    for step in 0..n {
        let t = step as f64 * dt_s;
        let tc = t % 20.0;
        let surfaces = (db(tc, 1.0, 0.03), db(tc, 6.0, -0.04), db(tc, 12.0, 0.05));
        let s = test_aircraft::sample(t, &x, surfaces, k);
        let u: ModelInputs = model.inputs(&s).expect("inputs");
        let d = model.eval(&th, &u, &x, &z8, &z8, None).expect("model");
        let row = [
            t, x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], surfaces.0, surfaces.1, surfaces.2,
            d.accel[0], d.accel[1], d.accel[2], d.xdot[3], d.xdot[4], d.xdot[5],
        ];
        line.clear();
        for (j, v) in row.iter().enumerate() {
            if j > 0 {
                line.push(',');
            }
            // Fixed width: sign, d.ddddddddd, e, sign-less exponent padded to 3 characters.
            let f = format!("{v:+.9e}");
            let (mant, exp) = f.split_once('e').expect("exponent");
            line.push_str(mant);
            line.push('e');
            let e: i32 = exp.parse().expect("exponent");
            line.push_str(&format!("{:+03}", e));
        }
        line.push('\n');
        debug_assert_eq!(line.len(), ROW_BYTES, "{line}");
        if !row.iter().all(|v| v.is_finite()) || line.len() != ROW_BYTES {
            eprintln!("row {step}: not finite or not {ROW_BYTES} bytes: {line}");
            std::process::exit(1);
        }
        out.write_all(line.as_bytes())?;
        if step % per_hour == 0 {
            eprintln!(
                "hour {:>2}: V {:.2} m/s, alpha {:.4} rad, beta {:.2e} rad, phi {:.2e} rad, theta {:.4} rad",
                step / per_hour,
                x[0],
                x[1],
                x[2],
                x[6],
                x[7]
            );
        }
        for _ in 0..4 {
            let f = model.eval(&th, &u, &x, &z8, &z8, None).expect("model").xdot;
            for (xj, fj) in x.iter_mut().zip(f) {
                *xj += 0.25 * dt_s * fj;
            }
        }
    }
    out.flush()
}
