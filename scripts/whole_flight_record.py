#!/usr/bin/env python3
"""An 80-minute, 10 Hz whole-flight record for timing `aeroident compat` (docs/real-data.md,
"A whole flight's compatibility check: what it costs").

The F-16 of scenarios/sim/ahrs_delay_nobeta.toml (AHRS 0.2 s late, biases and scale factors, no
beta vane) flown for 4,800 s through a doublet every 45 s on the elevator, aileron, rudder and
elevator again, every sensor at 10 Hz; the simulator's 50 Hz rows kept at every 5th (the
sensors' samples), and the shipped simulator mapping pointed at the measured columns without
beta.

    python3 scripts/whole_flight_record.py OUT_DIR [AEROIDENT]   # OUT_DIR/flight80.csv, map80.toml
"""
import csv
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SENSED = ["vt_air_fps", "alpha_air_rad", "ax_fps2", "ay_fps2", "az_fps2", "p_rad_s",
          "q_rad_s", "r_rad_s", "phi_rad", "theta_rad", "psi_rad"]
INPUTS = [("elevator", 1.5, 1.0), ("aileron", 3.0, 1.0), ("rudder", 3.0, 1.0),
          ("elevator", -1.0, 1.5)]


def scenario() -> str:
    base = (ROOT / "scenarios/sim/ahrs_delay_nobeta.toml").read_text()
    head, rest = base.split("[[input]]", 1)
    sensors = "[[sensor]]" + rest.split("[[sensor]]", 1)[1]
    sensors = sensors.replace("sample_rate_hz = 100.0", "sample_rate_hz = 10.0")
    head = head.replace("duration_s = 40.0", "duration_s = 4800.0")
    head = head.replace("dt_s = 0.01", "dt_s = 0.02")
    inputs = []
    for i, start in enumerate(range(30, 4780, 45)):
        channel, amplitude, width = INPUTS[i % 4]
        inputs.append(f'[[input]]\nchannel = "{channel}"\nkind = "doublet"\n'
                      f"amplitude_deg = {amplitude}\nstart_s = {start}.0\n"
                      f"pulse_width_s = {width}\n")
    return head + "\n".join(inputs) + "\n" + sensors


def main() -> None:
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    (out / "flight80.toml").write_text(scenario())
    aeroident = sys.argv[2] if len(sys.argv) > 2 else str(ROOT / "target/release/aeroident")
    subprocess.run([aeroident, "sim", str(out / "flight80.toml"), "--out", str(out / "sim")],
                   check=True)
    with open(out / "sim/timeseries.csv") as f, open(out / "flight80.csv", "w") as o:
        rows = csv.reader(f)
        o.write(",".join(next(rows)) + "\n")
        for k, row in enumerate(rows):
            if k % 5 == 0:
                o.write(",".join(row) + "\n")
    mapping = (ROOT / "mappings/aeroident-sim.toml").read_text().splitlines()
    text = "\n".join(line for line in mapping if not line.startswith("beta ="))
    for c in SENSED:
        text = text.replace(f'column = "{c}"', f'column = "meas_{c}"')
    (out / "map80.toml").write_text(text + "\n")


if __name__ == "__main__":
    main()
