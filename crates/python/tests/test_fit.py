"""`aeroident.fit` (batch output error and the filter-error method) against the CLI, against the
published HFB-320 output-error result, and against numpy recomputations of its own arrays."""

from __future__ import annotations

import json

import numpy as np
import pytest

import aeroident
from conftest import ROOT, cli, shared

HFB = "jategaonkar_hfb320_attas/csv/hfb320_1_10.csv"
HFB_MAP = ROOT / "mappings/hfb320.toml"
BOOK_MODEL = ROOT / "models/hfb320_book_q0.toml"
# Jategaonkar 2015, HFB-320 output error (../shared/flightdata/jategaonkar_hfb320_attas/README.md).
PUBLISHED = {"Cm_alpha": -1.002, "Cm_q0": -27.06, "Cm_de": -1.437, "CL_alpha": 3.212}


def without_wall_time(summary: dict) -> dict:
    d = dict(summary)
    d.pop("fit_wall_s")
    return d


@pytest.mark.parametrize("estimator", ["oe", "fem"])
def test_fit_equals_cli(tmp_path, estimator):
    data = shared(HFB)
    out = tmp_path / "out"
    r = cli("replay", data, "--map", HFB_MAP, "--model", BOOK_MODEL, "--estimator", estimator, "--out", out)
    assert r.returncode == 0, r.stderr
    expected = json.loads((out / "summary.json").read_text())
    py = aeroident.fit(data, HFB_MAP, estimator, model=BOOK_MODEL)
    assert without_wall_time(py["summary"]) == without_wall_time(expected)
    params = expected["parameters"]
    assert py["names"] == [p["name"] for p in params]
    np.testing.assert_array_equal(py["estimate"], [p["estimate"] for p in params])
    np.testing.assert_array_equal(py["std_error"], [p["std_error"] for p in params])
    np.testing.assert_array_equal(py["crb_std_error"], [p["crb_std_error"] for p in params])
    timing = [np.nan if p["timing_std_error"] is None else p["timing_std_error"] for p in params]
    np.testing.assert_array_equal(py["timing_std_error"], timing)
    unmodelled = [np.nan if p["unmodelled_std_error"] is None else p["unmodelled_std_error"] for p in params]
    np.testing.assert_array_equal(py["unmodelled_std_error"], unmodelled)
    # The verdict is the summary's, under the summary's names (docs/output-schema.md).
    assert py["status"] == [p["status"] for p in params]
    assert py["flags"] == [p["flags"] for p in params]
    assert py["parameter_notes"] == [p["notes"] for p in params]
    refs = [np.nan if p["reference"] is None else p["reference"] for p in params]
    np.testing.assert_array_equal(py["reference"], refs)
    assert set(py["status"]) <= {"identified", "flagged", "not identified", "not converged"}


def test_fit_reproduces_the_published_hfb320_output_error_result():
    py = aeroident.fit(shared(HFB), HFB_MAP, "oe", model=BOOK_MODEL)
    for name, published in PUBLISHED.items():
        est = py["estimate"][py["names"].index(name)]
        assert abs(est / published - 1.0) < 0.01, (name, est, published)


def test_fit_arrays_agree_with_each_other():
    py = aeroident.fit(shared(HFB), HFB_MAP, "oe", model=BOOK_MODEL)
    n, m = len(py["names"]), len(py["outputs"])
    rho = py["correlation"]
    assert rho.shape == (n, n)
    np.testing.assert_allclose(np.diag(rho), 1.0, rtol=1e-12)
    np.testing.assert_allclose(rho, rho.T, atol=1e-12)
    assert np.all(np.abs(rho) <= 1.0 + 1e-12)
    assert np.linalg.eigvalsh(rho).min() > 0.0, "a correlation matrix is positive definite"
    # Every sample of the record is one residual row; each output's residual RMS is the
    # summary's (recomputed here from the array, not read back).
    e = py["residuals"]
    assert e.shape == (py["summary"]["samples_read"] - py["summary"]["samples_rejected"], m)
    rms = dict(py["summary"]["residual_rms"])
    for j, name in enumerate(py["outputs"]):
        assert np.sqrt(np.mean(e[:, j] ** 2)) == pytest.approx(rms[name], rel=1e-9), name
    # The traces are measured and simulated with simulated = measured − residual (one manoeuvre,
    # every sample kept: stride 1).
    assert set(py["traces"]) == set(py["outputs"])
    for j, name in enumerate(py["outputs"]):
        tr = py["traces"][name]
        assert tr["t_s"].shape == tr["measured"].shape == tr["simulated"].shape == (e.shape[0],)
        np.testing.assert_allclose(tr["measured"] - tr["simulated"], e[:, j], rtol=0, atol=1e-12)
    # The coloured-residual σ is reported and exceeds the Cramér–Rao σ on this record.
    assert np.all(py["std_error"] > py["crb_std_error"])


