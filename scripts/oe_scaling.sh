#!/usr/bin/env bash
# Time and peak memory of a batch output-error fit against record length (docs/reliability.md,
# "Output error on long records"). Flies the F-16 (`aeroident f16 sim`, tables, 20,000 ft,
# 675 ft/s) through two elevator doublets for 60 s with white sensor noise on V, α, θ, q, ax, az
# and q̇, once per seed; keeps every 10th row (10 Hz, 600 samples a manoeuvre) and concatenates
# 1, 10, 100 and 1,000 manoeuvres 40 s apart (600 … 600,000 samples; the replay splits them at
# the gaps), then fits each with the longitudinal model and reports wall time and peak RSS.
# Usage: scripts/oe_scaling.sh [WORKDIR] [MAX_MANOEUVRES]   (default /tmp/oe_scaling, 1000)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
work=${1:-/tmp/oe_scaling}
max=${2:-1000}
bin="$root/target/release/aeroident"
cargo build --release -q --manifest-path "$root/Cargo.toml" -p aeroident
mkdir -p "$work" && cd "$work"
sensors=""
for ch in vt_air_fps:0.2 alpha_air_rad:0.0005 theta_rad:0.0005 q_rad_s:0.0005 ax_fps2:0.05 az_fps2:0.1 qdot_rad_s2:0.005; do
  sensors+=$'[[sensor]]\nchannel = "'"${ch%%:*}"$'"\nwhite_sigma = '"${ch##*:}"$'\nsample_rate_hz = 100.0\n'
done
# The mapping: aeroident-sim.toml with the sensed channels read from their meas_ columns.
sed -E 's/column = "(vt_air_fps|alpha_air_rad|theta_rad|q_rad_s|ax_fps2|az_fps2|qdot_rad_s2)"/column = "meas_\1"/' \
  "$root/mappings/aeroident-sim.toml" > meas.toml
for k in $(seq 1 "$max"); do
  [ -s "rows_$k.csv" ] && continue
  cat > m.toml <<TOML
kind = "sim"
[aircraft]
xcg = 0.30
actuators = "f16"
[trim]
alt_ft = 20000.0
vt_fps = 675.0
[run]
duration_s = 60.0
dt_s = 0.01
seed = $k
[[input]]
channel = "elevator"
kind = "doublet"
amplitude_deg = 1.5
start_s = 2.0
pulse_width_s = 1.0
[[input]]
channel = "elevator"
kind = "doublet"
amplitude_deg = -1.0
start_s = 30.0
pulse_width_s = 1.5
$sensors
TOML
  "$bin" f16 sim m.toml --out s >/dev/null
  awk -F, -v k="$k" -v OFS=, 'NR==1{next} (NR-2)%10==0 && NR<6002 {$1=sprintf("%.3f",$1+(k-1)*100); print}' \
    s/timeseries.csv > "rows_$k.csv"
  head -1 s/timeseries.csv > header.csv
done
for n in 1 10 100 1000; do
  [ "$n" -gt "$max" ] && break
  { cat header.csv; for k in $(seq 1 "$n"); do cat "rows_$k.csv"; done; } > "rec_$n.csv"
  rm -rf "fit_$n"
  /usr/bin/time -f "%e s wall, %U s user, %M kB peak RSS" "$bin" replay "rec_$n.csv" --map meas.toml \
    --model longitudinal --estimator oe --out "fit_$n" 2>&1 | grep -E "manoeuvre|peak RSS"
done
