#!/usr/bin/env python3
"""Fly one corpus record with JSBSim: `../shared/tools/jsbsim_log.py` with composite inputs.

Run by `corpus.py make` with a Python that has `jsbsim` (the CI venv
`/tmp/aeroident-ci-venv-jsbsim/bin/python`); not meant to be called by hand:

    PY fly.py SPEC.json

SPEC.json (written by corpus.py):
    {"tool": ".../shared/tools/jsbsim_log.py",
     "args": [jsbsim_log.py command-line arguments: --aircraft, --alt, --vt, --rate,
              --log-rate, --duration, --noise-preset, --noise-scale, --noise-seed,
              --coef-columns, --out, --derivs-json],
     "inputs": {"elevator"|"aileron"|"rudder": [segment, ...]},
     "servo": {"elevator": {"tau": s, "rate": cmd units/s}, ...} | null,
     "servo_log": path of a CSV of the per-step commands (when "servo" is set)}

A segment is {"kind": "doublet"|"3211"|"multisine"|"chirp"|"pilot", "t0": s, "amp": cmd
units, ...}: doublet/3211 "width" (s); multisine "T" (s) and "ks" (the harmonics k/T of this
surface, dealt out by corpus.py so that the surfaces of one manoeuvre are orthogonal);
chirp "f0", "f1" (Hz), "len" (s) (a linear sweep, 0.5 s cosine taper at both ends);
pilot "pulses": [[start offset s, duration s, amplitude], ...] (trapezoids with 0.12 s
ramps: irregular doublets as a hand flies them). "recenter": the free-play take-up pulse
of jsbsim_log.py (c172x elevator) after the segment, against the side from which the
segment returns to zero.

Why not the jsbsim_log.py command line: it has one input per surface. The corpus needs
several manoeuvres per record (the same surface excited again after a quiet stretch),
chirps, irregular 'pilot' doublets and a servo between the command and the surface. So
this script imports jsbsim_log and replaces only its `build_signals` (the trim, the
simulation loop, the CSV, the noise and the truth JSON are jsbsim_log.py's own); the
'inputs' key of the truth JSON then describes the composite segments.

Servo (degradation 'servo'): each excited surface's command goes through a rate-limited
first-order lag before JSBSim sees it; the per-step command and the applied value are
written to "servo_log", from which corpus.py puts the *command* into the logged surface
column (the clean `*_rad` columns stay the true surface positions).
"""
import importlib.util
import json
import math
import sys

RAMP = 0.12          # s, pilot pulse edges
TAPER = 0.5          # s, chirp cosine taper


