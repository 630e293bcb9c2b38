"""aeroident: real-time identification of aircraft aerodynamic derivatives, from Python.

The numbers come from the Rust library behind the ``aeroident`` command line (same code paths,
same results to the last bit, same error messages). Units are SI, angles in radians, times in
seconds, unless a name says otherwise (``alt_ft``, ``elevator_deg`` …). Vectors and matrices
(states, inputs, estimates, σ) are float64 numpy arrays whose shapes the docstrings give; a
value that does not exist (a parameter not identified, a σ the method does not give) is
``NaN``, and the result says why beside it (``reasons``). Array arguments take any array-like.

- :func:`read`: a record + channel mapping → dict of numpy arrays (one per channel).
- :class:`Estimator` and :class:`Rls`, :class:`RlsIv`, :class:`Ftr`, :class:`Ekf`,
  :class:`Smpe`, :class:`SmpeCorrected`, :class:`SmpeFiniteTime`, :class:`Gradient`: online estimators fed one sample
  dict at a time.
- :func:`replay`: a whole record (file + mapping, or arrays) through an estimator in Rust; the
  estimates as a (time × parameter) numpy matrix.
- :func:`fit`: the post-flight batch fit of a record by output error or the filter-error
  method (estimates, σ, correlation, residuals, model-vs-measured traces, validation).
- :func:`trim`, :func:`linearize`, :func:`simulate`: the F-16 model, in SI (its textbook's ft
  and ft/s only under ``*_textbook`` names and the keyword-only ``vt_fps``, ``alt_ft``).
- :class:`Aircraft`: the F-16 or a model-file aircraft to close your own loop around (trim,
  derivatives, one RK4 step, the linear model, the air-data sample an estimator takes, damage).
- :func:`montecarlo`: seeded closed-loop campaigns, locally (rayon) or on a Ray cluster.

Errors are raised as :class:`AeroidentError` with the message the CLI prints after ``error:``.
Long calls release the GIL, and Ctrl-C during one raises ``KeyboardInterrupt`` (a replay or a
Monte Carlo campaign stops at the next sample or chunk of runs; a fit, a trim or a simulation
when it returns). An :class:`Estimator` may be used from any thread: its calls are applied one
at a time.
"""

from __future__ import annotations

import os
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np

from . import _aeroident as _core
from ._aeroident import MAX_BOOTSTRAP_REFITS, MAX_RUNS, AeroidentError, __version__
from ._aeroident import Aircraft
from ._aeroident import EstimatorBase as _Estimator

PathLike = Union[str, "os.PathLike[str]"]

__all__ = [
    "AeroidentError",
    "Aircraft",
    "Estimator",
    "Rls",
    "RlsIv",
    "Ftr",
    "Ekf",
    "Smpe",
    "SmpeCorrected",
    "SmpeFiniteTime",
    "Gradient",
    "read",
    "replay",
    "fit",
    "freqresp",
    "sample_keys",
    "trim",
    "linearize",
    "simulate",
    "montecarlo",
    "MAX_RUNS",
    "MAX_BOOTSTRAP_REFITS",
    "__version__",
]


def sample_keys() -> list[str]:
    """The keys a sample dict (and :func:`read`'s result) may hold.

    Required channels ``t_s, vt_mps, alpha_rad, qbar_pa``; optional channels (``beta_rad,
    p_rad_s, q_rad_s, r_rad_s, pdot_rad_s2, …, ax_mps2, ay_mps2, az_mps2, de_rad, da_rad,
    dr_rad, thrust_n, …``); aircraft constants (``mass_kg, S_m2, cbar_m, b_m, Ixx_kgm2,
    Iyy_kgm2, Izz_kgm2, Ixz_kgm2, thrust_arm_m, thrust_incidence_rad, v0_mps``).
    """
    return list(_core.sample_keys())


def read(path: PathLike, mapping: PathLike) -> dict[str, Any]:
    """Reads a record with a channel mapping (TOML, see ``mappings/`` and docs/mapping.md), with
    the CLI's reader for the file's extension: CSV, ``.asc``, ``.mat``, ULog ``.ulg``,
    DataFlash ``.bin``.

    Returns a dict: one 1-D float64 array per key of :func:`sample_keys` (SI, at the CG, one
    entry per accepted sample; ``NaN`` where the record has no such channel), ``row`` (int: the
    record's line number of each sample), and the rows the reader set aside:
    ``rejected_rows`` (int array), ``rejected_reasons`` (list of str), ``gap_rows`` (int array:
    samples that follow a time gap), and ``notes`` (list of str: what the reading or the
    alignment of a multi-rate log left out, as the CLI prints them). Exactly the samples
    ``aeroident replay`` sees.

    Raises :class:`AeroidentError` (file, row and column named) on a bad mapping or record.
    """
    return _core.read(os.fspath(path), os.fspath(mapping))