def test_fit_with_the_initial_state_estimated():
    fixed = aeroident.fit(shared(HFB), HFB_MAP, "oe", model=BOOK_MODEL)
    free = aeroident.fit(shared(HFB), HFB_MAP, "oe", model=BOOK_MODEL, initial_states="estimate")
    assert fixed["summary"]["initial_states"] == "first-sample"
    assert free["summary"]["initial_states"] == "estimate"
    assert fixed["summary"]["estimated_initial_states"] == []
    x0 = free["summary"]["estimated_initial_states"]
    assert x0 and all(name.startswith("x0_m1_") for name, _, _ in x0)
    # The free initial state nests the fixed one: the likelihood cannot be worse.
    ln_det = lambda r: r["summary"]["iterations"][-1]["ln_det_r"]  # noqa: E731
    assert ln_det(free) <= ln_det(fixed) + 1e-9


def test_fit_refuses_what_it_cannot_do():
    data = shared(HFB)
    with pytest.raises(aeroident.AeroidentError, match="real-time method.*aeroident.replay"):
        aeroident.fit(data, HFB_MAP, "rls")
    with pytest.raises(aeroident.AeroidentError, match="initial_states: `bogus`"):
        aeroident.fit(data, HFB_MAP, "oe", initial_states="bogus")
    with pytest.raises(aeroident.AeroidentError, match="unknown estimator `nope`"):
        aeroident.fit(data, HFB_MAP, "nope")
    with pytest.raises(aeroident.AeroidentError, match=r"batch method.*aeroident\.fit"):
        aeroident.replay(data, mapping=HFB_MAP, estimator="oe")
    with pytest.raises(aeroident.AeroidentError, match="nothing_here.csv"):
        aeroident.fit(ROOT / "nothing_here.csv", HFB_MAP, "oe")
    with pytest.raises(aeroident.AeroidentError, match="max_iterations: must be an integer of at least 1, got 0"):
        aeroident.fit(data, HFB_MAP, "oe", max_iterations=0)
    with pytest.raises(aeroident.AeroidentError, match="`gamma` unknown"):
        aeroident.fit(data, HFB_MAP, "fem", process_noise="V,gamma")
    with pytest.raises(aeroident.AeroidentError, match="filter-error method"):
        aeroident.fit(data, HFB_MAP, "oe", process_noise="V")


def test_fit_options_go_through_one_parser():
    # Further keywords are the fit's other options by their keys, parsed as the CLI's flags:
    # Huber's weights reach output error (the estimates move), a real-time estimator's option is
    # refused naming what the fit takes, and the other method's option names whose it is.
    data = shared(HFB)
    plain = aeroident.fit(data, HFB_MAP, "oe", model=BOOK_MODEL)
    robust = aeroident.fit(data, HFB_MAP, "oe", model=BOOK_MODEL, robust=True)
    assert not np.array_equal(plain["estimate"], robust["estimate"])
    with pytest.raises(aeroident.AeroidentError, match=r"unknown keyword argument `forgetting` \(it takes `initial_states`, `step`, `bootstrap`, `max_iterations`, `robust`\)"):
        aeroident.fit(data, HFB_MAP, "oe", forgetting=0.9)
    with pytest.raises(aeroident.AeroidentError, match="filter-error method"):
        aeroident.fit(data, HFB_MAP, "oe", gain_constraint=False)


