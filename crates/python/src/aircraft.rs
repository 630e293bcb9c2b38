//! `aeroident.Aircraft`: the F-16 or a model-file aircraft as an object a user closes their own
//! loop around (trim, derivatives, one step, linearize, the estimator's sample). The work is the
//! library's ([`aeroident_pipelines::airframe::AnyAircraft`]); this module converts: states
//! in SI at the boundary (the F-16 computes in ft, [`crate::units`]), vectors as numpy arrays.

use aeroident_models::aircraft::N_CONTROLS;
use aeroident_pipelines::airframe::{AnyAircraft, Trim};
use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, IntoPyArray, PyArray1, PyArray2, PyArrayLike1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::Path;

use crate::convert::matrix;
use crate::units::StateUnits;
use crate::{err, to_py};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Aircraft>()
}

/// A vector argument: any array-like of numbers (a numpy array, a list, a tuple), as float64.
type Vector<'py> = PyArrayLike1<'py, f64, AllowTypeChange>;

/// See `aeroident.Aircraft`.
#[pyclass(module = "aeroident", name = "Aircraft", frozen)]
pub struct Aircraft {
    inner: AnyAircraft,
    /// The states' units: the library's (the F-16's ft, ft/s) and SI.
    units: StateUnits,
}

impl Aircraft {
    fn new(inner: AnyAircraft) -> Self {
        let units = StateUnits::of(&inner.state_names());
        Self { inner, units }
    }

    /// An SI state argument in the library's units.
    fn state_in(&self, state: &Vector<'_>) -> Vec<f64> {
        self.units.to_library(&state.as_array().to_vec())
    }
}

fn controls_of(c: &[f64]) -> PyResult<[f64; N_CONTROLS]> {
    <[f64; N_CONTROLS]>::try_from(c).map_err(|_| {
        err(format!(
            "controls: {} values given; 4 expected (engine, elevator_rad, aileron_rad, rudder_rad)",
            c.len()
        ))
    })
}

fn controls_in(c: &Vector<'_>) -> PyResult<[f64; N_CONTROLS]> {
    controls_of(&c.as_array().to_vec())
}

fn trim_dict<'py>(py: Python<'py>, units: &StateUnits, t: &Trim) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("state", units.to_si(&t.state).into_pyarray(py))?;
    d.set_item("state_textbook", t.state.clone().into_pyarray(py))?;
    d.set_item("controls", t.controls.to_vec().into_pyarray(py))?;
    d.set_item("state_names", units.si.clone())?;
    d.set_item("state_names_textbook", units.textbook.clone())?;
    d.set_item("control_names", aeroident_models::aircraft::CONTROL_NAMES.to_vec())?;
    d.set_item("max_abs_residual", t.max_abs_residual)?;
    Ok(d)
}

#[pymethods]
impl Aircraft {
    /// ``Aircraft.f16(xcg=0.35)``: the Stevens & Lewis F-16 with its centre of gravity at
    /// ``xcg`` (fraction of the mean aerodynamic chord). 13 states: ``state_names`` (SI: m/s,
    /// rad, rad/s, m, and the engine power in %); the library computes in the textbook's ft
    /// and ft/s, which ``to_textbook``/``from_textbook`` and the ``*_textbook`` keys give.
    ///
    /// Raises ``AeroidentError`` for an ``xcg`` outside the model's range.
    #[staticmethod]
    #[pyo3(signature = (xcg=0.35))]
    fn f16(xcg: f64) -> PyResult<Self> {
        Ok(Self::new(AnyAircraft::f16(xcg).map_err(to_py)?))
    }

