#!/usr/bin/env python3
"""Before/after behaviour check of a refactoring: run two `aeroident` binaries on the shipped
scenarios, the proof-of-concept cases and replays of the shipped flight records, and compare
every number of every `summary.json` (estimates, sigma, ...) to a relative tolerance.

Usage:
    scripts/compare_behaviour.py --base BIN_BEFORE --new BIN_AFTER [--base-root CHECKOUT]
        [--out DIR] [--rtol 1e-9] [--flip Cl_da,Cn_da,CY_da] [--only run,poc,replay]
        [--base-schema 1]

`--base-schema 1` reads the base's `summary.json` in the key set before `schema_version: 2`
(docs/output-schema.md): its renamed keys are compared under their new names, and the keys
schema 2 added (the per-parameter verdict and its σ source) are not compared.

`--flip NAMES` expects those parameters (and their reference values) to change sign exactly on
the replays whose mapping convention changed; every other number must agree within `--rtol`
(relative, with an absolute floor of rtol * 1e-6 for numbers that are zero in both). Keys that
are wall-clock times, paths or throughput are ignored. Exit 0 when everything agrees.

The base binary runs in `--base-root` (default: this checkout), so that it reads its own
mappings and scenarios. Build a base binary and its checkout from a commit with, e.g.:
    git worktree add /tmp/base <commit> && cargo build --release -p aeroident \
        --manifest-path /tmp/base/Cargo.toml --target-dir /tmp/base-target
"""
import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SHARED = ROOT.parent / "shared" / "flightdata"
HA = SHARED / "jategaonkar_hfb320_attas"
TO = SHARED / "sidpac_twin_otter"
JS = SHARED / "jsbsim_samples"
PX = SHARED / "px4_ardupilot"

# (name, record, mapping, extra arguments); every real-time case runs the default estimator.
REPLAYS = [
    ("hfb320_rls", HA / "hfb320_1_10.asc", "mappings/hfb320.toml",
     ["--model", "models/hfb320_book_q0.toml"]),
    ("hfb320_ftr", HA / "csv/hfb320_1_10.csv", "mappings/hfb320.toml",
     ["--model", "models/hfb320_book_q0.toml", "--estimator", "ftr"]),
    ("hfb320_ekf", HA / "csv/hfb320_1_10.csv", "mappings/hfb320.toml",
     ["--model", "models/hfb320_book_q0.toml", "--estimator", "ekf"]),
    ("hfb320_oe", HA / "csv/hfb320_1_10.csv", "mappings/hfb320.toml",
     ["--model", "models/hfb320_jategaonkar.toml", "--estimator", "oe"]),
    ("hfb320_fem", HA / "csv/hfb320_1_10.csv", "mappings/hfb320.toml",
     ["--model", "models/hfb320_book_q0.toml", "--estimator", "fem"]),
    ("attas_elv_validate", HA / "fAttasElv1.mat", "mappings/attas.toml",
     ["--validate-on", str(HA / "fAttasElv2.mat")]),
    ("attas_ailrud_oe", HA / "csv/fAttasAilRud1.csv", "mappings/attas_lateral.toml",
     ["--estimator", "oe", "--initial-states", "estimate"]),
    ("attas_ailrud_rls", HA / "csv/fAttasAilRud1.csv", "mappings/attas_lateral.toml", []),
    ("attas_ailrud_ekf", HA / "csv/fAttasAilRud1.csv", "mappings/attas_lateral.toml",
     ["--estimator", "ekf"]),
    ("attas_elv1_oe_boot", HA / "fAttasElv1.mat", "mappings/attas.toml",
     ["--estimator", "oe", "--initial-states", "estimate", "--bootstrap", "8"]),
    ("twin_otter_rls", TO / "csv/totter_lon_020213f1_018.csv", "mappings/twin_otter.toml", []),
    ("twin_otter_oe", TO / "csv/totter_lon_020213f1_018.csv", "mappings/twin_otter.toml",
     ["--estimator", "oe"]),
    ("jsbsim_lat_rls", JS / "f16_ail_rud_doublets_20s_60Hz.csv", "mappings/jsbsim.toml",
     ["--model", "lateral"]),
    ("jsbsim_lon_smpe", SHARED / "jsbsim_f16_sample/f16_doublet_20s_120Hz.csv",
     "mappings/jsbsim_clean.toml", ["--model", "longitudinal", "--estimator", "smpe-corrected"]),
    ("px4_ulog", PX / "f16capstone_log_52_2021-5-22-12-42-56.ulg", "mappings/px4-fixedwing.toml",
     []),
    ("ardupilot_bin", PX / "pyflightcoach_center_0003.bin", "mappings/arduplane-minimal.toml", []),
]

