#!/usr/bin/env python3
"""Calibration corpus of the per-parameter verdicts: how far `identified` can be trusted.

Records with a known truth are flown by JSBSim (`../shared/tools/jsbsim_log.py`, driven by
`fly.py` for composite inputs), degraded the way real logs are, replayed through
`aeroident replay` with every estimator, and each primary derivative's verdict is set against
its truth, on a split by aircraft: the 'tune' aircraft may be looked at while tuning the
verdict rules, the 'held-out' ones only to measure them. Not run in CI. See README.md.

    corpus.py make   --out DIR [--python PY] [--limit N] [--jobs J]
    corpus.py run    --out DIR [--bin PATH] [--estimators rls,rls-iv,ftr,ekf,oe,fem,fdoe]
                     [--jobs J] [--tag NAME] [--extra-args "..."] [--limit N]
    corpus.py report --out DIR [--half tune|held-out|all] [--tag NAME] [--markdown FILE]
    corpus.py design [--limit N]          (the design table, without flying anything)

Everything is deterministic (seeded by SEED and the record's name) and resumable: `make`
skips records whose meta.json exists (and records that failed before, unless
--retry-failed), `run` skips replays whose run.json exists. Standard library only.
"""
import argparse
import concurrent.futures as cf
import csv
import hashlib
import json
import math
import os
import random
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from collections import Counter, defaultdict
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
TOOL = ROOT.parent / "shared" / "tools" / "jsbsim_log.py"
FLY = HERE / "fly.py"
MAP = ROOT / "mappings" / "jsbsim.toml"
DEFAULT_PY = "/tmp/aeroident-ci-venv-jsbsim/bin/python"
DEFAULT_BIN = str(ROOT / "target" / "release" / "aeroident")
ESTIMATORS = "rls,rls-iv,ftr,ekf,oe,fem,fdoe"

SEED = 20251128          # the design's seed: change it and every record changes
RATE, LOG_RATE = 120, 60  # Hz: simulation, CSV rows (the shared samples' rates)
PER_CONDITION = 7        # records per (aircraft, flight condition)

PRIMARY = ["Cm_alpha", "Cm_q", "Cm_de", "CL_alpha", "Cl_beta", "Cl_p", "Cl_da", "Cn_beta",
           "Cn_r", "Cn_dr", "CY_beta"]
LON_PRIMARY = {"Cm_alpha", "Cm_q", "Cm_de", "CL_alpha"}

# ---------------------------------------------------------------------------------------
# aircraft, classes, conditions and the split
# ---------------------------------------------------------------------------------------
# (name, class, half, three flight conditions (alt ft, true airspeed ft/s)). Each condition
# has two fallbacks (the same altitude, 15 % slower, then 15 % faster) flown when it does not
# trim or its calibration doublets depart.
# The split: in each class half the aircraft are 'tune', half 'held-out'. The aircraft the
# developers already know (the shared samples c172x and f16; the 737 of the audits and docs)
# are 'tune'; sibling models (c172x/c172p) sit in the same half. No UAV-like model of the
# jsbsim 1.3.3 wheel trims (F450 is a quadrotor, minisgs/SGS are gliders: "Trim Failed"),
# so the J3Cub (765 lb empty) stands for the small, slow end.
AIRCRAFT = [
    ("c172x", "light", "tune", [(2500, 140), (4500, 165), (7500, 195)]),
    ("c172p", "light", "tune", [(3000, 145), (6000, 175), (8000, 200)]),
    ("pa28", "light", "held-out", [(2000, 140), (5000, 170), (7000, 185)]),
    ("J3Cub", "light", "held-out", [(1000, 90), (2500, 105), (4000, 120)]),
    ("DHC6", "turboprop", "tune", [(3000, 150), (6000, 190), (10000, 230)]),
    ("t6texan2", "turboprop", "held-out", [(6000, 200), (10000, 280), (15000, 350)]),
    ("f16", "jet", "tune", [(8000, 500), (15000, 650), (25000, 800)]),
    ("T38", "jet", "tune", [(10000, 500), (20000, 700), (30000, 850)]),
    ("A4", "jet", "tune", [(5000, 450), (15000, 600), (25000, 750)]),
    ("f15", "jet", "held-out", [(10000, 550), (20000, 700), (30000, 850)]),
    ("T37", "jet", "held-out", [(5000, 300), (10000, 400), (15000, 450)]),
    ("F4N", "jet", "held-out", [(10000, 500), (20000, 700), (30000, 850)]),
    ("737", "transport", "tune", [(10000, 450), (20000, 600), (33000, 780)]),
    ("global5000", "transport", "tune", [(10000, 400), (25000, 600), (40000, 750)]),
    ("B747", "transport", "tune", [(10000, 450), (25000, 650), (35000, 800)]),
    ("A320", "transport", "held-out", [(10000, 420), (25000, 600), (35000, 780)]),
    ("MD11", "transport", "held-out", [(12000, 450), (25000, 620), (35000, 790)]),
    ("787-8", "transport", "held-out", [(10000, 450), (25000, 650), (38000, 800)]),
]
AC = {a[0]: a for a in AIRCRAFT}

# Per class: doublet half-widths / 3211 unit (s) of elevator, aileron, rudder; the settling
# time after a manoeuvre (s); the multisine period and band; the chirp band; the response the
# amplitudes aim at (peak |Δα| deg, |p| deg/s, |β| deg; calibrated per condition, below).
CLASS = {
    "light": dict(w=(0.3, 0.5, 0.6), settle=6.0, ms_T=10.0, ms_band=(0.1, 1.5),
                  chirp=(0.15, 1.5, 10.0), target=(2.0, 12.0, 2.5)),
    "turboprop": dict(w=(0.35, 0.6, 0.7), settle=6.0, ms_T=10.0, ms_band=(0.1, 1.5),
                      chirp=(0.15, 1.5, 10.0), target=(2.0, 12.0, 2.5)),
    "jet": dict(w=(0.25, 0.4, 0.6), settle=5.0, ms_T=8.0, ms_band=(0.125, 2.0),
                chirp=(0.2, 2.0, 9.0), target=(1.5, 15.0, 2.0)),
    "transport": dict(w=(0.6, 0.8, 1.0), settle=8.0, ms_T=15.0, ms_band=(0.067, 1.0),
                      chirp=(0.08, 1.0, 14.0), target=(1.5, 8.0, 2.0)),
}
# free-play take-up pulse after each elevator input (jsbsim_log.py --elevator-recenter): the
# c172x elevator actuator has 0.05 rad hysteresis
RECENTER = {"c172x": {"elevator": 0.0623}}
SURF = ("elevator", "aileron", "rudder")

# ---------------------------------------------------------------------------------------
# the design
# ---------------------------------------------------------------------------------------
AXES = ["lon"] * 8 + ["lat"] * 8 + ["six"] * 5           # per aircraft (21 records)
KINDS = ["3211", "doublet", "multisine", "chirp", "pilot"]
MANOEUVRES = [1, 1, 2, 2, 3]
NOISE = [0.0, 0.5, 1.0, 2.0, 4.0]                          # --noise-scale of 'typical'
DEGRADATIONS = ["bias", "scale", "time_shift", "ahrs_lag", "servo", "no_beta", "no_thrust",
                "log_10hz", "spikes"]
DEGR_LIST = ["none"] * 3 + DEGRADATIONS * 2               # per aircraft (21 records)
MODEL = {"lon": "longitudinal", "lat": "lateral", "six": "six-axis"}
KIND_GAIN = {"doublet": 1.0, "3211": 0.7, "multisine": 0.9, "chirp": 0.6, "pilot": 0.8}


def _cycle(levels, n, offset):
    return [levels[(i + offset) % len(levels)] for i in range(n)]


def design():
    """Every record of the corpus, in flying order (a round robin over the aircraft, so that
    `--limit N` takes a spread of aircraft, conditions and factors). Deterministic."""
    per_ac = []
    for ai, (ac, cls, half, conds) in enumerate(AIRCRAFT):
        n = len(conds) * PER_CONDITION
        rng = random.Random("%d/design/%s" % (SEED, ac))
        axes = AXES[:n] + ["lon"] * max(0, n - len(AXES))
        factors = {
            "axis": axes,
            "kind": _cycle(KINDS, n, ai),
            "manoeuvres": _cycle(MANOEUVRES, n, ai),
            "noise": _cycle(NOISE, n, 2 * ai),
            "degradation": (DEGR_LIST * 2)[:n],
        }
        for k in factors:
            rng.shuffle(factors[k])
        # 'no_beta' only where the model reads β (lateral, six-axis): swap it with a
        # degradation of a lateral/six record that a longitudinal record can take
        ax, dg = factors["axis"], factors["degradation"]
        for i in range(n):
            if ax[i] == "lon" and dg[i] == "no_beta":
                j = rng.choice([j for j in range(n) if ax[j] != "lon" and dg[j] != "no_beta"])
                dg[i], dg[j] = dg[j], dg[i]
        recs = []
        for i in range(n):
            cond = i % len(conds)
            idx = i // len(conds)
            rid = "%s-c%d-%d" % (ac, cond, idx)
            recs.append({
                "id": rid, "aircraft": ac, "class": cls, "half": half, "cond": cond,
                "alt_ft": conds[cond][0], "vt_fps": conds[cond][1],
                "axis": ax[i], "model": MODEL[ax[i]], "kind": factors["kind"][i],
                "manoeuvres": factors["manoeuvres"][i], "noise_scale": factors["noise"][i],
                "degradation": dg[i],
            })
        per_ac.append(recs)
    out = []
    for j in range(max(len(r) for r in per_ac)):
        for recs in per_ac:
            if j < len(recs):
                out.append(recs[j])
    return out