class Estimator(_Estimator):
    """An online estimator over one model structure.

    ``Estimator(kind, model="longitudinal", constants=None, forgetting=None,
    sample_interval_s=None, parameter_walk_per_sqrt_s=None, ftr_grid_hz=None, sliding_gain_per_s=None,
    reaching_rate_per_s=None, **options)`` with ``kind`` one of ``rls, rls-iv,
    ftr, ekf, smpe, smpe-corrected, smpe-finite-time, gradient`` (the CLI's ``--estimator``) and ``model`` a preset
    (``longitudinal``, ``lateral``, ``six-axis``) or a model file (TOML, ``models/``).
    The estimator options (``forgetting`` … ``reaching_rate_per_s``) left ``None`` keep the
    estimator's defaults (no forgetting, no parameter walk); one the kind does not take (a
    forgetting factor for ``ekf``) raises :class:`AeroidentError` naming the kind and the options
    it takes, as the CLI and a scenario refuse it. ``**options``: any other option of the
    estimator by its scenario key (``instrument_delay=8`` for ``rls-iv``).
    ``constants``: the aircraft constants (keys as in :func:`sample_keys`) used for every sample
    that does not carry its own. ``ftr_grid_hz``: FTR's frequency grid ``(f_min, f_max, step)``
    in Hz (default Morelli's 0.1-1.5 Hz in 0.04 Hz); it must span the excitation. FTR's
    normal equations weight a sample by ``forgetting**2`` per step: ``forgetting=0.9975`` at
    100 Hz is a 2-s memory.

    - ``update(sample)``: one sample, a dict of SI channels (``None``/``NaN`` = absent). Raises
      :class:`AeroidentError` if the estimator refuses it (its state is then unchanged) or
      diverges.
    - ``estimates()``: dict with ``names`` (the ``n`` parameters), ``estimate`` (n,) float64
      (``NaN`` = not identified), ``std_error`` (n,) float64 (``NaN`` = none reported),
      ``reasons`` (``{name: why}`` for every parameter with a ``NaN``), ``estimator_status``
      (``initialising``, ``running``, ``diverged``) and ``samples``: the names of
      ``summary.json`` (docs/output-schema.md).
    - ``covariance_matrix()``: (n, n) float64 (``NaN`` where the method gives none);
      ``covariance(i, j)`` (``None`` where it gives none), ``nis()``, ``events()``,
      ``new_manoeuvre()``; properties ``names``, ``method``, ``model``, ``samples``.

    Raises :class:`AeroidentError` naming the option, the model or the constant that cannot be
    used (an unknown kind, an option the kind does not take, a constant out of range).

    Unlike :func:`replay` on a file, nothing is differentiated: give ``qdot_rad_s2`` etc. when
    the method needs them (see ``aeroident replay``'s derivative stage).
    """


def _subclass(kind: str, doc: str) -> type:
    def __new__(cls, model: PathLike = "longitudinal", constants: Optional[Mapping[str, float]] = None, **options: Any):  # noqa: N807
        return _Estimator.__new__(cls, kind, os.fspath(model), _plain(constants), **options)

    return type(kind.title().replace("-", ""), (Estimator,), {"__new__": __new__, "__doc__": doc, "__module__": __name__})


def _plain(constants: Optional[Mapping[str, float]]) -> Optional[dict[str, Optional[float]]]:
    return None if constants is None else {str(k): (None if v is None else float(v)) for k, v in constants.items()}


def _sequence(name: str, value: Any) -> Optional[list[Any]]:
    """``value`` as a list, refusing a lone string or path: iterating ``"57"`` would give the
    knots 5 and 7, ``"rec.csv"`` the records ``r``, ``e``, ``c`` …, without a word."""
    if value is None:
        return None
    if isinstance(value, (str, bytes, os.PathLike)):
        raise TypeError(f"{name} must be a list (e.g. {_list_hint(value)}), not a single {type(value).__name__}: {value!r}")
    try:
        return list(value)
    except TypeError:
        raise TypeError(f"{name} must be a list, got {type(value).__name__}: {value!r}") from None