def load_tool(path):
    spec = importlib.util.spec_from_file_location("jsbsim_log", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


class Segment:
    """One input segment on one surface (a function of absolute time)."""

    def __init__(self, jl, d):
        self.d = d
        self.kind, self.t0, self.amp = d["kind"], float(d["t0"]), float(d["amp"])
        self.sig = None
        if self.kind in ("doublet", "3211"):
            self.sig = jl.Signal(self.kind, self.t0, self.amp, float(d["width"]), 1.0, 0.0,
                                 float(d.get("recenter", 0.0)),
                                 float(d.get("recenter_dur", 0.2)))
            self.end = self.t0 + (2 if self.kind == "doublet" else 7) * float(d["width"])
            self.own_recenter = True
        else:
            self.own_recenter = False
            if self.kind == "multisine":
                self.sig = jl.Signal("multisine", self.t0, self.amp, 0.5, 1.0, 1.0)
                self.sig.setup_multisine(float(d["T"]), [int(k) for k in d["ks"]])
                self.end = self.t0 + float(d["T"])
            elif self.kind == "chirp":
                self.end = self.t0 + float(d["len"])
            elif self.kind == "pilot":
                self.end = self.t0 + max(s + w for s, w, _ in d["pulses"]) + RAMP
            else:
                raise SystemExit("unknown segment kind %r" % self.kind)
        # free-play take-up after the segment, against the side it returns from
        self.recenter = 0.0
        if not self.own_recenter and float(d.get("recenter", 0.0)) > 0:
            before = self.raw(self.end - 0.02)
            if before != 0.0:
                self.recenter = -math.copysign(float(d["recenter"]), before)

    def raw(self, t):
        if t < self.t0 or t > self.end + 1e-9:
            return 0.0
        if self.sig is not None:
            return self.sig(t)
        tau = t - self.t0
        if self.kind == "chirp":
            f0, f1, n = float(self.d["f0"]), float(self.d["f1"]), float(self.d["len"])
            phase = 2 * math.pi * (f0 * tau + 0.5 * (f1 - f0) * tau * tau / n)
            w = 1.0
            if tau < TAPER:
                w = 0.5 - 0.5 * math.cos(math.pi * tau / TAPER)
            elif tau > n - TAPER:
                w = 0.5 - 0.5 * math.cos(math.pi * max(n - tau, 0.0) / TAPER)
            return self.amp * w * math.sin(phase)
        v = 0.0
        for s, w, a in self.d["pulses"]:
            x = tau - s
            if 0.0 <= x <= w + RAMP:
                v += a * min(1.0, x / RAMP, (w + RAMP - x) / RAMP)
        return v

    def __call__(self, t):
        if self.sig is not None and self.own_recenter:
            return self.sig(t)          # jsbsim_log's own recenter pulse included
        v = self.raw(t)
        if self.recenter and self.end < t <= self.end + float(self.d.get("recenter_dur", 0.2)):
            v += self.recenter
        return v

    def describe(self):
        out = dict(self.d)
        if self.sig is not None:
            out["jsbsim_log"] = self.sig.describe()
        if self.recenter:
            out["recenter_pulse"] = {"start_s": self.end,
                                     "duration_s": float(self.d.get("recenter_dur", 0.2)),
                                     "amp": self.recenter}
        return out


class Composite:
    """The sum of a surface's segments, optionally through a rate-limited first-order servo."""

    def __init__(self, segments, servo, dt, log):
        self.segments, self.servo, self.dt, self.log = segments, servo, dt, log
        self.y = 0.0

    def __call__(self, t):
        u = sum(s(t) for s in self.segments)
        if not self.servo:
            return u
        tau, rate = float(self.servo["tau"]), float(self.servo["rate"])
        dy = (u - self.y) * min(1.0, self.dt / tau)
        lim = rate * self.dt
        self.y += max(-lim, min(lim, dy))
        self.log.append((t, u, self.y))
        return self.y

    def describe(self):
        if not self.segments:
            return {"kind": "none"}
        d = {"kind": "composite", "segments": [s.describe() for s in self.segments]}
        if self.servo:
            d["servo"] = self.servo
        return d


# JSBSim's default integrators (FGPropagate): rectangular Euler for the body rates and the
# attitude, Adams-Bashforth 2 for the velocities. Forward Euler moves an oscillatory pole
# λ = −ζω ± iω to ln(1 + λh)/h ≈ λ − λ²h/2, whose real part gains (1 − ζ²)ω²h/2: at 120 Hz
# and a Dutch roll of 1.5 rad/s that is 0.009 1/s against a typical Dutch-roll ζω of 0.05–0.1, so the flight
# is damped about a tenth less than its aerodynamic tables say, and output error reads a
# tenth smaller |Cn_r|. Adams-Bashforth 2 for the rates and the attitude (second order, error
# ~ ω³h²; JSBSim's codes: 1 Euler, 3 AB2, 4 AB3) makes the flown dynamics those of the truth
# the record states; the velocities (AB2) and the position (AB3) keep JSBSim's defaults.
INTEGRATORS = {
    "simulation/integrator/rate/rotational": 3,
    "simulation/integrator/position/rotational": 3,
}


def integrate_to_second_order(jl):
    """Makes every JSBSim model the tool creates integrate with `INTEGRATORS`."""
    make = jl.make_fdm

    def make_fdm(*a, **k):
        fdm = make(*a, **k)
        for prop, kind in INTEGRATORS.items():
            fdm[prop] = kind
        return fdm

    jl.make_fdm = make_fdm


def main():
    spec = json.load(open(sys.argv[1]))
    jl = load_tool(spec["tool"])
    args = jl.build_parser().parse_args(spec["args"])
    dt = 1.0 / args.rate
    logs = {}
    signals = {}
    for s in jl.SURFACES:
        segs = [Segment(jl, d) for d in spec["inputs"].get(s, [])]
        servo = (spec.get("servo") or {}).get(s) if segs else None
        logs[s] = []
        signals[s] = Composite(segs, servo, dt, logs[s])
    jl.build_signals = lambda _args: signals
    integrate_to_second_order(jl)
    info = jl.run(args)
    if spec.get("servo") and spec.get("servo_log"):
        used = [s for s in jl.SURFACES if logs[s]]
        with open(spec["servo_log"], "w") as fh:
            fh.write("t," + ",".join("%s_cmd,%s_applied" % (s, s) for s in used) + "\n")
            for i in range(len(logs[used[0]])):
                fh.write("%.6f," % logs[used[0]][i][0] + ",".join(
                    "%.9g,%.9g" % (logs[s][i][1], logs[s][i][2]) for s in used) + "\n")
    json.dump({k: v for k, v in info.items() if k not in ("trim_state", "run")}, sys.stdout)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
