#!/usr/bin/env bash
# Bounded memory and steady throughput of `aeroident replay` over a long record (target:
# 24 h at 100 Hz through `replay -` and `replay FILE --out DIR`, peak RSS ≤ 64 MB, throughput of
# the last hour within 20 % of the first). See docs/reliability.md for the measured numbers.
#
#   scripts/long_replay.sh [HOURS] [RATE_HZ] [WORKDIR]     (default 24 100 /tmp/aeroident-long)
#
# 1. builds the release binary and the generator (crates/aeroident/examples/long_record.rs),
# 2. writes WORKDIR/long.csv (HOURS·3600·RATE_HZ fixed-width rows, ≈ 306 bytes each) and its
#    mapping WORKDIR/map.toml,
# 3. replays it twice under /usr/bin/time -v: `replay - < long.csv > /dev/null` (live mode, one
#    estimates line per sample on stdout) and `replay long.csv --out WORKDIR/out`,
# 4. samples the replay's /proc/PID/io `rchar` (bytes read = rows consumed, the rows having a
#    fixed length), its CPU time (/proc/PID/stat utime + stime) and /proc/PID/status VmRSS
#    every 0.5 s, and prints per mode the peak RSS (VmHWM and time -v's maximum resident set
#    size) and the throughput of the first and the last hour of the record, both per second of
#    wall time (depends on the machine's load) and per second of the replay's own CPU time
#    (the load-independent measure of whether the work per sample grows), from the samples at
#    which the reader passed the hour's first and last byte, linearly interpolated.
# Everything runs under `nice`. The record is deleted at the end unless KEEP=1. MODES="stdin"
# (or "file") runs one mode only: the file mode writes estimates.csv, ≈ 5.4× the record's size
# (≈ 14 GB for 24 h at 100 Hz); check the free disk first.
set -euo pipefail
HOURS=${1:-24}
RATE=${2:-100}
WORK=${3:-/tmp/aeroident-long}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
TARGET=${CARGO_TARGET_DIR:-$ROOT/target}
mkdir -p "$WORK"
(cd "$ROOT" && nice cargo build --release -q -p aeroident --bin aeroident --example long_record)
BIN=$TARGET/release/aeroident
GEN=$TARGET/release/examples/long_record
if [[ ! -s $WORK/long.csv || ${REGEN:-0} == 1 ]]; then
    echo "generating $HOURS h at $RATE Hz into $WORK/long.csv" >&2
    nice "$GEN" "$HOURS" "$RATE" --mapping "$WORK/map.toml" > "$WORK/long.csv" 2> "$WORK/gen.log"
fi

# run MODE: replays with a 0.5 s sampler of rchar and VmRSS into $WORK/MODE.samples
run() {
    local mode=$1
    local log=$WORK/$mode.samples
    : > "$log"
    if [[ $mode == stdin ]]; then
        nice /usr/bin/time -v "$BIN" replay - --map "$WORK/map.toml" \
            < "$WORK/long.csv" > /dev/null 2> "$WORK/$mode.stderr" &
    else
        rm -rf "$WORK/out"
        nice /usr/bin/time -v "$BIN" replay "$WORK/long.csv" --map "$WORK/map.toml" \
            --out "$WORK/out" > /dev/null 2> "$WORK/$mode.stderr" &
    fi
    local tpid=$!
    local pid=""
    for _ in $(seq 100); do
        pid=$(pgrep -P "$tpid" -x aeroident || true)
        [[ -n $pid ]] && break
        sleep 0.05
    done
    local t0
    t0=$(date +%s.%N)
    while [[ -n $pid && -r /proc/$pid/io ]]; do
        local rchar rss hwm now cpu
        rchar=$(awk '/^rchar/ {print $2}' "/proc/$pid/io" 2> /dev/null || true)
        rss=$(awk '/^VmRSS/ {print $2}' "/proc/$pid/status" 2> /dev/null || true)
        hwm=$(awk '/^VmHWM/ {print $2}' "/proc/$pid/status" 2> /dev/null || true)
        cpu=$(awk '{print $14 + $15}' "/proc/$pid/stat" 2> /dev/null || true)
        now=$(date +%s.%N)
        [[ -n $rchar && -n $rss && -n $cpu ]] &&
            echo "$(echo "$now - $t0" | bc) $rchar $rss $hwm $cpu" >> "$log"
        sleep 0.5
    done
    wait "$tpid" || { echo "replay ($mode) failed:" >&2; tail -5 "$WORK/$mode.stderr" >&2; exit 1; }
}

report() {
    local mode=$1
    python3 - "$WORK/long.csv" "$WORK/$mode.samples" "$WORK/$mode.stderr" "$RATE" "$mode" << 'EOF'
import sys, re, os
csv, samples, stderr, rate, mode = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4]), sys.argv[5]
with open(csv, 'rb') as f:
    header = len(f.readline())
    row = len(f.readline())
rows = [tuple(map(float, l.split())) for l in open(samples) if len(l.split()) == 5]
tick = os.sysconf('SC_CLK_TCK')
per_hour = int(3600 * rate)
n_rows = (os.path.getsize(csv) - header) // row
def at(byte, col):
    # wall time (col 0) or CPU time (col 4, s) at which rchar reached `byte`, interpolated
    for a, b in zip(rows, rows[1:]):
        if b[1] >= byte:
            f = (byte - a[1]) / max(b[1] - a[1], 1)
            return a[col] + (b[col] - a[col]) * f
    return None
def rate_hour(h, col):
    a = at(header + h * per_hour * row, col)
    b = at(header + (h + 1) * per_hour * row, col)
    if a is None or b is None or b <= a:
        return None
    return per_hour / (b - a) * (tick if col == 4 else 1)
hours = n_rows // per_hour
hwm = max(r[3] for r in rows) / 1024
text = open(stderr).read()
maxrss = re.search(r'Maximum resident set size \(kbytes\): (\d+)', text)
wall = re.search(r'Elapsed \(wall clock\) time.*: (\S+)', text)
near = lambda b: min(rows, key=lambda r: abs(r[1] - b))
print(f"{mode}: {n_rows} rows, wall {wall.group(1) if wall else '?'}, peak RSS {hwm:.1f} MB (VmHWM sampled), "
      f"{int(maxrss.group(1)) / 1024 if maxrss else float('nan'):.1f} MB (time -v); "
      f"RSS after 1 h of record {near(header + per_hour * row)[2] / 1024:.1f} MB, "
      f"after {hours - 1} h {near(header + (hours - 1) * per_hour * row)[2] / 1024:.1f} MB")
# the last full hour the sampler saw completely (the process may exit between two samples)
last_h = max((h for h in range(hours) if rate_hour(h, 0) is not None), default=None)
for col, what in [(0, "rows/s of wall time"), (4, "rows/s of CPU time")]:
    first = rate_hour(0, col)
    last = rate_hour(last_h, col) if last_h is not None else None
    if first and last:
        print(f"{mode}: hour 1 {first:,.0f} {what}, hour {last_h + 1} {last:,.0f}, ratio {last / first:.3f}")
with open(samples + ".hours", "w") as f:
    for h in range(hours):
        f.write(f"{h + 1} {rate_hour(h, 0)} {rate_hour(h, 4)}\n")
EOF
}

for mode in ${MODES:-stdin file}; do
    run "$mode"
    report "$mode"
done
grep -h "samples read" "$WORK"/stdin.stderr "$WORK"/file.stderr >&2 || true
[[ ${KEEP:-0} == 1 ]] || rm -f "$WORK/long.csv"