    /// ``Aircraft.from_model(model, mapping, summary=None)``: an aircraft flying a model file's
    /// derivatives (``summary``: a ``summary.json`` whose estimates it flies, else the file's
    /// reference values) with the mass, geometry and inertias of a channel mapping. 12 states,
    /// SI (``state_names``).
    ///
    /// Raises ``AeroidentError`` naming the file and the missing value (a coefficient without a
    /// reference value, a mapping without a constant).
    #[staticmethod]
    #[pyo3(signature = (model, mapping, summary=None))]
    fn from_model(model: &str, mapping: &str, summary: Option<&str>) -> PyResult<Self> {
        let m = aeroident_pipelines::airframe::load(
            Path::new(model),
            summary.map(Path::new),
            Path::new(mapping),
        )
        .map_err(to_py)?;
        Ok(Self::new(AnyAircraft::ModelFile(Box::new(m))))
    }

    /// ``with_damage(increments, about, onset_s=None)``: the same F-16 with coefficient
    /// increments (``{"Cm_alpha": -0.04, "Cm_de": 0.2}``: per rad, or per unit
    /// non-dimensional rate) about the trim ``about`` (a ``trim()`` dict: its ``state``, SI, and
    /// ``controls``), from ``onset_s`` (s; ``None``: from the start) on.
    ///
    /// Raises ``AeroidentError`` naming an unknown coefficient or a missing key of ``about``.
    #[pyo3(signature = (increments, about, onset_s=None))]
    fn with_damage(
        &self,
        increments: std::collections::BTreeMap<String, f64>,
        about: &Bound<'_, PyDict>,
        onset_s: Option<f64>,
    ) -> PyResult<Self> {
        let get = |k: &str| -> PyResult<Vec<f64>> {
            let v = about.get_item(k)?.ok_or_else(|| err(format!("about: key `{k}` missing")))?;
            let a: Vector<'_> = v.extract().map_err(|_| err(format!("about[`{k}`]: a vector")))?;
            Ok(a.as_array().to_vec())
        };
        let state = self.units.to_library(&get("state")?);
        let controls = controls_of(&get("controls")?)?;
        let values: Vec<(String, f64)> = increments.into_iter().collect();
        let inner = self.inner.clone().with_increments(&values, &state, &controls, onset_s);
        Ok(Self::new(inner.map_err(to_py)?))
    }

    /// A short name (``"f16"``, or the model file's).
    #[getter]
    fn name(&self) -> String {
        self.inner.name()
    }

    /// The states' names with their SI units, in state order (list of ``n`` str).
    #[getter]
    fn state_names(&self) -> Vec<String> {
        self.units.si.clone()
    }

    /// The states' names in the library's units (the F-16's textbook ft, ft/s; SI for a model
    /// file): the order and units of ``to_textbook``'s result.
    #[getter]
    fn state_names_textbook(&self) -> Vec<String> {
        self.units.textbook.clone()
    }

