"""Type stubs of the aeroident Python package (see the module docstring for the API)."""

import os
from typing import Any, Literal, Mapping, Optional, Sequence, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str
MAX_RUNS: int
"""Most runs of one Monte Carlo campaign (every run's results are kept for the statistics)."""
MAX_BOOTSTRAP_REFITS: int
"""Most replicas of a fit's parametric bootstrap (each is a whole refit of the record)."""
PathLike = Union[str, os.PathLike[str]]
EstimatorName = Literal["rls", "rls-iv", "ftr", "ekf", "smpe", "smpe-corrected", "smpe-finite-time", "gradient"]
Constants = Mapping[str, Optional[float]]
FloatArray = npt.NDArray[np.float64]
"""A float64 numpy array; each docstring gives its shape and units. NaN: no value (``reasons``)."""

class AeroidentError(Exception): ...

class EstimatesDict(TypedDict):
    names: list[str]
    estimate: FloatArray
    """(n,) float64; NaN: not identified (``reasons`` says why)."""
    std_error: FloatArray
    """(n,) float64; NaN: no standard error (``reasons`` says why)."""
    reasons: dict[str, str]
    estimator_status: Literal["initialising", "running", "diverged"]
    samples: int

class ReplayResult(TypedDict, total=False):
    names: list[str]
    t_s: npt.NDArray[np.float64]
    estimates: npt.NDArray[np.float64]
    std_error: npt.NDArray[np.float64]
    model: str
    summary: dict[str, Any]
    samples_refused: int
    events: dict[str, Any]
    notes: list[str]
    selected_model: Optional[str]
    reasons: dict[str, str]

class AircraftTrim(TypedDict):
    state: FloatArray
    """(n,) float64, SI (``state_names``)."""
    state_textbook: FloatArray
    """(n,) float64, the library's units (``state_names_textbook``: the F-16's ft, ft/s)."""
    controls: FloatArray
    """(4,) float64: engine command, elevator_rad, aileron_rad, rudder_rad."""
    state_names: list[str]
    state_names_textbook: list[str]
    control_names: list[str]
    max_abs_residual: float

class Aircraft:
    """The F-16 (13 states) or a model-file aircraft (12 states) to close a loop around; states
    in SI (``state_names``), the F-16's textbook ft and ft/s only through ``to_textbook`` and the
    ``*_textbook`` keys.

    Controls: engine command, elevator_rad, aileron_rad, rudder_rad (SLJ signs)."""
    @staticmethod
    def f16(xcg: float = 0.35) -> Aircraft: ...
    @staticmethod
    def from_model(model: str, mapping: str, summary: Optional[str] = None) -> Aircraft: ...
    def with_damage(self, increments: Mapping[str, float], about: Mapping[str, Any], onset_s: Optional[float] = None) -> Aircraft: ...
    @property
    def name(self) -> str: ...
    @property
    def state_names(self) -> list[str]: ...
    @property
    def state_names_textbook(self) -> list[str]: ...
    @property
    def control_names(self) -> list[str]: ...
    @property
    def engine_command(self) -> str: ...
    @property
    def length_unit_m(self) -> float: ...
    def to_textbook(self, state: npt.ArrayLike) -> FloatArray: ...
    def from_textbook(self, state: npt.ArrayLike) -> FloatArray: ...
    def trim(self, vt_mps: float, alt_m: float) -> AircraftTrim: ...
    def derivatives(self, state: npt.ArrayLike, controls: npt.ArrayLike, t_s: float = 0.0) -> FloatArray: ...
    def step(self, state: npt.ArrayLike, controls: npt.ArrayLike, dt_s: float, t_s: float = 0.0) -> FloatArray: ...
    def linearize(self, vt_mps: float, alt_m: float) -> dict[str, Any]: ...
    def sample(self, state: npt.ArrayLike, controls: npt.ArrayLike, t_s: float = 0.0, v0_mps: Optional[float] = None) -> dict[str, float]: ...

