"""Flies an `aeroident export jsbsim --mapping` aircraft in the real JSBSim through the inputs
of an `aeroident sim` record, from the record's first row.

Usage: python jsbsim_fly.py ROOT NAME TIMESERIES.csv OUT.csv
       python jsbsim_fly.py --step ROOT NAME   (the elevator's response to a command step)

ROOT holds `aircraft/NAME/NAME.xml`. JSBSim starts at the record's first row (its trim: speed,
alpha, sideslip, pitch, bank, altitude, no rates: the lateral constants of an identified
aircraft, CY_0, Cl_0, Cn_0, are trimmed with a sideslip and surfaces) with standard gravity (`simulation/gravity-model`
0, as the record's flat earth), is stepped at 5 kHz with the record's surfaces and thrust
interpolated linearly in time (as `sim` ramps them between rows) into the aircraft's command
properties, and at each of the record's times writes t_s, p, q, r (rad/s), their rates
(rad/s²) and the specific force ax, ay, az (m/s², body axes: the aerodynamic and external
forces over the mass); the rates and forces are JSBSim's at that time's state with that
time's inputs (one extra step computes them, whose start they are). Exits 1 when JSBSim does not load the aircraft.
"""
import csv
import sys

import jsbsim

FT = 0.3048
# JSBSim's step, s: its rates lag its clock by about a step (1 ms moved p by 3 % of a 3°
# aileron doublet's peak; 0.2 ms by 0.8 %).
DT = 0.0002
N_PER_LBF = 4.4482216152605


def read(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def at(t, col, time):
    """Linear interpolation of col(t) at time (clamped to the record)."""
    if time <= t[0]:
        return col[0]
    if time >= t[-1]:
        return col[-1]
    lo, hi = 0, len(t) - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if t[mid] <= time:
            lo = mid
        else:
            hi = mid
    w = (time - t[lo]) / (t[hi] - t[lo])
    return col[lo] + w * (col[hi] - col[lo])


def load(root, name):
    """JSBSim with aircraft `name` of `root`, stepped at DT (set before loading: JSBSim computes
    its flight-control filters' coefficients from the step at load time)."""
    fdm = jsbsim.FGFDMExec(root)
    fdm.set_debug_level(0)
    fdm.set_dt(DT)
    if not fdm.load_model(name):
        print(f"JSBSim did not load aircraft {name} from {root}")
        sys.exit(1)
    return fdm


def step_response(root, name):
    """Prints the elevator position (rad) 50, 100 and 200 ms after a 0.05-rad command step
    from a settled start, one per line."""
    fdm = load(root, name)
    fdm["ic/h-sl-ft"], fdm["ic/vt-fps"] = 300.0, 60.0
    fdm.run_ic()
    for _ in range(5):
        fdm.run()
    t0 = fdm.get_sim_time()
    fdm["fcs/elevator-cmd-rad"] = 0.05
    for t in (0.05, 0.1, 0.2):
        while fdm.get_sim_time() - t0 < t - DT / 2:
            fdm.run()
        print(fdm["fcs/elevator-pos-rad"])


def main():
    if sys.argv[1] == "--step":
        step_response(*sys.argv[2:4])
        return
    root, name, record, out = sys.argv[1:5]
    r = read(record)
    t = r["t_s"]
    fdm = load(root, name)
    fdm["simulation/gravity-model"] = 0
    ic = {
        "ic/h-sl-ft": r["alt_m"][0] / FT, "ic/vt-fps": r["vt_mps"][0] / FT,
        "ic/alpha-rad": r["alpha_rad"][0], "ic/beta-rad": r["beta_rad"][0],
        "ic/theta-rad": r["theta_rad"][0], "ic/phi-rad": r["phi_rad"][0], "ic/psi-true-rad": 0.0, "ic/p-rad_sec": 0.0, "ic/q-rad_sec": 0.0,
        "ic/r-rad_sec": 0.0, "ic/lat-geod-deg": 45.0,
    }
    for k, v in ic.items():
        fdm[k] = v

    def command(time):
        fdm["fcs/elevator-cmd-rad"] = at(t, r["elevator_rad"], time)
        fdm["fcs/aileron-cmd-rad"] = at(t, r["aileron_rad"], time)
        fdm["fcs/rudder-cmd-rad"] = at(t, r["rudder_rad"], time)
        fdm["fcs/thrust-cmd-n"] = at(t, r["thrust_n"], time)

    command(0.0)
    fdm.run_ic()
    mass_kg = fdm["inertia/mass-slugs"] * 14.59390294
    rows = []
    for k, t_out in enumerate(t):
        while fdm.get_sim_time() < t_out - DT / 2:
            command(fdm.get_sim_time())
            fdm.run()
        rates = [fdm["velocities/p-rad_sec"], fdm["velocities/q-rad_sec"], fdm["velocities/r-rad_sec"]]
        # JSBSim's accelerations are those of its last step's start: one more step with the
        # row's own inputs gives them at the row's state and inputs.
        command(t_out)
        fdm.run()
        force = [
            (fdm[f"forces/fb{a}-aero-lbs"] + fdm[f"forces/fb{a}-external-lbs"]) * N_PER_LBF
            for a in "xyz"
        ]
        rows.append([
            t_out,
            *rates,
            fdm["accelerations/pdot-rad_sec2"], fdm["accelerations/qdot-rad_sec2"],
            fdm["accelerations/rdot-rad_sec2"],
            *[f / mass_kg for f in force],
        ])
    with open(out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t_s", "p_rad_s", "q_rad_s", "r_rad_s", "pdot_rad_s2", "qdot_rad_s2",
                    "rdot_rad_s2", "ax_mps2", "ay_mps2", "az_mps2"])
        w.writerows(rows)


if __name__ == "__main__":
    main()
