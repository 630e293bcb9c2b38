"""A pitch-rate controller that re-learns a damaged F-16 in flight.

The F-16 (Stevens & Lewis, xcg 0.30) flies level at 20,000 ft and 675 ft/s under a
proportional-integral pitch-rate controller,

    de = de_trim + K (q - q_cmd) + K_i * integral(q - q_cmd) dt,

tracking a +-2 deg/s square wave. At t = 10 s half the elevator's effectiveness and a third of
the pitch damping are lost (Cm_de and Cm_q increments about the trim). The loop gain is
M_de * K: with K fixed, the loop slows and the tracking error grows. The adaptive loop keeps
M_de * K constant from the real-time estimate of Cm_de (recursive least squares with forgetting
on each step's air-data sample):

    K = K0 * Cm_de_before / Cm_de_hat     (limited to 1-4 x K0)

where Cm_de_before is the estimate just before the damage. Both runs fly the same aircraft,
inputs and damage; they differ only in the gain.

Run:  python examples/python_adaptive_pitch.py [--plot adaptive_pitch.png]
It prints the RMS tracking error before and after the damage with and without adaptation, and
the estimates of Cm_de and Cm_q against the damaged aircraft's. Needs the `aeroident` package
(README, "Python"); the plot needs matplotlib.
"""
import argparse
import math

import numpy as np

import aeroident

VT_MPS, ALT_M = 675 * 0.3048, 20_000 * 0.3048
DT_S, DURATION_S, ONSET_S = 0.01, 30.0, 10.0
Q = 7  # state index of the pitch rate in the F-16's state (rad/s)
K0, KI = 0.8, 1.5  # rad per rad/s, rad per rad
DAMAGE = {"Cm_de": 0.29, "Cm_q": 2.2}  # about half of Cm_de (-0.58), a third of Cm_q (-6.7)


def q_command(t):
    """+-2 deg/s square wave of period 4 s from t = 1 s, rad/s."""
    if t < 1.0:
        return 0.0
    return math.radians(2.0) * (1.0 if int((t - 1.0) / 2.0) % 2 == 0 else -1.0)


def run(adapt):
    """Flies the closed loop; returns the time histories as numpy arrays."""
    nominal = aeroident.Aircraft.f16(xcg=0.30)
    trim = nominal.trim(VT_MPS, ALT_M)
    aircraft = nominal.with_damage(DAMAGE, about=trim, onset_s=ONSET_S)
    est = aeroident.Estimator("rls", model="longitudinal", forgetting=0.99)
    cm_de_index = est.names.index("Cm_de")
    x, u0 = trim["state"], trim["controls"]
    integral, gain, cm_de_before = 0.0, K0, None
    out = {k: [] for k in ("t", "q", "q_cmd", "de", "gain", "cm_de_hat", "cm_q_hat")}
    for k in range(int(DURATION_S / DT_S)):
        t = k * DT_S
        q_cmd = q_command(t)
        err = x[Q] - q_cmd
        de = u0[1] + gain * err + KI * integral
        u = [u0[0], de, u0[2], u0[3]]
        est.update(aircraft.sample(x, u, t_s=t))
        e = est.estimates()
        cm_de_hat = e["estimate"][cm_de_index]
        if adapt and cm_de_hat is not None and t >= 2.0:
            if t < ONSET_S:
                cm_de_before = cm_de_hat
            elif cm_de_before is not None:
                gain = K0 * min(4.0, max(1.0, cm_de_before / cm_de_hat))
        for key, v in (("t", t), ("q", x[Q]), ("q_cmd", q_cmd), ("de", de), ("gain", gain),
                       ("cm_de_hat", cm_de_hat), ("cm_q_hat", e["estimate"][est.names.index("Cm_q")])):
            out[key].append(math.nan if v is None else v)
        integral += err * DT_S
        x = aircraft.step(x, u, DT_S, t_s=t)
    return {k: np.asarray(v) for k, v in out.items()}


def rms_error(r, t0, t1):
    """RMS of q - q_cmd over [t0, t1), deg/s."""
    m = (r["t"] >= t0) & (r["t"] < t1)
    return math.degrees(float(np.sqrt(np.mean((r["q"][m] - r["q_cmd"][m]) ** 2))))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plot", help="write the responses to this image (needs matplotlib)")
    a = ap.parse_args()
    fixed, adaptive = run(False), run(True)
    for name, r in (("fixed gain", fixed), ("adaptive", adaptive)):
        print(f"{name:>10}: RMS q error {rms_error(r, 2.0, ONSET_S):.3f} deg/s before the damage, "
              f"{rms_error(r, ONSET_S + 2.0, DURATION_S):.3f} deg/s after; final gain {r['gain'][-1]:.2f}")
    print(f"Cm_de estimate: {adaptive['cm_de_hat'][int(ONSET_S / DT_S) - 1]:.3f} before, "
          f"{adaptive['cm_de_hat'][-1]:.3f} at the end; Cm_q {adaptive['cm_q_hat'][-1]:.2f}")
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(2, 1, sharex=True, figsize=(8, 5))
        ax[0].plot(fixed["t"], np.degrees(fixed["q_cmd"]), "k--", lw=1, label="command")
        ax[0].plot(fixed["t"], np.degrees(fixed["q"]), label="fixed gain")
        ax[0].plot(adaptive["t"], np.degrees(adaptive["q"]), label="adaptive")
        ax[0].axvline(ONSET_S, color="r", lw=0.8)
        ax[0].set_ylabel("q, deg/s")
        ax[0].legend(loc="upper right", fontsize=8)
        ax[1].plot(adaptive["t"], adaptive["cm_de_hat"], label="Cm_de estimate (RLS)")
        ax[1].axvline(ONSET_S, color="r", lw=0.8)
        ax[1].set_ylabel("Cm_de, 1/rad")
        ax[1].set_xlabel("time, s")
        ax[1].legend(loc="upper right", fontsize=8)
        fig.tight_layout()
        fig.savefig(a.plot, dpi=90)
        print(f"wrote {a.plot}")


if __name__ == "__main__":
    main()
