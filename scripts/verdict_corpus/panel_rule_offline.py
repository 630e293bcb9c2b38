"""Offline estimate of a candidate panel rule from stored replays, without replaying: an
estimate the panel confirmed is counted as flagged when two of the methods it agrees with
disagree with each other (agreement as `Estimate::agrees` in
crates/pipelines/src/replay/cross_check.rs: 2 combined σ or 10 % of the larger magnitude).

    python3 panel_rule_offline.py DIR/joined-<half>-<tag>.json DIR/runs-<tag>

Prints precision, recall and ±2σ coverage of `identified` per method, before and after.
"""
import json, math, sys
from pathlib import Path
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
def newly_flagged(r):
    q = panel(r["record"], r["estimator"]).get(r["name"])
    if not q or not q.get("confirmed"): return False
    aside = {s["method"] for s in q.get("set_aside", [])}
    left = [e for e in q["estimates"] if e["method"] not in aside and e.get("std_error") is not None]
    mine = [e for e in left if e["method"] == r["estimator"]]
    if not mine: return False
    mine = mine[0]
    allies = [e for e in left if e is not mine and agrees(mine, e)]
    return any(not agrees(a, b) for i, a in enumerate(allies) for b in allies[i+1:])
def metrics(rows, rule):
    ident = [r for r in rows if r["status"] == "identified" and not (rule and newly_flagged(r))]
    right = [r for r in rows if r["right10"]]
    ir = [r for r in ident if r["right10"]]; cov = [r for r in ident if r["covered"]]
    return len(ident), len(ir) / len(ident), len(ir) / len(right), len(cov) / len(ident)
for est in [None, "rls", "rls-iv", "ftr", "ekf", "oe", "fdoe"]:
    sel = [r for r in rows if est is None or r["estimator"] == est]
    a = metrics(sel, False); b = metrics(sel, True)
    print("%-7s before n=%d prec %.3f rec %.3f cov %.3f | after n=%d prec %.3f rec %.3f cov %.3f" % ((est or "all",) + a + b))