IGNORED_KEYS = {
    "wall_s", "wall_time_s", "elapsed_s", "throughput_samples_per_s", "real_time_factor",
    "path", "file", "out", "output", "created", "timestamp", "version", "git",
    "input", "log", "source", "mapping", "map", "model_file", "cpu_s",
}


# Schema 1 → 2: the per-parameter keys renamed (docs/output-schema.md).
RENAMED_1_TO_2 = {
    "final": "estimate", "sigma": "std_error", "truth": "reference",
    "crb_sigma": "crb_std_error", "coloured_sigma": "coloured_std_error",
    "prewhitened_sigma": "prewhitened_std_error", "bootstrap_sigma": "bootstrap_std_error",
    "mean_sigma": "mean_std_error", "crb_sigma_calm": "crb_std_error_calm",
}
# Keys schema 2 added, absent from a schema-1 base.
ADDED_IN_2 = {
    "schema_version", "std_error", "std_error_source", "crb_std_error", "reference", "flags",
}


def upgrade(v, in_parameters=False):
    """A schema-1 document in schema-2 keys: renamed keys; a run entry's estimator `status` is
    `estimator_status` (schema 2's `status` is the verdict)."""
    if isinstance(v, list):
        return [upgrade(x, in_parameters) for x in v]
    if not isinstance(v, dict):
        return v
    out = {}
    for k, x in v.items():
        k2 = RENAMED_1_TO_2.get(k, k) if in_parameters else k
        if in_parameters and k == "status" and "quantity" in v:
            k2 = "estimator_status"
        out[k2] = upgrade(x, in_parameters or k in ("parameters", "params"))
    return out


# Substrings of keys that measure the machine, not the estimate.
VOLATILE = ("wall", "realtime_factor", "real_time_factor", "throughput", "elapsed", "_per_s")


def run(binary, args, cwd):
    p = subprocess.run([binary, *args], cwd=cwd, capture_output=True, text=True)
    return p.returncode, p.stdout[-2000:] + p.stderr[-2000:]


def flip_matrix(m, names, flipped):
    """`m[i][j]` of a parameter matrix (correlations) negated where exactly one of parameters
    i, j is flipped."""
    f = [n in flipped for n in names]
    return [[(-v if f[i] != f[j] and isinstance(v, (int, float)) else v)
             for j, v in enumerate(row)] for i, row in enumerate(m)]


def compare(a, b, path, rtol, flip, diffs):
    if isinstance(a, dict) and isinstance(b, dict):
        if flip.get("base_schema") == 1:
            # A schema-1 base has no verdict, σ source or version: those keys are new ones.
            b = {k: v for k, v in b.items()
                 if k in a or (k not in ADDED_IN_2 and k != "status")}
        names = flip.get("names", ())
        if names and isinstance(b.get("names"), list) and isinstance(b.get("rho"), list):
            b = dict(b, rho=flip_matrix(b["rho"], b["names"], names))
        for k in sorted(set(a) | set(b)):
            if k in IGNORED_KEYS or any(w in k for w in VOLATILE):
                continue
            if k not in a or k not in b:
                diffs.append(f"{path}.{k}: only in {'base' if k in a else 'new'}")
                continue
            compare(a[k], b[k], f"{path}.{k}", rtol, flip, diffs)
        return
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            diffs.append(f"{path}: length {len(a)} vs {len(b)}")
            return
        for i, (x, y) in enumerate(zip(a, b)):
            # A parameter row carries its name: flip its numbers when the name is in `flip`.
            sub_flip = flip
            names = flip.get("names", ())
            if isinstance(x, dict) and x.get("name") in names:
                sub_flip = dict(flip, active=True)
            # A correlation of a flipped parameter with an unflipped one flips too.
            if isinstance(x, dict) and (x.get("a") in names) != (x.get("b") in names):
                sub_flip = dict(flip, active=True, signed=("rho",))
            compare(x, y, f"{path}[{i}]", rtol, sub_flip, diffs)
        return
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        x, y = float(a), float(b)
        if flip.get("active") and path.rsplit(".", 1)[-1] in flip.get("signed", ()):
            y = -y
        if math.isnan(x) and math.isnan(y):
            return
        if abs(x - y) > rtol * max(abs(x), abs(y), 1e-6):
            diffs.append(f"{path}: {a!r} vs {b!r}")
        return
    if a != b:
        diffs.append(f"{path}: {str(a)[:80]!r} vs {str(b)[:80]!r}")


