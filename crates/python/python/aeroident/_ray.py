"""The Ray backend of :func:`aeroident.montecarlo` (optional: ``pip install "aeroident[ray]"``).

Each task runs a contiguous chunk of run indices with the Rust campaign code
(``_aeroident.montecarlo_runs``) on the CPUs it reserved and returns the per-run results (plain
dicts of floats, ints and strings: pickled exactly); the driver reduces them with
``_aeroident.montecarlo_reduce`` (the statistics of ``aeroident montecarlo``).
"""

from __future__ import annotations

import math
import time
from typing import Any, Optional

from . import _aeroident as _core
from ._aeroident import AeroidentError


def _run_chunk(text: str, origin: str, seed: int, start: int, stop: int, threads: int) -> list:
    from aeroident import _aeroident

    return _aeroident.montecarlo_runs(text, origin, seed, start, stop, threads)


def montecarlo_ray(
    text: str, origin: str, runs: int, seed: int, chunk_size: Optional[int], per_run: bool
) -> dict[str, Any]:
    try:
        import ray
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise AeroidentError(
            'backend="ray" needs Ray: pip install "aeroident[ray]" (from the checkout: pip install "./crates/python[ray]")'
        ) from e
    if not ray.is_initialized():
        ray.init()
    cpus = max(1, int(ray.cluster_resources().get("CPU", 1)))
    chunk = chunk_size or max(1, math.ceil(runs / (4 * cpus)))
    task = ray.remote(num_cpus=1)(_run_chunk)
    start = time.perf_counter()
    refs = [task.remote(text, origin, seed, a, min(a + chunk, runs), 1) for a in range(0, runs, chunk)]
    results = [r for part in ray.get(refs) for r in part]
    wall_s = time.perf_counter() - start
    return _core.montecarlo_reduce(text, origin, runs, seed, results, wall_s, cpus, per_run)