def record_name(d):
    return "%s-%s-%s-m%d-n%g-%s" % (d["id"], d["axis"], d["kind"], d["manoeuvres"],
                                   d["noise_scale"], d["degradation"])


# ---------------------------------------------------------------------------------------
# flying
# ---------------------------------------------------------------------------------------
def fly(py, spec, workdir, timeout=600):
    """Run fly.py on `spec`; returns (ok, message)."""
    sp = Path(workdir) / "spec.json"
    sp.write_text(json.dumps(spec, indent=1))
    try:
        p = subprocess.run([py, str(FLY), str(sp)], capture_output=True, text=True,
                           timeout=timeout)
    except subprocess.TimeoutExpired:
        return False, "fly.py timed out after %d s" % timeout
    if p.returncode != 0:
        lines = [l for l in (p.stderr + p.stdout).strip().splitlines() if l.strip()]
        return False, (lines[-1] if lines else "exit %d" % p.returncode)[:300]
    return True, p.stdout.strip().splitlines()[-1] if p.stdout.strip() else ""


def read_csv(path):
    with open(path, newline="") as fh:
        r = csv.reader(fh)
        header = next(r)
        rows = list(r)
    return header, rows


def column(header, rows, name):
    i = header.index(name)
    return [float(r[i]) for r in rows]


def response(header, rows, t_from=0.0):
    """Peak excursions of a record (clean columns): deg, deg/s; and the validity check."""
    t = column(header, rows, "time")
    get = {k: column(header, rows, k) for k in ("alpha_rad", "beta_rad", "phi", "theta", "p",
                                                "q", "r", "vt_fps")}
    a0, b0, th0, v0 = (get["alpha_rad"][0], get["beta_rad"][0], get["theta"][0],
                       get["vt_fps"][0])
    sel = [i for i in range(len(t)) if t[i] >= t_from]
    d = math.degrees
    out = {
        "dalpha_deg": max(d(abs(get["alpha_rad"][i] - a0)) for i in sel),
        "beta_deg": max(d(abs(get["beta_rad"][i] - b0)) for i in sel),
        "p_dps": max(d(abs(get["p"][i])) for i in sel),
        "q_dps": max(d(abs(get["q"][i])) for i in sel),
        "phi_deg": max(d(abs(get["phi"][i])) for i in sel),
        "dtheta_deg": max(d(abs(get["theta"][i] - th0)) for i in sel),
        "vt_ratio": (min(get["vt_fps"][i] for i in sel) / v0,
                     max(get["vt_fps"][i] for i in sel) / v0),
    }
    bad = []
    if any(not math.isfinite(v) for k in get for v in get[k]):
        bad.append("non-finite state")
    else:
        if out["dalpha_deg"] > 10:
            bad.append("|Δα| %.1f° > 10°" % out["dalpha_deg"])
        if out["beta_deg"] > 12:
            bad.append("|β| %.1f° > 12°" % out["beta_deg"])
        if out["phi_deg"] > 60:
            bad.append("|φ| %.0f° > 60°" % out["phi_deg"])
        if out["dtheta_deg"] > 35:
            bad.append("|Δθ| %.0f° > 35°" % out["dtheta_deg"])
        if not (0.6 <= out["vt_ratio"][0] and out["vt_ratio"][1] <= 1.4):
            bad.append("V %.2f..%.2f of trim (outside 0.6..1.4)" % out["vt_ratio"])
    out["departed"] = "; ".join(bad)
    return out


def base_args(ac, alt, vt, duration, out_csv, derivs=None, noise_scale=0.0, seed=0,
              log_rate=LOG_RATE):
    a = ["--aircraft", ac, "--alt", str(alt), "--vt", str(vt), "--rate", str(RATE),
         "--log-rate", str(log_rate), "--duration", "%.3f" % duration,
         "--noise-preset", "typical", "--noise-scale", "%g" % noise_scale,
         "--noise-seed", str(seed), "--coef-columns", "none", "--out", str(out_csv)]
    if derivs:
        a += ["--derivs-json", str(derivs)]
    return a


def calibrate(py, out, ac, cond):
    """Per (aircraft, condition): the response per unit command of a doublet on each surface
    (peak |Δα| deg, |p| deg/s, |β| deg) and the surface deflection per unit command (rad),
    flown at the condition or its fallback. Cached in DIR/calib/."""
    cache = Path(out) / "calib" / ("%s-c%d.json" % (ac, cond))
    if cache.exists():
        return json.loads(cache.read_text())
    _, cls, _, conds = AC[ac]
    alt, vt = conds[cond]
    tries = [(alt, vt), (alt, round(vt * 0.85)), (alt, round(vt * 1.15))]
    reasons = []
    result = None
    with tempfile.TemporaryDirectory(prefix="vc-calib-") as tmp:
        for alt_, vt_ in tries:
            gains, ok = {}, True
            for si, s in enumerate(SURF):
                w = CLASS[cls]["w"][si]
                amp = {"elevator": 0.05, "aileron": 0.05, "rudder": 0.1}[s]
                for attempt in range(3):
                    seg = {"kind": "doublet", "t0": 1.0, "amp": amp, "width": w}
                    if RECENTER.get(ac, {}).get(s):
                        seg["recenter"] = RECENTER[ac][s]
                    csvp = Path(tmp) / "c.csv"
                    spec = {"tool": str(TOOL), "inputs": {s: [seg]},
                            "args": base_args(ac, alt_, vt_, 1.0 + 2 * w + 6.0, csvp)}
                    okf, msg = fly(py, spec, tmp)
                    if not okf:
                        ok = False
                        reasons.append("%s ft %s ft/s: %s" % (alt_, vt_, msg))
                        break
                    h, rows = read_csv(csvp)
                    rsp = response(h, rows)
                    surf = column(h, rows, s + "_rad")
                    dsurf = max(abs(x - surf[0]) for x in surf)
                    peak = {"elevator": rsp["dalpha_deg"], "aileron": rsp["p_dps"],
                            "rudder": rsp["beta_deg"]}[s]
                    target = CLASS[cls]["target"][si]
                    if rsp["departed"]:
                        amp /= 4
                        continue
                    if peak < 0.05 * target and attempt < 2:
                        amp *= 5
                        continue
                    break
                if not ok:
                    break
                if rsp["departed"] or peak <= 0 or dsurf <= 0:
                    ok = False
                    reasons.append("%s ft %s ft/s: %s doublet: %s" % (
                        alt_, vt_, s, rsp["departed"] or "no response"))
                    break
                gains[s] = {"amp": amp, "response_per_cmd": peak / amp,
                            "surface_rad_per_cmd": dsurf / amp, "response": rsp}
            if ok:
                result = {"ok": True, "alt_ft": alt_, "vt_fps": vt_, "gains": gains,
                          "fallback": (alt_, vt_) != (alt, vt), "tried": reasons}
                break
    if result is None:
        result = {"ok": False, "reason": "; ".join(reasons)}
    cache.parent.mkdir(parents=True, exist_ok=True)
    cache.write_text(json.dumps(result, indent=1))
    return result


