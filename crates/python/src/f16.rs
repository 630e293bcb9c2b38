//! The F-16 (Stevens, Lewis & Johnson 3rd ed.): `trim`, `linearize`, `simulate`, the same code
//! and messages as `aeroident f16 trim|linearize|sim`.

use std::io::Write as _;
use std::path::Path;

use aeroident_models::f16::{ALPHA, BETA, F16, N_STATES, STATE_NAMES, THETA};
use aeroident_models::linearize::{eigenvalues, f16_modes, linearize_f16};
use aeroident_models::trim::F16Trim;
use aeroident_pipelines::sim::trim::{TrimRequest, out_of_range_warning, trim_at};
use anyhow::bail;
use numpy::IntoPyArray;
use numpy::ndarray::Array2;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::to_py;

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

fn trim_dict<'py>(py: Python<'py>, t: &F16Trim) -> PyResult<Bound<'py, PyDict>> {
    let c = &t.controls;
    let d = PyDict::new(py);
    d.set_item("throttle", c.throttle)?;
    d.set_item("elevator_deg", c.elevator_rad.to_degrees())?;
    d.set_item("aileron_deg", c.aileron_rad.to_degrees())?;
    d.set_item("rudder_deg", c.rudder_rad.to_degrees())?;
    d.set_item("alpha_deg", t.state[ALPHA].to_degrees())?;
    d.set_item("beta_deg", t.state[BETA].to_degrees())?;
    d.set_item("theta_deg", t.state[THETA].to_degrees())?;
    d.set_item("cost", t.cost)?;
    d.set_item("state", t.state.iter().copied().collect::<Vec<f64>>().into_pyarray(py))?;
    d.set_item("state_names", STATE_NAMES.to_vec())?;
    d.set_item(
        "controls",
        vec![c.throttle, c.elevator_rad, c.aileron_rad, c.rudder_rad].into_pyarray(py),
    )?;
    d.set_item("out_of_range", t.out_of_range.clone())?;
    Ok(d)
}

/// See `aeroident.trim`.
#[pyfunction]
#[pyo3(signature = (alt_ft, vt_fps, xcg=0.35, gamma_deg=0.0, turn_rate_deg_s=None, pull_up_deg_s=None))]
fn trim<'py>(
    py: Python<'py>,
    alt_ft: f64,
    vt_fps: f64,
    xcg: f64,
    gamma_deg: f64,
    turn_rate_deg_s: Option<f64>,
    pull_up_deg_s: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let c = TrimRequest { alt_ft, vt_fps, xcg, gamma_deg, turn_rate_deg_s, pull_up_deg_s };
    let r = py.detach(move || do_trim(&c));
    py.check_signals()?;
    let (_, t) = r.map_err(to_py)?;
    trim_dict(py, &t)
}

/// See `aeroident.linearize`.
#[pyfunction]
#[pyo3(signature = (alt_ft, vt_fps, xcg=0.35, gamma_deg=0.0, turn_rate_deg_s=None, pull_up_deg_s=None))]
fn linearize<'py>(
    py: Python<'py>,
    alt_ft: f64,
    vt_fps: f64,
    xcg: f64,
    gamma_deg: f64,
    turn_rate_deg_s: Option<f64>,
    pull_up_deg_s: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let c = TrimRequest { alt_ft, vt_fps, xcg, gamma_deg, turn_rate_deg_s, pull_up_deg_s };
    let r = py.detach(move || -> anyhow::Result<_> {
        let (f16, t) = do_trim(&c)?;
        let lin = linearize_f16(&f16, &t.state, &t.controls)?;
        Ok((t, lin))
    });
    py.check_signals()?;
    let (t, lin) = r.map_err(to_py)?;
    let a = Array2::from_shape_fn((N_STATES, N_STATES), |(i, j)| lin.a[(i, j)]);
    let b = Array2::from_shape_fn((N_STATES, 4), |(i, j)| lin.b[(i, j)]);
    let ev = eigenvalues(&lin.a);
    let ev =
        Array2::from_shape_fn((ev.len(), 2), |(i, j)| if j == 0 { ev[i].re } else { ev[i].im });
    let d = PyDict::new(py);
    d.set_item("a", a.into_pyarray(py))?;
    d.set_item("b", b.into_pyarray(py))?;
    d.set_item("eigenvalues", ev.into_pyarray(py))?;
    let modes = pyo3::types::PyList::empty(py);
    for m in f16_modes(&lin.a) {
        let md = PyDict::new(py);
        md.set_item("name", m.name.as_str())?;
        md.set_item("eigenvalue", (m.eigenvalue.re, m.eigenvalue.im))?;
        md.set_item("wn_radps", m.wn_rad_s)?;
        md.set_item("zeta", m.zeta)?;
        modes.append(md)?;
    }
    d.set_item("modes", modes)?;
    d.set_item("state_names", STATE_NAMES.to_vec())?;
    d.set_item("input_names", vec!["throttle", "elevator_rad", "aileron_rad", "rudder_rad"])?;
    d.set_item("trim", trim_dict(py, &t)?)?;
    Ok(d)
}

/// See `aeroident.simulate`.
#[pyfunction]
fn simulate<'py>(py: Python<'py>, scenario: &str) -> PyResult<Bound<'py, PyDict>> {
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
        d.set_item(name, col.into_pyarray(py))?;
    }
    Ok(d)
}
