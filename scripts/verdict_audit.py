#!/usr/bin/env python3
"""Audit of the per-parameter verdicts against a known truth: how often `identified` stands
beside an estimate more than 10 % off, and how often an estimate within 10 % is `identified`.

Records are flown by JSBSim (`../shared/tools/jsbsim_log.py`, an independent simulator) at
conditions and seeds of this script's own (not the shared samples'), then replayed through
`aeroident replay` with clean and hostile mappings: as given; a surface logged in degrees but
mapped as radians; a reversed surface; thrust unmapped. Each primary derivative whose truth
exists is counted by its status and its error against the JSBSim truth (docs/output-schema.md).

Usage:
    scripts/verdict_audit.py --python PY_WITH_JSBSIM [--bin target/release/aeroident]
        [--out /tmp/aeroident-verdict-audit] [--estimators rls,ekf,oe] [--cross-check]

Exit 0 always; prints one line per case and the totals, and writes `audit.json` in `--out`.
"""
import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TOOL = ROOT.parent / "shared" / "tools" / "jsbsim_log.py"
MAP = ROOT / "mappings" / "jsbsim.toml"

PRIMARY = ["Cm_alpha", "Cm_q", "Cm_de", "CL_alpha", "Cl_beta", "Cl_p", "Cl_da", "Cn_beta",
           "Cn_r", "Cn_dr", "CY_beta"]

# (name, model, jsbsim_log.py arguments): conditions and seeds of this audit's own.
FLIGHTS = [
    ("c172_lon_ms", "longitudinal",
     ["--aircraft", "c172x", "--alt", "4000", "--vt", "170", "--elevator", "multisine",
      "--elevator-amp", "0.15", "--ms-period", "10", "--ms-fmin", "0.1", "--ms-fmax", "1.5",
      "--duration", "30", "--noise-seed", "21"]),
    ("c172_lon_3211_noisy", "longitudinal",
     ["--aircraft", "c172x", "--alt", "6000", "--vt", "190", "--elevator", "3211",
      "--elevator-t0", "1", "--elevator-amp", "0.2", "--elevator-width", "0.35",
      "--elevator-recenter", "0.0623", "--duration", "15", "--noise-seed", "22",
      "--noise-scale", "3"]),
    ("f16_lat_ms", "lateral",
     ["--aircraft", "f16", "--alt", "15000", "--vt", "600", "--aileron", "multisine",
      "--aileron-amp", "0.03", "--rudder", "multisine", "--rudder-amp", "0.3",
      "--ms-period", "10", "--ms-fmin", "0.1", "--ms-fmax", "1.5", "--duration", "30",
      "--noise-seed", "23"]),
]

COMMON = ["--rate", "120", "--log-rate", "60", "--noise-preset", "typical"]


def variants(text):
    """The mapping as given, and its hostile variants (name, text)."""
    out = [("as_given", text)]
    out.append(("surface_deg_as_rad", re.sub(
        r'^(de|da|dr) = \{ column = "(\w+)", unit = "rad"',
        r'\1 = { column = "\2", unit = "rad", scale = 57.29578', text, flags=re.M)
        .replace('scale = 57.29578, scale = -1.0', 'scale = -57.29578')))
    out.append(("reversed_surfaces", text.replace('unit = "rad", scale = -1.0', 'unit = "rad"')
                .replace('dr = { column = "rudder_rad_noisy", unit = "rad" }',
                         'dr = { column = "rudder_rad_noisy", unit = "rad", scale = -1.0 }')
                .replace('de = { column = "elevator_rad_noisy", unit = "rad" }',
                         'de = { column = "elevator_rad_noisy", unit = "rad", scale = -1.0 }')))
    out.append(("thrust_unmapped", "\n".join(
        l for l in text.splitlines() if not l.startswith(("thrust =", "thrust_moment =")))))
    return out


def truth_of(path, csv):
    """The JSBSim truth under the vocabulary's names and signs (δa flips).

    The presets have no `alphadot` term. Where the truth's `_alphadot` is more than 10 % of its
    `_q`, a preset's estimates of that coefficient are the structure's *equivalent* derivatives:
    in the short period α̇ ≈ q − Z_α α − Z_δe δe, so the α̇ moment is shared out over q̂, α and
    δe by how the record's inputs move them (Klein & Morelli 2006 §3.5). Their truth is then the
    least-squares projection of JSBSim's own noise-free coefficient onto the preset's regressors
    [1, α, q̂, δe] over the record (`equivalent`), not the full model's derivatives."""
    d = json.loads(Path(path).read_text())["derivatives"]
    out = {}
    for k, v in d.items():
        name = (k.replace("_phat", "_p").replace("_qhat", "_q").replace("_rhat", "_r")
                .replace("_adothat", "_alphadot"))
        out[name] = -v if name.endswith("_da") else v
    for c in ("CL", "Cm"):
        q, ad = out.get(f"{c}_q"), out.get(f"{c}_alphadot")
        if q is not None and ad is not None and abs(ad) > 0.1 * abs(q):
            for term, value in zip(("0", "alpha", "q", "de"), equivalent(csv, c)):
                out[f"{c}_{term}"] = value
    return out