def _list_hint(value: Any) -> str:
    """The list a lone string most likely meant: its parts when it holds separators (``'5,7'``
    and ``'0.1:1.5'`` are two numbers, where ``['5,7']`` would be refused again), else itself."""
    if isinstance(value, str):
        parts = [p.strip() for p in value.replace(":", ",").split(",") if p.strip()]
        if len(parts) > 1:
            try:
                return repr([float(p) for p in parts])
            except ValueError:
                return repr(parts)
    return f"[{value!r}]"


def _band(value: Any) -> Optional[tuple[float, float]]:
    """``band_hz`` as ``(f_min_hz, f_max_hz)``: exactly two numbers."""
    items = _sequence("band_hz", value)
    if items is None:
        return None
    if len(items) != 2:
        raise ValueError(f"band_hz must be (f_min_hz, f_max_hz), two numbers; got {len(items)}: {value!r}")
    return (float(items[0]), float(items[1]))


def _windows(value: Any) -> Optional[list[tuple[float, float]]]:
    items = _sequence("windows", value)
    if items is None:
        return None
    out = []
    for w in items:
        pair = _sequence("windows entry", w)
        if len(pair) != 2:
            raise ValueError(f"windows entries must be (start_s, end_s), two numbers; got {w!r}")
        out.append((float(pair[0]), float(pair[1])))
    return out


Rls = _subclass("rls", "Recursive least squares (equation error) on every modelled coefficient. ``Rls(model, constants, forgetting=1.0)``.")
RlsIv = _subclass("rls-iv", "Recursive instrumental variables: equation error whose estimates regressor noise does not pull towards zero; the state regressors' instruments are their values 5 samples earlier (in :func:`replay` of a file, the differentiator window). ``RlsIv(model, constants, forgetting=1.0)``.")
Ftr = _subclass("ftr", "Real-time Fourier-transform regression (Morelli 2000). ``Ftr(model, constants, forgetting=1.0, sample_interval_s=None, ftr_grid_hz=None)``.")
Ekf = _subclass("ekf", "Extended Kalman filter on states and parameters. ``Ekf(model, constants, sample_interval_s=None, parameter_walk_per_sqrt_s=0.0)``.")
Smpe = _subclass("smpe", "The thesis's sliding-mode parameter estimator. ``Smpe(model, constants)``.")
SmpeCorrected = _subclass("smpe-corrected", "The corrected sliding-mode parameter estimator. ``SmpeCorrected(model, constants)``.")
SmpeCorrected.__name__ = SmpeCorrected.__qualname__ = "SmpeCorrected"
SmpeFiniteTime = _subclass("smpe-finite-time", "The finite-time sliding-mode estimator on the forgotten information memory, with the memory's sigma (docs/smpe-finite-time.md). ``SmpeFiniteTime(model, constants, forgetting=1.0, sliding_gain_per_s=10.0, reaching_rate_per_s=10.0)``.")
SmpeFiniteTime.__name__ = SmpeFiniteTime.__qualname__ = "SmpeFiniteTime"
Gradient = _subclass("gradient", "The model-reference gradient estimator. ``Gradient(model, constants)``.")


