//! `aeroident.Aircraft`: the F-16 or a model-file aircraft as an object a user closes their own
//! loop around (trim, derivatives, one step, linearize, the estimator's sample). The work is the
//! library's ([`aeroident_pipelines::airframe::AnyAircraft`]); this module converts.

use aeroident_models::aircraft::N_CONTROLS;
use aeroident_pipelines::airframe::{AnyAircraft, Trim};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::Path;

use crate::{err, to_py};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Aircraft>()
}

/// See `aeroident.Aircraft`.
#[pyclass(module = "aeroident", name = "Aircraft", frozen)]
pub struct Aircraft {
    inner: AnyAircraft,
}

fn controls_of(c: &[f64]) -> PyResult<[f64; N_CONTROLS]> {
    <[f64; N_CONTROLS]>::try_from(c).map_err(|_| {
        err(format!(
            "controls: {} values given; 4 expected (engine, elevator_rad, aileron_rad, rudder_rad)",
            c.len()
        ))
    })
}

fn slice<'a>(a: &'a PyReadonlyArray1<'_, f64>, what: &str) -> PyResult<&'a [f64]> {
    a.as_slice().map_err(|_| err(format!("{what}: a contiguous 1-D float array is expected")))
}

fn trim_dict<'py>(py: Python<'py>, ac: &AnyAircraft, t: &Trim) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("state", t.state.clone().into_pyarray(py))?;
    d.set_item("controls", t.controls.to_vec().into_pyarray(py))?;
    d.set_item("state_names", ac.state_names())?;
    d.set_item("control_names", ac.control_names().0.to_vec())?;
    d.set_item("max_abs_residual", t.max_abs_residual)?;
    Ok(d)
}

fn matrix(rows: &[Vec<f64>]) -> Array2<f64> {
    let cols = rows.first().map_or(0, Vec::len);
    Array2::from_shape_fn((rows.len(), cols), |(i, j)| rows[i][j])
}

#[pymethods]
impl Aircraft {
    /// The Stevens & Lewis F-16 at cg `xcg` (fraction of c̄): 13 states in ft, ft/s, rad.
    #[staticmethod]
    #[pyo3(signature = (xcg=0.35))]
    fn f16(xcg: f64) -> PyResult<Self> {
        Ok(Self { inner: AnyAircraft::f16(xcg).map_err(to_py)? })
    }

    /// An aircraft flying a model file's derivatives (a summary's estimates, else the file's
    /// reference values) with a mapping's constants: 12 states, SI.
    #[staticmethod]
    #[pyo3(signature = (model, mapping, summary=None))]
    fn from_model(model: &str, mapping: &str, summary: Option<&str>) -> PyResult<Self> {
        let m = aeroident_pipelines::airframe::load(
            Path::new(model),
            summary.map(Path::new),
            Path::new(mapping),
        )
        .map_err(to_py)?;
        Ok(Self { inner: AnyAircraft::ModelFile(Box::new(m)) })
    }

    /// The same F-16 with coefficient increments (`{"Cm_alpha": -0.04, "Cm_de": 0.2}`, per rad
    /// or per unit hat-rate) about the trim `about` (a `trim()` dict), from `onset_s` on.
    #[pyo3(signature = (increments, about, onset_s=None))]
    fn with_damage(
        &self,
        increments: std::collections::BTreeMap<String, f64>,
        about: &Bound<'_, PyDict>,
        onset_s: Option<f64>,
    ) -> PyResult<Self> {
        let get = |k: &str| -> PyResult<Vec<f64>> {
            about.get_item(k)?.ok_or_else(|| err(format!("about: key `{k}` missing")))?.extract()
        };
        let (state, controls) = (get("state")?, controls_of(&get("controls")?)?);
        let values: Vec<(String, f64)> = increments.into_iter().collect();
        let inner = self.inner.clone().with_increments(&values, &state, &controls, onset_s);
        Ok(Self { inner: inner.map_err(to_py)? })
    }

