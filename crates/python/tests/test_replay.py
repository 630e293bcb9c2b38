"""The vectorised replay and the estimator objects against the CLI, against each other, and
against a record generated from known derivatives."""

from __future__ import annotations

import json

import numpy as np
import pytest

import aeroident
from conftest import ROOT, cli, cli_error, read_estimates_csv, shared

RECORDS = [
    ("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv", "mappings/hfb320.toml"),
    ("jsbsim_f16_sample/f16_doublet_20s_120Hz.csv", "mappings/jsbsim_clean.toml"),
    ("jsbsim_samples/f16_ail_rud_doublets_20s_60Hz.csv", "mappings/jsbsim_clean.toml"),
]


def assert_equal_nan(a: np.ndarray, b: np.ndarray, tol: float = 1e-12) -> None:
    assert a.shape == b.shape
    assert np.array_equal(np.isnan(a), np.isnan(b)), "identified at different samples"
    ok = ~np.isnan(a)
    scale = np.maximum(1.0, np.abs(b[ok]))
    assert np.all(np.abs(a[ok] - b[ok]) <= tol * scale), np.max(np.abs(a[ok] - b[ok]) / scale)


@pytest.mark.parametrize("record,mapping", RECORDS)
@pytest.mark.parametrize("estimator", ["rls", "rls-iv", "ftr", "ekf"])
def test_replay_equals_cli(tmp_path, record, mapping, estimator):
    data = shared(record)
    out = tmp_path / "out"
    # Every row: the command line writes one per 0.1 s of a file by default, Python every one.
    r = cli("replay", data, "--map", ROOT / mapping, "--estimator", estimator, "--estimates-every", "0", "--out", out)
    assert r.returncode == 0, r.stderr
    names, t, est, sig = read_estimates_csv(out / "estimates.csv")
    py = aeroident.replay(data, mapping=ROOT / mapping, estimator=estimator)
    assert py["names"] == names
    assert py["estimates"].shape == (len(t), len(names))
    np.testing.assert_array_equal(py["t_s"], t)
    assert_equal_nan(py["estimates"], est)
    # The command line writes each sigma to four significant digits (SIGMA_DIGITS).
    assert np.array_equal(np.isnan(py["std_error"]), np.isnan(sig))
    ok = ~np.isnan(sig)
    assert np.all(np.abs(py["std_error"][ok] - sig[ok]) <= 5e-4 * np.abs(py["std_error"][ok]))
    # The summary is the CLI's summary.json, except the measured throughput.
    expected = json.loads((out / "summary.json").read_text())
    got = dict(py["summary"])
    for d in (expected, got):
        d.pop("throughput_samples_per_s")
    assert got == expected


def test_estimator_objects_equal_vectorised_replay():
    data = shared(RECORDS[0][0])
    arrays = aeroident.read(data, ROOT / RECORDS[0][1])
    n = len(arrays["t_s"])
    assert n > 100 and arrays["row"].shape == (n,)
    vec = aeroident.replay(arrays, estimator="rls", model="longitudinal")
    est = aeroident.Rls(model="longitudinal")
    keys = aeroident.sample_keys()
    values = []
    for k in range(n):
        est.update({key: float(arrays[key][k]) for key in keys})
        values.append(est.estimates()["estimate"])
    assert est.samples == n and vec["estimates"].shape == (n, 12)
    np.testing.assert_array_equal(np.array(values), vec["estimates"])
    e = est.estimates()
    assert e["names"] == vec["names"] and e["estimator_status"] == "running"
    np.testing.assert_array_equal(e["std_error"], vec["std_error"][-1])