def replay(
    data: Union[PathLike, Mapping[str, Any]],
    mapping: Optional[PathLike] = None,
    estimator: str = "rls",
    model: Optional[PathLike] = None,
    *,
    forgetting: Optional[float] = None,
    derivatives: str = "auto",
    diff_window: int = 5,
    constants: Optional[Mapping[str, float]] = None,
    sample_interval_s: Optional[float] = None,
    compat: Optional[PathLike] = None,
    windows: Optional[Sequence[tuple[float, float]]] = None,
    cross_check: Optional[bool] = None,
    select: str = "swr",
    candidates: Optional[Sequence[str]] = None,
    knots_deg: Optional[Sequence[float]] = None,
    **options: Any,
) -> dict[str, Any]:
    """Replays a whole record through an estimator, every sample in Rust (no Python loop).

    ``data`` is a record file (then ``mapping=`` is required and the pipeline is exactly
    ``aeroident replay DATA --map MAPPING --estimator … --model …``: reader, derivative stage,
    estimator) or a dict of arrays as :func:`read` returns (then the samples go straight to the
    estimator: nothing is differentiated; ``constants=`` fills constants the arrays lack).
    ``model=None``: the richest preset the first sample supports, as the CLI chooses.
    ``model="auto"`` (or ``"auto:longitudinal"``, ``"auto:lateral"``, ``"auto:six-axis"``; a
    record file): each coefficient's terms chosen from the record by equation error
    (``select="swr"`` stepwise regression or ``"mof"`` orthogonal functions; ``candidates``: the
    terms offered, e.g. ``["alpha", "q", "alphadot", "de"]``; ``knots_deg``: the α knots of the
    spline candidates ``alpha_k1…``, degrees, else the record's α quantiles), as ``--model auto
    --select … --candidates … --knots-deg …``: ``summary["structure_selection"]`` holds the selection path and
    ``selected_model`` the chosen model as model-file TOML (``None`` otherwise).
    ``compat``: a record file's ``compat.json`` (``aeroident compat``) whose corrections are
    applied to every sample first (``--compat FILE``), or ``"auto"``: checked on the record
    first (``--compat auto``). ``windows``: ``[(start_s, end_s), …]``
    record-time windows, each its own manoeuvre, the rest not used (``--window START:END``).
    ``cross_check`` (a record file): by default (``None``) the record's other methods but the
    filter-error method (rls, rls-iv, ekf, oe, fdoe) run after the feed with the same model
    and ``summary["cross_check"]`` judges each estimate beside theirs, a parameter they do
    not confirm flagged with the camps and the tested cause; ``True`` adds ``fem``
    (``--cross-check``); ``False`` runs none (``--no-cross-check``; the summary's warnings
    say so). Further keyword arguments are the
    estimator's own options by their scenario keys (``instrument_delay=8`` for ``rls-iv``,
    ``parameter_walk_per_sqrt_s=0.01`` for ``ekf``; ``--estimator-option KEY=VALUE``); one the
    estimator does not take raises :class:`AeroidentError` naming those it takes.

    Returns a dict:

    - ``names``: list of the ``n`` parameter names;
    - ``t_s``: (k,) sample times, s, one per sample whose estimates the CLI writes as a line of
      ``estimates.csv`` (samples the reader or estimator rejected have none);
    - ``estimates``: (k, n) float64; ``NaN`` where the parameter is not yet identified (the
      CLI's empty field);
    - ``std_error``: (k, n) float64 standard errors; ``NaN`` where none is reported;
    - ``reasons``: ``{name: why}`` for every parameter whose last estimate or σ is ``NaN``
      (for a file the summary's status and flags; ``NaN`` alone never says why);
    - ``model``: the model's name; for a file also ``summary`` (the CLI's ``summary.json`` as a
      dict) and ``notes`` (what the reader left out, as :func:`read`), for arrays
      ``samples_refused`` and ``events``.

    A record file is read by the CLI's reader for its extension (CSV, ``.asc``, ``.mat``,
    ULog, DataFlash). Raises :class:`AeroidentError` with the CLI's message on bad input (a
    constant out of its physical range, such as a mass ≤ 0, is named), when the estimator
    diverges, or when it accepts none of the arrays' samples. The batch methods (``oe``, ``fem``) have no per-sample estimates: use :func:`fit`.
    """
    if isinstance(data, (str, os.PathLike)):
        if mapping is None:
            raise AeroidentError("replay of a record file needs mapping= (the channel mapping TOML)")
        r = _core.replay_file(
            os.fspath(data),
            os.fspath(mapping),
            estimator,
            None if model is None else os.fspath(model),
            forgetting,
            derivatives,
            diff_window,
            None if compat is None else os.fspath(compat),
            _windows(windows),
            cross_check,
            select,
            _sequence("candidates", candidates),
            None if knots_deg is None else [float(k) for k in _sequence("knots_deg", knots_deg)],
            **options,
        )
        last = lambda a: a[-1] if len(a) else np.full(len(r["names"]), np.nan)  # noqa: E731
        r["reasons"] = _reasons(r["names"], last(r["estimates"]), last(r["std_error"]), r["summary"]["parameters"], estimator)
        return r
    # What only a record file has a use for would be ignored for arrays: refused instead.
    file_only = dict(mapping=mapping, compat=compat, windows=windows, cross_check=cross_check, candidates=candidates, knots_deg=knots_deg)
    given = [k for k, v in file_only.items() if v is not None]
    if given:
        raise AeroidentError(
            f"replay of arrays: {', '.join(given)} apply to a record file (read, corrected and windowed by the pipeline); the arrays go to the estimator as they are"
        )
    keys = set(_core.sample_keys())
    arrays = {k: np.ascontiguousarray(v, dtype=np.float64) for k, v in data.items() if k in keys}
    r = _core.replay_arrays(
        arrays, estimator, None if model is None else os.fspath(model), _plain(constants), forgetting, sample_interval_s, **options
    )
    r["reasons"] = _reasons(r["names"], r["estimates"][-1], r["std_error"][-1], None, estimator)
    return r