def build_inputs(d, cal, rng, amp_scale):
    """The record's input segments per surface and its manoeuvre windows."""
    cls = CLASS[d["class"]]
    kind = d["kind"]
    surfaces = {"lon": ["elevator"], "lat": ["aileron", "rudder"],
                "six": ["elevator", "aileron", "rudder"]}[d["axis"]]
    base_amp = {}
    for s in surfaces:
        si = SURF.index(s)
        g = cal["gains"][s]["response_per_cmd"]
        base_amp[s] = cls["target"][si] / g * KIND_GAIN[kind] * rng.uniform(0.7, 1.3)
    wf = rng.uniform(0.8, 1.25)
    inputs = {s: [] for s in SURF}
    windows = []
    t = 1.5
    for m in range(d["manoeuvres"]):
        start = t
        end_inputs = t
        mf = rng.uniform(0.85, 1.15)
        if kind == "multisine":
            T = cls["ms_T"]
            lo, hi = cls["ms_band"]
            ks = [k for k in range(1, int(hi * T) + 2) if lo - 1e-9 <= k / T <= hi + 1e-9]
            off = rng.randrange(len(surfaces))
            order = surfaces[off:] + surfaces[:off]
            for i, s in enumerate(order):
                inputs[s].append({"kind": "multisine", "t0": round(t, 3),
                                  "amp": base_amp[s] * mf * amp_scale, "T": T,
                                  "ks": ks[i::len(order)]})
            end_inputs = t + T
        else:
            for s in surfaces:
                si = SURF.index(s)
                w = cls["w"][si] * wf
                amp = base_amp[s] * mf * amp_scale * rng.choice((1, -1))
                seg = {"kind": kind, "t0": round(end_inputs, 3), "amp": amp}
                if kind in ("doublet", "3211"):
                    seg["width"] = round(w, 3)
                    length = (2 if kind == "doublet" else 7) * w
                elif kind == "chirp":
                    f0, f1, n = cls["chirp"]
                    seg.update(f0=round(f0 * rng.uniform(0.8, 1.2), 3),
                               f1=round(f1 * rng.uniform(0.8, 1.1), 3),
                               len=round(n * rng.uniform(0.85, 1.25), 2))
                    length = seg["len"]
                else:  # pilot: 2–4 irregular pulses, mostly alternating
                    pulses, x, sign = [], 0.0, 1.0
                    for _ in range(rng.randint(2, 4)):
                        dur = w * rng.uniform(0.6, 1.6)
                        a = abs(amp) * rng.uniform(0.6, 1.1) * sign
                        pulses.append([round(x, 3), round(dur, 3), a])
                        x += dur + 0.12 + rng.uniform(0.0, 0.6) * w
                        sign = -sign if rng.random() < 0.85 else sign
                    if amp < 0:
                        pulses = [[p[0], p[1], -p[2]] for p in pulses]
                    seg["pulses"] = pulses
                    length = x
                if RECENTER.get(d["aircraft"], {}).get(s):
                    seg["recenter"] = RECENTER[d["aircraft"]][s]
                inputs[s].append(seg)
                end_inputs += length + rng.uniform(1.5, 3.0)
        win_end = end_inputs + cls["settle"]
        windows.append([round(start - 0.8, 2), round(win_end, 2)])
        t = win_end + rng.uniform(2.0, 4.0) + 0.8
    duration = windows[-1][1] + 0.5
    return inputs, windows, duration


# ---------------------------------------------------------------------------------------
# degradations (post-processing of the noisy columns the mapping reads; the clean columns
# stay the simulator's truth)
# ---------------------------------------------------------------------------------------
def choose_degradation(d, rng, cal):
    kind = d["degradation"]
    lat = d["axis"] in ("lat", "six")
    lon = d["axis"] in ("lon", "six")
    P = {}
    if kind == "bias":
        pool = [("alpha_rad_noisy", math.radians(rng.uniform(0.5, 1.5)), "rad"),
                ("q_noisy", math.radians(rng.uniform(0.2, 0.5)), "rad/s"),
                ("p_noisy", math.radians(rng.uniform(0.2, 0.5)), "rad/s"),
                ("r_noisy", math.radians(rng.uniform(0.2, 0.5)), "rad/s"),
                ("nz_noisy", rng.uniform(0.01, 0.03), "g"),
                ("nx_noisy", rng.uniform(0.005, 0.02), "g"),
                ("ny_noisy", rng.uniform(0.005, 0.02), "g"),
                ("theta_noisy", math.radians(rng.uniform(0.5, 1.0)), "rad"),
                ("elevator_rad_noisy", math.radians(rng.uniform(0.3, 1.0)), "rad")]
        if lat:
            pool.append(("beta_rad_noisy", math.radians(rng.uniform(0.5, 1.0)), "rad"))
        P["bias"] = {c: v * rng.choice((1, -1)) for c, v, _ in rng.sample(pool, rng.randint(2, 3))}
    elif kind == "scale":
        pool = [("alpha_rad_noisy", rng.uniform(1.05, 1.15)),
                ("vt_fps_noisy", rng.uniform(0.97, 1.03)),
                ("qbar_psf_noisy", rng.uniform(0.95, 1.05)),
                ("q_noisy", rng.uniform(0.97, 1.03)), ("p_noisy", rng.uniform(0.97, 1.03)),
                ("r_noisy", rng.uniform(0.97, 1.03)), ("nz_noisy", rng.uniform(0.97, 1.03))]
        if lat:
            pool.append(("beta_rad_noisy", rng.uniform(1.05, 1.15)))
        P["scale"] = dict(rng.sample(pool, rng.randint(1, 2)))
    elif kind == "time_shift":
        pool = (["alpha_rad_noisy", "q_noisy", "nz_noisy", "elevator_rad_noisy"] if lon else []) + \
               (["beta_rad_noisy", "p_noisy", "r_noisy", "aileron_rad_noisy",
                 "rudder_rad_noisy"] if lat else [])
        P["delay_s"] = {rng.choice(pool): round(rng.uniform(0.03, 0.15), 3)}
    elif kind == "ahrs_lag":
        P["tau_s"] = round(rng.uniform(0.05, 0.2), 3)
        P["columns"] = ["phi_noisy", "theta_noisy", "psi_unwrap_noisy", "p_noisy", "q_noisy",
                        "r_noisy"]
    elif kind == "servo":
        P["tau_s"] = round(rng.uniform(0.05, 0.12), 3)
        P["rate_limit_deg_s"] = round(rng.uniform(20.0, 45.0), 1)
    elif kind == "spikes":
        pool = (["alpha_rad_noisy", "q_noisy", "nz_noisy", "theta_noisy"] if lon else []) + \
               (["beta_rad_noisy", "p_noisy", "r_noisy", "ny_noisy", "phi_noisy"] if lat else [])
        P["count"] = rng.randint(5, 20)
        P["columns"] = sorted(set(rng.sample(pool, min(len(pool), rng.randint(1, 3)))))
    elif kind == "log_10hz":
        P["log_rate_hz"] = 10
    elif kind == "no_beta":
        P["mapping"] = "beta line removed"
    elif kind == "no_thrust":
        P["mapping"] = "thrust and thrust_moment lines removed"
    return P


SPIKE_SIZE = {"alpha_rad_noisy": math.radians(5), "beta_rad_noisy": math.radians(4),
              "q_noisy": math.radians(15), "p_noisy": math.radians(20),
              "r_noisy": math.radians(10), "nz_noisy": 0.6, "ny_noisy": 0.3,
              "theta_noisy": math.radians(5), "phi_noisy": math.radians(8)}