def synthetic(n: int = 400) -> tuple[dict[str, np.ndarray], dict[str, float]]:
    """A pitch/lift/drag record generated from known derivatives, noise-free:
    Cm = 0.02 − 0.6 α − 12 q c/2V − 1.1 δe, CL = 0.1 + 5 α, CD = 0.03 + 0.4 α."""
    t = 0.02 * np.arange(n)
    alpha = 0.05 + 0.02 * np.sin(1.3 * t)
    q = 0.03 * np.cos(2.1 * t)
    de = -0.02 + 0.01 * np.sin(3.7 * t)
    vt, rho, S, c, m, Iyy = 100.0, 1.0, 30.0, 3.0, 7000.0, 5.0e4
    qbar = 0.5 * rho * vt**2 * np.ones(n)
    cm = 0.02 - 0.6 * alpha - 12.0 * q * c / (2 * vt) - 1.1 * de
    cl, cd = 0.1 + 5.0 * alpha, 0.03 + 0.4 * alpha
    ax = qbar * S * (-cd * np.cos(alpha) + cl * np.sin(alpha)) / m
    az = qbar * S * (-cd * np.sin(alpha) - cl * np.cos(alpha)) / m
    arrays = dict(t_s=t, vt_mps=vt * np.ones(n), alpha_rad=alpha, qbar_pa=qbar, q_rad_s=q,
                  qdot_rad_s2=cm * qbar * S * c / Iyy, ax_mps2=ax, az_mps2=az, de_rad=de)
    constants = dict(mass_kg=m, S_m2=S, cbar_m=c, Iyy_kgm2=Iyy)
    return arrays, constants


def test_replay_of_arrays_recovers_known_derivatives():
    arrays, constants = synthetic()
    r = aeroident.replay(arrays, estimator="rls", model="longitudinal", constants=constants)
    last = dict(zip(r["names"], r["estimates"][-1]))
    for name, truth in [("Cm_alpha", -0.6), ("Cm_q", -12.0), ("Cm_de", -1.1), ("CL_alpha", 5.0), ("CD_alpha", 0.4)]:
        assert abs(last[name] - truth) < 1e-6 * max(1.0, abs(truth)), (name, last[name])
    assert r["samples_refused"] == 0
    # Not identified before enough samples: NaN, never 0.
    assert np.isnan(r["estimates"][0]).all()


def test_refused_sample_raises_and_leaves_the_state():
    arrays, constants = synthetic(50)
    est = aeroident.Estimator("rls", model="longitudinal", constants=constants)
    for k in range(20):
        est.update({key: v[k] for key, v in arrays.items()})
    before = est.estimates()
    bad = {key: v[20] for key, v in arrays.items()}
    bad["t_s"] = arrays["t_s"][10]  # time going backwards, or a non-finite channel
    bad["q_rad_s"] = float("inf")
    with pytest.raises(aeroident.AeroidentError, match="refused sample"):
        est.update(bad)
    after = est.estimates()
    np.testing.assert_array_equal(after["estimate"], before["estimate"])
    np.testing.assert_array_equal(after["std_error"], before["std_error"])
    assert after["reasons"] == before["reasons"] and est.samples == 20


def test_missing_required_channel_and_constant_are_named():
    arrays, constants = synthetic(10)
    est = aeroident.Rls(model="longitudinal", constants=constants)
    s = {key: v[0] for key, v in arrays.items() if key != "alpha_rad"}
    with pytest.raises(aeroident.AeroidentError, match="`alpha_rad` is missing"):
        est.update(s)
    with pytest.raises(aeroident.AeroidentError, match="`mass_kg` is missing"):
        aeroident.Rls(model="longitudinal").update({key: v[0] for key, v in arrays.items()})
    with pytest.raises(aeroident.AeroidentError, match="unknown key `mass`"):
        aeroident.Rls(constants={"mass": 1.0})


@pytest.mark.parametrize(
    "py_args,cli_args",
    [
        (dict(mapping="mappings/does_not_exist.toml"), ["--map", "mappings/does_not_exist.toml"]),
        (dict(mapping="mappings/hfb320.toml", model="no-such-model"), ["--map", "mappings/hfb320.toml", "--model", "no-such-model"]),
        (dict(mapping="mappings/jsbsim.toml"), ["--map", "mappings/jsbsim.toml"]),
    ],
)
def test_errors_carry_the_cli_message(tmp_path, py_args, cli_args):
    data = shared(RECORDS[0][0])
    py_args = {k: (str(ROOT / v) if k == "mapping" else v) for k, v in py_args.items()}
    cli_args = [str(ROOT / a) if a.startswith("mappings/") else a for a in cli_args]
    expected = cli_error("replay", data, *cli_args, "--out", tmp_path / "o")
    with pytest.raises(aeroident.AeroidentError) as e:
        aeroident.replay(data, **py_args)
    assert str(e.value) == expected


