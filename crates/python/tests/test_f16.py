"""The F-16 from Python against the CLI's JSON and independent checks; its SI results against
the textbook-unit ones converted here with the exact foot (0.3048 m), not the library's
constants."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import aeroident
from conftest import ROOT, cli, cli_error

M_PER_FT = 0.3048  # exact by definition (1959); independent of aeroident's own constant
N_PER_LBF = 0.45359237 * 9.80665  # the avoirdupois pound (exact) times standard gravity
PA_PER_PSF = N_PER_LBF / M_PER_FT**2
# Per SLJ state: 1, or the foot for the airspeed and the three positions.
STATE_FACTORS = np.array([M_PER_FT, 1, 1, 1, 1, 1, 1, 1, 1, M_PER_FT, M_PER_FT, M_PER_FT, 1])


def test_trim_equals_cli():
    r = cli("f16", "trim", "--alt-ft", "10000", "--vt-fps", "600", "--gamma-deg", "2", "--json")
    assert r.returncode == 0, r.stderr
    expected = json.loads(r.stdout)
    got = aeroident.trim(alt_ft=10000, vt_fps=600, gamma_deg=2)
    for k, v in expected.items():
        assert got[k] == pytest.approx(v, rel=1e-12, abs=1e-15), k
    # Independent: in wings-level trim θ = α + γ (β = 0, φ = 0).
    assert got["theta_deg"] == pytest.approx(got["alpha_deg"] + 2.0, abs=1e-6)
    for key, shape in (("state", (13,)), ("state_textbook", (13,)), ("controls", (4,))):
        assert got[key].dtype == np.float64 and got[key].shape == shape, key
    assert got["state_names"][0] == "vt_mps" and got["state_names_textbook"][0] == "vt_fps"


def test_trim_in_si_equals_the_textbook_trim_converted():
    si = aeroident.trim(600 * M_PER_FT, 10000 * M_PER_FT, gamma_rad=np.radians(2))
    ft = aeroident.trim(alt_ft=10000, vt_fps=600, gamma_deg=2)
    # The same trim (the SI condition is the textbook's to rounding).
    np.testing.assert_allclose(si["state_textbook"], ft["state_textbook"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(si["controls"], ft["controls"], rtol=1e-9, atol=1e-12)
    # Its SI state is the textbook state times the exact foot, to the last bit.
    for t in (si, ft):
        np.testing.assert_array_equal(t["state"], t["state_textbook"] * STATE_FACTORS)
        assert t["alpha_rad"] == pytest.approx(np.radians(t["alpha_deg"]), rel=1e-15)
        assert t["elevator_rad"] == t["controls"][1]
    assert si["state"][0] == pytest.approx(600 * M_PER_FT, rel=1e-12)
    assert si["state"][11] == pytest.approx(10000 * M_PER_FT, rel=1e-12)


def test_a_quantity_in_both_units_or_none_is_refused_by_name():
    with pytest.raises(TypeError, match="give vt_mps or vt_fps, not both"):
        aeroident.trim(180.0, 3000.0, vt_fps=600)
    with pytest.raises(TypeError, match=r"give alt_m \(SI\) or alt_ft"):
        aeroident.trim(vt_mps=180.0)
    with pytest.raises(TypeError, match="give gamma_rad or gamma_deg, not both"):
        aeroident.linearize(180.0, 3000.0, gamma_rad=0.0, gamma_deg=0.0)
    with pytest.raises(TypeError, match="xcg must be a number"):
        aeroident.trim(180.0, 3000.0, xcg="aft")


def test_linearize_equals_cli_and_its_eigenvalues():
    r = cli("f16", "linearize", "--alt-ft", "0", "--vt-fps", "502", "--json")
    assert r.returncode == 0, r.stderr
    expected = json.loads(r.stdout)
    got = aeroident.linearize(alt_ft=0, vt_fps=502)
    for key, shape in (("a", (13, 13)), ("b", (13, 4)), ("a_textbook", (13, 13)), ("b_textbook", (13, 4))):
        assert got[key].dtype == np.float64 and got[key].shape == shape, key
    np.testing.assert_allclose(got["a_textbook"], np.array(expected["a"]), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(got["b_textbook"], np.array(expected["b"]), rtol=1e-12, atol=1e-15)
    # In SI: x_si = D x_ft, so A_si = D A D⁻¹ and B_si = D B (the inputs are SI in both).
    d = STATE_FACTORS
    np.testing.assert_allclose(got["a"], d[:, None] * np.array(expected["a"]) / d[None, :], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(got["b"], d[:, None] * np.array(expected["b"]), rtol=1e-12, atol=1e-15)
    assert got["state_names"][9:12] == ["north_m", "east_m", "alt_m"]
    # Independent: numpy's eigenvalues of the returned A.
    ours = np.sort_complex(got["eigenvalues"])
    theirs = np.sort_complex(np.linalg.eigvals(got["a"]))
    # The repeated zero eigenvalues (north, east, psi) are defective: a rounding perturbation
    # moves them by ~sqrt(eps)·|A|, so they agree to 1e-5 and the others far better.
    np.testing.assert_allclose(ours, theirs, atol=1e-5)


def test_trim_error_message_equals_cli():
    expected = cli_error("f16", "trim", "--alt-ft", "0", "--vt-fps", "500", "--xcg", "7")
    with pytest.raises(aeroident.AeroidentError) as e:
        aeroident.trim(alt_ft=0, vt_fps=500, xcg=7)
    assert str(e.value) == expected


def test_simulate_equals_cli(tmp_path):
    scenario = ROOT / "scenarios" / "sim" / "elevator_doublet.toml"
    r = cli("f16", "sim", scenario, "--out", tmp_path)
    assert r.returncode == 0, r.stderr
    with open(tmp_path / "timeseries.csv", newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], np.array(rows[1:], dtype=np.float64)
    got = aeroident.simulate(scenario, textbook=True)
    assert list(got) == header
    for j, name in enumerate(header):
        # timeseries.csv holds 11 significant digits ({:.10e}): equal to that precision.
        np.testing.assert_allclose(got[name], body[:, j], rtol=6e-11, atol=0, err_msg=name)
    # Independent: a uniform time grid from 0.
    dt = np.diff(got["t_s"])
    np.testing.assert_allclose(dt, dt[0], rtol=1e-9)
    assert got["t_s"][0] == 0.0
    # SI by default: each textbook column converted by the exact foot, pound-force or psf,
    # renamed by its unit; the others as they are.
    si = aeroident.simulate(scenario)
    assert len(si) == len(got)
    factors = {"_fps2": ("_mps2", M_PER_FT), "_fps": ("_mps", M_PER_FT), "_ft": ("_m", M_PER_FT),
               "_psf": ("_pa", PA_PER_PSF), "_lbf": ("_n", N_PER_LBF)}
    converted = 0
    for name, col in got.items():
        suffix = next((k for k in factors if name.endswith(k)), None)
        if suffix is None:
            np.testing.assert_array_equal(si[name], col, err_msg=name)
            continue
        new, factor = factors[suffix]
        np.testing.assert_allclose(si[name[: -len(suffix)] + new], col * factor, rtol=1e-15, atol=0, err_msg=name)
        converted += 1
    assert {"vt_mps", "alt_m", "qbar_pa", "thrust_n", "ax_mps2"} <= set(si) and converted >= 10


def test_simulate_missing_file():
    expected = cli_error("f16", "sim", "no/such/scenario.toml", "--out", "/tmp/aeroident-py-nowhere")
    with pytest.raises(aeroident.AeroidentError) as e:
        aeroident.simulate("no/such/scenario.toml")
    assert str(e.value) == expected