def test_fit_past_the_iteration_limit_is_the_last_iterate(tmp_path):
    # The same as the CLI with --max-iterations 2: a result, status not_converged and why.
    data = shared(HFB)
    out = tmp_path / "out"
    args = ("--model", BOOK_MODEL, "--estimator", "oe", "--max-iterations", "2", "--out", out)
    r = cli("replay", data, "--map", HFB_MAP, *args)
    assert r.returncode == 0, r.stderr
    expected = json.loads((out / "summary.json").read_text())
    py = aeroident.fit(data, HFB_MAP, "oe", model=BOOK_MODEL, max_iterations=2)
    assert without_wall_time(py["summary"]) == without_wall_time(expected)
    assert py["summary"]["status"] == "not_converged"
    assert "iteration limit" in py["summary"]["status_reason"]
    assert np.all(np.isfinite(py["estimate"]))


def test_fit_bootstrap_sigma():
    plain = aeroident.fit(shared(HFB), HFB_MAP, "oe", model=BOOK_MODEL)
    boot = aeroident.fit(shared(HFB), HFB_MAP, "oe", model=BOOK_MODEL, bootstrap=10)
    b = boot["summary"]["bootstrap"]
    assert plain["summary"]["bootstrap"] is None
    assert b["refits"] == 10 and b["failed"] == 0
    # The bootstrap changes the σ, not the estimates; the reported σ is the bootstrap's with the
    # sample-timing and unmodelled σ in quadrature.
    np.testing.assert_array_equal(boot["estimate"], plain["estimate"])
    params = boot["summary"]["parameters"]
    noise = np.hypot([p["bootstrap_std_error"] for p in params], [p["timing_std_error"] for p in params])
    want = np.hypot(noise, [p["unmodelled_std_error"] or 0.0 for p in params])
    np.testing.assert_allclose(boot["std_error"], want, rtol=1e-12)
    assert np.all(boot["std_error"] > 0.5 * boot["crb_std_error"])
    with pytest.raises(aeroident.AeroidentError, match="bootstrap"):
        aeroident.fit(shared(HFB), HFB_MAP, "fem", model=BOOK_MODEL, bootstrap=10)
    with pytest.raises(aeroident.AeroidentError, match="at least 2"):
        aeroident.fit(shared(HFB), HFB_MAP, "oe", model=BOOK_MODEL, bootstrap=1)


def test_fit_windows_equal_cli(tmp_path):
    # fAttasAilRud1 is the aileron record (50.08–80.08 s) and the rudder record joined: the
    # window of the first is fitted as the CLI's --window, and a bad window is refused.
    data = shared("jategaonkar_hfb320_attas/csv/fAttasAilRud1.csv")
    mapping = ROOT / "mappings/attas_lateral.toml"
    out = tmp_path / "out"
    r = cli("replay", data, "--map", mapping, "--estimator", "oe", "--window", "50:81", "--out", out)
    assert r.returncode == 0, r.stderr
    expected = json.loads((out / "summary.json").read_text())
    py = aeroident.fit(data, mapping, "oe", windows=[(50, 81)])
    assert without_wall_time(py["summary"]) == without_wall_time(expected)
    assert py["summary"]["manoeuvres"] == 1
    with pytest.raises(aeroident.AeroidentError, match="windows: `5:2`"):
        aeroident.fit(data, mapping, "oe", windows=[(5, 2)])


def test_fit_of_two_records_equals_the_joined_record():
    # fAttasAilRud1 is fAttasAil1 and fAttasRud1 joined at a gap: fitted together (also=, the
    # CLI's --and) they give the joined record's estimates.
    rel = lambda n: shared(f"jategaonkar_hfb320_attas/csv/{n}.csv")  # noqa: E731
    mapping = ROOT / "mappings/attas_lateral.toml"
    together = aeroident.fit(rel("fAttasAil1"), mapping, "oe", also=[rel("fAttasRud1")])
    joined = aeroident.fit(rel("fAttasAilRud1"), mapping, "oe")
    assert together["summary"]["manoeuvres"] == 2
    np.testing.assert_array_equal(together["estimate"], joined["estimate"])


C172 = "jsbsim_samples/c172x_elevator_3211_15s_60Hz.csv"
JSBSIM_MAP = ROOT / "mappings/jsbsim_clean.toml"
ALPHADOT = ["alpha", "q", "alphadot", "de", "V", "alpha2", "alpha_de"]