def test_bad_arguments():
    with pytest.raises(aeroident.AeroidentError, match="unknown estimator `kalman`"):
        aeroident.Estimator("kalman")
    with pytest.raises(aeroident.AeroidentError, match="needs mapping="):
        aeroident.replay("some.csv")
    with pytest.raises(aeroident.AeroidentError, match="batch method"):
        aeroident.Estimator("oe")


def test_smpe_finite_time_recovers_known_derivatives_with_sigma_and_takes_its_options():
    # Noise-free samples of known derivatives: the memory's solution is exact and the sliding
    # estimate sits on it; unlike the thesis's sliding-mode estimators it reports a sigma.
    arrays, constants = synthetic()
    est = aeroident.SmpeFiniteTime(model="longitudinal", constants=constants, forgetting=1.0, sliding_gain_per_s=5.0)
    assert est.method == "smpe-finite-time"
    for k in range(len(arrays["t_s"])):
        est.update({key: v[k] for key, v in arrays.items()})
    e = est.estimates()
    last = dict(zip(e["names"], e["estimate"]))
    for name, truth in [("Cm_alpha", -0.6), ("Cm_q", -12.0), ("CL_alpha", 5.0)]:
        assert abs(last[name] - truth) < 1e-6 * max(1.0, abs(truth)), (name, last[name])
    assert not np.isnan(e["std_error"]).any() and e["reasons"] == {}
    with pytest.raises(aeroident.AeroidentError, match="sliding_gain_per_s"):
        aeroident.SmpeFiniteTime(model="longitudinal", sliding_gain_per_s=-1.0)
    with pytest.raises(aeroident.AeroidentError, match="reaching_rate_per_s"):
        aeroident.Estimator("smpe-finite-time", reaching_rate_per_s=float("nan"))


def test_estimator_options_are_checked_by_the_registry():
    # An option the kind does not take is refused naming the kind and the options it takes (the
    # EKF has no forgetting factor: it was silently ignored), from the estimator objects and the
    # replay of arrays alike, as the CLI and a scenario refuse it.
    with pytest.raises(aeroident.AeroidentError, match=r"estimator `ekf`: unknown keyword argument `forgetting` \(it takes `parameter_walk_per_sqrt_s`, `blocks`, `update_every`\)"):
        aeroident.Estimator("ekf", forgetting=0.9)
    with pytest.raises(aeroident.AeroidentError, match=r"estimator `ekf`: unknown keyword argument `forgetting`"):
        aeroident.Ekf(model="longitudinal", forgetting=0.9)
    with pytest.raises(aeroident.AeroidentError, match=r"estimator `rls`: unknown keyword argument `ftr_grid_hz` \(it takes `forgetting`, `change_false_alarm_interval_s`\)"):
        aeroident.Rls(model="longitudinal", ftr_grid_hz=(0.1, 1.5, 0.04))
    with pytest.raises(aeroident.AeroidentError, match=r"estimator `smpe`: unknown keyword argument `sliding_gain_per_s` \(it takes none\)"):
        aeroident.Estimator("smpe", sliding_gain_per_s=5.0)
    arrays, constants = synthetic(50)
    with pytest.raises(aeroident.AeroidentError, match=r"estimator `gradient`: unknown keyword argument `forgetting`"):
        aeroident.replay(arrays, estimator="gradient", model="longitudinal", constants=constants, forgetting=0.99)
    # Left out (None), an option keeps the estimator's default.
    assert aeroident.Estimator("ekf", forgetting=None).method == "ekf"