class EstimatorBase:
    def __new__(
        cls,
        kind: str,
        model: str = "longitudinal",
        constants: Optional[Constants] = None,
        forgetting: Optional[float] = None,
        sample_interval_s: Optional[float] = None,
        parameter_walk_per_sqrt_s: Optional[float] = None,
        ftr_grid_hz: Optional[tuple[float, float, float]] = None,
        sliding_gain_per_s: Optional[float] = None,
        reaching_rate_per_s: Optional[float] = None,
        **options: Any,
    ) -> EstimatorBase: ...
    @property
    def method(self) -> str: ...
    @property
    def model(self) -> str: ...
    @property
    def names(self) -> list[str]: ...
    @property
    def samples(self) -> int: ...
    def update(self, sample: Mapping[str, Optional[float]]) -> None: ...
    def estimates(self) -> EstimatesDict: ...
    def covariance(self, i: int, j: int) -> Optional[float]: ...
    def covariance_matrix(self) -> FloatArray: ...
    def nis(self) -> Optional[float]: ...
    def events(self) -> dict[str, Any]: ...
    def new_manoeuvre(self) -> None: ...

class Estimator(EstimatorBase): ...

class Rls(Estimator):
    def __new__(cls, model: PathLike = "longitudinal", constants: Optional[Constants] = None, *, forgetting: Optional[float] = None, sample_interval_s: Optional[float] = None) -> Rls: ...

class RlsIv(Estimator):
    def __new__(cls, model: PathLike = "longitudinal", constants: Optional[Constants] = None, *, forgetting: Optional[float] = None, sample_interval_s: Optional[float] = None) -> RlsIv: ...

class Ftr(Estimator):
    def __new__(cls, model: PathLike = "longitudinal", constants: Optional[Constants] = None, *, forgetting: Optional[float] = None, sample_interval_s: Optional[float] = None, ftr_grid_hz: Optional[tuple[float, float, float]] = None) -> Ftr: ...

class Ekf(Estimator):
    def __new__(cls, model: PathLike = "longitudinal", constants: Optional[Constants] = None, *, sample_interval_s: Optional[float] = None, parameter_walk_per_sqrt_s: Optional[float] = None) -> Ekf: ...

class Smpe(Estimator):
    def __new__(cls, model: PathLike = "longitudinal", constants: Optional[Constants] = None, *, sample_interval_s: Optional[float] = None) -> Smpe: ...

class SmpeCorrected(Estimator):
    def __new__(cls, model: PathLike = "longitudinal", constants: Optional[Constants] = None, *, sample_interval_s: Optional[float] = None) -> SmpeCorrected: ...

class SmpeFiniteTime(Estimator):
    def __new__(cls, model: PathLike = "longitudinal", constants: Optional[Constants] = None, *, forgetting: Optional[float] = None, sample_interval_s: Optional[float] = None, sliding_gain_per_s: Optional[float] = None, reaching_rate_per_s: Optional[float] = None) -> SmpeFiniteTime: ...

class Gradient(Estimator):
    def __new__(cls, model: PathLike = "longitudinal", constants: Optional[Constants] = None, *, sample_interval_s: Optional[float] = None) -> Gradient: ...

def sample_keys() -> list[str]: ...
def read(path: PathLike, mapping: PathLike) -> dict[str, Any]: ...
def replay(
    data: Union[PathLike, Mapping[str, npt.ArrayLike]],
    mapping: Optional[PathLike] = None,
    estimator: EstimatorName = "rls",
    model: Optional[PathLike] = None,
    *,
    forgetting: Optional[float] = None,
    derivatives: Literal["auto", "differentiate"] = "auto",
    diff_window: int = 5,
    constants: Optional[Constants] = None,
    sample_interval_s: Optional[float] = None,
    compat: Optional[PathLike] = None,
    windows: Optional[Sequence[tuple[float, float]]] = None,
    cross_check: Optional[bool] = None,
    select: Literal["swr", "mof"] = "swr",
    candidates: Optional[Sequence[str]] = None,
    knots_deg: Optional[Sequence[float]] = None,
    **options: Any,
) -> ReplayResult: ...
class FitTrace(TypedDict):
    t_s: npt.NDArray[np.float64]
    measured: npt.NDArray[np.float64]
    simulated: npt.NDArray[np.float64]

class FitResult(TypedDict):
    names: list[str]
    estimate: npt.NDArray[np.float64]
    std_error: npt.NDArray[np.float64]
    crb_std_error: npt.NDArray[np.float64]
    timing_std_error: npt.NDArray[np.float64]
    unmodelled_std_error: npt.NDArray[np.float64]
    reference: npt.NDArray[np.float64]
    status: list[str]
    flags: list[list[str]]
    correlation: npt.NDArray[np.float64]
    outputs: list[str]
    residuals: npt.NDArray[np.float64]
    traces: dict[str, FitTrace]
    model: str
    notes: list[str]
    summary: dict[str, Any]
    selected_model: Optional[str]
    reasons: dict[str, str]

