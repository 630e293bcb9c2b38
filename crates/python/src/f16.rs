//! The F-16 (Stevens, Lewis & Johnson 3rd ed.): `trim`, `linearize`, `simulate`, the same code
//! and messages as `aeroident f16 trim|linearize|sim`. The library computes in the textbook's
//! units (ft, ft/s); Python gets SI by default and those units only under `*_textbook` names
//! ([`crate::units`]).

use std::io::Write as _;
use std::path::Path;

use aeroident_models::f16::{ALPHA, BETA, CONTROL_NAMES, F16, N_STATES, STATE_NAMES, THETA};
use aeroident_models::linearize::{eigenvalues, f16_modes, linearize_f16};
use aeroident_models::trim::F16Trim;
use aeroident_physics::units::M_PER_FT;
use aeroident_pipelines::sim::trim::{TrimRequest, out_of_range_warning, trim_at};
use anyhow::bail;
use numpy::IntoPyArray;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::matrix;
use crate::to_py;
use crate::units::{StateUnits, si_name};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(trim, m)?)?;
    m.add_function(wrap_pyfunction!(linearize, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    Ok(())
}

/// The trim of `aeroident f16 trim` (same defaults, checks, error context and warnings:
/// [`aeroident_pipelines::sim::trim::trim_at`]); the command line enforces the turn/pull-up
/// exclusion in its parser, so it is checked here.
fn do_trim(a: &TrimRequest) -> anyhow::Result<(F16, F16Trim)> {
    if a.turn_rate_deg_s.is_some() && a.pull_up_deg_s.is_some() {
        bail!("give at most one of turn_rate_deg_s and pull_up_deg_s");
    }
    let (f16, t) = trim_at(a)?;
    for w in &t.out_of_range {
        // `eprintln!` panics when stderr is closed; a warning is not worth a panic.
        let _ = writeln!(std::io::stderr(), "warning: {}", out_of_range_warning(w));
    }
    Ok((f16, t))
}

/// A number keyword of `kw` (`None` or absent: not given).
///
/// # Errors
/// `TypeError` naming the keyword when it is not a number.
fn given(kw: &Bound<'_, PyDict>, key: &str) -> PyResult<Option<f64>> {
    match kw.get_item(key)? {
        None => Ok(None),
        Some(v) if v.is_none() => Ok(None),
        Some(v) => v.extract::<f64>().map(Some).map_err(|_| {
            let what = v.repr().map_or_else(|_| "?".into(), |r| r.to_string());
            PyTypeError::new_err(format!("{key} must be a number, got {what}"))
        }),
    }
}

/// A quantity given by its SI keyword `si` or its textbook keyword `textbook` (not both), in
/// the textbook unit (`to_textbook` converts an SI value).
///
/// # Errors
/// `TypeError` naming both keywords when both are given, or one that is not a number.
fn one_of(
    kw: &Bound<'_, PyDict>,
    si: &str,
    textbook: &str,
    to_textbook: fn(f64) -> f64,
) -> PyResult<Option<f64>> {
    match (given(kw, si)?, given(kw, textbook)?) {
        (Some(_), Some(_)) => {
            Err(PyTypeError::new_err(format!("give {si} or {textbook}, not both")))
        }
        (Some(v), None) => Ok(Some(to_textbook(v))),
        (None, v) => Ok(v),
    }
}

/// The keywords of a flight condition: SI first, then the textbook's (ft, ft/s, deg).
const CONDITION_KEYWORDS: [&str; 11] = [
    "vt_mps",
    "alt_m",
    "xcg",
    "gamma_rad",
    "turn_rate_rad_s",
    "pull_up_rad_s",
    "vt_fps",
    "alt_ft",
    "gamma_deg",
    "turn_rate_deg_s",
    "pull_up_deg_s",
];

/// The flight condition of `trim` and `linearize` from their keywords (the Python package's
/// wrappers pass every one, `None` when not given), in the textbook units the library's trim
/// takes: SI converted with the workspace's constants ([`M_PER_FT`]).
///
/// # Errors
/// `TypeError` naming the keyword: an unknown one, a quantity given twice (SI and textbook),
/// a missing airspeed or altitude.
fn condition(kw: &Bound<'_, PyDict>) -> PyResult<TrimRequest> {
    for k in kw.keys() {
        let k: String = k.extract()?;
        if !CONDITION_KEYWORDS.contains(&k.as_str()) {
            return Err(PyTypeError::new_err(format!("unexpected keyword argument `{k}`")));
        }
    }
    let ft: fn(f64) -> f64 = |m| m / M_PER_FT;
    let deg: fn(f64) -> f64 = f64::to_degrees;
    let required = |v: Option<f64>, si: &str, textbook: &str| {
        v.ok_or_else(|| PyTypeError::new_err(format!("give {si} (SI) or {textbook}")))
    };
    Ok(TrimRequest {
        vt_fps: required(one_of(kw, "vt_mps", "vt_fps", ft)?, "vt_mps", "vt_fps")?,
        alt_ft: required(one_of(kw, "alt_m", "alt_ft", ft)?, "alt_m", "alt_ft")?,
        xcg: given(kw, "xcg")?.unwrap_or(0.35),
        gamma_deg: one_of(kw, "gamma_rad", "gamma_deg", deg)?.unwrap_or(0.0),
        turn_rate_deg_s: one_of(kw, "turn_rate_rad_s", "turn_rate_deg_s", deg)?,
        pull_up_deg_s: one_of(kw, "pull_up_rad_s", "pull_up_deg_s", deg)?,
    })
}

/// The result dict of `trim` (documented on `aeroident.trim`): the command line's `--json`
/// keys, their SI twins, and the state in SI and in the textbook's units.
fn trim_dict<'py>(py: Python<'py>, t: &F16Trim) -> PyResult<Bound<'py, PyDict>> {
    let c = &t.controls;
    let d = PyDict::new(py);
    let (alpha, beta, theta) = (t.state[ALPHA], t.state[BETA], t.state[THETA]);
    // The command line's keys first, in degrees as it prints them, then the same in radians.
    let cli = [
        ("throttle", c.throttle),
        ("elevator_deg", c.elevator_rad.to_degrees()),
        ("aileron_deg", c.aileron_rad.to_degrees()),
        ("rudder_deg", c.rudder_rad.to_degrees()),
        ("alpha_deg", alpha.to_degrees()),
        ("beta_deg", beta.to_degrees()),
        ("theta_deg", theta.to_degrees()),
        ("cost", t.cost),
    ];
    let si = [
        ("elevator_rad", c.elevator_rad),
        ("aileron_rad", c.aileron_rad),
        ("rudder_rad", c.rudder_rad),
        ("alpha_rad", alpha),
        ("beta_rad", beta),
        ("theta_rad", theta),
    ];
    for (k, v) in cli.into_iter().chain(si) {
        d.set_item(k, v)?;
    }
    let units = StateUnits::of(&STATE_NAMES);
    let x: Vec<f64> = t.state.iter().copied().collect();
    d.set_item("state", units.to_si(&x).into_pyarray(py))?;
    d.set_item("state_names", units.si.clone())?;
    d.set_item("state_textbook", x.into_pyarray(py))?;
    d.set_item("state_names_textbook", units.textbook.clone())?;
    let u = vec![c.throttle, c.elevator_rad, c.aileron_rad, c.rudder_rad];
    d.set_item("controls", u.into_pyarray(py))?;
    d.set_item("control_names", CONTROL_NAMES.to_vec())?;
    d.set_item("out_of_range", t.out_of_range.clone())?;
    Ok(d)
}