def test_fit_model_auto_equals_cli(tmp_path):
    """`fit(..., model="auto:…", candidates=…)` is `replay --model auto:… --candidates …`: the
    same summary with its `structure_selection`, and `selected_model` is the CLI's model.toml."""
    data = shared(C172)
    out = tmp_path / "out"
    r = cli("replay", data, "--map", JSBSIM_MAP, "--model", "auto:longitudinal",
            "--candidates", ",".join(ALPHADOT), "--estimator", "oe", "--out", out)
    assert r.returncode == 0, r.stderr
    expected = json.loads((out / "summary.json").read_text())
    py = aeroident.fit(data, JSBSIM_MAP, "oe", model="auto:longitudinal", candidates=ALPHADOT)
    assert without_wall_time(py["summary"]) == without_wall_time(expected)
    assert "alphadot" in [c for s in expected["structure_selection"]["coefficients"]
                          if s["coefficient"] == "Cm" for c in s["kept"]]
    assert py["selected_model"] == (out / "model.toml").read_text()
    assert aeroident.fit(data, JSBSIM_MAP, "oe")["selected_model"] is None


def test_replay_model_auto_selects_and_refuses_a_bad_candidate():
    """The real-time replay takes the same selection; a bad candidate is the library's error."""
    data = shared(C172)
    py = aeroident.replay(data, JSBSIM_MAP, "rls", model="auto:longitudinal", candidates=ALPHADOT)
    assert "Cm_alphadot" in py["names"]
    assert py["summary"]["structure_selection"]["method"] == "swr"
    with pytest.raises(aeroident.AeroidentError, match="`bogus`"):
        aeroident.replay(data, JSBSIM_MAP, "rls", model="auto", candidates=["bogus"])


TOTTER = "sidpac_twin_otter/csv/totter_lon_020213f1_018.csv"
TOTTER_MAP = ROOT / "mappings/twin_otter.toml"


def null_as_nan(values) -> list[float]:
    return [np.nan if v is None else v for v in values]


@pytest.mark.parametrize("band", [None, (0.1, 1.2)])
def test_fdoe_fit_equals_cli_on_the_twin_otter(tmp_path, band):
    data = shared(TOTTER)
    out = tmp_path / "out"
    extra = [] if band is None else ["--band-hz", f"{band[0]}:{band[1]}"]
    r = cli("replay", data, "--map", TOTTER_MAP, "--estimator", "fdoe", *extra, "--out", out)
    assert r.returncode == 0, r.stderr
    expected = json.loads((out / "summary.json").read_text())
    py = aeroident.fit(data, TOTTER_MAP, "fdoe", band_hz=band)
    assert without_wall_time(py["summary"]) == without_wall_time(expected)
    params = expected["parameters"]
    assert py["names"] == [p["name"] for p in params]
    # fdoe leaves the parameters its linear model cannot see `null`: NaN in the arrays.
    assert any(p["estimate"] is None for p in params) and any(p["estimate"] is not None for p in params)
    np.testing.assert_array_equal(py["estimate"], null_as_nan(p["estimate"] for p in params))
    np.testing.assert_array_equal(py["std_error"], null_as_nan(p["std_error"] for p in params))
    np.testing.assert_array_equal(py["crb_std_error"], null_as_nan(p["crb_std_error"] for p in params))
    # Every NaN estimate carries its reason: the summary's verdict, never a bare NaN.
    for p in params:
        if p["estimate"] is None:
            assert py["reasons"][p["name"]].startswith(p["status"]), (p["name"], py["reasons"])
    assert py["estimate"].dtype == np.float64 and py["estimate"].shape == (len(params),)
    # The correlation of the estimated parameters, from the same covariance as their σ.
    est = [i for i, p in enumerate(params) if p["estimate"] is not None]
    rho = py["correlation"][np.ix_(est, est)]
    np.testing.assert_allclose(np.diag(rho), 1.0, rtol=1e-12)
    np.testing.assert_allclose(rho, rho.T, atol=1e-12)
    assert np.isnan(py["correlation"][[i for i in range(len(params)) if i not in est][0]]).all()


def test_fdoe_band_is_refused_for_other_estimators():
    with pytest.raises(aeroident.AeroidentError, match="band_hz"):
        aeroident.fit(shared(TOTTER), TOTTER_MAP, "oe", band_hz=(0.1, 2.0))
    with pytest.raises(aeroident.AeroidentError, match="0 < f_min < f_max"):
        aeroident.fit(shared(TOTTER), TOTTER_MAP, "fdoe", band_hz=(2.0, 1.0))
