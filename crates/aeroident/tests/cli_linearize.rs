//! `aeroident linearize --json` is the state-space export: A, B, C, D with the state and input
//! names. For the F-16 it goes through the aircraft interface (SI arguments, the trait's trim)
//! and must give the A and B of `aeroident f16 linearize`, which calls the F-16's own trim and
//! linearization with the textbook's units directly.

use serde_json::Value;
use std::process::Command;

fn json(args: &[&str]) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_aeroident")).args(args).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

fn matrix(v: &Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect())
        .collect()
}

/// 20 000 ft = 6096 m, 675 ft/s = 205.74 m/s, xcg 0.35: A and B agree element by element to
/// 1e-6 of each matrix's largest entry; C is the identity over the 13 named states, D is 0.
#[test]
fn analytic_the_state_space_export_equals_the_f16s_own_linearization() {
    let ss = json(&[
        "linearize",
        "--aircraft",
        "f16",
        "--vt-mps",
        "205.74",
        "--alt-m",
        "6096",
        "--json",
    ]);
    let f16 = json(&[
        "f16",
        "linearize",
        "--alt-ft",
        "20000",
        "--vt-fps",
        "675",
        "--xcg",
        "0.35",
        "--json",
    ]);
    for key in ["a", "b"] {
        let (x, y) = (matrix(&ss[key]), matrix(&f16[key]));
        assert_eq!((x.len(), x[0].len()), (y.len(), y[0].len()), "{key}");
        let scale = y.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for (i, (rx, ry)) in x.iter().zip(&y).enumerate() {
            for (j, (a, b)) in rx.iter().zip(ry).enumerate() {
                assert!((a - b).abs() <= 1e-6 * scale, "{key}[{i}][{j}]: {a} against {b}");
            }
        }
    }
    let states = ss["states"].as_array().unwrap();
    assert_eq!(states.len(), 13);
    assert_eq!(states[0], "vt_fps");
    assert_eq!(ss["inputs"].as_array().unwrap().len(), 4);
    let (c, d) = (matrix(&ss["c"]), matrix(&ss["d"]));
    for (i, row) in c.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            assert_eq!(*v, if i == j { 1.0 } else { 0.0 });
        }
    }
    assert!(d.len() == 13 && d.iter().flatten().all(|v| *v == 0.0));
}