def fit(
    data: PathLike,
    mapping: PathLike,
    estimator: Literal["oe", "fem", "fdoe"] = "oe",
    model: Optional[PathLike] = None,
    *,
    initial_states: Literal["first-sample", "estimate"] = "first-sample",
    validate_on: Optional[PathLike] = None,
    bootstrap: Optional[int] = None,
    max_iterations: Optional[int] = None,
    process_noise: Optional[str] = None,
    compat: Optional[PathLike] = None,
    windows: Optional[Sequence[tuple[float, float]]] = None,
    also: Optional[Sequence[PathLike]] = None,
    select: Literal["swr", "mof"] = "swr",
    candidates: Optional[Sequence[str]] = None,
    band_hz: Optional[tuple[float, float]] = None,
    knots_deg: Optional[Sequence[float]] = None,
    allow_duplicate_records: bool = False,
    cross_check: Optional[bool] = None,
    **options: Any,
) -> FitResult: ...
def freqresp(
    data: PathLike,
    map: PathLike,
    input: Union[str, Sequence[str]],
    output: Union[str, Sequence[str]],
    *,
    windows: Optional[Sequence[tuple[float, float]]] = None,
    windows_s: Optional[Sequence[float]] = None,
    overlap: float = 0.8,
    f_min_hz: Optional[float] = None,
    f_max_hz: Optional[float] = None,
    points_per_decade: int = 40,
    fit: Optional[Union[str, Sequence[str]]] = None,
    min_coherence: float = 0.6,
) -> dict[str, Any]: ...
class F16Trim(TypedDict):
    state: FloatArray
    """(13,) float64, SI: vt_mps, rad, rad/s, north_m, east_m, alt_m, pow_pct."""
    state_textbook: FloatArray
    """(13,) float64, the textbook's units: vt_fps, …, north_ft, east_ft, alt_ft, pow_pct."""
    state_names: list[str]
    state_names_textbook: list[str]
    controls: FloatArray
    """(4,) float64: throttle 0–1, elevator_rad, aileron_rad, rudder_rad."""
    control_names: list[str]
    alpha_rad: float
    beta_rad: float
    theta_rad: float
    elevator_rad: float
    aileron_rad: float
    rudder_rad: float
    throttle: float
    elevator_deg: float
    aileron_deg: float
    rudder_deg: float
    alpha_deg: float
    beta_deg: float
    theta_deg: float
    cost: float
    out_of_range: list[str]

class F16Linear(TypedDict):
    a: FloatArray
    """(13, 13) float64, SI."""
    b: FloatArray
    """(13, 4) float64, SI."""
    a_textbook: FloatArray
    b_textbook: FloatArray
    eigenvalues: npt.NDArray[np.complex128]
    modes: list[dict[str, Any]]
    state_names: list[str]
    state_names_textbook: list[str]
    input_names: list[str]
    trim: F16Trim

def trim(
    vt_mps: Optional[float] = None,
    alt_m: Optional[float] = None,
    xcg: float = 0.35,
    gamma_rad: Optional[float] = None,
    turn_rate_rad_s: Optional[float] = None,
    pull_up_rad_s: Optional[float] = None,
    *,
    vt_fps: Optional[float] = None,
    alt_ft: Optional[float] = None,
    gamma_deg: Optional[float] = None,
    turn_rate_deg_s: Optional[float] = None,
    pull_up_deg_s: Optional[float] = None,
) -> F16Trim: ...
def linearize(
    vt_mps: Optional[float] = None,
    alt_m: Optional[float] = None,
    xcg: float = 0.35,
    gamma_rad: Optional[float] = None,
    turn_rate_rad_s: Optional[float] = None,
    pull_up_rad_s: Optional[float] = None,
    *,
    vt_fps: Optional[float] = None,
    alt_ft: Optional[float] = None,
    gamma_deg: Optional[float] = None,
    turn_rate_deg_s: Optional[float] = None,
    pull_up_deg_s: Optional[float] = None,
) -> F16Linear: ...
def simulate(scenario: PathLike, *, textbook: bool = False) -> dict[str, FloatArray]: ...
def montecarlo(
    scenario: Optional[PathLike] = None,
    runs: int = 100,
    backend: Literal["local", "ray"] = "local",
    seed: int = 1,
    *,
    chunk_size: Optional[int] = None,
    per_run: bool = False,
) -> dict[str, Any]: ...