def degrade(csv_path, d, P, rng, windows, servo_log=None):
    """Apply the degradation to the CSV in place; returns extra facts for meta.json."""
    kind = d["degradation"]
    facts = {}
    if kind in ("none", "no_beta", "no_thrust", "log_10hz"):
        return facts
    header, rows = read_csv(csv_path)
    col = {n: i for i, n in enumerate(header)}
    t = [float(r[col["time"]]) for r in rows]

    def get(c):
        return [float(r[col[c]]) for r in rows]

    def put(c, vals):
        i = col[c]
        for r, v in zip(rows, vals):
            r[i] = "%.9g" % v

    if kind == "bias":
        for c, b in P["bias"].items():
            put(c, [v + b for v in get(c)])
    elif kind == "scale":
        for c, s in P["scale"].items():
            put(c, [v * s for v in get(c)])
    elif kind == "time_shift":
        for c, delay in P["delay_s"].items():
            x = get(c)
            y = []
            for ti in t:
                tq = ti - delay
                if tq <= t[0]:
                    y.append(x[0])
                    continue
                j = min(int((tq - t[0]) * LOG_RATE), len(t) - 2)
                while j > 0 and t[j] > tq:
                    j -= 1
                while j < len(t) - 2 and t[j + 1] < tq:
                    j += 1
                f = (tq - t[j]) / (t[j + 1] - t[j])
                y.append(x[j] + f * (x[j + 1] - x[j]))
            put(c, y)
    elif kind == "ahrs_lag":
        a = 1.0 - math.exp(-1.0 / LOG_RATE / P["tau_s"])
        for c in P["columns"]:
            x = get(c)
            y = [x[0]]
            for v in x[1:]:
                y.append(y[-1] + a * (v - y[-1]))
            put(c, y)
    elif kind == "spikes":
        inside = [i for i, ti in enumerate(t) if any(a <= ti <= b for a, b in windows)]
        placed = []
        for _ in range(P["count"]):
            c = rng.choice(P["columns"])
            i = rng.choice(inside[:-2])
            n = rng.choice((1, 1, 2))
            s = SPIKE_SIZE[c] * rng.uniform(0.6, 1.5) * rng.choice((1, -1))
            for k in range(n):
                rows[i + k][col[c]] = "%.9g" % (float(rows[i + k][col[c]]) + s)
            placed.append([c, round(t[i], 4), n, s])
        facts["spikes"] = placed
    elif kind == "servo":
        # logged surface = true surface + gain (command − servo output): the command as the
        # surface, the servo between them unlogged
        sh, srows = read_csv(servo_log)
        st = [float(r[0]) for r in srows]
        dt = 1.0 / RATE
        gains = {}
        for s in SURF:
            if s + "_cmd" not in sh:
                continue
            ci, ai = sh.index(s + "_cmd"), sh.index(s + "_applied")
            idx = [min(max(int(round(ti / dt)) - 1, 0), len(st) - 1) for ti in t]
            cmd = [float(srows[k][ci]) for k in idx]
            app = [float(srows[k][ai]) for k in idx]
            true = get(s + "_rad")
            mt, ma = sum(true) / len(true), sum(app) / len(app)
            sxx = sum((x - ma) ** 2 for x in app)
            g = sum((x - ma) * (y - mt) for x, y in zip(app, true)) / sxx if sxx > 0 else 0.0
            gains[s] = g
            noisy = get(s + "_rad_noisy")
            put(s + "_rad_noisy", [v + g * (c - a) for v, c, a in zip(noisy, cmd, app)])
        facts["servo_surface_gain_rad_per_cmd"] = gains
    with open(csv_path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(rows)
    return facts


def mapping_variant(text, kind):
    if kind == "no_beta":
        return "\n".join(l for l in text.splitlines() if not l.startswith("beta =")) + "\n"
    if kind == "no_thrust":
        return "\n".join(l for l in text.splitlines()
                         if not l.startswith(("thrust =", "thrust_moment ="))) + "\n"
    return text


# ---------------------------------------------------------------------------------------
# truth (as scripts/verdict_audit.py: names and signs of the vocabulary, α̇ equivalents)
# ---------------------------------------------------------------------------------------
def truth_of(derivs, header, rows, windows, longitudinal=True):
    """The JSBSim truth under aeroident's names and signs (δa flips: the mapping's da has
    scale −1). The presets have no α̇ term: where the truth's C_α̇ is more than 10 % of its
    C_q, a preset's estimates of that coefficient are the structure's *equivalent*
    derivatives (Klein & Morelli 2006 §3.5), whose truth is the least-squares projection of
    JSBSim's own noise-free coefficient on the preset's regressors [1, α, q̂, δe] over the
    fitted rows (the windows; the whole record with one manoeuvre) — verdict_audit.py's
    `truth_of`/`equivalent`, restricted to the fitted rows. Only for records whose model
    has the longitudinal axis (a lateral record does not move α, q̂, δe enough to project
    on), and only where C_α̇ is not a rounding zero (|C_α̇| > 1e-6)."""
    out, basis = {}, {}
    for k, v in derivs.items():
        name = (k.replace("_phat", "_p").replace("_qhat", "_q").replace("_rhat", "_r")
                .replace("_adothat", "_alphadot"))
        out[name] = -v if name.endswith("_da") else v
        basis[name] = "trim finite difference"
    col = {n: i for i, n in enumerate(header)}
    t = [float(r[col["time"]]) for r in rows]
    use = [i for i, ti in enumerate(t) if not windows or any(a <= ti <= b for a, b in windows)]
    for c in ("CL", "Cm"):
        q, ad = out.get(c + "_q"), out.get(c + "_alphadot")
        if (longitudinal and q is not None and ad is not None and abs(ad) > 1e-6
                and abs(ad) > 0.1 * abs(q)):
            for term, value in zip(("0", "alpha", "q", "de"), equivalent(rows, col, use, c)):
                out["%s_%s" % (c, term)] = value
                basis["%s_%s" % (c, term)] = "equivalent (α̇ %.3g shared out)" % ad
    return out, basis


def lstsq(x, y):
    """Least squares by the normal equations (Gauss–Jordan, partial pivoting)."""
    n = len(x[0])
    a = [[sum(xi[i] * xi[j] for xi in x) for j in range(n)] +
         [sum(xi[i] * yi for xi, yi in zip(x, y))] for i in range(n)]
    for i in range(n):
        p = max(range(i, n), key=lambda k: abs(a[k][i]))
        a[i], a[p] = a[p], a[i]
        if a[i][i] == 0:
            return [float("nan")] * n
        for k in range(n):
            if k != i:
                f = a[k][i] / a[i][i]
                a[k] = [ak - f * ai for ak, ai in zip(a[k], a[i])]
    return [a[i][n] / a[i][i] for i in range(n)]


def truth_ls(header, rows, windows, axis):
    """A second truth, for diagnosis only: the least-squares projection of JSBSim's own
    noise-free total coefficients (CSV columns CL, Cm, CY, Cl, Cn: the same axes and
    reference point as the derivatives) on the preset's regressors over the fitted rows —
    longitudinal [1, α, q̂, δe], lateral [1, β, p̂, r̂, δa, δr] (δa = −aileron_rad as the
    mapping). Where it differs from the trim slope by more than 10 %, the record's
    excursions see a different slope than the trim point (tables in α, β, Mach; couplings
    the preset lacks): a miss there says as much about the truth as about the estimator."""
    col = {n: i for i, n in enumerate(header)}
    use = [i for i, r in enumerate(rows) if not windows or any(
        a <= float(r[col["time"]]) <= b for a, b in windows)]
    f = lambda r, c: float(r[col[c]])
    out = {}
    if axis in ("lon", "six"):
        x = [[1.0, f(r, "alpha_rad"), f(r, "q") * f(r, "cbar_ft") / (2 * f(r, "vt_fps")),
              f(r, "elevator_rad")] for r in (rows[i] for i in use)]
        for c in ("CL", "Cm"):
            th = lstsq(x, [f(rows[i], c) for i in use])
            out.update({"%s_alpha" % c: th[1], "%s_q" % c: th[2], "%s_de" % c: th[3]})
    if axis in ("lat", "six"):
        x = []
        for i in use:
            r = rows[i]
            k = f(r, "b_ft") / (2 * f(r, "vt_fps"))
            x.append([1.0, f(r, "beta_rad"), f(r, "p") * k, f(r, "r") * k,
                      -f(r, "aileron_rad"), f(r, "rudder_rad")])
        for c in ("CY", "Cl", "Cn"):
            th = lstsq(x, [f(rows[i], c) for i in use])
            out.update({"%s_beta" % c: th[1], "%s_p" % c: th[2], "%s_r" % c: th[3],
                        "%s_da" % c: th[4], "%s_dr" % c: th[5]})
    return {k: v for k, v in out.items() if k in PRIMARY and math.isfinite(v)}


def equivalent(rows, col, use, coefficient):
    """verdict_audit.py's `equivalent`: least squares of the noise-free `coefficient` column
    on [1, α, q̂, δe] (clean columns; q̂ = q c̄ / 2V) over the rows `use`."""
    x, y = [], []
    for i in use:
        r = rows[i]
        v, cbar = float(r[col["vt_fps"]]), float(r[col["cbar_ft"]])
        x.append([1.0, float(r[col["alpha_rad"]]), float(r[col["q"]]) * cbar / (2 * v),
                  float(r[col["elevator_rad"]])])
        y.append(float(r[col[coefficient]]))
    return lstsq(x, y)


# ---------------------------------------------------------------------------------------
# make
# ---------------------------------------------------------------------------------------
def make_record(py, out, d):
    """Fly, check, degrade and describe one record. Returns (name, status, message, seconds)."""
    t_start = time.time()
    name = record_name(d)
    rdir = Path(out) / "records" / name
    fail = Path(out) / "failed" / (name + ".json")
    cal = calibrate(py, out, d["aircraft"], d["cond"])
    if not cal["ok"]:
        return name, "failed", "condition does not fly: " + cal["reason"], time.time() - t_start
    rng = random.Random("%d/record/%s" % (SEED, name))
    P = choose_degradation(d, rng, cal)
    log_rate = P.get("log_rate_hz", LOG_RATE) if d["degradation"] == "log_10hz" else LOG_RATE
    seed = rng.randrange(1, 10 ** 6)
    tmp = Path(tempfile.mkdtemp(prefix=".tmp-" + name[:40] + "-", dir=str(Path(out) / "records")))
    try:
        attempts = []
        amp_scale = 1.0
        ok = False
        for attempt in range(4):
            irng = random.Random("%d/inputs/%s" % (SEED, name))   # same shape every attempt
            inputs, windows, duration = build_inputs(d, cal, irng, amp_scale)
            spec = {"tool": str(TOOL), "inputs": inputs,
                    "args": base_args(d["aircraft"], cal["alt_ft"], cal["vt_fps"], duration,
                                      tmp / "record.csv", tmp / "truth.json",
                                      d["noise_scale"], seed, log_rate)}
            if d["degradation"] == "servo":
                spec["servo"] = {}
                for s in SURF:
                    if inputs[s]:
                        g = cal["gains"][s]["surface_rad_per_cmd"]
                        spec["servo"][s] = {"tau": P["tau_s"],
                                            "rate": math.radians(P["rate_limit_deg_s"]) / g}
                        for seg in inputs[s]:
                            if seg.get("recenter"):
                                seg["recenter_dur"] = 0.5
                spec["servo_log"] = str(tmp / "servo.csv")
            okf, msg = fly(py, spec, tmp)
            if not okf:
                attempts.append({"amp_scale": amp_scale, "result": msg})
                return name, "failed", msg, time.time() - t_start
            header, rows = read_csv(tmp / "record.csv")
            rsp = response(header, rows)
            attempts.append({"amp_scale": amp_scale, "response": rsp})
            if rsp["departed"]:
                amp_scale *= 0.5
                continue
            weak = ((d["axis"] in ("lon", "six") and rsp["dalpha_deg"] < 0.3) or
                    (d["axis"] in ("lat", "six") and rsp["p_dps"] < 1.5 and rsp["beta_deg"] < 0.3))
            if weak and attempt < 3 and amp_scale < 4:
                amp_scale *= 2
                continue
            ok = True
            break
        if not ok:
            msg = "departed at every amplitude tried: " + attempts[-1]["response"]["departed"]
            fail.parent.mkdir(parents=True, exist_ok=True)
            fail.write_text(json.dumps({"design": d, "reason": msg, "attempts": attempts},
                                       indent=1))
            return name, "failed", msg, time.time() - t_start
        facts = degrade(tmp / "record.csv", d, P, rng,
                        windows, tmp / "servo.csv" if d["degradation"] == "servo" else None)
        base_map = MAP.read_text()
        (tmp / "map.toml").write_text(mapping_variant(base_map, d["degradation"]))
        header, rows = read_csv(tmp / "record.csv")
        tj = json.loads((tmp / "truth.json").read_text())
        fit_windows = windows if len(windows) > 1 else []
        truth, basis = truth_of(tj["derivatives"], header, rows, fit_windows,
                                longitudinal=d["axis"] in ("lon", "six"))
        ls = truth_ls(header, rows, fit_windows, d["axis"])
        (tmp / "spec.json").unlink(missing_ok=True)
        (tmp / "servo.csv").unlink(missing_ok=True)
        meta = {
            "name": name, "design": d, "seed": SEED, "half": d["half"],
            "aircraft": d["aircraft"], "class": d["class"],
            "condition": {"slot": d["cond"], "alt_ft": cal["alt_ft"], "vt_fps": cal["vt_fps"],
                          "fallback": cal["fallback"], "mach": rows and float(
                              rows[0][header.index("mach")]),
                          "trim_alpha_deg": math.degrees(tj["trim"]["aero/alpha-rad"])},
            "model": d["model"], "axis": d["axis"], "input_kind": d["kind"],
            "inputs": inputs, "manoeuvres": windows, "windows": fit_windows,
            "duration_s": duration, "log_rate_hz": log_rate, "rows": len(rows),
            "noise": {"preset": "typical", "scale": d["noise_scale"], "seed": seed},
            "degradation": {"kind": d["degradation"], "params": P, **facts},
            "amplitude_attempts": attempts, "amp_scale": amp_scale,
            "surface_position_props": tj.get("run", {}).get("surface_position_props"),
            "truth": {k: v for k, v in truth.items() if v is not None},
            "truth_basis": {k: basis[k] for k in PRIMARY if k in basis},
            "truth_ls": ls,
            "files": {"csv": "record.csv", "truth": "truth.json", "map": "map.toml"},
            "base_mapping_sha256": hashlib.sha256(base_map.encode()).hexdigest(),
            "make_s": round(time.time() - t_start, 2),
        }
        (tmp / "meta.json").write_text(json.dumps(meta, indent=1))
        if rdir.exists():
            shutil.rmtree(rdir)
        tmp.rename(rdir)
        return name, "made", "Δα %.1f° p %.0f°/s β %.1f°, %d rows" % (
            rsp["dalpha_deg"], rsp["p_dps"], rsp["beta_deg"], len(rows)), time.time() - t_start
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


class _Inline:
    """A stand-in for the process pool with --jobs 1: everything in this process (one PID
    to stop), each call run when its result is asked for, in order."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def submit(self, fn, *args):
        f = cf.Future()
        f.fn_args = (fn, args)
        return f


def pool(jobs):
    return cf.ProcessPoolExecutor(jobs) if jobs > 1 else _Inline()


def _as_completed(futs):
    for f in futs:
        if hasattr(f, "fn_args") and not f.done():
            fn, args = f.fn_args
            try:
                f.set_result(fn(*args))
            except Exception as e:
                f.set_exception(e)
        yield f


def cmd_make(a):
    out = Path(a.out)
    (out / "records").mkdir(parents=True, exist_ok=True)
    for stale in (out / "records").glob(".tmp-*"):      # of a make that was stopped
        shutil.rmtree(stale, ignore_errors=True)
    recs = design()[: a.limit] if a.limit else design()
    todo = []
    for d in recs:
        name = record_name(d)
        if (out / "records" / name / "meta.json").exists():
            continue
        if (out / "failed" / (name + ".json")).exists() and not a.retry_failed:
            continue
        todo.append(d)
    log("make: %d records in the design%s, %d to fly (jobs %d)" % (
        len(recs), " (--limit)" if a.limit else "", len(todo), a.jobs))
    # calibrations first (each needed (aircraft, condition) once)
    cals = sorted({(d["aircraft"], d["cond"]) for d in todo})
    t0 = time.time()
    with pool(a.jobs) as ex:
        futs = {ex.submit(calibrate, a.python, str(out), ac, c): (ac, c) for ac, c in cals}
        for f in (_as_completed(futs) if a.jobs == 1 else cf.as_completed(futs)):
            ac, c = futs[f]
            r = f.result()
            log("calibrate %-10s c%d: %s" % (ac, c, (
                "%s ft %s ft/s%s" % (r["alt_ft"], r["vt_fps"], " (fallback)" if r["fallback"]
                                     else "")) if r["ok"] else "DROPPED: " + r["reason"]))
    log("calibration: %d conditions in %.0f s" % (len(cals), time.time() - t0))
    made = failed = 0
    times = []
    t0 = time.time()
    with pool(a.jobs) as ex:
        futs = [ex.submit(make_record, a.python, str(out), d) for d in todo]
        for f in (_as_completed(futs) if a.jobs == 1 else cf.as_completed(futs)):
            try:
                name, st, msg, sec = f.result()
            except Exception as e:          # a bug in one record must not stop the corpus
                name, st, msg, sec = "?", "failed", "%s: %s" % (type(e).__name__, e), 0.0
            if st == "made":
                made += 1
                times.append(sec)
            else:
                failed += 1
                fp = out / "failed" / (name + ".json")
                if name != "?" and not fp.exists():
                    fp.parent.mkdir(parents=True, exist_ok=True)
                    fp.write_text(json.dumps({"name": name, "reason": msg}, indent=1))
            log("%-6s %5.1fs %s: %s" % (st, sec, name, msg))
    n_total = len(list((out / "records").glob("*/meta.json")))
    log("make done: %d made, %d failed in %.0f s (%.1f s per made record); %d records in %s"
        % (made, failed, time.time() - t0, sum(times) / max(len(times), 1), n_total,
           out / "records"))


def log(msg):
    print(time.strftime("%H:%M:%S ") + msg, flush=True)


# ---------------------------------------------------------------------------------------
# run
# ---------------------------------------------------------------------------------------
KEEP = {"summary.json", "run.json"}


def replay_one(binp, rdir, est, odir, extra, timeout, keep_all):
    meta = json.loads((rdir / "meta.json").read_text())
    cmd = [binp, "replay", str(rdir / "record.csv"), "--map", str(rdir / "map.toml"),
           "--model", meta["model"], "--estimator", est, "--out", str(odir)]
    for w0, w1 in meta["windows"]:
        cmd += ["--window", "%g:%g" % (w0, w1)]
    cmd += extra
    odir.mkdir(parents=True, exist_ok=True)
    t0 = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        rc, err, outp = p.returncode, p.stderr, p.stdout
    except subprocess.TimeoutExpired as e:
        rc, err, outp = "timeout", "timed out after %d s" % timeout, ""
    wall = time.time() - t0
    lines = [l for l in (err or "").strip().splitlines() if l.strip()]
    info = {"record": meta["name"], "estimator": est, "cmd": cmd, "exit": rc,
            "wall_s": round(wall, 3), "last_stderr": lines[-1][:500] if lines else "",
            "summary": (odir / "summary.json").exists() and rc == 0,
            "stdout_tail": (outp or "").strip().splitlines()[-1:]}
    if not keep_all:
        for f in odir.iterdir():
            if f.name not in KEEP and f.is_file() and not f.name.startswith(".aeroident"):
                f.unlink()
    (odir / "run.json").write_text(json.dumps(info, indent=1))
    return info


def cmd_run(a):
    out = Path(a.out)
    runs = out / ("runs" if not a.tag else "runs-" + a.tag)
    recs = sorted(p.parent for p in (out / "records").glob("*/meta.json"))
    if a.half != "all":
        recs = [r for r in recs if json.loads((r / "meta.json").read_text())["half"] == a.half]
    if a.limit:
        recs = recs[: a.limit]
    ests = [e for e in a.estimators.split(",") if e]
    extra = shlex.split(a.extra_args or "")
    jobs = []
    for r in recs:
        for e in ests:
            od = runs / r.name / e
            if not (od / "run.json").exists():
                jobs.append((r, e, od))
    log("run: %d records × %d estimators, %d replays to do (jobs %d), into %s" % (
        len(recs), len(ests), len(jobs), a.jobs, runs))
    t0 = time.time()
    by_est = defaultdict(list)
    with cf.ThreadPoolExecutor(a.jobs) as ex:
        futs = [ex.submit(replay_one, a.bin, r, e, od, extra, a.timeout, a.keep_all)
                for r, e, od in jobs]
        for f in cf.as_completed(futs):
            i = f.result()
            by_est[i["estimator"]].append(i["wall_s"])
            tag = "ok" if i["exit"] == 0 else "exit %s" % i["exit"]
            log("%-9s %6.2fs %-6s %s%s" % (tag, i["wall_s"], i["estimator"], i["record"],
                                           "" if i["exit"] == 0 else ": " + i["last_stderr"][:160]))
    for e, ts in sorted(by_est.items()):
        log("run %-6s: %d replays, mean %.2f s, max %.2f s" % (e, len(ts), sum(ts) / len(ts),
                                                               max(ts)))
    log("run done in %.0f s" % (time.time() - t0))


# ---------------------------------------------------------------------------------------
# report
# ---------------------------------------------------------------------------------------
def wilson(k, n, z=1.96):
    if n == 0:
        return None
    p = k / n
    den = 1 + z * z / n
    c = (p + z * z / (2 * n)) / den
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return [round(max(0.0, c - h), 4), round(min(1.0, c + h), 4)]


def collect(out, tag, half):
    runs = Path(out) / ("runs" if not tag else "runs-" + tag)
    rows, replays = [], []
    for mp in sorted((Path(out) / "records").glob("*/meta.json")):
        meta = json.loads(mp.read_text())
        if half != "all" and meta["half"] != half:
            continue
        rdir = runs / meta["name"]
        if not rdir.exists():
            continue
        for ed in sorted(p for p in rdir.iterdir() if p.is_dir()):
            ri = ed / "run.json"
            if not ri.exists():
                continue
            info = json.loads(ri.read_text())
            rep = {"record": meta["name"], "estimator": ed.name, "exit": info["exit"],
                   "last_stderr": info["last_stderr"], "wall_s": info["wall_s"],
                   "aircraft": meta["aircraft"], "degradation": meta["degradation"]["kind"]}
            replays.append(rep)
            if info["exit"] != 0 or not (ed / "summary.json").exists():
                continue
            s = json.loads((ed / "summary.json").read_text())
            for q in s.get("parameters", []):
                nm = q.get("name")
                if nm not in PRIMARY:
                    continue
                t = meta["truth"].get(nm)
                if t is None or not math.isfinite(t) or abs(t) < 1e-6:
                    continue
                e, sd = q.get("estimate"), q.get("std_error")
                err = None if e is None else abs(e - t)
                rows.append({
                    "record": meta["name"], "estimator": ed.name, "aircraft": meta["aircraft"],
                    "class": meta["class"], "half": meta["half"], "model": meta["model"],
                    "input": meta["input_kind"], "manoeuvres": len(meta["manoeuvres"]),
                    "noise": meta["noise"]["scale"], "degradation": meta["degradation"]["kind"],
                    "name": nm, "truth": t, "truth_basis": meta["truth_basis"].get(nm),
                    "truth_ls": meta.get("truth_ls", {}).get(nm),
                    "estimate": e, "std_error": sd, "status": q.get("status"),
                    "flags": q.get("flags") or [], "notes": q.get("notes") or [],
                    "rel_error": None if err is None else err / abs(t),
                    "right10": err is not None and err <= 0.10 * abs(t),
                    "right_2s": err is not None and err <= max(0.10 * abs(t),
                                                               2 * (sd or 0.0)),
                    "covered": err is not None and sd is not None and err <= 2 * sd,
                })
                tl = rows[-1]["truth_ls"]
                rows[-1]["truth_consistent"] = (tl is not None and
                                                abs(tl - t) <= 0.10 * abs(t))
    return rows, replays


def relative_sigma(r):
    """σ/|estimate| of a joined row; None without both."""
    e, sd = r["estimate"], r["std_error"]
    return None if e is None or sd is None or e == 0 else sd / abs(e)


def within_10pct_if_gaussian(r):
    """The chance that an unbiased estimate whose error is normal with the row's own σ lies
    within 10 % of the truth, P(|z| < 0.1 |θ| / σ), taking |θ| as |estimate|: what the row's
    σ lets "right" expect."""
    rel = relative_sigma(r)
    return None if rel is None else math.erf(0.10 / rel / math.sqrt(2.0))


SIGMA_BINS = [0.0, 0.075, 0.10, 0.15, 0.20, float("inf")]


def by_relative_sigma(rows):
    """Identified estimates by σ/|estimate|: count, precision, precision₂σ, coverage, and the
    precision their own σ predicts for unbiased normal errors (within_10pct_if_gaussian)."""
    out = {}
    ident = [r for r in rows if r["status"] == "identified" and relative_sigma(r) is not None]
    for lo, hi in zip(SIGMA_BINS, SIGMA_BINS[1:]):
        sel = [r for r in ident if lo <= relative_sigma(r) < hi]
        if not sel:
            continue
        n = len(sel)
        out["%g–%g %%" % (100 * lo, 100 * hi)] = {
            "identified": n,
            "precision": round(sum(r["right10"] for r in sel) / n, 4),
            "precision_2sigma": round(sum(r["right_2s"] for r in sel) / n, 4),
            "coverage_2sigma": round(sum(r["covered"] for r in sel) / n, 4),
            "expected_precision_if_unbiased": round(
                sum(within_10pct_if_gaussian(r) for r in sel) / n, 4)}
    return out


def metrics(sel, reps=None):
    ident = [r for r in sel if r["status"] == "identified"]
    right = [r for r in sel if r["right10"]]
    ir = [r for r in ident if r["right10"]]
    ir2 = [r for r in ident if r["right_2s"]]
    cov = [r for r in ident if r["covered"]]
    nosig = [r for r in ident if r["std_error"] is None]
    m = {"n": len(sel), "identified": len(ident), "right": len(right),
         "identified_right": len(ir),
         "precision": round(len(ir) / len(ident), 4) if ident else None,
         "precision_ci95": wilson(len(ir), len(ident)),
         "precision_2sigma": round(len(ir2) / len(ident), 4) if ident else None,
         "recall": round(len(ir) / len(right), 4) if right else None,
         "recall_ci95": wilson(len(ir), len(right)),
         "coverage_2sigma": round(len(cov) / len(ident), 4) if ident else None,
         "coverage_ci95": wilson(len(cov), len(ident)),
         "identified_without_sigma": len(nosig),
         "statuses": dict(Counter(r["status"] for r in sel))}
    if reps is not None:
        m["replays"] = len(reps)
        m["failed_replays"] = sum(1 for r in reps if r["exit"] != 0)
    # The estimates the record determines to 10 % (σ ≤ 10 % of |estimate|, no `notes` entry
    # saying otherwise): the ones whose σ supports the 10 % that "right" asks for.
    det = [r for r in ident if relative_sigma(r) is not None and relative_sigma(r) <= 0.10]
    m["determined"] = len(det)
    m["precision_determined"] = (round(sum(r["right10"] for r in det) / len(det), 4)
                                 if det else None)
    m["precision_determined_ci95"] = wilson(sum(r["right10"] for r in det), len(det))
    m["meets_targets"] = (m["precision"] is not None and m["precision"] >= 0.95 and
                          m["recall"] is not None and m["recall"] >= 0.60 and
                          m["coverage_2sigma"] is not None and m["coverage_2sigma"] >= 0.90)
    return m


def cmd_report(a):
    rows, replays = collect(a.out, a.tag, a.half)
    ests = sorted({r["estimator"] for r in replays}, key=lambda e: ESTIMATORS.split(",").index(e)
                  if e in ESTIMATORS.split(",") else 99)
    rep = {"half": a.half, "tag": a.tag, "right": "|estimate − truth| ≤ 10 % of |truth|",
           "right_2sigma": "|estimate − truth| ≤ max(10 % |truth|, 2σ)",
           "targets": {"precision": 0.95, "recall": 0.60, "coverage_2sigma": 0.90},
           "records": len({r["record"] for r in replays}),
           "per_method": {e: metrics([r for r in rows if r["estimator"] == e],
                                     [r for r in replays if r["estimator"] == e])
                          for e in ests},
           "overall": metrics(rows, replays),
           "consistent_truth": {
               "what": "only estimates whose trim-slope truth and least-squares truth "
                       "(truth_ls) agree to 10 %: misses not owed to a truth the record's "
                       "excursions do not see",
               "per_method": {e: metrics([r for r in rows if r["estimator"] == e
                                          and r["truth_consistent"]]) for e in ests},
               "overall": metrics([r for r in rows if r["truth_consistent"]])}}
    for key in ("name", "degradation", "aircraft", "input", "noise", "model", "manoeuvres"):
        rep["by_" + key] = {str(k): metrics([r for r in rows if r[key] == k])
                            for k in sorted({r[key] for r in rows}, key=str)}
    rep["by_relative_sigma"] = by_relative_sigma(rows)
    misses = sorted((r for r in rows if r["status"] == "identified" and not r["right10"]),
                    key=lambda r: -(r["rel_error"] or 0))
    rep["worst_identified_misses"] = [
        {k: r[k] for k in ("record", "estimator", "name", "truth", "truth_basis", "truth_ls",
                           "estimate",
                           "std_error", "rel_error", "degradation", "flags", "notes")}
        for r in misses[: a.worst]]
    rep["failed_replays"] = [r for r in replays if r["exit"] != 0]
    out_json = Path(a.json or Path(a.out) / ("report-%s%s.json" % (
        a.half, "-" + a.tag if a.tag else "")))
    out_json.write_text(json.dumps(rep, indent=1))
    (Path(a.out) / ("joined-%s%s.json" % (a.half, "-" + a.tag if a.tag else ""))).write_text(
        json.dumps(rows, indent=0))
    md = markdown(rep)
    if a.markdown:
        Path(a.markdown).write_text(md)
    head = md if not a.markdown else md.split("\n\nOnly where")[0] + "\n"
    try:
        print(head)
        print("wrote %s%s" % (out_json, " and " + a.markdown if a.markdown else ""))
    except BrokenPipeError:
        pass


def _pct(x):
    return "—" if x is None else "%.1f %%" % (100 * x)


def _ci(c):
    return "" if not c else " [%.0f–%.0f]" % (100 * c[0], 100 * c[1])


def markdown(rep):
    L = ["# Verdict calibration — half `%s`%s" % (rep["half"], " (tag %s)" % rep["tag"]
                                                   if rep["tag"] else ""), "",
         "%d records; 'right' = within 10 %% of the truth; precision₂σ: right = within "
         "max(10 %%, 2σ). Targets: precision ≥ 95 %%, recall ≥ 60 %%, ±2σ coverage ≥ 90 %% "
         "(brackets: Wilson 95 %% interval)." % rep["records"], "",
         "| method | replays | failed | n | identified | precision | precision₂σ | recall | "
         "coverage ±2σ | targets |",
         "|---|---|---|---|---|---|---|---|---|---|"]
    for e, m in list(rep["per_method"].items()) + [("**all**", rep["overall"])]:
        L.append("| %s | %d | %d | %d | %d | %s%s | %s | %s%s | %s%s | %s |" % (
            e, m["replays"], m["failed_replays"], m["n"], m["identified"],
            _pct(m["precision"]), _ci(m["precision_ci95"]), _pct(m["precision_2sigma"]),
            _pct(m["recall"]), _ci(m["recall_ci95"]), _pct(m["coverage_2sigma"]),
            _ci(m["coverage_ci95"]), "met" if m["meets_targets"] else "not met"))
    L += ["", "Precision over the estimates the record determines to 10 % (σ ≤ 10 % of "
          "|estimate|, no note saying otherwise), and the identified estimates by σ/|estimate| "
          "beside the precision their own σ predicts for unbiased normal errors, "
          "P(|z| < 0.1/(σ/|θ|)):", "",
          "| method | determined to 10 % | precision there |", "|---|---|---|"]
    for e, m in list(rep["per_method"].items()) + [("**all**", rep["overall"])]:
        L.append("| %s | %d | %s%s |" % (e, m["determined"], _pct(m["precision_determined"]),
                                          _ci(m["precision_determined_ci95"])))
    L += ["", "| σ/\\|estimate\\| | identified | precision | expected if unbiased | "
          "precision₂σ | coverage ±2σ |", "|---|---|---|---|---|---|"]
    for k, b in rep["by_relative_sigma"].items():
        L.append("| %s | %d | %s | %s | %s | %s |" % (
            k, b["identified"], _pct(b["precision"]), _pct(b["expected_precision_if_unbiased"]),
            _pct(b["precision_2sigma"]), _pct(b["coverage_2sigma"])))
    ct = rep["consistent_truth"]
    L += ["", "Only where the trim-slope truth and the least-squares truth agree to 10 %:", "",
          "| method | n | identified | precision | recall | coverage ±2σ |",
          "|---|---|---|---|---|---|"]
    for e, m in list(ct["per_method"].items()) + [("**all**", ct["overall"])]:
        L.append("| %s | %d | %d | %s | %s | %s |" % (
            e, m["n"], m["identified"], _pct(m["precision"]), _pct(m["recall"]),
            _pct(m["coverage_2sigma"])))
    for key, title in (("by_name", "parameter"), ("by_degradation", "degradation"),
                       ("by_input", "input"), ("by_noise", "noise scale"),
                       ("by_aircraft", "aircraft")):
        L += ["", "| %s | n | identified | precision | recall | coverage ±2σ |" % title,
              "|---|---|---|---|---|---|"]
        for k, m in rep[key].items():
            L.append("| %s | %d | %d | %s | %s | %s |" % (
                k, m["n"], m["identified"], _pct(m["precision"]), _pct(m["recall"]),
                _pct(m["coverage_2sigma"])))
    L += ["", "## Worst identified misses", ""]
    for r in rep["worst_identified_misses"]:
        L.append("- %s `%s` %s = %.4g ± %s (truth %.4g, %s; LS truth %s; %+.0f %%) notes: %s" % (
            r["record"], r["estimator"], r["name"], r["estimate"],
            "—" if r["std_error"] is None else "%.2g" % r["std_error"], r["truth"],
            r["truth_basis"], "—" if r["truth_ls"] is None else "%.4g" % r["truth_ls"],
            100 * (r["estimate"] - r["truth"]) / abs(r["truth"]),
            "; ".join(r["notes"]) or "none"))
    if rep["failed_replays"]:
        L += ["", "## Failed replays (%d)" % len(rep["failed_replays"]), ""]
        for r in rep["failed_replays"][:40]:
            L.append("- %s `%s`: exit %s: %s" % (r["record"], r["estimator"], r["exit"],
                                                  r["last_stderr"][:200]))
    return "\n".join(L) + "\n"


# ---------------------------------------------------------------------------------------
# ---------------------------------------------------------------------------------------
# real: the shipped real records against their published values
# ---------------------------------------------------------------------------------------
# (record, mapping, model file with [reference.X] tables): a model file's references are
# compared beside the verdict (`reference_check`), never an input to it.
REAL = [("jategaonkar_hfb320_attas/csv/hfb320_1_10.csv", "mappings/hfb320.toml",
         "models/hfb320_book_q0.toml")]


def cmd_real(a):
    """Every method on every real record with published values: the verdict against them."""
    root = Path(__file__).resolve().parents[2]
    shared = root.parent / "shared" / "flightdata"
    rows = []
    for rec, mapping, model in REAL:
        for est in a.estimators.split(","):
            odir = Path(a.out) / "real" / Path(rec).stem / est
            cmd = [a.bin, "replay", str(shared / rec), "--map", str(root / mapping),
                   "--model", str(root / model), "--estimator", est, "--out", str(odir)]
            p = subprocess.run(cmd, capture_output=True, text=True)
            if p.returncode != 0:
                log("%s %s: exit %d: %s" % (rec, est, p.returncode, p.stderr.strip()[-200:]))
                continue
            s = json.loads((odir / "summary.json").read_text())
            for q in s["parameters"]:
                rc = q.get("reference_check")
                if not rc or rc.get("error_pct") is None:
                    continue
                rows.append({"record": Path(rec).stem, "estimator": est, "name": q["name"],
                             "status": q["status"], "error_pct": rc["error_pct"],
                             "within_2sigma": rc.get("within_2sigma")})
    idd = [r for r in rows if r["status"] == "identified"]
    right = [r for r in idd if abs(r["error_pct"]) <= 10.0]
    covered = [r for r in idd if r["within_2sigma"]]
    every_right = [r for r in rows if abs(r["error_pct"]) <= 10.0]
    print("| method | parameter | status | error vs published | within ±2σ |")
    print("|---|---|---|---|---|")
    for r in rows:
        print("| %s | %s | %s | %+.1f %% | %s |" % (r["estimator"], r["name"], r["status"],
                                                  r["error_pct"], r["within_2sigma"]))
    print()
    print("identified %d of %d; within 10 %%: %d (precision %.1f %%); recall %d of %d; "
          "±2σ covers the published value in %d" % (
              len(idd), len(rows), len(right), 100.0 * len(right) / max(len(idd), 1),
              len([r for r in every_right if r["status"] == "identified"]), len(every_right),
              len(covered)))
    for rec, mapping, model in REAL:
        reference_repeats(a, shared / rec, root / mapping, root / model)


def reference_repeats(a, rec, mapping, model):
    """Does the published values' own method repeat them on the record's manoeuvres?

    The references here are output-error fits of the whole record. Output error fitted on
    each manoeuvre `inspect` finds (`--window auto`), with the replay's repeatability test,
    says whether one value holds across them; where it does not, the whole-record value is a
    compromise between the manoeuvres and not a truth to 10 %.
    """
    odir = Path(a.out) / "real" / rec.stem / "oe-per-manoeuvre"
    cmd = [a.bin, "replay", str(rec), "--map", str(mapping), "--model", str(model),
           "--estimator", "oe", "--window", "auto", "--no-cross-check", "--out", str(odir)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        log("%s oe --window auto: exit %d: %s" % (rec.stem, p.returncode, p.stderr.strip()[-200:]))
        return
    s = json.loads((odir / "summary.json").read_text())
    refs = {k: v["value"] for k, v in tomllib.loads(model.read_text()).get("reference", {}).items()}
    print()
    print("%s: output error on each manoeuvre (`--window auto`) against the reference" % rec.stem)
    print("| parameter | reference | per manoeuvre ± σ | χ² p | repeats |")
    print("|---|---|---|---|---|")
    for r in s.get("repeatability", {}).get("parameters", []):
        if r["parameter"] not in refs:
            continue
        vals = ", ".join("%.4g ± %.2g" % (v["estimate"], v["std_error"]) for v in r["values"])
        print("| %s | %.4g | %s | %.3g | %s |" % (r["parameter"], refs[r["parameter"]], vals,
                                                  r["p_value"], r["repeats"]))


def cmd_repeats(a):
    """The uav_oat repeats: each file fitted alone by each method; every pair of `identified`
    values of one derivative (constant terms aside: each flight has its own trim) compared
    against 3 combined σ."""
    import itertools
    root = Path(__file__).resolve().parents[2]
    data = root.parent / "shared" / "flightdata" / "uav_oat" / "csv"
    rows = defaultdict(list)
    for f in sorted(data.glob("*.csv")):
        model = "longitudinal" if "_el_" in f.name else "lateral"
        for est in a.estimators.split(","):
            odir = Path(a.out) / "uav_oat" / f.stem / est
            cmd = [a.bin, "replay", str(f), "--map", str(root / "mappings" / "uav_oat.toml"),
                   "--model", model, "--estimator", est, "--out", str(odir)]
            if subprocess.run(cmd, capture_output=True, text=True).returncode != 0:
                log("%s %s: failed" % (f.stem, est))
                continue
            for q in json.loads((odir / "summary.json").read_text())["parameters"]:
                if q.get("estimate") is None or q.get("std_error") is None or \
                        q["name"].endswith("_0") or q["status"] != "identified":
                    continue
                rows[(est, q["name"])].append((f.stem, q["estimate"], q["std_error"]))
    print("| method | pairs of identified values | beyond 3 combined σ |")
    print("|---|---|---|")
    total = [0, 0]
    for est in a.estimators.split(","):
        pairs = bad = 0
        for (e, _), vs in rows.items():
            if e != est:
                continue
            for x, y in itertools.combinations(vs, 2):
                pairs += 1
                bad += abs(x[1] - y[1]) > 3.0 * math.hypot(x[2], y[2])
        total[0] += pairs
        total[1] += bad
        print("| %s | %d | %d |" % (est, pairs, bad))
    print("| all | %d | %d |" % tuple(total))
    print("\npairs beyond 3 combined σ (method, parameter, file: estimate ± σ, twice; |Δ|/σ):")
    for (e, name), vs in sorted(rows.items()):
        for x, y in itertools.combinations(vs, 2):
            z = abs(x[1] - y[1]) / math.hypot(x[2], y[2])
            if z > 3.0:
                print("- %s %s: %s %.4g ± %.2g; %s %.4g ± %.2g; %.1f" % (
                    e, name, x[0], x[1], x[2], y[0], y[1], y[2], z))


def cmd_repeats_joint(a):
    """The uav_oat repeats replayed together: per method, the elevator files in one
    longitudinal fit and the aileron and rudder files in one lateral fit (`--and`), whose
    repeatability test fits each file alone. Every pair of per-file values of one derivative
    (constant terms aside) beyond 3 combined σ is counted, and whether the fit says the
    derivative does not repeat (and scales its σ to the spread)."""
    import itertools
    root = Path(__file__).resolve().parents[2]
    data = root.parent / "shared" / "flightdata" / "uav_oat" / "csv"
    files = sorted(data.glob("*.csv"))
    groups = {"longitudinal": [f for f in files if "_el_" in f.name],
              "lateral": [f for f in files if "_el_" not in f.name]}
    print("| method | model | files | derivatives compared | pairs | beyond 3σ | of them named by the fit |")
    print("|---|---|---|---|---|---|---|")
    unnamed = []
    for est in a.estimators.split(","):
        for model, fs in groups.items():
            odir = Path(a.out) / "uav_oat_joint" / model / est
            cmd = [a.bin, "replay", str(fs[0])]
            for f in fs[1:]:
                cmd += ["--and", str(f)]
            cmd += ["--map", str(root / "mappings" / "uav_oat.toml"), "--model", model,
                    "--estimator", est, "--out", str(odir)]
            r = subprocess.run(cmd, capture_output=True, text=True)
            if r.returncode != 0:
                print("| %s | %s | %d | failed: %s | | | |" % (
                    est, model, len(fs), r.stderr.strip().splitlines()[-1][:80]))
                continue
            rep = json.loads((odir / "summary.json").read_text()).get("repeatability") or {}
            compared = pairs = bad = named = 0
            for q in rep.get("parameters", []):
                if q["parameter"].endswith("_0"):
                    continue
                compared += 1
                for x, y in itertools.combinations(q["values"], 2):
                    pairs += 1
                    z = abs(x["estimate"] - y["estimate"]) / math.hypot(
                        x["std_error"], y["std_error"])
                    if z > 3.0:
                        bad += 1
                        named += not q["repeats"]
                        if q["repeats"]:
                            unnamed.append("%s %s %s: #%d %.4g ± %.2g, #%d %.4g ± %.2g (%.1fσ; p = %.3g)" % (
                                est, model, q["parameter"], x["manoeuvre"] + 1, x["estimate"],
                                x["std_error"], y["manoeuvre"] + 1, y["estimate"],
                                y["std_error"], z, q["p_value"]))
            print("| %s | %s | %d | %d | %d | %d | %d |" % (
                est, model, len(fs), compared, pairs, bad, named))
    print("\npairs beyond 3 combined σ in a derivative the fit says repeats:")
    for u in unnamed:
        print("- " + u)


def cmd_design(a):
    recs = design()[: a.limit] if a.limit else design()
    print("%d records, %d aircraft" % (len(recs), len({d["aircraft"] for d in recs})))
    for key in ("half", "class", "aircraft", "axis", "kind", "manoeuvres", "noise_scale",
                "degradation"):
        c = Counter(d[key] for d in recs)
        print("%-12s %s" % (key, ", ".join("%s %d" % (k, v) for k, v in sorted(
            c.items(), key=lambda kv: str(kv[0])))))
    if a.list:
        for d in recs:
            print(record_name(d), d["half"], d["alt_ft"], d["vt_fps"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    m = sub.add_parser("make", help="fly the records")
    m.add_argument("--out", required=True)
    m.add_argument("--python", default=DEFAULT_PY, help="a Python with jsbsim (1.3.3)")
    m.add_argument("--limit", type=int, default=0, help="only the first N of the design")
    m.add_argument("--jobs", type=int, default=1)
    m.add_argument("--retry-failed", action="store_true")
    r = sub.add_parser("run", help="replay every record with every estimator")
    r.add_argument("--out", required=True)
    r.add_argument("--bin", default=DEFAULT_BIN)
    r.add_argument("--estimators", default=ESTIMATORS)
    r.add_argument("--jobs", type=int, default=1)
    r.add_argument("--tag", default="", help="runs-TAG/ instead of runs/ (e.g. other args)")
    r.add_argument("--extra-args", default="", help='more replay arguments, e.g. "--compat auto"')
    r.add_argument("--timeout", type=int, default=1200, help="s per replay")
    r.add_argument("--limit", type=int, default=0, help="only the first N records (by name)")
    r.add_argument("--half", default="all", choices=("tune", "held-out", "all"),
                   help="only the records of this half")
    r.add_argument("--keep-all", action="store_true",
                   help="keep report.html, figures and estimates.csv (default: summary.json)")
    p = sub.add_parser("report", help="join estimates with the truth")
    p.add_argument("--out", required=True)
    p.add_argument("--half", default="held-out", choices=("tune", "held-out", "all"))
    p.add_argument("--tag", default="")
    p.add_argument("--markdown", default="")
    p.add_argument("--json", default="", help="default DIR/report-HALF[-TAG].json")
    p.add_argument("--worst", type=int, default=25)
    d = sub.add_parser("design", help="print the design's counts (flies nothing)")
    d.add_argument("--limit", type=int, default=0)
    d.add_argument("--list", action="store_true")
    q = sub.add_parser("real", help="the shipped real records against their published values")
    q.add_argument("--out", required=True)
    q.add_argument("--bin", default=DEFAULT_BIN)
    q.add_argument("--estimators", default=ESTIMATORS)
    u = sub.add_parser("repeats", help="the uav_oat repeats: identified values across files")
    u.add_argument("--out", required=True)
    u.add_argument("--bin", default=DEFAULT_BIN)
    u.add_argument("--estimators", default="oe,rls,ekf")
    j = sub.add_parser("repeats-joint",
                       help="the uav_oat repeats replayed together (--and): pairs the fit names")
    j.add_argument("--out", required=True)
    j.add_argument("--bin", default=DEFAULT_BIN)
    j.add_argument("--estimators", default="oe,fem,fdoe", help="batch fits (--and takes no other)")
    a = ap.parse_args()
    {"make": cmd_make, "run": cmd_run, "report": cmd_report, "design": cmd_design,
     "real": cmd_real, "repeats": cmd_repeats, "repeats-joint": cmd_repeats_joint}[a.cmd](a)


if __name__ == "__main__":
    sys.exit(main())