def equivalent(csv, coefficient):
    """Least squares of the record's noise-free `coefficient` column on [1, α, q̂, δe] (the
    clean columns; q̂ = q c̄ / 2V), by the normal equations."""
    import csv as csvmod
    rows = list(csvmod.DictReader(open(csv)))
    x, y = [], []
    for r in rows:
        v, cbar = float(r["vt_fps"]), float(r["cbar_ft"])
        x.append([1.0, float(r["alpha_rad"]), float(r["q"]) * cbar / (2 * v),
                  float(r["elevator_rad"])])
        y.append(float(r[coefficient]))
    n = len(x[0])
    a = [[sum(xi[i] * xi[j] for xi in x) for j in range(n)] + [sum(xi[i] * yi for xi, yi in zip(x, y))]
         for i in range(n)]
    for i in range(n):
        p = max(range(i, n), key=lambda k: abs(a[k][i]))
        a[i], a[p] = a[p], a[i]
        for k in range(n):
            if k != i:
                f = a[k][i] / a[i][i]
                a[k] = [ak - f * ai for ak, ai in zip(a[k], a[i])]
    return [a[i][n] / a[i][i] for i in range(n)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--python", required=True, help="a Python with jsbsim==1.3.3")
    ap.add_argument("--bin", default=str(ROOT / "target/release/aeroident"))
    ap.add_argument("--out", default="/tmp/aeroident-verdict-audit")
    ap.add_argument("--estimators", default="rls,ekf,oe")
    ap.add_argument("--cross-check", action="store_true",
                    help="replay with --cross-check (the record's other methods beside each)")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    base_map = MAP.read_text()
    rows = []
    for name, model, args in FLIGHTS:
        csv, tj = out / f"{name}.csv", out / f"{name}_truth.json"
        if not csv.exists():
            subprocess.run([a.python, str(TOOL), *args, *COMMON, "--out", str(csv),
                            "--derivs-json", str(tj)], check=True, capture_output=True)
        truth = truth_of(tj, csv)
        for vname, text in variants(base_map):
            mp = out / f"map_{vname}.toml"
            mp.write_text(text)
            for est in a.estimators.split(","):
                d = out / f"{name}-{vname}-{est}"
                p = subprocess.run([a.bin, "replay", str(csv), "--map", str(mp), "--model", model,
                                    "--estimator", est, "--out", str(d),
                                    *(["--cross-check"] if a.cross_check else [])],
                                   capture_output=True, text=True)
                if p.returncode != 0:
                    print(f"{name:20s} {vname:18s} {est:4s} exit {p.returncode}: "
                          f"{p.stderr.strip().splitlines()[-1][:100]}")
                    continue
                s = json.loads((d / "summary.json").read_text())
                for q in s["parameters"]:
                    t = truth.get(q["name"])
                    if q["name"] not in PRIMARY or t is None or abs(t) < 1e-9:
                        continue
                    e = q["estimate"]
                    err = None if e is None else abs(e - t) / abs(t)
                    rows.append({"flight": name, "mapping": vname, "estimator": est,
                                 "name": q["name"], "truth": t, "estimate": e, "error": err,
                                 "status": q["status"], "flags": q["flags"]})
    (out / "audit.json").write_text(json.dumps(rows, indent=1))
    report(rows)


def report(rows):
    def count(sel):
        ident = [r for r in sel if r["status"] == "identified"]
        bad_ok = [r for r in ident if r["error"] is not None and r["error"] > 0.10]
        good = [r for r in sel if r["error"] is not None and r["error"] <= 0.10]
        good_ok = [r for r in good if r["status"] == "identified"]
        return len(sel), len(ident), len(bad_ok), len(good), len(good_ok)
    keys = sorted({(r["flight"], r["mapping"], r["estimator"]) for r in rows})
    print("flight               mapping            est  n  identified  >10%-off-identified  "
          "within-10%  of-which-identified")
    for k in keys:
        n, i, b, g, gi = count([r for r in rows if (r["flight"], r["mapping"], r["estimator"]) == k])
        print(f"{k[0]:20s} {k[1]:18s} {k[2]:4s} {n:2d} {i:6d} {b:12d} {g:16d} {gi:12d}")
    n, i, b, g, gi = count(rows)
    print(f"TOTAL: {n} primary estimates; identified {i}; identified but >10 % off {b} "
          f"({100 * b / max(i, 1):.0f} % of identified); within 10 % {g}, of which identified "
          f"{gi} ({100 * gi / max(g, 1):.0f} %)")
    # A plausibility flag is right to fire where the truth itself lies outside the range it
    # names (a simulator's model no conventional aircraft has): such estimates are counted apart.
    def truth_outside(r):
        for f in r["flags"]:
            m = re.search(r"range of a conventional aircraft \[([-0-9.e+]+), ([-0-9.e+]+)\]", f)
            if m and not float(m.group(1)) <= r["truth"] <= float(m.group(2)):
                return True
        return False
    good = [r for r in rows if r["error"] is not None and r["error"] <= 0.10]
    apart = [r for r in good if truth_outside(r)]
    rest = [r for r in good if not truth_outside(r)]
    ok = [r for r in rest if r["status"] == "identified"]
    print(f"  within 10 % with a truth outside the plausible range its flag names: {len(apart)}; "
          f"of the other {len(rest)}, identified {len(ok)} ({100 * len(ok) / max(len(rest), 1):.0f} %)")
    for r in rows:
        if r["status"] == "identified" and r["error"] is not None and r["error"] > 0.10:
            print(f"  identified but {100 * r['error']:.0f} % off: {r['flight']} {r['mapping']} "
                  f"{r['estimator']} {r['name']} = {r['estimate']:.4g} (truth {r['truth']:.4g})")


if __name__ == "__main__":
    sys.exit(main())