def test_any_estimator_option_goes_through_the_registry():
    # Options without a keyword of their own are further keyword arguments by their scenario key:
    # rls-iv's instrument delay reaches the estimator (the replay differs from the default
    # delay's and equals the CLI's flag), and a key the kind does not take is refused naming what
    # it takes.
    assert aeroident.Estimator("rls-iv", model="longitudinal", instrument_delay=8).method == "rls-iv"
    with pytest.raises(aeroident.AeroidentError, match=r"estimator `rls`: unknown keyword argument `instrument_delay` \(it takes `forgetting`, `change_false_alarm_interval_s`\)"):
        aeroident.Estimator("rls", instrument_delay=8)
    with pytest.raises(aeroident.AeroidentError, match=r"`instrument_delay`: expected a number"):
        aeroident.Estimator("rls-iv", instrument_delay={"a": 1})
    data = shared(RECORDS[0][0])
    mapping = ROOT / RECORDS[0][1]
    default = aeroident.replay(data, mapping=mapping, estimator="rls-iv")
    delayed = aeroident.replay(data, mapping=mapping, estimator="rls-iv", instrument_delay=12)
    assert not np.array_equal(default["estimates"], delayed["estimates"], equal_nan=True)
    with pytest.raises(aeroident.AeroidentError, match=r"unknown keyword argument `parameter_walk_per_sqrt_s`"):
        aeroident.replay(data, mapping=mapping, estimator="rls", parameter_walk_per_sqrt_s=0.01)


def test_smpe_finite_time_takes_forgetting_and_it_reaches_the_estimator():
    # smpe-finite-time forgets (its memory is the forgotten information): the factor is taken,
    # by the estimator object and by the replay of a record (the CLI refused it there), and
    # changes the estimates.
    est = aeroident.Estimator("smpe-finite-time", model="longitudinal", forgetting=0.99)
    assert est.method == "smpe-finite-time"
    data = shared(RECORDS[0][0])
    mapping = ROOT / RECORDS[0][1]
    plain = aeroident.replay(data, mapping=mapping, estimator="smpe-finite-time")
    forgot = aeroident.replay(data, mapping=mapping, estimator="smpe-finite-time", forgetting=0.99)
    np.testing.assert_array_equal(plain["t_s"], forgot["t_s"])
    same = np.array_equal(plain["estimates"], forgot["estimates"], equal_nan=True) and np.array_equal(plain["std_error"], forgot["std_error"], equal_nan=True)
    assert not same, "forgetting=0.99 did not reach the estimator"
    with pytest.raises(aeroident.AeroidentError, match=r"estimator `ekf`: unknown keyword argument `forgetting`"):
        aeroident.replay(data, mapping=mapping, estimator="ekf", forgetting=0.9)


def test_ftr_grid_reaches_the_estimator():
    # 0.1-1.7 Hz in 0.04 Hz is 41 frequencies and builds; 0.1-3.0 Hz is 73, over the 64 the
    # real-time FTR holds (ftr::MAX_FREQUENCIES), and the error names the field.
    assert aeroident.Ftr(model="longitudinal", forgetting=0.9975, ftr_grid_hz=(0.1, 1.7, 0.04)).method == "ftr"
    with pytest.raises(aeroident.AeroidentError, match="f_step_hz"):
        aeroident.Ftr(model="longitudinal", ftr_grid_hz=(0.1, 3.0, 0.04))


def test_estimator_events_name_a_stuck_vane():
    """An α vane stuck at 0.5 rad for 30 samples of the HFB-320 record (10 Hz): the EKF's gate
    rejects it 25 times in a row, then re-anchors the α state: one `reanchor` event naming
    `alpha_rad` at the 25th stuck sample, every kind counted, no restart; the vectorised replay
    of the same arrays reports the same events."""
    data = shared(RECORDS[0][0])
    arrays = aeroident.read(data, ROOT / RECORDS[0][1])
    t = arrays["t_s"]
    stuck = slice(400, 430)
    arrays["alpha_rad"][stuck] = 0.5
    est = aeroident.Ekf(model="longitudinal")
    keys = aeroident.sample_keys()
    for k in range(len(t)):
        est.update({key: float(arrays[key][k]) for key in keys})
    got = est.events()
    # The vectorised replay of the same arrays reports the same events.
    assert aeroident.replay(arrays, estimator="ekf", model="longitudinal")["events"] == got
    assert set(got["counts"]) == {"restart", "reanchor", "change_detected"}
    assert got["not_listed"] == 0 and len(got["listed"]) == sum(got["counts"].values())
    assert got["counts"]["restart"] == 0, got
    first = got["listed"][0]
    assert (first["kind"], first["subject"]) == ("reanchor", "alpha_rad"), got
    assert first["t_s"] == t[stuck.start + 24], (first, t[stuck.start + 24])
    assert aeroident.Rls(model="longitudinal").events()["listed"] == []


