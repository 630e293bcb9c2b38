"""aeroident.freqresp against a discrete system whose response is known exactly."""

from __future__ import annotations

import numpy as np
import pytest

import aeroident

DT = 0.02
A, G = 0.95, -2.0  # q[k] = A q[k-1] + G (1 - A) de[k-1], de in rad

MAP = """nominal_dt_s = 0.02
[time]
column = "t"
unit = "s"
[channels]
vt = { column = "V", unit = "m/s" }
alpha = { column = "a", unit = "rad" }
q = { column = "q", unit = "rad/s" }
de = { column = "de", unit = "deg" }
rho = { value = 1.0, unit = "kg/m3" }
mass = { value = 1000.0, unit = "kg" }
S = { value = 10.0, unit = "m2" }
cbar = { value = 1.5, unit = "m" }
Iyy = { value = 2000.0, unit = "kg*m2" }
"""


@pytest.fixture()
def record(tmp_path):
    rng = np.random.default_rng(3)
    de_deg = rng.standard_normal(6000)
    q = np.zeros_like(de_deg)
    for k in range(1, len(q)):
        q[k] = A * q[k - 1] + G * (1 - A) * np.radians(de_deg[k - 1])
    rows = ["t,V,a,q,de"] + [f"{k * DT:.2f},50,0.05,{q[k]:.9e},{de_deg[k]:.9e}" for k in range(len(q))]
    (tmp_path / "r.csv").write_text("\n".join(rows) + "\n")
    (tmp_path / "m.toml").write_text(MAP)
    return tmp_path / "r.csv", tmp_path / "m.toml"


def test_response_matches_the_exact_one(record):
    data, mapping = record
    r = aeroident.freqresp(data, map=mapping, input="de", output="q", fit="q/de:0/1")
    p = r["pairs"][0]
    assert (p["input"], p["output"], r["stretches"]) == ("de", "q", 1)
    z1 = np.exp(-2j * np.pi * p["frequency_hz"] * DT)
    exact = G * (1 - A) * z1 / (1 - A * z1)
    assert isinstance(p["magnitude_db"], np.ndarray)
    np.testing.assert_allclose(p["magnitude_db"], 20 * np.log10(np.abs(exact)), atol=0.3)
    dphase = (p["phase_deg"] - np.degrees(np.angle(exact)) + 180) % 360 - 180
    assert np.max(np.abs(dphase)) < 2.0
    assert np.min(p["coherence"]) > 0.99
    pole = r["fits"][0]["poles"][0]
    assert abs(pole["wn_rad_s"] / (-np.log(A) / DT) - 1) < 0.05


def test_unmapped_channel_is_named(record):
    data, mapping = record
    with pytest.raises(aeroident.AeroidentError, match="`p` is not in the record"):
        aeroident.freqresp(data, map=mapping, input="de", output="p")


@pytest.mark.parametrize(
    "keywords, message",
    [
        (dict(points_per_decade=10**12), r"`--points-per-decade`: 1\.000e12 is outside \[1, 1000\]"),
        (dict(points_per_decade=2**64 - 1), r"`--points-per-decade`: 1\.845e19 is outside"),
        (dict(min_coherence=float("nan")), r"`--min-coherence`: NaN is not a coherence"),
        (dict(f_max_hz=30.0), r"`--f-max-hz`: 30 Hz must lie above"),
        (dict(windows_s=[500.0]), r"`--windows-s`: 500 s is longer"),
    ],
)
def test_options_out_of_range_are_refused_naming_them(record, keywords, message):
    # 10^12 points per decade once aborted the interpreter on a 24.7 TB allocation.
    data, mapping = record
    with pytest.raises(aeroident.AeroidentError, match=message):
        aeroident.freqresp(data, map=mapping, input="de", output="q", **keywords)