def _reasons(names: Sequence[str], estimate: np.ndarray, std_error: np.ndarray, parameters: Optional[Sequence[Mapping[str, Any]]], method: str) -> dict[str, str]:
    """Why each parameter with a ``NaN`` estimate or σ has one: the summary's verdict and flags
    where there is a summary (``parameters``, its per-parameter entries), else what the arrays
    tell (a replay of arrays has no verdict)."""
    judged = {str(p["name"]).rstrip("*"): p for p in parameters or []}
    out = {}
    for name, e, s in zip(names, estimate, std_error):
        if not (np.isnan(e) or np.isnan(s)):
            continue
        p = judged.get(name)
        if not np.isnan(e):
            out[name] = f"no standard error: `{method}` reports none for it"
        elif p is not None:
            out[name] = "; ".join([str(p["status"]), *p.get("flags", []), *p.get("notes", [])])
        else:
            out[name] = "not identified: the samples do not determine it"
    return out


def fit(
    data: PathLike,
    mapping: PathLike,
    estimator: str = "oe",
    model: Optional[PathLike] = None,
    *,
    initial_states: str = "first-sample",
    validate_on: Optional[PathLike] = None,
    bootstrap: Optional[int] = None,
    max_iterations: Optional[int] = None,
    process_noise: Optional[str] = None,
    compat: Optional[PathLike] = None,
    windows: Optional[Sequence[tuple[float, float]]] = None,
    also: Optional[Sequence[PathLike]] = None,
    select: str = "swr",
    candidates: Optional[Sequence[str]] = None,
    band_hz: Optional[tuple[float, float]] = None,
    knots_deg: Optional[Sequence[float]] = None,
    allow_duplicate_records: bool = False,
    cross_check: Optional[bool] = None,
    **options: Any,
) -> dict[str, Any]:
    """Fits a whole record by batch output error (``"oe"``), the filter-error method
    (``"fem"``: output error with process noise on the air-data states, for turbulent records)
    or frequency-domain output error (``"fdoe"``: the model linearised about each manoeuvre's
    mean condition, fitted to the record's Fourier transforms over ``band_hz``; docs/fdoe.md).

    Exactly ``aeroident replay DATA --map MAPPING --estimator oe|fem [--model M]
    [--initial-states S] [--validate-on V]``: the same reader (CSV, ``.asc``, ``.mat``, ULog,
    DataFlash by extension), the record split into manoeuvres at its time gaps, maximum-likelihood
    Gauss–Newton with exact sensitivities and the noise covariance estimated (Jategaonkar 2015
    ch. 4–5). Not real time: the whole record is read first. ``model=None``: the richest preset
    the record's channels can drive. ``initial_states``: ``"first-sample"`` (each manoeuvre starts
    at its first sample's measured states) or ``"estimate"`` (estimated with the parameters).
    ``validate_on``: a second record (same mapping) on which the fitted model is simulated.
    ``bootstrap=N`` (``oe``, 2 ≤ N ≤ :data:`MAX_BOOTSTRAP_REFITS`, each replica being a whole
    refit): the parametric bootstrap σ from N replicas of the record
    flown through the fitted model with the process and measurement noise a filter-error fit
    of the same record estimates, each refitted (``--bootstrap N``; docs/uncertainty.md,
    "Output error: the parametric bootstrap"); it becomes ``std_error`` and ``summary["bootstrap"]``
    says how it was made. Each ``summary["parameters"]`` entry then also carries
    ``bootstrap_bias``, the refits' mean less the estimate (not subtracted from ``estimate``).
    ``max_iterations``: most Gauss–Newton iterations (``--max-iterations``; default 50 for
    ``oe``, 250 for ``fem``). ``process_noise`` (``fem``): the states with process noise,
    comma-separated (``"V,alpha,theta,q"``; ``--process-noise``; default ``V,alpha,beta``).
    ``compat``: a ``compat.json`` (``aeroident compat``) whose corrections are applied to every
    sample before the fit (``--compat FILE``), or ``"auto"`` (``--compat auto``). ``windows``: ``[(start_s, end_s), …]``
    record-time windows, each its own manoeuvre, the rest not used (``--window START:END``).
    ``also``: further records of the same aircraft (same mapping), fitted together with
    ``data``, each file a manoeuvre of its own (``--and FILE``); a list, never a lone path. A
    record given twice (the same file, or the same content) is refused, as it would shrink
    every σ by √2, unless ``allow_duplicate_records=True`` (``--allow-duplicate-records``).
    ``compat="auto"`` checks the records' compatibility first, as ``--compat auto``. ``model="auto[:scope]"``,
    ``select``, ``candidates`` and ``knots_deg``: the structure chosen from the records first,
    as in :func:`replay` (``--model auto --select … --candidates … --knots-deg …``). ``band_hz`` (``fdoe`` only):
    the band fitted, ``(f_min_hz, f_max_hz)`` (``--band-hz F0:F1``; default 0.1–1.5 Hz).
    Further keyword arguments are the fit's other options by their keys (``robust=True`` for
    Huber's weights in ``oe``, ``gain_constraint=False`` for ``fem``;
    ``--estimator-option KEY=VALUE``), parsed by the same parser as the CLI's flags.
    ``cross_check``: by default (``None``) the record's other methods but the filter-error
    method (rls, rls-iv, ekf without ``also``; oe, fdoe) run with the fitted model and
    ``summary["cross_check"]`` judges each estimate beside theirs, one they do not confirm
    flagged; ``True`` adds ``fem`` (``--cross-check``); ``False`` runs none
    (``--no-cross-check``; the summary's warnings say so).

    A fit that does not meet both convergence criteria is returned all the same:
    ``summary["status"]`` is ``"converged"``, ``"converged_in_cost"`` (the cost stopped
    changing, the step did not become negligible: ``ml_oem2``'s criterion) or
    ``"not_converged"`` (the last iterate), and ``summary["status_reason"]`` says how it ended.

    Returns a dict:

    - ``names``: the ``n`` structure parameters (``Cm_alpha`` …);
    - ``estimate``: (n,) estimates; ``std_error``: (n,) the reported σ (the bootstrap's when
      asked for, else coloured-residual where formed, else Cramér–Rao: docs/uncertainty.md);
      ``crb_std_error``: (n,) the Cramér–Rao σ; ``timing_std_error``: (n,) the sample-timing
      σ inside ``std_error`` (NaN where the test was not made); ``unmodelled_std_error``: (n,)
      the unmodelled σ inside ``std_error`` (a share of ``|estimate|``, NaN for a constant
      term); ``reference``: (n,) the model file's
      published values (NaN without one); ``fdoe``: NaN where the summary has ``null``
      (parameters the linear model cannot see: CD, zero-order, V and product terms);
    - ``status``, ``flags``: per parameter the summary's verdict and the warnings about it
      (docs/output-schema.md); ``reasons``: ``{name: why}`` for every parameter whose
      ``estimate`` or ``std_error`` is ``NaN`` (its verdict, flags and notes);
    - ``correlation``: (n, n) Cramér–Rao correlation of the estimates (``fdoe``: of its
      frequency-domain fit, NaN rows and columns for the parameters not estimated);
    - ``outputs``: the ``m`` fitted outputs; ``residuals``: (N, m) measured − model (``fem``:
      the filter's innovations; ``fdoe``: of the time-domain simulation at its estimates), the
      manoeuvres concatenated;
    - ``traces``: per output, ``{"t_s", "measured", "simulated"}`` arrays (NaN between
      manoeuvres; ``fem``, ``fdoe``: the model simulated at its estimates);
    - ``model``: the model's name; ``notes``: what the reader noted about the record;
    - ``summary``: the CLI's ``summary.json`` as a dict (iterations, identifiability, warnings,
      validation, process noise, estimated initial states, ``structure_selection`` …);
    - ``selected_model``: with ``model="auto…"`` the chosen model as model-file TOML (the
      CLI's ``model.toml``), else ``None``.

    Raises :class:`AeroidentError` with the CLI's message on bad input, a real-time estimator,
    or a fit that fails (e.g. a model that cannot be simulated).
    """
    if bootstrap is not None and (isinstance(bootstrap, bool) or not isinstance(bootstrap, int)):
        raise TypeError(f"bootstrap must be an int or None, got {bootstrap!r}")
    if bootstrap is not None:
        # The library's check and message, before the record is read (counts past 64 bits too).
        _core.check_bootstrap_refits(bootstrap)
    r = _core.fit_file(
        os.fspath(data),
        os.fspath(mapping),
        estimator,
        None if model is None else os.fspath(model),
        initial_states,
        None if validate_on is None else os.fspath(validate_on),
        bootstrap,
        max_iterations,
        process_noise,
        None if compat is None else os.fspath(compat),
        _windows(windows),
        None if also is None else [os.fspath(p) for p in _sequence("also", also)],
        select,
        _sequence("candidates", candidates),
        _band(band_hz),
        None if knots_deg is None else [float(k) for k in _sequence("knots_deg", knots_deg)],
        allow_duplicate_records=bool(allow_duplicate_records),
        cross_check=None if cross_check is None else bool(cross_check),
        **options,
    )
    r["reasons"] = _reasons(r["names"], r["estimate"], r["std_error"], r["summary"]["parameters"], estimator)
    return r


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
) -> dict[str, Any]:
    """Frequency responses of a sweep or chirp record, with coherence and random error, and
    optional transfer-function fits.

    Exactly ``aeroident freqresp DATA --map MAP --input … --output … [--window A:B …]
    [--windows-s …] [--overlap F] [--f-min-hz F] [--f-max-hz F] [--points-per-decade N]
    [--fit SPEC …] [--min-coherence G]`` (docs/frequency-response.md): composite-window
    spectral estimation (Tischler & Remple, CIFER), conditioned multi-input responses with
    partial coherence when several inputs are given, and low-order transfer functions with a
    delay fitted by the MIL-STD-1797 mismatch cost (``fit="q/de:1/2+delay@0.5:10"``, band in
    rad/s). Channels are mapping keys (``de``, ``q`` …) read in SI.

    Returns a dict: ``file``, ``samples``, ``stretches``, ``dt_s``, ``window_lengths_s``
    (array), ``overlap``, ``pairs`` (one dict per (output, input) with ``input``, ``output`` and
    the arrays ``frequency_hz``, ``magnitude_db``, ``phase_deg``, ``coherence``,
    ``multiple_coherence``, ``random_error``, ``magnitude_error_db``, ``phase_error_deg``; NaN
    where not identified), ``fits`` (as in ``freqresp.json``) and ``warnings``.

    Raises :class:`AeroidentError` with the CLI's message (an unmapped channel, an input not
    excited, a window longer than the data, a bad fit spec …).
    """
    as_list = lambda v: [v] if isinstance(v, str) else list(v)
    return _core.freqresp_file(
        os.fspath(data),
        os.fspath(map),
        as_list(input),
        as_list(output),
        None if windows is None else [tuple(w) for w in windows],
        None if windows_s is None else [float(w) for w in windows_s],
        float(overlap),
        f_min_hz,
        f_max_hz,
        int(points_per_decade),
        None if fit is None else as_list(fit),
        float(min_coherence),
    )


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
) -> dict[str, Any]:
    """Trims the F-16 (Stevens, Lewis & Johnson 3rd ed. §3.6), as ``aeroident f16 trim``.

    The condition in SI: true airspeed ``vt_mps`` (m/s), altitude ``alt_m`` (m), flight-path
    angle ``gamma_rad`` (rad, default 0), and at most one of a coordinated turn
    ``turn_rate_rad_s`` or a pull-up ``pull_up_rad_s`` (rad/s); ``xcg``: centre of gravity,
    fraction of the mean aerodynamic chord. The textbook's units only by name, keyword-only:
    ``vt_fps`` (ft/s), ``alt_ft`` (ft), ``gamma_deg``, ``turn_rate_deg_s``, ``pull_up_deg_s``
    (the command line's flags) instead of their SI twins.

    Returns a dict:

    - ``state``: (13,) float64, SI (``state_names``: ``vt_mps``, angles in rad, rates in rad/s,
      ``north_m``, ``east_m``, ``alt_m``, ``pow_pct``); ``state_textbook``: (13,) float64 in
      the textbook's ft and ft/s (``state_names_textbook``, the model's own state);
    - ``controls``: (4,) float64, ``control_names`` (throttle 0–1, elevator, aileron, rudder in
      rad);
    - ``alpha_rad``, ``beta_rad``, ``theta_rad``, ``elevator_rad``, ``aileron_rad``,
      ``rudder_rad`` (float, rad), and the command line's ``--json`` keys ``throttle``,
      ``elevator_deg``, ``aileron_deg``, ``rudder_deg``, ``alpha_deg``, ``beta_deg``,
      ``theta_deg``, ``cost``;
    - ``out_of_range``: list of str, the trim quantities outside the data's ranges.

    Raises ``TypeError`` naming the keywords when the airspeed or altitude is missing or a
    quantity is given in both units; :class:`AeroidentError` with the CLI's message when the
    trim does not converge or the condition is out of range.
    """
    # Every keyword goes to the one parser in Rust, which converts with the workspace's units.
    return _core.trim(dict(locals()))


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
) -> dict[str, Any]:
    """Linearizes the F-16 about its trim, as ``aeroident f16 linearize``; the condition as in
    :func:`trim` (SI, or the textbook's units by their keyword-only names).

    Returns a dict:

    - ``a``: (13, 13) float64 and ``b``: (13, 4) float64, ẋ = A x + B u in SI (states
      ``state_names``, inputs ``input_names``: throttle, elevator_rad, aileron_rad,
      rudder_rad);
    - ``a_textbook``, ``b_textbook``: the same model in the textbook's ft and ft/s
      (``state_names_textbook``), exactly the command line's ``--json`` ``a`` and ``b``;
    - ``eigenvalues``: (13,) complex128, 1/s, sorted by real then imaginary part (the same for
      both unit systems);
    - ``modes``: list of dicts (``name``, ``eigenvalue`` (re, im), ``wn_radps``, ``zeta``);
    - ``trim``: as :func:`trim` returns.

    Raises as :func:`trim`.
    """
    d = _core.linearize(dict(locals()))
    ev = d["eigenvalues"]
    d["eigenvalues"] = ev[:, 0] + 1j * ev[:, 1]
    return d


