"""The F-16 from Python against the CLI's JSON and independent checks."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import aeroident
from conftest import ROOT, cli, cli_error


def test_trim_equals_cli():
    r = cli("f16", "trim", "--alt-ft", "10000", "--vt-fps", "600", "--gamma-deg", "2", "--json")
    assert r.returncode == 0, r.stderr
    expected = json.loads(r.stdout)
    got = aeroident.trim(10000, 600, gamma_deg=2)
    for k, v in expected.items():
        assert got[k] == pytest.approx(v, rel=1e-12, abs=1e-15), k
    # Independent: in wings-level trim θ = α + γ (β = 0, φ = 0).
    assert got["theta_deg"] == pytest.approx(got["alpha_deg"] + 2.0, abs=1e-6)
    assert got["state"].shape == (13,) and got["controls"].shape == (4,)


def test_linearize_equals_cli_and_its_eigenvalues():
    r = cli("f16", "linearize", "--alt-ft", "0", "--vt-fps", "502", "--json")
    assert r.returncode == 0, r.stderr
    expected = json.loads(r.stdout)
    got = aeroident.linearize(0, 502)
    assert got["a"].shape == (13, 13) and got["b"].shape == (13, 4)
    np.testing.assert_allclose(got["a"], np.array(expected["a"]), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(got["b"], np.array(expected["b"]), rtol=1e-12, atol=1e-15)
    # Independent: numpy's eigenvalues of the returned A.
    ours = np.sort_complex(got["eigenvalues"])
    theirs = np.sort_complex(np.linalg.eigvals(got["a"]))
    # The repeated zero eigenvalues (north, east, psi) are defective: a rounding perturbation
    # moves them by ~sqrt(eps)·|A|, so they agree to 1e-5 and the others far better.
    np.testing.assert_allclose(ours, theirs, atol=1e-5)


def test_trim_error_message_equals_cli():
    expected = cli_error("f16", "trim", "--alt-ft", "0", "--vt-fps", "500", "--xcg", "7")
    with pytest.raises(aeroident.AeroidentError) as e:
        aeroident.trim(0, 500, xcg=7)
    assert str(e.value) == expected


def test_simulate_equals_cli(tmp_path):
    scenario = ROOT / "scenarios" / "sim" / "elevator_doublet.toml"
    r = cli("f16", "sim", scenario, "--out", tmp_path)
    assert r.returncode == 0, r.stderr
    with open(tmp_path / "timeseries.csv", newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], np.array(rows[1:], dtype=np.float64)
    got = aeroident.simulate(scenario)
    assert list(got) == header
    for j, name in enumerate(header):
        # timeseries.csv holds 11 significant digits ({:.10e}): equal to that precision.
        np.testing.assert_allclose(got[name], body[:, j], rtol=6e-11, atol=0, err_msg=name)
    # Independent: a uniform time grid from 0.
    dt = np.diff(got["t_s"])
    np.testing.assert_allclose(dt, dt[0], rtol=1e-9)
    assert got["t_s"][0] == 0.0


def test_simulate_missing_file():
    expected = cli_error("f16", "sim", "no/such/scenario.toml", "--out", "/tmp/aeroident-py-nowhere")
    with pytest.raises(aeroident.AeroidentError) as e:
        aeroident.simulate("no/such/scenario.toml")
    assert str(e.value) == expected
