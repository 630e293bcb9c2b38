"""Loads an `aeroident export jsbsim` fragment into JSBSim and checks every exported function.

Usage: python jsbsim_load.py FRAGMENT.xml PARAMS.json
PARAMS.json maps parameter names to the values the fragment should carry (null = omitted).

The fragment replaces the <aerodynamics> of a copy of the c172x shipped with the jsbsim wheel;
the aircraft is trimmed nowhere: it is started at a state with non-zero alpha, beta, rates and
surface deflections and run a few steps. Then each function property aero/coefficient/<name>
must equal value * regressor * scaling, with the regressors computed here from JSBSim's state
(alpha, beta, body aero rates, true airspeed, chord, span, surface positions), independently
of the fragment's product. Omitted parameters must not exist as properties. Prints one JSON
line with the largest relative error; exits 1 on any failure.
"""
import json
import os
import shutil
import sys
import tempfile

import jsbsim


def main():
    frag = open(sys.argv[1]).read()
    params = json.load(open(sys.argv[2]))
    root = jsbsim.get_default_root_dir()
    tmp = tempfile.mkdtemp(prefix="aeroident-jsbsim-")
    for sub in ("engine", "systems"):
        if os.path.isdir(os.path.join(root, sub)):
            shutil.copytree(os.path.join(root, sub), os.path.join(tmp, sub))
    src = os.path.join(root, "aircraft", "c172x")
    dst = os.path.join(tmp, "aircraft", "c172x")
    shutil.copytree(src, dst)
    path = os.path.join(dst, "c172x.xml")
    xml = open(path).read()
    start = xml.index("<aerodynamics>")
    end = xml.index("</aerodynamics>") + len("</aerodynamics>")
    open(path, "w").write(xml[:start] + frag + xml[end:])

    fdm = jsbsim.FGFDMExec(tmp)
    fdm.set_debug_level(0)
    if not fdm.load_model("c172x"):
        print("JSBSim did not load the aircraft with the fragment")
        sys.exit(1)
    for k, v in {
        "ic/h-sl-ft": 3000.0, "ic/vt-kts": 100.0, "ic/alpha-deg": 4.0, "ic/beta-deg": 2.0,
        "ic/p-rad_sec": 0.1, "ic/q-rad_sec": 0.05, "ic/r-rad_sec": -0.08,
    }.items():
        fdm[k] = v
    fdm.run_ic()
    fdm["fcs/elevator-cmd-norm"] = 0.3
    fdm["fcs/aileron-cmd-norm"] = 0.2
    fdm["fcs/rudder-cmd-norm"] = -0.1
    for _ in range(5):
        fdm.run()

    g = lambda p: fdm[p]
    alpha, beta = g("aero/alpha-rad"), g("aero/beta-rad")
    p, q, r = g("velocities/p-aero-rad_sec"), g("velocities/q-aero-rad_sec"), g("velocities/r-aero-rad_sec")
    vt, cbar, b, qs = g("velocities/vt-fps"), g("metrics/cbarw-ft"), g("metrics/bw-ft"), g("aero/qbar-area")
    de, dr = g("fcs/elevator-pos-rad"), g("fcs/rudder-pos-rad")
    # aeroident's δa > 0 gives a negative rolling moment; JSBSim's aileron > 0 rolls right.
    da = -g("fcs/left-aileron-pos-rad")
    adot = g("aero/alphadot-rad_sec")
    regressor = {
        "0": 1.0, "alpha": alpha, "alpha2": alpha * alpha, "beta": beta, "alpha_beta": alpha * beta,
        "p": p * b / (2 * vt), "q": q * cbar / (2 * vt), "r": r * b / (2 * vt),
        "alphadot": adot * cbar / (2 * vt), "de": de, "da": da, "dr": dr, "alpha_de": alpha * de,
    }
    scale = {"Cl": qs * b, "Cm": qs * cbar, "Cn": qs * b}
    state = dict(alpha=alpha, beta=beta, p=p, q=q, r=r, de=de, da=da, dr=dr, qbar_area=qs)
    worst, failures = 0.0, []
    for name, value in params.items():
        prop = "aero/coefficient/" + name
        coef, term = name.split("_", 1)
        exists = fdm.get_property_manager().hasNode(prop)
        if value is None:
            if exists:
                failures.append(f"{name}: omitted but {prop} exists")
            continue
        if not exists:
            failures.append(f"{name}: {prop} missing")
            continue
        if term not in regressor:
            failures.append(f"{name}: term {term} not checked here")
            continue
        expected = value * regressor[term] * scale.get(coef, qs)
        got = g(prop)
        if expected == 0.0:
            failures.append(f"{name}: regressor is 0 at the test state (no check)")
            continue
        rel = abs(got - expected) / abs(expected)
        worst = max(worst, rel)
        if rel > 1e-9:
            failures.append(f"{name}: JSBSim {got} vs expected {expected}")
    print(json.dumps({"checked": sum(v is not None for v in params.values()),
                      "max_rel_error": worst, "state": state, "failures": failures}))
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