def simulate(scenario: PathLike, *, textbook: bool = False) -> dict[str, np.ndarray]:
    """Runs an open-loop F-16 simulation scenario (TOML, ``scenarios/sim/``), as ``aeroident f16
    sim`` does. Relative paths in the scenario resolve against its directory.

    Returns its ``timeseries.csv`` columns as (k,) float64 arrays, first ``t_s``; the unit is in
    each name. In SI by default: a textbook column is converted and renamed by its unit
    (``vt_fps`` → ``vt_mps``, ``alt_ft`` → ``alt_m``, ``ax_fps2`` → ``ax_mps2``, ``qbar_psf`` →
    ``qbar_pa``, ``thrust_lbf`` → ``thrust_n``); load factors stay in g. ``textbook=True``: the
    columns exactly as the command line writes them (ft, ft/s, psf, lbf). Sensed channels are
    ``meas_<channel>``.

    Raises :class:`AeroidentError` with the CLI's message for a missing or bad scenario.
    """
    return _core.simulate(os.fspath(scenario), bool(textbook))


def montecarlo(
    scenario: Optional[PathLike] = None,
    runs: int = 100,
    backend: str = "local",
    seed: int = 1,
    *,
    chunk_size: Optional[int] = None,
    per_run: bool = False,
) -> dict[str, Any]:
    """A Monte Carlo campaign of the closed-loop ``run`` experiment.

    ``scenario``: a scenario file, or ``None`` for the built-in default scenario. Returns the
    same dict as ``aeroident montecarlo SCENARIO --runs RUNS --seed SEED --json``: ``runs`` and
    per estimator its ``parameters`` with ``reference, bias, scatter, mean_std_error,
    coverage_2sigma, crb_std_error, crb_std_error_calm, median_time_to_10pct_s`` (``None`` where
    the CLI prints null; ``reference`` is the truth at the end; ``crb_std_error`` is the bound of
    the experiment flown, turbulence included).
    ``per_run=True`` adds ``per_run`` (every run's final results, the CLI's ``runs.json``) and
    ``wall_s``. ``runs`` is at most :data:`MAX_RUNS` (every run's results are kept for the
    statistics; the sampling error of a σ at that many runs is already 0.7 %).

    ``backend="local"``: the runs on this machine's rayon pool. ``backend="ray"``: chunks of
    ``chunk_size`` seeded runs (default: about 4 chunks per CPU of the cluster) as Ray tasks,
    each running the Rust campaign code for its runs; the driver reduces the per-run results to
    the same statistics. Uses the running Ray cluster (``ray.init(address=…)`` first to use a
    real one), else starts a local one. Run ``i`` depends only on (scenario, seed, i), so both
    backends give bit-identical per-run results and statistics.
    """
    if isinstance(runs, bool) or not isinstance(runs, int) or runs < 1:
        raise AeroidentError("runs must be at least 1")
    # Before any run or task: the library's check and message (counts past 64 bits too).
    _core.check_runs(runs)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**64:
        raise AeroidentError("seed must be ≥ 0 (a 64-bit unsigned integer)")
    text, origin = _core.scenario_text(None if scenario is None else os.fspath(scenario))
    if backend == "local":
        return _core.montecarlo_local(text, origin, runs, seed, per_run)
    if backend == "ray":
        from ._ray import montecarlo_ray

        return montecarlo_ray(text, origin, runs, seed, chunk_size, per_run)
    raise AeroidentError(f"backend: `{backend}` is not `local` or `ray`")
