"""The decision tool of v10 (docs/validation.md): the cross-check panel's rules applied to the
six methods' summaries that `corpus.py run` already wrote for each record, so that variants of
the panel can be compared on the tune half without replaying anything.

It mirrors `crates/pipelines/src/replay/cross_check.rs` for the causes that need no `fem`
(regressor noise against instrumental variables; unexplained splits; confirmation by a method
open to another bias). The EKF and process-noise causes need `fem`, which the corpus runs
leave out, and the equation-wide regressor-noise cause is not mirrored. It is a prototype:
the numbers that count are the shipped binary's on the held-out half (`corpus.py run` and
`report`).

    python3 panel_prototype.py --out /tmp/verdict-corpus --tag head --half tune
"""
import argparse
import json
import math
from pathlib import Path

import corpus

LEAST_SQUARES = ["rls", "ftr"]
PANELS = {
    "default (rls, rls-iv, ekf, oe, fdoe)": ["rls", "rls-iv", "ekf", "oe", "fdoe"],
    "without the EKF": ["rls", "rls-iv", "oe", "fdoe"],
    "batch and rls-iv only": ["rls-iv", "oe", "fdoe"],
}


def family(method):
    return {"rls-iv": "iv", "oe": "oe", "fdoe": "oe", "fem": "fem", "ekf": "ekf"}.get(method, "ls")


def load(out, tag, half):
    """{record: (meta, {method: (failed, {name: parameter}))}} of one half of a tagged run."""
    runs = Path(out) / ("runs-" + tag if tag else "runs")
    records = {}
    for mp in sorted((Path(out) / "records").glob("*/meta.json")):
        meta = json.loads(mp.read_text())
        rd = runs / meta["name"]
        if meta["half"] != half or not rd.exists():
            continue
        methods = {}
        for ed in rd.iterdir():
            if not (ed / "summary.json").exists():
                continue
            if json.loads((ed / "run.json").read_text())["exit"] != 0:
                continue
            s = json.loads((ed / "summary.json").read_text())
            ps = {q["name"]: q for q in s["parameters"]}
            failed = s["status"].startswith(("initialising", "diverged")) or any(
                q.get("status") == "not_converged" for q in s["parameters"])
            methods[ed.name] = (failed, ps)
        records[meta["name"]] = (meta, methods)
    return records


def sigma(q, noise):
    """The σ the panel compares: the full `std_error`, or without the timing and unmodelled
    shares (`noise`), as `ParameterResult::noise_std_error`."""
    sd = q["std_error"]
    if not noise:
        return sd
    shares = (q.get("timing_std_error") or 0.0) ** 2 + (q.get("unmodelled_std_error") or 0.0) ** 2
    return math.sqrt(max(sd * sd - shares, 0.0))


def agrees(a, b, sigmas):
    d = abs(a[0] - b[0])
    return d <= sigmas * math.hypot(a[1], b[1]) or d <= 0.10 * max(abs(a[0]), abs(b[0]))


def usable(q):
    e, sd = q.get("estimate"), q.get("std_error")
    return e is not None and sd is not None and math.isfinite(e) and math.isfinite(sd) and sd > 0


def confirmed(own, name, methods, panel, sigmas, noise):
    """Whether the panel confirms `own`'s estimate of `name` (the Rust module's rules)."""
    est = {}
    for m in [own] + [p for p in panel if p != own]:
        if m in methods and (m == own or not methods[m][0]):
            q = methods[m][1].get(name)
            if q is not None and usable(q):
                est[m] = (q["estimate"], sigma(q, noise))
    if own not in est:
        return False
    aside = set()
    if "rls-iv" in est:
        oes = [est[m][0] for m in ("oe", "fem", "ekf") if m in est]
        ref = sum(oes) / len(oes) if oes else None
        for ls in (m for m in LEAST_SQUARES if m in est):
            if agrees(est[ls], est["rls-iv"], sigmas):
                continue
            iv_further = ref is not None and abs(est["rls-iv"][0] - ref) > abs(est[ls][0] - ref)
            aside.add("rls-iv" if iv_further else ls)
    left = {m: v for m, v in est.items() if m not in aside and m != own}
    if own in aside or not left or any(not agrees(est[own], v, sigmas) for v in left.values()):
        return False
    return any(family(m) != family(own) for m in left)


def metrics(records, panel, sigmas, noise):
    """(identified, precision, recall, ±2σ coverage) over the primary derivatives, `panel`
    None: the summaries' own verdict."""
    ident = right = ident_right = covered = 0
    for meta, methods in records.values():
        for own, (_, ps) in methods.items():
            for name in corpus.PRIMARY:
                t, q = meta["truth"].get(name), ps.get(name)
                if q is None or t is None or not math.isfinite(t) or abs(t) < 1e-6:
                    continue
                e, sd = q.get("estimate"), q.get("std_error")
                ok = e is not None and abs(e - t) <= 0.10 * abs(t)
                right += ok
                idd = q.get("status") == "identified" and (
                    panel is None or confirmed(own, name, methods, panel, sigmas, noise))
                if idd:
                    ident += 1
                    ident_right += ok
                    covered += sd is not None and abs(e - t) <= 2 * sd
    n = max(ident, 1)
    return ident, ident_right / n, ident_right / max(right, 1), covered / n


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="/tmp/verdict-corpus")
    ap.add_argument("--tag", default="")
    ap.add_argument("--half", default="tune", choices=["tune", "held-out"])
    a = ap.parse_args()
    records = load(a.out, a.tag, a.half)
    row = "| %s | %d | %.1f %% | %.1f %% | %.1f %% |"
    print("%d records, half %s" % (len(records), a.half))
    print("| panel | identified | precision | recall | ±2σ coverage |\n|---|---|---|---|---|")
    i, p, r, c = metrics(records, None, 2.0, False)
    print(row % ("none (the summaries' verdict)", i, 100 * p, 100 * r, 100 * c))
    for label, panel in PANELS.items():
        for sigmas in (2.0, 3.0):
            for noise in (False, True):
                i, p, r, c = metrics(records, panel, sigmas, noise)
                name = "%s, %g σ, %s σ" % (label, sigmas, "noise" if noise else "full")
                print(row % (name, i, 100 * p, 100 * r, 100 * c))


if __name__ == "__main__":
    main()
