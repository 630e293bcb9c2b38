"""Offline estimate of candidate panel rules from stored replays, without replaying: an
estimate the panel confirmed is counted as flagged when the rule holds among the methods it
agrees with (agreement as `Estimate::agrees` in crates/pipelines/src/replay/cross_check.rs:
2 combined σ or 10 % of the larger magnitude).

    python3 panel_rule_offline.py DIR/joined-<half>-<tag>.json DIR/runs-<tag> [-v]

Prints precision, recall and ±2σ coverage of `identified`, before and after each rule (per
method with -v). The rules:
- v1: two of the methods it agrees with disagree with each other;
- v5: the same, with the estimate strictly between the two;
- v6: the same, the two of families other than its own and each other's;
- v7 (adopted): every method of another family that agrees with it disagrees with some other
  method that agrees with it (`contested_confirmation` in cross_check.rs).
"""
import json, math, sys
from pathlib import Path
FAM = lambda m: {"rls-iv": "iv", "oe": "oe", "fdoe": "oe", "fem": "fem", "ekf": "ekf"}.get(m, "ls")
runs = Path(sys.argv[2]); rows = json.load(open(sys.argv[1]))
def agrees(a, b):
    d = abs(a["estimate"] - b["estimate"])
    return d <= 2.0 * math.hypot(a["std_error"], b["std_error"]) or d <= 0.10 * max(abs(a["estimate"]), abs(b["estimate"]))
cache = {}
def panel(rec, est):
    k = (rec, est)
    if k not in cache:
        p = runs / rec / est / "summary.json"
        cc = json.loads(p.read_text()).get("cross_check") if p.exists() else None
        cache[k] = {q["parameter"]: q for q in (cc or {}).get("parameters", [])}
    return cache[k]
def ctx(r):
    q = panel(r["record"], r["estimator"]).get(r["name"])
    if not q or not q.get("confirmed"): return None
    aside = {s["method"] for s in q.get("set_aside", [])}
    left = [e for e in q["estimates"] if e["method"] not in aside and e.get("std_error") is not None]
    mine = [e for e in left if e["method"] == r["estimator"]]
    if not mine: return None
    mine = mine[0]
    return mine, [e for e in left if e is not mine and agrees(mine, e)]
def v1(r):
    c = ctx(r)
    if not c: return False
    mine, al = c
    return any(not agrees(a, b) for i, a in enumerate(al) for b in al[i+1:])
def v5(r):  # mine strictly between two allies that disagree
    c = ctx(r)
    if not c: return False
    mine, al = c; m = mine["estimate"]
    return any(not agrees(a, b) and min(a["estimate"], b["estimate"]) < m < max(a["estimate"], b["estimate"]) for i, a in enumerate(al) for b in al[i+1:])
def v6(r):  # the disagreeing allies are of families other than mine and of each other
    c = ctx(r)
    if not c: return False
    mine, al = c; f = FAM(mine["method"])
    return any(not agrees(a, b) and FAM(a["method"]) != f and FAM(b["method"]) != f and FAM(a["method"]) != FAM(b["method"]) for i, a in enumerate(al) for b in al[i+1:])
def v7(r):  # every independent-family ally disagrees with another independent-family ally
    c = ctx(r)
    if not c: return False
    mine, al = c; f = FAM(mine["method"])
    ind = [a for a in al if FAM(a["method"]) != f]
    return bool(ind) and all(any(not agrees(a, b) for b in al if b is not a) for a in ind)
V = {"v1": v1, "v5": v5, "v6": v6, "v7": v7}
def metrics(rows, rule):
    ident = [r for r in rows if r["status"] == "identified" and not (rule and rule(r))]
    right = [r for r in rows if r["right10"]]
    ir = [r for r in ident if r["right10"]]; cov = [r for r in ident if r["covered"]]
    return len(ident), len(ir), len(ir) / len(ident), len(ir) / len(right), len(cov) / len(ident)
for est in [None] + (["rls", "rls-iv", "ftr", "ekf", "oe", "fdoe"] if "-v" in sys.argv else []):
    sel = [r for r in rows if est is None or r["estimator"] == est]
    b = metrics(sel, None)
    print("%-7s base  n=%d right=%d prec %.3f rec %.3f cov %.3f" % ((est or "all",) + b))
    for k, f in V.items():
        a = metrics(sel, f)
        print("%-7s %-5s n=%d right=%d prec %.3f rec %.3f cov %.3f  (lost right %d, wrong removed %d)" % ((est or "all", k) + a + (b[1] - a[1], (b[0] - b[1]) - (a[0] - a[1]))))
