//! Conversions between Python objects and the library's types: the sample's channels by name,
//! and JSON documents (`serde_json::Value`) as Python dicts/lists.

use aeroident_estimators::sample::MEASURED_FIELDS;
use aeroident_estimators::{AirDataSample, AircraftConstants};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::err;

/// A getter and a setter of one optional channel of [`AirDataSample`].
type OptField =
    (&'static str, fn(&AirDataSample) -> Option<f64>, fn(&mut AirDataSample, Option<f64>));

/// The required channels of a sample (SI): time, airspeed, angle of attack, dynamic pressure.
pub const REQUIRED: [&str; 4] = ["t_s", "vt_mps", "alpha_rad", "qbar_pa"];

macro_rules! opt_fields {
    ($($f:ident),* $(,)?) => {
        /// The optional channels of a sample, by their field names (SI units in the names).
        pub const OPTIONAL: &[OptField] = &[$(
            (stringify!($f), |s| s.$f, |s, v| s.$f = v),
        )*];
    };
}
aeroident_estimators::optional_sample_fields!(opt_fields);

// The channels are written out as identifiers (the getters and setters need them), so the
// build holds them to the sample's own list: `t_s`, then `REQUIRED` and `OPTIONAL` are
// `MEASURED_FIELDS` in its order, or this crate does not compile.
const _: () = assert!(
    channels_are_the_samples(),
    "REQUIRED and OPTIONAL must be t_s and aeroident_estimators::sample::MEASURED_FIELDS, in order"
);

/// Whether `REQUIRED` (after `t_s`) followed by `OPTIONAL` is [`MEASURED_FIELDS`], name for
/// name.
const fn channels_are_the_samples() -> bool {
    let r = REQUIRED.len();
    if r + OPTIONAL.len() != 1 + MEASURED_FIELDS.len() || !same(REQUIRED[0], "t_s") {
        return false;
    }
    let mut i = 1;
    while i < r {
        if !same(REQUIRED[i], MEASURED_FIELDS[i - 1]) {
            return false;
        }
        i += 1;
    }
    let mut k = 0;
    while k < OPTIONAL.len() {
        if !same(OPTIONAL[k].0, MEASURED_FIELDS[r - 1 + k]) {
            return false;
        }
        k += 1;
    }
    true
}

/// `a == b`, usable at compile time.
const fn same(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// A getter and a setter of one constant of [`AircraftConstants`] (`None` = absent).
type ConstField =
    (&'static str, fn(&AircraftConstants) -> Option<f64>, fn(&mut AircraftConstants, Option<f64>));

/// The aircraft constants by field name; `mass_kg` and `S_m2` are required, the two thrust
/// geometry values default to 0.
pub const CONSTANTS: &[ConstField] = &[
    ("mass_kg", |c| Some(c.mass_kg), |c, v| c.mass_kg = v.unwrap_or(f64::NAN)),
    ("S_m2", |c| Some(c.S_m2), |c, v| c.S_m2 = v.unwrap_or(f64::NAN)),
    ("cbar_m", |c| c.cbar_m, |c, v| c.cbar_m = v),
    ("b_m", |c| c.b_m, |c, v| c.b_m = v),
    ("Ixx_kgm2", |c| c.Ixx_kgm2, |c, v| c.Ixx_kgm2 = v),
    ("Iyy_kgm2", |c| c.Iyy_kgm2, |c, v| c.Iyy_kgm2 = v),
    ("Izz_kgm2", |c| c.Izz_kgm2, |c, v| c.Izz_kgm2 = v),
    ("Ixz_kgm2", |c| c.Ixz_kgm2, |c, v| c.Ixz_kgm2 = v),
    ("thrust_arm_m", |c| Some(c.thrust_arm_m), |c, v| c.thrust_arm_m = v.unwrap_or(0.0)),
    (
        "thrust_incidence_rad",
        |c| Some(c.thrust_incidence_rad),
        |c, v| c.thrust_incidence_rad = v.unwrap_or(0.0),
    ),
    ("v0_mps", |c| c.v0_mps, |c, v| c.v0_mps = v),
];

/// Every key a sample dict may hold: required channels, optional channels, constants.
pub fn all_keys() -> Vec<&'static str> {
    REQUIRED
        .iter()
        .copied()
        .chain(OPTIONAL.iter().map(|f| f.0))
        .chain(CONSTANTS.iter().map(|f| f.0))
        .collect()
}

/// `NaN` → absent (numpy's "no value"); anything else as is.
fn present(v: f64) -> Option<f64> {
    (!v.is_nan()).then_some(v)
}

/// A source of named values for one sample: `get(key)` is `None` when the key is absent.
pub trait Source {
    /// The value of `key`, `NaN` or missing = absent.
    fn get(&self, key: &str) -> PyResult<Option<f64>>;
}

/// Builds one sample from `src`, taking the constants it lacks from `constants`.
///
/// # Errors
/// A missing required channel or constant (`mass_kg`, `S_m2`), named; a constant out of its
/// physical range ([`check_constants`]).
pub fn sample_from(
    src: &impl Source,
    constants: &AircraftConstants,
    what: &dyn Fn() -> String,
) -> PyResult<AirDataSample> {
    let req = |k: &str| -> PyResult<f64> {
        src.get(k)?.ok_or_else(|| err(format!("{}: required channel `{k}` is missing", what())))
    };
    let mut s = AirDataSample {
        t_s: req("t_s")?,
        vt_mps: req("vt_mps")?,
        alpha_rad: req("alpha_rad")?,
        qbar_pa: req("qbar_pa")?,
        constants: *constants,
        ..AirDataSample::default()
    };
    for (k, _, set) in OPTIONAL {
        set(&mut s, src.get(k)?);
    }
    // The sample's own constants win over the estimator's (`constants`, already copied).
    for (k, _, set) in CONSTANTS {
        if let Some(v) = src.get(k)? {
            set(&mut s.constants, Some(v));
        }
    }
    for k in ["mass_kg", "S_m2"] {
        let v = CONSTANTS.iter().find(|f| f.0 == k).and_then(|f| (f.1)(&s.constants));
        if !v.is_some_and(f64::is_finite) {
            return Err(err(format!(
                "{}: constant `{k}` is missing (give it in the sample or in constants=)",
                what()
            )));
        }
    }
    check_constants(&s.constants).map_err(|e| err(format!("{}: {e}", what())))?;
    Ok(s)
}

/// Checks the constants present in `c` (absent: `NaN` mass or area, `None` others) against the
/// library's limits, so an impossible constant is refused where it enters instead of making
/// every sample's update fail: the estimators' finiteness and plausibility checks
/// ([`AirDataSample::first_non_finite`], [`AirDataSample::first_implausible`]: mass, area,
/// lengths and inertias positive and within [`aeroident_estimators::sample::PLAUSIBILITY`]),
/// and the three they do not cover: `v0_mps` positive, `thrust_arm_m` within the length limit,
/// `thrust_incidence_rad` within the angle limit.
///
/// # Errors
/// The first constant out of range, named, with its value and the limit.
pub fn check_constants(c: &AircraftConstants) -> Result<(), String> {
    let limits = &aeroident_estimators::sample::PLAUSIBILITY;
    // A probe sample with plausible channels: only the constants can be out of range. An absent
    // mass or area (taken per sample) is probed with 1.
    let present = |v: f64| if v.is_nan() { 1.0 } else { v };
    let probe = AirDataSample {
        vt_mps: 1.0,
        qbar_pa: limits.qbar_min_pa,
        constants: AircraftConstants { mass_kg: present(c.mass_kg), S_m2: present(c.S_m2), ..*c },
        ..AirDataSample::default()
    };
    if let Some((field, value)) = probe.first_non_finite() {
        return Err(format!("constant `{field}` = {value} is not a finite number"));
    }
    if let Some((field, value, limit)) = probe.first_implausible() {
        let why = if value >= limit {
            format!("above the limit {limit:e}")
        } else if limit <= f64::MIN_POSITIVE {
            "it must be positive".to_string()
        } else {
            format!("below the limit {limit:e}")
        };
        return Err(format!("constant `{field}` = {value}: {why}"));
    }
    let extra = [
        ("v0_mps", c.v0_mps, f64::MIN_POSITIVE, limits.vt_mps),
        ("thrust_arm_m", Some(c.thrust_arm_m), -limits.length_m, limits.length_m),
        ("thrust_incidence_rad", Some(c.thrust_incidence_rad), -limits.angle_rad, limits.angle_rad),
    ];
    for (field, v, lo, hi) in extra {
        if let Some(v) = v.filter(|v| !(*v >= lo && *v <= hi)) {
            let why = if lo > 0.0 { "positive and at most " } else { "within ±" };
            return Err(format!("constant `{field}` = {v}: it must be {why}{hi:e}"));
        }
    }
    Ok(())
}

/// A Python dict of floats as a [`Source`].
pub struct DictSource<'a, 'py>(pub &'a Bound<'py, PyDict>);

impl Source for DictSource<'_, '_> {
    fn get(&self, key: &str) -> PyResult<Option<f64>> {
        match self.0.get_item(key)? {
            None => Ok(None),
            Some(v) if v.is_none() => Ok(None),
            Some(v) => Ok(present(v.extract::<f64>().map_err(|_| {
                err(format!("sample key `{key}`: expected a number, got {}", describe(&v)))
            })?)),
        }
    }
}

/// Constants from a Python dict (`None` → all absent; mass and area then come per sample).
///
/// # Errors
/// An unknown key (listing the known ones), a non-number, or a constant out of its physical
/// range ([`check_constants`]).
pub fn constants_from(d: Option<&Bound<'_, PyDict>>) -> PyResult<AircraftConstants> {
    let mut c = AircraftConstants { mass_kg: f64::NAN, S_m2: f64::NAN, ..Default::default() };
    let Some(d) = d else { return Ok(c) };
    for (k, v) in d.iter() {
        let k: String = k.extract()?;
        let Some(f) = CONSTANTS.iter().find(|f| f.0 == k) else {
            let known: Vec<&str> = CONSTANTS.iter().map(|f| f.0).collect();
            return Err(err(format!("constants: unknown key `{k}` (known: {})", known.join(", "))));
        };
        let v: Option<f64> = if v.is_none() {
            None
        } else {
            present(v.extract().map_err(|_| {
                err(format!("constants: `{k}` must be a number or None, got {}", describe(&v)))
            })?)
        };
        (f.2)(&mut c, v);
    }
    check_constants(&c).map_err(|e| err(format!("constants: {e}")))?;
    Ok(c)
}

/// Rows of equal length as a 2-D array (`rows.len() × rows[0].len()`; `0 × 0` for none).
pub fn matrix(rows: &[Vec<f64>]) -> numpy::ndarray::Array2<f64> {
    let cols = rows.first().map_or(0, Vec::len);
    numpy::ndarray::Array2::from_shape_fn((rows.len(), cols), |(i, j)| rows[i][j])
}

/// A Python object's `repr` for an error message.
fn describe(v: &Bound<'_, PyAny>) -> String {
    v.repr().map_or_else(|_| "?".into(), |r| r.to_string())
}

/// A JSON document as Python objects (numbers stay `f64`/`int` exactly; no text round trip).
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value as V;
    Ok(match v {
        V::Null => py.None().into_bound(py),
        V::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        V::Number(n) => match (n.as_u64(), n.as_i64()) {
            (Some(u), _) => u.into_pyobject(py)?.into_any(),
            (None, Some(i)) => i.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        V::String(s) => s.into_pyobject(py)?.into_any(),
        V::Array(a) => {
            let l = PyList::empty(py);
            for x in a {
                l.append(json_to_py(py, x)?)?;
            }
            l.into_any()
        }
        V::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// Python objects (dicts, lists, str, int, float, bool, None) as a JSON document.
///
/// # Errors
/// Any other type.
pub fn py_to_json(o: &Bound<'_, PyAny>) -> PyResult<serde_json::Value> {
    use serde_json::Value as V;
    if o.is_none() {
        return Ok(V::Null);
    }
    if let Ok(b) = o.cast::<pyo3::types::PyBool>() {
        return Ok(V::Bool(b.is_true()));
    }
    if let Ok(i) = o.cast::<pyo3::types::PyInt>() {
        if let Ok(u) = i.extract::<u64>() {
            return Ok(V::from(u));
        }
        return Ok(V::from(i.extract::<i64>()?));
    }
    if let Ok(f) = o.cast::<pyo3::types::PyFloat>() {
        return Ok(serde_json::Number::from_f64(f.value()).map_or(V::Null, V::Number));
    }
    if let Ok(s) = o.cast::<pyo3::types::PyString>() {
        return Ok(V::String(s.to_str()?.to_owned()));
    }
    if let Ok(l) = o.cast::<PyList>() {
        return l.iter().map(|x| py_to_json(&x)).collect::<PyResult<Vec<_>>>().map(V::Array);
    }
    if let Ok(d) = o.cast::<PyDict>() {
        let mut m = serde_json::Map::new();
        for (k, v) in d.iter() {
            m.insert(k.extract::<String>()?, py_to_json(&v)?);
        }
        return Ok(V::Object(m));
    }
    Err(pyo3::exceptions::PyTypeError::new_err(format!(
        "cannot convert {} to JSON",
        o.get_type().name()?
    )))
}

/// Sample `s` as a dict of its channels and constants by field name (absent ones left out):
/// the form [`sample_from`] reads back.
///
/// # Errors
/// A Python error while filling the dict.
pub fn sample_to_dict<'py>(py: Python<'py>, s: &AirDataSample) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in REQUIRED.iter().zip([s.t_s, s.vt_mps, s.alpha_rad, s.qbar_pa]) {
        d.set_item(k, v)?;
    }
    for (k, get, _) in OPTIONAL {
        if let Some(v) = get(s) {
            d.set_item(k, v)?;
        }
    }
    for (k, get, _) in CONSTANTS {
        if let Some(v) = get(&s.constants).filter(|v| v.is_finite()) {
            d.set_item(k, v)?;
        }
    }
    Ok(d)
}