/// The trim of `aeroident.trim` (documented there) at the condition of its keywords.
#[pyfunction]
fn trim<'py>(py: Python<'py>, condition: &Bound<'py, PyDict>) -> PyResult<Bound<'py, PyDict>> {
    let c = self::condition(condition)?;
    let r = py.detach(move || do_trim(&c));
    py.check_signals()?;
    let (_, t) = r.map_err(to_py)?;
    trim_dict(py, &t)
}

/// The modes of a linear model as dicts (`name`, `eigenvalue` (re, im), `wn_radps`, `zeta`).
pub fn modes_list<'py>(
    py: Python<'py>,
    modes: &[aeroident_models::linearize::Mode],
) -> PyResult<Bound<'py, PyList>> {
    let list = PyList::empty(py);
    for m in modes {
        let md = PyDict::new(py);
        md.set_item("name", m.name.as_str())?;
        md.set_item("eigenvalue", (m.eigenvalue.re, m.eigenvalue.im))?;
        md.set_item("wn_radps", m.wn_rad_s)?;
        md.set_item("zeta", m.zeta)?;
        list.append(md)?;
    }
    Ok(list)
}

/// The linear model of `aeroident.linearize` (documented there) at the condition of its
/// keywords: `a`, `b` in SI, `a_textbook`, `b_textbook` as the command line's `--json`.
#[pyfunction]
fn linearize<'py>(py: Python<'py>, condition: &Bound<'py, PyDict>) -> PyResult<Bound<'py, PyDict>> {
    let c = self::condition(condition)?;
    let r = py.detach(move || -> anyhow::Result<_> {
        let (f16, t) = do_trim(&c)?;
        let lin = linearize_f16(&f16, &t.state, &t.controls)?;
        Ok((t, lin))
    });
    py.check_signals()?;
    let (t, lin) = r.map_err(to_py)?;
    let rows = |m: &dyn Fn(usize, usize) -> f64, cols: usize| -> Vec<Vec<f64>> {
        (0..N_STATES).map(|i| (0..cols).map(|j| m(i, j)).collect()).collect()
    };
    let a = rows(&|i, j| lin.a[(i, j)], N_STATES);
    let b = rows(&|i, j| lin.b[(i, j)], 4);
    let units = StateUnits::of(&STATE_NAMES);
    let ev = eigenvalues(&lin.a);
    let ev: Vec<Vec<f64>> = ev.iter().map(|e| vec![e.re, e.im]).collect();
    let d = PyDict::new(py);
    d.set_item("a", matrix(&units.a_to_si(&a)).into_pyarray(py))?;
    d.set_item("b", matrix(&units.b_to_si(&b)).into_pyarray(py))?;
    d.set_item("a_textbook", matrix(&a).into_pyarray(py))?;
    d.set_item("b_textbook", matrix(&b).into_pyarray(py))?;
    d.set_item("eigenvalues", matrix(&ev).into_pyarray(py))?;
    d.set_item("modes", modes_list(py, &f16_modes(&lin.a))?)?;
    d.set_item("state_names", units.si.clone())?;
    d.set_item("state_names_textbook", units.textbook.clone())?;
    d.set_item("input_names", CONTROL_NAMES.to_vec())?;
    d.set_item("trim", trim_dict(py, &t)?)?;
    Ok(d)
}

/// The open-loop simulation of `aeroident.simulate` (documented there): the columns of
/// `timeseries.csv`, in SI (renamed by their unit suffix) unless `textbook`.
#[pyfunction]
#[pyo3(signature = (scenario, textbook=false))]
fn simulate<'py>(py: Python<'py>, scenario: &str, textbook: bool) -> PyResult<Bound<'py, PyDict>> {
    let path = scenario.to_owned();
    let r = py.detach(move || {
        let p = Path::new(&path);
        let sc = aeroident_pipelines::sim::load_scenario(p)?;
        aeroident_pipelines::sim::run(&sc, p.parent().unwrap_or(Path::new(".")))
    });
    py.check_signals()?;
    let r = r.map_err(to_py)?;
    let d = PyDict::new(py);
    for (name, col) in r.table.columns.iter().zip(r.table.data) {
        if textbook {
            d.set_item(name, col.into_pyarray(py))?;
        } else {
            let (si, factor) = si_name(name);
            let col: Vec<f64> = col.into_iter().map(|v| v * factor).collect();
            d.set_item(si, col.into_pyarray(py))?;
        }
    }
    Ok(d)
}
