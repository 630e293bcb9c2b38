"""Monte Carlo: the local backend equals `aeroident montecarlo --json`; the Ray backend's
per-run results are bit-identical to the local ones for the same seeds."""

from __future__ import annotations

import json
import math
import os

import pytest

import aeroident
from conftest import ROOT, cli

SHORT = ROOT / "scenarios" / "montecarlo" / "short.toml"


def same(a, b) -> bool:
    """Exact equality of JSON-like values, NaN equal to NaN."""
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    return a == b


def test_local_equals_cli_json():
    r = cli("montecarlo", SHORT, "--runs", "3", "--seed", "7", "--json")
    assert r.returncode == 0, r.stderr
    expected = json.loads(r.stdout)
    got = aeroident.montecarlo(SHORT, runs=3, seed=7)
    assert got.keys() == expected.keys()
    assert got["runs"] == 3
    for eg, ee in zip(got["estimators"], expected["estimators"], strict=True):
        assert eg["name"] == ee["name"]
        for pg, pe in zip(eg["parameters"], ee["parameters"], strict=True):
            for k, v in pe.items():
                if isinstance(v, float):
                    assert pg[k] == pytest.approx(v, rel=1e-12, abs=1e-300), (eg["name"], pg["name"], k)
                else:
                    assert pg[k] == v, (eg["name"], pg["name"], k)


def test_default_scenario_and_errors():
    with pytest.raises(aeroident.AeroidentError, match="runs must be at least 1"):
        aeroident.montecarlo(runs=0)
    with pytest.raises(aeroident.AeroidentError, match="backend"):
        aeroident.montecarlo(SHORT, runs=1, backend="spark")
    r = cli("montecarlo", "no/such.toml", "--runs", "1", "--json")
    expected = [l for l in r.stderr.splitlines() if l.startswith("error: ")][-1][len("error: "):]
    with pytest.raises(aeroident.AeroidentError) as e:
        aeroident.montecarlo("no/such.toml", runs=1)
    assert str(e.value) == expected


def test_statistics_reduce_from_per_run_results():
    """The reduction used by the Ray backend, fed the local per-run results, gives the local
    statistics (and each per-run result is the seed rule's: run i's sensor seed)."""
    from aeroident import _aeroident as core

    local = aeroident.montecarlo(SHORT, runs=3, seed=11, per_run=True)
    text, origin = core.scenario_text(str(SHORT))
    reduced = core.montecarlo_reduce(text, origin, 3, 11, list(reversed(local["per_run"])))
    assert same(reduced["estimators"], local["estimators"])
    assert [r["index"] for r in local["per_run"]] == [0, 1, 2]
    assert len({r["sensor_seed"] for r in local["per_run"]}) == 3
    chunk = core.montecarlo_runs(text, origin, 11, 1, 3, 1)
    assert same(chunk, local["per_run"][1:])
    with pytest.raises(aeroident.AeroidentError, match="one result for each run"):
        core.montecarlo_reduce(text, origin, 4, 11, local["per_run"])


def test_ray_backend_is_bit_identical_to_local():
    try:
        import ray
    except ImportError:
        if os.environ.get("CI") == "true":
            pytest.fail("ray is not installed; CI installs it (pip install ./crates/python[ray])")
        pytest.skip('ray not installed (pip install "./crates/python[ray]")')
    runs, seed = 6, 3
    local = aeroident.montecarlo(SHORT, runs=runs, seed=seed, per_run=True)
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        remote = aeroident.montecarlo(SHORT, runs=runs, seed=seed, backend="ray", chunk_size=2, per_run=True)
    finally:
        ray.shutdown()
    assert same(remote["per_run"], local["per_run"])
    assert same(remote["estimators"], local["estimators"])
    assert remote["runs"] == runs