def summaries(d):
    return sorted(p.relative_to(d) for p in Path(d).rglob("*.json"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", required=True)
    ap.add_argument("--new", required=True)
    ap.add_argument("--out", default="/tmp/aeroident-compare")
    ap.add_argument("--rtol", type=float, default=1e-9)
    ap.add_argument("--flip", default="", help="parameter names that flip sign on replays")
    ap.add_argument("--only", default="run,poc,replay")
    ap.add_argument("--base-schema", type=int, default=2,
                    help="1: the base writes the key set before schema_version 2")
    ap.add_argument("--base-root", default=str(ROOT),
                    help="checkout the base binary runs in (its own mappings, models, scenarios)")
    a = ap.parse_args()
    only = set(a.only.split(","))
    out = Path(a.out)
    jobs = []
    if "run" in only:
        jobs.append(("run_all", ["run", "--all", "--no-figures", "--out", "{d}"], {}))
        jobs.append(("run_default", ["run", "--no-figures", "--out", "{d}"], {}))
    if "poc" in only:
        jobs.append(("poc_all", ["poc", "--all", "--out", "{d}"], {}))
    if "replay" in only:
        if not SHARED.is_dir():
            sys.exit(f"{SHARED} is absent: the replays need the shared flight records")
        flip = {"names": [n for n in a.flip.split(",") if n],
                "signed": ("value", "estimate", "reference", "truth", "final", "mean")}
        for name, rec, mp, extra in REPLAYS:
            args = ["replay", str(rec), "--map", mp, *extra, "--out", "{d}"]
            jobs.append((name, args, flip))
    failures = 0
    for name, args, flip in jobs:
        results = {}
        for side, binary, cwd in (("base", a.base, a.base_root), ("new", a.new, ROOT)):
            d = out / side / name
            subprocess.run(["rm", "-rf", str(d)])
            d.mkdir(parents=True)
            rc, log = run(os.path.abspath(binary), [x.format(d=d) for x in args], cwd)
            results[side] = (rc, d, log)
        (rb, db, lb), (rn, dn, ln) = results["base"], results["new"]
        diffs = []
        if rb != rn:
            diffs.append(f"exit {rb} vs {rn}\n{lb}\n{ln}")
        files_b, files_n = summaries(db), summaries(dn)
        if files_b != files_n:
            diffs.append(f"json files differ: {files_b} vs {files_n}")
        for f in set(files_b) & set(files_n):
            jb = json.loads((db / f).read_text())
            jn = json.loads((dn / f).read_text())
            if a.base_schema == 1:
                jb = upgrade(jb)
            compare(jb, jn, str(f), a.rtol, dict(flip, base_schema=a.base_schema), diffs)
        status = "same" if not diffs else f"{len(diffs)} differences"
        print(f"{name:24s} exit {rb}/{rn}  {len(files_b)} json  {status}", flush=True)
        for d in diffs[:15]:
            print("    " + d)
        failures += bool(diffs)
    print(f"{len(jobs) - failures} passed, {failures} failed")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