def test_cross_check_equals_cli(tmp_path):
    # The HFB-320 record with Jategaonkar's model: RLS beside the record's other methods, as
    # the CLI's --cross-check; equation error's Cm_q (α lagging the kinematics) is not
    # confirmed, and its flag is the parameter's.
    data = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv")
    mapping, model = ROOT / "mappings/hfb320.toml", ROOT / "models/hfb320_jategaonkar.toml"
    out = tmp_path / "out"
    r = cli("replay", data, "--map", mapping, "--model", model, "--cross-check", "--out", out)
    assert r.returncode == 0, r.stderr
    expected = json.loads((out / "summary.json").read_text())["cross_check"]
    py = aeroident.replay(data, mapping=mapping, model=model, cross_check=True)
    assert py["summary"]["cross_check"] == expected
    q = next(a for a in expected["parameters"] if a["parameter"] == "Cm_q")
    assert not q["confirmed"] and "split" in q["flag"], q
    cm_q = next(p for p in py["summary"]["parameters"] if p["name"] == "Cm_q")
    assert cm_q["status"] == "flagged" and q["flag"] in cm_q["flags"]
    # By default the panel runs without the filter-error method; cross_check=False runs none
    # and says so.
    default = aeroident.replay(data, mapping=mapping, model=model)["summary"]["cross_check"]
    assert [m["method"] for m in default["methods"]] == ["rls", "rls-iv", "ekf", "oe", "fdoe"]
    off = aeroident.replay(data, mapping=mapping, model=model, cross_check=False)["summary"]
    assert off["cross_check"] is None
    assert any(w.startswith("cross-check not run (turned off") for w in off["warnings"]), off["warnings"]


def test_fit_cross_check_equals_cli(tmp_path):
    # The HFB-320 record by output error with the record's other methods beside it: the
    # same panel as the CLI's `--estimator oe --cross-check`, whose verdicts the parameters
    # carry; `fem` and the EKF, which model the record's turbulence, give CL_alpha above oe.
    data = shared("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv")
    mapping, model = ROOT / "mappings/hfb320.toml", ROOT / "models/hfb320_jategaonkar.toml"
    out = tmp_path / "out"
    r = cli("replay", data, "--map", mapping, "--model", model, "--estimator", "oe",
            "--cross-check", "--out", out)
    assert r.returncode == 0, r.stderr
    expected = json.loads((out / "summary.json").read_text())["cross_check"]
    py = aeroident.fit(data, mapping, model=model, cross_check=True)
    assert py["summary"]["cross_check"] == expected
    a = next(a for a in expected["parameters"] if a["parameter"] == "CL_alpha")
    by = {e["method"]: e["estimate"] for e in a["estimates"]}
    assert by["fem"] > by["oe"] and by["ekf"] > by["oe"], by
    for a in expected["parameters"]:
        i = list(py["names"]).index(a["parameter"])
        assert (a["flag"] is None) or (py["status"][i] == "flagged" and a["flag"] in py["flags"][i])
    # By default the panel runs without fem; cross_check=False runs none and says so.
    default = aeroident.fit(data, mapping, model=model)["summary"]["cross_check"]
    assert [m["method"] for m in default["methods"]] == ["oe", "rls", "rls-iv", "ekf", "fdoe"]
    off = aeroident.fit(data, mapping, model=model, cross_check=False)["summary"]
    assert "cross_check" not in off
    assert any(w.startswith("cross-check not run (turned off") for w in off["warnings"]), off["warnings"]