    /// A short name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name()
    }

    /// The states' names with their units.
    #[getter]
    fn state_names(&self) -> Vec<&'static str> {
        self.inner.state_names()
    }

    /// The controls' names.
    #[getter]
    fn control_names(&self) -> Vec<&'static str> {
        self.inner.control_names().0.to_vec()
    }

    /// What the engine command (control 0) is.
    #[getter]
    fn engine_command(&self) -> &'static str {
        self.inner.control_names().1
    }

    /// Metres per length unit of the states.
    #[getter]
    fn length_unit_m(&self) -> f64 {
        self.inner.length_unit_m()
    }

    /// Wings-level, level trim at `vt_mps` (m/s), `alt_m` (m).
    fn trim<'py>(&self, py: Python<'py>, vt_mps: f64, alt_m: f64) -> PyResult<Bound<'py, PyDict>> {
        let t = self.inner.trim_level(vt_mps, alt_m).map_err(to_py)?;
        trim_dict(py, &self.inner, &t)
    }

    /// The state derivative at `state`, `controls` (time `t_s` for a damage onset).
    #[pyo3(signature = (state, controls, t_s=0.0))]
    fn derivatives<'py>(
        &self,
        py: Python<'py>,
        state: PyReadonlyArray1<'_, f64>,
        controls: Vec<f64>,
        t_s: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let c = controls_of(&controls)?;
        let xd = self.inner.derivatives(t_s, slice(&state, "state")?, &c).map_err(to_py)?;
        Ok(xd.into_pyarray(py))
    }

    /// The state `dt_s` later (one RK4 step, controls held), from time `t_s`.
    #[pyo3(signature = (state, controls, dt_s, t_s=0.0))]
    fn step<'py>(
        &self,
        py: Python<'py>,
        state: PyReadonlyArray1<'_, f64>,
        controls: Vec<f64>,
        dt_s: f64,
        t_s: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let c = controls_of(&controls)?;
        let x = self.inner.step(t_s, slice(&state, "state")?, &c, dt_s).map_err(to_py)?;
        Ok(x.into_pyarray(py))
    }

    /// The linear model about the level trim at `vt_mps`, `alt_m`: a, b, c, d, states,
    /// inputs, eigenvalues (n × 2: real, imaginary), modes, trim.
    fn linearize<'py>(
        &self,
        py: Python<'py>,
        vt_mps: f64,
        alt_m: f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let l = self.inner.linearize_level(vt_mps, alt_m).map_err(to_py)?;
        let n = l.a.len();
        let d = PyDict::new(py);
        d.set_item("a", matrix(&l.a).into_pyarray(py))?;
        d.set_item("b", matrix(&l.b).into_pyarray(py))?;
        d.set_item("c", Array2::<f64>::eye(n).into_pyarray(py))?;
        d.set_item("d", Array2::<f64>::zeros((n, N_CONTROLS)).into_pyarray(py))?;
        d.set_item("states", self.inner.state_names())?;
        d.set_item("inputs", self.inner.control_names().0.to_vec())?;
        let ev: Vec<Vec<f64>> = l.eigenvalues.iter().map(|&(re, im)| vec![re, im]).collect();
        d.set_item("eigenvalues", matrix(&ev).into_pyarray(py))?;
        let modes = pyo3::types::PyList::empty(py);
        for m in &l.modes {
            let md = PyDict::new(py);
            md.set_item("name", m.name.as_str())?;
            md.set_item("eigenvalue", (m.eigenvalue.re, m.eigenvalue.im))?;
            md.set_item("wn_radps", m.wn_rad_s)?;
            md.set_item("zeta", m.zeta)?;
            modes.append(md)?;
        }
        d.set_item("modes", modes)?;
        d.set_item("trim", trim_dict(py, &self.inner, &l.trim)?)?;
        Ok(d)
    }

    /// The exact air-data sample at `state`, `controls` (F-16): the dict an `Estimator`'s
    /// `update` takes; `v0_mps` the reference airspeed of the `V/V0` term (default: the
    /// state's airspeed).
    #[pyo3(signature = (state, controls, t_s=0.0, v0_mps=None))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        state: PyReadonlyArray1<'_, f64>,
        controls: Vec<f64>,
        t_s: f64,
        v0_mps: Option<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (x, c) = (slice(&state, "state")?, controls_of(&controls)?);
        let v0 = v0_mps.unwrap_or(x[0] * self.inner.length_unit_m());
        let s = self.inner.sample(t_s, x, &c, v0).map_err(to_py)?;
        crate::convert::sample_to_dict(py, &s)
    }

    fn __repr__(&self) -> String {
        format!("Aircraft({:?})", self.inner.name())
    }
}