    /// The controls' names (4): engine command, ``elevator_rad``, ``aileron_rad``,
    /// ``rudder_rad`` (Stevens & Lewis signs: a positive deflection gives a negative moment).
    #[getter]
    fn control_names(&self) -> Vec<&'static str> {
        self.inner.control_names().0.to_vec()
    }

    /// What the engine command (control 0) is: the F-16's throttle 0–1, or a model file's.
    #[getter]
    fn engine_command(&self) -> &'static str {
        self.inner.control_names().1
    }

    /// Metres per length unit of the textbook state (0.3048 for the F-16's ft, 1 for a model
    /// file); the SI state (``state_names``) is always in metres.
    #[getter]
    fn length_unit_m(&self) -> f64 {
        self.inner.length_unit_m()
    }

    /// ``to_textbook(state)``: an SI state (array-like, ``(n,)``) in the library's units
    /// (``state_names_textbook``): ``(n,)`` float64.
    fn to_textbook<'py>(&self, py: Python<'py>, state: Vector<'py>) -> Bound<'py, PyArray1<f64>> {
        self.state_in(&state).into_pyarray(py)
    }

    /// ``from_textbook(state)``: a state in the library's units (``state_names_textbook``,
    /// array-like ``(n,)``) in SI (``state_names``): ``(n,)`` float64.
    #[pyo3(name = "from_textbook")]
    fn textbook_to_si<'py>(
        &self,
        py: Python<'py>,
        state: Vector<'py>,
    ) -> Bound<'py, PyArray1<f64>> {
        self.units.to_si(&state.as_array().to_vec()).into_pyarray(py)
    }

    /// ``trim(vt_mps, alt_m)``: wings-level, level trim at true airspeed ``vt_mps`` (m/s) and
    /// altitude ``alt_m`` (m). Returns a dict: ``state`` ``(n,)`` float64 SI, ``controls``
    /// ``(4,)`` float64 (engine command, rad), ``state_textbook`` ``(n,)`` (library units),
    /// ``state_names``, ``state_names_textbook``, ``control_names`` and ``max_abs_residual``
    /// (the largest of ``[V̇, α̇, β̇, ṗ, q̇, ṙ]`` left, in the library's units per s: ft/s² for
    /// the F-16's V̇, rad/s and rad/s² for the rest).
    ///
    /// Raises ``AeroidentError`` when no trim is found (the condition is named).
    fn trim<'py>(&self, py: Python<'py>, vt_mps: f64, alt_m: f64) -> PyResult<Bound<'py, PyDict>> {
        let t = self.inner.trim_level(vt_mps, alt_m).map_err(to_py)?;
        trim_dict(py, &self.units, &t)
    }

    /// ``derivatives(state, controls, t_s=0.0)``: the state's time derivative ``(n,)``
    /// float64, SI per second, at ``state`` (array-like ``(n,)``, SI), ``controls``
    /// (array-like ``(4,)``) and time ``t_s`` (s; matters only after a damage onset).
    ///
    /// Raises ``AeroidentError`` naming a state or controls of the wrong length; ``TypeError``
    /// for an argument that is not a 1-D array of numbers.
    #[pyo3(signature = (state, controls, t_s=0.0))]
    fn derivatives<'py>(
        &self,
        py: Python<'py>,
        state: Vector<'py>,
        controls: Vector<'py>,
        t_s: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (x, c) = (self.state_in(&state), controls_in(&controls)?);
        let xd = self.inner.derivatives(t_s, &x, &c).map_err(to_py)?;
        Ok(self.units.to_si(&xd).into_pyarray(py))
    }

    /// ``step(state, controls, dt_s, t_s=0.0)``: the state ``dt_s`` seconds later (one RK4
    /// step, controls held) from ``state`` (array-like ``(n,)``, SI) at time ``t_s`` (s):
    /// ``(n,)`` float64, SI.
    ///
    /// Raises ``AeroidentError`` naming a state or controls of the wrong length or a ``dt_s``
    /// that is not positive and finite.
    #[pyo3(signature = (state, controls, dt_s, t_s=0.0))]
    fn step<'py>(
        &self,
        py: Python<'py>,
        state: Vector<'py>,
        controls: Vector<'py>,
        dt_s: f64,
        t_s: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (x, c) = (self.state_in(&state), controls_in(&controls)?);
        let x = self.inner.step(t_s, &x, &c, dt_s).map_err(to_py)?;
        Ok(self.units.to_si(&x).into_pyarray(py))
    }

    /// ``linearize(vt_mps, alt_m)``: the linear model ẋ = A x + B u about the level trim at
    /// ``vt_mps`` (m/s), ``alt_m`` (m). Returns a dict: ``a`` ``(n, n)``, ``b`` ``(n, 4)``,
    /// ``c`` ``(n, n)`` (identity), ``d`` ``(n, 4)`` float64 in SI (``states``);
    /// ``a_textbook``, ``b_textbook`` in the library's units (``states_textbook``); ``inputs``;
    /// ``eigenvalues`` ``(n, 2)`` float64 (real, imaginary; 1/s); ``modes`` (dicts: ``name``,
    /// ``eigenvalue``, ``wn_radps``, ``zeta``); ``trim`` (as :meth:`trim`). A model-file
    /// aircraft whose mapping declares surface actuators has one more state per actuator
    /// (``elevator_rad`` …, ẋ = (u − x)/τ, after the rigid body's) and their commands as inputs
    /// (``elevator_cmd_rad`` …); ``actuators`` lists them (dicts: ``surface``, ``state``,
    /// ``input``, ``tau_s``, ``trim_rad``), empty otherwise. Rate and position limits are not
    /// in a linear model.
    ///
    /// Raises ``AeroidentError`` when no trim is found.
    fn linearize<'py>(
        &self,
        py: Python<'py>,
        vt_mps: f64,
        alt_m: f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let l = self.inner.linearize_level_actuated(vt_mps, alt_m).map_err(to_py)?;
        let n = l.a.len();
        let units = StateUnits::of(&l.states);
        let array = |m: &[Vec<f64>]| -> Bound<'py, PyArray2<f64>> { matrix(m).into_pyarray(py) };
        let d = PyDict::new(py);
        d.set_item("a", array(&units.a_to_si(&l.a)))?;
        d.set_item("b", array(&units.b_to_si(&l.b)))?;
        d.set_item("c", Array2::<f64>::eye(n).into_pyarray(py))?;
        d.set_item("d", Array2::<f64>::zeros((n, N_CONTROLS)).into_pyarray(py))?;
        d.set_item("a_textbook", array(&l.a))?;
        d.set_item("b_textbook", array(&l.b))?;
        d.set_item("states", units.si.clone())?;
        d.set_item("states_textbook", units.textbook.clone())?;
        d.set_item("inputs", l.inputs.clone())?;
        d.set_item("actuators", actuator_list(py, &l.actuators)?)?;
        let ev: Vec<Vec<f64>> = l.eigenvalues.iter().map(|&(re, im)| vec![re, im]).collect();
        d.set_item("eigenvalues", array(&ev))?;
        d.set_item("modes", crate::f16::modes_list(py, &l.modes)?)?;
        d.set_item("trim", trim_dict(py, &self.units, &l.trim)?)?;
        Ok(d)
    }

    /// ``sample(state, controls, t_s=0.0, v0_mps=None)``: the exact (noise-free) air-data
    /// sample at ``state`` (array-like ``(n,)``, SI), ``controls`` (``(4,)``): the dict of SI
    /// channels and constants an ``Estimator``'s ``update`` takes (keys of ``sample_keys()``).
    /// ``v0_mps``: the reference airspeed of the ``V/V0`` term, m/s (default: the state's).
    ///
    /// Raises ``AeroidentError`` naming a state or controls of the wrong length.
    #[pyo3(signature = (state, controls, t_s=0.0, v0_mps=None))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        state: Vector<'py>,
        controls: Vector<'py>,
        t_s: f64,
        v0_mps: Option<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (x, c) = (self.state_in(&state), controls_in(&controls)?);
        let v0 = v0_mps.unwrap_or_else(|| state.as_array().first().copied().unwrap_or(f64::NAN));
        let s = self.inner.sample(t_s, &x, &c, v0).map_err(to_py)?;
        crate::convert::sample_to_dict(py, &s)
    }

    fn __repr__(&self) -> String {
        format!("Aircraft({:?})", self.inner.name())
    }
}

/// The actuator states of a linear model as a list of dicts (``Aircraft.linearize``).
fn actuator_list<'py>(
    py: Python<'py>,
    actuators: &[aeroident_pipelines::airframe::ActuatorState],
) -> PyResult<Bound<'py, pyo3::types::PyList>> {
    let list = pyo3::types::PyList::empty(py);
    for a in actuators {
        let d = PyDict::new(py);
        d.set_item("surface", a.surface)?;
        d.set_item("state", a.state)?;
        d.set_item("input", a.input)?;
        d.set_item("tau_s", a.actuator.tau_s)?;
        d.set_item("trim_rad", a.trim_rad)?;
        list.append(d)?;
    }
    Ok(list)
}