def test_estimates_are_float64_arrays_with_nan_and_its_reason():
    # Before any sample nothing is identified: NaN everywhere, each with its reason; after the
    # record every parameter has a number and a σ, and no reason is left.
    arrays, constants = synthetic()
    est = aeroident.Rls(model="longitudinal", constants=constants)
    e = est.estimates()
    n = len(est.names)
    for key in ("estimate", "std_error"):
        assert isinstance(e[key], np.ndarray) and e[key].dtype == np.float64 and e[key].shape == (n,), key
    assert np.isnan(e["estimate"]).all() and np.isnan(e["std_error"]).all()
    assert set(e["reasons"]) == set(est.names)
    assert all(r.startswith("not identified") for r in e["reasons"].values()), e["reasons"]
    for k in range(len(arrays["t_s"])):
        est.update({key: v[k] for key, v in arrays.items()})
    e = est.estimates()
    assert not np.isnan(e["estimate"]).any() and e["reasons"] == {} and e["samples"] == len(arrays["t_s"])
    cov = est.covariance_matrix()
    assert cov.dtype == np.float64 and cov.shape == (n, n)
    np.testing.assert_array_equal(cov, cov.T)
    i = est.names.index("Cm_alpha")
    assert cov[i, i] == est.covariance(i, i)


def test_a_method_without_sigma_says_so_beside_its_nan():
    # The thesis's sliding-mode estimator reports no σ: a number, a NaN σ and the reason.
    arrays, constants = synthetic()
    # Wings-level flight with the path level: the estimator's own model flies on θ and φ.
    arrays.update(theta_rad=arrays["alpha_rad"], phi_rad=np.zeros_like(arrays["t_s"]))
    est = aeroident.Smpe(model="longitudinal", constants=constants)
    for k in range(len(arrays["t_s"])):
        est.update({key: v[k] for key, v in arrays.items()})
    e = est.estimates()
    identified = ~np.isnan(e["estimate"])
    assert identified.sum() >= 6 and np.isnan(e["std_error"]).all()
    for name, ok in zip(e["names"], identified):
        why = e["reasons"][name]
        assert why == "no standard error: `smpe` reports none for it" if ok else why.startswith("not identified"), (name, why)


def test_replay_takes_lists_as_arrays_and_names_what_it_did_not_identify():
    # Array-likes in (lists), float64 arrays out, the same numbers as numpy arrays in.
    arrays, constants = synthetic(300)
    as_lists = {k: v.tolist() for k, v in arrays.items()}
    a = aeroident.replay(arrays, estimator="rls", model="longitudinal", constants=constants)
    b = aeroident.replay(as_lists, estimator="rls", model="longitudinal", constants=constants)
    for key in ("t_s", "estimates", "std_error"):
        assert b[key].dtype == np.float64
        np.testing.assert_array_equal(a[key], b[key])
    assert a["estimates"].shape == (300, len(a["names"])) and a["reasons"] == {}
    # Three samples identify nothing: NaN, each with its reason.
    few = aeroident.replay({k: v[:3] for k, v in arrays.items()}, estimator="rls", model="longitudinal", constants=constants)
    assert np.isnan(few["estimates"][-1]).all() and set(few["reasons"]) == set(few["names"])


def test_replay_of_a_record_gives_the_summarys_reason_for_a_nan():
    data = shared(RECORDS[0][0])
    r = aeroident.replay(data, mapping=ROOT / RECORDS[0][1], estimator="smpe")
    verdict = {p["name"]: p for p in r["summary"]["parameters"]}
    for i, name in enumerate(r["names"]):
        last, sigma = r["estimates"][-1, i], r["std_error"][-1, i]
        if np.isnan(last):
            assert r["reasons"][name].startswith(verdict[name]["status"]), r["reasons"]
        elif np.isnan(sigma):
            assert "no standard error" in r["reasons"][name]
        else:
            assert name not in r["reasons"]
