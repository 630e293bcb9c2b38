"""Shared helpers: the repository root, the third-party data in ../shared (skipped when absent,
a failure under CI=true), and the CLI (`cargo run --release -p aeroident`, or $AEROIDENT_BIN)."""

from __future__ import annotations

import csv
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[3]
SHARED = ROOT.parent / "shared" / "flightdata"


def shared(rel: str) -> Path:
    """A file under ../shared/flightdata; skip (or fail under CI=true) when it is absent."""
    p = SHARED / rel
    if not p.exists():
        msg = f"third-party data {p} absent (../shared not beside the checkout)"
        if os.environ.get("CI") == "true":
            pytest.fail(msg + "; CI must have it")
        pytest.skip(msg)
    return p


def cli(*args: str) -> subprocess.CompletedProcess:
    """Runs the `aeroident` CLI with `args` (no check; stdout and stderr captured as text)."""
    exe = os.environ.get("AEROIDENT_BIN")
    cmd = [exe] if exe else ["cargo", "run", "--release", "-q", "--manifest-path", str(ROOT / "Cargo.toml"), "-p", "aeroident", "--"]
    return subprocess.run(cmd + [str(a) for a in args], capture_output=True, text=True, cwd=ROOT)


def cli_error(*args: str) -> str:
    """The CLI's error message (stderr's `error: ` line, prefix removed); the run must fail."""
    r = cli(*args)
    assert r.returncode != 0, f"CLI succeeded: {args}"
    lines = [l for l in r.stderr.splitlines() if l.startswith("error: ")]
    assert lines, r.stderr
    return lines[-1][len("error: "):]


def read_estimates_csv(path: Path) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
    """`estimates.csv` of `aeroident replay`: names, t_s, estimates, sigma (empty → NaN)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    n = (len(header) - 1) // 2
    names = header[1 : 1 + n]
    m = np.array([[float(x) if x != "" else np.nan for x in r] for r in body], dtype=np.float64).reshape(len(body), 2 * n + 1)
    return names, m[:, 0], m[:, 1 : 1 + n], m[:, 1 + n :]


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT
